"""The inline sine, cosine and tangent of the compiled loops (quadcog.codegen.trig_c) against
glibc's (numpy's): sin and cos within 2 ulp, tan within 4, at random angles, at every kind of
multiple of pi/2 where the reduction cancels, at the edge of its range and beyond (libm takes
over), and at +-0, inf, NaN and subnormals; in scalar code (the single-flight kernel), in a vectorized loop, and in the
vector kernel, whose blocks fly on with libmvec's sines from a large angle."""
import ctypes
import math
import platform
import shutil

import casadi as ca
import numpy as np
import pytest

from quadcog.codegen import trig_c
from quadcog.codegen.compiler import compile_library
from quadcog.codegen.vector_kernel import INLINE_TRIG_ISAS, VectorKernel, detect_isa, vector_flags

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")
FUNCTIONS = {"sin": np.sin, "cos": np.cos, "tan": np.tan}


def _angles():
    rng = np.random.default_rng(7)
    L = trig_c.LARGE
    k = np.r_[np.arange(0, 200), rng.integers(0, 2 ** 20, 2000)].astype(float)
    near = k * (np.pi / 2)             # the doubles nearest k pi/2 and their neighbours
    near = np.r_[near, np.nextafter(near, np.inf), np.nextafter(near, -np.inf)]
    near = near[np.abs(near) < L]
    edge = np.array([L, np.nextafter(L, 0), np.nextafter(L, np.inf), 2 * L, 1e7, 1e10, 1.3e10,
                     1e16, 1e300, np.finfo(float).max])
    special = np.array([0.0, np.inf, np.nan, 5e-324, 1e-310, 2.2250738585072014e-308, 1e-20,
                        1e-9, np.pi / 4, 3 * np.pi / 4, 1.0, 2.5, 100.0])
    x = np.r_[rng.uniform(-10, 10, 20000), rng.uniform(-L, L, 20000),
              np.exp(rng.uniform(-40, math.log(L), 5000)), near, edge, special]
    return np.r_[x, -x]


X = _angles()


def _ulps(got, want):
    """|got - want| in units of the last place of want (0 where both are the same NaN or
    infinity, inf where only one is NaN)."""
    both_nan = np.isnan(got) & np.isnan(want)
    same = (got == want) | both_nan
    with np.errstate(invalid="ignore"):
        err = np.abs(got - want) / np.spacing(np.abs(want))
    err[same] = 0.0
    err[np.isnan(got) != np.isnan(want)] = np.inf
    return err


def _library(tmp_path, fallback, flags):
    loops = "".join(
        f"void many_{f}(long n, const double *x, double *out) {{\n"
        + ("#pragma omp simd\n" if not fallback else "")
        + f"  for (long i = 0; i < n; ++i) out[i] = qc_{f}(x[i]);\n}}\n" for f in FUNCTIONS)
    source = (trig_c.scalar_c(fallback) + loops).encode()
    lib = ctypes.CDLL(str(compile_library(source, f"trig_{int(fallback)}", flags=flags,
                                          folder=tmp_path)))
    out = {}
    for f in FUNCTIONS:
        x = X if fallback else X[np.abs(X) < trig_c.LARGE]    # no fallback: LARGE is the caller's
        y = np.empty_like(x)
        getattr(lib, f"many_{f}")(ctypes.c_long(x.size), x.ctypes.data_as(ctypes.c_void_p),
                                  y.ctypes.data_as(ctypes.c_void_p))
        out[f] = (x, y)
    return out


@np.errstate(invalid="ignore")         # numpy's sin(inf) is NaN, as it should be
def _check(results, ulps=2.0):
    for f, (x, y) in results.items():
        err = _ulps(y, FUNCTIONS[f](x))
        if f == "tan":       # a quotient of two results within 2 ulp each: 4 ulp
            err = err / 2
        worst = int(np.argmax(err))
        assert err[worst] <= ulps, (f, x[worst], y[worst], FUNCTIONS[f](x[worst]), err[worst])
        nz = ~np.isnan(y)              # the sign of every result, zeros included
        bad = np.flatnonzero(np.signbit(y[nz]) != np.signbit(FUNCTIONS[f](x[nz])))
        assert not bad.size, (f, x[nz][bad[:5]], y[nz][bad[:5]])


def test_scalar_with_libm_beyond_large(tmp_path):
    """The single-flight kernel's form: every double, large ones through libm."""
    _check(_library(tmp_path, True, ("-O3", "-ffp-contract=off", "-fno-math-errno", "-shared",
                                     "-fPIC")))


@pytest.mark.skipif(platform.machine() != "x86_64", reason="the vector kernel's x86 flags")
def test_vectorized_without_fallback(tmp_path):
    """The vector kernel's form, vectorized with the kernel's own flags for this CPU: the same
    accuracy below LARGE (no branch: the caller handles larger angles)."""
    flags = tuple(f for f in vector_flags(detect_isa()) if f not in ("-shared", "-fPIC"))
    _check(_library(tmp_path, False, flags + ("-shared", "-fPIC")))


def test_vector_kernel_flies_on_with_libmvec_from_a_large_angle():
    """A block that meets an angle of LARGE or more stops before that step and flies on with
    libmvec's sines (within 4 ulp of glibc's; the inline reduction would be far off there);
    the other blocks keep the inline ones; with two threads too, and at a later step."""
    Z, Q, row = ca.SX.sym("Z", 3), ca.SX.sym("Q"), ca.SX.sym("row")
    # x grows 1000-fold a step: its sine, cosine and tangent meet LARGE after a few steps
    step = ca.Function("trig", [Z, Q, row], [ca.vertcat(Z[0] * 1000.0, ca.sin(Z[0]),
                                                        ca.cos(Z[0]) + ca.tan(Z[0]))])
    rng = np.random.default_rng(3)
    x0 = np.r_[rng.uniform(-3, 3, 30), rng.uniform(1e-9, 1e-6, 20)]  # 4 blocks of 16
    Zv = np.column_stack([x0, np.zeros_like(x0), np.zeros_like(x0)])
    kernel = VectorKernel(step)
    x = x0.copy()                                  # the angle of the last step
    for steps in (1, 2, 3, 4):
        got = kernel(Zv, np.zeros((len(x0), 1)), np.zeros((steps, 1)), threads=2)
        assert np.array_equal(got[:, 0], x * 1000.0)
        assert _ulps(got[:, 1], np.sin(x)).max() <= 4, steps
        want = np.cos(x) + np.tan(x)
        assert np.all(np.abs(got[:, 2] - want) <= 8 * np.spacing(np.abs(np.tan(x)) + 1)), steps
        x = x * 1000.0
    assert kernel._libm is not None or kernel.isa not in INLINE_TRIG_ISAS   # it did fall back


def test_vector_kernel_large_angles_and_specials_in_one_step():
    """One step with 1.3e10, LARGE, -1e300, NaN, +-0 among ordinary angles: libmvec's values in
    the blocks that hold them (within 4 ulp of glibc's), NaN for NaN, the sign of zero kept."""
    Z, Q, row = ca.SX.sym("Z", 3), ca.SX.sym("Q"), ca.SX.sym("row")
    step = ca.Function("trig", [Z, Q, row], [ca.vertcat(ca.sin(Z[0]), ca.cos(Z[1]),
                                                        ca.tan(Z[2]))])
    rng = np.random.default_rng(3)
    x = np.r_[rng.uniform(-3, 3, 40), 1.3e10, trig_c.LARGE, -1e300, np.nan, 0.25, -0.0]
    Zv = np.column_stack([x, x[::-1], np.roll(x, 5)])
    got = VectorKernel(step)(Zv, np.zeros((len(x), 1)), np.zeros((1, 1)))
    for col, f in enumerate(FUNCTIONS.values()):
        with np.errstate(invalid="ignore"):
            want = f(Zv[:, col])
        err = _ulps(got[:, col], want)
        assert err.max() <= 4, (col, Zv[np.argmax(err), col])
        assert np.array_equal(np.signbit(got[:, col]), np.signbit(want))
