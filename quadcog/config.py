"""Default values of the simulation, in one place (the style of python-control's
``control.config.defaults``).

Functions whose argument is left at ``None`` read the value here when they are called, so
changing an entry changes the default everywhere::

    import quadcog
    quadcog.config.defaults["simulate.dt"] = 5e-4
    quadcog.config.reset_defaults()

Keys:

- ``simulate.dt``: RK4 step (s) of ``simulate``, ``simulate_batch`` and scenario files.
- ``limits.max_position_error``: a run diverges when the position error exceeds this (m).
- ``limits.max_tilt_deg``: ... or when |phi| or |theta| exceeds this (deg).
- ``metrics.tail_fraction``: the tail metrics cover this last fraction of the run.
- ``simulate.max_steps``: runs of more steps (duration / dt) are refused before anything is
  allocated (``quadcog.validate.BYTES_PER_STEP`` per step; ``quadcog.validate.step_count``).
- ``progress.log_every``: on a log or a pipe (not a terminal), progress printers write a line
  every this many seconds (s): the progress bar and a sweep's flight counter.
"""
from typing import Any

from quadcog import validate
from quadcog.errors import InputError

__all__ = ["defaults", "reset_defaults", "get", "RANGES"]

_FACTORY: dict[str, Any] = {
    "simulate.dt": 1e-3,
    "limits.max_position_error": 10.0,
    "limits.max_tilt_deg": 85.0,
    "metrics.tail_fraction": 0.25,
    "simulate.max_steps": 10_000_000,
    # `quadcog run` writes trajectory.csv every this many seconds unless --every or --full-rate
    "run.sample_period": 0.01,
    "progress.log_every": 5.0,
}

defaults: dict[str, Any] = dict(_FACTORY)

# What each entry may be, checked where it is read (a caller may have set anything: a NaN
# tail fraction gave NaN metrics, "a" a raw TypeError): (lo, hi, lo_open, unit)
RANGES: dict[str, tuple[float, float | None, bool, str | None]] = {
    "simulate.dt": (0.0, None, True, "s"),
    "limits.max_position_error": (0.0, None, True, "m"),
    "limits.max_tilt_deg": (0.0, 180.0, True, "deg"),
    "metrics.tail_fraction": (0.0, 1.0, True, None),
    "simulate.max_steps": (1.0, None, False, None),
    "run.sample_period": (0.0, None, True, "s"),
    "progress.log_every": (0.0, None, True, "s"),
}


def reset_defaults() -> None:
    """Restore every entry of ``defaults`` to its value at import.

    Returns
    -------
    None
        ``defaults`` is changed in place (the same dict object).
    """
    defaults.clear()
    defaults.update(_FACTORY)


def get(key: str, value: Any = None) -> Any:
    """``value`` when it is given (not None), else ``defaults[key]``, checked.

    Parameters
    ----------
    key : str
        An entry of ``defaults``, e.g. ``"simulate.dt"``.
    value : object, optional
        The value the caller was given (its caller checks it); None means "use the default".

    Returns
    -------
    object
        ``value``, or ``defaults[key]`` when ``value`` is None (read now, at the call) as a
        float within ``RANGES[key]``.

    Raises
    ------
    InputError
        The entry was deleted, or is not a number within ``RANGES[key]``; the message names
        ``quadcog.config.defaults['key']``.
    """
    if value is not None:
        return value
    where = f"quadcog.config.defaults[{key!r}]"
    if key not in defaults:
        raise InputError(f"{where}: expected an entry (it was deleted; "
                         "quadcog.config.reset_defaults() restores it), got none")
    lo, hi, lo_open, unit = RANGES[key]
    return validate.real(defaults[key], where, lo=lo, hi=hi, lo_open=lo_open, unit=unit)
