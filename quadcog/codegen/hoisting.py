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
"""
from collections.abc import Callable

import casadi as ca

__all__ = ["CONSTANT", "SLOW", "STEP", "levels", "divisor_uses", "through_reciprocal"]

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
