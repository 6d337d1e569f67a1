"""What happens to the vehicle over time: the CoG profile r_G(t) and disturbance pulses."""
from dataclasses import dataclass, field

import numpy as np

from .errors import InputError


@dataclass(frozen=True)
class CogChange:
    """From time ``t`` (s) the CoG moves to ``r`` (m, body frame) over ``ramp`` s (0: a step)."""
    t: float
    r: tuple
    ramp: float = 0.0


@dataclass
class CogProfile:
    """r_G(t): zero before the first change, then each change in turn (linear ramps)."""
    changes: list = field(default_factory=list)

    def __post_init__(self):
        clean, last = [], -np.inf
        for i, c in enumerate(self.changes):
            if not isinstance(c, CogChange):
                c = CogChange(*c) if isinstance(c, (tuple, list)) else CogChange(**c)
            r = np.asarray(c.r, dtype=float)
            if r.shape != (3,) or not np.isfinite(r).all():
                raise InputError(f"cog change {i}: r must be 3 finite numbers (m), got {c.r!r}")
            if not (np.isfinite(c.t) and c.t >= 0):
                raise InputError(f"cog change {i}: t must be >= 0 s, got {c.t!r}")
            if not (np.isfinite(c.ramp) and c.ramp >= 0):
                raise InputError(f"cog change {i}: ramp must be >= 0 s, got {c.ramp!r}")
            if c.t < last:
                raise InputError(f"cog change {i}: t = {c.t} s comes before the previous "
                                 f"change's end ({last} s); changes must be in time order")
            last = c.t + c.ramp
            clean.append(CogChange(float(c.t), tuple(r), float(c.ramp)))
        self.changes = clean

    @classmethod
    def step(cls, t, r):
        """A single step to ``r`` (m) at time ``t`` (s)."""
        return cls([CogChange(t, tuple(r), 0.0)])

    def sample(self, t):
        """(N, 3) r_G at the times ``t`` (s)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        r = np.zeros((t.size, 3))
        prev = np.zeros(3)
        for c in self.changes:
            target = np.array(c.r)
            if c.ramp > 0:
                s = np.clip((t - c.t) / c.ramp, 0.0, 1.0)
            else:
                s = (t >= c.t).astype(float)
            active = t >= c.t
            r[active] = prev + s[active, None] * (target - prev)
            prev = target
        return r


@dataclass(frozen=True)
class Disturbance:
    """A wrench pulse from ``t`` for ``duration`` s: ``force`` (N, ground axes, at O) and
    ``moment`` (N m, body axes)."""
    t: float
    duration: float
    force: tuple = (0.0, 0.0, 0.0)
    moment: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self):
        for name in ("force", "moment"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape != (3,) or not np.isfinite(v).all():
                raise InputError(f"disturbance {name} must be 3 finite numbers, got "
                                 f"{getattr(self, name)!r}")
        if not (np.isfinite(self.duration) and self.duration > 0):
            raise InputError(f"disturbance duration must be > 0 s, got {self.duration!r}")
        if not (np.isfinite(self.t) and self.t >= 0):
            raise InputError(f"disturbance t must be >= 0 s, got {self.t!r}")


def wrench_table(disturbances, t):
    """(N, 6) summed wrench of all pulses active at the times ``t`` (s)."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    w = np.zeros((t.size, 6))
    for d in disturbances:
        if not isinstance(d, Disturbance):
            d = Disturbance(**d) if isinstance(d, dict) else Disturbance(*d)
        on = (t >= d.t) & (t < d.t + d.duration)
        w[on] += np.concatenate([d.force, d.moment])
    return w
