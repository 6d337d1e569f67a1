"""PX4 ULog flight logs (``"ulog"``): a reader through pyulog and a minimal writer.

Topics read (instance 0 of each), their fields and the conversions to quadcog's signals.
PX4's ground frame is NED and its body frame FRD; both become z-up frames by the rotation
``T = diag(1, -1, -1)`` (a half turn about x): NED -> x north, y west, z up; FRD -> FLU.

- ``vehicle_local_position``: ``x, y, z``, ``vx, vy, vz``, ``ax, ay, az`` (NED, m, m/s,
  m/s^2; ``a`` is the kinematic acceleration, without gravity) -> ``position``,
  ``velocity``, ``acceleration`` = ``T @ v``, i.e. ``[x, -y, -z]``;
- ``vehicle_attitude``: ``q[0..3]`` = (w, x, y, z), the rotation FRD body -> NED. The
  rotation between quadcog's frames is ``R = T R_px4 T``, whose quaternion is
  ``(w, x, -y, -z)``; its ZYX angles are ``roll = phi_px4``, ``pitch = -theta_px4``,
  ``yaw = -psi_px4`` (tests/test_logs_ulog.py checks this on known rotations);
- ``vehicle_angular_velocity``: ``xyz[0..2]`` (FRD, rad/s) -> ``body_rates`` = ``[p, -q, -r]``;
- ``actuator_motors``: ``control[0..3]`` (0..1, PX4 motor order) -> ``motor_command`` in
  quadcog's order, assigned by the rotor positions of the parameters ``CA_ROTOR{i}_PX``,
  ``CA_ROTOR{i}_PY`` (FRD): one rotor per quadrant, front-right, back-right, back-left,
  front-left. Without those parameters (no ``CA_ROTOR_COUNT``: a PX4 before its control
  allocation) PX4's quad X numbering (1 front-right, 2 back-left, 3 front-left, 4 back-right)
  is assumed and ``meta["rotor_order"]`` says so; a ``CA_ROTOR_COUNT`` other than 4 (another
  airframe, or NaN), or rotor parameters that are not finite numbers, leave the order unknown
  and the motor outputs unread (said there too). A NaN control
  (PX4: motor stopped) is read as 0 and counted in ``meta["motor_command_nan_as_zero"]``;
- ``actuator_outputs``: ``output[n - 1]`` (us) of the channel ``n`` whose ``PWM_MAIN_FUNC{n}``
  is motor ``101 + i`` (channel ``i + 1`` without those parameters) -> ``motor_pwm`` =
  ``(output - PWM_MAIN_MIN{n}) / (PWM_MAIN_MAX{n} - PWM_MAIN_MIN{n})`` (PX4's defaults 1000 and
  2000 us when not logged or -1, ``meta["pwm_range"]`` says which; logged, they must lie
  within ``PWM_RANGE_US``, the minimum below the maximum), clipped to 0..1: a disarmed
  output (PWM_MAIN_DIS, 900 us) is 0, counted in ``meta["motor_pwm_clipped"]``;
- ``battery_status``: ``voltage_v`` (V) -> ``battery_voltage``;
- ``vehicle_thrust_setpoint``: ``xyz[2]`` (normalized, FRD: thrust along -z) ->
  ``thrust_command`` = ``-xyz[2]``.

The file must be of a format version PX4 writes (``ULOG_VERSIONS``), hold no message pyulog
takes for damage (``_check_messages``: pyulog would rescan the file byte by byte, for ever in
its header), and every topic read must stamp its samples with ``uint64_t timestamp`` (us), as
PX4's do.

Time base: the time stamps (``timestamp``, us) of the first of ``vehicle_local_position``,
``vehicle_attitude``, ``vehicle_angular_velocity`` in the log, within the span that every
topic read covers (so nothing is extrapolated; what is cut at either end is in
``meta["trimmed_s"]``). Each topic is interpolated onto it: linearly for float fields (the
quaternion component-wise with its sign kept continuous, then normalized: a logged sample
whose norm is farther from 1 than ``QUATERNION_NORM_TOLERANCE`` is refused, one with a NaN
leaves the attitude out, named as logged in ``meta["signals_dropped"]``), by the previous
sample for integer fields. ``raw`` holds every numeric field (not ``char``) of the topics read as
``"topic.field"`` on that base (fields not finite somewhere, NaN or infinite, are left out and
counted in ``meta["raw_dropped"]``); ``meta`` has the log's info messages (``sys_name``,
``ver_sw``, ...), its rotor geometry in quadcog's order (``rotor_positions_m``,
``rotor_directions``: ``-sign(CA_ROTOR{i}_KM)``, KM being positive for a counter-clockwise
rotor) and parameters of a rotor model (``param.THR_MDL_FAC``, ``param.MPC_THR_HOVER``, ...)
when logged (as logged: only ``THR_MDL_FAC``, which the thrust curve reads, is checked). A
signal with a NaN or infinite sample (an estimate not valid yet) is left out and named in
``meta["signals_dropped"]``, which ``FlightLog.signal`` quotes when it is asked for.
"""
import contextlib
import io
import itertools
import os
from pathlib import Path
import struct
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from quadcog.errors import AttitudeError, InputError, LogError, LogFormatError, LogSignalError
from quadcog.files import atomic_write_bytes
from quadcog.logs.access import log_path, read_bytes, writer_path
from quadcog.logs.flightlog import FlightLog
from quadcog.logs.limits import FLOAT32_MAX, check_range, check_unit_signals, microsecond_ticks
from quadcog.validate import array

__all__ = ["read_ulog", "write_ulog", "px4_to_quadcog_quaternion", "quaternion_to_euler",
           "euler_to_quaternion", "TOPICS", "QUADX_ORDER"]

ULOG_MAGIC = b"ULog\x01\x12\x35"
# The header's file format versions PX4 has written: 0 (its first ULogs, without the flag
# bits message) and 1 (since, with it); pyulog reads any version as 1, but a later version
# may change the messages, so it is refused rather than misread
ULOG_VERSIONS = (0, 1)
# topic -> the fields the reader uses
TOPICS = {
    "vehicle_local_position": ("x", "y", "z", "vx", "vy", "vz", "ax", "ay", "az"),
    "vehicle_attitude": ("q[0]", "q[1]", "q[2]", "q[3]"),
    "vehicle_angular_velocity": ("xyz[0]", "xyz[1]", "xyz[2]"),
    "actuator_motors": ("control[0]", "control[1]", "control[2]", "control[3]"),
    "actuator_outputs": tuple(f"output[{i}]" for i in range(16)),
    "battery_status": ("voltage_v",),
    "vehicle_thrust_setpoint": ("xyz[0]", "xyz[1]", "xyz[2]"),
}
BASE_TOPICS = ("vehicle_local_position", "vehicle_attitude", "vehicle_angular_velocity")
# PX4 motor index (0-based) of quadcog's rotors 1..4 in PX4's quad X numbering
QUADX_ORDER = (0, 3, 1, 2)
_FLIP = np.array([1.0, -1.0, -1.0])           # T = diag(1, -1, -1): NED <-> NWU, FRD <-> FLU
_PARAMS = ("THR_MDL_FAC", "MPC_THR_HOVER", "SYS_AUTOSTART", "CA_AIRFRAME", "CA_ROTOR_COUNT")
_STAMP_MAX = 2 ** 63 - 1        # us: the largest time stamp the reader's int64 steps hold
_INFO = ("sys_name", "ver_hw", "ver_sw", "ver_sw_release", "sys_os_name", "sys_uuid")
# ULog's base types and their sizes (bytes); char (text) and bool are not numbers
_BASE_TYPES = {"int8_t": 1, "uint8_t": 1, "int16_t": 2, "uint16_t": 2, "int32_t": 4,
               "uint32_t": 4, "int64_t": 8, "uint64_t": 8, "float": 4, "double": 8, "bool": 1,
               "char": 1}
_NOT_NUMBERS = ("char", "bool")
# A data message's size is a uint16 that also counts its 2-byte message id, so no format
# larger than this can be logged; PX4's nest at most a few deep
MAX_FORMAT_BYTES = 0xFFFF - 2
MAX_NESTING = 16
# The message types pyulog reads in the definitions section (the header's messages, until
# the first subscription or logged text) and in the data section. A message of another type
# that is of type 0, empty or over _PYULOG_MAX_UNKNOWN bytes pyulog takes for damage
# (ULog._check_packet_corruption) and rescans from the next byte; in the definitions section
# a header read there that runs past the end of the file sends it back to rescan the same
# bytes, for ever (a 3 kB log with one byte changed never returned). Refused first.
_DEFINITION_TYPES = tuple(map(ord, "BFIMPQALC"))
_DATA_TYPES = tuple(map(ord, "IMPQALCDOS"))
_DATA_START = tuple(map(ord, "ALC"))
_PYULOG_MAX_UNKNOWN = 10000
# |q| of a logged attitude quaternion: PX4 logs unit quaternions (float32, |q| = 1 to 1e-6);
# farther from 1 than this the sample is not an attitude (normalising would hide the damage)
QUATERNION_NORM_TOLERANCE = 0.1
# PWM_MAIN_MIN/MAX{n} (us): PX4's pulse widths lie within 0..2500 us (drv_pwm_output.h:
# PWM_HIGHEST_MAX = 2500); -1 is the older firmware's "not set" (use PWM_MIN/PWM_MAX), read
# as an absent parameter
PWM_RANGE_US = (0.0, 2500.0)
PWM_UNSET = -1
# THR_MDL_FAC, copied to meta and used by the thrust curve (rotor_model): PX4's range
THR_MDL_FAC_RANGE = (0.0, 1.0)


def px4_to_quadcog_quaternion(q: ArrayLike) -> np.ndarray:
    """PX4's attitude quaternion (FRD body -> NED) as quadcog's (FLU body -> NWU ground).

    Parameters
    ----------
    q : array_like, (..., 4)
        (w, x, y, z) of PX4's ``vehicle_attitude.q``.

    Returns
    -------
    numpy.ndarray, (..., 4)
        (w, x, -y, -z): the quaternion of ``T R T`` with ``T = diag(1, -1, -1)``.

    Raises
    ------
    InputError
        ``q`` not finite real numbers of shape (..., 4).
    """
    return _quaternions(q, "px4_to_quadcog_quaternion: q", unit=False) \
        * np.array([1.0, 1.0, -1.0, -1.0])


def _quaternions(q, where, unit=True):
    """``q`` as finite float64 quaternions (..., 4); with ``unit``, each of norm within
    ``QUATERNION_NORM_TOLERANCE`` of 1, returned normalized (an AttitudeError otherwise: a
    zero quaternion has no attitude)."""
    what = "quaternions (w, x, y, z): finite numbers of shape (..., 4)"
    a = array(q, where, what=what)
    if a.ndim < 1 or a.shape[-1] != 4:
        raise InputError(f"{where}: expected {what}, got shape {a.shape}")
    if not unit:
        return a
    norm = np.sqrt(np.einsum("...i,...i->...", a, a))
    bad = ~(np.abs(norm - 1.0) <= QUATERNION_NORM_TOLERANCE)
    if bad.any():
        k = np.unravel_index(int(np.argmax(bad)), bad.shape) if bad.ndim else ()
        raise AttitudeError(f"{where}: expected unit quaternions (norm within 1 +- "
                            f"{QUATERNION_NORM_TOLERANCE:g}), got {a[k].tolist()} of norm "
                            f"{float(norm[k]):.6g}" + (f" at {tuple(map(int, k))}" if k else ""))
    return a / norm[..., None]


def quaternion_to_euler(q: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """ZYX Euler angles of a unit quaternion, ``R(q) = Rz(yaw) Ry(pitch) Rx(roll)``.

    Parameters
    ----------
    q : array_like, (..., 4)
        (w, x, y, z), the rotation body -> ground.

    Returns
    -------
    roll : numpy.ndarray, (...)
        rad; yaw in (-pi, pi], pitch in [-pi/2, pi/2].
    pitch : numpy.ndarray, (...)
        rad; yaw in (-pi, pi], pitch in [-pi/2, pi/2].
    yaw : numpy.ndarray, (...)
        rad; yaw in (-pi, pi], pitch in [-pi/2, pi/2].

    Raises
    ------
    InputError
        ``q`` not finite real numbers of shape (..., 4); ``AttitudeError`` for a norm
        farther from 1 than ``QUATERNION_NORM_TOLERANCE`` (within it, ``q`` is normalized).
    """
    w, x, y, z = np.moveaxis(_quaternions(q, "quaternion_to_euler: q"), -1, 0)
    roll = np.arctan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2.0 * (w * y - z * x), -1.0, 1.0))
    yaw = np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return roll, pitch, yaw


def euler_to_quaternion(roll: ArrayLike, pitch: ArrayLike, yaw: ArrayLike) -> np.ndarray:
    """The unit quaternion of ``Rz(yaw) Ry(pitch) Rx(roll)``.

    Parameters
    ----------
    roll : array_like
        ZYX Euler angles (rad), broadcast together.
    pitch : array_like
        ZYX Euler angles (rad), broadcast together.
    yaw : array_like
        ZYX Euler angles (rad), broadcast together.

    Returns
    -------
    numpy.ndarray, (..., 4)
        (w, x, y, z).

    Raises
    ------
    InputError
        An angle not finite real numbers, or angles whose shapes do not broadcast.
    """
    angles = [array(a, f"euler_to_quaternion: {n}") for n, a in
              (("roll", roll), ("pitch", pitch), ("yaw", yaw))]
    try:
        roll, pitch, yaw = np.broadcast_arrays(*angles)
    except ValueError:
        raise InputError("euler_to_quaternion: expected roll, pitch and yaw of shapes that "
                         f"broadcast together, got shapes "
                         f"{', '.join(str(a.shape) for a in angles)}") from None
    cr, sr = np.cos(roll / 2), np.sin(roll / 2)
    cp, sp = np.cos(pitch / 2), np.sin(pitch / 2)
    cy, sy = np.cos(yaw / 2), np.sin(yaw / 2)
    return np.stack([cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                     cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy], axis=-1)


def _check_messages(path, data):
    """Walk the message headers: a file cut inside a message is refused (pyulog would stop
    there silently), as is a message pyulog takes for damage (of a type its section does not
    know, ``_DEFINITION_TYPES`` or ``_DATA_TYPES``, and of type 0, empty or over
    ``_PYULOG_MAX_UNKNOWN`` bytes); the format definitions met on the way are checked
    (``_check_formats``)."""
    if len(data) < 16 or data[:7] != ULOG_MAGIC:
        raise LogFormatError(f"{path}: not a ULog file (it does not start with the ULog magic "
                             f"bytes {ULOG_MAGIC.hex(' ')})")
    if data[7] not in ULOG_VERSIONS:
        raise LogFormatError(f"{path}: ULog file format version {data[7]} (header byte 7); "
                             f"expected {' or '.join(map(str, ULOG_VERSIONS))}, the versions "
                             "PX4 writes (a later version may define messages this reader "
                             "would misread)")
    i, end = 16, len(data)
    formats = []
    in_data = False
    while i < end:
        if i + 3 > end:
            raise LogFormatError(f"{path}: truncated ULog: {end - i} bytes of a message "
                                 f"header at byte {i}")
        size = data[i] | (data[i + 1] << 8)
        if i + 3 + size > end:
            raise LogFormatError(f"{path}: truncated ULog: the message at byte {i} (type "
                                 f"{chr(data[i + 2])!r}) needs {size} bytes, the file has "
                                 f"{end - i - 3}")
        kind = data[i + 2]
        known = _DATA_TYPES if in_data else _DEFINITION_TYPES
        if kind not in known and (kind == 0 or size == 0 or size > _PYULOG_MAX_UNKNOWN):
            section = "data" if in_data else "definitions"
            raise LogFormatError(
                f"{path}: damaged ULog: the message at byte {i} of the {section} section has "
                f"type 0x{kind:02x} and {size} bytes; expected a ULog message (types "
                f"{', '.join(map(chr, known))} there; another type of 1..{_PYULOG_MAX_UNKNOWN} "
                "bytes is skipped)")
        in_data = in_data or kind in _DATA_START
        if kind == ord("F"):
            formats.append(data[i + 3:i + 3 + size])
        i += 3 + size
    _check_formats(path, formats)


def _format_fields(payload: bytes) -> tuple[str, list[tuple[str, int]]] | None:
    """(name, [(type name, count)]) of a format message's payload ``name:type name;...``,
    parsed as pyulog parses it; None, or fields left out, where pyulog itself refuses."""
    parts = payload.decode("utf-8", "ignore").split(":")     # pyulog drops bad bytes too
    if len(parts) < 2:
        return None
    fields = []
    for text in parts[1].split(";"):
        words = text.split(" ")
        if not text or len(words) < 2:
            continue
        typ, a = words[0], words[0].find("[")
        count = 0
        if a >= 0:
            try:
                count = int(typ[a + 1:typ.find("]")])
            except ValueError:
                continue
            typ = typ[:a]
        fields.append((typ, max(count, 1)))     # pyulog reads an array of 0 as one value
    return parts[0], fields


def _check_formats(path: str, payloads: list[bytes]) -> None:
    """Refuse format definitions that pyulog would expand without end or beyond what a
    message holds: a format nesting itself (directly or through others), nesting deeper than
    ``MAX_NESTING``, or taking more than ``MAX_FORMAT_BYTES`` once expanded.

    Iterative (a hostile file must not exhaust Python's stack here either) and linear in the
    fields defined: each format is totalled once, and the chain searched for a cycle is at
    most ``MAX_NESTING`` long. A name defined twice is checked in each definition, whichever
    one pyulog keeps."""
    graph: dict[str, list[list[tuple[str, int]]]] = {}      # name -> its definitions' fields
    for payload in payloads:
        parsed = _format_fields(payload)
        if parsed is not None:
            graph.setdefault(parsed[0], []).append(parsed[1])
    size: dict[str, int] = {}       # bytes, an empty nested format counted as 1
    for root in graph:
        if root in size:
            continue
        chain = [root]        # the formats being expanded, outermost first (<= MAX_NESTING)
        todo = [itertools.chain(*graph[root])]
        while todo:
            step = next(todo[-1], None)
            if step is None:            # every field of chain[-1] is known: total it
                todo.pop()
                name = chain.pop()
                total = max(sum(n * (_BASE_TYPES[t] if t in _BASE_TYPES else
                                     max(size.get(t, 1), 1)) for t, n in fields)
                            for fields in graph[name])
                if total > MAX_FORMAT_BYTES:
                    raise LogFormatError(
                        f"{path}: ULog format {name!r} takes more than {MAX_FORMAT_BYTES:,} "
                        f"bytes once its arrays and nested formats are expanded; a ULog data "
                        f"message holds at most {MAX_FORMAT_BYTES:,}")
                size[name] = total
                continue
            sub = step[0]
            if sub in _BASE_TYPES or sub not in graph or sub in size:
                continue                # unknown types are pyulog's to refuse
            if sub in chain:
                loop = " -> ".join(chain[chain.index(sub):] + [sub])
                raise LogFormatError(f"{path}: ULog format {sub!r} contains itself ({loop}); "
                                     "expected formats whose fields are base types or other "
                                     "formats, without cycles")
            if len(chain) >= MAX_NESTING:
                raise LogFormatError(f"{path}: ULog format {chain[0]!r} nests formats more "
                                     f"than {MAX_NESTING} deep ({' -> '.join(chain)} -> "
                                     f"{sub} ...); expected at most {MAX_NESTING}")
            chain.append(sub)
            todo.append(itertools.chain(*graph[sub]))


def _load(path):
    from pyulog import ULog
    from pyulog.exceptions import ULogException
    data = read_bytes(Path(path))
    _check_messages(path, data)
    try:
        # pyulog reads the bytes checked above, from memory: given a name it opens the file
        # itself and leaves it open when it raises (a ResourceWarning)
        with contextlib.redirect_stdout(io.StringIO()), io.BytesIO(data) as f:
            u = ULog(f, message_name_filter_list=list(TOPICS))
    except (ULogException, struct.error, ValueError, IndexError, KeyError, OverflowError,
            UnicodeDecodeError) as e:
        raise LogFormatError(f"{path}: pyulog cannot read the ULog ({e})") from None
    except RecursionError:      # _check_formats should have refused such formats already
        raise LogFormatError(f"{path}: the ULog's formats nest too deeply for pyulog to "
                             "expand them (a damaged or hostile log)") from None
    if u.file_corruption:
        raise LogFormatError(f"{path}: the ULog is corrupt (pyulog found damaged messages)")
    return u


def _check_stamps(path, name, data):
    """A topic the reader uses must have ``timestamp`` as the format defines it,
    ``uint64_t`` (us since boot: a narrower or signed type wraps or goes negative), with
    values that fit an int64, the type the reader computes its steps in."""
    stamps = data.get("timestamp")
    if stamps is None or stamps.dtype != np.uint64:
        what = "no field 'timestamp'" if stamps is None else \
            f"a 'timestamp' of type {stamps.dtype}"
        raise LogFormatError(f"{path}: topic {name} has {what}; expected the ULog time stamp "
                             "'uint64_t timestamp' (us)")
    if stamps.size and int(stamps.max()) > _STAMP_MAX:
        raise LogFormatError(f"{path}: topic {name}: time stamp {int(stamps.max())} us is "
                             f"beyond {_STAMP_MAX} us (292,000 years after boot); a damaged "
                             "log")


def _check_types(path, d):
    """Refuse a topic whose time stamp or fields read as numbers (``TOPICS``) are declared
    ``char`` (text: pyulog gives its byte codes, 'a' would read as 97) or ``bool``."""
    for f in d.field_data:
        if f.type_str in _NOT_NUMBERS and (f.field_name == "timestamp"
                                           or f.field_name in TOPICS[d.name]):
            raise LogFormatError(f"{path}: topic {d.name}: field {f.field_name} has type "
                                 f"{f.type_str!r}; expected a number (float, double or an "
                                 "integer type, as in PX4's message definition)")


def _required(path, topic, data, names):
    """Refuse a topic that lacks fields the reader needs from it (a damaged format)."""
    missing = [n for n in names if n not in data]
    if missing:
        raise LogFormatError(f"{path}: topic {topic} lacks the field(s) {', '.join(missing)}; "
                             f"expected {', '.join(names)} (PX4's message definition)")


def _check_quaternions(path, q, stamps):
    """Refuse attitude samples that are not unit quaternions: |q| farther from 1 than
    ``QUATERNION_NORM_TOLERANCE``, or an infinite component. A sample with a NaN (PX4: no
    estimate yet) is left to the reader, which drops the attitude signals it spoils and
    names the sample as logged (its field, index and time stamp) in
    ``meta["signals_dropped"]``."""
    norm = np.sqrt(np.einsum("ij,ij->i", q, q))
    bad = np.isinf(q).any(axis=1) | (np.abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE)
    if bad.any():
        k = int(np.argmax(bad))
        raise LogFormatError(f"{path}: vehicle_attitude.q of sample {k} (time stamp "
                             f"{int(stamps[k])} us) is {q[k].tolist()}, of norm "
                             f"{float(norm[k]):.6g}; expected a unit quaternion (norm within "
                             f"1 +- {QUATERNION_NORM_TOLERANCE:g})")


def _is_number(value):
    """Whether a parameter's value is a real number (pyulog gives an int or a float; a
    damaged type gives bytes or text, and a bool is no number)."""
    return isinstance(value, (int, float, np.number)) and not isinstance(value, (bool, np.bool_))


def _check_thr_mdl_fac(path, params):
    """Refuse a logged ``THR_MDL_FAC`` that is not a number within ``THR_MDL_FAC_RANGE``:
    meta carries it to the thrust curve (``px4_thrust_curve_from_log``), where a NaN or
    inf would otherwise be refused without the log's name. The other parameters copied to
    meta are descriptive: nothing computes with them."""
    if "THR_MDL_FAC" not in params:
        return
    value = params["THR_MDL_FAC"]
    lo, hi = THR_MDL_FAC_RANGE
    ok = _is_number(value) and lo <= float(value) <= hi          # False for NaN
    if not ok:
        raise LogFormatError(f"{path}: parameter THR_MDL_FAC is {value!r}; expected PX4's "
                             f"thrust model factor, a number within {lo:g}..{hi:g}")


def _rotor_count(params):
    """``CA_ROTOR_COUNT`` as an int; None when it is not logged. A value that is not a whole
    number (NaN, 2.5, a bool) is returned as it is, for ``_rotor_map`` to name."""
    if "CA_ROTOR_COUNT" not in params:
        return None
    value = params["CA_ROTOR_COUNT"]
    whole = _is_number(value) and np.isfinite(float(value)) and float(value).is_integer()
    return int(value) if whole else value


def _rotor_map(params):
    """(PX4 motor index of quadcog's rotors 1..4, positions FLU (4, 2), directions, note).

    PX4's quad X numbering is assumed only where the log has no ``CA_ROTOR_COUNT`` (a PX4
    older than its control allocation) or positions for 4 rotors are not all logged. A
    ``CA_ROTOR_COUNT`` that is logged but is not 4 (another airframe, or not a count: NaN)
    leaves the order unknown, so no motor output is taken as one of quadcog's rotors."""
    count = _rotor_count(params)
    if count is not None and count != 4:
        what = (f"CA_ROTOR_COUNT = {count}: not a quadrotor" if isinstance(count, int) else
                f"CA_ROTOR_COUNT is {count!r}, not a rotor count")
        return None, None, None, f"{what}: rotor order unknown (motor outputs not read)"
    keys = [(f"CA_ROTOR{i}_PX", f"CA_ROTOR{i}_PY", f"CA_ROTOR{i}_KM") for i in range(4)]
    if count is None or not all(k in params for ks in keys for k in ks):
        return QUADX_ORDER, None, None, "assumed PX4 quad X (no CA_ROTOR parameters of 4 rotors)"
    odd = [k for ks in keys for k in ks if not _is_number(params[k])]
    if odd:
        return None, None, None, (f"CA_ROTOR parameters not numbers ({odd[0]} is "
                                  f"{params[odd[0]]!r:.40}): rotor order unknown")
    flu = np.array([[params[px], -params[py]] for px, py, _ in keys], dtype=float)
    km = np.array([params[k] for _, _, k in keys], dtype=float)
    if not (np.isfinite(flu).all() and np.isfinite(km).all()):
        return None, None, None, (f"CA_ROTOR parameters not finite (positions {flu.tolist()}, "
                                  f"KM {km.tolist()}): rotor order unknown")
    slot = {(1, -1): 0, (-1, -1): 1, (-1, 1): 2, (1, 1): 3}   # quadcog rotors 1..4
    order = [None] * 4
    for i, (x, y) in enumerate(flu):
        s = slot.get((int(np.sign(x)), int(np.sign(y))))
        if s is None or order[s] is not None:
            return None, flu, None, (f"not a quad X: CA_ROTOR positions (FLU) {flu.tolist()} "
                                     "do not put one rotor in each quadrant")
        order[s] = i
    return tuple(order), flu[order], -np.sign(km[order]), "from CA_ROTOR{i}_PX/PY"


def _pwm_range(path, params, n):
    """(PWM_MAIN_MIN{n}, PWM_MAIN_MAX{n}) in us, each None when not logged (or
    ``PWM_UNSET``); refused unless finite numbers within ``PWM_RANGE_US``, min below max."""
    lo_us, hi_us = PWM_RANGE_US
    where = f"for the motor output on channel {n} (actuator_outputs.output[{n - 1}])"
    keys = (f"PWM_MAIN_MIN{n}", f"PWM_MAIN_MAX{n}")
    values = []
    for key in keys:
        value = params.get(key)
        ok = value is None or (_is_number(value) and np.isfinite(float(value)))
        if not ok:          # (output - lo) / (hi - lo) would be NaN or a TypeError
            raise LogFormatError(f"{path}: parameter {key} is {value!r}; expected a finite "
                                 f"PWM (us) {where}")
        if value is None or value == PWM_UNSET:
            values.append(None)
            continue
        if not lo_us <= float(value) <= hi_us:
            raise LogFormatError(f"{path}: parameter {key} is {value!r} us; expected a PWM "
                                 f"within {lo_us:g}..{hi_us:g} us (PX4's pulse widths) {where}")
        values.append(float(value))
    lo, hi = values
    if lo is not None and hi is not None and not lo < hi:
        raise LogFormatError(f"{path}: parameters {keys[0]} = {lo:g} us and {keys[1]} = "
                             f"{hi:g} us; expected the minimum below the maximum {where}")
    return lo, hi


def _motor_pwm(path, d, t_us, order, params):
    """actuator_outputs as 0..1 per quadcog rotor (unclipped), and where its range came from."""
    # a function that is not a whole number (a damaged float parameter, or of a damaged
    # type: bytes) assigns no motor
    funcs = {int(params[f"PWM_MAIN_FUNC{n}"]): n for n in range(1, 17)
             if _is_number(params.get(f"PWM_MAIN_FUNC{n}"))
             and float(params[f"PWM_MAIN_FUNC{n}"]).is_integer()}
    ts = d["timestamp"].astype(np.float64)
    cols, defaults = [], False
    for i in order:
        n = funcs.get(101 + i, i + 1) if funcs else i + 1
        if f"output[{n - 1}]" not in d:
            return None, None
        lo, hi = _pwm_range(path, params, n)
        if lo is None or hi is None:
            lo, hi, defaults = 1000.0, 2000.0, True
        out = np.interp(t_us, ts, d[f"output[{n - 1}]"].astype(np.float64))
        cols.append((out - lo) / (hi - lo))
    note = ("PX4's defaults 1000..2000 us (no PWM_MAIN_MIN/MAX parameters)" if defaults
            else "PWM_MAIN_MIN{n}..PWM_MAIN_MAX{n}")
    return np.column_stack(cols), note


def _rate_hz(stamps_us):
    """Mean rate (Hz) of a topic's time stamps (us)."""
    return (stamps_us.size - 1) / ((float(stamps_us[-1]) - float(stamps_us[0])) * 1e-6)


def _interp(t_base, ts, values, is_float):
    if is_float:
        return np.interp(t_base, ts, values)
    idx = np.searchsorted(ts, t_base, side="right") - 1
    return values[np.clip(idx, 0, ts.size - 1)].astype(np.float64)


def read_ulog(path: str | os.PathLike) -> FlightLog:
    """Read a PX4 ULog (see the module docstring for topics, frames and the time base).

    Parameters
    ----------
    path : str or os.PathLike
        The ``.ulg`` file.

    Returns
    -------
    FlightLog
        Format ``"ulog"``.

    Raises
    ------
    LogFormatError
        Not a ULog, truncated or corrupt, formats that contain themselves, nest deeper than
        ``MAX_NESTING`` or expand beyond ``MAX_FORMAT_BYTES``, a field read as a number
        declared ``char`` or ``bool``, a topic whose time stamps do not increase, no overlap
        of the topics' spans, an attitude sample whose norm is not within
        ``QUATERNION_NORM_TOLERANCE`` of 1, a PWM range parameter that is not a finite number
        within ``PWM_RANGE_US`` or a minimum not below its maximum, a file format version
        not in ``ULOG_VERSIONS``, a time stamp not declared ``uint64_t``, a
        ``THR_MDL_FAC`` not within ``THR_MDL_FAC_RANGE``, a message pyulog takes for damage
        (of type 0, or of a type its section does not know and empty or over 10,000
        bytes). ``LogError`` for a path that is not one or a file that cannot be read.
    LogSignalError
        None of the time-base topics (``vehicle_local_position``, ``vehicle_attitude``,
        ``vehicle_angular_velocity``) is in the log.
    """
    # a signalling NaN of a float32 field warns when cast or interpolated: every value that
    # is not finite is dropped, counted and named here (raw_dropped, signals_dropped)
    path = log_path(path, "read_ulog: path")
    with np.errstate(invalid="ignore"):
        return _read_ulog(str(path))


def _read_ulog(path: str) -> FlightLog:
    """``read_ulog`` of a path (str), numpy's invalid-value warnings off."""
    u = _load(path)
    topics = {}
    text: set[str] = set()           # char fields: text, not numbers, so not in raw
    for d in u.data_list:
        if d.multi_id == 0 and d.name in TOPICS:
            _check_types(path, d)
            _check_stamps(path, d.name, d.data)
            if d.data["timestamp"].size >= 2:
                topics[d.name] = d.data
                text.update(f"{d.name}.{f.field_name}" for f in d.field_data
                            if f.type_str == "char")
    base = next((n for n in BASE_TOPICS if n in topics), None)
    if base is None:
        raise LogSignalError(f"{path}: the ULog has none of the topics {BASE_TOPICS} that "
                             f"give the time base (it has {sorted(topics) or 'none of'} "
                             f"{'' if topics else list(TOPICS)})", source=path)
    for name, d in topics.items():
        steps = np.diff(d["timestamp"].astype(np.int64))
        if not (steps > 0).all():
            k = int(np.argmax(steps <= 0))
            raise LogFormatError(f"{path}: topic {name}: time stamp of sample {k + 1} "
                                 f"({int(d['timestamp'][k + 1])} us) does not follow "
                                 f"{int(d['timestamp'][k])} us; expected increasing")
    ts_base = topics[base]["timestamp"].astype(np.int64)
    lo = max(int(d["timestamp"][0]) for d in topics.values())
    hi = min(int(d["timestamp"][-1]) for d in topics.values())
    keep = (ts_base >= lo) & (ts_base <= hi)
    if keep.sum() < 2:
        raise LogFormatError(f"{path}: the topics {sorted(topics)} overlap in fewer than 2 "
                             f"samples of {base}")
    tb = ts_base[keep]
    t_us = tb.astype(np.float64)
    raw, dropped = {}, 0
    for name, d in topics.items():
        ts = d["timestamp"].astype(np.float64)
        for field, values in d.items():
            if field.startswith("timestamp") or values.dtype.kind not in "biuf" or \
                    f"{name}.{field}" in text:
                continue
            v = _interp(t_us, ts, values, values.dtype.kind == "f")
            if np.isfinite(v).all():
                raw[f"{name}.{field}"] = v
            else:
                dropped += 1
    signals = {}

    def fields(topic, names):
        d = topics.get(topic)
        if d is None or not all(n in d for n in names):
            return None
        ts = d["timestamp"].astype(np.float64)
        return np.column_stack([np.interp(t_us, ts, d[n].astype(np.float64)) for n in names])

    lp = "vehicle_local_position"
    for signal, names in (("position", ("x", "y", "z")), ("velocity", ("vx", "vy", "vz")),
                          ("acceleration", ("ax", "ay", "az"))):
        v = fields(lp, names)
        if v is not None:
            signals[signal] = v * _FLIP
    attitude_dropped = None
    if "vehicle_attitude" in topics:
        d = topics["vehicle_attitude"]
        _required(path, "vehicle_attitude", d, TOPICS["vehicle_attitude"])
        q = np.column_stack([d[f"q[{i}]"].astype(np.float64) for i in range(4)])
        _check_quaternions(path, q, d["timestamp"])
        # q and -q are one rotation: keep the sign continuous before interpolating
        flips = np.cumprod(np.where(np.einsum("ij,ij->i", q[1:], q[:-1]) < 0, -1.0, 1.0))
        q[1:] *= flips[:, None]
        ts = d["timestamp"].astype(np.float64)
        qi = np.column_stack([np.interp(t_us, ts, q[:, i]) for i in range(4)])
        spoiled = np.isnan(qi).any(axis=1)
        if spoiled.any():       # named as logged: its field, sample and time stamp
            at = int(np.searchsorted(ts, t_us[int(np.argmax(spoiled))], side="right")) - 1
            k = next(j for j in (at, at + 1) if j < len(q) and np.isnan(q[j]).any())
            i = int(np.argmax(np.isnan(q[k])))
            attitude_dropped = (f"roll, pitch, yaw (vehicle_attitude.q[{i}] is nan in its "
                                f"sample {k}, time stamp {int(d['timestamp'][k])} us: "
                                f"{int(spoiled.sum())} of {t_us.size} samples not finite)")
        else:
            # unit quaternions (checked) with continuous signs: norms of 0.6 at least
            qi /= np.linalg.norm(qi, axis=1)[:, None]
            roll, pitch, yaw = quaternion_to_euler(px4_to_quadcog_quaternion(qi))
            signals.update(roll=roll, pitch=pitch, yaw=yaw)
    v = fields("vehicle_angular_velocity", ("xyz[0]", "xyz[1]", "xyz[2]"))
    if v is not None:
        signals["body_rates"] = v * _FLIP
    params = dict(u.initial_parameters)
    order, positions, directions, note = _rotor_map(params)
    meta = {str(k): str(u.msg_info_dict[k]) for k in _INFO if k in u.msg_info_dict}
    _check_thr_mdl_fac(path, params)
    meta.update({f"param.{k}": repr(params[k]) for k in _PARAMS if k in params})
    meta.update(vehicle=meta.get("sys_name", "PX4"), time_base=base,
                start_timestamp_us=str(int(tb[0])), rotor_order=note,
                trimmed_s=f"{(tb[0] - ts_base[0]) * 1e-6:.6g} at the start, "
                          f"{(ts_base[-1] - tb[-1]) * 1e-6:.6g} at the end",
                raw_dropped=str(dropped),
                rates_hz=", ".join(f"{n}: {_rate_hz(d['timestamp']):.4g}"
                                   for n, d in topics.items()))
    if positions is not None and directions is not None:
        meta["rotor_positions_m"] = "; ".join(f"{float(x)!r} {float(y)!r}"
                                              for x, y in positions)
        meta["rotor_directions"] = " ".join(str(int(d)) for d in directions)
    if order is not None and "actuator_motors" in topics:
        d = topics["actuator_motors"]
        _required(path, "actuator_motors", d, [f"control[{i}]" for i in sorted(order)])
        ts = d["timestamp"].astype(np.float64)
        cols = []
        nan = 0
        for i in order:
            c = d[f"control[{i}]"].astype(np.float64)
            nan += int(np.isnan(c).sum())
            cols.append(np.interp(t_us, ts, np.nan_to_num(c, nan=0.0)))
        signals["motor_command"] = np.column_stack(cols)
        meta["motor_command_nan_as_zero"] = str(nan)
    if order is not None and "actuator_outputs" in topics:
        pwm, note = _motor_pwm(path, topics["actuator_outputs"], t_us, order, params)
        if pwm is not None:
            signals["motor_pwm"] = np.clip(pwm, 0.0, 1.0)
            meta.update(pwm_range=note, motor_pwm_clipped=str(int(np.sum((pwm < 0) | (pwm > 1)))))
    v = fields("battery_status", ("voltage_v",))
    if v is not None:
        signals["battery_voltage"] = v[:, 0]
    v = fields("vehicle_thrust_setpoint", ("xyz[2]",))
    if v is not None:
        signals["thrust_command"] = -v[:, 0]
    # an estimate that is not valid yet is NaN in PX4's topics: leave such a signal out, say so
    not_finite: list[str] = [] if attitude_dropped is None else [attitude_dropped]
    for name in list(signals):
        bad = ~np.isfinite(signals[name]).reshape(t_us.size, -1).all(axis=1)
        if bad.any():
            del signals[name]
            not_finite.append(f"{name} ({int(bad.sum())} of {t_us.size} samples not finite)")
    if not_finite:
        meta["signals_dropped"] = "; ".join(not_finite)
    return FlightLog(path, "ulog", (tb - tb[0]) * 1e-6, signals, raw, meta)


# -- writer -------------------------------------------------------------------------------
_CARRIED = ("position", "velocity", "acceleration", "roll", "pitch", "yaw", "body_rates",
            "motor_command", "motor_pwm", "battery_voltage", "thrust_command")
_START_US = 1_000_000          # a log starts some time after boot


def _message(kind, payload):
    return struct.pack("<HB", len(payload), ord(kind)) + payload


def _key_value(ctype, key, value):
    name = f"{ctype} {key}".encode()
    return bytes([len(name)]) + name + value


# quadcog's rotors 1..4 (front-right, back-right, back-left, front-left): signs of x, y (FLU)
_QUADRANTS = ((1, -1), (-1, -1), (-1, 1), (1, 1))


def _nominal_positions(log):
    """Rotor positions (FLU, quadcog order) to write: the log's own, else a nominal X.

    The log's own (``meta["rotor_positions_m"]``, "x y; x y; x y; x y" in m) must survive
    the float32 parameters and the reader's assignment of motors by quadrant; anything else
    is refused, not replaced, since the motor signals read back would be reordered or lost."""
    text = log.meta.get("rotor_positions_m")
    if not text:
        from quadcog.vehicles.vehicle import x_layout
        return np.array(x_layout(0.25))
    where = f"{log.source}: cannot write as ULog: meta['rotor_positions_m'] = {text!r:.120}"
    try:
        pos = np.array([[float(v) for v in pair.split()] for pair in text.split(";")])
    except ValueError:
        pos = np.zeros(0)
    if pos.shape != (4, 2):
        raise LogError(f"{where} is not four rotor positions; expected 'x y; x y; x y; x y' "
                       "(m, FLU, quadcog's rotor order)")
    bad = ~(np.abs(pos) <= FLOAT32_MAX)
    if bad.any():
        r, c = (int(i) for i in np.argwhere(bad)[0])
        raise LogError(f"{where}: rotor {r + 1} {'xy'[c]} = {float(pos[r, c])!r} m is beyond "
                       f"the float32 of a ULog parameter (magnitude at most "
                       f"{FLOAT32_MAX:.4g}); expected a finite position")
    signs = np.sign(pos.astype(np.float32))        # as the reader sees them
    for r, (sx, sy) in enumerate(_QUADRANTS):
        if (signs[r, 0], signs[r, 1]) != (sx, sy):
            raise LogError(f"{where}: rotor {r + 1} at {pos[r].tolist()} m is not in its "
                           f"quadrant; expected quadcog's order, one rotor per quadrant: "
                           "front-right (x > 0, y < 0), back-right, back-left, front-left "
                           "(as float32), which the reader assigns the motors by")
    return pos


# what write_ulog puts in the info messages: the vehicle of the log's meta when it names one,
# else the placeholder WRITER_NAME, which names no vehicle type (the identification's
# vehicle-type check skips it)
WRITER_NAME, WRITER_HW = "quadcog", "quadcog.logs.write_log"


def _writer_name(log):
    name = str(log.meta.get("vehicle", "")).strip()
    ok = 0 < len(name) <= 64 and name.isascii() and name.isprintable()
    return name if ok else WRITER_NAME


def write_ulog(log: FlightLog, path: str | os.PathLike) -> Path:
    """Write a log's signals as a minimal valid ULog (version 1) that PX4's tools and
    ``read_ulog`` read.

    It holds the header, the flag-bits message, info (``sys_name``: the log's
    ``meta["vehicle"]``, else ``WRITER_NAME``; ``ver_hw`` = ``WRITER_HW``), the rotor
    parameters (``CA_ROTOR_COUNT``, ``CA_ROTOR{i}_PX/PY/KM``: PX4's quad X numbering, the
    log's rotor positions or a nominal X; with ``motor_pwm`` the channels' ``PWM_MAIN_FUNC``,
    ``PWM_MAIN_MIN`` = 1000 and ``PWM_MAIN_MAX`` = 2000), one format and subscription per topic
    and one
    data message per topic and sample (float32 fields, ``timestamp`` in integer us), in
    PX4's frames and units (the inverse of the reader's conversions).

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
        The log has a signal ULog does not carry here (``moment_command``),
        only some of roll, pitch and yaw (an attitude quaternion needs all three), no
        signal at all, none of the signals of the time-base topics (``BASE_TOPICS``: the
        reader would refuse the file), or times the integer-us stamps cannot hold
        (``quadcog.logs.limits.microsecond_ticks``).
    LogError
        ``meta["rotor_positions_m"]`` is not four positions, one per quadrant in quadcog's
        rotor order, that float32 parameters hold; ``log`` not a FlightLog, ``path`` not a
        file that may be replaced.
    """
    path = writer_path(log, path, "write_ulog")
    s = log.signals
    extra = [n for n in s if n not in _CARRIED]
    angles = [n for n in ("roll", "pitch", "yaw") if n in s]
    if extra or 0 < len(angles) < 3 or not s:
        why = (f"ULog does not carry {extra} here" if extra else
               f"it has {angles} but a ULog attitude needs roll, pitch and yaw" if angles else
               "it has no standard signal")
        raise LogSignalError(f"{log.source}: cannot write as ULog: {why}; write a FlightLog "
                             "without them (dataclasses.replace(log, signals=...))",
                             source=log.source, available=tuple(s))
    n = log.n_samples
    check_unit_signals(log, "ULog")
    ts = microsecond_ticks(log, _START_US, "ULog")
    topics = {}          # name -> [(field name, ctype, values (n,) or (n, k))]
    lp = [(f, s[sig] * _FLIP) for f, sig in (("p", "position"), ("v", "velocity"),
                                             ("a", "acceleration")) if sig in s]
    if lp:
        names = {"p": ("x", "y", "z"), "v": ("vx", "vy", "vz"), "a": ("ax", "ay", "az")}
        topics["vehicle_local_position"] = [(c, "float", v[:, j]) for f, v in lp
                                            for j, c in enumerate(names[f])]
    if angles:
        q = euler_to_quaternion(s["roll"], s["pitch"], s["yaw"])
        topics["vehicle_attitude"] = [("q", "float[4]", px4_to_quadcog_quaternion(q))]
    if "body_rates" in s:
        topics["vehicle_angular_velocity"] = [("xyz", "float[3]", s["body_rates"] * _FLIP)]
    positions = _nominal_positions(log)
    if "motor_command" in s:
        control = np.full((n, 12), np.nan)
        for rotor, i in enumerate(QUADX_ORDER):
            control[:, i] = s["motor_command"][:, rotor]
        topics["actuator_motors"] = [("control", "float[12]", control)]
    if "motor_pwm" in s:                 # channel i + 1 is motor i + 1, 1000..2000 us
        output = np.full((n, 16), 900.0)
        for rotor, i in enumerate(QUADX_ORDER):
            output[:, i] = 1000.0 + 1000.0 * s["motor_pwm"][:, rotor]
        topics["actuator_outputs"] = [("output", "float[16]", output)]
    if "battery_voltage" in s:
        topics["battery_status"] = [("voltage_v", "float", s["battery_voltage"])]
    if "thrust_command" in s:
        xyz = np.column_stack([np.zeros(n), np.zeros(n), -s["thrust_command"]])
        topics["vehicle_thrust_setpoint"] = [("xyz", "float[3]", xyz)]
    if not any(name in topics for name in BASE_TOPICS):
        raise LogSignalError(f"{log.source}: cannot write as ULog: it has none of position, "
                             "velocity, acceleration, roll/pitch/yaw or body_rates, whose "
                             f"topics {BASE_TOPICS} give a ULog its time base (read_ulog "
                             "refuses a ULog without them)", source=log.source,
                             available=tuple(s))
    out = bytearray(ULOG_MAGIC + bytes([1]) + struct.pack("<Q", _START_US))
    out += _message("B", bytes(40))                   # no compat/incompat flags, no appends
    for key, value in (("sys_name", _writer_name(log)), ("ver_hw", WRITER_HW)):
        out += _message("I", _key_value(f"char[{len(value)}]", key, value.encode()))
    params = {"CA_ROTOR_COUNT": ("int32_t", struct.pack("<i", 4))}
    directions = (-1, 1, -1, 1)            # quadcog order: the quad X's spins (KM > 0: CCW)
    for rotor, i in enumerate(QUADX_ORDER):
        x, y = positions[rotor]
        for key, v in (("PX", x), ("PY", -y), ("KM", -0.05 * directions[rotor])):
            params[f"CA_ROTOR{i}_{key}"] = ("float", struct.pack("<f", v))
    if "motor_pwm" in s:
        for ch in range(1, 5):
            params[f"PWM_MAIN_FUNC{ch}"] = ("int32_t", struct.pack("<i", 100 + ch))
            params[f"PWM_MAIN_MIN{ch}"] = ("int32_t", struct.pack("<i", 1000))
            params[f"PWM_MAIN_MAX{ch}"] = ("int32_t", struct.pack("<i", 2000))
    for key, (ctype, packed) in params.items():
        out += _message("P", _key_value(ctype, key, packed))
    dtypes = {}
    for msg_id, (name, flds) in enumerate(topics.items()):
        spec = ";".join(["uint64_t timestamp"] + [f"{c} {f}" for f, c, _ in flds]) + ";"
        out += _message("F", f"{name}:{spec}".encode())
        layout: list[tuple[Any, ...]] = [("size", "<u2"), ("type", "u1"), ("id", "<u2"),
                                         ("timestamp", "<u8")]
        layout += [(f, "<f4", v.shape[1:]) if v.ndim > 1 else (f, "<f4") for f, _, v in flds]
        dtypes[name] = (msg_id, np.dtype(layout))
    for name, (msg_id, _) in dtypes.items():
        out += _message("A", bytes([0]) + struct.pack("<H", msg_id) + name.encode())
    rows = []
    for name, flds in topics.items():
        msg_id, dt = dtypes[name]
        rec = np.zeros(n, dtype=dt)
        rec["size"], rec["type"], rec["id"], rec["timestamp"] = dt.itemsize - 3, ord("D"), \
            msg_id, ts
        for f, _, v in flds:
            check_range(log, f"{name}.{f}", v[np.isfinite(v)], "ULog")
            rec[f] = v
        rows.append(rec.view(np.uint8).reshape(n, dt.itemsize))
    # interleave the topics sample by sample, as a logger writes them
    out += b"".join(r[k].tobytes() for k in range(n) for r in rows)
    atomic_write_bytes(path, bytes(out), "write_log path", LogError)
    return path
