"""Input-output feedback linearization (paper sec. 3.2): U = alpha^{-1} (v - b) with alpha and
b from the generated Lie derivatives at the nominal r_G, v from PD on the output errors of
y = [z, phi, theta, psi], and an outer position loop that commands phi and theta."""
import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog.controllers.base import Controller
from quadcog.controllers.decoupling import decoupled_input
from quadcog.controllers.design import design
from quadcog.controllers.shaping import (
    desired_tilt,
    drag_over_mass,
    kinematics,
    second_order_gains,
    tilt_limit,
    wrap_angle,
)
from quadcog.kinds import Number, Poles
from quadcog.model.conventions import IDX
from quadcog.model.functions import Model
from quadcog.trajectories.analytic import ACC, JERK, POS, VEL, YAW, YAW_RATE
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["FeedbackLinearization"]


class FeedbackLinearization(Controller):
    """Feedback linearization with a cascade position loop; poles in rad/s.

    Parameters
    ----------
    vehicle : Vehicle, optional
        The controller's model of the vehicle (default: the Hummingbird with r_G = 0).
    model : quadcog.model.functions.Model, optional
        The generated functions (default ``quadcog.load()``).
    poles_z : sequence of float, optional
        2 poles (rad/s, real or a conjugate pair) of the height's linearized output error
        e_ddot + kd e_dot + kp e = 0. Default: from the vehicle
        (``quadcog.controllers.design``; the Hummingbird's (-3, -4)).
    poles_attitude : sequence of float, optional
        2 poles (rad/s) of the roll's and the pitch's output errors, as ``poles_z``. Default:
        from the vehicle (the Hummingbird's (-10, -12)).
    poles_psi : sequence of float, optional
        2 poles (rad/s) of the yaw's output error, as ``poles_z``. Default: from the vehicle
        (the Hummingbird's (-4, -5)).
    poles_position : sequence of float, optional
        2 poles (rad/s) of the outer x, y loop (slower than the attitude). Default: from the
        vehicle (the Hummingbird's (-1.5, -2)).
    max_tilt : float, optional
        Clip on the commanded roll and pitch (rad), in (0, pi/2]. Default: from the vehicle's
        thrust-to-weight ratio (0.6 for the Hummingbird).

    Raises
    ------
    InputError
        When a setting is out of range.
    """

    name = "feedback_linearization"

    def __init__(self, vehicle: Vehicle | None = None, model: Model | None = None, *,
                 poles_z: Poles | None = None, poles_attitude: Poles | None = None,
                 poles_psi: Poles | None = None, poles_position: Poles | None = None,
                 max_tilt: Number | None = None) -> None:
        super().__init__(vehicle, model)
        d = design(self.vehicle)            # the settings not given follow from the vehicle
        poles_z = d.poles_z if poles_z is None else poles_z
        poles_attitude = d.poles_attitude if poles_attitude is None else poles_attitude
        poles_psi = d.poles_psi if poles_psi is None else poles_psi
        poles_position = d.poles_position if poles_position is None else poles_position
        max_tilt = d.max_tilt if max_tilt is None else max_tilt
        kz = second_order_gains(poles_z, "poles_z")
        ka = second_order_gains(poles_attitude, "poles_attitude")
        kpsi = second_order_gains(poles_psi, "poles_psi")
        self.kp = np.array([kz[0], ka[0], ka[0], kpsi[0]])
        self.kd = np.array([kz[1], ka[1], ka[1], kpsi[1]])
        self.kp_pos, self.kd_pos = second_order_gains(poles_position, "poles_position")
        self.max_tilt = tilt_limit(max_tilt)

    def output_errors(self, x: ca.SX, ref: ca.SX, p: ca.SX | ca.DM | npt.NDArray[np.float64]
                      ) -> tuple[ca.SX, ca.SX, ca.SX]:
        """The output errors relative to y_d = [z_d, phi_d, theta_d, psi_d].

        The outer loop commands the acceleration a_cmd = a_ref + Kp e_p + Kd e_v (+ drag),
        turned into phi_d, theta_d by exact inversion of the thrust direction. The part of
        their rates that the reference explains (jerk, yaw rate) is fed forward; their second
        derivatives are taken as zero.

        Parameters
        ----------
        x : casadi.SX
            State (12,) [m, rad, m/s, rad/s].
        ref : casadi.SX
            Reference row (14,).
        p : casadi.SX or casadi.DM or (14,) numpy.ndarray
            Parameter vector the kinematics are evaluated with.

        Returns
        -------
        e : casadi.SX
            Output error y - y_d (4,) [m, rad, rad, rad].
        e_dot : casadi.SX
            Its rate (4,) [m/s, rad/s, rad/s, rad/s].
        y_ddot_d : casadi.SX
            Desired output acceleration (4,) [m/s^2, rad/s^2 (0), (0), (0)].
        """
        g = self.nominal[IDX["g"]]
        eta_dot, y_dot = kinematics(self.model, x, p)
        drag = ca.DM(np.append(drag_over_mass(self.nominal)[:2], 0.0))
        kp = ca.DM([self.kp_pos, self.kp_pos, self.kp[0]])
        kd = ca.DM([self.kd_pos, self.kd_pos, self.kd[0]])
        e_p, e_v = ref[POS] - x[0:3], ref[VEL] - eta_dot[0:3]
        # (the vertical component is the z output's own PD law, in v below)
        a_cmd = ref[ACC] + kp * e_p + kd * e_v + drag * eta_dot[0:3]
        a_cmd_dot = ref[JERK] + drag * ref[ACC]
        phi_d, theta_d, rates = self._tilt(a_cmd, x[5], a_cmd_dot, y_dot[3], g)
        e = ca.vertcat(x[2] - ref[POS][2], x[3] - phi_d, x[4] - theta_d,
                       wrap_angle(x[5] - ref[YAW]))
        y_dot_d = ca.vertcat(ref[VEL][2], rates[0], rates[1], ref[YAW_RATE])
        y_ddot_d = ca.vertcat(ref[ACC][2], 0, 0, 0)
        return e, y_dot - y_dot_d, y_ddot_d

    def _tilt(self, a_cmd, psi, a_cmd_dot, psi_dot, g):
        """(phi_d, theta_d, their rates) through a small Function, differentiated by AD."""
        if getattr(self, "_tilt_fn", None) is None:
            a, ps = ca.SX.sym("a", 3), ca.SX.sym("psi")
            ad, psd = ca.SX.sym("a_dot", 3), ca.SX.sym("psi_dot")
            tilt = ca.vertcat(*desired_tilt(a, g, ps, self.max_tilt))
            rate = ca.jtimes(tilt, ca.vertcat(a, ps), ca.vertcat(ad, psd))
            self._tilt_fn = ca.Function("desired_tilt", [a, ps, ad, psd], [tilt, rate])
        tilt, rate = self._tilt_fn(a_cmd, psi, a_cmd_dot, psi_dot)
        return tilt[0], tilt[1], rate

    def commanded_acceleration(self, e: ca.SX, e_dot: ca.SX, y_ddot_d: ca.SX) -> ca.SX:
        """The linearized output's command v = y_ddot_d - Kp e - Kd e_dot.

        Parameters
        ----------
        e : casadi.SX
            As returned by ``output_errors`` (4,) each.
        e_dot : casadi.SX
            As returned by ``output_errors`` (4,) each.
        y_ddot_d : casadi.SX
            As returned by ``output_errors`` (4,) each.

        Returns
        -------
        casadi.SX
            v (4,) [m/s^2, rad/s^2, rad/s^2, rad/s^2].
        """
        return y_ddot_d - ca.DM(self.kp) * e - ca.DM(self.kd) * e_dot

    def expression(self, t: ca.SX, x: ca.SX, ref: ca.SX, c: ca.SX) -> tuple[ca.SX, ca.SX]:
        """The feedback-linearizing law U = alpha^{-1} (v - b) at the nominal r_G.

        Parameters
        ----------
        t : casadi.SX
            Time (s), unused.
        x : casadi.SX
            State (12,) [m, rad, m/s, rad/s].
        ref : casadi.SX
            Reference row (14,).
        c : casadi.SX
            The controller state, empty (0,).

        Returns
        -------
        U : casadi.SX
            Input (4x1) [U1 (N), U2, U3, U4 (N m)].
        c_dot : casadi.SX
            Empty (0x1).
        """
        p = ca.DM(self.nominal)
        e, e_dot, y_ddot_d = self.output_errors(x, ref, p)
        v = self.commanded_acceleration(e, e_dot, y_ddot_d)
        alpha = self.model.casadi_function("decoupling")(x, p)
        b = self.model.casadi_function("drift")(x, p)
        return decoupled_input(alpha, v - b), ca.SX(0, 1)
