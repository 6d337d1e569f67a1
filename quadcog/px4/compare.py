"""PX4's controllers against quadcog's laws on the same vehicle and events: one row of figures
per flight over the same span of scenario time (from the first event to the end).

The figures of a row (``Comparison``): diverged; the RMS position error over the last quarter
of the span (the tail) and the largest error in the span (m, against the flight's own
reference: the mission's target for PX4, the trajectory for quadcog's law); the settling
time, seconds from the event until the error stays below ``SETTLED`` for good; the time any
rotor spends at a limit of its thrust (within 1 % of zero or of its maximum). PX4's span is
counted from its arming (the scenario's t = 0 in ``quadcog.px4.fly``), quadcog's from the
start of its run.
"""
from dataclasses import dataclass

import numpy as np

from quadcog.sim.result import SimulationResult, position_errors
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["SETTLED", "Comparison", "compare"]

SETTLED = 0.05          # m


@dataclass(frozen=True)
class Comparison:
    """One flight's figures over the span (see the module docstring).

    Parameters
    ----------
    name : str
        Who flew.
    diverged : bool
        The flight diverged (or PX4's ended early).
    tail_rms : float
        RMS position error over the last quarter of the span (m).
    largest : float
        Largest position error in the span (m).
    settling : float
        Seconds from the span's start until the error stays below ``SETTLED`` (nan: never).
    at_limit : float
        Seconds with a rotor within 1 % of a thrust limit.
    """
    name: str
    diverged: bool
    tail_rms: float
    largest: float
    settling: float
    at_limit: float


def compare(name: str, result: SimulationResult, vehicle: Vehicle, t0: float, t1: float,
            offset: float = 0.0, diverged: bool = False) -> Comparison:
    """The figures of one flight over scenario time [t0, t1].

    Parameters
    ----------
    name : str
        Who flew.
    result : SimulationResult
        The flight.
    vehicle : Vehicle
        Its rotor limits (``max_rotor_thrust``, N).
    t0 : float
        The span's start (s of scenario time).
    t1 : float
        The span's end (s of scenario time).
    offset : float
        The result's time at scenario t = 0 (PX4: its arming time).
    diverged : bool
        Count the flight as diverged whatever its figures.

    Returns
    -------
    Comparison
        The row.
    """
    t = result.t - offset
    sel = (t >= t0) & (t <= t1)
    e = position_errors(result.x[sel], result.ref[sel])
    ts = t[sel]
    if ts.size == 0:
        return Comparison(name, True, float("nan"), float("nan"), float("nan"), float("nan"))
    tail = ts >= t1 - 0.25 * (t1 - t0)
    out = np.flatnonzero(e >= SETTLED)
    settling = 0.0 if out.size == 0 else (float(ts[out[-1]] - t0) if out[-1] < ts.size - 1
                                          else float("nan"))
    dt = float(np.median(np.diff(ts))) if ts.size > 1 else 0.0
    limit = 0.0
    if result.rotor_thrust is not None:
        f = result.rotor_thrust[sel]
        hi = vehicle.max_rotor_thrust
        at = (f <= 0.01 * hi) | (f >= 0.99 * hi)
        limit = float(at.any(axis=1).sum() * dt)
    return Comparison(name, bool(diverged or result.metrics.diverged),
                      float(np.sqrt(np.mean(e[tail] ** 2))), float(e.max()), settling, limit)
