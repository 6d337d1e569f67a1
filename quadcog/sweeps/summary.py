"""What a sweep writes: the table (Parquet and CSV), a summary (survival per controller,
quantiles of the tail error) and plots chosen from the dimensions."""
import json
from pathlib import Path
import re
from typing import Any

import numpy as np
from numpy.typing import NDArray

from quadcog.files import save_figure
from quadcog.sweeps.arrow_table import require_pyarrow, to_arrow
from quadcog.sweeps.spec import Sweep

__all__ = ["QUANTILES", "summarize", "summary_markdown", "write_outputs", "plot_sweep",
           "summary_survival"]

QUANTILES = (0.5, 0.9, 0.99)
_COG_XY = re.compile(r"^(cog\[\d+\]\.r)\[([01])\]$")


def summarize(sweep: Sweep, columns: dict[str, NDArray[Any]]) -> dict[str, Any]:
    """The summary of a sweep's table.

    Parameters
    ----------
    sweep : quadcog.sweeps.spec.Sweep
        The sweep (its name, source, mode and threshold).
    columns : dict of str to numpy.ndarray
        The table: {column: (n_flights,) array}.

    Returns
    -------
    dict
        {"name", "source", "mode", "flights", "admissible", "threshold", "controllers":
        {name: {...}}}: per controller the flight counts, survivors (admissible, not
        diverged, tail RMS <= threshold), survival rate among the admissible flights, and
        quantiles of the tail RMS [m] over the flights that did not diverge.
    """
    ctl = columns["controller"]
    out: dict[str, Any] = {"name": sweep.name, "source": sweep.source, "mode": sweep.mode,
           "flights": int(len(ctl)), "admissible": int(columns["admissible"].sum()),
           "threshold": sweep.threshold, "controllers": {}}
    for name in dict.fromkeys(ctl.tolist()):
        sel = ctl == name
        adm = sel & columns["admissible"]
        ok = adm & ~columns["failed"]
        flown = adm & ~columns["diverged"]
        tail = columns["rms_position_error_tail"][flown]
        q = {f"tail_rms_p{round(100 * p)}": float(np.quantile(tail, p)) if tail.size else None
             for p in QUANTILES}
        out["controllers"][name] = dict(
            flights=int(sel.sum()), admissible=int(adm.sum()), survived=int(ok.sum()),
            survival=float(ok.sum() / adm.sum()) if adm.any() else None,
            diverged=int((adm & columns["diverged"]).sum()),
            tail_rms_max=float(tail.max()) if tail.size else None, **q)
    return out


def summary_markdown(summary: dict[str, Any]) -> str:
    """The summary as Markdown: a sentence and a table per controller.

    Parameters
    ----------
    summary : dict
        The result of ``summarize``.

    Returns
    -------
    str
        summary.md's text.
    """
    lines = [f"# Sweep {summary['name']}", "",
             f"{summary['flights']} flights ({summary['mode']}), {summary['admissible']} with an "
             f"admissible CoG; a flight survives when it does not diverge and its tail RMS "
             f"position error is at most {summary['threshold']:g} m.", "",
             "| controller | admissible flights | survived | survival | diverged | tail RMS p50 "
             "(m) | p90 (m) | p99 (m) | max (m) |", "|---|---|---|---|---|---|---|---|---|"]
    fmt = lambda v, f: "n/a" if v is None else format(v, f)
    for name, c in summary["controllers"].items():
        lines.append(f"| {name} | {c['admissible']} | {c['survived']} | "
                     f"{fmt(None if c['survival'] is None else 100 * c['survival'], '.1f')} % | "
                     f"{c['diverged']} | {fmt(c['tail_rms_p50'], '.4g')} | "
                     f"{fmt(c['tail_rms_p90'], '.4g')} | {fmt(c['tail_rms_p99'], '.4g')} | "
                     f"{fmt(c['tail_rms_max'], '.4g')} |")
    return "\n".join(lines) + "\n"


def write_outputs(sweep: Sweep, columns: dict[str, NDArray[Any]], summary: dict[str, Any],
                  out: Path, plots: bool = True) -> list[str]:
    """results.parquet, results.csv, summary.json, summary.md and the plots into ``out``.

    Parameters
    ----------
    sweep : quadcog.sweeps.spec.Sweep
        The sweep.
    columns : dict of str to numpy.ndarray
        The table: {column: (n_flights,) array}.
    summary : dict
        The result of ``summarize``.
    out : pathlib.Path
        The results folder (exists).
    plots : bool
        Draw the plots (skipped without matplotlib).

    Returns
    -------
    list of str
        The file names of the plots written.
    """
    pa = require_pyarrow()
    import pyarrow.csv  # noqa: F401

    from quadcog.files import RunFiles
    table = to_arrow(columns)
    with RunFiles(out, owned=(), protect=[p for _, p in sweep.inputs]) as files:  # all or none
        pa.parquet.write_table(table, files.path("results.parquet"))
        pa.csv.write_csv(table, files.path("results.csv"))
        files.path("summary.json").write_text(json.dumps(summary, indent=2) + "\n")
        files.path("summary.md").write_text(summary_markdown(summary))
    if plots:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            return []
        return plot_sweep(sweep, columns, out)
    return []


def _numeric(sweep, columns):
    """Names of the numeric table columns of the dimensions, with their distinct values."""
    out = []
    for d in sweep.dimensions:
        for c in d.columns():
            v = columns[c]
            if v.dtype.kind in "fi" and len(np.unique(v)) > 1:
                out.append(c)
    return out


def plot_sweep(sweep: Sweep, columns: dict[str, NDArray[Any]], out: Path) -> list[str]:
    """Plots chosen from the dimensions.

    A failure map over two CoG components (the x and y of one CoG change), survival against
    each numeric varied value, and histograms of the tail RMS per controller.

    Parameters
    ----------
    sweep : quadcog.sweeps.spec.Sweep
        The sweep.
    columns : dict of str to numpy.ndarray
        The table: {column: (n_flights,) array}.
    out : pathlib.Path
        The folder for the PNGs.

    Returns
    -------
    list of str
        The file names written.
    """
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.colors import LogNorm
    import matplotlib.pyplot as plt
    written = []
    ctl = columns["controller"]
    names = list(dict.fromkeys(ctl.tolist()))
    numeric = _numeric(sweep, columns)
    tail = columns["rms_position_error_tail"]
    failed, adm = columns["failed"], columns["admissible"]

    pairs: dict[str, dict[str, str]] = {}
    for c in numeric:
        m = _COG_XY.match(c)
        if m:
            pairs.setdefault(m.group(1), {})[m.group(2)] = c
    pair = next((p for p in pairs.values() if len(p) == 2), None)
    if pair:
        cx, cy = pair["0"], pair["1"]
        fig, axes = plt.subplots(1, len(names), figsize=(4.6 * len(names), 4.4), squeeze=False)
        finite = tail[adm & np.isfinite(tail) & (tail > 0)]
        norm = LogNorm(vmin=max(finite.min(), 1e-4), vmax=max(finite.max(), 1e-3)) \
            if finite.size else None
        # squares that fill their grid cell (about 250 pt of axis over the points per axis)
        per_axis = max(len(np.unique(columns[cx])), len(np.unique(columns[cy])), 1)
        s = float(np.clip((0.9 * 250 / per_axis) ** 2, 14, 400))
        for ax, name in zip(axes[0], names):
            sel = ctl == name
            x, y = 100 * columns[cx][sel], 100 * columns[cy][sel]
            a, f = adm[sel], failed[sel]
            ax.scatter(x[~a], y[~a], c="0.8", s=s, marker="s", label="inadmissible")
            ok = a & ~columns["diverged"][sel]
            sc = ax.scatter(x[ok], y[ok], c=np.maximum(tail[sel][ok], 1e-4), cmap="viridis",
                            norm=norm, s=s, marker="s")
            div = a & columns["diverged"][sel]
            ax.scatter(x[div], y[div], c="red", s=s, marker="s", label="diverged")
            ax.scatter(x[a & f & ~div], y[a & f & ~div], facecolors="none", edgecolors="white",
                       s=s, marker="s", linewidths=0.6, label="failed")
            ax.set_xlabel(f"{cx} (cm)")
            ax.set_ylabel(f"{cy} (cm)")
            ax.set_aspect("equal")
            surv = summary_survival(columns, name)
            ax.set_title(f"{name}: survives {surv}")
        if norm is not None:
            fig.colorbar(sc, ax=axes[0].tolist(), label="tail RMS position error (m)")
        # below the axes, outside the data: the legend never hides a point
        axes[0][0].legend(loc="upper left", bbox_to_anchor=(0.0, -0.14), ncol=3, fontsize=7,
                          markerscale=min(1.0, 8.0 / np.sqrt(s)), facecolor="0.85")
        save_figure(fig, out / "failure_map.png", "sweep figure", dpi=110, bbox_inches="tight")
        plt.close(fig)
        written.append("failure_map.png")

    for c in numeric:
        v = columns[c]
        levels = np.unique(v[adm])
        if levels.size > 25:                      # sampled values: 12 bins of equal count
            edges = np.unique(np.quantile(v[adm], np.linspace(0, 1, 13)))
            centre = lambda lo, hi: 0.5 * (lo + hi)
            bins = list(zip(edges[:-1], edges[1:]))
        else:
            bins = [(x, x) for x in levels]
            centre = lambda lo, hi: lo
        fig, ax = plt.subplots(figsize=(6, 4))
        for name in names:
            sel = (ctl == name) & adm
            xs, ys = [], []
            for lo, hi in bins:
                inb = sel & (v >= lo) & (v <= hi)
                if inb.any():
                    xs.append(centre(lo, hi))
                    ys.append(100 * np.mean(~failed[inb]))
            ax.plot(xs, ys, "o-", ms=3, label=name)
        ax.set_xlabel(c)
        ax.set_ylabel("survival (% of admissible flights)")
        ax.set_ylim(-3, 103)
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
        fname = "survival_" + re.sub(r"[^A-Za-z0-9]+", "_", c).strip("_") + ".png"
        fig.tight_layout()
        save_figure(fig, out / fname, "sweep figure", dpi=110)
        plt.close(fig)
        written.append(fname)

    fig, ax = plt.subplots(figsize=(6, 4))
    finite = tail[adm & np.isfinite(tail) & (tail > 0)]
    if finite.size:
        hist_bins = np.logspace(np.log10(finite.min()),
                                np.log10(max(finite.max(), finite.min() * 10)), 40)
        for name in names:
            sel = (ctl == name) & adm & np.isfinite(tail) & (tail > 0)
            # matplotlib's stubs name a Sequence for bins; an array of edges is what it takes
            ax.hist(tail[sel], bins=hist_bins,  # type: ignore[arg-type]
                    histtype="step", label=name)
        ax.set_xscale("log")
    ax.axvline(sweep.threshold, color="k", ls="--", lw=1, label="failure threshold")
    ax.set_xlabel("tail RMS position error (m)")
    ax.set_ylabel("flights")
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, out / "tail_rms_hist.png", "sweep figure", dpi=110)
    plt.close(fig)
    written.append("tail_rms_hist.png")
    return written


def summary_survival(columns: dict[str, NDArray[Any]], name: str) -> str:
    """The survival of one controller, as text.

    Parameters
    ----------
    columns : dict of str to numpy.ndarray
        The table: {column: (n_flights,) array}.
    name : str
        The controller's short name.

    Returns
    -------
    str
        Percent of its admissible flights that did not fail ("93 %"), or "n/a".
    """
    sel = (columns["controller"] == name) & columns["admissible"]
    if not sel.any():
        return "n/a"
    return f"{100 * np.mean(~columns['failed'][sel]):.0f} %"
