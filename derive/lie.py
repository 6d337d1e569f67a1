"""Lie derivatives for the outputs y = h(x) = [z, phi, theta, psi]; relative degree,
decoupling matrix alpha = L_g L_f h and drift b = L_f^2 h (paper sec. 3.2,
docs/model.md sec. 2.4)."""
from dataclasses import dataclass
import random

import sympy as sp

from derive.contract import output_symbols
from derive.symbols import state

OUTPUTS = sp.Matrix(output_symbols())


@dataclass(frozen=True)
class OutputDerivatives:
    h: sp.Matrix                  # 4x1 outputs
    L_g_h: sp.Matrix              # 4x4, zero
    L_f_h: sp.Matrix              # 4x1
    alpha: sp.Matrix              # 4x4 decoupling matrix L_g L_f h
    b: sp.Matrix                  # 4x1 drift L_f^2 h
    relative_degree: tuple        # one entry per output


def lie_derivative(expr, field):
    """L_field expr = d expr / dx * field; field may have several columns."""
    return expr.jacobian(state) * field


def _is_identically_zero(row, placeholders, rng):
    """Exact zero, or zero at random rational points and then after expansion.

    ``placeholders`` maps the I_G^{-1} symbols to their definition in the parameters,
    so that a random point is a consistent one.
    """
    if all(e == 0 for e in row):
        return True
    free = set().union(*(e.free_symbols for e in row)) - set(placeholders)
    for _ in range(3):
        point = {s: sp.Rational(rng.randint(1, 97), 101) for s in sorted(free, key=str)}
        point.update({s: d.subs(point) for s, d in placeholders.items()})
        if any(sp.N(e.subs(point)) != 0 for e in row):
            return False
    return all(sp.expand(e.subs(placeholders)) == 0 for e in row)


def relative_degree(h, f, G, placeholders, max_order=None):
    """Smallest k with L_g L_f^{k-1} h_i not identically zero, computed per output."""
    rng = random.Random(0)
    max_order = max_order or len(state)
    degrees = []
    for i in range(h.rows):
        lf = h[i:i + 1, :]
        for k in range(1, max_order + 1):
            if not _is_identically_zero(lie_derivative(lf, G), placeholders, rng):
                degrees.append(k)
                break
            lf = lie_derivative(lf, f)
        else:
            raise AssertionError(f"output {h[i]} has no relative degree up to {max_order}")
    return tuple(degrees)


def output_derivatives(f, G, placeholders):
    """All output derivatives; ``placeholders`` as in ``relative_degree``."""
    h = OUTPUTS
    L_g_h = lie_derivative(h, G)
    L_f_h = lie_derivative(h, f)
    alpha = lie_derivative(L_f_h, G)
    b = lie_derivative(L_f_h, f)
    rd = relative_degree(h, f, G, placeholders)
    return OutputDerivatives(h, L_g_h, L_f_h, alpha, b, rd)
