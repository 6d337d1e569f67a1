"""``quadcog.px4.fly``: a scenario flown by PX4's estimator and controllers on quadcog's plant.

What it takes from the scenario (``quadcog.scenarios``): the truth vehicle (the X500 preset,
checked against PX4's x500 airframe), the truth options (motor lag, rotor limits, parallel
axis), the CoG changes, the payload events and the disturbances (timed from PX4's arming), the
plant's dt, and the trajectory, which becomes the mission (``mission_of``): a hover is a
take-off to its position, a hold of the scenario's duration there, and a landing; a waypoint
trajectory is its waypoints, each held for an equal share of the duration; another
trajectory is flown through eight waypoints sampled over its duration. The scenario's
controller is not used: PX4 flies.

What it writes into ``out``: quadcog's run files (metrics.json, vehicle.json,
trajectory.csv, flight.png) of the plant's truth, and beside them ``px4.ulg``, the ULog that
PX4's logger wrote (from boot to disarm), ``px4.log``, PX4's console, and in metrics.json the
``px4`` entry: partial or not and why, when PX4 armed and disarmed, the speed of the
lockstep (simulated seconds per wall second), PX4's messages. A run that stopped early (PX4
died, the plant diverged) still writes what it has, with ``partial`` true in metrics.json.
"""
from dataclasses import dataclass
import os
from pathlib import Path
import shutil
import tempfile
import time
from typing import Any

import numpy as np

from quadcog.errors import Px4Error
from quadcog.files import RUN_FILES, RunFiles, strict_json
from quadcog.model.conventions import IDX, R_G
from quadcog.px4.airframe import SIM_AIRFRAME, SIM_MODEL, check_rotors, px4_parameters, read_airframe, rotor_map
from quadcog.px4.lockstep import PERIOD, Recording, run_lockstep
from quadcog.px4.mission import Mission, MissionLink, Waypoint
from quadcog.px4.process import Px4Process, free_instance
from quadcog.px4.sensors import HOME, Px4Sensing, Sensors, earth_field
from quadcog.px4.tree import Px4Build, build, cached_build
from quadcog.scenarios.scenario import Scenario, load_scenario, write_table
from quadcog.sim.divergence import Limits
from quadcog.sim.plant import PI_INDEX, Actuation, body_mass_and_cog
from quadcog.sim.prepare import as_cog_profile, as_payload_profile, check_cog_changes, check_payload_events
from quadcog.sim.result import SimulationResult, flight_metrics, position_errors
from quadcog.sim.schedule import Schedule
from quadcog.sim.sensing import Sensing
from quadcog.trajectories.analytic import Hover
from quadcog.trajectories.waypoints import MinimumSnap
from quadcog.validate import positive, require_extra

__all__ = ["PX4_FILES", "Px4Flight", "mission_of", "fly", "write_px4_outputs"]

PX4_FILES = RUN_FILES + ("px4.ulg", "px4.log")
_MISSION_POINTS = 8


@dataclass
class Px4Flight:
    """One PX4 flight on quadcog's plant.

    Parameters
    ----------
    result : SimulationResult
        The plant's truth, sampled at its dt from PX4's boot.
    recording : Recording
        The loop's record (armed and disarmed times, partial, speed, PX4's messages).
    scenario : Scenario
        What was flown.
    mission : Mission
        The mission PX4 flew.
    build : Px4Build
        The PX4 that flew it.
    instance : int
        Its instance.
    ulog : pathlib.Path or None
        The ULog PX4's logger wrote: ``out``/px4.ulg, or without ``out`` a copy in a
        temporary folder (``quadcog-px4-log-*``) that the caller may remove.
    console : pathlib.Path
        PX4's console output (px4.log beside it).
    """
    result: SimulationResult
    recording: Recording
    scenario: Scenario
    mission: Mission
    build: Px4Build
    instance: int
    ulog: Path | None
    console: Path

    @property
    def partial(self) -> bool:
        """The flight stopped before the mission ended."""
        return self.recording.partial

    @property
    def speed(self) -> float:
        """Simulated seconds per wall second in lockstep (0 when PX4 never answered)."""
        r = self.recording
        return r.lockstep_seconds / r.wall_seconds if r.wall_seconds > 0 else 0.0

    def summary(self) -> dict[str, Any]:
        """The ``px4`` entry of metrics.json.

        Returns
        -------
        dict
            partial, reason, armed_at, disarmed_at (s, PX4's time), speed (x real time),
            lockstep seconds, wall seconds, CPU seconds of each side, instance, PX4's commit and
            build key, the mission's waypoints, PX4's messages.
        """
        r = self.recording
        return {"partial": r.partial, "reason": r.reason, "armed_at": r.armed_at,
                "disarmed_at": r.disarmed_at, "speed": round(self.speed, 2),
                "lockstep_seconds": round(r.lockstep_seconds, 3),
                "wall_seconds": round(r.wall_seconds, 3),
                "waiting_for_px4_seconds": round(r.wait_seconds, 3),
                "cpu_seconds_px4": round(r.cpu_px4, 3),
                "cpu_seconds_quadcog": round(r.cpu_quadcog, 3),
                "instance": self.instance, "px4": self.build.commit(),
                "build_key": self.build.key, "airframe": SIM_AIRFRAME,
                "waypoints": [list(w.position) + [w.hold] for w in self.mission.waypoints],
                "statustext": [[round(t, 3), s] for t, s in r.statustext]}


def _point(p: Any) -> tuple[float, float, float]:
    return float(p[0]), float(p[1]), float(p[2])


def mission_of(scenario: Scenario) -> Mission:
    """The mission of a scenario's trajectory (see the module docstring).

    Parameters
    ----------
    scenario : Scenario
        Its trajectory and duration.

    Returns
    -------
    Mission
        Take-off, the waypoints, landing.

    Raises
    ------
    quadcog.Px4Error
        A trajectory that goes to or below the ground (z <= 0).
    """
    traj = scenario.trajectory
    if isinstance(traj, Hover):
        return Mission((Waypoint(_point(traj.position), scenario.duration),))
    if isinstance(traj, MinimumSnap):       # its waypoints, the duration spread over them
        corners = np.asarray(traj.waypoints, float)
        return Mission(tuple(Waypoint(_point(p), scenario.duration / len(corners))
                             for p in corners))
    t = np.linspace(0.0, scenario.duration, _MISSION_POINTS + 1)
    sampled = traj.sample(t)[:, :3]
    points = [Waypoint(_point(sampled[0]), 2.0)] + [Waypoint(_point(q)) for q in sampled[1:]]
    return Mission(tuple(points))


def _progress_line(t: float, link: MissionLink, speed: float) -> None:
    import sys
    print(f"quadcog px4: t = {t:6.1f} s  {link.state:<16s} item {link.current:2d}  "
          f"{speed:5.1f}x real time", file=sys.stderr, flush=True)


# PX4's SITL start-up (rcS) sources px4-rc.mavlink from PATH before its own etc/init.d-posix:
# this one starts only the link the mission needs, with few streams. PX4's own starts four
# links (ground station, API, camera, gimbal) streaming at up to 4 Mbit/s; in lockstep each
# link's thread wakes every millisecond of PX4's time, and those wake-ups cost more than
# everything else PX4 does.
_MAVLINK_LINKS = """#!/bin/sh
# written by quadcog.px4: the mission link only (PX4 listens on 14580 + i, sends to 14540 + i)
mavlink start -u $((14580+px4_instance)) -r 200000 -m minimal -o $((14540+px4_instance))
mavlink stream -r 1 -s EXTENDED_SYS_STATE -u $((14580+px4_instance))
"""


def _mavlink_links(workdir: Path) -> str:
    """PATH for PX4's start-up with quadcog's px4-rc.mavlink first."""
    rc = workdir / "rc"
    rc.mkdir(parents=True, exist_ok=True)
    (rc / "px4-rc.mavlink").write_text(_MAVLINK_LINKS)
    return str(rc) + os.pathsep + os.environ.get("PATH", "")


def fly(scenario: Scenario | str | os.PathLike[str], px4: str | os.PathLike[str] | None = None,
        out: str | os.PathLike[str] | None = None, mission: Mission | None = None,
        sensing: Px4Sensing | None = None, max_time: float | None = None,
        connect_timeout: float = 60.0, answer_timeout: float = 10.0,
        arm_timeout: float = 120.0, allow_build: bool = True, progress: bool = False,
        overrides: tuple[str, ...] = (), params: dict[str, float] | None = None) -> Px4Flight:
    """Fly a scenario with PX4 in the loop (see the module docstring).

    Parameters
    ----------
    scenario : Scenario, str or os.PathLike
        A Scenario, a scenario file or a shipped scenario's name.
    px4 : str or os.PathLike, optional
        A PX4-Autopilot tree or tarball (default: $QUADCOG_PX4, else the shared tarball;
        ``quadcog.px4.tree.find_source``).
    out : str or os.PathLike, optional
        Write the run files, px4.ulg and px4.log there (``write_px4_outputs``).
    mission : Mission, optional
        Instead of the scenario's (``mission_of``).
    sensing : Px4Sensing, optional
        The sensors (``quadcog.px4.sensors``); default ``Px4Sensing(imu)`` with the
        scenario's ``[sensing]`` table as the IMU, or ``Sensing()`` without one.
    max_time : float, optional
        Longest flight in PX4's time (s); default arm_timeout + the scenario's duration +
        the mission's travel + 60 s.
    connect_timeout : float
        Wall seconds for PX4 to start and connect.
    answer_timeout : float
        Wall seconds PX4 may take to answer one lockstep step.
    arm_timeout : float
        Seconds of PX4's time for it to accept arming.
    allow_build : bool
        Build PX4 into the cache when no build is there (else raise).
    progress : bool
        A line on stderr every 10 s of PX4's time.
    overrides : tuple of str
        ``--set`` texts for a scenario given by name or file.
    params : dict of str to float, optional
        PX4 parameters set at start-up over the airframe's (e.g. ``{"MPC_XY_CRUISE": 2}``).

    Returns
    -------
    Px4Flight
        The flight (``partial`` when it stopped early).

    Raises
    ------
    quadcog.Px4Error
        No tree, a failed build, no free instance, PX4 refusing the vehicle or the mission.
    quadcog.Px4TimeoutError
        PX4 did not connect, or stopped answering.
    quadcog.errors.MissingDependencyError
        Without pymavlink (the ``px4`` extra).
    """
    require_extra("px4", "pymavlink")
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario, overrides)
    for name, v in (("connect_timeout", connect_timeout), ("answer_timeout", answer_timeout),
                    ("arm_timeout", arm_timeout)):
        positive(v, name, unit="s")
    found = cached_build(px4)
    if found is None:
        if not allow_build:
            raise Px4Error("PX4 is not built in the cache: run `make px4-build` (or "
                           "quadcog.px4.tree.build())")
        found = build(px4)
    vehicle = scenario.vehicle
    airframe = read_airframe(found.source)
    check_rotors(airframe, vehicle)
    rotors = rotor_map(airframe, vehicle)
    mission = mission or mission_of(scenario)
    travel = sum(float(np.linalg.norm(np.subtract(a.position, b.position))) for a, b in
                 zip(mission.waypoints[1:], mission.waypoints[:-1]))
    holds = sum(w.hold for w in mission.waypoints)
    max_time = max_time or (arm_timeout + holds + travel + mission.waypoints[0].position[2]
                            + 90.0)
    positive(max_time, "max_time", unit="s")

    cog = as_cog_profile(scenario.cog)
    loads = as_payload_profile(scenario.payloads, vehicle)
    P = vehicle.airframe.parameters()
    check_cog_changes(P, cog)
    check_payload_events(vehicle, loads)
    dt = scenario.dt
    schedule = Schedule.build(Hover(), max_time, dt, cog, scenario.disturbances,
                              payloads=loads)
    actuation = Actuation.of(vehicle, scenario.truth)
    if sensing is None:
        sensing = Px4Sensing(scenario.sensing or Sensing())
    elif not isinstance(sensing, Px4Sensing):
        raise Px4Error(f"sensing: expected a quadcog.px4.sensors.Px4Sensing, got {sensing!r}")
    sensors = Sensors(earth_field(found.source, HOME[0], HOME[1]), float(P[IDX["g"]]),
                      1.0 / PERIOD, sensing)

    instance, server = free_instance()
    link = MissionLink(mission, instance, arm_timeout)
    workdir = Path(tempfile.mkdtemp(prefix=f"quadcog-px4-{instance}-"))
    env = {"PX4_SYS_AUTOSTART": str(SIM_AIRFRAME), "PX4_SIM_MODEL": SIM_MODEL,
           **px4_parameters({**airframe, **(params or {})}), "PATH": _mavlink_links(workdir)}
    try:
        link.open()
        with Px4Process(found.binary, found.etc, instance, workdir, env) as proc:
            rec = run_lockstep(proc, server, link, schedule, P, actuation, rotors, sensors,
                               max_time, connect_timeout, answer_timeout,
                               progress=_progress_line if progress else None)
        time.sleep(0.05)
        ulogs = sorted((workdir / "log").rglob("*.ulg"), key=lambda p: p.stat().st_mtime)
        keep = Path(tempfile.mkdtemp(prefix="quadcog-px4-log-"))
        ulog = None
        if ulogs:
            ulog = keep / "px4.ulg"
            shutil.copyfile(ulogs[-1], ulog)
        console = keep / "px4.log"
        shutil.copyfile(proc.log, console)
    finally:
        link.close()
        server.close()
        shutil.rmtree(workdir, ignore_errors=True)
    flight = Px4Flight(_result(rec, P, schedule, actuation), rec, scenario, mission, found,
                       instance, ulog, console)
    if out is not None:         # the files move into out; the temporary folder goes
        write_px4_outputs(flight, out)
        flight.ulog = Path(out) / "px4.ulg" if ulog is not None else None
        flight.console = Path(out) / "px4.log"
        shutil.rmtree(keep, ignore_errors=True)
    return flight


def _result(rec: Recording, P: np.ndarray, schedule: Schedule, actuation: Actuation
            ) -> SimulationResult:
    n = rec.n
    rows = rec.schedule_index[:n]
    load = schedule.payload[rows]
    r_air = schedule.r_G(P[R_G])[rows]
    mass, r_G = body_mass_and_cog(P[IDX["m"]], r_air, load[:, PI_INDEX["m"], None],
                                  load[:, [PI_INDEX[f"m{a}_G"] for a in "xyz"]])
    x, ref = rec.x[:n], rec.reference()
    e = position_errors(x, ref)
    t = rec.t
    tail = t >= 0.75 * t[-1] if n else np.zeros(0, bool)     # the last quarter
    metrics = flight_metrics(e, tail, None, None, None, Limits())
    return SimulationResult(t, x.copy(), rec.U[:n].copy(), ref, np.zeros((n, 3)), r_G,
                            metrics, controller="PX4 (EKF2, mc_pos_control, mc_att_control, "
                            "mc_rate_control)", path="px4",
                            info={"seconds": rec.wall_seconds},
                            rotor_thrust=rec.rotor_thrust[:n].copy(), mass=mass[:, 0],
                            _rotor_command=rec.rotor_command[:n].copy())


def write_px4_outputs(flight: Px4Flight, out: str | os.PathLike[str], plot: bool = True,
                      every: int = 10) -> Path:
    """The run files of a PX4 flight, px4.ulg and px4.log, into ``out``, all or none.

    Parameters
    ----------
    flight : Px4Flight
        The flight.
    out : str or os.PathLike
        The folder.
    plot : bool
        Draw flight.png (matplotlib).
    every : int
        Write every ``every``-th sample (and the last) into trajectory.csv.

    Returns
    -------
    pathlib.Path
        The folder.
    """
    result, scenario = flight.result, flight.scenario
    metrics = result.metrics.as_dict()
    metrics.update(name=scenario.name, controller="px4", duration=scenario.duration,
                   dt=scenario.dt, simulated_until=float(result.t[-1]) if result.t.size else 0.0,
                   wall_time_s=flight.recording.wall_seconds, px4=flight.summary(),
                   partial=flight.partial)
    with RunFiles(out, owned=PX4_FILES) as files:
        write_table(result, files.path("trajectory.csv"), every=every)
        if plot and result.t.size > 1:
            from quadcog.viz.plots import plot_flight
            plot_flight(result, files.path("flight.png"), name=f"{scenario.name} (PX4)",
                        disturbances=scenario.disturbances)
        files.path("vehicle.json").write_text(strict_json(scenario.vehicle.as_dict()))
        if flight.ulog is not None:
            shutil.copyfile(flight.ulog, files.path("px4.ulg"))
        shutil.copyfile(flight.console, files.path("px4.log"))
        files.path("metrics.json").write_text(strict_json(metrics))
    return Path(out)
