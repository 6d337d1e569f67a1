"""Diagnostic variants of the adaptive controller, used to explain the Lyapunov function.

OutputRegulationAdaptive: no outer position loop; the outputs [z, phi, theta, psi] are
    regulated to [z_ref, 0, 0, psi_ref], so the reference of the error model is exact
    (constant at hover) and the paper's error equation e_s_dot = A e_s + B Phi r_tilde holds
    without neglected reference derivatives. x and y are then free (the zero dynamics).
OracleB (mixin): the update law uses B = [0; H M(r_G)^{-1}] at the TRUE CoG instead of the
    estimate's M_hat. Not implementable (it needs r_G); it isolates the one approximation the
    law itself makes (docs/model.md sec. 3.2: "use M_hat in the law"), because the exact error
    model is e_s_dot = A e_s + B(M) Phi(nu, eta, nu_dot_star) r_tilde with the true M.
"""
from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np

from quadcog.controllers import AdaptiveFeedbackLinearization
from quadcog.controllers.shaping import kinematics, wrap_angle
from quadcog.trajectories.analytic import ACC, POS, VEL, YAW, YAW_RATE

__all__ = ["OutputRegulationAdaptive", "OracleBMixin", "OracleAdaptive",
           "OracleOutputRegulationAdaptive"]


class OutputRegulationAdaptive(AdaptiveFeedbackLinearization):
    """Adaptive FL regulating y = [z, phi, theta, psi] to [z_ref, 0, 0, psi_ref] (no position
    loop). Arguments as AdaptiveFeedbackLinearization.

    Parameters
    ----------
    vehicle : quadcog.Vehicle, optional
        The vehicle the law is designed for (default: the Hummingbird).
    model : quadcog.model.functions.Model, optional
        The generated model (default ``quadcog.load()``).
    gamma : float or (3,) sequence of float
        Adaptation gain (the diagonal of Gamma).
    Q : (8, 8) array_like, optional
        The positive definite matrix of the Lyapunov equation (default identity).
    projection_radius : float or str or None
        Keep |r_hat| <= this radius [m] by projection ('default': as
        AdaptiveFeedbackLinearization; None: no projection).
    **kwargs
        Other arguments as FeedbackLinearization.
    """

    name = "adaptive_output_regulation"

    def output_errors(self, x: ca.SX, ref: ca.SX, p: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
        """The output errors with phi_d = theta_d = 0.

        Parameters
        ----------
        x : casadi.SX
            (12,) state [m, rad, m/s, rad/s].
        ref : casadi.SX
            (14,) reference (``quadcog.trajectories.analytic``).
        p : casadi.SX
            (14,) parameters.

        Returns
        -------
        tuple of casadi.SX
            (e, e_dot, y_ddot_d), each 4x1 (m, rad; per s; per s^2).
        """
        _, y_dot = kinematics(self.model, x, p)
        e = ca.vertcat(x[2] - ref[POS][2], x[3], x[4], wrap_angle(x[5] - ref[YAW]))
        y_dot_d = ca.vertcat(ref[VEL][2], 0, 0, ref[YAW_RATE])
        return e, y_dot - y_dot_d, ca.vertcat(ref[ACC][2], 0, 0, 0)


class OracleBMixin:
    """Update law with B at the true CoG of a single step. Use as the first base of a
    controller class.

    Parameters
    ----------
    *args
        The controller's positional arguments.
    t_step : float
        Time of the CoG step [s].
    r_after : (3,) sequence of float
        The CoG from ``t_step`` on [m].
    r_before : (3,) sequence of float
        The CoG before ``t_step`` [m].
    **kwargs
        The controller's keyword arguments.
    """

    def __init__(self, *args: Any, t_step: float = 1.0,
                 r_after: Sequence[float] = (0.0, 0.0, 0.0),
                 r_before: Sequence[float] = (0.0, 0.0, 0.0), **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.t_step = float(t_step)
        self.r_after = np.asarray(r_after, dtype=float)
        self.r_before = np.asarray(r_before, dtype=float)
        self._t_sym: ca.SX | None = None

    def expression(self, t: ca.SX, x: ca.SX, ref: ca.SX, c: ca.SX) -> Any:
        """As the base class; t is kept so that ``parts`` can pick the true CoG.

        Parameters
        ----------
        t : casadi.SX
            Time [s].
        x : casadi.SX
            (12,) state [m, rad, m/s, rad/s].
        ref : casadi.SX
            (14,) reference.
        c : casadi.SX
            Controller state.

        Returns
        -------
        Any
            What the base class's ``expression`` returns: (U, c_dot).
        """
        self._t_sym = t
        try:
            # a mixin: the controller class after it in the MRO defines expression
            return super().expression(t, x, ref, c)  # type: ignore[misc]
        finally:
            self._t_sym = None

    def parts(self, x: ca.SX, ref: ca.SX, r_hat: ca.SX) -> tuple[Any, Any, Any, Any]:
        """As the base class, but inside the control law B is taken at the true CoG.

        Parameters
        ----------
        x : casadi.SX
            (12,) state [m, rad, m/s, rad/s].
        ref : casadi.SX
            (14,) reference.
        r_hat : casadi.SX
            (3,) CoG estimate [m].

        Returns
        -------
        tuple
            (U, e_s, Phi, B) as the base class, B at the true CoG while ``expression`` runs.
        """
        # a mixin: the controller class after it in the MRO defines parts
        U, e_s, Phi, B = super().parts(x, ref, r_hat)  # type: ignore[misc]
        if self._t_sym is None:
            return U, e_s, Phi, B
        r_true = ca.if_else(self._t_sym >= self.t_step, ca.DM(self.r_after), ca.DM(self.r_before))
        return U, e_s, Phi, super().parts(x, ref, r_true)[3]  # type: ignore[misc]  # as above


class OracleAdaptive(OracleBMixin, AdaptiveFeedbackLinearization):
    """The paper's adaptive FL (with the position loop), update law with the true-CoG B.

    Parameters
    ----------
    *args
        The controller's positional arguments (vehicle, model).
    t_step : float
        Time of the CoG step [s].
    r_after : (3,) sequence of float
        The true CoG from ``t_step`` on [m].
    r_before : (3,) sequence of float
        The true CoG before ``t_step`` [m].
    **kwargs
        The controller's keyword arguments (as AdaptiveFeedbackLinearization).
    """
    name = "adaptive_oracle_B"


class OracleOutputRegulationAdaptive(OracleBMixin, OutputRegulationAdaptive):
    """Output regulation (no position loop), update law with the true-CoG B: the case in which
    the Lyapunov argument of docs/model.md sec. 3.2 holds exactly in continuous time.

    Parameters
    ----------
    *args
        The controller's positional arguments (vehicle, model).
    t_step : float
        Time of the CoG step [s].
    r_after : (3,) sequence of float
        The true CoG from ``t_step`` on [m].
    r_before : (3,) sequence of float
        The true CoG before ``t_step`` [m].
    **kwargs
        The controller's keyword arguments (as AdaptiveFeedbackLinearization).
    """
    name = "adaptive_output_regulation_oracle_B"
