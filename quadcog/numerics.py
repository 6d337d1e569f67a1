"""Numerical helpers of the floor: fast forms that round exactly as numpy's general ones, and
exact linear algebra for the small matrices whose answers reach generated code."""
from fractions import Fraction
from functools import lru_cache

import numpy as np
import numpy.typing as npt

from quadcog.errors import ParameterError

__all__ = ["row_norms", "row_distances", "fill_rows", "repeated_row", "exact_inverse",
           "exact_solve", "exact_lyapunov", "exact_place"]


def row_norms(v: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The Euclidean norms of the rows of an (N, 3) array, ``np.linalg.norm(v, axis=1)``.

    The same sums in the same order, ``sqrt((v0^2 + v1^2) + v2^2)``, so the same bits, in a
    quarter of the time: numpy's reduction over a short last axis loops per row.

    Parameters
    ----------
    v : (N, 3) numpy.ndarray
        The vectors.

    Returns
    -------
    (N,) numpy.ndarray
        Their norms (inf where a square overflows, quietly).
    """
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    with np.errstate(over="ignore", invalid="ignore"):
        return _norms(x * x, y * y, z * z)


def _norms(xx: npt.NDArray[np.float64], yy: npt.NDArray[np.float64],
           zz: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """sqrt((xx + yy) + zz), in place in xx (fresh arrays: fewer temporaries, the same bits)."""
    xx += yy
    xx += zz
    return np.sqrt(xx, out=xx)


def row_distances(a: npt.NDArray[np.float64], b: npt.NDArray[np.float64]
                  ) -> npt.NDArray[np.float64]:
    """``row_norms(a[:, :3] - b[:, :3])``, the same bits, without the (N, 3) difference.

    Parameters
    ----------
    a : (N, >= 3) numpy.ndarray
        Rows whose first three columns are compared.
    b : (N, >= 3) numpy.ndarray
        Rows whose first three columns are compared.

    Returns
    -------
    (N,) numpy.ndarray
        The distances (inf where a square overflows, quietly).
    """
    with np.errstate(over="ignore", invalid="ignore"):
        d = [a[:, i] - b[:, i] for i in range(3)]
        for c in d:
            c *= c
        return _norms(*d)


def fill_rows(out: npt.NDArray[np.float64], row: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Set every row of a C-ordered (N, k) array to ``row``, in place: ``out[:] = row``.

    By doubling copies of whole rows (row 0, then rows 0..1 into 1..2, ...): contiguous
    block copies, where numpy's broadcast assignment loops per row over a short last axis,
    several times slower for the run-length arrays here (k of 3 to 14). The same bits.

    Parameters
    ----------
    out : (N, k) numpy.ndarray, C order
        The array to fill.
    row : (k,) array_like
        The row.

    Returns
    -------
    (N, k) numpy.ndarray
        ``out``.
    """
    n = out.shape[0]
    if n:
        out[0] = row
        done = 1
        while done < n:
            step = min(done, n - done)
            out[done:done + step] = out[:step]
            done += step
    return out


def repeated_row(row: npt.ArrayLike, n: int) -> npt.NDArray[np.float64]:
    """A new C-ordered (n, k) float64 array whose every row is ``row`` (``fill_rows``).

    Parameters
    ----------
    row : (k,) array_like
        The row.
    n : int
        The number of rows.

    Returns
    -------
    (n, k) numpy.ndarray
        The rows.
    """
    row = np.asarray(row, dtype=float).ravel()
    return fill_rows(np.empty((n, row.size)), row)


# Exact linear algebra. LAPACK's and BLAS's answers move in the last bits with the kernel the
# machine picks (AVX-512 or AVX2, say), and these numbers (a mixer's inverse, pole-placement
# gains, a Lyapunov matrix) go into generated C and compiled kernels, which must be the same
# bytes on every machine. Gauss-Jordan in exact rationals of the given floats rounds only once,
# at the end: each entry is the nearest float to the exact answer, and zeros are zeros. The
# matrices are small (at most 64 unknowns), so the rationals cost milliseconds, and answers
# are kept (the same vehicle asks again and again).

def exact_inverse(M: npt.ArrayLike, name: str = "matrix") -> npt.NDArray[np.float64]:
    """The inverse of a small square matrix, each entry the exact inverse's nearest float.

    Parameters
    ----------
    M : (n, n) array_like
        A square matrix of finite floats (n small: the cost grows as n^3 in rationals).
    name : str, optional
        What M is, for the error message.

    Returns
    -------
    (n, n) numpy.ndarray
        The inverse, correctly rounded entry by entry (a fresh array).

    Raises
    ------
    ParameterError
        When M is not square and finite, or is exactly singular.
    """
    A = _square(M, name)
    return exact_solve(A, np.eye(len(A)), name)


def exact_solve(M: npt.ArrayLike, rhs: npt.ArrayLike, name: str = "matrix"
                ) -> npt.NDArray[np.float64]:
    """The solution X of ``M X = rhs``, each entry the exact solution's nearest float.

    Parameters
    ----------
    M : (n, n) array_like
        A square matrix of finite floats.
    rhs : (n,) or (n, k) array_like
        Right-hand sides of finite floats.
    name : str, optional
        What M is, for the error message.

    Returns
    -------
    (n,) or (n, k) numpy.ndarray
        X, the shape of rhs, correctly rounded entry by entry.

    Raises
    ------
    ParameterError
        When M is not square and finite, rhs does not match it, or M is exactly singular.
    """
    A = _square(M, name)
    b = np.asarray(rhs, dtype=float)
    if b.shape[:1] != A.shape[:1] or b.ndim > 2 or not np.isfinite(b).all():
        raise ParameterError(f"the right-hand side for {name} must be {len(A)} rows of finite "
                             f"numbers, got shape {b.shape}")
    cols = b.reshape(len(A), -1)
    return np.array(_solve(_key(A), _key(cols), name)).reshape(b.shape)


def exact_lyapunov(A: npt.ArrayLike, Q: npt.ArrayLike, name: str = "A"
                   ) -> npt.NDArray[np.float64]:
    """The P of ``A^T P + P A + Q = 0``, each entry the exact solution's nearest float.

    The same equation as ``scipy.linalg.solve_continuous_lyapunov(A.T, -Q)``, solved in
    rationals: for each pair of the groups of states that A does not couple, the block of P
    from its own small Sylvester equation (n^2 unknowns at once where A couples all states).

    Parameters
    ----------
    A : (n, n) array_like
        A square matrix of finite floats (small: a block of g coupled states costs (g^2)^3).
    Q : (n, n) array_like
        The right-hand side, finite floats.
    name : str, optional
        What A is, for the error message.

    Returns
    -------
    (n, n) numpy.ndarray
        P, correctly rounded entry by entry (symmetric when Q is).

    Raises
    ------
    ParameterError
        When A or Q is not square and finite, or the equation has no unique solution (A has
        eigenvalues lambda_i + lambda_j = 0).
    """
    a = _square(A, name)
    q = _square(Q, "Q")
    if q.shape != a.shape:
        raise ParameterError(f"Q must have the shape of {name} {a.shape}, got {q.shape}")
    return np.array(_lyapunov(_key(a), _key(q), name))


def exact_place(A: npt.ArrayLike, b: npt.ArrayLike, poles: npt.ArrayLike, name: str = "poles"
                ) -> npt.NDArray[np.float64]:
    """The gains k of a single-input system that put the eigenvalues of ``A - b k`` at poles.

    Ackermann's formula, ``k = e_n^T C^-1 phi(A)`` with C = [b, A b, ..., A^(n-1) b] and
    phi the polynomial whose roots are the poles, in exact rationals: the formula's poor
    conditioning in floats does not arise, and each gain is the exact answer's nearest float.

    Parameters
    ----------
    A : (n, n) array_like
        The system matrix, finite floats.
    b : (n,) or (n, 1) array_like
        The input column, finite floats.
    poles : (n,) array_like
        Real poles (finite floats).
    name : str, optional
        Where the poles came from, for the error message.

    Returns
    -------
    (n,) numpy.ndarray
        The gains k (u = -k x), correctly rounded.

    Raises
    ------
    ParameterError
        When the shapes do not match, a value is not finite, or (A, b) is not controllable.
    """
    a = _square(A, "A")
    n = len(a)
    col = np.asarray(b, dtype=float).reshape(-1)
    p = np.asarray(poles, dtype=float).reshape(-1)
    if col.shape != (n,) or p.shape != (n,) or not (np.isfinite(col).all()
                                                   and np.isfinite(p).all()):
        raise ParameterError(f"{name}: expected {n} finite real poles for a {n}-state system "
                             f"with one input column, got poles {p.tolist()} and input "
                             f"{col.tolist()}")
    return np.array(_place(_key(a), tuple(col.tolist()), tuple(p.tolist()), name))


def _square(M: npt.ArrayLike, name: str) -> npt.NDArray[np.float64]:
    A = np.asarray(M, dtype=float)
    if A.ndim != 2 or A.shape[0] != A.shape[1] or not np.isfinite(A).all():
        raise ParameterError(f"{name} must be a square matrix of finite numbers, got {A!r}")
    return A


_Rows = tuple[tuple[float, ...], ...]


def _key(A: npt.NDArray[np.float64]) -> _Rows:
    return tuple(map(tuple, A.tolist()))


def _float(v: Fraction, name: str) -> float:
    """The nearest float, or a ParameterError where the exact answer is beyond floats."""
    try:
        return float(v)
    except OverflowError:
        raise ParameterError(f"{name}: the solution has an entry of about 10^"
                             f"{len(str(abs(v.numerator))) - len(str(v.denominator))}, beyond "
                             f"the largest float (1.8e308); expected inputs whose solution is "
                             f"finite") from None


def _fractions(rows: _Rows) -> list[list[Fraction]]:
    return [[Fraction(v) for v in row] for row in rows]


def _gauss_jordan(a: list[list[Fraction]], rhs: list[list[Fraction]], name: str
                  ) -> list[list[Fraction]]:
    """X with a X = rhs, exactly (a and rhs are consumed)."""
    n = len(a)
    rows = [ra + rb for ra, rb in zip(a, rhs)]
    width = len(rows[0]) if rows else 0
    for c in range(n):
        pivot = next((r for r in range(c, n) if rows[r][c] != 0), None)
        if pivot is None:
            raise ParameterError(f"{name} is singular: the linear equations have no unique "
                                 "solution (its columns are linearly dependent)")
        rows[c], rows[pivot] = rows[pivot], rows[c]
        p = rows[c][c]
        rc = [v / p for v in rows[c]]
        rows[c] = rc
        nonzero = [j for j in range(c, width) if rc[j] != 0]
        for r in range(n):
            k = rows[r][c]
            if r != c and k != 0:
                row = rows[r]
                for j in nonzero:
                    row[j] -= k * rc[j]
    return [row[n:] for row in rows]


@lru_cache(maxsize=64)
def _solve(M: _Rows, rhs: _Rows, name: str) -> list[list[float]]:
    try:
        x = _gauss_jordan(_fractions(M), _fractions(rhs), name)
    except ParameterError as e:
        raise ParameterError(f"{e}: {name} = {[list(r) for r in M]}") from None
    return [[_float(v, name) for v in row] for row in x]


@lru_cache(maxsize=64)
def _lyapunov(A: _Rows, Q: _Rows, name: str) -> list[list[float]]:
    a, q, n = _fractions(A), _fractions(Q), len(A)
    # A's states fall into groups that A does not couple (the error dynamics: one group per
    # channel); P's block (g, h) then solves its own small Sylvester equation
    # A_g^T P_gh + P_gh A_h = -Q_gh, which is much cheaper than all n^2 unknowns at once
    groups = _decoupled_groups(A)
    P = [[Fraction(0)] * n for _ in range(n)]
    what = f"the Lyapunov equation of {name} (eigenvalues summing to 0)"
    for g in groups:
        for h in groups:
            block = _sylvester([[a[i][j] for j in g] for i in g], [[a[i][j] for j in h] for i in h],
                               [[q[i][j] for j in h] for i in g], what)
            for r, i in enumerate(g):
                for c, j in enumerate(h):
                    P[i][j] = block[r][c]
    return [[_float(v, what) for v in row] for row in P]


def _decoupled_groups(A: _Rows) -> list[list[int]]:
    """The states in groups that A does not couple (connected through its nonzero entries)."""
    n = len(A)
    parent = list(range(n))

    def root(i: int) -> int:
        while parent[i] != i:
            i = parent[i]
        return i
    for i in range(n):
        for j in range(n):
            if A[i][j] != 0:
                parent[root(i)] = root(j)
    groups: dict[int, list[int]] = {}
    for i in range(n):
        groups.setdefault(root(i), []).append(i)
    return list(groups.values())


def _sylvester(Ag: list[list[Fraction]], Ah: list[list[Fraction]], Q: list[list[Fraction]],
               what: str) -> list[list[Fraction]]:
    """X with Ag^T X + X Ah + Q = 0, exactly, as len(Ag) * len(Ah) linear equations."""
    m, k = len(Ag), len(Ah)
    K = [[Fraction(0)] * (m * k) for _ in range(m * k)]
    # X's entries row by row: (Ag^T X)[i, j] = sum_l Ag[l][i] X[l][j]; (X Ah)[i, j] =
    # sum_l X[i][l] Ah[l][j]
    for i in range(m):
        for j in range(k):
            row = K[i * k + j]
            for l in range(m):
                row[l * k + j] += Ag[l][i]
            for l in range(k):
                row[i * k + l] += Ah[l][j]
    x = _gauss_jordan(K, [[-v] for r in Q for v in r], what)
    return [[x[i * k + j][0] for j in range(k)] for i in range(m)]


@lru_cache(maxsize=64)
def _place(A: _Rows, b: tuple[float, ...], poles: tuple[float, ...], name: str
           ) -> list[float]:
    a, n = _fractions(A), len(A)

    def times(M: list[list[Fraction]], v: list[Fraction]) -> list[Fraction]:
        return [sum((m * w for m, w in zip(row, v)), Fraction(0)) for row in M]

    # controllability columns b, A b, ..., A^(n-1) b
    cols = [[Fraction(v) for v in b]]
    for _ in range(n - 1):
        cols.append(times(a, cols[-1]))
    # the last row w of C^-1: C^T w = e_n, and the rows of C^T are those columns
    e_n = [[Fraction(int(i == n - 1))] for i in range(n)]
    try:
        w = [v[0] for v in _gauss_jordan(cols, e_n, "C")]
    except ParameterError:
        raise ParameterError(f"{name}: the system is not controllable from its input (its "
                             "controllability matrix is singular); no gains place its poles"
                             ) from None
    # coefficients of prod (s - p_i), highest first
    coef = [Fraction(1)]
    for p in poles:
        fp = Fraction(p)
        coef = [c - fp * d for c, d in zip(coef + [Fraction(0)], [Fraction(0)] + coef)]
    # k = w^T phi(A) = sum_m coef[n - m] w^T A^m, by rows w^T A^m
    k = [Fraction(0)] * n
    row = w
    for m in range(n + 1):
        c = coef[n - m]
        k = [ki + c * ri for ki, ri in zip(k, row)]
        row = [sum((row[r] * a[r][j] for r in range(n)), Fraction(0)) for j in range(n)]
    return [_float(v, name) for v in k]
