/* quadcog: the Crazyflie firmware in quadcog's truth plant, one flight per call.
 *
 * Each tick of the firmware's 1 kHz main loop (stabilizerStep from 1, as stabilizer.c starts
 * it): the truth state is turned into the firmware's state_t and sensorData_t (its units and
 * signs), the reference row into a full-state setpoint_t (as the high-level commander writes
 * it), the firmware's controller() runs with the tick (each controller decides itself whether
 * its stages run: RATE_DO_EXECUTE), the firmware's controlMotors() turns control_t (which
 * persists between ticks) into four PWMs, the PWMs into rotor thrusts through the thrust map
 * (the motor voltage V_bat PWM / 65535 in the cubic VMOTOR2THRUST0..3), and quadcog's plant
 * step (generated C, passed in as a function pointer) integrates one tick.
 *
 * Frames: quadcog's and the firmware's world and body axes agree (x forward, y left, z up);
 * quadcog's attitude is ZYX Euler angles (phi, theta, psi) of R = Rz Ry Rx, body to world.
 * Globals are the firmware's way (its controllers keep their state in statics): load one copy
 * of this library per flight.
 */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "controller.h"
#include "log.h"
#include "param.h"
#include "physicalConstants.h"
#include "power_distribution.h"
#include "stabilizer_types.h"

void qc_control_motors(const control_t *control);

typedef long long qc_int;          /* casadi_int */
typedef int (*qc_plant_fn)(const double **arg, double **res, qc_int *iw, double *w, int mem);

/* ---- the log and parameter tables (registered by the shims' constructors) ---- */
#define QC_MAX_ENTRIES 4096
struct qc_entry { const char *group; const char *name; int type; void *address; void (*callback)(void); };
static struct qc_entry qc_logs[QC_MAX_ENTRIES];
static int qc_nlogs;
static struct qc_entry qc_params[QC_MAX_ENTRIES];
static int qc_nparams;

void qc_register_log(const struct qc_log_s *table, int n)
{
  const char *group = 0;
  for (int i = 0; i < n; i++) {
    if (table[i].type & LOG_GROUP) {
      group = (table[i].type & LOG_START) ? table[i].name : 0;
      continue;
    }
    if (group && qc_nlogs < QC_MAX_ENTRIES && !(table[i].type & LOG_BY_FUNCTION))
      qc_logs[qc_nlogs++] = (struct qc_entry){group, table[i].name, table[i].type & 0x0F,
                                              table[i].address, 0};
  }
}

void qc_register_param(const struct param_s *table, int n)
{
  const char *group = 0;
  for (int i = 0; i < n; i++) {
    if (table[i].type & PARAM_GROUP) {
      group = (table[i].type & PARAM_START) ? table[i].name : 0;
      continue;
    }
    if (group && qc_nparams < QC_MAX_ENTRIES)
      qc_params[qc_nparams++] = (struct qc_entry){group, table[i].name, table[i].type,
                                                  table[i].address, table[i].callback};
  }
}

int qc_log_count(void) { return qc_nlogs; }
const char *qc_log_group(int i) { return qc_logs[i].group; }
const char *qc_log_name(int i) { return qc_logs[i].name; }
int qc_param_count(void) { return qc_nparams; }
const char *qc_param_group(int i) { return qc_params[i].group; }
const char *qc_param_name(int i) { return qc_params[i].name; }

static double qc_log_value(int i)
{
  const void *a = qc_logs[i].address;
  switch (qc_logs[i].type) {
    case LOG_UINT8: return *(const uint8_t *)a;
    case LOG_UINT16: return *(const uint16_t *)a;
    case LOG_UINT32: return *(const uint32_t *)a;
    case LOG_INT8: return *(const int8_t *)a;
    case LOG_INT16: return *(const int16_t *)a;
    case LOG_INT32: return *(const int32_t *)a;
    case LOG_FLOAT: return *(const float *)a;
    default: return NAN;
  }
}

/* param.h's type byte: bits 0-1 the size (1, 2, 4, 8 bytes), bit 2 float, bit 3 unsigned */
double qc_param_get(int i)
{
  const void *a = qc_params[i].address;
  int t = qc_params[i].type, size = 1 << (t & PARAM_BYTES_MASK);
  if (t & PARAM_TYPE_FLOAT) return size == 8 ? *(const double *)a : *(const float *)a;
  if (t & PARAM_UNSIGNED)
    return size == 1 ? *(const uint8_t *)a : size == 2 ? *(const uint16_t *)a : *(const uint32_t *)a;
  return size == 1 ? *(const int8_t *)a : size == 2 ? *(const int16_t *)a : *(const int32_t *)a;
}

int qc_param_set(int i, double v)
{
  void *a = qc_params[i].address;
  int t = qc_params[i].type, size = 1 << (t & PARAM_BYTES_MASK);
  if (t & PARAM_RONLY) return 1;
  if (t & PARAM_TYPE_FLOAT) { if (size == 8) *(double *)a = v; else *(float *)a = (float)v; }
  else if (t & PARAM_UNSIGNED) {
    if (size == 1) *(uint8_t *)a = (uint8_t)v; else if (size == 2) *(uint16_t *)a = (uint16_t)v;
    else *(uint32_t *)a = (uint32_t)v;
  } else {
    if (size == 1) *(int8_t *)a = (int8_t)v; else if (size == 2) *(int16_t *)a = (int16_t)v;
    else *(int32_t *)a = (int32_t)v;
  }
  if (qc_params[i].callback) qc_params[i].callback();
  return 0;
}

/* ---- what stands in for the hardware and the console ---- */
static char qc_console_text[16384];
static size_t qc_console_len;
static char qc_assert_text[512];
static int qc_asserted;
static double qc_battery_voltage = 4.2;
static uint16_t motor_ratios[STABILIZER_NR_OF_MOTORS];

static long qc_nonfinite_ticks;     /* ticks whose control_t (force-torque) was not finite */

const char *qc_console(void) { return qc_console_text; }
long qc_nonfinite_control(void) { return qc_nonfinite_ticks; }
const char *qc_assert_message(void) { return qc_assert_text; }

void qc_console_printf(const char *fmt, ...)
{
  if (qc_console_len + 1 >= sizeof qc_console_text) return;
  va_list ap;
  va_start(ap, fmt);
  int k = vsnprintf(qc_console_text + qc_console_len, sizeof qc_console_text - qc_console_len, fmt, ap);
  va_end(ap);
  if (k > 0) qc_console_len += (size_t)k;
  if (qc_console_len >= sizeof qc_console_text) qc_console_len = sizeof qc_console_text - 1;
}

void assertFail(char *exp, char *file, int line)
{
  if (!qc_asserted) snprintf(qc_assert_text, sizeof qc_assert_text, "%s in %s, line %d", exp, file, line);
  qc_asserted = 1;
}

float pmGetBatteryVoltage(void) { return (float)qc_battery_voltage; }

/* motors.c's motorsSetRatio with motorSetEnable 0: the PWM it sets is the ratio */
void motorsSetRatio(uint32_t id, uint16_t ithrust)
{
  if (id < STABILIZER_NR_OF_MOTORS) motor_ratios[id] = ithrust;
}

/* the firmware's log group of the motor PWMs (motors.c), which is not compiled here */
LOG_GROUP_START(motor)
LOG_ADD_CORE(LOG_UINT16, m1, &motor_ratios[0])
LOG_ADD_CORE(LOG_UINT16, m2, &motor_ratios[1])
LOG_ADD_CORE(LOG_UINT16, m3, &motor_ratios[2])
LOG_ADD_CORE(LOG_UINT16, m4, &motor_ratios[3])
LOG_GROUP_STOP(motor)

/* ---- the flight ---- */
#define QC_REF 14                  /* columns of a reference row (quadcog's ref) */
struct qc_flight {
  long n_steps;                /* ticks */
  int controller;              /* ControllerType */
  int nf;                      /* rotor states of the plant (0 or 4) */
  double dt;                   /* s, one tick */
  double battery;              /* V */
  double thrust_map[4];        /* thrust of one rotor (N), cubic of the motor voltage */
  double max_thrust;           /* N per rotor; <= 0: no cap beyond the PWM's */
  double mixer[16];            /* U = mixer f, row-major */
  double max_position_error;   /* m */
  double max_tilt;             /* rad */
  const double *P;             /* (n, 14) truth parameters per tick */
  const double *payload;       /* (n, 10) */
  const double *r_stated;      /* (3) */
  const double *wrench;        /* (n, 6) */
  const double *ref;           /* (n + 1, QC_REF): position, velocity, acceleration, jerk (m, m/s, m/s^2, m/s^3), yaw (rad), yaw rate (rad/s) */
  const double *noise;         /* (n, 12) or NULL: added to position, velocity (world), Euler angles, body rates */
  double *X;                   /* (n + 1, 12 + nf); row 0 holds the start */
  double *U;                   /* (n, 4) the input the rotors gave */
  double *F;                   /* (n, 4) rotor thrust from the PWM (N) */
  int n_log;
  const int *log_index;        /* (n_log) indices into the log table */
  float *log_out;              /* (n, n_log) */
  qc_plant_fn plant;
  qc_int *iw;
  double *w;
};

static double qc_deg(double rad) { return rad * (180.0 / M_PI); }

/* state_t and sensorData_t of a truth state (quadcog's x) and the world acceleration */
static void qc_sense(const double *x, const double *noise, const double *acc_world,
                     state_t *state, sensorData_t *sensors)
{
  double pos[3] = {x[0], x[1], x[2]}, eul[3] = {x[3], x[4], x[5]};
  double nu1[3] = {x[6], x[7], x[8]}, om[3] = {x[9], x[10], x[11]};
  double cphi = cos(eul[0]), sphi = sin(eul[0]), cth = cos(eul[1]), sth = sin(eul[1]);
  double cpsi = cos(eul[2]), spsi = sin(eul[2]);
  double R[3][3] = {
    {cpsi * cth, cpsi * sth * sphi - spsi * cphi, cpsi * sth * cphi + spsi * sphi},
    {spsi * cth, spsi * sth * sphi + cpsi * cphi, spsi * sth * cphi - cpsi * sphi},
    {-sth, cth * sphi, cth * cphi}};
  double vel[3];
  for (int i = 0; i < 3; i++) vel[i] = R[i][0] * nu1[0] + R[i][1] * nu1[1] + R[i][2] * nu1[2];
  if (noise) {
    for (int i = 0; i < 3; i++) {
      pos[i] += noise[i]; vel[i] += noise[3 + i]; eul[i] += noise[6 + i]; om[i] += noise[9 + i];
    }
  }
  double hr = 0.5 * eul[0], hp = 0.5 * eul[1], hy = 0.5 * eul[2];
  double cr = cos(hr), sr = sin(hr), cp = cos(hp), sp = sin(hp), cy = cos(hy), sy = sin(hy);
  memset(state, 0, sizeof *state);
  state->position.x = (float)pos[0]; state->position.y = (float)pos[1]; state->position.z = (float)pos[2];
  state->velocity.x = (float)vel[0]; state->velocity.y = (float)vel[1]; state->velocity.z = (float)vel[2];
  /* degrees, pitch negated: the legacy CF2 body coordinate system (kalman_core.c) */
  state->attitude.roll = (float)qc_deg(eul[0]);
  state->attitude.pitch = (float)-qc_deg(eul[1]);
  state->attitude.yaw = (float)qc_deg(eul[2]);
  /* body to world, not adjusted for the legacy system; stored x, y, z, w */
  state->attitudeQuaternion.w = (float)(cr * cp * cy + sr * sp * sy);
  state->attitudeQuaternion.x = (float)(sr * cp * cy - cr * sp * sy);
  state->attitudeQuaternion.y = (float)(cr * sp * cy + sr * cp * sy);
  state->attitudeQuaternion.z = (float)(cr * cp * sy - sr * sp * cy);
  /* world acceleration in g, gravity removed (acc.z without gravity) */
  state->acc.x = (float)(acc_world[0] / GRAVITY_MAGNITUDE);
  state->acc.y = (float)(acc_world[1] / GRAVITY_MAGNITUDE);
  state->acc.z = (float)(acc_world[2] / GRAVITY_MAGNITUDE);
  memset(sensors, 0, sizeof *sensors);
  /* the accelerometer's specific force in body axes (g), the gyro's body rates (deg/s) */
  double a_g[3] = {acc_world[0] / GRAVITY_MAGNITUDE, acc_world[1] / GRAVITY_MAGNITUDE,
                   acc_world[2] / GRAVITY_MAGNITUDE + 1.0};
  sensors->acc.x = (float)(R[0][0] * a_g[0] + R[1][0] * a_g[1] + R[2][0] * a_g[2]);
  sensors->acc.y = (float)(R[0][1] * a_g[0] + R[1][1] * a_g[1] + R[2][1] * a_g[2]);
  sensors->acc.z = (float)(R[0][2] * a_g[0] + R[1][2] * a_g[1] + R[2][2] * a_g[2]);
  sensors->gyro.x = (float)qc_deg(om[0]);
  sensors->gyro.y = (float)qc_deg(om[1]);
  sensors->gyro.z = (float)qc_deg(om[2]);
}

/* the full-state setpoint of the high-level commander (crtp_commander_high_level.c) */
static void qc_setpoint(const double *r, uint32_t tick, setpoint_t *sp)
{
  memset(sp, 0, sizeof *sp);
  sp->timestamp = tick;
  sp->position.x = (float)r[0]; sp->position.y = (float)r[1]; sp->position.z = (float)r[2];
  sp->velocity.x = (float)r[3]; sp->velocity.y = (float)r[4]; sp->velocity.z = (float)r[5];
  sp->acceleration.x = (float)r[6]; sp->acceleration.y = (float)r[7]; sp->acceleration.z = (float)r[8];
  sp->jerk.x = (float)r[9]; sp->jerk.y = (float)r[10]; sp->jerk.z = (float)r[11];
  sp->attitude.yaw = (float)qc_deg(r[12]);
  sp->attitudeRate.yaw = (float)qc_deg(r[13]);
  sp->mode.x = modeAbs; sp->mode.y = modeAbs; sp->mode.z = modeAbs;
  sp->mode.roll = modeDisable; sp->mode.pitch = modeDisable; sp->mode.yaw = modeAbs;
  sp->mode.quat = modeDisable;
  sp->velocity_body = false;
}

void qc_init(int controller_type)
{
  controllerInit((ControllerType)controller_type);
}

int qc_controller_type(void) { return (int)controllerGetType(); }

/* Returns the ticks run; *code: 0 finished, 1 non-finite, 2 position error, 3 tilt, 4 the
 * firmware asserted. */
long qc_run(struct qc_flight *f, int *code)
{
  const int nx = 12 + f->nf;
  static control_t control;
  setpoint_t setpoint;
  sensorData_t sensors;
  state_t state;
  double v_prev[3] = {0, 0, 0}, acc[3] = {0, 0, 0}, dt_arg, fcmd[4], Ucmd[4];
  qc_battery_voltage = f->battery;
  *code = 0;
  for (long k = 0; k < f->n_steps; k++) {
    const double *x = f->X + k * nx;
    double *x_next = f->X + (k + 1) * nx;
    uint32_t tick = (uint32_t)(k + 1);      /* stabilizerStep starts at 1 */
    /* the world velocity and its backward difference (the acceleration of the last tick) */
    {
      double cphi = cos(x[3]), sphi = sin(x[3]), cth = cos(x[4]), sth = sin(x[4]);
      double cpsi = cos(x[5]), spsi = sin(x[5]);
      double v[3] = {
        cpsi * cth * x[6] + (cpsi * sth * sphi - spsi * cphi) * x[7] + (cpsi * sth * cphi + spsi * sphi) * x[8],
        spsi * cth * x[6] + (spsi * sth * sphi + cpsi * cphi) * x[7] + (spsi * sth * cphi - cpsi * sphi) * x[8],
        -sth * x[6] + cth * sphi * x[7] + cth * cphi * x[8]};
      for (int i = 0; i < 3; i++) {
        acc[i] = k ? (v[i] - v_prev[i]) / f->dt : 0.0;
        v_prev[i] = v[i];
      }
    }
    qc_sense(x, f->noise ? f->noise + 12 * k : 0, acc, &state, &sensors);
    qc_setpoint(f->ref + QC_REF * k, tick, &setpoint);
    controller(&control, &setpoint, &sensors, &state, tick);
    /* a non-finite force-torque command reaches the motors as the firmware makes it (its
     * float-to-integer conversion in powerDistributionForceTorque); count it */
    if (control.controlMode == controlModeForceTorque
        && !(isfinite(control.thrustSi) && isfinite(control.torqueX)
             && isfinite(control.torqueY) && isfinite(control.torqueZ)))
      qc_nonfinite_ticks++;
    qc_control_motors(&control);
    for (int i = 0; i < 4; i++) {
      double v = f->battery * motor_ratios[i] / 65535.0, *c = f->thrust_map;
      double thrust = c[0] + v * (c[1] + v * (c[2] + v * c[3]));
      if (!(thrust > 0)) thrust = 0;          /* the motor does not turn */
      if (f->max_thrust > 0 && thrust > f->max_thrust) thrust = f->max_thrust;
      fcmd[i] = thrust;
      f->F[4 * k + i] = thrust;
    }
    for (int r = 0; r < 4; r++) {
      Ucmd[r] = 0;
      for (int i = 0; i < 4; i++) Ucmd[r] += f->mixer[4 * r + i] * fcmd[i];
    }
    dt_arg = f->dt;
    const double *arg[8] = {x, x + 12, Ucmd, f->P + 14 * k, f->payload + 10 * k, f->r_stated,
                            f->wrench + 6 * k, &dt_arg};
    double *res[3] = {x_next, x_next + 12, f->U + 4 * k};
    f->plant(arg, res, f->iw, f->w, 0);
    for (int j = 0; j < f->n_log; j++)
      f->log_out[(long)f->n_log * k + j] = (float)qc_log_value(f->log_index[j]);
    if (qc_asserted) { *code = 4; return k + 1; }
    const double *r_next = f->ref + QC_REF * (k + 1);
    double sum = 0, ex = x_next[0] - r_next[0], ey = x_next[1] - r_next[1], ez = x_next[2] - r_next[2];
    for (int i = 0; i < nx; i++) sum += fabs(x_next[i]);
    if (!(sum < INFINITY)) { *code = 1; return k + 1; }
    if (sqrt(ex * ex + ey * ey + ez * ez) > f->max_position_error) { *code = 2; return k + 1; }
    if (fabs(x_next[3]) > f->max_tilt || fabs(x_next[4]) > f->max_tilt) { *code = 3; return k + 1; }
  }
  return f->n_steps;
}
