"""Realistic sensing: the controller sees a noisy state estimate, biased gyroscopes, and its
input one control period late.

``Sensed(controller, sensing, dt)`` is a Controller that wraps another one. It adds to the
state the controller sees seeded Gaussian noise on position, velocity, attitude and body rates
and a constant gyroscope bias on the rates, and (``delay``) holds the computed input for one
period: the input applied during step k is the one computed from the measurement of step k-1.
Everything is part of the CasADi law, so the compiled closed loop and the Python loop carry it
unchanged. It is a simulation of the sensors, not flight code: the C export takes the wrapped
controller itself (the noise depends on the time t, which the exported step does not take).

The noise is a counter-based pseudo-random sequence of the time t and the seed (a sine hash
per channel turned Gaussian by Box-Muller), so a run is reproducible without a random state
and the same in every execution path.

Default accuracies (``Sensing()``), one standard deviation per axis:

- position 1 mm: motion capture, e.g. Merriaux et al., "A Study of Vicon System Positioning
  Performance", Sensors 17(7), 1591 (2017), report sub-millimetre static and about 2 mm
  dynamic errors;
- velocity 1 cm/s (body axes): the derivative of that position at 100 Hz, smoothed;
- attitude 0.2 deg: an attitude estimator fusing the IMU with motion capture;
- body rates 0.005 deg/s/sqrt(Hz) x sqrt(1/(2 dt)): the rate-noise spectral density of the
  InvenSense MPU-6000 gyroscope (product specification PS-MPU-6000A-00 rev. 3.4, table 6.1),
  about 0.11 deg/s at 1 kHz;
- gyroscope bias 0.1 deg/s per axis, drawn once per seed: the residual after the estimator's
  bias calibration (this project's assumption; the MPU-6000's uncalibrated zero-rate offset is
  +-20 deg/s).

The accelerometer (``accel_density``, ``accel_bias``): 400 ug/sqrt(Hz), the MPU-6000's
(table 6.2 of the same specification), about 0.044 m/s^2 per sample at 250 Hz, and a constant
bias of 0.02 m/s^2 (2 mg) per axis drawn once per seed, the residual after calibration (this
project's assumption; uncalibrated, +-50 mg). No law here needs an accelerometer (the
composite law's filtered identity replaces the acceleration by the derivative of the filtered
momentum): these two are the IMU that a flight stack's own estimator reads
(``quadcog.px4.sensors``: PX4's EKF2).

Per sample, a white noise of density ``d`` sampled every ``dt`` (one-sided density, the
bandwidth up to Nyquist, ``1 / (2 dt)``) has the standard deviation ``d sqrt(1 / (2 dt))``
(``per_sample``).
"""
from dataclasses import dataclass

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.controllers.base import Controller
from quadcog.errors import InputError
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["DEG", "GYRO_NOISE_DENSITY", "ACCEL_NOISE_DENSITY", "ACCEL_BIAS", "per_sample",
           "SENSING_LIMITS", "Sensing", "gaussian", "Sensed"]

DEG = np.pi / 180.0
GYRO_NOISE_DENSITY = 0.005 * DEG          # rad/s/sqrt(Hz), MPU-6000
ACCEL_NOISE_DENSITY = 400e-6 * 9.80665    # m/s^2/sqrt(Hz), MPU-6000 (400 ug/sqrt(Hz))
ACCEL_BIAS = 0.02                          # m/s^2 per axis, residual after calibration
MAX_SEED = 2**32 - 1                       # seeds: 0 .. 2^32 - 1
# the largest accuracy each field takes, and its unit: beyond these a "measurement" says
# nothing about the state (a position noise past 100 m, an angle's past half a turn, a gyro
# 1000 times a consumer MEMS part's, an accelerometer bias past 1 g)
SENSING_LIMITS = {"position": (100.0, "m"), "velocity": (10.0, "m/s"),
                  "attitude": (float(np.pi), "rad"), "gyro_density": (1.0, "rad/s/sqrt(Hz)"),
                  "gyro_bias": (1.0, "rad/s"), "accel_density": (1.0, "m/s^2/sqrt(Hz)"),
                  "accel_bias": (9.81, "m/s^2")}


def per_sample(density: float, dt: float) -> float:
    """The per-sample standard deviation of white noise of one-sided density ``density``
    sampled every ``dt``: ``density sqrt(1 / (2 dt))``.

    Parameters
    ----------
    density : float
        Noise density (unit/sqrt(Hz)).
    dt : float
        Sample period (s), > 0.

    Returns
    -------
    float
        One standard deviation per sample (unit).
    """
    return float(density) * float(np.sqrt(1.0 / (2.0 * dt)))


@dataclass(frozen=True)
class Sensing:
    """What the controller's measurements suffer (SI units; see the module docstring).

    Parameters
    ----------
    noise : bool
        Add the Gaussian noise below to the state the controller sees.
    delay : bool
        Apply each computed input one control period later.
    seed : int
        Seed of the noise and of the gyroscope bias.
    position : float
        Standard deviation of the measured position (m), >= 0.
    velocity : float
        Standard deviation of the measured body velocities (m/s, body axes), >= 0.
    attitude : float
        Standard deviation of the measured Euler angles (rad), >= 0.
    gyro_density : float
        Rate-noise spectral density (rad/s/sqrt(Hz)); the per-sample standard deviation is
        gyro_density * sqrt(1 / (2 dt)).
    gyro_bias : float
        Standard deviation of the constant gyroscope bias per axis (rad/s).
    accel_density : float
        Accelerometer noise density (m/s^2/sqrt(Hz)); only a flight stack's IMU reads it
        (``quadcog.px4``).
    accel_bias : float
        Standard deviation of the constant accelerometer bias per axis (m/s^2); the same.

    Raises
    ------
    quadcog.InputError
        A field of the wrong kind, or an accuracy below 0 or beyond ``SENSING_LIMITS``.
    """
    noise: bool = True
    delay: bool = True
    seed: int = 1
    position: float = 0.001
    velocity: float = 0.01
    attitude: float = 0.2 * DEG
    gyro_density: float = GYRO_NOISE_DENSITY
    gyro_bias: float = 0.1 * DEG
    accel_density: float = ACCEL_NOISE_DENSITY
    accel_bias: float = ACCEL_BIAS

    def __post_init__(self) -> None:
        for name in ("noise", "delay"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise InputError(f"Sensing.{name} must be True or False, got "
                                 f"{getattr(self, name)!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)):
            raise InputError(f"Sensing.seed must be an integer, got {self.seed!r}")
        if not 0 <= self.seed <= MAX_SEED:      # numpy's seeding refuses < 0; the noise
            raise InputError(f"Sensing.seed must be a whole number 0..{MAX_SEED}, got "
                             f"{self.seed!r}")  # hash needs 0.618 seed well inside floats
        for name, (hi, unit) in SENSING_LIMITS.items():
            validate.real(getattr(self, name), f"Sensing.{name}", lo=0.0, hi=hi, unit=unit)

    def sigmas(self, dt: float) -> npt.NDArray[np.float64]:
        """Per-sample standard deviations of the 12 state entries.

        Parameters
        ----------
        dt : float
            The sample (control) period (s).

        Returns
        -------
        (12,) numpy.ndarray
            In the state's order [m, rad, m/s, rad/s].
        """
        gyro = per_sample(self.gyro_density, dt)
        return np.repeat([self.position, self.attitude, self.velocity, gyro], 3)

    def imu_sigmas(self, dt: float) -> tuple[float, float]:
        """Per-sample standard deviations of an IMU sampled every ``dt`` (``per_sample``).

        Parameters
        ----------
        dt : float
            The IMU's sample period (s).

        Returns
        -------
        accel : float
            Accelerometer, per axis (m/s^2).
        gyro : float
            Gyroscope, per axis (rad/s): the body-rate entry of ``sigmas``.
        """
        return per_sample(self.accel_density, dt), per_sample(self.gyro_density, dt)

    def bias(self) -> npt.NDArray[np.float64]:
        """The constant gyroscope bias of this seed.

        Returns
        -------
        (3,) numpy.ndarray
            The bias of the body rates (rad/s).
        """
        return np.random.default_rng(self.seed).normal(scale=self.gyro_bias, size=3)

    def accel_offset(self) -> npt.NDArray[np.float64]:
        """The constant accelerometer bias of this seed (independent of ``bias``).

        Returns
        -------
        (3,) numpy.ndarray
            The bias of the specific force, body axes (m/s^2).
        """
        return np.random.default_rng((self.seed, 1)).normal(scale=self.accel_bias, size=3)


def _uniform(t: ca.SX, channel: int, seed: int) -> ca.SX:
    """A pseudo-random number in (0, 1) from t (SX): fract(sin(a t + b) * 43758.5453)."""
    a = 12989.8 + 78.233 * channel + 0.618 * seed
    b = 1.7 * channel + 3.1 * seed
    v = ca.sin(a * t + b) * 43758.5453
    return ca.fmin(ca.fmax(v - ca.floor(v), 1e-12), 1 - 1e-12)


def gaussian(t: ca.SX, channel: int, seed: int) -> ca.SX:
    """A standard normal sample per (t, channel, seed), by Box-Muller.

    Parameters
    ----------
    t : casadi.SX
        The time (s).
    channel : int
        Which noise channel (one per state entry).
    seed : int
        The seed.

    Returns
    -------
    casadi.SX
        The sample.
    """
    u1, u2 = _uniform(t, 2 * channel, seed), _uniform(t, 2 * channel + 1, seed)
    return ca.sqrt(-2 * ca.log(u1)) * ca.cos(2 * np.pi * u2)


class Sensed(Controller):
    """``controller`` flown with ``sensing`` at control period ``dt``.

    The state is the inner controller's state followed, with ``delay``, by the input computed
    in the previous period (4). ``estimates_cog`` and the projection pass through.

    Parameters
    ----------
    controller : Controller
        The controller that sees the measurements.
    sensing : Sensing
        What the measurements suffer.
    dt : float
        The control period (s), > 0.

    Raises
    ------
    quadcog.InputError
        An argument of the wrong kind, or dt not a positive number.
    """

    def __init__(self, controller: Controller, sensing: Sensing, dt: float) -> None:
        if not isinstance(controller, Controller):
            raise InputError(f"controller must be a quadcog Controller, got {controller!r}")
        if not isinstance(sensing, Sensing):
            raise InputError(f"sensing must be a quadcog Sensing, got {sensing!r}")
        dt = float(dt)
        if not (np.isfinite(dt) and dt > 0):
            raise InputError(f"dt must be a positive number of seconds, got {dt!r}")
        super().__init__(controller.vehicle, controller.model)
        self.inner, self.sensing, self.dt = controller, sensing, dt
        self.name = f"{controller.name}_sensed"
        self.estimates_cog = getattr(controller, "estimates_cog", False)
        self.n_inner = controller.n_state
        self.n_state = self.n_inner + (4 if sensing.delay else 0)
        self._sigma = sensing.sigmas(dt)
        self._bias = np.r_[np.zeros(9), sensing.bias()]

    def for_vehicle(self, vehicle: Vehicle) -> "Sensed":
        """This sensed controller with its inner controller designed for ``vehicle``.

        Parameters
        ----------
        vehicle : Vehicle
            The controller's model.

        Returns
        -------
        Sensed
            ``self`` when that is already its model.
        """
        if vehicle == self.vehicle:
            return self
        return Sensed(self.inner.for_vehicle(vehicle), self.sensing, self.dt)

    def initial_state(self) -> npt.NDArray[np.float64]:
        """The state at t = 0: the inner controller's, then (``delay``) the hover input.

        Returns
        -------
        (n_state,) numpy.ndarray
            The controller state.
        """
        c = self.inner.initial_state()
        if self.sensing.delay:
            c = np.r_[c, self.vehicle.hover_input()]
        return c

    def measured(self, t: ca.SX, x: ca.SX) -> ca.SX:
        """The state the controller sees.

        Parameters
        ----------
        t : casadi.SX
            The time (s).
        x : (12,) casadi.SX
            The true state [m, rad, m/s, rad/s].

        Returns
        -------
        (12,) casadi.SX
            x with the noise and the gyroscope bias (x itself without ``noise``).
        """
        if not self.sensing.noise:
            return x
        noise = ca.vertcat(*[gaussian(t, i, self.sensing.seed) for i in range(12)])
        return x + ca.DM(self._sigma) * noise + ca.DM(self._bias)

    def expression(self, t: ca.SX, x: ca.SX, ref: ca.SX, c: ca.SX) -> tuple[ca.SX, ca.SX]:
        """The law: the inner law on the measured state, its input held one period.

        Parameters
        ----------
        t : casadi.SX
            The time (s).
        x : (12,) casadi.SX
            The true state [m, rad, m/s, rad/s].
        ref : (14,) casadi.SX
            The reference row.
        c : (n_state,) casadi.SX
            The controller state.

        Returns
        -------
        U : (4,) casadi.SX
            The input [N, N m, N m, N m].
        c_dot : (n_state,) casadi.SX
            The controller state's derivative.
        """
        inner_c = c[:self.n_inner]
        U, c_dot = self.inner.function()(t, self.measured(t, x), ref, inner_c)
        if not self.sensing.delay:
            return U, c_dot
        held = c[self.n_inner:]
        # the Euler update c + dt c_dot stores exactly the new input for the next period
        return held, ca.vertcat(c_dot, (U - held) / self.dt)

    def project(self, c: ca.SX) -> ca.SX:
        """The inner controller's projection of its part of the state.

        Parameters
        ----------
        c : (n_state,) casadi.SX
            The controller state after an update step.

        Returns
        -------
        (n_state,) casadi.SX
            The projected state.
        """
        return ca.vertcat(self.inner.project(c[:self.n_inner]), c[self.n_inner:])

    def project_numpy(self, c: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """``project`` for numpy arrays, in place.

        Parameters
        ----------
        c : (n_state,) numpy.ndarray
            The controller state after an update step.

        Returns
        -------
        (n_state,) numpy.ndarray
            ``c``, projected in place.
        """
        self.inner.project_numpy(c[:self.n_inner])
        return c
