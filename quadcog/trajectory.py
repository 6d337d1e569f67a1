"""Reference trajectories: position, velocity, acceleration, yaw and yaw rate.

A trajectory maps time t (s) to the 14-vector ``[p (3, m), v (3, m/s), a (3, m/s^2),
j (3, m/s^3), yaw (rad), yaw_rate (rad/s)]``; ``sample(t)`` does it for an array of times and
returns (N, 14). The jerk lets the controllers feed forward the rate of the attitude they command.
"""
from dataclasses import dataclass

import numpy as np

from .errors import InputError

REF_SIZE = 14
POS, VEL, ACC, JERK = slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12)
YAW, YAW_RATE = 12, 13


def _vec3(name, value):
    a = np.asarray(value, dtype=float)
    if a.shape != (3,) or not np.isfinite(a).all():
        raise InputError(f"{name} must be 3 finite numbers (m), got {value!r}")
    return a


def _positive(name, value):
    if not (np.isfinite(value) and value > 0):
        raise InputError(f"{name} must be a positive number, got {value!r}")
    return float(value)


class Trajectory:
    """Base class: subclasses implement ``_pvaj(t)`` for an array t -> four (N, 3) arrays."""

    yaw = 0.0

    def sample(self, t):
        """(N, 14) reference rows at the times ``t`` (s)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        p, v, a, j = self._pvaj(t)
        yaw = np.full((t.size, 1), float(self.yaw))
        return np.hstack([p, v, a, j, yaw, np.zeros((t.size, 1))])

    def __call__(self, t):
        """The 14-vector reference at time t (s)."""
        return self.sample([t])[0]


@dataclass
class Hover(Trajectory):
    """Hold ``position`` (m) at heading ``yaw`` (rad)."""
    position: tuple = (0.0, 0.0, 1.0)
    yaw: float = 0.0

    def __post_init__(self):
        self.position = _vec3("hover position", self.position)

    def _pvaj(self, t):
        p = np.tile(self.position, (t.size, 1))
        return p, np.zeros_like(p), np.zeros_like(p), np.zeros_like(p)


@dataclass
class Circle(Trajectory):
    """Horizontal circle of ``radius`` (m) about ``center`` (m), one lap per ``period`` (s),
    counter-clockwise, starting at center + [radius, 0, 0]."""
    center: tuple = (0.0, 0.0, 1.0)
    radius: float = 1.0
    period: float = 10.0
    yaw: float = 0.0

    def __post_init__(self):
        self.center = _vec3("circle center", self.center)
        self.radius = _positive("circle radius", self.radius)
        self.period = _positive("circle period", self.period)

    def _pvaj(self, t):
        w = 2 * np.pi / self.period
        c, s, z = np.cos(w * t), np.sin(w * t), np.zeros_like(t)
        r = self.radius
        p = self.center + np.stack([r * c, r * s, z], 1)
        v = np.stack([-r * w * s, r * w * c, z], 1)
        a = np.stack([-r * w ** 2 * c, -r * w ** 2 * s, z], 1)
        j = np.stack([r * w ** 3 * s, -r * w ** 3 * c, z], 1)
        return p, v, a, j


@dataclass
class Figure8(Trajectory):
    """Lemniscate of Gerono in the horizontal plane: x = size sin(w t),
    y = size sin(2 w t) / 2 about ``center``, one figure per ``period`` (s)."""
    center: tuple = (0.0, 0.0, 1.0)
    size: float = 1.0
    period: float = 12.0
    yaw: float = 0.0

    def __post_init__(self):
        self.center = _vec3("figure8 center", self.center)
        self.size = _positive("figure8 size", self.size)
        self.period = _positive("figure8 period", self.period)

    def _pvaj(self, t):
        w, a_, z = 2 * np.pi / self.period, self.size, np.zeros_like(t)
        p = self.center + np.stack([a_ * np.sin(w * t), a_ / 2 * np.sin(2 * w * t), z], 1)
        v = np.stack([a_ * w * np.cos(w * t), a_ * w * np.cos(2 * w * t), z], 1)
        acc = np.stack([-a_ * w ** 2 * np.sin(w * t), -2 * a_ * w ** 2 * np.sin(2 * w * t), z], 1)
        j = np.stack([-a_ * w ** 3 * np.cos(w * t), -4 * a_ * w ** 3 * np.cos(2 * w * t), z], 1)
        return p, v, acc, j


@dataclass
class Helix(Circle):
    """A circle that climbs at ``climb_rate`` (m/s)."""
    climb_rate: float = 0.1

    def __post_init__(self):
        super().__post_init__()
        if not np.isfinite(self.climb_rate):
            raise InputError(f"helix climb_rate must be finite, got {self.climb_rate!r}")

    def _pvaj(self, t):
        p, v, a, j = super()._pvaj(t)
        p[:, 2] += self.climb_rate * t
        v[:, 2] += self.climb_rate
        return p, v, a, j


class FromCallable(Trajectory):
    """Wrap a user function ``f(t)`` returning a position (3,), a tuple
    (position, velocity, acceleration[, jerk]), or the full 14-vector. Missing derivatives
    are taken by central differences with step ``h`` (s); yaw is 0."""

    def __init__(self, f, h=1e-3):
        self.f, self.h = f, h

    def _eval(self, t):
        out = self.f(float(t))
        if isinstance(out, tuple):
            parts = [np.asarray(o, dtype=float).reshape(3) for o in out]
            return parts + [None] * (4 - len(parts))
        out = np.asarray(out, dtype=float).reshape(-1)
        if out.size == REF_SIZE:
            return out
        if out.size != 3:
            raise InputError(f"trajectory callable must return a position (3,), a tuple "
                             f"(p, v, a[, j]) or a 14-vector, got shape {out.shape}")
        return [out, None, None, None]

    def sample(self, t):
        rows = []
        for tk in np.atleast_1d(np.asarray(t, dtype=float)):
            got = self._eval(tk)
            if not isinstance(got, list):
                rows.append(got)
                continue
            p, v, a, j = got
            h = self.h
            pos = lambda s: np.asarray(self._eval(s)[0])
            if v is None:
                v = (pos(tk + h) - pos(tk - h)) / (2 * h)
            if a is None:
                a = (pos(tk + h) - 2 * p + pos(tk - h)) / h ** 2
            if j is None:
                j = (pos(tk + 2 * h) - 2 * pos(tk + h) + 2 * pos(tk - h) - pos(tk - 2 * h)) / (
                    2 * h ** 3)
            rows.append(np.concatenate([p, v, a, j, [0.0, 0.0]]))
        ref = np.array(rows)
        if not np.isfinite(ref).all():
            raise InputError("trajectory callable returned non-finite values")
        return ref


def as_trajectory(trajectory):
    """Accept a Trajectory, a name ('hover', 'circle', 'figure8', 'helix') or a callable."""
    if isinstance(trajectory, Trajectory):
        return trajectory
    if isinstance(trajectory, str):
        kinds = {"hover": Hover, "circle": Circle, "figure8": Figure8, "helix": Helix}
        if trajectory not in kinds:
            raise InputError(f"unknown trajectory {trajectory!r}; expected one of {tuple(kinds)}")
        return kinds[trajectory]()
    if callable(trajectory):
        return FromCallable(trajectory)
    raise InputError(f"trajectory must be a Trajectory, a name or a callable, got {trajectory!r}")
