"""Pieces shared by the controllers: gains from poles, yaw-frame errors, desired tilt,
and the exact output derivative y_dot = H(eta) nu taken from the generated dynamics."""
import casadi as ca
import numpy as np

from quadcog import validate
from quadcog.model.conventions import IDX, OUTPUT_ROWS


def second_order_gains(poles, what):
    """(kp, kd) so that s^2 + kd s + kp has the two given poles (real or a conjugate pair)."""
    coeffs = np.poly(validate.poles(poles, what, 2))
    return float(coeffs.real[2]), float(coeffs.real[1])


def tilt_limit(max_tilt, what="max_tilt"):
    """The clip on commanded roll and pitch (rad), a number in (0, pi/2]."""
    return validate.real(max_tilt, what, lo=0.0, lo_open=True, hi=np.pi / 2, unit="rad")


def wrap_angle(a):
    """Angle difference wrapped into (-pi, pi] (SX)."""
    return ca.atan2(ca.sin(a), ca.cos(a))


def yaw_rotation_T(psi):
    """Rz(psi)^T: ground axes to the yaw-aligned frame (SX 3x3)."""
    c, s = ca.cos(psi), ca.sin(psi)
    return ca.vertcat(ca.horzcat(c, s, 0), ca.horzcat(-s, c, 0), ca.horzcat(0, 0, 1))


def desired_tilt(a_cmd, g, psi, max_tilt):
    """(phi_d, theta_d) that point the thrust along a_cmd + g e_z (ground axes) at heading psi:
    exact inversion of R e_z, each angle clipped to +-max_tilt (rad)."""
    a = yaw_rotation_T(psi) @ a_cmd
    lift = g + a[2]
    theta_d = ca.atan2(a[0], lift)
    phi_d = ca.atan2(-a[1], ca.sqrt(a[0] ** 2 + lift ** 2))
    clip = lambda v: ca.fmin(ca.fmax(v, -max_tilt), max_tilt)
    return clip(phi_d), clip(theta_d)


def kinematics(model, x, p):
    """(eta_dot (6x1), y_dot (4x1)) at x: rows of the generated dynamics that do not depend
    on U or p (they are R nu1 and Q nu2)."""
    xdot = model.casadi_function("dynamics")(x, ca.SX.zeros(4), p)
    return xdot[:6], xdot[list(OUTPUT_ROWS)]


def drag_over_mass(p):
    """(c_x / m, c_y / m, c_z / m) as numbers."""
    return np.asarray(p[IDX["c_x"]:IDX["c_z"] + 1]) / p[IDX["m"]]
