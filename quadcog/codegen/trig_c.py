"""Sine, cosine and tangent as inline C, for the compiled loops of a flight.

A call to libm's ``sin`` or libmvec's vector ``sin`` clobbers every vector register (the x86-64
ABI saves none), so around each of the step's 13 angles the vector kernel stored its live
values to the stack and read them back; inline, the compiler keeps them, and the sine and
cosine of one angle share their reduction. On a Zen 3 (AVX2) the batch step got about a tenth
faster (docs/performance.md has the measured figures).

- **Reduction** (Cody and Waite): ``k = round(x 2/pi)`` by the ``1.5 * 2**52`` trick, whose low
  bits are also ``k mod 4`` (the quadrant); ``r = x - k pi/2`` with pi/2 in three parts, the
  first two of 33 bits, so that ``k`` times each is exact while ``|x| < LARGE``.
- **Kernels on [-pi/4, pi/4]**: the minimax polynomials of fdlibm's ``__kernel_sin`` (degree 13)
  and ``__kernel_cos`` (degree 14); the sine keeps the sign of r (at r = -0 too).
- **Quadrant**: sine and cosine swapped for odd k, the sign bit flipped by bit 1 of k (of k + 1
  for the cosine); the tangent is their quotient.
- **Large arguments**, ``|x| >= LARGE`` (1.6e6 rad): libm's ``sin`` and ``cos`` with their full
  reduction. The single-flight kernel branches to them (``scalar_c(fallback=True)``); the vector
  kernel cannot branch per lane: a block whose step meets one stops before it and flies on
  with libmvec's sines (``quadcog.codegen.vector_kernel.VectorKernel``). The sensing noise's hash takes the sine of
  ``a t + b`` with b of ~1e10 for a large seed, so such arguments do occur.

tests/test_trig_c.py holds sin and cos within 2 ulp of numpy's (glibc's), tan within 4,
around every multiple of pi/2 up to ``LARGE``, at its edge, beyond it, and at +-0, inf and NaN.
Both kernels (``quadcog.codegen.vector_kernel``, ``quadcog.codegen.flight_kernel``) use this one
definition.
"""
__all__ = ["LARGE", "scalar_c"]

# |x| at and above which libm reduces: k < 2**20, so k times each 33-bit part of pi/2 is exact
LARGE = 2.0 ** 19 * 3.14159265358979311600e+00   # 1647099.3...: (2**20) * pi/2

_PARTS = ("1.57079632673412561417e+00",      # pi/2, first 33 bits
          "6.07710050630396597660e-11",      # the next 33 bits
          "2.02226624879595063154e-21")      # the rest, to double precision
_SIN = ("-1.66666666666666324348e-01", "8.33333333332248946124e-03",
        "-1.98412698298579493134e-04", "2.75573137070700676789e-06",
        "-2.50507602534068634195e-08", "1.58969099521155010221e-10")
_COS = ("4.16666666666666019037e-02", "-1.38888888888741095749e-03",
        "2.48015872894767294178e-05", "-2.75573143513906633035e-07",
        "2.08757232129817482790e-09", "-1.13596475577881948265e-11")


def _horner(coefficients, z):
    """C text of c0 + z (c1 + z (c2 + ...))."""
    text = coefficients[-1]
    for c in reversed(coefficients[:-1]):
        text = f"{c} + {z} * ({text})"
    return text


def _body(T, B, splat, mask_of, select, tail, copysign):
    """The shared C of the reduction and kernels for type T (bits type B)."""
    k = splat
    return f"""
static inline {T} qc_trig_r_({T} x, {B} *q) {{
  {T} kd = x * {k('6.36619772367581382433e-01')} + {k('0x1.8p52')};
  memcpy(q, &kd, sizeof kd);
  {T} n = kd - {k('0x1.8p52')};
  return ((x - n * {k(_PARTS[0])}) - n * {k(_PARTS[1])}) - n * {k(_PARTS[2])};
}}
static inline {T} qc_trig_s_({T} r) {{
  {T} z = r * r;
  /* the sign of r again: at r = -0 the sum is +0 (fdlibm returns a tiny r itself) */
  return {copysign('r + z * r * (' + k(_SIN[0]) + ' + z * (' + _horner([k(c) for c in _SIN[1:]], 'z') + '))', 'r')};
}}
static inline {T} qc_trig_c_({T} r) {{
  {T} z = r * r, hz = {k('0.5')} * z, w = {k('1.0')} - hz;
  return w + ((({k('1.0')} - w) - hz) + z * (z * ({_horner([k(c) for c in _COS], 'z')})));
}}
static inline {T} qc_trig_sign_({T} v, {B} bit) {{
  {B} b; memcpy(&b, &v, sizeof b); b ^= bit << 63; memcpy(&v, &b, sizeof v); return v;
}}
static inline {T} qc_sin({T} x) {{
  {B} q; {T} r = qc_trig_r_(x, &q), s = qc_trig_s_(r), c = qc_trig_c_(r);
  {T} v = qc_trig_sign_({select(mask_of('q & 1'), 'c', 's')}, (q >> 1) & 1);
  {tail('sin')}
}}
static inline {T} qc_cos({T} x) {{
  {B} q; {T} r = qc_trig_r_(x, &q), s = qc_trig_s_(r), c = qc_trig_c_(r);
  {T} v = qc_trig_sign_({select(mask_of('q & 1'), 's', 'c')}, ((q + 1) >> 1) & 1);
  {tail('cos')}
}}
static inline {T} qc_tan({T} x) {{ return qc_sin(x) / qc_cos(x); }}
"""


def scalar_c(fallback: bool = True) -> str:
    """The C of ``qc_sin``, ``qc_cos`` and ``qc_tan`` on doubles.

    Parameters
    ----------
    fallback : bool
        Send ``|x| >= LARGE`` to libm's sin and cos (a branch: the single-flight kernel's).
        Without it the functions have no branch and gcc vectorizes them in a ``#pragma omp
        simd`` loop; the caller then handles large arguments (the vector kernel stops such a
        block and flies it on with libmvec's sines, ``quadcog.codegen.vector_kernel``).

    Returns
    -------
    str
        C text: includes, declarations of libm's sin, cos and fabs, the static inline
        functions.
    """
    if fallback:
        tail = lambda f: f"return fabs(x) < {LARGE!r} ? v : {f}(x);"
    else:
        tail = lambda f: "return v;"
    return ("#include <stdint.h>\n#include <string.h>\ndouble sin(double);\ndouble cos(double);\n"
            "double fabs(double);\n" + _body("double", "uint64_t", lambda c: c,
                                             lambda m: f"({m})",
                                             lambda m, a, b: f"{m} ? {a} : {b}", tail,
                                             lambda a, b: f"__builtin_copysign({a}, {b})"))
