"""Assemble the whole derivation into one object, stage by stage."""
from dataclasses import dataclass, field
import time

import sympy as sp

from derive import symbols as sym
from derive.inertial import InertialModel, inertial_model
from derive.kinematics import kinematics
from derive.lie import OutputDerivatives, output_derivatives
from derive.linearization import linearization
from derive.newton_euler import (
    RigidBody,
    factored_check,
    inverse_inertia_definition,
    rigid_body,
    solve_accelerations,
    solve_accelerations_factored,
    velocity_terms,
)
from derive.regressor import regressor
from derive.se3 import SE3Model, se3_model
from derive.vector_field import dynamics, vector_field


@dataclass
class DerivedModel:
    """Every derived object; matrices may contain the I_G^{-1} placeholders."""

    R: sp.Matrix
    Q: sp.Matrix
    J: sp.Matrix
    body: RigidBody
    f: sp.Matrix
    G: sp.Matrix
    xdot: sp.Matrix
    Phi: sp.Matrix
    outputs: OutputDerivatives
    A: sp.Matrix
    B: sp.Matrix
    I_G_inv: dict                          # placeholder symbol -> definition in p
    M_inv: sp.Matrix                       # 6x6 inverse mass matrix by block elimination
    xdot_general: sp.Matrix                # truth model: products of inertia, external wrench
    I_G_inv_general: dict                  # placeholders for that model
    inertial: InertialModel                # the model linear in the ten inertial parameters
    se3: SE3Model                          # the same body on SE(3) (quaternion, R)
    timings: dict = field(default_factory=dict)

    def substituted(self, expr):
        """``expr`` with the I_G^{-1} placeholders replaced by their definition."""
        return expr.xreplace(self.I_G_inv)


def derive_model(log=None):
    """Run the derivation; ``log(stage, seconds)`` is called after every stage."""
    timings = {}

    def stage(name, fn, *args):
        t0 = time.perf_counter()
        out = fn(*args)
        timings[name] = time.perf_counter() - t0
        if log:
            log(name, timings[name])
        return out

    R, Q, J = stage("kinematics", kinematics)
    body = stage("newton-euler", rigid_body, R)
    placeholders = _placeholders(body)
    f, G = stage("vector field", vector_field, R, Q, body)
    xdot = dynamics(f, G)
    general_body, *general = stage("truth model (full I_O)", _general_inertia_dynamics, R, Q)
    Phi = stage("regressor", regressor, body)
    inertial = stage("inertial parameters", inertial_model, R, Q, general_body, body, Phi,
                     xdot, _placeholders)
    se3 = stage("SE(3) (quaternion)", se3_model, R, inertial)
    outputs = stage("lie derivatives", output_derivatives, f, G, placeholders)
    A, B = stage("linearization", linearization, xdot)
    M_inv = solve_accelerations(body, sp.eye(6))
    return DerivedModel(R, Q, J, body, f, G, xdot, Phi, outputs, A, B, placeholders, M_inv,
                        *general, inertial, se3, timings)


def _placeholders(body):
    """I_G^{-1} placeholder symbol -> its definition (adjugate / determinant of I_G)."""
    inv = inverse_inertia_definition(body.I_G)
    upper = [(i, j) for i in range(3) for j in range(i, 3)]
    return {s: inv[i, j] for s, (i, j) in zip(sym.I_G_INV_SYMBOLS, upper)}


def _general_inertia_dynamics(R, Q):
    """The truth model: the same derivation with a full symmetric I_O (diagonal from p,
    products extra) and an external wrench [F (ground axes, at O); M (body axes)]; returns
    (the rigid body, x_dot, its I_G^{-1} placeholders).

    Written as the simulators evaluate it, four times per RK4 step: every generalized force
    (rotors, wrench, drag, gravity, C(nu) nu in Newton-Euler's cross products) summed first,
    then one block elimination in cross products. It is proved here, term by term, to be the
    control-affine form f + G U of the same body plus the wrench's accelerations.
    """
    body = rigid_body(R, sym.I_O_full)
    placeholders = _placeholders(body)
    Cnu = velocity_terms(body.M)
    factored_check(Cnu, body.C * sym.nu, "C(nu) nu")
    tau_ext = sp.Matrix.vstack(R.T * sym.wrench[:3, :], sym.wrench[3:, :])
    rhs = body.B_u * sym.U + tau_ext - Cnu - body.D * sym.nu - body.g_G
    xdot = sp.Matrix.vstack(R * sym.nu1, Q * sym.nu2, solve_accelerations_factored(body, rhs))
    f, G = vector_field(R, Q, body)
    f_ext = sp.Matrix.vstack(sp.zeros(6, 1), solve_accelerations(body, tau_ext))
    factored_check(xdot, dynamics(f, G) + f_ext, "truth model")
    return body, xdot, placeholders
