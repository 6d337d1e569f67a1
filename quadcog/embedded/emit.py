"""Straight-line C from a CasADi SX Function, in float or double.

CasADi's own code generator writes double literals and calls sin/cos even with
casadi_real=float, so a float32 build promotes to double (software double on a Cortex-M4).
Here every instruction of the SX algorithm becomes one C statement on a local scalar: float
literals with an f suffix and sinf/cosf/... for float32, full round-trip literals for double.
The output depends only on the algorithm, so it is byte-reproducible.
"""
import casadi as ca
import numpy as np

from ..errors import QuadcogError


class ExportError(QuadcogError):
    """A controller cannot be exported: the message names the controller and the reason."""


PRECISIONS = ("double", "float32")
C_TYPE = {"double": "double", "float32": "float"}
# significant digits of the double constants: gains come out of LAPACK (pole placement, the
# Lyapunov equation), whose last bit may differ between CPUs; 15 digits keep the file the same
# everywhere and change no result by more than 1e-15 relative.
DOUBLE_DIGITS = 15

_UNARY = {ca.OP_SQRT: "sqrt", ca.OP_SIN: "sin", ca.OP_COS: "cos", ca.OP_TAN: "tan",
          ca.OP_ASIN: "asin", ca.OP_ACOS: "acos", ca.OP_ATAN: "atan", ca.OP_EXP: "exp",
          ca.OP_LOG: "log", ca.OP_FABS: "fabs", ca.OP_FLOOR: "floor", ca.OP_CEIL: "ceil",
          ca.OP_SINH: "sinh", ca.OP_COSH: "cosh", ca.OP_TANH: "tanh", ca.OP_ERF: "erf"}
_BINARY_FN = {ca.OP_ATAN2: "atan2", ca.OP_FMIN: "fmin", ca.OP_FMAX: "fmax", ca.OP_POW: "pow",
              ca.OP_CONSTPOW: "pow", ca.OP_FMOD: "fmod", ca.OP_COPYSIGN: "copysign",
              ca.OP_HYPOT: "hypot"}
_BINARY_OP = {ca.OP_ADD: "+", ca.OP_SUB: "-", ca.OP_MUL: "*", ca.OP_DIV: "/"}
_COMPARE = {ca.OP_LT: "<", ca.OP_LE: "<=", ca.OP_EQ: "==", ca.OP_NE: "!="}


def literal(value, precision):
    """A C literal of ``value`` in the given precision (reproducible text)."""
    value = float(value)
    if not np.isfinite(value):
        raise ExportError(f"constant {value} in the expression is not finite")
    if precision == "float32":
        text = np.format_float_scientific(np.float32(value), unique=True, trim="0")
        mantissa, exponent = text.split("e")
        exp = int(exponent)
        mantissa = mantissa if "." in mantissa else mantissa + ".0"
        return f"{mantissa}e{exp}f" if exp else f"{mantissa}f"
    text = f"{value:.{DOUBLE_DIGITS - 1}e}"
    mantissa, exponent = text.split("e")
    mantissa = mantissa.rstrip("0")
    mantissa = mantissa + "0" if mantissa.endswith(".") else mantissa
    exp = int(exponent)
    return f"{mantissa}e{exp}" if exp else mantissa


def body(fn, precision, arg_names, res_names, indent="    "):
    """(declarations, statements, inputs read): C lines evaluating the SX Function ``fn``.

    Input i, nonzero j is read as ``arg_names[i][j]`` (as ``arg_names[i]`` when the input is a
    scalar); output i, nonzero j is written to ``res_names[i][j]``. Each work-vector slot of CasADi's algorithm is one local scalar
    ``w<k>`` (CasADi already reuses slots), so the work space is fixed and small."""
    if not isinstance(fn, ca.Function) or not fn.is_a("SXFunction"):
        raise ExportError(f"expected an SX Function, got {fn!r}")
    suffix = "f" if precision == "float32" else ""
    one, zero = literal(1.0, precision), literal(0.0, precision)
    used, read = set(), set()
    lines = []
    for k in range(fn.n_instructions()):
        op = fn.instruction_id(k)
        i = fn.instruction_input(k)
        o = fn.instruction_output(k)
        w = lambda n: f"w{n}"
        if op == ca.OP_INPUT:
            src = (arg_names[i[0]] if fn.numel_in(i[0]) == 1 else
                   f"{arg_names[i[0]]}[{i[1]}]")
            lines.append(f"{w(o[0])} = {src};")
            used.add(o[0])
            read.add(i[0])
            continue
        if op == ca.OP_OUTPUT:
            lines.append(f"{res_names[o[0]]}[{o[1]}] = {w(i[0])};")
            continue
        used.add(o[0])
        if op == ca.OP_CONST:
            rhs = literal(fn.instruction_constant(k), precision)
        elif op == ca.OP_ASSIGN:
            rhs = w(i[0])
        elif op in _BINARY_OP:
            rhs = f"{w(i[0])} {_BINARY_OP[op]} {w(i[1])}"
        elif op == ca.OP_NEG:
            rhs = f"-{w(i[0])}"
        elif op == ca.OP_SQ:
            rhs = f"{w(i[0])} * {w(i[0])}"
        elif op == ca.OP_TWICE:
            rhs = f"{w(i[0])} + {w(i[0])}"
        elif op == ca.OP_INV:
            rhs = f"{one} / {w(i[0])}"
        elif op in _UNARY:
            rhs = f"{_UNARY[op]}{suffix}({w(i[0])})"
        elif op in _BINARY_FN:
            rhs = f"{_BINARY_FN[op]}{suffix}({w(i[0])}, {w(i[1])})"
        elif op in _COMPARE:
            rhs = f"({w(i[0])} {_COMPARE[op]} {w(i[1])}) ? {one} : {zero}"
        elif op == ca.OP_NOT:
            rhs = f"({w(i[0])} == {zero}) ? {one} : {zero}"
        elif op == ca.OP_AND:
            rhs = f"({w(i[0])} != {zero} && {w(i[1])} != {zero}) ? {one} : {zero}"
        elif op == ca.OP_OR:
            rhs = f"({w(i[0])} != {zero} || {w(i[1])} != {zero}) ? {one} : {zero}"
        elif op == ca.OP_IF_ELSE_ZERO:
            rhs = f"({w(i[0])} != {zero}) ? {w(i[1])} : {zero}"
        elif op == ca.OP_SIGN:
            rhs = (f"({w(i[0])} > {zero}) ? {one} : "
                   f"(({w(i[0])} < {zero}) ? -{one} : {w(i[0])})")
        else:
            raise ExportError(f"{fn.name()}: CasADi operation {op} (instruction {k}) has no "
                              "C translation here; rewrite the law without it")
        lines.append(f"{w(o[0])} = {rhs};")
    slots = sorted(used)
    decls = []
    for start in range(0, len(slots), 12):
        names = ", ".join(f"w{n}" for n in slots[start:start + 12])
        decls.append(f"qc_real {names};")
    return [indent + d for d in decls], [indent + s for s in lines], read
