"""What happens to the vehicle over time: the CoG profile r_G(t) and disturbance pulses."""
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.errors import InputError
from quadcog.model.parameters import LARGEST

__all__ = ["CogChange", "CogProfile", "Disturbance", "wrench_table", "as_disturbances"]


@dataclass(frozen=True)
class CogChange:
    """From time ``t`` the CoG moves to ``r`` over ``ramp`` (0: a step).

    Parameters
    ----------
    t : float
        Start of the change (s).
    r : tuple of 3 float
        The CoG offset it moves to (m, body frame).
    ramp : float
        Duration of the linear ramp (s; 0: a step).
    """
    t: float
    r: tuple
    ramp: float = 0.0


@dataclass
class CogProfile:
    """r_G(t): zero before the first change, then each change in turn (linear ramps).

    Parameters
    ----------
    changes : sequence of CogChange
        The changes in time order; also tuples (t, r[, ramp]) or dicts with keys t, r and
        ramp, checked and turned into CogChanges.

    Raises
    ------
    quadcog.InputError
        A change that is not one of those, or changes out of time order.
    """
    changes: list = field(default_factory=list)

    def __post_init__(self) -> None:
        clean, last = [], -np.inf
        if isinstance(self.changes, (str, bytes, dict)) or not hasattr(self.changes, "__iter__"):
            validate.fail("cog", "a CogProfile or a list of changes (t, r[, ramp])", self.changes)
        for i, c in enumerate(self.changes):
            where = f"cog change {i}"
            if not isinstance(c, CogChange):
                if isinstance(c, (tuple, list)) and 2 <= len(c) <= 3:
                    c = CogChange(*c)
                elif isinstance(c, dict):
                    try:
                        c = CogChange(**c)
                    except TypeError:
                        validate.fail(where, "a table with keys t, r and ramp", c)
                else:
                    validate.fail(where, "a CogChange or a tuple (t, r[, ramp])", c)
            r = validate.array(c.r, f"{where}: r", (3,), what="3 finite numbers (m)")
            c = CogChange(validate.nonnegative(c.t, f"{where}: t", "s"), tuple(r.tolist()),
                          validate.nonnegative(c.ramp, f"{where}: ramp", "s"))
            if c.t < last:
                raise InputError(f"cog change {i}: t = {c.t} s comes before the previous "
                                 f"change's end ({last} s); expected changes in time order")
            last = c.t + c.ramp
            clean.append(c)
        self.changes = clean

    @classmethod
    def step(cls, t: float, r: Sequence[float]) -> "CogProfile":
        """A single step of the CoG.

        Parameters
        ----------
        t : float
            When (s).
        r : (3,) sequence of float
            The CoG offset it steps to (m, body frame).

        Returns
        -------
        CogProfile
            One change, without a ramp.
        """
        return cls([CogChange(t, tuple(r), 0.0)])

    def sample(self, t: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The CoG offset at given times.

        Parameters
        ----------
        t : (N,) array_like
            Times (s).

        Returns
        -------
        (N, 3) numpy.ndarray
            r_G (m, body frame).
        """
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
    """A wrench pulse from ``t`` for ``duration``.

    Parameters
    ----------
    t : float
        Start (s), >= 0.
    duration : float
        Length (s), > 0.
    force : (3,) tuple of float
        Force (N, ground axes, at O).
    moment : (3,) tuple of float
        Moment (N m, body axes).

    Raises
    ------
    quadcog.InputError
        A field that is not a number in its range.
    """
    t: float
    duration: float
    force: tuple = (0.0, 0.0, 0.0)
    moment: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        for name in ("force", "moment"):
            v = validate.array(getattr(self, name), f"disturbance {name}", (3,),
                               what=f"3 finite numbers ({'N' if name == 'force' else 'N m'})")
            if not np.abs(v).max() <= LARGEST:
                validate.fail(f"disturbance {name}", f"entries within +-{LARGEST:g}",
                              v.tolist())
            object.__setattr__(self, name, tuple(v.tolist()))
        object.__setattr__(self, "duration",
                           validate.positive(self.duration, "disturbance duration", "s"))
        object.__setattr__(self, "t", validate.nonnegative(self.t, "disturbance t", "s"))


def wrench_table(disturbances: Any, t: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The summed wrench of all pulses active at given times.

    Parameters
    ----------
    disturbances : sequence of Disturbance or None
        The pulses (or what ``as_disturbances`` accepts).
    t : (N,) array_like
        Times (s).

    Returns
    -------
    (N, 6) numpy.ndarray
        Force (N, ground axes) and moment (N m, body axes).
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    w = np.zeros((t.size, 6))
    for d in as_disturbances(disturbances):
        on = (t >= d.t) & (t < d.t + d.duration)
        w[on] += np.concatenate([d.force, d.moment])
    return w


def as_disturbances(disturbances: Any) -> list[Disturbance]:
    """A list of Disturbance from what a user may write.

    Parameters
    ----------
    disturbances : sequence or None
        Disturbance objects, dicts of their fields or tuples (t, duration[, force[,
        moment]]); None for none.

    Returns
    -------
    list of Disturbance
        The checked pulses.

    Raises
    ------
    quadcog.InputError
        Naming the entry that is none of those.
    """
    if disturbances is None:
        return []
    if isinstance(disturbances, (Disturbance, dict, str, bytes)) or not hasattr(
            disturbances, "__iter__"):
        validate.fail("disturbances", "a list of Disturbance pulses", disturbances)
    out = []
    for i, d in enumerate(disturbances):
        if isinstance(d, Disturbance):
            out.append(d)
            continue
        try:
            if isinstance(d, dict):
                out.append(Disturbance(**d))
                continue
            if isinstance(d, (tuple, list)) and 2 <= len(d) <= 4:
                out.append(Disturbance(*d))
                continue
        except TypeError:           # unknown or missing fields
            pass
        validate.fail(f"disturbances[{i}]", "a Disturbance, a dict of its fields (t, duration, "
                      "force, moment) or a tuple (t, duration[, force[, moment]])", d)
    return out
