"""Scenario files (TOML): parse, validate with messages naming file and key, run, write results.

A scenario names a controller, a trajectory, CoG changes, disturbances, the truth vehicle
(``[vehicle]``) and what the controller believes (``[controller_model]``), controller
parameters and truth-model switches; `quadcog run FILE --out DIR` writes
metrics.json, vehicle.json, trajectory.csv and flight.png. The keys are documented in
docs/reference/scenario-keys.md (generated).
"""
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
import math
import os
from pathlib import Path
from typing import Any
import warnings

import numpy as np

from quadcog import config, validate
from quadcog.controllers.base import Controller
from quadcog.controllers.registry import controller_names, make_controller
from quadcog.errors import InputError, ScenarioError
from quadcog.files import RUN_FILES, RunFiles, check_outputs, creatable_folder, one_line, strict_json, write_csv
from quadcog.model.columns import trajectory_columns
from quadcog.scenarios.lookup import display_name, read_toml, scenario_path
from quadcog.scenarios.schema import (
    COG,
    DISTURBANCE,
    LIMITS,
    NUMBER,
    PAYLOAD,
    SENSING,
    STACK,
    STACKS,
    TOP,
    TRUTH,
    VEHICLE,
    controller_params,
    trajectory_schema,
)
from quadcog.sim.divergence import Limits
from quadcog.sim.flight import simulate, start_at_reference
from quadcog.sim.plant import TruthOptions
from quadcog.sim.result import SimulationResult
from quadcog.sim.sensing import Sensed, Sensing
from quadcog.sim.timeline import CogChange, CogProfile, Disturbance, PayloadEvent, PayloadProfile
from quadcog.trajectories.analytic import Hover, Trajectory
from quadcog.vehicles.vehicle import HUMMINGBIRD, PRESETS, Vehicle
from quadcog.viz.progress import ProgressBar

__all__ = ["Scenario", "parse", "load_scenario", "write_table", "output_files", "write_outputs",
           "run_with_progress", "run_file", "default_out", "FILE_KEYS", "resolve_paths"]

FILE_KEYS = ("file", "identified")
"""The keys of ``[vehicle]`` and ``[controller_model]`` that name a file: relative to the
scenario file's folder in a file, to the current folder in a ``--set`` (``resolve_paths``)."""
_FILE_TABLES = ("vehicle", "controller_model")


def resolve_paths(data: dict[str, Any], folder: str | os.PathLike[str]) -> dict[str, Any]:
    """Make the relative file paths of a parsed scenario absolute, relative to ``folder``.

    The keys of ``FILE_KEYS`` in ``[vehicle]`` and ``[controller_model]`` are changed in
    place; an absolute path, or a value that is not a non-empty string (the validation
    reports it), is left as it is. ``load_scenario`` calls it with the scenario file's folder
    before the ``--set`` texts are applied and with the current folder after them, so that a
    path in the file is relative to the file and one in a ``--set`` to where the command
    runs; a sweep file's ``set`` and dimension values are relative to the sweep file.

    Parameters
    ----------
    data : dict
        A parsed scenario (changed in place).
    folder : str or os.PathLike
        The folder the relative paths are relative to.

    Returns
    -------
    dict
        ``data``.
    """
    base = Path(folder).absolute()
    for table in _FILE_TABLES:
        entries = data.get(table) if isinstance(data, dict) else None
        if not isinstance(entries, dict):
            continue
        for key in FILE_KEYS:
            value = entries.get(key)
            if isinstance(value, str) and value.strip() and not Path(value).is_absolute():
                entries[key] = str(base / value)
    return data


def _file_path(value, where, what):
    """The path of a file key (made absolute by ``resolve_paths``), refused when it is empty
    or names nothing: ScenarioError naming the key, the path and how relative paths are read."""
    if not value.strip():
        validate.fail(where, f"the path of {what}", value, ScenarioError)
    path = Path(value)
    try:
        exists = os.path.lexists(path)
    except (OSError, ValueError):       # a name too long, a null byte
        exists = False
    if not exists:
        raise ScenarioError(f"{where}: {one_line(path, word=200)}: no such file; expected "
                            f"{what} (a path in a scenario file is relative to its folder, "
                            "one given with --set to the current folder)")
    return path


@dataclass
class Scenario:
    """A validated scenario, ready to run.

    Parameters
    ----------
    name : str
        The scenario's name (its ``name`` key).
    controller : str
        Short name of the controller (``quadcog.controllers.registry.CONTROLLERS``).
    duration : float
        Simulated time [s].
    dt : float
        Control period and integration step [s] (default ``config.defaults["simulate.dt"]``).
    description : str
        One line for ``quadcog scenarios``.
    path : str
        'compiled' or 'python': the simulation path of ``quadcog.simulate``.
    trajectory : quadcog.trajectories.analytic.Trajectory
        The reference (default: hover).
    cog : quadcog.sim.timeline.CogProfile
        The CoG changes of the truth vehicle over time.
    payloads : list of quadcog.sim.timeline.PayloadEvent
        Payloads attached, moved and dropped over time (``[[payload]]``).
    disturbances : list of quadcog.sim.timeline.Disturbance
        External force and moment pulses.
    vehicle : quadcog.Vehicle
        The truth vehicle (default: the Hummingbird).
    controller_model : quadcog.Vehicle or None
        What the controller believes; None: the truth vehicle with r_G = 0.
    controller_params : dict
        The ``[controller_params]`` table: the controller's settings, ``Q_scale`` for a
        multiple of the identity as the Lyapunov weight Q.
    truth : quadcog.sim.plant.TruthOptions
        Truth-model switches (parallel axis, rotor saturation, motor lag).
    sensing : quadcog.sim.sensing.Sensing or None
        Noise and delay of the state estimate; None: the controller sees the true state.
    limits : quadcog.sim.divergence.Limits
        When a run counts as diverged.
    initial_offset : tuple of float
        (3,) start position relative to the reference at t = 0 [m].
    source : str
        What error messages name (the file, with its ``--set`` texts).
    stack : dict
        The ``[stack]`` table: a flight stack's controller flies instead of ``controller``
        (``name``, ``controller``, ``propellers``, ``battery_voltage``); empty for none.
    inputs : tuple of (str, pathlib.Path)
        The files the scenario reads, each with what names it in a message (the scenario
        file, ``key 'vehicle.file'``, ...): a run's outputs must not overwrite them.
    """
    name: str
    controller: str
    duration: float
    dt: float = field(default_factory=lambda: config.get("simulate.dt"))
    description: str = ""
    path: str = "compiled"
    trajectory: Trajectory = field(default_factory=Hover)
    cog: CogProfile = field(default_factory=CogProfile)
    payloads: list[PayloadEvent] = field(default_factory=list)
    disturbances: list[Disturbance] = field(default_factory=list)
    vehicle: Vehicle = HUMMINGBIRD                # the truth Vehicle
    controller_model: Vehicle | None = None       # what the controller believes (a Vehicle)
    controller_params: dict[str, Any] = field(default_factory=dict)
    truth: TruthOptions = field(default_factory=TruthOptions)
    sensing: Sensing | None = None
    limits: Limits = field(default_factory=Limits)
    initial_offset: tuple[float, ...] = (0.0, 0.0, 0.0)
    source: str = "<scenario>"
    stack: dict[str, Any] = field(default_factory=dict)   # [stack]: a flight stack flies instead
    inputs: tuple[tuple[str, Path], ...] = ()

    def make_controller(self) -> Controller | Sensed:
        """The scenario's controller, designed for its controller model.

        Returns
        -------
        quadcog.Controller or quadcog.sim.sensing.Sensed
            The controller of ``controller`` with ``controller_params``, wrapped in the
            sensing model when the scenario has ``[sensing]``.

        Raises
        ------
        quadcog.errors.ScenarioError
            When the controller's design refuses a setting (named with ``source``).
        """
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

    def model_vehicle(self) -> Vehicle:
        """The controller's model: ``controller_model``, or the truth vehicle with r_G = 0.

        Returns
        -------
        quadcog.Vehicle
            The vehicle the controller is designed for.
        """
        if self.controller_model is not None:
            return self.controller_model
        return self.vehicle.airframe.with_cog(np.zeros(3))

    def payload_profile(self) -> PayloadProfile:
        """The payloads over the run: the truth vehicle's own from t = 0, then ``payloads``.

        Returns
        -------
        quadcog.sim.timeline.PayloadProfile
            The checked profile.
        """
        return PayloadProfile(self.payloads, self.vehicle.payloads)

    def run(self, progress: Callable[[float], object] | None = None) -> SimulationResult:
        """Simulate the scenario.

        Parameters
        ----------
        progress : callable or None
            Called with the fraction done (0..1) as the run goes (a ProgressBar); None: quiet.

        Returns
        -------
        quadcog.sim.result.SimulationResult
            The flight: times [s], states, inputs, references, estimates and metrics.
        """
        x0 = None
        if any(self.initial_offset):
            x0 = start_at_reference(self.trajectory(0.0))
            x0[:3] += np.asarray(self.initial_offset)
        return simulate(self.make_controller(), self.trajectory, duration=self.duration,
                        dt=self.dt, vehicle=self.vehicle, controller_model=self.model_vehicle(),
                        cog=self.cog, disturbances=self.disturbances,
                        truth=self.truth, x0=x0, path=self.path, limits=self.limits,
                        progress=progress, payloads=self.payloads)


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


def _payload_events(data, source, vehicle):
    events = []
    for where, entry in _entries(data, "payload", PAYLOAD, source, ("t", "action", "name")):
        try:
            events.append(PayloadEvent(**entry))
        except InputError as e:
            raise ScenarioError(f"{source}: key {where!r}: {e}") from None
    try:
        PayloadProfile(events, vehicle.payloads)        # time order and names on board
    except InputError as e:
        raise ScenarioError(f"{source}: {e}") from None
    return events


def _disturbances(data, source):
    pulses = []
    for where, entry in _entries(data, "disturbance", DISTURBANCE, source, ("t", "duration")):
        try:
            pulses.append(Disturbance(**entry))
        except InputError as e:
            raise ScenarioError(f"{source}: key {where!r}: {e}") from None
    return pulses


def parse(data: dict[str, Any], source: str = "<scenario>") -> Scenario:
    """A Scenario from a parsed TOML dict.

    Parameters
    ----------
    data : dict
        The parsed scenario file (keys as in docs/reference/scenario-keys.md).
    source : str
        What error messages name (the file).

    Returns
    -------
    Scenario
        The validated scenario.

    Raises
    ------
    quadcog.errors.ScenarioError
        Naming ``source``, the key and the expectation, for any key or value the schema
        refuses.
    """
    _validate(data, TOP, source)
    for key in ("name", "controller", "duration"):
        if key not in data:
            raise ScenarioError(f"{source}: missing key {key!r}")
    w = lambda key: f"{source}: key {key!r}"
    controller = validate.choice(data["controller"], w("controller"), controller_names(),
                                 ScenarioError)
    duration = validate.positive(data["duration"], w("duration"), "s", ScenarioError)
    dt = validate.positive(data.get("dt", config.get("simulate.dt")), w("dt"), "s",
                           ScenarioError)
    validate.step_count(duration, dt, int(config.get("simulate.max_steps")), source,
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
    inputs: list[tuple[str, Path]] = []
    vehicle = _vehicle(data, "vehicle", None, source, inputs)
    controller_model = (_vehicle(data, "controller_model", vehicle.with_cog(np.zeros(3)), source,
                                 inputs)
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
    stack = dict(data.get("stack", {}))
    if stack:
        _validate(stack, STACK, source, "stack.")
        validate.choice(stack.get("name"), w("stack.name"), STACKS, ScenarioError)
    max_error = validate.positive(
        limits.get("max_position_error", config.get("limits.max_position_error")),
        w("limits.max_position_error"), "m", ScenarioError)
    max_tilt_deg = validate.real(
        limits.get("max_tilt_deg", config.get("limits.max_tilt_deg")),
        w("limits.max_tilt_deg"), lo=0.0, lo_open=True, hi=180.0, unit="deg",
        error=ScenarioError)
    offset = [float(v) for v in data.get("initial_offset", (0.0, 0.0, 0.0))]
    if not math.hypot(*offset) < max_error:     # (hypot: no overflow for 1e200)
        raise ScenarioError(f"{w('initial_offset')}: expected an offset shorter than "
                            f"limits.max_position_error = {max_error:g} m (a run that starts "
                            f"diverged), got {validate.plain(offset)}, "
                            f"{math.hypot(*offset):.3g} m long")
    cog, pulses = _cog_changes(data, source), _disturbances(data, source)
    events = _payload_events(data, source, vehicle)
    try:
        return Scenario(
            name=data["name"], controller=controller, duration=duration, dt=dt,
            description=data.get("description", ""),
            path=data.get("path", "compiled"), trajectory=cls(**traj), cog=cog,
            payloads=events, disturbances=pulses, vehicle=vehicle, controller_model=controller_model,
            controller_params=dict(cparams),
            truth=TruthOptions(**truth),
            sensing=None if sensing is None else Sensing(**sensing),
            limits=Limits(max_error, math.radians(max_tilt_deg)),
            initial_offset=tuple(data.get("initial_offset", (0.0, 0.0, 0.0))), source=source,
            stack=stack, inputs=tuple(inputs))
    except InputError as e:
        raise ScenarioError(f"{source}: {e}") from None


def _vehicle(data, key, base, source, inputs):
    """The Vehicle of table ``key``: its ``preset`` (default: ``base``, or the Hummingbird)
    with the fields the table sets; the files it reads are appended to ``inputs``."""
    table = dict(data.get(key, {}))
    _validate(table, VEHICLE, source, f"{key}.", " vehicle field")
    preset = table.pop("preset", None)
    identified = table.pop("identified", None)
    file = table.pop("file", None)
    if preset is not None:
        base = PRESETS[validate.choice(preset, f"{source}: key '{key}.preset'", tuple(PRESETS),
                                       ScenarioError)]
    # relative paths: to the scenario file's folder (resolve_paths made them absolute when
    # the scenario came from a file; a dict given to parse reads them from source's folder)
    if file is not None:
        file = _file_path(file, f"{source}: key '{key}.file'", "a URDF or SDF vehicle file")
    if identified is not None:
        identified = _file_path(identified, f"{source}: key '{key}.identified'",
                                "the JSON file of `quadcog identify --json`")
    where = key                         # the key the error names: the file's, or the table
    try:
        if file is not None:                # a URDF or SDF file
            where = f"{key}.file"
            inputs.append((f"key '{key}.file'", Path(source).parent / file))
            base = Vehicle.from_file(Path(source).parent / file)
        where = key
        vehicle = (base or HUMMINGBIRD).replace(**table)
        if identified is not None:
            from quadcog.identification.identified import identified_cog
            where = f"{key}.identified"
            path = Path(source).parent / identified
            inputs.append((f"key '{key}.identified'", path))
            vehicle = vehicle.with_cog(identified_cog(path))
        return vehicle
    except InputError as e:
        raise ScenarioError(f"{source}: key {where!r}: {e}") from None


def load_scenario(path: str | os.PathLike[str],
                  overrides: Sequence[str] = ()) -> Scenario:
    """Read and validate a scenario.

    Parameters
    ----------
    path : str or os.PathLike
        A file path or the name of a shipped scenario ("fig6"; see
        ``quadcog.scenarios.lookup.scenario_path``).
    overrides : sequence of str
        ``--set`` texts ("vehicle.m=0.8", see ``quadcog.scenarios.keys``), applied before the
        validation, which then names them. A file path in the scenario file is relative to
        the file's folder, one in a ``--set`` to the current folder (``resolve_paths``).

    Returns
    -------
    Scenario
        The validated scenario.

    Raises
    ------
    quadcog.errors.ScenarioError
        When the file is missing or not valid, naming the file, the key and the ``--set``
        texts.
    quadcog.errors.OverrideError
        For a malformed ``--set`` text.
    """
    path = scenario_path(path)
    data = resolve_paths(read_toml(path, ScenarioError), path.parent)   # relative to the file
    label = display_name(path, "scenario")      # a shipped file by its name, not a site-packages path
    source = label
    if overrides:
        from quadcog.scenarios.keys import apply_overrides
        data, notes = apply_overrides(data, overrides)
        resolve_paths(data, ".")                # a --set path: relative to the current folder
        for note in notes:
            warnings.warn(f"{label}: {note}", stacklevel=2)
        # each text shortened: the messages name the source, and a --set may be megabytes
        source = f"{label} with " + " ".join(f"--set {one_line(o, word=80)}"
                                              for o in overrides)
    scenario = parse(data, source)
    scenario.inputs = (("the scenario file", path),) + scenario.inputs
    return scenario


def write_table(result: SimulationResult, path: str | os.PathLike[str], every: int = 1,
                fmt: str = "csv") -> Path:
    """The run's samples into a CSV or Parquet file.

    The column names are those of ``quadcog.model.columns.trajectory_columns()`` (units in
    the names). The CSV is written block by block (``quadcog.files.write_csv``): no memory
    beyond the result arrays.

    Parameters
    ----------
    result : quadcog.sim.result.SimulationResult
        The run.
    path : str or os.PathLike
        The file to write.
    every : int
        Write every ``every``-th sample, and the last.
    fmt : str
        'csv' or 'parquet' (needs pyarrow).

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    quadcog.errors.InputError
        For a bad ``every`` or ``fmt``, or 'parquet' without pyarrow.
    """
    if not (isinstance(every, int) and not isinstance(every, bool) and every >= 1):
        raise InputError(f"every: expected a whole number >= 1 (write every N-th sample), "
                         f"got {every!r}")
    if fmt not in ("csv", "parquet"):
        raise InputError(f"format: expected 'csv' or 'parquet', got {fmt!r}")
    columns = [result.t, result.x, result.U, result.ref, result.r_hat, result.r_G,
               result.rotor_command, result.rotor_thrust, result.mass]
    n = len(result.t)
    every = min(every, max(n, 1))       # a step beyond the run: first and last sample only
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


def output_files(fmt: str = "csv", plot: bool = True) -> tuple[str, ...]:
    """The files ``write_outputs`` writes, in its order.

    Parameters
    ----------
    fmt : str
        'csv' or 'parquet': the table's format.
    plot : bool
        Whether flight.png is drawn.

    Returns
    -------
    tuple of str
        File names inside the run folder.
    """
    return ("metrics.json", "vehicle.json", f"trajectory.{fmt}") + (("flight.png",) if plot
                                                                      else ())


def write_outputs(result: SimulationResult, scenario: Scenario, out: str | os.PathLike[str],
                  plot: bool = True, every: int = 1, fmt: str = "csv",
                  animate: bool = False, progress: bool = False,
                  protect: Sequence[str | os.PathLike[str]] = ()) -> dict[str, Any]:
    """The files of one run, into a folder: all of them or none.

    metrics.json, vehicle.json, trajectory.csv (or .parquet), with ``plot`` flight.png and
    with ``animate`` flight.gif, written through ``quadcog.files.RunFiles``, so an error or
    Ctrl-C while writing leaves the folder's previous files as they were, and the files of an
    earlier run that this one does not write are removed. metrics.json and vehicle.json are
    strict JSON.

    Parameters
    ----------
    result : quadcog.sim.result.SimulationResult
        The run.
    scenario : Scenario
        The scenario flown (its name, controller, duration, dt go into metrics.json; with a
        ``[stack]``, the controller is the stack's, ``result.controller``).
    out : str or os.PathLike
        The folder.
    plot : bool
        Draw flight.png (needs matplotlib).
    every : int
        Write every ``every``-th sample (and the last) into the table.
    fmt : str
        'csv' or 'parquet'.
    animate : bool
        Also write flight.gif (``quadcog.viz.animation``), in the same all-or-nothing commit.
    progress : bool
        A progress bar while the animation is drawn.
    protect : sequence of str or os.PathLike
        Files the run read, never replaced nor removed (default: the scenario's ``inputs``
        too).

    Returns
    -------
    dict
        The metrics as written to metrics.json (errors in m, times in s).
    """
    metrics = result.metrics.as_dict()
    # with a [stack], the stack's controller flew (result.controller names it)
    metrics.update(name=scenario.name,
                   controller=result.controller if scenario.stack else scenario.controller,
                   duration=scenario.duration, dt=scenario.dt,
                   simulated_until=float(result.t[-1]), wall_time_s=result.info.get("seconds"))
    protect = [*protect, *(p for _, p in scenario.inputs)]
    with RunFiles(out, protect=protect) as files:
        write_table(result, files.path(f"trajectory.{fmt}"), every=every, fmt=fmt)
        if plot:
            from quadcog.viz.plots import plot_flight
            plot_flight(result, files.path("flight.png"), name=scenario.name,
                        disturbances=scenario.disturbances)
        files.path("vehicle.json").write_text(strict_json(scenario.vehicle.as_dict()))
        files.path("metrics.json").write_text(strict_json(metrics))
        if animate:         # from the table as written, as `quadcog animate` would read it
            from quadcog.viz.animation import animate_table, read_table
            animate_table(read_table(files.path(f"trajectory.{fmt}")), metrics,
                          scenario.vehicle, files.path("flight.gif"), progress=progress)
    return metrics


def run_with_progress(scenario: Scenario, label: str | None = None,
                      progress: bool = True) -> SimulationResult:
    """Run a scenario with a progress bar on stderr (or none).

    Parameters
    ----------
    scenario : Scenario
        What to fly.
    label : str, optional
        The bar's label (default: the scenario's name).
    progress : bool
        Show the bar.

    Returns
    -------
    quadcog.sim.result.SimulationResult
        The flight.
    """
    bar = ProgressBar(label or scenario.name) if progress else None
    try:
        result = scenario.run(progress=bar)
        if bar and result.metrics.diverged:       # why the bar stops short of 100 %
            bar.label += f" (diverged at {result.metrics.diverged_at:.3f} s: the run stops there)"
        return result
    finally:
        if bar:
            bar.close()


def run_file(path: str | os.PathLike[str], out: str | os.PathLike[str] | None = None,
             progress: bool = True, overrides: Sequence[str] = (), plot: bool = True,
             every: int = 1, fmt: str = "csv", animate: bool = False,
             stack_runner: Callable[["Scenario"], SimulationResult] | None = None,
             inputs: Sequence[tuple[str, str | os.PathLike[str]]] = ()) -> dict[str, Any]:
    """`quadcog run`: load, simulate with a progress bar, write the outputs, print a line.

    Parameters
    ----------
    path : str or os.PathLike
        A scenario file or the name of a shipped scenario.
    out : str or os.PathLike, optional
        The results folder (default ``out/<scenario>`` in the current folder).
    progress : bool
        Show a progress bar on stderr.
    overrides : sequence of str
        ``--set`` texts (``KEY=VALUE``).
    plot : bool
        Draw flight.png.
    every : int
        Write every ``every``-th sample (and the last) into the table.
    fmt : str
        'csv' or 'parquet'.
    animate : bool
        Also write flight.gif.
    stack_runner : callable, optional
        Flies a scenario that has a ``[stack]`` table (the stacks layer's, which this layer
        cannot import; ``quadcog run`` passes ``quadcog.crazyflie.scenario.run_scenario``).
    inputs : sequence of (str, path)
        Files the command reads besides the scenario's own (``("--identified", path)``),
        named as the command line gives them.

    Returns
    -------
    dict
        The metrics of metrics.json.

    Raises
    ------
    quadcog.errors.ScenarioError
        When the scenario is not valid or its run refuses a setting (e.g. dt too large for
        the closed loop), naming the file.
    quadcog.errors.InputError
        Before the flight, when a file the run would replace or remove (any of
        ``quadcog.files.RUN_FILES`` in ``out``) is one it reads.
    """
    scenario = load_scenario(path, overrides)
    out = Path(out) if out is not None else default_out(path)
    inputs = [*inputs, *scenario.inputs]
    # before the flight: the folder can be made, and a run replaces or removes each of these
    # files in it
    creatable_folder(out, "--out", ScenarioError)
    check_outputs([(f"--out (its {name})", out / name) for name in RUN_FILES],
                  inputs)
    if every is None:                       # the command's default: decimated, not every step
        every = max(1, round(config.get("run.sample_period") / scenario.dt))
    try:
        if scenario.stack:
            if stack_runner is None:
                raise ScenarioError(f"{scenario.source}: key 'stack': a flight stack flies "
                                    "through `quadcog run` (or quadcog.crazyflie.simulate)")
            result = stack_runner(scenario)
        else:
            result = run_with_progress(scenario, progress=progress)
    except ScenarioError:
        raise
    except InputError as e:                 # e.g. dt too large for the closed loop
        raise ScenarioError(f"{scenario.source}: {e}") from None
    metrics = write_outputs(result, scenario, out, plot=plot, every=every, fmt=fmt,
                            animate=animate, progress=progress, protect=[p for _, p in inputs])
    written = ["metrics.json", f"trajectory.{fmt}"] + (["flight.png"] if plot else []) + (
        ["flight.gif"] if animate else [])
    status = (f"DIVERGED at {metrics['diverged_at']:.3f} s ({metrics['diverged_reason']}); "
              f"the flight stops there, a valid result (the paper's failure scenarios diverge), "
              f"not an error"
              if metrics["diverged"] else
              f"tail RMS position error {100 * metrics['rms_position_error_tail']:.2f} cm")
    print(one_line(f"{scenario.name}: {status}; wrote {out}/{', '.join(written)}"))
    return metrics


def default_out(scenario: str | os.PathLike[str]) -> Path:
    """Where `quadcog run` writes by default.

    Parameters
    ----------
    scenario : str or os.PathLike
        A scenario name or file path.

    Returns
    -------
    pathlib.Path
        ``out/<stem>``, relative to the current folder.
    """
    return Path("out") / Path(str(scenario)).stem
