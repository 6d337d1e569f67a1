"""Many flights at once, keeping metrics (the same definition and divergence rule as single
flights) instead of trajectories: the monitored closed-loop step run by the vector kernel
(``quadcog.codegen.vector_kernel``, flights in the CPU's vector lanes, ``threads`` threads)
or, where that cannot be built, by CasADi's map."""
from collections.abc import Callable, Sequence
from dataclasses import dataclass
import itertools
import time
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog import config, validate
from quadcog.codegen.vector_kernel import VectorKernel, kernel_for
from quadcog.controllers.base import Controller
from quadcog.errors import InputError
from quadcog.model.conventions import N_STATE, R_G
from quadcog.model.parameters import MARGIN, check_parameters, inertia_ratio
from quadcog.sim.closed_loop import ACCUMULATORS, CHUNK, SLOW_INPUTS, monitored_chunk_function, monitored_step, packed
from quadcog.sim.divergence import DivergenceCause, Limits, divergence_rule, magnitude
from quadcog.sim.plant import Actuation, TruthOptions
from quadcog.sim.prepare import (
    RK4_LIMIT,
    batch_start,
    check_fastest_eigenvalue,
    check_step_size,
    check_time,
    run_options,
    start_at_reference,
    warn_late_disturbances,
    whole_body,
)
from quadcog.sim.result import metric_arrays, position_errors
from quadcog.sim.schedule import STEP_INPUTS, Schedule, cog_at
from quadcog.sim.timeline import CogProfile, PayloadProfile
from quadcog.trajectories.registry import as_trajectory
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["BatchResult", "MAX_FLIGHTS", "BYTES_PER_FLIGHT", "batch_kernel", "simulate_batch",
           "check_vehicles", "check_cog_range", "check_step_sizes", "run_kernel", "run_map",
           "batch_metrics", "slow_row_entries"]


@dataclass
class BatchResult:
    """Metrics of many flights, each as ``quadcog.Metrics`` defines it for a single flight.

    Parameters
    ----------
    rms_position_error : (B,) numpy.ndarray
        RMS position error of each flight (m).
    max_position_error : (B,) numpy.ndarray
        Largest position error (m).
    rms_position_error_tail : (B,) numpy.ndarray
        RMS position error over the tail (m; inf where the flight diverged).
    final_position_error : (B,) numpy.ndarray
        Position error at the last counted sample (m).
    diverged : (B,) numpy.ndarray of bool
        True where the flight diverged.
    diverged_at : (B,) numpy.ndarray
        Time of the first diverged sample (s; NaN where the flight did not diverge).
    diverged_cause : list of DivergenceCause or None
        Why each flight diverged (None where it did not).
    final_state : (B, 12 + rotor states + n_state) numpy.ndarray
        The state after the last step.
    seconds : float
        Wall time of the step loop (s).
    """
    rms_position_error: np.ndarray
    max_position_error: np.ndarray
    rms_position_error_tail: np.ndarray   # inf where the flight diverged
    final_position_error: np.ndarray
    diverged: np.ndarray
    diverged_at: np.ndarray           # NaN where the flight did not diverge
    diverged_cause: list              # a DivergenceCause or None per flight
    final_state: np.ndarray           # (B, 12 + rotor states + n_state)
    seconds: float

    def __repr__(self) -> str:
        n = len(self.diverged)
        ok = ~np.asarray(self.diverged, bool)
        tail = np.asarray(self.rms_position_error_tail)[ok]
        rms = (f"tail RMS median {np.median(tail):.4g} m, max {np.max(tail):.4g} m"
               if tail.size else "no flight survived")
        return (f"BatchResult({n} flights in {self.seconds:.2f} s: {int(n - ok.sum())} diverged, "
                f"{rms}; .to_pandas() for the table)")

    def columns(self) -> dict[str, np.ndarray]:
        """The metrics as columns, one row per flight.

        Returns
        -------
        dict of str to numpy.ndarray
            {name: (B,) array}: the metrics (m, s), ``diverged`` and ``diverged_cause`` (its
            name, or '' where the flight did not diverge).
        """
        return {"rms_position_error_m": np.asarray(self.rms_position_error),
                "max_position_error_m": np.asarray(self.max_position_error),
                "rms_position_error_tail_m": np.asarray(self.rms_position_error_tail),
                "final_position_error_m": np.asarray(self.final_position_error),
                "diverged": np.asarray(self.diverged, bool),
                "diverged_at_s": np.asarray(self.diverged_at),
                "diverged_cause": np.array([c.name if c is not None else ""
                                            for c in self.diverged_cause])}

    def to_arrow(self) -> Any:  # a pyarrow.Table (pyarrow is optional, has no stubs)
        """The metrics as a pyarrow Table, one row per flight (needs pyarrow).

        Returns
        -------
        pyarrow.Table
            The columns of ``columns()``.
        """
        validate.require_extra("sweep", "pyarrow")
        import pyarrow as pa
        return pa.table({k: v.tolist() if v.dtype.kind == "U" else v
                         for k, v in self.columns().items()})

    def to_pandas(self) -> Any:  # a pandas.DataFrame (pandas is optional)
        """The metrics as a pandas DataFrame, one row per flight (needs pandas).

        Returns
        -------
        pandas.DataFrame
            The columns of ``columns()``.
        """
        try:
            import pandas as pd
        except ImportError:
            from quadcog.errors import MissingDependencyError
            raise MissingDependencyError("BatchResult.to_pandas needs pandas: pip install pandas") \
                from None
        return pd.DataFrame(self.columns())


def slow_row_entries(n_extra: int = 0) -> tuple[int, ...]:
    """The entries of a packed row (``quadcog.sim.closed_loop.packed``) that change seldom.

    Parameters
    ----------
    n_extra : int
        Slow entries appended after the ``STEP_INPUTS`` (the sweep engine's CoG shapes).

    Returns
    -------
    tuple of int
        The row entries of ``SLOW_INPUTS`` (the CoG profile and the payloads) and the
        ``n_extra`` after the ``STEP_INPUTS``: the vector kernel reruns what depends only on
        them and the flight's parameters where they change (``quadcog.codegen.hoisting``).
    """
    entries: list[int] = []
    start = 0
    for name, rows in STEP_INPUTS:
        if name in SLOW_INPUTS:
            entries += range(start, start + rows)
        start += rows
    return tuple(entries) + tuple(range(start, start + n_extra))


def batch_kernel(controller: Controller, actuation: Actuation, limits: Limits
                 ) -> VectorKernel | None:
    """The vector kernel of the monitored step (``quadcog.codegen.vector_kernel.kernel_for``).

    Rows come from ``Schedule.rows``.

    Parameters
    ----------
    controller : Controller
        The law (designed for its model already).
    actuation : Actuation
        The truth's rotors.
    limits : Limits
        The divergence limits.

    Returns
    -------
    VectorKernel or None
        None where it cannot be built.
    """
    return kernel_for(("batch", controller.cache_key(), actuation, limits),
                      lambda: packed(monitored_step(controller, actuation, limits)),
                      slow=slow_row_entries())


# the Vehicle fields that are not among the 14 parameters: what the rotors are, and labels
_ROTOR_FIELDS = ("rotor_positions", "rotor_directions", "thrust_constant", "moment_constant",
                 "max_rotor_thrust", "min_rotor_thrust", "motor_time_constant")


# Flights of one batch: each costs its state, parameters and metrics (about BYTES_PER_FLIGHT:
# 1.37 kB measured as peak RSS per flight of a 1e5-flight batch, rounded up), so a million
# is about 1.4 GB; more is refused before the vehicles are even listed.
MAX_FLIGHTS = 1_000_000
BYTES_PER_FLIGHT = 1400
# rows of check_step_sizes per mapped call: its Jacobians take n^2 doubles each
STEP_CHECK_BLOCK = 4096


def check_vehicles(vehicles: Any, options: TruthOptions
                   ) -> tuple[list[Vehicle], npt.NDArray[np.float64], Actuation]:
    """The checked list of truth vehicles, their parameters (B, 14) and shared Actuation.

    Each Vehicle was checked when it was built; here only what the batch adds is checked, in
    vectorized form: at most ``MAX_FLIGHTS`` of them, in an order (one result per flight),
    sharing the rotors (the compiled step holds them).

    Parameters
    ----------
    vehicles : Vehicle or sequence of Vehicle
        The truth vehicles.
    options : TruthOptions
        The truth options (for the Actuation).

    Returns
    -------
    vehicles : list of Vehicle
        The B vehicles.
    params : (B, 14) numpy.ndarray
        Their airframes' parameters.
    actuation : Actuation
        Their rotors.

    Raises
    ------
    quadcog.InputError
        Naming the first vehicle that is none, or differs from vehicles[0] in its rotors or
        payloads, or giving the count and its memory beyond ``MAX_FLIGHTS``.
    """
    what = "a non-empty sequence of quadcog Vehicles"
    if isinstance(vehicles, Vehicle):
        vehicles = [vehicles]
    elif (isinstance(vehicles, (str, bytes, dict, set, frozenset))      # no order of flights
          or not hasattr(vehicles, "__iter__")):
        validate.fail("vehicles", what, vehicles)
    # a sized sequence is counted before it is copied; an iterator is read one past the limit
    sized = hasattr(vehicles, "__len__")
    n = len(vehicles) if sized else 0
    if n <= MAX_FLIGHTS:
        vehicles = list(itertools.islice(vehicles, MAX_FLIGHTS + 1))
        n = len(vehicles)
    if n > MAX_FLIGHTS:
        count = f"{n:,} flights" if sized else f"more than {MAX_FLIGHTS:,} flights"
        raise InputError(f"vehicles: expected at most {MAX_FLIGHTS:,} flights (about "
                         f"{MAX_FLIGHTS * BYTES_PER_FLIGHT / 2**30:.3g} GiB), got {count}, "
                         f"about {n * BYTES_PER_FLIGHT / 2**30:.3g} GiB")
    if not vehicles:
        validate.fail("vehicles", what, vehicles)
    for b, v in enumerate(vehicles):
        if not isinstance(v, Vehicle):
            validate.fail(f"vehicles[{b}]", "a quadcog Vehicle", v)
    actuation = Actuation.of(vehicles[0], options)
    rotors = tuple(getattr(vehicles[0], f) for f in _ROTOR_FIELDS)
    for b, v in enumerate(vehicles):
        if v is not vehicles[0] and tuple(getattr(v, f) for f in _ROTOR_FIELDS) != rotors:
            raise InputError(f"vehicles[{b}] has other rotors than vehicles[0] (layout, "
                             "constants, limits or motor time constant); a batch shares them")
        if v.payloads != vehicles[0].payloads:
            raise InputError(f"vehicles[{b}] carries other payloads than vehicles[0]; a batch "
                             "shares them (they are part of its schedule)")
    # the airframes: the payloads reach the truth through the schedule
    params = np.array([v.airframe.parameters() for v in vehicles])
    return vehicles, params, actuation


def _same_but_cog(params):
    """The index of the first flight whose parameters differ from flight 0's in more than
    r_G, or None."""
    other = np.ones(params.shape[1], dtype=bool)
    other[R_G] = False
    bad = np.flatnonzero(np.any(params[:, other] != params[0, other], axis=1))
    return int(bad[0]) if bad.size else None


def _cog_scale(cog_shape: Any) -> Callable[[float], float] | None:
    """cog_shape as a checked function of time (or None)."""
    if cog_shape is None:
        return None
    if isinstance(cog_shape, CogProfile):
        profile = cog_shape
        for i, change in enumerate(profile.changes):
            if change.r[1] or change.r[2]:      # only x is the shape: y, z would be dropped
                validate.fail(f"cog_shape change {i}", "a shape in x alone (r = (s, 0, 0))",
                              list(change.r))
        return lambda t: profile.sample([t])[0, 0]
    if not callable(cog_shape):
        validate.fail("cog_shape", "None, a CogProfile or a function of time", cog_shape)
    shape = validate.user_function(cog_shape, "cog_shape")
    return lambda t: validate.real(shape(t), f"cog_shape({validate.plain(float(t))})")


def check_cog_range(params: npt.NDArray[np.float64], schedule: Schedule) -> None:
    """Refuse a batch whose CoG schedule takes a flight's truth where no rigid body is.

    Flight b's r_G at step k is ``cog_scale_k * r_b + cog_k``. The inertia about the CoG's
    least fraction of I_O (``inertia_ratio``) is concave in r_G (I_G = I_O - m S(r)^T S(r),
    S linear in r), so along the schedule's scales it is least at the smallest or the
    largest: those two CoGs of each flight are checked (each distinct CoG row, where the
    additive part varies), as ``simulate`` checks each CoG of its profile.

    Parameters
    ----------
    params : (B, 14) numpy.ndarray
        The flights' parameter vectors (their own r_G).
    schedule : Schedule
        The batch's schedule (``cog_scale``, ``cog``).

    Raises
    ------
    quadcog.ParameterError
        Naming the flight, the time and the scale where its CoG is not admissible.
    """
    scale, cog = schedule.cog_scale, schedule.cog
    if (cog == cog[0]).all():
        steps = np.unique([int(np.argmin(scale)), int(np.argmax(scale))])
    else:
        steps = np.unique(np.column_stack([scale, cog]), axis=0, return_index=True)[1]
    for k in steps:
        P = params.copy()
        with np.errstate(over="ignore", invalid="ignore"):
            P[:, R_G] = cog_at(params[:, R_G], scale[k], cog[k])
        ok = inertia_ratio(P) >= MARGIN       # NaN (overflow) is not
        if not ok.all():
            b = int(np.flatnonzero(~ok)[0])
            check_parameters(P[b], f"vehicles[{b}] at t = {validate.plain(schedule.t[k])} s "
                                   f"(cog_shape {validate.plain(scale[k])} x its r_G)")


def check_step_sizes(controller: Controller, x0: npt.NDArray[np.float64],
                     ref0: npt.NDArray[np.float64], P: npt.NDArray[np.float64], dt: float,
                     actuation: Actuation) -> None:
    """``quadcog.sim.prepare.check_step_size`` for each flight, as ``simulate`` checks one.

    Flights of equal parameters share a closed loop, so each distinct row is checked once:
    the first by ``check_step_size`` (the motor lag too), the others' Jacobians in one mapped
    call, ``STEP_CHECK_BLOCK`` rows at a time, bounded by their norms, and the eigenvalues
    computed only where the bound does not pass (a thousand flights in about 30 ms, where a
    call per flight took 0.15 s).

    Parameters
    ----------
    controller : Controller
        Designed for its model already.
    x0 : (12,) numpy.ndarray
        The start state, shared.
    ref0 : (14,) numpy.ndarray
        The reference row at t = 0.
    P : (B, 14) numpy.ndarray
        Each flight's truth parameters at t = 0, with the payloads on board.
    dt : float
        The step (s).
    actuation : Actuation
        The rotors.

    Raises
    ------
    quadcog.InputError
        Naming the first flight for which dt is too large.
    """
    rows = np.sort(np.unique(P, axis=0, return_index=True)[1])
    try:
        check_step_size(controller, x0, ref0, P[rows[0]], dt, actuation)
    except InputError as e:
        raise InputError(f"vehicles[{rows[0]}]: {e}") from None
    jacobian = controller.closed_loop_jacobian()
    n = jacobian.size1_out(0)
    for a in range(1, rows.size, STEP_CHECK_BLOCK):
        block = rows[a:a + STEP_CHECK_BLOCK]
        # the mapped Jacobians side by side, (n, n k), as k (n, n) matrices
        A = np.array(jacobian.map(block.size)(x0, ref0, P[block].T))
        A = A.reshape(n, block.size, n).transpose(1, 0, 2)
        bad = np.flatnonzero(~np.isfinite(A).all(axis=(1, 2)))
        if bad.size:
            raise InputError(f"vehicles[{block[bad[0]]}]: the closed loop's Jacobian at the "
                             f"start is not finite; expected a vehicle the law can fly")
        # the spectral radius is at most any induced norm: a row whose smaller of the 1- and
        # inf-norms passes the rule needs no eigenvalues (at 1 ms, every row of a usual batch)
        bound = np.minimum(np.abs(A).sum(axis=1).max(axis=1), np.abs(A).sum(axis=2).max(axis=1))
        near = np.flatnonzero(bound * dt > RK4_LIMIT)
        fastest = np.abs(np.linalg.eigvals(A[near])).max(axis=1) if near.size else ()
        for b, f in zip(block[near].tolist(), list(fastest)):
            try:
                check_fastest_eigenvalue(float(f), dt)
            except InputError as e:
                raise InputError(f"vehicles[{b}]: {e}") from None


def simulate_batch(controller: Controller, vehicles: Sequence[Vehicle] | Vehicle,
                   trajectory: Any = "hover", duration: float = 10.0, dt: float | None = None,
                   controller_model: Vehicle | None = None,
                   cog_shape: Callable[[float], float] | CogProfile | None = None,
                   disturbances: Any = (), truth: TruthOptions | None = None,
                   limits: Limits | None = None, threads: int = 2,
                   progress: Callable[[float], Any] | None = None) -> BatchResult:
    """Fly one controller over many truth vehicles in parallel; keep metrics, not trajectories.

    Parameters
    ----------
    controller : Controller
        The law; it is redesigned for ``controller_model``.
    vehicles : sequence of Vehicle
        The B truth vehicles. They may differ in the 14 parameters (``Vehicle.parameters()``);
        their rotors (layout, constants, limits, time constant) must agree, since the compiled
        step holds them.
    trajectory : Trajectory, str or callable
        The reference, as for ``simulate``.
    duration : float
        Seconds.
    dt : float, optional
        The step (s); default ``quadcog.config.defaults["simulate.dt"]``.
    controller_model : Vehicle, optional
        The Vehicle the controller is designed for (one for all flights); default: the
        vehicles with r_G = 0, which must then be one vehicle.
    cog_shape : callable, CogProfile or None
        Flight b's CoG at time t is ``cog_shape(t) * vehicles[b].r_G``: a function of time,
        a CogProfile whose x component is used as the shape, or None (the CoG is there from
        t = 0).
    disturbances : sequence of Disturbance
        Wrench pulses, as for ``simulate``.
    truth : TruthOptions, optional
        As for ``simulate``.
    limits : Limits, optional
        As for ``simulate``.
    threads : int
        The number of threads that share the flights.
    progress : callable, optional
        ``progress(fraction)``, e.g. a ProgressBar.

    Returns
    -------
    BatchResult
        One entry per flight.

    Raises
    ------
    quadcog.InputError
        An argument of the wrong kind, vehicles with other rotors, or vehicles that differ in
        more than r_G without a ``controller_model``.
    """
    if not isinstance(controller, Controller):
        validate.fail("controller", "a quadcog Controller", controller)
    options, limits = run_options(truth, limits, progress)
    progress = validate.user_function(progress, "progress") if progress else None
    threads = validate.integer(threads, "threads", lo=1, hi=1024)
    cog_scale = _cog_scale(cog_shape)
    dt = config.get("simulate.dt", dt)
    vehicles, params, actuation = check_vehicles(vehicles, options)
    if controller_model is None:
        b = _same_but_cog(params)
        if b is not None:
            raise InputError(f"vehicles[{b}] differs from vehicles[0] in more than r_G: "
                             "pass controller_model (what the controller believes)")
        controller_model = vehicles[0].airframe.with_cog(np.zeros(3))
    elif not isinstance(controller_model, Vehicle):
        raise InputError(f"controller_model: expected a quadcog Vehicle or None, got "
                         f"{validate.plain(controller_model)}")
    controller = controller.for_vehicle(controller_model)
    duration, dt = check_time(duration, dt)
    schedule = Schedule.build(as_trajectory(trajectory), duration, dt,
                              disturbances=disturbances, cog_scale=cog_scale,
                              payloads=PayloadProfile([], vehicles[0].payloads))
    warn_late_disturbances(disturbances, duration)
    check_cog_range(params, schedule)
    x0 = start_at_reference(schedule.ref[0])
    nX = N_STATE + actuation.n_rotor_states + controller.n_state
    P0 = params.copy()
    P0[:, R_G] = cog_at(params[:, R_G], schedule.cog_scale[0], schedule.cog[0])
    P0 = whole_body(P0, schedule.payload[0])
    check_step_sizes(controller, x0, schedule.ref[0], P0, dt, actuation)
    Z = batch_start(controller, actuation, P0, x0)
    t0 = time.perf_counter()
    kernel = batch_kernel(controller, actuation, limits)
    if kernel is not None:
        Z = run_kernel(kernel, Z, params, schedule, threads=threads, progress=progress)
    else:
        Z = run_map(monitored_chunk_function(controller, actuation, limits), Z, params,
                    schedule, threads=threads, progress=progress)
    seconds = time.perf_counter() - t0
    return batch_metrics(Z, nX, schedule, limits, seconds)


def run_kernel(kernel: VectorKernel, Z: npt.NDArray[np.float64], Q: npt.NDArray[np.float64],
               schedule: Schedule, *extra: npt.ArrayLike, threads: int = 1,
               progress: Callable[[float], Any] | None = None) -> npt.NDArray[np.float64]:
    """The flights' states after the schedule's steps through a vector kernel.

    A chunk of steps at a time (for progress).

    Parameters
    ----------
    kernel : VectorKernel
        The step (``batch_kernel``).
    Z : (B, nZ) numpy.ndarray
        The flights' states at the start.
    Q : (B, nQ) numpy.ndarray
        The flights' parameters.
    schedule : Schedule
        The per-step inputs.
    *extra : (N, k) array_like
        Per-step arrays appended to the rows.
    threads : int
        Threads that share the flights.
    progress : callable, optional
        ``progress(fraction)``.

    Returns
    -------
    (B, nZ) numpy.ndarray
        Z after the last step.
    """
    n = schedule.n_steps
    k = 0
    while k < n:
        m = min(CHUNK, n - k)
        Z = kernel(Z, Q, schedule.rows(k, k + m, *extra), threads=threads)
        k += m
        if progress:
            progress(k / n)
    return Z


def run_map(chunk: ca.Function, Z: npt.NDArray[np.float64], Q: npt.NDArray[np.float64],
            schedule: Schedule, *extra: Any, threads: int = 1,
            progress: Callable[[float], Any] | None = None) -> npt.NDArray[np.float64]:
    """The flights' states after the schedule's steps through CasADi's map of ``chunk``.

    ``threads`` threads, each mapping its share of the flights serially (a plain "thread" map
    starts about one thread per flight); the per-step inputs and the ``extra`` per-step
    arrays are shared by all flights (reduce_in, not B copies). Padding steps have dt = 0 and
    count nothing.

    Parameters
    ----------
    chunk : casadi.Function
        CHUNK steps (``quadcog.sim.closed_loop.chunk_of``).
    Z : (B, nZ) numpy.ndarray
        The flights' states at the start.
    Q : (B, nQ) numpy.ndarray
        The flights' parameters.
    schedule : Schedule
        The per-step inputs.
    *extra : (N, k) array_like
        Further per-step inputs of ``chunk``.
    threads : int
        Threads that share the flights.
    progress : callable, optional
        ``progress(fraction)``.

    Returns
    -------
    (B, nZ) numpy.ndarray
        Z after the last step.
    """
    B = Z.shape[0]
    n_shared = chunk.n_in() - 2
    shared = list(range(2, 2 + n_shared))
    parts = max(1, min(threads, B))
    share = -(-B // parts)
    mapped = chunk.map("share", "serial", share, shared, [])
    if parts > 1:
        mapped = mapped.map("batch", "thread", parts, shared, [])
    pad = parts * share - B
    Zp = np.vstack([Z, np.repeat(Z[-1:], pad, axis=0)]).T if pad else Z.T
    Qp = np.vstack([Q, np.repeat(Q[-1:], pad, axis=0)]).T if pad else Q.T
    padded, n = schedule.padded(CHUNK), schedule.n_steps
    n_pad = padded.n_steps - n
    # extra: the *extra tuple, rebound to lists of 2-d arrays
    extra = [np.asarray(a, dtype=float).reshape(len(a), -1)  # type: ignore[assignment]
             for a in extra]
    extra = [np.vstack([a, np.repeat(a[-1:], n_pad, axis=0)])  # type: ignore[assignment]
             if n_pad else a for a in extra]
    k = 0
    while k < n:
        Zp = np.array(mapped(Zp, Qp, *padded.matrices(k, k + CHUNK),
                             *[a[k:k + CHUNK].T for a in extra]))
        k += min(CHUNK, n - k)
        if progress:
            progress(k / n)
    return Zp[:, :B].T


def batch_metrics(Z: npt.NDArray[np.float64], nX: int, schedule: Schedule, limits: Limits,
                  seconds: float) -> BatchResult:
    """The BatchResult of the monitored states after the last step.

    Metrics over the samples t_0 .. t_n, as for a single flight (the steps counted
    t_0 .. t_{n-1}; the final sample is checked and counted here, with the same rule).

    Parameters
    ----------
    Z : (B, nX + accumulators) numpy.ndarray
        The monitored states after the last step.
    nX : int
        12 + rotor states + controller states.
    schedule : Schedule
        The per-step inputs (reference, tail, times).
    limits : Limits
        The divergence limits.
    seconds : float
        The wall time to report (s).

    Returns
    -------
    BatchResult
        One entry per flight.
    """
    a = dict(zip(ACCUMULATORS, Z[:, nX:].T))
    n, B = schedule.n_steps, Z.shape[0]
    e_final = position_errors(Z[:, :3], np.repeat(schedule.ref[n:n + 1], B, axis=0))
    final_codes = np.array(divergence_rule(limits).map(B)(
        Z[:, :N_STATE].T, e_final[None, :], magnitude(Z[:, N_STATE:nX])[None, :])).ravel()
    tail_n = schedule.tail[n]
    code, at = a["code"].astype(int), a["diverged_at"].copy()
    count, sum_sq, mx = a["count"].copy(), a["sum_sq"].copy(), a["max"].copy()
    count_tail, sum_sq_tail = a["count_tail"].copy(), a["sum_sq_tail"].copy()
    last = a["last"].copy()
    final_hit = (code == 0) & (final_codes != 0)
    code[final_hit], at[final_hit] = final_codes[final_hit].astype(int), schedule.t[n]
    ok = code == 0                  # the final sample counts
    e = e_final
    count[ok] += 1
    sum_sq[ok] += e[ok] ** 2
    mx[ok] = np.maximum(mx[ok], e[ok])
    count_tail[ok] += tail_n
    sum_sq_tail[ok] += tail_n * e[ok] ** 2
    last[ok] = e[ok]
    diverged = code != 0
    m = metric_arrays(count, sum_sq, mx, count_tail, sum_sq_tail, last, diverged)
    causes = {c: DivergenceCause(c) for c in np.unique(code[diverged]).tolist()}
    return BatchResult(
        **m, diverged=diverged, diverged_at=np.where(diverged, at, np.nan),
        diverged_cause=[causes[c] if c else None for c in code.tolist()],
        final_state=Z[:, :nX].copy(), seconds=seconds)
