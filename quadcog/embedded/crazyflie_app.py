"""A quadcog law as an out-of-tree controller app of the Crazyflie firmware.

``write_crazyflie_app(controller, out)`` writes the app that the firmware's own
``examples/app_out_of_tree_controller`` shows (Makefile, Kbuild, app-config, ``src/``): the law
as the float32 module of ``quadcog.embedded.controller_export`` and a C file that implements the
firmware's out-of-tree controller API (``controller.h``: ``controllerOutOfTreeInit``,
``controllerOutOfTreeTest``, ``controllerOutOfTree(control_t *, const setpoint_t *,
const sensorData_t *, const state_t *, stabilizerStep_t)``) and converts at the boundary:

- the state from the firmware's units (``stabilizer_types.h``; the estimators write it in
  ``kalmanCoreExternalizeState`` and ``estimator_complementary.c``): ``state->attitude`` in
  degrees with the pitch negated (the legacy CF2 body frame) gives phi, theta, psi;
  ``state->attitudeQuaternion`` (x, y, z, w; not negated) gives the rotation that takes the
  world-frame ``state->velocity`` into quadcog's body velocities u, v, w;
  ``sensors->gyro`` is the body rate in deg/s. The world frame (x, y, z up) and the body frame
  (x forward, y left, z up) are quadcog's. ``state->acc`` (g, 1 g removed) is not read: the
  law's state has no acceleration.
- the setpoint (world-frame position m, velocity m/s, acceleration m/s^2, jerk m/s^3, yaw
  and yaw rate in degrees) into quadcog's reference; an axis in ``modeVelocity`` holds the
  current position; with ``velocity_body`` (hover setpoints) the x, y velocity is turned by
  the yaw into the world frame; the yaw reference is taken within half a turn of the current yaw (the
  firmware's yaw is wrapped to +-180 deg, quadcog's law subtracts angles).
- the output as ``controlModeForceTorque``: thrustSi = U1 (N), torque = U2..U4 (N m), which
  the firmware's ``powerDistributionForceTorque`` mixes for its X frame.

The law runs at ``ATTITUDE_RATE`` (500 Hz, ``RATE_DO_EXECUTE``) with dt = 1/ATTITUDE_RATE and
leaves ``control_t`` alone on the other ticks (the stabilizer's ``control`` is static, so the
command persists). With ``setpoint->mode.z == modeDisable`` (no position setpoint: the law
cannot fly manual attitude setpoints) it commands zero thrust and restarts its state.
"""
import os
from pathlib import Path

from quadcog.controllers.base import Controller
from quadcog.controllers.registry import CONTROLLERS, make_controller
from quadcog.embedded.c_text import c_identifier, comment_text
from quadcog.embedded.controller_export import NOTICE, file_names, out_folder, render, short_name, write_files
from quadcog.errors import ExportError
from quadcog.vehicles.vehicle import PRESETS, Vehicle

__all__ = ["DEFAULT_VEHICLE", "RATE", "CONTROL_PERIOD", "resolve_vehicle", "app_files", "app_file_names",
           "write_crazyflie_app"]

# the Crazyflie 2.1 preset, built from the firmware's own constants (the firmware's default
# 2.1+ propellers): the vehicle the firmware is built for
DEFAULT_VEHICLE = "crazyflie21"
RATE = 500                       # Hz: ATTITUDE_RATE of the firmware's stabilizer_types.h
CONTROL_PERIOD = 1.0 / RATE      # s: the dt the law is designed and simulated for


def resolve_vehicle(vehicle: str | Vehicle | None) -> Vehicle:
    """The vehicle the app's law is designed for.

    Parameters
    ----------
    vehicle : str, Vehicle or None
        A preset name of ``quadcog.vehicles.vehicle.PRESETS``, a Vehicle, or None for
        ``DEFAULT_VEHICLE``.

    Returns
    -------
    quadcog.vehicles.Vehicle
        The vehicle.

    Raises
    ------
    quadcog.errors.ExportError
        An unknown preset name or something that is not a Vehicle.
    """
    if vehicle is None:
        vehicle = DEFAULT_VEHICLE
    if isinstance(vehicle, str):
        if vehicle not in PRESETS:
            raise ExportError(f"vehicle {vehicle!r}: expected one of {tuple(PRESETS)} or a "
                              "quadcog Vehicle")
        return PRESETS[vehicle]
    if not isinstance(vehicle, Vehicle):
        raise ExportError(f"vehicle: expected a preset name {tuple(PRESETS)} or a quadcog "
                          f"Vehicle, got {vehicle!r} ({type(vehicle).__name__})")
    return vehicle


_MAKEFILE = """\
# {notice}
# An out-of-tree controller app of the Crazyflie firmware (as its
# examples/app_out_of_tree_controller): make CRAZYFLIE_BASE=/path/to/crazyflie-firmware
CRAZYFLIE_BASE ?= ../crazyflie-firmware
OOT_CONFIG := $(PWD)/app-config
include $(CRAZYFLIE_BASE)/tools/make/oot.mk
"""

_APP_CONFIG = """\
CONFIG_APP_ENABLE=y
CONFIG_APP_PRIORITY=1
CONFIG_APP_STACKSIZE=350
CONFIG_CONTROLLER_OOT=y
"""


def _controller_c(name: str, nc: int, notice: str) -> str:
    """The firmware's out-of-tree controller API around quadcog_<name>_step."""
    pad = " " * len(f"static void quadcog_cf_{name}_state(")      # continuation lines
    return f"""\
/* {notice} */
/* quadcog_cf_{name}: the quadcog law quadcog_{name} as the Crazyflie firmware's
 * out-of-tree controller (controller.h). Units and frames at the boundary: see
 * quadcog/embedded/crazyflie_app.py. float32 throughout. */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>

#include "controller.h"
#include "quadcog_{name}.h"

#define QC_DEG_TO_RAD 0.0174532925f
#define QC_PI 3.14159265f
#define QC_DT (1.0f / (float)ATTITUDE_RATE)

/* the law's state (estimates, filters): one controller per firmware */
static qc_real qc_state[QUADCOG_{name.upper()}_NC > 0 ? QUADCOG_{name.upper()}_NC : 1];

/* quadcog's x (12): position (m), ZYX Euler angles (rad), body velocity (m/s), body rates
   (rad/s), from the firmware's state (attitude in deg with the pitch negated, quaternion
   x y z w, world-frame velocity) and gyro (deg/s) */
static void quadcog_cf_{name}_state(const state_t *state, const sensorData_t *sensors,
{pad}qc_real x[12])
{{
    const float qx = state->attitudeQuaternion.x, qy = state->attitudeQuaternion.y;
    const float qz = state->attitudeQuaternion.z, qw = state->attitudeQuaternion.w;
    const float vx = state->velocity.x, vy = state->velocity.y, vz = state->velocity.z;
    /* the columns of R (body to world) from the unit quaternion; body velocity = R^T v */
    const float r00 = 1.0f - 2.0f * (qy * qy + qz * qz), r10 = 2.0f * (qx * qy + qw * qz);
    const float r20 = 2.0f * (qx * qz - qw * qy), r01 = 2.0f * (qx * qy - qw * qz);
    const float r11 = 1.0f - 2.0f * (qx * qx + qz * qz), r21 = 2.0f * (qy * qz + qw * qx);
    const float r02 = 2.0f * (qx * qz + qw * qy), r12 = 2.0f * (qy * qz - qw * qx);
    const float r22 = 1.0f - 2.0f * (qx * qx + qy * qy);
    x[0] = state->position.x;
    x[1] = state->position.y;
    x[2] = state->position.z;
    x[3] = QC_DEG_TO_RAD * state->attitude.roll;
    x[4] = -QC_DEG_TO_RAD * state->attitude.pitch;     /* legacy CF2 frame: pitch negated */
    x[5] = QC_DEG_TO_RAD * state->attitude.yaw;
    x[6] = r00 * vx + r10 * vy + r20 * vz;
    x[7] = r01 * vx + r11 * vy + r21 * vz;
    x[8] = r02 * vx + r12 * vy + r22 * vz;
    x[9] = QC_DEG_TO_RAD * sensors->gyro.x;
    x[10] = QC_DEG_TO_RAD * sensors->gyro.y;
    x[11] = QC_DEG_TO_RAD * sensors->gyro.z;
}}

/* quadcog's ref (14): position, velocity, acceleration, jerk (world), yaw (rad, within half a
   turn of the current yaw psi), yaw rate (rad/s), from the setpoint */
static void quadcog_cf_{name}_reference(const setpoint_t *setpoint, const state_t *state,
{pad}    qc_real psi, qc_real ref[14])
{{
    const float yaw_rate = QC_DEG_TO_RAD * setpoint->attitudeRate.yaw;
    float yaw = psi, turn, vx = setpoint->velocity.x, vy = setpoint->velocity.y;
    if (setpoint->velocity_body) {{
        /* hover setpoints: x and y velocity in the frame turned by the yaw (as the firmware's
           position controller reads them) */
        const float c = cosf(psi), s = sinf(psi);
        vx = c * setpoint->velocity.x - s * setpoint->velocity.y;
        vy = s * setpoint->velocity.x + c * setpoint->velocity.y;
    }}
    ref[0] = setpoint->mode.x == modeAbs ? setpoint->position.x : state->position.x;
    ref[1] = setpoint->mode.y == modeAbs ? setpoint->position.y : state->position.y;
    ref[2] = setpoint->mode.z == modeAbs ? setpoint->position.z : state->position.z;
    ref[3] = vx;
    ref[4] = vy;
    ref[5] = setpoint->velocity.z;
    ref[6] = setpoint->acceleration.x;
    ref[7] = setpoint->acceleration.y;
    ref[8] = setpoint->acceleration.z;
    ref[9] = setpoint->jerk.x;
    ref[10] = setpoint->jerk.y;
    ref[11] = setpoint->jerk.z;
    if (setpoint->mode.yaw == modeAbs) {{
        yaw = QC_DEG_TO_RAD * setpoint->attitude.yaw;
        turn = 2.0f * QC_PI * floorf((yaw - psi + QC_PI) / (2.0f * QC_PI));
        yaw -= turn;
    }} else if (setpoint->mode.yaw == modeVelocity) {{
        yaw = psi + yaw_rate * QC_DT;
    }}
    ref[12] = yaw;
    ref[13] = setpoint->mode.yaw == modeDisable ? 0.0f : yaw_rate;
}}

void controllerOutOfTreeInit(void)
{{
    quadcog_{name}_init(qc_state);
}}

bool controllerOutOfTreeTest(void)
{{
    return true;
}}

void controllerOutOfTree(control_t *control, const setpoint_t *setpoint,
                         const sensorData_t *sensors, const state_t *state,
                         const stabilizerStep_t stabilizerStep)
{{
    qc_real x[12], ref[14], U[4];
    if (!RATE_DO_EXECUTE(ATTITUDE_RATE, stabilizerStep)) {{
        return;                 /* the command of the last attitude tick stays in control */
    }}
    control->controlMode = controlModeForceTorque;
    if (setpoint->mode.z == modeDisable) {{
        control->thrustSi = 0.0f;
        control->torqueX = 0.0f;
        control->torqueY = 0.0f;
        control->torqueZ = 0.0f;
        quadcog_{name}_init(qc_state);
        return;
    }}
    quadcog_cf_{name}_state(state, sensors, x);
    quadcog_cf_{name}_reference(setpoint, state, x[5], ref);
    quadcog_{name}_step(x, ref, qc_state, QC_DT, U);
    control->thrustSi = U[0];
    control->torqueX = U[1];
    control->torqueY = U[2];
    control->torqueZ = U[3];
}}
"""


def _app_main_c(notice: str) -> str:
    """The app task the firmware's app layer starts (the example's: it only sleeps)."""
    return f"""\
/* {notice} */
/* The app layer wants an appMain; the controller is called by the stabilizer, not here. */
#include "app.h"

#include "FreeRTOS.h"
#include "task.h"

void appMain(void)
{{
    while (1) {{
        vTaskDelay(M2T(2000));
    }}
}}
"""


def app_files(controller: Controller, name: str, command: str) -> dict[str, str]:
    """The app's files as text.

    Parameters
    ----------
    controller : quadcog.Controller
        The law, designed for its vehicle.
    name : str
        The C name part (a C identifier).
    command : str
        What wrote the files, named in their first line.

    Returns
    -------
    dict of str to str
        {path relative to the app folder: text}.

    Raises
    ------
    quadcog.errors.ExportError
        As ``quadcog.embedded.controller_export.render``.
    """
    notice = NOTICE.format(command=command)
    law = render(controller, "float32", name, command, dt=CONTROL_PERIOD)
    texts = [_MAKEFILE.format(notice=notice), "obj-y += src/\n", _APP_CONFIG,
             f"obj-y += quadcog_{name}.o\nobj-y += quadcog_cf_{name}.o\nobj-y += quadcog_cf_app.o\n",
             _controller_c(name, int(controller.n_state), notice), _app_main_c(notice),
             *law.values()]
    return dict(zip(app_file_names(name), texts, strict=True))


def app_file_names(name: str) -> list[str]:
    """The files of the app for a law named ``name``, relative to the app folder, in the
    order ``app_files`` gives them.

    Parameters
    ----------
    name : str
        As for ``quadcog.embedded.controller_export.file_names``.

    Returns
    -------
    list of str
        Makefile, Kbuild, app-config, then ``src/``: its Kbuild, the firmware's controller
        entry points, the app's main, and the law's header and source (``file_names``).
    """
    return ["Makefile", "Kbuild", "app-config", "src/Kbuild", f"src/quadcog_cf_{name}.c",
            "src/quadcog_cf_app.c", *(f"src/{f}" for f in file_names(name))]


def write_crazyflie_app(controller: str | Controller, out: str | os.PathLike[str],
                        vehicle: str | Vehicle | None = None, name: str | None = None,
                        command: str | None = None) -> list[Path]:
    """Write an out-of-tree controller app of the Crazyflie firmware for a quadcog law.

    Parameters
    ----------
    controller : str or Controller
        A short name of ``quadcog.controllers.CONTROLLERS`` (built with its default settings
        for ``vehicle``) or a controller object (redesigned for ``vehicle`` when it is given).
    out : path
        The app folder (created when missing); build it with ``make
        CRAZYFLIE_BASE=<firmware>`` inside it, or ``quadcog.embedded.crazyflie_firmware``.
    vehicle : str or Vehicle, optional
        The vehicle the law is designed for (default ``DEFAULT_VEHICLE``).
    name : str, optional
        ``<name>`` in the file and function names (default the controller's short name).
    command : str, optional
        What wrote the files, named in their first line (default: this Python call).

    Returns
    -------
    list of Path
        The files written, in the order of ``app_files``.

    Raises
    ------
    quadcog.errors.ExportError
        An unknown controller or vehicle, a name that is not a C identifier, a law that
        depends on t, or a folder that cannot be written.
    """
    out = out_folder(out)
    given_vehicle = vehicle is not None
    vehicle = resolve_vehicle(vehicle)
    if isinstance(controller, str):
        if controller not in CONTROLLERS:
            raise ExportError(f"controller {controller!r}: expected one of "
                              f"{tuple(CONTROLLERS)} or a quadcog Controller")
        if command is None:
            command = (f"quadcog.embedded.crazyflie_app.write_crazyflie_app({controller!r}, "
                       f"vehicle={vehicle.name!r})")
        name = c_identifier(controller if name is None else name, "name")
        controller = make_controller(controller, vehicle=vehicle)
    elif isinstance(controller, Controller):
        if given_vehicle:
            controller = controller.for_vehicle(vehicle)
        name = c_identifier(short_name(controller) if name is None else name, "name")
    else:
        raise ExportError(f"controller: expected one of {tuple(CONTROLLERS)} or a quadcog "
                          f"Controller, got {controller!r} ({type(controller).__name__})")
    command = comment_text(command, "command") if command is not None else (
        f"quadcog.embedded.crazyflie_app.write_crazyflie_app({type(controller).__name__}(...))")
    return write_files(app_files(controller, name, command), out, "app file")
