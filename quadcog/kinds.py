"""The kinds of value a setting takes, as type aliases that carry their check.

A controller's or a trajectory's constructor annotates each setting with one of these aliases
(``poles_z: Poles``); the alias is an ordinary type for a reader and a type checker, and its
``Kind`` tells the scenario schema how to check the value in a file. So the names and kinds of
the settings are written once, in the constructors' signatures, and the scenario schema,
``--set``, sweep keys and the studies read them from there (``quadcog.controllers.registry``,
``quadcog.trajectories.registry``).
"""
from collections.abc import Sequence
import enum
import functools
import typing
from typing import Annotated, Any

__all__ = ["Kind", "Number", "Flag", "Vec3", "Poles", "Vector", "Points", "Pairs4",
           "NumberOrVec3", "NumberOrNone", "kind_of", "settings_of"]


class Kind(enum.Enum):
    """How a setting is checked when it comes from a file (TOML) or ``--set``."""

    NUMBER = "a number"
    FLAG = "true or false"
    STRING = "a string"
    VEC3 = "an array of 3 numbers"
    VECTOR = "a non-empty array of numbers"
    POINTS = "an array of at least 2 arrays [x, y, z] of numbers"
    PAIRS4 = "an array of 4 arrays [x, y] of numbers"
    NUMBER_OR_VEC3 = "a number or an array of 3 numbers"
    NUMBER_OR_FALSE = "a number, or false for none"


Number = Annotated[float, Kind.NUMBER]
Flag = Annotated[bool, Kind.FLAG]
Vec3 = Annotated[Sequence[float], Kind.VEC3]
Poles = Annotated[Sequence[float], Kind.VECTOR]        # closed-loop poles, 1/s (negative)
Vector = Annotated[Sequence[float], Kind.VECTOR]
Points = Annotated[Sequence[Sequence[float]], Kind.POINTS]
Pairs4 = Annotated[Sequence[Sequence[float]], Kind.PAIRS4]
NumberOrVec3 = Annotated[float | Sequence[float], Kind.NUMBER_OR_VEC3]
# a number, or None (written ``false`` in a file): e.g. a projection radius that can be off
NumberOrNone = Annotated[float | str | None, Kind.NUMBER_OR_FALSE]


def kind_of(annotation: Any) -> Kind | None:
    """The ``Kind`` an annotation carries.

    Parameters
    ----------
    annotation : Any
        A type annotation, e.g. ``quadcog.kinds.Poles`` or ``Poles | None``.

    Returns
    -------
    Kind or None
        The kind of its ``Annotated`` metadata (also inside ``X | None``), or None when the
        annotation carries none (the setting is then not available from files).
    """
    if typing.get_origin(annotation) is Annotated:
        for meta in annotation.__metadata__:
            if isinstance(meta, Kind):
                return meta
    for arg in typing.get_args(annotation):
        kind = kind_of(arg)
        if kind is not None:
            return kind
    return None


def settings_of(owner: type, skip: Sequence[str] = ()) -> dict[str, Kind]:
    """The settings of ``owner``'s constructor that carry a ``Kind``, along its MRO.

    Parameters
    ----------
    owner : type
        A class whose ``__init__`` (or dataclass fields) annotate its settings.
    skip : sequence of str
        Parameter names to leave out.

    Returns
    -------
    dict of str to Kind
        {name: kind} in signature order, the subclass's own settings first.
    """
    return dict(_settings(owner, tuple(skip)))


# a class's annotations do not change: read them once (a sweep validates thousands of
# scenarios, and get_type_hints is most of that time)
@functools.lru_cache(maxsize=None)
def _settings(owner: type, skip: tuple[str, ...]) -> dict[str, Kind]:
    out: dict[str, Kind] = {}
    for klass in owner.__mro__:
        init = klass.__dict__.get("__init__")
        if init is None:
            continue
        hints = typing.get_type_hints(init, include_extras=True)
        for name, annotation in hints.items():
            kind = kind_of(annotation)
            if name != "return" and name not in skip and kind is not None:
                out.setdefault(name, kind)
    return out
