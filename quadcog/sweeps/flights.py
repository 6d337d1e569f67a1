"""Fly one chunk of a sweep: the flights are grouped by everything but their truth CoG, and
each group is one batch of the compiled closed-loop step.

A chunk is a plain dict (the base scenario data, the flights' values) and its result a dict of
columns, so it travels to a Dask worker and back without any compiled object: the worker builds
or loads the compiled code itself (from the disk cache, keyed by its source).
"""
from collections.abc import Callable, Sequence
import copy
from typing import Any

import numpy as np
from numpy.typing import NDArray

from quadcog.scenarios.keys import set_key
from quadcog.scenarios.scenario import Scenario, parse
from quadcog.sim.flight import start_at_reference
from quadcog.sweeps.groups import CONTROLLERS_BY_GROUP, group_key
from quadcog.sweeps.spec import Flight, Sweep

__all__ = ["METRICS", "STACK_RUNNERS", "register_stack", "make_job", "run_chunk", "cog_steps",
           "fly_group"]

METRICS = ("rms_position_error", "max_position_error", "rms_position_error_tail",
           "final_position_error", "diverged", "diverged_at")
# how a flight stack (a layer above: quadcog.crazyflie registers itself on import) flies one
# scenario with a [stack] table; such flights run one by one, not as a batch
STACK_RUNNERS: dict[str, Callable[[Scenario], Any]] = {}


def register_stack(name: str, runner: Callable[[Scenario], Any]) -> None:
    """Let sweeps fly scenarios whose ``[stack]`` table names ``name``.

    Parameters
    ----------
    name : str
        The stack's name (``stack.name``).
    runner : callable
        ``runner(scenario) -> SimulationResult``.
    """
    STACK_RUNNERS[name] = runner


def _fly_stack(scenarios: Sequence[Scenario]) -> dict[str, NDArray[Any]]:
    """The METRICS of flights of a flight stack, one after the other."""
    from quadcog.sweeps.spec import SweepError
    name = str(scenarios[0].stack.get("name"))
    runner = STACK_RUNNERS.get(name)
    if runner is None:
        raise SweepError(f"{scenarios[0].source}: key 'stack.name' = {name!r}: no such flight "
                         "stack in this process; import quadcog.crazyflie before the sweep "
                         "(`quadcog sweep` does)")
    out: dict[str, NDArray[Any]] = {k: np.full(len(scenarios), np.nan) for k in METRICS}
    out["diverged"] = np.zeros(len(scenarios), dtype=bool)
    for i, scenario in enumerate(scenarios):
        m = runner(scenario).metrics
        for k in METRICS:
            v = getattr(m, k)
            out[k][i] = np.nan if v is None else v
    return out


def make_job(sweep: Sweep, chunk_index: int, flights: Sequence[Flight]) -> dict[str, Any]:
    """The picklable description of one chunk.

    Parameters
    ----------
    sweep : quadcog.sweeps.spec.Sweep
        The sweep.
    chunk_index : int
        The chunk's index.
    flights : sequence of quadcog.sweeps.spec.Flight
        Its flights.

    Returns
    -------
    dict
        {"chunk", "base", "source", "threshold", "dimensions": [(key, width)], "flights":
        [(index, values, admissible)]}: plain data only.
    """
    return {"chunk": chunk_index, "base": sweep.base, "source": sweep.source,
            "threshold": sweep.threshold,
            "dimensions": [(d.key, d.width) for d in sweep.dimensions],
            "flights": [(f.index, f.values, f.admissible) for f in flights],
            # the modules that registered flight stacks here, imported again in a worker
            "stacks": sorted({runner.__module__ for runner in STACK_RUNNERS.values()})}


def run_chunk(job: dict[str, Any], threads: int = 1) -> dict[str, NDArray[Any]]:
    """Fly the flights of one chunk.

    Deterministic: the same job gives the same bits anywhere.

    Parameters
    ----------
    job : dict
        The chunk (see ``make_job``).
    threads : int
        Threads of the batch kernel.

    Returns
    -------
    dict of str to numpy.ndarray
        {column: (n,) array}, one row per flight in flight order: ``flight``, the varied
        keys, ``controller``, ``admissible``, the ``METRICS`` (m, s) and ``failed``.
    """
    import importlib
    for module in job.get("stacks", ()):       # a worker process registers them again
        importlib.import_module(module)
    flights = job["flights"]
    n = len(flights)
    metrics = {k: np.full(n, np.nan) for k in METRICS}
    metrics["diverged"] = np.zeros(n, dtype=bool)
    groups: dict[str, list[int]] = {}
    scenarios = {}
    for row, (index, values, admissible) in enumerate(flights):
        data = copy.deepcopy(job["base"])
        for key, value in values.items():
            set_key(data, key, value)
        scenarios[row] = parse(data, f"{job['source']} (flight {index})")
        if admissible:
            groups.setdefault(group_key(data), []).append(row)
    for key, rows in groups.items():
        result = fly_group(key, [scenarios[r] for r in rows], threads)
        for name in METRICS:
            metrics[name][rows] = result[name]
    columns = {"flight": np.array([f[0] for f in flights], dtype=np.int64)}
    for key, width in job["dimensions"]:
        values = [f[1][key] for f in flights]
        if width == 1:
            columns[key] = np.array(values)
        else:
            arr = np.array(values, dtype=float).reshape(n, width)
            for i in range(width):
                columns[f"{key}[{i}]"] = arr[:, i]
    if "controller" not in columns:
        columns["controller"] = np.array([
            f"{scenarios[r].stack['name']} {scenarios[r].stack.get('controller', 'pid')}"
            if scenarios[r].stack else scenarios[r].controller for r in range(n)])
    columns["admissible"] = np.array([f[2] for f in flights], dtype=bool)
    columns.update(metrics)
    tail = metrics["rms_position_error_tail"]
    with np.errstate(invalid="ignore"):
        columns["failed"] = columns["admissible"] & (metrics["diverged"]
                                                     | ~(tail <= job["threshold"]))
    return columns


def cog_steps(scenario: Scenario) -> NDArray[np.float64]:
    """The increments of a scenario's CoG changes.

    Parameters
    ----------
    scenario : quadcog.scenarios.scenario.Scenario
        The flight.

    Returns
    -------
    (J, 3) numpy.ndarray
        d_j = r_j - r_{j-1} [m] of its J CoG changes, so that
        r_G(t) = r_G(vehicle) + sum_j s_j(t) d_j.
    """
    changes = scenario.cog.changes
    r = np.array([c.r for c in changes], dtype=float).reshape(-1, 3)
    d = np.diff(np.vstack([np.zeros((1, 3)), r]), axis=0)
    return d


def fly_group(key: str, scenarios: Sequence[Scenario], threads: int = 1,
              precision: str = "float64") -> dict[str, NDArray[Any]]:
    """Metrics of scenarios that differ only in their truth CoG, flown as one batch.

    Parameters
    ----------
    key : str
        What the scenarios share (the controller is built once per key and process).
    scenarios : sequence of quadcog.scenarios.scenario.Scenario
        The flights.
    threads : int
        Threads of the batch kernel.
    precision : str
        "float64" or "float32", the vector kernel's (for measuring; see
        ``quadcog.sim.vector_batch.fly_batch``).

    Returns
    -------
    dict of str to numpy.ndarray
        {metric: (len(scenarios),) array} of the ``METRICS`` (m, s, bool).
    """
    from quadcog.sim.vector_batch import fly_batch
    s0 = scenarios[0]
    if s0.stack:
        return _fly_stack(scenarios)
    ctl = CONTROLLERS_BY_GROUP.get(key)
    if ctl is None:
        ctl = CONTROLLERS_BY_GROUP[key] = s0.make_controller()
    D = np.array([cog_steps(s).ravel() for s in scenarios]).reshape(len(scenarios), -1)
    x0 = start_at_reference(s0.trajectory(0.0))
    x0[:3] += np.asarray(s0.initial_offset)
    r = fly_batch(ctl, [s.vehicle for s in scenarios], D, s0.trajectory, duration=s0.duration,
                  dt=s0.dt,
                  cog_times=[(c.t, c.ramp) for c in s0.cog.changes],
                  disturbances=s0.disturbances, truth=s0.truth, limits=s0.limits, x0=x0,
                  threads=threads, precision=precision, payloads=s0.payload_profile())
    return {name: getattr(r, name) for name in METRICS}
