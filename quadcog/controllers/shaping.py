"""Pieces shared by the controllers: gains from poles, yaw-frame errors, desired tilt,
and the exact output derivative y_dot = H(eta) nu taken from the generated dynamics."""
from collections.abc import Sequence
import functools

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.model.conventions import IDX, OUTPUT_ROWS
from quadcog.model.functions import Model
from quadcog.model.parameters import LARGEST, SMALLEST

__all__ = ["second_order_gains", "checked_poles", "tilt_limit", "wrap_angle", "yaw_rotation_T", "desired_tilt",
           "kinematics", "drag_over_mass"]


def second_order_gains(poles: Sequence[complex], what: str) -> tuple[float, float]:
    """The gains of a second-order loop with the given poles.

    Parameters
    ----------
    poles : sequence of 2 numbers
        The poles (rad/s), real or a conjugate pair, negative real parts.
    what : str
        The setting's name, for the error message.

    Returns
    -------
    kp : float
        Stiffness (1/s^2) of s^2 + kd s + kp.
    kd : float
        Damping (1/s).

    Raises
    ------
    InputError
        When ``poles`` are not 2 stable poles.
    """
    if isinstance(poles, tuple) and all(type(p) in (float, int, complex) for p in poles):
        return _gains_of(poles, what)       # the designs' tuples: once per process
    return _gains_of_poles(poles, what)


def checked_poles(poles: object, what: str, n: int) -> npt.NDArray[np.complex128]:
    """``n`` stable poles (``validate.poles``) whose magnitudes lie within [SMALLEST, LARGEST]
    (1e-9 to 1e6 rad/s): beyond, the gains (products of up to ``n`` poles) overflow to inf or
    vanish to 0, and the loop has poles other than the ones asked for.

    Parameters
    ----------
    poles : sequence of n numbers
        The poles (rad/s), real or in conjugate pairs, negative real parts.
    what : str
        The setting's name, for the error message.
    n : int
        How many poles.

    Returns
    -------
    (n,) numpy.ndarray of complex128
        The poles.

    Raises
    ------
    InputError
        When ``poles`` are not ``n`` stable poles of magnitudes within the range.
    """
    p = validate.poles(poles, what, n)
    for k, z in enumerate(p):
        if not SMALLEST <= abs(z) <= LARGEST:
            validate.fail(f"{what}[{k}]", f"a pole of magnitude in [{SMALLEST:g}, {LARGEST:g}] "
                          "rad/s (the gains stay within the float range)",
                          z.real if z.imag == 0 else z)
    return p


def _gains_of_poles(poles, what):
    coeffs = np.poly(checked_poles(poles, what, 2))
    return float(coeffs.real[2]), float(coeffs.real[1])


_gains_of = functools.lru_cache(maxsize=256)(_gains_of_poles)


def tilt_limit(max_tilt: float, what: str = "max_tilt") -> float:
    """The clip on commanded roll and pitch, checked.

    Parameters
    ----------
    max_tilt : float
        The clip (rad), in (0, pi/2].
    what : str
        The setting's name, for the error message.

    Returns
    -------
    float
        ``max_tilt`` (rad).

    Raises
    ------
    InputError
        When it is not a number in (0, pi/2].
    """
    return validate.real(max_tilt, what, lo=0.0, lo_open=True, hi=np.pi / 2, unit="rad")


def wrap_angle(a: ca.SX) -> ca.SX:
    """Angle difference wrapped into (-pi, pi].

    Parameters
    ----------
    a : casadi.SX
        An angle difference (rad).

    Returns
    -------
    casadi.SX
        atan2(sin a, cos a) (rad).
    """
    return ca.atan2(ca.sin(a), ca.cos(a))


def yaw_rotation_T(psi: ca.SX) -> ca.SX:
    """Rz(psi)^T: ground axes to the yaw-aligned frame.

    Parameters
    ----------
    psi : casadi.SX
        Yaw (rad).

    Returns
    -------
    casadi.SX
        The 3x3 rotation.
    """
    c, s = ca.cos(psi), ca.sin(psi)
    return ca.vertcat(ca.horzcat(c, s, 0), ca.horzcat(-s, c, 0), ca.horzcat(0, 0, 1))


def desired_tilt(a_cmd: ca.SX, g: float, psi: ca.SX,
                 max_tilt: float) -> tuple[ca.SX, ca.SX]:
    """The roll and pitch that point the thrust along a_cmd + g e_z (ground axes) at heading
    psi: exact inversion of R e_z, each angle clipped to +-max_tilt.

    Parameters
    ----------
    a_cmd : casadi.SX
        Commanded acceleration (3,) (m/s^2), ground axes.
    g : float
        Gravitational acceleration (m/s^2).
    psi : casadi.SX
        Heading (rad).
    max_tilt : float
        Clip of each angle (rad).

    Returns
    -------
    phi_d : casadi.SX
        Desired roll (rad).
    theta_d : casadi.SX
        Desired pitch (rad).
    """
    a = yaw_rotation_T(psi) @ a_cmd
    lift = g + a[2]
    theta_d = ca.atan2(a[0], lift)
    phi_d = ca.atan2(-a[1], ca.sqrt(a[0] ** 2 + lift ** 2))
    clip = lambda v: ca.fmin(ca.fmax(v, -max_tilt), max_tilt)
    # the lambda's argument is untyped, so mypy picks fmin's float overload; the result is SX
    return clip(phi_d), clip(theta_d)  # type: ignore[return-value]


def kinematics(model: Model, x: ca.SX,
               p: ca.SX | ca.DM | npt.NDArray[np.float64]) -> tuple[ca.SX, ca.SX]:
    """The pose rate and the output rate at x: rows of the generated dynamics that do not
    depend on U or p (they are R nu1 and Q nu2).

    Parameters
    ----------
    model : quadcog.model.functions.Model
        The generated functions.
    x : casadi.SX
        State (12,) [m, rad, m/s, rad/s].
    p : casadi.SX or casadi.DM or (14,) numpy.ndarray
        Parameter vector.

    Returns
    -------
    eta_dot : casadi.SX
        Pose rate (6x1) [m/s, rad/s].
    y_dot : casadi.SX
        Rate of the outputs y = [z, phi, theta, psi] (4x1) [m/s, rad/s].
    """
    xdot = model.casadi_function("dynamics")(x, ca.SX.zeros(4), p)
    return xdot[:6], xdot[list(OUTPUT_ROWS)]


def drag_over_mass(p: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The linear drag per mass.

    Parameters
    ----------
    p : (14,) numpy.ndarray
        Parameter vector (``Vehicle.parameters()`` order).

    Returns
    -------
    (3,) numpy.ndarray
        (c_x / m, c_y / m, c_z / m) (1/s).
    """
    return np.asarray(p[IDX["c_x"]:IDX["c_z"] + 1]) / p[IDX["m"]]
