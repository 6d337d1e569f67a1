"""What a simulation returns: arrays, metrics (one definition for every path), and a plot."""
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from quadcog import config, validate
from quadcog.numerics import row_distances

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from quadcog.sim.divergence import DivergenceCause, Limits

__all__ = ["Metrics", "metric_arrays", "metrics_from_sums", "position_errors", "flight_metrics",
           "position_metrics", "SimulationResult"]


@dataclass
class Metrics:
    """Position-error metrics (m) of one flight, over the samples before any divergence.

    Parameters
    ----------
    rms_position_error : float
        RMS of the position error (m).
    max_position_error : float
        Its largest value (m).
    final_position_error : float
        At the last counted sample (m).
    rms_position_error_tail : float
        RMS over the tail, the last ``quadcog.config.defaults["metrics.tail_fraction"]`` of
        the run (m; inf when the run diverged: it has no finished tail).
    diverged : bool
        True when the run stopped early.
    diverged_at : float or None
        The time of the first diverged sample (s).
    diverged_cause : DivergenceCause or None
        Why it diverged.
    diverged_reason : str or None
        The cause in words.
    r_hat_final : list of 3 float or None
        The CoG estimate at the last counted sample (m; adaptive controllers only).
    r_G_final : list of 3 float or None
        The true CoG at the last counted sample (m; adaptive controllers only).
    reference : dict or None
        ``quadcog.trajectories.feasibility.ReferenceCheck.as_dict()`` of the run.
    """
    rms_position_error: float
    max_position_error: float
    final_position_error: float
    rms_position_error_tail: float
    diverged: bool = False
    diverged_at: float | None = None
    diverged_cause: "DivergenceCause | None" = None
    diverged_reason: str | None = None
    r_hat_final: list | None = None
    r_G_final: list | None = None
    reference: dict | None = None    # feasibility.ReferenceCheck.as_dict() of the run

    def as_dict(self) -> dict[str, Any]:
        """The metrics as a plain dict (the keys of metrics.json).

        Returns
        -------
        dict
            The fields by name; the cause as its lower-case name.
        """
        d = dict(self.__dict__)
        if self.diverged_cause is not None:
            d["diverged_cause"] = self.diverged_cause.name.lower()
        return d


def metric_arrays(count: npt.ArrayLike, sum_sq: npt.ArrayLike, max_error: npt.ArrayLike,
                  count_tail: npt.ArrayLike, sum_sq_tail: npt.ArrayLike,
                  last_error: npt.ArrayLike, diverged: npt.ArrayLike
                  ) -> dict[str, npt.NDArray[np.float64]]:
    """The metrics of many flights from their sums (arrays of one entry per flight).

    The one definition behind single flights (``metrics_from_sums``) and batches.

    Parameters
    ----------
    count : (B,) array_like
        Samples counted.
    sum_sq : (B,) array_like
        Their sums of e^2 (m^2).
    max_error : (B,) array_like
        Their largest e (m).
    count_tail : (B,) array_like
        Samples counted in the tail.
    sum_sq_tail : (B,) array_like
        Their sums of e^2 (m^2).
    last_error : (B,) array_like
        e at the last counted sample (m).
    diverged : (B,) array_like of bool
        True for a diverged flight.

    Returns
    -------
    dict of str to (B,) numpy.ndarray
        rms_position_error (NaN without samples), max_position_error,
        rms_position_error_tail (inf for a diverged flight) and final_position_error (m).
    """
    count, count_tail = np.asarray(count, float), np.asarray(count_tail, float)
    with np.errstate(invalid="ignore", divide="ignore"):
        rms = np.where(count > 0,
                       np.sqrt(np.asarray(sum_sq, float) / np.where(count > 0, count, 1)),
                       np.nan)
        tail = np.where(count_tail > 0, np.sqrt(np.asarray(sum_sq_tail, float)
                                                / np.where(count_tail > 0, count_tail, 1)), np.nan)
    tail = np.where(np.asarray(diverged, bool), np.inf, tail)
    return {"rms_position_error": rms, "max_position_error": np.asarray(max_error, float),
            "rms_position_error_tail": tail,
            "final_position_error": np.asarray(last_error, float)}


def metrics_from_sums(count: float, sum_sq: float, max_error: float, count_tail: float,
                      sum_sq_tail: float, last_error: float, diverged_at: float | None = None,
                      cause: "DivergenceCause | None" = None, limits: "Limits | None" = None
                      ) -> Metrics:
    """Metrics of one flight from the sums of the squared position errors over the counted
    samples.

    ``metric_arrays``, for one flight.

    Parameters
    ----------
    count : float
        Samples counted.
    sum_sq : float
        Their sum of e^2 (m^2).
    max_error : float
        Their largest e (m).
    count_tail : float
        Samples counted in the tail.
    sum_sq_tail : float
        Their sum of e^2 (m^2).
    last_error : float
        e at the last counted sample (m).
    diverged_at : float, optional
        Time of the first diverged sample (s), with ``cause``.
    cause : DivergenceCause, optional
        Why the run diverged; None when it did not.
    limits : Limits, optional
        The limits ``cause`` is described with.

    Returns
    -------
    Metrics
        RMS values are NaN when nothing was counted.
    """
    m = metric_arrays([count], [sum_sq], [max_error], [count_tail], [sum_sq_tail],
                      [last_error], [cause is not None])
    return Metrics(
        # the four float metrics by name (mypy matches a dict to every field)
        **{k: float(v[0]) for k, v in m.items()},  # type: ignore[arg-type]
        diverged=cause is not None,
        # diverged_at and limits come with a cause
        diverged_at=None if cause is None else float(diverged_at),  # type: ignore[arg-type]
        diverged_cause=cause,
        diverged_reason=(None if cause is None
                         else cause.describe(limits)))  # type: ignore[arg-type]


def position_errors(x: npt.NDArray[np.float64], ref: npt.NDArray[np.float64]
                    ) -> npt.NDArray[np.float64]:
    """The position errors |p - p_ref|.

    Parameters
    ----------
    x : (N, >= 3) numpy.ndarray
        States (position first, m).
    ref : (N, >= 3) numpy.ndarray
        Reference rows (position first, m).

    Returns
    -------
    (N,) numpy.ndarray
        |p - p_ref| (m); a diverged sample may overflow to inf, quietly.
    """
    return row_distances(x, ref)


def flight_metrics(e: npt.NDArray[np.float64], tail: npt.NDArray[Any],
                   diverged_index: int | None = None, diverged_at: float | None = None,
                   cause: "DivergenceCause | None" = None, limits: "Limits | None" = None
                   ) -> Metrics:
    """Metrics of the position errors of one flight.

    Parameters
    ----------
    e : (N,) numpy.ndarray
        Position errors (m).
    tail : (N,) numpy.ndarray of bool or float
        The tail mask (nonzero in the tail).
    diverged_index : int, optional
        Samples before it count (all when None).
    diverged_at : float, optional
        Time of the first diverged sample (s).
    cause : DivergenceCause, optional
        Why the run diverged.
    limits : Limits, optional
        The limits ``cause`` is described with.

    Returns
    -------
    Metrics
        See ``metrics_from_sums``.
    """
    n = e.size if diverged_index is None else diverged_index
    e, tail = e[:n], np.asarray(tail[:n], dtype=bool)
    # numpy's pairwise sums, not e @ e: BLAS's dot wakes its threads for a long e (slow on a
    # busy machine, and its sum then depends on the thread count)
    sq = e * e
    return metrics_from_sums(n, float(np.sum(sq)), float(e.max()) if n else float("nan"),
                             int(np.count_nonzero(tail)), float(np.sum(sq[tail])),
                             float(e[-1]) if n else float("nan"), diverged_at, cause, limits)


def position_metrics(t: npt.NDArray[np.float64], x: npt.NDArray[np.float64],
                     ref: npt.NDArray[np.float64], duration: float,
                     tail_fraction: float | None = None) -> dict[str, float]:
    """Metrics of the position error ||p - p_ref|| of a sampled flight.

    Parameters
    ----------
    t : (N,) numpy.ndarray
        Sample times (s).
    x : (N, 12) numpy.ndarray
        States [m, rad, m/s, rad/s].
    ref : (N, >= 3) numpy.ndarray
        Reference rows.
    duration : float
        The run's duration (s).
    tail_fraction : float, optional
        The tail is the last ``tail_fraction`` of ``duration`` (default:
        ``config.defaults["metrics.tail_fraction"]``).

    Returns
    -------
    dict of str to float
        rms_position_error, max_position_error, final_position_error and
        rms_position_error_tail (m).
    """
    tail_fraction = (config.get("metrics.tail_fraction") if tail_fraction is None else
                     validate.real(tail_fraction, "tail_fraction", lo=0.0, hi=1.0, lo_open=True))
    m = flight_metrics(position_errors(x, ref), t >= (1 - tail_fraction) * duration - 1e-12)
    return {k: getattr(m, k) for k in ("rms_position_error", "max_position_error",
                                       "final_position_error", "rms_position_error_tail")}


@dataclass
class SimulationResult:
    """One flight, sampled at the step times.

    Parameters
    ----------
    t : (N,) numpy.ndarray
        Step times (s).
    x : (N, 12) numpy.ndarray
        State [m, rad, m/s, rad/s].
    U : (N, 4) numpy.ndarray
        Applied input [N, N m, N m, N m] (held over each step; the last row repeats).
    ref : (N, 14) numpy.ndarray
        Reference rows (``quadcog.trajectories.analytic``).
    r_hat : (N, 3) numpy.ndarray
        The CoG estimate (m; zeros for controllers without one).
    r_G : (N, 3) numpy.ndarray
        The true CoG of the whole body, airframe and payloads (m, body frame).
    metrics : Metrics
        The flight's metrics.
    controller : str
        The controller's name.
    path : str
        'compiled' or 'python'.
    info : dict
        More about the run (e.g. "seconds", "scenario", "disturbances").
    rotor_thrust : (N, 4) numpy.ndarray or None
        What each rotor gives (N), within its limits (with motor lag, the lagged thrust).
    mass : (N,) numpy.ndarray or None
        The true mass of the whole body, airframe and payloads (kg).
    controller_state : (N, n_state) numpy.ndarray or None
        The controller's own state c at each sample (with sensing, the sensed controller's:
        the inner state first); None when not recorded.
    _command_law : callable or None
        Internal: computes ``rotor_command`` on first use.
    _rotor_command : (N, 4) numpy.ndarray or None
        Internal: the cache of ``rotor_command``.
    """
    t: np.ndarray
    x: np.ndarray
    U: np.ndarray
    ref: np.ndarray
    r_hat: np.ndarray
    r_G: np.ndarray
    metrics: Metrics
    controller: str = ""
    path: str = ""
    info: dict = field(default_factory=dict)
    # per rotor (N, 4), N: what the rotor gives (clipped to its limits; with motor lag, the
    # lagged thrust) and, computed on first use (the law re-evaluated along the flight), what
    # the controller's U asked of it (the inverse mixer, no limit)
    rotor_thrust: np.ndarray | None = None
    mass: np.ndarray | None = None
    controller_state: np.ndarray | None = None
    _command_law: object = field(default=None, repr=False, compare=False)
    _rotor_command: np.ndarray | None = field(default=None, repr=False, compare=False)

    @property
    def rotor_command(self):
        """The thrust (N, 4) in N that the controller's input asked of each rotor, before the
        rotors' limits (a negative value: a rotor asked to pull); None if not known."""
        if self._rotor_command is None and self._command_law is not None:
            self._rotor_command = self._command_law()
        return self._rotor_command

    @property
    def diverged(self) -> bool:
        """True when the run stopped early (see metrics.diverged_at, diverged_cause)."""
        return self.metrics.diverged

    def plot(self, path: str | Path | None = None, title: str | None = None,
             **options: Any) -> "Figure":
        """The flight figure; saved to ``path`` if given.

        ``quadcog.viz.plots.plot_flight``: position, position error, attitude, inputs and,
        when it moves, the CoG.

        Parameters
        ----------
        path : str or Path, optional
            Where to save the figure (PNG); the figure is then closed.
        title : str, optional
            Replaces the title's first part.
        **options
            Further keywords of ``plot_flight`` (``name``, ``disturbances``).

        Returns
        -------
        matplotlib.figure.Figure
            The figure.
        """
        from quadcog.viz.plots import plot_flight
        return plot_flight(self, path, title=title, **options)
