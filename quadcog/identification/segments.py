"""What the estimators take from a flight log: the hover window, the rotor thrusts, the
vertical acceleration, and block statistics for samples that are not independent.

The hover window (take-off and landing removed) is found from the height alone, so that it
works with every log: the plateau height h is the median of the heights above half the
largest one; the window is every run of samples within ``HOVER_BAND`` of h (a log may hold
several flights), each shortened by ``HOVER_TRIM`` seconds at both ends (the climb and the
descent settle there). Samples of one flight are correlated, so intervals come from the means
of blocks of ``BLOCK_SECONDS`` (Student t over the blocks, widened for the blocks' remaining
lag-one correlation).
"""
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from quadcog.errors import IdentificationError
from quadcog.identification import _checks
from quadcog.logs.flightlog import FlightLog
from quadcog.validate import array, fail, integer, positive, real
from quadcog.vehicles.rotor_model import CRAZYFLIE_FIRMWARE_COMMAND, ROTOR_MODELS, RotorModel
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["check_arguments", "MAX_GAP", "HOVER_BAND", "HOVER_TRIM", "BLOCK_SECONDS", "MIN_BLOCKS", "HoverWindow",
           "hover_window", "rotor_thrusts", "vertical_acceleration", "block_means",
           "block_mean_ci95", "ar1_inflation", "speed_corrected", "body_velocity",
           "SPEED_SPREAD", "t_quantile", "commands_from_mixer", "FALLBACK_NOTE", "thrust_source"]

HOVER_BAND = 0.25        # fraction of the plateau height: |z - h| < 0.25 h is "at the plateau"
HOVER_TRIM = 1.5         # s cut at both ends of the plateau (the climb and descent settle)
BLOCK_SECONDS = 1.0      # samples of one flight are correlated (slow integrators): blocks,
                         # and the blocks' own lag-one correlation widens the interval
MIN_BLOCKS = 3           # fewer blocks than this: too few hover samples for an interval
# Flown at constant height but moving (the CrazyPAD flights cross the room at 0.47 m/s, once
# each way), the rotors' flapping and drag add a moment proportional to the speed, which reads
# as a CoG shift along the motion. When the blocks' mean speeds spread by more than this along
# a body axis, the CoG is the zero-speed intercept of a line fitted through the blocks.
SPEED_SPREAD = 0.1       # m/s
# samples further apart than this are two stretches (a logging gap, or two flights in one
# log): no plateau and no block spans the gap
MAX_GAP = 0.5            # s
# how ``rotor_thrusts`` starts the note on a fallback in its sentence; the sentence before it
# names the rotor model and the signals the thrust came from (``thrust_source``)
FALLBACK_NOTE = " (the log has no "


@dataclass(frozen=True, eq=False)
class HoverWindow:
    """The take-off and landing free part of one log: one or more plateaus (a log may hold
    several flights).

    Parameters
    ----------
    segments : tuple of (float, float)
        Start and end (s, on the log's time) of each trimmed plateau.
    height : float
        The plateau height h (m).
    mask : numpy.ndarray, shape (N,), bool
        The log's samples inside the window.

    Returns
    -------
    HoverWindow

    Raises
    ------
    IdentificationError
        ``segments`` not pairs (start, end) of finite times with start <= end, one after
        the other; ``height`` not a finite number; ``mask`` not a one-dimensional bool
        array (integers would index samples, not mask them).
    """
    segments: tuple
    height: float
    mask: np.ndarray

    def __post_init__(self) -> None:
        at = "HoverWindow."
        pairs = _checks.sequence(self.segments, at + "segments", (list, tuple, np.ndarray),
                                 "(start, end) pair")
        segments: list[tuple[float, float]] = []
        for i, pair in enumerate(pairs):
            a, b = array(pair, f"{at}segments[{i}]", shape=(2,),
                         what="a (start, end) pair of times (s)", error=IdentificationError)
            if not a <= b or (segments and a < segments[-1][1]):
                fail(f"{at}segments[{i}]", "start <= end, after the segment before (s)",
                     pair, IdentificationError)
            segments.append((float(a), float(b)))
        object.__setattr__(self, "segments", tuple(segments))
        object.__setattr__(self, "height", real(self.height, at + "height", unit="m",
                                                error=IdentificationError))
        mask = self.mask
        if not isinstance(mask, np.ndarray) or mask.dtype != np.bool_ or mask.ndim != 1 \
                or np.ma.is_masked(mask):
            fail(at + "mask", "a one-dimensional bool array (one entry per sample of the log)",
                 mask, IdentificationError)
        object.__setattr__(self, "mask", np.array(mask))

    @property
    def samples(self) -> int:
        """Number of samples in the window."""
        return int(self.mask.sum())

    @property
    def t0(self) -> float:
        """Start of the first segment (s)."""
        return self.segments[0][0]

    @property
    def t1(self) -> float:
        """End of the last segment (s)."""
        return self.segments[-1][1]

    def blocks(self, t: npt.NDArray[np.float64], seconds: float = BLOCK_SECONDS
               ) -> npt.NDArray[np.int_]:
        """Block number of each time in ``t`` (the window's samples): consecutive blocks of
        ``seconds`` within each segment, -1 for the rest of a segment shorter than a block.

        Parameters
        ----------
        t : numpy.ndarray, shape (n,)
            Times (s) inside the window.
        seconds : float
            Block length (s).

        Returns
        -------
        numpy.ndarray of int, shape (n,)
            Block numbers from 0 over the segments in turn; -1 outside every block.

        Raises
        ------
        IdentificationError
            ``t`` not a 1-D array of finite real numbers, ``seconds`` not a finite number > 0.
        """
        t = array(t, "HoverWindow.blocks: t", shape=(None,), error=IdentificationError)
        seconds = positive(seconds, "HoverWindow.blocks: seconds", "s", IdentificationError)
        index = np.full(len(t), -1)
        # n equal blocks tile a segment, each at least ``seconds`` long; a segment shorter
        # than a block has none
        a, b = np.array(self.segments, dtype=float).reshape(-1, 2).T
        n = ((b - a) // seconds).astype(int)
        a, b, n = a[n > 0], b[n > 0], n[n > 0]
        first = np.cumsum(n) - n
        # each time's segment found by bisection (a loop over the segments, each over every
        # time, was quadratic in a long log of many plateaus); where two segments touch,
        # the later one holds the shared time
        seg = np.searchsorted(a, t, side="right") - 1
        inside = seg >= 0
        inside[inside] = t[inside] <= b[seg[inside]]
        s = seg[inside]
        k = np.minimum(np.floor((t[inside] - a[s]) / ((b[s] - a[s]) / n[s])).astype(int), n[s] - 1)
        index[inside] = k + first[s]
        return index


def check_arguments(where: str, log: object, vehicle: object = None) -> None:
    """Refuse a ``log`` that is not a FlightLog and a ``vehicle`` (when given) that is not a
    Vehicle, with the IdentificationError of quadcog.validate's grammar.

    Parameters
    ----------
    where : str
        The function's name, for the message.
    log : object
        What was passed as the log.
    vehicle : object, optional
        What was passed as the vehicle (None: not checked).

    Raises
    ------
    IdentificationError
        Naming the argument and what was expected (``where`` not a str).
    """
    _checks.text(where, "check_arguments: where")
    if not isinstance(log, FlightLog):
        fail(f"{where}: log", "a quadcog.logs.FlightLog", log, IdentificationError)
    if vehicle is not None and not isinstance(vehicle, Vehicle):
        fail(f"{where}: vehicle", "a quadcog Vehicle", vehicle, IdentificationError)


def hover_window(log: FlightLog, band: float = HOVER_BAND, trim: float = HOVER_TRIM
                 ) -> HoverWindow:
    """The hover window of ``log`` (module docstring: plateaus of the height, trimmed).

    Parameters
    ----------
    log : quadcog.logs.FlightLog
        With the signal ``"position"`` (m, ground frame, z up).
    band : float
        Half-width of the plateau band as a fraction of its height.
    trim : float
        Seconds removed at each end of each plateau.

    Returns
    -------
    HoverWindow
        The plateaus, trimmed, with at least ``MIN_BLOCKS`` blocks.

    Raises
    ------
    IdentificationError
        The log has no position, never leaves the ground, or its plateaus hold fewer than
        ``MIN_BLOCKS`` blocks of ``BLOCK_SECONDS`` after the trim.
    """
    check_arguments("hover_window", log)
    band = real(band, "hover_window: band", lo=0.0, hi=1.0, lo_open=True,
                error=IdentificationError)
    trim = real(trim, "hover_window: trim", lo=0.0, unit="s", error=IdentificationError)
    if not log.has("position"):
        raise IdentificationError(f"{log.source}: no 'position' signal, so the hover (take-off "
                                  "and landing free) part cannot be found from the height")
    z = log.signal("position")[:, 2]
    t = log.t
    top = np.max(z)
    if not top > 0.05:
        raise IdentificationError(f"{log.source}: the height never exceeds 5 cm (largest "
                                  f"{top:.3f} m): no flight to identify from")
    h = float(np.median(z[z > 0.5 * top]))
    inside = np.abs(z - h) < band * h
    # a run of samples at the plateau ends where it leaves the band or where the time stamps
    # jump (a logging gap, two flights in one log): no segment spans a gap
    gap = np.diff(t) > MAX_GAP
    first = inside & ~(np.r_[False, inside[:-1]] & ~np.r_[False, gap])
    last = inside & ~(np.r_[inside[1:], False] & ~np.r_[gap, False])
    runs = zip(np.flatnonzero(first), np.flatnonzero(last) + 1)
    segments = []
    for i, j in runs:
        a, b = t[i] + trim, t[j - 1] - trim
        if b - a >= BLOCK_SECONDS:
            segments.append((float(a), float(b)))
    # each segment's samples by bisection of the increasing times: linear in the log
    mask = np.zeros(len(t), bool)
    for a, b in segments:
        mask[np.searchsorted(t, a, side="left"):np.searchsorted(t, b, side="right")] = True
    window = HoverWindow(tuple(segments), h, mask)
    n_blocks = window.blocks(t[mask]).max(initial=-1) + 1
    if n_blocks < MIN_BLOCKS:
        raise IdentificationError(
            f"{log.source}: too few hover samples: the plateau(s) near {h:.2f} m give "
            f"{n_blocks} block(s) of {BLOCK_SECONDS:g} s after cutting {trim:g} s at each end "
            f"(at least {MIN_BLOCKS} needed)")
    return window


def commands_from_mixer(log: FlightLog, vehicle: Vehicle) -> npt.NDArray[np.float64]:
    """Rotor commands from thrust_command and moment_command, by the mixer the signals are
    defined with (quadcog.logs.SIGNALS['moment_command']).

    Parameters
    ----------
    log : quadcog.logs.FlightLog
        With the signals thrust_command and moment_command.
    vehicle : quadcog.Vehicle
        Its rotor positions and spin directions.

    Returns
    -------
    numpy.ndarray of shape (N, 4)
        The commands 0..1 of full scale (clipped), rotors in quadcog's order.

    Raises
    ------
    IdentificationError
        ``log`` not a FlightLog, ``vehicle`` not a Vehicle.
    LogSignalError
        The log lacks thrust_command or moment_command.
    """
    check_arguments("commands_from_mixer", log)
    _checks.vehicle(vehicle, "commands_from_mixer: vehicle")
    pos = np.asarray(vehicle.rotor_positions)
    d = np.asarray(vehicle.rotor_directions, float)
    T = log.signal("thrust_command")[:, None]
    m = log.signal("moment_command")
    u = T + np.sign(pos[:, 1])[None] * m[:, :1] - np.sign(pos[:, 0])[None] * m[:, 1:2] \
        + d[None] * m[:, 2:3]
    return np.clip(u, 0.0, 1.0)


def rotor_thrusts(log: FlightLog, vehicle: Vehicle, rotor_model: RotorModel | str | None = None
                  ) -> tuple[npt.NDArray[np.float64], str, RotorModel]:
    """The thrust of each rotor (N) over the whole log, and how it was obtained.

    Parameters
    ----------
    log : quadcog.logs.FlightLog
        With the rotor model's signals (or a fallback's: motor_command, or thrust_command and
        moment_command).
    vehicle : quadcog.Vehicle
        Its ``rotor_model`` is used unless ``rotor_model`` is given.
    rotor_model : RotorModel or str, optional
        A model or a name of ``ROTOR_MODELS``.

    Returns
    -------
    (numpy.ndarray of shape (N, 4), str, RotorModel)
        Thrusts (N), a sentence saying which signals and model gave them, the model used.

    Raises
    ------
    IdentificationError
        No rotor model, or the log lacks the signals it needs and no fallback applies (the
        message names the signals); ``log``, ``vehicle`` or ``rotor_model`` of another type.
    """
    check_arguments("rotor_thrusts", log, vehicle)
    _checks.vehicle(vehicle, "rotor_thrusts: vehicle")
    _checks.rotor_model(rotor_model, "rotor_thrusts: rotor_model")
    model = vehicle.rotor_model if rotor_model is None else rotor_model
    if isinstance(model, str):
        if model not in ROTOR_MODELS:
            fail("rotor_model", f"a name of {', '.join(ROTOR_MODELS)} or a RotorModel",
                 model, IdentificationError)
        model = ROTOR_MODELS[model]
    if not isinstance(model, RotorModel):
        raise IdentificationError(f"vehicle {vehicle.name!r} has no rotor_model, so motor "
                                  "outputs cannot be turned into thrust; pass rotor_model= (--rotor-model "
                                  f"on the command line), one of {', '.join(ROTOR_MODELS)}")
    missing = [s for s in model.signals if not log.has(s)]
    if not missing:
        u = log.signal(model.signal)
        v = log.signal("battery_voltage") if model.uses_voltage else None
        return model.thrust(u, v), f"{model.name} from {' and '.join(model.signals)}", model
    # A Crazyflie log without the PWM (the controller logs): with battery compensation the
    # firmware's command is linear in thrust, so the command is the next best input.
    crazyflie = model.name in ROTOR_MODELS
    fallback = CRAZYFLIE_FIRMWARE_COMMAND if crazyflie else None
    if fallback is not None and log.has("motor_command"):
        return (fallback.thrust(log.signal("motor_command")),
                f"{fallback.name} from motor_command{FALLBACK_NOTE}{', '.join(missing)})",
                fallback)
    if fallback is not None and log.has("thrust_command") and log.has("moment_command"):
        u = commands_from_mixer(log, vehicle)
        return (fallback.thrust(u), f"{fallback.name} from thrust_command and moment_command "
                f"through the firmware's mixer{FALLBACK_NOTE}{', '.join(missing)})", fallback)
    raise IdentificationError(
        f"{log.source}: rotor model {model.name!r} needs the signal(s) "
        f"{', '.join(missing)}, which the log lacks (it has "
        f"{', '.join(log.signals) or 'no standard signals'})")


def thrust_source(description: str) -> str:
    """The rotor model and the signals a thrust came from: a sentence of ``rotor_thrusts``
    without its note on what the log lacks (two logs whose thrusts have one source carry the
    same model error, which a baseline cancels).

    Parameters
    ----------
    description : str
        The sentence ``rotor_thrusts`` returned (``FlightEstimate.rotor``).

    Returns
    -------
    str
        E.g. ``"bitcraze-voltage from motor_pwm and battery_voltage"``.

    Raises
    ------
    IdentificationError
        ``description`` not a str.
    """
    return _checks.text(description, "thrust_source: description").partition(FALLBACK_NOTE)[0]


def vertical_acceleration(log: FlightLog) -> tuple[npt.NDArray[np.float64], str]:
    """Kinematic vertical acceleration (N,) (m/s^2, z up) and where it came from: the
    ``"acceleration"`` signal, else the derivative of the vertical velocity, else zero.

    Parameters
    ----------
    log : quadcog.logs.FlightLog
        The flight.

    Returns
    -------
    (numpy.ndarray of shape (N,), str)
        The acceleration (m/s^2) and a phrase saying where it came from.

    Raises
    ------
    IdentificationError
        ``log`` not a FlightLog.
    """
    check_arguments("vertical_acceleration", log)
    if log.has("acceleration"):
        return log.signal("acceleration")[:, 2], "the logged acceleration"
    if log.has("velocity"):
        return np.gradient(log.signal("velocity")[:, 2], log.t), "the derivative of velocity"
    return np.zeros(log.n_samples), "none logged (taken as 0)"


def block_means(index: npt.NDArray[np.int_], values: npt.NDArray[np.float64]
                ) -> npt.NDArray[np.float64]:
    """Means of ``values`` per block number (``HoverWindow.blocks``; -1 is left out).

    Parameters
    ----------
    index : numpy.ndarray of int, shape (n,)
        Block number of each sample.
    values : numpy.ndarray, shape (n, ...)
        Samples.

    Returns
    -------
    numpy.ndarray, shape (B, ...)
        One mean per block, B = index.max() + 1.

    Raises
    ------
    IdentificationError
        ``index`` not integers from -1 to n - 1 in one dimension; ``values`` not finite real
        numbers with n rows.
    """
    index = _checks.block_index(index, "block_means: index")
    values = _checks.rows(values, "block_means: values", n_rows=len(index))
    return _block_means(index, values)


def _block_means(index, values):
    """``block_means`` without the argument checks (the estimators' own arrays)."""
    # one pass over the samples (a mask per block would make it quadratic in the log)
    n_blocks = int(index.max(initial=-1)) + 1
    keep = index >= 0
    idx, flat = index[keep], values[keep].reshape(int(keep.sum()), -1)
    counts = np.bincount(idx, minlength=n_blocks).astype(float)
    sums = np.column_stack([np.bincount(idx, weights=flat[:, j], minlength=n_blocks)
                            for j in range(flat.shape[1])]) if flat.shape[1] else \
        np.zeros((n_blocks, 0))
    return (sums / counts[:, None]).reshape((n_blocks,) + values.shape[1:])


# beyond this many degrees of freedom Student's t quantile is the normal's to 1e-9 (and
# scipy takes no integer past int64: 10**400 raised TypeError)
T_DOF_NORMAL = 10 ** 9


def t_quantile(dof: int) -> float:
    """The 97.5 % quantile of Student's t with ``dof`` degrees of freedom (two-sided 95 %).

    Parameters
    ----------
    dof : int
        Degrees of freedom, >= 1.

    Returns
    -------
    float
        The quantile.

    Raises
    ------
    IdentificationError
        ``dof`` not a whole number >= 1 (0 or -1 was read as 1, True as 1, 2.7 as 2).
    """
    from scipy import stats  # here: slow to import
    dof = integer(dof, "t_quantile: dof", lo=1, error=IdentificationError)
    return float(stats.t.ppf(0.975, min(dof, T_DOF_NORMAL)))


def block_mean_ci95(blocks: npt.ArrayLike
                    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Mean of block means and the half-width of its 95 % interval (Student t on the blocks).

    Parameters
    ----------
    blocks : array_like, shape (B, ...)
        Block means (``block_means``), B >= 2.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        Mean and half-width, each of shape (...).

    Raises
    ------
    IdentificationError
        ``blocks`` not finite real numbers of at least 2 rows.
    """
    return _block_mean_ci95(_checks.rows(blocks, "block_mean_ci95: blocks", min_rows=2))


def _block_mean_ci95(blocks):
    """``block_mean_ci95`` without the argument checks (the estimators' own arrays)."""
    b = np.asarray(blocks, dtype=float)
    n = b.shape[0]
    return b.mean(axis=0), t_quantile(n - 1) * b.std(axis=0, ddof=1) / np.sqrt(n) \
        * np.sqrt(_ar1_inflation(b))


def ar1_inflation(blocks: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Variance factor (1 + rho) / (1 - rho) of the mean of block means whose neighbours
    correlate with lag-one coefficient rho > 0 (AR(1)); 1 when rho <= 0 or too few blocks.

    Parameters
    ----------
    blocks : array_like, shape (B, ...)
        Block means (or residuals), in time order.

    Returns
    -------
    numpy.ndarray, shape (...)
        The factor, >= 1.

    Raises
    ------
    IdentificationError
        ``blocks`` not finite real numbers of at least one row.
    """
    return _ar1_inflation(_checks.rows(blocks, "ar1_inflation: blocks", min_rows=1))


def _ar1_inflation(blocks):
    """``ar1_inflation`` without the argument checks (the estimators' own arrays)."""
    b = np.asarray(blocks, dtype=float)
    if b.shape[0] < 4:
        return np.ones(b.shape[1:])
    d = b - b.mean(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        rho = (d[1:] * d[:-1]).sum(axis=0) / (d * d).sum(axis=0)
    rho = np.clip(np.nan_to_num(rho), 0.0, 0.9)
    return (1 + rho) / (1 - rho)


def body_velocity(log: FlightLog) -> npt.NDArray[np.float64]:
    """Horizontal velocity in heading axes (N, 2) (m/s: forward, left), the ground velocity
    (else the derivative of the position) turned by -yaw (when logged); zeros without either.

    Parameters
    ----------
    log : quadcog.logs.FlightLog
        The flight.

    Returns
    -------
    numpy.ndarray, shape (N, 2)
        Forward and left velocity (m/s).

    Raises
    ------
    IdentificationError
        ``log`` not a FlightLog.
    """
    check_arguments("body_velocity", log)
    if log.has("velocity"):
        v = log.signal("velocity")[:, :2]
    elif log.has("position"):
        v = np.gradient(log.signal("position")[:, :2], log.t, axis=0)
    else:
        return np.zeros((log.n_samples, 2))
    if not log.has("yaw"):
        return v.copy()
    c, s = np.cos(log.signal("yaw")), np.sin(log.signal("yaw"))
    return np.column_stack([c * v[:, 0] + s * v[:, 1], -s * v[:, 0] + c * v[:, 1]])


def speed_corrected(blocks_r: npt.NDArray[np.float64], blocks_v: npt.NDArray[np.float64],
                    spread: float = SPEED_SPREAD
                    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64],
                               npt.NDArray[np.float64]]:
    """x_G and y_G from block estimates, free of a moment proportional to the speed.

    For each of x and y: when the blocks' speeds along that axis spread by more than
    ``spread``, the zero-speed intercept of the least-squares line r_b = r + k v_b and the
    95 % half-width of that intercept (Student t with B - 2 degrees of freedom, widened for the
    residuals' lag-one correlation); otherwise the mean of the blocks (``block_mean_ci95``).

    Parameters
    ----------
    blocks_r : numpy.ndarray, shape (B, 3)
        Block estimates of r_G (m).
    blocks_v : numpy.ndarray, shape (B, 2)
        Block mean speeds forward and left (m/s).
    spread : float
        Spread of the block speeds (m/s) above which the line is fitted.

    Returns
    -------
    (numpy.ndarray (3,), numpy.ndarray (3,), numpy.ndarray (2,))
        r_G, half-widths (the z entry as ``block_mean_ci95`` gives it) and the slopes k
        (m per m/s; 0 where not fitted).

    Raises
    ------
    IdentificationError
        ``blocks_r`` not finite real numbers of shape (B, 3) with B >= 2, ``blocks_v`` not
        of shape (B, 2), ``spread`` not a finite number >= 0.
    """
    blocks_r = _checks.rows(blocks_r, "speed_corrected: blocks_r", columns=3, min_rows=2)
    blocks_v = _checks.rows(blocks_v, "speed_corrected: blocks_v", columns=2,
                            n_rows=len(blocks_r))
    spread = real(spread, "speed_corrected: spread", lo=0.0, unit="m/s",
                  error=IdentificationError)
    return _speed_corrected(blocks_r, blocks_v, spread)


def _speed_corrected(blocks_r, blocks_v, spread=SPEED_SPREAD):
    """``speed_corrected`` without the argument checks (the estimators' own arrays)."""
    r, half = _block_mean_ci95(blocks_r)
    slopes = np.zeros(2)
    n = len(blocks_r)
    for i in (0, 1):
        v = blocks_v[:, i]
        if n < 4 or np.ptp(v) <= spread:
            continue
        A = np.column_stack([np.ones(n), v])
        coef, *_ = np.linalg.lstsq(A, blocks_r[:, i], rcond=None)
        e = blocks_r[:, i] - A @ coef
        cov = np.linalg.inv(A.T @ A) * (e @ e) / (n - 2)
        r[i], slopes[i] = coef
        half[i] = t_quantile(n - 2) * np.sqrt(cov[0, 0] * _ar1_inflation(e[:, None])[0])
    return r, half, slopes
