"""Structural identities of M and C at random admissible points (compiled functions)."""
import numpy as np

from conftest import assert_close


def test_mass_matrix_symmetric_positive_definite(model, points):
    for k, (x, U, p, _) in enumerate(points):
        M = model.mass_matrix(p)
        assert_close(M, M.T, 1e-15, "M - M^T", k)
        assert np.linalg.eigvalsh(M)[0] > 0, f"M not positive definite at point {k}"


def test_mass_matrix_is_the_papers_matrix(model, points):
    # Built here from the definition M = [[m I, -m S(r)], [m S(r), I_O]] (Fossen).
    for k, (x, U, p, _) in enumerate(points):
        m, r = p[0], p[11:14]
        S = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
        expected = np.block([[m * np.eye(3), -m * S], [m * S, np.diag(p[2:5])]])
        assert_close(model.mass_matrix(p), expected, 1e-14, "M", k)


def test_coriolis_skew_symmetric(model, points):
    for k, (x, U, p, _) in enumerate(points):
        C = model.coriolis(x, p)
        assert_close(C + C.T, np.zeros((6, 6)), 1e-14, "C + C^T", k)
        assert np.max(np.abs(C)) > 0, "C vanished at a point with non-zero velocity"


def test_damping_diagonal(model, points):
    for k, (x, U, p, _) in enumerate(points):
        assert_close(model.damping(p), np.diag(p[5:11]), 0, "D", k)


def test_equations_of_motion_hold(model, points):
    """M nu_dot + C nu + D nu + g_G = B_u U with nu_dot from the exported dynamics."""
    B_u = np.vstack([np.zeros((2, 4)), np.eye(4)])
    for k, (x, U, p, _) in enumerate(points):
        nu_dot = model.dynamics(x, U, p)[6:]
        nu = x[6:]
        lhs = (model.mass_matrix(p) @ nu_dot + model.coriolis(x, p) @ nu
               + model.damping(p) @ nu + model.gravity(x, p))
        assert_close(lhs, B_u @ U, 1e-11, "equations of motion", k)


def test_newton_euler_z_row_sign(model, points):
    """MODEL.md item 1: the z force row has y_G (r q + p_dot), not the paper's (r q - p_dot)."""
    for k, (x, U, p, _) in enumerate(points):
        m, (x_G, y_G, z_G) = p[0], p[11:14]
        u, v, w, P, Q, R = x[6:]
        udot, vdot, wdot, pdot, qdot, rdot = model.dynamics(x, U, p)[6:]
        # Euler's first axiom along body z, expanded by hand.
        F_z = m * (wdot - u * Q + v * P + x_G * (R * P - qdot) + y_G * (R * Q + pdot)
                   - z_G * (Q ** 2 + P ** 2))
        lhs = model.mass_matrix(p) @ model.dynamics(x, U, p)[6:] + model.coriolis(x, p) @ x[6:]
        assert_close(lhs[2], F_z, 1e-11, "F_z row", k)
