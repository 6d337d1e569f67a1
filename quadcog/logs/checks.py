"""What a log can tell about itself: filters and fits that check a log's signals against each
other (velocity against the derivative of position, the roll sign against the lateral
acceleration, ...). ``tests/test_logs_crazyflie.py`` and ``docs/logs_survey.py`` use them on the
CrazyPAD flights, which are logged at 100 Hz."""
import numpy as np
import numpy.typing as npt
from scipy.signal import butter, filtfilt

from quadcog.errors import InputError
from quadcog.logs.flightlog import FlightLog
from quadcog.validate import array, fail, nonnegative, real

__all__ = ["lowpass", "bandpass", "airborne_segments", "fit_gain"]

_B, _A = butter(2, 2.0 / 50)                                   # 2 Hz low-pass at 100 Hz
_BB, _AB = butter(2, [0.2 / 50, 2.0 / 50], btype="band")      # 0.2 .. 2 Hz at 100 Hz


def _samples(y, where, b, a):
    """``y`` as finite float64 samples along the first axis, (N,) or (N, k), with more
    samples than filtfilt pads with (3 times the filter's length)."""
    pad = 3 * max(len(a), len(b))
    what = f"an array of shape (N,) or (N, k) of finite numbers with N > {pad} samples"
    y = array(y, where, what=what)
    if y.ndim not in (1, 2) or y.shape[0] <= pad:
        raise InputError(f"{where}: expected {what} (filtfilt's padding), got shape {y.shape}")
    return y


def lowpass(y: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """A zero-phase 2 Hz low-pass of signals sampled at 100 Hz.

    Parameters
    ----------
    y : (N,) or (N, k) array_like
        Samples along the first axis.

    Returns
    -------
    numpy.ndarray
        Filtered, the same shape.

    Raises
    ------
    InputError
        ``y`` not finite real numbers of shape (N,) or (N, k) with more than 9 samples.
    """
    return filtfilt(_B, _A, _samples(y, "lowpass: y", _B, _A), axis=0)


def bandpass(y: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """A zero-phase 0.2-2 Hz band-pass of signals sampled at 100 Hz (removes offsets and noise).

    Parameters
    ----------
    y : (N,) or (N, k) array_like
        Samples along the first axis.

    Returns
    -------
    numpy.ndarray
        Filtered, the same shape.

    Raises
    ------
    InputError
        ``y`` not finite real numbers of shape (N,) or (N, k) with more than 15 samples.
    """
    return filtfilt(_BB, _AB, _samples(y, "bandpass: y", _BB, _AB), axis=0)


def airborne_segments(log: FlightLog, zmin: float = 0.4,
                      trim: float = 0.5) -> list[npt.NDArray[np.bool_]]:
    """The airborne stretches of a log, as masks.

    Parameters
    ----------
    log : FlightLog
        A log with the signal ``position``.
    zmin : float
        Height (m) above which the vehicle counts as airborne.
    trim : float
        Seconds left out at either end of each stretch (take-off and landing).

    Returns
    -------
    list of (N,) numpy.ndarray of bool
        One mask per stretch of more than 200 samples.

    Raises
    ------
    InputError
        ``log`` not a FlightLog, ``zmin`` not a finite number, ``trim`` not a finite number
        >= 0; ``LogSignalError`` when the log has no position.
    """
    if not isinstance(log, FlightLog):
        fail("airborne_segments: log", "a quadcog.logs.FlightLog", log)
    zmin = real(zmin, "airborne_segments: zmin", unit="m")
    trim = nonnegative(trim, "airborne_segments: trim", "s")
    up = log.signal("position")[:, 2] > zmin
    edges = np.r_[0, np.flatnonzero(np.diff(up.astype(int))) + 1, up.size]
    out = []
    for s, e in zip(edges[:-1], edges[1:]):
        keep = up[s] & (log.t >= log.t[s] + trim) & (log.t <= log.t[e - 1] - trim)
        if keep.sum() > 200:
            out.append(keep)
    return out


def fit_gain(x: npt.ArrayLike, y: npt.ArrayLike) -> tuple[float, float]:
    """The least-squares gain of y on x and their correlation, means removed.

    Parameters
    ----------
    x : (N,) array_like
        The two signals.
    y : (N,) array_like
        The two signals.

    Returns
    -------
    tuple of (float, float)
        (gain, correlation coefficient).

    Raises
    ------
    InputError
        ``x`` or ``y`` not finite real numbers of shape (N,) with N >= 2, of different
        lengths, or constant (no gain or no correlation: 0 / 0).
    """
    what = "an array of shape (N,) of finite numbers, N >= 2"
    a, b = array(x, "fit_gain: x", what=what), array(y, "fit_gain: y", what=what)
    for where, v in (("fit_gain: x", a), ("fit_gain: y", b)):
        if v.ndim != 1 or v.size < 2 or v.shape != a.shape:
            raise InputError(f"{where}: expected {what} (as many as x), got shape {v.shape}")
    # scaled to magnitudes of 1 first, so that neither the means nor the products overflow
    sa, sb = float(np.abs(a).max()), float(np.abs(b).max())
    a, b = a / (sa or 1.0), b / (sb or 1.0)
    a, b = a - a.mean(), b - b.mean()
    for where, v, value in (("fit_gain: x", a, x), ("fit_gain: y", b, y)):
        if not (v @ v) > 0:             # constant: the gain or the correlation is 0 / 0
            fail(where, "samples that vary (a constant has no gain or correlation)", value)
    return float((a @ b) / (a @ a) * (sb / sa)), float(np.corrcoef(a, b)[0, 1])
