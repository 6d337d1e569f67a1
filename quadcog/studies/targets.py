"""`quadcog targets`: how the controllers' default settings do on every preset vehicle.

For each preset (``quadcog.vehicles.vehicle.PRESETS``) x law x case, a flight with the
realistic truth and sensing of the ``*-real`` scenarios (those of the shipped ``fig6-real``:
parallel-axis inertia, rotor saturation and lag in the truth, ``Sensing`` with its seed, and
the composite law's model of its motor lag) and otherwise the defaults that
``quadcog.controllers.design`` derives for the vehicle, measured against targets:

- ``hover``: 5 s at hover with nothing changing; the CoG estimate stays within 2 % of the arm
  length of the truth;
- ``cog-step``: the CoG steps by 10 % of the arm length along the diagonal [1, 1, 0] / sqrt 2
  at t = 1 s at hover; the position excursion stays within one arm length and 1 s after the
  step the estimate is within 5 % of the step.

A diverged flight fails every target of its case. Cases are data (``Case``: a name, a function
from the Vehicle to the keyword arguments of ``quadcog.simulate`` and a tuple of ``Metric``);
``CASES`` is the list the command flies, and other cases plug into it (``CASES.append``).
"""
from collections.abc import Callable, Sequence
import csv
from dataclasses import dataclass, field
import io
import math
from pathlib import Path
from typing import Any

import numpy as np

from quadcog.controllers.registry import make_controller
from quadcog.files import RunFiles, strict_json
from quadcog.scenarios.scenario import load_scenario
from quadcog.sim.flight import simulate
from quadcog.sim.result import SimulationResult
from quadcog.validate import choice
from quadcog.vehicles.vehicle import N_ROTORS, PRESETS, Vehicle

__all__ = ["Metric", "Case", "Row", "CASES", "LAWS", "ESTIMATING_LAWS", "MASS_LAWS", "parcel",
           "mass_error_at", "REAL_SCENARIO",
           "STEP_TIME", "STEP_FRACTION", "cog_step", "estimate_drift", "excursion",
           "step_estimate_error", "step_estimate_error_xy", "realistic", "fly", "run_targets", "markdown_table",
           "write_targets", "TARGET_FILES"]

REAL_SCENARIO = "fig6-real"     # the shipped scenario whose truth and sensing are "realistic"
LAWS = ("adaptive", "composite", "payload_adaptive", "pd", "fl", "fl_integral")
ESTIMATING_LAWS = ("adaptive", "composite", "payload_adaptive")   # the others: excursion only
MASS_LAWS = ("payload_adaptive",)           # the laws that estimate the mass too
STEP_TIME = 1.0                 # s
STEP_FRACTION = 0.1             # of the arm length
TARGET_FILES = ("targets.csv", "targets.json", "targets.md")


@dataclass(frozen=True)
class Metric:
    """One measured number of a flight and its target.

    Parameters
    ----------
    name : str
        Short name (a column value of the table).
    measure : callable
        ``measure(result, vehicle) -> float``: the number, from the flight's samples before
        any divergence.
    target : float or None
        The largest value that meets the target (None: reported only).
    unit : str
        What the number is, in words ("of the arm").
    scale : float
        Display factor for the table (100 for percent).
    estimating_only : bool
        True: only for laws that estimate the CoG.
    mass_only : bool
        True: only for laws that estimate the mass (``MASS_LAWS``).
    """
    name: str
    measure: Callable[[SimulationResult, Vehicle], float]
    target: float | None
    unit: str
    scale: float = 1.0
    estimating_only: bool = False
    mass_only: bool = False


@dataclass(frozen=True)
class Case:
    """A flight to measure: what it is, how it is flown on a vehicle, what is measured.

    Parameters
    ----------
    name : str
        Short name.
    description : str
        One line.
    flight : callable
        ``flight(vehicle) -> dict``: keyword arguments of ``quadcog.simulate`` (trajectory,
        duration, cog, ...) for this vehicle; the truth, sensing, vehicle and controller model
        are added by ``fly``.
    metrics : tuple of Metric
        What is measured.
    """
    name: str
    description: str
    flight: Callable[[Vehicle], dict[str, Any]]
    metrics: tuple[Metric, ...]


@dataclass
class Row:
    """One measured metric of one flight.

    Parameters
    ----------
    vehicle : str
        The preset, the controller's short name, the case and the metric.
    law : str
        The preset, the controller's short name, the case and the metric.
    case : str
        The preset, the controller's short name, the case and the metric.
    metric : str
        The preset, the controller's short name, the case and the metric.
    value : float
        The measured number (NaN when the flight diverged before it could be measured).
    target : float or None
        Its target.
    holds : bool or None
        Whether the target holds (False for a diverged flight; None without a target).
    diverged_at : float or None
        When the flight diverged (s).
    unit : str
        The metric's unit in words.
    scale : float
        Its display factor.
    """
    vehicle: str
    law: str
    case: str
    metric: str
    value: float
    target: float | None
    holds: bool | None
    diverged_at: float | None = None
    unit: str = ""
    scale: float = field(default=1.0)


def cog_step(vehicle: Vehicle) -> np.ndarray:
    """The CoG step of the ``cog-step`` case.

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle.

    Returns
    -------
    (3,) numpy.ndarray
        ``STEP_FRACTION`` of the arm length along [1, 1, 0] / sqrt 2 (m).
    """
    return np.array([1.0, 1.0, 0.0]) / math.sqrt(2.0) * STEP_FRACTION * vehicle.arm_length


def estimate_drift(result: SimulationResult, vehicle: Vehicle) -> float:
    """The largest CoG estimate error over the flight, in arm lengths.

    Parameters
    ----------
    result : SimulationResult
        The flight.
    vehicle : Vehicle
        The truth vehicle.

    Returns
    -------
    float
        max_t |r_hat - r_G| / arm length.
    """
    return float(np.max(np.linalg.norm(result.r_hat - result.r_G, axis=1)) / vehicle.arm_length)


def excursion(result: SimulationResult, vehicle: Vehicle) -> float:
    """The largest position error over the flight, in arm lengths.

    Parameters
    ----------
    result : SimulationResult
        The flight.
    vehicle : Vehicle
        The truth vehicle.

    Returns
    -------
    float
        max_t |p - p_ref| / arm length.
    """
    err = np.linalg.norm(result.x[:, 0:3] - result.ref[:, 0:3], axis=1)
    return float(np.max(err) / vehicle.arm_length)


def step_estimate_error(result: SimulationResult, vehicle: Vehicle,
                        axes: slice = slice(0, 3)) -> float:
    """The CoG estimate's error 1 s after the step, relative to the step.

    Parameters
    ----------
    result : SimulationResult
        The flight of the ``cog-step`` case.
    vehicle : Vehicle
        The truth vehicle.
    axes : slice
        The components of the error counted (default all three; ``slice(0, 2)``: x and y).

    Returns
    -------
    float
        |r_hat(STEP_TIME + 1) - r_step| / |r_step|; NaN when the flight ended before.
    """
    r = cog_step(vehicle)
    t = STEP_TIME + 1.0
    if result.t[-1] < t - 1e-9:
        return math.nan
    k = int(np.argmin(np.abs(result.t - t)))
    return float(np.linalg.norm((result.r_hat[k] - r)[axes]) / np.linalg.norm(r))


def step_estimate_error_xy(result: SimulationResult, vehicle: Vehicle) -> float:
    """``step_estimate_error`` of the x and y components only (z_G is barely excited at hover,
    so this shows what the z component adds).

    Parameters
    ----------
    result : SimulationResult
        The flight of the ``cog-step`` case.
    vehicle : Vehicle
        The truth vehicle.

    Returns
    -------
    float
        |(r_hat - r_step)[x, y]| / |r_step| at STEP_TIME + 1.
    """
    return step_estimate_error(result, vehicle, slice(0, 2))


def _hover(vehicle: Vehicle) -> dict[str, Any]:
    return {"trajectory": "hover", "duration": 5.0}


def _step(vehicle: Vehicle) -> dict[str, Any]:
    return {"trajectory": "hover", "duration": 3.0,
            "cog": [(STEP_TIME, tuple(cog_step(vehicle)), 0.0)]}


# The parcel: picked up at PICK_UP, dropped at DROP, its mass a fraction of the vehicle's (30 %,
# or a quarter of the thrust margin where that is less: the Crazyflie preset's rotors give only
# 1.33 times its weight, the X500's 1.74 times, and the offset CoG needs rotor headroom too;
# with a third of the margin the X500's rotors saturate and it diverges), a box at 3/4 of the
# arm out along x and 1/5 of it below O (on the Hummingbird the whole body's CoG moves 2.9 cm
# off the axis).
PICK_UP, DROP, SETTLE = 1.0, 5.0, 2.0       # s; the mass target holds SETTLE after each event
PARCEL_FRACTION = 0.30


def parcel(vehicle: Vehicle) -> dict[str, Any]:
    """The parcel of the parcel cases, as an attach event's fields.

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle that picks it up.

    Returns
    -------
    dict
        ``mass`` (kg), ``position`` and ``size`` (m) of the box, ``name``.
    """
    margin = N_ROTORS * vehicle.max_rotor_thrust / (vehicle.m * vehicle.g) - 1.0
    fraction = min(PARCEL_FRACTION, margin / 4.0)
    arm = vehicle.arm_length
    return {"name": "parcel", "mass": fraction * vehicle.m,
            "position": [0.75 * arm, 0.0, -0.2 * arm], "size": [0.3 * arm] * 3}


def _parcel_events(vehicle: Vehicle) -> list[dict[str, Any]]:
    return [dict(t=PICK_UP, action="attach", **parcel(vehicle)),
            dict(t=DROP, action="drop", name="parcel")]


def mass_error_at(when: float) -> Callable[[SimulationResult, Vehicle], float]:
    """A measure: the mass estimate's relative error ``when`` seconds into the flight.

    Parameters
    ----------
    when : float
        The time (s).

    Returns
    -------
    callable
        ``measure(result, vehicle) -> |m_hat / m - 1|`` (NaN when the flight ended before).
    """
    def measure(result: SimulationResult, vehicle: Vehicle) -> float:
        state, mass = result.controller_state, result.mass
        if result.t[-1] < when - 1e-9 or state is None or mass is None:
            return math.nan
        k = int(np.argmin(np.abs(result.t - when)))
        return float(abs(state[k, 3] / mass[k] - 1.0))
    return measure


def _parcel_hover(vehicle: Vehicle) -> dict[str, Any]:
    return {"trajectory": "hover", "duration": DROP + SETTLE + 0.5,
            "payloads": _parcel_events(vehicle)}


def _parcel_circle(vehicle: Vehicle) -> dict[str, Any]:
    return {"trajectory": "circle", "duration": DROP + SETTLE + 0.5,
            "payloads": _parcel_events(vehicle)}


_PARCEL_METRICS = (
    Metric("excursion", excursion, None, "arm lengths"),
    Metric("mass 2 s after pick-up", mass_error_at(PICK_UP + SETTLE), 0.03, "% of the mass",
           100.0, mass_only=True),
    Metric("mass 2 s after the drop", mass_error_at(DROP + SETTLE), 0.03, "% of the mass",
           100.0, mass_only=True))

CASES: list[Case] = [
    Case("hover", "hover 5 s, nothing changes", _hover,
         (Metric("estimate drift", estimate_drift, 0.02, "% of the arm", 100.0, True),
          Metric("excursion", excursion, None, "arm lengths"))),
    Case("cog-step", "CoG steps 10 % of the arm along the diagonal at t = 1 s, hover", _step,
         (Metric("excursion", excursion, 1.0, "arm lengths"),
          Metric("estimate 1 s after", step_estimate_error, 0.05, "% of the step", 100.0,
                 True),
          Metric("its x, y part", step_estimate_error_xy, None, "% of the step", 100.0, True))),
    Case("parcel-hover", "a parcel (+30 % mass, or a quarter of the thrust margin) picked up at "
         "t = 1 s and dropped at 5 s, hover", _parcel_hover, _PARCEL_METRICS),
    Case("parcel-circle", "the parcel picked up and dropped on a 1 m circle (10 s a lap)",
         _parcel_circle, _PARCEL_METRICS),
]


def realistic() -> dict[str, Any]:
    """The realistic truth, sensing and composite motor model of ``REAL_SCENARIO``.

    Returns
    -------
    dict
        ``truth`` (TruthOptions), ``sensing`` (Sensing) and ``composite`` (the composite law's
        ``controller_params`` of that scenario other than its gains: ``motor_lag``).
    """
    sc = load_scenario(REAL_SCENARIO)
    return {"truth": sc.truth, "sensing": sc.sensing,
            "composite": {k: v for k, v in sc.controller_params.items() if k == "motor_lag"}}


def fly(vehicle_name: str, law: str, case: Case,
        real: dict[str, Any] | None = None) -> list[Row]:
    """One flight of the table: a law with its default settings on a preset, one case.

    Parameters
    ----------
    vehicle_name : str
        A key of ``PRESETS``.
    law : str
        A controller's short name.
    case : Case
        The case.
    real : dict, optional
        ``realistic()`` (computed when not given).

    Returns
    -------
    list of Row
        One per metric of the case that applies to the law.

    Raises
    ------
    quadcog.InputError
        For an unknown preset or law.
    """
    choice(vehicle_name, "vehicle", tuple(PRESETS))
    choice(law, "law", LAWS)
    real = realistic() if real is None else real
    vehicle = PRESETS[vehicle_name]
    model = vehicle.with_cog(np.zeros(3))
    settings = real["composite"] if law in ("composite", "payload_adaptive") else {}
    ctl = make_controller(law, vehicle=model, **settings)
    res = simulate(ctl, vehicle=vehicle, controller_model=model, truth=real["truth"],
                   sensing=real["sensing"], **case.flight(vehicle))
    m = res.metrics
    rows = []
    for metric in case.metrics:
        if ((metric.estimating_only and law not in ESTIMATING_LAWS)
                or (metric.mass_only and law not in MASS_LAWS)):
            continue
        value = metric.measure(res, vehicle)
        holds = None if metric.target is None else bool(
            not m.diverged and np.isfinite(value) and value <= metric.target)
        rows.append(Row(vehicle_name, law, case.name, metric.name, value, metric.target, holds,
                        m.diverged_at if m.diverged else None, metric.unit, metric.scale))
    return rows


def run_targets(vehicles: Sequence[str] = tuple(PRESETS), laws: Sequence[str] = LAWS,
                cases: Sequence[Case] | None = None,
                progress: Callable[[str], Any] | None = None) -> list[Row]:
    """Every flight of the table.

    Parameters
    ----------
    vehicles : sequence of str
        Preset names (default all).
    laws : sequence of str
        Controller short names (default ``LAWS``).
    cases : sequence of Case, optional
        Default ``CASES``.
    progress : callable, optional
        Called with one line per flight as it finishes.

    Returns
    -------
    list of Row
        In the order vehicle, law, case, metric.
    """
    real = realistic()
    rows: list[Row] = []
    for v in vehicles:
        for law in laws:
            for case in (CASES if cases is None else cases):
                done = fly(v, law, case, real)
                rows += done
                if progress is not None:
                    progress("  ".join(_line(r) for r in done))
    return rows


def _shown(r: Row, value: float | None) -> str:
    if value is None:
        return ""
    if not np.isfinite(value):
        return "n/a"
    return f"{value * r.scale:.3g}"


def _line(r: Row) -> str:
    mark = {True: "ok", False: "MISSED", None: ""}[r.holds]
    div = "" if r.diverged_at is None else f" (diverged at {r.diverged_at:.2f} s)"
    return f"{r.vehicle} {r.law} {r.case}: {r.metric} {_shown(r, r.value)} {r.unit} {mark}{div}"


def markdown_table(rows: Sequence[Row]) -> str:
    """The rows as a Markdown table.

    Parameters
    ----------
    rows : sequence of Row
        From ``run_targets``.

    Returns
    -------
    str
        | vehicle | law | case | metric | measured | target | holds | (newline-terminated).
    """
    out = ["| vehicle | law | case | metric | measured | target | holds |",
           "|---|---|---|---|---|---|---|"]
    for r in rows:
        holds = {True: "yes", False: "**no**", None: ""}[r.holds]
        if r.diverged_at is not None:
            holds += f" (diverged at {r.diverged_at:.2f} s)"
        target = "" if r.target is None else f"<= {_shown(r, r.target)}"
        out.append(f"| {r.vehicle} | {r.law} | {r.case} | {r.metric} ({r.unit}) | "
                   f"{_shown(r, r.value)} | {target} | {holds.strip()} |")
    return "\n".join(out) + "\n"


def write_targets(rows: Sequence[Row], out: str | Path) -> Path:
    """Write targets.csv, targets.json and targets.md into a folder.

    Parameters
    ----------
    rows : sequence of Row
        From ``run_targets``.
    out : str or pathlib.Path
        The folder (created when missing).

    Returns
    -------
    pathlib.Path
        The folder.
    """
    keys = ("vehicle", "law", "case", "metric", "value", "target", "holds", "diverged_at",
            "unit")
    data = [{k: getattr(r, k) for k in keys} for r in rows]
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(keys)
    for d in data:
        writer.writerow(["" if d[k] is None else d[k] for k in keys])
    with RunFiles(out, owned=TARGET_FILES) as files:
        files.path("targets.csv").write_text(buf.getvalue())
        files.path("targets.json").write_text(strict_json(data))
        files.path("targets.md").write_text(
            "# Targets of the default settings\n\nRealistic truth and sensing of "
            f"`{REAL_SCENARIO}`; every law with the defaults derived for the vehicle "
            "(`quadcog targets`).\n\n" + markdown_table(rows))
    return Path(out)
