"""Cascade PD control (paper sec. 3.1), designed by pole placement on the generated
linearization at hover with r_G = 0.

Inner loops z, phi, theta, psi; outer loops x -> theta and y -> phi. The x-theta chain
(x, u, theta, q) and the y-phi chain (y, v, phi, p) are each placed as one 4th-order system;
the state-feedback gain [k1, k2, k3, k4] is then read as a cascade,
theta_d = -(k1 e_x + k2 e_u) / k3 (+ feedforward), U3 = -k3 (theta - theta_d) - k4 q,
so all 12 closed-loop eigenvalues are exactly the chosen poles.
"""
import casadi as ca
import numpy as np

from quadcog import validate
from quadcog.controllers.base import Controller
from quadcog.controllers.design import design
from quadcog.controllers.shaping import drag_over_mass, kinematics, tilt_limit, wrap_angle, yaw_rotation_T
from quadcog.errors import InputError, ParameterError
from quadcog.kinds import Number, Poles
from quadcog.model.conventions import IDX, N_STATE
from quadcog.model.functions import Model
from quadcog.model.parameters import with_cog
from quadcog.numerics import exact_place
from quadcog.trajectories.analytic import ACC, POS, VEL, YAW, YAW_RATE
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["CascadePD", "LOOPS"]

# (states, input) of each decoupled loop of the hover linearization (yaw 0, r_G = 0).
LOOPS = {"z": ([2, 8], 0), "psi": ([5, 11], 3),
         "x": ([0, 6, 4, 10], 2), "y": ([1, 7, 3, 9], 1)}


class CascadePD(Controller):
    """Linear cascade PD; poles in rad/s (negative real parts).

    Parameters
    ----------
    vehicle : Vehicle, optional
        The controller's model of the vehicle (default: the Hummingbird with r_G = 0); the
        loops are designed at its hover with r_G = 0, a CoG it believes in is fed forward as
        the hover moment.
    model : quadcog.model.functions.Model, optional
        The generated functions (default ``quadcog.load()``).
    poles_z : sequence of float, optional
        2 real poles (rad/s) of the height loop. Default: from the vehicle
        (``quadcog.controllers.design``; the Hummingbird's (-3, -4)).
    poles_psi : sequence of float, optional
        2 real poles (rad/s) of the yaw loop. Default: from the vehicle (the Hummingbird's
        (-4, -5)).
    poles_x : sequence of float, optional
        4 real poles (rad/s) of the x-theta chain: two slow for position, two fast for
        attitude. Default: from the vehicle (the Hummingbird's (-2, -2.5, -10, -12)).
    poles_y : sequence of float, optional
        4 real poles (rad/s) of the y-phi chain, as ``poles_x``. Default: from the vehicle
        (the Hummingbird's (-2, -2.5, -10, -12)).
    max_tilt : float, optional
        Clip on the commanded roll and pitch (rad), in (0, pi/2]. Default: from the vehicle's
        thrust-to-weight ratio (0.6 for the Hummingbird).

    Raises
    ------
    InputError
        When a pole setting cannot be placed on its loop, or a setting is out of range.
    """

    name = "cascade_pd"

    def __init__(self, vehicle: Vehicle | None = None, model: Model | None = None, *,
                 poles_z: Poles | None = None, poles_psi: Poles | None = None,
                 poles_x: Poles | None = None, poles_y: Poles | None = None,
                 max_tilt: Number | None = None) -> None:
        super().__init__(vehicle, model)
        d = design(self.vehicle)            # the settings not given follow from the vehicle
        poles_z = d.poles_z if poles_z is None else poles_z
        poles_psi = d.poles_psi if poles_psi is None else poles_psi
        poles_x = d.poles_x if poles_x is None else poles_x
        poles_y = d.poles_y if poles_y is None else poles_y
        max_tilt = d.max_tilt if max_tilt is None else max_tilt
        self.poles = {"z": poles_z, "psi": poles_psi, "x": poles_x, "y": poles_y}
        self.max_tilt = tilt_limit(max_tilt)
        # designed at r_G = 0 (the loops decouple there); a CoG the model believes in enters
        # only as the hover moment it needs, fed forward
        self.hover_input = self.vehicle.hover_input()
        p = with_cog(self.nominal, np.zeros(3))
        A, B = self.model.linearization(np.zeros(N_STATE), [self.hover_input[0], 0, 0, 0], p)
        self.A, self.B = A, B
        self.gains = {}
        K = np.zeros((4, 12))
        for loop, (states, inp) in LOOPS.items():
            poles = validate.poles(self.poles[loop], f"poles_{loop}", len(states))
            if np.any(poles.imag != 0):
                validate.fail(f"poles_{loop}", f"{len(states)} real negative poles",
                              self.poles[loop])
            real_poles = poles.real
            Ai = A[np.ix_(states, states)]
            Bi = B[np.ix_(states, [inp])]
            # distinct poles: a repeated one makes a Jordan block, whose eigenvalues a rounding
            # error of eps moves by eps^(1/multiplicity)
            if len(set(real_poles.tolist())) < len(real_poles):
                raise InputError(f"poles_{loop}: expected poles that can be placed on a "
                                 f"single-input chain (distinct poles; a repeated pole makes "
                                 f"the closed loop's eigenvalues sensitive to rounding), got "
                                 f"{validate.plain(self.poles[loop])}")
            try:                        # exact arithmetic: the same gains on every machine
                k = exact_place(Ai, Bi, real_poles, f"poles_{loop}")
            except ParameterError as e:
                raise InputError(f"poles_{loop}: expected poles that can be placed on a "
                                 f"single-input chain ({e}), got "
                                 f"{validate.plain(self.poles[loop])}") from None
            self.gains[loop] = k
            K[inp, states] = k
        self.K = K
        # sorted: LAPACK's order differs between machines
        self.closed_loop_eigenvalues = np.sort(np.linalg.eigvals(A - B @ K))
        chosen = np.sort(np.concatenate([np.asarray(v, float) for v in self.poles.values()]))
        got = np.sort(self.closed_loop_eigenvalues.real)
        if np.max(np.abs(got - chosen)) > 1e-6 * np.max(np.abs(chosen)) or \
                np.max(np.abs(self.closed_loop_eigenvalues.imag)) > 1e-6:
            raise InputError(f"poles: the placed closed-loop eigenvalues "
                             f"{validate.plain(got.tolist())} differ from the chosen poles "
                             f"{validate.plain(chosen.tolist())}; expected poles the hover "
                             f"linearization can be placed at (too fast or too close together)")

    def expression(self, t: ca.SX, x: ca.SX, ref: ca.SX, c: ca.SX) -> tuple[ca.SX, ca.SX]:
        """The cascade PD law (see the module docstring) as CasADi expressions.

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
        p = self.nominal
        m, g = p[IDX["m"]], p[IDX["g"]]
        cx, cy, cz = drag_over_mass(p)
        eta_dot, _ = kinematics(self.model, x, ca.DM(p))
        psi = x[5]
        Rt = yaw_rotation_T(psi)
        e_p = Rt @ (x[0:3] - ref[POS])           # position error in the yaw frame
        e_v = Rt @ (eta_dot[0:3] - ref[VEL])     # ground velocity error in the yaw frame
        a_ff, v_ff = Rt @ ref[ACC], Rt @ ref[VEL]
        kx, ky, kz, kpsi = (self.gains[k] for k in ("x", "y", "z", "psi"))
        clip = lambda v: ca.fmin(ca.fmax(v, -self.max_tilt), self.max_tilt)
        theta_d = clip(-(kx[0] * e_p[0] + kx[1] * e_v[0]) / kx[2] + (a_ff[0] + cx * v_ff[0]) / g)
        phi_d = clip(-(ky[0] * e_p[1] + ky[1] * e_v[1]) / ky[2] - (a_ff[1] + cy * v_ff[1]) / g)
        U1 = (m * (g + ref[ACC][2]) + cz * m * ref[VEL][2] - kz[0] * (x[2] - ref[POS][2])
              - kz[1] * e_v[2])
        U2 = self.hover_input[1] - ky[2] * (x[3] - phi_d) - ky[3] * x[9]
        U3 = self.hover_input[2] - kx[2] * (x[4] - theta_d) - kx[3] * x[10]
        U4 = -kpsi[0] * wrap_angle(x[5] - ref[YAW]) - kpsi[1] * (x[11] - ref[YAW_RATE])
        return ca.vertcat(U1, U2, U3, U4), ca.SX(0, 1)
