"""MAVLink 2 framing and the simulator link's messages, packed with ``struct``.

The lockstep loop sends one ``HIL_SENSOR`` per step and reads one ``HIL_ACTUATOR_CONTROLS``;
pymavlink's generic codec (a Python object per message, a field at a time) costs more than the
plant's step, so these few messages are packed and read here directly: the payload fields in
MAVLink's wire order (by type size, largest first, extensions last, ``MESSAGES``), the frame
``0xFD len incompat compat seq sysid compid msgid[3] payload crc[2]`` with MAVLink 2's trailing
zero bytes of the payload cut, and the checksum CRC-16/MCRF4XX (the X.25 CRC, initial 0xFFFF)
over the frame after its first byte plus the message's CRC_EXTRA byte. The definitions are
those of common.xml (PX4's mavlink submodule); tests/test_px4_hil.py checks every message
against pymavlink's generated codec when pymavlink is installed, and the CRC against its
textbook check value.
"""
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
import struct
from typing import Any

__all__ = ["Message", "MESSAGES", "x25_crc", "x25_crc_python", "frame", "FrameReader", "HIL_SENSOR_ALL_FIELDS",
           "pack_hil_sensor", "pack_hil_gps", "unpack_hil_actuator_controls", "padded"]


@dataclass(frozen=True)
class Message:
    """One MAVLink message's wire layout.

    Parameters
    ----------
    msgid : int
        Its id.
    crc_extra : int
        The CRC_EXTRA seed byte of its definition.
    layout : str
        ``struct`` format of its payload in wire order, little-endian.
    """
    msgid: int
    crc_extra: int
    layout: str

    @property
    def size(self) -> int:
        """The full payload length (bytes), extensions included."""
        return struct.calcsize(self.layout)


MESSAGES = {
    # time_usec; xacc..zacc, xgyro..zgyro, xmag..zmag, abs_pressure, diff_pressure,
    # pressure_alt, temperature; fields_updated; id (extension)
    "HIL_SENSOR": Message(107, 108, "<Q13fIB"),
    # time_usec; lat, lon, alt; eph, epv, vel; vn, ve, vd; cog; fix_type,
    # satellites_visible; id, yaw (extensions)
    "HIL_GPS": Message(113, 124, "<Q3i3H3hH2BBH"),
    # time_usec, flags; controls[16]; mode
    "HIL_ACTUATOR_CONTROLS": Message(93, 47, "<2Q16fB"),
    # custom_mode; type, autopilot, base_mode, system_status, mavlink_version
    "HEARTBEAT": Message(0, 50, "<I5B"),
}
_BY_ID = {m.msgid: (name, m) for name, m in MESSAGES.items()}
# fields_updated of a HIL_SENSOR that carries every field (accel, gyro, mag, baro, diff
# pressure, pressure altitude, temperature: bits 0..12)
HIL_SENSOR_ALL_FIELDS = 0x1FFF


def _crc_table() -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0x8408 if crc & 1 else crc >> 1
        table.append(crc)
    return tuple(table)


_TABLE = _crc_table()


def x25_crc_python(data: bytes, crc: int = 0xFFFF) -> int:
    """CRC-16/MCRF4XX (MAVLink's X.25 checksum) of ``data``, table-driven, in Python.

    Parameters
    ----------
    data : bytes
        The bytes.
    crc : int
        The running value (start: 0xFFFF).

    Returns
    -------
    int
        The checksum (0 .. 65535); b"123456789" gives 0x6F91.
    """
    table = _TABLE
    for b in data:
        crc = (crc >> 8) ^ table[(crc ^ b) & 0xFF]
    return crc


_mcrf4xx: Any = None
try:        # fastcrc (a compiled CRC that pymavlink installs) is several times faster
    from fastcrc import crc16 as _fastcrc
    _mcrf4xx = _fastcrc.mcrf4xx
except ImportError:         # pragma: no cover - without pymavlink's dependency
    pass


def x25_crc(data: bytes, crc: int = 0xFFFF) -> int:
    """CRC-16/MCRF4XX (MAVLink's X.25 checksum) of ``data``: fastcrc's where installed,
    else ``x25_crc_python``.

    Parameters
    ----------
    data : bytes
        The bytes.
    crc : int
        The running value (start: 0xFFFF).

    Returns
    -------
    int
        The checksum (0 .. 65535); b"123456789" gives 0x6F91.
    """
    if _mcrf4xx is not None:
        return _mcrf4xx(bytes(data), crc)
    return x25_crc_python(data, crc)


def frame(message: Message, payload: bytes, seq: int, sysid: int = 1, compid: int = 1) -> bytes:
    """A MAVLink 2 frame of one message (unsigned).

    Parameters
    ----------
    message : Message
        Its layout (id, CRC_EXTRA).
    payload : bytes
        The full payload (``message.size`` bytes); its trailing zero bytes are cut, as
        MAVLink 2 sends it (at least one byte stays).
    seq : int
        Sequence number (taken modulo 256).
    sysid : int
        The sender's system id.
    compid : int
        The sender's component id.

    Returns
    -------
    bytes
        The frame, ready for the wire.
    """
    body = payload.rstrip(b"\0") or payload[:1]
    head = struct.pack("<BBBBBBBHB", 0xFD, len(body), 0, 0, seq & 0xFF, sysid, compid,
                       message.msgid & 0xFFFF, message.msgid >> 16)
    crc = x25_crc(bytes((message.crc_extra,)), x25_crc(head[1:] + body))
    return head + body + struct.pack("<H", crc)


def padded(message: Message, payload: bytes) -> bytes:
    """A received payload with the zero bytes MAVLink 2 cut put back.

    Parameters
    ----------
    message : Message
        Its layout.
    payload : bytes
        The payload as received.

    Returns
    -------
    bytes
        ``message.size`` bytes.
    """
    return payload + b"\0" * (message.size - len(payload))


def pack_hil_sensor(time_usec: int, acc: Sequence[float], gyro: Sequence[float],
                    mag: Sequence[float],
                    abs_pressure: float, diff_pressure: float, pressure_alt: float,
                    temperature: float, fields_updated: int = HIL_SENSOR_ALL_FIELDS,
                    sensor_id: int = 0) -> bytes:
    """The payload of a ``HIL_SENSOR``.

    Parameters
    ----------
    time_usec : int
        Time stamp (us); in lockstep it sets PX4's clock.
    acc : sequence of 3 float
        Specific force, FRD body axes (m/s^2).
    gyro : sequence of 3 float
        Body rates, FRD (rad/s).
    mag : sequence of 3 float
        Magnetic field, FRD (gauss).
    abs_pressure : float
        Static pressure (hPa).
    diff_pressure : float
        Differential (airspeed) pressure (hPa).
    pressure_alt : float
        Altitude from the pressure (m).
    temperature : float
        Temperature (deg C).
    fields_updated : int
        Bit mask of the fields that are new (``HIL_SENSOR_ALL_FIELDS``).
    sensor_id : int
        Which sensor instance (0: the first).

    Returns
    -------
    bytes
        The full payload (65 bytes).
    """
    return struct.pack(MESSAGES["HIL_SENSOR"].layout, time_usec, *acc, *gyro, *mag,
                       abs_pressure, diff_pressure, pressure_alt, temperature,
                       fields_updated, sensor_id)


def pack_hil_gps(time_usec: int, lat: int, lon: int, alt: int, eph: int, epv: int, vel: int,
                 vn: int, ve: int, vd: int, cog: int, fix_type: int = 3,
                 satellites_visible: int = 10, gps_id: int = 0, yaw: int = 0) -> bytes:
    """The payload of a ``HIL_GPS``.

    Parameters
    ----------
    time_usec : int
        Time stamp (us).
    lat : int
        Latitude (degrees * 1e7).
    lon : int
        Longitude (degrees * 1e7).
    alt : int
        Altitude above mean sea level (mm).
    eph : int
        Horizontal dilution of precision (* 100).
    epv : int
        Vertical dilution of precision (* 100).
    vel : int
        Ground speed (cm/s).
    vn : int
        Velocity north (cm/s).
    ve : int
        Velocity east (cm/s).
    vd : int
        Velocity down (cm/s).
    cog : int
        Course over ground (cdeg, 0..35999).
    fix_type : int
        3: a 3D fix.
    satellites_visible : int
        Satellites in view.
    gps_id : int
        Which GPS (0: the first).
    yaw : int
        Heading from a dual-antenna GPS (cdeg); 0: not given.

    Returns
    -------
    bytes
        The full payload (39 bytes).
    """
    return struct.pack(MESSAGES["HIL_GPS"].layout, time_usec, lat, lon, alt, eph, epv, vel,
                       vn, ve, vd, cog, fix_type, satellites_visible, gps_id, yaw)


def unpack_hil_actuator_controls(payload: bytes) -> tuple[int, int, tuple[float, ...], int]:
    """Read a ``HIL_ACTUATOR_CONTROLS`` payload (as received: trailing zeros may be cut).

    Parameters
    ----------
    payload : bytes
        The payload.

    Returns
    -------
    time_usec : int
        PX4's time stamp (us).
    flags : int
        Bit 0: PX4 runs in lockstep.
    controls : tuple of 16 float
        The outputs; motors in [0, 1] in PX4's motor order (zeros while disarmed).
    mode : int
        MAV_MODE_FLAG bits (128: armed).
    """
    message = MESSAGES["HIL_ACTUATOR_CONTROLS"]
    values = struct.unpack(message.layout, padded(message, payload))
    return values[0], values[1], values[2:18], values[18]


class FrameReader:
    """Split a byte stream into MAVLink frames (version 1 and 2), checking each checksum
    where the message's CRC_EXTRA is known (``MESSAGES``; others are passed on unchecked).

    Parameters
    ----------
    wanted : set of int, optional
        Message ids to hand out; None: all.
    """

    def __init__(self, wanted: set[int] | None = None) -> None:
        self._buf = bytearray()
        self.wanted = wanted
        self.bad_crc = 0            # frames dropped for a wrong checksum

    def feed(self, data: bytes) -> Iterator[tuple[int, int, int, bytes, bytes]]:
        """Add bytes; yield every complete frame.

        Parameters
        ----------
        data : bytes
            Bytes as received.

        Yields
        ------
        tuple of (int, int, int, bytes, bytes)
            ``(msgid, sysid, compid, payload, frame)``: the payload as sent (MAVLink 2 may
            have cut its trailing zeros) and the whole frame.
        """
        buf = self._buf
        buf += data
        i = 0
        n = len(buf)
        while True:
            j2, j1 = buf.find(b"\xfd", i), buf.find(b"\xfe", i)
            j = j2 if j1 < 0 or (0 <= j2 < j1) else j1
            if j < 0:
                i = n
                break
            v2 = buf[j] == 0xFD
            head = 10 if v2 else 6
            if j + head > n:
                i = j
                break
            length = buf[j + 1]
            signed = v2 and buf[j + 2] & 1
            end = j + head + length + 2 + (13 if signed else 0)
            if end > n:
                i = j
                break
            if v2:
                msgid = buf[j + 7] | buf[j + 8] << 8 | buf[j + 9] << 16
                sysid, compid = buf[j + 5], buf[j + 6]
            else:
                msgid, sysid, compid = buf[j + 5], buf[j + 3], buf[j + 4]
            known = _BY_ID.get(msgid)
            stop = j + head + length
            if known is not None:
                crc = x25_crc(bytes((known[1].crc_extra,)), x25_crc(bytes(buf[j + 1:stop])))
                if crc != buf[stop] | buf[stop + 1] << 8:
                    self.bad_crc += 1
                    i = j + 1          # not a frame start after all: look further
                    continue
            if self.wanted is None or msgid in self.wanted:
                yield msgid, sysid, compid, bytes(buf[j + head:stop]), bytes(buf[j:end])
            i = end
        del buf[:i]
