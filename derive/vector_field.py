"""The 12-state control-affine vector field x_dot = f(x) + g(x) U."""
import sympy as sp

from derive.newton_euler import solve_accelerations
from derive.symbols import U, nu, nu1, nu2


def vector_field(R, Q, body):
    """Return (f, G): drift (12x1) and input matrix (12x4), with I_G^{-1} as placeholders."""
    n = body.C * nu + body.D * nu + body.g_G
    eta_dot = sp.Matrix.vstack(R * nu1, Q * nu2)
    f = sp.Matrix.vstack(eta_dot, solve_accelerations(body, -n))
    G = sp.Matrix.vstack(sp.zeros(6, 4), solve_accelerations(body, body.B_u))
    return f, G


def dynamics(f, G):
    """x_dot = f + G U."""
    return f + G * U
