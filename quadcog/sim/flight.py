"""Closed-loop simulation of one flight: a Python step loop (any controller) and a one-call
compiled path (the closed-loop step mapaccum'd over chunks of steps, compiled). Batches of
flights are in ``quadcog.sim.batch``.

Two vehicles take part in a run: the truth ``vehicle`` that flies, and the ``controller_model``
the controller is designed for (what it believes; by default the truth with r_G = 0, since the
CoG is what it does not know).

Controllers. A quadcog ``Controller`` runs on both paths. With ``path="python"`` any callable
with the same protocol runs too: ``ctrl(t, x, ref, c)`` returns ``U`` (4,), or ``(U, c_dot)``
when it has a state; t in s, x (12,), ref (14,) the reference row
(``quadcog.trajectories.analytic``), c its state. Optional attributes, as on a Controller:
``n_state`` (default 0), ``initial_state()`` (default zeros), ``project_numpy(c)`` (applied
after each update), ``estimates_cog`` (True when the first 3 states estimate r_G), ``name``.
"""
from collections.abc import Callable
import math
import time
from typing import Any
import warnings

import numpy as np
import numpy.typing as npt

from quadcog import config, validate
from quadcog.codegen.compiled import cached_compile
from quadcog.codegen.fastcall import FastCall
from quadcog.controllers.base import Controller
from quadcog.errors import InputError, ReferenceWarning
from quadcog.model.conventions import IDX, N_STATE, R_G
from quadcog.model.functions import load
from quadcog.sim.closed_loop import CHUNK, chunk_function, flight_kernel
from quadcog.sim.divergence import (
    DivergenceCause,
    Limits,
    check_euler_singularity,
    divergence_rule,
    first_divergence,
    magnitude,
)
from quadcog.sim.plant import PI_INDEX, TruthOptions, body_mass_and_cog, plant_step_function
from quadcog.sim.prepare import (
    RK4_LIMIT,
    as_cog_profile,
    check_cog_changes,
    check_step_size,
    check_time,
    prepare_flight,
    run_options,
    start_at_reference,
)
from quadcog.sim.result import SimulationResult, flight_metrics, position_errors
from quadcog.sim.schedule import STEP_INPUTS, Schedule, truth_parameters
from quadcog.sim.sensing import Sensed, Sensing
from quadcog.sim.user_controller import user_call
from quadcog.trajectories.feasibility import check_reference
from quadcog.vehicles.vehicle import Vehicle

# check_time ... start_at_reference live in quadcog.sim.prepare; importable here as before
__all__ = ["simulate", "check_time", "check_step_size", "start_at_reference", "run_options",
           "as_cog_profile", "check_cog_changes", "RK4_LIMIT", "Limits"]


def simulate(controller: Controller | Callable[..., Any], trajectory: Any = "hover",
             duration: float = 10.0, dt: float | None = None, vehicle: Vehicle | None = None,
             controller_model: Vehicle | None = None, cog: Any = None, disturbances: Any = (),
             truth: TruthOptions | None = None, x0: npt.ArrayLike | None = None,
             path: str = "compiled", limits: Limits | None = None,
             progress: Callable[[float], Any] | None = None, check_dt: bool = True,
             sensing: Sensing | None = None, payloads: Any = None) -> SimulationResult:
    """Fly one closed-loop run and return a SimulationResult.

    Parameters
    ----------
    controller : Controller or callable
        A quadcog Controller, or (path="python" only) a callable with the same protocol,
        ``ctrl(t, x, ref, c) -> U or (U, c_dot)`` (see the module docstring).
    trajectory : Trajectory, str or callable
        A Trajectory, 'hover' | 'circle' | 'figure8' | 'helix', or a callable (see
        quadcog.trajectories.analytic).
    duration : float
        Seconds (fixed-step RK4).
    dt : float, optional
        The step (s); default ``quadcog.config.defaults["simulate.dt"]``, 1 ms.
    vehicle : Vehicle, optional
        The truth Vehicle that flies (default: the controller's model, or the Hummingbird
        for a callable). Its CoG during the run is ``vehicle.r_G + cog(t)``.
    controller_model : Vehicle, optional
        The Vehicle the controller is designed for, i.e. what it believes (default:
        ``vehicle`` with r_G = 0 when ``vehicle`` is given, else the controller's own model).
        The controller is redesigned for it with ``controller.for_vehicle``.
    cog : CogProfile or list of (t, r, ramp), optional
        The CoG changes (s, m in the body frame, s).
    disturbances : sequence of Disturbance
        Wrench pulses.
    truth : TruthOptions, optional
        Parallel axis, rotor saturation, motor lag; default all off.
    x0 : (12,) array_like, optional
        Initial state [m, rad, m/s, rad/s] (default: at the reference, level, with the
        reference velocity).
    path : {"compiled", "python"}
        "compiled" (the flight kernel: one compiled call for the whole flight, one per 1000
        steps with a progress callback; CasADi's compiled chunks without a C compiler) or
        "python" (a step loop).
    limits : Limits, optional
        Limits of divergence (default ``Limits()``).
    progress : callable, optional
        ``progress(fraction)``, e.g. a ProgressBar.
    check_dt : bool
        Refuse a dt too large for RK4 on the closed loop at the start.
    sensing : Sensing, optional
        Noise, gyro bias, one-period delay of what the controller measures; default None,
        the perfect state. The controller is flown as ``Sensed(controller, sensing, dt)``.
    payloads : sequence of PayloadEvent or dict, optional
        Payloads attached, moved and dropped during the run
        (``quadcog.sim.timeline.PayloadEvent``: t, action "attach" | "move" | "drop", name,
        mass, position, size, ramp), in time order; the vehicle's own ``payloads`` are on
        board from the start. The truth model flies the whole body; the controller's model
        does not know them.

    Returns
    -------
    SimulationResult
        A diverged run stops at the first diverged sample (kept when finite); result.metrics
        counts the samples before it and says when and why.

    Raises
    ------
    quadcog.InputError
        An argument that is wrong (named, with what was expected), or a controller that
        gives a non-finite input or state at t = 0.
    quadcog.ParameterError
        A vehicle that is inadmissible with one of the CoG changes.
    quadcog.PhysicalConsistencyError
        An airframe that with the payloads on board is no rigid body's.
    quadcog.EulerSingularityError
        |theta| reached pi/2 (only with a tilt limit at or above 90 deg).
    """
    if sensing is not None:
        if not isinstance(controller, Controller):
            validate.fail("controller", "a quadcog Controller when sensing is given (a Python "
                          "callable measures what it likes itself)", controller)
        controller = Sensed(controller, sensing, config.get("simulate.dt", dt))
    setup = prepare_flight(controller, trajectory, duration, dt, vehicle, controller_model, cog,
                           disturbances, truth, x0, path, limits, progress, check_dt, payloads)
    progress = validate.user_function(progress, "progress") if progress else None
    t0 = time.perf_counter()
    if setup.path == "compiled":
        X, U, e, code = _run_compiled(setup, progress)
    else:
        X, U, e, code = _run_python(setup, progress)
    elapsed = time.perf_counter() - t0
    result = _result(setup, X, U, e, code, elapsed)
    _check_reference(result, setup.schedule, setup.vehicle, setup.limits)
    return result


def _check_reference(result: SimulationResult, schedule: Schedule, vehicle: Vehicle,
                     limits: Limits) -> None:
    """Metrics entry ``reference`` and a ReferenceWarning when the reference asks for more
    acceleration or jerk than the vehicle can give (quadcog.trajectories.feasibility)."""
    check = check_reference(schedule.t, schedule.ref, vehicle, limits.max_tilt,
                            schedule.constant_reference)
    result.metrics.reference = check.as_dict()
    if not check.feasible:
        warnings.warn(f"the reference asks for more than the vehicle ({vehicle.name}) can "
                      f"follow from t = {check.first_violation_t:.3f} s: {check.reason}",
                      ReferenceWarning, stacklevel=3)


def _run_compiled(setup, progress):
    kernel = flight_kernel(setup.controller, setup.actuation, setup.limits)
    if kernel is None:
        return _run_chunks(setup, progress)
    schedule, X0, n_steps = setup.schedule, setup.X0, setup.schedule.n_steps
    X, U, e, codes = _outputs(n_steps, X0.size)
    X[0] = X0
    run = kernel.bind(X, [np.ascontiguousarray(setup.P, dtype=float)]
                      + [getattr(schedule, name) for name, _ in STEP_INPUTS], [U, e, codes])
    # one call without a progress bar; with one, a call per CHUNK steps to report between
    every = CHUNK if progress else n_steps
    k = 0
    while k < n_steps:
        m = min(every, n_steps - k)
        stop = run(k, k + m)
        if stop < k + m:        # the step's divergence rule ran on samples k .. stop
            return X[:stop + 1], U[:stop + 1], e[:stop + 1], int(codes[stop])
        k += m
        if progress:
            progress(k / n_steps)
    U[n_steps] = U[n_steps - 1]
    return X, U, _last_error(e, X, schedule), 0


def _outputs(n_steps, n_x):
    """X (n_steps + 1, n_x), U (n_steps + 1, 4), e (n_steps + 1,) and codes (n_steps,): views
    of one block. One allocation, not four: glibc maps each large block afresh, and the
    kernel then pays a page fault per 4 KiB it first writes (about 700, a millisecond, for a
    20 s flight); one block is mostly served again from what the last flight freed."""
    n = n_steps + 1
    sizes = np.cumsum([0, n * n_x, n * 4, n, n_steps])
    block = np.empty(int(sizes[-1]))
    X, U, e, codes = (block[a:b] for a, b in zip(sizes[:-1], sizes[1:]))
    return X.reshape(n, n_x), U.reshape(n, 4), e, codes


def _last_error(e, X, schedule):
    """e with its last entry, the final sample's position error, which no step computed."""
    n = X.shape[0]
    e[n - 1:n] = position_errors(X[n - 1:n], schedule.ref[n - 1:n])
    return e[:n]


def _run_chunks(setup, progress):
    """The steps through CasADi's compiled chunks (``chunk_function``): where the C loop of
    ``flight_kernel`` cannot be built (without a C compiler, CasADi's virtual machine)."""
    controller, P, schedule, X0 = setup.controller, setup.P, setup.schedule, setup.X0
    actuation, limits = setup.actuation, setup.limits
    chunk = chunk_function(controller, actuation, limits)
    n_steps = schedule.n_steps
    padded = schedule.padded(CHUNK)
    # C-ordered (steps, k) blocks are exactly CasADi's column-major (k, steps) matrices:
    # the compiled function reads the schedule and writes X and U in place, without copies.
    X = np.empty((padded.n_steps + 1, X0.size))
    U = np.empty((padded.n_steps + 1, 4))
    e = np.empty(padded.n_steps + 1)
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
        buf.set_res(2, memoryview(e[k:k + CHUNK]))
        buf.set_res(3, memoryview(codes[k:k + CHUNK]))
        evaluate()
        m = min(CHUNK, n_steps - k)
        # the step's divergence rule ran on samples k .. k + m - 1; the next chunk (or the
        # check below) covers sample k + m
        hit = np.flatnonzero(codes[k:k + m])
        if hit.size:
            stop = k + int(hit[0])
            return X[:stop + 1], U[:stop + 1], e[:stop + 1], int(codes[stop])
        k += m
        if progress:
            progress(k / n_steps)
    U[n_steps] = U[n_steps - 1]
    return X[:n_steps + 1], U[:n_steps + 1], _last_error(e, X[:n_steps + 1], schedule), 0


def _run_python(setup, progress):
    controller, P, schedule, X0 = setup.controller, setup.P, setup.schedule, setup.X0
    actuation, limits, is_law = setup.actuation, setup.limits, setup.is_law
    plant = FastCall(cached_compile(("plant", actuation),
                                    lambda: plant_step_function(load(), actuation)))
    rule = FastCall(divergence_rule(limits))
    n_steps = schedule.n_steps
    nf = actuation.n_rotor_states
    ic = N_STATE + nf                 # where the controller state starts in X
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
        call, project = user_call(controller, nc)
    px, pf, pU, pP, pload, pr, pw, pdt = plant.inputs
    pr[:] = P[R_G]
    x_next, f_next, U_app = plant.outputs
    rule_x, rule_e, rule_rest = rule.inputs
    code = rule.outputs[0]
    s = schedule
    report_every = max(1, n_steps // 100)
    with np.errstate(over="ignore", invalid="ignore"):     # a diverging step may overflow
        for k in range(n_steps):
            x, c = X[k, :N_STATE], X[k, ic:]
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
            pf[:] = X[k, N_STATE:ic]
            pP[:] = truth_parameters(P, s.cog_scale[k], s.cog[k])
            pload[:] = s.payload[k]
            pw[:] = s.wrench[k]
            pdt[0] = s.dt[k]
            plant()
            U[k] = U_app
            # the divergence rule on sample k, as the compiled step has it
            d = x[:3] - s.ref[k, :3]
            rule_x[:] = x
            rule_e[0] = math.sqrt(d @ d)
            rule_rest[0] = magnitude(X[k, N_STATE:]) + magnitude(pU)
            rule.eval()
            if code[0]:
                return X[:k + 1], U[:k + 1], position_errors(X[:k + 1], s.ref[:k + 1]), \
                    int(code[0])
            X[k + 1, :N_STATE] = x_next
            X[k + 1, N_STATE:ic] = f_next
            if nc:
                X[k + 1, ic:] = project(c + s.dt[k] * c_dot, s.t[k + 1])
            if progress and k % report_every == 0:
                progress(k / n_steps)
    U[n_steps] = U[n_steps - 1]
    if progress:
        progress(1.0)
    return X, U, position_errors(X, s.ref), 0


def _result(setup, X, U, e, code, elapsed):
    """The SimulationResult of samples X (n, .), applied inputs U (n, 4) and position errors
    e (n,). The loops stop
    at the first diverged sample, with its divergence code (0: none); the final sample of a
    finished run, which no step has checked, is checked here with the same rule."""
    controller, schedule, P, limits = setup.controller, setup.schedule, setup.P, setup.limits
    path, nf = setup.path, setup.n_rotor_states
    n = X.shape[0]
    t, ref = schedule.t[:n], schedule.ref[:n]
    # the whole body's mass and CoG: the airframe at its CoG profile with the payloads
    load = schedule.payload[:n]
    if load[:, PI_INDEX["m"]].any():     # a payload's mass is > 0: its column alone says
        mass, r_G = body_mass_and_cog(P[IDX["m"]], schedule.r_G(P[R_G])[:n],
                                      load[:, PI_INDEX["m"], None],
                                      load[:, [PI_INDEX[f"m{a}_G"] for a in "xyz"]])
        mass = mass[:, 0]
    else:       # nothing on board: what body_mass_and_cog gives then (m + 0, r + 0)
        mass, r_G = np.full(n, P[IDX["m"]] + 0.0), schedule.r_G(P[R_G])[:n]
        r_G += 0.0          # in place: r_G gives a new array
    if code:
        idx, cause = n - 1, DivergenceCause(code)
    else:
        idx, cause = first_divergence(X[-1:, :N_STATE], e[-1:], limits,
                                      magnitude(X[-1:, N_STATE:]))
        idx = None if idx is None else n - 1
    if idx == 0:       # x0 was checked: the controller's first output or state is not finite
        raise InputError(f"the controller gives a non-finite input or state at t = 0 (U = "
                         f"{validate.plain(U[0].tolist())}): expected finite numbers; check "
                         f"its settings and the start state")
    keep = n
    if idx is not None:    # never hand out NaN arrays: drop a non-finite diverged sample
        finite = np.isfinite(X[idx]).all() and np.isfinite(U[idx]).all()
        keep = idx + 1 if finite else idx
    if not setup.actuation.options.quaternion:      # on SE(3) the truth has no singularity
        check_euler_singularity(t[:keep], X[:keep], limits)
    metrics = flight_metrics(e, schedule.tail[:n], idx, None if idx is None else t[idx],
                             cause, limits)
    x = X[:keep, :N_STATE]
    estimating = bool(getattr(controller, "estimates_cog", False))
    r_hat = X[:keep, N_STATE + nf:N_STATE + 3 + nf] if estimating else np.zeros((keep, 3))
    if estimating:
        last = n - 1 if idx is None else idx - 1       # the last counted sample
        metrics.r_hat_final = X[last, N_STATE + nf:N_STATE + 3 + nf].tolist()
        metrics.r_G_final = r_G[last].tolist()
    name = getattr(controller, "name", getattr(controller, "__name__", "user controller"))
    inverse = setup.actuation.mixer_inverse().T
    if nf:
        thrust = X[:keep, N_STATE:N_STATE + nf].copy()
    else:               # in place: no second (n, 4) array
        thrust = U[:keep] @ inverse
        np.clip(thrust, setup.actuation.lower, setup.actuation.upper, out=thrust)
    Xk, tk, refk, Uk = X[:keep], t[:keep], ref[:keep], U[:keep]
    command = lambda: _commanded(controller, tk, Xk, refk, nf, Uk) @ inverse   # on first use
    return SimulationResult(t[:keep], x, U[:keep], ref[:keep], r_hat, r_G[:keep], metrics,
                            controller=name, path=path, info={"seconds": elapsed},
                            rotor_thrust=thrust, mass=mass[:keep],
                            controller_state=X[:keep, N_STATE + nf:], _command_law=command)


def _commanded(controller, t, X, ref, nf, U_applied):
    """The input U (n, 4) the law asked for at each sample, before the rotors' limits (the
    result's U is what the rotors gave): the law re-evaluated along the flight, all samples
    in one mapped call. A user's callable (path="python") is called sample by sample."""
    n = len(t)
    if not n:
        return U_applied.copy()
    c = X[:, N_STATE + nf:]
    if isinstance(controller, Controller):
        law = controller.function().map(n)
        U = law(t[None, :], X[:, :N_STATE].T, ref.T, c.T)[0]
        return np.array(U).T.reshape(n, 4)
    out = np.empty((n, 4))
    for k in range(n):
        r = controller(float(t[k]), X[k, :N_STATE].copy(), ref[k].copy(), c[k].copy())
        out[k] = np.asarray(r[0] if isinstance(r, tuple) and len(r) == 2 else r, float)
    return out


