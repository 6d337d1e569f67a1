"""alpha and b against the output acceleration computed independently from the exported
dynamics by CasADi's automatic differentiation: y_dot = (rows z, phi, theta, psi of x_dot),
y_ddot = d y_dot / dx * x_dot; then alpha = d y_ddot / dU and b = y_ddot at U = 0."""
import casadi as ca
import numpy as np
import pytest

import quadcog
from quadcog.conventions import B_U, OUTPUT_ROWS
from conftest import assert_close



@pytest.fixture(scope="module")
def output_acceleration(model):
    f = model.casadi_function("dynamics")
    x, U, p = ca.SX.sym("x", 12), ca.SX.sym("U", 4), ca.SX.sym("p", 14)
    xdot = f(x, U, p)
    y_dot = xdot[list(OUTPUT_ROWS)]
    y_ddot = ca.jtimes(y_dot, x, xdot)
    return ca.Function("yfun", [x, U, p], [ca.jacobian(y_dot, U), y_ddot, ca.jacobian(y_ddot, U)])


def test_relative_degree_one_is_absent(output_acceleration, points):
    """L_g h = 0: the inputs do not reach y_dot."""
    for k, (x, U, p, _) in enumerate(points):
        L_g_h, _, _ = output_acceleration(x, U, p)
        assert_close(np.array(L_g_h), np.zeros((4, 4)), 0, "L_g h", k)


def test_decoupling_and_drift(model, output_acceleration, points):
    for k, (x, U, p, _) in enumerate(points):
        _, y_ddot, dy_dU = output_acceleration(x, U, p)
        _, y_ddot0, _ = output_acceleration(x, np.zeros(4), p)
        assert_close(model.decoupling(x, p), np.array(dy_dU), 1e-10, "alpha", k)
        assert_close(model.drift(x, p), np.array(y_ddot0).ravel(), 1e-10, "b", k)
        assert_close(model.decoupling(x, p) @ U + model.drift(x, p), np.array(y_ddot).ravel(),
                     1e-10, "alpha U + b", k)


def test_decoupling_matches_H_Minv_Bu(model, points):
    """docs/model.md sec. 2.4: alpha = H M^{-1} B_u with H = blockdiag(row 3 of R, Q)."""
    for k, (x, U, p, _) in enumerate(points):
        phi, th, psi = x[3:6]
        R_row3 = [-np.sin(th), np.sin(phi) * np.cos(th), np.cos(phi) * np.cos(th)]
        Q = np.array([[1, np.sin(phi) * np.tan(th), np.cos(phi) * np.tan(th)],
                      [0, np.cos(phi), -np.sin(phi)],
                      [0, np.sin(phi) / np.cos(th), np.cos(phi) / np.cos(th)]])
        H = np.zeros((4, 6))
        H[0, :3], H[1:, 3:] = R_row3, Q
        expected = H @ np.linalg.solve(model.mass_matrix(p), B_U)
        assert_close(model.decoupling(x, p), expected, 1e-10, "alpha = H M^-1 B_u", k)


def test_relative_degree_computed(derived):
    assert derived.outputs.relative_degree == (2, 2, 2, 2)
    assert all(e == 0 for e in derived.outputs.L_g_h)


def test_alpha_nonsingular_and_thrust_in_attitude_rows(model):
    x = np.zeros(12)
    balanced = quadcog.default_parameters()
    a0 = model.decoupling(x, balanced)
    assert abs(np.linalg.det(a0)) > 1e-6
    assert np.all(a0[1:, 0] == 0), "balanced: thrust must not enter attitude rows at hover"
    shifted = quadcog.default_parameters(x_G=0.03, y_G=0.02)
    a1 = model.decoupling(x, shifted)
    assert abs(np.linalg.det(a1)) > 1e-6
    assert np.all(np.abs(a1[1:3, 0]) > 1e-3), "shifted CoG: thrust must enter phi, theta rows"
