"""Kinematics: R (body to ground, ZYX), Q (body rates to Euler rates), J = blockdiag(R, Q)."""
import sympy as sp

from derive.symbols import phi, psi, theta


def elementary_rotations():
    """Rx(phi), Ry(theta), Rz(psi)."""
    rx = sp.Matrix([[1, 0, 0], [0, sp.cos(phi), -sp.sin(phi)], [0, sp.sin(phi), sp.cos(phi)]])
    ry = sp.Matrix([[sp.cos(theta), 0, sp.sin(theta)], [0, 1, 0], [-sp.sin(theta), 0, sp.cos(theta)]])
    rz = sp.Matrix([[sp.cos(psi), -sp.sin(psi), 0], [sp.sin(psi), sp.cos(psi), 0], [0, 0, 1]])
    return rx, ry, rz


def rotation():
    """R = Rz(psi) Ry(theta) Rx(phi), mapping body {A} components to ground {G}."""
    rx, ry, rz = elementary_rotations()
    return rz * ry * rx


def euler_rate_map():
    """Q(eta2) with eta2_dot = Q nu2.

    Angular velocities add up through the three elementary rotations, so the body
    rate is nu2 = E(eta2) eta2_dot with E = [e_x, Rx^T e_y, Rx^T Ry^T e_z]; Q = E^{-1}
    through the adjugate. Only the scalar determinant is simplified, so this is fast.
    (tests/test_kinematics.py checks S(nu2) = R^T R_dot at random points.)
    """
    rx, ry, _ = elementary_rotations()
    e = sp.eye(3)
    E = sp.Matrix.hstack(e[:, 0], rx.T * e[:, 1], rx.T * ry.T * e[:, 2])
    det = sp.trigsimp(E.det())
    return (E.adjugate() / det).applyfunc(lambda e: sp.trigsimp(sp.factor_terms(e)))


def kinematics():
    """Return (R, Q, J) as SymPy matrices."""
    R = rotation()
    Q = euler_rate_map()
    J = sp.diag(R, Q)
    return R, Q, J
