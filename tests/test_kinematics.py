"""Kinematics: S(nu2) = R^T R_dot when eta2_dot = Q nu2; R orthonormal; eta1_dot = R nu1."""
from conftest import assert_close
import numpy as np
import pytest
import sympy as sp

from derive import symbols as sym
from quadcog.model.conventions import rotation_matrix


@pytest.fixture(scope="module")
def kin(derived):
    R = sp.lambdify([list(sym.eta2)], derived.R, "numpy")
    dR = [sp.lambdify([list(sym.eta2)], derived.R.diff(a), "numpy") for a in sym.eta2]
    Q = sp.lambdify([list(sym.eta2)], derived.Q, "numpy")
    return R, dR, Q


def test_euler_rate_map(kin, points):
    R, dR, Q = kin
    for k, (x, _, _, _) in enumerate(points):
        eta2, nu2 = x[3:6], x[9:12]
        rates = np.array(Q(eta2)) @ nu2
        R_dot = sum(np.array(d(eta2)) * r for d, r in zip(dR, rates))
        S = np.array(R(eta2)).T @ R_dot
        expected = np.array([[0, -nu2[2], nu2[1]], [nu2[2], 0, -nu2[0]], [-nu2[1], nu2[0], 0]])
        assert_close(S, expected, 1e-12, "R^T R_dot", k)


def test_rotation_zyx(kin, points):
    R, _, _ = kin
    for k, (x, _, _, _) in enumerate(points):
        ph, th, ps = x[3:6]
        c, s = np.cos, np.sin
        Rz = np.array([[c(ps), -s(ps), 0], [s(ps), c(ps), 0], [0, 0, 1]])
        Ry = np.array([[c(th), 0, s(th)], [0, 1, 0], [-s(th), 0, c(th)]])
        Rx = np.array([[1, 0, 0], [0, c(ph), -s(ph)], [0, s(ph), c(ph)]])
        Rk = np.array(R(x[3:6]))
        assert_close(Rk, Rz @ Ry @ Rx, 1e-14, "R", k)
        # the runtime's numpy R (quadcog.model.conventions) is the same matrix
        assert_close(rotation_matrix(ph, th, ps), Rz @ Ry @ Rx, 1e-14, "rotation_matrix", k)
        assert_close(Rk.T @ Rk, np.eye(3), 1e-14, "R^T R", k)


def test_position_kinematics(model, kin, points):
    R, _, Q = kin
    for k, (x, U, p, _) in enumerate(points):
        xdot = model.dynamics(x, U, p)
        assert_close(xdot[:3], np.array(R(x[3:6])) @ x[6:9], 1e-12, "eta1_dot", k)
        assert_close(xdot[3:6], np.array(Q(x[3:6])) @ x[9:12], 1e-12, "eta2_dot", k)
