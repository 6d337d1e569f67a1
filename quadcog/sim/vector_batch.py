"""Many flights of one controller at once, differing in their truth parameters and in the size
of their CoG changes (not in their times): the engine of sweeps.

Flight b's CoG is ``r_G(t) = r_G(P[b]) + sum_j s_j(t) D[b, 3j:3j+3]``, where s_j is the shape
(0 -> 1, step or ramp) of CoG change j, shared by all flights. The closed-loop step is the
monitored step of ``quadcog.sim.closed_loop`` (the same divergence rule and metric
accumulators as ``simulate_batch``); this module feeds it the per-flight CoG and runs it
either through the vectorized C kernel of ``quadcog.codegen.vector_kernel`` (flights in the
vector lanes) or, without a C compiler, through CasADi's map.
"""
from collections.abc import Sequence
import time
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog import config, validate
from quadcog.controllers.base import Controller
from quadcog.errors import InputError
from quadcog.model.conventions import N_PARAM, N_STATE, R_G
from quadcog.model.parameters import MARGIN, check_parameters, inertia_ratio
from quadcog.sim.batch import BatchResult, batch_metrics, check_vehicles, run_kernel, run_map, slow_row_entries
from quadcog.sim.closed_loop import chunk_of, monitored_step, packed
from quadcog.sim.divergence import Limits
from quadcog.sim.plant import Actuation, TruthOptions
from quadcog.sim.prepare import batch_start, check_start, check_time, run_options, start_at_reference, whole_body
from quadcog.sim.schedule import STEP_INPUTS, Schedule, cog_at
from quadcog.sim.timeline import CogChange, CogProfile, PayloadProfile
from quadcog.trajectories.registry import as_trajectory
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["sweep_step", "cog_shapes", "check_cog_increments", "fly_batch"]


def sweep_step(controller: Controller, actuation: Actuation, limits: Limits, n_changes: int
               ) -> ca.Function:
    """The monitored step with the flight's CoG, as an SX Function.

    Padding steps have dt = 0 and change nothing (the monitored step counts only dt > 0).

    Parameters
    ----------
    controller : Controller
        The law (designed for its model already).
    actuation : Actuation
        The truth's rotors.
    limits : Limits
        The divergence limits.
    n_changes : int
        J, the number of CoG changes.

    Returns
    -------
    casadi.Function
        ``sweep_step(Z, Q, per-step inputs (STEP_INPUTS), shapes) -> Z_next``, with
        Q = [P (14); D (3 J)] per flight and shapes = [s_1 .. s_J] at the step.
    """
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
    inputs: dict[str, Any] = dict(per_step, cog=cog, cog_scale=1.0)
    Z_next = step(Z, Q[:N_PARAM], *[inputs[name] for name, _ in STEP_INPUTS])
    names = [name for name, _ in STEP_INPUTS]
    return ca.Function("sweep_step", [Z, Q] + [per_step[n] for n in names] + [shapes],
                       [Z_next], ["Z", "Q"] + names + ["shapes"], ["Z_next"])


def cog_shapes(times: npt.NDArray[np.float64], cog_times: Sequence[tuple[float, float]]
               ) -> npt.NDArray[np.float64]:
    """The shapes s_j (0 -> 1, a step or a ramp) of the CoG changes.

    Parameters
    ----------
    times : (N,) numpy.ndarray
        Sample times (s).
    cog_times : sequence of (t, ramp)
        Start and ramp (s) of each of the J changes.

    Returns
    -------
    (N, J) numpy.ndarray
        s_j at each time.
    """
    shapes = [CogProfile([CogChange(t, (1.0, 0.0, 0.0), ramp)]).sample(times)[:, 0]
              for t, ramp in cog_times]
    return np.ascontiguousarray(np.column_stack(shapes) if shapes else
                                np.zeros((len(times), 0)))


def check_cog_increments(P: npt.NDArray[np.float64], D: npt.NDArray[np.float64],
                         cog_times: Sequence[tuple[float, float]]) -> None:
    """Refuse CoG increments that take a flight where no rigid body is.

    Between the starts and ends of the changes every shape s_j is linear in t, so each
    flight's r_G(t) is too, and the admissible set of r_G is convex
    (``quadcog.sim.prepare.check_cog_changes``): the CoGs at those instants cover the run.

    Parameters
    ----------
    P : (B, 14) numpy.ndarray
        The flights' parameters (their own r_G).
    D : (B, 3 J) numpy.ndarray
        The increments (m).
    cog_times : sequence of (t, ramp)
        The changes' starts and ramps (s).

    Raises
    ------
    quadcog.ParameterError
        Naming the first flight and the instant where its CoG is not admissible.
    """
    B, J = len(P), len(cog_times)
    instants = np.unique([t + a for t, ramp in cog_times for a in (0.0, ramp)])
    for t, s in zip(instants.tolist(), cog_shapes(instants, cog_times)):
        Pk = P.copy()
        with np.errstate(over="ignore", invalid="ignore"):
            Pk[:, R_G] = cog_at(P[:, R_G], 1.0, np.einsum("j,bjk->bk", s, D.reshape(B, J, 3)))
        ok = inertia_ratio(Pk) >= MARGIN       # NaN (overflow) is not
        if not ok.all():
            b = int(np.flatnonzero(~ok)[0])
            check_parameters(Pk[b], f"vehicles[{b}] with the CoG increments D[{b}] at "
                                    f"t = {validate.plain(t)} s")


def fly_batch(controller: Controller, vehicles: Sequence[Vehicle], D: npt.ArrayLike,
              trajectory: Any = "hover", duration: float = 10.0, dt: float | None = None,
              cog_times: Sequence[tuple[float, float]] = (), disturbances: Any = (),
              truth: TruthOptions | None = None, limits: Limits | None = None,
              x0: npt.ArrayLike | None = None, threads: int = 1, kernel: str = "auto",
              precision: str = "float64", payloads: PayloadProfile | None = None) -> BatchResult:
    """Fly ``controller`` (designed for its model already) with each truth vehicle and CoG
    increments D (B, 3 J).

    Parameters
    ----------
    controller : Controller
        The law, designed for its model already.
    vehicles : sequence of B Vehicles
        The truth vehicles; they may differ in their 14 parameters, not in their rotors (the
        caller checks that).
    D : (B, 3 J) array_like
        Size of each of the J CoG changes per flight (m), see the module docstring.
    trajectory : Trajectory, str or callable
        As for ``quadcog.simulate``.
    duration : float
        Seconds, as for ``quadcog.simulate`` (dt default
        ``quadcog.config.defaults["simulate.dt"]``).
    dt : float
        Seconds, as for ``quadcog.simulate`` (dt default
        ``quadcog.config.defaults["simulate.dt"]``).
    cog_times : sequence of (t, ramp)
        Start (s) and ramp (s, 0 for a step) of each CoG change, shared by all flights.
    disturbances : sequence of Disturbance
        As for ``quadcog.simulate``.
    truth : TruthOptions, optional
        As for ``quadcog.simulate``.
    limits : Limits, optional
        As for ``quadcog.simulate``.
    x0 : (12,) array_like or None
        Initial state [m, rad, m/s, rad/s] (default: at the reference).
    threads : int
        Threads that share the flights.
    kernel : {"auto", "vector", "casadi"}
        The vectorized C kernel ("auto" when a C compiler is there) or CasADi's map.
    precision : {"float64", "float32"}
        The vector kernel's precision. float32 is for measuring only (bench/precision.py):
        its metrics are not within 1e-4 of float64's (docs/performance.md).
    payloads : PayloadProfile, optional
        The payloads over the run, shared by the flights (the vehicles' own must be the
        profile's ``carried``); default: the first vehicle's own payloads.

    Returns
    -------
    quadcog.BatchResult
        One entry per flight.

    Raises
    ------
    quadcog.InputError
        An argument of the wrong kind or shape (named), vehicles of other rotors, a start
        state beyond the scale or diverged already, or a precision other than float64 with
        kernel='casadi'.
    quadcog.ParameterError
        A flight whose CoG increments take it where no rigid body is.
    """
    validate.choice(kernel, "kernel", ("auto", "vector", "casadi"))
    validate.choice(precision, "precision", ("float64", "float32"))
    if precision != "float64" and kernel == "casadi":
        raise InputError(f"precision={precision!r} needs kernel='auto' or 'vector' (CasADi's "
                         "map runs in float64), got kernel='casadi'")
    if not isinstance(controller, Controller):
        validate.fail("controller", "a quadcog Controller", controller)
    threads = validate.integer(threads, "threads", lo=1, hi=1024)
    options, limits = run_options(truth, limits, None)
    dt = config.get("simulate.dt", dt)
    duration, dt = check_time(duration, dt)
    vehicles, P, actuation = check_vehicles(vehicles, options)
    if isinstance(cog_times, (str, bytes)) or not isinstance(cog_times, Sequence):
        validate.fail("cog_times", "a sequence of (t, ramp) pairs (s)", cog_times)
    cog_times = [(float(t), float(ramp)) for t, ramp in
                 (validate.vector(c, f"cog_times[{j}]", 2) for j, c in enumerate(cog_times))]
    if payloads is None:
        payloads = PayloadProfile([], vehicles[0].payloads)
    schedule = Schedule.build(as_trajectory(trajectory), duration, dt,
                              disturbances=disturbances, payloads=payloads)
    B, J = P.shape[0], len(cog_times)
    D = validate.array(D, "D", (B, 3 * J))
    shapes = cog_shapes(schedule.t, cog_times)
    check_cog_increments(P, D, cog_times)
    nX = N_STATE + actuation.n_rotor_states + controller.n_state
    x0 = (start_at_reference(schedule.ref[0]) if x0 is None
          else check_start(x0, schedule.ref[0], limits))
    P0 = P.copy()
    if J:           # each flight's CoG at t = 0
        P0[:, R_G] = cog_at(P[:, R_G], 1.0,
                            np.einsum("j,bjk->bk", shapes[0], D.reshape(B, J, 3)))
    Z = batch_start(controller, actuation, whole_body(P0, schedule.payload[0]), x0)
    Q = np.hstack([P, D])
    t0 = time.perf_counter()
    run = None
    if kernel in ("auto", "vector"):
        from quadcog.codegen.vector_kernel import kernel_for
        run = kernel_for(("sweep_step", controller.cache_key(), actuation, limits, J),
                         lambda: packed(sweep_step(controller, actuation, limits, J)),
                         required=kernel == "vector" or precision == "float32",
                         precision=precision, slow=slow_row_entries(J))
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
