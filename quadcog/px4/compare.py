"""PX4's controllers against quadcog's laws on the same vehicle and events: one row of figures
per flight over the same span of scenario time (from the first event to the end).

The figures of a row (``Comparison``): diverged; the RMS position error over the last quarter
of the span (the tail) and the largest error in the span (m, against the flight's own
reference: for PX4 the position setpoint its position controller tracked, read from its ULog
(``setpoint_reference``), or the mission's target; the trajectory for quadcog's law); the
settling time, seconds from the event until the error stays below ``SETTLED`` for good
(``None``: it never settles within the span); the time any rotor spends at a limit of its
thrust (within 1 % of zero or of its maximum). PX4's span is counted from its arming (the
scenario's t = 0 in ``quadcog.px4.fly``), quadcog's from the start of its run.
"""
from dataclasses import dataclass
import os

import numpy as np
import numpy.typing as npt

from quadcog.errors import LogFormatError
from quadcog.px4.frames import FLIP
from quadcog.px4.lockstep import PERIOD
from quadcog.px4.sensors import EARTH_RADIUS, HOME
from quadcog.sim.result import SimulationResult, position_errors
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["SETTLED", "SETPOINT_TOPIC", "Comparison", "compare", "setpoint_reference",
           "settling_text"]

SETPOINT_TOPIC = "vehicle_local_position_setpoint"     # mc_pos_control's, logged at 10 Hz

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
    settling : float or None
        Seconds from the span's start until the error stays below ``SETTLED`` (None: never
        within the span).
    at_limit : float
        Seconds with a rotor within 1 % of a thrust limit.
    """
    name: str
    diverged: bool
    tail_rms: float
    largest: float
    settling: float | None
    at_limit: float


def settling_text(settling: float | None) -> str:
    """A settling time for a table.

    Parameters
    ----------
    settling : float or None
        ``Comparison.settling``.

    Returns
    -------
    str
        Seconds with two decimals, or "never settles".
    """
    return "never settles" if settling is None else f"{settling:.2f}"


def setpoint_reference(ulog: str | os.PathLike[str], t: npt.ArrayLike
                       ) -> npt.NDArray[np.float64]:
    """The position setpoint PX4's position controller tracked, at the plant's times, in the
    plant's frame.

    PX4's setpoint is in its EKF2's local frame, whose origin (``vehicle_local_position``'s
    ``ref_lat``, ``ref_lon``, ``ref_alt``) is where EKF2 started, not the plant's origin
    (``quadcog.px4.sensors.HOME``): a GPS sample's noise away. The setpoint is moved by that
    origin's offset (the sensors' flat Earth) into the plant's frame: where PX4 wants the
    vehicle to be, in truth.

    Parameters
    ----------
    ulog : str or os.PathLike
        The ULog PX4 wrote in the flight.
    t : (n,) array_like
        The result's sample times (s of PX4's clock from boot; a HIL_SENSOR stamped
        ``t_us`` carries the plant's state at ``t_us - PERIOD``).

    Returns
    -------
    (n, 3) numpy.ndarray
        ``SETPOINT_TOPIC``'s x, y, z in quadcog's ground frame (m), linearly interpolated
        (held before the first and after the last sample); NaN where PX4 set no position
        (velocity-only phases: take-off, landing).

    Raises
    ------
    quadcog.LogFormatError
        The log cannot be read or lacks the topics.
    """
    lp = "vehicle_local_position"
    try:
        from pyulog import ULog
        u = ULog(str(ulog), message_name_filter_list=[SETPOINT_TOPIC, lp])
        d, o = u.get_dataset(SETPOINT_TOPIC).data, u.get_dataset(lp).data
        ned = np.column_stack([d["x"], d["y"], d["z"]]).astype(float)
        origin = np.column_stack([o["ref_lat"], o["ref_lon"], o["ref_alt"]]).astype(float)
        ts, to = d["timestamp"] * 1e-6 - PERIOD, o["timestamp"] * 1e-6 - PERIOD
    except (OSError, ValueError, IndexError, KeyError) as e:
        raise LogFormatError(f"{ulog}: no {SETPOINT_TOPIC} and {lp} with its origin in "
                             f"PX4's ULog ({e})") from None
    lat0, lon0, alt0 = HOME
    offset = np.column_stack([
        np.radians(origin[:, 0] - lat0) * EARTH_RADIUS,
        np.radians(origin[:, 1] - lon0) * EARTH_RADIUS * np.cos(np.radians(lat0)),
        -(origin[:, 2] - alt0)])
    ned = ned + np.column_stack([np.interp(ts, to, offset[:, i]) for i in range(3)])
    tq = np.asarray(t, float)
    out = np.column_stack([np.interp(tq, ts, ned[:, i]) for i in range(3)])
    # a NaN sample: NaN over its neighbourhood (np.interp would spread it wrongly)
    bad = ~np.isfinite(ned).all(axis=1)
    if bad.any():
        near = np.clip(np.searchsorted(ts, tq), 0, ts.size - 1)
        prev = np.clip(near - 1, 0, ts.size - 1)
        out[bad[near] | bad[prev]] = np.nan
    return out * FLIP


def compare(name: str, result: SimulationResult, vehicle: Vehicle, t0: float, t1: float,
            offset: float = 0.0, diverged: bool = False,
            reference: npt.ArrayLike | None = None) -> Comparison:
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
    reference : (n, 3) array_like, optional
        The position reference per sample instead of the result's (``setpoint_reference``);
        samples where it is NaN are left out.

    Returns
    -------
    Comparison
        The row.
    """
    t = result.t - offset
    sel = (t >= t0) & (t <= t1)
    ref = result.ref[:, :3]
    if reference is not None:
        ref = np.asarray(reference, float)
        sel &= np.isfinite(ref).all(axis=1)
    e = position_errors(result.x[sel], ref[sel])
    ts = t[sel]
    if ts.size == 0:
        return Comparison(name, True, float("nan"), float("nan"), None, float("nan"))
    tail = ts >= t1 - 0.25 * (t1 - t0)
    out = np.flatnonzero(e >= SETTLED)
    settling = 0.0 if out.size == 0 else (float(ts[out[-1]] - t0) if out[-1] < ts.size - 1
                                          else None)
    dt = float(np.median(np.diff(ts))) if ts.size > 1 else 0.0
    limit = 0.0
    if result.rotor_thrust is not None:
        f = result.rotor_thrust[sel]
        hi = vehicle.max_rotor_thrust
        at = (f <= 0.01 * hi) | (f >= 0.99 * hi)
        limit = float(at.any(axis=1).sum() * dt)
    return Comparison(name, bool(diverged or result.metrics.diverged),
                      float(np.sqrt(np.mean(e[tail] ** 2))), float(e.max()), settling, limit)
