"""The C of a Crazyflie out-of-tree controller app, compiled for the host against the
firmware's own struct headers, and quadcog states written in the firmware's units.

``firmware_units`` writes a quadcog flight (x, ref) as the estimator and the commander would
hand it to a controller: ``state_t`` as ``kalmanCoreExternalizeState`` fills it (attitude in
degrees with the pitch negated and the yaw wrapped to +-180 deg, quaternion x, y, z, w of the
body-to-world rotation, world-frame position and velocity, acceleration in g with gravity
removed), ``sensorData_t.gyro`` in deg/s, and a full-state ``setpoint_t`` (position,
velocity, acceleration, jerk, yaw in degrees). ``HostApp`` runs the app's
``controllerOutOfTree`` over those rows (``target/cf_host_shim.c`` fills the structs).
"""
import ctypes
import os
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from quadcog.codegen.compiler import find_compiler
from quadcog.embedded.host import compile_checked
from quadcog.embedded.target import TARGET_DIR
from quadcog.errors import CompileError, ExportError
from quadcog.model.conventions import rotation_matrix

__all__ = ["HOST_INCLUDES", "HOST_FLAGS", "MODE_DISABLE", "MODE_ABS", "MODE_VELOCITY",
           "STANDARD_GRAVITY", "AGREEMENT_RTOL", "firmware_units", "agreement", "build_host_app",
           "HostApp"]

# the firmware folders whose headers stabilizer_types.h and controller.h need
HOST_INCLUDES = ("src/modules/interface", "src/modules/interface/controller",
                 "src/hal/interface", "src/utils/interface", "src/utils/interface/lighthouse")
# gnu11: the firmware's structs have anonymous unions; no FMA contraction, as on the target
# build of the law (quadcog.embedded.target)
HOST_FLAGS = ("-std=gnu11", "-O2", "-Wall", "-Wextra", "-Wdouble-promotion",
              "-Wfloat-conversion", "-Werror", "-ffp-contract=off", "-fno-math-errno",
              "-fPIC", "-shared", "-DCONFIG_CONTROLLER_OOT=1")
MODE_DISABLE, MODE_ABS, MODE_VELOCITY = 0, 1, 2     # stab_mode_t of stabilizer_types.h
STANDARD_GRAVITY = 9.81   # m/s^2 per g of state->acc (the firmware's GRAVITY_MAGNITUDE)
# The app's float32 C against quadcog's double law along the same flight (``agreement``):
# largest |difference| over the largest |value|, for the thrust and for the torque vector
# (one scale for its three components: they are one quantity in N m, and the yaw torque of a
# flight without yaw is 1/50 of the others, so its own scale would magnify rounding). Sources:
# the state rounded to float32 in the firmware's units (degrees: 6e-8 relative) and converted
# back in float32, the law's ~1,000 float32 operations, and the float32 controller state c
# that integrates 2,500 Euler steps apart from the double one (the filters forget: bounded).
# Measured on the 5 s circle with a CoG ramp of the tests: 4e-6 (thrust) and 1.5e-5 (torque)
# for composite and payload_adaptive; a pitch-sign, quaternion-order (w, x, y, z) or gyro-sign
# error in the conversion gives 0.03 to 0.19 (thrust) and 2.3 to 2.6 (torque) on composite.
AGREEMENT_RTOL = {"thrust": 1e-4, "torque": 1e-4}


def _quaternion_xyzw(phi, theta, psi):
    """The unit quaternion (x, y, z, w) of R = Rz(psi) Ry(theta) Rx(phi)."""
    cr, sr = np.cos(phi / 2), np.sin(phi / 2)
    cp, sp = np.cos(theta / 2), np.sin(theta / 2)
    cy, sy = np.cos(psi / 2), np.sin(psi / 2)
    return np.stack([sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
                     cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy], axis=-1)


def firmware_units(x: ArrayLike, ref: ArrayLike,
                   dt: float) -> tuple[NDArray[np.float32], NDArray[np.float32],
                                       NDArray[np.float32]]:
    """A quadcog flight as the rows ``HostApp.run`` takes, in the firmware's units.

    Parameters
    ----------
    x : (N, 12) array_like
        quadcog states [m, rad, m/s body, rad/s body].
    ref : (N, 14) array_like
        quadcog references (position, velocity, acceleration, jerk, yaw, yaw rate).
    dt : float
        Their sample period (s), for the acceleration (central differences of the velocity).

    Returns
    -------
    tuple of numpy.ndarray (float32)
        state (N, 16), gyro (N, 3), setpoint (N, 14): see ``target/cf_host_shim.c``.

    Raises
    ------
    quadcog.errors.ExportError
        Shapes other than (N, 12) and (N, 14) with the same N.
    """
    x, ref = np.asarray(x, float), np.asarray(ref, float)
    if x.ndim != 2 or x.shape[1] != 12 or ref.shape != (len(x), 14):
        raise ExportError(f"x, ref: expected (N, 12) and (N, 14) arrays, got {x.shape} and "
                          f"{ref.shape}")
    phi, theta, psi = x[:, 3], x[:, 4], x[:, 5]
    wrapped = np.angle(np.exp(1j * psi))
    v_world = np.stack([rotation_matrix(*e) @ v for e, v in zip(x[:, 3:6], x[:, 6:9])])
    acc = (np.gradient(v_world, dt, axis=0) if len(x) > 1 else np.zeros_like(v_world))
    state = np.column_stack([np.degrees(phi), -np.degrees(theta), np.degrees(wrapped),
                             _quaternion_xyzw(phi, theta, wrapped), x[:, 0:3], v_world,
                             acc / STANDARD_GRAVITY])
    gyro = np.degrees(x[:, 9:12])
    setpoint = np.column_stack([ref[:, 0:12], np.degrees(np.angle(np.exp(1j * ref[:, 12]))),
                                np.degrees(ref[:, 13])])
    return (state.astype(np.float32), gyro.astype(np.float32), setpoint.astype(np.float32))


def agreement(U: ArrayLike, U_ref: ArrayLike) -> dict[str, float]:
    """How far the app's commands are from quadcog's, in the terms of ``AGREEMENT_RTOL``.

    Parameters
    ----------
    U : (N, 4) array_like
        The app's thrustSi (N) and torque (N m).
    U_ref : (N, 4) array_like
        quadcog's U along the same flight.

    Returns
    -------
    dict of str to float
        {'thrust': ..., 'torque': ...}: largest |U - U_ref| over the largest |U_ref|.
    """
    U, U_ref = np.asarray(U, float), np.asarray(U_ref, float)
    rel = lambda a, b: float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))
    return {"thrust": rel(U[:, 0], U_ref[:, 0]), "torque": rel(U[:, 1:4], U_ref[:, 1:4])}


def build_host_app(app: str | os.PathLike[str], firmware: str | os.PathLike[str],
                   out: str | os.PathLike[str]) -> Path:
    """Compile an app's C (``src/*.c`` but the app task) with the host driver as a library.

    Parameters
    ----------
    app : str or os.PathLike
        The app folder (``write_crazyflie_app``).
    firmware : str or os.PathLike
        A firmware tree (its headers only are read).
    out : str or os.PathLike
        The shared library to write.

    Returns
    -------
    pathlib.Path
        ``out``.

    Raises
    ------
    quadcog.errors.CompileError
        Without a C compiler, or when the compile fails (a warning fails it).
    """
    cc = find_compiler()
    if cc is None:
        raise CompileError("no C compiler found (looked for $CC or `cc` on PATH)")
    src = Path(app) / "src"
    sources = sorted(p for p in src.glob("*.c") if p.name != "quadcog_cf_app.c")
    includes = [a for d in HOST_INCLUDES for a in ("-I", str(Path(firmware) / d))]
    compile_checked([cc, *HOST_FLAGS, "-I", src, *includes, TARGET_DIR / "cf_host_shim.c",
                     *sources, "-o", out, "-lm"])
    return Path(out)


class HostApp:
    """An app's host library: ``controllerOutOfTree`` over rows in the firmware's units.

    Parameters
    ----------
    library : str or os.PathLike
        The library of ``build_host_app`` (one controller state per loaded file).
    """

    def __init__(self, library: str | os.PathLike[str]) -> None:
        self.lib = ctypes.CDLL(str(library))
        f = ctypes.POINTER(ctypes.c_float)
        self.lib.qc_cf_run.argtypes = [ctypes.c_int, f, f, f, ctypes.POINTER(ctypes.c_int),
                                       ctypes.c_uint32, ctypes.c_uint32, f]
        self.lib.qc_cf_run.restype = None
        self.lib.qc_cf_test.restype = ctypes.c_int

    def init(self) -> bool:
        """Call ``controllerOutOfTreeInit``, then ``controllerOutOfTreeTest``.

        Returns
        -------
        bool
            What the test returned.
        """
        self.lib.qc_cf_init()
        return bool(self.lib.qc_cf_test())

    def run(self, state: ArrayLike, gyro: ArrayLike, setpoint: ArrayLike,
            modes: tuple[int, int, int, int] = (MODE_ABS,) * 4, tick0: int = 0,
            tick_step: int = 2, velocity_body: bool = False) -> NDArray[np.float32]:
        """Call ``controllerOutOfTree`` once per row, at ticks tick0 + k tick_step.

        Parameters
        ----------
        state : array_like
            (N, 16) rows of the firmware's state (``firmware_units``).
        gyro : array_like
            (N, 3) rows of the gyroscope (``firmware_units``).
        setpoint : array_like
            (N, 14) rows of the setpoint (``firmware_units``).
        modes : tuple of int
            ``setpoint.mode`` of x, y, z, yaw (``MODE_ABS``, ...).
        tick0 : int
            The first ``stabilizerStep`` (1 kHz ticks).
        tick_step : int
            Ticks between rows (2: every row at the 500 Hz rate of the law).
        velocity_body : bool
            ``setpoint.velocity_body``: the x, y velocity in the frame turned by the yaw.

        Returns
        -------
        (N, 5) numpy.ndarray (float32)
            thrustSi (N), torque x, y, z (N m), controlMode after each call.
        """
        rows = [np.ascontiguousarray(a, dtype=np.float32) for a in (state, gyro, setpoint)]
        n = len(rows[0])
        out = np.zeros((n, 5), dtype=np.float32)
        m = (ctypes.c_int * 5)(*modes, int(velocity_body))
        ptr = lambda a: a.ctypes.data_as(ctypes.POINTER(ctypes.c_float))
        self.lib.qc_cf_run(n, *(ptr(a) for a in rows), m, tick0, tick_step, ptr(out))
        return out
