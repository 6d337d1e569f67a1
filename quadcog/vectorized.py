"""Many flights of one controller at once, differing in their truth parameters and in the size
of their CoG changes (not in their times): the engine of sweeps.

Flight b's CoG is ``r_G(t) = r_G(P[b]) + sum_j s_j(t) D[b, 3j:3j+3]``, where s_j is the shape
(0 -> 1, step or ramp) of CoG change j, shared by all flights. The closed-loop step is the
monitored step of ``quadcog.closed_loop`` (the same divergence rule and metric accumulators as
``simulate_batch``); this module feeds it the per-flight CoG and runs it either through the
vectorized C kernel of ``quadcog.kernel`` (flights in the vector lanes) or, without a C
compiler, through CasADi's map.
"""
import time

import casadi as ca
import numpy as np

from . import config
from .batch import _batch_result
from .closed_loop import TABLE, TABLE_SIZE, monitored_step, step_table
from .plant import Actuation, TruthOptions, initial_rotor_thrusts
from .simulation import CHUNK, Limits, _check_time, _compiled, start_at_reference, tail_start
from .timeline import CogChange, CogProfile, wrench_table
from .trajectory import as_trajectory


def sweep_step(controller, actuation, limits, n_changes):
    """SX Function (Z, Q, row) -> Z_next: the monitored step with the flight's CoG.

    Q = [P (14); D (3 n_changes)] per flight; row = [step-table row (TABLE_SIZE);
    s_1 .. s_J; active]. A row with active = 0 leaves Z as it is (padding)."""
    step = monitored_step(controller, actuation, limits)
    nZ = step.size1_in(0)
    Z, Q = ca.SX.sym("Z", nZ), ca.SX.sym("Q", 14 + 3 * n_changes)
    row = ca.SX.sym("row", TABLE_SIZE + n_changes + 1)
    r = Q[11:14]
    for j in range(n_changes):
        r = r + row[TABLE_SIZE + j] * Q[14 + 3 * j:17 + 3 * j]
    P = ca.vertcat(Q[:11], r)
    inner = [row[i] for i in range(TABLE_SIZE)]
    inner[TABLE["s"]] = 1.0                       # the CoG is all in P here
    for i in range(TABLE["r_table"].start, TABLE["r_table"].stop):
        inner[i] = 0.0
    Z_next = step(Z, P, ca.vertcat(*inner))
    Z_next = ca.if_else(row[TABLE_SIZE + n_changes] > 0, Z_next, Z)
    return ca.Function("sweep_step", [Z, Q, row], [Z_next], ["Z", "Q", "row"], ["Z_next"])


def batch_table(trajectory, duration, dt, cog_times, disturbances):
    """(n + 1, TABLE_SIZE + J + 1) rows for the steps at t_0 .. t_n: the step table, the CoG
    shapes s_j and the active flag (1)."""
    n = int(round(duration / dt))
    times = np.arange(n + 1) * dt
    refs = trajectory.sample(times)
    table = step_table(times, dt, refs, np.zeros((n + 1, 3)),
                       wrench_table(disturbances, times), tail_from=tail_start(duration))
    shapes = [CogProfile([CogChange(t, (1.0, 0.0, 0.0), ramp)]).sample(times)[:, 0]
              for t, ramp in cog_times]
    return np.column_stack([table] + shapes + [np.ones(n + 1)])


def fly_batch(controller, vehicles, D, trajectory="hover", duration=10.0, dt=None,
              cog_times=(), disturbances=(), truth=None, limits=None, x0=None, threads=1,
              kernel="auto"):
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

    Returns
    -------
    quadcog.BatchResult
    """
    options = truth or TruthOptions()
    limits = limits or Limits()
    dt = config.get("simulate.dt", dt)
    _check_time(duration, dt)
    traj = as_trajectory(trajectory)
    actuation = Actuation.of(vehicles[0], options)
    P = np.array([v.parameters() for v in vehicles])
    B, J = P.shape[0], len(cog_times)
    D = np.asarray(D, dtype=float).reshape(B, 3 * J)
    table = batch_table(traj, duration, dt, cog_times, disturbances)
    n = table.shape[0] - 1
    nc, nf = controller.n_state, actuation.n_rotor_states
    if x0 is None:
        x0 = start_at_reference(table[0, TABLE["ref"]])
    Z = np.zeros((B, 12 + nf + nc + 4))
    Z[:, :12] = x0
    s0 = table[0, TABLE_SIZE:TABLE_SIZE + J]
    for b, v in enumerate(vehicles):
        r0 = v.r_G + (s0 @ D[b].reshape(J, 3) if J else 0.0)
        Z[b, 12:12 + nf] = initial_rotor_thrusts(v.with_cog(r0), actuation)
    Z[:, 12 + nf:12 + nf + nc] = controller.initial_state()
    Z[:, -1] = -1.0
    Q = np.hstack([P, D])
    t0 = time.perf_counter()
    run = None
    if kernel in ("auto", "vector"):
        from .kernel import kernel_for
        run = kernel_for(("sweep_step", controller.cache_key(), actuation, limits, J),
                         lambda: sweep_step(controller, actuation, limits, J),
                         required=kernel == "vector")
    if run is not None:
        Z = run(Z, Q, table[:n], threads=threads)
    else:
        Z = _run_casadi(controller, actuation, limits, J, Z, Q, table[:n], threads)
    seconds = time.perf_counter() - t0
    return _batch_result(Z.T.copy(), n, table, nf + nc, seconds, limits)


def _run_casadi(controller, actuation, limits, J, Z, Q, rows, threads):
    key = ("sweep_batch", controller.cache_key(), actuation, limits, J, CHUNK)

    def build():
        step = sweep_step(controller, actuation, limits, J)
        acc = step.mapaccum("sweep_chunk", CHUNK)
        z, q = ca.MX.sym("Z", step.size1_in(0)), ca.MX.sym("Q", step.size1_in(1))
        r = ca.MX.sym("rows", step.size1_in(2), CHUNK)
        return ca.Function("sweep_last", [z, q, r], [acc(z, q, r)[:, -1]])

    last = _compiled(key, build)
    B = Z.shape[0]
    mapped = last.map("batch", "thread" if threads > 1 else "serial", B, [2], [])
    n = rows.shape[0]
    Zt, Qt = Z.T, Q.T
    for k in range(0, n, CHUNK):
        block = rows[k:k + CHUNK]
        if block.shape[0] < CHUNK:
            pad = np.repeat(block[-1:], CHUNK - block.shape[0], axis=0)
            pad[:, -1] = 0.0                      # inactive: Z stays
            block = np.vstack([block, pad])
        Zt = np.array(mapped(Zt, Qt, block.T))
    return Zt.T
