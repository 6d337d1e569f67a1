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
from quadcog.validate import array, fail, integer, real

__all__ = ["FLOAT32_MAX", "TICKS_MAX", "EXACT_INTEGER", "EXACT_US", "UNIT_SIGNALS", "BODY_RATE_MAX_DEG_S",
           "microsecond_ticks", "check_range", "check_unit_signals"]

FLOAT32_MAX = float(np.finfo(np.float32).max)
TICKS_MAX = 2 ** 64 - 1                         # a uint64 time stamp (us)
UNIT_SIGNALS = ("motor_command", "motor_pwm")   # 0..1 of full scale in every format
# |body rate| (deg/s) a logged gyroscope can give: above the largest full scale of the
# gyroscopes flight controllers use (2000 deg/s; 4000 deg/s for some), so a rate beyond it is
# no measurement (deg/s read as something else, or a damaged value). The Crazyflie reader
# refuses such gyro variables, the identification such a body_rates signal
# (quadcog.identification.plausibility.MAX_BODY_RATE, in rad/s).
BODY_RATE_MAX_DEG_S = 4000.0


# float64 holds every integer up to this magnitude, and not every one beyond (2^53 + 1 reads
# as 2^53): a time stamp in us (EXACT_US), an integer cell of a table (quadcog.logs.table)
EXACT_INTEGER = 2 ** 53
EXACT_US = float(EXACT_INTEGER)       # us: float64 holds every whole number of us below this


def _log_and_format(log: object, fmt: object, where: str) -> None:
    """Refuse a ``log`` that is not a FlightLog and a format name that is not a str."""
    if not isinstance(log, FlightLog):
        fail(f"{where}: log", "a quadcog.logs.FlightLog", log, LogSignalError)
    if not isinstance(fmt, str):
        fail(f"{where}: fmt", "the format's name (a str)", fmt, LogSignalError)


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
        closer than 1 us; ``log`` not a FlightLog, ``start_us`` not a whole number in
        0..``TICKS_MAX``, ``fmt`` not a str.
    """
    _log_and_format(log, fmt, "microsecond_ticks")
    start_us = integer(start_us, "microsecond_ticks: start_us", lo=0, hi=TICKS_MAX,
                       error=LogSignalError)
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
        A value outside [lo, hi] (NaN too), naming it and its sample; an argument of
        another type (``values`` not real numbers, ``lo`` or ``hi`` not finite).
    """
    _log_and_format(log, fmt, "check_range")
    for arg, value in (("name", name), ("why", why)):
        if not isinstance(value, str):
            fail(f"check_range: {arg}", "a str", value, LogSignalError)
    lo = real(lo, "check_range: lo", error=LogSignalError)
    hi = real(hi, "check_range: hi", error=LogSignalError)
    a = array(values, "check_range: values", finite=False, error=LogSignalError)
    if a.ndim == 0:
        fail("check_range: values", "an array of one row per sample", values, LogSignalError)
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
        Naming the signal and the sample; ``log`` not a FlightLog, ``fmt`` not a str.
    """
    _log_and_format(log, fmt, "check_unit_signals")
    for name in UNIT_SIGNALS:
        if log.has(name):
            check_range(log, name, log.signal(name), fmt, 0.0, 1.0, "0..1 of full scale")
