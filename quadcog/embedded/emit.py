"""Straight-line C from a CasADi SX Function, in float or double.

CasADi's own code generator writes double literals and calls sin/cos even with
casadi_real=float, so a float32 build promotes to double (software double on a Cortex-M4).
Here every instruction of the SX algorithm becomes one C statement on a local scalar (the
operations and the walk are quadcog.codegen.sx_to_c's, shared with the vector kernel): float
literals with an f suffix and sinf/cosf/fminf/... for float32, 15-digit literals for double.
The output depends only on the algorithm, so it is byte-reproducible.
"""
from collections.abc import Sequence
import functools

import casadi as ca
import numpy as np

from quadcog.codegen import sx_to_c as sxc
from quadcog.errors import ExportError

__all__ = ["PRECISIONS", "C_TYPE", "DOUBLE_DIGITS", "literal", "target", "body"]

PRECISIONS = ("double", "float32")
C_TYPE = {"double": "double", "float32": "float"}
# significant digits of the double constants. The gains, the mixer's inverse and the Lyapunov
# matrix are computed in exact arithmetic (quadcog.numerics), so they are the same bits on
# every CPU; 15 digits keep the text short and change no result by more than 1e-15 relative.
DOUBLE_DIGITS = 15


def literal(value: float, precision: str) -> str:
    """A C literal of ``value`` in the given precision (reproducible text).

    Parameters
    ----------
    value : float
        The constant.
    precision : str
        'float32' (shortest round-trip float with an f suffix) or 'double'
        (``DOUBLE_DIGITS`` significant digits).

    Returns
    -------
    str
        The C literal.

    Raises
    ------
    quadcog.errors.ExportError
        When ``value`` is not finite.
    """
    value = float(value)
    if not np.isfinite(value):
        raise ExportError(f"constant {value} in the expression is not finite")
    if precision == "float32":
        return sxc.float32_literal(value)
    text = f"{value:.{DOUBLE_DIGITS - 1}e}"
    mantissa, exponent = text.split("e")
    mantissa = mantissa.rstrip("0")
    mantissa = mantissa + "0" if mantissa.endswith(".") else mantissa
    exp = int(exponent)
    return f"{mantissa}e{exp}" if exp else mantissa


@functools.cache
def target(precision: str) -> sxc.Target:
    """The ``quadcog.codegen.sx_to_c.Target`` of a precision.

    Parameters
    ----------
    precision : str
        One of ``PRECISIONS``.

    Returns
    -------
    quadcog.codegen.sx_to_c.Target
        Its literals, sinf/fminf... in float32, fmin and fmax as calls (the C library's,
        exact on any target).

    Raises
    ------
    quadcog.errors.ExportError
        For an unknown precision.
    """
    if precision not in PRECISIONS:
        raise ExportError(f"precision must be one of {PRECISIONS}, got {precision!r}")
    return sxc.Target(literal=functools.partial(literal, precision=precision),
                      suffix="f" if precision == "float32" else "", selects=False,
                      error=ExportError)


def body(fn: ca.Function, precision: str, arg_names: Sequence[str], res_names: Sequence[str],
         indent: str = "    ") -> tuple[list[str], list[str], set[int]]:
    """C lines evaluating the SX Function ``fn``.

    Each work-vector slot of CasADi's algorithm is one local scalar ``w<k>`` (CasADi already
    reuses slots), so the work space is fixed and small.

    Parameters
    ----------
    fn : casadi.Function
        An SX Function.
    precision : str
        One of ``PRECISIONS``.
    arg_names : sequence of str
        Input i, nonzero j is read as ``arg_names[i][j]`` (as ``arg_names[i]`` when the input
        is a scalar).
    res_names : sequence of str
        Output i, nonzero j is written to ``res_names[i][j]``.
    indent : str
        Put before every line.

    Returns
    -------
    tuple of (list of str, list of str, set of int)
        (declarations, statements, indices of the inputs read).

    Raises
    ------
    quadcog.errors.ExportError
        When ``fn`` is not an SX Function, or for an operation without a C form (named).
    """
    if not isinstance(fn, ca.Function) or not fn.is_a("SXFunction"):
        raise ExportError(f"expected an SX Function, got {fn!r}")
    scalar = lambda i: fn.numel_in(i) == 1
    c = sxc.walk(fn, target(precision),
                 read=lambda i, nz: arg_names[i] if scalar(i) else f"{arg_names[i]}[{nz}]",
                 write=lambda i, nz: f"{res_names[i]}[{nz}]")
    slots = sorted(c.slots)
    decls = []
    for start in range(0, len(slots), 12):
        names = ", ".join(f"w{n}" for n in slots[start:start + 12])
        decls.append(f"qc_real {names};")
    return [indent + d for d in decls], [indent + s for s in c.statements], c.inputs
