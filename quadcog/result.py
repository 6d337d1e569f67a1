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

    def plot(self, path=None, title=None):
        """Four panels: position vs reference, attitude, inputs, and the CoG (true, and the
        estimate r_hat for the adaptive controller); saved to ``path`` if given. Returns the
        matplotlib Figure."""
        import matplotlib
        if path is not None:
            matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt
        with plt.rc_context({"font.size": 12, "legend.fontsize": 10}):
            fig, axes = plt.subplots(2, 2, figsize=(12, 7.5), sharex=True)
            (a_pos, a_att), (a_in, a_cog) = axes
            t = self.t
            for i, (name, col) in enumerate(zip("xyz", ("C0", "C1", "C2"))):
                a_pos.plot(t, self.x[:, i], color=col, label=name)
                a_pos.plot(t, self.ref[:, i], color=col, ls="--", lw=1)
            a_pos.set_ylabel("position (m), dashed: reference")
            for i, name in enumerate(("phi", "theta", "psi")):
                a_att.plot(t, np.degrees(self.x[:, 3 + i]), label=name)
            a_att.set_ylabel("attitude (deg)")
            a_in.plot(t, self.U[:, 0], label="U1 (N)")
            for i in range(1, 4):
                a_in.plot(t, 10 * self.U[:, i], label=f"10 U{i + 1} (N m)")
            a_in.set_ylabel("inputs")
            estimating = self.metrics.r_hat_final is not None
            for i, (name, col) in enumerate(zip(("x_G", "y_G", "z_G"), ("C0", "C1", "C2"))):
                a_cog.plot(t, 100 * self.r_G[:, i], color=col, ls="--" if estimating else "-",
                           lw=1.2, label=f"{name}" + (" true" if estimating else ""))
                if estimating:
                    a_cog.plot(t, 100 * self.r_hat[:, i], color=col, label=f"{name} estimate")
            a_cog.set_ylabel("CoG offset (cm)")
            for a in (a_in, a_cog):
                a.set_xlabel("time (s)")
            for a in axes.ravel():
                a.grid(alpha=0.3)
                a.legend(loc="best", ncol=2 if a is a_cog and estimating else 1,
                         framealpha=0.8)
            m = self.metrics
            status = (f"diverged at {m.diverged_at:.3f} s ({m.diverged_cause})" if m.diverged
                      else f"tail RMS error {100 * m.rms_position_error_tail:.2f} cm")
            fig.suptitle(f"{title or self.controller}: {status}")
            fig.tight_layout()
            if path is not None:
                fig.savefig(path, dpi=100)
                plt.close(fig)
        return fig
