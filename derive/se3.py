"""The rigid body in the ten inertial parameters on SE(3) (docs/model.md sec. 8): the attitude
as a rotation matrix R or a unit quaternion q instead of ZYX Euler angles, the velocities in
body axes as before.

Nothing about the body is derived anew: Euler's axioms about O (``newton_euler.rigid_body``)
see the attitude only through the weight in body axes, R^T [0, 0, -m g], so the body is built
with R a matrix of nine symbols, rewritten in pi (``inertial.in_inertial_parameters``) and its
regressor taken as in ``inertial.inertial_regressor``. What is new is the kinematics of the
quaternion, derived here from the quaternion product and proved:

- R(q) is read off q (0, v) q^* = |q|^2 R(q) v; R(q)^T R(q) = I and det R(q) = 1 for every
  q != 0 (R(q) is a rotation for any nonzero q, so an integrator's drift of |q| never
  leaves SO(3));
- q_dot = q (0, nu2) / 2 gives d/dt R(q) = R(q) S(nu2) (body rates) and keeps |q|;
- with R = R(eta) (ZYX) the regressor is the Euler model's Y and nu_dot that of
  ``inertial_dynamics``: the two models agree wherever the Euler one is valid.
"""
from dataclasses import dataclass

import sympy as sp

from derive import symbols as sym
from derive.inertial import in_inertial_parameters, inertial_regressor
from derive.newton_euler import RigidBody, rigid_body, solve_accelerations


@dataclass(frozen=True)
class SE3Model:
    """The model on SE(3); matrices may contain the I_G^{-1} placeholders of pi."""

    R_q: sp.Matrix          # 3x3 R(q) = J(q) / |q|^2, body to ground
    q_dot: sp.Matrix        # 4x1 quaternion rate in q and nu2
    body: RigidBody         # the rigid body in pi with the attitude as the nine symbols of R
    Y: sp.Matrix            # 6x10 regressor in R, nu, nu_dot (gravity g)
    xdot: sp.Matrix         # 13x1 state derivative in [eta1; q; nu], U, pi, g, c, wrench
    I_G_inv: dict           # placeholder -> definition in pi


def quaternion_product(a, b):
    """The Hamilton product a b of two quaternions [w, x, y, z]."""
    aw, av = a[0], a[1:, :]
    bw, bv = b[0], b[1:, :]
    return sp.Matrix.vstack(sp.Matrix([aw * bw - (av.T * bv)[0]]),
                            aw * bv + bw * av + av.cross(bv))


def conjugate(q):
    """q^* = [w, -x, -y, -z]."""
    return sp.Matrix([q[0], -q[1], -q[2], -q[3]])


def rotation_of_quaternion(q):
    """(J, n): q (0, v) q^* = [0; J v] with J = n R(q), n = |q|^2 (J read off as a Jacobian)."""
    v = sp.Matrix(sp.symbols("v_1:4", real=True))
    rotated = quaternion_product(quaternion_product(q, sp.Matrix.vstack(sp.zeros(1, 1), v)),
                                 conjugate(q)).applyfunc(sp.expand)
    if rotated[0] != 0:
        raise AssertionError("q (0, v) q^* has a scalar part")
    J = rotated[1:, :].jacobian(v)
    if J.free_symbols & set(v):
        raise AssertionError("q (0, v) q^* is not linear in v")
    return J, (q.T * q)[0]


def rotation_check(J, n):
    """Prove J^T J = n^2 I and det J = n^3, polynomial identities: J / n is a rotation for any
    q != 0."""
    if (J.T * J - n**2 * sp.eye(3)).applyfunc(sp.expand) != sp.zeros(3, 3):
        raise AssertionError("R(q)^T R(q) is not I")
    if sp.expand(J.det(method="berkowitz") - n**3) != 0:
        raise AssertionError("det R(q) is not 1")


def quaternion_rate(q, omega):
    """q_dot = q (0, omega) / 2: omega in body axes (R_dot = R S(omega))."""
    return (quaternion_product(q, sp.Matrix.vstack(sp.zeros(1, 1), omega)) / 2
            ).applyfunc(sp.expand)


def kinematics_check(q, q_dot, J, n, omega):
    """Prove, as polynomial identities along q_dot: d|q|^2/dt = 0 and dJ/dt = J S(omega), so
    d/dt (J / n) = R(q) S(omega)."""
    n_dot = sp.expand((sp.Matrix([n]).jacobian(q) * q_dot)[0])
    if n_dot != 0:
        raise AssertionError(f"|q|^2 changes along q_dot: {n_dot}")
    J_dot = sp.Matrix(3, 3, lambda i, j: (sp.Matrix([J[i, j]]).jacobian(q) * q_dot)[0])
    if (J_dot - J * sym.skew(omega)).applyfunc(sp.expand) != sp.zeros(3, 3):
        raise AssertionError("d/dt R(q) is not R(q) S(omega)")


def se3_model(R_euler, euler_inertial):
    """Derive the model on SE(3) (see the module text); ``R_euler`` is the ZYX R(eta) and
    ``euler_inertial`` the Euler model in pi (``inertial.InertialModel``), which it must
    reproduce at R = R(eta)."""
    q, omega = sym.quaternion, sym.nu2
    J, n = rotation_of_quaternion(q)
    rotation_check(J, n)
    q_dot = quaternion_rate(q, omega)
    kinematics_check(q, q_dot, J, n, omega)
    R_q = J / n

    body = in_inertial_parameters(rigid_body(sym.R_matrix, sym.I_O_full))
    Y = inertial_regressor(body)
    if (body.I_G - euler_inertial.body.I_G).applyfunc(sp.expand) != sp.zeros(3, 3):
        raise AssertionError("I_G in pi on SE(3) is not the Euler model's")
    # The force of the wrench is in ground axes (as in truth_dynamics), its moment in body axes.
    tau_ext = sp.Matrix.vstack(sym.R_matrix.T * sym.wrench[:3, :], sym.wrench[3:, :])
    n_terms = body.C * sym.nu + body.D * sym.nu + body.g_G
    nu_dot = solve_accelerations(body, body.B_u * sym.U + tau_ext - n_terms)
    xdot_R = sp.Matrix.vstack(sym.R_matrix * sym.nu1, q_dot, nu_dot)

    to_euler = dict(zip(sym.R_entries, R_euler))
    if (Y.xreplace(to_euler) - euler_inertial.Y).applyfunc(sp.expand) != sp.zeros(6, 10):
        raise AssertionError("Y on SE(3) at R = R(eta) is not the Euler model's Y")
    no_wrench = dict.fromkeys(sym.wrench, 0)
    euler_nu_dot = euler_inertial.xdot[6:, :]
    if (nu_dot.xreplace(to_euler).xreplace(no_wrench) - euler_nu_dot).applyfunc(sp.expand) \
            != sp.zeros(6, 1):
        raise AssertionError("nu_dot on SE(3) at R = R(eta) is not the Euler model's")

    xdot = xdot_R.xreplace(dict(zip(sym.R_entries, R_q)))
    return SE3Model(R_q, q_dot, body, Y, xdot, euler_inertial.I_G_inv)
