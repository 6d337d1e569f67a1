"""Composite adaptive feedback linearization that learns a payload: the mass and the first
moment of mass ``h = m r_G`` together, projected onto the physically consistent set.

The law is the composite law (``composite.py``) with the unknown widened from r_G to
``theta = [m, h] = [m, m x_G, m y_G, m z_G]``, the first four of the ten inertial parameters
``pi = [theta; I_O]`` (``quadcog.model.inertial_parameters``). The inertia about O is held at
the controller model's I_O (as the paper's model holds it while the CoG moves).

Prediction error. The equations of motion are linear in pi (docs/model.md sec. 7.1):
``B_u U - D nu = Y(x, nu_dot) pi`` (the generated ``inertial_regressor``; drag D separate).
``Y(x, nu_dot) = Y(x, 0) + W(nu_dot)`` with ``W(nu) pi = M(pi) nu``: M is constant in body
axes, so ``M nu_dot = d/dt (W(nu) pi)`` and the filter F(s) = lam / (s + lam) needs no
acceleration (F[d/dt y] = lam y - lam F[y]). With the known part ``k = Y(x, 0)[:, 4:] I_O``,
``w = W(nu)[:, 4:] I_O`` (columns of the held inertia):

    z = zeta - lam w,            zeta_dot = lam (B_u U_a - D nu - k + lam w - zeta)
    Y_f = lam W_th + Psi,        Psi_dot = lam (Y_th(x, 0) - lam W_th - Psi)

(``_th``: the four columns of theta). U_a is what the controller believes its rotors deliver
(``composite.believed_input``). The filters start at rest, so ``z - Y_f theta`` carries the
start transient ``-lam exp(-lam t) M nu(0)`` (the filter of d/dt (M nu) did not start at its
signal). The composite law waits it out (its warm-up); a payload can tip a small vehicle over
within that wait (the Crazyflie with the scaled parcel from t = 0 flips at 0.26 s with a
warm-up of 5 / lam = 0.25 s), and a law that starts learning at once from a moving start
drives m_hat to its bound. This law takes the transient out exactly instead:
``M nu(0) = M nu(t) - int_0^t M nu_dot``, and ``M nu_dot = B_u U - D nu - Y(x, 0) pi`` is
linear in pi with a known regressor, so with the integrals ``A = int_0^t (B_u U_a - D nu - k)``
and ``B_int = int_0^t Y_th(x, 0)`` (states that stop once the transient is below 1e-8):

    M nu(0) = (W_th + B_int) theta + w - A,
    z + d (w - A) = (Y_f - d (W_th + B_int)) theta,      d = lam exp(-lam t),

an identity from t = 0 on, whatever the start (``start_compensation``, default on; the
warm-up, default 0, stays available).

Normalisation (one gain setting for every vehicle). ``theta = S_p theta_n``,
``S_p = diag(m0, m0 l, m0 l, m0 l)``: theta_n is the mass relative to the model's m0 and the
CoG moment in arm lengths l (``theta_n = [m / m0, m r_G / (m0 l)]``). The rows are divided by
m0 g (forces) and m0 g l (moments): ``Y_n = S_r Y_f S_p``, ``z_n = S_r z`` are of order one on
any airframe. Least squares with forgetting and a bounded covariance, as the composite law:

    theta_n_dot = Proj(P tau),
    tau = -kappa S_p Phi^T B^T P_L e_s - Y_n^T G (Y_n theta_n - z_n)
    P_dot = beta P (I - P / k0) - P Y_n^T G Y_n P,      P(0) = k0 I (4x4)

The tracking-error term (``gamma``, kappa = gamma / k0; Phi = Y_th(x, nu_dot_star),
B = [0; H M_hat^-1]) is off by default: see "The paper's law" below.

Defaults from the vehicle (``quadcog.controllers.design`` is not on main yet, so they are
derived here): lam = 1 / (4 tau_m) from the rotor time constant tau_m (20 1/s at 12.5 ms; 20
1/s without a lag), beta = lam / 2.5, the mass bounds relative to m0 (``design.mass_bounds_of``:
m_hi = 4 f_max / (m0 g), what the rotors lift, m_lo = 0.5), the rows scaled by m0 g and the
arm length as above. The feedback-linearization poles are the base class's.

The projection: which set, and why the Lyapunov argument survives. With I_O held, pi is
physically consistent when its pseudo-inertia ``J = [[Sigma_O, h], [h^T, m]]``,
``Sigma_O = tr(I_O)/2 I - I_O``, is positive definite (Wensing, Kim, Slotine 2017), i.e.
(Schur complement, m > 0) ``h^T Sigma_O^-1 h < m``. The law keeps theta in

    K = {m_lo <= m <= m_hi,  h^T Sigma_O^-1 h <= (1 - delta) m}

(``mass_bounds`` = [m_lo, m_hi] / m0, ``consistency_margin`` = delta). On K the second
moment about the CoG is ``Sigma_O - h h^T / m >= delta Sigma_O`` (Loewner order), so the
inertia about the estimated CoG, hence M_hat, stays positive definite and the feedback
linearization well conditioned, with a margin. K is convex: the mass bounds are half-spaces and
``h^T S h / m`` (quadratic over linear) is convex for m > 0. The update is projected onto the
tangent cone of K in the metric of P^-1: where theta_n is on a face g_i = 0 (``g_i`` the
constraint functions, normals ``n_i = grad g_i``) and P tau points out,
``theta_n_dot = P tau - P N (N^T P N)^-1 N^T P tau`` over the active normals N (at most two
faces meet: a mass bound and the cone). Then ``theta_n_dot - P tau = -P N lambda`` with
``lambda >= 0``, and for the truth theta* in K convexity gives
``n_i^T (theta_hat - theta*) >= g_i(theta_hat) - g_i(theta*) >= 0``, so with
``V = theta~^T P^-1 theta~`` (plus kappa e_s^T P_L e_s with the tracking term) the projection
adds ``-2 theta~^T N lambda <= 0`` to

    V_dot = -theta~^T Y_n^T G Y_n theta~ - beta theta~^T (P^-1 - I / k0) theta~ <= 0

for a constant payload: V_dot keeps its sign, and theta stays in K. After each discrete
(Euler) step ``project`` maps the state back into K: m clipped to its bounds, then r_G scaled
toward O until ``m r^T Sigma_O^-1 r <= 1 - delta`` (a map into K, not the P-metric nearest
point; the step is O(dt) outside K at most). The truth must lie in K for the argument: a
payload heavier than ``m_hi`` or with its CoG beyond the cone is outside what the law holds.

The paper's law (non-composite) cannot be extended to mass with its Lyapunov argument. Its
update ``-Gamma Phi^T B^T P e_s`` comes from ``e_s_dot = A e_s + B (nu_dot - nu_dot_star)``,
and with pi unknown ``M(pi) (nu_dot - nu_dot_star) = Y(x, nu_dot_star) (pi_hat - pi)``, so

    e_s_dot = A e_s + [0; H M(pi)^-1] Y(x, nu_dot_star) pi~.

The input gain ``M(pi)^-1`` is unknown and multiplies pi~: the error dynamics are bilinear,
not linear in the parameters with a known regressor. The cross term
``e_s^T P_L [0; H M^-1] Y pi~`` can be cancelled only by an update that knows M. Using M_hat
(as the paper's law does for r_G, where M's dependence on r is a small coupling) leaves
``M^-1 - M_hat^-1 = M^-1 (M_hat - M) M_hat^-1``, a term quadratic in pi~. That gives at best
stability near the truth, not the global V_dot <= 0. With the mass the gain is off by the
mass error itself (30 % for the parcel). Only in the special case of a centred payload
(h = 0 known) is the gain a positive scalar 1/m on the force rows. The classical
unknown-high-frequency-gain trick then applies (weight the parameter term of V by 1/m, known
sign). With h unknown too, M(pi)^-1 couples force and moment rows through the unknown r_G and
has no such factorization. The prediction error needs no B at all: ``z = Y_f theta`` is
exactly linear, which is why the composite law extends and carries the argument above. The
tracking term stays available (``gamma > 0``) with the composite law's caveat: its
cancellation holds for the true M in B.

Controller state c (``n_state``, ``STATE_SLICES``): r_hat (3, m), m_hat (1, kg), zeta (6),
Psi (24, column-major 6x4), the ten entries of the upper triangle of P (row by row), a clock
(s; it stops at warm_up + 20 / lam), the start integrals A (6) and B_int (24, column-major
6x4) and, with ``motor_lag``, the four believed rotor thrusts. The
state holds (r_hat, m_hat), so results report r_hat as every CoG-estimating law's; the
update is computed in theta_n and mapped (``r_dot = (h_dot - r m_dot) / m``).
"""
from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.controllers.composite import believed_input
from quadcog.controllers.decoupling import decoupled_input, linearizing_terms
from quadcog.controllers.design import mass_bounds_of, setting
from quadcog.controllers.feedback_linearization import FeedbackLinearization
from quadcog.errors import PhysicalConsistencyError
from quadcog.kinds import Flag, Number, Vector
from quadcog.model.conventions import B_U, IDX, NU
from quadcog.model.functions import Model
from quadcog.model.inertial_parameters import inertial_arguments, pseudo_inertia, symmetric_inertia
from quadcog.numerics import exact_inverse, exact_lyapunov
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["PayloadAdaptive", "N_THETA", "consistency_excess"]

N_THETA = 4                    # theta = [m, m x_G, m y_G, m z_G]: the first four entries of pi
_TRI = [(i, j) for i in range(N_THETA) for j in range(i, N_THETA)]


def _unpack(v: ca.SX) -> ca.SX:
    rows: list[list[Any]] = [[None] * N_THETA for _ in range(N_THETA)]
    for k, (i, j) in enumerate(_TRI):
        rows[i][j] = rows[j][i] = v[k]
    return ca.vertcat(*[ca.horzcat(*row) for row in rows])


def _pack(P: ca.SX) -> ca.SX:
    return ca.vertcat(*[P[i, j] for i, j in _TRI])


def consistency_excess(m: float, r_G: npt.ArrayLike, I_O: npt.ArrayLike) -> float:
    """How far (m, r_G) with the inertia I_O held is from the rim of physical consistency.

    Parameters
    ----------
    m : float
        Mass (kg), > 0.
    r_G : (3,) array_like
        CoG from O (m).
    I_O : (3, 3) array_like
        Inertia about O (kg m^2), symmetric, with its principal values meeting the strict
        triangle inequalities (``Sigma_O`` positive definite).

    Returns
    -------
    float
        ``m r^T Sigma_O^-1 r`` with ``Sigma_O = tr(I_O)/2 I - I_O``: below 1 exactly when the
        pseudo-inertia is positive definite (``PayloadAdaptive`` keeps it at most
        1 - consistency_margin).

    Raises
    ------
    InputError
        ``m`` not a finite number > 0, ``r_G`` not 3 finite numbers, ``I_O`` not a
        symmetric 3x3 matrix of finite numbers.
    PhysicalConsistencyError
        ``Sigma_O`` is not positive definite: no mass distribution has the inertia I_O about
        O, so no (m, r_G) is consistent with it.
    """
    m = validate.positive(m, "consistency_excess: m", "kg")
    r = validate.vector(r_G, "consistency_excess: r_G", 3)
    I = symmetric_inertia(I_O, "consistency_excess: I_O")
    Sigma = 0.5 * np.trace(I) * np.eye(3) - I
    lowest = float(np.linalg.eigvalsh(Sigma)[0])
    if not lowest > 0:
        raise PhysicalConsistencyError(
            f"consistency_excess: I_O = {validate.plain(I.tolist())} kg m^2 has "
            f"Sigma_O = tr(I_O)/2 - I_O with smallest eigenvalue {lowest:.6g} kg m^2; expected "
            f"> 0 (its principal inertias must meet the strict triangle inequalities)")
    return float(m * r @ np.linalg.solve(Sigma, r))


class PayloadAdaptive(FeedbackLinearization):
    """Composite adaptive FL estimating the mass and m r_G (see the module docstring).

    Parameters
    ----------
    vehicle : Vehicle, optional
        The controller's model (default: the Hummingbird with r_G = 0); m_hat starts at its
        m, r_hat at its r_G, and its I_O is held.
    model : quadcog.model.functions.Model, optional
        The generated functions (default ``quadcog.load()``).
    filter_rate : float, optional
        lam (1/s) of F(s) = lam / (s + lam); default 1 / (4 motor_time_constant), 20 without
        a motor time constant.
    ls_gain : float
        Least-squares weight (1/s) of the normalized prediction error, default 200.
    forgetting : float, optional
        beta (1/s), default filter_rate / 2.5.
    covariance_bound : float
        k0 (dimensionless, normalized units), default 1.
    force_weight : float
        Weight of the three force rows against the moment rows, default 1.
    gamma : float
        Tracking-error gain at P = k0 I (normalized units), default 0: off (see "The paper's
        law" in the module docstring).
    mass_bounds : (2,) sequence of float, optional
        [m_lo, m_hi] relative to the model's mass, 0 < m_lo < 1 < m_hi; default
        ``design.mass_bounds_of``: (0.5, the thrust-to-weight ratio), m_hi the heaviest body
        the rotors lift (3.60 for the Hummingbird).
    consistency_margin : float
        delta in (0, 1), default 0.1: the estimate keeps ``h^T Sigma_O^-1 h <= (1 - delta) m``.
    allocation : bool
        Reduce the command to what the rotors can give (yaw first), default True.
    motor_lag : bool
        The filter sees the rotor thrusts lag with the vehicle's motor time constant.
    warm_up : float
        Seconds from t = 0 without the prediction error, default 0 (the start transient is
        taken out exactly, see ``start_compensation``).
    start_compensation : bool
        Take the filters' start transient out of the prediction error (module docstring),
        default True.
    **kwargs
        The feedback-linearization poles and ``max_tilt``.

    Raises
    ------
    InputError
        When a setting is out of range.
    """

    name = "payload_adaptive"
    estimates_cog = True          # c starts with r_hat (results report it as the estimate)
    STATE_SLICES = {"r_hat": slice(0, 3), "m_hat": slice(3, 4), "zeta": slice(4, 10),
                    "Psi": slice(10, 34), "P": slice(34, 44), "clock": slice(44, 45),
                    "start_input": slice(45, 51), "start_regressor": slice(51, 75),
                    "rotor_thrusts": slice(75, 79)}

    def __init__(self, vehicle: Vehicle | None = None, model: Model | None = None, *,
                 filter_rate: Number | None = None, ls_gain: Number = 200.0,
                 forgetting: Number | None = None, covariance_bound: Number = 1.0,
                 force_weight: Number = 1.0, gamma: Number = 0.0,
                 mass_bounds: Vector | None = None, consistency_margin: Number = 0.1,
                 allocation: Flag = True, motor_lag: Flag = False,
                 warm_up: Number = 0.0, start_compensation: Flag = True,
                 **kwargs: Any) -> None:
        super().__init__(vehicle, model, **kwargs)
        v = self.vehicle
        tau_m = v.motor_time_constant
        self.filter_rate = (setting(filter_rate, "filter_rate", "1/s")
                            if filter_rate is not None
                            else (0.25 / tau_m if tau_m > 0 else 20.0))
        self.ls_gain = setting(ls_gain, "ls_gain", "1/s")
        self.forgetting = (setting(forgetting, "forgetting", "1/s")
                           if forgetting is not None else self.filter_rate / 2.5)
        self.covariance_bound = setting(covariance_bound, "covariance_bound")
        self.force_weight = setting(force_weight, "force_weight", zero=True)
        self.gamma = setting(gamma, "gamma", zero=True)
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
        # the clock runs until the start transient exp(-lam t) is below 1e-8 and warm-up is
        # over, then stops (so that float32 keeps its resolution)
        self.clock_stop = self.warm_up + 20.0 / self.filter_rate
        self.allocation = validate.flag(allocation, "allocation")
        self.motor_lag = validate.flag(motor_lag, "motor_lag")
        self.motor_states = 4 if (self.motor_lag and tau_m > 0) else 0
        self.n_state = 75 + self.motor_states
        pi, _, _ = inertial_arguments(self.nominal, "the controller model's parameters")
        self.inertia = pi[N_THETA:]          # I_O entries of pi, held
        # Sigma_O = tr(I_O)/2 I - I_O: the pseudo-inertia's second-moment block
        self.sigma_inverse = exact_inverse(pseudo_inertia(pi)[:3, :3], "Sigma_O")
        m0, l, mg = v.m, v.arm_length, v.m * v.g
        self.parameter_scale = np.r_[m0, [m0 * l] * 3]
        self.row_scale = np.r_[[1.0 / mg] * 3, [1.0 / (mg * l)] * 3]
        self.row_weight = self.ls_gain * np.r_[[self.force_weight] * 3, [1.0] * 3]
        # the cone in normalized units: b^T Q_n b <= (1 - delta) a, b = h / (m0 l), a = m / m0
        self.cone = m0 * l * l * self.sigma_inverse
        A = np.block([[np.zeros((4, 4)), np.eye(4)], [-np.diag(self.kp), -np.diag(self.kd)]])
        self.P = exact_lyapunov(A, np.eye(8), "the error dynamics")   # the same bits everywhere

    def initial_state(self) -> npt.NDArray[np.float64]:
        """The controller state at t = 0.

        Returns
        -------
        (n_state,) numpy.ndarray
            r_hat = the model's r_G (m), m_hat = its m (kg), filters at rest, P = k0 I,
            clock 0 s, start integrals 0, believed rotor thrusts at the model's hover (N).
        """
        c = np.zeros(self.n_state)
        c[0:3] = self.vehicle.r_G
        c[3] = self.vehicle.m
        c[34:44] = [self.covariance_bound * (i == j) for i, j in _TRI]
        if self.motor_states:
            c[75:79] = self.vehicle.rotor_thrusts(self.vehicle.hover_input())
        return c

    def estimated_parameters(self, m_hat: ca.SX, r_hat: ca.SX) -> ca.SX:
        """The 14-entry p of the feedback linearization: the model's with m_hat and r_hat.

        Parameters
        ----------
        m_hat : casadi.SX
            Mass estimate (kg).
        r_hat : casadi.SX
            CoG estimate (3,) (m).

        Returns
        -------
        casadi.SX
            p (14,), I_O and drag the model's.
        """
        p = ca.SX(ca.DM(self.nominal))
        return ca.vertcat(m_hat, p[1:IDX["x_G"]], r_hat)

    def parts(self, x: ca.SX, ref: ca.SX, m_hat: ca.SX,
              r_hat: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
        """The feedback linearization on the estimate and the pieces of the tracking term.

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
        e_s : casadi.SX
            Output error [e; e_dot] (8,).
        Phi : casadi.SX
            The theta columns of Y(x, nu_dot_star) (6x4) [m/s^2, m/s^2 (3)].
        B : casadi.SX
            [0; H M_hat^-1] (8x6).
        """
        p_hat = self.estimated_parameters(m_hat, r_hat)
        e, e_dot, y_ddot_d = self.output_errors(x, ref, p_hat)
        v = self.commanded_acceleration(e, e_dot, y_ddot_d)
        lin = linearizing_terms(self.model, x, p_hat)
        U = decoupled_input(lin.alpha, v - lin.b)
        nu_dot_star = lin.M_inv @ (ca.DM(B_U) @ U - lin.n)
        Phi = self.model.casadi_function("inertial_regressor")(
            x, nu_dot_star, self.nominal[IDX["g"]])[:, :N_THETA]
        return U, ca.vertcat(e, e_dot), Phi, ca.vertcat(ca.SX.zeros(4, 6), lin.HM)

    def filtered_regression(self, x: ca.SX, U_a: ca.SX, zeta: ca.SX,
                            Psi: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
        """The filtered identity z = Y_f theta of the module docstring.

        Parameters
        ----------
        x : casadi.SX
            State (12,) [m, rad, m/s, rad/s].
        U_a : casadi.SX
            The input believed delivered (4x1) [N, N m, N m, N m].
        zeta : casadi.SX
            The filter state of z (6,).
        Psi : casadi.SX
            The filter state of Y_f (6x4).

        Returns
        -------
        z : casadi.SX
            Filtered left-hand side (6,) [N, N m], the held inertia's part taken out.
        Y_f : casadi.SX
            Filtered regressor (6x4) [m/s^2, m/s^2 (3)] of theta = [m, h].
        zeta_dot : casadi.SX
            Rate of zeta (6,).
        Psi_dot : casadi.SX
            Rate of Psi (6x4).
        """
        lam = self.filter_rate
        Y0_th, k = self.gravity_coriolis_columns(x)
        W_th, w = self.momentum_columns(x)
        zeta_dot = lam * (ca.DM(B_U) @ U_a - self.drag(x) - k + lam * w - zeta)
        Psi_dot = lam * (Y0_th - lam * W_th - Psi)
        return zeta - lam * w, lam * W_th + Psi, zeta_dot, Psi_dot

    def drag(self, x: ca.SX) -> ca.SX:
        """The drag D nu of the model (6,) [N, N m] (not in the inertial regressor).

        Parameters
        ----------
        x : casadi.SX
            State (12,) [m, rad, m/s, rad/s].

        Returns
        -------
        casadi.SX
            D nu (6,).
        """
        return self.model.casadi_function("damping")(ca.DM(self.nominal)) @ x[NU]

    def gravity_coriolis_columns(self, x: ca.SX) -> tuple[ca.SX, ca.SX]:
        """C(nu) nu + g_G split into the unknown and the held part: ``Y(x, 0) pi``.

        Parameters
        ----------
        x : casadi.SX
            State (12,) [m, rad, m/s, rad/s].

        Returns
        -------
        Y0_th : casadi.SX
            ``Y(x, 0)[:, :4]`` (6x4) [m/s^2, m/s^2 (3)].
        k : casadi.SX
            ``Y(x, 0)[:, 4:] I_O`` (6,) [N, N m]: the part of the held inertia.
        """
        Y0 = self.model.casadi_function("inertial_regressor")(x, ca.SX.zeros(6),
                                                               self.nominal[IDX["g"]])
        return Y0[:, :N_THETA], Y0[:, N_THETA:] @ ca.DM(self.inertia)

    def momentum_columns(self, x: ca.SX) -> tuple[ca.SX, ca.SX]:
        """The momentum M(pi) nu split into the unknown and the held part.

        Parameters
        ----------
        x : casadi.SX
            State (12,) [m, rad, m/s, rad/s].

        Returns
        -------
        W_th : casadi.SX
            ``W(nu)[:, :4]`` (6x4) [m/s, m/s (3)]: ``W_th theta`` is the part of M nu of
            theta = [m, h].
        w : casadi.SX
            ``W(nu)[:, 4:] I_O`` (6,) [N s, N m s]: the part of the held inertia.
        """
        f = self.model.casadi_function
        g = self.nominal[IDX["g"]]
        W = f("inertial_regressor")(x, x[NU], g) - f("inertial_regressor")(x, ca.SX.zeros(6), g)
        return W[:, :N_THETA], W[:, N_THETA:] @ ca.DM(self.inertia)

    def projected_update(self, th: ca.SX, u: ca.SX, P: ca.SX) -> ca.SX:
        """The update projected onto the tangent cone of K (module docstring).

        Parameters
        ----------
        th : casadi.SX
            theta_n (4,): [m / m0, m r_G / (m0 l)].
        u : casadi.SX
            The raw update P tau (4,) (1/s).
        P : casadi.SX
            The covariance (4x4), symmetric positive definite.

        Returns
        -------
        casadi.SX
            The nearest point to u, in the metric of P^-1, of the cone
            ``{v : n_i^T v <= 0}`` of the faces of K that th is on (u itself inside K).
        """
        a, b = th[0], th[1:4]
        lo, hi = self.mass_bounds
        keep = 1.0 - self.consistency_margin
        Q = ca.DM(self.cone)
        e1 = ca.DM([1.0, 0.0, 0.0, 0.0])
        n_m = ca.if_else(a >= hi, 1.0, -1.0) * e1            # the face of the nearer bound
        on_m = ca.logic_or(a >= hi, a <= lo)
        n_c = ca.vertcat(-keep, 2 * Q @ b)
        # on the cone to rounding: the discrete map puts an estimate beyond it back on it
        on_c = ca.dot(b, Q @ b) - keep * a >= -1e-9 * a

        def single(n):
            Pn = P @ n
            return u - Pn * ca.dot(n, u) / ca.fmax(ca.dot(n, Pn), 1e-12)

        N = ca.horzcat(n_m, n_c)
        PN = P @ N
        G = N.T @ PN
        # 2x2 solve written out; both faces active only where they are not parallel
        det = ca.fmax(G[0, 0] * G[1, 1] - G[0, 1] * G[1, 0], 1e-12)
        s = N.T @ u
        lam = ca.vertcat(G[1, 1] * s[0] - G[0, 1] * s[1], G[0, 0] * s[1] - G[1, 0] * s[0]) / det
        u_mc = u - PN @ lam
        u_m, u_c = single(n_m), single(n_c)
        out_m = ca.logic_and(on_m, ca.dot(n_m, u) > 0)
        out_c = ca.logic_and(on_c, ca.dot(n_c, u) > 0)
        # the nearest point of the cone {n_i^T v <= 0, i active} in the P^-1 metric
        m_ok = ca.logic_and(out_m, ca.logic_not(ca.logic_and(on_c, ca.dot(n_c, u_m) > 0)))
        c_ok = ca.logic_and(out_c, ca.logic_not(ca.logic_and(on_m, ca.dot(n_m, u_c) > 0)))
        return ca.if_else(ca.logic_not(ca.logic_or(out_m, out_c)), u,
                          ca.if_else(m_ok, u_m, ca.if_else(c_ok, u_c, u_mc)))

    def expression(self, t: ca.SX, x: ca.SX, ref: ca.SX, c: ca.SX) -> tuple[ca.SX, ca.SX]:
        """The law (see the module docstring) as CasADi expressions.

        Parameters
        ----------
        t : casadi.SX
            Time (s), unused.
        x : casadi.SX
            State (12,) [m, rad, m/s, rad/s].
        ref : casadi.SX
            Reference row (14,).
        c : casadi.SX
            The controller state (``n_state``,), laid out as ``STATE_SLICES``.

        Returns
        -------
        U : casadi.SX
            Input (4x1) [U1 (N), U2, U3, U4 (N m)].
        c_dot : casadi.SX
            Its rate (``n_state`` x 1).
        """
        r_hat, m_hat, zeta = c[0:3], c[3], c[4:10]
        Psi = ca.reshape(c[10:34], 6, N_THETA)
        P = _unpack(c[34:44])
        clock = c[44]
        A, B_int = c[45:51], ca.reshape(c[51:75], 6, N_THETA)
        f_hat = c[75:75 + self.motor_states]
        U, e_s, Phi, B = self.parts(x, ref, m_hat, r_hat)
        U_a, U, f_hat_dot = believed_input(U, f_hat, self.vehicle, self.allocation,
                                           self.motor_states > 0)
        z, Y, zeta_dot, Psi_dot = self.filtered_regression(x, U_a, zeta, Psi)
        running = ca.if_else(clock < self.clock_stop, 1.0, 0.0)
        W_th, w = self.momentum_columns(x)
        Y0_th, k = self.gravity_coriolis_columns(x)
        # the start transient (module docstring): M nu(0) = (W_th + B_int) theta + w - A
        A_dot = running * (ca.DM(B_U) @ U_a - self.drag(x) - k)
        B_int_dot = running * Y0_th
        if self.start_compensation:
            decay = self.filter_rate * ca.exp(-self.filter_rate * clock)
            Y, z = Y - decay * (W_th + B_int), z + decay * (w - A)
        Sp, Sr = ca.DM(self.parameter_scale), ca.DM(self.row_scale)
        Y_n = (Sr * Y) @ ca.diag(Sp)
        z_n = Sr * z
        th = ca.vertcat(m_hat, m_hat * r_hat) / Sp
        G = ca.if_else(clock >= self.warm_up, 1.0, 0.0) * ca.DM(np.diag(self.row_weight))
        tau = -Y_n.T @ (G @ (Y_n @ th - z_n))
        if self.gamma > 0:
            kappa = self.gamma / self.covariance_bound
            tau -= kappa * Sp * (Phi.T @ (B.T @ (ca.DM(self.P) @ e_s)))
        th_dot = self.projected_update(th, P @ tau, P)
        m_dot = Sp[0] * th_dot[0]
        h_dot = Sp[1:4] * th_dot[1:4]
        r_dot = (h_dot - r_hat * m_dot) / m_hat
        k0 = self.covariance_bound
        P_dot = self.forgetting * P @ (ca.DM.eye(N_THETA) - P / k0) - P @ Y_n.T @ G @ Y_n @ P
        c_dot = ca.vertcat(r_dot, m_dot, zeta_dot, ca.vec(Psi_dot), _pack(P_dot),
                           running, A_dot, ca.vec(B_int_dot), f_hat_dot)
        return U, c_dot

    def _limits(self) -> tuple[float, float, float]:
        lo, hi = self.mass_bounds * self.vehicle.m
        return float(lo), float(hi), 1.0 - self.consistency_margin

    def project(self, c: ca.SX) -> ca.SX:
        """Map (m_hat, r_hat) back into K after a discrete step; the rest unchanged.

        Parameters
        ----------
        c : casadi.SX
            The controller state (``n_state``,).

        Returns
        -------
        casadi.SX
            The state with m_hat within the mass bounds and
            ``m_hat r_hat^T Sigma_O^-1 r_hat <= 1 - consistency_margin``.
        """
        lo, hi, keep = self._limits()
        m = ca.fmin(ca.fmax(c[3], lo), hi)
        r = c[0:3]
        q = m * ca.dot(r, ca.DM(self.sigma_inverse) @ r)
        r = ca.if_else(q > keep, r * ca.sqrt(keep / ca.fmax(q, 1e-300)), r)
        return ca.vertcat(r, m, c[4:])

    def project_numpy(self, c: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """``project`` for numpy arrays, in place.

        Parameters
        ----------
        c : (n_state,) numpy.ndarray
            The controller state.

        Returns
        -------
        (n_state,) numpy.ndarray
            ``c``, with (m_hat, r_hat) mapped into K in place.
        """
        lo, hi, keep = self._limits()
        c[3] = min(max(c[3], lo), hi)
        q = c[3] * c[0:3] @ self.sigma_inverse @ c[0:3]
        if q > keep:
            c[0:3] *= np.sqrt(keep / q)
        return c

    def estimate_of(self, c: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The CoG estimate in controller states.

        Parameters
        ----------
        c : (..., n_state) array_like
            Controller states.

        Returns
        -------
        (..., 3) numpy.ndarray
            r_hat (m), a view.
        """
        return np.asarray(c)[..., 0:3]

    def mass_of(self, c: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The mass estimate in controller states.

        Parameters
        ----------
        c : (..., n_state) array_like
            Controller states.

        Returns
        -------
        (...,) numpy.ndarray
            m_hat (kg).
        """
        return np.asarray(c)[..., 3]

    def inertial_parameters_of(self, c: Sequence[float] | npt.NDArray[np.float64]
                               ) -> npt.NDArray[np.float64]:
        """The ten inertial parameters the law believes: [m_hat, m_hat r_hat, I_O held].

        Parameters
        ----------
        c : (n_state,) array_like
            A controller state.

        Returns
        -------
        (10,) numpy.ndarray
            pi (kg, kg m, kg m^2), for ``quadcog.model.inertial_parameters``.
        """
        c = np.asarray(c, dtype=float)
        return np.r_[c[3], c[3] * c[0:3], self.inertia]
