"""The vectorized batch kernel: a closed-loop step of many flights in the CPU's vector lanes.

A batch step is a CasADi SX Function ``step(Z, Q, row) -> Z_next``: Z the state of one flight
(with its metric accumulators), Q its constant parameters, row the step's entry of the step
table (shared by all flights). This module emits C from the step's SX instructions (the
operations and the walk are quadcog.codegen.sx_to_c's, shared with the embedded export) with
the flight index as the innermost loop of every operation: flights go in blocks of ``LANES``, the
whole step is one ``#pragma omp simd`` loop over a block, and gcc turns every operation into a
vector instruction, with glibc's libmvec for sin, cos, tan and atan2. A block's state stays in
the L1 cache for all its steps, so memory traffic is a few hundred bytes per flight.

The C is compiled through the build cache (its key holds the flags), loaded with ctypes (which
releases the GIL), and called from ``threads`` Python threads, each on its own share of the
blocks: the thread count asked for is the thread count used. A flight's bits do not depend on
the block it is in (every lane runs the same vector code; a partial block is padded), so
results are the same for any batch size, thread count or chunking.
"""
from collections.abc import Callable, Hashable
import ctypes
import hashlib
import math
import platform
import threading
import warnings

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog.codegen import sx_to_c as sxc
from quadcog.codegen.compiler import compile_library, find_compiler
from quadcog.errors import CompileError, KernelError, QuadcogWarning

__all__ = ["LANES", "vector_flags", "emit_c", "VectorKernel", "kernel_for"]

LANES = 16         # flights per block: four AVX2 vectors of doubles per operation

# functions libmvec provides in vector form (glibc >= 2.35 for tan, atan2, erf, hypot, ...)
_VECTOR_MATH = ("sin", "cos", "tan", "exp", "log", "pow", "atan2", "atan", "asin", "acos",
                "tanh", "sinh", "cosh", "erf", "hypot")


def _literal(v):
    """A C double literal, exact (repr round-trips), with inf and NaN spelled for C."""
    v = float(v)
    if math.isnan(v):
        return "__builtin_nan(\"\")"
    if math.isinf(v):
        return "__builtin_inf()" if v > 0 else "(-__builtin_inf())"
    return repr(v)


# exact double literals, fmin/fmax as selects (a call would stop the vectorizer)
_TARGET = sxc.Target(literal=_literal, suffix="", selects=True, error=KernelError)


def vector_flags() -> tuple[str, ...]:
    """Compiler flags for this CPU.

    No -ffast-math: IEEE arithmetic, only errno and traps are given up (which lets sqrt and
    the libmvec calls vectorize).

    Returns
    -------
    tuple of str
        AVX2 + FMA where /proc/cpuinfo lists them (x86-64), else the baseline.
    """
    flags = ["-O3", "-fno-math-errno", "-fno-trapping-math", "-fopenmp-simd", "-fno-builtin-sin",
             "-fno-builtin-cos", "-shared", "-fPIC"]
    if platform.machine() in ("x86_64", "AMD64"):
        try:
            with open("/proc/cpuinfo") as fh:
                cpu = next((line for line in fh if line.startswith("flags")), "").split()
        except OSError:
            cpu = []
        if "avx2" in cpu and "fma" in cpu:
            flags[1:1] = ["-mavx2", "-mfma"]
    return tuple(flags)


def emit_c(step: ca.Function, name: str = "qc_kernel", lanes: int = LANES) -> str:
    """C source of ``void name(long n_steps, const double *rows, double *Z, const double *Q,
    long n_blocks)`` for the SX Function ``step(Z, Q, row) -> Z_next``.

    Layouts (C order): rows (n_steps, n_row); Z (n_blocks, nZ, lanes), updated in place;
    Q (n_blocks, nQ, lanes).

    Parameters
    ----------
    step : casadi.Function
        The SX Function ``step(Z, Q, row) -> Z_next``, Z_next of the size of Z.
    name : str, optional
        Name of the C function.
    lanes : int, optional
        Flights per block.

    Returns
    -------
    str
        The C translation unit.

    Raises
    ------
    KernelError
        ``step`` is not an SX Function of that form, or uses an operation without a C form.
    """
    if not step.is_a("SXFunction"):
        raise KernelError(f"{step.name()}: expected an SX Function")
    nZ, nQ, nR = (step.nnz_in(i) for i in range(3))
    if step.nnz_out(0) != nZ or step.n_in() != 3 or step.n_out() != 1:
        raise KernelError(f"{step.name()}: expected step(Z, Q, row) -> Z_next of equal size")
    inputs = (lambda nz: f"z[{nz * lanes}+j]", lambda nz: f"q[{nz * lanes}+j]",
              lambda nz: f"row[{nz}]")
    c = sxc.walk(step, _TARGET, read=lambda i, nz: inputs[i](nz),
                 write=lambda i, nz: f"zn[{nz * lanes}+j]")
    # const + simd: gcc may call libmvec's vector versions (flags: -fno-builtin-sin/cos, or
    # gcc merges sin and cos into a sincos that has no vector form); sqrt, fabs, floor, ceil
    # and copysign are inlined as vector instructions
    decls = "".join(f"double {f}({', '.join(['double'] * n)})"
                    + (" __attribute__((const, __simd__(\"notinbranch\")))"
                       if f in _VECTOR_MATH else "") + ";\n"
                    for f, n in sorted(c.calls.items()))
    work = ", ".join(f"w{i}" for i in range(step.sz_w()))
    lines = "\n      ".join(c.statements)
    return f"""/* quadcog vector kernel for {step.name()}: generated, do not edit. */
{decls}#define LANES {lanes}
#define NZ {nZ}
#define NQ {nQ}
#define NR {nR}
void {name}(long n_steps, const double *rows, double *Z, const double *Q, long n_blocks) {{
  for (long b = 0; b < n_blocks; ++b) {{
    double *z = Z + b * NZ * LANES;
    const double *q = Q + b * NQ * LANES;
    double zn[NZ * LANES] __attribute__((aligned(64)));
    for (long k = 0; k < n_steps; ++k) {{
      const double *row = rows + k * NR;
      #pragma omp simd
      for (long j = 0; j < LANES; ++j) {{
      double {work};
      {lines}
      }}
      for (long i = 0; i < NZ * LANES; ++i) z[i] = zn[i];
    }}
  }}
}}
"""


class VectorKernel:
    """A compiled vector kernel: ``kernel(Z (B, nZ), Q (B, nQ), rows (n, n_row), threads)``
    returns Z after the n steps (B, nZ).

    Parameters
    ----------
    step : casadi.Function
        The SX Function ``step(Z, Q, row) -> Z_next`` (see ``emit_c``).
    lanes : int, optional
        Flights per block.

    Raises
    ------
    KernelError
        No C compiler, or ``step`` cannot be written as C.
    CompileError
        The C does not build here (e.g. no libmvec).
    """

    def __init__(self, step: ca.Function, lanes: int = LANES) -> None:
        cc = find_compiler()
        if cc is None:
            raise KernelError("no C compiler")
        self.lanes = lanes
        self.nZ, self.nQ, self.nR = (step.nnz_in(i) for i in range(3))
        source = emit_c(step, "qc_kernel", lanes).encode()
        stem = "vector_kernel_" + hashlib.sha256(source).hexdigest()[:12]
        self.library = compile_library(source, stem, cc,
                                       flags=vector_flags() + ("-Wl,--no-as-needed", "-lmvec"))
        self._fn = ctypes.CDLL(str(self.library)).qc_kernel
        self._fn.restype = None
        self._fn.argtypes = [ctypes.c_long, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                             ctypes.c_long]

    def __call__(self, Z: npt.ArrayLike, Q: npt.ArrayLike, rows: npt.ArrayLike,
                 threads: int = 1) -> npt.NDArray[np.float64]:
        Z, Q = np.asarray(Z, dtype=float), np.asarray(Q, dtype=float)
        B, L = Z.shape[0], self.lanes
        n_blocks = -(-B // L)
        pad = n_blocks * L - B
        if pad:            # copies of the last flight fill the last block's free lanes
            Z = np.vstack([Z, np.repeat(Z[-1:], pad, axis=0)])
            Q = np.vstack([Q, np.repeat(Q[-1:], pad, axis=0)])
        Zb = np.ascontiguousarray(Z.reshape(n_blocks, L, self.nZ).transpose(0, 2, 1))
        Qb = np.ascontiguousarray(Q.reshape(n_blocks, L, self.nQ).transpose(0, 2, 1))
        rows = np.ascontiguousarray(rows, dtype=float)
        n = rows.shape[0]
        threads = max(1, min(int(threads), n_blocks))
        bounds = np.linspace(0, n_blocks, threads + 1).round().astype(int)

        def work(t: int) -> None:
            lo, hi = bounds[t], bounds[t + 1]
            if hi > lo:
                self._fn(n, rows.ctypes.data, Zb[lo:hi].ctypes.data, Qb[lo:hi].ctypes.data,
                         hi - lo)
        if threads == 1:
            work(0)
        else:            # exactly `threads` threads (a pool may reuse one for short shares)
            pool = [threading.Thread(target=work, args=(t,)) for t in range(threads)]
            for th in pool:
                th.start()
            for th in pool:
                th.join()
        return Zb.transpose(0, 2, 1).reshape(n_blocks * L, self.nZ)[:B].copy()


_kernels: dict[Hashable, VectorKernel | None] = {}
_warned: list[bool] = []


def kernel_for(key: Hashable, build_step: Callable[[], ca.Function],
               required: bool = False) -> VectorKernel | None:
    """The VectorKernel of the step that ``build_step()`` makes, once per ``key`` and process.

    Parameters
    ----------
    key : hashable
        What identifies the step in this process.
    build_step : callable
        ``build_step() -> casadi.Function``, the SX step (called the first time only).
    required : bool, optional
        Raise instead of returning None when the kernel cannot be built.

    Returns
    -------
    VectorKernel or None
        The kernel; None without a C compiler, or where the C does not build (no libmvec:
        not glibc on x86-64), after one QuadcogWarning (callers then use CasADi's map).

    Raises
    ------
    KernelError
        When ``required`` and the kernel cannot be built here.
    """
    if key not in _kernels:
        try:
            _kernels[key] = VectorKernel(build_step())
        except (KernelError, CompileError) as e:
            if required:
                raise KernelError(f"the vector kernel cannot be built here: {e}") from None
            if not _warned:
                warnings.warn(f"vector kernel unavailable ({str(e)[:200]}); batches run "
                              "through CasADi's map (slower)", QuadcogWarning, stacklevel=3)
                _warned.append(True)
            _kernels[key] = None
    return _kernels[key]
