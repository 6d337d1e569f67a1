"""Prepare a run: every check of the arguments, once, and the start of the state.

``prepare_flight`` is the first of the three parts of ``quadcog.simulate`` (prepare -> step loop
-> result): it checks the arguments in a fixed order (so the first mistake is the one named),
designs the controller for its model, builds the schedule of per-step inputs and the start
state, and hands the loop a ``FlightSetup``. The batch paths (``quadcog.sim.batch``,
``quadcog.sim.vector_batch``) use the same checks and ``batch_start``.
"""
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any
import warnings

import numpy as np
import numpy.typing as npt

from quadcog import config, validate
from quadcog.codegen.fastcall import evaluate
from quadcog.controllers.base import Controller
from quadcog.errors import InputError, QuadcogWarning
from quadcog.model.conventions import IDX, N_PARAM, N_STATE, R_G, rotation_matrix
from quadcog.model.inertial_parameters import N_PI, check_physically_consistent
from quadcog.model.inertial_parameters import is_physically_consistent as consistency_ok
from quadcog.model.parameters import LARGEST, check_parameters, with_cog
from quadcog.sim.closed_loop import ACCUMULATORS
from quadcog.sim.divergence import Limits, first_divergence
from quadcog.sim.plant import PI_INDEX, Actuation, TruthOptions, body_mass_and_cog, initial_rotor_thrusts
from quadcog.sim.result import position_errors
from quadcog.sim.schedule import Schedule, check_time, cog_at, truth_parameters
from quadcog.sim.timeline import CogProfile, PayloadProfile
from quadcog.sim.user_controller import user_state
from quadcog.trajectories.analytic import POS, REF_SIZE, VEL, YAW
from quadcog.trajectories.registry import as_trajectory
from quadcog.validate import positive
from quadcog.vehicles.payload import check_lift, check_reach
from quadcog.vehicles.vehicle import HUMMINGBIRD, N_ROTORS, Vehicle

__all__ = ["RK4_LIMIT", "FlightSetup", "prepare_flight", "batch_start", "check_time",
           "run_options", "check_start", "check_step_size", "check_fastest_eigenvalue", "start_at_reference",
           "as_cog_profile", "check_cog_changes", "warn_late_disturbances", "as_payload_profile",
           "check_payload_events", "whole_body"]

RK4_LIMIT = 2.5       # |lambda| dt below this: inside RK4's stability region with margin


@dataclass(frozen=True)
class FlightSetup:
    """Everything the step loop of one flight needs, checked.

    Parameters
    ----------
    controller : Controller or callable
        The controller, designed for its model (or a user's Python callable).
    is_law : bool
        True for a quadcog Controller.
    vehicle : Vehicle
        The truth vehicle.
    P : (14,) numpy.ndarray
        The truth vehicle's parameters (r_G at the vehicle's own CoG).
    schedule : Schedule
        The per-step inputs.
    X0 : (12 + rotor states + controller states,) numpy.ndarray
        The start.
    actuation : Actuation
        The rotors as the truth model has them.
    limits : Limits
        When a run counts as diverged.
    path : str
        'compiled' or 'python'.
    n_rotor_states : int
        Rotor states in X (motor lag), 0 or 4.
    """
    controller: Any
    is_law: bool
    vehicle: Vehicle
    P: np.ndarray
    schedule: Schedule
    X0: np.ndarray
    actuation: Actuation
    limits: Limits
    path: str
    n_rotor_states: int


def prepare_flight(controller: Any, trajectory: Any, duration: float, dt: float | None,
                   vehicle: Vehicle | None, controller_model: Vehicle | None, cog: Any,
                   disturbances: Any, truth: TruthOptions | None, x0: Any, path: str,
                   limits: Limits | None, progress: Callable[[float], Any] | None,
                   check_dt: bool, payloads: Any = None) -> FlightSetup:
    """The checked set-up of one flight (the arguments as ``quadcog.simulate`` takes them).

    Parameters
    ----------
    controller : Controller or callable
        As for ``quadcog.simulate``.
    trajectory : Trajectory, str or callable
        As for ``quadcog.simulate``.
    duration : float
        Seconds.
    dt : float or None
        The step (s); None for ``quadcog.config.defaults["simulate.dt"]``.
    vehicle : Vehicle or None
        The truth vehicle, as for ``quadcog.simulate``.
    controller_model : Vehicle or None
        What the controller believes, as for ``quadcog.simulate``.
    cog : CogProfile, list of (t, r, ramp) or None
        The CoG changes (s, m, s).
    disturbances : sequence of Disturbance
        Wrench pulses.
    truth : TruthOptions or None
        As for ``quadcog.simulate``.
    x0 : (12,) array_like or None
        Initial state [m, rad, m/s, rad/s].
    path : {"compiled", "python"}
        The step loop.
    limits : Limits or None
        As for ``quadcog.simulate``.
    progress : callable or None
        ``progress(fraction)``.
    check_dt : bool
        Refuse a dt too large for RK4 on the closed loop at the start.
    payloads : sequence of PayloadEvent or dict, PayloadProfile or None
        Payloads attached, moved and dropped during the run, as for ``quadcog.simulate``.

    Returns
    -------
    FlightSetup
        What the step loop needs.

    Raises
    ------
    quadcog.InputError
        Naming the first argument that is wrong, and what was expected.
    """
    options, limits = run_options(truth, limits, progress)
    validate.flag(check_dt, "check_dt")
    dt = config.get("simulate.dt", dt)
    validate.choice(path, "path", ("compiled", "python"))
    is_law = isinstance(controller, Controller)
    if not is_law and not (path == "python" and callable(controller)):
        validate.fail("controller", "a quadcog Controller, or a callable ctrl(t, x, ref, c) "
                      "with path='python'", controller)
    if vehicle is None:
        vehicle = controller.vehicle if is_law else HUMMINGBIRD
        model_default = vehicle
    else:
        # the controller knows the airframe, not its CoG offset or what it carries
        model_default = (vehicle.airframe.with_cog(np.zeros(3)) if isinstance(vehicle, Vehicle)
                         else None)
    for name, v in (("vehicle", vehicle), ("controller_model", controller_model)):
        if v is not None and not isinstance(v, Vehicle):
            validate.fail(name, "a quadcog Vehicle", v)      # plain: no numpy repr
    if is_law:
        controller = controller.for_vehicle(controller_model or model_default)
    duration, dt = check_time(duration, dt)
    trajectory = as_trajectory(trajectory)
    cog = as_cog_profile(cog)
    loads = as_payload_profile(payloads, vehicle)
    P = vehicle.airframe.parameters()        # the payloads reach the truth through the schedule
    check_cog_changes(P, cog, duration)
    check_payload_events(vehicle, loads, duration)
    warn_late_disturbances(disturbances, duration)
    schedule = Schedule.build(trajectory, duration, dt, cog, disturbances, payloads=loads)
    x0 = start_at_reference(schedule.ref[0]) if x0 is None else check_start(x0, schedule.ref[0],
                                                                            limits)
    actuation = Actuation.of(vehicle, options)
    P0 = whole_body(truth_parameters(P, schedule.cog_scale[0], schedule.cog[0]),
                    schedule.payload[0])
    f0 = initial_rotor_thrusts(P0, actuation)
    if check_dt:
        check_step_size(controller if is_law else None, x0, schedule.ref[0], P0, dt, actuation)
    n_state, c0 = ((controller.n_state, controller.initial_state()) if is_law
                   else user_state(controller))
    X0 = np.concatenate([x0, f0, c0])

    return FlightSetup(controller, is_law, vehicle, P, schedule, X0, actuation, limits, path,
                       f0.size)


def batch_start(controller: Controller, actuation: Actuation, P0: npt.NDArray[np.float64],
                x0: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The start of many flights: state, rotor thrusts, controller state and accumulators.

    Parameters
    ----------
    controller : Controller
        Designed for its model already.
    actuation : Actuation
        The rotors (shared by the flights).
    P0 : (B, 14) numpy.ndarray
        Each flight's truth parameters at t = 0 (its CoG at the start).
    x0 : (12,) array_like
        The start state [m, rad, m/s, rad/s], shared.

    Returns
    -------
    (B, 12 + rotor states + controller states + accumulators) numpy.ndarray
        Z, as the monitored step (``quadcog.sim.closed_loop``) takes it.

    Raises
    ------
    quadcog.InputError
        An argument of the wrong kind or shape.
    """
    if not isinstance(controller, Controller):
        validate.fail("controller", "a quadcog Controller", controller)
    if not isinstance(actuation, Actuation):
        validate.fail("actuation", "a quadcog.sim.plant.Actuation", actuation)
    P0 = validate.array(P0, "P0", (None, N_PARAM), what=f"an array of shape (B, {N_PARAM})")
    x0 = validate.vector(x0, "x0", N_STATE)
    nc, nf = controller.n_state, actuation.n_rotor_states
    nX = N_STATE + nf + nc
    Z = np.zeros((P0.shape[0], nX + len(ACCUMULATORS)))
    Z[:, :N_STATE] = x0
    Z[:, N_STATE:N_STATE + nf] = initial_rotor_thrusts(P0, actuation)
    Z[:, N_STATE + nf:nX] = controller.initial_state()
    Z[:, nX + ACCUMULATORS.index("diverged_at")] = -1.0
    return Z


def check_start(x0: npt.ArrayLike, ref0: npt.NDArray[np.float64], limits: Limits
                ) -> npt.NDArray[np.float64]:
    """A start state the caller gave, checked: 12 numbers within the model's scale, not
    diverged already (a flight from there would only report its divergence).

    Parameters
    ----------
    x0 : (12,) array_like
        The start state [m, rad, m/s, rad/s].
    ref0 : (14,) numpy.ndarray
        The reference row at t = 0.
    limits : Limits
        The divergence limits.

    Returns
    -------
    (12,) numpy.ndarray
        x0 as floats.

    Raises
    ------
    quadcog.InputError
        x0 not 12 finite numbers within +-``LARGEST``, or diverged at t = 0.
    """
    x0 = validate.vector(x0, "x0", N_STATE)
    if not np.abs(x0).max() <= LARGEST:
        validate.fail("x0", f"12 finite numbers within +-{LARGEST:g}", x0.tolist())
    _, cause = first_divergence(x0[None, :], position_errors(x0[None, :], ref0[None, :]),
                                limits)
    if cause is not None:
        raise InputError(f"x0 = {x0.tolist()} has already diverged: {cause.describe(limits)}")
    return x0


def run_options(truth: TruthOptions | None, limits: Limits | None,
                progress: Callable[[float], Any] | None) -> tuple[TruthOptions, Limits]:
    """The checked truth options and limits of a run (defaults for None).

    Shared by ``simulate`` and the batch paths.

    Parameters
    ----------
    truth : TruthOptions, optional
        Default ``TruthOptions()``.
    limits : Limits, optional
        Default ``Limits()``.
    progress : callable, optional
        ``progress(fraction)``; only checked here.

    Returns
    -------
    options : TruthOptions
        The truth options.
    limits : Limits
        The divergence limits.

    Raises
    ------
    quadcog.InputError
        Naming ``truth``, ``limits`` or ``progress`` when one is of the wrong kind.
    """
    options = TruthOptions() if truth is None else truth
    if not isinstance(options, TruthOptions):
        validate.fail("truth", "a quadcog TruthOptions", truth)
    limits = Limits() if limits is None else limits
    if not isinstance(limits, Limits):
        validate.fail("limits", "a quadcog Limits", limits)
    if progress is not None and not callable(progress):
        validate.fail("progress", "None or a callable(fraction), e.g. a ProgressBar", progress)
    return options, limits



def check_step_size(controller: Controller | None, x0: npt.NDArray[np.float64],
                    ref0: npt.NDArray[np.float64], P: npt.NDArray[np.float64], dt: float,
                    actuation: Actuation) -> None:
    """Raise InputError if RK4 with step dt is unstable for the closed loop at the start.

    Also for the motor lag. The closed-loop Jacobian d/dx f(x, U(x)) at (x0, ref0) comes from
    CasADi AD.

    Parameters
    ----------
    controller : Controller or None
        None for a Python controller: no closed-loop check.
    x0 : (12,) numpy.ndarray
        The start state [m, rad, m/s, rad/s].
    ref0 : (14,) numpy.ndarray
        The reference row at t = 0.
    P : (14,) numpy.ndarray
        The truth parameters at t = 0.
    dt : float
        The step (s).
    actuation : Actuation
        The rotors (motor time constant).

    Raises
    ------
    quadcog.InputError
        An argument of the wrong kind or shape, or dt too large for the motor time constant
        or for the closed loop's fastest eigenvalue.
    """
    if controller is not None and not isinstance(controller, Controller):
        validate.fail("controller", "None or a quadcog Controller", controller)
    if not isinstance(actuation, Actuation):
        validate.fail("actuation", "a quadcog.sim.plant.Actuation", actuation)
    x0, ref0 = validate.vector(x0, "x0", N_STATE), validate.vector(ref0, "ref0", REF_SIZE)
    P, dt = validate.vector(P, "P", N_PARAM), positive(dt, "dt", "s")
    if actuation.n_rotor_states and dt / actuation.time_constant > RK4_LIMIT:
        raise InputError(f"dt = {dt} s is too large for the motor time constant "
                         f"{actuation.time_constant} s: RK4 needs dt < "
                         f"{RK4_LIMIT * actuation.time_constant:.3g} s")
    if controller is None:
        return
    lam = np.linalg.eigvals(evaluate(controller.closed_loop_jacobian(), x0, ref0, P)[0])
    check_fastest_eigenvalue(float(np.max(np.abs(lam))), dt)


def check_fastest_eigenvalue(fastest: float, dt: float) -> None:
    """Raise InputError if RK4 with step dt is unstable for a closed loop whose fastest
    eigenvalue has magnitude ``fastest`` (the rule of ``check_step_size``).

    Parameters
    ----------
    fastest : float
        The largest magnitude of the closed-loop Jacobian's eigenvalues (1/s).
    dt : float
        The step (s).

    Raises
    ------
    quadcog.InputError
        ``fastest * dt`` beyond ``RK4_LIMIT``.
    """
    if fastest * dt > RK4_LIMIT:
        raise InputError(f"dt = {dt} s is too large: the closed loop has an eigenvalue of "
                         f"magnitude {fastest:.3g} 1/s, and RK4 needs dt < "
                         f"{RK4_LIMIT / fastest:.3g} s")



def start_at_reference(ref: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The state on a reference row: its position and heading, level, with its velocity.

    Parameters
    ----------
    ref : (14,) numpy.ndarray
        A reference row (``quadcog.trajectories.analytic``).

    Returns
    -------
    (12,) numpy.ndarray
        The state [m, rad, m/s, rad/s] (velocity expressed in body axes).

    Raises
    ------
    quadcog.InputError
        ``ref`` not 14 finite numbers.
    """
    ref = validate.vector(ref, "ref", REF_SIZE)
    x0 = np.zeros(N_STATE)
    x0[:3], x0[5] = ref[POS], ref[YAW]
    x0[6:9] = rotation_matrix(0.0, 0.0, ref[YAW]).T @ ref[VEL]
    return x0



def as_cog_profile(cog: Any) -> CogProfile:
    """A CogProfile from what ``simulate`` takes as ``cog``.

    Parameters
    ----------
    cog : CogProfile, list of (t, r, ramp) or None
        The CoG changes (s, m, s).

    Returns
    -------
    CogProfile
        Empty for None.

    Raises
    ------
    quadcog.InputError
        ``cog`` is none of those.
    """
    if cog is None:
        return CogProfile([])
    if isinstance(cog, CogProfile):
        return cog
    if not isinstance(cog, (list, tuple)):
        validate.fail("cog", "None, a CogProfile or a list of (t, r, ramp) changes", cog)
    return CogProfile(list(cog))



def check_cog_changes(P: npt.NDArray[np.float64], cog: CogProfile,
                      duration: float | None = None) -> None:
    """Raise ParameterError if the vehicle is inadmissible with any CoG of the profile, and
    a QuadcogWarning for a change that starts after the end of the run (it never happens).

    The admissible set of r_G is convex (|r|^2 - (u.r)^2 is convex for every unit u), so
    checking where each change ends covers the ramps between them.

    Parameters
    ----------
    P : (14,) numpy.ndarray
        The vehicle's parameters.
    cog : CogProfile
        The CoG changes.
    duration : float, optional
        The run's length (s): a change that starts after it is refused.

    Raises
    ------
    quadcog.InputError
        ``P`` not 14 finite numbers, ``cog`` not a CogProfile, ``duration`` not positive.
    quadcog.ParameterError
        Naming the change whose CoG makes the vehicle inadmissible.

    Warns
    -----
    QuadcogWarning
        A change that starts after the end of the run (it never happens in it; a shipped
        scenario flown shorter with ``--set duration=...`` is told so, not refused).
    """
    P = validate.vector(P, "P", N_PARAM)
    if not isinstance(cog, CogProfile):
        validate.fail("cog", "a CogProfile (quadcog.sim.prepare.as_cog_profile)", cog)
    if duration is not None:
        duration = positive(duration, "duration", unit="s")
    for i, change in enumerate(cog.changes):
        if duration is not None and change.t > duration:
            warnings.warn(f"cog[{i}] (the change to r = {list(change.r)} m at t = "
                          f"{change.t:g} s): after the end of the run (duration "
                          f"{duration:g} s), so it never happens in this run",
                          QuadcogWarning, stacklevel=2)
        check_parameters(with_cog(P, cog_at(P[R_G], 1.0, np.asarray(change.r))),
                         f"vehicle with the CoG of cog change {i} (r = {list(change.r)} m)")


def warn_late_disturbances(disturbances: Any, duration: float, stacklevel: int = 2) -> None:
    """A QuadcogWarning for each disturbance that starts after the end of the run.

    Parameters
    ----------
    disturbances : sequence of Disturbance
        The pulses (their type is checked by ``Schedule.build``).
    duration : float
        The run's length (s).
    stacklevel : int
        The warning's, as for ``warnings.warn`` from the caller.

    Warns
    -----
    QuadcogWarning
        A pulse after the end: it never happens in this run.
    """
    # only a sequence can hold a late disturbance
    for i, d in enumerate(disturbances if isinstance(disturbances, (list, tuple)) else ()):
        start = getattr(d, "t", None)
        if isinstance(start, (int, float)) and start > duration:
            warnings.warn(f"disturbance[{i}] (at t = {start:g} s): after the end of the run "
                          f"(duration {duration:g} s), so it never happens in this run",
                          QuadcogWarning, stacklevel=stacklevel + 1)


def as_payload_profile(payloads: Any, vehicle: Vehicle) -> PayloadProfile:
    """The PayloadProfile of a run: the vehicle's own payloads on board from t = 0, then the
    events.

    Parameters
    ----------
    payloads : sequence of PayloadEvent or dict, PayloadProfile or None
        The events (attach, move, drop) in time order; a PayloadProfile is taken as its events.
    vehicle : Vehicle
        The truth vehicle; its ``payloads`` are on board at the start.

    Returns
    -------
    PayloadProfile
        The checked profile.

    Raises
    ------
    quadcog.InputError
        ``payloads`` is none of those, or an event is out of order or names no payload on
        board.
    """
    if isinstance(payloads, PayloadProfile):
        payloads = payloads.events
    if payloads is None:
        payloads = []
    if isinstance(payloads, (str, bytes, dict)) or not isinstance(payloads, (list, tuple)):
        validate.fail("payloads", "None or a list of payload events (PayloadEvent or dicts "
                      "with t, action, name, ...)", payloads)
    if not isinstance(vehicle, Vehicle):
        validate.fail("vehicle", "a quadcog Vehicle (the truth, with its payloads on board)",
                      vehicle)
    return PayloadProfile(list(payloads), vehicle.payloads)


def check_payload_events(vehicle: Vehicle, loads: PayloadProfile,
                         duration: float | None = None) -> None:
    """Raise if a payload event cannot happen as written: after the end of the run (it would
    never happen), a payload placed farther from O than ``PAYLOAD_REACH`` arm lengths (not
    carried on the vehicle), an attach the rotors cannot lift with what is on board then
    (``quadcog.vehicles.payload.check_lift``), or the airframe with what is on board after
    an event not physically consistent.

    Adding a payload of positive mass to a consistent body keeps it consistent wherever the
    payload sits (the pseudo-inertia matrices add, and a payload's is positive semidefinite),
    so the check at the events' ends covers the moves between them; it fails only when the
    airframe itself is not a rigid body's (a CoG offset that the paper's model holds with
    I_O fixed, beyond what any mass distribution allows). The events are walked once in time
    order with the sum of the payloads' pi kept up to date, so the cost is linear in the
    number of events.

    Parameters
    ----------
    vehicle : Vehicle
        The truth vehicle (its airframe at its own CoG).
    loads : PayloadProfile
        The payloads over the run.
    duration : float, optional
        The run's length (s): an event after it is refused.

    Raises
    ------
    quadcog.InputError
        An event after the end of the run, or a payload beyond the vehicle's reach.
    quadcog.ParameterError
        An attach of a payload heavier than the rotors lift with what is on board.
    quadcog.PhysicalConsistencyError
        Naming the event after which the whole body is not physically consistent.
    """
    if not isinstance(vehicle, Vehicle):
        validate.fail("vehicle", "a quadcog Vehicle (the truth)", vehicle)
    if not isinstance(loads, PayloadProfile):
        validate.fail("loads", "a PayloadProfile (quadcog.sim.prepare.as_payload_profile)", loads)
    if duration is not None:
        duration = positive(duration, "duration", unit="s")
    if not loads.events:
        return
    import heapq
    on_board = {p.name: (p, p.inertial_parameters()) for p in loads.carried}
    total = vehicle.airframe.inertial_parameters() + sum(
        (pi for _, pi in on_board.values()), np.zeros(N_PI))
    ends: list = []                  # (end time, index, name, target) of sliding moves
    thrust = N_ROTORS * vehicle.max_rotor_thrust

    def place(name, payload):
        nonlocal total
        if name in on_board:
            total = total - on_board.pop(name)[1]
        if payload is not None:
            pi = payload.inertial_parameters()
            on_board[name] = (payload, pi)
            total = total + pi

    def check(i, e, when):
        if not consistency_ok(total):
            check_physically_consistent(
                total, f"payload[{i}] ({e.action} {e.name!r}): the airframe with "
                f"{list(on_board)} on board at t = {when:g} s")

    for i, e in enumerate(loads.events):
        where = f"payload[{i}] ({e.action} {e.name!r} at t = {e.t:g} s)"
        if duration is not None and e.t > duration:
            raise InputError(f"{where}: after the end of the run (duration {duration:g} s), "
                             "so it would never happen; expected t <= duration")
        if e.position is not None:
            check_reach(e.position, e.size, vehicle.arm_length, where)
        while ends and ends[0][0] <= e.t:
            end, j, name, target = heapq.heappop(ends)
            if name in on_board:
                place(name, on_board[name][0].moved(target))
                check(j, loads.events[j], end)
        if e.action == "attach":
            # the rotors must lift it with what is on board then (a 1e6 kg parcel flew)
            check_lift(e.mass, float(total[0]), vehicle.g, thrust, where)
            place(e.name, e.payload())
        elif e.action == "drop":
            place(e.name, None)
        elif e.ramp > 0:
            heapq.heappush(ends, (e.t + e.ramp, i, e.name, e.position))
        else:
            place(e.name, on_board[e.name][0].moved(e.position))
        check(i, e, e.t)
    while ends:
        end, j, name, target = heapq.heappop(ends)
        if name in on_board:
            place(name, on_board[name][0].moved(target))
            check(j, loads.events[j], end)


def whole_body(p: npt.NDArray[np.float64], payload: npt.NDArray[np.float64]
               ) -> npt.NDArray[np.float64]:
    """The paper's 14-entry p of the airframe ``p`` with payloads ``payload`` on board.

    Parameters
    ----------
    p : (14,) or (B, 14) numpy.ndarray
        The airframe's parameters, of one flight or of B flights.
    payload : (10,) numpy.ndarray
        The payloads' summed inertial parameters about O (shared by the flights).

    Returns
    -------
    (14,) or (B, 14) numpy.ndarray
        m and r_G of the whole body, the diagonal of its inertia about O, the rest of ``p``.

    Raises
    ------
    quadcog.InputError
        ``p`` not (14,) or (B, 14) finite numbers, or ``payload`` not 10.
    """
    out = validate.array(p, "p", what=f"an array of shape ({N_PARAM},) or (B, {N_PARAM})")
    if out.shape[-1:] != (N_PARAM,) or out.ndim > 2:
        validate.fail("p", f"an array of shape ({N_PARAM},) or (B, {N_PARAM})",
                      f"an array of shape {out.shape}")
    payload = validate.vector(payload, "payload", N_PI)
    m, r = body_mass_and_cog(out[..., IDX["m"], None], out[..., R_G], payload[PI_INDEX["m"]],
                             payload[[PI_INDEX[f"m{a}_G"] for a in "xyz"]])
    out[..., IDX["m"]] = m[..., 0]
    out[..., R_G] = r
    out[..., IDX["Ixx"]:IDX["Izz"] + 1] += payload[[PI_INDEX[n] for n in ("Ixx", "Iyy", "Izz")]]
    return out
