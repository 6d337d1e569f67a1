"""The feedback linearization's linear step, shared by the laws that invert alpha(q).

The outputs y = [z, phi, theta, psi] obey y_ddot = alpha(q) U + b(q, nu) (paper sec. 3.2,
docs/model.md). A law asks for y_ddot = v and solves ``alpha U = v - b``.

``decoupled_input`` solves that 4x4 system by Gaussian elimination in the outputs' order,
without pivoting. alpha = H M^-1 B_U is the inverse mass matrix seen through the output rates:
about the hover it is diagonal (1/m, 1/I_xx, 1/I_yy, 1/I_zz) with the CoG offset in its
off-diagonal entries, and its pivots in this order are the z row's thrust gain (cos phi
cos theta / m at r_G = 0) and the attitude rows' inverse inertias. They vanish only where the
law itself has no useful solution (a tilt of 90 deg, where thrust no longer reaches z): U is
then not finite and the flight's divergence rule stops it, where a QR factorization, on an
alpha kept barely regular by the CoG offset's coupling, would give an enormous input.

Why not CasADi's symbolic ``solve``: it is a Gram-Schmidt QR, 182 operations, 4 of them
square roots and 20 divisions, on the step's longest chain of dependencies; the elimination
is 62, whose 10 divisions are by the four pivots (a compiled kernel multiplies by their
reciprocals). Over the law's working range it is also the more accurate of the two
(``tests/test_decoupling.py`` holds it within 2e-15 of the exact solution, and every law
within 1e-9 of its QR-solved form).

``linearizing_terms`` gives alpha and b of an estimated model from the pieces that the
adaptive update needs anyway (M_hat^-1, n_hat and H M_hat^-1): alpha = H M^-1 B_U and
b = (d y_dot / d eta) eta_dot - H M^-1 n, the chain rule of y_dot = H nu. They are the
generated ``decoupling`` and ``drift`` functions up to rounding (within 1e-12 relative,
``tests/test_decoupling.py``), and the adaptive law is 157 operations shorter for it.

``inverse_mass_matrix`` forms M_hat^-1 from its blocks. An adaptive law's r_hat changes every
step, so M_hat^-1 is computed every step; the generated ``inverse_mass_matrix`` writes each
entry as a polynomial in (m, r_G, I_O) over I_G's determinant, and the blocks take less than
half of its operations (``tests/test_decoupling.py`` counts both).
"""
from dataclasses import dataclass

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog.controllers.shaping import kinematics
from quadcog.model.conventions import B_U, IDX, NU, R_G
from quadcog.model.functions import Model

__all__ = ["decoupled_input", "inverse_mass_matrix", "LinearizingTerms", "linearizing_terms"]


def decoupled_input(alpha: ca.SX, rhs: ca.SX) -> ca.SX:
    """U with ``alpha U = rhs``, by elimination in the outputs' order (module docstring).

    Parameters
    ----------
    alpha : casadi.SX
        The decoupling matrix (4x4), rows per output [z, phi, theta, psi], columns per input.
    rhs : casadi.SX
        ``v - b`` (4x1) [m/s^2, rad/s^2].

    Returns
    -------
    casadi.SX
        U (4x1) [U1 (N), U2, U3, U4 (N m)]; not finite where a pivot is zero.
    """
    n = alpha.shape[0]
    a = [[alpha[i, j] for j in range(n)] for i in range(n)]
    y = [rhs[i] for i in range(n)]
    inverse = []
    for k in range(n):
        inverse.append(1.0 / a[k][k])
        for i in range(k + 1, n):
            factor = a[i][k] * inverse[k]
            for j in range(k + 1, n):
                a[i][j] = a[i][j] - factor * a[k][j]
            y[i] = y[i] - factor * y[k]
    U = [ca.SX(0)] * n
    for i in reversed(range(n)):
        s = y[i]
        for j in range(i + 1, n):
            s = s - a[i][j] * U[j]
        U[i] = s * inverse[i]
    return ca.vertcat(*U)


def inverse_mass_matrix(p: ca.SX | ca.DM | npt.NDArray[np.float64]) -> ca.SX:
    """M^-1 (6x6) of the parameter vector p, from its blocks (module docstring).

    M = [[m I, -m S(r)], [m S(r), I_O]] with S(r) the cross-product matrix of r = r_G and I_O
    = diag(Ixx, Iyy, Izz) about O. The Schur complement of m I is the inertia about the CoG,
    I_G = I_O - m (|r|^2 I - r r^T), and with G = I_G^-1 (adjugate over determinant)

        M^-1 = [[I / m - S G S, S G], [-G S, G]].

    Parameters
    ----------
    p : casadi.SX or casadi.DM or (14,) numpy.ndarray
        Parameter vector (order ``PARAM_NAMES``), e.g. the nominal one with the CoG estimate.

    Returns
    -------
    casadi.SX
        M^-1 (6x6); the generated ``inverse_mass_matrix`` up to rounding
        (``tests/test_decoupling.py``).
    """
    p = ca.SX(p)
    m = p[IDX["m"]]
    rx, ry, rz = (p[i] for i in range(R_G.start, R_G.stop))
    rr = rx * rx + ry * ry + rz * rz
    # I_G (symmetric): diagonal a, b, c; off-diagonal d (xy), e (xz), f (yz)
    a = p[IDX["Ixx"]] - m * (rr - rx * rx)
    b = p[IDX["Iyy"]] - m * (rr - ry * ry)
    c = p[IDX["Izz"]] - m * (rr - rz * rz)
    d, e, f = m * (rx * ry), m * (rx * rz), m * (ry * rz)
    # its adjugate (symmetric) and determinant, by the first column's cofactors
    A11, A22, A33 = b * c - f * f, a * c - e * e, a * b - d * d
    A12, A13, A23 = e * f - d * c, d * f - b * e, d * e - a * f
    k = 1.0 / (a * A11 + d * A12 + e * A13)
    G = ca.blockcat([[A11 * k, A12 * k, A13 * k],
                     [A12 * k, A22 * k, A23 * k],
                     [A13 * k, A23 * k, A33 * k]])
    GS = G @ ca.skew(ca.vertcat(rx, ry, rz))       # G S; S G = -(G S)^T since S^T = -S
    return ca.blockcat([[ca.SX.eye(3) / m + GS.T @ ca.skew(ca.vertcat(rx, ry, rz)), -GS.T],
                        [-GS, G]])


@dataclass(frozen=True)
class LinearizingTerms:
    """What the feedback linearization on an estimated model computes (``linearizing_terms``).

    Parameters
    ----------
    M_inv : casadi.SX
        M_hat^-1 (6x6).
    n : casadi.SX
        n_hat = C nu + D nu + G (6x1), so that M nu_dot = B_U U - n.
    HM : casadi.SX
        H M_hat^-1 (4x6), H = d y_dot / d nu.
    alpha : casadi.SX
        H M_hat^-1 B_U (4x4).
    b : casadi.SX
        (d y_dot / d eta) eta_dot - H M_hat^-1 n (4x1).
    """

    M_inv: ca.SX
    n: ca.SX
    HM: ca.SX
    alpha: ca.SX
    b: ca.SX


def linearizing_terms(model: Model, x: ca.SX,
                      p: ca.SX | ca.DM | npt.NDArray[np.float64]) -> LinearizingTerms:
    """alpha and b at x for parameters p, from M^-1, n and H M^-1 (module docstring).

    Parameters
    ----------
    model : quadcog.model.functions.Model
        The generated functions.
    x : casadi.SX
        State (12,) [m, rad, m/s, rad/s].
    p : casadi.SX or casadi.DM or (14,) numpy.ndarray
        Parameter vector, e.g. the nominal one with the CoG estimate.

    Returns
    -------
    LinearizingTerms
        M_inv, n, HM, alpha and b.
    """
    f = model.casadi_function
    nu = x[NU]
    M_inv = inverse_mass_matrix(p)
    n = f("coriolis")(x, p) @ nu + f("damping")(p) @ nu + f("gravity")(x, p)
    eta_dot, y_dot = kinematics(model, x, p)
    HM = ca.jacobian(y_dot, x)[:, NU] @ M_inv
    alpha = HM @ ca.DM(B_U)
    b = ca.jacobian(y_dot, x[:6]) @ eta_dot - HM @ n
    return LinearizingTerms(M_inv, n, HM, alpha, b)
