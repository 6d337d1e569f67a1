"""``quadcog identify`` on the ULogs PX4 wrote while flying quadcog's plant.

Two things connect a PX4 log to the identification (``quadcog.identification.identify``):

- the rotor model: PX4's motor command u (``actuator_motors``) is the rotor speed
  ``omega_min + (omega_max - omega_min) u`` of the x500 airframe and the thrust
  ``k omega^2`` (``quadcog.px4.airframe.RotorMap``), a quadratic in u, i.e. quadcog's
  ``"polynomial"`` rotor model ``c0 + c1 u + c2 u^2`` with ``c0 = k omega_min^2``,
  ``c1 = 2 k omega_min (omega_max - omega_min)``, ``c2 = k (omega_max - omega_min)^2``;
- the rotor order: the ULog reader (``quadcog.logs.ulog``) hands the motors out by quadrant
  (front-right, back-right, back-left, front-left), while the X500 preset keeps PX4's motor
  order; ``log_order`` gives the vehicle with its rotors in the reader's order.

``identify_flight`` identifies a PX4 flight (the part after its first payload or CoG event,
when it has one, settled for ``settle`` seconds) against a baseline flight, and returns the
estimate with the truth the plant flew (the whole body's mass and CoG there).
"""
from dataclasses import dataclass
from typing import Any

import numpy as np

from quadcog.identification.core import Identification, identify
from quadcog.logs import read_log
from quadcog.px4.airframe import RotorMap, read_airframe, rotor_map
from quadcog.vehicles.rotor_model import RotorModel
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["QUADRANTS", "rotor_model", "log_order", "IdentifiedFlight", "identify_flight"]

# the ULog reader's rotor order: (sign of x, sign of y) in FLU, front-right first
QUADRANTS = ((1, -1), (-1, -1), (-1, 1), (1, 1))


def rotor_model(rotors: RotorMap) -> RotorModel:
    """The x500's thrust curve as quadcog's polynomial rotor model of ``motor_command``.

    Parameters
    ----------
    rotors : RotorMap
        ``quadcog.px4.airframe.rotor_map``'s (one rotor-speed range for all motors).

    Returns
    -------
    RotorModel
        ``"px4-gz-x500"``: ``f = k (omega_min + (omega_max - omega_min) u)^2`` expanded.
    """
    lo, hi, k = rotors.omega_min[0], rotors.omega_max[0], rotors.thrust_constant
    d = hi - lo
    return RotorModel(
        name="px4-gz-x500", kind="polynomial", signal="motor_command",
        coefficients=(k * lo * lo, 2.0 * k * lo * d, k * d * d), max_thrust=k * hi * hi,
        source=f"PX4 airframe 4001_gz_x500 (SIM_GZ_EC_MIN {lo:g}, SIM_GZ_EC_MAX {hi:g} rad/s) "
               f"and the gz x500 motorConstant {k:g} N s^2/rad^2")


def log_order(vehicle: Vehicle) -> Vehicle:
    """The vehicle with its rotors in the ULog reader's quadrant order (``QUADRANTS``).

    Parameters
    ----------
    vehicle : Vehicle
        One rotor per quadrant.

    Returns
    -------
    Vehicle
        The same vehicle, rotor positions and directions reordered.
    """
    pos = np.asarray(vehicle.rotor_positions)
    order = [int(np.flatnonzero((np.sign(pos[:, 0]) == qx) & (np.sign(pos[:, 1]) == qy))[0])
             for qx, qy in QUADRANTS]
    return vehicle.replace(rotor_positions=tuple(vehicle.rotor_positions[i] for i in order),
                           rotor_directions=tuple(vehicle.rotor_directions[i] for i in order))


@dataclass(frozen=True)
class IdentifiedFlight:
    """An identification of a PX4 flight and the truth it is held against.

    Parameters
    ----------
    identification : Identification
        ``quadcog.identify``'s result (relative to the baseline when there is one).
    window : tuple of 2 float
        The part of the ULog used (s, on the log's time).
    true_shift : tuple of 3 float
        The plant's whole-body CoG in the window minus the baseline's (m).
    true_mass : float
        The plant's whole-body mass in the window (kg).
    true_mass_change : float
        Its change against the baseline (kg).
    """
    identification: Identification
    window: tuple[float, float]
    true_shift: tuple[float, float, float]
    true_mass: float
    true_mass_change: float


def identify_flight(flight: Any, baseline: Any, settle: float = 5.0,
                    method: str = "auto") -> IdentifiedFlight:
    """Identify a PX4 flight's CoG shift and mass against a baseline flight.

    Parameters
    ----------
    flight : Px4Flight
        ``quadcog.px4.fly``'s, with its ULog.
    baseline : Px4Flight
        ``quadcog.px4.fly``'s, with its ULog: the same vehicle without the payload.
    settle : float
        Seconds after the flight's first payload or CoG event that are left out.
    method : str
        As for ``quadcog.identify``.

    Returns
    -------
    IdentifiedFlight
        The estimate and the truth.
    """
    airframe = read_airframe(flight.build.source)
    vehicle = flight.scenario.vehicle
    model = rotor_model(rotor_map(airframe, vehicle))
    log = read_log(flight.ulog)
    start_us = float(log.meta.get("start_timestamp_us", 0.0))
    events = sorted([e.t for e in flight.scenario.payloads]
                    + [float(c.t) for c in getattr(flight.scenario.cog, "changes", ())])
    t0 = float(log.t[0])
    if events and flight.recording.armed_at is not None:
        # the plant's time t is PX4's time stamp (t + one period) in us; the log counts from
        # its first sample
        t0 = (flight.recording.armed_at + events[0] + settle) - start_us * 1e-6
    window = (t0, float(log.t[-1]))
    result = identify(log.window(*window), vehicle=log_order(vehicle),
                      baseline=read_log(baseline.ulog), method=method, rotor_model=model)
    truth, base = flight.result, baseline.result
    t_plant = window[0] + start_us * 1e-6
    after = truth.t >= t_plant
    airborne = lambda r, sel: sel & (r.x[:, 2] > 0.5)                 # noqa: E731
    sel = airborne(truth, after)
    sel_b = airborne(base, np.ones(base.t.size, bool))
    r_true = truth.r_G[sel].mean(axis=0) - base.r_G[sel_b].mean(axis=0)
    m_true = float(truth.mass[sel].mean())
    return IdentifiedFlight(result, window, (float(r_true[0]), float(r_true[1]),
                                             float(r_true[2])),
                            m_true, m_true - float(base.mass[sel_b].mean()))
