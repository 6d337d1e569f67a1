"""The cascade PD design checked as the paper does: closed-loop eigenvalues and a MIMO Bode
(singular value) analysis of the loop broken at the plant input, with per-channel margins,
through python-control (``control.singular_values_response``, ``control.stability_margins``)."""
import os
from typing import Any

import numpy as np
from numpy.typing import NDArray

from quadcog.controllers import CascadePD
from quadcog.files import save_figure
from quadcog.studies.analysis.frequency import channel_loop, channel_margins, gain_range_by_eigenvalues
from quadcog.studies.analysis.linear import loop_statespace

__all__ = ["CHANNELS", "OMEGA", "pd_design", "plot_sigma"]

CHANNELS = ("U1 thrust (z loop)", "U2 roll moment (y-phi loop)",
            "U3 pitch moment (x-theta loop)", "U4 yaw moment (psi loop)")
OMEGA = np.logspace(-2, 3, 1001)          # rad/s


def pd_design(controller: CascadePD | None = None,
              omega: NDArray[np.float64] = OMEGA) -> dict[str, Any]:
    """Eigenvalues, singular values and margins of a CascadePD design.

    Parameters
    ----------
    controller : quadcog.controllers.CascadePD, optional
        Default: the default design. It supplies the hover linearization A (12, 12) [1/s],
        B (12, 4) and the equivalent state feedback K (4, 12), U = U_trim - K dx.
    omega : (N,) numpy.ndarray
        Frequencies [rad/s] for the singular-value plot.

    Returns
    -------
    dict
        eigenvalues (12,) complex [1/s]; omega (N,); sigma_L (N, 4), the singular values of
        L(j omega) = K (j omega I - A)^{-1} B, largest first (absolute, not dB);
        sigma_min_return_difference (N,) = sigma_min(I + L) and
        sigma_min_inverse_return_difference (N,) = sigma_min(I + L^{-1}); their minima over
        omega with the frequency; the guaranteed simultaneous gain (dB) and phase (deg)
        margins that sigma_min(I + L) >= a implies (gain in [1/(1 + a), 1/(1 - a)], phase
        +-2 asin(a / 2)); and margins, one dict per input channel from ``channel_margins``
        (that channel broken, the others closed) plus the stable gain interval found
        independently from eigenvalues; loop, the ``control.StateSpace`` of L.
    """
    import control
    ctl = controller or CascadePD()
    A, B, K = ctl.A, ctl.B, ctl.K
    eig = np.linalg.eigvals(A - B @ K)
    loop = loop_statespace(A, B, K)
    I = np.eye(B.shape[1])
    sv = lambda sys: np.asarray(control.singular_values_response(sys, omega).magnitude)[:, 0].T
    sigma = sv(loop)                                      # (N, m), largest first
    rd = sv(loop + I)[:, -1]
    L = np.moveaxis(np.asarray(loop.frequency_response(omega).complex), -1, 0)   # (N, m, m)
    ird = np.linalg.svd(I + np.linalg.inv(L), compute_uv=False)[:, -1]
    a = float(rd.min())
    margins = []
    for i, name in enumerate(CHANNELS):
        m = channel_margins(*channel_loop(A, B, K, i))
        k_lo, k_hi = gain_range_by_eigenvalues(A, B, K, i)
        m["channel"] = name
        m["eigenvalue_gain_range"] = [k_lo, k_hi]
        m["eigenvalue_gain_range_db"] = [20 * np.log10(k_lo) if k_lo > 0 else -np.inf,
                                         20 * np.log10(k_hi) if np.isfinite(k_hi) else np.inf]
        margins.append(m)
    gm = (-20 * np.log10(1 + a), 20 * np.log10(1 / (1 - a)) if a < 1 else np.inf)
    return {
        "eigenvalues": eig[np.argsort(eig.real)],
        "poles": {k: list(v) for k, v in ctl.poles.items()},
        "omega": omega, "sigma_L": sigma,
        "sigma_min_return_difference": rd,
        "sigma_min_inverse_return_difference": ird,
        "min_sigma_return_difference": a,
        "min_sigma_return_difference_at_rad_s": float(omega[np.argmin(rd)]),
        "min_sigma_inverse_return_difference": float(ird.min()),
        "min_sigma_inverse_return_difference_at_rad_s": float(omega[np.argmin(ird)]),
        "guaranteed_simultaneous_gain_margin_db": gm,
        "guaranteed_simultaneous_phase_margin_deg":
            float(np.degrees(2 * np.arcsin(min(a, 2) / 2))),
        "margins": margins, "loop": loop,
    }


def plot_sigma(result: dict[str, Any], path: str | os.PathLike[str]) -> None:
    """Save the singular-value (MIMO Bode) plot of ``pd_design``'s result.

    Parameters
    ----------
    result : dict
        The result of ``pd_design``.
    path : str or os.PathLike
        The PNG to write.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    w, s = result["omega"], result["sigma_L"]
    db = lambda v: 20 * np.log10(v)
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.5))
    ax.semilogx(w, db(s[:, 0]), "C0", lw=2, label=r"$\sigma_{max}(L)$")
    ax.semilogx(w, db(s[:, -1]), "C3", lw=2, label=r"$\sigma_{min}(L)$")
    for k in range(1, s.shape[1] - 1):
        ax.semilogx(w, db(s[:, k]), "0.6", lw=1, label="other singular values" if k == 1 else None)
    ax.axhline(0, color="k", lw=0.8, ls="--")
    for m in result["margins"]:
        if np.isfinite(m["gain_crossover_rad_s"]):
            ax.axvline(m["gain_crossover_rad_s"], color="0.8", lw=0.8, zorder=0)
    ax.set_xlabel(r"frequency $\omega$ (rad/s)")
    ax.set_ylabel("singular value (dB)")
    ax.set_title(r"Cascade PD: $L(j\omega) = K (j\omega I - A)^{-1} B$ (loop broken at $U$)",
                 pad=26)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="lower left", bbox_to_anchor=(0, 1.0), ncol=3, frameon=False, fontsize=9,
              borderaxespad=0.2)
    bx.semilogx(w, db(result["sigma_min_return_difference"]), "C2", lw=2,
                label=r"$\sigma_{min}(I + L)$ (return difference)")
    bx.semilogx(w, db(result["sigma_min_inverse_return_difference"]), "C4", lw=2,
                label=r"$\sigma_{min}(I + L^{-1})$")
    bx.axhline(0, color="k", lw=0.8, ls="--")
    bx.set_xlabel(r"frequency $\omega$ (rad/s)")
    bx.set_ylabel("singular value (dB)")
    bx.set_title(f"MIMO robustness: min $\\sigma_{{min}}(I+L)$ = "
                 f"{result['min_sigma_return_difference']:.3f}", pad=26)
    bx.grid(True, which="both", alpha=0.3)
    bx.legend(loc="lower left", bbox_to_anchor=(0, 1.0), ncol=2, frameon=False, fontsize=9,
              borderaxespad=0.2)
    fig.tight_layout()
    save_figure(fig, path, "sigma plot", dpi=120)
    plt.close(fig)
