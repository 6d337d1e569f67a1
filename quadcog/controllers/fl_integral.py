"""Feedback linearization with integral action on the attitude errors: the baseline a
practitioner would try first against a CoG offset.

A CoG offset leaves the nominal feedback linearization with a nearly constant moment it does
not know about (docs/model.md sec. 3.3: ``m g [y_G, -x_G]`` at hover), which shows as a
standing attitude error. An integrator on the phi, theta and psi errors removes a constant
one: v = y_ddot_d - Kp e - Kd e_dot - Ki integral(e) on those rows. Each row's three poles are
its two feedback-linearization poles and ``integral_pole``, placed exactly:
(s^2 + kd s + kp)(s - a) = s^3 + (kd - a) s^2 + (kp - a kd) s - a kp.
The integrator states are clipped to +-``integral_limit`` (rad s) after every update, so they
cannot wind up without bound while the rotors saturate.

Controller state c (3): the integrals of the phi, theta and psi errors (rad s).
"""
from typing import Any

import casadi as ca
import numpy as np

from quadcog import validate
from quadcog.controllers.feedback_linearization import FeedbackLinearization
from quadcog.kinds import Number
from quadcog.model.functions import Model
from quadcog.vehicles.vehicle import Vehicle

ATTITUDE_ROWS = slice(1, 4)          # phi, theta, psi in y = [z, phi, theta, psi]


class FeedbackLinearizationIntegral(FeedbackLinearization):
    """Feedback linearization with an integrator on the attitude errors.

    Parameters
    ----------
    vehicle, model : as every controller.
    integral_pole : the third pole (1/s, negative) of each attitude row, default -4.
    integral_limit : clip of each integrator state (rad s), default 1.
    The other keywords are FeedbackLinearization's (its attitude and yaw poles stay poles of
    the new rows).
    """

    name = "feedback_linearization_integral"
    n_state = 3

    def __init__(self, vehicle: Vehicle | None = None, model: Model | None = None, *,
                 integral_pole: Number = -4.0, integral_limit: Number = 1.0,
                 **kwargs: Any) -> None:
        super().__init__(vehicle, model, **kwargs)
        a = validate.real(integral_pole, "integral_pole", hi=0.0, hi_open=True, unit="1/s")
        limit = validate.positive(integral_limit, "integral_limit", "rad s")
        self.integral_pole, self.integral_limit = a, limit
        kp, kd = self.kp[ATTITUDE_ROWS].copy(), self.kd[ATTITUDE_ROWS].copy()
        self.kp[ATTITUDE_ROWS] = kp - a * kd
        self.kd[ATTITUDE_ROWS] = kd - a
        self.ki = -a * kp

    def expression(self, t, x, ref, c):
        p = ca.DM(self.nominal)
        e, e_dot, y_ddot_d = self.output_errors(x, ref, p)
        v = self.commanded_acceleration(e, e_dot, y_ddot_d)
        v = v - ca.vertcat(0, ca.DM(self.ki) * c)
        alpha = self.model.casadi_function("decoupling")(x, p)
        b = self.model.casadi_function("drift")(x, p)
        return ca.solve(alpha, v - b), e[ATTITUDE_ROWS]

    def project(self, c):
        """Clip the integrators to +-integral_limit (SX)."""
        return ca.fmin(ca.fmax(c, -self.integral_limit), self.integral_limit)

    def project_numpy(self, c):
        np.clip(c, -self.integral_limit, self.integral_limit, out=c)
        return c
