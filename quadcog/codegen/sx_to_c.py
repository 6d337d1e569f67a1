"""C from a CasADi SX Function: the one table of operations and the walk over its instructions.

Both C emitters of quadcog use this module: ``quadcog.embedded.emit`` (straight-line C99 for a
flight controller, in double or float32) and ``quadcog.codegen.vector_kernel`` (the vectorized
batch kernel, flights in the vector lanes). Every instruction of the SX algorithm becomes one
C statement on a local scalar ``w<slot>`` (CasADi's work-vector slots, already reused). What
differs between the two is a ``Target``: how constants are written (and so the literals 1 and 0
of the logic), the suffix of the math functions (``sinf`` for float32), and whether fmin/fmax
are calls or selects; how inputs are read and outputs written is given to ``walk`` by the
caller.

Logic (comparisons, not, and, or, if_else_zero, sign) is written as selects on the floating
type, never as _Bool or int temporaries: a select vectorizes, and it is valid C99 on a
flight controller.
"""
from collections.abc import Callable
from dataclasses import dataclass
import re

import casadi as ca
import numpy as np

from quadcog.errors import QuadcogError

__all__ = ["CALL", "OPERATIONS", "SELECTS", "Target", "Walk", "op_name", "template", "walk"]

# operation -> C expression of the operands {0}, {1}; {one} and {zero} are the target's literals
# of 1 and 0; {f} is the suffix of the math functions ("f" in float32: sinf, fminf).
OPERATIONS = {
    ca.OP_ASSIGN: "{0}",
    ca.OP_ADD: "{0} + {1}", ca.OP_SUB: "{0} - {1}", ca.OP_MUL: "{0} * {1}",
    ca.OP_DIV: "{0} / {1}",
    ca.OP_NEG: "-{0}", ca.OP_SQ: "{0} * {0}", ca.OP_TWICE: "{0} + {0}",
    ca.OP_INV: "{one} / {0}",
    ca.OP_LT: "({0} < {1}) ? {one} : {zero}", ca.OP_LE: "({0} <= {1}) ? {one} : {zero}",
    ca.OP_EQ: "({0} == {1}) ? {one} : {zero}", ca.OP_NE: "({0} != {1}) ? {one} : {zero}",
    ca.OP_NOT: "({0} == {zero}) ? {one} : {zero}",
    ca.OP_AND: "({0} != {zero} && {1} != {zero}) ? {one} : {zero}",
    ca.OP_OR: "({0} != {zero} || {1} != {zero}) ? {one} : {zero}",
    ca.OP_IF_ELSE_ZERO: "({0} != {zero}) ? {1} : {zero}",
    ca.OP_SIGN: "({0} > {zero}) ? {one} : (({0} < {zero}) ? -{one} : {0})",
    ca.OP_SQRT: "sqrt{f}({0})", ca.OP_FABS: "fabs{f}({0})",
    ca.OP_FLOOR: "floor{f}({0})", ca.OP_CEIL: "ceil{f}({0})",
    ca.OP_SIN: "sin{f}({0})", ca.OP_COS: "cos{f}({0})", ca.OP_TAN: "tan{f}({0})",
    ca.OP_ASIN: "asin{f}({0})", ca.OP_ACOS: "acos{f}({0})", ca.OP_ATAN: "atan{f}({0})",
    ca.OP_SINH: "sinh{f}({0})", ca.OP_COSH: "cosh{f}({0})", ca.OP_TANH: "tanh{f}({0})",
    ca.OP_EXP: "exp{f}({0})", ca.OP_LOG: "log{f}({0})", ca.OP_ERF: "erf{f}({0})",
    ca.OP_ATAN2: "atan2{f}({0}, {1})", ca.OP_HYPOT: "hypot{f}({0}, {1})",
    ca.OP_POW: "pow{f}({0}, {1})", ca.OP_CONSTPOW: "pow{f}({0}, {1})",
    ca.OP_FMOD: "fmod{f}({0}, {1})", ca.OP_COPYSIGN: "copysign{f}({0}, {1})",
    ca.OP_FMIN: "fmin{f}({0}, {1})", ca.OP_FMAX: "fmax{f}({0}, {1})",
}
# fmin and fmax as selects, with C's rule (a NaN argument yields the other argument): a call to
# fmin stops gcc's vectorizer (libmvec has no fmin), a select does not. Keep this form: the
# shorter equivalent "({1} != {1} || {0} < {1}) ? {0} : {1}" gives the same values alone, but
# gcc then compiles the kernel around it differently and the batch metrics change in their
# last bits.
SELECTS = {
    ca.OP_FMIN: "({1} != {1}) ? {0} : "
                "((({0} < {1}) || ({0} != {0})) ? (({0} != {0}) ? {1} : {0}) : {1})",
    ca.OP_FMAX: "({1} != {1}) ? {0} : "
                "((({0} > {1}) || ({0} != {0})) ? (({0} != {0}) ? {1} : {0}) : {1})",
}
# a template that is a call of a math function: its name and its arguments
CALL = re.compile(r"^(\w+)\{f\}\((.*)\)$")


@dataclass(frozen=True)
class Target:
    """What the C of one target differs in.

    Parameters
    ----------
    literal : callable
        ``literal(value) -> str``: a constant as C text; it may raise for a constant the
        target cannot hold.
    suffix : str, optional
        Suffix of the math functions (``"f"`` in float32: ``sinf``).
    selects : bool, optional
        Write fmin/fmax as SELECTS instead of calls.
    error : type, optional
        The QuadcogError subclass raised for an operation with no C form.
    """
    literal: Callable[[float], str]
    suffix: str = ""
    selects: bool = False
    error: type[QuadcogError] = QuadcogError


@dataclass(frozen=True)
class Walk:
    """The C of an SX Function.

    Parameters
    ----------
    statements : list of str
        One per instruction, in order, unindented.
    slots : set of int
        The work slots written: declare ``w<slot>`` for each.
    inputs : set of int
        The indices of the inputs read.
    calls : dict of str to int
        {C function without suffix: number of arguments}.
    """
    statements: list[str]
    slots: set[int]
    inputs: set[int]
    calls: dict[str, int]


def op_name(op: int) -> str:
    """CasADi's name of an operation code.

    Parameters
    ----------
    op : int
        A CasADi operation code (``casadi.OP_SIN``, ...).

    Returns
    -------
    str
        Its name ('OP_SIN'), or the number if it has none.
    """
    return _NAMES.get(op, str(op))


_NAMES = {getattr(ca, n): n for n in dir(ca) if n.startswith("OP_")}


def template(op: int, target: Target) -> str | None:
    """The C template of ``op`` for ``target`` (see OPERATIONS).

    Parameters
    ----------
    op : int
        A CasADi operation code.
    target : Target
        The target (its ``selects`` chooses SELECTS for fmin/fmax).

    Returns
    -------
    str or None
        The template with operands ``{0}``, ``{1}`` and ``{one}``, ``{zero}``, ``{f}``, or
        None if the operation has no C form.
    """
    if target.selects and op in SELECTS:
        return SELECTS[op]
    return OPERATIONS.get(op)


def walk(fn: ca.Function, target: Target, read: Callable[[int, int], str],
         write: Callable[[int, int], str]) -> Walk:
    """Walk the instructions of the SX Function ``fn`` into C statements.

    Parameters
    ----------
    fn : casadi.Function
        An SX Function.
    target : Target
        How constants and math functions are written.
    read : callable
        ``read(i, nz)`` is the C expression of nonzero ``nz`` of input ``i``.
    write : callable
        ``write(i, nz)`` is the C lvalue of nonzero ``nz`` of output ``i``.

    Returns
    -------
    Walk
        The statements, the work slots written, the inputs read and the math calls.

    Raises
    ------
    QuadcogError
        ``target.error``, naming an operation without a C form.
    """
    one, zero = target.literal(1.0), target.literal(0.0)
    statements: list[str] = []
    slots: set[int] = set()
    inputs: set[int] = set()
    calls: dict[str, int] = {}
    for k in range(fn.n_instructions()):
        op = fn.instruction_id(k)
        ins, outs = fn.instruction_input(k), fn.instruction_output(k)
        if op == ca.OP_INPUT:
            statements.append(f"w{outs[0]} = {read(ins[0], ins[1])};")
            slots.add(outs[0])
            inputs.add(ins[0])
            continue
        if op == ca.OP_OUTPUT:
            statements.append(f"{write(outs[0], outs[1])} = w{ins[0]};")
            continue
        if op == ca.OP_CONST:
            rhs = target.literal(fn.instruction_constant(k))
        else:
            form = template(op, target)
            if form is None:
                raise target.error(f"{fn.name()}: CasADi operation {op_name(op)} (instruction "
                                   f"{k}) has no C form in quadcog.codegen.sx_to_c; rewrite the "
                                   "function without it, or add it to "
                                   "quadcog.codegen.sx_to_c.OPERATIONS")
            call = CALL.match(form)
            if call:
                calls[call.group(1)] = call.group(2).count(",") + 1
            rhs = form.format(*(f"w{n}" for n in ins), one=one, zero=zero, f=target.suffix)
        statements.append(f"w{outs[0]} = {rhs};")
        slots.add(outs[0])
    return Walk(statements, slots, inputs, calls)


def float32_literal(value: float) -> str:
    """The C float literal of the float32 nearest to ``value``: the shortest text that
    round-trips, with an ``f`` suffix (the same text on every machine).

    Parameters
    ----------
    value : float
        A finite number.

    Returns
    -------
    str
        E.g. ``"0.1f"``, ``"1.5e-7f"``.
    """
    text = np.format_float_scientific(np.float32(value), unique=True, trim="0")
    mantissa, exponent = text.split("e")
    exp = int(exponent)
    mantissa = mantissa if "." in mantissa else mantissa + ".0"
    return f"{mantissa}e{exp}f" if exp else f"{mantissa}f"
