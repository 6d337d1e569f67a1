"""The single-flight kernel: the steps of one flight as one C loop, compiled for this machine.

A step is a CasADi SX Function ``step(X, P, *per_step) -> (X_next, *per_step_out, code)``: X
the state, P inputs constant over the flight, the per-step inputs one row per step, and the
last output a stop code (the loop stops after the first step whose code is not 0). This module
emits C from the step's SX instructions (the operations are quadcog.codegen.sx_to_c's, shared
with the vector kernel and the embedded export): one loop over the steps, the state read from
row k of the trajectory and written to row k + 1, the per-step outputs to row k.

It differs from CasADi's own code of the same step (``mapaccum``, what the flight ran on
before) in what it computes once:

- Instructions that depend only on the constant inputs (P) and on literals run once per call,
  before the loop.
- Instructions that depend only on the constant inputs and the *slow* per-step inputs (those
  that are the same for long runs of steps: for a flight, the CoG profile) run again only at
  steps whose slow inputs differ, bit for bit, from those of the last run of them.

gcc contracts no multiply-add (``-ffp-contract=off``); on the ISAs of ``FMA_ISAS`` the loop
writes its own fused products where no math function takes the sum, as the vector kernel does.
The sines, cosines and tangents are inline (``quadcog.codegen.trig_c``, the vector kernel's
too), sin and cos within 2 ulp of libm's; with ``trig="libm"`` and without reciprocals the trajectory is
bit for bit the one of CasADi's code of the same step (tests/test_flight_kernel.py). The loop
is compiled with the instruction set of ``quadcog.codegen.vector_kernel.kernel_isa`` (its
flags and ``-O3``).
"""
from collections.abc import Callable, Sequence
import ctypes
import hashlib

import casadi as ca
import numpy as np

from quadcog.codegen import hoisting, trig_c
from quadcog.codegen import sx_to_c as sxc
from quadcog.codegen.compiler import compile_library, find_compiler
from quadcog.codegen.hoisting import CONSTANT as _CONSTANT
from quadcog.codegen.hoisting import SLOW as _SLOW
from quadcog.codegen.hoisting import STEP as _STEP
from quadcog.codegen.vector_kernel import FMA_ISAS, INLINE_TRIG, ISA_FLAGS, TARGETS, TRIGS, kernel_isa, pressure_order
from quadcog.errors import CompileError, KernelError

__all__ = ["flight_flags", "emit_flight_c", "FlightKernel"]

def flight_flags(isa: str | None = None) -> tuple[str, ...]:
    """Compiler flags of the single-flight kernel.

    Parameters
    ----------
    isa : str, optional
        One of ``quadcog.codegen.vector_kernel.ISAS`` (default ``kernel_isa()``).

    Returns
    -------
    tuple of str
        ``-O3``, the ISA's flags, no FMA contraction by gcc, no errno, ``-shared -fPIC``.
    """
    isa = kernel_isa() if isa is None else isa
    return ("-O3", *ISA_FLAGS[isa], "-ffp-contract=off", "-fno-math-errno", "-shared", "-fPIC")


def emit_flight_c(step: ca.Function, constant: Sequence[int] = (1,),
                  slow: Sequence[int] = (), name: str = "qc_flight",
                  reciprocals: bool = True, trig: str = "inline", fma: bool = False) -> str:
    """C source of the single-flight loop of the SX Function ``step``.

    Parameters
    ----------
    step : casadi.Function
        ``step(X, *inputs) -> (X_next, *outputs, code)``, SX; X_next of X's size; code a
        scalar.
    constant : sequence of int
        The inputs that are the same in every step (read from one array).
    slow : sequence of int
        The per-step inputs whose change sets off the instructions that depend only on them
        and the constant inputs.
    reciprocals : bool
        Divide by a divisor that is used more than once or is computed less often than the
        division (once, or on a change of the slow inputs) through its reciprocal: ``a / d``
        becomes ``a * (1 / d)``, with ``1 / d`` computed once where ``d`` is. It saves most
        divisions of a step and changes a result by at most an ulp per such division.
    trig : {"inline", "libm"}
        sin, cos and tan inline (``quadcog.codegen.trig_c``: one reduction for the sine and
        cosine of an angle, the same bits as the vector kernel's) or libm's calls (CasADi's
        own code calls libm: with "libm" and no reciprocals the loop is CasADi's step bit for
        bit).
    fma : bool
        Take a product into the sum that is its only use as one fused multiply-add, as the
        vector kernel does (``quadcog.codegen.hoisting.fused_products``); ``FlightKernel``
        turns it on for the ISAs of ``quadcog.codegen.vector_kernel.FMA_ISAS``.
    name : str
        The C function: ``long name(long start, long stop, double *X, const double *const
        *in, double *const *out)``. ``in[i]`` is input i (i >= 1): the constant ones one
        row, the others one row per step (C order); ``out[j]`` is output j (j >= 1, the code
        included) with one row per step; X has a row per sample, and step k reads row k and writes row
        k + 1. It returns the first step in start .. stop - 1 whose code is not 0 (its
        outputs written), else stop.

    Returns
    -------
    str
        The C.

    Raises
    ------
    KernelError
        ``step`` is not an SX Function of that form, or has an operation without a C form.
    """
    if trig not in TRIGS:
        raise KernelError(f"trig must be one of {', '.join(map(repr, TRIGS))}, got {trig!r}")
    if not step.is_a("SXFunction"):
        raise KernelError(f"{step.name()}: expected an SX Function")
    n_in, n_out = step.n_in(), step.n_out()
    nX = step.nnz_in(0)
    if n_out < 2 or step.nnz_out(0) != nX or step.nnz_out(n_out - 1) != 1:
        raise KernelError(f"{step.name()}: expected step(X, ...) -> (X_next, ..., code) with "
                          "X_next of X's size and a scalar code")
    constant_set, slow_set = frozenset(constant), frozenset(slow)
    if 0 in constant_set | slow_set or not constant_set | slow_set <= set(range(1, n_in)):
        raise KernelError(f"{step.name()}: constant and slow inputs are among inputs 1 .. "
                          f"{n_in - 1}")
    target = TARGETS["float64"]
    one, zero = target.literal(1.0), target.literal(0.0)
    levels = hoisting.levels(step, lambda i, nz: (_CONSTANT if i in constant_set else _SLOW
                                                  if i in slow_set else _STEP))
    rows = [step.nnz_in(i) for i in range(n_in)]
    blocks: dict[int, list[str]] = {_CONSTANT: [], _SLOW: [], _STEP: []}
    calls: dict[str, int] = {}
    name_of: dict[int, str] = {}          # work slot -> the variable that holds it now
    code_var = None
    uses = hoisting.divisor_uses(step) if reciprocals else {}
    made_by: dict[int, int] = {}          # work slot -> the instruction of its value
    inverted: set[int] = set()            # instructions whose reciprocal r<k> is declared
    inlined = False                       # an inline sin, cos or tan is used
    fused = hoisting.fused_products(step, levels) if fma else {}
    absorbed = {m for m, _ in fused.values()}
    product: dict[int, tuple[str, str]] = {}   # absorbed multiplication -> its factors

    def read(i: int, nz: int) -> str:
        if i == 0:
            return f"x[{nz}]"
        if i in constant_set:
            return f"in{i}[{nz}]"
        return f"in{i}[k * {rows[i]} + {nz}]"

    for k in range(step.n_instructions()):
        op, level = step.instruction_id(k), levels[k]
        ins, outs = step.instruction_input(k), step.instruction_output(k)
        var = f"v{k}"
        if op == ca.OP_OUTPUT:
            o, nz = outs[0], outs[1]
            src = name_of[ins[0]]
            if o == 0:
                blocks[_STEP].append(f"xn[{nz}] = {src};")
            else:
                blocks[_STEP].append(f"out{o}[k * {step.nnz_out(o)} + {nz}] = {src};")
                if o == n_out - 1:
                    code_var = src
            continue
        if op == ca.OP_INPUT:
            rhs = read(ins[0], ins[1])
        elif op == ca.OP_CONST:
            rhs = target.literal(step.instruction_constant(k))
        elif op == ca.OP_DIV and hoisting.through_reciprocal(made_by[ins[1]], level, levels, uses):
            d = made_by[ins[1]]
            if d not in inverted:       # once, where the divisor is computed
                inverted.add(d)
                blocks[levels[d]].append(
                    f"{'double ' if levels[d] == _STEP else ''}r{d} = {one} / v{d};")
            rhs = f"{name_of[ins[0]]} * r{d}"
        elif k in absorbed:                  # written by the addition that takes it in
            product[k] = (name_of[ins[0]], name_of[ins[1]])
            name_of[outs[0]] = var
            made_by[outs[0]] = k
            continue
        elif k in fused:
            m, which = fused[k]
            calls["fma"] = 3
            rhs = hoisting.fused_form(op, which, *product[m], name_of[ins[1 - which]])
        elif trig == "inline" and op in INLINE_TRIG:
            rhs = f"qc_{INLINE_TRIG[op]}({name_of[ins[0]]})"
            inlined = True
        else:
            form = sxc.template(op, target)
            if form is None:
                raise KernelError(f"{step.name()}: CasADi operation {sxc.op_name(op)} "
                                  f"(instruction {k}) has no C form in quadcog.codegen.sx_to_c")
            call = sxc.CALL.match(form)
            if call:
                calls[call.group(1)] = call.group(2).count(",") + 1
            rhs = form.format(*(name_of[n] for n in ins), one=one, zero=zero, f="")
        declare = "double " if level == _STEP else ""
        blocks[level].append(f"{declare}{var} = {rhs};")
        name_of[outs[0]] = var
        made_by[outs[0]] = k
    if code_var is None:
        code_var = zero
    persistent = [f"v{k}" for k, lv in enumerate(levels)
                  if lv != _STEP and step.instruction_id(k) != ca.OP_OUTPUT and k not in absorbed]
    blocks[_STEP] = pressure_order(blocks[_STEP])
    persistent += [f"r{k}" for k in sorted(inverted) if levels[k] != _STEP]
    decls = "".join(f"double {f}({', '.join(['double'] * n)});\n" for f, n in sorted(calls.items()))
    inputs = "".join(f"  const double *in{i} = in[{i}];\n" for i in range(1, n_in))
    outputs = "".join(f"  double *out{j} = out[{j}];\n" for j in range(1, n_out))
    changed = " || ".join(f"memcmp(in{i} + k * {rows[i]}, in{i} + last * {rows[i]}, "
                          f"{rows[i]} * sizeof(double))" for i in sorted(slow_set) if rows[i])
    indent = "\n      "
    slow_code = (f"    if (last < 0 || {changed or '0'}) {{\n      last = k;{indent}"
                 + indent.join(blocks[_SLOW]) + "\n    }\n") if blocks[_SLOW] else ""
    declared = (f"  double {', '.join(persistent)};\n" if persistent else "")
    return f"""/* quadcog single-flight kernel for {step.name()}: generated, do not edit. */
#include <string.h>
{decls}{trig_c.scalar_c() if inlined else ""}long {name}(long start, long stop, double *X, const double *const *in,
          double *const *out) {{
{inputs}{outputs}{declared}  long last = -1;
  (void) last;
  {(chr(10) + '  ').join(blocks[_CONSTANT])}
  for (long k = start; k < stop; ++k) {{
    const double *x = X + k * {nX};
    double *xn = X + (k + 1) * {nX};
{slow_code}    {(chr(10) + '    ').join(blocks[_STEP])}
    if ({code_var} != {zero}) return k;
  }}
  return stop;
}}
"""


class FlightKernel:
    """A compiled single-flight kernel (``emit_flight_c``), called through ctypes.

    Parameters
    ----------
    step : casadi.Function
        ``step(X, *inputs) -> (X_next, *outputs, code)``, SX.
    constant : sequence of int
        The inputs that are the same in every step.
    slow : sequence of int
        The per-step inputs that change seldom (see ``emit_flight_c``).
    isa : str, optional
        One of ``quadcog.codegen.vector_kernel.ISAS`` (default ``kernel_isa()``).

    Attributes
    ----------
    flags, library
        The compiler flags and the library's path.

    Raises
    ------
    KernelError
        No C compiler, or a step of the wrong form.
    CompileError
        The compiler failed.
    """

    def __init__(self, step: ca.Function, constant: Sequence[int] = (1,),
                 slow: Sequence[int] = (), isa: str | None = None) -> None:
        cc = find_compiler()
        if cc is None:
            raise KernelError("no C compiler")
        self.n_in, self.n_out = step.n_in(), step.n_out()
        self.constant = frozenset(constant)
        self.rows_in = [step.nnz_in(i) for i in range(self.n_in)]
        self.rows_out = [step.nnz_out(j) for j in range(self.n_out)]
        source = emit_flight_c(step, constant, slow,
                               fma=(kernel_isa() if isa is None else isa) in FMA_ISAS).encode()
        self.flags = flight_flags(isa)
        stem = "flight_kernel_" + hashlib.sha256(source).hexdigest()[:12]
        try:
            self.library = compile_library(source, stem, cc, flags=self.flags)
        except CompileError:            # the ISA's flags refused: the compiler's defaults
            self.flags = flight_flags("portable")
            self.library = compile_library(source, stem, cc, flags=self.flags)
        self._fn = ctypes.CDLL(str(self.library)).qc_flight
        self._fn.restype = ctypes.c_long
        self._fn.argtypes = [ctypes.c_long, ctypes.c_long, ctypes.c_void_p, ctypes.c_void_p,
                             ctypes.c_void_p]

    def bind(self, X: np.ndarray, inputs: Sequence[np.ndarray],
             outputs: Sequence[np.ndarray]) -> "FlightRun":
        """Bind the arrays of one flight.

        Parameters
        ----------
        X : (N + 1, nX) float64 array, C order
            Row 0 the start; the steps write rows 1 ..
        inputs : sequence of float64 arrays, C order
            Inputs 1 .. n_in - 1: the constant ones of their size, the others at least
            (N, rows).
        outputs : sequence of float64 arrays, C order
            Outputs 1 .. n_out - 1 (the code the last), each at least (N, rows).

        Returns
        -------
        FlightRun
            ``run(start, stop) -> int``: the first step in start .. stop - 1 whose code is
            not 0, else stop.

        Raises
        ------
        KernelError
            An array of the wrong shape, type or order.
        """
        n = X.shape[0] - 1

        def check(a: np.ndarray, rows: int, size: int, what: str) -> None:
            # at least `rows` rows of `size`: a schedule holds one sample more than steps
            if not (isinstance(a, np.ndarray) and a.dtype == np.float64 and a.flags.c_contiguous
                    and a.size >= rows * size and (a.ndim == 1 or a.size == a.shape[0] * size)):
                raise KernelError(f"{what}: expected a C-ordered float64 array of at least "
                                  f"{rows} rows of {size}, got {a.dtype} {a.shape}")
        check(X, n + 1, self.rows_in[0], "X")
        if len(inputs) != self.n_in - 1 or len(outputs) != self.n_out - 1:
            raise KernelError(f"expected {self.n_in - 1} inputs and {self.n_out - 1} outputs")
        for i, a in enumerate(inputs, 1):
            check(a, 1 if i in self.constant else n, self.rows_in[i], f"input {i}")
        for j, a in enumerate(outputs, 1):
            check(a, n, self.rows_out[j], f"output {j}")
        return FlightRun(self._fn, X, list(inputs), list(outputs))


class FlightRun:
    """The arrays of one flight bound to a FlightKernel (``FlightKernel.bind``).

    Parameters
    ----------
    fn : callable
        The kernel's C function (ctypes).
    X : numpy.ndarray
        The trajectory.
    inputs, outputs : list of numpy.ndarray
        The kernel's inputs 1 .. and outputs 1 ...
    """

    def __init__(self, fn: Callable[..., int], X: np.ndarray, inputs: list[np.ndarray],
                 outputs: list[np.ndarray]) -> None:
        self._fn, self._keep = fn, (X, inputs, outputs)     # keep the arrays alive
        self._X = X.ctypes.data
        self._in = (ctypes.c_void_p * (len(inputs) + 1))(None, *(a.ctypes.data for a in inputs))
        self._out = (ctypes.c_void_p * (len(outputs) + 1))(None, *(a.ctypes.data for a in outputs))
        self.steps = X.shape[0] - 1

    def __call__(self, start: int, stop: int) -> int:
        """Run steps start .. stop - 1.

        Parameters
        ----------
        start : int
            The first step.
        stop : int
            One past the last step (at most the flight's step count).

        Returns
        -------
        int
            The first step whose code is not 0 (its outputs written), else ``stop``.
        """
        if not 0 <= start <= stop <= self.steps:
            raise KernelError(f"steps {start} .. {stop} outside 0 .. {self.steps}")
        return int(self._fn(start, stop, self._X, self._in, self._out))
