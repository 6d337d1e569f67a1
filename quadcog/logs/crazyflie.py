"""The Crazyflie uSD-deck binary log (``"crazyflie-usd"``): reader and writer.

Format (Bitcraze crazyflie-firmware, ``src/deck/drivers/src/usddeck.c``, the writer; and its
decoder ``tools/usdlog/cfusdlog.py``), little-endian throughout:

- header: magic byte ``0xBC``; ``uint16`` version (1 or 2); ``uint16`` number of event
  types; per event type: ``uint16`` event id (``0xFFFF`` is the fixed-frequency log),
  its name (NUL-terminated), ``uint16`` number of variables, and each variable as the
  NUL-terminated text ``group.name(T)`` with the type character ``T`` of Python's struct
  module (``B b H h I i f``, and ``e`` for a half float);
- records: ``uint16`` event id, the time stamp (version 1: ``uint32`` ms; version 2:
  ``uint64`` us since boot), then the event's variables packed in header order;
- the file ends with the CRC-32 (zlib's, ``uint32``) of every byte before it.

Time base: the records of the fixed-frequency event, id ``0xFFFF`` (named
``fixedFrequency``: the logging at the configured rate, e.g. 100 Hz synchronous with the
stabilizer), at their own time stamps, shifted to start at 0 (``meta["time_origin_us"]``).
Records are not resampled or filled: the log is event based, so a record dropped by the
firmware (its buffer full) is a longer step, reported in ``meta["max_step_s"]``. Other event
types are not on that time base: their record counts are in ``meta["events"]``.

Values no firmware logs are refused, named with their record: a variable that is not
finite, a motor variable (``MOTOR_VARIABLES``) outside 0..65535 (the outputs are 16-bit
whatever type the header declares), a motor request (``MOTOR_REQUEST_VARIABLES``) beyond an
int32, ``controller.cmd_thrust`` outside 0..65535 (the thrust the firmware caps at
UINT16_MAX), ``controller.cmd_roll, cmd_pitch, cmd_yaw`` beyond +-``MOMENT_COMMAND_MAX``
(the int16 of the firmware's ``control_t``), a body rate (``gyro.*`` in deg/s,
``controller.r_*`` in rad/s) beyond ``quadcog.logs.limits.BODY_RATE_MAX_DEG_S``, a battery
voltage (``pm.vbat``, ``pm.vbatMV``) outside 0..``VBAT_MAX_V``, a roll or pitch beyond
+-180 deg, a yaw beyond +-``YAW_MAX_DEG`` (``_limits`` has them all; the writer refuses the
same values before writing).

Conversions to quadcog's signals (the firmware's ground frame is z up and its body frame x
forward, y left, z up, as quadcog's):

- ``stateEstimate.x, y, z`` (m), ``vx, vy, vz`` (m/s): position and velocity as they are;
- ``stateEstimate.ax, ay, az`` (g; ``az`` without gravity, i.e. the world-frame specific
  force minus 1 g): times ``GRAVITY`` = 9.81 m/s^2 (the firmware's ``GRAVITY_MAGNITUDE``)
  is the kinematic acceleration;
- ``stateEstimate.roll``, ``yaw`` (deg): the ZYX angles phi and psi; ``stateEstimate.pitch``
  (deg) is logged with the inverted sign of the "legacy CF2 body coordinate system"
  (``kalman_core.c``: ``.pitch = -pitch``), so ``pitch = -stateEstimate.pitch``;
- body rates: ``gyro.x, y, z`` (deg/s, body frame) when logged, else ``controller.r_roll,
  r_pitch, r_yaw`` (rad/s; ``controller_pid.c`` logs ``r_pitch = -radians(gyro.y)``, so
  ``q = -r_pitch``);
- ``motor.m1..m4`` (0..65535): in firmware that logs ``pwm.*`` (before 2022-11, ``motor.m*``
  of type ``I``) the motor power requested by the power distribution before battery
  compensation -> ``motor_command``; ``pwm.m1_pwm..m4_pwm`` the duty cycle after it ->
  ``motor_pwm``. In later firmware ``motor.m*`` (type ``H``) is the applied duty cycle
  (``motor_pwm``) and ``motor.m1req..m4req`` the request (``motor_command``). The firmware's
  M1..M4 (front-right, back-right, back-left, front-left; checked against its power
  distribution) are quadcog's rotors 1..4;
- ``pm.vbatMV`` (mV) or ``pm.vbat`` (V): ``battery_voltage``;
- ``controller.cmd_thrust`` (0..65535 scale): ``thrust_command`` = cmd_thrust / 65535;
  ``controller.cmd_roll, cmd_pitch, cmd_yaw``: the legacy mixer gives M1 = T - r + p + y,
  M2 = T - r - p - y, M3 = T + r - p + y, M4 = T + r + p - y with r = cmd_roll / 2,
  p = cmd_pitch / 2, y = cmd_yaw, so ``moment_command`` = [cmd_roll / 2, -cmd_pitch / 2,
  -cmd_yaw] / 65535 in quadcog's signs.
"""
import os
from pathlib import Path
import struct
import zlib

import numpy as np

from quadcog.errors import LogCRCError, LogError, LogFormatError, LogSignalError
from quadcog.files import atomic_write_bytes
from quadcog.logs.access import log_path, read_bytes, writer_path
from quadcog.logs.flightlog import FlightLog
from quadcog.logs.limits import BODY_RATE_MAX_DEG_S, check_range, microsecond_ticks

__all__ = ["read_usd", "write_usd", "parse_usd", "GRAVITY", "FULL_SCALE",
           "FIXED_FREQUENCY_ID"]

GRAVITY = 9.81                 # m/s^2 per g: the firmware's GRAVITY_MAGNITUDE
FULL_SCALE = 65535.0           # motor power and PWM: 0..UINT16_MAX
FIXED_FREQUENCY_ID = 0xFFFF
FIXED_FREQUENCY_NAME = "fixedFrequency"
_MAGIC = 0xBC
_TYPES = {"B": "<u1", "b": "<i1", "H": "<u2", "h": "<i2", "I": "<u4", "i": "<i4",
          "f": "<f4", "e": "<f2"}
_STAMP = {1: ("<u4", 1e-3), 2: ("<u8", 1e-6)}          # version: (dtype, s per tick)
_DEG = np.pi / 180.0
_RESERVED = ("_id", "_tick")          # the fields of every record before its variables
# The motor variables: the firmware's 16-bit outputs (motor power capped by the power
# distribution, or PWM duty cycle: 0..FULL_SCALE), whatever type a log declares them in
# (type I holds up to 2^32 - 1)
MOTOR_VARIABLES = tuple([f"motor.m{k}" for k in range(1, 5)]
                        + [f"pwm.m{k}_pwm" for k in range(1, 5)])
# The requests before the cap (stabilizer.c: motorThrustBatCompUncapped, logged as int32):
# beyond 0..FULL_SCALE when saturated, never beyond an int32
MOTOR_REQUEST_VARIABLES = tuple(f"motor.m{k}req" for k in range(1, 5))
_INT32 = (-2.0 ** 31, 2.0 ** 31 - 1)
# controller.cmd_roll, cmd_pitch, cmd_yaw: the firmware's control_t holds the moment commands
# as int16 (stabilizer_types.h; controller_pid.c logs them as floats, cmd_yaw negated, so
# -32767..32768): beyond +-2^15 no firmware logs them
MOMENT_COMMAND_VARIABLES = ("controller.cmd_roll", "controller.cmd_pitch", "controller.cmd_yaw")
MOMENT_COMMAND_MAX = 2.0 ** 15
# the body rates: the gyroscope in deg/s, or the controller's copy in rad/s
GYRO_VARIABLES = ("gyro.x", "gyro.y", "gyro.z")
RATE_VARIABLES = ("controller.r_roll", "controller.r_pitch", "controller.r_yaw")
# V: the most the battery voltage pm.vbatMV (a uint16 of mV) holds; pm.vbat (V) likewise
VBAT_MAX_V = 65.535
# |roll|, |pitch| (deg): the firmware's estimators give atan2/asin angles, within 180 deg
ROLL_PITCH_MAX_DEG = 180.0
# |yaw| (deg): the firmware's is within 180 deg, but a yaw written unwrapped (quadcog's
# writer keeps a log's own yaw) is read and wrapped; up to 1e5 deg (278 turns) float32
# still resolves it to 0.01 deg, beyond that wrapping would give rounding noise
YAW_MAX_DEG = 1e5
# float32 rounding of an angle at its limit (atan2f can return pi as 3.1415927 > pi)
ANGLE_ROUNDING_DEG = 1e-3


def _cstring(data, i, path, what):
    end = data.find(b"\x00", i)
    if end < 0:
        raise LogFormatError(f"{path}: truncated header: {what} at byte {i} has no NUL end")
    try:
        return data[i:end].decode("ascii"), end + 1
    except UnicodeDecodeError:
        raise LogFormatError(f"{path}: {what} at byte {i} is not ASCII text: "
                             f"{data[i:end][:40]!r}") from None


def parse_usd(path: str | os.PathLike) -> tuple[int, dict]:
    """Decode a Crazyflie uSD log into its events, checking the magic byte and the CRC-32.

    Parameters
    ----------
    path : str or os.PathLike
        The log file.

    Returns
    -------
    version : int
        The format version (1 or 2).
    events : dict
        ``{event name: (ticks, {variable name: array})}`` with ``ticks`` the records' time
        stamps in seconds since boot (float64) and the variables in their logged types.

    Raises
    ------
    LogFormatError
        Not a uSD log (magic byte), an unknown version or type, a truncated header or
        record, a record of an event the header does not declare, two event types with one
        id or one name.
    LogCRCError
        The stored CRC-32 differs from the content's.
    LogError
        ``path`` not a path (a str or os.PathLike naming a file), or a file that cannot be
        read.
    """
    version, events = _parse(log_path(path, "parse_usd: path"))
    return version, {name: (ticks, variables) for name, ticks, variables in events.values()}


def _parse(file: Path) -> tuple[int, dict[int, tuple[str, np.ndarray, dict[str, np.ndarray]]]]:
    """``parse_usd`` keyed by event id: (version, {id: (name, ticks, variables)})."""
    data = read_bytes(file)
    path = str(file)
    if len(data) < 9:
        raise LogFormatError(f"{path}: {len(data)} bytes: too short for a Crazyflie uSD log "
                             "(magic, version, event count and CRC take 9)")
    if data[0] != _MAGIC:
        raise LogFormatError(f"{path}: first byte 0x{data[0]:02x}; a Crazyflie uSD log "
                             f"starts with 0x{_MAGIC:02X}")
    stored, = struct.unpack_from("<I", data, len(data) - 4)
    found = zlib.crc32(data[:-4]) & 0xFFFFFFFF
    if stored != found:
        raise LogCRCError(path, stored, found)
    version, n_events = struct.unpack_from("<HH", data, 1)
    if version not in _STAMP:
        raise LogFormatError(f"{path}: format version {version}; expected 1 or 2")
    end = len(data) - 4
    i = 5
    layouts: dict[int, tuple[str, np.dtype]] = {}
    ids: dict[str, int] = {}          # event name -> its id
    for k in range(n_events):
        if i + 2 > end:
            raise LogFormatError(f"{path}: truncated header: event type {k + 1} of "
                                 f"{n_events} missing")
        event_id, = struct.unpack_from("<H", data, i)
        name, i = _cstring(data, i + 2, path, f"the name of event type {k + 1}")
        if i + 2 > end:
            raise LogFormatError(f"{path}: truncated header in event {name!r}")
        n_vars, = struct.unpack_from("<H", data, i)
        i += 2
        fields = []
        for _ in range(n_vars):
            spec, i = _cstring(data, i, path, f"a variable of event {name!r}")
            if len(spec) < 4 or spec[-3] != "(" or spec[-1] != ")" or spec[-2] not in _TYPES:
                raise LogFormatError(f"{path}: event {name!r}: variable {spec!r} is not "
                                     f"'name(T)' with T one of {''.join(_TYPES)}")
            fields.append((spec[:-3], _TYPES[spec[-2]]))
        if event_id in layouts:
            raise LogFormatError(f"{path}: event id 0x{event_id:04X} declared twice (event "
                                 f"types {layouts[event_id][0]!r} and {name!r}); expected one "
                                 "event type per id")
        if name in ids:             # events are known by name: the second would hide the first
            raise LogFormatError(f"{path}: event name {name!r} declared twice (ids "
                                 f"0x{ids[name]:04X} and 0x{event_id:04X}); expected one event "
                                 "type per name")
        ids[name] = event_id
        names = [f for f, _ in fields]
        reserved = [f for f in names if f in _RESERVED]
        if reserved:
            raise LogFormatError(f"{path}: event {name!r} has a variable named {reserved[0]!r}; "
                                 f"a Crazyflie variable is 'group.name' (the names "
                                 f"{', '.join(_RESERVED)} are the record's own fields)")
        if len(set(names)) != len(names):
            raise LogFormatError(f"{path}: event {name!r} repeats a variable: {names}")
        stamp = _STAMP[version][0]
        dtype = np.dtype([("_id", "<u2"), ("_tick", stamp)] + fields)
        layouts[event_id] = (name, dtype)
    # Records: find where each starts (only the event id is read here), then gather each
    # event's records at once.
    starts: dict[int, list[int]] = {e: [] for e in layouts}
    while i < end:
        if i + 2 > end:
            raise LogFormatError(f"{path}: truncated record at byte {i} (before the CRC)")
        event_id = data[i] | (data[i + 1] << 8)
        if event_id not in layouts:
            raise LogFormatError(f"{path}: record at byte {i} has event id {event_id}, which "
                                 f"the header does not declare ({sorted(layouts)})")
        size = layouts[event_id][1].itemsize
        if i + size > end:
            raise LogFormatError(f"{path}: truncated record of event "
                                 f"{layouts[event_id][0]!r} at byte {i}: {end - i} of {size} "
                                 "bytes before the CRC")
        starts[event_id].append(i)
        i += size
    raw = np.frombuffer(data, dtype=np.uint8)
    events = {}
    for event_id, (name, dtype) in layouts.items():
        at = np.asarray(starts[event_id], dtype=np.int64)
        # each record's bytes, through a window view of the file (no copy): one copy of the
        # records in all (an index array per byte took 8 times the file)
        block = np.lib.stride_tricks.sliding_window_view(raw, dtype.itemsize)[at] \
            if at.size else np.zeros((0, dtype.itemsize), np.uint8)
        rec = np.ascontiguousarray(block).view(dtype).reshape(-1)
        ticks = rec["_tick"].astype(np.float64) * _STAMP[version][1]
        # a structured dtype always has names
        events[event_id] = (name, ticks,
                            {f: rec[f] for f in dtype.names[2:]})  # type: ignore[index]
    return version, events


def _limits(var):
    """(lo, hi, what, unit) the values of a variable the reader converts must lie within
    (the firmware's own range, without float32 rounding), or None when the reader does not
    bound it. ``what`` is said by the reader, ``unit`` by the writer."""
    if var in MOTOR_VARIABLES:
        return 0.0, FULL_SCALE, "the firmware's 16-bit motor output", "16-bit"
    if var in MOTOR_REQUEST_VARIABLES:
        return *_INT32, "the firmware's int32 motor request", "int32"
    if var == "controller.cmd_thrust":
        return 0.0, FULL_SCALE, "the firmware's thrust command (capped at UINT16_MAX)", \
            "16-bit thrust command"
    if var in MOMENT_COMMAND_VARIABLES:
        return (-MOMENT_COMMAND_MAX, MOMENT_COMMAND_MAX,
                "the firmware's int16 moment command", "int16")
    if var in GYRO_VARIABLES:
        return (-BODY_RATE_MAX_DEG_S, BODY_RATE_MAX_DEG_S,
                "a gyroscope's rate (deg/s; the largest full scale in use)", "deg/s")
    if var in RATE_VARIABLES:
        w = float(np.radians(BODY_RATE_MAX_DEG_S))
        return -w, w, "a gyroscope's rate (rad/s; the largest full scale in use)", "rad/s"
    if var == "pm.vbat":
        return 0.0, VBAT_MAX_V, "a battery voltage (V)", "V"
    if var == "pm.vbatMV":
        return 0.0, VBAT_MAX_V * 1e3, "a battery voltage (mV)", "mV"
    angle = var.removeprefix("stateEstimate.")
    if angle in ("roll", "pitch"):
        return -ROLL_PITCH_MAX_DEG, ROLL_PITCH_MAX_DEG, f"a {angle} angle (deg)", "deg"
    if angle == "yaw":
        return -YAW_MAX_DEG, YAW_MAX_DEG, "a yaw angle (deg) that float32 resolves", "deg"
    return None


def _check_limits(path, event, ticks, raw):
    """Refuse a variable outside its ``_limits`` (motor outputs beyond 16 bits, attitudes
    beyond any orientation), naming it, its value, record and time."""
    for var, v in raw.items():
        limits = _limits(var)
        if limits is None:
            continue
        lo, hi, what, unit = limits
        if unit == "deg":             # an angle: atan2f can return pi as 3.1415927 > pi
            lo, hi = lo - ANGLE_ROUNDING_DEG, hi + ANGLE_ROUNDING_DEG
        bad = (v < lo) | (v > hi)
        if bad.any():
            k = int(np.argmax(bad))
            raise LogFormatError(f"{path}: variable {var!r} of event {event!r} is "
                                 f"{float(v[k])!r} in record {k} (t = "
                                 f"{float(ticks[k] - ticks[0])!r} s); expected {what} within "
                                 f"{lo:g}..{hi:g}")


def _pick(raw, *groups):
    """The first group of variable names that are all logged, or None."""
    for names in groups:
        if all(n in raw for n in names):
            return names
    return None


def _signals(raw, types):
    """The standard signals of a fixed-frequency event's variables (float64 arrays)."""
    s = {}
    for name, v in (("position", ("x", "y", "z")), ("velocity", ("vx", "vy", "vz"))):
        names = _pick(raw, [f"stateEstimate.{c}" for c in v])
        if names:
            s[name] = np.column_stack([raw[n] for n in names])
    names = _pick(raw, [f"stateEstimate.{c}" for c in ("ax", "ay", "az")])
    if names:
        s["acceleration"] = np.column_stack([raw[n] for n in names]) * GRAVITY
    for angle, sign in (("roll", 1.0), ("pitch", -1.0), ("yaw", 1.0)):
        if f"stateEstimate.{angle}" in raw:
            s[angle] = sign * raw[f"stateEstimate.{angle}"] * _DEG
    if "yaw" in s:
        s["yaw"] = np.angle(np.exp(1j * s["yaw"]))        # (-pi, pi]
    names = _pick(raw, ["gyro.x", "gyro.y", "gyro.z"])
    if names:
        s["body_rates"] = np.column_stack([raw[n] for n in names]) * _DEG
    elif _pick(raw, ["controller.r_roll", "controller.r_pitch", "controller.r_yaw"]):
        s["body_rates"] = np.column_stack([raw["controller.r_roll"], -raw["controller.r_pitch"],
                                           raw["controller.r_yaw"]])
    motors = [f"motor.m{k}" for k in range(1, 5)]
    pwm = _pick(raw, [f"pwm.m{k}_pwm" for k in range(1, 5)])
    requests = _pick(raw, [f"motor.m{k}req" for k in range(1, 5)])
    if pwm:
        s["motor_pwm"] = np.column_stack([raw[n] for n in pwm]) / FULL_SCALE
        if _pick(raw, motors):
            s["motor_command"] = np.column_stack([raw[n] for n in motors]) / FULL_SCALE
    elif _pick(raw, motors) and types.get("motor.m1") != "<u4":
        s["motor_pwm"] = np.column_stack([raw[n] for n in motors]) / FULL_SCALE
    elif _pick(raw, motors):
        s["motor_command"] = np.column_stack([raw[n] for n in motors]) / FULL_SCALE
    if requests:
        s["motor_command"] = np.column_stack([raw[n] for n in requests]) / FULL_SCALE
    if "pm.vbatMV" in raw:
        s["battery_voltage"] = raw["pm.vbatMV"] * 1e-3
    elif "pm.vbat" in raw:
        s["battery_voltage"] = raw["pm.vbat"].copy()
    if "controller.cmd_thrust" in raw:
        s["thrust_command"] = raw["controller.cmd_thrust"] / FULL_SCALE
    if _pick(raw, ["controller.cmd_roll", "controller.cmd_pitch", "controller.cmd_yaw"]):
        s["moment_command"] = np.column_stack([raw["controller.cmd_roll"] / 2,
                                               -raw["controller.cmd_pitch"] / 2,
                                               -raw["controller.cmd_yaw"]]) / FULL_SCALE
    return s


def read_usd(path: str | os.PathLike) -> FlightLog:
    """Read a Crazyflie uSD log (see the module docstring for the format and conversions).

    Parameters
    ----------
    path : str or os.PathLike
        The log file.

    Returns
    -------
    FlightLog
        Format ``"crazyflie-usd"``; ``raw`` holds every variable of the fixed-frequency event
        under its logged name (``"motor.m1"``, ``"stateEstimate.roll"``), in its logged
        units; ``meta`` the version, rate and steps of the time base, and the other events.

    Raises
    ------
    LogFormatError
        See ``parse_usd``; also fewer than 2 fixed-frequency records (id ``0xFFFF``), time
        stamps that do not increase, a variable that is not finite (NaN, inf), or one
        beyond what the firmware logs (module docstring: motor outputs and requests, thrust
        and moment commands, body rates, battery voltage, angles; the angles' limits plus
        float32 rounding, ``ANGLE_ROUNDING_DEG``).
    LogCRCError
        The CRC-32 does not match.
    LogError
        ``path`` not a path, or a file that cannot be read.
    """
    file = log_path(path, "read_usd: path")
    path = str(file)
    version, events = _parse(file)
    # the time base is the event of id 0xFFFF, whatever its name (the firmware's is
    # FIXED_FREQUENCY_NAME; parse_usd has refused two events of one name or one id)
    name, ticks, variables = events.get(FIXED_FREQUENCY_ID, (FIXED_FREQUENCY_NAME, None, {}))
    if ticks is None or ticks.size < 2:
        counts = {n: v.size for n, v, _ in events.values()}      # names are unique
        raise LogFormatError(f"{path}: fewer than 2 '{FIXED_FREQUENCY_NAME}' records (event "
                             f"id 0x{FIXED_FREQUENCY_ID:04X}), the time base of the signals; "
                             f"the events hold {counts}")
    steps = np.diff(ticks)
    if not (steps > 0).all():
        k = int(np.argmax(steps <= 0))
        raise LogFormatError(f"{path}: fixed-frequency record {k + 1} has time stamp "
                             f"{float(ticks[k + 1])!r} s after {float(ticks[k])!r} s; "
                             "expected increasing")
    types = {k: v.dtype.str for k, v in variables.items()}
    with np.errstate(invalid="ignore"):     # a signalling NaN: refused below, by name
        raw = {k: v.astype(np.float64) for k, v in variables.items()}
    for var, v in raw.items():      # before any conversion: named as logged, inf as inf
        bad = ~np.isfinite(v)
        if bad.any():
            k = int(np.argmax(bad))
            raise LogFormatError(f"{path}: variable {var!r} of event {name!r} is "
                                 f"{float(v[k])!r} in record {k} (t = "
                                 f"{float(ticks[k] - ticks[0])!r} s); expected finite values")
    _check_limits(path, name, ticks, raw)
    median = float(np.median(steps))
    others = ", ".join(f"{n}: {v.size} records" for e, (n, v, _) in events.items()
                       if e != FIXED_FREQUENCY_ID)
    meta = {"vehicle": "Crazyflie", "usd_version": str(version),
            "time_origin_us": str(int(round(ticks[0] * 1e6))),
            "rate_hz": f"{1.0 / median:.6g}", "median_step_s": repr(median),
            "max_step_s": repr(float(steps.max())), "events": others or "none",
            "variables": ", ".join(variables)}
    return FlightLog(path, "crazyflie-usd", ticks - ticks[0], _signals(raw, types), raw, meta)


def _variables(log):
    """The raw variables (name, struct type, values) a Crazyflie log of ``log`` carries."""
    s = log.signals
    out = []

    def add(names, typ, values):
        values = np.asarray(values, dtype=np.float64).reshape(log.n_samples, -1)
        out.extend((n, typ, values[:, j]) for j, n in enumerate(names))

    if "motor_command" in s:
        add([f"motor.m{k}" for k in range(1, 5)], "I", s["motor_command"] * FULL_SCALE)
    if "motor_pwm" in s:
        add([f"pwm.m{k}_pwm" for k in range(1, 5)], "I", s["motor_pwm"] * FULL_SCALE)
    if "battery_voltage" in s:
        add(["pm.vbatMV"], "H", s["battery_voltage"] * 1e3)
    for name, v in (("position", ("x", "y", "z")), ("velocity", ("vx", "vy", "vz"))):
        if name in s:
            add([f"stateEstimate.{c}" for c in v], "f", s[name])
    if "acceleration" in s:
        add([f"stateEstimate.{c}" for c in ("ax", "ay", "az")], "f", s["acceleration"] / GRAVITY)
    for angle, sign in (("roll", 1.0), ("pitch", -1.0), ("yaw", 1.0)):
        if angle in s:
            add([f"stateEstimate.{angle}"], "f", sign * s[angle] / _DEG)
    if "body_rates" in s:
        p, q, r = s["body_rates"].T
        add(["controller.r_roll", "controller.r_pitch", "controller.r_yaw"], "f",
            np.column_stack([p, -q, r]))
    if "thrust_command" in s:
        add(["controller.cmd_thrust"], "f", s["thrust_command"] * FULL_SCALE)
    if "moment_command" in s:
        mx, my, mz = (s["moment_command"] * FULL_SCALE).T
        add(["controller.cmd_roll", "controller.cmd_pitch", "controller.cmd_yaw"], "f",
            np.column_stack([2 * mx, -2 * my, -mz]))
    return out


def write_usd(log: FlightLog, path: str | os.PathLike) -> Path:
    """Write a log's signals as a Crazyflie uSD log (version 2) that ``read_usd`` reads back.

    The variables are the firmware's, in its units and signs (the inverse of the reader's
    conversions): ``motor.m*`` and ``pwm.m*_pwm`` as integers 0..65535 (type ``I``),
    ``pm.vbatMV`` in integer mV, ``stateEstimate.*`` and ``controller.*`` as float32; one
    ``fixedFrequency`` record per sample, time stamps in integer us from 0. (The firmware
    logs at most 20 variables per event; this writer does not impose that limit.)

    Parameters
    ----------
    log : FlightLog
        The log to write.
    path : str or os.PathLike
        The file (replaced if it exists).

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    LogSignalError
        The log has none of the signals a Crazyflie log carries, a motor value outside
        0..1 or a voltage outside 0..65.535 V (the integer fields cannot hold it), or a value
        the reader refuses (``_limits``: a thrust command outside 0..1, a moment command
        beyond the int16 of the firmware, a body rate beyond ``BODY_RATE_MAX_DEG_S``, a roll
        or pitch beyond ``ROLL_PITCH_MAX_DEG``, a yaw beyond ``YAW_MAX_DEG``).
    LogError
        ``log`` not a FlightLog, ``path`` not a file that may be replaced.
    """
    path = writer_path(log, path, "write_usd")
    variables = _variables(log)
    if not variables:
        raise LogSignalError(f"{log.source}: no signal a Crazyflie log carries (it has "
                             f"{', '.join(log.signals) or 'none'})", source=log.source,
                             available=tuple(log.signals))
    ticks = microsecond_ticks(log, 0, "Crazyflie")
    fields = [("_id", "<u2"), ("_tick", "<u8")]
    columns = []
    for name, typ, values in variables:
        if typ in "IH":
            values = np.round(values)
            hi = np.iinfo(_TYPES[typ]).max if typ == "H" else FULL_SCALE
            if values.min() < 0 or values.max() > hi:
                raise LogSignalError(
                    f"{log.source}: {name} would be {values.min():g}..{values.max():g}, "
                    f"outside the 0..{hi:g} the Crazyflie logs", source=log.source)
        else:
            check_range(log, name, values, "Crazyflie")        # float32 holds it
            limits = _limits(name)
            if limits is not None:      # the reader's limits, on the float32 it will read
                lo, hi, _, unit = limits
                check_range(log, name, values.astype(np.float32), "Crazyflie", lo, hi, unit)
        fields.append((name, _TYPES[typ]))
        columns.append(values)
    rec = np.zeros(log.n_samples, dtype=np.dtype(fields))
    rec["_id"] = FIXED_FREQUENCY_ID
    rec["_tick"] = ticks
    for (name, _, _), values in zip(variables, columns):
        rec[name] = values
    header = bytearray(struct.pack("<BHH", _MAGIC, 2, 1))
    header += struct.pack("<H", FIXED_FREQUENCY_ID) + FIXED_FREQUENCY_NAME.encode() + b"\x00"
    header += struct.pack("<H", len(variables))
    for name, typ, _ in variables:
        header += f"{name}({typ})".encode() + b"\x00"
    body = bytes(header) + rec.tobytes()
    atomic_write_bytes(path, body + struct.pack("<I", zlib.crc32(body) & 0xFFFFFFFF),
                       "write_log path", LogError)
    return path
