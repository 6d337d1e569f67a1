"""The one table of trajectory kinds by name, and their settings read from the constructors.

The scenario schema (``[trajectory] kind = ...``), ``--set trajectory.*``, sweep keys,
``quadcog.simulate(trajectory="circle")`` and the studies take the kinds from here.
"""
import inspect

from quadcog import validate
from quadcog.errors import InputError
from quadcog.kinds import Kind, settings_of
from quadcog.trajectories.aerobatic import BankedCircle, Flip
from quadcog.trajectories.analytic import Circle, Figure8, FromCallable, Helix, Hover, Trajectory
from quadcog.trajectories.waypoints import MinimumSnap

__all__ = ["TRAJECTORIES", "trajectory_kinds", "default_kinds", "trajectory_settings",
           "make_trajectory", "as_trajectory"]

TRAJECTORIES: dict[str, type[Trajectory]] = {
    "hover": Hover,
    "circle": Circle,
    "figure8": Figure8,
    "helix": Helix,
    "waypoints": MinimumSnap,
    "flip": Flip,
    "banked_circle": BankedCircle,
}


def trajectory_kinds() -> tuple[str, ...]:
    """The names of the trajectory kinds.

    Returns
    -------
    tuple of str
        In the order of ``TRAJECTORIES``.
    """
    return tuple(TRAJECTORIES)


def default_kinds() -> tuple[str, ...]:
    """The kinds that can be built from their name alone (every setting has a default).

    Returns
    -------
    tuple of str
        E.g. ('hover', 'circle', 'figure8', 'helix'); 'waypoints' needs its points.
    """
    return tuple(name for name, cls in TRAJECTORIES.items() if _all_defaults(cls))


_ALL_DEFAULTS: dict[type, bool] = {}


def _all_defaults(cls: type) -> bool:
    # a class's signature does not change; reading it costs more than sampling a hover
    if cls not in _ALL_DEFAULTS:
        _ALL_DEFAULTS[cls] = all(p.default is not inspect.Parameter.empty
                                 for p in inspect.signature(cls).parameters.values())
    return _ALL_DEFAULTS[cls]


def trajectory_settings(kind: str) -> dict[str, Kind]:
    """The settings of a trajectory kind, with the kind of value of each.

    Parameters
    ----------
    kind : str
        A name of ``TRAJECTORIES``.

    Returns
    -------
    dict of str to quadcog.kinds.Kind
        {setting: kind}, read from the constructor's annotations.

    Raises
    ------
    quadcog.InputError
        When ``kind`` is not a trajectory kind.
    """
    validate.choice(kind, "trajectory kind", trajectory_kinds())
    return settings_of(TRAJECTORIES[kind])


def make_trajectory(kind: str, **settings: object) -> Trajectory:
    """A trajectory by kind with keyword settings.

    Parameters
    ----------
    kind : str
        A name of ``TRAJECTORIES``.
    **settings
        The constructor's arguments (e.g. ``radius=1.0, period=10.0`` for a circle).

    Returns
    -------
    quadcog.Trajectory
        The reference, a callable of time (s) returning its 14-entry row.

    Raises
    ------
    quadcog.InputError
        An unknown kind or setting, or a setting the constructor refuses.
    """
    validate.choice(kind, "trajectory kind", trajectory_kinds())
    known = tuple(inspect.signature(TRAJECTORIES[kind]).parameters)
    unknown = sorted(set(settings) - set(known))
    if unknown:         # the constructor's TypeError named its own internals
        raise InputError(f"trajectory {kind!r}: expected settings among {', '.join(known)}, "
                         f"got unknown {', '.join(map(repr, unknown))}")
    return TRAJECTORIES[kind](**settings)


def as_trajectory(trajectory: "Trajectory | str | object") -> Trajectory:
    """A Trajectory from a Trajectory, a kind's name or a callable.

    Parameters
    ----------
    trajectory : Trajectory, str or callable
        A Trajectory (returned as is), the name of a kind that has defaults for every setting
        (``default_kinds()``), or a function of time (s) wrapped in ``FromCallable``.

    Returns
    -------
    quadcog.Trajectory
        The reference.

    Raises
    ------
    quadcog.InputError
        For anything else, or an unknown name.
    """
    if isinstance(trajectory, Trajectory):
        return trajectory
    if isinstance(trajectory, str):
        return TRAJECTORIES[validate.choice(trajectory, "trajectory", default_kinds())]()
    if callable(trajectory):
        return FromCallable(trajectory)
    validate.fail("trajectory", "a Trajectory, a name or a callable", trajectory)
    raise AssertionError("unreachable")         # validate.fail always raises
