"""Sweep files (TOML): a base scenario, fixed settings and the dimensions to vary, expanded
into a deterministic list of flights.

Every flight is the base scenario with some keys replaced. A key names a scenario value the
way the scenario file spells it: ``controller``, ``duration``, ``vehicle.m``,
``controller_params.gamma``, ``cog[0].r`` (a 3-vector), ``cog[0].r[1]`` (one component),
``cog[0].ramp``, ``trajectory.radius``... Every flight is validated by the scenario parser, so
a sweep accepts exactly what a scenario file accepts. The keys of a sweep file are listed in
docs/reference/sweep-keys.md.
"""
from collections.abc import Callable
import copy
from dataclasses import dataclass, field
import hashlib
import itertools
import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from quadcog.errors import ParameterError, SizeError, SweepError
from quadcog.model.parameters import admissible_radius
from quadcog.scenarios.keys import KEY_EXAMPLE, parse_key, set_key
from quadcog.scenarios.lookup import display_name, find_file, read_toml, scenario_path, shipped_names
from quadcog.scenarios.scenario import Scenario, ScenarioError, parse, resolve_paths
from quadcog.sim.flight import check_cog_changes
from quadcog.sim.prepare import check_payload_events
from quadcog.sweeps.groups import CONTROLLERS_BY_GROUP, group_key
from quadcog.validate import plain

__all__ = ["MODES", "TOP", "SOURCES", "DEFAULT_CHUNK", "DEFAULT_THRESHOLD", "MAX_CHUNK",
           "MAX_THRESHOLD", "Dimension",
           "Flight", "Sweep", "cog_admissible", "from_dict", "sweep_names", "sweep_path",
           "read_sweep_file", "load_sweep"]

MODES = ("grid", "monte-carlo")
TOP = {"name", "description", "scenario", "mode", "samples", "seed", "chunk", "threshold",
       "inadmissible", "set", "dimension"}
SOURCES = ("values", "range", "uniform", "normal", "ball")
DEFAULT_CHUNK = 64          # flights per chunk: the unit of scheduling, retry and resume
DEFAULT_THRESHOLD = 0.5     # m: tail RMS above this (or a diverged run) counts as failed
MAX_FLIGHTS = 1_000_000     # flights of one sweep (and values of one dimension): each is
                            # validated before any flies, so more would not even start
MAX_CHUNK = 10_000          # flights per chunk: a chunk is one batch in one process, and the
                            # unit of retry and resume; more only loses work on a failure
MAX_THRESHOLD = 1e6         # m: a tail RMS error this large is a divergence long before


def _plain(v):
    """numpy scalars/arrays -> Python numbers/lists (TOML-like values)."""
    if isinstance(v, np.ndarray):
        return [_plain(x) for x in v.tolist()]
    if isinstance(v, (np.floating,)):
        return float(v)
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    return v


@dataclass
class Dimension:
    """One varied key: ``values`` or ``sampler``.

    Parameters
    ----------
    key : str
        The scenario key varied (``vehicle.m``, ``cog[0].r``).
    kind : str
        Where its values come from: one of ``SOURCES``.
    values : list or None
        Grid values, or the pool Monte-Carlo draws from.
    sampler : callable or None
        ``sampler(rng, n)`` -> n values (a list), for the random kinds.
    n : int or None
        Draws of ``sampler`` in a grid (None in Monte-Carlo mode).
    random : bool
        Whether the values are drawn (uniform, normal, ball).
    width : int
        Columns in the table: 3 for a vector value.
    """
    key: str
    kind: str
    values: list[Any] | None = None
    sampler: Callable[[np.random.Generator, int], list[Any]] | None = None
    n: int | None = None
    random: bool = False
    width: int = 1              # columns in the table: 3 for a vector value

    def columns(self) -> list[str]:
        """The table's column names of this dimension.

        Returns
        -------
        list of str
            ``[key]``, or ``key[0]``, ``key[1]``, ... for a vector value.
        """
        return [self.key] if self.width == 1 else [f"{self.key}[{i}]" for i in range(self.width)]


@dataclass
class Flight:
    """One flight of a sweep.

    Parameters
    ----------
    index : int
        Its place in the sweep (the table's ``flight`` column).
    values : dict
        {key: value} of the varied keys (TOML-like values).
    admissible : bool
        Whether its CoG is admissible (inadmissible grid points are kept as rows without
        metrics when ``inadmissible = "skip"``).
    """
    index: int
    values: dict[str, Any]
    admissible: bool = True


@dataclass
class Sweep:
    """A validated sweep: the base scenario, the dimensions and the expanded flights.

    Parameters
    ----------
    name : str
        The sweep's name (default: the file's stem).
    description : str
        One line about it.
    source : str
        The sweep file, as error messages name it.
    base : dict
        The base scenario data, with the fixed settings (``[set]``) applied.
    base_source : str
        The base scenario file.
    mode : str
        'grid' or 'monte-carlo'.
    seed : int
        The seed of the random dimensions.
    chunk : int
        Flights per chunk: the unit of scheduling, retry and resume.
    threshold : float
        Tail RMS position error above which a flight counts as failed [m].
    dimensions : list of Dimension
        The varied keys, in the file's order.
    flights : list of Flight
        The expanded flights, in order.
    inputs : list of (str, pathlib.Path)
        The files the sweep reads (the sweep file, the base scenario, its vehicle files),
        each with what names it in a message: its results must not overwrite them.
    """
    name: str
    description: str
    source: str
    base: dict[str, Any]
    base_source: str
    mode: str
    seed: int
    chunk: int
    threshold: float
    dimensions: list[Dimension]
    flights: list[Flight] = field(default_factory=list)
    inputs: list[tuple[str, Path]] = field(default_factory=list)

    @property
    def columns(self) -> list[str]:
        """The table's columns of the varied keys, in the dimensions' order."""
        return [c for d in self.dimensions for c in d.columns()]

    def flight_data(self, flight: Flight) -> dict[str, Any]:
        """The scenario dict of one flight.

        Parameters
        ----------
        flight : Flight
            One of ``flights``.

        Returns
        -------
        dict
            A copy of ``base`` with the flight's values set.
        """
        data = copy.deepcopy(self.base)
        for key, value in flight.values.items():
            set_key(data, key, value)
        return data

    def chunks(self) -> list[tuple[int, list[Flight]]]:
        """The flights in chunks.

        Returns
        -------
        list of (int, list of Flight)
            [(chunk index, flights)]: consecutive runs of ``chunk`` flights, fixed by the file
            alone (never by the scheduler), so results do not depend on where they ran.
        """
        return [(c, self.flights[k:k + self.chunk])
                for c, k in enumerate(range(0, len(self.flights), self.chunk))]

    def fingerprint(self) -> str:
        """SHA-256 of what determines the results.

        Returns
        -------
        str
            The hex digest of the base data, the settings and every flight's values. A
            results folder remembers it, so that resuming never mixes sweeps.
        """
        text = json.dumps({"base": self.base, "threshold": self.threshold, "chunk": self.chunk,
                           "flights": [(f.index, f.values, f.admissible) for f in self.flights]},
                          sort_keys=True, default=_plain)
        return hashlib.sha256(text.encode()).hexdigest()


def _err(source, key, message):
    return SweepError(f"{source}: key {key!r}: {message}")


def _number(v):
    if not isinstance(v, (int, float)) or isinstance(v, bool):
        return False
    try:
        return math.isfinite(v)
    except OverflowError:           # an integer beyond the float range
        return False


def _field_err(source, where, message):
    """``where`` = (dimension key, field): the error names the key, the message the field."""
    key, fld = where
    return _err(source, key, f"{fld}: {message}")


def _table(spec, where, source, required, optional=()):
    if not isinstance(spec, dict):
        raise _field_err(source, where, f"expected a table with {', '.join(required)}, got "
                         f"{spec!r}")
    for k in spec:
        if k not in required and k not in optional:
            raise _field_err(source, where, f"{k!r} is unknown; expected one of "
                             f"{', '.join(list(required) + list(optional))}")
    for k in required:
        if k not in spec:
            raise _field_err(source, where, f"missing {k!r}")
    for k, v in spec.items():
        if k != "plane" and not _number(v):
            raise _field_err(source, where, f"{k}: expected a finite number, got {plain(v)}")
    return spec


def _count(spec, where, source, mode):
    if mode == "monte-carlo":
        if "n" in spec:
            raise _field_err(source, where, "n is not used with mode = \"monte-carlo\" (every "
                       "flight draws once; set the top-level 'samples')")
        return None
    if "n" not in spec:
        raise _field_err(source, where, "missing 'n' (the number of samples in the grid)")
    n = spec["n"]
    if not isinstance(n, int) or isinstance(n, bool) or n < 1:
        raise _field_err(source, where, f"n: expected a whole number >= 1, got {n!r}")
    _size(source, where, n, "samples")
    return n


def _size(source, where, n, what):
    """Refuse a count above MAX_FLIGHTS before anything of that size is allocated."""
    if not n <= MAX_FLIGHTS:
        raise SizeError(f"{source}: key {where[0]!r}: {where[1]}: {n:.6g} {what} is too large "
                        f"(at most {MAX_FLIGHTS} flights per sweep)")


def _check_values(source, key, values):
    """A dimension's ``values``: all numbers, all strings, all booleans or all vectors (lists
    of numbers) of one length; a table or a mixture would fail only after the flights, when
    the table is written."""
    def kind(v):
        if isinstance(v, bool):
            return "boolean"
        if isinstance(v, (int, float)):
            return "number"
        if isinstance(v, str):
            return "string"
        if isinstance(v, list) and v and all(_number(x) for x in v):
            return f"vector of {len(v)}"
        return None
    if len(values) > MAX_FLIGHTS:
        _size(source, (key, "values"), len(values), "values")
    kinds = [kind(v) for v in values]
    for v, k in zip(values, kinds):
        if k is None:
            raise _err(source, key, f"values: {plain(v)} is not a number, a string, a boolean or "
                       f"a vector of finite numbers")
        if k != kinds[0]:
            raise _err(source, key, f"values: {plain(v)} is a {k}, the first value "
                       f"{plain(values[0])} a {kinds[0]}: all values of a dimension must be of one "
                       f"kind")
    if kinds[0] == "number" and not all(_number(v) for v in values):
        bad = next(v for v in values if not _number(v))
        raise _err(source, key, f"values: {plain(bad)} is not a finite number")


def _range_values(spec, where, source):
    if not isinstance(spec, dict):
        raise _field_err(source, where, f"expected a table {{start, stop, num}} or "
                         f"{{start, stop, step}}, got {spec!r}")
    has_num, has_step = "num" in spec, "step" in spec
    if has_num == has_step:
        raise _field_err(source, where, "expected exactly one of 'num' (points, stop included) "
                         "and 'step'")
    _table(spec, where, source, ("start", "stop", "num" if has_num else "step"))
    start, stop = float(spec["start"]), float(spec["stop"])
    if not math.isfinite(stop - start):
        raise _field_err(source, where, f"start = {start}, stop = {stop}: a range wider than "
                         "the float range (stop - start overflows)")
    if has_num:
        num = spec["num"]
        if not isinstance(num, int) or num < 1:
            raise _field_err(source, where, f"empty range: num must be a whole number >= 1, "
                             f"got {num!r}")
        _size(source, where, num, "points")
        return np.linspace(start, stop, num).tolist()
    step = float(spec["step"])
    if step == 0 or (stop - start) / step < 0:
        raise _field_err(source, where, f"empty range: from {start} to {stop} in steps of "
                         f"{step}")
    ratio = (stop - start) / step
    if not ratio < MAX_FLIGHTS:
        _size(source, where, ratio, "points")
    count = int(math.floor(ratio + 1e-9)) + 1
    _size(source, where, count, "points")
    return [start + i * step for i in range(count)]


def _finite(v, source, where, field):
    """A sampler's bound as a finite float, else the SweepError naming the field."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise _field_err(source, where, f"{field}: expected a finite number, got {v!r:.40}")
    try:
        x = float(v)
    except OverflowError:
        x = float("inf")
    if not math.isfinite(x):
        raise _field_err(source, where, f"{field}: expected a finite number, got {plain(v)}")
    return x


def _dimension(i, spec, source, mode):
    where = f"dimension[{i}]"
    if not isinstance(spec, dict):
        raise _err(source, where, f"expected a table, got {spec!r}")
    key = spec.get("key")
    if not isinstance(key, str) or parse_key(key) is None:
        try:
            set_key({}, key, None, error=SweepError, where=f"{source}: key {where + '.key'!r}")
        except SweepError as e:         # the grammar's own reason (e.g. the bracket form)
            raise SweepError(f"{e}; got {key!r}") from None
        raise _err(source, f"{where}.key", f"expected a scenario key ({KEY_EXAMPLE}), got "
                   f"{key!r}")
    for k in spec:
        if k != "key" and k not in SOURCES:
            raise _err(source, f"{where}.{k}", f"unknown; expected 'key' and one of "
                       f"{', '.join(SOURCES)}")
    given = [k for k in SOURCES if k in spec]
    if len(given) != 1:
        raise _err(source, key, f"expected exactly one of {', '.join(SOURCES)}, got "
                   f"{', '.join(given) or 'none'}")
    kind, value = given[0], spec[given[0]]
    w = (key, kind)
    if kind == "values":
        if not isinstance(value, list) or not value:
            raise _err(source, key, f"'values' must be a non-empty array, got {value!r}")
        _check_values(source, key, value)
        width = len(value[0]) if isinstance(value[0], list) else 1
        return Dimension(key, kind, values=list(value), width=width)
    if kind == "range":
        values = _range_values(value, w, source)
        return Dimension(key, kind, values=values)
    if kind == "uniform":
        _table(value, w, source, ("low", "high"), ("n",))
        lo = _finite(value["low"], source, w, "low")
        hi = _finite(value["high"], source, w, "high")
        if not hi > lo:
            raise _field_err(source, w, f"empty range: low = {lo} must be below high = {hi}")
        if not np.isfinite(hi - lo):
            raise _field_err(source, w, f"low = {lo}, high = {hi}: a range wider than the "
                             "float range (high - low overflows)")
        return Dimension(key, kind, sampler=lambda rng, n: rng.uniform(lo, hi, n).tolist(),
                         n=_count(value, w, source, mode), random=True)
    if kind == "normal":
        _table(value, w, source, ("mean", "std"), ("n",))
        mu = _finite(value["mean"], source, w, "mean")
        sd = _finite(value["std"], source, w, "std")
        if not abs(mu) + 10 * sd < 1e300:
            raise _field_err(source, w, f"mean = {mu}, std = {sd}: draws would overflow the "
                             "float range")
        if not sd > 0:
            raise _field_err(source, w, f"std: expected a positive number, got {sd}")
        return Dimension(key, kind, sampler=lambda rng, n: rng.normal(mu, sd, n).tolist(),
                         n=_count(value, w, source, mode), random=True)
    # ball: uniform inside a ball of CoG offsets (3-vectors), optionally in the rotor plane
    _table(value, w, source, ("radius",), ("n", "plane"))
    radius = _finite(value["radius"], source, w, "radius")
    if not radius < 1e300:
        raise _field_err(source, w, f"radius = {radius}: beyond the float range of a draw")
    plane = value.get("plane", "xyz")
    if plane not in ("xyz", "xy"):
        raise _field_err(source, w, f"plane: expected \"xy\" or \"xyz\", got {plane!r}")
    if not radius > 0:
        raise _field_err(source, w, f"radius: expected a positive number of metres, got "
                         f"{radius}")
    dim = 2 if plane == "xy" else 3

    def ball(rng, n):
        v = rng.normal(size=(n, dim))
        v *= (radius * rng.uniform(size=n) ** (1.0 / dim)
              / np.linalg.norm(v, axis=1))[:, None]
        if dim == 2:
            v = np.hstack([v, np.zeros((n, 1))])
        return v.tolist()
    return Dimension(key, kind, sampler=ball, n=_count(value, w, source, mode), random=True,
                     width=3)


def _expand(dims, mode, samples, seed):
    """[{key: value}] in a fixed order: grid = all combinations, first dimension slowest;
    Monte-Carlo = ``samples`` independent draws. Dimension i draws from its own stream
    (seed, i), so adding a dimension does not change the others' samples."""
    rngs = [np.random.default_rng([seed, i]) for i in range(len(dims))]
    if mode == "grid":
        pools = [d.values if d.values is not None else d.sampler(rng, d.n)
                 for d, rng in zip(dims, rngs)]
        return [dict(zip((d.key for d in dims), combo)) for combo in itertools.product(*pools)]
    columns = []
    for d, rng in zip(dims, rngs):
        if d.values is not None:
            columns.append([d.values[k] for k in rng.integers(0, len(d.values), samples)])
        else:
            columns.append(d.sampler(rng, samples))
    return [dict(zip((d.key for d in dims), row)) for row in zip(*columns)]


def cog_admissible(scenario: Scenario) -> str | None:
    """Whether the vehicle stays admissible through every CoG change of a scenario.

    Parameters
    ----------
    scenario : quadcog.scenarios.scenario.Scenario
        The flight.

    Returns
    -------
    str or None
        None when the vehicle with every CoG change is admissible, else the reason (the
        ParameterError message).
    """
    try:
        check_cog_changes(scenario.vehicle.airframe.parameters(), scenario.cog)
        check_payload_events(scenario.vehicle, scenario.payload_profile())
    except ParameterError as e:
        return str(e)
    return None


def from_dict(data: dict[str, Any], source: str = "<sweep>",
              folder: str | os.PathLike[str] | None = None, *, progress: bool = False) -> Sweep:
    """A validated Sweep from a parsed sweep file.

    Parameters
    ----------
    data : dict
        The parsed sweep file (keys as in docs/reference/sweep-keys.md).
    source : str
        What error messages name.
    folder : str or os.PathLike, optional
        The sweep file's folder (default: the current folder): a relative base-scenario path
        and the relative file paths of ``set`` and of the dimensions' values
        (``vehicle.file``, ``vehicle.identified``) are read from it; those of the base
        scenario file from the base scenario's folder.
    progress : bool
        Show on stderr how far the validation of a large sweep (``VALIDATE_PROGRESS_AT``
        flights or more) got.

    Returns
    -------
    Sweep
        With every flight expanded and validated as a scenario.

    Raises
    ------
    quadcog.errors.SweepError
        For any key or value refused, naming ``source`` and the key; for a flight that is
        not a valid scenario or whose CoG is inadmissible.
    """
    if not isinstance(data, dict):
        raise SweepError(f"{source}: expected a table at the top level")
    for k in data:
        if k not in TOP:
            raise _err(source, k, f"unknown; expected one of {', '.join(sorted(TOP))}")
    if "scenario" not in data:
        raise SweepError(f"{source}: missing key 'scenario' (a shipped scenario name or a "
                         f"scenario file, relative to the sweep file)")
    mode = data.get("mode", "grid")
    if mode not in MODES:
        raise _err(source, "mode", f"expected one of {', '.join(MODES)}, got {mode!r}")
    ints: dict[str, Any] = {"seed": 0, "chunk": DEFAULT_CHUNK, "samples": None}
    for k, default in ints.items():
        v = data.get(k, default)
        if (v is not None or k != "samples") and (
                not isinstance(v, int) or isinstance(v, bool) or v < 0
                or (k != "seed" and v < 1)):
            raise _err(source, k, f"expected a whole number{' >= 1' if k != 'seed' else ''}, "
                       f"got {v!r}")
        ints[k] = v
    if ints["chunk"] > MAX_CHUNK:
        raise SizeError(f"{source}: key 'chunk': expected a whole number in [1, {MAX_CHUNK}] "
                        f"(flights per chunk, flown as one batch in one process), got "
                        f"{plain(ints['chunk'])}")
    if mode == "monte-carlo" and ints["samples"] is None:
        raise _err(source, "samples", "missing: mode = \"monte-carlo\" needs the flight count")
    if mode == "grid" and ints["samples"] is not None:
        raise _err(source, "samples", "only used with mode = \"monte-carlo\"")
    threshold = data.get("threshold", DEFAULT_THRESHOLD)
    if not _number(threshold) or not 0 < threshold <= MAX_THRESHOLD:
        raise _err(source, "threshold", f"expected a positive number of metres up to "
                   f"{MAX_THRESHOLD:g}, got {plain(threshold)}")
    inadmissible = data.get("inadmissible", "error")
    if inadmissible not in ("error", "skip"):
        raise _err(source, "inadmissible", f"expected \"error\" or \"skip\", got "
                   f"{inadmissible!r}")
    for k in ("name", "description"):
        if k in data and not isinstance(data[k], str):
            raise _err(source, k, f"expected a string, got {data[k]!r}")

    spec = data["scenario"]
    if not isinstance(spec, str):
        raise _err(source, "scenario", f"expected a string, got {spec!r}")
    candidate = Path(folder or ".") / spec
    try:
        base_path = candidate if candidate.is_file() else scenario_path(spec)
        # the base scenario's file paths are relative to its own folder
        base = resolve_paths(read_toml(Path(base_path), ScenarioError), Path(base_path).parent)
    except ScenarioError as e:
        raise _err(source, "scenario", str(e)) from None
    base_source = str(base_path)
    fixed = data.get("set", {})
    if not isinstance(fixed, dict):
        raise _err(source, "set", f"expected a table of scenario keys, got {fixed!r}")
    for key, value in fixed.items():
        set_key(base, key, value, error=SweepError, where=f"{source}: key {'set.' + key!r}")
    resolve_paths(base, folder or ".")      # those of [set]: relative to the sweep file
    try:
        # a shipped base by its name in the messages, not its path in site-packages
        inputs = [("the base scenario", Path(base_path)),
                  *parse(base, display_name(base_path, "scenario")).inputs]
    except ScenarioError as e:
        raise _err(source, "set", f"the base scenario with these settings is not valid: "
                   f"{e}") from None

    raw = data.get("dimension", [])
    if not isinstance(raw, list) or not raw:
        raise _err(source, "dimension", "expected at least one [[dimension]] table")
    dims = [_dimension(i, d, source, mode) for i, d in enumerate(raw)]
    for d in dims:              # file paths among the values: relative to the sweep file
        if d.values is not None:
            d.values = [_resolve_value(d.key, v, folder or ".") for v in d.values]
    keys = [d.key for d in dims]
    if len(set(keys)) != len(keys):
        dup = next(k for k in keys if keys.count(k) > 1)
        raise _err(source, dup, "appears in two dimensions")
    _check_overlaps(source, keys)
    sizes = [len(d.values) if d.values is not None else d.n for d in dims]
    count = ints["samples"] if mode == "monte-carlo" else math.prod(sizes)
    if count > MAX_FLIGHTS:
        shape = " x ".join(map(str, sizes)) if mode == "grid" else "samples"
        raise SizeError(f"{source}: the sweep has {count:.6g} flights ({shape}): at most "
                        f"{MAX_FLIGHTS} are accepted; split it into several sweeps")
    sweep = Sweep(name=data.get("name", Path(source).stem), description=data.get("description", ""),
                  source=source, base=base, base_source=base_source, mode=mode,
                  seed=ints["seed"], chunk=ints["chunk"], threshold=float(threshold),
                  dimensions=dims, inputs=inputs)
    if Path(source).is_file():
        sweep.inputs.insert(0, ("the sweep file", Path(source)))
    combos = _expand(dims, mode, ints["samples"], ints["seed"])
    if not combos:
        raise SweepError(f"{source}: the sweep has no flights")
    _validate_flights(sweep, combos, inadmissible == "skip", progress)
    return sweep


VALIDATE_PROGRESS_AT = 10_000
"""Flights from which the validation shows its progress (about 1 ms a flight: 10 s)."""


def _validate_flights(sweep, combos, skip, progress=False):
    """Parse every flight as a scenario (errors name the sweep file and the varied key) and
    check its CoG; fills ``sweep.flights`` and adds the files the flights read to
    ``sweep.inputs``."""
    by_key = {d.key: d for d in sweep.dimensions}
    designed = {}
    report = None
    if progress and len(combos) >= VALIDATE_PROGRESS_AT:    # minutes of silence otherwise
        from quadcog.viz.progress import ProgressCounter
        report = ProgressCounter(f"sweep {sweep.name}: validating", len(combos))
    known = {path for _, path in sweep.inputs}
    for index, values in enumerate(combos):
        if report is not None:
            report(1)
        values = {k: _plain(v) for k, v in values.items()}
        data = copy.deepcopy(sweep.base)
        for key, value in values.items():
            set_key(data, key, value, error=SweepError, where=f"{sweep.source}: key {key!r}")
        try:
            scenario = parse(data, f"{sweep.source} (flight {index})")
        except ScenarioError as e:
            raise _err(sweep.source, _culprit(e, values), f"flight {index} "
                       f"({_describe(values)}) is not a valid scenario: {e}") from None
        for what, path in scenario.inputs:      # a dimension may vary vehicle.file
            if path not in known:
                known.add(path)
                sweep.inputs.append((what, path))
        key = group_key(data)
        if key not in designed:         # each controller design once, before any flight
            try:
                designed[key] = CONTROLLERS_BY_GROUP[key] = scenario.make_controller()
            except ScenarioError as e:
                raise _err(sweep.source, _culprit(e, values), f"flight {index} "
                           f"({_describe(values)}): the controller cannot be designed: "
                           f"{e}") from None
        reason = cog_admissible(scenario)
        admissible = reason is None
        if not admissible:
            random = [k for k in values if by_key[k].random]
            if random or not skip:
                key = random[0] if random else _cog_key(values)
                hint = ("samples must stay inside the admissible CoG ball (radius "
                        f"{admissible_radius(scenario.vehicle.airframe.parameters()):.4g} m "
                        "for this vehicle)" if random else
                        "set inadmissible = \"skip\" to keep such grid points as rows "
                        "without metrics")
                raise _err(sweep.source, key, f"flight {index} ({_describe(values)}) has an "
                           f"inadmissible CoG: {reason}; {hint}")
        sweep.flights.append(Flight(index, values, admissible))


def _resolve_value(key, value, folder):
    """A dimension's value with a relative file path (``vehicle.file``, or a ``vehicle``
    table with a ``file``) made absolute, relative to ``folder`` (``resolve_paths``)."""
    tokens = parse_key(key)
    if not tokens or tokens[0] not in ("vehicle", "controller_model") or len(tokens) > 2 \
            or any(isinstance(t, int) for t in tokens):
        return value
    holder: dict[str, Any] = {}
    set_key(holder, key, copy.deepcopy(value))
    resolve_paths(holder, folder)
    table = holder[tokens[0]]
    return table[tokens[1]] if len(tokens) == 2 else table


def _check_overlaps(source, keys):
    """Refuse two dimensions of which one key contains the other (``cog[0].r`` and
    ``cog[0].r[0]``, ``vehicle`` and ``vehicle.m``): one would silently replace the other's
    values. (A ``set`` key may contain a dimension's: it gives the structure, such as a CoG
    change, whose values the dimension varies.)"""
    parsed = [(k, parse_key(k)) for k in keys]
    for i, (a, pa_) in enumerate(parsed):
        for b, pb in parsed[i + 1:]:
            short, long_ = (pa_, pb) if len(pa_) <= len(pb) else (pb, pa_)
            if long_[:len(short)] == short:
                raise _err(source, a, f"overlaps the dimension key {b!r} (one contains the "
                           f"other, so one would replace the other's values); vary each value "
                           f"in one dimension")


def _culprit(error, values):
    """The varied key a scenario error is about (the first one its message names)."""
    text = str(error)
    named = [k for k in values if f"'{k.split('[')[0]}" in text or f"'{k}" in text]
    return named[0] if named else next(iter(values))


def _cog_key(values):
    cog = [k for k in values if k.startswith("cog") or k.startswith("vehicle")]
    return cog[0] if cog else next(iter(values))


def _describe(values):
    return ", ".join(f"{k} = {v}" for k, v in values.items())


def sweep_names() -> tuple[str, ...]:
    """Names of the shipped sweep files.

    Returns
    -------
    tuple of str
        Sorted, without ``.toml``.
    """
    return shipped_names("sweep")


def sweep_path(spec: str | os.PathLike[str]) -> Path:
    """The sweep file that ``spec`` stands for.

    Parameters
    ----------
    spec : str or os.PathLike
        A sweep file path, or the name of a shipped one (``"failure-map"``).

    Returns
    -------
    pathlib.Path
        The file to read.

    Raises
    ------
    quadcog.errors.SweepError
        When it is neither a file nor a shipped name (or not a str or os.PathLike).
    """
    if not isinstance(spec, (str, os.PathLike)) or spec == "":
        raise SweepError(f"sweep: expected a sweep file path or a shipped sweep name "
                         f"({', '.join(sweep_names())}), got {spec!r} ({type(spec).__name__})")
    return find_file(spec, "sweep")


def read_sweep_file(spec: str | os.PathLike[str]) -> tuple[dict[str, Any], Path]:
    """A sweep file, parsed but not validated.

    Parameters
    ----------
    spec : str or os.PathLike
        A sweep file path, or the name of a shipped one.

    Returns
    -------
    tuple of (dict, pathlib.Path)
        The parsed TOML and the file's path.

    Raises
    ------
    quadcog.errors.SweepError
        When the file is missing or not valid TOML.
    """
    path = sweep_path(spec)
    return read_toml(path, SweepError), path


def load_sweep(spec: str | os.PathLike[str], *, progress: bool = False,
               **settings: Any) -> Sweep:
    """Read and validate a sweep file (a path or a shipped name).

    Parameters
    ----------
    spec : str or os.PathLike
        The sweep file, or the name of a shipped sweep (``"failure-map"``).
    progress : bool
        Show the validation's progress for a large sweep (``from_dict``).
    **settings
        Top-level keys of the sweep file to replace before validation (``seed=3``,
        ``set={...}``), as in the file.

    Returns
    -------
    Sweep
        The validated sweep with its flights.

    Raises
    ------
    quadcog.errors.SweepError
        For a missing or invalid file, naming it and the key.
    """
    data, path = read_sweep_file(spec)
    data.update(settings)
    return from_dict(data, str(path), path.parent, progress=progress)
