/* quadcog: the firmware's motor pipeline, cut from stabilizer.c and motors.c (below), which
 * the host cannot compile whole. What stands in for the hardware is quadcog's (qc_loop.c):
 * pmGetBatteryVoltage (the plant's battery) and motorsSetRatio (records the PWM). */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include "autoconf.h"
#include "cfassert.h"
#include "debug.h"
#include "platform_defaults.h"
#include "power_distribution.h"
#include "stabilizer_types.h"
#define NBR_OF_MOTORS STABILIZER_NR_OF_MOTORS
#define MOTOR_M1 0
#define MOTOR_M2 1
#define MOTOR_M3 2
#define MOTOR_M4 3
float pmGetBatteryVoltage(void);
void motorsSetRatio(uint32_t id, uint16_t ithrust);
float motorsCompensateBatteryVoltage(uint32_t id, float iThrust, float supplyVoltage);
void qc_control_motors(const control_t *control);

