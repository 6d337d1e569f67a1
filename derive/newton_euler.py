"""Rigid-body dynamics about the rotor-plane centre O with the CoG at r_G (body frame).

Everything starts from Euler's two axioms written with cross products; M is read off as
the Jacobian of the equations with respect to nu_dot, and C(nu) is built from M by
Fossen's theorem (Handbook of Marine Craft Hydrodynamics, Thm 3.2), which makes it
skew-symmetric; ``coriolis_check`` proves C(nu) nu equals the Newton-Euler terms.
"""
from dataclasses import dataclass

import sympy as sp

from derive.symbols import (
    NU_DOT,
    I_G_inv,
    Ixx,
    Iyy,
    Izz,
    c_phi,
    c_psi,
    c_theta,
    c_x,
    c_y,
    c_z,
    g,
    m,
    nu,
    nu1,
    nu2,
    r_G,
    skew,
)


@dataclass(frozen=True)
class RigidBody:
    """The terms of M nu_dot + C(nu) nu + D nu + g_G(eta) = B_u U (docs/model.md sec. 1.3;
    paper eq. 3)."""

    newton_euler: sp.Matrix   # left-hand side of the two axioms, 6x1, in nu_dot and nu
    M: sp.Matrix              # 6x6 mass matrix
    C: sp.Matrix              # 6x6 skew-symmetric Coriolis-centripetal matrix
    D: sp.Matrix              # 6x6 damping
    g_G: sp.Matrix            # 6x1 gravity forces and moments
    B_u: sp.Matrix            # 6x4 input matrix
    f_G: sp.Matrix            # 3x1 weight in body axes
    I_O: sp.Matrix            # 3x3 inertia about O (held constant, docs/model.md sec. 1.3)
    I_G: sp.Matrix            # 3x3 inertia about the CoG, I_O - m (|r|^2 I - r r^T)


def newton_euler_lhs(I_O):
    """Left-hand sides of Euler's first and second axioms, about O, in body components.

    First axiom: m a_G = f with v_G = nu1 + nu2 x r_G and r_G fixed in the body, so
    a_G = nu1_dot + nu2_dot x r_G + nu2 x v_G.
    Second axiom about the moving point O: h_O = I_O nu2 + m r_G x nu1, and
    d/dt h_O + nu2 x h_O + nu1 x (m v_G) = m_O.
    """
    nu1_dot, nu2_dot = NU_DOT[:3, :], NU_DOT[3:, :]
    v_G = nu1 + nu2.cross(r_G)
    force = m * (nu1_dot + nu2_dot.cross(r_G) + nu2.cross(v_G))
    h_O = I_O * nu2 + m * r_G.cross(nu1)
    h_O_dot = I_O * nu2_dot + m * r_G.cross(nu1_dot)
    moment = h_O_dot + nu2.cross(h_O) + nu1.cross(m * v_G)
    return sp.Matrix.vstack(force, moment).applyfunc(sp.expand)


def velocity_terms(M):
    """C(nu) nu in cross products, not expanded: with the momenta a = M11 nu1 + M12 nu2
    (= m v_G) and b = M21 nu1 + M22 nu2 (= h_O, about O), C(nu) nu = [nu2 x a;
    nu2 x b + nu1 x a] (Fossen's theorem, as ``coriolis_from_mass_matrix`` builds C).

    The same polynomial as ``C * nu`` (``factored_check`` proves it) in about a third of
    the operations: the simulators evaluate it four times per RK4 step, the laws once.
    """
    a = M[:3, :3] * nu1 + M[:3, 3:] * nu2
    b = M[3:, :3] * nu1 + M[3:, 3:] * nu2
    return sp.Matrix.vstack(nu2.cross(a), nu2.cross(b) + nu1.cross(a))


def factored_check(factored, expanded, what):
    """Prove symbolically that a factored form is the expanded one, term by term."""
    residual = (factored - expanded).applyfunc(sp.expand)
    if residual != sp.zeros(*residual.shape):
        raise AssertionError(f"the factored {what} is not the expanded one: {residual.T}")


def coriolis_from_mass_matrix(M):
    """Fossen Thm 3.2: C = [[0, -S(M11 nu1 + M12 nu2)], [-S(M11 nu1 + M12 nu2), -S(M21 nu1 + M22 nu2)]]."""
    a = M[:3, :3] * nu1 + M[:3, 3:] * nu2
    b = M[3:, :3] * nu1 + M[3:, 3:] * nu2
    Sa, Sb = skew(a), skew(b)
    return sp.Matrix.vstack(sp.Matrix.hstack(sp.zeros(3, 3), -Sa),
                            sp.Matrix.hstack(-Sa, -Sb)).applyfunc(sp.expand)


def rigid_body(R, I_O=None):
    """Derive M, C, D, g_G and B_u; ``R`` is the body-to-ground rotation.

    ``I_O`` defaults to diag(Ixx, Iyy, Izz), the paper's (and the controller's) model.
    """
    I_O = sp.diag(Ixx, Iyy, Izz) if I_O is None else I_O
    lhs = newton_euler_lhs(I_O)
    M = lhs.jacobian(NU_DOT)
    C = coriolis_from_mass_matrix(M)
    D = sp.diag(c_x, c_y, c_z, c_phi, c_theta, c_psi)
    f_G = R.T * sp.Matrix([0, 0, -m * g])
    g_G = -sp.Matrix.vstack(f_G, r_G.cross(f_G))
    # Thrust U1 along body z at O, moments U2..U4 about O (docs/model.md sec. 2.2).
    B_u = sp.Matrix.vstack(sp.zeros(2, 4), sp.eye(4))
    I_G = (I_O - m * ((r_G.T * r_G)[0] * sp.eye(3) - r_G * r_G.T)).applyfunc(sp.expand)
    body = RigidBody(lhs, M, C, D, g_G, B_u, f_G, I_O, I_G)
    coriolis_check(body)
    return body


def coriolis_check(body):
    """Prove symbolically that M nu_dot + C(nu) nu is the Newton-Euler left-hand side."""
    residual = (body.M * NU_DOT + body.C * nu - body.newton_euler).applyfunc(sp.expand)
    if residual != sp.zeros(6, 1):
        raise AssertionError(f"C(nu) nu does not reproduce the Newton-Euler terms: {residual.T}")
    if (body.C + body.C.T).applyfunc(sp.expand) != sp.zeros(6, 6):
        raise AssertionError("C(nu) is not skew-symmetric")


def solve_accelerations(body, rhs):
    """nu_dot = M^{-1} rhs by block elimination, with I_G^{-1} kept as placeholders.

    With M = [[m I, -m S(r)], [m S(r), I_O]], the Schur complement of m I is
    I_O + m S(r)^2 = I_G, so nu2_dot = I_G^{-1} (rhs2 - r x rhs1) and
    nu1_dot = rhs1 / m + r x nu2_dot. No symbolic 6x6 inverse is ever formed.
    """
    schur = (body.M[3:, 3:] - body.M[3:, :3] * body.M[:3, 3:] / m).applyfunc(sp.expand)
    if schur != body.I_G:
        raise AssertionError("Schur complement of the mass matrix is not I_G")
    rhs1, rhs2 = rhs[:3, :], rhs[3:, :]
    nu2_dot = I_G_inv * (rhs2 - body.M[3:, :3] * rhs1 / m)
    nu1_dot = rhs1 / m - body.M[:3, 3:] * nu2_dot / m
    return sp.Matrix.vstack(nu1_dot, nu2_dot)


def solve_accelerations_factored(body, rhs):
    """``solve_accelerations`` written with cross products: nu2_dot = I_G^{-1} (rhs2 -
    r_G x rhs1), nu1_dot = rhs1 / m + r_G x nu2_dot (M's off-diagonal blocks are
    -m S(r_G) and m S(r_G), checked here), for an ``rhs`` that is one column."""
    if (body.M[3:, :3] - m * skew(r_G)).applyfunc(sp.expand) != sp.zeros(3, 3) or \
            (body.M[:3, 3:] + m * skew(r_G)).applyfunc(sp.expand) != sp.zeros(3, 3):
        raise AssertionError("the mass matrix's off-diagonal blocks are not -+m S(r_G)")
    rhs1, rhs2 = rhs[:3, :], rhs[3:, :]
    nu2_dot = I_G_inv * (rhs2 - r_G.cross(rhs1))
    return sp.Matrix.vstack(rhs1 / m + r_G.cross(nu2_dot), nu2_dot)


def inverse_inertia_definition(I_G):
    """The 3x3 I_G^{-1} (adjugate over determinant) that the placeholders stand for."""
    return I_G.adjugate() / I_G.det(method="berkowitz")
