"""Scenario files (TOML): parse, validate with messages naming file and key, run, write results.

A scenario names a controller, a trajectory, CoG changes, disturbances, the truth vehicle
(``[vehicle]``) and what the controller believes (``[controller_model]``), controller
parameters and truth-model switches; `quadcog run FILE --out DIR` writes
metrics.json, vehicle.json, trajectory.csv and flight.png. The keys are documented in README.md.
"""
from dataclasses import dataclass, field
import csv
import json
import math
from pathlib import Path
import tomllib
import warnings

import numpy as np

from . import config
from .catalog import scenario_path
from .controllers import BY_NAME, make_controller
from .sensing import Sensed, Sensing
from .columns import trajectory_columns
from .errors import InputError
from .plant import TruthOptions
from .progress import ProgressBar
from .simulation import Limits, simulate, start_at_reference
from .timeline import CogChange, CogProfile, Disturbance
from .trajectory import Circle, Figure8, Helix, Hover
from .vehicle import FIELD_NAMES, HUMMINGBIRD, PRESETS


class ScenarioError(InputError):
    """A scenario file is malformed: the message names the file, the key and what was expected."""


NUMBER = (int, float)
TRAJECTORIES = {
    "hover": (Hover, {"position": "vec3", "yaw": NUMBER}),
    "circle": (Circle, {"center": "vec3", "radius": NUMBER, "period": NUMBER, "yaw": NUMBER}),
    "figure8": (Figure8, {"center": "vec3", "size": NUMBER, "period": NUMBER, "yaw": NUMBER}),
    "helix": (Helix, {"center": "vec3", "radius": NUMBER, "period": NUMBER,
                      "climb_rate": NUMBER, "yaw": NUMBER}),
}
CONTROLLER_PARAMS = {
    "pd": {"poles_z": "vec", "poles_psi": "vec", "poles_x": "vec", "poles_y": "vec",
           "max_tilt": NUMBER},
    "fl": {"poles_z": "vec", "poles_attitude": "vec", "poles_psi": "vec",
           "poles_position": "vec", "max_tilt": NUMBER},
}
CONTROLLER_PARAMS["adaptive"] = dict(CONTROLLER_PARAMS["fl"], gamma="number_or_vec3",
                                     projection_radius="number_or_false", Q_scale=NUMBER)
CONTROLLER_PARAMS["fl_integral"] = dict(CONTROLLER_PARAMS["fl"], integral_pole=NUMBER,
                                        integral_limit=NUMBER)
CONTROLLER_PARAMS["composite"] = dict(
    CONTROLLER_PARAMS["adaptive"], filter_rate=NUMBER, ls_gain=NUMBER, forgetting=NUMBER,
    covariance_bound=NUMBER, force_weight=NUMBER, allocation=bool, motor_lag=bool)
TOP = {"name": str, "description": str, "controller": str, "duration": NUMBER, "dt": NUMBER,
       "path": str, "trajectory": dict, "cog": list, "disturbance": list, "vehicle": dict,
       "controller_model": dict, "controller_params": dict, "truth": dict, "limits": dict,
       "sensing": dict,
       "initial_offset": "vec3"}
# every Vehicle field, and a preset to start from
VEHICLE = {name: {"rotor_positions": "pairs4", "rotor_directions": "vec",
                  "name": str}.get(name, NUMBER) for name in FIELD_NAMES}
VEHICLE["preset"] = str
TRUTH = {"parallel_axis": bool, "rotor_saturation": bool, "motor_lag": bool}
SENSING = {"noise": bool, "delay": bool, "seed": NUMBER, "position": NUMBER, "velocity": NUMBER,
           "attitude": NUMBER, "gyro_density": NUMBER, "gyro_bias": NUMBER}
LIMITS = {"max_position_error": NUMBER, "max_tilt_deg": NUMBER}
COG = {"t": NUMBER, "r": "vec3", "ramp": NUMBER}
DISTURBANCE = {"t": NUMBER, "duration": NUMBER, "force": "vec3", "moment": "vec3"}


@dataclass
class Scenario:
    """A validated scenario, ready to run."""
    name: str
    controller: str
    duration: float
    dt: float = field(default_factory=lambda: config.defaults["simulate.dt"])
    description: str = ""
    path: str = "compiled"
    trajectory: object = field(default_factory=Hover)
    cog: CogProfile = field(default_factory=CogProfile)
    disturbances: list = field(default_factory=list)
    vehicle: object = HUMMINGBIRD                 # the truth Vehicle
    controller_model: object = None               # what the controller believes (a Vehicle)
    controller_params: dict = field(default_factory=dict)
    truth: TruthOptions = field(default_factory=TruthOptions)
    sensing: Sensing | None = None
    limits: Limits = field(default_factory=Limits)
    initial_offset: tuple = (0.0, 0.0, 0.0)
    source: str = "<scenario>"

    def make_controller(self):
        """The scenario's controller, designed for its controller model."""
        params = dict(self.controller_params)
        if "Q_scale" in params:
            params["Q"] = np.eye(8) * params.pop("Q_scale")
        if params.get("projection_radius") is False:
            params["projection_radius"] = None
        ctl = make_controller(self.controller, vehicle=self.model_vehicle(), **params)
        return ctl if self.sensing is None else Sensed(ctl, self.sensing, self.dt)

    def model_vehicle(self):
        """The controller's model: ``controller_model``, or the truth vehicle with r_G = 0."""
        if self.controller_model is not None:
            return self.controller_model
        return self.vehicle.with_cog(np.zeros(3))

    def run(self, progress=None):
        """Simulate; returns a quadcog SimulationResult."""
        x0 = None
        if any(self.initial_offset):
            x0 = start_at_reference(self.trajectory(0.0))
            x0[:3] += np.asarray(self.initial_offset)
        return simulate(self.make_controller(), self.trajectory, duration=self.duration,
                        dt=self.dt, vehicle=self.vehicle, controller_model=self.model_vehicle(),
                        cog=self.cog, disturbances=self.disturbances,
                        truth=self.truth, x0=x0, path=self.path, limits=self.limits,
                        progress=progress)


def _type_name(kind):
    return {str: "a string", bool: "true or false", dict: "a table", list: "an array of tables",
            "vec3": "an array of 3 numbers", "vec": "an array of numbers",
            "number_or_vec3": "a number or an array of 3 numbers",
            "number_or_false": "a number or false",
            "pairs4": "an array of 4 arrays [x, y] of numbers"}.get(
        kind, "a number" if kind == NUMBER else str(kind))


def _check(value, kind, where):
    def is_num(v):
        return isinstance(v, NUMBER) and not isinstance(v, bool) and math.isfinite(v)
    ok = {
        "vec3": lambda v: isinstance(v, list) and len(v) == 3 and all(map(is_num, v)),
        "pairs4": lambda v: isinstance(v, list) and len(v) == 4 and all(
            isinstance(r, list) and len(r) == 2 and all(map(is_num, r)) for r in v),
        "vec": lambda v: isinstance(v, list) and len(v) > 0 and all(map(is_num, v)),
        "number_or_vec3": lambda v: is_num(v) or (isinstance(v, list) and len(v) == 3
                                                  and all(map(is_num, v))),
        "number_or_false": lambda v: v is False or is_num(v),
    }
    if kind in ok:
        good = ok[kind](value)
    elif kind == NUMBER:
        good = is_num(value)
    else:
        good = isinstance(value, kind)
    if not good:
        raise ScenarioError(f"{where}: expected {_type_name(kind)}, got {value!r}")
    return value


def _validate(table, schema, source, prefix="", what=""):
    """Check every key of ``table`` against ``schema`` (key -> expected type)."""
    for key, value in table.items():
        name = f"{source}: key {prefix + key!r}"
        if key not in schema:
            raise ScenarioError(f"{name}: unknown{what}; expected one of "
                                f"{', '.join(sorted(schema))}")
        _check(value, schema[key], name)


def _entries(data, key, schema, source, required):
    """Validate an array of tables; yields (where, entry) pairs."""
    for i, entry in enumerate(data.get(key, [])):
        where = f"{key}[{i}]"
        _validate(entry, schema, source, where + ".")
        for name in required:
            if name not in entry:
                raise ScenarioError(f"{source}: key {where!r}: missing key {name!r}")
        yield where, entry


def _cog_changes(data, source):
    changes, last = [], -math.inf
    for where, entry in _entries(data, "cog", COG, source, ("t", "r")):
        t, ramp = entry["t"], entry.get("ramp", 0.0)
        if t < 0 or ramp < 0:
            raise ScenarioError(f"{source}: key {where!r}: t and ramp must be >= 0 s, got "
                                f"t = {t}, ramp = {ramp}")
        if t < last:
            raise ScenarioError(f"{source}: key {where + '.t'!r}: expected entries in time "
                                f"order; t = {t} s starts before the previous change ends at "
                                f"{last} s")
        last = t + ramp
        changes.append(CogChange(float(t), tuple(entry["r"]), float(ramp)))
    return CogProfile(changes)


def _disturbances(data, source):
    pulses = []
    for where, entry in _entries(data, "disturbance", DISTURBANCE, source, ("t", "duration")):
        try:
            pulses.append(Disturbance(**entry))
        except InputError as e:
            raise ScenarioError(f"{source}: key {where!r}: {e}") from None
    return pulses


def parse(data, source="<scenario>"):
    """A Scenario from a parsed TOML dict; ScenarioError names ``source``, the key and the
    expectation."""
    _validate(data, TOP, source)
    for key in ("name", "controller", "duration"):
        if key not in data:
            raise ScenarioError(f"{source}: missing key {key!r}")
    w = lambda key: f"{source}: key {key!r}"
    controller = data["controller"]
    if controller not in BY_NAME:
        raise ScenarioError(f"{w('controller')}: expected one of {', '.join(BY_NAME)}, got "
                            f"{controller!r}")
    for key in ("duration", "dt"):
        if key in data and data[key] <= 0:
            raise ScenarioError(f"{w(key)}: expected a positive number of seconds, got "
                                f"{data[key]!r}")
    if data.get("path", "compiled") not in ("compiled", "python"):
        raise ScenarioError(f"{w('path')}: expected 'compiled' or 'python', got "
                            f"{data['path']!r}")
    traj = dict(data.get("trajectory", {"kind": "hover"}))
    kind = traj.pop("kind", None)
    if kind not in TRAJECTORIES:
        raise ScenarioError(f"{w('trajectory.kind')}: expected one of "
                            f"{', '.join(TRAJECTORIES)}, got {kind!r}")
    cls, schema = TRAJECTORIES[kind]
    _validate(traj, schema, source, "trajectory.", f" for kind {kind!r}")
    vehicle = _vehicle(data, "vehicle", None, source)
    controller_model = (_vehicle(data, "controller_model", vehicle.with_cog(np.zeros(3)), source)
                        if "controller_model" in data else None)
    cparams = data.get("controller_params", {})
    _validate(cparams, CONTROLLER_PARAMS[controller], source, "controller_params.",
              f" for controller {controller!r}")
    truth, limits = data.get("truth", {}), data.get("limits", {})
    sensing = data.get("sensing")
    if sensing is not None:
        _validate(sensing, SENSING, source, "sensing.")
        if "seed" in sensing:
            if sensing["seed"] != int(sensing["seed"]):
                raise ScenarioError(f"{source}: sensing.seed: expected an integer, got "
                                    f"{sensing['seed']!r}")
            sensing = dict(sensing, seed=int(sensing["seed"]))
    _validate(truth, TRUTH, source, "truth.")
    _validate(limits, LIMITS, source, "limits.")
    cog, pulses = _cog_changes(data, source), _disturbances(data, source)
    try:
        return Scenario(
            name=data["name"], controller=controller, duration=float(data["duration"]),
            dt=float(data.get("dt", config.defaults["simulate.dt"])), description=data.get("description", ""),
            path=data.get("path", "compiled"), trajectory=cls(**traj), cog=cog,
            disturbances=pulses, vehicle=vehicle, controller_model=controller_model,
            controller_params=dict(cparams),
            truth=TruthOptions(**truth),
            sensing=None if sensing is None else Sensing(**sensing),
            limits=Limits(
                limits.get("max_position_error", config.defaults["limits.max_position_error"]),
                math.radians(limits.get("max_tilt_deg", config.defaults["limits.max_tilt_deg"]))),
            initial_offset=tuple(data.get("initial_offset", (0.0, 0.0, 0.0))), source=source)
    except InputError as e:
        raise ScenarioError(f"{source}: {e}") from None


def _vehicle(data, key, base, source):
    """The Vehicle of table ``key``: its ``preset`` (default: ``base``, or the Hummingbird)
    with the fields the table sets."""
    table = dict(data.get(key, {}))
    _validate(table, VEHICLE, source, f"{key}.", " vehicle field")
    preset = table.pop("preset", None)
    if preset is not None:
        if preset not in PRESETS:
            raise ScenarioError(f"{source}: key '{key}.preset': expected one of "
                                f"{', '.join(PRESETS)}, got {preset!r}")
        base = PRESETS[preset]
    try:
        return (base or HUMMINGBIRD).replace(**table)
    except InputError as e:
        raise ScenarioError(f"{source}: key {key!r}: {e}") from None


def load_scenario(path, overrides=()):
    """Read and validate a scenario: a file path or the name of a shipped scenario ("fig6";
    see ``quadcog.catalog.scenario_path``). ``overrides``: ``--set`` texts ("vehicle.m=0.8",
    see ``quadcog.overrides``), applied before the validation, which then names them."""
    path = scenario_path(path)
    if path.is_dir():
        raise ScenarioError(f"{path}: is a folder, not a scenario file")
    if not path.is_file():
        raise ScenarioError(f"{path}: no such scenario file")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as e:
        raise ScenarioError(f"{path}: not valid TOML ({e})") from None
    except UnicodeDecodeError as e:
        raise ScenarioError(f"{path}: not UTF-8 text ({e.reason} at byte {e.start})") from None
    except OSError as e:
        raise ScenarioError(f"{path}: cannot be read ({e.strerror})") from None
    source = str(path)
    if overrides:
        from .overrides import apply_overrides
        data, notes = apply_overrides(data, overrides)
        for note in notes:
            warnings.warn(f"{path}: {note}", stacklevel=2)
        source = f"{path} with " + " ".join(f"--set {o}" for o in overrides)
    return parse(data, source)


def write_table(result, path, every=1, fmt="csv"):
    """The run's samples (every ``every``-th, and the last) into ``path`` as CSV or Parquet
    (``fmt``), with the column names of ``quadcog.columns.trajectory_columns()`` (units in the
    names). Returns the path written."""
    if not (isinstance(every, int) and not isinstance(every, bool) and every >= 1):
        raise InputError(f"every: expected a whole number >= 1 (write every N-th sample), "
                         f"got {every!r}")
    data = np.hstack([result.t[:, None], result.x, result.U, result.ref, result.r_hat,
                      result.r_G])
    rows = np.unique(np.r_[np.arange(0, len(data), every), len(data) - 1])
    data = data[rows]
    names = trajectory_columns()
    path = Path(path)
    if fmt == "parquet":
        try:
            import pyarrow as pa
            import pyarrow.parquet as pq
        except ImportError:
            raise InputError("format 'parquet' needs pyarrow: pip install pyarrow "
                             "(or use the default, csv)") from None
        pq.write_table(pa.table({n: data[:, k] for k, n in enumerate(names)}), path)
    elif fmt == "csv":
        with open(path, "w", newline="") as fh:
            writer = csv.writer(fh)
            writer.writerow(names)
            writer.writerows(np.round(data, 10).tolist())
    else:
        raise InputError(f"format: expected 'csv' or 'parquet', got {fmt!r}")
    return path


def write_outputs(result, scenario, out, plot=True, every=1, fmt="csv"):
    """metrics.json, vehicle.json, trajectory.csv (or .parquet: ``fmt``; every ``every``-th
    sample) and, with ``plot``, flight.png of one run into folder ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    metrics = result.metrics.as_dict()
    metrics.update(name=scenario.name, controller=scenario.controller,
                   duration=scenario.duration, dt=scenario.dt,
                   simulated_until=float(result.t[-1]), wall_time_s=result.info.get("seconds"))
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2) + "\n")
    (out / "vehicle.json").write_text(json.dumps(scenario.vehicle.as_dict(), indent=2) + "\n")
    write_table(result, out / f"trajectory.{fmt}", every=every, fmt=fmt)
    if plot:
        from .plots import plot_flight
        plot_flight(result, out / "flight.png", name=scenario.name,
                    disturbances=scenario.disturbances)
    return metrics


def run_with_progress(scenario, label=None, progress=True):
    """Run a scenario with a progress bar on stderr (or none); returns the result."""
    bar = ProgressBar(label or scenario.name) if progress else None
    try:
        return scenario.run(progress=bar)
    finally:
        if bar:
            bar.close()


def run_file(path, out=None, progress=True, overrides=(), plot=True, every=1, fmt="csv",
             animate=False):
    """`quadcog run`: load (with ``overrides``), simulate with a progress bar, write the
    outputs into ``out`` (default ``out/<scenario>`` in the current folder); returns metrics."""
    scenario = load_scenario(path, overrides)
    out = Path(out) if out is not None else default_out(path)
    try:
        result = run_with_progress(scenario, progress=progress)
    except ScenarioError:
        raise
    except InputError as e:                 # e.g. dt too large for the closed loop
        raise ScenarioError(f"{scenario.source}: {e}") from None
    metrics = write_outputs(result, scenario, out, plot=plot, every=every, fmt=fmt)
    written = ["metrics.json", f"trajectory.{fmt}"] + (["flight.png"] if plot else [])
    if animate:
        from .animate import animate_run
        animate_run(out, out / "flight.gif")
        written.append("flight.gif")
    status = (f"diverged at {metrics['diverged_at']:.3f} s ({metrics['diverged_cause']})"
              if metrics["diverged"] else
              f"tail RMS position error {100 * metrics['rms_position_error_tail']:.2f} cm")
    print(f"{scenario.name}: {status}; wrote {out}/{', '.join(written)}")
    return metrics


def default_out(scenario):
    """``out/<stem>`` for a scenario name or file path: where `quadcog run` writes by default."""
    return Path("out") / Path(str(scenario)).stem
