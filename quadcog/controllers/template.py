"""The interface a controller of your own implements, and a complete example.

This module is the one place the protocol is stated; ``quadcog.sim.user_controller`` (which
checks every call) and ``quadcog.sim.flight`` (which calls it) follow it. With
``quadcog.simulate(ctrl, ..., path="python")`` any object ``ctrl`` that satisfies
``ControllerProtocol`` flies. What it must have is ``ctrl(t, x, ref, c)``, with the arguments

- ``t``: float, the time (s);
- ``x``: (12,) ndarray, the state ``[x, y, z (m, ground axes), phi, theta, psi (rad, ZYX
  Euler angles), u, v, w (m/s, body axes), p, q, r (rad/s, body axes)]``;
- ``ref``: (14,) ndarray, the reference row ``[p (3, m), v (3, m/s), a (3, m/s^2), j (3,
  m/s^3), yaw (rad), yaw_rate (rad/s)]`` (``quadcog.trajectories.template``);
- ``c``: (n_state,) ndarray, the controller's own state (empty when it has none);

and it returns either

- ``U``: (4,) ``[U1 (N): total thrust along body z, U2, U3, U4 (N m): the moments about
  body x, y, z at O]``, or
- ``(U, c_dot)``, with ``c_dot`` (n_state,) the rate of its state (per second); quadcog
  integrates ``c`` with the step dt: ``c + dt c_dot``.

Optional attributes (``FullControllerProtocol`` has them all); each has a default:

- ``n_state`` : int, the length of c (default 0);
- ``initial_state()`` : (n_state,) array, c at t = 0 (default zeros);
- ``project_numpy(c)`` : (n_state,) array, applied to c after every update (default: none),
  e.g. to clip an integrator or keep an estimate in a ball;
- ``estimates_cog`` : bool, True when ``c[0:3]`` is an estimate of the CoG offset r_G (m)
  (results then report it as ``r_hat``; default False);
- ``name`` : str, the name results carry (default the function's ``__name__``).

A call that raises, or returns anything but finite numbers of these shapes, stops the run
with an ``InputError`` naming the time. Every built-in ``quadcog.Controller`` satisfies
``FullControllerProtocol``, and also runs on the compiled path; a Python controller runs on
``path="python"`` only.

``HoverPD`` below is a complete controller in numpy, to copy from:

>>> import numpy as np, quadcog
>>> from quadcog.controllers.template import HoverPD
>>> ctrl = HoverPD()
>>> U, c_dot = ctrl(0.0, np.r_[0, 0, 1.0, np.zeros(9)], np.r_[0, 0, 1.0, np.zeros(11)],
...                 ctrl.initial_state())
>>> U.round(3).tolist()                        # [N, N m, N m, N m]: m g at hover
[6.671, 0.0, 0.0, 0.0]
>>> result = quadcog.simulate(HoverPD(), "hover", duration=2.0, path="python")
"""
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.controllers.base import Controller
from quadcog.model.conventions import rotation_matrix
from quadcog.trajectories.analytic import ACC, POS, VEL, YAW, YAW_RATE
from quadcog.vehicles.vehicle import HUMMINGBIRD, Vehicle

__all__ = ["ControllerProtocol", "FullControllerProtocol", "HoverPD"]

Array = npt.NDArray[np.float64]


def _refuse_instances(self: object) -> None:
    """What typing does for a Protocol class itself: it is implemented, not instantiated."""
    if getattr(type(self), "_is_protocol", False):
        raise TypeError("Protocols cannot be instantiated")


@runtime_checkable
class ControllerProtocol(Protocol):
    """A controller: what ``quadcog.simulate(..., path="python")`` calls at every step.

    Only the call is required; ``isinstance(obj, ControllerProtocol)`` is True for any
    callable. The optional attributes are in ``FullControllerProtocol`` and the module
    docstring.

    See Also
    --------
    FullControllerProtocol : the call and every optional attribute.
    HoverPD : a complete example.
    """

    # Stated so that the protocol's own signature is empty (typing would give it a
    # placeholder (*args, **kwargs)); a class that implements it needs no such constructor.
    def __init__(self) -> None:
        """Refuse to instantiate the protocol itself (as typing does)."""
        _refuse_instances(self)

    def __call__(self, t: float, x: Array, ref: Array,
                 c: Array) -> npt.ArrayLike | tuple[npt.ArrayLike, npt.ArrayLike]:
        """The law at one instant.

        Parameters
        ----------
        t : float
            Time (s).
        x : (12,) numpy.ndarray
            State [x, y, z (m), phi, theta, psi (rad), u, v, w (m/s, body), p, q, r (rad/s,
            body)]; a copy, the controller may change it.
        ref : (14,) numpy.ndarray
            Reference row [p (m), v (m/s), a (m/s^2), j (m/s^3), yaw (rad), yaw_rate
            (rad/s)].
        c : (n_state,) numpy.ndarray
            The controller's own state (empty without ``n_state``).

        Returns
        -------
        U : (4,) array_like
            [U1 (N), U2, U3, U4 (N m, about O in body axes)]; alone when the controller has
            no state, else
        (U, c_dot) : tuple of (4,) and (n_state,) array_like
            With the rate of the controller's state.
        """
        ...


@runtime_checkable
class FullControllerProtocol(ControllerProtocol, Protocol):
    """A controller with every optional attribute (every built-in Controller has them).

    Attributes
    ----------
    name : str
        The name results carry.
    n_state : int
        Length of the controller's state c, >= 0.
    estimates_cog : bool
        True when ``c[0:3]`` is an estimate r_hat of the CoG offset r_G (m).
    """

    name: str
    n_state: int
    estimates_cog: bool

    def __init__(self) -> None:
        """Refuse to instantiate the protocol itself (as typing does)."""
        _refuse_instances(self)

    def initial_state(self) -> npt.ArrayLike:
        """The controller's state at t = 0.

        Returns
        -------
        (n_state,) array_like
            c(0).
        """
        ...

    def project_numpy(self, c: Array) -> npt.ArrayLike:
        """Map the state after every update step (e.g. clip an integrator).

        Parameters
        ----------
        c : (n_state,) numpy.ndarray
            The state after the step ``c + dt c_dot``; a copy, it may be changed in place.

        Returns
        -------
        (n_state,) array_like
            The state the next step starts from.
        """
        ...


class HoverPD:
    """An example controller: PD position and attitude loops in numpy, with an integrator
    on the height error so that it shows the controller state.

    The outer loop commands an acceleration a = a_ref + kp e_p + kd e_v (+ ki times the
    integral of the height error), the thrust U1 gives its vertical part, and a small-angle
    inversion of the thrust direction turns its horizontal part into the roll and pitch the
    inner loop tracks. Gains from natural frequencies: kp = w^2, kd = 2 zeta w.

    Parameters
    ----------
    vehicle : Vehicle, optional
        The controller's model of the vehicle: mass, gravity, inertia and the hover moment of
        the CoG it believes (default: the Hummingbird with r_G = 0).
    omega_position : float
        Natural frequency of the position loops (rad/s), default 2.
    omega_attitude : float
        Natural frequency of the roll, pitch and yaw loops (rad/s), default 10; several
        times ``omega_position``.
    damping : float
        Damping ratio zeta of every loop, default 0.7.
    integral_gain : float
        ki of the height integrator (1/s^3), default 2 (with the default position loop the
        three height poles lie near -0.9 1/s).
    integral_limit : float
        Clip of the integrator state (m s), default 1.
    max_tilt : float
        Clip on the commanded roll and pitch (rad), default 0.5.

    Attributes
    ----------
    name : str
        ``"hover_pd"``.
    n_state : int
        1: the integral of the height error z_ref - z (m s).
    estimates_cog : bool
        False.
    """

    name = "hover_pd"
    n_state = 1
    estimates_cog = False

    def __init__(self, vehicle: Vehicle | None = None, *, omega_position: float = 2.0,
                 omega_attitude: float = 10.0, damping: float = 0.7,
                 integral_gain: float = 2.0, integral_limit: float = 1.0,
                 max_tilt: float = 0.5) -> None:
        v = HUMMINGBIRD if vehicle is None else vehicle
        self.m, self.g = v.m, v.g                            # kg, m/s^2
        self.inertia = np.array([v.Ixx, v.Iyy, v.Izz])       # (3,) kg m^2, about O
        self.hover_moment = v.hover_input()[1:3]             # (2,) N m: U2, U3 of r_G
        wp = validate.positive(omega_position, "omega_position", "rad/s")
        wa = validate.positive(omega_attitude, "omega_attitude", "rad/s")
        zeta = validate.positive(damping, "damping")
        self.kp, self.kd = wp ** 2, 2 * zeta * wp            # 1/s^2, 1/s
        self.kp_att, self.kd_att = wa ** 2, 2 * zeta * wa    # 1/s^2, 1/s
        self.ki = validate.nonnegative(integral_gain, "integral_gain")          # 1/s^3
        self.integral_limit = validate.positive(integral_limit, "integral_limit", "m s")
        self.max_tilt = validate.real(max_tilt, "max_tilt", lo=0.0, lo_open=True,
                                      hi=np.pi / 2, unit="rad")

    def initial_state(self) -> Array:
        """The integrator at t = 0.

        Returns
        -------
        (1,) numpy.ndarray
            [0] (m s).
        """
        return np.zeros(self.n_state)

    def project_numpy(self, c: Array) -> Array:
        """Clip the integrator (anti-windup).

        Parameters
        ----------
        c : (1,) numpy.ndarray
            The integral of the height error (m s) after an update step.

        Returns
        -------
        (1,) numpy.ndarray
            ``c`` clipped in place to +-``integral_limit``.
        """
        np.clip(c, -self.integral_limit, self.integral_limit, out=c)
        return c

    def __call__(self, t: float, x: Array, ref: Array,
                 c: Array) -> tuple[Array, Array]:
        """The law at one instant.

        Parameters
        ----------
        t : float
            Time (s), unused: the law is time-invariant.
        x : (12,) numpy.ndarray
            State [x, y, z (m), phi, theta, psi (rad), u, v, w (m/s, body), p, q, r (rad/s,
            body)].
        ref : (14,) numpy.ndarray
            Reference row [p (m), v (m/s), a (m/s^2), j (m/s^3), yaw (rad), yaw_rate
            (rad/s)].
        c : (1,) numpy.ndarray
            The integral of the height error (m s).

        Returns
        -------
        U : (4,) numpy.ndarray
            [U1 (N), U2, U3, U4 (N m)].
        c_dot : (1,) numpy.ndarray
            The height error z_ref - z (m): the integrator's rate.
        """
        phi, theta, psi = x[3:6]                              # rad
        R = rotation_matrix(phi, theta, psi)                  # (3, 3) body -> ground axes
        e_p = ref[POS] - x[0:3]                               # (3,) m, ground axes
        e_v = ref[VEL] - R @ x[6:9]                           # (3,) m/s, ground axes
        a = ref[ACC] + self.kp * e_p + self.kd * e_v          # (3,) m/s^2 commanded
        a[2] += self.ki * c[0]                                # m/s^2, height integrator
        U1 = self.m * (self.g + a[2]) / (np.cos(phi) * np.cos(theta))   # N, along body z
        # small-angle inversion of the thrust direction R e_z at heading psi
        cp, sp = np.cos(psi), np.sin(psi)
        theta_d = (a[0] * cp + a[1] * sp) / self.g            # rad
        phi_d = (a[0] * sp - a[1] * cp) / self.g              # rad
        tilt_d = np.clip([phi_d, theta_d], -self.max_tilt, self.max_tilt)      # (2,) rad
        e_att = tilt_d - np.array([phi, theta])               # (2,) rad
        e_yaw = np.arctan2(np.sin(ref[YAW] - psi), np.cos(ref[YAW] - psi))      # rad
        angle_error = np.r_[e_att, e_yaw]                     # (3,) rad
        rate_error = np.r_[0.0, 0.0, ref[YAW_RATE]] - x[9:12]                   # (3,) rad/s
        alpha = self.kp_att * angle_error + self.kd_att * rate_error           # (3,) rad/s^2
        moments = self.inertia * alpha                        # (3,) N m, about O
        moments[0:2] += self.hover_moment                     # N m: the believed CoG's
        U = np.r_[U1, moments]                                # (4,) [N, N m, N m, N m]
        c_dot = np.array([e_p[2]])                            # (1,) m
        return U, c_dot

    def __repr__(self) -> str:
        return f"HoverPD(kp={self.kp:g}, kd={self.kd:g}, ki={self.ki:g})"


if TYPE_CHECKING:       # mypy checks that the example and the built-ins satisfy the protocol
    _example: FullControllerProtocol = HoverPD()
    _builtin: FullControllerProtocol = Controller()
