"""The model on SE(3) (docs/model.md sec. 8) against Pinocchio's free-flyer, a library that
shares nothing with derive/: its joint-torque regressor, RNEA, ABA, quaternion and
configuration integrator, over random attitudes drawn uniformly on SO(3) and attitudes at and
beyond 90 degrees of pitch, where the Euler model cannot go.

The mapping (as in tests/test_inertial_pinocchio.py): Pinocchio's configuration is
[position of O in ground axes; quaternion (x, y, z, w)], ours [position; (w, x, y, z)]; its
velocity is [nu1; nu2] in body axes, its joint torque the wrench at O in body axes.
"""
from conftest import assert_close
import numpy as np
import pinocchio as pin
import pytest

from quadcog.model.conventions import B_U
from quadcog.model.inertial_parameters import box, combine, point_mass

RTOL = 1e-12
N = 60
PITCH_DEG = (89.0, 89.999999, 90.0, 90.000001, 91.0, 120.0, 179.0, 180.0, -90.0, -135.0)


def _random_pi(rng):
    parts = [box(rng.uniform(0.2, 2.0), rng.uniform(0.05, 0.5, 3), rng.uniform(-0.05, 0.05, 3))]
    parts += [point_mass(rng.uniform(0.01, 0.5), rng.uniform(-0.2, 0.2, 3))
              for _ in range(rng.integers(1, 5))]
    return combine(parts)


def _pinocchio(pi, g):
    model = pin.Model()
    joint = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "vehicle")
    model.appendBodyToJoint(joint, pin.Inertia.FromDynamicParameters(pi), pin.SE3.Identity())
    model.gravity = pin.Motion(np.array([0.0, 0.0, -g, 0.0, 0.0, 0.0]))
    return model, model.createData()


def _pitched(pitch_deg, rng):
    """A unit quaternion (w, x, y, z) with a pitch of pitch_deg about the body y axis after a
    random yaw, and a small random roll: the flip's attitudes."""
    half = np.radians(pitch_deg) / 2
    q_pitch = pin.Quaternion(np.cos(half), 0.0, np.sin(half), 0.0)
    yaw = rng.uniform(-np.pi, np.pi) / 2
    roll = rng.uniform(-1e-3, 1e-3) / 2
    q = (pin.Quaternion(np.cos(yaw), 0.0, 0.0, np.sin(yaw)) * q_pitch
         * pin.Quaternion(np.cos(roll), np.sin(roll), 0.0, 0.0))
    return np.array([q.w, q.x, q.y, q.z])


def _uniform_quaternion(rng):
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


@pytest.fixture(scope="module")
def cases():
    rng = np.random.default_rng(31)
    attitudes = [_uniform_quaternion(rng) for _ in range(N)]
    attitudes += [_pitched(a, rng) for a in PITCH_DEG]
    out = []
    for q in attitudes:
        xq = np.concatenate([rng.uniform(-5, 5, 3), q, rng.uniform(-3, 3, 6)])
        out.append((xq, rng.uniform(-5, 5, 6), rng.uniform(9.0, 10.5), _random_pi(rng),
                    np.concatenate([[rng.uniform(0, 20)], rng.uniform(-1, 1, 3)]),
                    rng.uniform(0, 0.5, 6), rng.uniform(-2, 2, 6)))
    return out


def _configuration(xq):
    w, x, y, z = xq[3:7]
    return np.concatenate([xq[:3], [x, y, z, w]])


def test_quaternion_rotation_is_pinocchios(model, cases):
    for k, (xq, *_) in enumerate(cases):
        w, x, y, z = xq[3:7]
        expected = pin.Quaternion(w, x, y, z).toRotationMatrix()
        assert_close(model.quaternion_rotation(xq[3:7]), expected, 1e-15, "R(q)", k)


def test_regressor_is_pinocchios(model, cases):
    worst = 0.0
    for k, (xq, nu_dot, g, pi, *_) in enumerate(cases):
        pm, pd = _pinocchio(pi, g)
        q = _configuration(xq)
        R = model.quaternion_rotation(xq[3:7])
        Y = model.se3_regressor(R, xq[7:], nu_dot, g)
        expected = pin.computeJointTorqueRegressor(pm, pd, q, xq[7:], nu_dot)
        worst = max(worst, assert_close(Y, expected, RTOL, "Y vs computeJointTorqueRegressor",
                                        k))
        worst = max(worst, assert_close(Y @ pi, pin.rnea(pm, pd, q, xq[7:], nu_dot), RTOL,
                                        "Y pi vs rnea", k))
    print(f"SE(3) regressor vs Pinocchio: worst relative error {worst:.2e}")


def test_dynamics_is_aba(model, cases):
    """nu_dot of se3_dynamics is Pinocchio's ABA under B_u U - D nu plus the external wrench
    (its force turned into body axes); the position rate is R(q) nu1."""
    worst = 0.0
    for k, (xq, _, g, pi, U, c, wrench) in enumerate(cases):
        pm, pd = _pinocchio(pi, g)
        R = model.quaternion_rotation(xq[3:7])
        tau = B_U @ U - c * xq[7:] + np.concatenate([R.T @ wrench[:3], wrench[3:]])
        expected = pin.aba(pm, pd, _configuration(xq), xq[7:], tau)
        xq_dot = model.se3_dynamics(xq, U, pi, g, c, wrench)
        worst = max(worst, assert_close(xq_dot[7:], expected, RTOL, "nu_dot vs aba", k))
        assert_close(xq_dot[:3], R @ xq[7:10], RTOL, "position rate", k)
    print(f"SE(3) nu_dot vs Pinocchio's aba: worst relative error {worst:.2e}")


def test_configuration_rate_is_pinocchios_integrator(model, cases):
    """[position rate; q_dot] is the derivative of Pinocchio's integrate(q, nu t) at t = 0
    (central differences, h = 1e-6: error O(h^2) and rounding O(eps / h))."""
    h = 1e-6
    for k, (xq, _, g, pi, U, c, wrench) in enumerate(cases):
        pm, _ = _pinocchio(pi, g)
        q0 = _configuration(xq)
        plus, minus = (pin.integrate(pm, q0, s * h * xq[7:]) for s in (1.0, -1.0))
        d = (plus - minus) / (2 * h)
        xq_dot = model.se3_dynamics(xq, U, pi, g, c, wrench)
        assert_close(xq_dot[:3], d[:3], 1e-8, "position rate vs integrate", k)
        assert_close(xq_dot[3:7], [d[6], d[3], d[4], d[5]], 1e-8, "q_dot vs integrate", k)
