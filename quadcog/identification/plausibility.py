"""Is a flight log physically possible, in the units quadcog reads? Checked before any
estimate (``quadcog.identify``), so that an impossible log is refused in its own terms, naming
the log and the column, instead of giving a number that means nothing.

- time: seconds; the median step must be a logger's (``RATE_HZ``: 2 Hz .. 100 kHz), no step
  shorter than its fastest one, and the log at most ``MAX_SPAN`` long. A time column in
  milliseconds or microseconds fails here, and the message says which unit it looks like;
- values: each signal within what a quadrotor and its sensors can give (``LIMITS``: speed,
  acceleration, the full scale of a flight controller's gyroscope, angles in radians, an
  unwrapped yaw no day at that full scale exceeds, motor outputs 0..1, moment commands
  within +-1, a battery voltage);
- the hover (``hover_physics``): over the window the estimators use, the logged vertical
  acceleration must average near 0 (a vehicle holding its height; gravity is not part of the
  kinematic acceleration), the rotors must carry the vehicle's weight within
  ``WEIGHT_RATIO`` (motors off, a vehicle standing or carried by hand, or a rotor model of
  another vehicle fail here), no motor output (or command of the mixer) at full scale over
  most of the hover, nor a rotor at its rotor model's largest thrust, and the angular
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
from quadcog.identification import _checks
from quadcog.identification.segments import MAX_GAP, check_arguments, commands_from_mixer
from quadcog.logs.flightlog import FlightLog
from quadcog.logs.limits import BODY_RATE_MAX_DEG_S
from quadcog.logs.signals import SIGNALS, TIME_COLUMN, signal_columns
from quadcog.logs.ulog import WRITER_HW, WRITER_NAME
from quadcog.validate import array, choice, fail, integer
from quadcog.vehicles.rotor_model import MAX_BATTERY_VOLTAGE, RotorModel
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["RATE_HZ", "MAX_SPAN", "LIMITS", "WEIGHT_RATIO", "RATE_MARGIN", "MAX_BODY_RATE",
           "AGREE_SECONDS", "AGREE_TOLERANCE", "MAX_HOVER_TILT", "SATURATED",
           "SATURATED_FRACTION", "YAW_IMBALANCE", "ACCEL_AGREE", "VELOCITY_SECONDS",
           "VELOCITY_TOLERANCE", "column_name", "check_log", "hover_physics",
           "vehicle_type", "check_types"]

RATE_HZ = (2.0, 1e5)              # a logger's sample rate (median step), Hz
MAX_SPAN = 86400.0                # s: a log of more than a day is not one flight
# rad/s: above the largest gyroscope full scale in use (one definition, quadcog.logs.limits)
MAX_BODY_RATE = float(np.radians(BODY_RATE_MAX_DEG_S))
GRAVITY_FRACTION = 0.3            # |mean vertical acceleration| over the hover, fraction of g
WEIGHT_RATIO = (0.5, 3.0)         # rotor thrust over the hover / the vehicle's weight
RATE_MARGIN = 1.0                 # angular acceleration at most this times the rotors' reach
_SMOOTH_S = 0.1                   # s: rates averaged over this before differencing
AGREE_SECONDS = 0.5               # s: the rates integrated over this (and 1/5, 1/2 of it) ...
AGREE_TOLERANCE = 0.3             # rad: ... turn the logged roll and pitch to within this
MAX_HOVER_TILT = np.radians(60.0)  # rad: tilted further over the hover, no level balance
SATURATED = 0.99                  # a motor output at or above this fraction of full scale ...
SATURATED_FRACTION = 0.5          # ... over more than this fraction of the hover: saturated
YAW_IMBALANCE = 0.3               # |sum d_i f_i| / sum f_i over the hover: the yaw moment
ACCEL_AGREE = 0.05                # fraction of g: mean logged a_z against the velocity's change
VELOCITY_SECONDS = 1.0            # s: the velocity integrated over this ...
VELOCITY_TOLERANCE = (0.25, 0.25)  # ... moves as far as the position, to 0.25 m + 25 %

# signal: (lowest, highest, unit, what a value beyond says)
LIMITS = {
    "position": (-1e5, 1e5, "m", "100 km from the origin"),
    "velocity": (-150.0, 150.0, "m/s", "faster than any quadrotor flies (150 m/s)"),
    "acceleration": (-200.0, 200.0, "m/s^2", "beyond 20 g"),
    "roll": (-np.pi, np.pi, "rad", "beyond +-pi rad: degrees?"),
    # unwrapped, yaw turns at most a gyroscope's full scale for the longest log
    "yaw": (-MAX_BODY_RATE * MAX_SPAN, MAX_BODY_RATE * MAX_SPAN, "rad",
            "more than a day at a gyroscope's full scale turns"),
    "pitch": (-np.pi / 2, np.pi / 2, "rad", "beyond +-pi/2 rad (ZYX pitch): degrees?"),
    "body_rates": (-MAX_BODY_RATE, MAX_BODY_RATE, "rad/s",
                   "beyond a gyroscope's full scale (4000 deg/s): deg/s?"),
    "motor_command": (0.0, 1.0, "1", "outside 0..1 of full scale"),
    "motor_pwm": (0.0, 1.0, "1", "outside 0..1 of full scale"),
    "thrust_command": (0.0, 1.0, "1", "outside 0..1 of full scale"),
    # a moment command of more than full scale turns a rotor from off to full and beyond
    "moment_command": (-1.0, 1.0, "1", "beyond full scale of a motor"),
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

    Raises
    ------
    IdentificationError
        ``log`` not a FlightLog, ``signal`` not a signal name, or ``component`` not one of
        the signal's (-1 named the last column, True the second).
    """
    check_arguments("column_name", log)
    if not isinstance(signal, str):         # an array compared with "t" raised ValueError
        fail("column_name: signal", "'t' or a name of quadcog.logs.SIGNALS", signal,
             IdentificationError)
    if signal != "t":
        choice(signal, "column_name: signal", SIGNALS, error=IdentificationError)
    if signal == "t":
        return f"column {TIME_COLUMN!r}" if log.format in ("csv", "parquet") else "the time stamps"
    width = max(len(SIGNALS[signal].components), 1)
    k = 0 if component is None else integer(component, "column_name: component", lo=0,
                                            hi=width - 1, error=IdentificationError)
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
        Naming the log, the column and what is wrong, in the log's units; ``log`` not a
        FlightLog.
    """
    check_arguments("check_log", log)
    step = float(np.median(np.diff(log.t)))
    span = float(log.t[-1] - log.t[0])
    if not RATE_HZ[0] <= 1.0 / step <= RATE_HZ[1] or span > MAX_SPAN:
        raise IdentificationError(
            f"{log.source}: {column_name(log, 't')}: samples {step:.3g} s apart (median), "
            f"{1.0 / step:.3g} Hz, over {span:.3g} s; a flight log is sampled at "
            f"{RATE_HZ[0]:g} Hz to {RATE_HZ[1]:g} Hz and lasts at most a day"
            + _unit_guess(step))
    # every step, not only the median: a sample closer to the one before than any logger
    # writes (a stamp repeated with a jitter, or rewritten) makes the derivatives of the
    # velocity and the position that the checks and estimators take numbers of no flight
    short = np.diff(log.t) < 1.0 / RATE_HZ[1]
    if short.any():
        k = int(np.argmax(short))
        raise IdentificationError(
            f"{log.source}: {column_name(log, 't')}: sample {k + 1} at "
            f"t = {float(log.t[k + 1])!r} s follows sample {k} by "
            f"{float(log.t[k + 1] - log.t[k]):.3g} s (the first of {int(short.sum())} such "
            f"step(s)); expected steps of at least {1.0 / RATE_HZ[1]:g} s (a logger writes at "
            f"most {RATE_HZ[1]:g} Hz): a time stamp repeated or rewritten?")
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
    _position_speed(log)


def _stretches(t: np.ndarray) -> list[slice]:
    """Runs of samples without a gap of more than ``MAX_GAP`` between them."""
    cuts = np.flatnonzero(np.diff(t) > MAX_GAP) + 1
    edges = np.r_[0, cuts, len(t)]
    return [slice(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]


def _position_speed(log):
    """The speed the position gives (over ``_SMOOTH_S``), against ``LIMITS["velocity"]``:
    positions in mm (or cm) read as m climb and land a thousand times too fast."""
    if not log.has("position"):
        return
    p, t = log.signal("position"), log.t
    hi = LIMITS["velocity"][1]
    n = max(int(round(_SMOOTH_S / float(np.median(np.diff(t))))), 1)
    for part in _stretches(t):
        tp, pp = t[part], p[part]
        if len(tp) <= n:
            continue
        speed = np.abs(pp[n:] - pp[:-n]) / (tp[n:] - tp[:-n])[:, None]
        if speed.max() > hi:
            k, j = (int(i) for i in np.unravel_index(int(np.argmax(speed)), speed.shape))
            raise IdentificationError(
                f"{log.source}: {column_name(log, 'position', j)} changes at "
                f"{float(speed[k, j]):.4g} m/s near t = {float(tp[k]):.6g} s, faster than any "
                f"quadrotor flies ({hi:g} m/s): is the position in mm or cm? (quadcog reads m)")


def hover_physics(log: FlightLog, vehicle: Vehicle, mask: np.ndarray, thrusts: np.ndarray,
                  a_z: np.ndarray, a_from: str, rotor_model: RotorModel | None = None) -> None:
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
    rotor_model : RotorModel, optional
        The model that gave ``thrusts``: a rotor at its largest thrust over most of the
        hover (``SATURATED_FRACTION``) is refused, as a saturated output is.

    Raises
    ------
    IdentificationError
        Naming the log and what is impossible; arguments of another type or shape (``mask``
        not a bool array of the log's samples selecting one at least, ``thrusts`` not finite
        (N, 4), ``a_z`` not finite (N,), ``a_from`` not a str, ``rotor_model`` not a
        RotorModel or None).
    """
    check_arguments("hover_physics", log)
    _checks.vehicle(vehicle, "hover_physics: vehicle")
    n = log.n_samples
    mask = _checks.mask(mask, "hover_physics: mask", n)
    thrusts = array(thrusts, "hover_physics: thrusts", shape=(n, 4), error=IdentificationError)
    a_z = array(a_z, "hover_physics: a_z", shape=(n,), error=IdentificationError)
    _checks.text(a_from, "hover_physics: a_from")
    if rotor_model is not None and not isinstance(rotor_model, RotorModel):
        fail("hover_physics: rotor_model", "a RotorModel or None", rotor_model,
             IdentificationError)
    g, weight = vehicle.g, vehicle.m * vehicle.g
    h = float(np.median(log.signal("position")[mask, 2]))
    cos_tilt = _hover_tilt(log, mask, h)
    _saturation(log, vehicle, mask, h)
    if rotor_model is not None:
        _thrust_ceiling(log, mask, thrusts, rotor_model, h)
    _yaw_balance(log, vehicle, mask, thrusts, h)
    if log.has("velocity"):
        _velocity_agrees_with_position(log, mask)
    if log.has("acceleration"):
        _acceleration_agrees(log, mask, a_z, h, g)
    mean_a = float(np.mean(a_z[mask]))
    if abs(mean_a) > GRAVITY_FRACTION * g:
        where = column_name(log, "acceleration", 2) if log.has("acceleration") else a_from
        raise IdentificationError(
            f"{log.source}: the vertical acceleration ({where}) averages {mean_a:.3g} m/s^2 "
            f"over the hover at {h:.2f} m, where a vehicle holding its height averages 0; "
            f"expected the kinematic acceleration, without gravity (is g = {g:g} m/s^2 "
            "counted in it, or removed twice?)")
    total = thrusts[mask].sum(axis=1) * cos_tilt     # what carries the weight: the vertical
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


def _hover_tilt(log, mask, h):
    """cos(roll) cos(pitch) over the hover (ones without both angles); refuse a hover
    tilted beyond ``MAX_HOVER_TILT`` (upside down: a frame with z down read as z up)."""
    if not (log.has("roll") and log.has("pitch")):
        return np.ones(int(mask.sum()))
    phi, theta = log.signal("roll")[mask], log.signal("pitch")[mask]
    cos_tilt = np.cos(phi) * np.cos(theta)
    tilt = float(np.degrees(np.arccos(np.clip(np.median(cos_tilt), -1.0, 1.0))))
    if tilt > np.degrees(MAX_HOVER_TILT):
        upside = " (upside down: angles in degrees, or of a frame with z down read as z up?)" \
            if tilt > 90.0 else ""
        raise IdentificationError(
            f"{log.source}: over the hover at {h:.2f} m {column_name(log, 'roll')} and "
            f"{column_name(log, 'pitch')} tilt the vehicle {tilt:.3g} deg (median), where its "
            f"rotors cannot hold its height{upside}; expected a hover within "
            f"{np.degrees(MAX_HOVER_TILT):g} deg of level (quadcog reads ZYX angles in rad, "
            "body z up)")
    return cos_tilt


def _saturation(log, vehicle, mask, h):
    """A motor output at full scale over most of the hover: the thrust beyond the limit is
    unknown, so no balance holds (and a vehicle at full thrust is not hovering). Without
    motor outputs, the commands the firmware's mixer makes of thrust_command and
    moment_command (``segments.commands_from_mixer``) are checked."""
    outputs = [(log.signal(name)[mask], lambda j, name=name: column_name(log, name, j))
               for name in ("motor_pwm", "motor_command") if log.has(name)]
    if not outputs and log.has("thrust_command") and log.has("moment_command"):
        outputs = [(commands_from_mixer(log, vehicle)[mask], lambda j: (
            f"the command of rotor {j + 1} that thrust_command and moment_command give "
            "through the mixer"))]
    for u, name_of in outputs:
        at_top = (u >= SATURATED).mean(axis=0)
        j = int(np.argmax(at_top))
        if at_top[j] > SATURATED_FRACTION:
            raise IdentificationError(
                f"{log.source}: {name_of(j)} is at full scale (>= "
                f"{SATURATED:g}) over {100 * float(at_top[j]):.3g} % of the hover at {h:.2f} m: "
                "the motor is saturated, so its thrust is not known and the vehicle is not "
                "hovering on it; expected outputs below full scale (a log of a flight that "
                "held its height)")


def _thrust_ceiling(log, mask, thrusts, model, h):
    """A rotor at the largest thrust its model gives (full output at the highest battery
    voltage; a voltage fit saturates beyond its parabola's vertex) over most of the hover:
    its thrust is not known, and rotors all at that ceiling read as a CoG at O with no
    spread (a battery voltage in other units puts every rotor there)."""
    top = float(model.thrust(np.ones((1, 4)), MAX_BATTERY_VOLTAGE if model.uses_voltage
                             else None)[0, 0])
    at_top = (thrusts[mask] >= top * (1.0 - 1e-9)).mean(axis=0)
    j = int(np.argmax(at_top))
    if top > 0 and at_top[j] > SATURATED_FRACTION:
        volts = (f": is the battery voltage in other units? ({column_name(log, 'battery_voltage')} "
                 f"is {float(np.median(log.signal('battery_voltage')[mask])):.3g} V, median)"
                 if model.uses_voltage and log.has("battery_voltage") else "")
        raise IdentificationError(
            f"{log.source}: rotor {j + 1} gives the largest thrust of rotor model "
            f"{model.name!r} ({top:.4g} N) over {100 * float(at_top[j]):.3g} % of the hover at "
            f"{h:.2f} m, beyond the range of its fit, so its thrust is not known; expected "
            f"thrusts below the model's largest{volts}")


def _yaw_balance(log, vehicle, mask, thrusts, h):
    """The rotors spinning one way against the others: their reaction moment turns the
    vehicle in yaw unless they balance (a hover holds its heading)."""
    f = thrusts[mask]
    total = float(f.sum(axis=1).mean())
    if not total > 0:
        return
    d = np.asarray(vehicle.rotor_directions, float)
    share = float((f @ d).mean()) / total
    if abs(share) > YAW_IMBALANCE:
        one = float((f[:, d > 0].sum(axis=1)).mean()) / total
        alpha = abs(share) * total * vehicle.moment_constant / vehicle.Izz
        raise IdentificationError(
            f"{log.source}: over the hover at {h:.2f} m the rotors spinning one way carry "
            f"{100 * one:.3g} % of the thrust and the others {100 * (1 - one):.3g} %: their "
            f"reaction moment would turn {vehicle.name!r} in yaw at {alpha:.3g} rad/s^2; a "
            f"hover balances them (expected within {100 * YAW_IMBALANCE:g} % of the thrust): "
            "are the motor outputs in the vehicle's rotor order, or a motor's output missing?")


def _velocity_agrees_with_position(log, mask):
    """The velocity integrated over ``VELOCITY_SECONDS`` against the position's change over
    the hover: a velocity in mm/s, or in another frame, moves the vehicle elsewhere."""
    t, p, v = log.t[mask], log.signal("position")[mask], log.signal("velocity")[mask]
    h = np.diff(t)
    if not len(h):
        return
    moved = np.vstack([np.zeros(3), np.cumsum(0.5 * (v[1:] + v[:-1]) * h[:, None], axis=0)])
    n = max(int(round(VELOCITY_SECONDS / float(np.median(h)))), 1)
    if len(t) <= n:
        return
    contiguous = (t[n:] - t[:-n]) < 2 * VELOCITY_SECONDS
    dv, dp = (moved[n:] - moved[:-n])[contiguous], (p[n:] - p[:-n])[contiguous]
    if not len(dv):
        return
    excess = np.abs(dv - dp) - (VELOCITY_TOLERANCE[0] + VELOCITY_TOLERANCE[1] * np.abs(dp))
    k, j = (int(i) for i in np.unravel_index(int(np.argmax(excess)), excess.shape))
    if excess[k, j] > 0:
        raise IdentificationError(
            f"{log.source}: {column_name(log, 'velocity', j)} integrated over "
            f"{VELOCITY_SECONDS:g} s moves the vehicle {float(dv[k, j]):.3g} m where "
            f"{column_name(log, 'position', j)} moves {float(dp[k, j]):.3g} m (expected within "
            f"{VELOCITY_TOLERANCE[0]:g} m + {100 * VELOCITY_TOLERANCE[1]:g} %): is the velocity "
            "in mm/s or in another frame? (quadcog reads m/s, ground frame z up)")


def _acceleration_agrees(log, mask, a_z, h, g):
    """The logged vertical acceleration averaged over the hover against the change of the
    vertical velocity (logged, else of the position): an accelerometer in g, or with a
    bias, reads a climb that the height does not show."""
    t = log.t
    if log.has("velocity"):
        vz, source = log.signal("velocity")[:, 2], column_name(log, "velocity", 2)
    else:
        vz, source = np.gradient(log.signal("position")[:, 2], t), \
            f"the derivative of {column_name(log, 'position', 2)}"
    change = float(np.mean(np.gradient(vz, t)[mask]))
    mean_a = float(np.mean(a_z[mask]))
    if abs(mean_a - change) > ACCEL_AGREE * g and abs(mean_a) <= GRAVITY_FRACTION * g:
        raise IdentificationError(
            f"{log.source}: the vertical acceleration ({column_name(log, 'acceleration', 2)}) "
            f"averages {mean_a:.3g} m/s^2 over the hover at {h:.2f} m, while {source} changes "
            f"at {change:.3g} m/s^2 on average (expected to agree within "
            f"{ACCEL_AGREE * g:.3g} m/s^2): is the acceleration in g, or biased? (quadcog reads "
            "the kinematic acceleration in m/s^2, without gravity)")


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
    none (also a ULog that quadcog wrote from a log naming no vehicle).

    Parameters
    ----------
    log : FlightLog
        One flight.

    Returns
    -------
    str or None
        Lower case.

    Raises
    ------
    IdentificationError
        ``log`` not a FlightLog.
    """
    check_arguments("vehicle_type", log)
    if log.format == "crazyflie-usd":
        return "crazyflie"
    if (log.format == "ulog" and log.meta.get("ver_hw") == WRITER_HW
            and log.meta.get("vehicle") == WRITER_NAME):
        return None          # written by quadcog from a log that named no vehicle
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
        Naming the two logs and their types; arguments of the wrong type (a vehicle that is
        no Vehicle was ignored).
    """
    for arg, value in (("logs", logs), ("baseline", baseline)):
        if isinstance(value, (str, bytes)) or not isinstance(value, Sequence):
            fail(f"check_types: {arg}", "a sequence of quadcog.logs.FlightLog", value,
                 IdentificationError)
    if vehicle is not None and not isinstance(vehicle, Vehicle):
        fail("check_types: vehicle", "a quadcog Vehicle or None", vehicle, IdentificationError)
    for arg, value in (("logs", logs), ("baseline", baseline)):
        for i, item in enumerate(value):
            if not isinstance(item, FlightLog):
                fail(f"check_types: {arg}[{i}]", "a quadcog.logs.FlightLog", item,
                     IdentificationError)
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
