"""Margins of a state-feedback loop through python-control, and an independent check.

The loop is broken at the plant input: the plant x_dot = A x + B u is closed by u = -K x, so
the loop transfer matrix is L(s) = K (s I - A)^{-1} B (``linear.loop_statespace``) and the
closed loop is stable exactly when A - B K is Hurwitz. ``channel_margins`` reads the SISO
margins of one input channel with ``control.stability_margins``; ``gain_range_by_eigenvalues``
finds the same gain range from eigenvalues only (no frequency response), the cross-check.
"""
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from quadcog.errors import InputError

__all__ = ["channel_loop", "channel_margins", "gain_range_by_eigenvalues"]


def channel_loop(A: ArrayLike, B: ArrayLike, K: ArrayLike, i: int
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The SISO loop of input channel i with the other channels closed.

    The loop is broken at input i only, so L_i(s) = k_i (s I - A_i)^{-1} b_i.

    Parameters
    ----------
    A : (n, n) array_like
        State matrix [1/s].
    B : (n, m) array_like
        Input matrix.
    K : (m, n) array_like
        State feedback gain (u = -K x).
    i : int
        The channel.

    Returns
    -------
    tuple of (numpy.ndarray, numpy.ndarray, numpy.ndarray)
        A_i = A - B_j K_j (j != i) (n, n), b_i = B[:, i] (n,), k_i = K[i] (n,).
    """
    A, B, K = (np.asarray(a, dtype=float) for a in (A, B, K))
    others = [j for j in range(B.shape[1]) if j != i]
    A_i = A - B[:, others] @ K[others]
    return A_i, B[:, i], K[i]


def channel_margins(A_i: ArrayLike, b_i: ArrayLike, k_i: ArrayLike) -> dict[str, Any]:
    """Gain and phase margins of L_i(s) = k_i (s I - A_i)^{-1} b_i.

    By ``control.stability_margins`` (all crossovers).

    Parameters
    ----------
    A_i : (n, n) array_like
        The loop's state matrix [1/s] (``channel_loop``).
    b_i : (n,) array_like
        Its input vector.
    k_i : (n,) array_like
        Its output (gain) vector.

    Returns
    -------
    dict
        phase_margin_deg (the smallest over the gain crossovers, inf if none) and
        gain_crossover_rad_s; gain_margin_db, the upper margin (how much the gain may grow:
        the smallest positive one, inf if none) at phase_crossover_rad_s;
        lower_gain_margin_db (how much it may shrink, negative: a conditionally stable loop;
        -inf if the gain may go to zero) at lower_phase_crossover_rad_s; and the lists of all
        crossovers.
    """
    import control
    L = control.ss(A_i, np.asarray(b_i, float)[:, None], np.asarray(k_i, float)[None, :], 0.0)
    gm, pm, _, wpc, wgc, _ = control.stability_margins(L, returnall=True)
    gms = [float(20 * np.log10(g)) for g in np.atleast_1d(gm)]
    pc, gc = [float(w) for w in np.atleast_1d(wpc)], [float(w) for w in np.atleast_1d(wgc)]
    pms = [float(p) for p in np.atleast_1d(pm)]
    upper = [(g, w) for g, w in zip(gms, pc) if g > 0]
    lower = [(g, w) for g, w in zip(gms, pc) if g < 0]
    k_pm = int(np.argmin(pms)) if pms else None
    up = min(upper) if upper else (float("inf"), float("nan"))
    lo = max(lower) if lower else (float("-inf"), float("nan"))
    return {
        "phase_margin_deg": pms[k_pm] if k_pm is not None else float("inf"),
        "gain_crossover_rad_s": gc[k_pm] if k_pm is not None else float("nan"),
        "gain_margin_db": up[0], "phase_crossover_rad_s": up[1],
        "lower_gain_margin_db": lo[0], "lower_phase_crossover_rad_s": lo[1],
        "all_gain_crossovers_rad_s": gc, "all_phase_margins_deg": pms,
        "all_phase_crossovers_rad_s": pc, "all_gain_margins_db": gms,
    }


def gain_range_by_eigenvalues(A: ArrayLike, B: ArrayLike, K: ArrayLike, i: int,
                              k_max: float = 1e4, n_grid: int = 4000) -> tuple[float, float]:
    """Scalar gains k on channel i (u_i = -k K_i x) that keep A - B K(k) Hurwitz.

    Found by eigenvalues on a log grid of k in [1/k_max, k_max] and refined by bisection:
    an independent check of the gain margins, 20 log10 k_high = gain_margin_db,
    20 log10 k_low = lower_gain_margin_db.

    Parameters
    ----------
    A : (n, n) array_like
        State matrix [1/s].
    B : (n, m) array_like
        Input matrix.
    K : (m, n) array_like
        State feedback gain.
    i : int
        The channel.
    k_max : float
        The grid's end.
    n_grid : int
        Grid points (half above k = 1, half below).

    Returns
    -------
    tuple of (float, float)
        (k_low, k_high), the stable interval around k = 1 (k_low = 0 / k_high = inf when
        stability holds to the grid ends).

    Raises
    ------
    quadcog.errors.InputError
        When the nominal loop (k = 1) is not stable.
    """
    A, B, K = (np.asarray(a, dtype=float) for a in (A, B, K))

    def stable(k):
        Kk = K.copy()
        Kk[i] *= k
        return np.max(np.linalg.eigvals(A - B @ Kk).real) < 0

    if not stable(1.0):
        raise InputError("the nominal loop (k = 1) is not stable: expected poles that make the "
                         "linearized closed loop stable")

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
