"""Scenario files (TOML): parse, validate with messages naming file and key, run, write results.

A scenario names a controller, a trajectory, CoG changes, disturbances, the truth vehicle
(``[vehicle]``) and what the controller believes (``[controller_model]``), controller
parameters and truth-model switches; `quadcog run FILE --out DIR` writes
metrics.json, vehicle.json, trajectory.csv and flight.png. The keys are documented in README.md.
"""
from dataclasses import dataclass, field
import math
from pathlib import Path
import warnings

import numpy as np

from quadcog import config, validate
from quadcog.controllers.registry import controller_names, make_controller
from quadcog.errors import InputError, ScenarioError
from quadcog.files import RunFiles, strict_json, write_csv
from quadcog.model.columns import trajectory_columns
from quadcog.scenarios.files import display_name, read_toml, scenario_path
from quadcog.scenarios.schema import (
    COG,
    DISTURBANCE,
    LIMITS,
    NUMBER,
    SENSING,
    TOP,
    TRUTH,
    VEHICLE,
    controller_params,
    trajectory_schema,
)
from quadcog.sim.divergence import Limits
from quadcog.sim.flight import simulate, start_at_reference
from quadcog.sim.plant import TruthOptions
from quadcog.sim.sensing import Sensed, Sensing
from quadcog.sim.timeline import CogChange, CogProfile, Disturbance
from quadcog.trajectories.analytic import Hover
from quadcog.vehicles.vehicle import HUMMINGBIRD, PRESETS
from quadcog.viz.progress import ProgressBar


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
        try:
            ctl = make_controller(self.controller, vehicle=self.model_vehicle(), **params)
        except ScenarioError:
            raise
        except InputError as e:         # a setting the controller's design refuses
            raise ScenarioError(f"{self.source}: key 'controller_params': {e}") from None
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


def _check(value, kind, where):
    """``value`` if it is of ``kind`` (a schema entry), else ScenarioError naming ``where``.
    The checks are those of quadcog.validate, shared with the API."""
    err = dict(error=ScenarioError)
    if kind == NUMBER:
        validate.real(value, where, **err)
    elif kind == "vec3":
        validate.array(value, where, (3,), what="an array of 3 numbers", **err)
    elif kind == "vec":
        a = validate.array(value, where, (None,), what="an array of numbers", **err)
        if a.size == 0:
            validate.fail(where, "a non-empty array of numbers", value, ScenarioError)
    elif kind == "points":
        a = validate.array(value, where, (None, 3),
                           what="an array of at least 2 arrays [x, y, z] of numbers", **err)
        if a.shape[0] < 2:
            validate.fail(where, "an array of at least 2 arrays [x, y, z] of numbers", value,
                          ScenarioError)
    elif kind == "pairs4":
        validate.array(value, where, (4, 2), what="an array of 4 arrays [x, y] of numbers",
                       **err)
    elif kind == "number_or_vec3":
        if not (isinstance(value, list) and len(value) == 3):
            validate.real(value, where, **err) if not isinstance(value, list) else \
                validate.fail(where, "a number or an array of 3 numbers", value, ScenarioError)
        else:
            validate.array(value, where, (3,), **err)
    elif kind == "number_or_false":
        if value is not False:
            validate.real(value, where, **err)
    elif kind is bool:
        validate.flag(value, where, **err)
    elif kind is list:                       # an array of tables
        if not (isinstance(value, list) and all(isinstance(v, dict) for v in value)):
            validate.fail(where, "an array of tables ([[...]] entries)", value, ScenarioError)
    elif not isinstance(value, kind):
        validate.fail(where, {str: "a string", dict: "a table"}.get(kind, str(kind)), value,
                      ScenarioError)
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
        t = validate.nonnegative(entry["t"], f"{source}: key {where + '.t'!r}", "s",
                                 ScenarioError)
        ramp = validate.nonnegative(entry.get("ramp", 0.0), f"{source}: key {where + '.ramp'!r}",
                                    "s", ScenarioError)
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
    controller = validate.choice(data["controller"], w("controller"), controller_names(),
                                 ScenarioError)
    duration = validate.positive(data["duration"], w("duration"), "s", ScenarioError)
    dt = validate.positive(data.get("dt", config.defaults["simulate.dt"]), w("dt"), "s",
                           ScenarioError)
    validate.step_count(duration, dt, config.defaults["simulate.max_steps"], source,
                        ScenarioError)
    validate.choice(data.get("path", "compiled"), w("path"), ("compiled", "python"),
                    ScenarioError)
    traj = dict(data.get("trajectory", {"kind": "hover"}))
    if "kind" not in traj:
        raise ScenarioError(f"{w('trajectory')}: missing key 'kind' (one of "
                            f"{', '.join(trajectory_schema())})")
    kind = validate.choice(traj.pop("kind"), w("trajectory.kind"), tuple(trajectory_schema()),
                           ScenarioError)
    cls, schema = trajectory_schema()[kind]
    _validate(traj, schema, source, "trajectory.", f" for kind {kind!r}")
    vehicle = _vehicle(data, "vehicle", None, source)
    controller_model = (_vehicle(data, "controller_model", vehicle.with_cog(np.zeros(3)), source)
                        if "controller_model" in data else None)
    cparams = data.get("controller_params", {})
    _validate(cparams, controller_params()[controller], source, "controller_params.",
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
    max_error = validate.positive(
        limits.get("max_position_error", config.defaults["limits.max_position_error"]),
        w("limits.max_position_error"), "m", ScenarioError)
    max_tilt_deg = validate.real(
        limits.get("max_tilt_deg", config.defaults["limits.max_tilt_deg"]),
        w("limits.max_tilt_deg"), lo=0.0, lo_open=True, hi=180.0, unit="deg",
        error=ScenarioError)
    offset = [float(v) for v in data.get("initial_offset", (0.0, 0.0, 0.0))]
    if not math.hypot(*offset) < max_error:     # (hypot: no overflow for 1e200)
        raise ScenarioError(f"{w('initial_offset')}: expected an offset shorter than "
                            f"limits.max_position_error = {max_error:g} m (a run that starts "
                            f"diverged), got {validate.plain(offset)}, "
                            f"{math.hypot(*offset):.3g} m long")
    cog, pulses = _cog_changes(data, source), _disturbances(data, source)
    try:
        return Scenario(
            name=data["name"], controller=controller, duration=duration, dt=dt,
            description=data.get("description", ""),
            path=data.get("path", "compiled"), trajectory=cls(**traj), cog=cog,
            disturbances=pulses, vehicle=vehicle, controller_model=controller_model,
            controller_params=dict(cparams),
            truth=TruthOptions(**truth),
            sensing=None if sensing is None else Sensing(**sensing),
            limits=Limits(max_error, math.radians(max_tilt_deg)),
            initial_offset=tuple(data.get("initial_offset", (0.0, 0.0, 0.0))), source=source)
    except InputError as e:
        raise ScenarioError(f"{source}: {e}") from None


def _vehicle(data, key, base, source):
    """The Vehicle of table ``key``: its ``preset`` (default: ``base``, or the Hummingbird)
    with the fields the table sets."""
    table = dict(data.get(key, {}))
    _validate(table, VEHICLE, source, f"{key}.", " vehicle field")
    preset = table.pop("preset", None)
    identified = table.pop("identified", None)
    if preset is not None:
        base = PRESETS[validate.choice(preset, f"{source}: key '{key}.preset'", tuple(PRESETS),
                                       ScenarioError)]
    try:
        vehicle = (base or HUMMINGBIRD).replace(**table)
        if identified is not None:
            from quadcog.identification.identified import identified_cog
            path = Path(source).parent / identified        # relative to the scenario file
            vehicle = vehicle.with_cog(identified_cog(path))
        return vehicle
    except InputError as e:
        raise ScenarioError(f"{source}: key {key!r}: {e}") from None


def load_scenario(path, overrides=()):
    """Read and validate a scenario: a file path or the name of a shipped scenario ("fig6";
    see ``quadcog.scenarios.files.scenario_path``). ``overrides``: ``--set`` texts ("vehicle.m=0.8",
    see ``quadcog.scenarios.keys``), applied before the validation, which then names them."""
    path = scenario_path(path)
    data = read_toml(path, ScenarioError)
    label = display_name(path, "scenario")      # a shipped file by its name, not a site-packages path
    source = label
    if overrides:
        from quadcog.scenarios.keys import apply_overrides
        data, notes = apply_overrides(data, overrides)
        for note in notes:
            warnings.warn(f"{label}: {note}", stacklevel=2)
        source = f"{label} with " + " ".join(f"--set {o}" for o in overrides)
    return parse(data, source)


def write_table(result, path, every=1, fmt="csv"):
    """The run's samples (every ``every``-th, and the last) into ``path`` as CSV or Parquet
    (``fmt``), with the column names of ``quadcog.model.columns.trajectory_columns()`` (units in the
    names). The CSV is written block by block (``quadcog.files.write_csv``): no memory
    beyond the result arrays. Returns the path written."""
    if not (isinstance(every, int) and not isinstance(every, bool) and every >= 1):
        raise InputError(f"every: expected a whole number >= 1 (write every N-th sample), "
                         f"got {every!r}")
    if fmt not in ("csv", "parquet"):
        raise InputError(f"format: expected 'csv' or 'parquet', got {fmt!r}")
    columns = [result.t, result.x, result.U, result.ref, result.r_hat, result.r_G,
               result.rotor_command, result.rotor_thrust]
    n = len(result.t)
    if every > 1:
        rows = np.unique(np.r_[np.arange(0, n, every), n - 1])
        columns, n = [c[rows] for c in columns], len(rows)
    names = trajectory_columns()
    path = Path(path)
    if fmt == "parquet":
        try:
            import pyarrow as pa
            import pyarrow.parquet as pq
        except ImportError:
            raise InputError("format 'parquet' needs pyarrow: pip install pyarrow "
                             "(or use the default, csv)") from None
        data = np.hstack([np.asarray(c, dtype=float).reshape(n, -1) for c in columns])
        pq.write_table(pa.table({name: data[:, k] for k, name in enumerate(names)}), path)
    else:
        with open(path, "w", newline="") as fh:
            write_csv(fh, names, columns, n)
    return path


def output_files(fmt="csv", plot=True):
    """The files ``write_outputs`` writes, in its order."""
    return ("metrics.json", "vehicle.json", f"trajectory.{fmt}") + (("flight.png",) if plot
                                                                      else ())


def write_outputs(result, scenario, out, plot=True, every=1, fmt="csv"):
    """metrics.json, vehicle.json, trajectory.csv (or .parquet: ``fmt``; every ``every``-th
    sample) and, with ``plot``, flight.png of one run into folder ``out``: all of them or
    none (``quadcog.files.RunFiles``), so an error or Ctrl-C while writing leaves the
    folder's previous files as they were. metrics.json and vehicle.json are strict JSON."""
    metrics = result.metrics.as_dict()
    metrics.update(name=scenario.name, controller=scenario.controller,
                   duration=scenario.duration, dt=scenario.dt,
                   simulated_until=float(result.t[-1]), wall_time_s=result.info.get("seconds"))
    with RunFiles(out) as files:
        write_table(result, files.path(f"trajectory.{fmt}"), every=every, fmt=fmt)
        if plot:
            from quadcog.viz.plots import plot_flight
            plot_flight(result, files.path("flight.png"), name=scenario.name,
                        disturbances=scenario.disturbances)
        files.path("vehicle.json").write_text(strict_json(scenario.vehicle.as_dict()))
        files.path("metrics.json").write_text(strict_json(metrics))
    return metrics


def run_with_progress(scenario, label=None, progress=True):
    """Run a scenario with a progress bar on stderr (or none); returns the result."""
    bar = ProgressBar(label or scenario.name) if progress else None
    try:
        result = scenario.run(progress=bar)
        if bar and result.metrics.diverged:       # why the bar stops short of 100 %
            bar.label += f" (diverged at {result.metrics.diverged_at:.3f} s: the run stops there)"
        return result
    finally:
        if bar:
            bar.close()


def run_file(path, out=None, progress=True, overrides=(), plot=True, every=1, fmt="csv",
             animate=False):
    """`quadcog run`: load (with ``overrides``), simulate with a progress bar, write the
    outputs into ``out`` (default ``out/<scenario>`` in the current folder); returns metrics."""
    scenario = load_scenario(path, overrides)
    out = Path(out) if out is not None else default_out(path)
    if every is None:                       # the command's default: decimated, not every step
        every = max(1, round(config.defaults["run.sample_period"] / scenario.dt))
    try:
        result = run_with_progress(scenario, progress=progress)
    except ScenarioError:
        raise
    except InputError as e:                 # e.g. dt too large for the closed loop
        raise ScenarioError(f"{scenario.source}: {e}") from None
    metrics = write_outputs(result, scenario, out, plot=plot, every=every, fmt=fmt)
    written = ["metrics.json", f"trajectory.{fmt}"] + (["flight.png"] if plot else [])
    if animate:
        from quadcog.viz.animation import animate_run
        animate_run(out, out / "flight.gif", progress=progress)
        written.append("flight.gif")
    status = (f"DIVERGED at {metrics['diverged_at']:.3f} s ({metrics['diverged_reason']}); "
              f"the flight stops there, a valid result (the paper's failure scenarios diverge), "
              f"not an error"
              if metrics["diverged"] else
              f"tail RMS position error {100 * metrics['rms_position_error_tail']:.2f} cm")
    print(f"{scenario.name}: {status}; wrote {out}/{', '.join(written)}")
    return metrics


def default_out(scenario):
    """``out/<stem>`` for a scenario name or file path: where `quadcog run` writes by default."""
    return Path("out") / Path(str(scenario)).stem
