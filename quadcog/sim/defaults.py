"""The entries of ``quadcog.config.defaults`` that the simulation reads, each checked when it
is read: a caller may have set any value there (``defaults["metrics.tail_fraction"] = nan``
gave NaN metrics, ``"a"`` a raw TypeError, a deleted key a KeyError). A bad entry is an
InputError naming ``quadcog.config.defaults['key']``, the value and what was expected.
"""
import math
from typing import Any

from quadcog import config, validate
from quadcog.errors import InputError

__all__ = ["configured", "default_dt", "tail_fraction", "max_steps", "max_position_error",
           "max_tilt"]


def configured(key: str) -> Any:
    """``quadcog.config.defaults[key]`` as set, or InputError when the entry is missing.

    Parameters
    ----------
    key : str
        An entry of ``quadcog.config.defaults``.

    Returns
    -------
    object
        Its value, unchecked.

    Raises
    ------
    InputError
        The entry was deleted.
    """
    try:
        return config.defaults[key]
    except KeyError:
        raise InputError(f"quadcog.config.defaults[{key!r}]: expected an entry (it was "
                         "deleted; quadcog.config.reset_defaults() restores it), got none"
                         ) from None


def _where(key: str) -> str:
    return f"quadcog.config.defaults[{key!r}]"


def default_dt(dt: Any = None) -> Any:
    """``dt`` when given (its caller checks it), else the checked default step (s).

    Parameters
    ----------
    dt : object, optional
        The step the caller was given.

    Returns
    -------
    object
        ``dt``, or ``defaults["simulate.dt"]`` as a float > 0.

    Raises
    ------
    InputError
        The default is missing or not a finite number > 0.
    """
    if dt is not None:
        return dt
    return validate.positive(configured("simulate.dt"), _where("simulate.dt"), "s")


def tail_fraction(value: Any = None) -> float:
    """The fraction of a run its tail metrics cover, in (0, 1].

    Parameters
    ----------
    value : object, optional
        The fraction the caller was given (None: ``defaults["metrics.tail_fraction"]``).

    Returns
    -------
    float
        The fraction.

    Raises
    ------
    InputError
        It is not a number in (0, 1] (NaN gave NaN metrics, 2.5 a tail before the start).
    """
    where = "tail_fraction" if value is not None else _where("metrics.tail_fraction")
    value = configured("metrics.tail_fraction") if value is None else value
    return validate.real(value, where, lo=0.0, hi=1.0, lo_open=True)


def max_steps() -> int:
    """The most steps a run may take, ``defaults["simulate.max_steps"]``, a number >= 1.

    Returns
    -------
    int
        The limit, rounded down (NaN let every run through, "a" raised a raw TypeError).

    Raises
    ------
    InputError
        It is not a finite number >= 1.
    """
    return int(validate.real(configured("simulate.max_steps"), _where("simulate.max_steps"),
                             lo=1.0))


def max_position_error() -> float:
    """``defaults["limits.max_position_error"]`` (m), a finite number > 0.

    Returns
    -------
    float
        The limit.

    Raises
    ------
    InputError
        It is not a finite number > 0.
    """
    return validate.positive(configured("limits.max_position_error"),
                             _where("limits.max_position_error"), "m")


def max_tilt() -> float:
    """``defaults["limits.max_tilt_deg"]`` in radians; the entry a number in (0, 180] (deg).

    Returns
    -------
    float
        The limit (rad).

    Raises
    ------
    InputError
        It is not a number in (0, 180] (a str or None raised a raw TypeError).
    """
    return math.radians(validate.real(configured("limits.max_tilt_deg"),
                                      _where("limits.max_tilt_deg"), lo=0.0, hi=180.0,
                                      lo_open=True, unit="deg"))
