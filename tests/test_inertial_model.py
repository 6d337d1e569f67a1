"""The generated model in the ten inertial parameters, numerically at random points:

(b) the paper's regressor Phi follows from Y when m and I_O are held: Phi = m Y[:, 1:4]
    (the columns of h = m r_G), and the rest of Y pi is the model at r_G = 0;
(c) the paper's 14-entry p is the special case pi = [m, m r_G, Ixx, 0, Iyy, 0, 0, Izz]:
    inertial_dynamics equals dynamics;
(d) Y is the Jacobian, by central finite differences, of the left-hand side
    M(pi) nu_dot + C(nu, pi) nu + g_G(pi), which is computed here from inertial_dynamics and
    inertial_mass_matrix (not from Y), and that left-hand side is Y pi (linearity).
"""
from conftest import assert_close
import numpy as np
import pytest

import quadcog
from quadcog.errors import PhysicalConsistencyError
from quadcog.model.conventions import B_U, IDX, R_G
from quadcog.model.inertial_parameters import (
    N_PI,
    box,
    combine,
    inertial_arguments,
    is_physically_consistent,
    point_mass,
)
from quadcog.model.parameters import with_cog

RTOL = 1e-12


def test_phi_is_m_times_the_h_columns_of_Y(model, points):
    for k, (x, _, p, v) in enumerate(points):
        Y = model.inertial_regressor(x, v, p[IDX["g"]])
        assert_close(model.regressor(x, v, p), p[IDX["m"]] * Y[:, 1:4], RTOL, "Phi = m Y_h", k)


def test_paper_model_is_Y_times_its_pi(model, points):
    """M vartheta + C nu + g_G of p is Y pi(p); with m and I_O held the part without r_G is
    Y pi at r_G = 0, so the whole is (value at r_G = 0) + Phi r_G (docs/model.md sec. 3.1)."""
    for k, (x, _, p, v) in enumerate(points):
        lhs = model.mass_matrix(p) @ v + model.coriolis(x, p) @ x[6:] + model.gravity(x, p)
        pi, g, _ = inertial_arguments(p)
        Y = model.inertial_regressor(x, v, g)
        assert_close(Y @ pi, lhs, RTOL, "Y pi(p) vs M v + C nu + g_G", k)
        pi0, _, _ = inertial_arguments(with_cog(p, np.zeros(3)))
        assert_close(Y @ pi0 + model.regressor(x, v, p) @ p[R_G], lhs, RTOL,
                     "Y pi(r_G = 0) + Phi r_G", k)


def test_inertial_arguments_layout():
    p = quadcog.default_parameters(x_G=0.03, y_G=-0.01, z_G=0.02)
    pi, g, c = inertial_arguments(p)
    m = p[IDX["m"]]
    assert pi.tolist() == [m, m * 0.03, m * -0.01, m * 0.02, p[IDX["Ixx"]], 0.0,
                           p[IDX["Iyy"]], 0.0, 0.0, p[IDX["Izz"]]]
    assert g == p[IDX["g"]] and c.tolist() == p[IDX["c_x"]:IDX["c_psi"] + 1].tolist()


def test_dynamics_special_case(model, points):
    """Through the checked API where the paper's pi is physically consistent, through the
    CasADi function (no consistency check) everywhere: the identity is algebraic and holds
    for every admissible p, consistent or not."""
    unchecked = model.casadi_function("inertial_dynamics")
    consistent = 0
    for k, (x, U, p, _) in enumerate(points):
        pi, g, c = inertial_arguments(p)
        expected = model.dynamics(x, U, p)
        assert_close(np.array(unchecked(x, U, pi, g, c)).ravel(), expected, 1e-11,
                     "inertial_dynamics (VM) vs dynamics", k)
        if is_physically_consistent(pi):
            consistent += 1
            assert_close(model.inertial_dynamics(x, U, pi, g, c), expected, 1e-11,
                         "inertial_dynamics vs dynamics", k)
        else:
            with pytest.raises(PhysicalConsistencyError):
                model.inertial_dynamics(x, U, pi, g, c)
    # the sampler draws Ixx, Iyy, Izz independently: many admissible p are no rigid body
    assert 0 < consistent < len(points)


def test_default_vehicle_special_case(model, points):
    """The Hummingbird with its CoG 3 cm forward is a consistent body: the checked API."""
    p = quadcog.default_parameters(x_G=0.03)
    pi, g, c = inertial_arguments(p)
    for k, (x, U, _, _) in enumerate(points[:50]):
        assert_close(model.inertial_dynamics(x, U, pi, g, c), model.dynamics(x, U, p), 1e-11,
                     "Hummingbird", k)


def _random_pi(rng):
    return combine([box(rng.uniform(0.3, 2.0), rng.uniform(0.1, 0.5, 3),
                        rng.uniform(-0.05, 0.05, 3)),
                    point_mass(rng.uniform(0.05, 0.5), rng.uniform(-0.2, 0.2, 3))])


def _lhs(model, x, U, v, pi, g, c):
    """M(pi) v + C(nu, pi) nu + g_G(pi) from the dynamics: with nu_dot the accelerations of
    inertial_dynamics, M nu_dot + C nu + g_G = B_u U - D nu, so the left-hand side at v is
    M (v - nu_dot) + B_u U - D nu."""
    nu_dot = model.inertial_dynamics(x, U, pi, g, c)[6:]
    return model.inertial_mass_matrix(pi) @ (v - nu_dot) + B_U @ U - c * x[6:]


def test_Y_is_the_jacobian_in_pi(model, points):
    rng = np.random.default_rng(7)
    for k, (x, U, p, v) in enumerate(points[:40]):
        pi, g, c = _random_pi(rng), p[IDX["g"]], p[IDX["c_x"]:IDX["c_psi"] + 1]
        Y = model.inertial_regressor(x, v, g)
        lhs = _lhs(model, x, U, v, pi, g, c)
        assert_close(Y @ pi, lhs, 1e-10, "Y pi vs the left-hand side of the dynamics", k)
        step = 1e-4 * np.maximum(np.abs(pi), 1e-3)      # small: pi stays consistent
        fd = np.empty((6, N_PI))
        for j in range(N_PI):
            e = np.zeros(N_PI)
            e[j] = step[j]
            fd[:, j] = (_lhs(model, x, U, v, pi + e, g, c)
                        - _lhs(model, x, U, v, pi - e, g, c)) / (2 * step[j])
        assert_close(fd, Y, 1e-8, "central differences vs Y", k)


def test_truth_model_flies_the_same_body(model, points):
    """truth_dynamics (full I_O through p and I_products, no wrench) of the body pi is
    inertial_dynamics: the same rigid body, reached once through r_G and once through h."""
    rng = np.random.default_rng(11)
    for k, (x, U, p, _) in enumerate(points[:40]):
        pi, g, c = _random_pi(rng), p[IDX["g"]], p[IDX["c_x"]:IDX["c_psi"] + 1]
        m, h = pi[0], pi[1:4]
        Ixx, Ixy, Iyy, Ixz, Iyz, Izz = pi[4:]
        p_truth = np.array([m, g, Ixx, Iyy, Izz, *c, *(h / m)])
        assert_close(model.truth_dynamics(x, U, p_truth, [Ixy, Ixz, Iyz], np.zeros(6)),
                     model.inertial_dynamics(x, U, pi, g, c), 1e-11, "truth vs inertial", k)


def test_bad_p_and_pi_are_typed_errors(model):
    """A string or a ragged list as p or pi: quadcog's InputError naming the argument, not
    numpy's ValueError from converting it."""
    x, U = np.zeros(12), np.zeros(4)
    for bad in ("abc", [1.0, "a"] + [1.0] * 12, [[1.0, 2.0], [3.0]]):
        with pytest.raises(quadcog.InputError, match=r"^p\b"):
            model.dynamics(x, U, bad)
        with pytest.raises(quadcog.InputError, match=r"^pi\b"):
            model.inertial_mass_matrix(bad)
