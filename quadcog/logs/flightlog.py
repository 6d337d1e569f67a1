"""``FlightLog``: one flight's signals on one time base, as every reader of quadcog.logs
returns them, checked once here (shapes, finite values, strictly increasing time)."""
from collections.abc import Mapping
from dataclasses import dataclass
import os
from types import MappingProxyType

import numpy as np

from quadcog.errors import InputError, LogFormatError, LogSignalError
from quadcog.logs.signals import LOG_FORMATS, SIGNALS
from quadcog.validate import array, fail, plain

__all__ = ["FlightLog"]


# what a log's time and values must be (validate.array adds "of real numbers, not ...")
_NUMERIC = "a numeric array"


def _frozen(value, where):
    """``value`` as a new read-only float64 array of real numbers (``validate.array``:
    strings, bools, complex numbers, dates, objects, masked entries and integers beyond the
    float range refused, naming ``where``); not yet checked to be finite."""
    a = array(value, where, finite=False, what=_NUMERIC, error=LogFormatError)
    a.setflags(write=False)           # a copy: the log owns its arrays
    return a


def _signal_name(name, where):
    """``name`` if it is a string (a signal name), else a LogSignalError."""
    if not isinstance(name, str):
        raise LogSignalError(f"{where}: expected a signal name (a str, one of "
                             f"{', '.join(SIGNALS)}), got {plain(name)}", signal=None)
    return name


def _first_bad(a):
    """Index (sample, ...) of the first non-finite entry of ``a``."""
    return tuple(int(i) for i in np.argwhere(~np.isfinite(a))[0])


@dataclass(frozen=True)
class FlightLog:
    """One flight log: standard signals (``SIGNALS``) in SI units and quadcog's frames, and
    every logged variable under its source name, all on one time base.

    Arrays are float64 copies and read-only; ``signals``, ``raw`` and ``meta`` are read-only
    mappings.

    Parameters
    ----------
    source : str or os.PathLike
        The file (or a name) the log came from; used in messages (kept as a str).
    format : str
        One of ``LOG_FORMATS``.
    t : array_like, (N,)
        Time (s) from the log's first sample (a ``window`` keeps its parent's origin);
        finite and strictly increasing, N >= 2.
    signals : mapping of str to array_like
        Standard signals on ``t``: keys of ``SIGNALS``, each of shape (N,) + its
        ``SIGNALS[name].shape``, finite.
    raw : mapping of str to array_like
        Every logged variable under its source name, in source units, on ``t``, each (N,).
    meta : mapping of str to str
        What the log says about itself (vehicle, firmware, time base, ...).

    Returns
    -------
    FlightLog

    Raises
    ------
    LogFormatError
        Time, a signal or a raw variable that is not real numbers (text, bools, complex
        numbers, dates, masked entries), of the wrong shape, with a non-finite entry (named
        with its sample); ``t`` not strictly increasing or spanning more than a float holds;
        ``InputError`` for an unknown format or signal name, a source that is not a str or
        os.PathLike, a raw or meta key that is not a str.
    """
    source: str
    format: str
    t: np.ndarray
    signals: Mapping[str, np.ndarray]
    raw: Mapping[str, np.ndarray]
    meta: Mapping[str, str]

    def __post_init__(self):
        source = self.source
        if isinstance(source, bytes) or not isinstance(source, (str, os.PathLike)) or \
                not isinstance(os.fspath(source), str):
            fail("FlightLog: source", "the log's file or name (a str or os.PathLike)", source)
        src = os.fspath(source)
        object.__setattr__(self, "source", src)
        if not isinstance(self.format, str) or self.format not in LOG_FORMATS:
            raise InputError(f"{src}: format {self.format!r} is not one of {LOG_FORMATS}")
        t = _frozen(self.t, f"{src}: time")
        if t.ndim != 1 or t.size < 2:
            raise LogFormatError(f"{src}: time must be (N,) with N >= 2 samples, got shape "
                                 f"{t.shape}")
        if not np.isfinite(t).all():
            raise LogFormatError(f"{src}: time is not finite at sample {_first_bad(t)[0]}")
        with np.errstate(over="ignore"):        # said below, in the log's terms
            steps = np.diff(t)
        if not np.isfinite(steps).all():
            raise LogFormatError(f"{src}: time runs from {float(t[0])!r} s to "
                                 f"{float(t[-1])!r} s, a span beyond the range of a float; "
                                 "expected the times of one flight (s)")
        if not (steps > 0).all():
            i = int(np.argmax(steps <= 0))
            raise LogFormatError(f"{src}: time is not strictly increasing: sample {i + 1} at "
                                 f"{float(t[i + 1])!r} s follows {float(t[i])!r} s")
        object.__setattr__(self, "t", t)
        for field in ("signals", "raw", "meta"):
            if not isinstance(getattr(self, field), Mapping):
                raise InputError(f"{src}: {field} must be a mapping of names to values, got "
                                 f"{type(getattr(self, field)).__name__}")
        n = t.size
        signals = {}
        for name, value in dict(self.signals).items():
            if name not in SIGNALS:
                raise InputError(f"{src}: {name!r} is not a standard signal; expected one of "
                                 f"{tuple(SIGNALS)}")
            a = self._array(value, f"signal {name!r}", (n,) + SIGNALS[name].shape)
            signals[name] = a
        for field in ("raw", "meta"):       # names: two keys must not become one name
            for k in getattr(self, field):
                if not isinstance(k, str):
                    fail(f"{src}: {field} key", "a name (a str)", k)
        raw = {str(k): self._array(v, f"variable {k!r}", (n,)) for k, v in dict(self.raw).items()}
        object.__setattr__(self, "signals", MappingProxyType(signals))
        object.__setattr__(self, "raw", MappingProxyType(raw))
        object.__setattr__(self, "meta", MappingProxyType({str(k): str(v) for k, v in
                                                           dict(self.meta).items()}))

    def _array(self, value, what, shape):
        a = _frozen(value, f"{self.source}: {what}")
        if a.shape != shape:
            raise LogFormatError(f"{self.source}: {what} has shape {a.shape}, expected {shape} "
                                 "(one row per sample of t)")
        if not np.isfinite(a).all():
            i = _first_bad(a)
            raise LogFormatError(f"{self.source}: {what} is {float(a[i])!r} at sample {i[0]} "
                                 f"(t = {float(self.t[i[0]])!r} s); expected finite values")
        return a

    @property
    def n_samples(self) -> int:
        """Number of samples N (int)."""
        return int(self.t.size)

    def has(self, name: str) -> bool:
        """Whether the log carries the standard signal ``name``.

        Parameters
        ----------
        name : str
            A key of ``SIGNALS``.

        Returns
        -------
        bool
            True when ``signals`` holds it.

        Raises
        ------
        LogSignalError
            ``name`` is not a string.
        """
        return _signal_name(name, "FlightLog.has") in self.signals

    def signal(self, name: str) -> np.ndarray:
        """The standard signal ``name`` (read-only float64 array on ``t``).

        Parameters
        ----------
        name : str
            A key of ``SIGNALS``.

        Returns
        -------
        numpy.ndarray
            Shape (N,) + ``SIGNALS[name].shape``, in ``SIGNALS[name].unit``.

        Raises
        ------
        LogSignalError
            The log lacks the signal (or it is not a standard signal); the message names the
            signal, the log and the signals it has.
        """
        if _signal_name(name, "FlightLog.signal") in self.signals:
            return self.signals[name]
        has = tuple(self.signals)
        what = ("is not a standard signal (quadcog.logs.SIGNALS: "
                f"{', '.join(SIGNALS)})" if name not in SIGNALS else "is not in this log")
        dropped = self.meta.get("signals_dropped", "")
        if name and name in dropped.replace(",", " ").split():
            what += f" (the reader left out {self.meta['signals_dropped']})"
        raise LogSignalError(
            f"signal {name!r} {what}: {self.format} log {self.source} has "
            f"{', '.join(has) if has else 'no standard signals'}"
            + (f" (and the raw variables {', '.join(list(self.raw)[:30])}"
               f"{', ...' if len(self.raw) > 30 else ''})" if self.raw else ""),
            signal=name, source=self.source, available=has)

    def window(self, t0: float, t1: float) -> "FlightLog":
        """The samples with ``t0 <= t <= t1``, as a new log (times keep this log's origin).

        Parameters
        ----------
        t0 : float
            Start and end (s), on this log's ``t``; ``t0 < t1``.
        t1 : float
            Start and end (s), on this log's ``t``; ``t0 < t1``.

        Returns
        -------
        FlightLog
            Same source, format and meta (``meta["window"]`` added).

        Raises
        ------
        InputError
            ``t0``, ``t1`` not finite numbers, ``t0 >= t1``, or fewer than 2 samples in the
            window (the message gives the log's time span).
        """
        from quadcog.validate import real
        t0 = real(t0, "window t0 (s)")
        t1 = real(t1, "window t1 (s)")
        keep = (self.t >= t0) & (self.t <= t1)
        if not t0 < t1 or keep.sum() < 2:
            raise InputError(
                f"{self.source}: window [{t0!r}, {t1!r}] s holds {int(keep.sum())} samples; "
                f"expected t0 < t1 and at least 2 samples of the log's "
                f"[{float(self.t[0])!r}, {float(self.t[-1])!r}] s")
        meta = dict(self.meta, window=f"{t0!r} {t1!r}")
        return FlightLog(self.source, self.format, self.t[keep],
                         {k: v[keep] for k, v in self.signals.items()},
                         {k: v[keep] for k, v in self.raw.items()}, meta)
