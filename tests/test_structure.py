"""Structural identities of M and C at random admissible points (compiled functions)."""
import numpy as np

from conftest import assert_close
from quadcog.conventions import B_U


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


def test_input_matrix_is_the_derived_one(derived):
    """The runtime's numpy B_U (quadcog.conventions) is the B_u of the SymPy derivation."""
    assert np.array(derived.body.B_u, dtype=float).tolist() == B_U.tolist()


def test_equations_of_motion_hold(model, points):
    """M nu_dot + C nu + D nu + g_G = B_u U with nu_dot from the exported dynamics."""
    for k, (x, U, p, _) in enumerate(points):
        nu_dot = model.dynamics(x, U, p)[6:]
        nu = x[6:]
        lhs = (model.mass_matrix(p) @ nu_dot + model.coriolis(x, p) @ nu
               + model.damping(p) @ nu + model.gravity(x, p))
        assert_close(lhs, B_U @ U, 1e-11, "equations of motion", k)


def test_newton_euler_z_row_sign(model, points):
    """docs/model.md sec. 2.1: the z force row has y_G (r q + p_dot), not the paper's (r q - p_dot)."""
    for k, (x, U, p, _) in enumerate(points):
        m, (x_G, y_G, z_G) = p[0], p[11:14]
        u, v, w, P, Q, R = x[6:]
        udot, vdot, wdot, pdot, qdot, rdot = model.dynamics(x, U, p)[6:]
        # Euler's first axiom along body z, expanded by hand.
        F_z = m * (wdot - u * Q + v * P + x_G * (R * P - qdot) + y_G * (R * Q + pdot)
                   - z_G * (Q ** 2 + P ** 2))
        lhs = model.mass_matrix(p) @ model.dynamics(x, U, p)[6:] + model.coriolis(x, p) @ x[6:]
        assert_close(lhs[2], F_z, 1e-11, "F_z row", k)


def test_truth_model_equations_of_motion(model, points):
    """truth_dynamics satisfies Euler's axioms with a full I_O and an external wrench, written
    out by hand in numpy; with zero products and wrench it is ``dynamics``."""
    for k, (x, U, p, vt) in enumerate(points):
        F_ground, M_body = vt[:3], 0.1 * vt[3:]
        Ixy, Ixz, Iyz = 0.1 * p[2:5] * np.sin(x[:3])
        I_O = np.array([[p[2], Ixy, Ixz], [Ixy, p[3], Iyz], [Ixz, Iyz, p[4]]])
        m, g, r, c = p[0], p[1], p[11:14], p[5:11]
        nu1, nu2 = x[6:9], x[9:12]
        wrench = np.concatenate([F_ground, M_body])
        a, al = np.split(model.truth_dynamics(x, U, p, [Ixy, Ixz, Iyz], wrench)[6:], 2)
        phi, th, ps = x[3:6]
        c_, s_ = np.cos, np.sin
        R = (np.array([[c_(ps), -s_(ps), 0], [s_(ps), c_(ps), 0], [0, 0, 1]])
             @ np.array([[c_(th), 0, s_(th)], [0, 1, 0], [-s_(th), 0, c_(th)]])
             @ np.array([[1, 0, 0], [0, c_(phi), -s_(phi)], [0, s_(phi), c_(phi)]]))
        f_G = m * g * np.array([np.sin(th), -np.sin(phi) * np.cos(th), -np.cos(phi) * np.cos(th)])
        force = f_G + [0, 0, U[0]] - c[:3] * nu1 + R.T @ F_ground
        moment = np.cross(r, f_G) + U[1:] - c[3:] * nu2 + M_body
        v_G = nu1 + np.cross(nu2, r)
        assert_close(m * (a + np.cross(al, r) + np.cross(nu2, v_G)), force, 1e-11, "1st axiom", k)
        h_O = I_O @ nu2 + m * np.cross(r, nu1)
        h_dot = I_O @ al + m * np.cross(r, a)
        assert_close(h_dot + np.cross(nu2, h_O) + np.cross(nu1, m * v_G), moment, 1e-11,
                     "2nd axiom", k)
        assert_close(model.truth_dynamics(x, U, p, np.zeros(3), np.zeros(6)),
                     model.dynamics(x, U, p), 1e-13, "zero products and wrench", k)
