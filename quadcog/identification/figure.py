"""The figure of ``quadcog identify``: the estimate over the flight and the moment balance.

Left: the CoG estimate of each block of the hover (mm), with the pooled estimate and its 95 %
band; right: the rotor moments about O over the hover window (mN m) against the weight's
moment ``m g [y_G, -x_G]`` of the estimate (docs/model.md sec. 3.3). House style of
``quadcog.viz.plots``: units on every axis, legends above the panels.
"""
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from quadcog.errors import IdentificationError
from quadcog.files import plot_text, save_figure
from quadcog.validate import fail

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from quadcog.identification.core import Identification

__all__ = ["plot_identification"]


def plot_identification(result: "Identification", path: str | Path | None = None,
                        title: str = "quadcog identify") -> "Figure":
    """Draw the figure of an Identification; saved to ``path`` (PNG) if given.

    Parameters
    ----------
    result : quadcog.identification.Identification
        The identification, with its per-log estimates (``flights``, ``baseline``).
    path : str or Path, optional
        Where to save (dpi 100); the figure is then closed.
    title : str
        The figure's title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (closed when saved).

    Raises
    ------
    quadcog.IdentificationError
        ``result`` not an Identification with per-log estimates, ``path`` neither None nor a
        path, ``title`` not a str (before matplotlib is imported).
    """
    from quadcog.identification import _checks
    from quadcog.identification.core import Identification
    if not isinstance(result, Identification) or not result.flights:
        fail("plot_identification: result", "a quadcog Identification with its per-log "
             "estimates (flights)", result, IdentificationError)
    if path is not None:
        path = _checks.path(path, "plot_identification: path")
    title = _checks.text(title, "plot_identification: title")
    import matplotlib
    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from quadcog.identification.segments import BLOCK_SECONDS
    with plt.rc_context({"font.size": 11, "legend.fontsize": 9}):
        fig, (ax_r, ax_m) = plt.subplots(1, 2, figsize=(12, 4.8))
        offset = 0.0
        from quadcog.identification.core import pooled_estimate
        # the blocks relative to the baseline's pooled estimate (the one subtracted)
        base = pooled_estimate(result.baseline)[0] if result.baseline else np.zeros(3)
        for k, e in enumerate(result.flights):
            tb = offset + BLOCK_SECONDS * (np.arange(len(e.blocks_r)) + 0.5)
            for i, (name, col) in enumerate((("x_G", "C0"), ("y_G", "C1"))):
                ax_r.plot(tb, 1e3 * (e.blocks_r[:, i] - base[i]), "o-", color=col, ms=4,
                          lw=1, label=name if k == 0 else None)
            offset = tb[-1] + BLOCK_SECONDS
        for i, col in ((0, "C0"), (1, "C1")):
            h = result.r_G_ci95[i]
            if h is not None:
                ax_r.axhspan(1e3 * (result.r_G[i] - h), 1e3 * (result.r_G[i] + h),
                             color=col, alpha=0.15, lw=0)
                ax_r.axhline(1e3 * result.r_G[i], color=col, lw=1.5, ls="--")
        ax_r.plot([], [], color="0.3", ls="--", label="pooled estimate, 95 % band")
        what = "shift from the baseline" if result.baseline else "CoG offset"
        ax_r.set_ylabel(f"{what} (mm)")
        ax_r.set_xlabel(f"hover time, {BLOCK_SECONDS:g} s blocks, logs one after another (s)")
        e = result.flights[0]
        for i, (name, col, sign, j) in enumerate((("U2 (roll)", "C1", 1, 1),
                                                  ("U3 (pitch)", "C0", -1, 0))):
            gap = np.r_[np.diff(e.t) > 5 * np.median(np.diff(e.t)), False]
            tt = np.where(gap, np.nan, e.t)          # no line across the gap between hops
            ax_m.plot(tt, 1e3 * e.moment[:, i], color=col, lw=0.6, alpha=0.7,
                      label=f"{name} of the rotors")
            # the weight's moment m g [y_G, -x_G] of this log's own estimate
            ax_m.axhline(1e3 * sign * e.weight[0] * e.r_G[j], color=col, lw=1.5, ls="--",
                         label=f"{'m g y_G' if j else '-m g x_G'} (estimate)")
        ax_m.set_ylabel("moment about O (mN m)")
        ax_m.set_xlabel(f"time in {Path(e.source).name} (s)")
        for a in (ax_r, ax_m):
            a.grid(alpha=0.3)
            handles, labels = a.get_legend_handles_labels()
            if handles:
                a.legend(loc="lower left", bbox_to_anchor=(0.0, 1.0), ncol=2, frameon=False,
                         borderaxespad=0.2, handlelength=1.5, columnspacing=1.0)
        fig.suptitle(plot_text(title))
        fig.tight_layout()
        if path is not None:
            Path(path).parent.mkdir(parents=True, exist_ok=True)
            save_figure(fig, path, "identification figure", dpi=100)
            plt.close(fig)
    return fig
