"""Composite adaptive feedback linearization: the paper's law plus a prediction-error term.

The feedback linearization runs on the estimate r_hat as in the paper's law (``adaptive.py``).
The estimate learns from two errors:

- the output tracking error e_s, as the paper: the term -Phi^T B^T P_L e_s;
- the prediction error of the equations of motion ``M(r) nu_dot + n(nu, eta, r) = B_u U``,
  which are linear in r: ``B_u U - n(nu, eta, 0) - M(0) nu_dot = Phi(nu, eta, nu_dot) r``
  (docs/model.md sec. 3.1). Both sides pass through the stable filter F(s) = lam / (s + lam);
  because ``M(r) nu_dot = d/dt (M(r) nu)`` and F[d/dt y] = lam y - lam F[y], no acceleration is
  needed:

      z = zeta - lam M_0 nu,          zeta_dot = lam (B_u U_a - n_0 + lam M_0 nu - zeta)
      Y = lam W(nu) + Psi,             Psi_dot = lam (Phi_0 - lam W(nu) - Psi)

  with n_0 = n(nu, eta, 0), Phi_0 = Phi(nu, eta, 0), W(nu) = Phi(nu, eta, nu) - Phi_0 (the
  part of the regressor that is M's dependence on r, applied to nu) and U_a the input the
  rotors deliver (the controller's own model of its motors, optional). Then z = Y r up to a
  term that decays as exp(-lam t) from the filter's initial state.

The gain is least squares with forgetting and a bounded covariance:

    r_hat_dot = P tau,  tau = -kappa Phi^T B^T P_L e_s - Y_n^T G (Y_n r_hat - z_n)
    P_dot = beta P (I - P / k0) - P Y_n^T G Y_n P,        P(0) = k0 I

Y_n, z_n are Y and z scaled to metres of CoG (moment rows by 1/(m g), force rows by
l/(m g), l the arm length), G = ls_gain * diag(force_weight (3), 1 (3)). P stays between a
positive lower bound and k0 I: in every direction the covariance forgets at rate beta, so the
estimate follows a CoG that keeps moving, and where the data do not excite a direction (z_G at
hover) P settles at k0 instead of growing without bound. kappa = gamma / k0, so at P = k0 I the
tracking term is the paper's law with gain gamma. With V = kappa e_s^T P_L e_s + r~^T P^-1 r~
(r~ = r_hat - r), the cross terms cancel and

    V_dot = -kappa e_s^T Q e_s - r~^T Y_n^T G Y_n r~ - beta r~^T (P^-1 - I / k0) r~ <= 0

for a constant r and the true M in B (the derived report gives the argument and its limits).
The projection onto the ball |r_hat| <= projection_radius is P-weighted so that it keeps V_dot
as it is.

Controller state c (``n_state``): r_hat (3), zeta (6), Psi (18, column-major 6x3), the six
entries of P (xx, xy, xz, yy, yz, zz), a clock (s since the start, it stops counting after
``warm_up``) and, with ``motor_lag``, the four rotor thrusts the
controller believes its rotors deliver (``motor_lag``). ``STATE_SLICES`` names them.
"""
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.controllers.adaptive import AdaptiveFeedbackLinearization
from quadcog.controllers.allocation import prioritized_input
from quadcog.controllers.design import design, setting
from quadcog.kinds import Flag, Number, NumberOrVec3
from quadcog.model.conventions import B_U, NU
from quadcog.model.functions import Model
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["CompositeAdaptive", "unpack_covariance", "pack_covariance", "believed_input"]

_P_INDEX = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))


def _positive(name, value):
    return setting(value, name)


def unpack_covariance(v: ca.SX | npt.NDArray[np.float64]) -> ca.SX | npt.NDArray[np.float64]:
    """The symmetric 3x3 P from its six entries.

    Parameters
    ----------
    v : casadi.SX or (6,) numpy.ndarray
        The entries (xx, xy, xz, yy, yz, zz).

    Returns
    -------
    casadi.SX or (3, 3) numpy.ndarray
        P, of the kind of ``v``.
    """
    if isinstance(v, np.ndarray):
        P = np.empty((3, 3))
        for k, (i, j) in enumerate(_P_INDEX):
            P[i, j] = P[j, i] = v[k]
        return P
    rows: list[list[Any]] = [[None] * 3 for _ in range(3)]
    for k, (i, j) in enumerate(_P_INDEX):
        rows[i][j] = rows[j][i] = v[k]
    return ca.vertcat(*[ca.horzcat(*row) for row in rows])


def pack_covariance(P: ca.SX) -> ca.SX:
    """The six entries of a symmetric 3x3 P.

    Parameters
    ----------
    P : casadi.SX
        A symmetric 3x3 matrix.

    Returns
    -------
    casadi.SX
        Its entries (xx, xy, xz, yy, yz, zz) (6x1).
    """
    return ca.vertcat(*[P[i, j] for i, j in _P_INDEX])


def believed_input(U: ca.SX, f_hat: ca.SX, vehicle: Vehicle, allocation: bool,
                   motor_lag: bool) -> tuple[ca.SX, ca.SX, ca.SX]:
    """The input a law commands and what it believes its rotors deliver (see
    ``CompositeAdaptive.delivered_input``; the payload law uses it too).

    Parameters
    ----------
    U : casadi.SX
        The law's input (4x1) [U1 (N), U2, U3, U4 (N m)].
    f_hat : casadi.SX
        The believed rotor thrusts (4,) (N), empty (0,) without ``motor_lag``.
    vehicle : Vehicle
        The controller's model (mixer, rotor limits, motor time constant).
    allocation : bool
        Reduce U to what the rotors can give, yaw first (``allocation.prioritized_input``).
    motor_lag : bool
        The rotor thrusts lag behind the command with the vehicle's motor time constant
        (which must then be > 0).

    Returns
    -------
    U_a : casadi.SX
        The input believed delivered (4x1).
    U_cmd : casadi.SX
        The commanded input (4x1).
    f_hat_dot : casadi.SX
        Rate of the believed rotor thrusts (N/s), empty without ``motor_lag``.
    """
    if allocation:
        U = prioritized_input(U, vehicle)
    if not motor_lag:
        return U, U, ca.SX(0, 1)
    f_cmd = ca.DM(vehicle.mixer_inverse()) @ U
    return ca.DM(vehicle.mixer()) @ f_hat, U, (f_cmd - f_hat) / vehicle.motor_time_constant


class CompositeAdaptive(AdaptiveFeedbackLinearization):
    """Composite adaptive feedback linearization (see the module docstring).

    Parameters
    ----------
    vehicle : Vehicle, optional
        The controller's model of the vehicle (r_G = 0 by default, and r_hat starts at the
        model's r_G).
    model : quadcog.model.functions.Model, optional
        The generated functions (default ``quadcog.load()``).
    gamma : float or (3,) sequence of float, optional
        Tracking-error gain at P = k0 I (the paper's Gamma). Default: from the vehicle, as
        AdaptiveFeedbackLinearization (0.01 for the Hummingbird).
    filter_rate : float, optional
        lam (1/s) of the filter F(s) = lam / (s + lam). Default: from the vehicle
        (``quadcog.controllers.design``), a quarter of the rotor bandwidth, at most twice the
        attitude rate (20 for the Hummingbird).
    ls_gain : float, optional
        The least-squares weight (1/s) of the normalized prediction error. Default: from the
        vehicle, 10 times its filter rate (200 for the Hummingbird).
    forgetting : float, optional
        beta (1/s): data older than a few 1/beta no longer count. Default: from the vehicle,
        its filter rate / 2.5 (8 for the Hummingbird).
    covariance_bound : float, optional
        k0 (dimensionless, in the normalized units). Default: from the vehicle, 1.
    force_weight : float
        Weight of the three force rows against the moment rows, default 1.
    allocation : bool
        True (default): the commanded input is reduced to what the rotors can give, yaw first
        (``allocation.prioritized_input``), so the filter knows what is delivered.
    motor_lag : bool
        True: the filter sees the rotor thrusts lagging behind the command with the vehicle's
        motor_time_constant (4 more states); False (default): the command itself.
    warm_up : float, optional
        Seconds from t = 0 during which the prediction error is not used (default
        5 / filter_rate): the filters start at rest, and while the vehicle starts moving (a
        trajectory that begins with a velocity) their start-up term exp(-lam t) would
        otherwise read as a CoG offset.
    **kwargs
        Q, projection_radius and the feedback-linearization poles, as
        AdaptiveFeedbackLinearization.

    Raises
    ------
    InputError
        When a setting is out of range.
    """

    name = "composite_adaptive"

    def __init__(self, vehicle: Vehicle | None = None, model: Model | None = None, *,
                 gamma: NumberOrVec3 | None = None, filter_rate: Number | None = None,
                 ls_gain: Number | None = None, forgetting: Number | None = None,
                 covariance_bound: Number | None = None, force_weight: Number = 1.0,
                 allocation: Flag = True, motor_lag: Flag = False,
                 warm_up: Number | None = None, **kwargs: Any) -> None:
        super().__init__(vehicle, model, gamma=gamma, **kwargs)
        d = design(self.vehicle)            # the settings not given follow from the vehicle
        self.filter_rate = _positive("filter_rate", d.filter_rate if filter_rate is None
                                     else filter_rate)
        self.ls_gain = _positive("ls_gain", d.ls_gain if ls_gain is None else ls_gain)
        self.forgetting = _positive("forgetting", d.forgetting if forgetting is None
                                    else forgetting)
        self.covariance_bound = _positive("covariance_bound", d.covariance_bound
                                          if covariance_bound is None else covariance_bound)
        self.force_weight = setting(force_weight, "force_weight", zero=True)
        self.warm_up = (5.0 / self.filter_rate if warm_up is None
                        else validate.nonnegative(warm_up, "warm_up", "s"))
        self.allocation = validate.flag(allocation, "allocation")
        self.motor_lag = validate.flag(motor_lag, "motor_lag")
        self.motor_states = 4 if (self.motor_lag and self.vehicle.motor_time_constant > 0) else 0
        self.n_state = 34 + self.motor_states
        v = self.vehicle
        mg = v.m * v.g
        self.row_scale = np.r_[[v.arm_length / mg] * 3, [1.0 / mg] * 3]
        self.row_weight = self.ls_gain * np.r_[[self.force_weight] * 3, [1.0] * 3]

    STATE_SLICES = {"r_hat": slice(0, 3), "zeta": slice(3, 9), "Psi": slice(9, 27),
                    "P": slice(27, 33), "clock": slice(33, 34), "rotor_thrusts": slice(34, 38)}

    def initial_state(self) -> npt.NDArray[np.float64]:
        """The controller state at t = 0.

        Returns
        -------
        (n_state,) numpy.ndarray
            r_hat = the model's r_G (m), filters at rest, P = k0 I, clock 0 s, believed rotor
            thrusts at the model's hover (N).
        """
        c = np.zeros(self.n_state)
        c[0:3] = self.vehicle.r_G
        c[27:33] = self.covariance_bound * np.array([1, 0, 0, 1, 0, 1.0])
        if self.motor_states:
            c[34:38] = self.vehicle.rotor_thrusts(self.vehicle.hover_input())
        return c

    def delivered_input(self, U: ca.SX, f_hat: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
        """The input the law commands and what the controller believes its rotors deliver.

        Parameters
        ----------
        U : casadi.SX
            The law's input (4x1) [U1 (N), U2, U3, U4 (N m)].
        f_hat : casadi.SX
            The believed rotor thrusts (4,) (N), empty (0,) without ``motor_lag``.

        Returns
        -------
        U_a : casadi.SX
            The input believed delivered (4x1): the command, or with ``motor_lag`` the one of
            the rotor thrusts lagging behind it.
        U_cmd : casadi.SX
            The commanded input (4x1), after yaw-last allocation within the rotor limits when
            ``allocation``.
        f_hat_dot : casadi.SX
            Rate of the believed rotor thrusts (N/s), empty without ``motor_lag``.
        """
        return believed_input(U, f_hat, self.vehicle, self.allocation, self.motor_states > 0)

    def filtered_regression(self, x: ca.SX, U_a: ca.SX, zeta: ca.SX,
                            Psi: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
        """The filtered identity z = Y r of the module docstring.

        Parameters
        ----------
        x : casadi.SX
            State (12,) [m, rad, m/s, rad/s].
        U_a : casadi.SX
            The input believed delivered (4x1) [N, N m, N m, N m].
        zeta : casadi.SX
            The filter state of z (6,).
        Psi : casadi.SX
            The filter state of Y (6x3).

        Returns
        -------
        z : casadi.SX
            Filtered left-hand side (6,) [N, N m].
        Y : casadi.SX
            Filtered regressor (6x3) [N/m, N].
        zeta_dot : casadi.SX
            Rate of zeta (6,).
        Psi_dot : casadi.SX
            Rate of Psi (6x3).
        """
        f = self.model.casadi_function
        lam = self.filter_rate
        p0 = self.nominal_with_cog(ca.SX.zeros(3))
        nu = x[NU]
        M0 = f("mass_matrix")(p0)
        n0 = f("coriolis")(x, p0) @ nu + f("damping")(p0) @ nu + f("gravity")(x, p0)
        Phi0 = f("regressor")(x, ca.SX.zeros(6), p0)
        W = f("regressor")(x, nu, p0) - Phi0
        zeta_dot = lam * (ca.DM(B_U) @ U_a - n0 + lam * M0 @ nu - zeta)
        Psi_dot = lam * (Phi0 - lam * W - Psi)
        return zeta - lam * M0 @ nu, lam * W + Psi, zeta_dot, Psi_dot

    def expression(self, t: ca.SX, x: ca.SX, ref: ca.SX, c: ca.SX) -> tuple[ca.SX, ca.SX]:
        """The composite adaptive law (see the module docstring).

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
        r_hat, zeta = c[0:3], c[3:9]
        Psi = ca.reshape(c[9:27], 6, 3)
        P = unpack_covariance(c[27:33])
        f_hat = c[34:34 + self.motor_states]
        U, e_s, Phi, B = self.parts(x, ref, r_hat)
        U_a, U, f_hat_dot = self.delivered_input(U, f_hat)
        z, Y, zeta_dot, Psi_dot = self.filtered_regression(x, U_a, zeta, Psi)
        S = ca.DM(self.row_scale)
        # the filters start at rest, so z - Y r starts at -lam M nu(0) and decays as
        # exp(-lam t): learn from the prediction error only once that has died out
        # (a clock state rather than t: the exported step does not take the time)
        clock = c[33]
        G = ca.if_else(clock >= self.warm_up, 1.0, 0.0) * ca.DM(np.diag(self.row_weight))
        Y_n, z_n = S * Y, S * z                       # rows scaled to metres of CoG
        kappa = ca.DM(self.gamma / self.covariance_bound)
        tau = -kappa * (Phi.T @ (B.T @ (ca.DM(self.P) @ e_s))) - Y_n.T @ (G @ (Y_n @ r_hat - z_n))
        r_dot = P @ tau
        if self.projection_radius is not None:
            # P-weighted projection: remove the outward part along P r_hat on the sphere
            outward = ca.dot(r_hat, r_dot)
            Pr = P @ r_hat
            on_rim = ca.logic_and(ca.dot(r_hat, r_hat) >= self.projection_radius ** 2,
                                  outward > 0)
            r_dot = ca.if_else(on_rim, r_dot - Pr * outward / ca.fmax(ca.dot(r_hat, Pr), 1e-12),
                               r_dot)
        k0 = self.covariance_bound
        P_dot = (self.forgetting * P @ (ca.DM.eye(3) - P / k0)
                 - P @ Y_n.T @ G @ Y_n @ P)
        c_dot = ca.vertcat(r_dot, zeta_dot, ca.vec(Psi_dot), pack_covariance(P_dot),
                           ca.fmin(1.0, ca.fmax(0.0, self.warm_up + 1.0 - clock)), f_hat_dot)
        return U, c_dot

    def project(self, c: ca.SX) -> ca.SX:
        """Scale r_hat back onto the ball after a discrete step; the rest unchanged.

        Parameters
        ----------
        c : casadi.SX
            The controller state (``n_state``,).

        Returns
        -------
        casadi.SX
            The state with r_hat within ``projection_radius``.
        """
        if self.projection_radius is None:
            return c
        return ca.vertcat(super().project(c[0:3]), c[3:])

    def project_numpy(self, c: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """``project`` for numpy arrays, in place.

        Parameters
        ----------
        c : (n_state,) numpy.ndarray
            The controller state.

        Returns
        -------
        (n_state,) numpy.ndarray
            ``c``, with r_hat scaled in place onto the ball when outside it.
        """
        if self.projection_radius is not None:
            super().project_numpy(c[0:3])       # c[0:3] is a view: scaled in place
        return c

    def estimate_of(self, c: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The CoG estimate in a controller state.

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
