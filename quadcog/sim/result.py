"""What a simulation returns: arrays, metrics (one definition for every path), and a plot."""
from dataclasses import dataclass, field

import numpy as np

from quadcog import config


@dataclass
class Metrics:
    """Position-error metrics (m) of one flight, over the samples before any divergence.

    rms_position_error, max_position_error; final_position_error (at the last counted
    sample); rms_position_error_tail over the tail, the last
    ``quadcog.config.defaults["metrics.tail_fraction"]`` of the run (inf when the run
    diverged: it has no finished tail). diverged, diverged_at (s, the time of the first
    diverged sample), diverged_cause (a DivergenceCause) and diverged_reason (in words).
    r_hat_final, r_G_final: estimate and true CoG at the last counted sample (m; adaptive
    controllers only)."""
    rms_position_error: float
    max_position_error: float
    final_position_error: float
    rms_position_error_tail: float
    diverged: bool = False
    diverged_at: float | None = None
    diverged_cause: object = None
    diverged_reason: str | None = None
    r_hat_final: list | None = None
    r_G_final: list | None = None
    reference: dict | None = None    # quadcog.trajectories.feasibility.ReferenceCheck.as_dict() of the run

    def as_dict(self):
        """The metrics as a plain dict (the keys of metrics.json); the cause as its name."""
        d = dict(self.__dict__)
        if self.diverged_cause is not None:
            d["diverged_cause"] = self.diverged_cause.name.lower()
        return d


def metrics_from_sums(count, sum_sq, max_error, count_tail, sum_sq_tail, last_error,
                      diverged_at=None, cause=None, limits=None):
    """Metrics from the sums of the squared position errors over the counted samples: the one
    definition behind single flights (``flight_metrics``) and batches (compiled sums).

    count, count_tail: samples counted (all, tail); sum_sq, sum_sq_tail: their sums of e^2
    (m^2); max_error, last_error (m). cause: a DivergenceCause or None, described with
    ``limits``."""
    nan = float("nan")
    return Metrics(
        rms_position_error=float(np.sqrt(sum_sq / count)) if count else nan,
        max_position_error=float(max_error), final_position_error=float(last_error),
        rms_position_error_tail=(float("inf") if cause is not None else
                                 float(np.sqrt(sum_sq_tail / count_tail)) if count_tail else nan),
        diverged=cause is not None,
        diverged_at=None if cause is None else float(diverged_at),
        diverged_cause=cause,
        diverged_reason=None if cause is None else cause.describe(limits))


def position_errors(x, ref):
    """|p - p_ref| (N,) (m) of states x (N, >= 3) and reference rows ref (N, >= 3); a
    diverged sample may overflow to inf, quietly."""
    with np.errstate(over="ignore", invalid="ignore"):
        return np.linalg.norm(x[:, :3] - ref[:, :3], axis=1)


def flight_metrics(e, tail, diverged_index=None, diverged_at=None, cause=None, limits=None):
    """Metrics of position errors e (N,) (m) with the tail mask ``tail`` (N,): samples before
    ``diverged_index`` (all when None) count."""
    n = e.size if diverged_index is None else diverged_index
    e, tail = e[:n], np.asarray(tail[:n], dtype=bool)
    return metrics_from_sums(n, float(e @ e), float(e.max()) if n else float("nan"),
                             int(tail.sum()), float(e[tail] @ e[tail]),
                             float(e[-1]) if n else float("nan"), diverged_at, cause, limits)


def position_metrics(t, x, ref, duration, tail_fraction=None):
    """Metrics (a dict) of the position error ||p - p_ref|| of x (N, 12) sampled at ``t``
    (N,); the tail is the last ``tail_fraction`` of ``duration`` (default:
    ``config.defaults["metrics.tail_fraction"]``)."""
    tail_fraction = config.get("metrics.tail_fraction", tail_fraction)
    m = flight_metrics(position_errors(x, ref), t >= (1 - tail_fraction) * duration - 1e-12)
    return {k: getattr(m, k) for k in ("rms_position_error", "max_position_error",
                                       "final_position_error", "rms_position_error_tail")}


@dataclass
class SimulationResult:
    """One flight. Arrays are sampled at the step times t (N,): state x (N, 12), applied input
    U (N, 4) (held over each step; the last row repeats), reference ref (N, 11), the estimate
    r_hat (N, 3) (zeros for controllers without one) and the true CoG r_G (N, 3)."""
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
    def diverged(self):
        """True when the run stopped early (see metrics.diverged_at, diverged_cause)."""
        return self.metrics.diverged

    def plot(self, path=None, title=None, **options):
        """The flight figure (``quadcog.viz.plots.plot_flight``: position, position error,
        attitude, inputs and, when it moves, the CoG); saved to ``path`` if given. Returns the
        matplotlib Figure."""
        from quadcog.viz.plots import plot_flight
        return plot_flight(self, path, title=title, **options)
