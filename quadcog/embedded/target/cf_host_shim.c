/* Host driver of a Crazyflie out-of-tree controller app (quadcog.embedded.crazyflie_host):
   fills the firmware's own structs (stabilizer_types.h) from rows of numbers already in the
   firmware's units and calls controllerOutOfTree once per row, as the stabilizer does.

   state row (16): attitude roll, pitch, yaw (deg, pitch negated), quaternion x, y, z, w,
                   position (m), velocity (m/s, world), acc (g, world, 1 g removed)
   gyro row (3):   deg/s, body
   setpoint row (14): position, velocity, acceleration, jerk (world), yaw (deg), yaw rate (deg/s)
   modes (5):      stab_mode_t of x, y, z and yaw, then velocity_body (the same for every row)
   out row (5):    thrustSi (N), torque x, y, z (N m), controlMode */
#include <stdint.h>
#include <string.h>

#include "controller.h"

void qc_cf_init(void)
{
    controllerOutOfTreeInit();
}

int qc_cf_test(void)
{
    return controllerOutOfTreeTest() ? 1 : 0;
}

void qc_cf_run(int n, const float *state_rows, const float *gyro_rows, const float *setpoint_rows,
               const int *modes, uint32_t tick0, uint32_t tick_step, float *out)
{
    control_t control;
    setpoint_t setpoint;
    sensorData_t sensors;
    state_t state;
    int k;
    memset(&control, 0, sizeof control);
    memset(&setpoint, 0, sizeof setpoint);
    memset(&sensors, 0, sizeof sensors);
    memset(&state, 0, sizeof state);
    setpoint.mode.x = (stab_mode_t)modes[0];
    setpoint.mode.y = (stab_mode_t)modes[1];
    setpoint.mode.z = (stab_mode_t)modes[2];
    setpoint.mode.yaw = (stab_mode_t)modes[3];
    setpoint.velocity_body = modes[4] != 0;
    for (k = 0; k < n; ++k) {
        const float *s = state_rows + 16 * k, *g = gyro_rows + 3 * k, *p = setpoint_rows + 14 * k;
        float *o = out + 5 * k;
        state.attitude.roll = s[0];
        state.attitude.pitch = s[1];
        state.attitude.yaw = s[2];
        state.attitudeQuaternion.x = s[3];
        state.attitudeQuaternion.y = s[4];
        state.attitudeQuaternion.z = s[5];
        state.attitudeQuaternion.w = s[6];
        state.position.x = s[7];
        state.position.y = s[8];
        state.position.z = s[9];
        state.velocity.x = s[10];
        state.velocity.y = s[11];
        state.velocity.z = s[12];
        state.acc.x = s[13];
        state.acc.y = s[14];
        state.acc.z = s[15];
        sensors.gyro.x = g[0];
        sensors.gyro.y = g[1];
        sensors.gyro.z = g[2];
        setpoint.position.x = p[0];
        setpoint.position.y = p[1];
        setpoint.position.z = p[2];
        setpoint.velocity.x = p[3];
        setpoint.velocity.y = p[4];
        setpoint.velocity.z = p[5];
        setpoint.acceleration.x = p[6];
        setpoint.acceleration.y = p[7];
        setpoint.acceleration.z = p[8];
        setpoint.jerk.x = p[9];
        setpoint.jerk.y = p[10];
        setpoint.jerk.z = p[11];
        setpoint.attitude.yaw = p[12];
        setpoint.attitudeRate.yaw = p[13];
        controllerOutOfTree(&control, &setpoint, &sensors, &state,
                            (stabilizerStep_t)(tick0 + tick_step * (uint32_t)k));
        o[0] = control.thrustSi;
        o[1] = control.torqueX;
        o[2] = control.torqueY;
        o[3] = control.torqueZ;
        o[4] = (float)control.controlMode;
    }
}
