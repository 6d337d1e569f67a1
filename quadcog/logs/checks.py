"""What a log can tell about itself: filters and fits that check a log's signals against each
other (velocity against the derivative of position, the roll sign against the lateral
acceleration, ...). ``tests/test_logs_crazyflie.py`` and ``docs/logs_survey.py`` use them on the
CrazyPAD flights, which are logged at 100 Hz."""
import numpy as np
import numpy.typing as npt
from scipy.signal import butter, filtfilt

from quadcog.logs.flightlog import FlightLog

__all__ = ["lowpass", "bandpass", "airborne_segments", "fit_gain"]

_B, _A = butter(2, 2.0 / 50)                                   # 2 Hz low-pass at 100 Hz
_BB, _AB = butter(2, [0.2 / 50, 2.0 / 50], btype="band")      # 0.2 .. 2 Hz at 100 Hz


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
    """
    return filtfilt(_B, _A, np.asarray(y, dtype=float), axis=0)


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
    """
    return filtfilt(_BB, _AB, np.asarray(y, dtype=float), axis=0)


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
    """
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
    """
    a, b = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    a, b = a - a.mean(), b - b.mean()
    return float((a @ b) / (a @ a)), float(np.corrcoef(a, b)[0, 1])
