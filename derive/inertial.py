"""The Newton-Euler equations linear in the ten inertial parameters about O (docs/model.md
sec. 7).

pi = [m, h_x, h_y, h_z, Ixx, Ixy, Iyy, Ixz, Iyz, Izz] with the first moment of mass
h = m r_G and the full inertia about O (Pinocchio's ``Inertia.toDynamicParameters`` order).
Nothing is derived anew: the rigid body of ``newton_euler.rigid_body`` with the full I_O
(the truth model's) is rewritten by substituting r_G = h / m. About O, every r_G in Euler's
axioms and in g_G comes multiplied by m (the force m nu2 x (nu2 x r_G), the momentum
m r_G x nu1, the moment r_G x f_G with f_G proportional to m), so the result is a polynomial
linear in pi, and Y = d/dpi [M nu_dot + C(nu) nu + g_G] is exact. ``inertial_model`` proves
that, and how the paper's model and its regressor Phi follow from it.
"""
from dataclasses import dataclass, fields

import sympy as sp

from derive import symbols as sym
from derive.newton_euler import RigidBody
from derive.vector_field import dynamics, vector_field


@dataclass(frozen=True)
class InertialModel:
    """The model in pi; matrices may contain the I_G^{-1} placeholders."""

    body: RigidBody        # M, C, D, g_G, I_G, ... in pi (D and B_u as before)
    Y: sp.Matrix           # 6x10 inertial regressor in x and nu_dot (NU_DOT), free of pi
    xdot: sp.Matrix        # 12x1 state derivative in x, U, pi, g, c
    I_G_inv: dict          # placeholder -> definition in pi
    paper_pi: sp.Matrix    # pi of the paper's model: [m, m r_G, Ixx, 0, Iyy, 0, 0, Izz]


def in_inertial_parameters(body):
    """``body`` (with a full I_O) with r_G = h / m substituted and expanded, field by field."""
    to_h = {s: hs / sym.m for s, hs in zip(sym.r_G, sym.h)}
    return RigidBody(**{f.name: getattr(body, f.name).xreplace(to_h).applyfunc(sp.expand)
                        for f in fields(body)})


def paper_inertial_parameters():
    """pi of the paper's model, in the symbols of p: m, m r_G and diag(Ixx, Iyy, Izz)."""
    return sp.Matrix([sym.m, *(sym.m * sym.r_G), sym.Ixx, 0, sym.Iyy, 0, 0, sym.Izz])


def inertial_regressor(body):
    """Y (6x10) = d/dpi [M nu_dot + C(nu) nu + g_G] of the body in pi; raises AssertionError
    unless the left-hand side is linear in pi (Y free of pi and Y pi equal to it)."""
    lhs = (body.M * sym.NU_DOT + body.C * sym.nu + body.g_G).applyfunc(sp.expand)
    pi = list(sym.inertial)
    for k, e in enumerate(lhs):
        if not e.is_polynomial(*pi):
            raise AssertionError(f"row {k + 1} of M nu_dot + C nu + g_G is not a polynomial "
                                 f"in pi: {e}")
    Y = lhs.jacobian(sym.inertial)
    if Y.free_symbols & set(pi):
        raise AssertionError(f"Y depends on pi: {Y.free_symbols & set(pi)}")
    if (Y * sym.inertial - lhs).applyfunc(sp.expand) != sp.zeros(6, 1):
        raise AssertionError("Y pi is not M nu_dot + C nu + g_G")
    return Y


def special_case_check(Y, body_pi, paper_body, Phi, paper_xdot, xdot):
    """Prove that the paper's model is the special case pi = paper_pi (m, m r_G, diag I_O):

    - Y paper_pi = M vartheta + C nu + g_G of the paper's body, with nu_dot = vartheta;
    - Phi = m [Y_2, Y_3, Y_4] (columns of h): with m and I_O held, pi depends on r_G only
      through h = m r_G, so d(Y pi)/dr_G = Y d(pi)/dr_G = m Y[:, 1:4];
    - I_G and the state derivative in pi equal the paper's at pi = paper_pi.
    """
    at_paper = dict(zip(sym.inertial, paper_inertial_parameters()))
    to_vartheta = dict(zip(sym.NU_DOT, sym.vartheta))
    Y_v = Y.xreplace(to_vartheta)
    paper_lhs = paper_body.M * sym.vartheta + paper_body.C * sym.nu + paper_body.g_G
    if (Y_v * paper_inertial_parameters() - paper_lhs).applyfunc(sp.expand) != sp.zeros(6, 1):
        raise AssertionError("Y paper_pi is not the paper's M vartheta + C nu + g_G")
    if (sym.m * Y_v[:, 1:4] - Phi).applyfunc(sp.expand) != sp.zeros(6, 3):
        raise AssertionError("Phi is not m times the h columns of Y")
    if (body_pi.I_G.xreplace(at_paper) - paper_body.I_G).applyfunc(sp.expand) != sp.zeros(3, 3):
        raise AssertionError("I_G in pi at the paper's pi is not the paper's I_G")
    # Same I_G, so the same I_G^{-1} placeholders stand for the same values on both sides.
    if (xdot.xreplace(at_paper) - paper_xdot).applyfunc(sp.expand) != sp.zeros(12, 1):
        raise AssertionError("the dynamics in pi at the paper's pi are not the paper's")


def inertial_model(R, Q, general_body, paper_body, Phi, paper_xdot, placeholders):
    """Derive the model in pi from the full-I_O body ``general_body`` (see the module text);
    ``placeholders(body)`` gives the I_G^{-1} definitions of a body."""
    body = in_inertial_parameters(general_body)
    leftover = set().union(*(getattr(body, f.name).free_symbols for f in fields(body)))
    if leftover & set(sym.r_G):
        raise AssertionError("r_G is left in the body in pi")
    Y = inertial_regressor(body)
    f, G = vector_field(R, Q, body)
    xdot = dynamics(f, G)
    special_case_check(Y, body, paper_body, Phi, paper_xdot, xdot)
    return InertialModel(body, Y, xdot, placeholders(body), paper_inertial_parameters())
