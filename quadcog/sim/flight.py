"""Closed-loop simulation of one flight: a Python step loop (any controller) and a one-call
compiled path (the closed-loop step mapaccum'd over chunks of steps, compiled). Batches of
flights are in ``quadcog.sim.batch``.

Two vehicles take part in a run: the truth ``vehicle`` that flies, and the ``controller_model``
the controller is designed for (what it believes; by default the truth with r_G = 0, since the
CoG is what it does not know).

Controllers. A quadcog ``Controller`` runs on both paths. With ``path="python"`` any callable
with the same protocol runs too: ``ctrl(t, x, ref, c)`` returns ``U`` (4,), or ``(U, c_dot)``
when it has a state; t in s, x (12,), ref (14,) the reference row (``quadcog.trajectories.analytic``), c
its state. Optional attributes, as on a Controller: ``n_state`` (default 0),
``initial_state()`` (default zeros), ``project_numpy(c)`` (applied after each update),
``estimates_cog`` (True when the first 3 states estimate r_G), ``name``.
"""
import math
import time
import warnings

import numpy as np

from quadcog import config, validate
from quadcog.sim.closed_loop import CHUNK, chunk_function
from quadcog.codegen.compiled import cached_compile
from quadcog.controllers.base import Controller
from quadcog.model.conventions import R_G, rotation_matrix
from quadcog.model.admissibility import LARGEST
from quadcog.sim.divergence import (DivergenceCause, Limits, check_euler_singularity,
                                    divergence_rule, first_divergence, magnitude)
from quadcog.errors import InputError, QuadcogError
from quadcog.codegen.fastcall import FastCall
from quadcog.model.functions import load
from quadcog.model.parameters import check_parameters, with_cog
from quadcog.trajectories.feasibility import ReferenceWarning, check_reference
from quadcog.sim.plant import Actuation, TruthOptions, initial_rotor_thrusts, plant_step_function
from quadcog.sim.result import SimulationResult, flight_metrics, position_errors
from quadcog.sim.schedule import Schedule, cog_at, truth_parameters
from quadcog.sim.timeline import CogProfile
from quadcog.trajectories.analytic import POS, VEL, YAW, as_trajectory
from quadcog.validate import positive, step_count
from quadcog.vehicles.vehicle import HUMMINGBIRD, Vehicle

RK4_LIMIT = 2.5       # |lambda| dt below this: inside RK4's stability region with margin

__all__ = ["simulate", "check_time", "check_step_size", "start_at_reference", "run_options",
           "RK4_LIMIT", "Limits"]


def check_time(duration, dt):
    """(duration, dt) as floats; InputError unless both are positive numbers (s), dt <=
    duration and the step count is within ``config.defaults["simulate.max_steps"]``."""
    duration, dt = positive(duration, "duration", "s"), positive(dt, "dt", "s")
    if dt > duration:
        raise InputError(f"dt = {dt} s is longer than the duration {duration} s")
    step_count(duration, dt, config.defaults["simulate.max_steps"])
    return duration, dt


def run_options(truth, limits, progress):
    """The checked (TruthOptions, Limits) of a run (defaults for None); a typed error naming
    ``truth``, ``limits`` or ``progress`` when one is of the wrong kind. Shared by ``simulate``
    and the batch paths."""
    options = TruthOptions() if truth is None else truth
    if not isinstance(options, TruthOptions):
        validate.fail("truth", "a quadcog TruthOptions", truth)
    limits = Limits() if limits is None else limits
    if not isinstance(limits, Limits):
        validate.fail("limits", "a quadcog Limits", limits)
    if progress is not None and not callable(progress):
        validate.fail("progress", "None or a callable(fraction), e.g. a ProgressBar", progress)
    return options, limits


def check_step_size(controller, x0, ref0, P, dt, actuation):
    """Raise InputError if RK4 with step dt is unstable for the closed loop at the start, or
    for the motor lag. ``controller`` may be None (a Python controller: no closed-loop check).

    The closed-loop Jacobian d/dx f(x, U(x)) at (x0, ref0) comes from CasADi AD."""
    if actuation.n_rotor_states and dt / actuation.time_constant > RK4_LIMIT:
        raise InputError(f"dt = {dt} s is too large for the motor time constant "
                         f"{actuation.time_constant} s: RK4 needs dt < "
                         f"{RK4_LIMIT * actuation.time_constant:.3g} s")
    if controller is None:
        return
    lam = np.linalg.eigvals(np.array(controller.closed_loop_jacobian()(x0, ref0, P)))
    fastest = float(np.max(np.abs(lam)))
    if fastest * dt > RK4_LIMIT:
        raise InputError(f"dt = {dt} s is too large: the closed loop has an eigenvalue of "
                         f"magnitude {fastest:.3g} 1/s, and RK4 needs dt < "
                         f"{RK4_LIMIT / fastest:.3g} s")


def start_at_reference(ref):
    """The state (12,) on the reference row ``ref`` (14,): its position and heading, level,
    moving with its velocity (expressed in body axes)."""
    x0 = np.zeros(12)
    x0[:3], x0[5] = ref[POS], ref[YAW]
    x0[6:9] = rotation_matrix(0.0, 0.0, ref[YAW]).T @ ref[VEL]
    return x0


def as_cog_profile(cog):
    """A CogProfile from ``cog`` (None, a CogProfile or a list of (t, r, ramp) changes)."""
    if cog is None:
        return CogProfile([])
    if isinstance(cog, CogProfile):
        return cog
    if not isinstance(cog, (list, tuple)):
        validate.fail("cog", "None, a CogProfile or a list of (t, r, ramp) changes", cog)
    return CogProfile(list(cog))


def check_cog_changes(P, cog):
    """Raise ParameterError if the vehicle (parameters P) is inadmissible with any CoG of the
    profile. The admissible set of r_G is convex (|r|^2 - (u.r)^2 is convex for every unit u),
    so checking where each change ends covers the ramps between them."""
    for i, change in enumerate(cog.changes):
        check_parameters(with_cog(P, cog_at(P[R_G], 1.0, np.asarray(change.r))),
                         f"vehicle with the CoG of cog change {i} (r = {list(change.r)} m)")


def simulate(controller, trajectory="hover", duration=10.0, dt=None, vehicle=None,
             controller_model=None, cog=None, disturbances=(), truth=None, x0=None,
             path="compiled", limits=None, progress=None, check_dt=True):
    """Fly one closed-loop run and return a SimulationResult.

    Parameters
    ----------
    controller : a quadcog Controller, or (path="python" only) a callable with the same
        protocol, ``ctrl(t, x, ref, c) -> U or (U, c_dot)`` (see the module docstring).
    trajectory : a Trajectory, 'hover' | 'circle' | 'figure8' | 'helix', or a callable
        (see quadcog.trajectories.analytic).
    duration, dt : seconds (fixed-step RK4; dt defaults to
        ``quadcog.config.defaults["simulate.dt"]``, 1 ms).
    vehicle : the truth Vehicle that flies (default: the controller's model, or the
        Hummingbird for a callable). Its CoG during the run is ``vehicle.r_G + cog(t)``.
    controller_model : the Vehicle the controller is designed for, i.e. what it believes
        (default: ``vehicle`` with r_G = 0 when ``vehicle`` is given, else the controller's own
        model). The controller is redesigned for it with ``controller.for_vehicle``.
    cog : a CogProfile or a list of (t, r, ramp) changes (m, body frame).
    disturbances : Disturbance pulses.
    truth : TruthOptions (parallel axis, rotor saturation, motor lag); default all off.
    x0 : initial state (12,) (default: at the reference, level, with the reference velocity).
    path : "compiled" (one compiled call per 1000 steps) or "python" (a step loop).
    limits : Limits of divergence (default ``Limits()``).
    progress : a callable(fraction), e.g. a ProgressBar.
    check_dt : refuse a dt too large for RK4 on the closed loop at the start.

    Returns
    -------
    SimulationResult. A diverged run stops at the first diverged sample (kept when finite);
    result.metrics counts the samples before it and says when and why.
    """
    options, limits = run_options(truth, limits, progress)
    validate.flag(check_dt, "check_dt")
    dt = config.get("simulate.dt", dt)
    validate.choice(path, "path", ("compiled", "python"))
    is_law = isinstance(controller, Controller)
    if not is_law and not (path == "python" and callable(controller)):
        raise InputError("controller must be a quadcog Controller, or a callable "
                         f"ctrl(t, x, ref, c) with path='python'; got {controller!r}")
    if vehicle is None:
        vehicle = controller.vehicle if is_law else HUMMINGBIRD
        model_default = vehicle
    else:
        model_default = vehicle.with_cog(np.zeros(3)) if isinstance(vehicle, Vehicle) else None
    for name, v in (("vehicle", vehicle), ("controller_model", controller_model)):
        if v is not None and not isinstance(v, Vehicle):
            raise InputError(f"{name} must be a quadcog Vehicle, got {v!r}")
    if is_law:
        controller = controller.for_vehicle(controller_model or model_default)
    duration, dt = check_time(duration, dt)
    trajectory = as_trajectory(trajectory)
    cog = as_cog_profile(cog)
    P = vehicle.parameters()
    check_cog_changes(P, cog)
    schedule = Schedule.build(trajectory, duration, dt, cog, disturbances)
    x0 = start_at_reference(schedule.ref[0]) if x0 is None else validate.vector(x0, "x0", 12)
    if not np.abs(x0).max() <= LARGEST:
        validate.fail("x0", f"12 finite numbers within +-{LARGEST:g}", x0.tolist())
    _, cause = first_divergence(x0[None, :], position_errors(x0[None, :], schedule.ref[:1]),
                                limits)
    if cause is not None:
        raise InputError(f"x0 = {x0.tolist()} has already diverged: {cause.describe(limits)}")
    actuation = Actuation.of(vehicle, options)
    P0 = truth_parameters(P, schedule.cog_scale[0], schedule.cog[0])
    f0 = initial_rotor_thrusts(vehicle.with_parameters(P0), actuation)
    if check_dt:
        check_step_size(controller if is_law else None, x0, schedule.ref[0], P0, dt, actuation)
    n_state, c0 = ((controller.n_state, controller.initial_state()) if is_law
                   else _user_state(controller))
    X0 = np.concatenate([x0, f0, c0])
    t0 = time.perf_counter()
    if path == "compiled":
        X, U, code = _run_compiled(controller, P, schedule, X0, actuation, limits, progress)
    else:
        X, U, code = _run_python(controller, P, schedule, X0, actuation, limits, progress,
                                 is_law)
    elapsed = time.perf_counter() - t0
    result = _result(controller, X, U, code, schedule, P, limits, path, elapsed, f0.size)
    _check_reference(result, schedule, vehicle, limits)
    return result


def _check_reference(result, schedule, vehicle, limits):
    """Metrics entry ``reference`` and a ReferenceWarning when the reference asks for more
    acceleration or jerk than the vehicle can give (quadcog.trajectories.feasibility)."""
    check = check_reference(schedule.t, schedule.ref, vehicle, limits.max_tilt)
    result.metrics.reference = check.as_dict()
    if not check.feasible:
        warnings.warn(f"the reference asks for more than the vehicle ({vehicle.name}) can "
                      f"follow from t = {check.first_violation_t:.3f} s: {check.reason}",
                      ReferenceWarning, stacklevel=3)


def _run_compiled(controller, P, schedule, X0, actuation, limits, progress):
    chunk = chunk_function(controller, actuation, limits)
    n_steps = schedule.n_steps
    padded = schedule.padded(CHUNK)
    # C-ordered (steps, k) blocks are exactly CasADi's column-major (k, steps) matrices:
    # the compiled function reads the schedule and writes X and U in place, without copies.
    X = np.empty((padded.n_steps + 1, X0.size))
    U = np.empty((padded.n_steps + 1, 4))
    codes = np.empty(padded.n_steps)
    X[0] = X0
    P = np.ascontiguousarray(P, dtype=float)
    buf, evaluate = chunk.buffer()
    buf.set_arg(1, memoryview(P))
    k = 0
    while k < n_steps:
        buf.set_arg(0, memoryview(X[k]))
        for i, a in enumerate(padded.block(k, k + CHUNK)):
            buf.set_arg(2 + i, memoryview(a))
        buf.set_res(0, memoryview(X[k + 1:k + 1 + CHUNK]))
        buf.set_res(1, memoryview(U[k:k + CHUNK]))
        buf.set_res(2, memoryview(codes[k:k + CHUNK]))
        evaluate()
        m = min(CHUNK, n_steps - k)
        # the step's divergence rule ran on samples k .. k + m - 1; the next chunk (or the
        # check below) covers sample k + m
        hit = np.flatnonzero(codes[k:k + m])
        if hit.size:
            stop = k + int(hit[0])
            return X[:stop + 1], U[:stop + 1], int(codes[stop])
        k += m
        if progress:
            progress(k / n_steps)
    U[n_steps] = U[n_steps - 1]
    return X[:n_steps + 1], U[:n_steps + 1], 0


def _guarded(fn, what, when, *args):
    """``fn(*args)`` of a user's controller; an exception it raises becomes an InputError
    naming ``what`` and ``when`` (the cause kept)."""
    try:
        return fn(*args)
    except QuadcogError:
        raise
    except Exception as e:              # the user's function failed: say when, keep the cause
        hint = (" (a Python controller is called as ctrl(t, x, ref, c))"
                if isinstance(e, TypeError) and "positional argument" in str(e) else "")
        raise InputError(f"{what} raised {type(e).__name__} at {when}: {e}{hint}") from e


def _finite(value, where, n):
    """``value`` as n finite numbers, else an InputError naming ``where``."""
    a = validate.vector(value, where, n, finite=False)
    if not np.isfinite(a).all():
        raise InputError(f"{where}: expected {n} finite numbers, got {validate.plain(a.tolist())}")
    return a


def _user_call(controller, n_state):
    """(call, project) for a user's Python controller: ``call(t, x, ref, c)`` returns
    (U (4,), c_dot (n_state,)) and ``project(c, t)`` its optional ``project_numpy(c)``,
    checked: a typed error naming the time when the controller raises or returns anything but
    finite numbers of those shapes."""
    user_project = getattr(controller, "project_numpy", None)

    def call(t, x, ref, c):
        when = f"t = {validate.plain(float(t))} s"
        out = _guarded(controller, "controller", when, float(t), x.copy(), ref.copy(), c.copy())
        U, c_dot = out if isinstance(out, tuple) and len(out) == 2 else (out, np.zeros(0))
        return (_finite(U, f"controller output at {when}", 4),
                _finite(c_dot, f"controller output c_dot at {when}", n_state))

    def project(c, t):
        if user_project is None:
            return c
        when = f"t = {validate.plain(float(t))} s"
        return _finite(_guarded(user_project, "controller.project_numpy", when, c.copy()),
                       f"controller.project_numpy output at {when}", n_state)
    return call, project


def _user_state(controller):
    """(n_state, c0) of a user's Python controller: its optional ``n_state`` and
    ``initial_state()`` (default 0 and zeros), checked."""
    n = validate.integer(getattr(controller, "n_state", 0), "controller.n_state", lo=0,
                         hi=10_000)
    if not hasattr(controller, "initial_state"):
        return n, np.zeros(n)
    c0 = _guarded(controller.initial_state, "controller.initial_state()", "the start")
    return n, _finite(c0, "controller.initial_state()", n)


def _run_python(controller, P, schedule, X0, actuation, limits, progress, is_law):
    plant = FastCall(cached_compile(("plant", actuation),
                                    lambda: plant_step_function(load(), actuation)))
    rule = FastCall(divergence_rule(limits))
    n_steps = schedule.n_steps
    nf = actuation.n_rotor_states
    ic = 12 + nf                 # where the controller state starts in X
    nc = X0.size - ic
    X = np.empty((n_steps + 1, X0.size))
    U = np.empty((n_steps + 1, 4))
    X[0] = X0
    if is_law:
        law = controller.compiled()
        t_in, x_in, ref_in, c_in = law.inputs
        U_out, cdot_out = law.outputs
        project = lambda c, t: controller.project_numpy(c)
    else:
        call, project = _user_call(controller, nc)
    px, pf, pU, pP, pw, pdt = plant.inputs
    x_next, f_next, U_app = plant.outputs
    rule_x, rule_e, rule_rest = rule.inputs
    code = rule.outputs[0]
    s = schedule
    report_every = max(1, n_steps // 100)
    with np.errstate(over="ignore", invalid="ignore"):     # a diverging step may overflow
        for k in range(n_steps):
            x, c = X[k, :12], X[k, ic:]
            if is_law:
                t_in[0] = s.t[k]
                x_in[:] = x
                ref_in[:] = s.ref[k]
                c_in[:] = c
                law()
                pU[:] = U_out
                c_dot = cdot_out
            else:
                pU[:], c_dot = call(float(s.t[k]), x, s.ref[k], c)
            px[:] = x
            pf[:] = X[k, 12:ic]
            pP[:] = truth_parameters(P, s.cog_scale[k], s.cog[k])
            pw[:] = s.wrench[k]
            pdt[0] = s.dt[k]
            plant()
            U[k] = U_app
            # the divergence rule on sample k, as the compiled step has it
            d = x[:3] - s.ref[k, :3]
            rule_x[:] = x
            rule_e[0] = math.sqrt(d @ d)
            rule_rest[0] = magnitude(X[k, 12:]) + magnitude(pU)
            rule.eval()
            if code[0]:
                return X[:k + 1], U[:k + 1], int(code[0])
            X[k + 1, :12] = x_next
            X[k + 1, 12:ic] = f_next
            if nc:
                X[k + 1, ic:] = project(c + s.dt[k] * c_dot, s.t[k + 1])
            if progress and k % report_every == 0:
                progress(k / n_steps)
    U[n_steps] = U[n_steps - 1]
    if progress:
        progress(1.0)
    return X, U, 0


def _result(controller, X, U, code, schedule, P, limits, path, elapsed, nf):
    """The SimulationResult of samples X (n, .) and applied inputs U (n, 4). Both loops stop
    at the first diverged sample, with its divergence code (0: none); the final sample of a
    finished run, which no step has checked, is checked here with the same rule."""
    n = X.shape[0]
    t, ref = schedule.t[:n], schedule.ref[:n]
    r_G = schedule.r_G(P[R_G])[:n]
    e = position_errors(X, ref)
    if code:
        idx, cause = n - 1, DivergenceCause(code)
    else:
        idx, cause = first_divergence(X[-1:, :12], e[-1:], limits, magnitude(X[-1:, 12:]))
        idx = None if idx is None else n - 1
    if idx == 0:       # x0 was checked: the controller's first output or state is not finite
        raise InputError(f"the controller gives a non-finite input or state at t = 0 (U = "
                         f"{validate.plain(U[0].tolist())}): expected finite numbers; check "
                         f"its settings and the start state")
    keep = n
    if idx is not None:    # never hand out NaN arrays: drop a non-finite diverged sample
        finite = np.isfinite(X[idx]).all() and np.isfinite(U[idx]).all()
        keep = idx + 1 if finite else idx
    check_euler_singularity(t[:keep], X[:keep], limits)
    metrics = flight_metrics(e, schedule.tail[:n], idx, None if idx is None else t[idx],
                             cause, limits)
    x = X[:keep, :12]
    estimating = bool(getattr(controller, "estimates_cog", False))
    r_hat = X[:keep, 12 + nf:15 + nf] if estimating else np.zeros((keep, 3))
    if estimating:
        last = n - 1 if idx is None else idx - 1       # the last counted sample
        metrics.r_hat_final = X[last, 12 + nf:15 + nf].tolist()
        metrics.r_G_final = r_G[last].tolist()
    name = getattr(controller, "name", getattr(controller, "__name__", "user controller"))
    return SimulationResult(t[:keep], x, U[:keep], ref[:keep], r_hat, r_G[:keep], metrics,
                            controller=name, path=path, info={"seconds": elapsed})
