"""What happens to the vehicle over time: the CoG profile r_G(t), the payloads carried (attach,
move, drop) and disturbance pulses."""
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.errors import InputError
from quadcog.model.inertial_parameters import N_PI
from quadcog.model.parameters import LARGEST
from quadcog.numerics import fill_rows
from quadcog.trajectories.analytic import sample_times
from quadcog.vehicles.payload import Payload, as_payload

__all__ = ["CogChange", "CogProfile", "Disturbance", "wrench_table", "as_disturbances",
           "PAYLOAD_ACTIONS", "PayloadEvent", "PayloadProfile"]


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

    Raises
    ------
    quadcog.InputError
        ``t`` or ``ramp`` not a number >= 0 (s), a ramp that ends past the float range, or
        ``r`` not 3 finite numbers (m).
    """
    t: float
    r: tuple
    ramp: float = 0.0

    def __post_init__(self) -> None:
        # checked here too, not only in CogProfile: CogChange(b"abc", "xyz") was kept as is
        t, r, ramp = _checked_change(self.t, self.r, self.ramp, "CogChange")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "r", r)
        object.__setattr__(self, "ramp", ramp)


def _checked_change(t: Any, r: Any, ramp: Any, where: str) -> tuple[float, tuple, float]:
    """(t, r, ramp) of a CoG change checked: t, ramp >= 0 (s) ending at a finite time, r 3
    finite numbers (m); errors name ``where``."""
    r = tuple(validate.array(r, f"{where}: r", (3,), what="3 finite numbers (m)").tolist())
    t = validate.nonnegative(t, f"{where}: t", "s")
    ramp = validate.nonnegative(ramp, f"{where}: ramp", "s")
    if not np.isfinite(t + ramp):
        validate.fail(f"{where}: ramp", f"a ramp that ends at a finite time (t = {t:g} s)", ramp)
    return t, r, ramp


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
        A change that is not one of those, changes out of time order, a ramp that ends past
        the float range, or a step at the instant of the previous step (which is then never
        held).
    """
    changes: list = field(default_factory=list)

    def __post_init__(self) -> None:
        clean: list[CogChange] = []
        last = -np.inf
        if isinstance(self.changes, (str, bytes, dict, np.ndarray)) or not hasattr(
                self.changes, "__iter__"):
            validate.fail("cog", "a CogProfile or a list of changes (t, r[, ramp])", self.changes)
        for i, c in enumerate(self.changes):
            where = f"cog change {i}"
            if not isinstance(c, CogChange):     # checked under this change's name
                if isinstance(c, (tuple, list)) and 2 <= len(c) <= 3:
                    fields = (*c, 0.0)[:3]
                elif isinstance(c, dict) and {"t", "r"} <= set(c) <= {"t", "r", "ramp"}:
                    fields = (c["t"], c["r"], c.get("ramp", 0.0))
                elif isinstance(c, dict):
                    validate.fail(where, "a table with keys t, r and ramp", c)
                else:
                    validate.fail(where, "a CogChange or a tuple (t, r[, ramp])", c)
                c = CogChange(*_checked_change(fields[0], fields[1], fields[2], where))
            if c.t < last:
                raise InputError(f"cog change {i}: t = {c.t} s comes before the previous "
                                 f"change's end ({last} s); expected changes in time order")
            if clean and c.ramp == 0 and clean[-1].ramp == 0 and c.t == clean[-1].t:
                raise InputError(f"cog change {i}: t = {c.t:g} s is the time of the step of "
                                 f"change {i - 1} to r = {list(clean[-1].r)} m, which is then "
                                 f"never held (this step replaces it at once); expected t after "
                                 f"{c.t:g} s, or a ramp")
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

        Raises
        ------
        quadcog.InputError
            ``t`` not a number >= 0 (s) or ``r`` not 3 finite numbers (m).
        """
        # checked by the profile, as any change (tuple(r) of a number was a raw TypeError)
        return cls([CogChange(t, cast(tuple, r), 0.0)])

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

        Raises
        ------
        quadcog.InputError
            A time that is not a finite real number (``sample_times``).
        """
        t = sample_times(t)
        r = np.zeros((t.size, 3))
        if t.size < 2 or (np.diff(t) >= 0).all():
            return self._sampled_in_order(t, r)
        prev = np.zeros(3)
        for c in self.changes:
            target = np.array(c.r)
            active = _suffix(t >= c.t)
            if c.ramp > 0:
                s = np.clip((t[active] - c.t) / c.ramp, 0.0, 1.0)
                r[active] = prev + s[:, None] * (target - prev)
            elif isinstance(active, slice):     # s = 1 on every active row: one row, the same bits
                fill_rows(r[active], prev + 1.0 * (target - prev))
            else:
                r[active] = prev + 1.0 * (target - prev)
            prev = target
        return r


    def _sampled_in_order(self, t: npt.NDArray[np.float64],
                          r: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """``sample`` at times in order: each change writes only the samples up to the next
        change's start (the next one writes the rest), the same numbers as writing every
        sample from its start on, in time linear in the changes and the samples (that cost
        changes x samples)."""
        starts = np.searchsorted(t, [c.t for c in self.changes], side="left").tolist()
        prev = np.zeros(3)
        for i, c in enumerate(self.changes):
            target = np.array(c.r)
            a, b = starts[i], (starts[i + 1] if i + 1 < len(starts) else t.size)
            if b > a and c.ramp > 0:
                s = np.clip((t[a:b] - c.t) / c.ramp, 0.0, 1.0)
                r[a:b] = prev + s[:, None] * (target - prev)
            elif b > a:
                fill_rows(r[a:b], prev + 1.0 * (target - prev))
            prev = target
        return r


def _suffix(mask: npt.NDArray[np.bool_]) -> slice | npt.NDArray[np.bool_]:
    """``mask`` as the slice of its rows where it is a run to the end (times in order: a
    slice assigns rows many times faster than a mask), else ``mask``."""
    first = int(np.argmax(mask)) if mask.size else 0
    if mask.size and mask[first] and mask[first:].all():
        return slice(first, None)
    return mask if mask.any() else slice(0, 0)


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

    Raises
    ------
    quadcog.InputError
        A pulse that is none (``as_disturbances``) or a time that is not a finite real
        number (``sample_times``).
    """
    t = sample_times(t)
    pulses = as_disturbances(disturbances)
    w = np.zeros((t.size, 6))
    if t.size > 1 and not (np.diff(t) >= 0).all():     # times in any order: pulse by pulse
        for d in pulses:
            on = (t >= d.t) & (t < d.t + d.duration)
            w[on] += np.concatenate([d.force, d.moment])
        return w
    # times in order (a run's grid): the table is constant between the samples where a pulse
    # starts or ends, so each stretch is filled once with the sum of the pulses on in it, in
    # their order (the bits of adding them pulse by pulse). The cost is linear in the pulses
    # and the samples; a mask per pulse over every sample cost pulses x samples.
    first = np.searchsorted(t, [d.t for d in pulses], side="left")       # first t >= start
    stop = np.searchsorted(t, [d.t + d.duration for d in pulses], side="left")
    edges: dict[int, list[tuple[int, int]]] = {}
    for i, (a, b) in enumerate(zip(first.tolist(), stop.tolist())):
        if a < b:
            edges.setdefault(a, []).append((1, i))
            edges.setdefault(b, []).append((-1, i))
    active: set[int] = set()
    marks = sorted(edges)
    for k, mark in enumerate(marks):
        for sign, i in edges[mark]:
            (active.add if sign > 0 else active.discard)(i)
        if active and k + 1 < len(marks):
            total = np.zeros(6)
            for i in sorted(active):
                total += np.concatenate([pulses[i].force, pulses[i].moment])
            fill_rows(w[mark:marks[k + 1]], total)
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
    if isinstance(disturbances, (Disturbance, dict, str, bytes, np.ndarray)) or not hasattr(
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


PAYLOAD_ACTIONS = ("attach", "move", "drop")


@dataclass(frozen=True)
class PayloadEvent:
    """At time ``t`` a payload is attached, moved (over ``ramp``) or dropped.

    Parameters
    ----------
    t : float
        When (s), >= 0.
    action : str
        ``"attach"`` (needs ``mass`` and ``position``; ``size`` optional), ``"move"`` (needs
        ``position``; slides there linearly over ``ramp``) or ``"drop"``.
    name : str
        Which payload (attach names it; move and drop refer to it; a vehicle's own payloads
        count).
    mass : float, optional
        Its mass (kg), attach only.
    position : (3,) sequence of float, optional
        Its centre from O in body axes (m): where it is attached or moved to.
    size : (3,) sequence of float, optional
        Box edges (m), attach only; default a point mass.
    ramp : float
        Duration of a move (s; 0: a step). Attach and drop are instants.

    Raises
    ------
    quadcog.InputError
        A field missing, not allowed for the action, or of the wrong type; a name that is not
        a non-empty string; a move whose ramp ends past the float range.
    """
    t: float
    action: str
    name: str = "payload"
    mass: float | None = None
    position: tuple | None = None
    size: tuple | None = None
    ramp: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            validate.fail("payload event: name", "a non-empty string (the payload's name)",
                          self.name)
        where = f"payload event {self.name!r}"
        object.__setattr__(self, "t", validate.nonnegative(self.t, f"{where}: t", "s"))
        validate.choice(self.action, f"{where}: action", PAYLOAD_ACTIONS)
        object.__setattr__(self, "ramp", validate.nonnegative(self.ramp, f"{where}: ramp", "s"))
        if not np.isfinite(self.t + self.ramp):
            validate.fail(f"{where}: ramp", f"a ramp that ends at a finite time (t = "
                          f"{self.t:g} s)", self.ramp)
        needs = {"attach": ("mass", "position"), "move": ("position",), "drop": ()}[self.action]
        allowed = {"attach": ("mass", "position", "size"), "move": ("position",),
                   "drop": ()}[self.action]
        for key in ("mass", "position", "size"):
            given = getattr(self, key) is not None
            if key in needs and not given:
                raise InputError(f"{where}: {self.action} needs {key!r}")
            if given and key not in allowed:
                raise InputError(f"{where}: {key!r} is not a setting of {self.action!r} "
                                 f"(expected only {', '.join(map(repr, allowed)) or 'name and t'})")
        if self.ramp > 0 and self.action != "move":
            raise InputError(f"{where}: ramp = {self.ramp} s: only a move has a ramp ({self.action} "
                             "is an instant)")
        if self.position is not None:
            r = validate.array(self.position, f"{where}: position", (3,),
                               what="3 finite numbers (m, body axes)")
            object.__setattr__(self, "position", tuple(r.tolist()))
        if self.action == "attach":
            # the Payload checks mass, position and size once
            object.__setattr__(self, "size", self.payload().size)

    def payload(self) -> Payload:
        """The payload an attach puts on.

        Returns
        -------
        Payload
            Its mass, position, size and name.

        Raises
        ------
        quadcog.InputError
            For a move or a drop, which carry no payload.
        """
        if self.action != "attach":
            raise InputError(f"payload event {self.name!r}: a {self.action} carries no payload")
        return Payload(self.mass, self.position,     # type: ignore[arg-type]
                       self.size if self.size is not None else (0.0, 0.0, 0.0), self.name)


def _as_event(e: Any, where: str) -> PayloadEvent:
    if isinstance(e, PayloadEvent):
        return e
    if isinstance(e, dict):
        try:
            return PayloadEvent(**e)
        except TypeError:
            keys = ("t", "action", "name", "mass", "position", "size", "ramp")
            unknown = sorted(set(e) - set(keys))
            raise InputError(f"{where}: expected a table with keys t, action and name (and "
                             f"mass, position, size, ramp by action), got keys {sorted(e)}"
                             + (f"; unknown: {unknown}" if unknown else "")) from None
    validate.fail(where, "a PayloadEvent or a table with keys t, action, name[, mass, position, "
                  "size, ramp]", e)


@dataclass
class PayloadProfile:
    """The payloads carried over time: attach, move and drop events in time order.

    ``sample`` gives the summed inertial parameters about O of every payload on board at each
    time; the truth model adds them to the airframe's (``quadcog.sim.plant``).

    Parameters
    ----------
    events : sequence of PayloadEvent
        In time order; dicts of the fields are accepted.
    carried : sequence of Payload
        Payloads on board at t = 0 (a vehicle's own, ``Vehicle.payloads``); tables of their
        fields are accepted (``quadcog.vehicles.payload.as_payload``).

    Raises
    ------
    quadcog.InputError
        ``carried`` not a list of payloads of different names, an event out of time order,
        an attach of a name already on board, a move or drop of a name not on board, an
        event that starts inside another's ramp of the same payload, or a drop or instant move
        at the instant the payload was attached or moved (which is then never held).
    """
    events: list = field(default_factory=list)
    carried: tuple = ()

    def __post_init__(self) -> None:
        if isinstance(self.events, (str, bytes, dict, np.ndarray)) or not hasattr(
                self.events, "__iter__"):
            validate.fail("payload", "a list of payload events (attach, move, drop)", self.events)
        if not isinstance(self.carried, (list, tuple)):
            validate.fail("carried", "a list of the Payloads on board at t = 0", self.carried)
        self.carried = tuple(as_payload(p, f"carried[{i}]") for i, p in enumerate(self.carried))
        on_board = {p.name for p in self.carried}
        if len(on_board) < len(self.carried):
            names = [p.name for p in self.carried]
            validate.fail("carried", "payloads of different names", names)
        clean: list[PayloadEvent] = []
        last, busy = -np.inf, dict[str, float]()
        placed: dict[str, PayloadEvent] = {}    # a payload's last instant attach or move
        for i, e in enumerate(self.events):
            e = _as_event(e, f"payload[{i}]")
            where = f"payload[{i}] ({e.action} {e.name!r} at t = {e.t:g} s)"
            if e.t < last:
                raise InputError(f"{where}: comes before the previous event (t = {last:g} s); "
                                 "expected events in time order")
            if e.t < busy.get(e.name, -np.inf):
                raise InputError(f"{where}: starts while its previous move still slides (until "
                                 f"t = {busy[e.name]:g} s)")
            before = placed.get(e.name)
            if before is not None and before.t == e.t and e.action in ("drop", "move") and \
                    e.ramp == 0:
                # what happened to it at this instant is undone at once: never held
                if before.action == "attach" and e.action == "drop":
                    raise InputError(f"{where}: at the time {e.name!r} is attached, so it is "
                                     "never carried (the drop undoes the attach at once); "
                                     f"expected t after the attach at {e.t:g} s")
                raise InputError(f"{where}: at the time {e.name!r} is "
                                 f"{'attached at' if before.action == 'attach' else 'moved to'} "
                                 f"{list(before.position or ())} m, which is then never held "
                                 f"(this {e.action} replaces it at once); expected t after "
                                 f"{e.t:g} s, or a move with a ramp")
            if e.action == "drop" or e.ramp > 0:
                placed.pop(e.name, None)
            else:
                placed[e.name] = e
            if e.action == "attach" and e.name in on_board:
                raise InputError(f"{where}: a payload named {e.name!r} is already on board; "
                                 "expected a new name (or move it)")
            if e.action != "attach" and e.name not in on_board:
                raise InputError(f"{where}: no payload named {e.name!r} is on board then "
                                 f"(on board: {sorted(on_board) or 'none'})")
            if e.action == "attach":
                on_board.add(e.name)
            elif e.action == "drop":
                on_board.discard(e.name)
            busy[e.name] = e.t + e.ramp
            last = e.t
            clean.append(e)
        self.events = clean

    def __bool__(self) -> bool:
        return bool(self.events or self.carried)

    def on_board(self, t: float) -> list[Payload]:
        """The payloads on board at time t, where they are then.

        Parameters
        ----------
        t : float
            Time (s).

        Returns
        -------
        list of Payload
            In the order they came on board.

        Raises
        ------
        quadcog.InputError
            ``t`` is not a finite real number.
        """
        when = validate.real(t, "t", unit="s")
        return [p.moved(r[0]) for p, r, on in self._tracks(np.array([when])) if on[0]]

    def _tracks(self, t: np.ndarray) -> list[tuple[Payload, np.ndarray, np.ndarray]]:
        """(payload, its centre at each t (N, 3), on board at each t (N,)) per payload life."""
        # [payload, positions, on board, where its last attach or move put it]; a move
        # starts from there (no event starts inside the same payload's previous move), not
        # from a sample: the times may be in any order, or one (on_board), and a move started
        # from the attach position or a mid-ramp sample
        tracks: list[list[Any]] = []
        alive: dict[str, list[Any]] = {}
        for p in self.carried:
            alive[p.name] = [p, np.repeat(np.array([p.position]), t.size, 0),
                             np.ones(t.size, bool), np.array(p.position)]
            tracks.append(alive[p.name])
        for e in self.events:
            after = t >= e.t
            if e.action == "attach":
                p = e.payload()
                alive[e.name] = [p, np.repeat(np.array([p.position]), t.size, 0), after.copy(),
                                 np.array(p.position)]
                tracks.append(alive[e.name])
            elif e.action == "drop":
                alive.pop(e.name)[2] &= ~after
            else:
                track = alive[e.name]
                start, end = track[3], np.array(e.position)
                s = (np.clip((t - e.t) / e.ramp, 0.0, 1.0) if e.ramp > 0
                     else after.astype(float))
                moved = start + s[:, None] * (end - start)
                track[1] = np.where(after[:, None], moved, track[1])
                track[3] = end
        return [(p, r, on) for p, r, on, _ in tracks]

    def sample(self, t: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The summed inertial parameters of the payloads on board at given times.

        Parameters
        ----------
        t : (N,) array_like
            Times (s), increasing.

        Returns
        -------
        (N, 10) numpy.ndarray
            pi about O (``quadcog.model.inertial_parameters.PI_NAMES`` order; kg, kg m,
            kg m^2); zeros where nothing is on board.

        Raises
        ------
        quadcog.InputError
            A time that is not a finite real number (``sample_times``).
        """
        t = sample_times(t)
        if t.size > 1 and not (np.diff(t) >= 0).all():
            return self._sampled_by_tracks(t)
        # one pass over the events: each adds the change of pi from its first sample on (a
        # running sum), a sliding move also its in-between positions over its ramp; the cost
        # is linear in the events and the samples (the tracks were payloads x samples)
        step = np.zeros((t.size + 1, N_PI))
        out = np.zeros((t.size, N_PI))
        where: dict[str, tuple[Payload, tuple]] = {}

        def pi_at(payload, position):
            return payload.inertial_parameters(np.array([position], dtype=float))[0]

        for p in self.carried:
            step[0] += pi_at(p, p.position)
            where[p.name] = (p, p.position)
        for e in self.events:
            k = int(np.searchsorted(t, e.t, side="left"))       # the first sample at t >= e.t
            if e.action == "attach":
                p = e.payload()
                step[k] += pi_at(p, p.position)
                where[e.name] = (p, p.position)
            elif e.action == "drop":
                p, at = where.pop(e.name)
                step[k] -= pi_at(p, at)
            else:
                p, start = where[e.name]
                end = int(np.searchsorted(t, e.t + e.ramp, side="left")) if e.ramp > 0 else k
                if end > k:
                    s = (t[k:end] - e.t) / e.ramp
                    r = np.asarray(start) + s[:, None] * (np.asarray(e.position) - start)
                    out[k:end] += p.inertial_parameters(r) - pi_at(p, start)
                step[end] += pi_at(p, e.position) - pi_at(p, start)
                where[e.name] = (p, e.position)
        return out + np.cumsum(step[:-1], axis=0)

    def _sampled_by_tracks(self, t: np.ndarray) -> npt.NDArray[np.float64]:
        """``sample`` at times in any order, track by track (payloads x samples)."""
        out = np.zeros((t.size, N_PI))
        for p, r, on in self._tracks(t):
            out[on] += p.inertial_parameters(r[on])
        return out

    def times(self) -> list[float]:
        """The times at which what is on board changes: each event's start and a move's end.

        Returns
        -------
        list of float
            Sorted, unique (s).
        """
        return sorted({e.t for e in self.events} | {e.t + e.ramp for e in self.events})
