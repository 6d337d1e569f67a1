"""Conversions between AdaptiveQuadBench (RotorPy) and quadcog: vehicle, state, reference, rotors.

Both use ground axes with z up and body axes x forward, z along the thrust, so no axis flips.
RotorPy's state dictionary holds the position ``x`` and velocity ``v`` in ground axes, the
attitude ``q`` as a unit quaternion [i, j, k, w] (scalar last, body to ground) and the body
rates ``w``; quadcog's state is ``[x, y, z, phi, theta, psi, u, v, w, p, q, r]`` with ZYX Euler
angles and body-axis velocities (``quadcog.model.conventions``). RotorPy commands rotor speeds
(rad/s) with thrust ``k_eta omega^2`` and reaction moment ``rotor_dir k_m omega^2`` about body z;
quadcog's Vehicle takes the thrust constant k_eta and the moment per thrust k_m / k_eta with the
same spin signs. Only the true state (x, v, q, w) is read, never ``ext_force``,
``ext_torque`` or ``payload_mass``.
"""
from collections.abc import Mapping
from typing import Any

import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.errors import InputError, ParameterError, PeerStateError
from quadcog.model.conventions import N_STATE
from quadcog.trajectories.analytic import ACC, JERK, POS, REF_SIZE, VEL, YAW, YAW_RATE
from quadcog.vehicles.vehicle import N_ROTORS, Vehicle

__all__ = ["ROTORPY_GRAVITY", "MAX_ROTOR_SPEED", "STATE_KEYS", "FLAT_KEYS", "vehicle_from_quad_params",
           "quaternion_to_matrix", "euler_zyx", "state_vector", "reference_row",
           "motor_speeds"]

# RotorPy's Multirotor.g: gravity is a constant of its simulator, not a vehicle parameter
ROTORPY_GRAVITY = 9.81
# what a quadcog law reads from the state dictionary: key -> length
STATE_KEYS = {"x": 3, "v": 3, "q": 4, "w": 3}
# the flat outputs a reference row needs (x_dddot and yaw_dot default to 0 when absent)
FLAT_KEYS = {"x": 3, "x_dot": 3, "x_ddot": 3, "yaw": 1}
_PARAM_KEYS = ("mass", "Ixx", "Iyy", "Izz", "num_rotors", "rotor_pos", "rotor_directions",
               "k_eta", "k_m", "k_d", "k_z", "tau_m", "rotor_speed_min", "rotor_speed_max")
# each number of quad_params the Vehicle is made of: its check (a real number, not a string,
# a bool or an array) and unit; a negative rotor speed would square into a positive thrust
_PARAM_CHECKS = (("mass", validate.positive, "kg"), ("Ixx", validate.positive, "kg m^2"),
                 ("Iyy", validate.positive, "kg m^2"), ("Izz", validate.positive, "kg m^2"),
                 ("k_eta", validate.positive, "N/(rad/s)^2"),
                 ("k_m", validate.positive, "N m/(rad/s)^2"),
                 ("k_d", validate.nonnegative, "N/(m/s)/(rad/s)"),
                 ("k_z", validate.nonnegative, "N/(m/s)/(rad/s)"),
                 ("tau_m", validate.nonnegative, "s"),
                 ("rotor_speed_min", validate.nonnegative, "rad/s"),
                 ("rotor_speed_max", validate.positive, "rad/s"))
# a rotor speed beyond this is no rotor's (the fastest small props turn ~6e3 rad/s); past
# ~1e154 rad/s its square overflowed (OverflowError from 1e300 ** 2)
MAX_ROTOR_SPEED = 1e6


def _param(params, key):
    if key not in params:
        raise InputError(f"quad_params[{key!r}] is missing: expected a RotorPy quad_params "
                         f"dictionary with {', '.join(_PARAM_KEYS)}")
    return params[key]


def vehicle_from_quad_params(params: Mapping[str, Any], name: str = "aqb") -> Vehicle:
    """A quadcog Vehicle of a RotorPy/AdaptiveQuadBench ``quad_params`` dictionary.

    The rotors: positions (x, y) of ``rotor_pos`` in its order, spin signs
    ``rotor_directions``, thrust constant ``k_eta``, moment per thrust ``k_m / k_eta``,
    thrust limits ``k_eta omega^2`` at ``rotor_speed_min`` and ``rotor_speed_max``, time
    constant ``tau_m``. The drag: RotorPy's rotor drag ``H = -omega k_d v`` (``k_z`` along z)
    on each rotor, linearized at the hover rotor speed ``omega_h = sqrt(m g / (N k_eta))``:
    ``c_x = c_y = N k_d omega_h``, ``c_z = N k_z omega_h``; its parasitic (quadratic) drag
    and rate drag are left out. The CoG: ``com`` (default 0), what the controller believes.

    Parameters
    ----------
    params : mapping
        RotorPy's quad_params (SI units).
    name : str
        The Vehicle's label.

    Returns
    -------
    Vehicle
        The vehicle (inertia about O from Ixx, Iyy, Izz; products of inertia must be 0).

    Raises
    ------
    quadcog.InputError
        A key missing, a rotor out of the rotor plane, products of inertia, or not 4 rotors.
    quadcog.ParameterError
        A value the Vehicle refuses (named by its field), a rotor speed beyond
        ``MAX_ROTOR_SPEED``, or rotors that cannot lift the mass at ``rotor_speed_max``.
    """
    if not isinstance(params, Mapping):
        validate.fail("quad_params", "a RotorPy quad_params dictionary", params)
    n = validate.integer(_param(params, "num_rotors"), "quad_params['num_rotors']")
    if n != N_ROTORS:
        validate.fail("quad_params['num_rotors']", f"{N_ROTORS} rotors", n)
    for key in ("Ixy", "Ixz", "Iyz"):
        if validate.real(params.get(key, 0.0), f"quad_params[{key!r}]", unit="kg m^2") != 0.0:
            validate.fail(f"quad_params[{key!r}]", "0 (quadcog's model has a diagonal inertia)",
                          params[key])
    rotor_pos = _param(params, "rotor_pos")
    if not isinstance(rotor_pos, Mapping):
        validate.fail("quad_params['rotor_pos']",
                      "a dictionary of each rotor's position (3,) (m)", rotor_pos)
    pos = np.array([validate.array(r, f"quad_params['rotor_pos'][{k!r}]", (3,))
                    for k, r in rotor_pos.items()])
    if pos.shape != (N_ROTORS, 3) or np.abs(pos[:, 2]).max() > 0.0:
        validate.fail("quad_params['rotor_pos']", f"{N_ROTORS} rotors in the plane z = 0 (m)",
                      pos.tolist())
    dirs = validate.array(_param(params, "rotor_directions"), "quad_params['rotor_directions']",
                          (N_ROTORS,))
    if not np.isin(dirs, (-1.0, 1.0)).all():
        validate.fail("quad_params['rotor_directions']", f"{N_ROTORS} spin signs, each 1 or -1",
                      dirs.tolist())
    number = {key: check(_param(params, key), f"quad_params[{key!r}]", unit)
              for key, check, unit in _PARAM_CHECKS}
    m, k_eta = number["mass"], number["k_eta"]
    for key in ("rotor_speed_min", "rotor_speed_max"):
        if not number[key] <= MAX_ROTOR_SPEED:
            validate.fail(f"quad_params[{key!r}]", f"a rotor speed <= {MAX_ROTOR_SPEED:g} rad/s",
                          number[key], ParameterError)
    # a vehicle whose rotors at full speed cannot lift it flies no scenario: the impossible
    # physics is named here, by its keys, not as a divergence later
    lift = N_ROTORS * k_eta * number["rotor_speed_max"] ** 2
    if not lift > m * ROTORPY_GRAVITY:
        raise ParameterError(
            f"quad_params: {N_ROTORS} rotors at rotor_speed_max = "
            f"{validate.plain(number['rotor_speed_max'])} rad/s with k_eta = "
            f"{validate.plain(k_eta)} N/(rad/s)^2 lift {lift:.3g} N, not more than the weight "
            f"{m * ROTORPY_GRAVITY:.3g} N of mass = {validate.plain(m)} kg; expected a vehicle "
            "that can hover")
    omega_h = np.sqrt(m * ROTORPY_GRAVITY / (N_ROTORS * k_eta))
    com = validate.array(params.get("com", np.zeros(3)), "quad_params['com']", (3,))
    return Vehicle(
        m=m, g=ROTORPY_GRAVITY, Ixx=number["Ixx"], Iyy=number["Iyy"], Izz=number["Izz"],
        c_x=N_ROTORS * number["k_d"] * omega_h, c_y=N_ROTORS * number["k_d"] * omega_h,
        c_z=N_ROTORS * number["k_z"] * omega_h, c_phi=0.0, c_theta=0.0, c_psi=0.0,
        rotor_positions=tuple((float(x), float(y)) for x, y, _ in pos),
        rotor_directions=tuple(int(d) for d in dirs),
        thrust_constant=k_eta, moment_constant=number["k_m"] / k_eta,
        max_rotor_thrust=k_eta * number["rotor_speed_max"] ** 2,
        min_rotor_thrust=k_eta * number["rotor_speed_min"] ** 2,
        motor_time_constant=number["tau_m"],
        x_G=float(com[0]), y_G=float(com[1]), z_G=float(com[2]), name=name)


def quaternion_to_matrix(q: npt.ArrayLike, where: str = "q") -> npt.NDArray[np.float64]:
    """The rotation matrix of a quaternion [i, j, k, w] (scalar last, RotorPy's order).

    Parameters
    ----------
    q : (4,) array_like
        The quaternion; normalized here (it need not be of norm 1, but not 0).
    where : str
        Its name in messages.

    Returns
    -------
    (3, 3) numpy.ndarray
        R, rotating body-axis components into ground axes.

    Raises
    ------
    quadcog.PeerStateError
        A quaternion of the wrong shape, not finite, or of norm 0.
    """
    try:
        q = validate.vector(q, where, 4)
    except InputError as e:
        raise PeerStateError(str(e)) from None
    n = float(np.linalg.norm(q))
    if not n > 1e-12:
        raise PeerStateError(f"{where} = {validate.plain(q.tolist())}: a quaternion of norm "
                             f"{n:.3g}; expected a unit quaternion [i, j, k, w]")
    x, y, z, w = q / n
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def euler_zyx(R: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """ZYX Euler angles of R = Rz(psi) Ry(theta) Rx(phi) (``conventions.rotation_matrix``).

    Parameters
    ----------
    R : (3, 3) numpy.ndarray
        A rotation matrix, body to ground.

    Returns
    -------
    (3,) numpy.ndarray
        [phi, theta, psi] (rad), theta in [-pi/2, pi/2].

    Raises
    ------
    quadcog.InputError
        ``R`` not a (3, 3) array of finite real numbers.
    """
    R = validate.array(R, "R", (3, 3), what="a (3, 3) rotation matrix")
    return np.array([np.arctan2(R[2, 1], R[2, 2]), -np.arcsin(np.clip(R[2, 0], -1.0, 1.0)),
                     np.arctan2(R[1, 0], R[0, 0])])


def _entry(mapping, key, n, what):
    """mapping[key] as a checked (n,) array; PeerStateError naming the key otherwise."""
    if key not in mapping:
        needs = STATE_KEYS if what == "state" else FLAT_KEYS
        raise PeerStateError(f"{what}[{key!r}] is missing: a quadcog law needs "
                             f"{', '.join(repr(k) for k in needs)}")
    try:
        return validate.vector(np.atleast_1d(mapping[key]), f"{what}[{key!r}]", n)
    except (InputError, TypeError, ValueError) as e:
        raise PeerStateError(str(e)) from None


def state_vector(state: Mapping[str, Any]) -> npt.NDArray[np.float64]:
    """quadcog's state (12,) from RotorPy's true state dictionary.

    Parameters
    ----------
    state : mapping
        With ``x`` (m), ``v`` (m/s, ground axes), ``q`` ([i, j, k, w]), ``w`` (rad/s, body
        axes); other keys (``ext_force``, ``ext_torque``, ``payload_mass``, ...) are ignored.

    Returns
    -------
    (12,) numpy.ndarray
        [x, y, z (m), phi, theta, psi (rad), u, v, w (m/s, body), p, q, r (rad/s)].

    Raises
    ------
    quadcog.PeerStateError
        Naming the key that is missing, of the wrong length, not finite, or a quaternion of
        norm 0.
    """
    if not isinstance(state, Mapping):
        raise PeerStateError(f"state must be a dictionary with keys {', '.join(STATE_KEYS)}, "
                             f"got {type(state).__name__}")
    p, v, w = (_entry(state, k, 3, "state") for k in ("x", "v", "w"))
    R = quaternion_to_matrix(_entry(state, "q", 4, "state"), "state['q']")
    x = np.empty(N_STATE)
    x[0:3], x[3:6], x[6:9], x[9:12] = p, euler_zyx(R), R.T @ v, w
    return x


def reference_row(flat: Mapping[str, Any]) -> npt.NDArray[np.float64]:
    """quadcog's reference row (14,) from RotorPy's flat outputs.

    Parameters
    ----------
    flat : mapping
        ``x``, ``x_dot``, ``x_ddot`` (m, m/s, m/s^2), ``yaw`` (rad); ``x_dddot`` (m/s^3) and
        ``yaw_dot`` (rad/s) when given, else 0.

    Returns
    -------
    (14,) numpy.ndarray
        ``[p, v, a, j, yaw, yaw_rate]`` (``quadcog.trajectories.analytic``).

    Raises
    ------
    quadcog.PeerStateError
        Naming the key that is missing or malformed.
    """
    if not isinstance(flat, Mapping):
        raise PeerStateError(f"flat_output must be a dictionary with keys {', '.join(FLAT_KEYS)}, "
                             f"got {type(flat).__name__}")
    ref = np.zeros(REF_SIZE)
    ref[POS], ref[VEL], ref[ACC] = (_entry(flat, k, 3, "flat_output")
                                    for k in ("x", "x_dot", "x_ddot"))
    ref[YAW] = _entry(flat, "yaw", 1, "flat_output")[0]
    if "x_dddot" in flat:
        ref[JERK] = _entry(flat, "x_dddot", 3, "flat_output")
    if "yaw_dot" in flat:
        ref[YAW_RATE] = _entry(flat, "yaw_dot", 1, "flat_output")[0]
    return ref


def motor_speeds(vehicle: Vehicle, U: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Rotor speed commands (rad/s) for an input U, through the vehicle's rotor model.

    Parameters
    ----------
    vehicle : Vehicle
        Its mixer gives the rotor thrusts ``f = B^-1 U``; each is clipped to
        [min_rotor_thrust, max_rotor_thrust] and turned into ``sqrt(f / thrust_constant)``.
    U : (4,) array_like
        [U1 (N), U2, U3, U4 (N m, about O)].

    Returns
    -------
    (4,) numpy.ndarray
        Rotor speeds (rad/s), in the order of the vehicle's rotors (RotorPy's ``rotor_pos``).

    Raises
    ------
    quadcog.InputError
        ``vehicle`` not a Vehicle, or ``U`` not 4 finite real numbers.
    """
    if not isinstance(vehicle, Vehicle):
        validate.fail("motor_speeds: vehicle", "a quadcog Vehicle", vehicle)
    f = np.clip(vehicle.rotor_thrusts(U), vehicle.min_rotor_thrust, vehicle.max_rotor_thrust)
    return np.asarray(vehicle.rotor_speeds(f), dtype=np.float64)
