"""``identify``: where is the CoG, and what is the mass, from flight logs.

Several logs are pooled. The method is ``"static"`` (moment and thrust balance at hover),
``"regression"`` (whole-flight filtered least squares with the generated regressor) or
``"auto"``: the regression when every log has the signals it needs, else the static balance,
and the result says why. With ``baseline`` logs of the same vehicle without the payload, the
same estimator runs on them and the result is the difference: the payload's shift of the CoG
and its mass, free of the vehicle's own rotor asymmetry (which reads as a CoG offset: a rotor
that gives 5 % less thrust per command than the model moves the apparent CoG by 5 % / 4 of its
distance from O toward it).
"""
from collections.abc import Sequence
from dataclasses import dataclass
import hashlib
import os
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from quadcog.errors import IdentificationError
from quadcog.identification import _checks
from quadcog.identification.estimators import (
    R_G_NAMES,
    REGRESSION_SIGNALS,
    FlightEstimate,
    missing_for,
    regression,
    static_balance,
)
from quadcog.identification.plausibility import check_log, check_types, hover_physics
from quadcog.logs.flightlog import FlightLog
from quadcog.model.parameters import LARGEST
from quadcog.validate import array, fail, integer, real
from quadcog.vehicles.rotor_model import RotorModel
from quadcog.vehicles.vehicle import PRESETS, Vehicle

__all__ = ["METHODS", "JSON_KEYS", "R_G_NAMES", "IDENTIFIABLE_FRACTION", "NEVER_DETERMINED",
           "ROTOR_ASYMMETRY", "Identification", "pooled_estimate", "identify", "as_logs",
           "as_vehicle"]

METHODS = ("auto", "static", "regression")
JSON_KEYS = ("r_G", "r_G_ci95", "mass", "mass_ci95", "mass_change", "samples", "identifiable")
# an entry of r_G is "determined" when its 95 % half-width is below this fraction of the arm
IDENTIFIABLE_FRACTION = 0.05
# z_G is never reported determined: where a flight excites it at all (tilt, angular
# acceleration), its regressor column is made of measured rates, angles and velocities whose
# noise biases the least squares toward 0 (errors in variables) by more than the interval
# shows (docs/identify.md: a simulated 23 deg circle with the *-real sensing noise)
NEVER_DETERMINED = ("z_G",)
ROTOR_ASYMMETRY = 0.05         # the weaker-rotor example of the verdict: 5 % less thrust


def _r_G(value: object, where: str) -> tuple[float, float, float]:
    """r_G: 3 finite numbers (m) within +-LARGEST, as a tuple of floats (a list, a tuple or
    an array of shape (3,); not a column)."""
    what = "3 finite numbers (m)"
    try:
        r = array(value, where, shape=(3,), what=what,  # type: ignore[arg-type]
                  error=IdentificationError)
    except IdentificationError:          # the value as a whole, not its first bad entry
        fail(where, what, value, IdentificationError)
    if not np.abs(r).max() <= LARGEST:
        fail(where, f"3 numbers within +-{LARGEST:g} m", value, IdentificationError)
    return (float(r[0]), float(r[1]), float(r[2]))


def _r_G_ci95(value: object, where: str) -> tuple[float | None, ...]:
    """r_G's 95 % half-widths: 3 entries, each None (not estimated) or a finite number >= 0
    (m)."""
    what = "3 half-widths (m), each a number >= 0 or None (not estimated)"
    items = value.tolist() if isinstance(value, np.ndarray) and value.ndim == 1 else value
    if not isinstance(items, (list, tuple)) or len(items) != 3:
        fail(where, what, value, IdentificationError)
    return tuple(None if v is None else real(v, f"{where}[{i}]", lo=0.0, unit="m",
                                                 error=IdentificationError)
                 for i, v in enumerate(items))


def _mass(value: object, where: str) -> float:
    """A mass (kg) in (0, LARGEST], as every vehicle's."""
    return real(value, where, lo=0.0, lo_open=True, hi=LARGEST, unit="kg",
                error=IdentificationError)


def _mass_ci95(value: object, where: str) -> float:
    return real(value, where, lo=0.0, unit="kg", error=IdentificationError)


def _mass_change(value: object, where: str) -> float:
    return real(value, where, lo=-LARGEST, hi=LARGEST, unit="kg", error=IdentificationError)


def _samples(value: object, where: str) -> int:
    """The log samples an identification used: a whole number >= 1."""
    return integer(value, where, lo=1, error=IdentificationError)


def _identifiable(value: object, where: str) -> tuple[str, ...]:
    """The entries of r_G the data determine: distinct names of ``R_G_NAMES``, in order."""
    what = f"distinct names of {', '.join(R_G_NAMES)}"
    items = value.tolist() if isinstance(value, np.ndarray) and value.ndim == 1 else value
    if not isinstance(items, (list, tuple)) or len(set(map(repr, items))) != len(items):
        fail(where, what, value, IdentificationError)
    for i, name in enumerate(items):
        if not isinstance(name, str) or name not in R_G_NAMES:
            fail(f"{where}[{i}]", f"one of {', '.join(R_G_NAMES)}", name, IdentificationError)
    return tuple(str(n) for n in items)


# The checks of the fields ``as_json`` writes (JSON_KEYS): Identification checks its own
# with them, ``identified_cog`` the keys of a JSON file (where null stands for None)
JSON_CHECKS = {"r_G": _r_G, "r_G_ci95": _r_G_ci95, "mass": _mass, "mass_ci95": _mass_ci95,
               "mass_change": _mass_change, "samples": _samples,
               "identifiable": _identifiable}


@dataclass(frozen=True, eq=False)
class Identification:
    """The identified CoG offset and mass (what ``quadcog identify --json`` writes, and more).

    Parameters
    ----------
    r_G : tuple of 3 float
        CoG offset (m, body frame: x forward, y left, z up); with a baseline the shift
        relative to the baseline flights, else relative to O. An entry the method does not
        estimate is the vehicle's own value (baseline: 0).
    r_G_ci95 : tuple of 3 (float or None)
        95 % half-widths (m); None where the method does not estimate the entry.
    mass : float
        Mass (kg) during the flights.
    mass_ci95 : float
        Its 95 % half-width (kg).
    mass_change : float or None
        Mass minus the baseline's (kg); None without a baseline.
    samples : int
        Log samples used (flights, and baseline flights).
    identifiable : tuple of str
        The entries of r_G the data determine (names of ``R_G_NAMES``).
    method : str
        ``"static"`` or ``"regression"``, with the reason when ``"auto"`` chose.
    verdict : str
        The identifiability report in words.
    flights : tuple of FlightEstimate
        Per-log estimates (for figures and surveys).
    baseline : tuple of FlightEstimate
        Per-log estimates (for figures and surveys).
    condition : float or None
        Largest condition number of the scaled regressor over the logs (regression).

    Returns
    -------
    Identification

    Raises
    ------
    IdentificationError
        A field of another type or out of range, named ``Identification.<field>``: r_G not 3
        finite numbers within +-LARGEST (m), a half-width negative or not a number (None
        where not estimated), a mass not in (0, LARGEST] kg, samples not a whole number
        >= 1, identifiable not distinct names of ``R_G_NAMES``, method or verdict not a str,
        flights or baseline not a list or tuple of FlightEstimate, a condition number that
        is not a finite number > 0.
    """
    r_G: tuple
    r_G_ci95: tuple
    mass: float
    mass_ci95: float
    mass_change: float | None
    samples: int
    identifiable: tuple
    method: str
    verdict: str
    flights: tuple = ()
    baseline: tuple = ()
    condition: float | None = None

    def __post_init__(self) -> None:
        for key, check in JSON_CHECKS.items():
            value = getattr(self, key)
            if not (key == "mass_change" and value is None):
                object.__setattr__(self, key, check(value, f"Identification.{key}"))
        for key in ("method", "verdict"):
            object.__setattr__(self, key, _checks.text(getattr(self, key),
                                                       f"Identification.{key}"))
        for key in ("flights", "baseline"):
            object.__setattr__(self, key, tuple(_checks.sequence(
                getattr(self, key), f"Identification.{key}", FlightEstimate, "FlightEstimate")))
        if self.condition is not None:
            object.__setattr__(self, "condition", real(
                self.condition, "Identification.condition", lo=0.0, lo_open=True,
                error=IdentificationError))

    def as_json(self) -> dict[str, Any]:
        """Exactly the ``JSON_KEYS`` as plain JSON values (None for null).

        Returns
        -------
        dict
            What ``quadcog identify --json`` writes (m, kg).
        """
        return {"r_G": [float(v) for v in self.r_G],
                "r_G_ci95": [None if v is None else float(v) for v in self.r_G_ci95],
                "mass": float(self.mass), "mass_ci95": float(self.mass_ci95),
                "mass_change": None if self.mass_change is None else float(self.mass_change),
                "samples": int(self.samples), "identifiable": list(self.identifiable)}

    def summary(self) -> str:
        """The lines ``quadcog identify`` prints (mm and g).

        Returns
        -------
        str
            Several lines, without a final newline.
        """
        what = "shift relative to the baseline" if self.mass_change is not None else \
            "offset from O"
        parts = []
        for name, v, h in zip(R_G_NAMES, self.r_G, self.r_G_ci95):
            parts.append(f"{name} = {1e3 * v:+.2f} +- {1e3 * h:.2f} mm" if h is not None
                         else f"{name} not estimated")
        lines = [f"CoG {what} (body x forward, y left, z up; 95 % intervals): "
                 + ", ".join(parts),
                 f"mass: {1e3 * self.mass:.2f} +- {1e3 * self.mass_ci95:.2f} g"
                 + ("" if self.mass_change is None else
                    f" (change against the baseline: {1e3 * self.mass_change:+.2f} g)"),
                 f"samples: {self.samples} ({len(self.flights)} log(s)"
                 + (f", {len(self.baseline)} baseline log(s)" if self.baseline else "")
                 + f"); method: {self.method}",
                 f"identifiable: {', '.join(self.identifiable) or 'nothing'}",
                 f"verdict: {self.verdict}"]
        return "\n".join(lines)


def as_vehicle(vehicle: str | Vehicle) -> Vehicle:
    """A Vehicle from a preset name (``quadcog.vehicles.vehicle.PRESETS``) or a Vehicle.

    Parameters
    ----------
    vehicle : str or Vehicle
        A preset name, e.g. ``"crazyflie"``, or a Vehicle (returned as it is).

    Returns
    -------
    Vehicle
        The vehicle.

    Raises
    ------
    IdentificationError
        An unknown name or another type.
    """
    if isinstance(vehicle, Vehicle):
        return vehicle
    if isinstance(vehicle, str) and vehicle in PRESETS:
        return PRESETS[vehicle]
    fail("vehicle", f"a preset name ({', '.join(PRESETS)}) or a quadcog Vehicle", vehicle,
         IdentificationError)


def as_logs(logs: FlightLog | str | Path | Sequence[FlightLog | str | Path],
            what: str = "logs") -> list[FlightLog]:
    """FlightLogs from one log or path, or a sequence of them.

    Paths are read with ``quadcog.logs.read_log``, the format from the file.

    Parameters
    ----------
    logs : FlightLog, str, Path or a sequence of them
        The flights.
    what : str
        The argument's name, for messages.

    Returns
    -------
    list of FlightLog
        At least one.

    Raises
    ------
    IdentificationError
        An empty sequence or an item of another type, ``what`` not a str; the readers'
        LogError for bad files.
    """
    from quadcog.logs import FlightLog, read_log
    _checks.text(what, "as_logs: what")
    expected = "a FlightLog, a log file's path, or a list of them"
    if isinstance(logs, (str, os.PathLike, FlightLog)):
        items = [logs]
    elif isinstance(logs, (list, tuple)):
        items = list(logs)
    else:
        fail(what, expected, logs, IdentificationError)
    if not items:
        raise IdentificationError(f"{what}: expected at least one flight log, got none")
    out = []
    for i, item in enumerate(items):
        if isinstance(item, FlightLog):
            out.append(item)
        elif isinstance(item, (str, os.PathLike)) and not isinstance(item, bytes):
            out.append(read_log(item))
        else:
            fail(f"{what}[{i}]" if len(items) > 1 or not isinstance(logs, FlightLog) else what,
                 "a FlightLog or a log file's path", item, IdentificationError)
    return out


def _choose(method: str, logs: list[FlightLog]) -> tuple[str, str]:
    if not isinstance(method, str) or method not in METHODS:
        fail("method", f"one of {', '.join(METHODS)}", method, IdentificationError)
    lacking = {log.source: missing_for(log, REGRESSION_SIGNALS) for log in logs}
    lacking = {k: v for k, v in lacking.items() if v}
    if method == "regression" and lacking:
        src, miss = next(iter(lacking.items()))
        raise IdentificationError(f"{src}: method 'regression' needs {', '.join(miss)}, which "
                                  "the log lacks; method 'static' needs only the rotor outputs "
                                  "and the height")
    if method != "auto":
        return method, method
    if lacking:
        src, miss = next(iter(lacking.items()))
        return "static", (f"static (auto: the whole-flight least squares needs "
                          f"{', '.join(miss)}, which {Path(src).name} lacks)")
    return "regression", "regression (auto: every log has the signals it needs)"


def pooled_estimate(estimates: Sequence[FlightEstimate]
                    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], float, float,
                               int]:
    """The estimate of several logs: the static balance's blocks pooled (speed-corrected);
    the regression's per-log results combined by inverse variance.

    Parameters
    ----------
    estimates : sequence of FlightEstimate
        Of one method.

    Returns
    -------
    (numpy.ndarray (3,), numpy.ndarray (3,), float, float, int)
        r_G and its half-widths (m, NaN where not estimated), mass and half-width (kg),
        samples.

    Raises
    ------
    IdentificationError
        ``estimates`` not a non-empty list or tuple of FlightEstimate, or estimates of
        different methods.
    """
    from quadcog.identification.segments import _block_mean_ci95, _speed_corrected
    estimates = _checks.sequence(estimates, "pooled_estimate: estimates", FlightEstimate,
                                 "FlightEstimate", min_items=1)
    methods = [e.method for e in estimates]
    for i, method in enumerate(methods):
        if method != methods[0] or method not in ("static", "regression"):
            fail(f"pooled_estimate: estimates[{i}].method",
                 "'static' or 'regression', the same for every estimate", method,
                 IdentificationError)
    samples = sum(e.samples for e in estimates)
    m, m_half = _block_mean_ci95(np.concatenate([e.blocks_m for e in estimates]))
    if estimates[0].method == "static":
        if len(estimates) == 1:
            r, half = estimates[0].r_G, estimates[0].r_G_ci95
        else:
            r, half, _ = _speed_corrected(np.concatenate([e.blocks_r for e in estimates]),
                                         np.concatenate([e.blocks_v for e in estimates]))
            half[2] = np.nan
        return r, half, float(m), float(m_half), samples
    # inverse-variance weights relative to the narrowest interval, so that neither a tiny
    # half-width (1/h^2 overflows to inf, inf/inf is NaN) nor a zero one gives NaN
    h = np.array([e.r_G_ci95 for e in estimates], dtype=float)
    rs = np.array([e.r_G for e in estimates], dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        h_min = np.min(h, axis=0)
        w = np.where(h_min == 0, (h == 0).astype(float), (h_min / h) ** 2)
        total = w.sum(axis=0)
        r = (w * rs).sum(axis=0) / total
        half = h_min / np.sqrt(total)
    return r, half, float(m), float(m_half), samples


def _estimate(logs, vehicle, method, rotor_model):
    run = static_balance if method == "static" else regression
    return [run(log, vehicle, rotor_model) for log in logs]


def identify(logs: FlightLog | str | Path | Sequence[FlightLog | str | Path],
             vehicle: str | Vehicle = "crazyflie",
             baseline: FlightLog | str | Path | Sequence[FlightLog | str | Path] | None = None,
             method: str = "auto", rotor_model: RotorModel | str | None = None
             ) -> Identification:
    """Identify the CoG offset r_G and the mass from flight logs (module docstring).

    Parameters
    ----------
    logs : FlightLog, path, or a sequence of them
        The flights (pooled). The take-off and landing are cut by ``hover_window``.
    vehicle : str or Vehicle
        ``"crazyflie"``, ``"hummingbird"`` or a Vehicle: rotor positions, rotor model, inertia.
    baseline : FlightLog, path, sequence of them, or None
        Flights of the same vehicle without the payload: the result is relative to them.
    method : str
        ``"auto"``, ``"static"`` or ``"regression"``.
    rotor_model : RotorModel or str, optional
        Instead of the vehicle's (a name of ``quadcog.vehicles.rotor_model.ROTOR_MODELS``).

    Returns
    -------
    Identification
        The estimate, its intervals and the verdict.

    Raises
    ------
    IdentificationError
        Unknown vehicle or method, a log without the signals the method needs, too few hover
        samples, a flight given twice (among the logs, or the logs and the baseline: the same
        samples); LogError for a file that cannot be read.
    """
    preset = isinstance(vehicle, str)
    vehicle = as_vehicle(vehicle)
    if rotor_model is not None and not isinstance(rotor_model, (str, RotorModel)):
        fail("rotor_model", "a RotorModel, a name of quadcog.vehicles.rotor_model.ROTOR_MODELS "
             "or None", rotor_model, IdentificationError)
    logs = as_logs(logs)
    base = None if baseline is None else as_logs(baseline, "baseline")
    chosen, described = _choose(method, logs + (base or []))
    # the units and the physics of every log, before any estimate
    check_types(logs, base or [], vehicle if preset else None)
    _check_distinct(logs, base or [])
    _check_thrust_sources(logs, base or [], [_check_physics(log, vehicle, rotor_model)
                                             for log in logs + (base or [])])
    flights = _estimate(logs, vehicle, chosen, rotor_model)
    r, half, m, m_half, samples = pooled_estimate(flights)
    base_est = ()
    mass_change = None
    if base is not None:
        base_est = tuple(_estimate(base, vehicle, chosen, rotor_model))
        rb, hb, mb, _, sb = pooled_estimate(base_est)
        r, half = r - rb, np.sqrt(half ** 2 + hb ** 2)
        mass_change, samples = m - mb, samples + sb
    # an entry the method does not estimate: the vehicle's own value (no shift with a baseline)
    r = np.where(np.isnan(half), 0.0 if base is not None else vehicle.r_G, r)
    limit = IDENTIFIABLE_FRACTION * vehicle.arm_length
    ok = tuple(n for n, h in zip(R_G_NAMES, half)
               if np.isfinite(h) and h < limit and n not in NEVER_DETERMINED)
    _check_answer(logs, vehicle, r, half, m, m_half, mass_change)
    conditions = [e.condition for e in flights + list(base_est) if e.condition is not None]
    condition = max(conditions) if conditions else None
    verdict = _verdict(vehicle, flights, half, ok, limit, condition, base is not None)
    return Identification(
        r_G=tuple(float(v) for v in r),
        r_G_ci95=tuple(None if not np.isfinite(h) else float(h) for h in half),
        mass=m, mass_ci95=m_half, mass_change=None if mass_change is None else
        float(mass_change), samples=int(samples), identifiable=ok, method=described,
        verdict=verdict, flights=tuple(flights), baseline=base_est, condition=condition)


def _flight_digest(log: FlightLog) -> bytes:
    """A digest of a log's samples (time and standard signals): equal for the same flight
    read twice, whatever its source is called (linear in the log)."""
    h = hashlib.blake2b(digest_size=16)
    h.update(np.ascontiguousarray(log.t).tobytes())
    for name in sorted(log.signals):
        h.update(name.encode() + b"\0" + np.ascontiguousarray(log.signals[name]).tobytes())
    return h.digest()


def _check_distinct(logs: list[FlightLog], baseline: list[FlightLog]) -> None:
    """Refuse a flight given twice (the same file twice, or among the logs and the
    baseline): its samples would count twice, narrowing the intervals without new data, and
    a flight against itself shows no shift, whatever the payload."""
    seen: dict[bytes, str] = {}
    for role, items in (("logs", logs), ("baseline", baseline)):
        for i, log in enumerate(items):
            where = f"{role}[{i}]"
            first = seen.setdefault(_flight_digest(log), where)
            if first != where:
                raise IdentificationError(
                    f"{where}: expected a flight not given before, got {log.source}, the same "
                    f"samples as {first}: a flight counted twice narrows the intervals without "
                    "new data (and against itself shows no shift)")


def _check_physics(log, vehicle, rotor_model):
    """The plausibility checks of one log (quadcog.identification.plausibility); returns
    the sentence saying where its thrust comes from (``rotor_thrusts``)."""
    from quadcog.identification.segments import hover_window, rotor_thrusts, vertical_acceleration
    check_log(log)
    window = hover_window(log)
    thrusts, described, model = rotor_thrusts(log, vehicle, rotor_model)
    a_z, a_from = vertical_acceleration(log)
    hover_physics(log, vehicle, window.mask, thrusts, a_z, a_from, model)
    return described


def _check_thrust_sources(logs, baseline, described):
    """Refuse logs (and baseline logs) whose thrusts come from different rotor models or
    signals (``segments.thrust_source``): each source has its own error, which pooling mixes
    and a baseline does not cancel (a payload would read as a change of the model's error:
    a mass that falls when the payload is added)."""
    from quadcog.identification.segments import thrust_source
    roles = [f"logs[{i}]" for i in range(len(logs))] + \
        [f"baseline[{i}]" for i in range(len(baseline))]
    items = list(zip(roles, logs + baseline, map(thrust_source, described)))
    first_role, first, source = items[0]
    for role, log, other in items[1:]:
        if other != source:
            raise IdentificationError(
                f"{role}: expected a log whose thrust comes from {source} as in {first_role} "
                f"({first.source}), got {log.source}, whose thrust comes from {other}: each "
                "rotor model and signal has its own error, which pooling mixes and a baseline "
                "does not cancel; give logs that log the same signals")


def _check_answer(logs, vehicle, r, half, m, m_half, mass_change):
    """Never an answer of inf, NaN or a CoG beyond the rotors: say what the data lack."""
    names = ", ".join(log.source for log in logs)
    values = [m, m_half] + list(r) + ([] if mass_change is None else [mass_change])
    estimated = [h for h in half if not np.isnan(h)]
    # within the model's scale too (LARGEST: what an Identification holds), z_G included
    if not (np.isfinite(values).all() and np.isfinite(estimated).all() and m > 0
            and np.abs(values).max() <= LARGEST):
        raise IdentificationError(
            f"{names}: the estimate is not a number within the model's scale (mass {m!r} kg, "
            f"r_G {list(r)!r} m, each within {LARGEST:g}): the logs do not determine the CoG; "
            "check their units and signals")
    arm = vehicle.arm_length
    if np.abs(r[:2]).max() > arm:
        raise IdentificationError(
            f"{names}: the estimate puts the CoG {1e3 * float(np.abs(r[:2]).max()):.3g} mm from "
            f"O, beyond the rotors of {vehicle.name!r} (arm {1e3 * arm:.3g} mm), where no "
            "vehicle hovers: the motor outputs, the rotor model or the rotor order are not "
            "this vehicle's")


def _verdict(vehicle, flights, half, ok, limit, condition, with_baseline):
    out = []
    not_ok = [n for n in R_G_NAMES if n not in ok]
    if ok:
        out.append(f"{', '.join(ok)} determined (95 % half-widths below "
                   f"{1e3 * limit:.2f} mm, {100 * IDENTIFIABLE_FRACTION:g} % of the arm)")
    for n, h in zip(R_G_NAMES, half):
        if n in not_ok:
            if not np.isfinite(h):
                why = [note for e in flights for note in e.notes
                       if note.startswith(f"{n} not estimated")]
                out.append(why[0] if why else f"{n} not estimated")
            elif n in NEVER_DETERMINED:
                out.append(f"{n} estimated (half-width {1e3 * h:.2f} mm) but not determined: "
                           "the noise of the measured rates, angles and velocities in its "
                           "regressor column biases it toward 0 by more than its interval")
            else:
                out.append(f"{n} not determined by these flights (half-width "
                           f"{1e3 * h:.2f} mm)")
    for start in ("not a hover", "moving at constant height"):
        notes = [note for e in flights for note in e.notes if note.startswith(start)]
        if notes:
            out.append(notes[0] + (f" ({len(notes)} of {len(flights)} logs)"
                                   if len(flights) > 1 else ""))
    if condition is not None:
        out.append(f"condition number of the scaled regressor {condition:.3g}")
    arm = max(np.hypot(*np.asarray(vehicle.rotor_positions).T))
    shift = ROTOR_ASYMMETRY * arm / 4
    if with_baseline:
        out.append("relative to the baseline flights, so the vehicle's own rotor asymmetry "
                   "cancels (if it did not change between the flights)")
    else:
        out.append(f"a rotor {100 * ROTOR_ASYMMETRY:g} % weaker than the rotor model reads as a "
                   f"CoG shift of {1e3 * shift:.2f} mm toward it, indistinguishable in these "
                   "data; fly baseline flights without the payload (--baseline) to remove it")
    out.append(f"thrust: {flights[0].rotor}")
    return "; ".join(out)
