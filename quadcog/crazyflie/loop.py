"""One flight of the Crazyflie firmware in quadcog's truth plant: ``simulate``.

The firmware's C (its controllers, power distribution, thrust map and battery compensation,
``quadcog.crazyflie.firmware``) and a C driver loop are one shared library; quadcog's plant
step (the generated truth model, RK4, motor lag, CoG and payload schedule) is a second one,
passed to the loop as a function pointer. The whole flight is one call. The firmware keeps its
controllers' state in C statics, so every flight loads its own copy of the library (copied
under a unique name, opened, closed and removed): two flights never share a controller's
state, in one process or many.
"""
import _ctypes
from collections.abc import Mapping, Sequence
import contextlib
import ctypes
import os
from pathlib import Path
import shutil
import tempfile
import time
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.codegen.compiler import compile_library
from quadcog.crazyflie.firmware import CONTROLLERS, OUT_OF_TREE, build_firmware, constants
from quadcog.crazyflie.law import LAWS, law_sources
from quadcog.errors import InputError, StackError
from quadcog.model.conventions import IDX, N_STATE, R_G
from quadcog.model.functions import load
from quadcog.sim.divergence import DivergenceCause, Limits
from quadcog.sim.plant import PI_INDEX, Actuation, TruthOptions, body_mass_and_cog, plant_step_function
from quadcog.sim.prepare import prepare_flight
from quadcog.sim.result import SimulationResult, flight_metrics, position_errors
from quadcog.sim.schedule import cog_at
from quadcog.sim.sensing import Sensing
from quadcog.trajectories.analytic import ACC, JERK, POS, VEL, YAW, YAW_RATE
from quadcog.vehicles.vehicle import CRAZYFLIE_21, Vehicle, x_layout

__all__ = ["DT", "DEFAULT_LOG", "sensing_noise", "simulate"]

DT = 0.001                 # s: the firmware's RATE_MAIN_LOOP, 1 kHz
FIRMWARE_DIVERGED = 4      # the loop's code when the firmware asserted
# recorded unless the caller names others: the PID's commands and the motor PWMs
DEFAULT_LOG = ("controller.cmd_thrust", "controller.cmd_roll", "controller.cmd_pitch",
               "controller.cmd_yaw", "motor.m1", "motor.m2", "motor.m3", "motor.m4")
_REF_COLUMNS = [*range(POS.start, POS.stop), *range(VEL.start, VEL.stop),
                *range(ACC.start, ACC.stop), *range(JERK.start, JERK.stop), YAW, YAW_RATE]


class _Flight(ctypes.Structure):
    """``struct qc_flight`` of loop.c."""
    _fields_ = [("n_steps", ctypes.c_long), ("controller", ctypes.c_int), ("nf", ctypes.c_int),
                ("dt", ctypes.c_double), ("battery", ctypes.c_double),
                ("thrust_map", ctypes.c_double * 4), ("max_thrust", ctypes.c_double),
                ("mixer", ctypes.c_double * 16), ("max_position_error", ctypes.c_double),
                ("max_tilt", ctypes.c_double),
                *[(n, ctypes.c_void_p) for n in ("P", "payload", "r_stated", "wrench", "ref",
                                                 "noise", "X", "U", "F")],
                ("n_log", ctypes.c_int), ("log_index", ctypes.c_void_p),
                ("log_out", ctypes.c_void_p), ("plant", ctypes.c_void_p),
                ("iw", ctypes.c_void_p), ("w", ctypes.c_void_p)]


_plants: dict[Actuation, tuple[Path, int, int]] = {}


def _plant(actuation: Actuation) -> tuple[Path, int, int]:
    """The plant step's library (CasADi's C of ``plant_step_function``) and its work sizes."""
    if actuation not in _plants:
        fn = plant_step_function(load(), actuation)
        cg = ca.CodeGenerator("qc_plant.c", {"with_header": False, "casadi_int": "long long int"})
        cg.add(fn)
        lib = compile_library(cg.dump().encode(), "crazyflie-plant")
        _plants[actuation] = (lib, int(fn.sz_iw()), int(fn.sz_w()))
    return _plants[actuation]


def _check_x_frame(vehicle: Vehicle) -> None:
    """The firmware's mixers fly an "X" frame with M1 front-right .. M4 front-left, M2 and M4
    turning clockwise; refuse a vehicle whose rotors are not in that order."""
    pos = np.asarray(vehicle.rotor_positions)
    signs_ok = (np.sign(pos) == np.sign(np.asarray(x_layout(1.0)))).all()
    if not signs_ok or tuple(vehicle.rotor_directions) != (-1, 1, -1, 1):
        raise InputError(f"vehicle {vehicle.name!r}: the Crazyflie firmware's mixers fly an "
                         "'X' frame with rotor 1 front-right, 2 back-right, 3 back-left, 4 "
                         "front-left and rotor_directions (-1, 1, -1, 1); got rotor_positions "
                         f"{vehicle.rotor_positions} and rotor_directions "
                         f"{vehicle.rotor_directions} (in a scenario: vehicle.preset = "
                         "\"crazyflie21\")")


@contextlib.contextmanager
def _own_copy(library: Path):
    """A private copy of the library, opened: fresh C statics for one flight."""
    folder = Path(tempfile.mkdtemp(prefix="quadcog-crazyflie-"))
    try:
        path = folder / f"{library.stem}-{os.getpid()}.so"
        shutil.copyfile(library, path)
        lib = ctypes.CDLL(str(path), mode=ctypes.RTLD_LOCAL)
        try:
            yield lib
        finally:
            handle = lib._handle
            del lib
            _ctypes.dlclose(handle)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _table(lib: ctypes.CDLL, kind: str) -> dict[str, int]:
    count = getattr(lib, f"qc_{kind}_count")
    group, name = getattr(lib, f"qc_{kind}_group"), getattr(lib, f"qc_{kind}_name")
    group.restype = name.restype = ctypes.c_char_p
    return {f"{group(i).decode()}.{name(i).decode()}": i for i in range(count())}


def _controller(controller: Any) -> tuple[int, Path | None, str]:
    if isinstance(controller, str) and controller in CONTROLLERS:
        return CONTROLLERS[controller], None, controller
    if isinstance(controller, (str, os.PathLike)) and Path(controller).is_dir():
        return OUT_OF_TREE, Path(controller), f"out-of-tree {Path(controller).name}"
    if isinstance(controller, str) and controller in LAWS:      # its app, once the vehicle is known
        return OUT_OF_TREE, None, f"quadcog {controller}"
    validate.fail("controller", f"one of {tuple(CONTROLLERS)}, a quadcog law {tuple(LAWS)} or "
                  "the folder of an out-of-tree controller's C sources", controller)


def sensing_noise(sensing: Sensing, n: int) -> npt.NDArray[np.float64] | None:
    """What ``sensing`` adds to the firmware's inputs over n ticks.

    Parameters
    ----------
    sensing : Sensing
        Its noise flag, standard deviations, seed and gyroscope bias.
    n : int
        Ticks.

    Returns
    -------
    (n, 12) numpy.ndarray or None
        Position (m), world velocity (m/s), Euler angles (rad), body rates (rad/s, the bias
        included); None without noise.
    """
    if not isinstance(sensing, Sensing):
        validate.fail("sensing", "a quadcog.sim.sensing.Sensing", sensing)
    if not sensing.noise:
        return None
    sig = sensing.sigmas(DT)          # state order: position, attitude, velocity, rates
    sig = np.concatenate([sig[0:3], sig[6:9], sig[3:6], sig[9:12]])
    rows = np.random.default_rng(sensing.seed).normal(size=(n, 12)) * sig
    rows[:, 9:] += sensing.bias()
    return rows


def simulate(controller: Any = "pid", trajectory: Any = "hover", duration: float = 10.0,
             vehicle: Vehicle | None = None, cog: Any = None, payloads: Any = None,
             disturbances: Any = (), truth: TruthOptions | None = None,
             firmware: str | os.PathLike[str] | None = None, propellers: str = "2.1+",
             battery_voltage: float = 4.0, params: Mapping[str, float] | None = None,
             log: Sequence[str] = DEFAULT_LOG, x0: npt.ArrayLike | None = None,
             limits: Limits | None = None, sensing: Sensing | None = None) -> SimulationResult:
    """Fly the Crazyflie firmware's controller in quadcog's truth plant, one tick per 1 ms.

    Parameters
    ----------
    controller : str or os.PathLike
        ``"pid"``, ``"mellinger"``, ``"indi"``, ``"brescianini"``, ``"lee"``, or the folder of
        an out-of-tree controller app (C sources in it or in its ``src/`` defining
        ``controllerOutOfTreeInit``, ``controllerOutOfTreeTest``, ``controllerOutOfTree``),
        compiled in with ``CONFIG_CONTROLLER_OOT``, or a quadcog law's name (a key of
        ``quadcog.controllers.CONTROLLERS``): its app (``quadcog export --target crazyflie``)
        written for ``vehicle`` as ``quadcog.simulate`` designs the law by default
        (``quadcog.crazyflie.law``) and flown as that out-of-tree controller.
    trajectory : Trajectory, str or callable
        As for ``quadcog.simulate``; the firmware gets it as the high-level commander's
        full-state setpoint (position, velocity, acceleration, jerk, yaw, yaw rate).
    duration : float
        Seconds.
    vehicle : Vehicle, optional
        The truth vehicle (default ``CRAZYFLIE_21``); an "X" frame in the firmware's motor
        order. Its ``rotor_model`` is not used: the thrust map is the firmware's own.
    cog : CogProfile or list of (t, r, ramp), optional
        The CoG changes, as for ``quadcog.simulate``.
    payloads : sequence of PayloadEvent or dict, optional
        Payload events, as for ``quadcog.simulate``.
    disturbances : sequence of Disturbance
        Wrench pulses, as for ``quadcog.simulate``.
    truth : TruthOptions, optional
        As for ``quadcog.simulate``: ``rotor_saturation`` caps each rotor at the vehicle's
        ``max_rotor_thrust`` beyond the PWM's own cap; ``motor_lag`` lags the rotors. Default
        ``TruthOptions(motor_lag=True)``: without the lag the firmware's rate loops chatter
        (the PID's once it must hold a torque, Mellinger's and Brescianini's at hover).
    x0 : (12,) array_like, optional
        Initial state, as for ``quadcog.simulate``.
    limits : Limits, optional
        When a run counts as diverged, as for ``quadcog.simulate``.
    firmware : str or os.PathLike, optional
        The firmware tree (default ``$QUADCOG_CRAZYFLIE_FIRMWARE``, else the vendor tarball).
    propellers : str
        ``"2.1+"`` (the firmware's default), ``"legacy"`` or ``"upgrade-kit"``: the thrust map
        and limits the firmware is built with; the truth rotors follow the same map.
    battery_voltage : float
        The battery's voltage (V), constant; the firmware's battery compensation filters it.
    params : mapping of str to float, optional
        Firmware parameters set before the flight, by firmware name (``"pid_rate.roll_kp"``).
    log : sequence of str
        Firmware log variables recorded every tick, by firmware name (``"group.name"``).
    sensing : Sensing, optional
        Gaussian noise (``Sensing.sigmas`` at 1 ms, from its seed) and the gyroscope bias added
        to what the firmware is told each tick: position, world velocity, attitude, body
        rates. Its ``delay`` is not applied (the firmware's own timing is the tick).

    Returns
    -------
    SimulationResult
        As ``quadcog.simulate``'s, ``path="crazyflie"``; ``info["log"]`` maps each recorded
        firmware name to its (N,) values (the last sample repeats the last tick's),
        ``info["console"]`` is what the firmware printed, ``info["nonfinite_control_ticks"]``
        counts the ticks whose force-torque ``control_t`` was not finite (the firmware's
        power distribution turns such a command into motors off), ``rotor_thrust`` is the
        thrust the PWMs gave.

    Raises
    ------
    quadcog.StackError
        No firmware tree or not one, structs that differ, no compiler, a failed build (its
        first error line), or the firmware asserted during the flight.
    quadcog.InputError
        A bad argument, a log or parameter name the firmware does not have.
    """
    kind, oot, name = _controller(controller)
    vehicle = CRAZYFLIE_21 if vehicle is None else vehicle
    if not isinstance(vehicle, Vehicle):
        validate.fail("vehicle", "a quadcog Vehicle", vehicle)
    _check_x_frame(vehicle)
    if kind == OUT_OF_TREE and oot is None:     # a quadcog law: its app written for the vehicle
        oot = law_sources(controller, vehicle)
    battery = validate.real(battery_voltage, "battery_voltage", lo=2.0, hi=5.0, unit="V")
    params = dict(params or {})
    log = tuple(log)
    build = build_firmware(firmware, propellers, oot)
    c = constants(build.tree, propellers)
    truth = TruthOptions(motor_lag=True) if truth is None else truth
    hold = lambda t, x, ref, s: np.zeros(4)     # never called: the firmware flies
    setup = prepare_flight(hold, trajectory, duration, DT, vehicle, None, cog, disturbances,
                           truth, x0, "python", limits, None, False, payloads)
    s, P, actuation = setup.schedule, setup.P, setup.actuation
    n, nf = s.n_steps, setup.n_rotor_states
    noise = None if sensing is None else sensing_noise(sensing, n)
    plant_lib, n_iw, n_w = _plant(actuation)
    plant = ctypes.CDLL(str(plant_lib))
    Pn = np.tile(P, (n, 1))
    Pn[:, R_G] = cog_at(P[R_G], s.cog_scale[:n, None], s.cog[:n])
    payload = np.ascontiguousarray(s.payload[:n])
    wrench = np.ascontiguousarray(s.wrench[:n])
    ref = np.ascontiguousarray(s.ref[:, _REF_COLUMNS])
    X = np.zeros((n + 1, N_STATE + nf))
    X[0] = setup.X0[:N_STATE + nf]
    U = np.zeros((n + 1, 4))
    F = np.zeros((n + 1, 4))
    r_stated = np.ascontiguousarray(P[R_G])
    iw = np.zeros(max(n_iw, 1), dtype=np.int64)
    w = np.zeros(max(n_w, 1))
    t0 = time.perf_counter()
    with _own_copy(build.library) as lib:
        logs, table = _table(lib, "log"), _table(lib, "param")
        missing = [v for v in log if v not in logs]
        if missing:
            raise InputError(f"log: the firmware has no log variable {missing[0]!r}; it has "
                             f"{len(logs)}, e.g. {', '.join(list(logs)[:6])}")
        lib.qc_init(kind)
        for key, value in params.items():
            if key not in table:
                raise InputError(f"params: the firmware has no parameter {key!r}; it has "
                                 f"{len(table)}, e.g. {', '.join(list(table)[:6])}")
            lib.qc_param_set.argtypes = [ctypes.c_int, ctypes.c_double]
            if lib.qc_param_set(table[key], validate.real(value, f"params[{key!r}]")):
                raise InputError(f"params: {key!r} is read-only in the firmware")
        index = np.array([logs[v] for v in log] or [0], dtype=np.int32)
        out = np.zeros((n + 1, max(len(log), 1)), dtype=np.float32)
        f = _Flight(n_steps=n, controller=kind, nf=nf, dt=DT, battery=battery,
                    max_thrust=actuation.upper if np.isfinite(actuation.upper) else 0.0,
                    max_position_error=setup.limits.max_position_error,
                    max_tilt=setup.limits.max_tilt, n_log=len(log))
        f.thrust_map[:] = [c[f"VMOTOR2THRUST{k}"] for k in range(4)]
        f.mixer[:] = actuation.mixer
        arrays = dict(P=Pn, payload=payload, r_stated=r_stated, wrench=wrench, ref=ref,
                      noise=noise, X=X, U=U, F=F)
        for key, a in arrays.items():
            setattr(f, key, None if a is None else a.ctypes.data)
        f.log_index, f.log_out = index.ctypes.data, out.ctypes.data
        f.plant = ctypes.cast(plant.plant_step, ctypes.c_void_p).value
        f.iw, f.w = iw.ctypes.data, w.ctypes.data
        code = ctypes.c_int(0)
        lib.qc_run.restype = ctypes.c_long
        ran = lib.qc_run(ctypes.byref(f), ctypes.byref(code))
        lib.qc_console.restype = lib.qc_assert_message.restype = ctypes.c_char_p
        console = lib.qc_console().decode(errors="replace")
        lib.qc_nonfinite_control.restype = ctypes.c_long
        nonfinite = int(lib.qc_nonfinite_control())
        if code.value == FIRMWARE_DIVERGED:
            raise StackError(f"the firmware asserted at t = {ran * DT:.3f} s: "
                             f"{lib.qc_assert_message().decode(errors='replace')}")
    elapsed = time.perf_counter() - t0
    result = _result(setup, X, U, F, out, log, ran, code.value, elapsed, name, build, console)
    result.info["nonfinite_control_ticks"] = nonfinite
    return result


def _result(setup, X, U, F, out, log, ran, code, elapsed, name, build, console):
    """The SimulationResult of ``ran`` ticks (stopped with ``code``)."""
    s, P = setup.schedule, setup.P
    keep = ran + 1
    if code:           # like quadcog.simulate: keep the diverged sample when it is finite
        keep = ran + 1 if np.isfinite(X[ran]).all() else ran
    U[ran], F[ran], out[ran] = U[ran - 1], F[ran - 1], out[ran - 1]
    t, ref = s.t[:keep], s.ref[:keep]
    load = s.payload[:keep]
    r_G0 = s.r_G(P[R_G])[:keep]
    mass, r_G = body_mass_and_cog(P[IDX["m"]], r_G0, load[:, PI_INDEX["m"], None],
                                  load[:, [PI_INDEX[f"m{a}_G"] for a in "xyz"]])
    x = X[:keep, :N_STATE]
    e = position_errors(x, ref)
    idx = ran if code else None
    cause = DivergenceCause(code) if code else None
    metrics = flight_metrics(e, s.tail[:keep], idx, None if idx is None else s.t[idx], cause,
                             setup.limits)
    thrust = F[:keep]
    info = {"seconds": elapsed, "firmware": str(build.tree), "propellers": build.propellers,
            "log": {v: out[:keep, j].astype(float) for j, v in enumerate(log)},
            "console": console}
    return SimulationResult(t, x, U[:keep], ref, np.zeros((keep, 3)), r_G, metrics,
                            controller=f"crazyflie {name}", path="crazyflie", info=info,
                            rotor_thrust=thrust, mass=mass[:, 0],
                            controller_state=np.zeros((keep, 0)),
                            _command_law=lambda: thrust.copy())
