"""A geometric adaptive law on SE(3): Lee-style tracking (T. Lee, M. Leok, N. H. McClamroch,
"Geometric tracking control of a quadrotor UAV on SE(3)", IEEE CDC 2010) that learns the
payload, the mass m and the first moment of mass h = m r_G, through the derived regressor on
SE(3) (docs/model.md sec. 8; ``se3_regressor``), projected onto the physically consistent set.

Nothing in the law uses Euler angles: the state's ZYX angles (every law's interface) are turned
into R once (``quaternion_of_euler`` then the generated ``quaternion_rotation``: R is defined
at every attitude, also at and beyond 90 degrees of pitch), and everything after is on SO(3).

Tracking (ground axes; p, v of O; a_d, j_d, yaw from the reference row):

    e_x = p - p_d,  e_v = v - v_d,  a_c = a_d - k_x e_x - k_v e_v
    f = m_hat (a_c + g e3) + R (w x (w x h_hat) + D_v nu1)  (the force the body needs)
    b3_c = f / |f|,  b1_c = (b2_d x b3_c) / |b2_d x b3_c|,  b2_c = b3_c x b1_c,
    U1 = f . R e3

The heading enters through b2_d = [-sin yaw, cos yaw, 0] (Lee's construction turned by 90
degrees: b1_c from b2_d rather than b2_c from b1_d). A flip about the body y axis, where b3_c
sweeps through the horizontal along b1_d, then never meets the construction's singularity
b3_c || b2_d, which would take a roll of 90 degrees. Omega_c = (R_c^T R_c_dot)^vee with
R_c_dot the derivative of R_c(f, yaw) along f_dot = m_hat (j_d - k_x e_v - k_v (a - a_d)) +
d/dt (R D_v nu1) and yaw_rate, with a = (U1 R e3 - R D_v nu1) / m_hat - g e3 the acceleration
that the thrust gives the believed body (assuming instead that e_v follows its command makes
the feedforward cancel the feedback: in a development run, a hover held 0.66 m off after a CoG
step). The reference has no snap, so Omega_c_dot is the derivative of Omega_c through a first-order
filter, ``Omega_f_dot = lam_d (Omega_c - Omega_f)``, ``Omega_c_dot ~ lam_d (Omega_c -
Omega_f)`` (``rate_filter`` lam_d; without it, in a development run, the banked circle at 60
degrees lagged by 8.6 cm RMS, its body rates turning at 2.9 rad/s).

    e_R = (R_c^T R - R^T R_c)^vee / 2,  e_W = w - R^T R_c Omega_c
    w_dot* = -k_R e_R - k_W e_W - w x R^T R_c Omega_c + R^T R_c Omega_c_dot

The moments are the inverse dynamics of the believed body through the regressor:
``[U2, U3, U4] = rows 4-6 of Y(R, nu, nu_dot*) pi_hat + D_w w``, where nu_dot* holds w_dot* and
the acceleration of O that the thrust U1 gives the believed body,
``a_O* = (U1 e3 - w_dot* x h - w x (w x h) - D_v nu1) / m_hat`` (so the moment of a CoG offset,
h x a_O, is cancelled with the thrust it rides on). f leaves out the w_dot x h term of the
force (it would make f depend on the attitude loop's output).

Estimation: the prediction-error (composite) estimator of ``PayloadAdaptive`` (its filters,
start compensation, normalization, least squares with forgetting and the projection onto
``K = {m_lo <= m <= m_hi, h^T Sigma_O^-1 h <= (1 - delta) m}``), its methods reused as they are,
with its regressor columns taken from ``se3_regressor`` at R. It has the same controller state
(``PayloadAdaptive.STATE_SLICES``) followed by Omega_f (3, rad/s), and I_O is held at the
model's. The tracking-error term of
the estimator (``gamma``) does not exist here: the update is the prediction error's alone.

Defaults from the vehicle (``quadcog.controllers.design``): k_R, k_W from the attitude poles,
k_x, k_v from the z poles of feedback linearization (the geometric law has no small-angle
cascade, so every axis gets the loop the thrust axis has), the estimator's filter, gain and
forgetting from the design's rules, the mass bounds (0.5, what the rotors lift: the
thrust-to-weight ratio) from ``design.mass_bounds_of``, lam_d = min(rotor bandwidth,
8 attitude rates) (80 1/s for the Hummingbird: the feedforward acts through the motors, no
faster).
"""
import casadi as ca
import numpy as np

from quadcog import validate
from quadcog.controllers.base import Controller
from quadcog.controllers.design import attitude_rate, design, mass_bounds_of, rotor_bandwidth, setting
from quadcog.controllers.payload_adaptive import N_THETA, PayloadAdaptive
from quadcog.controllers.shaping import second_order_gains
from quadcog.kinds import Flag, Number, Poles, Vector
from quadcog.model.attitude import quaternion_of_euler
from quadcog.model.conventions import IDX, NU
from quadcog.model.functions import Model
from quadcog.model.inertial_parameters import inertial_arguments, pseudo_inertia
from quadcog.numerics import exact_inverse
from quadcog.trajectories.analytic import ACC, JERK, POS, VEL, YAW, YAW_RATE
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["GeometricAdaptive", "desired_attitude"]

_E3 = ca.DM([0.0, 0.0, 1.0])


def _vee(S: ca.SX) -> ca.SX:
    return ca.vertcat(S[2, 1], S[0, 2], S[1, 0])


def desired_attitude(f: ca.SX, yaw: ca.SX) -> ca.SX:
    """R_c = [b1_c, b2_c, b3_c] of a needed force and a heading (module docstring).

    Parameters
    ----------
    f : (3,) casadi.SX
        The force the body needs, ground axes (N); b3_c = f / |f|.
    yaw : casadi.SX
        Heading (rad): b2_d = [-sin yaw, cos yaw, 0].

    Returns
    -------
    (3, 3) casadi.SX
        R_c, body to ground.
    """
    b3 = f / ca.norm_2(f)
    b2d = ca.vertcat(-ca.sin(yaw), ca.cos(yaw), 0)
    b1 = ca.cross(b2d, b3)
    b1 = b1 / ca.norm_2(b1)
    return ca.horzcat(b1, ca.cross(b3, b1), b3)


class GeometricAdaptive(Controller):
    """Geometric tracking on SE(3) with a composite estimate of m and m r_G (module docstring).

    Parameters
    ----------
    vehicle : Vehicle, optional
        The controller's model (default: the Hummingbird with r_G = 0); m_hat starts at its m,
        r_hat at its r_G, and its I_O is held.
    model : quadcog.model.functions.Model, optional
        The generated functions (default ``quadcog.load()``).
    poles_position : sequence of float, optional
        2 poles (rad/s) of e_x_ddot + k_v e_x_dot + k_x e_x = 0, every axis; default the
        design's poles_z.
    poles_attitude : sequence of float, optional
        2 poles (rad/s) of the attitude error (k_R, k_W per unit inertia); default the
        design's poles_attitude.
    filter_rate : float, optional
        The estimator's filter rate lam (1/s); default the design's
        (``quadcog.controllers.design``).
    ls_gain : float, optional
        The estimator's least-squares weight (1/s); default the design's.
    forgetting : float, optional
        The estimator's forgetting rate beta (1/s); default the design's.
    covariance_bound : float, optional
        k0, the bound of the estimator's covariance; default the design's.
    force_weight : float
        Weight of the force rows against the moment rows, default 1.
    mass_bounds : (2,) sequence of float, optional
        [m_lo, m_hi] relative to the model's mass; default ``design.mass_bounds_of``: (0.5,
        the thrust-to-weight ratio), m_hi the heaviest body the rotors lift.
    consistency_margin : float
        delta in (0, 1), default 0.1.
    allocation : bool
        Reduce the command to what the rotors can give (yaw first), default True.
    motor_lag : bool
        The estimator sees the rotor thrusts lag with the vehicle's motor time constant.
    warm_up : float
        Seconds from t = 0 without the prediction error, default 0.
    start_compensation : bool
        Take the filters' start transient out exactly (``PayloadAdaptive``), default True.
    rate_filter : float, optional
        lam_d (1/s) of the derivative of Omega_c; default min(rotor bandwidth, 8 attitude
        rates).

    Raises
    ------
    InputError
        When a setting is out of range.
    """

    name = "geometric"
    estimates_cog = True
    STATE_SLICES = {**PayloadAdaptive.STATE_SLICES, "rate_filter": slice(-3, None)}
    # the composite estimator, reused as it is (it reads the attributes set in __init__)
    initial_state = PayloadAdaptive.initial_state
    filtered_regression = PayloadAdaptive.filtered_regression
    drag = PayloadAdaptive.drag
    projected_update = PayloadAdaptive.projected_update
    _limits = PayloadAdaptive._limits
    project = PayloadAdaptive.project
    project_numpy = PayloadAdaptive.project_numpy
    estimate_of = PayloadAdaptive.estimate_of
    mass_of = PayloadAdaptive.mass_of
    inertial_parameters_of = PayloadAdaptive.inertial_parameters_of

    def __init__(self, vehicle: Vehicle | None = None, model: Model | None = None, *,
                 poles_position: Poles | None = None, poles_attitude: Poles | None = None,
                 filter_rate: Number | None = None, ls_gain: Number | None = None,
                 forgetting: Number | None = None, covariance_bound: Number | None = None,
                 force_weight: Number = 1.0, mass_bounds: Vector | None = None,
                 consistency_margin: Number = 0.1, allocation: Flag = True,
                 motor_lag: Flag = False, warm_up: Number = 0.0,
                 start_compensation: Flag = True, rate_filter: Number | None = None) -> None:
        super().__init__(vehicle, model)
        v = self.vehicle
        d = design(v)
        self.k_x, self.k_v = second_order_gains(
            d.poles_z if poles_position is None else poles_position, "poles_position")
        self.k_R, self.k_W = second_order_gains(
            d.poles_attitude if poles_attitude is None else poles_attitude, "poles_attitude")
        # the estimator's settings and scales, as PayloadAdaptive holds them
        self.filter_rate = (d.filter_rate if filter_rate is None
                            else setting(filter_rate, "filter_rate", "1/s"))
        self.ls_gain = d.ls_gain if ls_gain is None else setting(ls_gain, "ls_gain", "1/s")
        self.forgetting = (d.forgetting if forgetting is None
                           else setting(forgetting, "forgetting", "1/s"))
        self.covariance_bound = (d.covariance_bound if covariance_bound is None
                                 else setting(covariance_bound, "covariance_bound"))
        self.force_weight = setting(force_weight, "force_weight", zero=True)
        self.gamma = 0.0
        bounds = validate.array(mass_bounds_of(v) if mass_bounds is None else mass_bounds,
                                "mass_bounds", (2,),
                                what="[m_lo, m_hi] relative to the model's mass")
        if not 0 < bounds[0] < 1 < bounds[1]:
            validate.fail("mass_bounds" if mass_bounds is not None else
                          "mass_bounds (default: 4 max_rotor_thrust / (m g) of the vehicle, "
                          f"max_rotor_thrust = {v.max_rotor_thrust:g} N)",
                          "[m_lo, m_hi] with 0 < m_lo < 1 < m_hi (relative to the model's "
                          "mass; rotors that lift it)", bounds.tolist())
        self.mass_bounds = bounds
        self.consistency_margin = validate.real(consistency_margin, "consistency_margin",
                                                lo=0.0, hi=1.0, lo_open=True, hi_open=True)
        self.warm_up = validate.nonnegative(warm_up, "warm_up", "s")
        self.start_compensation = validate.flag(start_compensation, "start_compensation")
        self.clock_stop = self.warm_up + 20.0 / self.filter_rate
        self.allocation = validate.flag(allocation, "allocation")
        self.motor_lag = validate.flag(motor_lag, "motor_lag")
        self.motor_states = 4 if (self.motor_lag and v.motor_time_constant > 0) else 0
        self.n_estimator = 75 + self.motor_states      # PayloadAdaptive's state, then Omega_f
        self.n_state = self.n_estimator + 3
        self.rate_filter = (min(rotor_bandwidth(v), 8.0 * attitude_rate(v)) if rate_filter is None
                            else setting(rate_filter, "rate_filter", "1/s"))
        pi, _, _ = inertial_arguments(self.nominal, "the controller model's parameters")
        self.inertia = pi[N_THETA:]
        self.sigma_inverse = exact_inverse(pseudo_inertia(pi)[:3, :3], "Sigma_O")
        m0, l, mg = v.m, v.arm_length, v.m * v.g
        self.parameter_scale = np.r_[m0, [m0 * l] * 3]
        self.row_scale = np.r_[[1.0 / mg] * 3, [1.0 / (mg * l)] * 3]
        self.row_weight = self.ls_gain * np.r_[[self.force_weight] * 3, [1.0] * 3]
        self.cone = m0 * l * l * self.sigma_inverse
        # R_c(f, yaw) and its derivative along (f_dot, yaw_rate), by CasADi's forward mode
        f, yaw, f_dot, yaw_rate = (ca.SX.sym(n, k) for n, k in
                                   (("f", 3), ("yaw", 1), ("f_dot", 3), ("yaw_rate", 1)))
        Rc = desired_attitude(f, yaw)
        Rc_dot = ca.reshape(ca.jtimes(ca.vec(Rc), ca.vertcat(f, yaw),
                                      ca.vertcat(f_dot, yaw_rate)), 3, 3)
        self._desired = ca.Function("desired_attitude", [f, yaw, f_dot, yaw_rate],
                                    [Rc, Rc_dot])
        # Omega_f and its rate, set by expression() for parts() while one law is built
        self._omega_f, self._omega_f_dot = ca.SX.zeros(3), ca.SX.zeros(3)

    def expression(self, t: ca.SX, x: ca.SX, ref: ca.SX, c: ca.SX) -> tuple[ca.SX, ca.SX]:
        """The law as CasADi expressions: ``PayloadAdaptive``'s estimator around ``parts``,
        and the rate filter of Omega_c.

        Parameters
        ----------
        t : casadi.SX
            Time (s).
        x : casadi.SX
            State (12,) [m, rad, m/s, rad/s].
        ref : casadi.SX
            Reference row (14,).
        c : casadi.SX
            The controller state (``n_state``,).

        Returns
        -------
        U : casadi.SX
            Input (4x1) [U1 (N), U2, U3, U4 (N m)].
        c_dot : casadi.SX
            Its rate (``n_state`` x 1).
        """
        n = self.n_estimator
        # parts() reads Omega_f and leaves its rate here, for this one build
        self._omega_f, self._omega_f_dot = c[n:n + 3], ca.SX.zeros(3)
        U, c_dot = PayloadAdaptive.expression(self, t, x, ref, c[:n])  # type: ignore[arg-type]
        return U, ca.vertcat(c_dot, self._omega_f_dot)

    def attitude(self, x: ca.SX) -> ca.SX:
        """R of the state, body to ground, defined at every attitude.

        Parameters
        ----------
        x : casadi.SX
            State (12,) [m, rad, m/s, rad/s].

        Returns
        -------
        (3, 3) casadi.SX
            R = R(q(eta)) (generated ``quaternion_rotation``).
        """
        q = ca.vertcat(*quaternion_of_euler(x[3], x[4], x[5], ca))
        return self.model.casadi_function("quaternion_rotation")(q)

    def regressor(self, x: ca.SX, nu_dot: ca.SX) -> ca.SX:
        """Y(R, nu, nu_dot) on SE(3) with the model's g (6x10).

        Parameters
        ----------
        x : casadi.SX
            State (12,).
        nu_dot : casadi.SX
            A generalized acceleration (6,) [m/s^2, rad/s^2].

        Returns
        -------
        (6, 10) casadi.SX
            ``se3_regressor(R(x), nu, nu_dot, g)``.
        """
        R_rows = ca.vec(self.attitude(x).T)          # row by row, as the contract has it
        return self.model.casadi_function("se3_regressor")(R_rows, x[NU], nu_dot,
                                                           self.nominal[IDX["g"]])

    def gravity_coriolis_columns(self, x: ca.SX) -> tuple[ca.SX, ca.SX]:
        """``Y(R, nu, 0)`` split into the theta columns and the held inertia's part.

        Parameters
        ----------
        x : casadi.SX
            State (12,).

        Returns
        -------
        Y0_th : casadi.SX
            (6x4).
        k : casadi.SX
            (6,) [N, N m].
        """
        Y0 = self.regressor(x, ca.SX.zeros(6))
        return Y0[:, :N_THETA], Y0[:, N_THETA:] @ ca.DM(self.inertia)

    def momentum_columns(self, x: ca.SX) -> tuple[ca.SX, ca.SX]:
        """The momentum M(pi) nu = W(nu) pi split into the theta columns and the held part.

        Parameters
        ----------
        x : casadi.SX
            State (12,).

        Returns
        -------
        W_th : casadi.SX
            (6x4).
        w : casadi.SX
            (6,) [N s, N m s].
        """
        W = self.regressor(x, x[NU]) - self.regressor(x, ca.SX.zeros(6))
        return W[:, :N_THETA], W[:, N_THETA:] @ ca.DM(self.inertia)

    def parts(self, x: ca.SX, ref: ca.SX, m_hat: ca.SX,
              r_hat: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
        """The geometric tracking law on the estimate (module docstring).

        Parameters
        ----------
        x : casadi.SX
            State (12,) [m, rad, m/s, rad/s].
        ref : casadi.SX
            Reference row (14,).
        m_hat : casadi.SX
            Mass estimate (kg).
        r_hat : casadi.SX
            CoG estimate (3,) (m).

        Returns
        -------
        U : casadi.SX
            Input (4x1) [U1 (N), U2, U3, U4 (N m)].
        e_s, Phi, B : casadi.SX
            Zeros: the estimator's tracking term does not exist here (``gamma`` is 0).
        """
        g = float(self.nominal[IDX["g"]])
        R = self.attitude(x)
        nu1, w = x[6:9], x[9:12]
        h = m_hat * r_hat
        c = ca.DM(self.nominal[IDX["c_x"]:IDX["c_psi"] + 1])
        drag_v, drag_w = c[:3] * nu1, c[3:] * w
        e_x, e_v = x[0:3] - ref[POS], R @ nu1 - ref[VEL]
        a_c = ref[ACC] - self.k_x * e_x - self.k_v * e_v
        f = m_hat * (a_c + g * _E3) + R @ (ca.cross(w, ca.cross(w, h)) + drag_v)
        U1 = ca.dot(f, R @ _E3)
        # the acceleration of O that U1 gives the believed body (CoG terms aside), and the rate
        # of f along it (the CoG term's rate aside: it needs w_dot)
        a = (U1 * (R @ _E3) - R @ drag_v) / m_hat - g * _E3
        nu1_dot = R.T @ a - ca.cross(w, nu1)
        f_dot = (m_hat * (ref[JERK] - self.k_x * e_v - self.k_v * (a - ref[ACC]))
                 + R @ (ca.cross(w, drag_v) + c[:3] * nu1_dot))
        Rc, Rc_dot = self._desired(f, ref[YAW], f_dot, ref[YAW_RATE])
        Omega_c = _vee(Rc.T @ Rc_dot)
        e_R = _vee(Rc.T @ R - R.T @ Rc) / 2
        w_c = R.T @ Rc @ Omega_c
        Omega_c_dot = self.rate_filter * (Omega_c - self._omega_f)
        self._omega_f_dot = Omega_c_dot
        w_dot = (-self.k_R * e_R - self.k_W * (w - w_c) - ca.cross(w, w_c)
                 + R.T @ Rc @ Omega_c_dot)
        a_O = (U1 * _E3 - ca.cross(w_dot, h) - ca.cross(w, ca.cross(w, h)) - drag_v) / m_hat
        nu1_dot = a_O - ca.cross(w, nu1) - g * (R.T @ _E3)
        pi_hat = ca.vertcat(m_hat, h, ca.DM(self.inertia))
        wrench = self.regressor(x, ca.vertcat(nu1_dot, w_dot)) @ pi_hat
        U = ca.vertcat(U1, wrench[3:6] + drag_w)
        return U, ca.SX.zeros(8), ca.SX.zeros(6, N_THETA), ca.SX.zeros(8, 6)
