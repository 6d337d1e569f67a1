"""The design rules: every default setting of every controller, as a function of the Vehicle.

A controller built for a Vehicle without a setting gets the value these rules give for that
vehicle (``design(vehicle)``); a setting given explicitly is kept, and ``for_vehicle`` re-derives
only the settings that were not given.

The rules are the paper's design on the Hummingbird (``REFERENCE``: poles -10/-12 rad/s for
the attitude, gamma = 0.01, ...) carried to another vehicle by the physical scales that set what
each setting has to be, as dynamic similarity does. Every rule is the reference value times a
ratio of this vehicle's scale to the Hummingbird's (or a bound by one of the vehicle's limits),
so the Hummingbird gets the paper's numbers exactly (ratio 1) and the paper's reproduction does
not move, and a vehicle two orders of magnitude lighter or heavier gets a law tuned for it. The
scales:

- the rotor bandwidth ``1 / motor_time_constant`` (rad/s): no loop may be faster than the
  motors that act for it;
- the pendulum rate ``sqrt(m g l / I)`` (rad/s, l the arm length, I the smaller of Ixx, Iyy):
  the angular acceleration of the weight acting at the arm, i.e. of a CoG offset of one arm
  length. A CoG offset that is a given fraction of the arm tilts a vehicle by
  ``(m g l / I) / omega_att^2`` of that fraction: the attitude poles scale with the pendulum
  rate so that this tilt, and the position excursion it causes, is the same on every vehicle;
- the thrust-to-weight ratio ``4 max_rotor_thrust / (m g)``: the tilt at which full thrust
  still holds the weight bounds the commanded tilt;
- m g and the arm length: the adaptation gains are normalised by them so that their
  dimensionless values (what the reference fixes) mean the same on every vehicle.
"""
from dataclasses import dataclass
import functools
import math

from quadcog import validate
from quadcog.model.parameters import LARGEST
from quadcog.vehicles.vehicle import HUMMINGBIRD, N_ROTORS, Vehicle

__all__ = ["REFERENCE", "REFERENCE_VEHICLE", "DERIVED_SETTINGS", "Design", "design",
           "rotor_bandwidth", "thrust_to_weight", "pendulum_rate", "attitude_rate",
           "similarity", "tilt_limit_of", "adaptation_gain", "filter_rate_of",
           "admissible_estimate_radius", "mass_bounds_of", "PROJECTION_ARM_FRACTION",
           "ROTOR_FRACTION", "FILTER_ROTOR_FRACTION", "TILT_FRACTION", "MASS_LOWER_FRACTION",
           "setting"]

REFERENCE_VEHICLE = HUMMINGBIRD

# The settings whose default comes from the vehicle (the docs' reference says so).
DERIVED_SETTINGS = ("poles_attitude", "poles_z", "poles_psi", "poles_position", "poles_x",
                    "poles_y", "max_tilt", "gamma", "filter_rate", "ls_gain", "forgetting",
                    "covariance_bound", "warm_up", "projection_radius", "mass_bounds",
                    "integral_pole", "integral_limit")

ROTOR_FRACTION = 0.25          # the attitude loop at most a quarter of the rotor bandwidth
FILTER_ROTOR_FRACTION = 0.25   # the composite law's filter at most a quarter of it too
TILT_FRACTION = 0.75           # of the tilt at which full thrust just holds the weight
PROJECTION_ARM_FRACTION = 1.0  # r_hat within the circle through the rotors
MASS_LOWER_FRACTION = 0.5      # the lightest mass estimate, of the model's mass
_MIN_TILT = 0.1                # rad: the floor of max_tilt for a vehicle that can barely hover


def setting(value: object, where: str, unit: str | None = None, zero: bool = False) -> float:
    """A controller's rate, gain or bound given by the caller: a finite number > 0 (>= 0 with
    ``zero``) and at most ``LARGEST`` (1e6, the parameters' scale), as ``float``.

    Beyond that scale the law's products (a filter rate times a covariance, a gain times a
    weight) leave the float range, and the first call of the law would blame the state.

    Parameters
    ----------
    value : object
        What the caller passed.
    where : str
        The keyword's name, for the message.
    unit : str, optional
        Its unit, named in the message.
    zero : bool, optional
        Accept 0 (a weight or a gain that turns a term off).

    Returns
    -------
    float
        ``value`` as a Python float.

    Raises
    ------
    InputError
        ``value`` is not a finite real number in (0, 1e6] (or [0, 1e6] with ``zero``).
    """
    x = (validate.nonnegative if zero else validate.positive)(value, where, unit)
    return validate.real(x, where, lo=0.0, lo_open=not zero, hi=LARGEST, unit=unit)


def rotor_bandwidth(vehicle: Vehicle) -> float:
    """The rotors' bandwidth.

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle.

    Returns
    -------
    float
        1 / motor_time_constant (rad/s); inf for instant motors (time constant 0).
    """
    tau = vehicle.motor_time_constant
    return math.inf if tau <= 0 else 1.0 / tau


def thrust_to_weight(vehicle: Vehicle) -> float:
    """The thrust-to-weight ratio.

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle.

    Returns
    -------
    float
        4 max_rotor_thrust / (m g) (dimensionless).
    """
    return N_ROTORS * vehicle.max_rotor_thrust / (vehicle.m * vehicle.g)


def pendulum_rate(vehicle: Vehicle) -> float:
    """The rate of the weight acting at the arm: sqrt(m g l / I).

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle.

    Returns
    -------
    float
        sqrt(m g l / min(Ixx, Iyy)) (rad/s), l the arm length: the square root of the angular
        acceleration per radian-equivalent of a CoG offset of one arm length.
    """
    return math.sqrt(vehicle.m * vehicle.g * vehicle.arm_length / min(vehicle.Ixx, vehicle.Iyy))


def attitude_rate(vehicle: Vehicle) -> float:
    """The slower attitude pole's magnitude.

    The reference's 10 rad/s scaled by the pendulum rate (a CoG offset of a given fraction of
    the arm then tilts every vehicle alike), but never above ``ROTOR_FRACTION`` of the rotor
    bandwidth: the feedback linearization does not model the motor lag, and a loop that comes
    near the motors' bandwidth loses its phase margin to it (and to the sensing delay).

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle.

    Returns
    -------
    float
        omega_att (rad/s), > 0.
    """
    ref = -REFERENCE.poles_attitude[0]
    scaled = ref * (pendulum_rate(vehicle) / pendulum_rate(REFERENCE_VEHICLE))
    return min(scaled, ROTOR_FRACTION * rotor_bandwidth(vehicle))


def similarity(vehicle: Vehicle) -> float:
    """The ratio of this vehicle's attitude rate to the reference's: every loop's scale.

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle.

    Returns
    -------
    float
        attitude_rate(vehicle) / attitude_rate(REFERENCE_VEHICLE); 1 for the Hummingbird.
    """
    return attitude_rate(vehicle) / attitude_rate(REFERENCE_VEHICLE)


def _scaled(poles: tuple[float, ...], s: float) -> tuple[float, ...]:
    return tuple(p * s for p in poles)


def tilt_limit_of(vehicle: Vehicle) -> float:
    """The clip on commanded roll and pitch.

    The reference's 0.6 rad (the range where the outer loop's small-angle design holds), but
    at most ``TILT_FRACTION`` of arccos(1 / thrust-to-weight), the tilt at which the rotors at
    full thrust just hold the weight: beyond it the vehicle sinks whatever the thrust, and the
    rest of the margin is left to the attitude loop.

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle.

    Returns
    -------
    float
        max_tilt (rad), in [0.1, 0.6].
    """
    hold = math.acos(min(1.0, 1.0 / thrust_to_weight(vehicle)))
    return max(_MIN_TILT, min(REFERENCE.max_tilt, TILT_FRACTION * hold))


def adaptation_gain(vehicle: Vehicle) -> float:
    """The adaptation gain gamma of the paper's law (and of the composite law's tracking term).

    At hover the paper's law learns a constant CoG offset at the rate
    ``lambda = gamma (m g / (I kp))^2 / 2`` (linearized: the offset's moment m g r over I
    gives an attitude error m g r / (I kp), which the update gamma Phi^T B^T P e_s, with
    Phi ~ m g, B ~ 1 / I and P e ~ e / (2 kp), turns back into r_hat_dot; kp the product of
    the derived attitude poles). The rule keeps that rate at the reference's (about 0.3 1/s):
    gamma is the reference gain times (I kp / (m g))^2 over the reference's, so the
    dimensionless gain gamma (m g / (I kp))^2 is the same on every vehicle. The rate is not
    scaled up with the loops: the paper's gradient law holds only for adaptation much slower
    than every loop (docs/tour/simulate.md, "Choosing gamma"); fast learning is the composite law's
    least-squares term.

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle.

    Returns
    -------
    float
        gamma (in the units that make gamma Phi^T B^T P e_s a rate of r_hat, m/s), > 0.
    """
    def scale(v: Vehicle) -> float:
        slow, fast = _scaled(REFERENCE.poles_attitude, similarity(v))
        return (min(v.Ixx, v.Iyy) * slow * fast / (v.m * v.g)) ** 2
    return REFERENCE.gamma * (scale(vehicle) / scale(REFERENCE_VEHICLE))


def filter_rate_of(vehicle: Vehicle) -> float:
    """The composite law's filter rate lam.

    ``FILTER_ROTOR_FRACTION`` of the rotor bandwidth (the filter passes the input the rotors
    deliver, which the controller only knows through its model of their lag), and at most
    twice the attitude rate (for instant motors: the filter need not be faster than the loop
    whose data it filters). 20 1/s for the Hummingbird.

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle.

    Returns
    -------
    float
        lam (1/s), > 0.
    """
    return min(FILTER_ROTOR_FRACTION * rotor_bandwidth(vehicle), 2.0 * attitude_rate(vehicle))


def admissible_estimate_radius(vehicle: Vehicle, margin: float = 0.95) -> float:
    """The radius of the ball of CoG estimates: a fraction of the arm, and admissible.

    Any r_hat in this ball keeps the model's inertia about the estimated CoG positive definite
    (m |r|^2 < min I suffices) and the CoG within ``PROJECTION_ARM_FRACTION`` of the arm
    length (a CoG outside the circle through the rotors cannot be held at hover).

    Parameters
    ----------
    vehicle : Vehicle
        The controller's model of the vehicle.
    margin : float
        Fraction of sqrt(min(Ixx, Iyy, Izz) / m) allowed, default 0.95.

    Returns
    -------
    float
        min(PROJECTION_ARM_FRACTION * arm length, margin * sqrt(min(Ixx, Iyy, Izz) / m)) (m).
    """
    smallest = min(vehicle.Ixx, vehicle.Iyy, vehicle.Izz)
    return float(min(PROJECTION_ARM_FRACTION * vehicle.arm_length,
                     margin * math.sqrt(smallest / vehicle.m)))


def mass_bounds_of(vehicle: Vehicle) -> tuple[float, float]:
    """The bounds of a mass estimate, relative to the model's mass.

    The upper bound is what the rotors can lift: ``4 max_rotor_thrust / g`` over the model's
    mass, i.e. the thrust-to-weight ratio. A body heavier than that cannot be held at full
    thrust, so no vehicle that flies has a mass beyond it, and an estimate beyond it would
    only command more thrust than the rotors have. The lower bound is
    ``MASS_LOWER_FRACTION`` (a payload law learns what is added, and half the airframe is
    never lost in flight).

    Parameters
    ----------
    vehicle : Vehicle
        The controller's model of the vehicle.

    Returns
    -------
    tuple of float
        (m_lo, m_hi) / m: (0.5, thrust_to_weight(vehicle)); m_hi <= 1 for rotors that cannot
        lift the vehicle, which the mass-learning laws refuse (naming max_rotor_thrust).
    """
    return (MASS_LOWER_FRACTION, float(thrust_to_weight(vehicle)))


@dataclass(frozen=True)
class Design:
    """Every default setting of every controller for one vehicle (``design(vehicle)``).

    Parameters
    ----------
    poles_attitude : tuple of float
        Feedback linearization's poles (rad/s): the reference's times ``similarity``.
    poles_z : tuple of float
        Feedback linearization's poles (rad/s): the reference's times ``similarity``.
    poles_psi : tuple of float
        Feedback linearization's poles (rad/s): the reference's times ``similarity``.
    poles_position : tuple of float
        Feedback linearization's poles (rad/s): the reference's times ``similarity``.
    poles_x : tuple of float
        Cascade PD's x-theta and y-phi chains (rad/s), likewise.
    poles_y : tuple of float
        Cascade PD's x-theta and y-phi chains (rad/s), likewise.
    max_tilt : float
        ``tilt_limit_of`` (rad).
    gamma : float
        ``adaptation_gain``.
    filter_rate : float
        ``filter_rate_of`` (1/s).
    ls_gain : float
        10 filter_rate (1/s): the least-squares term settles the normalized prediction error
        ten times faster than the filter passes it, so it is the filter that sets how fast the
        composite law learns.
    forgetting : float
        filter_rate / 2.5 (1/s): data older than a few filter time constants are forgotten,
        so a CoG that keeps moving is followed.
    covariance_bound : float
        1 (dimensionless: the estimator's rows are normalized by m g and the arm).
    warm_up : float
        5 / filter_rate (s): until the filters' start-up term exp(-lam t) has died out.
    projection_radius : float
        ``admissible_estimate_radius`` (m).
    mass_bounds : tuple of float
        ``mass_bounds_of``: [m_lo, m_hi] relative to the model's mass, m_hi what the rotors
        lift.
    integral_pole : float
        The reference's -4 1/s times ``similarity``.
    integral_limit : float
        The reference's 1 rad s over ``similarity``: the integrator's authority ki * limit
        then scales as the angular accelerations (similarity squared).
    """
    poles_attitude: tuple[float, ...]
    poles_z: tuple[float, ...]
    poles_psi: tuple[float, ...]
    poles_position: tuple[float, ...]
    poles_x: tuple[float, ...]
    poles_y: tuple[float, ...]
    max_tilt: float
    gamma: float
    filter_rate: float
    ls_gain: float
    forgetting: float
    covariance_bound: float
    warm_up: float
    projection_radius: float
    mass_bounds: tuple[float, float]
    integral_pole: float
    integral_limit: float


@functools.lru_cache(maxsize=256)    # a Design is frozen; a new controller of a known vehicle
def design(vehicle: Vehicle) -> Design:
    """Every default setting for a vehicle (see the module docstring for the rules).

    Parameters
    ----------
    vehicle : Vehicle
        The controller's model of the vehicle.

    Returns
    -------
    Design
        The defaults; for the Hummingbird exactly the paper's values (``REFERENCE``).
    """
    s = similarity(vehicle)
    lam = filter_rate_of(vehicle)
    poles = {k: _scaled(getattr(REFERENCE, k), s) for k in ("poles_attitude", "poles_z", "poles_psi",
                                                  "poles_position", "poles_x", "poles_y")}
    return Design(**poles, max_tilt=tilt_limit_of(vehicle),
                  gamma=adaptation_gain(vehicle), filter_rate=lam,
                  ls_gain=10.0 * lam, forgetting=lam / 2.5,
                  covariance_bound=REFERENCE.covariance_bound, warm_up=5.0 / lam,
                  projection_radius=admissible_estimate_radius(vehicle),
                  mass_bounds=mass_bounds_of(vehicle),
                  integral_pole=REFERENCE.integral_pole * s,
                  integral_limit=REFERENCE.integral_limit / s)


# The paper's design on REFERENCE_VEHICLE (Palunko and Fierro's gains as quadcog has always
# shipped them, rad/s, rad and dimensionless): the values every rule scales from, and what
# design(HUMMINGBIRD) gives.
REFERENCE = Design(
    poles_attitude=(-10.0, -12.0), poles_z=(-3.0, -4.0), poles_psi=(-4.0, -5.0),
    poles_position=(-1.5, -2.0), poles_x=(-2.0, -2.5, -10.0, -12.0),
    poles_y=(-2.0, -2.5, -10.0, -12.0), max_tilt=0.6, gamma=0.01, filter_rate=20.0,
    ls_gain=200.0, forgetting=8.0, covariance_bound=1.0, warm_up=0.25,
    projection_radius=admissible_estimate_radius(REFERENCE_VEHICLE),
    mass_bounds=mass_bounds_of(REFERENCE_VEHICLE), integral_pole=-4.0,
    integral_limit=1.0)
