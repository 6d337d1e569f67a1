"""The vectorized batch kernel: a closed-loop step of many flights in the CPU's vector lanes.

A batch step is a CasADi SX Function ``step(Z, Q, row) -> Z_next``: Z the state of one flight
(with its metric accumulators), Q its constant parameters, row the step's entry of the step
table (shared by all flights). This module emits C from the step's SX instructions (the
operations and the walk are quadcog.codegen.sx_to_c's, shared with the embedded export) with the flight
index as the innermost loop of every operation: flights go in blocks of ``lanes``, the
whole step is one ``#pragma omp simd`` loop over a block, and gcc turns every operation into a
vector instruction (glibc's libmvec for atan2 and the other math functions). A block's state stays in
the L1 cache for all its steps, so memory traffic is a few hundred bytes per flight.

Instruction set. The kernel is compiled on the user's machine for the widest vector unit its
CPU reports (``detect_isa``: AVX-512, AVX2 + FMA, SSE2 on x86-64; the compiler's defaults
elsewhere), with the flags of ``ISA_FLAGS`` and a block of ``VECTORS_PER_BLOCK`` vectors
(``lanes_for``: 16 doubles with AVX2, 32 with AVX-512, twice that in float32). The ISA is part
of the library's name and its flags are part of the compile-cache key. Where the compiler
refuses the ISA's flags, the kernel is built once more with the portable flags (one
QuadcogWarning).

Rounding. gcc contracts nothing (``-ffp-contract=off``); on the ISAs with FMA units
(``FMA_ISAS``) the kernel itself writes ``fma(a, b, c)`` where a product's only use is a sum that
no math function takes (``quadcog.codegen.hoisting.fused_products``): one rounding less, and
never in such an argument, because a function can magnify it (the sensing noise's hash
``fract(sin(a t + b) * 43758.5453)`` turns the rounding an FMA saves into 1e-7 of the noise).
On AVX2 and AVX-512 (``INLINE_TRIG_ISAS``) the step's sin, cos and tan are inline
(``quadcog.codegen.trig_c``: sin, cos within 2 ulp of glibc's); atan2 and the rest are libmvec's, whose
SSE, AVX2 and AVX-512 variants are different code (within 4 ulp of glibc's). So the bits of a
flight differ between instruction sets and, in the last places, from the single-flight path.

Precision. ``precision="float32"`` emits the same step in float (sinf, float literals), with
twice the lanes per vector; the state, parameters and step table are rounded to float32 on
the way in and widened on the way out (docs/performance.md has its accuracy).

The C is compiled through the build cache, loaded with ctypes (which releases the GIL), and
called from ``threads`` Python threads, each on its own share of the blocks: the thread count
asked for is the thread count used. A flight's bits do not depend on the block it is in (every
lane runs the same vector code; a partial block is padded), so results are the same for any
batch size, thread count or chunking.
"""
from collections.abc import Callable, Hashable, Sequence
import ctypes
import functools
import hashlib
import heapq
import math
import os
import platform
import re
import threading
import warnings

import casadi as ca
import numpy as np

from quadcog.codegen import hoisting, trig_c
from quadcog.codegen import sx_to_c as sxc
from quadcog.codegen.compiler import compile_library, find_compiler
from quadcog.errors import CompileError, InputError, KernelError, QuadcogWarning

__all__ = ["FMA_ISAS", "INLINE_TRIG", "INLINE_TRIG_ISAS", "ISAS", "ISA_FLAGS", "LANES", "PRECISIONS",
           "SCHEDULE_FLAGS", "TARGETS", "TRIGS", "VECTOR_BITS", "VECTORS_PER_BLOCK", "ISA_ENV",
           "KernelError", "VectorKernel", "cpu_features", "detect_isa", "emit_c", "kernel_for",
           "kernel_isa", "lanes_for", "pressure_order", "vector_flags"]

PRECISIONS = ("float64", "float32")
# instruction sets, widest first: "portable" is the compiler's default target (SSE2 on x86-64)
ISAS = ("avx512", "avx2", "sse2", "portable")
# the /proc/cpuinfo flags an ISA needs. -mfma: with -ffp-contract=off no FMA appears in the step
# itself, only inside libmvec's functions and in `make bench`'s roofline loop
_CPU_NEEDS = {"avx512": ("avx512f", "avx512dq", "avx512vl", "avx512bw", "fma"),
              "avx2": ("avx2", "fma"), "sse2": ("sse2",), "portable": ()}
ISA_FLAGS = {"avx512": ("-mavx512f", "-mavx512dq", "-mavx512vl", "-mavx512bw", "-mfma",
                        # gcc 12 prefers 256-bit vectors even with AVX-512 unless told
                        "-mprefer-vector-width=512"),
             "avx2": ("-mavx2", "-mfma"), "sse2": ("-msse2",), "portable": ()}
# pins the ISA (e.g. "portable": the workers of one sweep on different CPUs then agree in
# every bit); unset, the CPU's widest is used
ISA_ENV = "QUADCOG_KERNEL_ISA"
VECTOR_BITS = {"avx512": 512, "avx2": 256, "sse2": 128, "portable": 128}
# gcc's register-pressure-aware scheduling before allocation: the step holds more live
# values than the vector registers, and CasADi's instruction order keeps many of them alive
# long; reordered, fewer are spilled to the stack (llvm-mca's Zen 3 model: 528 -> 462 cycles
# per flight-step of the AVX2 loop; docs/performance.md). The bits do not change.
SCHEDULE_FLAGS = ("-fschedule-insns", "-fsched-pressure", "-fira-loop-pressure")
VECTORS_PER_BLOCK = 4   # independent vectors per operation: enough to hide a few cycles' latency
_BYTES = {"float64": 8, "float32": 4}
C_TYPE = {"float64": "double", "float32": "float"}
NUMPY_TYPE = {"float64": np.float64, "float32": np.float32}
LANES = VECTORS_PER_BLOCK * VECTOR_BITS["avx2"] // 64   # 16: the AVX2 block of doubles

# functions libmvec provides in vector form (glibc >= 2.35 for tan, atan2, erf, hypot, ...)
_VECTOR_MATH = ("sin", "cos", "tan", "exp", "log", "pow", "atan2", "atan", "asin", "acos",
                "tanh", "sinh", "cosh", "erf", "hypot")
# the instruction sets whose kernels fuse a product into its sum (emit_c's fma)
FMA_ISAS = ("avx512", "avx2")
# the instruction sets whose kernels inline the sines (emit_c's trig="inline"): SSE2 has no
# 64-bit integer comparison, so gcc would leave the step loop scalar (4x slower); the others
# call libmvec
INLINE_TRIG_ISAS = ("avx512", "avx2")
# the kernels' choices for sin, cos and tan (inline: quadcog.codegen.trig_c), and the operations
# that are inlined
TRIGS = ("inline", "libm")
INLINE_TRIG = {ca.OP_SIN: "sin", ca.OP_COS: "cos", ca.OP_TAN: "tan"}


def _literal(v):
    """A C double literal, exact (repr round-trips), with inf and NaN spelled for C."""
    v = float(v)
    if math.isnan(v):
        return "__builtin_nan(\"\")"
    if math.isinf(v):
        return "__builtin_inf()" if v > 0 else "(-__builtin_inf())"
    return repr(v)


def _literal32(v):
    """A C float literal: the float32 nearest to ``v`` (shortest round-trip text, the embedded
    export's), inf beyond the float range, NaN spelled for C."""
    v = float(v)
    if math.isnan(v):
        return "__builtin_nanf(\"\")"
    if abs(v) >= _FLOAT32_MAX:    # beyond the float range (or inf): rounds to inf
        return "__builtin_inff()" if v > 0 else "(-__builtin_inff())"
    return sxc.float32_literal(v)


# the largest double that rounds to a finite float (half an ulp above FLT_MAX rounds to inf)
_FLOAT32_MAX = float(np.finfo(np.float32).max) * (1 + 2.0 ** -25)
# how each precision writes C: exact literals, fmin/fmax as selects (a call would stop the
# vectorizer); also the single-flight kernel's (quadcog.codegen.flight_kernel)
TARGETS = {"float64": sxc.Target(literal=_literal, suffix="", selects=True, error=KernelError),
            "float32": sxc.Target(literal=_literal32, suffix="f", selects=True,
                                  error=KernelError)}


def _check_precision(precision, where="precision"):
    if not isinstance(precision, str) or precision not in PRECISIONS:
        raise InputError(f"{where} must be one of {', '.join(map(repr, PRECISIONS))}, got "
                         f"{precision!r}")
    return precision


def _check_isa(isa, where="isa"):
    if not isinstance(isa, str) or isa not in ISAS:
        raise InputError(f"{where} must be one of {', '.join(map(repr, ISAS))}, got {isa!r}")
    return isa


@functools.lru_cache(maxsize=None)
def cpu_features() -> frozenset[str]:
    """The CPU's feature flags as /proc/cpuinfo lists them.

    Returns
    -------
    frozenset of str
        E.g. {"sse2", "avx2", "fma", ...}; empty where /proc/cpuinfo has no flags line (not
        Linux, or not x86).
    """
    try:
        with open("/proc/cpuinfo") as fh:
            line = next((ln for ln in fh if ln.startswith("flags")), "")
    except OSError:
        return frozenset()
    return frozenset(line.partition(":")[2].split())


def detect_isa(features: frozenset[str] | set[str] | None = None,
               machine: str | None = None) -> str:
    """The widest instruction set of ``ISAS`` that the CPU can run.

    Parameters
    ----------
    features : set of str, optional
        CPU feature flags (default ``cpu_features()``).
    machine : str, optional
        ``platform.machine()`` (default: this machine's).

    Returns
    -------
    str
        "avx512", "avx2" or "sse2" on x86-64 by the features (AVX-512 F, DQ, VL, BW; AVX2 and
        FMA; SSE2), else "portable".
    """
    features = cpu_features() if features is None else set(features)
    machine = platform.machine() if machine is None else machine
    if machine not in ("x86_64", "AMD64"):
        return "portable"
    for isa in ("avx512", "avx2", "sse2"):
        if all(f in features for f in _CPU_NEEDS[isa]):
            return isa
    return "portable"


def kernel_isa() -> str:
    """The instruction set the kernel is built for.

    Returns
    -------
    str
        $QUADCOG_KERNEL_ISA (``ISA_ENV``) when it is set, checked to be one of ``ISAS``; else
        ``detect_isa()``.
    """
    env = os.environ.get(ISA_ENV)
    if env:
        return _check_isa(env, f"${ISA_ENV}")
    return detect_isa()


def lanes_for(isa: str, precision: str = "float64") -> int:
    """Flights per block: ``VECTORS_PER_BLOCK`` vectors of the ISA's width.

    Parameters
    ----------
    isa : str
        One of ``ISAS``.
    precision : str
        "float64" or "float32" (twice the lanes per vector).

    Returns
    -------
    int
        8, 16 or 32 doubles for SSE2 / portable, AVX2, AVX-512; twice that in float32.
    """
    _check_isa(isa)
    return VECTORS_PER_BLOCK * VECTOR_BITS[isa] // (8 * _BYTES[_check_precision(precision)])


def vector_flags(isa: str | None = None, precision: str = "float64") -> tuple[str, ...]:
    """Compiler flags of the kernel for an instruction set.

    No -ffast-math: IEEE arithmetic, only errno and traps are given up (which lets sqrt and
    the libmvec calls vectorize), and no FMA contraction by gcc (the kernel writes its own
    fused products: the module docstring says where and why).

    Parameters
    ----------
    isa : str, optional
        One of ``ISAS`` (default ``kernel_isa()``).
    precision : str
        "float64" or "float32" (which math builtins to turn off: gcc merges sin and cos into a
        sincos that has no vector form).

    Returns
    -------
    tuple of str
        The flags, ``-shared -fPIC`` included.
    """
    isa = kernel_isa() if isa is None else _check_isa(isa)
    f = "f" if _check_precision(precision) == "float32" else ""
    return ("-O3", *ISA_FLAGS[isa], "-ffp-contract=off", "-fno-math-errno",
            "-fno-trapping-math", "-fopenmp-simd", f"-fno-builtin-sin{f}",
            f"-fno-builtin-cos{f}", *SCHEDULE_FLAGS, "-shared", "-fPIC")


def emit_c(step: ca.Function, name: str = "qc_kernel", lanes: int = LANES,
           precision: str = "float64", slow: Sequence[int] = (), reciprocals: bool = True,
           trig: str = "inline", fma: bool = False, order: bool = True) -> str:
    """C source of the kernel of the SX Function ``step(Z, Q, row) -> Z_next``.

    What a flight computes less often than every step is hoisted out of the step
    (``quadcog.codegen.hoisting``, as in the single-flight kernel), per flight and so per
    lane: what depends only on Q (and literals) runs once per block and call, what depends
    only on Q and the ``slow`` entries of the row runs again only at the steps where those
    entries differ, bit for bit, from the last run of them (the row is shared by the
    flights, so all lanes of a block rerun together). Their results reach the step through
    a per-block array of lanes. A divisor shared by several divisions or computed less often
    is inverted once (``reciprocals``).

    The sines, cosines and tangents of the step are inline (``quadcog.codegen.trig_c``): a
    call to libmvec clobbers every vector register, so the step spilled its live values around
    each of its 13 angles. The inline reduction is exact only for ``|x| < trig_c.LARGE``; each
    lane keeps the largest |argument| of its step, and a block where one reached it stops
    before that step: ``VectorKernel`` flies it on from there with the same step calling
    libmvec (built only then: such angles are beyond 1.6e6 rad, a noise hash's of a large
    seed). What runs once or seldom (the hoisted loops) calls libmvec.

    Parameters
    ----------
    step : casadi.Function
        An SX Function of three inputs (Z, Q, row) and one output of Z's size.
    name : str
        Name of the C function: ``long name(long n_steps, const real *rows, real *Z,
        const real *Q, long n_blocks, long *stopped)``, real the C type of ``precision``. It
        returns -1 when every block ran every step, else the first block that stopped before a
        step with an angle of ``trig_c.LARGE`` or more (its Z holds the state there, the
        blocks before it are done, those after it untouched) with that step in ``*stopped``.
    lanes : int
        Flights per block.
    precision : str
        "float64" (double) or "float32" (float, sinf, float literals).
    slow : sequence of int
        The nonzeros of the row that change seldom (the CoG profile, the payloads).
    reciprocals : bool
        Divide through reciprocals (``quadcog.codegen.hoisting.through_reciprocal``: one
        rounding more, at most an ulp, per such division).
    trig : {"inline", "libm"}
        The step's sin, cos and tan: inline (float64; float32 always calls libmvec's) or
        libmvec's calls.
    fma : bool
        Take a product into the sum that is its only use as one fused multiply-add
        (``quadcog.codegen.hoisting.fused_products``: one rounding less, never in an argument
        of a math function); for ISAs with FMA units (``FMA_ISAS``).
    order : bool
        Order the step's statements for register pressure (``pressure_order``; the same bits).

    Returns
    -------
    str
        The C. Layouts (C order): rows (n_steps, n_row); Z (n_blocks, nZ, lanes), updated in
        place; Q (n_blocks, nQ, lanes).
    """
    precision = _check_precision(precision)
    if not step.is_a("SXFunction"):
        raise KernelError(f"{step.name()}: expected an SX Function")
    nZ, nQ, nR = (step.nnz_in(i) for i in range(3))
    if step.nnz_out(0) != nZ or step.n_in() != 3 or step.n_out() != 1:
        raise KernelError(f"{step.name()}: expected step(Z, Q, row) -> Z_next of equal size")
    slow_set = frozenset(int(i) for i in slow)
    if not slow_set <= set(range(nR)):
        raise KernelError(f"{step.name()}: slow row entries {sorted(slow_set)} outside 0 .. "
                          f"{nR - 1}")
    if trig not in TRIGS:
        raise KernelError(f"trig must be one of {', '.join(map(repr, TRIGS))}, got {trig!r}")
    inline = trig == "inline" and precision == "float64"
    target = TARGETS[precision]
    real, sfx = C_TYPE[precision], target.suffix
    one, zero = target.literal(1.0), target.literal(0.0)
    levels = hoisting.levels(step, lambda i, nz: (
        hoisting.CONSTANT if i == 1 else hoisting.SLOW if i == 2 and nz in slow_set
        else hoisting.STEP))
    checked: set[str] = set()             # the step's arguments of inline sin, cos, tan
    fused = hoisting.fused_products(step, levels) if fma else {}
    absorbed = {m for m, _ in fused.values()}
    product: dict[int, tuple[str, str]] = {}   # absorbed multiplication -> its factors
    uses = hoisting.divisor_uses(step) if reciprocals else {}
    blocks: dict[int, list[str]] = {hoisting.CONSTANT: [], hoisting.SLOW: [], hoisting.STEP: []}
    level_of: dict[str, int] = {}         # variable -> the loop that computes it
    hoisted: dict[str, int] = {}          # variable -> its row in h (read by a later loop)
    free: dict[int, str] = {}             # instruction -> C text valid in any loop
    reads: set[str] = set()               # the texts of free that read memory (Q, the row)
    name_of: dict[int, str] = {}          # work slot -> the C text of its value now
    made_by: dict[int, int] = {}          # work slot -> the instruction of its value
    calls: dict[str, int] = {}

    loaded: dict[tuple[str, int], str] = {}    # (memory read, loop) -> its local variable

    def load(text: str, level: int) -> str:
        """A memory read as a local of the loop, read once: a select of a read would not be
        if-converted (gcc does not speculate a load), which stops the vectorizer."""
        if (text, level) not in loaded:
            loaded[text, level] = f"l{len(loaded)}"
            blocks[level].append(f"{real} {loaded[text, level]} = {text};")
        return loaded[text, level]

    def use(text: str, level: int) -> str:
        """A value in the loop of ``level``: its variable, or its row of h."""
        if text in reads:
            return load(text, level)
        if text not in level_of or level_of[text] == level:
            return text
        if text not in hoisted:
            hoisted[text] = len(hoisted)
            blocks[level_of[text]].append(f"h[{hoisted[text] * lanes}+j] = {text};")
        return load(f"h[{hoisted[text] * lanes}+j]", level)

    def define(var: str, rhs: str, level: int) -> None:
        blocks[level].append(f"{real} {var} = {rhs};")
        level_of[var] = level

    for k in range(step.n_instructions()):
        op, level = step.instruction_id(k), levels[k]
        ins, outs = step.instruction_input(k), step.instruction_output(k)
        if op == ca.OP_OUTPUT:
            blocks[hoisting.STEP].append(
                f"zn[{outs[1] * lanes}+j] = {use(name_of[ins[0]], hoisting.STEP)};")
            continue
        var = f"v{k}"
        if op == ca.OP_CONST:
            free[k] = var = target.literal(step.instruction_constant(k))
        elif op == ca.OP_INPUT and ins[0] == 1:
            free[k] = var = f"q[{ins[1] * lanes}+j]"
            reads.add(var)
        elif op == ca.OP_INPUT and ins[0] == 2:
            free[k] = var = f"row[{ins[1]}]"
            reads.add(var)
        elif op == ca.OP_INPUT:
            define(var, f"z[{ins[1] * lanes}+j]", level)
        elif op == ca.OP_DIV and hoisting.through_reciprocal(made_by[ins[1]], level, levels,
                                                              uses):
            d = made_by[ins[1]]
            r = f"r{d}"
            if r not in level_of:          # once, where the divisor is computed
                define(r, f"{one} / {use(name_of[ins[1]], levels[d])}", levels[d])
            define(var, f"{use(name_of[ins[0]], level)} * {use(r, level)}", level)
        elif k in absorbed:                  # written by the addition that takes it in
            product[k] = (use(name_of[ins[0]], level), use(name_of[ins[1]], level))
        elif k in fused:
            m, which = fused[k]
            calls["fma"] = 3
            define(var, hoisting.fused_form(op, which, *product[m],
                                            use(name_of[ins[1 - which]], level), sfx), level)
        elif inline and level == hoisting.STEP and op in INLINE_TRIG:
            x = use(name_of[ins[0]], level)
            define(var, f"qc_{INLINE_TRIG[op]}({x})", level)
            if x not in checked:
                checked.add(x)
                # the largest |x| of the step (a NaN is skipped: it gives NaN either way)
                blocks[level].append(f"qc_large = (fabs({x}) > qc_large) ? fabs({x}) : qc_large;")
        else:
            form = sxc.template(op, target)
            if form is None:
                raise KernelError(f"{step.name()}: CasADi operation {sxc.op_name(op)} "
                                  f"(instruction {k}) has no C form in quadcog.codegen.sx_to_c")
            call = sxc.CALL.match(form)
            if call:
                calls[call.group(1)] = call.group(2).count(",") + 1
            define(var, form.format(*(use(name_of[n], level) for n in ins), one=one,
                                    zero=zero, f=sfx), level)
        name_of[outs[0]] = var
        made_by[outs[0]] = k
    # const + simd: gcc may call libmvec's vector versions (flags: -fno-builtin-sin/cos, or
    # gcc merges sin and cos into a sincos that has no vector form); sqrt, fabs, floor,
    # ceil and copysign are inlined as vector instructions
    decls = "".join(f"{real} {f}{sfx}({', '.join([real] * n)})"
                    + (" __attribute__((const, __simd__(\"notinbranch\")))"
                       if f in _VECTOR_MATH else "") + ";\n"
                    for f, n in sorted(calls.items()))
    runs = _runs(sorted(slow_set))
    changed = " || ".join(f"memcmp(row + {lo}, rows + last * NR + {lo}, {n} * sizeof(real))"
                          for lo, n in runs)
    if order:
        blocks[hoisting.STEP] = pressure_order(blocks[hoisting.STEP])
    body = {lv: "\n        ".join(b) for lv, b in blocks.items()}
    simd = "#pragma omp simd\n"
    if checked:      # each lane's largest argument of the step's inline sines
        body[hoisting.STEP] = ("double qc_large = 0.0;\n        " + body[hoisting.STEP]
                               + "\n        large[j] = qc_large;")
    # a block whose step has a large angle stops before it (z still holds the state there)
    stop = ("      {\n        int any = 0;\n        for (long j = 0; j < LANES; ++j) any |= "
            f"large[j] >= {trig_c.LARGE!r};\n        if (any) {{ *stopped = k; return b; }}"
            "\n      }\n" if checked else "")
    constant_loop = (f"    {simd}    for (long j = 0; j < LANES; ++j) {{\n        "
                     f"{body[hoisting.CONSTANT]}\n    }}\n" if blocks[hoisting.CONSTANT] else "")
    slow_loop = (f"      if (last < 0 || {changed or '0'}) {{\n        last = k;\n"
                 f"        {simd}        for (long j = 0; j < LANES; ++j) {{\n        "
                 f"{body[hoisting.SLOW]}\n        }}\n      }}\n" if blocks[hoisting.SLOW] else "")
    return f"""/* quadcog vector kernel for {step.name()} ({precision}): generated, do not edit. */
#include <string.h>
typedef {real} real;
{decls}{trig_c.scalar_c(fallback=False) if checked else ""}#define LANES {lanes}
#define NZ {nZ}
#define NQ {nQ}
#define NR {nR}
long {name}(long n_steps, const real *rows, real *Z, const real *Q, long n_blocks,
          long *stopped) {{
  for (long b = 0; b < n_blocks; ++b) {{
    real *z = Z + b * NZ * LANES;
    const real *q = Q + b * NQ * LANES;
    real zn[NZ * LANES] __attribute__((aligned(64)));
    real h[{max(1, len(hoisted)) * lanes}] __attribute__((aligned(64)));
    real large[LANES];
    long last = -1;
    (void) last; (void) h; (void) q; (void) large;
{constant_loop}    for (long k = 0; k < n_steps; ++k) {{
      const real *row = rows + k * NR;
{slow_loop}      {simd}      for (long j = 0; j < LANES; ++j) {{
        {body[hoisting.STEP]}
      }}
{stop}      for (long i = 0; i < NZ * LANES; ++i) z[i] = zn[i];
    }}
  }}
  (void) stopped;
  return -1;
}}
"""


_DEFINES = re.compile(r"^\w+ (\w+) = ")
_NAMES = re.compile(r"\b[vlr]\d+\b")


def pressure_order(statements: list[str]) -> list[str]:
    """The statements of one loop body in an order that keeps fewer values alive at once.

    The step has far more live values than a CPU has vector registers (16 with AVX2), and
    what does not fit goes to the stack and back: on a Zen 3 those loads and stores, not
    the arithmetic, bound the step (llvm-mca: the load/store pipes). CasADi's order computes
    many values long before their use. This is list scheduling: of the statements whose
    operands are ready, take the one that ends the most live ranges and starts the fewest
    (ties: the earlier one). Only the order changes, never an operation, so the bits do not.

    Parameters
    ----------
    statements : list of str
        C statements, each ``T name = expression;`` (defines name) or one that only reads
        (a store); names are ``v``, ``l`` or ``r`` and digits.

    Returns
    -------
    list of str
        The same statements, reordered.
    """
    n = len(statements)
    defined = [(m.group(1) if (m := _DEFINES.match(text)) else None) for text in statements]
    where = {name: i for i, name in enumerate(defined) if name}
    operands = []
    for i, text in enumerate(statements):
        names = set(_NAMES.findall(text)) - {defined[i]}
        operands.append({where[x] for x in names if x in where})
    users: list[list[int]] = [[] for _ in range(n)]
    for i, ops in enumerate(operands):
        for j in ops:
            users[j].append(i)
    left = [len(u) for u in users]           # uses of each value not yet scheduled
    waiting = [len(ops) for ops in operands]  # operands of each statement not yet scheduled
    done = [False] * n

    def score(i):
        return (1 if users[i] else 0) - sum(1 for j in operands[i] if left[j] == 1)

    # a heap of (score, statement); a score only falls (an operand's last use comes nearer),
    # so a statement whose score fell is pushed again and its older entries are skipped
    heap = [(score(i), i) for i in range(n) if not waiting[i]]
    heapq.heapify(heap)
    order = []
    while heap:
        key, best = heapq.heappop(heap)
        if done[best] or key != score(best):
            continue
        done[best] = True
        order.append(best)
        for j in operands[best]:
            left[j] -= 1
            if left[j] == 1:              # its last user, if ready, now ends it
                for u in users[j]:
                    if not done[u] and not waiting[u]:
                        heapq.heappush(heap, (score(u), u))
        for u in users[best]:
            waiting[u] -= 1
            if not waiting[u]:
                heapq.heappush(heap, (score(u), u))
    return [statements[i] for i in order]


def _runs(entries: list[int]) -> list[tuple[int, int]]:
    """Sorted integers as runs of consecutive ones: [(first, length), ...]."""
    runs: list[tuple[int, int]] = []
    for e in entries:
        if runs and runs[-1][0] + runs[-1][1] == e:
            runs[-1] = (runs[-1][0], runs[-1][1] + 1)
        else:
            runs.append((e, 1))
    return runs


class VectorKernel:
    """A compiled vector kernel.

    ``kernel(Z (B, nZ), Q (B, nQ), rows (n, n_row), threads)`` returns Z after the n steps
    (B, nZ), in float64 whatever the precision.

    Parameters
    ----------
    step : casadi.Function
        The SX step ``step(Z, Q, row) -> Z_next``.
    lanes : int, optional
        Flights per block (default ``lanes_for(isa, precision)``).
    isa : str, optional
        One of ``ISAS`` (default ``kernel_isa()``); one the CPU cannot run is refused.
    precision : str
        "float64" or "float32".
    slow : sequence of int
        The nonzeros of the row that change seldom (``emit_c``).
    trig : {"inline", "libm"}, optional
        ``emit_c``'s trig (default: inline on ``INLINE_TRIG_ISAS``, libm elsewhere). A block
        that meets an angle beyond the inline sines' range is flown on from that step by the
        same kernel with libm's (built on first need).

    Attributes
    ----------
    isa, precision, lanes, flags, library
        The instruction set built for ("portable" after a refused flag), the precision, the
        flights per block, the compiler flags and the library's path.
    """

    def __init__(self, step: ca.Function, lanes: int | None = None, isa: str | None = None,
                 precision: str = "float64", slow: Sequence[int] = (),
                 trig: str | None = None) -> None:
        cc = find_compiler()
        if cc is None:
            raise KernelError("no C compiler")
        self.precision = _check_precision(precision)
        native = detect_isa()
        isa = kernel_isa() if isa is None else _check_isa(isa)
        if ISAS.index(isa) < ISAS.index(native):
            raise KernelError(f"isa={isa!r}: this CPU runs at most {native!r} (CPU flags of "
                              "/proc/cpuinfo); its instructions would stop the process")
        self.nZ, self.nQ, self.nR = (step.nnz_in(i) for i in range(3))
        self.slow = tuple(slow)
        self._step, self._trig = step, trig
        self._libm: VectorKernel | None = None     # the libmvec-sine twin, on first need
        self._lock = threading.Lock()
        try:
            self._build(step, cc, isa, lanes)
        except CompileError as e:
            if isa == "portable":
                raise
            warnings.warn(f"the compiler refused the {isa} flags ({str(e)[-300:]}); the vector "
                          "kernel is built with the portable flags (slower)", QuadcogWarning,
                          stacklevel=2)
            self._build(step, cc, "portable", lanes)
        self._fn = ctypes.CDLL(str(self.library)).qc_kernel
        self._fn.restype = ctypes.c_long
        self._fn.argtypes = [ctypes.c_long, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                             ctypes.c_long, ctypes.POINTER(ctypes.c_long)]

    def _build(self, step, cc, isa, lanes):
        self.isa = isa
        self.lanes = lanes_for(isa, self.precision) if lanes is None else int(lanes)
        self.flags = vector_flags(isa, self.precision) + ("-Wl,--no-as-needed", "-lmvec")
        trig = self._trig or ("inline" if isa in INLINE_TRIG_ISAS else "libm")
        source = emit_c(step, "qc_kernel", self.lanes, self.precision, self.slow,
                        trig=trig, fma=isa in FMA_ISAS).encode()
        # the ISA in the name too: the flags are in the cache key already
        stem = f"vector_kernel_{isa}_" + hashlib.sha256(source).hexdigest()[:12]
        self.library = compile_library(source, stem, cc, flags=self.flags)

    def __call__(self, Z: np.ndarray, Q: np.ndarray, rows: np.ndarray,
                 threads: int = 1) -> np.ndarray:
        """Z after the steps of ``rows``.

        Parameters
        ----------
        Z : (B, nZ) array
            The flights' states (with their accumulators).
        Q : (B, nQ) array
            The flights' constant parameters.
        rows : (n, n_row) array
            The step table, shared by all flights.
        threads : int
            Threads that share the blocks.

        Returns
        -------
        (B, nZ) float64 array
        """
        real = NUMPY_TYPE[self.precision]
        Z, Q = np.asarray(Z, dtype=real), np.asarray(Q, dtype=real)
        B, L = Z.shape[0], self.lanes
        n_blocks = -(-B // L)
        pad = n_blocks * L - B
        if pad:            # copies of the last flight fill the last block's free lanes
            Z = np.vstack([Z, np.repeat(Z[-1:], pad, axis=0)])
            Q = np.vstack([Q, np.repeat(Q[-1:], pad, axis=0)])
        Zb = np.ascontiguousarray(Z.reshape(n_blocks, L, self.nZ).transpose(0, 2, 1))
        Qb = np.ascontiguousarray(Q.reshape(n_blocks, L, self.nQ).transpose(0, 2, 1))
        rows = np.ascontiguousarray(rows, dtype=real)
        n = rows.shape[0]
        threads = max(1, min(int(threads), n_blocks))
        bounds = np.linspace(0, n_blocks, threads + 1).round().astype(int)

        def work(t):
            lo, hi = bounds[t], bounds[t + 1]
            stopped = ctypes.c_long(0)
            while hi > lo:
                b = self._fn(n, rows.ctypes.data, Zb[lo:hi].ctypes.data, Qb[lo:hi].ctypes.data,
                             hi - lo, ctypes.byref(stopped))
                if b < 0:
                    break
                lo += b          # this block met a large angle: on from there with libm's
                k = stopped.value
                Zb[lo] = self._libm_kernel().blocks(Zb[lo:lo + 1], Qb[lo:lo + 1], rows[k:])[0]
                lo += 1
        if threads == 1:
            work(0)
        else:            # exactly `threads` threads (a pool may reuse one for short shares)
            pool = [threading.Thread(target=work, args=(t,)) for t in range(threads)]
            for th in pool:
                th.start()
            for th in pool:
                th.join()
        out = Zb.transpose(0, 2, 1).reshape(n_blocks * L, self.nZ)[:B]
        return out.astype(np.float64)

    def _libm_kernel(self) -> "VectorKernel":
        """The same kernel with libmvec's sines (no stop), built on first need."""
        with self._lock:
            if self._libm is None:
                self._libm = VectorKernel(self._step, self.lanes, self.isa, self.precision,
                                          self.slow, trig="libm")
            libm: VectorKernel = self._libm
        return libm

    def blocks(self, Zb: np.ndarray, Qb: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """Whole blocks (the kernel's layout, ``(n_blocks, nZ, lanes)``) after the steps of
        ``rows``, one thread; a kernel built with trig="libm" never stops early.

        Parameters
        ----------
        Zb : (n_blocks, nZ, lanes) array
            The blocks' states, in the kernel's precision, C order.
        Qb : (n_blocks, nQ, lanes) array
            Their parameters.
        rows : (n, n_row) array
            The step table, C order.

        Returns
        -------
        (n_blocks, nZ, lanes) array
            The states after the steps.
        """
        Zb = np.array(Zb, order="C")
        Qb, rows = np.ascontiguousarray(Qb), np.ascontiguousarray(rows)
        stopped = ctypes.c_long(0)
        b = self._fn(rows.shape[0], rows.ctypes.data, Zb.ctypes.data, Qb.ctypes.data,
                     Zb.shape[0], ctypes.byref(stopped))
        if b >= 0:
            raise KernelError(f"block {b} stopped at step {stopped.value} in a kernel with "
                              "libm's sines")
        return Zb


_kernels: dict = {}
_warned: list = []


def kernel_for(key: Hashable, build_step: Callable[[], ca.Function], required: bool = False,
               precision: str = "float64", isa: str | None = None,
               slow: Sequence[int] = ()) -> "VectorKernel | None":
    """The VectorKernel of the step that ``build_step()`` makes, once per key and process.

    Parameters
    ----------
    key : hashable
        What identifies the step (the precision and ISA are added to it).
    build_step : callable
        ``build_step() -> casadi.Function``, the SX step.
    required : bool
        Raise KernelError instead of returning None where the kernel cannot be built.
    precision : str
        "float64" or "float32".
    isa : str, optional
        One of ``ISAS`` (default ``kernel_isa()``).
    slow : sequence of int
        The nonzeros of the row that change seldom (``emit_c``).

    Returns
    -------
    VectorKernel or None
        None (after one QuadcogWarning) without a C compiler, or where the C does not build
        (no libmvec: not glibc on x86-64); callers then use CasADi's map.
    """
    precision = _check_precision(precision)
    isa = kernel_isa() if isa is None else _check_isa(isa)
    key = (key, precision, isa, tuple(slow))
    if key not in _kernels:
        try:
            _kernels[key] = VectorKernel(build_step(), isa=isa, precision=precision, slow=slow)
        except (KernelError, CompileError) as e:
            if required:
                raise KernelError(f"the vector kernel cannot be built here: {e}") from None
            if not _warned:
                warnings.warn(f"vector kernel unavailable ({str(e)[:200]}); batches run "
                              "through CasADi's map (slower)", QuadcogWarning, stacklevel=3)
                _warned.append(True)
            _kernels[key] = None
    return _kernels[key]
