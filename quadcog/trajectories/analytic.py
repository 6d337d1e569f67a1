"""Reference trajectories: position, velocity, acceleration, yaw and yaw rate.

A trajectory maps time t (s) to the 14-vector ``[p (3, m), v (3, m/s), a (3, m/s^2),
j (3, m/s^3), yaw (rad), yaw_rate (rad/s)]``; ``sample(t)`` does it for an array of times and
returns (N, 14). The jerk lets the controllers feed forward the rate of the attitude they
command. ``quadcog.trajectories.template`` states that interface as a Protocol.
"""
from collections.abc import Callable
import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.errors import InputError
from quadcog.kinds import Number, Vec3
from quadcog.model.parameters import LARGEST
from quadcog.numerics import fill_rows

# position, velocity, acceleration, jerk: each (N, 3), ground axes (m, m/s, m/s^2, m/s^3)
_PVAJ = tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64],
              npt.NDArray[np.float64]]

__all__ = ["sample_times", "Trajectory", "Hover", "Circle", "Figure8", "Helix", "FromCallable",
           "DIFFERENCE_STEP", "REF_SIZE", "REF_NAMES", "REFERENCE_LIMIT", "POS", "VEL", "ACC", "JERK",
           "YAW", "YAW_RATE"]

REF_SIZE = 14
POS, VEL, ACC, JERK = slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12)
YAW, YAW_RATE = 12, 13
# A reference row beyond this (SI units) is refused: far above any flyable reference (a
# finite-differenced waypoint step reaches ~5e8 m/s^3, which
# quadcog.trajectories.feasibility reports),
# and low enough that the closed loop's products stay finite (a radius of 1e300 m does not).
REFERENCE_LIMIT = 1e12
REF_NAMES = ("x", "y", "z", "vx", "vy", "vz", "ax", "ay", "az", "jx", "jy", "jz", "yaw",
             "yaw_rate")


def _vec3(name, value):
    return validate.array(value, name, (3,), what="3 finite numbers (m)")


def _positive(name, value):
    return validate.positive(value, name)


def _angle(name, value):
    return validate.real(value, name, unit="rad")


def _rate(name, period):
    """2 pi / period (rad/s), refused when it overflows (a period of 5e-324 s)."""
    w = 2 * np.pi / period
    if not w <= LARGEST:
        raise InputError(f"{name}: expected a period of at least {2 * np.pi / LARGEST:.3g} s "
                         f"(at most {LARGEST:g} rad/s), got {validate.plain(period)}")
    return w


def _describe(trajectory):
    """'Circle(center=[0.0, 0.0, 1.0], radius=1e+300, ...)' with plain numbers."""
    if dataclasses.is_dataclass(trajectory):
        fields = ", ".join(f"{f.name}={validate.plain(getattr(trajectory, f.name))}"
                           for f in dataclasses.fields(trajectory))
        return f"{type(trajectory).__name__}({fields})"
    times = getattr(trajectory, "times", None)
    if isinstance(times, np.ndarray) and times.size:     # MinimumSnap: no dataclass
        return (f"{type(trajectory).__name__}({times.size} waypoints from "
                f"{validate.plain(times[0])} s to {validate.plain(times[-1])} s)")
    return repr(trajectory)


def _checked_reference(ref, t, trajectory, pieces=None):
    """``ref`` (N, 14) if every entry is finite and within +-REFERENCE_LIMIT, else InputError
    naming the trajectory, the first bad time and entry. ``pieces``, arrays that hold every
    entry of ``ref`` between them (the row constant in time and the varying columns), are
    checked in its place when given: a hover's 20,000 equal rows are one row to check."""
    # the common case without a temporary array: NaN fails both comparisons
    if ref.size == 0 or all(a.max() <= REFERENCE_LIMIT and a.min() >= -REFERENCE_LIMIT
                            for a in ([ref] if pieces is None else pieces)):
        return ref
    with np.errstate(invalid="ignore"):
        bad = ~(np.abs(ref) <= REFERENCE_LIMIT)
    if bad.any():
        k, i = np.unravel_index(int(np.argmax(bad)), bad.shape)
        raise InputError(f"trajectory {_describe(trajectory)}: {REF_NAMES[i]} at t = "
                         f"{validate.plain(t[k])} s is {validate.plain(ref[k, i])}; expected "
                         f"finite values within +-{REFERENCE_LIMIT:g} (SI units)")
    return ref


def sample_times(t: npt.ArrayLike, where: str = "t") -> npt.NDArray[np.float64]:
    """Times to sample a trajectory at: a real number or a 1-D array of them, finite (s).

    Parameters
    ----------
    t : float or (N,) array_like
        Times (s).
    where : str
        The argument's name, for messages.

    Returns
    -------
    (N,) numpy.ndarray
        A float64 copy (a number gives one time).

    Raises
    ------
    InputError
        A bool, complex, string, None, NaN or infinite time, or an array of more than one
        dimension.
    """
    if isinstance(t, np.ndarray) and t.dtype == np.float64 and t.ndim == 1 and \
            np.isfinite(t).all():
        return t                     # the simulator's own grids: nothing to convert
    a = validate.array(t, where, what="a time or a 1-D array of times (s)")
    if a.ndim > 1:
        validate.fail(where, "a time or a 1-D array of times (s)", t)
    return np.atleast_1d(a)


class Trajectory:
    """Base class: subclasses implement ``_pvaj(t)`` for an array t -> four (N, 3) arrays.

    A trajectory maps time (s) to the reference row ``[p (3, m), v (3, m/s), a (3, m/s^2),
    j (3, m/s^3), yaw (rad), yaw_rate (rad/s)]`` (``quadcog.trajectories.template``).
    """

    yaw: float = 0.0
    # every row the same at every time (a hover): the checks of a run's rows need only one
    constant: ClassVar[bool] = False
    # what a subclass implements (an annotation only: the base class defines no such method)
    _pvaj: Callable[[npt.NDArray[np.float64]], tuple[npt.NDArray[np.float64], ...]]

    def sample(self, t: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Reference rows at many times.

        Parameters
        ----------
        t : float or (N,) array_like
            Times (s).

        Returns
        -------
        (N, 14) numpy.ndarray
            One row ``[p (m), v (m/s), a (m/s^2), j (m/s^3), yaw (rad), yaw_rate (rad/s)]``
            per time.

        Raises
        ------
        InputError
            When a row is not finite or beyond REFERENCE_LIMIT (a radius of 1e300 m).
        """
        t = sample_times(t)
        with np.errstate(over="ignore", invalid="ignore"):
            # one array, no hstack of copies: the parts constant in time (broadcast views,
            # stride 0) go into one row that fills every row at once; a column block is a
            # strided copy, several times slower
            row = np.zeros(REF_SIZE)
            row[YAW] = float(self.yaw)
            varying = []
            for part, cols in zip(self._pvaj(t), (POS, VEL, ACC, JERK)):
                part = np.asarray(part, dtype=float)    # a subclass may give lists
                if t.size and part.ndim == 2 and part.strides[0] == 0:
                    row[cols] = part[0]
                else:
                    varying.append((cols, part))
            ref = fill_rows(np.empty((t.size, REF_SIZE)), row)
            for cols, part in varying:
                ref[:, cols] = part
        return _checked_reference(ref, t, self, [row] + [ref[:, cols] for cols, _ in varying])

    def __call__(self, t: float) -> npt.NDArray[np.float64]:
        """The reference row at one time.

        Parameters
        ----------
        t : float
            Time (s).

        Returns
        -------
        (14,) numpy.ndarray
            ``[p (m), v (m/s), a (m/s^2), j (m/s^3), yaw (rad), yaw_rate (rad/s)]``.

        Raises
        ------
        InputError
            When the row is not finite or beyond REFERENCE_LIMIT.
        """
        return self.sample([t])[0]


@dataclass
class Hover(Trajectory):
    """Hold ``position`` (m) at heading ``yaw`` (rad).

    Parameters
    ----------
    position : (3,) array_like
        The position held (m), ground axes; default [0, 0, 1].
    yaw : float
        Heading (rad), default 0.

    Raises
    ------
    InputError
        When a setting is not finite or of the wrong shape.
    """
    position: Vec3 = (0.0, 0.0, 1.0)
    yaw: Number = 0.0
    constant: ClassVar[bool] = True

    def __post_init__(self) -> None:
        self.position = _vec3("hover position", self.position)
        self.yaw = _angle("hover yaw", self.yaw)

    def _pvaj(self, t: npt.NDArray[np.float64]) -> _PVAJ:
        p = np.broadcast_to(np.asarray(self.position, float), (t.size, 3))
        zero = np.broadcast_to(0.0, (t.size, 3))
        return p, zero, zero, zero


@dataclass
class Circle(Trajectory):
    """Horizontal circle of ``radius`` (m) about ``center`` (m), one lap per ``period`` (s),
    counter-clockwise, starting at center + [radius, 0, 0].

    Parameters
    ----------
    center : (3,) array_like
        Centre of the circle (m), ground axes; default [0, 0, 1].
    radius : float
        Radius (m), > 0; default 1.
    period : float
        Time of one lap (s), > 0; default 10.
    yaw : float
        Heading held (rad), default 0.

    Raises
    ------
    InputError
        When a setting is not finite, out of range or of the wrong shape.
    """
    center: Vec3 = (0.0, 0.0, 1.0)
    radius: Number = 1.0
    period: Number = 10.0
    yaw: Number = 0.0

    def __post_init__(self) -> None:
        self.center = _vec3("circle center", self.center)
        self.radius = _positive("circle radius", self.radius)
        self.period = _positive("circle period", self.period)
        self.yaw = _angle("circle yaw", self.yaw)
        _rate("circle period", self.period)

    def _pvaj(self, t: npt.NDArray[np.float64]) -> _PVAJ:
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
    y = size sin(2 w t) / 2 about ``center``, one figure per ``period`` (s), w = 2 pi / period.

    Parameters
    ----------
    center : (3,) array_like
        Centre of the figure (m), ground axes; default [0, 0, 1].
    size : float
        Half-width along x (m), > 0; default 1.
    period : float
        Time of one figure (s), > 0; default 12.
    yaw : float
        Heading held (rad), default 0.

    Raises
    ------
    InputError
        When a setting is not finite, out of range or of the wrong shape.
    """
    center: Vec3 = (0.0, 0.0, 1.0)
    size: Number = 1.0
    period: Number = 12.0
    yaw: Number = 0.0

    def __post_init__(self) -> None:
        self.center = _vec3("figure8 center", self.center)
        self.size = _positive("figure8 size", self.size)
        self.period = _positive("figure8 period", self.period)
        self.yaw = _angle("figure8 yaw", self.yaw)
        _rate("figure8 period", self.period)

    def _pvaj(self, t: npt.NDArray[np.float64]) -> _PVAJ:
        w, a_, z = 2 * np.pi / self.period, self.size, np.zeros_like(t)
        p = self.center + np.stack([a_ * np.sin(w * t), a_ / 2 * np.sin(2 * w * t), z], 1)
        v = np.stack([a_ * w * np.cos(w * t), a_ * w * np.cos(2 * w * t), z], 1)
        acc = np.stack([-a_ * w ** 2 * np.sin(w * t), -2 * a_ * w ** 2 * np.sin(2 * w * t), z], 1)
        j = np.stack([-a_ * w ** 3 * np.cos(w * t), -4 * a_ * w ** 3 * np.cos(2 * w * t), z], 1)
        return p, v, acc, j


@dataclass
class Helix(Circle):
    """A circle that climbs at ``climb_rate`` (m/s).

    Parameters
    ----------
    center : (3,) array_like
        Centre of the circle at t = 0 (m), ground axes; default [0, 0, 1].
    radius : float
        Radius (m), > 0; default 1.
    period : float
        Time of one lap (s), > 0; default 10.
    yaw : float
        Heading held (rad), default 0.
    climb_rate : float
        Vertical speed (m/s), default 0.1 (negative: descends).

    Raises
    ------
    InputError
        When a setting is not finite, out of range or of the wrong shape.
    """
    climb_rate: Number = 0.1

    def __post_init__(self) -> None:
        super().__post_init__()
        self.climb_rate = validate.real(self.climb_rate, "helix climb_rate", unit="m/s")

    def _pvaj(self, t: npt.NDArray[np.float64]) -> _PVAJ:
        p, v, a, j = super()._pvaj(t)
        p[:, 2] += self.climb_rate * t
        v[:, 2] += self.climb_rate
        return p, v, a, j


# the central differences' step h of FromCallable (s): the jerk divides by h^3, so below
# 1e-6 s a position's rounding (1e-16 of it) is amplified past 1e2 m/s^3; above 1 s it is
# no derivative of a flight's reference
DIFFERENCE_STEP = (1e-6, 1.0)

class FromCallable(Trajectory):
    """Wrap a user function of time as a Trajectory.

    Missing derivatives are taken by central differences with step ``h`` (s); yaw is 0.

    Parameters
    ----------
    f : callable
        ``f(t)`` for a time t (s, float) returning a position (3,) (m), a tuple
        (position (m), velocity (m/s), acceleration (m/s^2)[, jerk (m/s^3)]) of 3-vectors, or
        the full 14-entry reference row.
    h : float
        Step of the central differences (s), default 1e-3, within ``DIFFERENCE_STEP``: below
        it the jerk's third difference is rounding noise, above it no derivative.

    Raises
    ------
    InputError
        ``f`` not callable, or ``h`` not a number within ``DIFFERENCE_STEP``.
    """

    def __init__(self, f: Callable[[float], Any], h: float = 1e-3) -> None:
        if not callable(f):
            validate.fail("FromCallable: f", "a function of time t (s)", f)
        lo, hi = DIFFERENCE_STEP
        self.f, self.h = f, validate.real(h, "FromCallable: h", lo=lo, hi=hi, unit="s")

    def _eval(self, t):
        name = getattr(self.f, "__name__", type(self.f).__name__)
        where = f"trajectory callable {name}(t = {validate.plain(t)})"
        out = validate.user_function(self.f, f"trajectory callable {name}")(float(t))
        shape = "a position (3,), a tuple (p, v, a[, j]) of 3-vectors or a 14-vector"
        if isinstance(out, tuple):
            if not 1 <= len(out) <= 4:
                validate.fail(where, shape, out)
            parts = [validate.array(o, f"{where}[{k}]", (3,), what=shape)
                     for k, o in enumerate(out)]
            return parts + [None] * (4 - len(parts))
        out = validate.array(out, where, what=shape).reshape(-1)
        if out.size == REF_SIZE:
            return out
        if out.size != 3:
            raise InputError(f"{where}: expected {shape}, got shape {out.shape}")
        return [out, None, None, None]

    def sample(self, t: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Reference rows at many times, from the wrapped function.

        Parameters
        ----------
        t : float or (N,) array_like
            Times (s).

        Returns
        -------
        (N, 14) numpy.ndarray
            One row ``[p (m), v (m/s), a (m/s^2), j (m/s^3), yaw (rad), yaw_rate (rad/s)]``
            per time.

        Raises
        ------
        InputError
            When ``t`` is not finite times (``sample_times``), the function raises, returns
            something of another shape, or a row is not finite or beyond REFERENCE_LIMIT.
        """
        rows = []
        t = sample_times(t)             # NaN, strings, 2-D arrays: named, not raw or NaN rows
        for tk in t:
            got = self._eval(tk)
            if not isinstance(got, list):
                rows.append(got)
                continue
            p, v, a, j = got
            h = self.h
            pos = lambda s: np.asarray(self._eval(s)[0])
            with np.errstate(over="ignore", invalid="ignore"):
                if v is None:
                    v = (pos(tk + h) - pos(tk - h)) / (2 * h)
                if a is None:
                    a = (pos(tk + h) - 2 * p + pos(tk - h)) / h ** 2
                if j is None:
                    j = (pos(tk + 2 * h) - 2 * pos(tk + h) + 2 * pos(tk - h)
                         - pos(tk - 2 * h)) / (2 * h ** 3)
            rows.append(np.concatenate([p, v, a, j, [0.0, 0.0]]))
        return _checked_reference(np.array(rows).reshape(t.size, REF_SIZE), t, self)

    def __repr__(self):
        return f"FromCallable({getattr(self.f, '__name__', type(self.f).__name__)})"
