"""Adaptive feedback linearization (paper sec. 3.3, docs/model.md sec. 3.2).

The feedback-linearizing law runs on the estimate r_hat: U solves alpha_hat U + b_hat = v.
With nu_dot_star = M_hat^{-1} (B_u U - n_hat), the output error e_s = [e; e_dot] obeys
e_s_dot = A e_s + B Phi(nu, eta, nu_dot_star) (r_hat - r), B = [0; H M^{-1}], and
r_hat_dot = -Gamma Phi^T B^T P e_s with A^T P + P A = -Q (M_hat in place of M).
An optional projection keeps r_hat inside a ball (the radial part of the update is removed on
the sphere, and each discrete update is scaled back onto it); without it this is the paper's law.
"""
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.controllers.decoupling import decoupled_input, linearizing_terms
from quadcog.controllers.design import admissible_estimate_radius, design, setting
from quadcog.controllers.feedback_linearization import FeedbackLinearization
from quadcog.errors import InputError
from quadcog.kinds import NumberOrNone, NumberOrVec3
from quadcog.model.conventions import B_U
from quadcog.model.functions import Model
from quadcog.model.parameters import LARGEST
from quadcog.numerics import exact_lyapunov
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["AdaptiveFeedbackLinearization", "admissible_estimate_radius"]


class AdaptiveFeedbackLinearization(FeedbackLinearization):
    """Feedback linearization with an online estimate r_hat (m) of the CoG offset.

    Parameters
    ----------
    vehicle : Vehicle, optional
        The controller's model of the vehicle (default: the Hummingbird with r_G = 0); r_hat
        starts at its r_G.
    model : quadcog.model.functions.Model, optional
        The generated functions (default ``quadcog.load()``).
    gamma : float or (3,) sequence of float, optional
        Adaptation gain, a number or 3 numbers (diagonal of Gamma). Default: from the vehicle
        (``quadcog.controllers.design.adaptation_gain``: the same dimensionless learning rate
        on every vehicle). On the Hummingbird after a [6, 6, 0] cm step at hover, 0.01
        recovers with estimates within 1 %, larger gains oscillate with larger tails and
        0.003 is too slow to recover (measured: docs/tour/simulate.md, "Choosing gamma").
    Q : (8, 8) array_like, optional
        The positive definite matrix of the Lyapunov equation (default identity).
    projection_radius : float or None or "default"
        Keep |r_hat| <= this radius (m) by projection. Default: from the vehicle, the arm
        length (``design.PROJECTION_ARM_FRACTION`` of it), but never
        beyond 95 % of sqrt(min(Ixx, Iyy, Izz) / m), inside which every estimate keeps M_hat
        positive definite (9.6 cm for the default vehicle; beyond it M_hat turns singular and
        the law blows up). None switches projection off: the paper's law.
    **kwargs
        The other arguments, as FeedbackLinearization (its poles and ``max_tilt``).

    Raises
    ------
    InputError
        When a setting is out of range (gamma not positive, Q not symmetric positive
        definite, a radius not positive).
    """

    name = "adaptive_feedback_linearization"
    n_state = 3
    estimates_cog = True          # c starts with r_hat (results report it as the estimate)
    projection_radius: float | None

    def __init__(self, vehicle: Vehicle | None = None, model: Model | None = None, *,
                 gamma: NumberOrVec3 | None = None, Q: npt.ArrayLike | None = None,
                 projection_radius: NumberOrNone = "default", **kwargs: Any) -> None:
        super().__init__(vehicle, model, **kwargs)
        if gamma is None:                   # from the vehicle (quadcog.controllers.design)
            gamma = design(self.vehicle).gamma
        what = "a positive number or 3 positive numbers (the diagonal of Gamma)"
        if isinstance(gamma, (list, tuple, np.ndarray)):
            gains = validate.array(gamma, "gamma", (3,), what=what)
        else:
            gains = np.full(3, validate.positive(gamma, "gamma"))
        if not np.all((gains > 0) & (gains <= LARGEST)):
            validate.fail("gamma", what + f" up to {LARGEST:g}", gains.tolist())
        self.gamma = gains
        Q = np.eye(8) if Q is None else validate.array(Q, "Q", (8, 8))
        if not (np.allclose(Q, Q.T) and np.linalg.eigvalsh(0.5 * (Q + Q.T))[0] > 0):
            raise InputError(f"Q: expected a symmetric positive definite 8x8 matrix, got one "
                             f"with smallest eigenvalue "
                             f"{validate.plain(np.linalg.eigvalsh(0.5 * (Q + Q.T))[0])}")
        self.Q = Q
        if isinstance(projection_radius, str) and projection_radius == "default":
            projection_radius = design(self.vehicle).projection_radius
        elif projection_radius is not None:
            projection_radius = setting(projection_radius, "projection_radius", "m")
        # a str other than "default" was refused by validate.positive above
        self.projection_radius = projection_radius
        self.A_error = np.block([[np.zeros((4, 4)), np.eye(4)],
                                 [-np.diag(self.kp), -np.diag(self.kd)]])
        self.P = exact_lyapunov(self.A_error, Q, "A_error")   # the same bits everywhere

    def initial_state(self) -> npt.NDArray[np.float64]:
        """r_hat at t = 0: the CoG of the controller's model (zero unless it believes one).

        Returns
        -------
        (3,) numpy.ndarray
            r_hat (m).
        """
        return self.vehicle.r_G

    def parts(self, x: ca.SX, ref: ca.SX,
              r_hat: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
        """The law at estimate r_hat and the pieces of the update.

        Parameters
        ----------
        x : casadi.SX
            State (12,) [m, rad, m/s, rad/s].
        ref : casadi.SX
            Reference row (14,).
        r_hat : casadi.SX
            The CoG estimate (3,) (m).

        Returns
        -------
        U : casadi.SX
            Input (4x1) [U1 (N), U2, U3, U4 (N m)] of the feedback linearization on r_hat.
        e_s : casadi.SX
            Output error [e; e_dot] (8,).
        Phi : casadi.SX
            Regressor (6x3) of the equations of motion in r at nu_dot_star.
        B : casadi.SX
            [0; H M_hat^{-1}] (8x6).
        """
        p_hat = self.nominal_with_cog(r_hat)
        e, e_dot, y_ddot_d = self.output_errors(x, ref, p_hat)
        v = self.commanded_acceleration(e, e_dot, y_ddot_d)
        # alpha_hat and b_hat from M_hat^-1, n_hat and H M_hat^-1, which the update needs too
        lin = linearizing_terms(self.model, x, p_hat)
        U = decoupled_input(lin.alpha, v - lin.b)
        nu_dot_star = lin.M_inv @ (ca.DM(B_U) @ U - lin.n)
        Phi = self.model.casadi_function("regressor")(x, nu_dot_star, p_hat)
        B = ca.vertcat(ca.SX.zeros(4, 6), lin.HM)
        return U, ca.vertcat(e, e_dot), Phi, B

    def expression(self, t: ca.SX, x: ca.SX, ref: ca.SX, c: ca.SX) -> tuple[ca.SX, ca.SX]:
        """The adaptive law (see the module docstring) as CasADi expressions.

        Parameters
        ----------
        t : casadi.SX
            Time (s), unused.
        x : casadi.SX
            State (12,) [m, rad, m/s, rad/s].
        ref : casadi.SX
            Reference row (14,).
        c : casadi.SX
            The controller state: r_hat (3,) (m).

        Returns
        -------
        U : casadi.SX
            Input (4x1) [U1 (N), U2, U3, U4 (N m)].
        c_dot : casadi.SX
            r_hat_dot (3x1) (m/s), with the radial part removed on the projection sphere.
        """
        U, e_s, Phi, B = self.parts(x, ref, c)
        r_dot = -ca.DM(self.gamma) * (Phi.T @ (B.T @ (ca.DM(self.P) @ e_s)))
        if self.projection_radius is not None:
            R2 = self.projection_radius ** 2
            outward = ca.dot(c, r_dot)
            radial = c * outward / ca.fmax(ca.dot(c, c), 1e-12)
            r_dot = ca.if_else(ca.logic_and(ca.dot(c, c) >= R2, outward > 0), r_dot - radial,
                               r_dot)
        return U, r_dot

    def project(self, c: ca.SX) -> ca.SX:
        """Scale r_hat back onto the ball after a discrete update step.

        Parameters
        ----------
        c : casadi.SX
            The controller state r_hat (3,) (m).

        Returns
        -------
        casadi.SX
            r_hat within ``projection_radius`` (unchanged when projection is off).
        """
        if self.projection_radius is None:
            return c
        norm = ca.norm_2(c)
        return ca.if_else(norm > self.projection_radius, c * (self.projection_radius / norm), c)

    def project_numpy(self, c: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """``project`` for numpy arrays, in place.

        Parameters
        ----------
        c : (3,) numpy.ndarray
            r_hat (m).

        Returns
        -------
        (3,) numpy.ndarray
            ``c``, scaled in place onto the ball when outside it.
        """
        if self.projection_radius is None:
            return c
        norm = np.sqrt(c @ c)
        if norm > self.projection_radius:
            c *= self.projection_radius / norm
        return c
