"""quadcog's truth plant as PX4's simulator, in lockstep.

Each lockstep period T (4 ms: PX4's SITL IMU rate, ``IMU_INTEG_RATE`` 250 Hz) the loop

1. makes the sensor readings from the truth state (``quadcog.px4.sensors``) and sends one
   ``HIL_SENSOR`` (its ``time_usec`` is PX4's clock), and a ``HIL_GPS`` at 10 Hz;
2. lets the mission link (``quadcog.px4.mission``) read and answer PX4 at that time;
3. waits for PX4's ``HIL_ACTUATOR_CONTROLS`` of that time stamp: PX4 ran its estimator and
   controllers up to it;
4. maps the motor outputs to rotor thrusts (``quadcog.px4.airframe.RotorMap``) and steps the
   compiled truth plant (``quadcog.sim.plant``: RK4, the schedule's CoG profile and payloads,
   motor lag, drag, rotor limits) through the period in steps of the scenario's dt; with the
   sensing model's ``delay`` (``Sensing.delay``) on the answer of the period before: the input
   computed from the measurement of period j-1 acts in period j.

The ground: the plant has none, so the loop holds the vehicle at rest on the ground plane
z = 0 (level, its heading kept) while the rotors' thrust is below its weight, and puts it
back there when it comes down through it. Before PX4's first answer (while it boots) the loop
paces itself at real time; after it, it waits for PX4 at each step.

The CoG profile and the payload events of the scenario are timed from the moment PX4 arms
(the scenario's t = 0); before that the vehicle is as at t = 0. PX4's own time (the result's
t) starts at its boot.
"""
import contextlib
from dataclasses import dataclass, field
import math
import os
import socket
import subprocess
import time
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog.codegen.compiled import cached_compile
from quadcog.codegen.fastcall import FastCall
from quadcog.errors import Px4Error, Px4TimeoutError
from quadcog.model.conventions import IDX, N_STATE, R_G, rotation_matrix
from quadcog.model.functions import load
from quadcog.px4.airframe import RotorMap
from quadcog.px4.mavlink import (
    MESSAGES,
    FrameReader,
    frame,
    pack_hil_gps,
    pack_hil_sensor,
    unpack_hil_actuator_controls,
)
from quadcog.px4.mission import MissionLink
from quadcog.px4.process import Px4Process
from quadcog.px4.sensors import GPS_RATE, Sensors
from quadcog.sim.plant import PI_INDEX, Actuation, plant_step_function
from quadcog.sim.schedule import Schedule, truth_parameters
from quadcog.trajectories.analytic import POS, REF_SIZE

__all__ = ["PERIOD", "Recording", "run_lockstep"]

PERIOD = 0.004                  # s: one HIL_SENSOR, one answer
_SENSOR = MESSAGES["HIL_SENSOR"]
_GPS = MESSAGES["HIL_GPS"]
_CONTROLS = MESSAGES["HIL_ACTUATOR_CONTROLS"].msgid
_ARMED_FLAG = 128
_MISSION_EVERY = 5              # lockstep periods between two looks at the mission link (20 ms)


@dataclass
class Recording:
    """What the loop recorded, sample k at t = k dt (PX4's clock).

    Parameters
    ----------
    dt : float
        The plant's step (s).
    n : int
        Samples recorded.
    x : numpy.ndarray
        State (n, 12).
    rotor_states : numpy.ndarray
        Rotor-thrust states (n, 0 or 4).
    U : numpy.ndarray
        Applied input (n, 4).
    rotor_thrust : numpy.ndarray
        Rotor thrust (n, 4, N).
    rotor_command : numpy.ndarray
        Commanded rotor thrust (n, 4, N).
    target : numpy.ndarray
        The mission's target (n, 3, m).
    schedule_index : numpy.ndarray
        (n,) the schedule's row at each sample (0 before arming).
    armed_at : float or None
        PX4's time of arming (s).
    disarmed_at : float or None
        PX4's time of disarming (s).
    partial : bool
        The run stopped before the mission ended.
    reason : str
        Why it stopped.
    wall_seconds : float
        Wall time of the lockstep from PX4's first answer on.
    lockstep_seconds : float
        Simulated time in that span.
    wait_seconds : float
        Of ``wall_seconds``, the time spent waiting for PX4's answers (the rest is
        quadcog's: sensors, codec, plant, mission link).
    cpu_px4 : float
        CPU seconds (user + system) PX4 spent in that span.
    cpu_quadcog : float
        CPU seconds (user + system) this process spent in that span: lockstep is serial, so
        ``lockstep_seconds / (cpu_px4 + cpu_quadcog)`` is the speed on an idle machine, less
        the wake-up latencies.
    statustext : list
        PX4's STATUSTEXT messages on the mission link, (t, text).
    """
    dt: float
    n: int = 0
    x: np.ndarray = field(default_factory=lambda: np.empty((0, N_STATE)))
    rotor_states: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    U: np.ndarray = field(default_factory=lambda: np.empty((0, 4)))
    rotor_thrust: np.ndarray = field(default_factory=lambda: np.empty((0, 4)))
    rotor_command: np.ndarray = field(default_factory=lambda: np.empty((0, 4)))
    target: np.ndarray = field(default_factory=lambda: np.empty((0, 3)))
    schedule_index: np.ndarray = field(default_factory=lambda: np.empty(0, int))
    armed_at: float | None = None
    disarmed_at: float | None = None
    partial: bool = False
    reason: str = ""
    wall_seconds: float = 0.0
    lockstep_seconds: float = 0.0
    statustext: list = field(default_factory=list)
    wait_seconds: float = 0.0
    cpu_px4: float = 0.0
    cpu_quadcog: float = 0.0

    @property
    def t(self) -> npt.NDArray[np.float64]:
        """(n,) sample times (s)."""
        return np.arange(self.n, dtype=np.float64) * self.dt

    def reference(self) -> npt.NDArray[np.float64]:
        """The reference rows of the result.

        Returns
        -------
        (n, 14) numpy.ndarray
            The mission's target as the position (m), the rest zero.
        """
        ref = np.zeros((self.n, REF_SIZE))
        ref[:, POS] = self.target[:self.n]
        return ref


def period_function(actuation: Actuation, nsub: int) -> ca.Function:
    """``nsub`` plant steps with the input, parameters and payload held: one lockstep period
    as one compiled call (``plant_step_function`` mapaccum'd).

    Parameters
    ----------
    actuation : Actuation
        The truth's rotors.
    nsub : int
        Plant steps per period.

    Returns
    -------
    casadi.Function
        ``(x, f, U, p, payload, r_stated, wrench, dt) -> (X (12 x nsub), F (nf x nsub),
        U_applied (4 x nsub))``: the state and rotor thrusts after each step, the input the
        rotors gave during each.
    """
    def build():
        step = plant_step_function(load(), actuation)
        acc = step.mapaccum("plant_steps", nsub)
        ins = [ca.MX.sym(step.name_in(i), step.size1_in(i)) for i in range(step.n_in())]
        held = [ca.repmat(v, 1, nsub) for v in ins[2:]]
        X, F, U = acc(ins[0], ins[1], *held)
        return ca.Function("px4_period", ins, [X, F, U],
                           [step.name_in(i) for i in range(step.n_in())],
                           ["X", "F", "U_applied"])
    return cached_compile(("px4-period", actuation, nsub), build)


def _cpu_seconds(pid: int) -> float:
    """User + system CPU seconds of a running process (0 when it is gone)."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            fields = fh.read().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _at_rest(x: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    rest = np.zeros(N_STATE)
    rest[0], rest[1], rest[5] = x[0], x[1], x[5]
    return rest


class _SimLink:
    """The TCP link PX4 connects to: HIL_SENSOR out, HIL_ACTUATOR_CONTROLS in."""

    def __init__(self, server: socket.socket, px4: Px4Process, connect_timeout: float):
        server.settimeout(0.2)
        t_end = time.monotonic() + connect_timeout
        while True:
            try:
                conn, _ = server.accept()
                break
            except socket.timeout:
                if not px4.alive():
                    raise Px4Error(f"PX4 ended before it connected to the simulator port "
                                   f"({px4.describe_exit()}): {px4.last_lines()}") from None
                if time.monotonic() > t_end:
                    raise Px4TimeoutError(
                        f"PX4 did not connect to the simulator port 127.0.0.1:"
                        f"{server.getsockname()[1]} within {connect_timeout:g} s (wall "
                        f"clock); its last lines: {px4.last_lines()}") from None
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.conn = conn
        self.reader = FrameReader({_CONTROLS})
        self.seq = 0
        self._timeout: float | None = None
        self.latest: tuple[int, int, tuple[float, ...], int] = (0, 0, (0.0,) * 16, 0)

    def send(self, message, payload: bytes) -> None:
        self.conn.sendall(frame(message, payload, self.seq, 1, 200))
        self.seq += 1

    def read(self, timeout: float) -> bool:
        """Read what has arrived within ``timeout`` s; False when nothing came."""
        if timeout != self._timeout:            # one recv with a timeout: no select first
            self.conn.settimeout(timeout)
            self._timeout = timeout
        try:
            data = self.conn.recv(1 << 16)
        except socket.timeout:
            return False
        if not data:
            raise ConnectionResetError("PX4 closed the simulator link")
        for _, _, _, payload, _ in self.reader.feed(data):
            self.latest = unpack_hil_actuator_controls(payload)
        return True

    def close(self) -> None:
        self.conn.close()


def run_lockstep(px4: Px4Process, server: socket.socket, mission: MissionLink,
                 schedule: Schedule, P: npt.NDArray[np.float64], actuation: Actuation,
                 rotors: RotorMap, sensors: Sensors, max_time: float, connect_timeout: float,
                 answer_timeout: float, after_landing: float = 2.0, period: float = PERIOD,
                 progress: Any = None) -> Recording:
    """Fly: the lockstep loop of the module docstring, until PX4 has landed and disarmed (and
    ``after_landing`` s more, for its logger to close the log), ``max_time`` s, or a fault.

    Parameters
    ----------
    px4 : Px4Process
        The running PX4.
    server : socket.socket
        The listening simulator port (``quadcog.px4.process.free_instance``).
    mission : MissionLink
        The mission link, open.
    schedule : Schedule
        The scenario's per-step inputs from arming on, at the plant's dt.
    P : (14,) numpy.ndarray
        The airframe's parameters.
    actuation : Actuation
        The truth's rotors.
    rotors : RotorMap
        PX4's outputs to rotor thrusts.
    sensors : Sensors
        The sensor models.
    max_time : float
        Longest flight (s of PX4's time).
    connect_timeout : float
        Wall seconds for PX4 to connect.
    answer_timeout : float
        Wall seconds PX4 may take to answer one step once it has started answering.
    after_landing : float
        Simulated seconds to go on after PX4 disarmed.
    period : float
        The lockstep period (s), a whole number of plant steps.
    progress : callable, optional
        ``progress(t, mission, speed)`` every 10 s of PX4's time.

    Returns
    -------
    Recording
        The flight; ``partial`` when it stopped before the mission ended (``reason``).

    Raises
    ------
    quadcog.Px4TimeoutError
        PX4 did not connect in time, or stopped answering (PX4 still running).
    quadcog.Px4Error
        PX4 refused the mission or arming.
    """
    dt = float(schedule.dt[0])
    nsub = int(round(period / dt))
    if nsub < 1 or abs(nsub * dt - period) > 1e-9:
        raise Px4Error(f"the lockstep period {period:g} s is not a whole number of plant "
                       f"steps of dt = {dt:g} s")
    nf = actuation.n_rotor_states
    n_max = int(math.ceil(max_time / dt)) + 1
    rec = Recording(dt, 0, np.empty((n_max, N_STATE)), np.empty((n_max, nf)),
                    np.empty((n_max, 4)), np.empty((n_max, 4)), np.empty((n_max, 4)),
                    np.empty((n_max, 3)), np.zeros(n_max, int))
    plant = FastCall(period_function(actuation, nsub))
    px, pf, pU, pP, pload, pr, pw, pdt = plant.inputs
    X_out, F_out, U_out = plant.outputs
    step = plant.eval
    pr[:] = P[R_G]
    pdt[0] = dt
    mixer = actuation.mixer_matrix()
    g = float(P[IDX["g"]])
    m_air = float(P[IDX["m"]])
    n_sched = schedule.n_steps
    lower, upper = actuation.lower, actuation.upper
    # the rows where an input of the schedule differs from the row before
    inputs = np.hstack([schedule.cog, schedule.cog_scale[:, None], schedule.payload,
                        schedule.wrench])
    changes = 1 + np.flatnonzero(np.any(inputs[1:] != inputs[:-1], axis=1))
    last_segment = -1
    mass = m_air

    x = np.zeros(N_STATE)
    R = np.eye(3)
    f = np.zeros(nf)
    accel = np.zeros(3)
    on_ground = True
    link = _SimLink(server, px4, connect_timeout)
    period_us = int(round(period * 1e6))
    gps_every = int(round(1.0 / (GPS_RATE * period)))
    answered = False
    delay = bool(sensors.sensing.imu.delay)
    held = np.zeros(4)          # with delay: PX4's answer of the period before
    wall0 = sim0 = 0.0
    cpu0 = (0.0, 0.0)
    j = 0                       # lockstep periods done
    k = 0                       # plant steps done
    k_arm = None
    stop_at = None
    next_report = 10.0
    try:
        while True:
            t = k * dt
            if k + nsub >= n_max:
                rec.partial, rec.reason = True, (f"the mission did not end within max_time = "
                                                 f"{max_time:g} s")
                break
            if stop_at is not None and t >= stop_at:
                break
            # 1. sensors at time t
            t_us = period_us * (j + 1)
            acc, gyro, mag, pressure, alt, temp = sensors.imu(R, x[9:12], accel, x[2])
            link.send(_SENSOR, pack_hil_sensor(t_us, acc, gyro, mag, pressure, 0.0, alt, temp))
            if j % gps_every == 0:
                lat, lon, alt_mm, vn, ve, vd, cog = sensors.gps(x[:3], R @ x[6:9])
                link.send(_GPS, pack_hil_gps(t_us, lat, lon, alt_mm, 30, 40,
                                             int(math.hypot(vn, ve)), vn, ve, vd, cog))
            # 2. the mission, at PX4's time
            if j % _MISSION_EVERY == 0:
                mission.poll(t)
            if mission.armed and k_arm is None:
                k_arm, rec.armed_at = k, t
            if mission.finished and stop_at is None:
                rec.disarmed_at = mission.disarmed_at
                stop_at = t + after_landing
            # 3. PX4's answer for t_us
            if not answered:
                link.read(period)           # booting: real-time pace
                if link.latest[0] >= t_us:
                    answered, wall0, sim0 = True, time.monotonic(), t
                    cpu0 = time.process_time(), _cpu_seconds(px4.proc.pid)
            else:
                w0 = time.monotonic()
                t_wait = w0 + answer_timeout
                while link.latest[0] < t_us:
                    if not link.read(0.05):
                        if not px4.alive():
                            raise ConnectionResetError("PX4 ended")
                        if time.monotonic() > t_wait:
                            raise Px4TimeoutError(
                                f"PX4 stopped answering: no HIL_ACTUATOR_CONTROLS for t = "
                                f"{t:.3f} s within {answer_timeout:g} s (wall clock); it still "
                                f"runs; its last lines: {px4.last_lines()}")
                rec.wait_seconds += time.monotonic() - w0
            _, _, controls, mode = link.latest
            armed = bool(mode & _ARMED_FLAG)
            thrust_cmd = rotors.thrust(controls, armed)
            if delay:
                thrust_cmd, held = held, thrust_cmd
            U = mixer @ thrust_cmd
            pU[:] = U
            # 4. the plant through the period (the schedule's row of its start held; its
            # inputs set again only where the schedule changes)
            row = 0 if k_arm is None else min(k - k_arm, n_sched)
            segment = int(np.searchsorted(changes, row, side="right"))
            if segment != last_segment:
                pP[:] = truth_parameters(P, schedule.cog_scale[row], schedule.cog[row])
                pload[:] = schedule.payload[row]
                pw[:] = schedule.wrench[row]
                mass = m_air + float(pload[PI_INDEX["m"]])
                last_segment = segment
            px[:] = x
            pf[:] = f
            step()
            ks = slice(k, k + nsub)
            rec.x[k] = x
            rec.x[k + 1:k + nsub] = X_out[:, :nsub - 1].T
            if nf:
                rec.rotor_states[k] = f
                rec.rotor_states[k + 1:k + nsub] = F_out[:, :nsub - 1].T
            rec.U[ks] = U_out.T
            rec.rotor_command[ks] = thrust_cmd
            rec.rotor_thrust[ks] = (rec.rotor_states[ks] if nf else
                                    np.clip(thrust_cmd, lower, upper))
            rec.target[ks] = mission.mission.target_at(mission.current)
            rec.schedule_index[ks] = row
            x_new = X_out[:, nsub - 1].copy()
            if on_ground:
                if U[0] > mass * g:
                    on_ground = False
                else:
                    x_new = _at_rest(x)
                    rec.x[k + 1:k + nsub] = x_new
            elif x_new[2] < 0.0:
                on_ground, x_new = True, _at_rest(x_new)
                below = k + 1 + np.flatnonzero(X_out[2, :nsub - 1] < 0.0)
                rec.x[below] = x_new
            if not np.isfinite(x_new).all():     # kept: the samples before this period
                rec.partial, rec.reason = True, f"the plant's state is not finite at " \
                                                f"t = {(k + nsub) * dt:.3f} s"
                break
            # the accelerometer: the last plant step's change of the ground velocity
            before = X_out[:, nsub - 2] if nsub > 1 else x
            v_before = rotation_matrix(before[3], before[4], before[5]) @ before[6:9]
            R = rotation_matrix(x_new[3], x_new[4], x_new[5])      # the next sensors' too
            v_new = R @ x_new[6:9]
            accel = (v_new - v_before) / dt if not on_ground else np.zeros(3)
            x = x_new
            f = F_out[:, nsub - 1].copy()
            k += nsub
            j += 1
            if progress is not None and t >= next_report:
                span = time.monotonic() - wall0
                progress(t, mission, (t - sim0) / span if answered and span > 0 else 0.0)
                next_report += 10.0
    except (ConnectionResetError, BrokenPipeError, ConnectionAbortedError):
        with contextlib.suppress(subprocess.TimeoutExpired):
            px4.proc.wait(timeout=2.0)      # a closed link: PX4 is ending, or it closed it
        rec.partial = True
        rec.reason = (f"PX4 died at t = {k * dt:.3f} s ({px4.describe_exit()}): "
                      f"{px4.last_lines()}" if not px4.alive() else
                      f"PX4 closed the simulator link at t = {k * dt:.3f} s")
    finally:
        if answered:
            rec.cpu_quadcog = time.process_time() - cpu0[0]
            rec.cpu_px4 = _cpu_seconds(px4.proc.pid) - cpu0[1]
        link.close()
        rec.statustext = list(mission.statustext)
    rec.n = k
    if answered:
        rec.wall_seconds = time.monotonic() - wall0
        rec.lockstep_seconds = k * dt - sim0
    if rec.armed_at is None and not rec.partial:
        rec.partial, rec.reason = True, "PX4 never armed"
    return rec
