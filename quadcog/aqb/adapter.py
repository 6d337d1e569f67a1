"""A quadcog law as an AdaptiveQuadBench controller: a thin layer over the compiled law.

AdaptiveQuadBench calls ``update(t, state, flat_output)`` once per simulation step (100 Hz)
and flies the rotor speeds of ``cmd_motor_speeds``; the class here implements that interface
(its ``MultirotorControlTemplate``, to which it is registered when AdaptiveQuadBench is
importable). Each call converts the true state and the flat outputs (``quadcog.aqb.convert``),
advances the law's own state c from the previous call to this one, then evaluates the compiled
law once: U = [U1 (N), U2, U3, U4 (N m about O)], rotor thrusts through the mixer, rotor speeds
through the rotor model.

The law's state c advances with Euler steps of at most ``substep`` (1 ms, the step quadcog's own
simulator uses) on the measurements held since the previous call, then ``project_numpy``: at a
10 ms step alone, a least-squares gain of hundreds per second would make the Euler step
unstable. A call at an earlier time than the previous one (AdaptiveQuadBench's delay-margin
test reuses a controller for each new flight) restarts c from ``initial_state()``.
"""
from collections.abc import Mapping
from typing import Any

import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.aqb.convert import motor_speeds, reference_row, state_vector, vehicle_from_quad_params
from quadcog.controllers.base import Controller
from quadcog.controllers.registry import controller_names, make_controller
from quadcog.model.conventions import rotation_matrix

__all__ = ["QuadcogAQBController", "AQB_PREFIX", "AQB_NAMES", "MAX_GAP", "aqb_controller_factory",
           "register_template"]

# AdaptiveQuadBench's name of each quadcog law: "qc-" + quadcog's registry name
AQB_PREFIX = "qc-"
AQB_NAMES = {AQB_PREFIX + name: name for name in controller_names()}
# the longest time between two calls (s) over which the law's own state advances on the state
# held since the previous call: AdaptiveQuadBench calls every 10 ms; a longer gap (a time in
# ms, a clock that jumped) would be that many Euler substeps on a stale measurement
MAX_GAP = 1.0


class QuadcogAQBController:
    """A quadcog controller flying in AdaptiveQuadBench (see the module docstring).

    Parameters
    ----------
    quad_params : mapping
        AdaptiveQuadBench's vehicle parameters (``aqb.quad_param.quad_params``): the law is
        designed for the Vehicle they describe (``vehicle_from_quad_params``).
    law : str or Controller
        A name of quadcog's controller registry (``"composite"``, ``"geometric"``, ...) or a
        Controller already designed.
    substep : float
        Longest Euler step of the law's own state (s), default 1 ms.
    on_nonfinite : {"raise", "cut"}
        What a law that is no longer finite (it went unstable) does: raise InputError
        (default), or cut the motors (rotor speeds 0) until the next flight, as a flight
        controller's failsafe would, so that a benchmark records a failed flight;
        ``failures`` counts such calls.
    **settings
        Keyword settings of the law (with a name).

    Raises
    ------
    quadcog.InputError
        An unknown law, a setting it refuses, or quad_params that are not a vehicle's.
    """

    def __init__(self, quad_params: Mapping[str, Any], law: str | Controller = "composite",
                 substep: float = 1e-3, on_nonfinite: str = "raise", **settings: Any) -> None:
        self.vehicle = vehicle_from_quad_params(quad_params)
        if isinstance(law, Controller):
            self.controller = law
        else:
            self.controller = make_controller(law, vehicle=self.vehicle, **settings)
        self.substep = validate.positive(substep, "substep", "s")
        self.on_nonfinite = validate.choice(on_nonfinite, "on_nonfinite", ("raise", "cut"))
        self.failures = 0
        self._call = self.controller.compiled()
        self._call.inputs[0][:] = 0.0
        self.reset()

    def reset(self) -> None:
        """Start the law's own state again (``initial_state()``); the next call is t0."""
        self.c = np.array(self.controller.initial_state(), dtype=float)
        self._t: float | None = None
        self._held: tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]] | None = None

    def update_trajectory(self, trajectory: Any) -> None:
        """AdaptiveQuadBench hands the trajectory before a flight: the law starts again.

        Parameters
        ----------
        trajectory : object
            Unused (the reference comes with each call).
        """
        self.reset()

    def _law(self, t: float, x: npt.NDArray[np.float64], ref: npt.NDArray[np.float64]
             ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        ins = self._call.inputs
        ins[0][0] = t
        ins[1][:], ins[2][:] = x, ref
        if self.controller.n_state:
            ins[3][:] = self.c
        U, c_dot = self._call()
        return U.ravel(), c_dot.ravel()

    def _advance(self, t: float) -> None:
        """c from the previous call's time to t, on the measurements held since then."""
        if self._t is None or self._held is None or not self.controller.n_state:
            return
        span = t - self._t
        n = max(1, int(np.ceil(span / self.substep - 1e-9)))
        h = span / n
        x, ref = self._held
        for k in range(n):
            _, c_dot = self._law(self._t + k * h, x, ref)
            self.c = np.asarray(self.controller.project_numpy(self.c + h * c_dot), dtype=float)

    def update(self, t: float, state: Mapping[str, Any], flat_output: Mapping[str, Any]
               ) -> dict[str, Any]:
        """The rotor speed commands at time t.

        Parameters
        ----------
        t : float
            Time (s).
        state : mapping
            The true state: ``x``, ``v``, ``q``, ``w`` (nothing else is read).
        flat_output : mapping
            The reference: ``x``, ``x_dot``, ``x_ddot``, ``x_dddot``, ``yaw``, ``yaw_dot``.

        Returns
        -------
        dict
            ``cmd_motor_speeds`` (4,) (rad/s), and for AdaptiveQuadBench's records
            ``cmd_motor_thrusts`` (N), ``cmd_thrust`` (N), ``cmd_moment`` (N m about O),
            ``cmd_q`` (the attitude of the law's ZYX reference tilt at the reference yaw, as
            [i, j, k, w]; AdaptiveQuadBench only logs it), ``cmd_w``, ``cmd_v``.

        Raises
        ------
        quadcog.PeerStateError
            A key of ``state`` or ``flat_output`` missing or malformed (named).
        quadcog.InputError
            A law that is not finite at this state, or a t more than ``MAX_GAP`` after the
            previous call's (nothing changes then).
        """
        t = validate.real(t, "t", unit="s")
        x, ref = state_vector(state), reference_row(flat_output)
        if self._t is not None and t - self._t > MAX_GAP:
            validate.fail("t", f"a time at most {validate.plain(MAX_GAP)} s after the previous "
                          f"call's t = {validate.plain(self._t)} s (a call each simulation step, times in s; "
                          "reset() or an earlier t starts a new flight)", t)
        if self._t is not None and t < self._t:
            self.reset()                        # a new flight with the same controller
        with np.errstate(all="ignore"):         # an unstable law is caught just below
            self._advance(t)
            U, _ = self._law(t, x, ref)
        if not np.isfinite(U).all():
            if self.on_nonfinite == "raise":
                validate.fail(f"controller {self.controller.name!r} at t = {t} s",
                              "a finite input", U.tolist())
            self.failures += 1
            self._t, self._held = t, (x, ref)
            return {"cmd_motor_speeds": np.zeros(4), "cmd_motor_thrusts": np.zeros(4),
                    "cmd_thrust": 0.0, "cmd_moment": np.zeros(3),
                    "cmd_q": np.array([0.0, 0.0, 0.0, 1.0]), "cmd_w": np.zeros(3),
                    "cmd_v": ref[3:6].copy()}
        self._t, self._held = t, (x, ref)
        f = np.clip(self.vehicle.rotor_thrusts(U), self.vehicle.min_rotor_thrust,
                    self.vehicle.max_rotor_thrust)
        return {"cmd_motor_speeds": motor_speeds(self.vehicle, U),
                "cmd_motor_thrusts": f,
                "cmd_thrust": float(U[0]),
                "cmd_moment": U[1:].copy(),
                "cmd_q": _quaternion(rotation_matrix(x[3], x[4], ref[12])),
                "cmd_w": np.zeros(3), "cmd_v": ref[3:6].copy()}


def _quaternion(R: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """[i, j, k, w] of a rotation matrix (Shepperd's method, w >= 0)."""
    w = 0.5 * np.sqrt(max(1.0 + R[0, 0] + R[1, 1] + R[2, 2], 1e-12))
    q = np.array([(R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w),
                  (R[1, 0] - R[0, 1]) / (4 * w), w])
    return q / np.linalg.norm(q)


def aqb_controller_factory(peer_factory: Any = None, on_nonfinite: str = "raise") -> Any:
    """A ``controller_factory(controller_type, quad_params)`` for AdaptiveQuadBench's runner:
    ``"qc-<name>"`` makes quadcog's law ``<name>`` (``AQB_NAMES``), anything else goes to
    ``peer_factory`` (AdaptiveQuadBench's own ``switch_controller``).

    Parameters
    ----------
    peer_factory : callable, optional
        The factory of the peers' controllers.
    on_nonfinite : {"raise", "cut"}
        Passed to each QuadcogAQBController (a benchmark cuts the motors of an unstable law).

    Returns
    -------
    callable
        The factory.

    Raises
    ------
    quadcog.InputError
        ``on_nonfinite`` not one of its values, or a ``peer_factory`` that is not callable
        (here, before any flight); the factory raises it for a ``controller_type`` that is
        not a name, or an unknown name.
    """
    on_nonfinite = validate.choice(on_nonfinite, "on_nonfinite", ("raise", "cut"))
    if peer_factory is not None and not callable(peer_factory):
        validate.fail("peer_factory", "a callable (controller_type, quad_params) or None",
                      peer_factory)

    def factory(controller_type: str, quad_params: Mapping[str, Any]) -> Any:
        if not isinstance(controller_type, str):
            validate.fail("controller", "a controller name (a string)", controller_type)
        if controller_type.startswith(AQB_PREFIX):
            validate.choice(controller_type, "controller", tuple(AQB_NAMES))
            return QuadcogAQBController(quad_params, AQB_NAMES[controller_type],
                                        on_nonfinite=on_nonfinite)
        if peer_factory is None:
            validate.choice(controller_type, "controller", tuple(AQB_NAMES))
        return peer_factory(controller_type, quad_params)
    return factory


def register_template() -> bool:
    """Register QuadcogAQBController as a virtual subclass of AdaptiveQuadBench's
    ``MultirotorControlTemplate`` (an ABC) when AdaptiveQuadBench is importable.

    Returns
    -------
    bool
        True when registered.
    """
    try:
        from aqb.controller.controller_template import MultirotorControlTemplate
    except ImportError:
        return False
    MultirotorControlTemplate.register(QuadcogAQBController)
    return True
