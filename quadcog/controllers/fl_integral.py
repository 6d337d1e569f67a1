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
import numpy.typing as npt

from quadcog import validate
from quadcog.controllers.decoupling import decoupled_input
from quadcog.controllers.design import design, setting
from quadcog.controllers.feedback_linearization import FeedbackLinearization
from quadcog.kinds import Number
from quadcog.model.functions import Model
from quadcog.model.parameters import LARGEST
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["FeedbackLinearizationIntegral", "ATTITUDE_ROWS"]

ATTITUDE_ROWS = slice(1, 4)          # phi, theta, psi in y = [z, phi, theta, psi]


class FeedbackLinearizationIntegral(FeedbackLinearization):
    """Feedback linearization with an integrator on the attitude errors.

    Parameters
    ----------
    vehicle : Vehicle, optional
        The controller's model of the vehicle (default: the Hummingbird with r_G = 0).
    model : quadcog.model.functions.Model, optional
        The generated functions (default ``quadcog.load()``).
    integral_pole : float, optional
        The third pole (1/s, negative) of each attitude row. Default: from the vehicle
        (``quadcog.controllers.design``; -4 for the Hummingbird).
    integral_limit : float, optional
        Clip of each integrator state (rad s), > 0. Default: from the vehicle (1 for the
        Hummingbird).
    **kwargs
        FeedbackLinearization's keywords (its attitude and yaw poles stay poles of the new
        rows).

    Raises
    ------
    InputError
        When a setting is out of range.
    """

    name = "feedback_linearization_integral"
    n_state = 3

    def __init__(self, vehicle: Vehicle | None = None, model: Model | None = None, *,
                 integral_pole: Number | None = None, integral_limit: Number | None = None,
                 **kwargs: Any) -> None:
        super().__init__(vehicle, model, **kwargs)
        d = design(self.vehicle)            # the settings not given follow from the vehicle
        integral_pole = d.integral_pole if integral_pole is None else integral_pole
        integral_limit = d.integral_limit if integral_limit is None else integral_limit
        a = validate.real(integral_pole, "integral_pole", lo=-LARGEST, hi=0.0, hi_open=True,
                          unit="1/s")
        limit = setting(integral_limit, "integral_limit", "rad s")
        self.integral_pole, self.integral_limit = a, limit
        kp, kd = self.kp[ATTITUDE_ROWS].copy(), self.kd[ATTITUDE_ROWS].copy()
        self.kp[ATTITUDE_ROWS] = kp - a * kd
        self.kd[ATTITUDE_ROWS] = kd - a
        self.ki = -a * kp

    def expression(self, t: ca.SX, x: ca.SX, ref: ca.SX, c: ca.SX) -> tuple[ca.SX, ca.SX]:
        """Feedback linearization with the integrators on the attitude rows.

        Parameters
        ----------
        t : casadi.SX
            Time (s), unused.
        x : casadi.SX
            State (12,) [m, rad, m/s, rad/s].
        ref : casadi.SX
            Reference row (14,).
        c : casadi.SX
            The integrals of the phi, theta, psi errors (3,) (rad s).

        Returns
        -------
        U : casadi.SX
            Input (4x1) [U1 (N), U2, U3, U4 (N m)].
        c_dot : casadi.SX
            The phi, theta, psi errors (3x1) (rad).
        """
        p = ca.DM(self.nominal)
        e, e_dot, y_ddot_d = self.output_errors(x, ref, p)
        v = self.commanded_acceleration(e, e_dot, y_ddot_d)
        v = v - ca.vertcat(0, ca.DM(self.ki) * c)
        alpha = self.model.casadi_function("decoupling")(x, p)
        b = self.model.casadi_function("drift")(x, p)
        return decoupled_input(alpha, v - b), e[ATTITUDE_ROWS]

    def project(self, c: ca.SX) -> ca.SX:
        """Clip the integrators to +-integral_limit.

        Parameters
        ----------
        c : casadi.SX
            The integrator states (3,) (rad s).

        Returns
        -------
        casadi.SX
            The states clipped to +-``integral_limit``.
        """
        return ca.fmin(ca.fmax(c, -self.integral_limit), self.integral_limit)

    def project_numpy(self, c: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """``project`` for numpy arrays, in place.

        Parameters
        ----------
        c : (3,) numpy.ndarray
            The integrator states (rad s).

        Returns
        -------
        (3,) numpy.ndarray
            ``c``, clipped in place to +-``integral_limit``.
        """
        np.clip(c, -self.integral_limit, self.integral_limit, out=c)
        return c
