"""Is a flight log physically possible, in the units quadcog reads? Checked before any
estimate (``quadcog.identify``), so that an impossible log is refused in its own terms, naming
the log and the column, instead of giving a number that means nothing.

- time: seconds; the median step must be a logger's (``RATE_HZ``: 2 Hz .. 100 kHz) and the
  log at most ``MAX_SPAN`` long. A time column in milliseconds or microseconds fails here, and
  the message says which unit it looks like;
- values: each signal within what a quadrotor and its sensors can give (``LIMITS``: speed,
  acceleration, the full scale of a flight controller's gyroscope, angles in radians, motor
  outputs 0..1, a battery voltage);
- the hover (``hover_physics``): over the window the estimators use, the logged vertical
  acceleration must average near 0 (a vehicle holding its height; gravity is not part of the
  kinematic acceleration), the rotors must carry the vehicle's weight within
  ``WEIGHT_RATIO`` (motors off, a vehicle standing or carried by hand, or a rotor model of
  another vehicle fail here), and the angular
  acceleration of the logged rates must be one the airframe's rotors can give
  (``RATE_MARGIN``) and the rates integrated over ``AGREE_SECONDS`` must turn the logged
  roll and pitch as far as they turn (ZYX kinematics, to ``AGREE_TOLERANCE``): deg/s read as
  rad/s fails here;
- the vehicle: logs and baseline logs that name their vehicle (a Crazyflie uSD log, a PX4
  ULog's hardware, ``meta["vehicle"]``) must name the same type (``vehicle_type``).
"""
from collections.abc import Sequence

import numpy as np

from quadcog.errors import IdentificationError
from quadcog.logs.flightlog import FlightLog
from quadcog.logs.signals import SIGNALS, TIME_COLUMN, signal_columns
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["RATE_HZ", "MAX_SPAN", "LIMITS", "WEIGHT_RATIO", "RATE_MARGIN", "MAX_BODY_RATE",
           "AGREE_SECONDS", "AGREE_TOLERANCE", "column_name", "check_log", "hover_physics",
           "vehicle_type", "check_types"]

RATE_HZ = (2.0, 1e5)              # a logger's sample rate (median step), Hz
MAX_SPAN = 86400.0                # s: a log of more than a day is not one flight
MAX_BODY_RATE = np.radians(4000.0)   # rad/s: above the largest gyroscope full scale in use
GRAVITY_FRACTION = 0.3            # |mean vertical acceleration| over the hover, fraction of g
WEIGHT_RATIO = (0.5, 3.0)         # rotor thrust over the hover / the vehicle's weight
RATE_MARGIN = 1.0                 # angular acceleration at most this times the rotors' reach
_SMOOTH_S = 0.1                   # s: rates averaged over this before differencing
AGREE_SECONDS = 0.5               # s: the rates integrated over this (and 1/5, 1/2 of it) ...
AGREE_TOLERANCE = 0.3             # rad: ... turn the logged roll and pitch to within this

# signal: (lowest, highest, unit, what a value beyond says)
LIMITS = {
    "position": (-1e5, 1e5, "m", "100 km from the origin"),
    "velocity": (-150.0, 150.0, "m/s", "faster than any quadrotor flies (150 m/s)"),
    "acceleration": (-200.0, 200.0, "m/s^2", "beyond 20 g"),
    "roll": (-np.pi, np.pi, "rad", "beyond +-pi rad: degrees?"),
    "pitch": (-np.pi / 2, np.pi / 2, "rad", "beyond +-pi/2 rad (ZYX pitch): degrees?"),
    "body_rates": (-MAX_BODY_RATE, MAX_BODY_RATE, "rad/s",
                   "beyond a gyroscope's full scale (4000 deg/s): deg/s?"),
    "motor_command": (0.0, 1.0, "1", "outside 0..1 of full scale"),
    "motor_pwm": (0.0, 1.0, "1", "outside 0..1 of full scale"),
    "thrust_command": (0.0, 1.0, "1", "outside 0..1 of full scale"),
    "battery_voltage": (0.5, 100.0, "V", "not a flight battery's voltage (0.5..100 V)"),
}


def column_name(log: FlightLog, signal: str, component: int | None = None) -> str:
    """How the user finds a signal in the log: its column in a table (``position_z_m``),
    else the signal and component (``body_rates p``).

    Parameters
    ----------
    log : FlightLog
        The log.
    signal : str
        A key of ``SIGNALS`` or ``"t"`` for time.
    component : int, optional
        The component of a vector signal.

    Returns
    -------
    str
        A quoted name for a message.
    """
    if signal == "t":
        return f"column {TIME_COLUMN!r}" if log.format in ("csv", "parquet") else "the time stamps"
    k = 0 if component is None else component
    if log.format in ("csv", "parquet"):
        return f"column {signal_columns(signal)[k]!r}"
    comps = SIGNALS[signal].components
    return f"signal {signal!r}" + (f" ({comps[k]})" if comps else "")


def _unit_guess(step: float) -> str:
    for factor, unit in ((1e-3, "milliseconds"), (1e-6, "microseconds"), (1e-9, "nanoseconds")):
        if RATE_HZ[0] <= 1.0 / (step * factor) <= RATE_HZ[1]:
            return f"; it looks like {unit} (quadcog reads seconds: divide by {1 / factor:g})"
    return "; quadcog reads seconds"


def check_log(log: FlightLog) -> None:
    """Refuse a log whose time base or values no flight gives (module docstring).

    Parameters
    ----------
    log : FlightLog
        One flight.

    Raises
    ------
    IdentificationError
        Naming the log, the column and what is wrong, in the log's units.
    """
    step = float(np.median(np.diff(log.t)))
    span = float(log.t[-1] - log.t[0])
    if not RATE_HZ[0] <= 1.0 / step <= RATE_HZ[1] or span > MAX_SPAN:
        raise IdentificationError(
            f"{log.source}: {column_name(log, 't')}: samples {step:.3g} s apart (median), "
            f"{1.0 / step:.3g} Hz, over {span:.3g} s; a flight log is sampled at "
            f"{RATE_HZ[0]:g} Hz to {RATE_HZ[1]:g} Hz and lasts at most a day"
            + _unit_guess(step))
    for name, (lo, hi, unit, why) in LIMITS.items():
        if not log.has(name):
            continue
        a = log.signal(name).reshape(log.n_samples, -1)
        bad = ~((a >= lo) & (a <= hi))
        if bad.any():
            k, j = (int(i) for i in np.argwhere(bad)[0])
            u = "" if unit == "1" else f" {unit}"
            raise IdentificationError(
                f"{log.source}: {column_name(log, name, j)} is {float(a[k, j]):.6g}{u} at "
                f"t = {float(log.t[k]):.6g} s, {why}; expected {lo:.6g}..{hi:.6g}{u}: "
                "is the log in other units?")


def hover_physics(log: FlightLog, vehicle: Vehicle, mask: np.ndarray, thrusts: np.ndarray,
                  a_z: np.ndarray, a_from: str) -> None:
    """Refuse a hover that gravity, the rotors or the airframe cannot give (module docstring).

    Parameters
    ----------
    log : FlightLog
        One flight.
    vehicle : Vehicle
        Its weight, rotors and inertia.
    mask : numpy.ndarray of bool, shape (N,)
        The hover window's samples.
    thrusts : numpy.ndarray, shape (N, 4)
        Rotor thrusts (N) over the log, from the rotor model.
    a_z : numpy.ndarray, shape (N,)
        Kinematic vertical acceleration (m/s^2).
    a_from : str
        Where ``a_z`` came from (for the message).

    Raises
    ------
    IdentificationError
        Naming the log and what is impossible.
    """
    g, weight = vehicle.g, vehicle.m * vehicle.g
    h = float(np.median(log.signal("position")[mask, 2]))
    mean_a = float(np.mean(a_z[mask]))
    if abs(mean_a) > GRAVITY_FRACTION * g:
        where = column_name(log, "acceleration", 2) if log.has("acceleration") else a_from
        raise IdentificationError(
            f"{log.source}: the vertical acceleration ({where}) averages {mean_a:.3g} m/s^2 "
            f"over the hover at {h:.2f} m, where a vehicle holding its height averages 0; "
            f"expected the kinematic acceleration, without gravity (is g = {g:g} m/s^2 "
            "counted in it, or removed twice?)")
    total = thrusts[mask].sum(axis=1)
    ratio = float(np.mean(total)) / weight
    if not ratio >= WEIGHT_RATIO[0]:
        off = " (the motors are off: a log of the vehicle standing or carried?)" \
            if ratio < 0.05 else ""
        raise IdentificationError(
            f"{log.source}: over the hover at {h:.2f} m the rotors give {100 * ratio:.3g} % of "
            f"the weight of {vehicle.name!r} ({1e3 * vehicle.m:.4g} g){off}; a hovering "
            f"vehicle's rotors carry its weight (expected {100 * WEIGHT_RATIO[0]:g} % to "
            f"{100 * WEIGHT_RATIO[1]:g} %): check the motor outputs' scale and the vehicle")
    if ratio > WEIGHT_RATIO[1]:
        raise IdentificationError(
            f"{log.source}: over the hover at {h:.2f} m the rotors give {ratio:.3g} times the "
            f"weight of {vehicle.name!r} ({1e3 * vehicle.m:.4g} g); expected at most "
            f"{WEIGHT_RATIO[1]:g} times (another vehicle's log, or motor outputs in other units?)")
    if log.has("body_rates"):
        _rates_within_reach(log, vehicle, mask)
        if log.has("roll") and log.has("pitch"):
            _rates_agree_with_angles(log, mask)


def _rates_within_reach(log, vehicle, mask):
    """The angular acceleration of the logged roll and pitch rates (smoothed) against what
    the rotors can give: deg/s read as rad/s is 57 times too fast."""
    pos = np.abs(np.asarray(vehicle.rotor_positions))
    f_max = vehicle.max_rotor_thrust if vehicle.max_rotor_thrust > 0 else \
        WEIGHT_RATIO[1] * vehicle.m * vehicle.g / len(pos)
    # the largest moment: the rotors on one side at full thrust, the others off
    reach = 0.5 * f_max * np.array([pos[:, 1].sum() / vehicle.Ixx, pos[:, 0].sum() / vehicle.Iyy])
    t = log.t[mask]
    w = log.signal("body_rates")[mask, :2]
    n = max(int(round(_SMOOTH_S / float(np.median(np.diff(log.t))))), 1)
    if len(t) < 3 * n:
        return
    kernel = np.ones(n) / n
    ws = np.column_stack([np.convolve(w[:, i], kernel, mode="valid") for i in (0, 1)])
    ts = np.convolve(t, kernel, mode="valid")
    dt = ts[n:] - ts[:-n]
    ok = dt < 3 * _SMOOTH_S            # not across a gap between two plateaus
    if not ok.any():
        return
    alpha = np.abs(ws[n:] - ws[:-n])[ok] / dt[ok, None]
    worst = alpha.max(axis=0)
    for i, axis in enumerate("pq"):
        if worst[i] > RATE_MARGIN * reach[i]:
            raise IdentificationError(
                f"{log.source}: {column_name(log, 'body_rates', i)}: the rate changes by "
                f"{worst[i]:.3g} rad/s^2 over the hover, {worst[i] / reach[i]:.3g} times the "
                f"angular acceleration the rotors of {vehicle.name!r} can give "
                f"({reach[i]:.3g} rad/s^2); are the rates in deg/s? (quadcog reads rad/s)")


def _rates_agree_with_angles(log, mask):
    """The roll and pitch the body rates integrate to (ZYX kinematics) against the logged
    angles, over ``AGREE_SECONDS``: rates in deg/s read as rad/s turn 57 times too far."""
    t = log.t[mask]
    if len(t) < 3:
        return
    phi, theta = log.signal("roll")[mask], log.signal("pitch")[mask]
    p, q, r = log.signal("body_rates")[mask].T
    rates = np.column_stack([p + np.tan(theta) * (q * np.sin(phi) + r * np.cos(phi)),
                             q * np.cos(phi) - r * np.sin(phi)])
    h = np.diff(t)
    turned = np.vstack([np.zeros(2), np.cumsum(0.5 * (rates[1:] + rates[:-1]) * h[:, None],
                                               axis=0)])
    angles = np.unwrap(np.column_stack([phi, theta]), axis=0)
    # over several spans, so that no rotation period hides a turn (a span of one period
    # integrates a sine to 0)
    for span in (0.2 * AGREE_SECONDS, 0.5 * AGREE_SECONDS, AGREE_SECONDS):
        n = max(int(round(span / float(np.median(h)))), 1)
        if len(t) <= n:
            continue
        contiguous = (t[n:] - t[:-n]) < 2 * span        # not across two plateaus
        miss = np.abs((turned[n:] - turned[:-n]) - (angles[n:] - angles[:-n]))[contiguous]
        if miss.size and miss.max() > AGREE_TOLERANCE:
            j = int(np.argmax(miss.max(axis=0)))
            name = ("roll", "pitch")[j]
            raise IdentificationError(
                f"{log.source}: {column_name(log, 'body_rates', j)}: the body rates turn the "
                f"vehicle {float(miss.max()):.3g} rad more in {name} over {span:g} s than "
                f"{column_name(log, name)} shows (expected within {AGREE_TOLERANCE:g} rad): "
                "are the rates in deg/s? (quadcog reads rad/s)")


def vehicle_type(log: FlightLog) -> str | None:
    """The vehicle type a log names: ``"crazyflie"`` for a Crazyflie uSD log, the first word
    of ``meta["vehicle"]``, a PX4 ULog's hardware (``"px4 " + ver_hw``); None when it names
    none.

    Parameters
    ----------
    log : FlightLog
        One flight.

    Returns
    -------
    str or None
        Lower case.
    """
    if log.format == "crazyflie-usd":
        return "crazyflie"
    name = log.meta.get("vehicle", "").strip().lower()
    if name:
        return name.split()[0]
    if log.format == "ulog":
        hw = log.meta.get("ver_hw", "").strip().lower()
        return f"px4 {hw}" if hw else "px4"
    return None


def _same_type(a, b):
    """Equal, or one is the other's family with no hardware named (``px4`` and ``px4 x``)."""
    return a == b or a.split()[0] == b or b.split()[0] == a


def check_types(logs: Sequence[FlightLog], baseline: Sequence[FlightLog],
                vehicle: Vehicle | None = None) -> None:
    """Refuse logs (and baseline logs) that name different vehicle types, or a preset vehicle
    of another type than the logs name.

    Parameters
    ----------
    logs : sequence of FlightLog
        The flights.
    baseline : sequence of FlightLog
        The baseline flights.
    vehicle : Vehicle, optional
        A preset the user named (its name's first word is its type).

    Returns
    -------
    None
        The logs agree.

    Raises
    ------
    IdentificationError
        Naming the two logs and their types.
    """
    named: list[tuple[FlightLog, str]] = []
    for log in list(logs) + list(baseline):
        kind = vehicle_type(log)
        if kind is not None:
            named.append((log, kind))
    for log, k in named[1:]:
        if not _same_type(k, named[0][1]):
            role = "baseline log" if any(log is b for b in baseline) else "log"
            raise IdentificationError(
                f"{log.source}: this {role} is of a {k!r} vehicle but {named[0][0].source} of a "
                f"{named[0][1]!r}; logs and baseline logs must be flights of the same vehicle "
                "type (the baseline removes the vehicle's own asymmetry)")
    if vehicle is not None and named:
        own = vehicle.name.strip().lower().split()[0] if vehicle.name.strip() else ""
        log, k = named[0]
        if own and k.split()[0] not in (own, "px4") and own not in k:
            raise IdentificationError(
                f"{log.source}: a log of a {k!r} vehicle identified as {vehicle.name!r}; pass "
                "the vehicle that flew it (--vehicle)")
