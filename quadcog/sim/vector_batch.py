"""Many flights of one controller at once, differing in their truth parameters and in the size
of their CoG changes (not in their times): the engine of sweeps.

Flight b's CoG is ``r_G(t) = r_G(P[b]) + sum_j s_j(t) D[b, 3j:3j+3]``, where s_j is the shape
(0 -> 1, step or ramp) of CoG change j, shared by all flights. The closed-loop step is the
monitored step of ``quadcog.sim.closed_loop`` (the same divergence rule and metric accumulators as
``simulate_batch``); this module feeds it the per-flight CoG and runs it either through the
vectorized C kernel of ``quadcog.codegen.vector_kernel`` (flights in the vector lanes) or, without a C
compiler, through CasADi's map.
"""
import time

import casadi as ca
import numpy as np

from quadcog import config
from quadcog.errors import InputError
from quadcog.model.conventions import N_PARAM, N_STATE, R_G
from quadcog.sim.batch import batch_metrics, run_kernel, run_map
from quadcog.sim.closed_loop import chunk_of, monitored_step, packed
from quadcog.sim.plant import Actuation
from quadcog.sim.prepare import batch_start, check_time, run_options, start_at_reference
from quadcog.sim.schedule import STEP_INPUTS, Schedule, cog_at
from quadcog.sim.timeline import CogChange, CogProfile
from quadcog.trajectories.registry import as_trajectory


def sweep_step(controller, actuation, limits, n_changes):
    """SX Function (Z, Q, per-step inputs (``STEP_INPUTS``), shapes) -> Z_next: the monitored
    step with the flight's CoG.

    Q = [P (14); D (3 n_changes)] per flight; shapes = [s_1 .. s_J] at the step. Padding steps
    have dt = 0 and change nothing (the monitored step counts only dt > 0)."""
    step = monitored_step(controller, actuation, limits)
    nZ = step.size1_in(0)
    Z, Q = ca.SX.sym("Z", nZ), ca.SX.sym("Q", N_PARAM + 3 * n_changes)
    per_step = {name: ca.SX.sym(name, rows) for name, rows in STEP_INPUTS}
    shapes = ca.SX.sym("shapes", n_changes)
    # the flight's CoG profile enters where a single flight's does (the schedule's cog input),
    # so r_G(t) is formed in one place (``quadcog.sim.schedule.cog_at``)
    cog = ca.SX.zeros(3)
    for j in range(n_changes):
        cog = cog + shapes[j] * Q[N_PARAM + 3 * j:N_PARAM + 3 * j + 3]
    inputs = dict(per_step, cog=cog, cog_scale=1.0)
    Z_next = step(Z, Q[:N_PARAM], *[inputs[name] for name, _ in STEP_INPUTS])
    names = [name for name, _ in STEP_INPUTS]
    return ca.Function("sweep_step", [Z, Q] + [per_step[n] for n in names] + [shapes],
                       [Z_next], ["Z", "Q"] + names + ["shapes"], ["Z_next"])


def cog_shapes(times, cog_times):
    """(N, J) shapes s_j (0 -> 1, a step or a ramp) of the CoG changes (t, ramp) at ``times``."""
    shapes = [CogProfile([CogChange(t, (1.0, 0.0, 0.0), ramp)]).sample(times)[:, 0]
              for t, ramp in cog_times]
    return np.ascontiguousarray(np.column_stack(shapes) if shapes else
                                np.zeros((len(times), 0)))


def fly_batch(controller, vehicles, D, trajectory="hover", duration=10.0, dt=None,
              cog_times=(), disturbances=(), truth=None, limits=None, x0=None, threads=1,
              kernel="auto", precision="float64"):
    """Fly ``controller`` (designed for its model already) with each truth vehicle and CoG
    increments D (B, 3 J).

    Parameters
    ----------
    controller : quadcog Controller
    vehicles : sequence of B Vehicles
        The truth vehicles; they may differ in their 14 parameters, not in their rotors (the
        caller checks that).
    D : (B, 3 J) array
        Size of each of the J CoG changes per flight (m), see the module docstring.
    trajectory, duration, dt, disturbances, truth, limits
        As for ``quadcog.simulate``.
    cog_times : sequence of (t, ramp)
        Start (s) and ramp (s, 0 for a step) of each CoG change, shared by all flights.
    x0 : (12,) array or None
        Initial state (default: at the reference).
    threads : int
        Threads that share the flights.
    kernel : "auto", "vector" or "casadi"
        The vectorized C kernel ("auto" when a C compiler is there) or CasADi's map.
    precision : "float64" or "float32"
        The vector kernel's precision. float32 is for measuring only (bench/precision.py):
        its metrics are not within 1e-4 of float64's (docs/performance.md).

    Returns
    -------
    quadcog.BatchResult
    """
    if precision != "float64" and kernel == "casadi":
        raise InputError(f"precision={precision!r} needs kernel='auto' or 'vector' (CasADi's "
                         "map runs in float64), got kernel='casadi'")
    options, limits = run_options(truth, limits, None)
    dt = config.get("simulate.dt", dt)
    duration, dt = check_time(duration, dt)
    schedule = Schedule.build(as_trajectory(trajectory), duration, dt,
                              disturbances=disturbances)
    actuation = Actuation.of(vehicles[0], options)
    P = np.array([v.parameters() for v in vehicles])
    B, J = P.shape[0], len(cog_times)
    D = np.asarray(D, dtype=float).reshape(B, 3 * J)
    shapes = cog_shapes(schedule.t, cog_times)
    nX = N_STATE + actuation.n_rotor_states + controller.n_state
    if x0 is None:
        x0 = start_at_reference(schedule.ref[0])
    P0 = P.copy()
    if J:           # each flight's CoG at t = 0
        P0[:, R_G] = cog_at(P[:, R_G], 1.0, np.einsum("j,bjk->bk", shapes[0], D.reshape(B, J, 3)))
    Z = batch_start(controller, actuation, P0, x0)
    Q = np.hstack([P, D])
    t0 = time.perf_counter()
    run = None
    if kernel in ("auto", "vector"):
        from quadcog.codegen.vector_kernel import kernel_for
        run = kernel_for(("sweep_step", controller.cache_key(), actuation, limits, J),
                         lambda: packed(sweep_step(controller, actuation, limits, J)),
                         required=kernel == "vector" or precision == "float32",
                         precision=precision)
    if run is not None:
        Z = run_kernel(run, Z, Q, schedule, shapes, threads=threads)
    else:
        chunk = chunk_of(sweep_step(controller, actuation, limits, J),
                         ("sweep_step", controller.cache_key(), actuation, limits, J))
        Z = run_map(chunk, Z, Q, schedule, shapes, threads=threads)
    seconds = time.perf_counter() - t0
    # the CoG is in P, so the schedule's own CoG (zero) is what batch_metrics sees: it only
    # needs the reference, the tail and the times
    return batch_metrics(Z, nX, schedule, limits, seconds)
