"""What a simulation returns: arrays, metrics, and a plot."""
from dataclasses import dataclass, field

import numpy as np

from . import config


@dataclass
class Metrics:
    """Position-error metrics in m; ``diverged_at`` in s or None; the tail is the last
    ``quadcog.config.defaults["metrics.tail_fraction"]`` of the run (25 %)."""
    rms_position_error: float
    max_position_error: float
    final_position_error: float
    rms_position_error_tail: float
    diverged: bool = False
    diverged_at: float | None = None
    diverged_cause: str | None = None
    r_hat_final: list | None = None
    r_G_final: list | None = None
    reference: dict | None = None    # quadcog.feasibility.ReferenceCheck.as_dict() of the run

    def as_dict(self):
        """The metrics as a plain dict (the keys of metrics.json)."""
        return dict(self.__dict__)


def position_metrics(t, x, ref, duration, tail_fraction=None):
    """Metrics of the position error ||p - p_ref|| sampled at ``t``; the tail is the last
    ``tail_fraction`` of ``duration`` (default: ``config.defaults["metrics.tail_fraction"]``)."""
    tail_fraction = config.get("metrics.tail_fraction", tail_fraction)
    with np.errstate(over="ignore", invalid="ignore"):     # a diverged run's last sample
        e = np.linalg.norm(x[:, :3] - ref[:, :3], axis=1)
    tail = t >= (1 - tail_fraction) * duration - 1e-12
    rms_tail = float(np.sqrt(np.mean(e[tail] ** 2))) if tail.any() else float("nan")
    return dict(rms_position_error=float(np.sqrt(np.mean(e ** 2))),
                max_position_error=float(np.max(e)), final_position_error=float(e[-1]),
                rms_position_error_tail=rms_tail)


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

    @property
    def diverged(self):
        """True when the run stopped early (see metrics.diverged_at, diverged_cause)."""
        return self.metrics.diverged

    def plot(self, path=None, title=None, **options):
        """The flight figure (``quadcog.plots.plot_flight``: position, position error,
        attitude, inputs and, when it moves, the CoG); saved to ``path`` if given. Returns the
        matplotlib Figure."""
        from .plots import plot_flight
        return plot_flight(self, path, title=title, **options)
