"""The model on SE(3) against the Euler model where both are valid, against textbook formulas
written here (Rodrigues' rotation, R_dot = R S(omega)), numerical differentiation, and its
refusal of attitudes that are not one."""
from conftest import assert_close
import numpy as np
import pytest

from quadcog.errors import AttitudeError, InputError, PhysicalConsistencyError
from quadcog.model.attitude import euler_of_rotation, quaternion_of_euler
from quadcog.model.conventions import rotation_matrix
from quadcog.model.inertial_parameters import box, combine, point_mass
from quadcog.model.sampling import random_state

N = 40


def _pi(rng):
    return combine([box(rng.uniform(0.3, 1.5), rng.uniform(0.1, 0.4, 3), np.zeros(3)),
                    point_mass(rng.uniform(0.05, 0.4), rng.uniform(-0.15, 0.15, 3))])


def _skew(a):
    return np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


def test_same_as_euler_model_where_both_are_valid(model):
    """At q = q(eta): Y and nu_dot of the Euler model, the position rate R nu1, and q_dot the
    derivative of q(eta(t)) along the Euler rates of inertial_dynamics."""
    rng = np.random.default_rng(8)
    for k in range(N):
        x, pi = random_state(rng), _pi(rng)
        g, c = rng.uniform(9, 10.5), rng.uniform(0, 0.5, 6)
        U, nu_dot = rng.uniform(-2, 12, 4), rng.uniform(-5, 5, 6)
        q = quaternion_of_euler(*x[3:6])
        xq = np.concatenate([x[:3], q, x[6:]])
        R = rotation_matrix(*x[3:6])
        assert_close(model.se3_regressor(R, x[6:], nu_dot, g),
                     model.inertial_regressor(x, nu_dot, g), 1e-13, "Y", k)
        euler = model.inertial_dynamics(x, U, pi, g, c)
        se3 = model.se3_dynamics(xq, U, pi, g, c)
        assert_close(se3[7:], euler[6:], 1e-12, "nu_dot", k)
        assert_close(se3[:3], euler[:3], 1e-13, "position rate", k)
        h = 1e-6
        dq = (quaternion_of_euler(*(x[3:6] + h * euler[3:6]))
              - quaternion_of_euler(*(x[3:6] - h * euler[3:6]))) / (2 * h)
        assert_close(se3[3:7], dq, 1e-8, "q_dot vs d/dt q(eta)", k)


def test_rotation_is_rodrigues(model):
    """q = [cos(a/2), sin(a/2) n] rotates by a about n: R = I + sin a S(n) + (1 - cos a) S(n)^2."""
    rng = np.random.default_rng(2)
    for k in range(N):
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        a = rng.uniform(-np.pi, np.pi)
        q = np.concatenate([[np.cos(a / 2)], np.sin(a / 2) * n])
        S = _skew(n)
        assert_close(model.quaternion_rotation(q),
                     np.eye(3) + np.sin(a) * S + (1 - np.cos(a)) * S @ S, 1e-15, "R(q)", k)


def test_quaternion_rate_gives_body_rates(model):
    """(R(q + h q_dot) - R(q - h q_dot)) / 2h = R S(omega), and q_dot keeps |q|."""
    rng = np.random.default_rng(4)
    pi = _pi(rng)
    for k in range(N):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        xq = np.concatenate([np.zeros(3), q, rng.uniform(-3, 3, 6)])
        q_dot = model.se3_dynamics(xq, np.zeros(4), pi, 9.81, np.zeros(6))[3:7]
        assert abs(q @ q_dot) < 1e-14
        h = 1e-6
        dR = (model.quaternion_rotation((q + h * q_dot) / np.linalg.norm(q + h * q_dot))
              - model.quaternion_rotation((q - h * q_dot) / np.linalg.norm(q - h * q_dot)))
        assert_close(dR / (2 * h), model.quaternion_rotation(q) @ _skew(xq[10:]), 1e-8,
                     "R_dot", k)


def test_euler_chart_round_trip(model):
    """euler_of_rotation inverts R(eta) on the chart, and at and near gimbal lock still gives
    angles whose R is the rotation (phi and psi alone are not defined there)."""
    rng = np.random.default_rng(6)
    for k in range(N):
        eta = random_state(rng)[3:6]
        assert_close(euler_of_rotation(rotation_matrix(*eta)), eta, 1e-13, "eta", k)
    for theta in (np.pi / 2, -np.pi / 2, np.pi / 2 - 1e-9, np.pi / 2 - 1e-13):
        R = rotation_matrix(0.3, theta, -1.1)
        assert_close(rotation_matrix(*euler_of_rotation(R)), R, 1e-12, f"R at theta={theta}")


@pytest.mark.parametrize("bad, what", [
    (np.diag([1.0, 1.0, -1.0]), "det R"),                     # a reflection
    (2 * np.eye(3), "R^T R"),                                  # a scaled rotation
    (np.eye(3) + 1e-3, "R^T R"),
    (np.zeros((3, 3)), "R^T R"),
])
def test_refuses_a_matrix_that_is_no_rotation(model, bad, what):
    with pytest.raises(AttitudeError, match=r"R: expected a rotation matrix.*" + what.replace("^", r"\^")):
        model.se3_regressor(bad, np.zeros(6), np.zeros(6), 9.81)


def test_refuses_a_rotation_of_the_wrong_shape_or_not_finite(model):
    with pytest.raises(InputError, match="R"):
        model.se3_regressor(np.eye(2), np.zeros(6), np.zeros(6), 9.81)
    R = np.eye(3)
    R[0, 0] = np.nan
    with pytest.raises(InputError, match="R"):
        model.se3_regressor(R, np.zeros(6), np.zeros(6), 9.81)
    with pytest.raises(InputError, match="R"):
        model.se3_regressor("not a matrix", np.zeros(6), np.zeros(6), 9.81)


@pytest.mark.parametrize("q", [[0.0, 0.0, 0.0, 0.0], [2.0, 0.0, 0.0, 0.0], [0.9, 0.1, 0.0, 0.0]])
def test_refuses_a_quaternion_that_is_not_unit(model, q):
    with pytest.raises(AttitudeError, match=r"quaternion.*\|q\| = "):
        model.quaternion_rotation(q)
    xq = np.concatenate([np.zeros(3), q, np.zeros(6)])
    pi = _pi(np.random.default_rng(0))
    with pytest.raises(AttitudeError, match=r"xq\[3:7\]"):
        model.se3_dynamics(xq, np.zeros(4), pi, 9.81, np.zeros(6))


def test_se3_dynamics_checks_pi_and_g(model):
    xq = np.concatenate([np.zeros(3), [1.0, 0, 0, 0], np.zeros(6)])
    pi = _pi(np.random.default_rng(0))
    with pytest.raises(PhysicalConsistencyError):
        model.se3_dynamics(xq, np.zeros(4), -pi, 9.81, np.zeros(6))
    with pytest.raises(InputError, match="g"):
        model.se3_dynamics(xq, np.zeros(4), pi, 0.0, np.zeros(6))
    with pytest.raises(InputError, match="wrench"):
        model.se3_dynamics(xq, np.zeros(4), pi, 9.81, np.zeros(6), np.zeros(5))


@pytest.mark.parametrize("bad", [
    np.eye(3, dtype=bool),                          # was cast: True, False read as 1, 0
    np.eye(3) + 1e-3j,                              # was cast: the imaginary part dropped
    [[True, False, False], [False, True, False], [False, False, True]],
    [[1.0, 0.0, 0.0], [0.0, 1.0], [0.0, 0.0, 1.0]],  # ragged: np.size raised a raw ValueError
])
def test_refuses_a_rotation_of_booleans_complex_numbers_or_ragged_rows(model, bad):
    """R goes through validate.array as every other argument does, never a cast to float."""
    with pytest.raises(InputError, match=r"^R(\[[0-9, ]+\])?: expected"):
        model.se3_regressor(bad, np.zeros(6), np.zeros(6), 9.81)
