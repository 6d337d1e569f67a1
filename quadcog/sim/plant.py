"""The truth model: the generated ``truth_dynamics`` driven through the vehicle's rotors, with
optional parallel-axis inertia, rotor saturation and first-order motor lag, integrated by one
fixed RK4 step (a CasADi expression, compiled on use).

The rotors always hold ``f >= 0`` (fixed-pitch rotors only push): the commanded input U is
mapped to rotor thrusts by the inverse mixer, clipped, and mapped back. Saturation clips to
``[min_rotor_thrust, max_rotor_thrust]`` instead; motor lag makes the rotor thrusts states that
follow the clipped command with the vehicle's motor time constant.
"""
from dataclasses import dataclass
from typing import Any, TypeVar

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog.errors import InputError
from quadcog.model.attitude import QUATERNION, euler_of_rotation, quaternion_of_euler
from quadcog.model.conventions import IDX, N_PARAM, N_STATE, R_G, hover_trim
from quadcog.model.functions import Model
from quadcog.model.inertial_parameters import PI_NAMES
from quadcog.numerics import exact_inverse
from quadcog.vehicles.vehicle import N_ROTORS, Vehicle

__all__ = ["TruthOptions", "Actuation", "PI_INDEX", "body_mass_and_cog", "truth_arguments", "rk4_step_expression",
           "plant_step_function", "initial_rotor_thrusts"]

PI_INDEX = {name: k for k, name in enumerate(PI_NAMES)}
_Matrix = TypeVar("_Matrix", ca.SX, ca.DM)      # a symbolic or a numeric CasADi matrix


@dataclass(frozen=True)
class TruthOptions:
    """Effects of the truth model that the controllers' model leaves out (docs/model.md sec. 5;
    all off by default).

    Parameters
    ----------
    parallel_axis : bool
        The inertia about O follows the moving mass: the vehicle's Ixx, Iyy, Izz are its
        inertia about O at its stated CoG ``r_0`` (as the controllers' model reads them), and
        a CoG at ``r`` adds ``m (S(r) - S(r_0))``, ``S(r) = |r|^2 I - r r^T`` (for a vehicle
        stated at ``r_0 = 0``, as the presets are: the parallel-axis theorem from the CoG).
    rotor_saturation : bool
        Each rotor's thrust is clipped to the vehicle's
        ``[min_rotor_thrust, max_rotor_thrust]`` (without it: to ``[0, inf)``).
    motor_lag : bool
        Rotor thrusts follow the clipped command through a first-order lag with the
        vehicle's ``motor_time_constant`` (adds 4 rotor-thrust states; a time constant of 0 is
        instant, i.e. no lag).
    quaternion : bool
        The truth integrates the attitude on SE(3), as a unit quaternion (the generated
        ``se3_dynamics``, docs/model.md sec. 8), so it flies through 90 degrees of pitch and
        upside down; each step enters the quaternion of the state's Euler angles and hands
        back the ZYX Euler chart of the quaternion it reached (``quadcog.model.attitude``),
        which is what every controller reads. Without it the truth integrates the Euler
        angles, whose rates are singular at a pitch of 90 degrees.

    Raises
    ------
    quadcog.InputError
        An option that is not True or False.
    """
    parallel_axis: bool = False
    rotor_saturation: bool = False
    motor_lag: bool = False
    quaternion: bool = False

    def __post_init__(self) -> None:
        for name in ("parallel_axis", "rotor_saturation", "motor_lag", "quaternion"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise InputError(f"TruthOptions.{name} must be True or False, got "
                                 f"{getattr(self, name)!r}")


@dataclass(frozen=True)
class Actuation:
    """The rotors of one vehicle under given truth options: what the plant step bakes in.

    It is hashable, so it keys the compile cache. Build it with
    ``Actuation.of(vehicle, options)``.

    Parameters
    ----------
    options : TruthOptions
        The truth options it was built under.
    mixer : tuple of 16 float
        The (4, 4) mixer, row-major: U = mixer @ f.
    lower : float
        Lowest rotor thrust (N, per rotor).
    upper : float
        Highest rotor thrust (N, per rotor; inf without saturation).
    time_constant : float
        Motor time constant (s); 0: instant.
    """
    options: TruthOptions
    mixer: tuple                 # (4, 4) row-major, U = mixer @ f
    lower: float                 # N, per rotor
    upper: float                 # N, per rotor (inf without saturation)
    time_constant: float         # s; 0: instant

    @classmethod
    def of(cls, vehicle: Vehicle, options: TruthOptions | None = None) -> "Actuation":
        """The actuation of a vehicle under truth options.

        Parameters
        ----------
        vehicle : Vehicle
            Its mixer, rotor thrust limits and motor time constant are used.
        options : TruthOptions, optional
            Default ``TruthOptions()`` (all off).

        Returns
        -------
        Actuation
            The rotors as the truth model has them.
        """
        options = options or TruthOptions()
        sat = options.rotor_saturation
        return cls(options, tuple(vehicle.mixer().ravel().tolist()),
                   vehicle.min_rotor_thrust if sat else 0.0,
                   vehicle.max_rotor_thrust if sat else float("inf"),
                   vehicle.motor_time_constant if options.motor_lag else 0.0)

    @property
    def n_rotor_states(self) -> int:
        """4 when the rotor thrusts are states (motor lag with a time constant > 0), else 0."""
        return N_ROTORS if self.time_constant > 0 else 0

    def mixer_matrix(self) -> npt.NDArray[np.float64]:
        """The (4, 4) mixer as a numpy array.

        Returns
        -------
        (4, 4) numpy.ndarray
            U = mixer @ f (N, N m from rotor thrusts in N).
        """
        return np.array(self.mixer).reshape(4, 4)

    def mixer_inverse(self) -> npt.NDArray[np.float64]:
        """The inverse of the mixer, correctly rounded (``numerics.exact_inverse``).

        Returns
        -------
        (4, 4) numpy.ndarray
            f = mixer_inverse @ U (rotor thrusts in N from N, N m).
        """
        return exact_inverse(self.mixer_matrix(), "the mixer")

    def rotor_command(self, U: _Matrix) -> _Matrix:
        """Rotor thrusts for input U: inverse mixer, then the limits.

        A non-finite command stays non-finite.

        Parameters
        ----------
        U : (4,) casadi.SX or casadi.DM
            The input [N, N m, N m, N m].

        Returns
        -------
        (4,) casadi.SX or casadi.DM
            Rotor thrusts (N).
        """
        f = ca.DM(self.mixer_inverse()) @ U
        clipped = ca.fmax(f, self.lower)
        if not np.isinf(self.upper):
            clipped = ca.fmin(clipped, self.upper)
        # a non-finite command stays non-finite (fmax(NaN, 0) = 0 would hide a failed law)
        return ca.if_else(ca.fabs(f) < np.inf, clipped, f)

    def rotor_command_numpy(self, U: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """``rotor_command`` for numpy inputs, of one flight or many.

        Parameters
        ----------
        U : (4,) or (B, 4) array_like
            The input [N, N m, N m, N m], or one per flight.

        Returns
        -------
        (4,) or (B, 4) numpy.ndarray
            Rotor thrusts (N), within the limits.
        """
        U = np.asarray(U, dtype=float)
        f = U @ self.mixer_inverse().T
        return np.clip(f, self.lower, self.upper)


def body_mass_and_cog(m: Any, r: Any, dm: Any, dh: Any) -> tuple[Any, Any]:
    """Mass and CoG of the airframe (m, r) with payloads of mass dm and first moment dh added.

    ``r + (dh - dm r) / (m + dm)``, which is ``(m r + dh) / (m + dm)`` written so that it is
    exactly r when nothing is on board (x + 0 is x), so a run without payloads keeps its bits.
    Numpy arrays (broadcast: m, dm of shape (N, 1) against r, dh of shape (N, 3)) or CasADi.

    Parameters
    ----------
    m : float, numpy.ndarray or casadi.SX
        The airframe's mass (kg).
    r : (..., 3) numpy.ndarray or (3,) casadi.SX
        The airframe's CoG (m, body axes).
    dm : float, numpy.ndarray or casadi.SX
        The payloads' mass (kg).
    dh : (..., 3) numpy.ndarray or (3,) casadi.SX
        The payloads' first moment of mass about O (kg m).

    Returns
    -------
    m_total : float, numpy.ndarray or casadi.SX
        The whole body's mass (kg).
    r_total : (..., 3) numpy.ndarray or casadi.SX
        The whole body's CoG (m).
    """
    m_total = m + dm
    return m_total, r + (dh - dm * r) / m_total


def truth_arguments(p: ca.SX, options: TruthOptions, payload: ca.SX | None = None,
                    r_stated: ca.SX | None = None) -> tuple[ca.SX, ca.SX]:
    """The parameter and inertia-product arguments of the truth model: the airframe at the
    step's CoG plus the payloads on board.

    With ``parallel_axis`` the airframe's inertia about O follows its moving mass: the
    vehicle's Ixx, Iyy, Izz are its inertia about O at its stated CoG ``r_stated`` (as the
    controllers' model reads them), and a CoG at r adds ``m (S(r) - S(r_stated))``,
    ``S(r) = |r|^2 I - r r^T``. The payloads' inertial parameters ``payload`` (about O) add to
    the airframe's: mass, first moment and inertia are integrals over the body.

    Parameters
    ----------
    p : (14,) casadi.SX
        The airframe's parameter vector at the step (``quadcog.PARAM_NAMES``).
    options : TruthOptions
        With ``parallel_axis``, the inertia about O follows the CoG.
    payload : (10,) casadi.SX, optional
        The summed pi of the payloads on board (``quadcog.model.inertial_parameters.PI_NAMES``
        order); None for none.
    r_stated : (3,) casadi.SX, optional
        The CoG at which the vehicle states its inertia (default 0).

    Returns
    -------
    p_eff : (14,) casadi.SX
        The whole body's mass, diagonal inertia about O and CoG in ``p``'s layout.
    products : (3,) casadi.SX
        The whole body's products of inertia (Ixy, Ixz, Iyz) (kg m^2).
    """
    m, r = p[IDX["m"]], p[R_G.start:R_G.stop]
    diag, products = p[IDX["Ixx"]:IDX["Izz"] + 1], ca.SX.zeros(3)
    if options.parallel_axis:
        x, y, z = r[0], r[1], r[2]
        S_diag = ca.vertcat(y * y + z * z, x * x + z * z, x * x + y * y)
        S_off = ca.vertcat(x * y, x * z, y * z)
        if r_stated is not None:
            # the stated inertia holds at the stated CoG (a - 0 is a: no change at r_stated = 0)
            a, b, c = r_stated[0], r_stated[1], r_stated[2]
            S_diag = S_diag - ca.vertcat(b * b + c * c, a * a + c * c, a * a + b * b)
            S_off = S_off - ca.vertcat(a * b, a * c, b * c)
        diag, products = diag + S_diag * m, -m * S_off
    if payload is not None:
        m, r = body_mass_and_cog(m, r, payload[PI_INDEX["m"]],
                                 payload[[PI_INDEX[f"m{a}_G"] for a in "xyz"]])
        diag = diag + payload[[PI_INDEX[n] for n in ("Ixx", "Iyy", "Izz")]]
        products = products + payload[[PI_INDEX[n] for n in ("Ixy", "Ixz", "Iyz")]]
    p_eff = ca.vertcat(m, p[IDX["m"] + 1:IDX["Ixx"]], diag, p[IDX["Izz"] + 1:R_G.start], r,
                       p[R_G.stop:])
    return p_eff, products


def rk4_step_expression(model: Model, x: ca.SX, f: ca.SX, U: ca.SX, p: ca.SX, wrench: ca.SX,
                        dt: ca.SX, actuation: Actuation, payload: ca.SX | None = None,
                        r_stated: ca.SX | None = None) -> tuple[ca.SX, ca.SX, ca.SX]:
    """One RK4 step of length dt of the truth plant with U, p, payload and wrench held.

    Parameters
    ----------
    model : Model
        The generated functions (``truth_dynamics``).
    x : (12,) casadi.SX
        The state [m, rad, m/s, rad/s].
    f : (4,) or (0,) casadi.SX
        The rotor thrusts (N) when ``actuation.n_rotor_states`` is 4, else an empty SX.
    U : (4,) casadi.SX
        The commanded input [N, N m, N m, N m].
    p : (14,) casadi.SX
        The truth parameter vector.
    wrench : (6,) casadi.SX
        Disturbance force (N, ground axes) and moment (N m, body axes).
    dt : casadi.SX
        Step length (s).
    actuation : Actuation
        The rotors.
    payload : (10,) casadi.SX, optional
        The payloads' summed pi about O (``truth_arguments``); None for none.
    r_stated : (3,) casadi.SX, optional
        The CoG at which the vehicle states its inertia (``truth_arguments``).

    Returns
    -------
    x_next : (12,) casadi.SX
        The state after the step.
    f_next : (4,) or (0,) casadi.SX
        The rotor thrusts after the step.
    U_applied : (4,) casadi.SX
        The input the rotors deliver at the start of the step (mixer @ rotor thrusts).
    """
    mix = ca.DM(actuation.mixer_matrix())
    p_eff, products = truth_arguments(p, actuation.options, payload, r_stated)
    f_cmd = actuation.rotor_command(U)
    field, enter, leave = _attitude_chart(model, actuation.options, p_eff, products, wrench)
    x_in = enter(x)
    if not actuation.n_rotor_states:
        U_app = mix @ f_cmd
        rhs = lambda s: field(s, U_app)
        k1 = rhs(x_in)
        k2 = rhs(x_in + dt / 2 * k1)
        k3 = rhs(x_in + dt / 2 * k2)
        k4 = rhs(x_in + dt * k3)
        return leave(x_in + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)), f, U_app
    tau = actuation.time_constant
    n = x_in.numel()

    def rhs(s):  # type: ignore[no-redef]  # the motor-lag branch's rhs, of [x; f]
        xs, fs = s[:n], s[n:]
        return ca.vertcat(field(xs, mix @ fs), (f_cmd - fs) / tau)

    s = ca.vertcat(x_in, f)
    k1 = rhs(s)
    k2 = rhs(s + dt / 2 * k1)
    k3 = rhs(s + dt / 2 * k2)
    k4 = rhs(s + dt * k3)
    s_next = s + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return leave(s_next[:n]), s_next[n:], mix @ f


def _attitude_chart(model: Model, options: TruthOptions, p_eff: ca.SX, products: ca.SX,
                    wrench: ca.SX) -> tuple[Any, Any, Any]:
    """(field(s, U), enter(x), leave(s)): the truth's vector field on the state it integrates,
    and the maps from and to the 12-state x with Euler angles (identities on the Euler chart;
    x -> [position, q(eta), nu] and back through R(q) on SE(3))."""
    if not options.quaternion:
        truth = model.casadi_function("truth_dynamics")
        same = lambda s: s
        return (lambda s, U: truth(s, U, p_eff, products, wrench)), same, same
    se3 = model.casadi_function("se3_dynamics")
    rotation = model.casadi_function("quaternion_rotation")
    m, r = p_eff[IDX["m"]], p_eff[R_G.start:R_G.stop]
    Ixx, Iyy, Izz = p_eff[IDX["Ixx"]], p_eff[IDX["Iyy"]], p_eff[IDX["Izz"]]
    # pi = [m, m r_G, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]; products are (Ixy, Ixz, Iyz)
    pi = ca.vertcat(m, m * r, Ixx, products[0], Iyy, products[1], products[2], Izz)
    g, c = p_eff[IDX["g"]], p_eff[IDX["c_x"]:IDX["c_psi"] + 1]

    def enter(x):
        return ca.vertcat(x[:3], *quaternion_of_euler(x[3], x[4], x[5], ca), x[6:])

    def leave(s):
        q = s[QUATERNION] / ca.norm_2(s[QUATERNION])     # back onto |q| = 1 after the step
        phi, theta, psi = euler_of_rotation(rotation(q), ca)
        return ca.vertcat(s[:3], phi, theta, psi, s[7:])

    return (lambda s, U: se3(s, U, pi, g, c, wrench)), enter, leave


def plant_step_function(model: Model, actuation: Actuation) -> ca.Function:
    """The truth plant's RK4 step as a CasADi Function.

    Parameters
    ----------
    model : Model
        The generated functions.
    actuation : Actuation
        The rotors; f has ``actuation.n_rotor_states`` entries (0 or 4).

    Returns
    -------
    casadi.Function
        ``plant_step(x, f, U, p, payload, r_stated, wrench, dt) -> (x_next, f_next,
        U_applied)``, see ``rk4_step_expression``.
    """
    nf = actuation.n_rotor_states
    x, f, U, p = ca.SX.sym("x", N_STATE), ca.SX.sym("f", nf), ca.SX.sym("U", 4), ca.SX.sym("p", N_PARAM)
    load, r0 = ca.SX.sym("payload", len(PI_NAMES)), ca.SX.sym("r_stated", 3)
    w, dt = ca.SX.sym("wrench", 6), ca.SX.sym("dt")
    x_next, f_next, U_app = rk4_step_expression(model, x, f, U, p, w, dt, actuation, load, r0)
    return ca.Function("plant_step", [x, f, U, p, load, r0, w, dt], [x_next, f_next, U_app],
                       ["x", "f", "U", "p", "payload", "r_stated", "wrench", "dt"],
                       ["x_next", "f_next", "U_applied"])


def initial_rotor_thrusts(P0: npt.NDArray[np.float64], actuation: Actuation
                          ) -> npt.NDArray[np.float64]:
    """Rotor thrusts at t = 0: those of a level hover, within the limits.

    The motors spin up before the run starts.

    Parameters
    ----------
    P0 : (14,) or (B, 14) numpy.ndarray
        The truth parameters (r_G at t = 0), of one flight or of B flights.
    actuation : Actuation
        The rotors.

    Returns
    -------
    (n_rotor_states,) or (B, n_rotor_states) numpy.ndarray
        Rotor thrusts (N); empty without motor lag.
    """
    if not actuation.n_rotor_states:
        return np.zeros(np.shape(P0)[:-1] + (0,))
    return actuation.rotor_command_numpy(hover_trim(P0))
