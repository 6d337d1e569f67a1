"""What the binary log formats can hold, checked by their writers before a byte is written,
so that a writer never writes what its own reader (or the format) refuses: time stamps are
integer microseconds in a ``uint64`` (Crazyflie uSD version 2, ULog), values are float32
(finite, at most ``FLOAT32_MAX`` in magnitude: beyond it float32 is infinite), motor outputs
are 0..1 of full scale (the Crazyflie's integer fields hold no more; the ULog reader clips
a PWM outside its range, so a written 1.5 would read back as 1)."""
import numpy as np
import numpy.typing as npt

from quadcog.errors import LogSignalError
from quadcog.logs.flightlog import FlightLog

__all__ = ["FLOAT32_MAX", "TICKS_MAX", "EXACT_US", "UNIT_SIGNALS", "microsecond_ticks", "check_range",
           "check_unit_signals"]

FLOAT32_MAX = float(np.finfo(np.float32).max)
TICKS_MAX = 2 ** 64 - 1                         # a uint64 time stamp (us)
UNIT_SIGNALS = ("motor_command", "motor_pwm")   # 0..1 of full scale in every format


EXACT_US = float(2 ** 53)       # us: float64 holds every whole number of us below this


def microsecond_ticks(log: FlightLog, start_us: int, fmt: str) -> npt.NDArray[np.uint64]:
    """The log's times as integer microseconds from ``start_us``, refused when a stamp does
    not fit a uint64 or two samples fall on the same microsecond.

    Parameters
    ----------
    log : FlightLog
        The log to write.
    start_us : int
        The stamp of t = 0 (us).
    fmt : str
        The format's name, for the message.

    Returns
    -------
    numpy.ndarray of uint64, shape (N,)
        The stamps.

    Raises
    ------
    LogSignalError
        A stamp beyond a uint64, a time before the first stamp (negative), a time beyond
        ``EXACT_US`` (float64 would round its stamp: the steps would change), or samples
        closer than 1 us.
    """
    last = float(log.t[-1]) * 1e6 + start_us
    if not last < TICKS_MAX:
        raise LogSignalError(f"{log.source}: time t = {float(log.t[-1])!r} s is {last:.3g} us, "
                             f"past the largest {fmt} time stamp (a uint64 of us: "
                             f"{TICKS_MAX / 1e6:.3g} s); cannot write it", source=log.source)
    first = float(log.t[0]) * 1e6 + start_us
    if not first >= 0:
        raise LogSignalError(f"{log.source}: time t = {float(log.t[0])!r} s is before the "
                             f"first {fmt} time stamp (an unsigned count of us from "
                             f"{start_us / 1e6:g} s); cannot write it: shift the log's time "
                             "(t - t[0])", source=log.source)
    if not last < EXACT_US:
        raise LogSignalError(f"{log.source}: time t = {float(log.t[-1])!r} s is {last:.3g} us, "
                             f"beyond the {EXACT_US:.3g} us that a float64 time holds to the "
                             f"microsecond; the {fmt} stamps would be rounded (steps changed): "
                             "shift the log's time (t - t[0])", source=log.source)
    ticks = np.round(log.t * 1e6)
    if not (np.diff(ticks) > 0).all():
        raise LogSignalError(f"{log.source}: samples closer than 1 us cannot be written as "
                             f"{fmt} time stamps (integer us)", source=log.source)
    return ticks.astype(np.uint64) + np.uint64(start_us)


def check_range(log: FlightLog, name: str, values: npt.ArrayLike, fmt: str,
                lo: float = -FLOAT32_MAX, hi: float = FLOAT32_MAX, why: str = "float32") -> None:
    """Refuse values that ``fmt`` cannot hold.

    Parameters
    ----------
    log : FlightLog
        The log (its source is named).
    name : str
        The variable or signal, for the message.
    values : array_like
        What would be written.
    fmt : str
        The format's name.
    lo : float
        The lowest value the range holds (default: float32's).
    hi : float
        The highest value the range holds (default: float32's).
    why : str
        What the range is (``"float32"``, ``"0..1 of full scale"``).

    Raises
    ------
    LogSignalError
        A value outside [lo, hi], naming it and its sample.
    """
    a = np.asarray(values, dtype=np.float64)
    bad = ~((a >= lo) & (a <= hi))
    if bad.any():
        k = np.unravel_index(int(np.argmax(bad)), a.shape)
        raise LogSignalError(f"{log.source}: {name} is {float(a[k])!r} at sample {int(k[0])}; "
                             f"a {fmt} log holds {lo:g}..{hi:g} ({why}): cannot write it",
                             signal=name, source=log.source)


def check_unit_signals(log: FlightLog, fmt: str) -> None:
    """Refuse motor outputs outside 0..1 of full scale (``UNIT_SIGNALS``).

    Parameters
    ----------
    log : FlightLog
        The log to write.
    fmt : str
        The format's name.

    Raises
    ------
    LogSignalError
        Naming the signal and the sample.
    """
    for name in UNIT_SIGNALS:
        if log.has(name):
            check_range(log, name, log.signal(name), fmt, 0.0, 1.0, "0..1 of full scale")
