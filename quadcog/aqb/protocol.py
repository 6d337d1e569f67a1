"""AdaptiveQuadBench's payload protocol as quadcog flights, on quadcog's payload model.

The distribution, read from AdaptiveQuadBench's ``aqb/config/randomization_config.py`` and
RotorPy's ``trajectories/random_motion_prim_traj.py`` (commit ee7df29 / 6d2045d):

- a motion primitive from rest at the origin to a goal whose position, velocity and
  acceleration are each U(-2, 2)^3 (m, m/s, m/s^2), reached at T = 5 s: per axis the
  minimum-jerk quintic (Mueller, Hehn, D'Andrea 2015), the flight lasting T;
- a payload of mass U(0, 0.5) x the vehicle's 0.826 kg (``--when2fail`` at intensity k:
  exactly min(k, 2) x the mass) at a CoM offset U(-0.2, 0.2)^3 x the 0.166 m arm, a point mass;
- 1 to 4 toggle times (``randint(1, 5)``), each U(0.5, 4.5) s and at least 0.5 s from the
  others (up to 100 draws each; a toggle that finds no place ends the list), sorted: the
  payload is attached at the first, dropped at the second, and so on.

``payload_trials`` draws them in AdaptiveQuadBench's order from a legacy numpy RandomState
seeded as its ``--seed`` (all trajectories, then all payloads, then all toggle lists; the
when2fail mode draws payloads and toggles again at each intensity), so trial i is the trial i
AdaptiveQuadBench flies (trial i depends on the number of trials, as there: all goals are drawn
before the first payload). ``fly`` flies a trial in quadcog's simulator, whose truth model
carries the payload as a rigid body (its ten inertial parameters added to the airframe's,
``quadcog.vehicles.payload``), at any rate and with the real-sensing options: its
``MotionPrimitive`` trajectory and its ``payload_events`` are ordinary ``quadcog.simulate``
arguments.
"""
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.aqb.convert import vehicle_from_quad_params
from quadcog.controllers.registry import make_controller
from quadcog.errors import SizeError
from quadcog.sim.flight import simulate
from quadcog.sim.plant import TruthOptions
from quadcog.sim.result import SimulationResult
from quadcog.sim.sensing import Sensing
from quadcog.sim.timeline import PayloadEvent
from quadcog.trajectories.analytic import Trajectory
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["AQB_QUAD_PARAMS", "GOAL_RANGE", "MASS_RATIO_RANGE", "OFFSET_RATIO_RANGE",
           "FLIGHT_TIME", "MIN_TOGGLE_INTERVAL", "SUCCESS_RMSE", "MAX_DRAWS", "MotionPrimitive",
           "PayloadTrial", "payload_trials", "aqb_vehicle", "rmse", "fly"]

# AdaptiveQuadBench's vehicle (aqb/quad_param/quadrotor.py): what the conversion needs of it;
# tests/test_aqb.py compares it with the installed package's
_D = 0.166
AQB_QUAD_PARAMS: dict[str, Any] = {
    "mass": 0.826, "Ixx": 0.0047, "Iyy": 0.005, "Izz": 0.0074, "Ixy": 0.0, "Iyz": 0.0,
    "Ixz": 0.0, "arm_length": _D, "com": np.zeros(3), "num_rotors": 4,
    "rotor_pos": {"r1": _D * np.array([np.sin(np.pi / 4), np.cos(np.pi / 4), 0]),
                  "r2": _D * np.array([np.sin(np.pi / 4), -np.cos(np.pi / 4), 0]),
                  "r3": _D * np.array([-np.sin(np.pi / 4), -np.cos(np.pi / 4), 0]),
                  "r4": _D * np.array([-np.sin(np.pi / 4), np.cos(np.pi / 4), 0])},
    "rotor_directions": np.array([1, -1, 1, -1]), "k_eta": 7.64e-6, "k_m": 7.64e-6 * 0.0140,
    "k_d": 1.19e-04, "k_z": 2.32e-04, "k_flap": 0.0, "tau_m": 0.005,
    "rotor_speed_min": 0.0, "rotor_speed_max": 1000.0, "c_Dx": 0.0, "c_Dy": 0.0, "c_Dz": 0.0}
GOAL_RANGE = (-2.0, 2.0)
MASS_RATIO_RANGE = (0.0, 0.5)
OFFSET_RATIO_RANGE = (-0.2, 0.2)
FLIGHT_TIME = 5.0
MIN_TOGGLE_INTERVAL = 0.5
# AdaptiveQuadBench counts a flight a success when its position RMSE is below 5 m
SUCCESS_RMSE = 5.0
# the most trial draws payload_trials makes (n trials, times intensity + 1 when2fail steps)
MAX_DRAWS = 1_000_000


@dataclass
class MotionPrimitive(Trajectory):
    """A minimum-jerk motion primitive from rest at the origin to a goal state at ``duration``.

    Per axis ``p(t) = alpha t^5 / 120 + beta t^4 / 24 + gamma t^3 / 6`` with
    ``alpha = (60 T^2 a_f - 360 T v_f + 720 p_f) / T^5``,
    ``beta = (-24 T^3 a_f + 168 T^2 v_f - 360 T p_f) / T^5``,
    ``gamma = (3 T^4 a_f - 24 T^3 v_f + 60 T^2 p_f) / T^5`` (RotorPy's ``RapidTrajectory``
    with every goal set); yaw 0.

    Parameters
    ----------
    goal_position : (3,) array_like
        The position at ``duration`` (m), ground axes.
    goal_velocity : (3,) array_like
        The velocity at ``duration`` (m/s), ground axes.
    goal_acceleration : (3,) array_like
        The acceleration at ``duration`` (m/s^2), ground axes.
    duration : float
        T (s), > 0.

    Raises
    ------
    quadcog.InputError
        A goal that is not 3 finite numbers, or T <= 0.
    """
    goal_position: Any = (0.0, 0.0, 0.0)
    goal_velocity: Any = (0.0, 0.0, 0.0)
    goal_acceleration: Any = (0.0, 0.0, 0.0)
    duration: float = FLIGHT_TIME

    def __post_init__(self) -> None:
        self.goal_position = validate.array(self.goal_position, "goal_position", (3,))
        self.goal_velocity = validate.array(self.goal_velocity, "goal_velocity", (3,))
        self.goal_acceleration = validate.array(self.goal_acceleration, "goal_acceleration", (3,))
        T = self.duration = validate.positive(self.duration, "duration", "s")
        p, v, a = self.goal_position, self.goal_velocity, self.goal_acceleration
        self._alpha = (60 * T**2 * a - 360 * T * v + 720 * p) / T**5
        self._beta = (-24 * T**3 * a + 168 * T**2 * v - 360 * T * p) / T**5
        self._gamma = (3 * T**4 * a - 24 * T**3 * v + 60 * T**2 * p) / T**5

    def _pvaj(self, t):
        t = t[:, None]
        al, be, ga = self._alpha, self._beta, self._gamma
        return (al * t**5 / 120 + be * t**4 / 24 + ga * t**3 / 6,
                al * t**4 / 24 + be * t**3 / 6 + ga * t**2 / 2,
                al * t**3 / 6 + be * t**2 / 2 + ga * t,
                al * t**2 / 2 + be * t + ga)


@dataclass(frozen=True)
class PayloadTrial:
    """One trial of the payload protocol.

    Parameters
    ----------
    index : int
        Its number in the draw (AdaptiveQuadBench's ``traj_number``).
    goal_position : tuple of 3 float
        The motion primitive's goal position (m).
    goal_velocity : tuple of 3 float
        The motion primitive's goal velocity (m/s).
    goal_acceleration : tuple of 3 float
        The motion primitive's goal acceleration (m/s^2).
    payload_mass : float
        kg (0: no payload).
    payload_position : tuple of 3 float
        Its CoM from O in body axes (m).
    toggle_times : tuple of float
        Attach, drop, attach, ... times (s), increasing.
    """
    index: int
    goal_position: tuple[float, ...]
    goal_velocity: tuple[float, ...]
    goal_acceleration: tuple[float, ...]
    payload_mass: float
    payload_position: tuple[float, ...]
    toggle_times: tuple[float, ...]

    def trajectory(self) -> MotionPrimitive:
        """The motion primitive.

        Returns
        -------
        MotionPrimitive
            To the trial's goal in ``FLIGHT_TIME``.
        """
        return MotionPrimitive(self.goal_position, self.goal_velocity, self.goal_acceleration)

    def payload_events(self, name: str = "payload") -> tuple[PayloadEvent, ...]:
        """The payload attached at the first toggle time, dropped at the second, ...

        Parameters
        ----------
        name : str
            The payload's name.

        Returns
        -------
        tuple of PayloadEvent
            Empty when the payload has no mass.
        """
        if self.payload_mass <= 0:
            return ()
        return tuple(PayloadEvent(t=t, action="drop", name=name) if k % 2 else
                     PayloadEvent(t=t, action="attach", name=name, mass=self.payload_mass,
                                  position=self.payload_position)
                     for k, t in enumerate(self.toggle_times))


def _toggle_times(rng: np.random.RandomState, t_final: float = FLIGHT_TIME,
                  gap: float = MIN_TOGGLE_INTERVAL) -> tuple[float, ...]:
    """One trial's toggle times, drawn as ``create_disturbance_toggle_times`` draws them."""
    times: list[float] = []
    for _ in range(rng.randint(1, 5)):
        for _ in range(100):
            candidate = rng.uniform(gap, t_final - gap)
            if not times or min(abs(candidate - t) for t in times) >= gap:
                times.append(candidate)
                break
        else:
            break
    return tuple(float(t) for t in sorted(times))


def payload_trials(n: int, seed: int = 42, intensity: float | None = None,
                   quad_params: dict[str, Any] | None = None) -> list[PayloadTrial]:
    """The trials AdaptiveQuadBench's payload experiment flies.

    Parameters
    ----------
    n : int
        Number of trials (``--num_trials``), >= 1.
    seed : int
        ``--seed`` (42 by default, as AdaptiveQuadBench's).
    intensity : float, optional
        None: the payload experiment (mass ratio U(0, 0.5)). A number k >= 0: the
        ``--when2fail`` step at intensity k (mass ratio exactly min(k, 2); the draws of the
        steps 0, 1, ... before it are made first, as ``RandomizationConfig`` makes them), in
        whole steps of 1. AdaptiveQuadBench's own when2fail runner draws steps >= 1 from
        numpy's global state as the previous step's flights left it (its serial runner
        reseeds it per flight), so its trials there differ from these.
    quad_params : dict, optional
        The vehicle whose mass and arm scale the payload (default ``AQB_QUAD_PARAMS``).

    Returns
    -------
    list of PayloadTrial
        Trials 0 .. n-1.

    Raises
    ------
    quadcog.InputError
        n < 1, a seed that is not an integer in [0, 2^32 - 1] (numpy's RandomState), an
        intensity that is not a whole number >= 0, or quad_params without a positive
        ``mass`` and ``arm_length``.
    quadcog.errors.SizeError
        More than ``MAX_DRAWS`` draws (n times the when2fail steps), before any.
    """
    n = validate.integer(n, "n", lo=1)
    seed = validate.integer(seed, "seed", lo=0, hi=2**32 - 1)
    params = AQB_QUAD_PARAMS if quad_params is None else quad_params
    if not isinstance(params, Mapping):
        validate.fail("quad_params", "a RotorPy quad_params dictionary", params)
    scale = {key: validate.positive(params.get(key), f"quad_params[{key!r}]", "m" if
                                    key == "arm_length" else "kg")
             for key in ("mass", "arm_length")}
    if intensity is not None:
        intensity = validate.real(intensity, "intensity", lo=0.0)
        if intensity != int(intensity):
            validate.fail("intensity", "a whole number of when2fail steps (step 1)", intensity)
    draws = n * (1 if intensity is None else int(intensity) + 1)
    if draws > MAX_DRAWS:
        per = "" if intensity is None else f" x {int(intensity) + 1} when2fail steps"
        raise SizeError(f"n = {n} trials{per} take {draws:,} draws of a trial; expected at "
                        f"most {MAX_DRAWS:,} (n or intensity too large)")
    rng = np.random.RandomState(seed)
    goals = [tuple(tuple(float(v) for v in rng.uniform(*GOAL_RANGE, size=3)) for _ in range(3))
             for _ in range(n)]
    steps = [None] if intensity is None else [float(k) for k in range(int(intensity) + 1)]
    for step in steps:
        ratio = MASS_RATIO_RANGE if step is None else (min(2.0, step),) * 2
        payloads = [(float(rng.uniform(*ratio) * scale["mass"]),
                     tuple(float(v) for v in rng.uniform(*OFFSET_RATIO_RANGE, size=3)
                           * scale["arm_length"])) for _ in range(n)]
        toggles = [_toggle_times(rng) for _ in range(n)]
    return [PayloadTrial(index=i, goal_position=goals[i][0], goal_velocity=goals[i][1],
                         goal_acceleration=goals[i][2], payload_mass=payloads[i][0],
                         payload_position=payloads[i][1], toggle_times=toggles[i])
            for i in range(n)]


def aqb_vehicle() -> Vehicle:
    """AdaptiveQuadBench's vehicle as a quadcog Vehicle (``vehicle_from_quad_params``).

    Returns
    -------
    Vehicle
        The 0.826 kg X quadrotor of ``AQB_QUAD_PARAMS``.
    """
    return vehicle_from_quad_params(AQB_QUAD_PARAMS, name="aqb")


def rmse(position: npt.ArrayLike, reference: npt.ArrayLike) -> float:
    """AdaptiveQuadBench's cost: sqrt(mean over samples of |p - p_ref|^2).

    Parameters
    ----------
    position : (N, 3) array_like
        Positions flown (m).
    reference : (N, 3) array_like
        Reference positions at the same samples (m).

    Returns
    -------
    float
        The RMSE (m).
    """
    e = np.asarray(position, float) - np.asarray(reference, float)
    return float(np.sqrt(np.mean(np.sum(e**2, axis=1))))


def fly(trial: PayloadTrial, law: str = "composite", dt: float = 0.01,
        sensing: Sensing | None = None, truth: TruthOptions | None = None,
        vehicle: Vehicle | None = None, **settings: Any) -> tuple[float, SimulationResult]:
    """Fly one trial in quadcog's simulator: the law designed for the bare vehicle, the truth
    carrying the payload as a rigid body from toggle to toggle.

    Parameters
    ----------
    trial : PayloadTrial
        The trial.
    law : str
        A registry name of the law.
    dt : float
        Step of the simulation and the control (s): 0.01 is AdaptiveQuadBench's 100 Hz.
    sensing : Sensing, optional
        Real sensing (noise, delay); default the true state.
    truth : TruthOptions, optional
        Default: rotor saturation on (RotorPy clips rotor speeds too), motor lag on (its
        5 ms motor time constant).
    vehicle : Vehicle, optional
        Default ``aqb_vehicle()``.
    **settings
        The law's settings.

    Returns
    -------
    rmse : float
        AdaptiveQuadBench's cost over the flight (inf when it diverged before the end).
    result : SimulationResult
        The flight.
    """
    vehicle = aqb_vehicle() if vehicle is None else vehicle
    truth = TruthOptions(rotor_saturation=True, motor_lag=True) if truth is None else truth
    controller = make_controller(law, vehicle=vehicle, **settings)
    res = simulate(controller, trial.trajectory(), duration=FLIGHT_TIME, dt=dt, vehicle=vehicle,
                   controller_model=vehicle, truth=truth, sensing=sensing, x0=np.zeros(12),
                   payloads=list(trial.payload_events()), check_dt=False)
    cost = np.inf if res.metrics.diverged else rmse(res.x[:, 0:3], res.ref[:, 0:3])
    return cost, res

