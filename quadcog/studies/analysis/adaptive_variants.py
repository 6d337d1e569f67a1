"""Diagnostic variants of the adaptive controller, used to explain the Lyapunov function.

OutputRegulationAdaptive: no outer position loop; the outputs [z, phi, theta, psi] are
    regulated to [z_ref, 0, 0, psi_ref], so the reference of the error model is exact
    (constant at hover) and the paper's error equation e_s_dot = A e_s + B Phi r_tilde holds
    without neglected reference derivatives. x and y are then free (the zero dynamics).
OracleB (mixin): the update law uses B = [0; H M(r_G)^{-1}] at the TRUE CoG instead of the
    estimate's M_hat. Not implementable (it needs r_G); it isolates the one approximation the
    law itself makes (docs/model.md sec. 3.2: "use M_hat in the law"), because the exact error model
    is e_s_dot = A e_s + B(M) Phi(nu, eta, nu_dot_star) r_tilde with the true M.
"""
import casadi as ca
import numpy as np

from quadcog.controllers import AdaptiveFeedbackLinearization
from quadcog.controllers.shaping import kinematics, wrap_angle
from quadcog.trajectories.analytic import ACC, POS, VEL, YAW, YAW_RATE


class OutputRegulationAdaptive(AdaptiveFeedbackLinearization):
    """Adaptive FL regulating y = [z, phi, theta, psi] to [z_ref, 0, 0, psi_ref] (no position
    loop). Arguments as AdaptiveFeedbackLinearization."""

    name = "adaptive_output_regulation"

    def output_errors(self, x, ref, p):
        """(e, e_dot, y_ddot_d), each 4x1 SX, with phi_d = theta_d = 0 (m, rad; per s; per s^2)."""
        _, y_dot = kinematics(self.model, x, p)
        e = ca.vertcat(x[2] - ref[POS][2], x[3], x[4], wrap_angle(x[5] - ref[YAW]))
        y_dot_d = ca.vertcat(ref[VEL][2], 0, 0, ref[YAW_RATE])
        return e, y_dot - y_dot_d, ca.vertcat(ref[ACC][2], 0, 0, 0)


class OracleBMixin:
    """Update law with B at the true CoG of a single step: r_G = r_before for t < t_step,
    r_after from t_step on (s, m). Use as the first base of a controller class."""

    def __init__(self, *args, t_step=1.0, r_after=(0.0, 0.0, 0.0), r_before=(0.0, 0.0, 0.0),
                 **kwargs):
        super().__init__(*args, **kwargs)
        self.t_step = float(t_step)
        self.r_after = np.asarray(r_after, dtype=float)
        self.r_before = np.asarray(r_before, dtype=float)
        self._t_sym = None

    def expression(self, t, x, ref, c):
        """As the base class; t (SX, s) is kept so that ``parts`` can pick the true CoG."""
        self._t_sym = t
        try:
            return super().expression(t, x, ref, c)
        finally:
            self._t_sym = None

    def parts(self, x, ref, r_hat):
        """As the base class, but inside the control law B is taken at the true CoG."""
        U, e_s, Phi, B = super().parts(x, ref, r_hat)
        if self._t_sym is None:
            return U, e_s, Phi, B
        r_true = ca.if_else(self._t_sym >= self.t_step, ca.DM(self.r_after), ca.DM(self.r_before))
        return U, e_s, Phi, super().parts(x, ref, r_true)[3]


class OracleAdaptive(OracleBMixin, AdaptiveFeedbackLinearization):
    """The paper's adaptive FL (with the position loop), update law with the true-CoG B."""
    name = "adaptive_oracle_B"


class OracleOutputRegulationAdaptive(OracleBMixin, OutputRegulationAdaptive):
    """Output regulation (no position loop), update law with the true-CoG B: the case in which
    the Lyapunov argument of docs/model.md sec. 3.2 holds exactly in continuous time."""
    name = "adaptive_output_regulation_oracle_B"
