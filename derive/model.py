"""Assemble the whole derivation into one object, stage by stage."""
from dataclasses import dataclass, field
import time

import sympy as sp

from . import symbols as sym
from .kinematics import kinematics
from .lie import OutputDerivatives, output_derivatives
from .linearization import linearization
from .newton_euler import RigidBody, inverse_inertia_definition, rigid_body
from .regressor import regressor
from .vector_field import dynamics, vector_field


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
    inv = inverse_inertia_definition(body.I_G)
    placeholders = {s: inv[i, j] for s, (i, j) in zip(
        sym.I_G_INV_SYMBOLS, [(i, j) for i in range(3) for j in range(i, 3)])}
    f, G = stage("vector field", vector_field, R, Q, body)
    xdot = dynamics(f, G)
    Phi = stage("regressor", regressor, body)
    outputs = stage("lie derivatives", output_derivatives, f, G, placeholders)
    A, B = stage("linearization", linearization, xdot)
    return DerivedModel(R, Q, J, body, f, G, xdot, Phi, outputs, A, B, placeholders, timings)
