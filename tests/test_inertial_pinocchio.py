"""The model in the ten inertial parameters against two oracles that share nothing with
derive/: Pinocchio (a second rigid-body library: its joint-torque regressor, RNEA, CRBA and
ABA on a free-flyer joint) and a rigid body made of point masses, whose wrench about O is
summed particle by particle from Newton's law in this file.

The mapping to Pinocchio, which the tests use as it is:
- the free-flyer's configuration is q = [position of O in ground axes; quaternion (x, y, z, w)
  of R], R = Rz(psi) Ry(theta) Rx(phi) our rotation (body to ground);
- its velocity is the spatial velocity of the body in body axes, [v; omega] = [nu1; nu2] (the
  same order as nu), and its acceleration the derivative of those body components, nu_dot;
- its joint torque is the wrench at O in body axes, [force; moment about O] = the left-hand
  side M nu_dot + C nu + g_G of our equations (drag excluded: D nu is not in Y);
- ``Inertia.FromDynamicParameters`` and ``computeJointTorqueRegressor`` use
  [m, m c_x, m c_y, m c_z, Ixx, Ixy, Iyy, Ixz, Iyz, Izz] about the joint origin: our pi, in
  our order, with no permutation (checked below on one body).
"""
from conftest import assert_close
import numpy as np
import pinocchio as pin
import pytest

from quadcog.model.conventions import B_U, rotation_matrix
from quadcog.model.inertial_parameters import box, combine, point_mass
from quadcog.model.sampling import random_state

RTOL = 1e-12
N = 60


def _random_pi(rng):
    """A consistent pi: a box (the frame) plus 1 to 4 point masses, all off O."""
    parts = [box(rng.uniform(0.2, 2.0), rng.uniform(0.05, 0.5, 3), rng.uniform(-0.05, 0.05, 3))]
    parts += [point_mass(rng.uniform(0.01, 0.5), rng.uniform(-0.2, 0.2, 3))
              for _ in range(rng.integers(1, 5))]
    return combine(parts)


def _pinocchio(pi, g):
    """A free-flyer joint carrying one body with inertial parameters pi at its origin."""
    model = pin.Model()
    joint = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "vehicle")
    model.appendBodyToJoint(joint, pin.Inertia.FromDynamicParameters(pi), pin.SE3.Identity())
    model.gravity = pin.Motion(np.array([0.0, 0.0, -g, 0.0, 0.0, 0.0]))
    return model, model.createData()


def _configuration(x):
    R = rotation_matrix(*x[3:6])
    return np.concatenate([x[:3], pin.Quaternion(R).coeffs()])


@pytest.fixture(scope="module")
def cases():
    rng = np.random.default_rng(20)
    return [(random_state(rng), rng.uniform(-5, 5, 6), rng.uniform(9.0, 10.5), _random_pi(rng),
             rng.uniform(0, 20), rng.uniform(-1, 1, 3), rng.uniform(0, 0.5, 6))
            for _ in range(N)]


def test_parameter_order_is_pinocchios():
    pi = _random_pi(np.random.default_rng(1))
    inertia = pin.Inertia.FromDynamicParameters(pi)
    assert_close(inertia.toDynamicParameters(), pi, 1e-14, "round trip")
    assert inertia.mass == pytest.approx(pi[0], rel=1e-15)
    assert_close(inertia.lever * inertia.mass, pi[1:4], 1e-14, "m c = h")
    # inertia about O from Pinocchio's inertia about the CoM, by the parallel-axis theorem
    c = inertia.lever
    I_O = inertia.inertia + inertia.mass * (c @ c * np.eye(3) - np.outer(c, c))
    assert_close(I_O[[0, 0, 1, 0, 1, 2], [0, 1, 1, 2, 2, 2]], pi[4:], 1e-14, "I_O entries")


def test_euler_angles_are_pinocchios_rpy(cases):
    for x, *_ in cases:
        assert_close(pin.rpy.rpyToMatrix(*x[3:6]), rotation_matrix(*x[3:6]), 1e-15, "R")


def test_regressor_is_pinocchios(model, cases):
    for k, (x, nu_dot, g, pi, *_) in enumerate(cases):
        pm, pd = _pinocchio(pi, g)
        q = _configuration(x)
        expected = pin.computeJointTorqueRegressor(pm, pd, q, x[6:], nu_dot)
        Y = model.inertial_regressor(x, nu_dot, g)
        assert_close(Y, expected, RTOL, "Y vs computeJointTorqueRegressor", k)
        assert_close(Y @ pi, pin.rnea(pm, pd, q, x[6:], nu_dot), RTOL, "Y pi vs rnea", k)


def test_gravity_in_body_axes(model, cases):
    """The same wrench with the body level in Pinocchio (identity quaternion) and gravity
    given in body axes, R^T [0, 0, -g]: Y sees gravity only through the attitude."""
    for k, (x, nu_dot, g, pi, *_) in enumerate(cases[:20]):
        pm, pd = _pinocchio(pi, g)
        R = rotation_matrix(*x[3:6])
        pm.gravity = pin.Motion(np.concatenate([R.T @ [0.0, 0.0, -g], np.zeros(3)]))
        level = np.concatenate([x[:3], [0.0, 0.0, 0.0, 1.0]])
        assert_close(model.inertial_regressor(x, nu_dot, g) @ pi,
                     pin.rnea(pm, pd, level, x[6:], nu_dot), RTOL, "Y pi vs rnea (body g)", k)


def test_mass_matrix_is_crba(model, cases):
    for k, (x, _, g, pi, *_) in enumerate(cases):
        pm, pd = _pinocchio(pi, g)
        M = pin.crba(pm, pd, _configuration(x))
        M = np.triu(M) + np.triu(M, 1).T          # crba fills the upper triangle
        assert_close(model.inertial_mass_matrix(pi), M, RTOL, "M vs crba", k)


def test_dynamics_is_aba(model, cases):
    """nu_dot of inertial_dynamics is Pinocchio's forward dynamics (ABA) under the wrench
    B_u U - D nu; the kinematic rows are R nu1 and the Euler-angle rates of nu2."""
    for k, (x, nu_dot, g, pi, U1, moments, c) in enumerate(cases):
        U = np.concatenate([[U1], moments])
        pm, pd = _pinocchio(pi, g)
        tau = B_U @ U - c * x[6:]
        expected = pin.aba(pm, pd, _configuration(x), x[6:], tau)
        xdot = model.inertial_dynamics(x, U, pi, g, c)
        assert_close(xdot[6:], expected, 1e-10, "nu_dot vs aba", k)
        assert_close(xdot[:3], rotation_matrix(*x[3:6]) @ x[6:9], RTOL, "eta1_dot", k)


def _particle_wrench(masses, points, x, nu_dot, g):
    """Sum over particles i of [m_i (a_i - g_b); r_i x m_i (a_i - g_b)], about O in body
    axes: a_i = nu1_dot + nu2_dot x r_i + nu2 x (nu1 + nu2 x r_i) is the acceleration of a
    particle fixed in the body at r_i, g_b the gravity in body axes."""
    nu1, nu2 = x[6:9], x[9:]
    g_b = rotation_matrix(*x[3:6]).T @ [0.0, 0.0, -g]
    wrench = np.zeros(6)
    for m_i, r_i in zip(masses, points):
        a_i = nu_dot[:3] + np.cross(nu_dot[3:], r_i) + np.cross(nu2, nu1 + np.cross(nu2, r_i))
        f_i = m_i * (a_i - g_b)
        wrench += np.concatenate([f_i, np.cross(r_i, f_i)])
    return wrench


def test_regressor_against_point_masses(model, cases):
    rng = np.random.default_rng(3)
    for k, (x, nu_dot, g, *_) in enumerate(cases):
        masses, points = rng.uniform(0.01, 1.0, 6), rng.uniform(-0.3, 0.3, (6, 3))
        pi = combine([point_mass(m_i, r_i) for m_i, r_i in zip(masses, points)])
        assert_close(model.inertial_regressor(x, nu_dot, g) @ pi,
                     _particle_wrench(masses, points, x, nu_dot, g), RTOL,
                     "Y pi vs the particle sum", k)
