"""Closed-loop simulation of one flight: a Python step loop (any controller) and a one-call
compiled path (the closed-loop step mapaccum'd over chunks of steps, compiled). Batches of
flights are in ``quadcog.batch``.

Two vehicles take part in a run: the truth ``vehicle`` that flies, and the ``controller_model``
the controller is designed for (what it believes; by default the truth with r_G = 0, since the
CoG is what it does not know)."""
from dataclasses import dataclass, field
import math
import time
import warnings

import casadi as ca
import numpy as np

from . import config, validate
from .closed_loop import (TABLE, TABLE_SIZE, closed_loop_step, step_table,
                          truth_parameters)
from .compiled import compile_function
from .controllers.base import Controller
from .conventions import rotation_matrix
from .admissibility import LARGEST
from .errors import EulerSingularityError, InputError, QuadcogError
from .fastcall import FastCall
from .model import load
from .params import check_parameters, with_cog
from .feasibility import ReferenceWarning, check_reference
from .plant import Actuation, TruthOptions, initial_rotor_thrusts, plant_step_function
from .result import Metrics, SimulationResult, position_metrics
from .timeline import CogProfile, wrench_table
from .trajectory import POS, VEL, YAW, as_trajectory
from .validate import positive, step_count
from .vehicle import HUMMINGBIRD, Vehicle

CHUNK = 1000          # steps per compiled call
RK4_LIMIT = 2.5       # |lambda| dt below this: inside RK4's stability region with margin


@dataclass(frozen=True)
class Limits:
    """When a run counts as diverged: position error over ``max_position_error`` (m) or
    |phi| or |theta| over ``max_tilt`` (rad). Defaults: ``quadcog.config.defaults``."""
    max_position_error: float = field(
        default_factory=lambda: config.defaults["limits.max_position_error"])
    max_tilt: float = field(
        default_factory=lambda: math.radians(config.defaults["limits.max_tilt_deg"]))


_compiled_cache = {}


def _compiled(key, build):
    if key not in _compiled_cache:
        _compiled_cache[key] = compile_function(build())
    return _compiled_cache[key]


def _check_time(duration, dt):
    duration, dt = positive(duration, "duration", "s"), positive(dt, "dt", "s")
    if dt > duration:
        raise InputError(f"dt = {dt} s is longer than the duration {duration} s")
    step_count(duration, dt, config.defaults["simulate.max_steps"])


def check_step_size(controller, x0, ref0, P, dt, actuation):
    """Raise InputError if RK4 with step dt is unstable for the closed loop at the start, or
    for the motor lag.

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
                         f"magnitude {fastest:.3g} 1/s, and RK4 needs dt < {RK4_LIMIT / fastest:.3g} s")


def _prepare(trajectory, duration, dt, vehicle, cog, disturbances, x0):
    """Validate the run's inputs and tabulate them: (trajectory, P, step table, x0)."""
    _check_time(duration, dt)
    trajectory = as_trajectory(trajectory)
    P = vehicle.parameters()
    if cog is None:
        cog = CogProfile([])
    elif not isinstance(cog, CogProfile):
        if not isinstance(cog, (list, tuple)):
            validate.fail("cog", "None, a CogProfile or a list of (t, r, ramp) changes", cog)
        cog = CogProfile(list(cog))
    n = int(round(duration / dt))
    times = np.arange(n + 1) * dt
    refs = trajectory.sample(times)
    r_tab = cog.sample(times)
    # The admissible set of r_G is convex (|r|^2 - (u.r)^2 is convex for every unit u), so
    # checking where each change ends covers the ramps between them.
    for i, change in enumerate(cog.changes):
        check_parameters(with_cog(P, P[11:14] + np.asarray(change.r)),
                         f"vehicle with the CoG of cog change {i} (r = {list(change.r)} m)")
    table = step_table(times, dt, refs, r_tab, wrench_table(disturbances, times),
                       tail_from=tail_start(duration))
    x0 = start_at_reference(refs[0]) if x0 is None else validate.vector(x0, "x0", 12)
    if not np.abs(x0).max() <= LARGEST:
        validate.fail("x0", f"12 finite numbers within +-{LARGEST:g}", x0.tolist())
    return trajectory, P, table, x0


def tail_start(duration):
    """Time (s) from which the tail metrics count: the last ``metrics.tail_fraction``."""
    return (1 - config.defaults["metrics.tail_fraction"]) * duration


def start_at_reference(ref):
    """The state (12,) on the reference row ``ref`` (14,): its position and heading, level,
    moving with its velocity (expressed in body axes)."""
    x0 = np.zeros(12)
    x0[:3], x0[5] = ref[POS], ref[YAW]
    x0[6:9] = rotation_matrix(0.0, 0.0, ref[YAW]).T @ ref[VEL]
    return x0


def _position_error(X, rows):
    """|p - p_ref| per sample (N,); a diverged sample may overflow to inf, quietly."""
    with np.errstate(over="ignore", invalid="ignore"):
        return np.linalg.norm(X[:, :3] - rows[:, TABLE["ref"]][:, :3], axis=1)


def _first_divergence(x, err, limits):
    """(index, cause) of the first diverged sample, or (None, None)."""
    with np.errstate(invalid="ignore"):
        quick = (np.max(err) <= limits.max_position_error
                 and np.max(np.abs(x[:, 3:5])) <= limits.max_tilt)
    if quick:            # every comparison with NaN is False, so quick is False then
        return None, None
    finite = np.isfinite(x).all(axis=1) & np.isfinite(err)
    tilt = np.max(np.abs(x[:, 3:5]), axis=1)
    causes = [(~finite, "non-finite state"),
              (finite & (err > limits.max_position_error),
               f"position error over {limits.max_position_error:g} m"),
              (finite & (tilt > limits.max_tilt),
               f"|phi| or |theta| over {np.degrees(limits.max_tilt):.0f} deg")]
    first = [(int(np.argmax(m)), cause) for m, cause in causes if m.any()]
    if not first:
        return None, None
    return min(first)


def _singularity_check(t, x):
    th = np.abs(x[:, 4])
    hit = np.flatnonzero(np.isfinite(th) & (th >= np.pi / 2 - 1e-6))
    if hit.size:
        k = hit[0]
        raise EulerSingularityError(
            f"|theta| = {th[k]:.6f} rad reached pi/2 at t = {t[k]:.4f} s: the Euler-angle "
            f"kinematics (Q(eta2)) are singular there; lower Limits.max_tilt below 90 deg")


def run_options(truth, limits, progress):
    """The checked (TruthOptions, Limits) of a run (defaults for None); a typed error naming
    ``truth``, ``limits`` or ``progress`` when one is of the wrong kind. Shared by ``simulate``
    and ``simulate_batch``."""
    options = TruthOptions() if truth is None else truth
    if not isinstance(options, TruthOptions):
        validate.fail("truth", "a quadcog TruthOptions", truth)
    limits = Limits() if limits is None else limits
    if not isinstance(limits, Limits):
        validate.fail("limits", "a quadcog Limits", limits)
    if progress is not None and not callable(progress):
        validate.fail("progress", "None or a callable(fraction), e.g. a ProgressBar", progress)
    return options, limits


def simulate(controller, trajectory="hover", duration=10.0, dt=None, vehicle=None,
             controller_model=None, cog=None, disturbances=(), truth=None, x0=None,
             path="compiled", limits=None, progress=None, check_dt=True):
    """Fly one closed-loop run and return a SimulationResult.

    Parameters
    ----------
    controller : a quadcog Controller, or (path="python" only) a callable U = ctrl(t, x).
    trajectory : a Trajectory, 'hover' | 'circle' | 'figure8' | 'helix', or a callable
        (see quadcog.trajectory).
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
    limits : Limits of divergence.
    progress : a callable(fraction), e.g. a ProgressBar.
    check_dt : refuse a dt too large for RK4 on the closed loop at the start.

    Returns
    -------
    SimulationResult. A diverged run stops there and says when and why in result.metrics.
    """
    options, limits = run_options(truth, limits, progress)
    validate.flag(check_dt, "check_dt")
    dt = config.get("simulate.dt", dt)
    validate.choice(path, "path", ("compiled", "python"))
    is_law = isinstance(controller, Controller)
    if not is_law and not (path == "python" and callable(controller)):
        raise InputError("controller must be a quadcog Controller, or a callable U = ctrl(t, x) "
                         f"with path='python'; got {controller!r}")
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
    trajectory, P, table, x0 = _prepare(trajectory, duration, dt, vehicle, cog, disturbances, x0)
    actuation = Actuation.of(vehicle, options)
    P0 = truth_parameters(P, table[0])
    f0 = initial_rotor_thrusts(vehicle.with_parameters(P0), actuation)
    if check_dt:
        check_step_size(controller if is_law else None, x0, table[0, TABLE["ref"]], P0, dt,
                        actuation)
    t0 = time.perf_counter()
    if path == "compiled":
        X, U = _run_compiled(controller, P, table, x0, f0, actuation, limits, progress)
    else:
        X, U = _run_python(controller, P, table, x0, f0, actuation, limits, progress, is_law)
    elapsed = time.perf_counter() - t0
    result = _result(controller, X, U, table, P, duration, limits, path, elapsed,
                     actuation.n_rotor_states)
    _check_reference(result, table, vehicle, limits)
    return result


def _check_reference(result, table, vehicle, limits):
    """Metrics entry ``reference`` and a ReferenceWarning when the reference asks for more
    acceleration or jerk than the vehicle can give (quadcog.feasibility)."""
    check = check_reference(table[:, TABLE["t"]], table[:, TABLE["ref"]], vehicle,
                            limits.max_tilt)
    result.metrics.reference = check.as_dict()
    if not check.feasible:
        warnings.warn(f"the reference asks for more than the vehicle ({vehicle.name}) can "
                      f"follow from t = {check.first_violation_t:.3f} s: {check.reason}",
                      ReferenceWarning, stacklevel=3)


def chunk_function(controller, actuation, n=CHUNK):
    """Compiled Function (X0, P, rows 27 x n) -> (X, U 4 x n): n closed-loop steps.

    P is shared by all steps (mapaccum alone would expect one copy per step)."""
    def build():
        step = closed_loop_step(controller, actuation)
        acc = step.mapaccum("closed_loop_steps", n)
        X0, P = ca.MX.sym("X0", step.size1_in(0)), ca.MX.sym("P", 14)
        rows = ca.MX.sym("rows", TABLE_SIZE, n)
        Xs, Us = acc(X0, ca.repmat(P, 1, n), rows)
        return ca.Function("closed_loop_chunk", [X0, P, rows], [Xs, Us],
                           ["X0", "P", "rows"], ["X", "U"])
    return _compiled(("chunk", controller.cache_key(), actuation, n), build)


def _padded(table):
    """The table with rows appended (copies of the last) up to a whole number of chunks."""
    n_rows = -(-(table.shape[0] - 1) // CHUNK) * CHUNK + 1
    if n_rows == table.shape[0]:
        return table
    return np.vstack([table, np.repeat(table[-1:], n_rows - table.shape[0], axis=0)])


def _run_compiled(controller, P, table, x0, f0, actuation, limits, progress):
    chunk = chunk_function(controller, actuation)
    n_steps = table.shape[0] - 1
    rows = _padded(table)
    n_pad = rows.shape[0] - 1
    # C-ordered (steps, k) blocks are exactly CasADi's column-major (k, steps) matrices:
    # the compiled function reads the table and writes X and U in place, without copies.
    X = np.empty((n_pad + 1, 12 + f0.size + controller.n_state))
    U = np.empty((n_pad + 1, 4))
    X[0] = np.concatenate([x0, f0, controller.initial_state()])
    P = np.ascontiguousarray(P, dtype=float)
    buf, evaluate = chunk.buffer()
    buf.set_arg(1, memoryview(P))
    k = 0
    while k < n_steps:
        buf.set_arg(0, memoryview(X[k]))
        buf.set_arg(2, memoryview(rows[k:k + CHUNK]))
        buf.set_res(0, memoryview(X[k + 1:k + 1 + CHUNK]))
        buf.set_res(1, memoryview(U[k:k + CHUNK]))
        evaluate()
        m = min(CHUNK, n_steps - k)
        seg = slice(k, k + m + 1)
        err = _position_error(X[seg], table[seg])
        idx, _ = _first_divergence(X[seg, :12], err, limits)
        k += m
        if progress:
            progress(k / n_steps)
        if idx is not None:
            stop = seg.start + idx
            return X[:stop + 1], U[:stop + 1]
    U[n_steps] = U[n_steps - 1]
    return X[:n_steps + 1], U[:n_steps + 1]


def _run_python(controller, P, table, x0, f0, actuation, limits, progress, is_law):
    key = ("plant", actuation)
    plant = FastCall(_compiled(key, lambda: plant_step_function(load(), actuation)))
    n_steps = table.shape[0] - 1
    nc = controller.n_state if is_law else 0
    nf = f0.size
    ic = 12 + nf                 # where the controller state starts in X
    X = np.empty((n_steps + 1, ic + nc))
    U = np.empty((n_steps + 1, 4))
    X[0, :12] = x0
    X[0, 12:ic] = f0
    if nc:
        X[0, ic:] = controller.initial_state()
    law = controller.compiled() if is_law else None
    if law is not None:
        t_in, x_in, ref_in, c_in = law.inputs
        U_out, cdot_out = law.outputs
    px, pf, pU, pP, pw, pdt = plant.inputs
    x_next, f_next, U_app = plant.outputs
    ref_slice, w_slice = TABLE["ref"], TABLE["wrench"]
    refs = table[:, ref_slice]
    max_err2, max_tilt = limits.max_position_error ** 2, limits.max_tilt
    report_every = max(1, n_steps // 100)
    for k in range(n_steps):
        row = table[k]
        x = X[k, :12]
        if law is not None:
            t_in[0] = row[0]
            x_in[:] = x
            ref_in[:] = refs[k]
            if nc:
                c_in[:] = X[k, ic:]
            law()
            pU[:] = U_out
        else:
            pU[:] = _user_output(controller, row[0], x)
        px[:] = x
        if nf:
            pf[:] = X[k, 12:ic]
        pP[:] = truth_parameters(P, row)
        pw[:] = row[w_slice]
        pdt[0] = row[1]
        plant()
        X[k + 1, :12] = x_next
        if nf:
            X[k + 1, 12:ic] = f_next
        U[k] = U_app
        if nc:
            X[k + 1, ic:] = controller.project_numpy(X[k, ic:] + row[1] * cdot_out)
        # scalar checks (NaN fails every comparison); _result names the cause precisely
        r = refs[k + 1]
        dx, dy, dz = x_next[0] - r[0], x_next[1] - r[1], x_next[2] - r[2]
        if not (dx * dx + dy * dy + dz * dz <= max_err2 and abs(x_next[3]) <= max_tilt
                and abs(x_next[4]) <= max_tilt and math.isfinite(float(x_next.sum()))):
            return X[:k + 2], U[:k + 2]
        if progress and k % report_every == 0:
            progress(k / n_steps)
    U[n_steps] = U[n_steps - 1]
    if progress:
        progress(1.0)
    return X, U


def _user_output(controller, t, x):
    """U (4,) of a user's Python controller at time t, checked: a typed error naming the time
    when it is not 4 finite numbers (or when the controller raises)."""
    where = f"controller output at t = {validate.plain(float(t))} s"
    try:
        out = controller(float(t), x.copy())
    except QuadcogError:
        raise
    except Exception as e:              # the user's function failed: say when, keep the cause
        raise InputError(f"controller raised {type(e).__name__} at t = "
                         f"{validate.plain(float(t))} s: {e}") from e
    U = validate.vector(out, where, 4, finite=False)
    if not np.isfinite(U).all():
        raise InputError(f"{where}: expected 4 finite numbers, got {validate.plain(U.tolist())}")
    return U


def _first_nonfinite(X, U):
    """Index of the first sample whose state, controller state or input is not finite."""
    bad = ~(np.isfinite(X).all(axis=1) & np.isfinite(U).all(axis=1))
    return int(np.argmax(bad)) if bad.any() else None


def _result(controller, X, U, table, P, duration, limits, path, elapsed, nf):
    # never hand out NaN: a sample whose controller state or input is not finite (while x
    # may still be) ends the run before it, as a divergence
    k = _first_nonfinite(X, U[:X.shape[0]])
    if k == 0:
        raise InputError(f"the controller gives a non-finite input or state at t = 0 (U = "
                         f"{validate.plain(U[0].tolist())}): expected finite numbers; check "
                         f"its settings and the start state")
    n = X.shape[0]
    t = table[:n, TABLE["t"]]
    ref = table[:n, TABLE["ref"]]
    r_G = table[:n, TABLE["s"], None] * P[11:14] + table[:n, TABLE["r_table"]]
    err = _position_error(X, table[:n])
    idx, cause = _first_divergence(X[:, :12], err, limits)
    if k is not None and (idx is None or k <= idx):
        idx, cause = k, "non-finite controller output or state"
    if idx is not None and k == idx:
        keep = idx              # never hand out NaN arrays: drop the non-finite sample
    elif idx is not None and not np.isfinite(X[idx]).all():
        keep = idx
    else:
        keep = n if idx is None else idx + 1
    if limits.max_tilt >= np.pi / 2 - 1e-6:     # otherwise the tilt limit catches it first
        _singularity_check(t[:keep], X[:keep])
    x = X[:keep, :12]
    # the adaptive laws keep r_hat in their first three state entries
    estimating = getattr(controller, "estimates_cog", False)
    r_hat = X[:keep, 12 + nf:15 + nf] if estimating else np.zeros((keep, 3))
    metrics = Metrics(**position_metrics(t[:keep], x, ref[:keep], duration))
    if idx is not None:
        metrics.diverged, metrics.diverged_at, metrics.diverged_cause = True, float(t[idx]), cause
    if estimating:
        metrics.r_hat_final = r_hat[-1].tolist()
        metrics.r_G_final = r_G[keep - 1].tolist()
    name = getattr(controller, "name", getattr(controller, "__name__", "user controller"))
    return SimulationResult(t[:keep], x, U[:keep], ref[:keep], r_hat, r_G[:keep], metrics,
                            controller=name, path=path, info={"seconds": elapsed})
