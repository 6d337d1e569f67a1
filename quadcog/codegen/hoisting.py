"""What both compiled loops (the single-flight kernel and the vector batch kernel) compute less
often than every step, read from a step's SX instructions.

- **Levels.** Each instruction's result depends on inputs that are constant over a call (the
  vehicle's parameters: ``CONSTANT``), that change seldom (the CoG profile and the payloads:
  ``SLOW``) or that change every step (the state, the reference: ``STEP``); its level is the
  highest of its operands'. A loop computes a ``CONSTANT`` result once and a ``SLOW`` one
  again only where the slow inputs change.
- **Reciprocals.** A division whose divisor is shared by several divisions, or is computed
  less often than the division, goes through the divisor's reciprocal, computed once where
  the divisor is: a division costs several multiplications' time, and the divisions of a
  step share few divisors (the inverse mass matrix's, the Euler angles' cosines).
- **Fused products.** On an ISA with FMA units, a product used only by one sum of its own
  loop goes into that sum as one ``fma`` (one rounding less), unless a math function takes
  the sum (``fused_products``, ``fused_form``).
"""
from collections.abc import Callable

import casadi as ca

__all__ = ["CONSTANT", "SLOW", "STEP", "levels", "divisor_uses", "fused_form", "fused_products",
           "through_reciprocal"]

CONSTANT, SLOW, STEP = 0, 1, 2      # when an instruction runs: once, on a change, each step


def levels(step: ca.Function, level_of_input: Callable[[int, int], int]) -> list[int]:
    """The level (CONSTANT, SLOW, STEP) of every instruction's result.

    Parameters
    ----------
    step : casadi.Function
        An SX Function.
    level_of_input : callable
        ``level_of_input(i, nz)``: the level of nonzero ``nz`` of input ``i``.

    Returns
    -------
    list of int
        One per instruction: a literal is CONSTANT, an input its ``level_of_input``, an
        output STEP, an operation the highest level of its operands.
    """
    slot: dict[int, int] = {}
    out = []
    for k in range(step.n_instructions()):
        op = step.instruction_id(k)
        ins, outs = step.instruction_input(k), step.instruction_output(k)
        if op == ca.OP_INPUT:
            level = level_of_input(ins[0], ins[1])
        elif op == ca.OP_CONST:
            level = CONSTANT
        elif op == ca.OP_OUTPUT:
            level = STEP
        else:
            level = max((slot[i] for i in ins if i >= 0), default=CONSTANT)
        if op != ca.OP_OUTPUT:
            slot[outs[0]] = level
        out.append(level)
    return out


def divisor_uses(step: ca.Function) -> dict[int, int]:
    """How many divisions divide by each instruction's result.

    Parameters
    ----------
    step : casadi.Function
        An SX Function.

    Returns
    -------
    dict of int to int
        {instruction: number of divisions by its result}.
    """
    made_by: dict[int, int] = {}       # work slot -> the instruction whose result it holds
    uses: dict[int, int] = {}
    for k in range(step.n_instructions()):
        op, ins, outs = step.instruction_id(k), step.instruction_input(k), step.instruction_output(k)
        if op == ca.OP_DIV:
            d = made_by[ins[1]]
            uses[d] = uses.get(d, 0) + 1
        if op != ca.OP_OUTPUT:
            made_by[outs[0]] = k
    return uses


def through_reciprocal(d: int, level: int, levels_: list[int], uses: dict[int, int]) -> bool:
    """Whether a division (at ``level``) by instruction d's result goes through ``1 / d``.

    Parameters
    ----------
    d : int
        The instruction of the divisor.
    level : int
        The division's level.
    levels_ : list of int
        Every instruction's level (``levels``).
    uses : dict of int to int
        ``divisor_uses`` of the step.

    Returns
    -------
    bool
        True where d divides more than once, or is computed less often than the division.
        ``a / d`` then becomes ``a * (1 / d)``: one rounding more, at most an ulp.
    """
    return d in uses and (uses[d] > 1 or levels_[d] < level)


def fused_products(step: ca.Function, levels_: list[int]) -> dict[int, tuple[int, int]]:
    """The additions that take in a product as one fused multiply-add (one rounding).

    An addition or subtraction takes in a multiplication when the product is used there only,
    is computed in the same loop (level), and the sum is not the argument of a math function
    (sin, floor, ...): such an argument is rounded as CasADi rounds it, because a function can
    magnify an ulp (the sensing noise's ``fract(sin(a t + b) * 43758.5453)`` turns the rounding
    an FMA saves into 1e-7 of the noise).

    Parameters
    ----------
    step : casadi.Function
        An SX Function.
    levels_ : list of int
        Every instruction's level (``levels``).

    Returns
    -------
    dict of int to (int, int)
        {addition: (multiplication, which operand of the addition it is, 0 or 1)}.
    """
    made_by: dict[int, int] = {}
    n_uses: dict[int, int] = {}
    argument: set[int] = set()        # instructions whose result a math function takes
    arithmetic = {ca.OP_ADD, ca.OP_SUB, ca.OP_MUL, ca.OP_DIV, ca.OP_NEG, ca.OP_SQ, ca.OP_TWICE,
                  ca.OP_INV, ca.OP_LT, ca.OP_LE, ca.OP_EQ, ca.OP_NE, ca.OP_NOT, ca.OP_AND,
                  ca.OP_OR, ca.OP_IF_ELSE_ZERO, ca.OP_FMIN, ca.OP_FMAX, ca.OP_FABS,
                  ca.OP_OUTPUT, ca.OP_ASSIGN}
    candidates = []
    for k in range(step.n_instructions()):
        op, ins, outs = step.instruction_id(k), step.instruction_input(k), step.instruction_output(k)
        if op not in (ca.OP_INPUT, ca.OP_CONST):
            for i in ins:
                if i >= 0:
                    d = made_by[i]
                    n_uses[d] = n_uses.get(d, 0) + 1
                    if op not in arithmetic:
                        argument.add(d)
        if op in (ca.OP_ADD, ca.OP_SUB):
            candidates.append((k, [made_by[i] for i in ins]))
        if op != ca.OP_OUTPUT:
            made_by[outs[0]] = k
    fused: dict[int, tuple[int, int]] = {}
    for k, operands in candidates:
        if k in argument:
            continue
        for which, m in enumerate(operands):     # used once: no other sum can take it
            if (step.instruction_id(m) == ca.OP_MUL and n_uses.get(m) == 1
                    and levels_[m] == levels_[k]):
                fused[k] = (m, which)
                break
    return fused


def fused_form(op: int, which: int, a: str, b: str, other: str, suffix: str = "") -> str:
    """The C of an addition or subtraction that takes in the product ``a * b``.

    Parameters
    ----------
    op : int
        ``casadi.OP_ADD`` or ``casadi.OP_SUB``.
    which : int
        Which operand of ``op`` the product is (0 or 1), as ``fused_products`` gives it.
    a : str
        The C of the product's first factor.
    b : str
        The C of its second factor.
    other : str
        The C of the other operand.
    suffix : str
        The math functions' suffix (``"f"`` in float32).

    Returns
    -------
    str
        ``fma(a, b, other)``; for a subtraction ``fma(a, b, -(other))`` (product first) or
        ``fma(-(a), b, other)``: negation is exact, so one rounding as for the sum.
    """
    other = f"({other})"
    if op == ca.OP_SUB:
        a, other = (a, f"-{other}") if which == 0 else (f"-({a})", other)
    return f"fma{suffix}({a}, {b}, {other})"
