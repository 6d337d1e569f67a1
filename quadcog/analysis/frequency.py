"""Frequency responses of a state-feedback loop and SISO stability margins (numpy/scipy only).

The loop is broken at the plant input: the plant x_dot = A x + B u is closed by u = -K x, so
the loop transfer matrix is L(s) = K (s I - A)^{-1} B and the closed loop is stable exactly when
det(I + L) has no zeros in the closed right half plane (A - B K Hurwitz).
"""
import numpy as np
from scipy.optimize import brentq


def loop_transfer(A, B, K, omega):
    """L(j omega) = K (j omega I - A)^{-1} B at each frequency.

    A: (n, n) plant matrix (1/s); B: (n, m) input matrix; K: (m, n) feedback gain
    (u = -K x, in the units of u per unit of x); omega: (N,) frequencies in rad/s.
    Returns (N, m, m) complex (dimensionless: input units per input unit).
    """
    A, B, K = (np.asarray(a, dtype=float) for a in (A, B, K))
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    n, m = B.shape
    lhs = 1j * omega[:, None, None] * np.eye(n) - A              # (N, n, n)
    X = np.linalg.solve(lhs, np.broadcast_to(B.astype(complex), (omega.size, n, m)))
    return K @ X


def singular_values(L):
    """Singular values, largest first, of each matrix in L (N, m, m) -> (N, m)."""
    return np.linalg.svd(L, compute_uv=False)


def channel_loop(A, B, K, i):
    """(A_i, b_i, k_i) of the SISO loop of input channel i with the other channels closed.

    The loop is broken at input i only: A_i = A - B_j K_j (j != i), b_i = B[:, i] (n,),
    k_i = K[i] (n,), so L_i(s) = k_i (s I - A_i)^{-1} b_i.
    """
    A, B, K = (np.asarray(a, dtype=float) for a in (A, B, K))
    others = [j for j in range(B.shape[1]) if j != i]
    A_i = A - B[:, others] @ K[others]
    return A_i, B[:, i], K[i]


def siso_response(A_i, b_i, k_i, omega):
    """L_i(j omega) = k_i (j omega I - A_i)^{-1} b_i, (N,) complex, for omega (N,) in rad/s."""
    return loop_transfer(A_i, b_i[:, None], k_i[None, :], omega)[:, 0, 0]


def _refine(fun, w, idx):
    """Roots of fun(log w) between grid points idx and idx + 1 (log-frequency brentq)."""
    roots = []
    for k in idx:
        a, b = np.log(w[k]), np.log(w[k + 1])
        roots.append(float(np.exp(brentq(lambda s: fun(np.exp(s)), a, b, xtol=1e-14))))
    return roots


def siso_margins(A_i, b_i, k_i, w_min=1e-3, w_max=1e4, n_grid=20000):
    """Gain and phase margins of the SISO loop L_i(s) = k_i (s I - A_i)^{-1} b_i.

    A_i: (n, n), b_i: (n,), k_i: (n,); frequencies searched on a log grid w_min..w_max (rad/s)
    and refined with brentq. Gain crossovers: |L_i(j w)| = 1; phase margin there
    180 deg + angle(L_i) wrapped to (-180, 180]. Phase crossovers: Im L_i = 0 with Re L_i < 0
    (phase -180 deg mod 360); the gain margin there is -20 log10 |L_i| dB: positive = the loop
    gain may grow by that much (upper margin), negative = it may shrink by that much (lower
    margin, a conditionally stable loop). Returns a dict with phase_margin_deg (the smallest
    over the gain crossovers, inf if none), phase_crossover/gain_crossover lists (rad/s),
    gain_margin_db (the upper margin, inf if there is no phase crossover with |L| < 1),
    lower_gain_margin_db (-inf if none: the gain may be reduced to zero) and the lists of all
    crossovers found.
    """
    w = np.logspace(np.log10(w_min), np.log10(w_max), n_grid)
    L = siso_response(A_i, b_i, k_i, w)
    resp = lambda x: siso_response(A_i, b_i, k_i, np.array([x]))[0]
    mag = np.log(np.abs(L))
    gc = _refine(lambda x: np.log(abs(resp(x))), w, np.flatnonzero(np.diff(np.sign(mag)) != 0))
    im = L.imag
    cand = np.flatnonzero((np.diff(np.sign(im)) != 0) & (L.real[:-1] + L.real[1:] < 0))
    pc = [x for x in _refine(lambda x: resp(x).imag, w, cand) if resp(x).real < 0]
    pms = []
    for x in gc:
        pm = 180.0 + np.degrees(np.angle(resp(x)))
        pms.append(float(pm - 360.0 if pm > 180.0 else pm))
    gms = [float(-20 * np.log10(abs(resp(x)))) for x in pc]
    upper = [g for g in gms if g > 0]
    lower = [g for g in gms if g < 0]
    k_pm = int(np.argmin(pms)) if pms else None
    k_up = int(np.argmin(upper)) if upper else None
    k_lo = int(np.argmax(lower)) if lower else None
    return {
        "phase_margin_deg": pms[k_pm] if pms else float("inf"),
        "gain_crossover_rad_s": gc[k_pm] if pms else float("nan"),
        "gain_margin_db": upper[k_up] if upper else float("inf"),
        "phase_crossover_rad_s": ([x for x, g in zip(pc, gms) if g > 0][k_up]
                                  if upper else float("nan")),
        "lower_gain_margin_db": lower[k_lo] if lower else float("-inf"),
        "lower_phase_crossover_rad_s": ([x for x, g in zip(pc, gms) if g < 0][k_lo]
                                        if lower else float("nan")),
        "all_gain_crossovers_rad_s": gc, "all_phase_margins_deg": pms,
        "all_phase_crossovers_rad_s": pc, "all_gain_margins_db": gms,
    }


def gain_range_by_eigenvalues(A, B, K, i, k_max=1e4, n_grid=4000):
    """Scalar gains k on channel i (u_i = -k K_i x) that keep A - B K(k) Hurwitz, found by
    eigenvalues on a log grid of k in [1/k_max, k_max] and refined by bisection.

    A: (n, n), B: (n, m), K: (m, n). Returns (k_low, k_high), the stable interval around
    k = 1 (k_low = 0 / k_high = inf when stability holds to the grid ends): an independent
    check of the gain margins, 20 log10 k_high = gain_margin_db, 20 log10 k_low =
    lower_gain_margin_db.
    """
    A, B, K = (np.asarray(a, dtype=float) for a in (A, B, K))

    def stable(k):
        Kk = K.copy()
        Kk[i] *= k
        return np.max(np.linalg.eigvals(A - B @ Kk).real) < 0

    if not stable(1.0):
        raise ValueError("the nominal loop (k = 1) is not stable")

    def edge(lo, hi):          # stable at lo, unstable at hi (in log k)
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if stable(np.exp(mid)) else (lo, mid)
        return float(np.exp(0.5 * (lo + hi)))

    ks = np.logspace(0, np.log10(k_max), n_grid // 2)
    bad = [k for k in ks if not stable(k)]
    k_high = edge(0.0, np.log(bad[0])) if bad else float("inf")
    ks = np.logspace(0, -np.log10(k_max), n_grid // 2)
    bad = [k for k in ks if not stable(k)]
    k_low = edge(0.0, np.log(bad[0])) if bad else 0.0
    return k_low, k_high
