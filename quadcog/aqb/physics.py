"""AdaptiveQuadBench's payload model measured against a rigid body's, and the same trials flown
in RotorPy with its payload model as shipped and corrected.

RotorPy's fork integrates the vehicle about its CoM, with the rotor arms taken from the CoM, so
a payload changes the mass, the CoM and the inertia about it. Its ``attach_payload``,
``detach_payload`` and the toggling in ``simulate.py`` have three flaws (issue 31):

- attach: the base body's inertia is moved to the new CoM with the parallel-axis term
  *subtracted* (``I0 - m0 (|d|^2 I - d d^T)``); a rigid body adds it;
- the payload's weight is applied a second time as an external torque
  ``(r_p - c) x (0, 0, -m_p g)``: world-frame gravity crossed with a body-frame offset, fixed at
  attach time and applied in body axes whatever the attitude, while about the CoM the weight
  of the whole body has no moment at all (the offset acts through the rotor arms already);
- detach: the CoM is recomputed with the mass already reduced and the inertia moved back with
  the same sign error, so neither comes back to the bare vehicle's.

``flaw_measures`` puts numbers on each over a set of trials; ``corrected_multirotor`` is RotorPy's
Multirotor with the rigid body's attach and detach and without the extra torque, so that the
same trials flown with both show what the payload model alone changes (``fly_rotorpy``).
Needs AdaptiveQuadBench (``make aqb``).
"""
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from quadcog.aqb.adapter import AQB_NAMES, QuadcogAQBController
from quadcog.aqb.convert import ROTORPY_GRAVITY
from quadcog.aqb.install import require_aqb
from quadcog.aqb.protocol import FLIGHT_TIME, PayloadTrial

__all__ = ["parallel_axis", "rigid_body_inertia", "corrected_multirotor", "flaw_measures",
           "fly_rotorpy"]


def parallel_axis(m: float, d: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The parallel-axis term ``m (|d|^2 I - d d^T)`` (kg m^2) of a mass m at offset d (m).

    Parameters
    ----------
    m : float
        Mass (kg).
    d : (3,) array_like
        Offset of its CoM from the new reference point (m).

    Returns
    -------
    (3, 3) numpy.ndarray
        The term.
    """
    d = np.asarray(d, dtype=float)
    return m * (d @ d * np.eye(3) - np.outer(d, d))


def rigid_body_inertia(m0: float, c0: npt.ArrayLike, I0: npt.ArrayLike, mp: float,
                       rp: npt.ArrayLike) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """CoM and inertia about it of a body (m0, CoM c0, inertia I0 about c0) with a point mass
    mp at rp: ``c = (m0 c0 + mp rp) / (m0 + mp)``, ``I = I0 + S(m0, c0 - c) + S(mp, rp - c)``.

    Parameters
    ----------
    m0 : float
        The body's mass (kg).
    c0 : (3,) array_like
        Its CoM (m, body axes).
    I0 : (3, 3) array_like
        Its inertia about c0 (kg m^2).
    mp : float
        The point mass (kg).
    rp : (3,) array_like
        Its position (m, body axes).

    Returns
    -------
    c : (3,) numpy.ndarray
        The CoM of both (m).
    I : (3, 3) numpy.ndarray
        Their inertia about c (kg m^2).
    """
    c0, rp = np.asarray(c0, float), np.asarray(rp, float)
    c = (m0 * c0 + mp * rp) / (m0 + mp)
    return c, np.asarray(I0, float) + parallel_axis(m0, c0 - c) + parallel_axis(mp, rp - c)


def corrected_multirotor() -> type:
    """RotorPy's Multirotor with a rigid body's payload: attach and detach move the CoM and the
    inertia as ``rigid_body_inertia`` does (detach restores the bare vehicle exactly), and the
    extra torque ``simulate.py`` adds for an attached payload is taken out again.

    Returns
    -------
    type
        A subclass of ``rotorpy.vehicles.multirotor.Multirotor``.

    Raises
    ------
    quadcog.MissingDependencyError
        Without AdaptiveQuadBench's RotorPy fork.
    """
    require_aqb()
    from rotorpy.vehicles.multirotor import Multirotor

    class RigidPayloadMultirotor(Multirotor):
        """Multirotor whose payload is a rigid body's (quadcog.aqb.physics); its methods are
        left unannotated: they override RotorPy's untyped ones."""

        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            self._bare = (self.mass, np.array(self.com, float), self.inertia.copy())
            self._extra_torque = np.zeros(3)

        def _refresh(self):
            self.inv_inertia = np.linalg.inv(self.inertia)
            self.weight = np.array([0, 0, -self.mass * self.g])
            self.extract_geometry()
            k = self.k_m / self.k_eta
            self.f_to_TM = np.vstack((np.ones((1, self.num_rotors)), np.hstack(
                [np.cross(self.rotor_pos[key] - self.com, np.array([0, 0, 1])).reshape(-1, 1)[0:2]
                 for key in self.rotor_pos]), (k * self.rotor_dir).reshape(1, -1)))
            self.TM_to_f = np.linalg.inv(self.f_to_TM)

        def attach_payload(self):
            if self.payload_mass == 0:
                return np.zeros(3)
            m0, c0, I0 = self._bare
            rp = np.asarray(self.payload_position, float)
            c, inertia = rigid_body_inertia(m0, c0, I0, self.payload_mass, rp)
            if getattr(self, "payload_inertia", None) is not None:
                inertia = inertia + self.payload_inertia
            shift = c - self.com
            self.mass, self.com, self.inertia = m0 + self.payload_mass, c, inertia
            self._refresh()
            # what simulate.py adds as ext_torque right after this call (taken out in _s_dot_fn)
            self._extra_torque = np.cross(rp - c, np.array([0, 0, -self.payload_mass * self.g]))
            return shift

        def detach_payload(self):
            if self.payload_mass == 0:
                return np.zeros(3)
            m0, c0, I0 = self._bare
            shift = c0 - self.com
            self.mass, self.com, self.inertia = m0, c0.copy(), I0.copy()
            self._refresh()
            self._extra_torque = np.zeros(3)
            self.payload_mass, self.payload_position, self.payload_inertia = 0, np.zeros(3), None
            return shift

        def _s_dot_fn(self, t, s, cmd_rotor_speeds, ext_force, ext_torque):
            return super()._s_dot_fn(t, s, cmd_rotor_speeds, ext_force,
                                     np.asarray(ext_torque, float) - self._extra_torque)

    return RigidPayloadMultirotor


def _norm_ratio(A: npt.NDArray[np.float64], B: npt.NDArray[np.float64]) -> float:
    return float(np.linalg.norm(A - B) / np.linalg.norm(B))


def flaw_measures(trials: Sequence[PayloadTrial]) -> dict[str, float]:
    """Each flaw of the shipped payload model, measured over the trials' toggle sequences on
    RotorPy's own Multirotor (no flight: attach and detach as ``simulate.py`` calls them).

    Parameters
    ----------
    trials : sequence of PayloadTrial
        The trials (their payload and toggles).

    Returns
    -------
    dict of str to float
        ``inertia_error_attach`` (largest relative Frobenius error of the inertia about the
        CoM after an attach, against ``rigid_body_inertia``), ``com_error_detach`` (m, largest
        distance of the CoM from the bare vehicle's after a detach),
        ``inertia_error_detach`` (relative, against the bare inertia),
        ``extra_torque_max`` (N m, the largest extra torque), ``extra_torque_ratio`` (largest
        ratio of it to the moment the CoG offset has through the rotor arms, ``M g |c_xy|``),
        ``trials`` (how many had a payload).
    """
    require_aqb()
    from aqb.quad_param.quadrotor import quad_params
    from rotorpy.vehicles.multirotor import Multirotor
    out = {"inertia_error_attach": 0.0, "com_error_detach": 0.0, "inertia_error_detach": 0.0,
           "extra_torque_max": 0.0, "extra_torque_ratio": 0.0, "trials": 0.0}
    for trial in trials:
        if trial.payload_mass <= 0:
            continue
        out["trials"] += 1
        v = Multirotor(quad_params)
        m0, c0, I0 = v.mass, np.array(v.com, float), v.inertia.copy()
        rp = np.array(trial.payload_position)
        v.update_payload(trial.payload_mass, rp.copy())
        for k, _ in enumerate(trial.toggle_times):
            if k % 2 == 0:            # simulate.py restores mass and position before attaching
                if v.payload_mass == 0:
                    v.payload_mass, v.payload_position = trial.payload_mass, rp.copy()
                v.attach_payload()
                c_true, I_true = rigid_body_inertia(m0, c0, I0, trial.payload_mass, rp)
                out["inertia_error_attach"] = max(out["inertia_error_attach"],
                                                  _norm_ratio(v.inertia, I_true))
                tau = np.cross(v.payload_position - v.com,
                               np.array([0, 0, -v.payload_mass * ROTORPY_GRAVITY]))
                arm = (m0 + trial.payload_mass) * ROTORPY_GRAVITY * np.hypot(*c_true[:2])
                out["extra_torque_max"] = max(out["extra_torque_max"], float(np.linalg.norm(tau)))
                if arm > 0:
                    out["extra_torque_ratio"] = max(out["extra_torque_ratio"],
                                                    float(np.linalg.norm(tau) / arm))
            else:
                v.detach_payload()
                out["com_error_detach"] = max(out["com_error_detach"],
                                              float(np.linalg.norm(v.com - c0)))
                out["inertia_error_detach"] = max(out["inertia_error_detach"],
                                                  _norm_ratio(v.inertia, I0))
    return out


def fly_rotorpy(trial: PayloadTrial, controller: str, corrected: bool = False) -> float:
    """One trial in RotorPy as AdaptiveQuadBench flies it (100 Hz, its start state, its motor
    noise seeded by the trial's number as its serial runner does), with its payload model as
    shipped or corrected.

    Parameters
    ----------
    trial : PayloadTrial
        The trial.
    controller : str
        ``"qc-<law>"`` (a quadcog law, ``AQB_NAMES``) or a peer's AdaptiveQuadBench name
        (``geo``, ``geo-a``, ``l1geo``, ``indi-a``).
    corrected : bool
        Fly ``corrected_multirotor()`` instead of RotorPy's Multirotor.

    Returns
    -------
    float
        AdaptiveQuadBench's cost: the position RMSE (m).
    """
    tree = require_aqb()
    import sys
    sys.path.insert(0, str(tree.aqb))
    from aqb.quad_param.quadrotor import quad_params
    from aqb.utils.parallel_data_collection import compute_cost
    from rotorpy.environments import Environment
    from rotorpy.trajectories.random_motion_prim_traj import RapidTrajectory
    from rotorpy.vehicles.multirotor import Multirotor
    import run_eval

    cls = corrected_multirotor() if corrected else Multirotor
    vehicle = cls(quad_params)
    vehicle.update_payload(trial.payload_mass, np.array(trial.payload_position))
    traj = RapidTrajectory(np.zeros(3), np.zeros(3), np.zeros(3), np.array([0, 0, -9.81]))
    traj.set_goal_position(np.array(trial.goal_position))
    traj.set_goal_velocity(np.array(trial.goal_velocity))
    traj.set_goal_acceleration(np.array(trial.goal_acceleration))
    traj.generate(FLIGHT_TIME)
    ctl = (QuadcogAQBController(quad_params, AQB_NAMES[controller], on_nonfinite="cut")
           if controller in AQB_NAMES else run_eval.switch_controller(controller, quad_params))
    ctl.update_trajectory(traj)
    np.random.seed(trial.index)
    env = Environment(vehicle=vehicle, controller=ctl, wind_profile=None, trajectory=traj,
                      sim_rate=100, ext_force=np.zeros(3), ext_torque=np.zeros(3),
                      disturbance_toggle_times=list(trial.toggle_times))
    vehicle.initial_state = {"x": np.zeros(3), "v": np.zeros(3), "q": np.array([0, 0, 0, 1.0]),
                             "w": np.zeros(3), "wind": np.zeros(3), "rotor_speeds": np.zeros(4)}
    result = env.run(t_final=FLIGHT_TIME, use_mocap=False, terminate=False, plot=False,
                     plot_mocap=False, plot_estimator=False, plot_imu=False, animate_bool=False,
                     animate_wind=False, verbose=False)
    return float(compute_cost(result)[0])
