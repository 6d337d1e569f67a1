"""The mission, flown over MAVLink: upload, arm in mission mode, watch until PX4 disarms.

A ground station on its own UDP link (PX4's API link: PX4 listens on 14580 + instance and
sends to 14540 + instance): ``MissionLink.poll(t)`` is called from the lockstep loop with the
simulated time, so every wait is in PX4's time, not the wall clock's. It sends a GCS
heartbeat each second, uploads the mission (``MISSION_COUNT``, then one ``MISSION_ITEM_INT`` per
``MISSION_REQUEST_INT``) once PX4's heartbeat is seen, then each second asks for mission mode
(``MAV_CMD_DO_SET_MODE``: AUTO, MISSION) and arming (``MAV_CMD_COMPONENT_ARM_DISARM``) until
PX4's heartbeat says armed. PX4 then takes off, flies the items and lands; it disarms by
itself on the ground (``COM_DISARM_LAND``), which ends the mission.

The messages are pymavlink's (its generated ``common`` dialect: the same definitions PX4 is
built from; pymavlink is the codec of PX4's own Python tools, and MAVSDK would need its
``mavsdk_server`` binary downloaded at run time). Only the few messages read here are decoded:
the frames are split by ``quadcog.px4.mavlink.FrameReader`` and the others dropped unread, so
the telemetry PX4 streams on this link at simulated rate costs little.
"""
from dataclasses import dataclass, field
import math
import socket
from typing import Any

import numpy as np
import numpy.typing as npt

from quadcog.errors import Px4Error
from quadcog.px4.frames import FLIP
from quadcog.px4.mavlink import FrameReader
from quadcog.px4.sensors import EARTH_RADIUS, HOME
from quadcog.validate import import_extra

__all__ = ["GCS_PORT", "Waypoint", "Mission", "MissionLink", "PX4_MODE_AUTO", "PX4_MODE_MISSION"]

GCS_PORT = 14540                    # + instance: where PX4's API link sends
PX4_MODE_AUTO, PX4_MODE_MISSION = 4, 4      # px4_custom_mode main and sub mode
_ARMED = 128                        # MAV_MODE_FLAG_SAFETY_ARMED
_WANTED = {0, 40, 42, 46, 47, 51, 77, 245, 253}   # heartbeat, mission, command ack, statustext


@dataclass(frozen=True)
class Waypoint:
    """One point of the mission.

    Parameters
    ----------
    position : tuple of 3 float
        (x north, y west, z up) relative to home (m), quadcog's ground frame.
    hold : float
        Seconds to hold there.
    """
    position: tuple[float, float, float]
    hold: float = 0.0


@dataclass(frozen=True)
class Mission:
    """Take off to the first waypoint's height, fly the waypoints, land at the last one.

    Parameters
    ----------
    waypoints : tuple of Waypoint
        At least one; z > 0.
    """
    waypoints: tuple[Waypoint, ...]

    def __post_init__(self) -> None:
        if not self.waypoints:
            raise Px4Error("a mission needs at least one waypoint")
        for k, w in enumerate(self.waypoints):
            if not (np.all(np.isfinite(w.position)) and w.position[2] > 0 and w.hold >= 0):
                raise Px4Error(f"mission waypoint {k}: expected a finite position with z > 0 "
                               f"(m, up) and hold >= 0 s, got {w}")

    def items(self, mav: Any, target: int, home: tuple[float, float, float] = HOME
              ) -> list[Any]:
        """The MISSION_ITEM_INT messages: take-off, one waypoint per point, land.

        Parameters
        ----------
        mav : pymavlink MAVLink
            The encoder.
        target : int
            PX4's system id.
        home : tuple of 3 float
            lat, lon (deg) and altitude of the origin (m).

        Returns
        -------
        list
            The messages, in order.
        """
        c = import_extra("px4", "pymavlink.dialects.v20.common")
        frame = c.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT

        def latlon(p):
            north, east, _ = np.asarray(p, float) * FLIP
            lat = home[0] + math.degrees(north / EARTH_RADIUS)
            lon = home[1] + math.degrees(east / (EARTH_RADIUS * math.cos(math.radians(home[0]))))
            return int(round(lat * 1e7)), int(round(lon * 1e7))

        first, last = self.waypoints[0], self.waypoints[-1]
        rows = [(c.MAV_CMD_NAV_TAKEOFF, 0.0, first.position)]
        rows += [(c.MAV_CMD_NAV_WAYPOINT, w.hold, w.position) for w in self.waypoints]
        rows += [(c.MAV_CMD_NAV_LAND, 0.0, (last.position[0], last.position[1], 0.0))]
        out = []
        for seq, (cmd, hold, p) in enumerate(rows):
            lat, lon = latlon(p)
            out.append(mav.mission_item_int_encode(target, 1, seq, frame, cmd, int(seq == 0), 1,
                                                   hold, 0.0, 0.0, float("nan"), lat, lon,
                                                   float(p[2])))
        return out

    def target_at(self, seq: int) -> npt.NDArray[np.float64]:
        """The position (m, quadcog's ground frame) that mission item ``seq`` flies to.

        Parameters
        ----------
        seq : int
            The item (0 take-off, 1..n waypoints, n + 1 land).

        Returns
        -------
        (3,) numpy.ndarray
            The target (the land item's: the last waypoint on the ground).
        """
        n = len(self.waypoints)
        if seq <= 0:
            return np.array(self.waypoints[0].position, float)
        if seq <= n:
            return np.array(self.waypoints[seq - 1].position, float)
        last = self.waypoints[-1].position
        return np.array([last[0], last[1], 0.0])


@dataclass
class MissionLink:
    """The ground station's side of the mission (see the module docstring).

    Parameters
    ----------
    mission : Mission
        What to fly.
    instance : int
        PX4's instance (its system id is instance + 1).
    arm_timeout : float
        Simulated seconds to wait for PX4 to accept arming.
    """
    mission: Mission
    instance: int
    arm_timeout: float = 120.0
    # what the link has seen (not arguments): its state, PX4's arming, the current item,
    # PX4's STATUSTEXT messages (t, text)
    state: str = field(default="waiting for PX4", init=False)
    armed: bool = field(default=False, init=False)
    armed_at: float | None = field(default=None, init=False)
    disarmed_at: float | None = field(default=None, init=False)
    current: int = field(default=0, init=False)
    statustext: list[tuple[float, str]] = field(default_factory=list, init=False)
    _sock: socket.socket | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        c = import_extra("px4", "pymavlink.dialects.v20.common")
        self._c = c
        self._mav = c.MAVLink(None, srcSystem=255, srcComponent=190)
        self._mav.robust_parsing = True
        self._reader = FrameReader(_WANTED)
        self._items: list[Any] = []
        self._chunks: dict[int, str] = {}
        self._next_heartbeat = 0.0
        self._next_try = 0.0
        self._px4: tuple[str, int] | None = None
        self.target = self.instance + 1

    def open(self) -> None:
        """Bind the ground station's UDP port (``GCS_PORT + instance``) on 127.0.0.1.

        Raises
        ------
        quadcog.Px4Error
            When the port is taken.
        """
        port = GCS_PORT + self.instance
        s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            s.bind(("127.0.0.1", port))
        except OSError as e:
            s.close()
            raise Px4Error(f"UDP port {port} (PX4 instance {self.instance}'s mission link) is "
                           f"taken: {e.strerror}") from None
        s.setblocking(False)
        self._sock = s

    def close(self) -> None:
        """Close the socket."""
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def _send(self, msg: Any) -> None:
        if self._px4 is not None and self._sock is not None:
            self._sock.sendto(msg.pack(self._mav), self._px4)

    def _command(self, cmd: int, *params: float) -> None:
        p = list(params) + [0.0] * (7 - len(params))
        self._send(self._mav.command_long_encode(self.target, 1, cmd, 0, *p))

    @property
    def finished(self) -> bool:
        """PX4 armed, flew and disarmed."""
        return self.disarmed_at is not None

    def poll(self, t: float) -> None:
        """Read what PX4 sent, answer it, and send what is due at simulated time t.

        Parameters
        ----------
        t : float
            Simulated time (s).

        Raises
        ------
        quadcog.Px4Error
            When the mission is refused, or PX4 does not arm within ``arm_timeout``
            (with PX4's last messages).
        """
        sock = self._sock
        while sock is not None:
            try:
                data, addr = sock.recvfrom(65536)
            except BlockingIOError:
                break
            self._px4 = addr
            for msgid, sysid, _, _, raw in self._reader.feed(data):
                if sysid == self.target:
                    self._handle(t, msgid, raw)
        if self._px4 is None:
            return
        if t >= self._next_heartbeat:
            c = self._c
            self._send(self._mav.heartbeat_encode(c.MAV_TYPE_GCS, c.MAV_AUTOPILOT_INVALID, 0, 0,
                                                  c.MAV_STATE_ACTIVE))
            self._next_heartbeat = t + 1.0
        if self.state == "waiting for PX4":
            self._items = self.mission.items(self._mav, self.target)
            self._send(self._mav.mission_count_encode(self.target, 1, len(self._items), 0))
            self.state = "uploading"
            self._next_try = t + 2.0
        elif self.state == "uploading" and t >= self._next_try:
            self.state = "waiting for PX4"          # no request came: start over
        elif self.state == "arming" and t >= self._next_try:
            c = self._c
            self._command(c.MAV_CMD_DO_SET_MODE, c.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                          PX4_MODE_AUTO, PX4_MODE_MISSION)
            self._command(c.MAV_CMD_COMPONENT_ARM_DISARM, 1.0)
            self._next_try = t + 1.0
            if t > self.arm_timeout:
                said = "; ".join(text for _, text in self.statustext[-4:]) or "nothing"
                raise Px4Error(f"PX4 did not arm within {self.arm_timeout:g} s of simulated "
                               f"time; its last messages: {said}")

    def _handle(self, t: float, msgid: int, raw: bytes) -> None:
        try:
            msg = self._mav.decode(bytearray(raw))
        except Exception:                       # a frame pymavlink refuses: not ours
            return
        c = self._c
        if msgid == c.MAVLINK_MSG_ID_HEARTBEAT:
            armed = bool(msg.base_mode & _ARMED)
            if armed and not self.armed:
                self.armed, self.armed_at, self.state = True, t, "flying"
            elif self.armed and not armed and self.disarmed_at is None:
                self.armed, self.disarmed_at, self.state = False, t, "landed"
        elif msgid in (c.MAVLINK_MSG_ID_MISSION_REQUEST_INT, c.MAVLINK_MSG_ID_MISSION_REQUEST):
            if self.state == "uploading" and msg.seq < len(self._items):
                self._send(self._items[msg.seq])
                self._next_try = t + 2.0
        elif msgid == c.MAVLINK_MSG_ID_MISSION_ACK and self.state == "uploading":
            if msg.type != c.MAV_MISSION_ACCEPTED:
                raise Px4Error(f"PX4 refused the mission: MISSION_ACK type {msg.type} "
                               f"({c.enums['MAV_MISSION_RESULT'][msg.type].name})")
            self.state, self._next_try = "arming", t
        elif msgid == c.MAVLINK_MSG_ID_MISSION_CURRENT:
            self.current = int(msg.seq)
        elif msgid == c.MAVLINK_MSG_ID_STATUSTEXT:
            # a text longer than 50 characters comes in chunks of one id; the last is shorter
            text = msg.text if isinstance(msg.text, str) else str(msg.text)
            if msg.id:
                text = self._chunks.pop(msg.id, "") + text
                if len(msg.text) >= 50:
                    self._chunks[msg.id] = text
                    return
            text = text.strip()
            if not self.statustext or self.statustext[-1][1] != text:
                self.statustext.append((t, text))
