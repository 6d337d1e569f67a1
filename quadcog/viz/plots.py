"""The flight figure: position, position error, attitude, inputs and (when it moves) the CoG.

Every panel says its unit; legends sit above their panel, outside the data; disturbance pulses
are shaded on every panel. ``flight_title`` is the one naming scheme for runs, used by
``SimulationResult.plot``, ``quadcog run`` and ``quadcog paper``.
"""
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from quadcog.files import plot_text, save_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["CONTROLLER_LABELS", "COG_STILL", "controller_label", "flight_title", "status_text",
           "cog_moves", "plot_flight"]

# how a controller (its ``name`` attribute) is called in titles
CONTROLLER_LABELS = {"cascade_pd": "cascade PD",
                     "feedback_linearization": "feedback linearization",
                     "adaptive_feedback_linearization": "adaptive FL"}
# a CoG (or estimate) that changes by less than this over the run is "not moving": no panel
COG_STILL = 1e-6           # m


def controller_label(name: str) -> str:
    """How a controller is called in titles.

    Parameters
    ----------
    name : str
        The controller's ``name``, e.g. 'adaptive_feedback_linearization'.

    Returns
    -------
    str
        Its label, e.g. 'adaptive FL' (``CONTROLLER_LABELS``); unknown names with spaces.
    """
    return CONTROLLER_LABELS.get(name, str(name).replace("_", " "))


def flight_title(controller: str, name: str | None = None) -> str:
    """The title of a run.

    Parameters
    ----------
    controller : str
        The controller's ``name``.
    name : str, optional
        The scenario's name.

    Returns
    -------
    str
        '<scenario name>: <controller>' ('fig6: adaptive FL'), or only the controller when
        the run has no scenario name.
    """
    label = controller_label(controller)
    return f"{name}: {label}" if name else label


def status_text(metrics: Any) -> str:
    """How a run ended, in a few words.

    Parameters
    ----------
    metrics : quadcog.Metrics
        The run's metrics.

    Returns
    -------
    str
        'tail RMS error 3.78 cm' or 'diverged at 1.350 s (tilt)'.
    """
    if metrics.diverged:
        return f"diverged at {metrics.diverged_at:.3f} s ({metrics.diverged_reason})"
    return f"tail RMS error {100 * metrics.rms_position_error_tail:.2f} cm"


def cog_moves(result: Any) -> bool:
    """Whether the CoG or its estimate moves during a run.

    Parameters
    ----------
    result : quadcog.SimulationResult
        The run (``r_G`` and ``r_hat``, (N, 3), m).

    Returns
    -------
    bool
        True when the true CoG r_G or the estimate r_hat changes by more than ``COG_STILL``.
    """
    return any(np.ptp(a, axis=0).max() > COG_STILL for a in (result.r_G, result.r_hat)
               if len(a))


def _intervals(disturbances: Iterable[Any] | None) -> list[tuple[float, float]]:
    return [(float(d.t), float(d.t) + float(d.duration)) for d in disturbances or ()]


MARKERS = ("o", "s", "^", "D")


def _marks(i, n, count=12):
    """Line options that put ``count`` markers of series ``i`` on a line of ``n`` samples, at
    times shifted per series: two series that coincide (x and y after a symmetric CoG step)
    both stay visible."""
    step = max(1, n // count)
    return {"marker": MARKERS[i % len(MARKERS)], "markersize": 4, "markevery":
            (min(n - 1, (i * step) // len(MARKERS)), step)}


def _rotor_panel(a, result):
    """Each rotor's applied thrust (solid, with markers) and commanded thrust (dashed), in N.
    The axis spans the applied thrusts and the 1st-99th percentiles of the commands, so one
    spike of the command cannot flatten the rest; what lies beyond is said in the legend."""
    f, fc = result.rotor_thrust, result.rotor_command
    if f is None or fc is None:               # a result from before per-rotor thrust
        a.plot(result.t, result.U[:, 0], color="C3", label="U1 (thrust)")
        a.set_ylabel("thrust U1 (N)")
        return
    t = result.t
    for i in range(4):
        a.plot(t, fc[:, i], color=f"C{i}", ls="--", lw=0.9)
        a.plot(t, f[:, i], color=f"C{i}", lw=1.2, label=f"rotor {i + 1}", **_marks(i, len(t)))
    a.plot([], [], color="0.3", ls="--", lw=0.9, label="commanded")
    _robust_ylim(a, np.concatenate([f.ravel(), fc.ravel()]), "N")
    a.set_ylabel("rotor thrust (N)")


def _robust_ylim(a, values, unit):
    """Limit axis ``a`` to the 1st-99th percentiles of ``values`` (with a margin), so that a
    spike (the last samples of a diverging flight) cannot flatten the rest; when values lie
    beyond, a note in the panel says how far."""
    finite = values[np.isfinite(values)]
    if not finite.size:
        return
    lo, hi = np.percentile(finite, [1, 99])
    pad = 0.1 * max(hi - lo, 1e-3 * max(abs(hi), abs(lo), 1.0))
    lo, hi = lo - pad, hi + pad
    if finite.min() < lo or finite.max() > hi:
        a.set_ylim(lo, hi)
        a.text(0.99, 0.96, f"axis clipped; values from {finite.min():.3g} to {finite.max():.3g} {unit}",
               transform=a.transAxes, ha="right", va="top", fontsize=8, color="0.3",
               bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.8, "pad": 1})


def plot_flight(result: Any, path: str | Path | None = None, name: str | None = None,
                title: str | None = None, disturbances: Iterable[Any] | None = None
                ) -> "Figure":
    """The flight figure of a SimulationResult; saved to ``path`` (PNG) if given.

    Parameters
    ----------
    result : quadcog.SimulationResult
        The run: t (N,) s, x (N, 12), U (N, 4), ref (N, 14), r_G and r_hat (N, 3) m,
        metrics, controller and info.
    path : str or Path, optional
        Where to save the figure (dpi 100); the figure is then closed.
    name : str, optional
        The scenario's name, for the title (``flight_title``); default
        ``result.info.get("scenario")``.
    title : str, optional
        Replaces the title's first part entirely.
    disturbances : list of Disturbance, optional
        Pulses to shade; default ``result.info.get("disturbances")``.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (closed when saved).
    """
    import matplotlib
    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    name = name if name is not None else result.info.get("scenario")
    if disturbances is None:
        disturbances = result.info.get("disturbances", ())
    t, x, ref = result.t, result.x, result.ref
    show_cog = cog_moves(result)
    layout = [["P", "A"], ["E", "C" if show_cog else "E"], ["T", "M"]]
    with plt.rc_context({"font.size": 11, "legend.fontsize": 9}):
        # matplotlib's stub asks for list[HashableList[str]]; a list of lists of str is one
        fig, ax = plt.subplot_mosaic(layout, figsize=(12, 9),  # type: ignore[arg-type]
                                     sharex=True)
        for i, (axis, col) in enumerate(zip("xyz", ("C0", "C1", "C2"))):
            ax["P"].plot(t, x[:, i], color=col, label=axis, **_marks(i, len(t)))
            ax["P"].plot(t, ref[:, i], color=col, ls="--", lw=1)
        ax["P"].plot([], [], color="0.3", ls="--", lw=1, label="reference")
        ax["P"].set_ylabel("position (m)")
        err = x[:, :3] - ref[:, :3]
        for i, (axis, col) in enumerate(zip("xyz", ("C0", "C1", "C2"))):
            ax["E"].plot(t, 100 * err[:, i], color=col, lw=1, label=f"{axis} - {axis}_ref",
                         **_marks(i, len(t)))
        ax["E"].plot(t, 100 * np.linalg.norm(err, axis=1), color="k", lw=1.5, label="|error|")
        ax["E"].set_ylabel("position error (cm)")
        for i, (angle, col) in enumerate(zip(("phi", "theta", "psi"), ("C0", "C1", "C2"))):
            ax["A"].plot(t, np.degrees(x[:, 3 + i]), color=col, label=angle, **_marks(i, len(t)))
        ax["A"].set_ylabel("attitude (deg)")
        _rotor_panel(ax["T"], result)
        for i, col in zip(range(1, 4), ("C0", "C1", "C2")):
            ax["M"].plot(t, result.U[:, i], color=col, label=f"U{i + 1}", **_marks(i - 1, len(t)))
        _robust_ylim(ax["M"], result.U[:, 1:].ravel(), "N m")
        ax["M"].set_ylabel("moments (N m)")
        if show_cog:
            for i, (axis, col) in enumerate(zip(("x_G", "y_G", "z_G"), ("C0", "C1", "C2"))):
                estimating = np.any(result.r_hat)
                ax["C"].plot(t, 100 * result.r_G[:, i], color=col, ls="--" if estimating else "-",
                             lw=1.2, label=None if estimating else axis,
                             **({} if estimating else _marks(i, len(t))))
                if estimating:
                    ax["C"].plot(t, 100 * result.r_hat[:, i], color=col,
                                 label=f"{axis} estimate", **_marks(i, len(t)))
            if np.any(result.r_hat):
                ax["C"].plot([], [], color="0.3", ls="--", lw=1.2, label="true")
            ax["C"].set_ylabel("CoG offset (cm)")
        mass = getattr(result, "mass", None)
        if mass is not None and len(mass) and np.ptp(mass) > 0:
            # payloads came or went: the whole body's mass on its own axis (kg)
            host = ax["C" if show_cog else "E"]
            twin = host.twinx()
            twin.plot(t, mass, color="k", lw=1.2, ls=":")
            twin.set_ylabel("mass (kg)")
            host.plot([], [], color="k", lw=1.2, ls=":", label="mass (right axis)")
        spans = _intervals(disturbances)
        for key, a in ax.items():
            for k, (t0, t1) in enumerate(spans):
                a.axvspan(t0, t1, color="0.5", alpha=0.2, lw=0,
                          label="disturbance" if (k == 0 and key == "E") else None)
            a.grid(alpha=0.3)
            # above the panel, outside the data: a legend never hides a curve
            handles, labels = a.get_legend_handles_labels()
            if handles:
                a.legend(loc="lower left", bbox_to_anchor=(0.0, 1.0), ncol=len(handles),
                         frameon=False, borderaxespad=0.2, handlelength=1.5,
                         columnspacing=1.0)
        for key in ("T", "M"):
            ax[key].set_xlabel("time (s)")
        # plot_text: a '$' in a scenario name must not start mathtext (savefig would fail)
        fig.suptitle(plot_text(f"{title or flight_title(result.controller, name)}, "
                               f"{status_text(result.metrics)}"))
        fig.tight_layout()
        if path is not None:
            Path(path).parent.mkdir(parents=True, exist_ok=True)
            save_figure(fig, path, "flight figure", dpi=100)
            plt.close(fig)
    return fig
