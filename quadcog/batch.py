"""Many flights at once: the compiled closed-loop steps mapped over parameter sets on
several threads, keeping metrics instead of trajectories."""
from dataclasses import dataclass
import time

import casadi as ca
import numpy as np

from . import config, validate
from .controllers.base import Controller
from .closed_loop import TABLE, TABLE_SIZE, monitored_step, step_table
from .kernel import kernel_for
from .errors import InputError
from .plant import Actuation, TruthOptions, initial_rotor_thrusts
from .simulation import (CHUNK, Limits, run_options, _check_time, _compiled, _first_divergence,
                         _position_error, start_at_reference, tail_start)
from .timeline import CogProfile, wrench_table
from .trajectory import as_trajectory
from .vehicle import Vehicle


@dataclass
class BatchResult:
    """Metrics of many flights (arrays with one entry per flight, lengths in m, times in s)."""
    rms_position_error: np.ndarray
    max_position_error: np.ndarray
    rms_position_error_tail: np.ndarray
    final_position_error: np.ndarray
    diverged: np.ndarray
    diverged_at: np.ndarray           # NaN where the flight did not diverge
    final_state: np.ndarray           # (B, 12 + rotor states + n_state)
    seconds: float


def simulate_batch(controller, vehicles, trajectory="hover", duration=10.0, dt=None,
                   controller_model=None, cog_shape=None, disturbances=(), truth=None,
                   limits=None, threads=2, progress=None):
    """Fly one controller over many truth vehicles in parallel; keep metrics, not trajectories.

    Parameters
    ----------
    controller : a quadcog Controller.
    vehicles : a sequence of B truth Vehicles. They may differ in the 14 parameters
        (``Vehicle.parameters()``); their rotors (layout, constants, limits, time constant) must
        agree, since the compiled step holds them.
    controller_model : the Vehicle the controller is designed for (one for all flights);
        default: the vehicles with r_G = 0, which must then be one vehicle.
    cog_shape : flight b's CoG at time t is ``cog_shape(t) * vehicles[b].r_G``: a function of
        time, a CogProfile whose x component is used as the shape, or None (the CoG is there
        from t = 0).
    trajectory, duration, dt, disturbances, truth, limits, progress : as ``simulate``.
    threads : the number of threads that share the flights.

    Returns
    -------
    BatchResult.
    """
    if not isinstance(controller, Controller):
        validate.fail("controller", "a quadcog Controller", controller)
    options, limits = run_options(truth, limits, progress)
    threads = validate.integer(threads, "threads", lo=1, hi=1024)
    if not (cog_shape is None or isinstance(cog_shape, CogProfile) or callable(cog_shape)):
        validate.fail("cog_shape", "None, a CogProfile or a function of time", cog_shape)
    dt = config.get("simulate.dt", dt)
    if isinstance(vehicles, Vehicle):
        vehicles = [vehicles]
    elif isinstance(vehicles, (str, bytes)) or not hasattr(vehicles, "__iter__"):
        validate.fail("vehicles", "a non-empty sequence of quadcog Vehicles", vehicles)
    vehicles = list(vehicles)
    if not vehicles or not all(isinstance(v, Vehicle) for v in vehicles):
        raise InputError("vehicles must be a non-empty sequence of quadcog Vehicles, got "
                         f"{vehicles!r:.200}")
    actuation = Actuation.of(vehicles[0], options)
    for b, v in enumerate(vehicles):
        if Actuation.of(v, options) != actuation:
            raise InputError(f"vehicles[{b}] has other rotors than vehicles[0] (layout, "
                             "constants, limits or motor time constant); a batch shares them")
    if controller_model is None:
        controller_model = vehicles[0].with_cog(np.zeros(3))
        for b, v in enumerate(vehicles):
            if v.with_cog(np.zeros(3)) != controller_model:
                raise InputError(f"vehicles[{b}] differs from vehicles[0] in more than r_G: "
                                 "pass controller_model (what the controller believes)")
    elif not isinstance(controller_model, Vehicle):
        raise InputError(f"controller_model must be a quadcog Vehicle, got {controller_model!r}")
    controller = controller.for_vehicle(controller_model)
    params = np.array([v.parameters() for v in vehicles])
    _check_time(duration, dt)
    traj = as_trajectory(trajectory)
    n = int(round(duration / dt))
    times = np.arange(n + 1) * dt
    refs = traj.sample(times)
    if cog_shape is None:
        s = np.ones_like(times)
    elif isinstance(cog_shape, CogProfile):
        s = cog_shape.sample(times)[:, 0]
    else:
        s = np.array([validate.real(cog_shape(t), f"cog_shape({validate.plain(float(t))})")
                      for t in times])
    table = step_table(times, dt, refs, np.zeros((n + 1, 3)), wrench_table(disturbances, times),
                       tail_from=tail_start(duration))
    table[:, TABLE["s"]] = s
    x0 = start_at_reference(refs[0])
    B = params.shape[0]
    key = ("batch", controller.cache_key(), actuation, limits, CHUNK)

    def build():
        step = monitored_step(controller, actuation, limits)
        acc = step.mapaccum("monitored_chunk", CHUNK)
        Z, P, rows = ca.MX.sym("Z", step.size1_in(0)), ca.MX.sym("P", 14), \
            ca.MX.sym("rows", TABLE_SIZE, CHUNK)
        return ca.Function("monitored_last", [Z, P, rows], [acc(Z, P, rows)[:, -1]])

    nc, nf = controller.n_state, actuation.n_rotor_states
    Z = np.zeros((12 + nf + nc + 4, B))
    Z[:12] = x0[:, None]
    for b, v in enumerate(vehicles):
        Z[12:12 + nf, b] = initial_rotor_thrusts(v.with_cog(s[0] * v.r_G), actuation)
    Z[12 + nf:12 + nf + nc] = controller.initial_state()[:, None]
    Z[-1] = -1.0
    # the vector kernel (quadcog.kernel): flights in vector lanes, `threads` threads
    kernel = kernel_for(key, lambda: monitored_step(controller, actuation, limits))
    t0 = time.perf_counter()
    k = 0
    if kernel is not None:
        Zb = Z.T
        while k < n:
            m = min(CHUNK, n - k)
            Zb = kernel(Zb, params, table[k:k + m], threads=threads)
            k += m
            if progress:
                progress(k / n)
        Z = Zb.T
    else:
        last = _compiled(key, build)
        # `threads` threads, each mapping its share of the flights serially (a plain
        # "thread" map starts about one thread per flight); the step table (input 2) is
        # shared by all flights: reduce_in, not B copies
        parts = max(1, min(int(threads), B))
        share = -(-B // parts)
        mapped = last.map("share", "serial", share, [2], [])
        if parts > 1:
            mapped = mapped.map("batch", "thread", parts, [2], [])
        pad = parts * share - B
        Zp = np.hstack([Z, np.repeat(Z[:, -1:], pad, axis=1)]) if pad else Z
        Pp = np.vstack([params, np.repeat(params[-1:], pad, axis=0)]) if pad else params
        while k < n:
            rows = table[k:k + CHUNK]
            if rows.shape[0] < CHUNK:
                # pad with rows that change nothing: dt = 0 and no contribution to the sums
                pad_rows = np.repeat(rows[-1:], CHUNK - rows.shape[0], axis=0)
                pad_rows[:, TABLE["dt"]] = 0.0
                rows = np.vstack([rows, pad_rows])
            Zp = np.array(mapped(Zp, Pp.T, rows.T))
            k += min(CHUNK, n - k)
            if progress:
                progress(k / n)
        Z = Zp[:, :B]
    seconds = time.perf_counter() - t0
    return _batch_result(Z, n, table, nf + nc, seconds, limits)


def _batch_result(Z, n, table, n_extra, seconds, limits):
    """Metrics over the samples t_0 .. t_n, as for a single flight: the steps accumulated
    t_0 .. t_{n-1}; the final state is added here. n_extra: states after x (rotors, controller)."""
    nX = 12 + n_extra
    Z = Z.copy()
    sumsq, emax, sumsq_tail, div_at = Z[nX], Z[nX + 1], Z[nX + 2], Z[nX + 3]
    running = div_at < 0
    e_final = _position_error(Z[:3].T, table[n][None, :])
    for b in np.flatnonzero(running):
        idx, _ = _first_divergence(Z[None, :12, b], e_final[b:b + 1], limits)
        if idx is not None:
            div_at[b] = table[n, TABLE["t"]]
            continue
        sumsq[b] += e_final[b] ** 2
        sumsq_tail[b] += e_final[b] ** 2
        emax[b] = max(emax[b], e_final[b])
    n_tail = int(table[:n, TABLE["tail"]].sum()) + 1
    diverged = div_at >= 0
    dt = table[0, TABLE["dt"]]
    samples = np.where(diverged, np.maximum(np.round(div_at / dt), 1), n + 1)
    rms = np.sqrt(sumsq / samples)
    return BatchResult(rms_position_error=rms, max_position_error=emax,
                       rms_position_error_tail=np.where(diverged, np.inf,
                                                        np.sqrt(sumsq_tail / max(n_tail, 1))),
                       final_position_error=e_final,
                       diverged=diverged, diverged_at=np.where(diverged, div_at, np.nan),
                       final_state=Z[:nX].T, seconds=seconds)
