/* A small hand-written out-of-tree controller for quadcog's tests: a PD hover in
 * controlModeForceTorque (thrust in N, torques in N m), in the firmware's out-of-tree API.
 * It reads the firmware's units: state->attitude in degrees with pitch negated, gyro in
 * deg/s. */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>

#include "app.h"
#include "controller.h"
#include "platform_defaults.h"
#include "stabilizer_types.h"

#define DEG 0.017453292519943295f
static const float J[3] = {16.6e-6f, 16.7e-6f, 29.3e-6f};   /* kg m^2 */

void appMain(void) {}

void controllerOutOfTreeInit(void) {}

bool controllerOutOfTreeTest(void) { return true; }

void controllerOutOfTree(control_t *control, const setpoint_t *setpoint,
                         const sensorData_t *sensors, const state_t *state, const uint32_t tick)
{
  if (tick % 2) return;                                  /* 500 Hz; control_t persists */
  const float g = 9.81f;
  float ax = 4.0f * (setpoint->position.x - state->position.x) + 3.0f * (setpoint->velocity.x - state->velocity.x);
  float ay = 4.0f * (setpoint->position.y - state->position.y) + 3.0f * (setpoint->velocity.y - state->velocity.y);
  float az = 6.0f * (setpoint->position.z - state->position.z) + 4.0f * (setpoint->velocity.z - state->velocity.z);
  float roll = state->attitude.roll * DEG, pitch = -state->attitude.pitch * DEG;   /* legacy sign */
  float roll_d = -ay / g, pitch_d = ax / g;
  float p = sensors->gyro.x * DEG, q = sensors->gyro.y * DEG, r = sensors->gyro.z * DEG;
  control->controlMode = controlModeForceTorque;
  control->thrustSi = CF_MASS * (g + az) / (cosf(roll) * cosf(pitch));
  control->torqueX = J[0] * (400.0f * (roll_d - roll) - 40.0f * p);
  control->torqueY = J[1] * (400.0f * (pitch_d - pitch) - 40.0f * q);
  control->torqueZ = J[2] * (-100.0f * state->attitude.yaw * DEG - 20.0f * r);
}
