"""Guards of the control laws (quadcog.controllers) against oracles written here: Lee's
attitude law on SO(3) (T. Lee, M. Leok, N. H. McClamroch, CDC 2010) realised through Euler's
rotation equations of the true body, a heading held the short way across +-pi, and a purely
vertical error that, by symmetry, tilts nothing and leaves the attitude integrators at zero.
The composite law's covariance is held to the logistic equation's fixed point k0 in the
direction the data do not excite. (bench/mutations.py: geometric_rate_cross_term_dropped,
geometric_attitude_error_order, cascade_yaw_error_unwrapped, fl_integral_integrates_wrong_rows,
composite_covariance_unbounded.)"""
import math

import numpy as np
import pytest

from quadcog import HUMMINGBIRD, CascadePD, Hover, simulate
from quadcog.controllers.composite import CompositeAdaptive, unpack_covariance
from quadcog.controllers.fl_integral import FeedbackLinearizationIntegral
from quadcog.controllers.geometric import GeometricAdaptive


def _rotation(phi, theta, psi):
    """Rz(psi) Ry(theta) Rx(phi), written out."""
    c, s = np.cos, np.sin
    Rz = np.array([[c(psi), -s(psi), 0], [s(psi), c(psi), 0], [0, 0, 1]])
    Ry = np.array([[c(theta), 0, s(theta)], [0, 1, 0], [-s(theta), 0, c(theta)]])
    Rx = np.array([[1, 0, 0], [0, c(phi), -s(phi)], [0, s(phi), c(phi)]])
    return Rz @ Ry @ Rx


def _lee_desired(f, yaw):
    """R_c = [b1, b2, b3]: b3 = f / |f|, b1 = b2_d x b3 normalized, b2 = b3 x b1, with the
    heading's b2_d = [-sin yaw, cos yaw, 0]."""
    b3 = f / np.linalg.norm(f)
    b1 = np.cross([-np.sin(yaw), np.cos(yaw), 0.0], b3)
    b1 /= np.linalg.norm(b1)
    return np.column_stack([b1, np.cross(b3, b1), b3])


def _vee(S):
    return np.array([S[2, 1], S[0, 2], S[1, 0]])


@pytest.mark.parametrize("angles, yaw_d, yaw_rate, w", [
    ((0.0, 0.0, 0.3), 0.3, 0.8, (1.0, 0.0, 0.0)),          # R = R_c, e_R = 0
    ((0.2, -0.15, 0.3), 0.5, -1.1, (0.4, -0.7, 0.2)),      # tilted, heading 0.2 rad off
    ((-0.3, 0.25, -2.9), 3.0, 0.6, (-0.5, 0.9, -0.3)),     # tilted, across +-pi
])
def test_geometric_law_gives_lees_angular_acceleration(angles, yaw_d, yaw_rate, w):
    """Lee's attitude law, with R_c, Omega_c and e_R built here from the paper's definitions:

        w_dot = -k_R e_R - k_W (w - w_c) - w x w_c + R^T R_c Omega_c_dot,
        e_R = (R_c^T R - R^T R_c)^vee / 2,  w_c = R^T R_c Omega_c.

    The state is chosen so that the needed force f = m s R e3 (the reference acceleration is
    what the thrust along the body's own z axis gives, at rest at the reference point,
    without translational drag) stays constant: then Omega_c = (R_c^T dR_c/dyaw)^vee yaw_rate
    (central differences here) and, with the rate filter settled (Omega_f = Omega_c),
    Omega_c_dot = 0. The body's response to the law's moments, by Euler's equations
    I w_dot = tau - w x I w - D_w w (CoG at O), must be that acceleration."""
    v = HUMMINGBIRD.replace(c_x=0.0, c_y=0.0, c_z=0.0)
    ctl = GeometricAdaptive(v, allocation=False)
    R = _rotation(*angles)
    s = v.g / R[2, 2]
    f = v.m * s * R[:, 2]
    Rc = _lee_desired(f, yaw_d)
    h = 1e-6
    Rc_dot = (_lee_desired(f, yaw_d + h) - _lee_desired(f, yaw_d - h)) / (2 * h) * yaw_rate
    Omega_c = _vee(Rc.T @ Rc_dot)
    x = np.zeros(12)
    x[:3], x[3:6], x[9:12] = (0.1, -0.2, 1.0), angles, w
    ref = np.zeros(14)
    ref[:3], ref[6:9] = x[:3], s * R[:, 2] - [0.0, 0.0, v.g]
    ref[12], ref[13] = yaw_d, yaw_rate
    c = ctl.initial_state()
    c[-3:] = Omega_c                                # Omega_f = Omega_c: the filter has settled
    U, c_dot = ctl(0.0, x, ref, c)
    np.testing.assert_allclose(c_dot[-3:], 0.0, atol=1e-7)
    assert U[0] == pytest.approx(v.m * s, rel=1e-12)
    I = np.array([v.Ixx, v.Iyy, v.Izz])
    drag = np.array([v.c_phi, v.c_theta, v.c_psi])
    w = np.asarray(w, float)
    w_dot = (U[1:] - np.cross(w, I * w) - drag * w) / I
    e_R = _vee(Rc.T @ R - R.T @ Rc) / 2
    w_c = R.T @ Rc @ Omega_c
    lee = -ctl.k_R * e_R - ctl.k_W * (w - w_c) - np.cross(w, w_c)
    np.testing.assert_allclose(w_dot, lee, rtol=1e-7, atol=1e-7)


def test_cascade_turns_the_short_way_across_pi():
    """From a heading of -3 rad to a reference of +3 rad the short way is 0.28 rad through
    +-pi; the heading never comes near 0 (cos psi stays near -1) and settles on the
    reference modulo 2 pi."""
    x0 = np.zeros(12)
    x0[2], x0[5] = 1.0, -3.0
    res = simulate(CascadePD(), Hover(yaw=3.0), duration=3.0, x0=x0)
    assert not res.metrics.diverged
    psi = res.x[:, 5]
    assert np.cos(psi).max() < -0.95, f"turned the long way: psi from {psi[0]} to {psi[-1]}"
    assert abs(math.remainder(psi[-1] - 3.0, 2 * math.pi)) < 0.01


def test_fl_integral_a_vertical_error_tilts_nothing():
    """Started 0.2 m below the hover point, level, CoG at O: the error is in z alone, so the
    phi, theta, psi errors and their integrals stay zero and the vehicle climbs straight."""
    x0 = np.zeros(12)
    x0[2] = 0.8
    res = simulate(FeedbackLinearizationIntegral(), "hover", duration=2.0, x0=x0)
    assert abs(res.x[-1, 2] - 1.0) < 0.01                 # it did climb
    assert np.abs(res.controller_state).max() < 1e-12
    assert np.abs(res.x[:, [0, 1, 3, 4, 5]]).max() < 1e-12


def test_composite_covariance_stays_within_its_bound():
    """In a level hover the data excite x_G and y_G (the weight's moment about a CoG off the
    axis) but not z_G (the weight is along it), so P_zz obeys the logistic equation
    P' = beta P (1 - P / k0) alone: from P(0) = k0 it stays at k0 exactly (its fixed point),
    and no direction of P exceeds k0 ("P stays between a positive lower bound and k0 I")."""
    ctl = CompositeAdaptive()
    k0 = ctl.covariance_bound
    res = simulate(ctl, "hover", duration=3.0)
    P = res.controller_state[:, ctl.STATE_SLICES["P"]]
    np.testing.assert_allclose(P[:, 5], k0, rtol=1e-12)
    assert max(np.linalg.eigvalsh(unpack_covariance(p)).max() for p in P[::50]) <= k0 * (1 + 1e-12)
    assert P[-1, 0] < 0.5 * k0 and P[-1, 3] < 0.5 * k0       # the excited directions learnt
