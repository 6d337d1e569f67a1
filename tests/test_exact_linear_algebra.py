"""quadcog.numerics' exact linear algebra against independent oracles.

SymPy's rational matrices give the exact answers (rounded once to floats, they must equal ours
bit for bit); SciPy's float solvers and textbook formulas check the equations are the right
ones; a subprocess under another OpenBLAS kernel checks that nothing goes through BLAS.
"""
import json
import os
import subprocess
import sys

import numpy as np
import pytest
from scipy.linalg import solve_continuous_lyapunov
from scipy.signal import place_poles
import sympy as sp

from quadcog.errors import ParameterError
from quadcog.numerics import exact_inverse, exact_lyapunov, exact_place, exact_solve
from quadcog.vehicles.vehicle import HUMMINGBIRD

RNG = np.random.default_rng(20261202)


def rational(M):
    return sp.Matrix([[sp.Rational(float(v)) for v in row] for row in np.atleast_2d(M)])


def floats(M):
    return np.array([[float(v) for v in row] for row in M.tolist()])


@pytest.mark.parametrize("n", [2, 3, 4, 5])
def test_inverse_and_solve_are_the_exact_answers_rounded(n):
    A = RNG.normal(size=(n, n))
    b = RNG.normal(size=(n, 2))
    exact = rational(A).inv()
    assert np.array_equal(exact_inverse(A), floats(exact))
    assert np.array_equal(exact_solve(A, b), floats(exact * rational(b)))
    assert exact_solve(A, b[:, 0]).shape == (n,)


def test_an_integer_matrix_has_its_integer_inverse():
    # the Pascal matrix has determinant 1 and an integer inverse; floats round it (cond ~ 1e7)
    P = np.array([[float(sp.binomial(i + j, i)) for j in range(7)] for i in range(7)])
    inv = exact_inverse(P)
    assert np.array_equal(inv, np.round(inv))
    assert np.array_equal(inv @ P, np.eye(7))


def test_the_mixer_inverse_is_the_textbook_one_with_exact_zeros():
    v = HUMMINGBIRD
    inv = v.mixer_inverse()
    pos = np.asarray(v.rotor_positions)
    # a "+" quad: rotor i on one axis at distance l takes U1/4, its moment arm's share of
    # U2 or U3 (1/(2l), the opposite rotor the other half) and U4/(4 k_i d_i)
    l = np.max(np.abs(pos))
    expected = np.zeros((4, 4))
    for i, (x, y) in enumerate(pos[:, :2]):
        expected[i] = [0.25, y / (2 * l * l), -x / (2 * l * l),
                       1 / (4 * v.moment_constant * v.rotor_directions[i])]
    assert np.array_equal(inv == 0, expected == 0)
    np.testing.assert_allclose(inv, expected, rtol=1e-15, atol=0)
    f = np.array([1.0, 2.0, 3.0, 4.0])
    np.testing.assert_allclose(v.rotor_thrusts(v.mixer() @ f), f, rtol=1e-14)


@pytest.mark.parametrize("n, decoupled", [(2, False), (4, False), (6, False), (4, True),
                                          (8, True)])
def test_lyapunov_is_scipys_equation_solved_exactly(n, decoupled):
    A = RNG.normal(size=(n, n)) - 3 * np.eye(n)
    if decoupled:   # the error dynamics' shape: channels A does not couple, in shuffled order
        A = np.kron(np.eye(n // 2), A[:2, :2])
        order = RNG.permutation(n)
        A = A[np.ix_(order, order)]
    Q = RNG.normal(size=(n, n))
    Q = Q @ Q.T + np.eye(n)
    P = exact_lyapunov(A, Q)
    ref = solve_continuous_lyapunov(A.T, -Q)
    np.testing.assert_allclose(P, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())
    if n <= 4:      # the exact solution, rounded once, from SymPy's own linear solve
        Ps = sp.Matrix(n, n, lambda i, j: sp.Symbol(f"p{i}_{j}"))
        eqs = rational(A).T * Ps + Ps * rational(A) + rational(Q)
        sol = sp.solve(list(eqs), list(Ps), rational=True)
        assert np.array_equal(P, floats(Ps.subs(sol)))


def test_lyapunov_of_a_second_order_error_is_the_textbook_one():
    # A = [[0, 1], [-kp, -kd]], Q = I: P = [[(kp^2 + kp + kd^2) / (2 kp kd), 1 / (2 kp)],
    #                                       [1 / (2 kp), (1 + kp) / (2 kp kd)]]
    kp, kd = 8.16, 4.66
    P = exact_lyapunov([[0, 1], [-kp, -kd]], np.eye(2))
    expected = [[(kp * kp + kp + kd * kd) / (2 * kp * kd), 1 / (2 * kp)],
                [1 / (2 * kp), (1 + kp) / (2 * kp * kd)]]
    np.testing.assert_allclose(P, expected, rtol=1e-15)
    assert P[0, 1] == P[1, 0]


@pytest.mark.parametrize("n", [2, 3, 4])
def test_place_puts_the_poles_where_asked(n):
    A = RNG.normal(size=(n, n))
    b = RNG.normal(size=(n, 1))
    poles = -np.arange(1.0, n + 1) * 1.5
    k = exact_place(A, b, poles)
    np.testing.assert_allclose(k, place_poles(A, b, poles).gain_matrix.ravel(), rtol=1e-9)
    got = np.sort(np.linalg.eigvals(A - b @ k[None, :]).real)
    np.testing.assert_allclose(got, np.sort(poles), rtol=1e-9)
    # the exact answer of Ackermann's formula, from SymPy
    As, bs = rational(A), rational(b.T).T
    C = sp.Matrix.hstack(*[As ** i * bs for i in range(n)])
    s = sp.Symbol("s")
    phi = sp.Poly(sp.prod([s - sp.Rational(float(p)) for p in poles]), s).all_coeffs()[::-1]
    phiA = sum((c * As ** i for i, c in enumerate(phi)), sp.zeros(n, n))
    ks = (sp.Matrix([[0] * (n - 1) + [1]]) * C.inv() * phiA)
    assert np.array_equal(k, floats(ks).ravel())


def test_errors_name_what_is_wrong():
    with pytest.raises(ParameterError, match=r"^the mixer is singular.*the mixer = \[\[1\.0"):
        exact_inverse(np.ones((3, 3)), "the mixer")
    with pytest.raises(ParameterError, match="must be a square matrix of finite numbers"):
        exact_inverse([[1.0, np.nan], [0.0, 1.0]])
    with pytest.raises(ParameterError, match="square"):
        exact_solve(np.ones((2, 3)), [1, 2])
    with pytest.raises(ParameterError, match=r"right-hand side .* 2 rows"):
        exact_solve(np.eye(2), [1, 2, 3])
    with pytest.raises(ParameterError, match=r"^poles_x: the system is not controllable"):
        exact_place(np.zeros((2, 2)), [1, 0], [-1, -2], "poles_x")
    with pytest.raises(ParameterError, match=r"^poles_z: expected 2 finite real poles"):
        exact_place(np.zeros((2, 2)), [0, 1], [-1, np.inf], "poles_z")
    with pytest.raises(ParameterError, match=r"^poles_z: the solution has an entry of about "
                                             r"10\^600, beyond the largest float"):
        exact_place([[0.0, 1.0], [0.0, 0.0]], [0, 1], [-1e300, -2e300], "poles_z")
    with pytest.raises(ParameterError, match="Lyapunov equation of A.*singular"):
        exact_lyapunov(np.zeros((2, 2)), np.eye(2))
    with pytest.raises(ParameterError, match=r"Q must have the shape of A \(2, 2\)"):
        exact_lyapunov(np.eye(2), np.eye(3))


_PROBE = """
import json, numpy as np
from quadcog.controllers import CascadePD, CompositeAdaptive
from quadcog.vehicles.vehicle import HUMMINGBIRD
c, a = CascadePD(), CompositeAdaptive()
print(json.dumps({"mixer": HUMMINGBIRD.mixer_inverse().tolist(), "K": c.K.tolist(),
                  "P": a.P.tolist()}))
"""


@pytest.mark.parametrize("core", ["Prescott", "Haswell"])
def test_the_numbers_do_not_depend_on_the_blas_kernel(core):
    """The exported constants are the same bits under another OpenBLAS kernel (the cause of a
    stale generated/embedded/ on an AVX-512 machine, when these went through LAPACK)."""
    def probe(env):
        out = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True,
                             text=True, timeout=120, check=True).stdout
        return json.loads(out)
    base = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
    assert probe(dict(base, OPENBLAS_CORETYPE=core)) == probe(base)
