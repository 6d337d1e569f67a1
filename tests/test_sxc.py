"""quadcog.codegen.sx_to_c, the one table from CasADi operations to C: every operation in it, emitted by
both C emitters (the embedded export in double and float32, the vector kernel), compiled with
the C compiler and evaluated at points with zeros of both signs, equal operands and NaN, gives
CasADi's own values; an operation missing from the table is refused with each emitter's typed
error, naming it."""
import ctypes
import math
import platform
import subprocess

import casadi as ca
import numpy as np
import pytest

from quadcog.codegen import sx_to_c as sxc
from quadcog.codegen.compiler import find_compiler
from quadcog.codegen.vector_kernel import VectorKernel, emit_c, vector_flags
from quadcog.embedded.emit import C_TYPE, body
from quadcog.errors import ExportError, KernelError

CC = find_compiler()
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler")

# exact in float32, so the float32 code sees the same operands as CasADi's double evaluation
VALUES = (0.375, -0.75, 0.0, -0.0, 1.0, 2.5, math.nan)
POINTS = np.array([(a, b) for a in VALUES for b in VALUES])       # 49: not a multiple of 16
# results that IEEE 754 / C99 define exactly (correctly rounded or exact selects); the others
# come from a math library (glibc's libm, libmvec's vector versions, CasADi's), to a few ulp
EXACT = {ca.OP_ADD, ca.OP_SUB, ca.OP_MUL, ca.OP_DIV, ca.OP_NEG, ca.OP_SQ, ca.OP_TWICE,
         ca.OP_INV, ca.OP_LT, ca.OP_LE, ca.OP_EQ, ca.OP_NE, ca.OP_NOT, ca.OP_AND, ca.OP_OR,
         ca.OP_IF_ELSE_ZERO, ca.OP_SIGN, ca.OP_SQRT, ca.OP_FABS, ca.OP_FLOOR, ca.OP_CEIL,
         ca.OP_FMOD, ca.OP_COPYSIGN, ca.OP_FMIN, ca.OP_FMAX}
# OP_ASSIGN never appears in an SX Function's algorithm (CasADi folds it away): its template
# is the operand itself
NOT_IN_SX = {ca.OP_ASSIGN}


def every_operation(skip=()):
    """(ops, step): step(Z (n), Q (1), row (1)) -> Z_next (n), entry k of Z_next being ops[k]
    applied to a = Z[0] (and b = Z[1]); every operation of quadcog.codegen.sx_to_c.OPERATIONS but
    NOT_IN_SX and ``skip``."""
    ops = [op for op in sxc.OPERATIONS if op not in NOT_IN_SX and op not in skip]
    Z, Q, row = ca.SX.sym("Z", len(ops)), ca.SX.sym("Q"), ca.SX.sym("row")
    a, b = Z[0], Z[1]
    out = []
    for op in ops:
        if op == ca.OP_CONSTPOW:
            out.append(ca.SX.binary(op, a, ca.SX(2.5)))
        elif "{1}" in sxc.OPERATIONS[op]:
            out.append(ca.SX.binary(op, a, b))
        else:
            out.append(ca.SX.unary(op, a))
    step = ca.Function("every_op", [Z, Q, row], [ca.vertcat(*out)], ["Z", "Q", "row"], ["Zn"])
    return ops, step


def test_the_function_exercises_every_operation_of_the_table():
    ops, step = every_operation()
    seen = {step.instruction_id(k) for k in range(step.n_instructions())}
    assert set(sxc.OPERATIONS) - NOT_IN_SX <= seen, [
        sxc.op_name(op) for op in set(sxc.OPERATIONS) - NOT_IN_SX - seen]


def _casadi(step, n):
    return np.array([np.asarray(step(np.r_[p, np.zeros(n - 2)], 0.0, 0.0)).ravel()
                     for p in POINTS])


def _embedded(step, n, precision, tmp_path):
    """Through quadcog.embedded.emit.body, compiled like the committed modules on the host."""
    decls, stmts, _ = body(step, precision, ["a", "q", "row"], ["y"])
    real = C_TYPE[precision]
    src = tmp_path / f"every_op_{precision}.c"
    src.write_text("#include <math.h>\n"
                   f"typedef {real} qc_real;\n"
                   "void every_op(const qc_real a[], qc_real q, qc_real row, qc_real y[]);\n"
                   "void every_op(const qc_real a[], qc_real q, qc_real row, qc_real y[])\n{\n"
                   "    (void)q;\n    (void)row;\n" + "\n".join(decls + stmts) + "\n}\n")
    lib = tmp_path / f"every_op_{precision}.so"
    r = subprocess.run([CC, "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Wdouble-promotion",
                        "-Wfloat-conversion", "-Werror", "-O2", "-shared", "-fPIC", str(src),
                        "-o", str(lib), "-lm"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-3000:]
    fn = ctypes.CDLL(str(lib)).every_op
    dtype = np.float32 if precision == "float32" else np.float64
    scalar = ctypes.c_float if precision == "float32" else ctypes.c_double
    fn.restype = None
    fn.argtypes = [ctypes.c_void_p, scalar, scalar, ctypes.c_void_p]
    out = np.zeros((len(POINTS), n), dtype=dtype)
    for i, p in enumerate(POINTS):
        a = np.zeros(n, dtype=dtype)
        a[:2] = p
        fn(a.ctypes.data, 0.0, 0.0, out[i].ctypes.data)
    return out.astype(float)


def _kernel(step, n):
    """Through quadcog.codegen.vector_kernel.emit_c, one step of a batch of len(POINTS) flights."""
    Z = np.zeros((len(POINTS), n))
    Z[:, :2] = POINTS
    return VectorKernel(step)(Z, np.zeros((len(POINTS), 1)), np.zeros((1, 1)))


def _check(name, ops, got, want, rtol_math, rtol_exact=0.0):
    bad = []
    for k, op in enumerate(ops):
        g, w = got[:, k], want[:, k]
        rtol = rtol_exact if op in EXACT else rtol_math
        nan = np.isnan(g) != np.isnan(w)
        ok = np.isnan(g) & np.isnan(w)
        ok |= (g == w) | np.isclose(g, w, rtol=rtol, atol=0.0)
        signed = ~np.isnan(w)
        if op in (ca.OP_FMIN, ca.OP_FMAX):       # C99 leaves the sign of fmin(0, -0) open
            signed &= (POINTS[:, 0] != 0) | (POINTS[:, 1] != 0)
        ok &= (np.signbit(g) == np.signbit(w)) | ~signed
        for i in np.flatnonzero(~ok | nan):
            bad.append(f"{sxc.op_name(op)}{tuple(POINTS[i])}: {name} {g[i]!r}, CasADi {w[i]!r}")
    assert not bad, "\n".join(bad[:40])


@needs_cc
def test_both_emitters_agree_with_casadi_on_every_operation(tmp_path):
    ops, step = every_operation()
    n = len(ops)
    want = _casadi(step, n)
    double = _embedded(step, n, "double", tmp_path)
    _check("embedded double", ops, double, want, rtol_math=4e-16)
    # float32: one rounding of the result (and float32 libm's few ulp)
    _check("embedded float32", ops, _embedded(step, n, "float32", tmp_path), want,
           rtol_math=1e-6, rtol_exact=1.2e-7)
    kernel = _kernel(step, n)
    _check("kernel", ops, kernel, want, rtol_math=1e-14)     # libmvec, trig_c: a few ulp
    # and the two double paths agree bit for bit on what IEEE 754 defines exactly
    exact = [k for k, op in enumerate(ops) if op in EXACT]
    assert double[:, exact].tobytes() == kernel[:, exact].tobytes()


@needs_cc
@pytest.mark.skipif(platform.machine() != "x86_64", reason="checks gcc's x86-64 vectorizer")
@pytest.mark.parametrize("isa", ["avx2", "avx512"])
def test_every_operation_of_the_table_vectorizes_in_the_kernel(tmp_path, isa):
    """The shared forms (the logic as selects, fmin/fmax as selects) and every math function
    are vector code in the kernel, for either ISA whatever this CPU runs (compiled only):
    libmvec's, or inline for sin, cos and tan; only fmod has no vector form (libmvec has
    none)."""
    _, step = every_operation(skip={ca.OP_FMOD})
    src = tmp_path / "k.c"
    src.write_text(emit_c(step))
    flags = [f for f in vector_flags(isa) if f not in ("-shared", "-fPIC")]
    r = subprocess.run([CC, *flags, "-fopt-info-vec-optimized", "-c", str(src), "-o",
                        str(tmp_path / "k.o")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "loop vectorized" in r.stderr, r.stderr[-2000:]
    nm = subprocess.run(["nm", str(tmp_path / "k.o")], capture_output=True, text=True).stdout
    abi = {"avx2": "_ZGVd", "avx512": "_ZGVe"}[isa]      # the vector ABI's ISA letter
    for f in ("asin", "erf", "hypot", "atan2", "pow"):
        assert any(line.startswith(abi) and line.endswith("_" + f)
                   for line in nm.split()), (f, nm)
    for f in ("sin", "cos", "tan"):      # inline (quadcog.codegen.trig_c)
        assert not any(line.startswith(abi) and line.endswith("_" + f)
                       for line in nm.split()), (f, nm)


def test_an_operation_missing_from_the_table_is_named():
    Z, Q, row = ca.SX.sym("Z", 2), ca.SX.sym("Q"), ca.SX.sym("row")
    assert ca.OP_ERFINV not in sxc.OPERATIONS
    step = ca.Function("uses_erfinv", [Z, Q, row], [ca.vertcat(ca.erfinv(Z[0]), Z[1])])
    for precision in ("double", "float32"):
        with pytest.raises(ExportError, match="uses_erfinv: CasADi operation OP_ERFINV"):
            body(step, precision, ["z", "q", "row"], ["zn"])
    with pytest.raises(KernelError, match="uses_erfinv: CasADi operation OP_ERFINV"):
        emit_c(step)
