"""Many flights at once, keeping metrics (the same definition and divergence rule as single
flights) instead of trajectories: the monitored closed-loop step run by the vector kernel
(``quadcog.codegen.vector_kernel``, flights in the CPU's vector lanes, ``threads`` threads) or, where that
cannot be built, by CasADi's map."""
from dataclasses import dataclass
import time

import numpy as np

from quadcog import config, validate
from quadcog.codegen.vector_kernel import kernel_for
from quadcog.controllers.base import Controller
from quadcog.errors import InputError
from quadcog.model.conventions import N_STATE, R_G
from quadcog.sim.closed_loop import ACCUMULATORS, CHUNK, monitored_chunk_function, monitored_step, packed
from quadcog.sim.divergence import DivergenceCause, divergence_rule, magnitude
from quadcog.sim.plant import Actuation
from quadcog.sim.prepare import batch_start, check_time, run_options, start_at_reference
from quadcog.sim.result import metrics_from_sums, position_errors
from quadcog.sim.schedule import Schedule, cog_at
from quadcog.sim.timeline import CogProfile
from quadcog.trajectories.registry import as_trajectory
from quadcog.vehicles.vehicle import Vehicle


@dataclass
class BatchResult:
    """Metrics of many flights (arrays with one entry per flight, lengths in m, times in s),
    each as ``quadcog.Metrics`` defines it for a single flight."""
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

    def to_arrow(self):  # -> pyarrow.Table (pyarrow is optional)
        """The metrics as a pyarrow Table, one row per flight (needs pyarrow).

        Returns
        -------
        pyarrow.Table
            The columns of ``columns()``.
        """
        from quadcog.logs.table import require_pyarrow
        require_pyarrow()
        import pyarrow as pa
        return pa.table({k: v.tolist() if v.dtype.kind == "U" else v
                         for k, v in self.columns().items()})

    def to_pandas(self):  # -> pandas.DataFrame (pandas is optional)
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


def batch_kernel(controller, actuation, limits):
    """The vector kernel of the monitored step (``quadcog.codegen.vector_kernel.kernel_for``), or None where
    it cannot be built. Rows come from ``Schedule.rows``."""
    return kernel_for(("batch", controller.cache_key(), actuation, limits),
                      lambda: packed(monitored_step(controller, actuation, limits)))


def _vehicles(vehicles, options):
    """The checked list of truth vehicles and their shared Actuation."""
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
    return vehicles, actuation


def _cog_scale(cog_shape):
    """cog_shape as a checked function of time (or None)."""
    if cog_shape is None:
        return None
    if isinstance(cog_shape, CogProfile):
        profile = cog_shape
        return lambda t: profile.sample([t])[0, 0]
    if not callable(cog_shape):
        validate.fail("cog_shape", "None, a CogProfile or a function of time", cog_shape)
    return lambda t: validate.real(cog_shape(t), f"cog_shape({validate.plain(float(t))})")


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
    cog_scale = _cog_scale(cog_shape)
    dt = config.get("simulate.dt", dt)
    vehicles, actuation = _vehicles(vehicles, options)
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
    duration, dt = check_time(duration, dt)
    schedule = Schedule.build(as_trajectory(trajectory), duration, dt,
                              disturbances=disturbances, cog_scale=cog_scale)
    x0 = start_at_reference(schedule.ref[0])
    nX = N_STATE + actuation.n_rotor_states + controller.n_state
    P0 = params.copy()
    P0[:, R_G] = cog_at(params[:, R_G], schedule.cog_scale[0], schedule.cog[0])
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


def run_kernel(kernel, Z, Q, schedule, *extra, threads=1, progress=None):
    """Z (B, nZ) after the schedule's steps through a vector kernel, a chunk of steps at a
    time (for progress); ``extra``: per-step arrays appended to the rows."""
    n = schedule.n_steps
    k = 0
    while k < n:
        m = min(CHUNK, n - k)
        Z = kernel(Z, Q, schedule.rows(k, k + m, *extra), threads=threads)
        k += m
        if progress:
            progress(k / n)
    return Z


def run_map(chunk, Z, Q, schedule, *extra, threads=1, progress=None):
    """Z (B, nZ) after the schedule's steps through CasADi's map of ``chunk``
    (``quadcog.sim.closed_loop.chunk_of``): ``threads`` threads, each mapping its share of the
    flights serially (a plain "thread" map starts about one thread per flight); the per-step
    inputs and the ``extra`` per-step arrays (N, k) are shared by all flights (reduce_in, not
    B copies). Padding steps have dt = 0 and count nothing."""
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
    extra = [np.asarray(a, dtype=float).reshape(len(a), -1) for a in extra]
    extra = [np.vstack([a, np.repeat(a[-1:], n_pad, axis=0)]) if n_pad else a for a in extra]
    k = 0
    while k < n:
        Zp = np.array(mapped(Zp, Qp, *padded.matrices(k, k + CHUNK),
                             *[a[k:k + CHUNK].T for a in extra]))
        k += min(CHUNK, n - k)
        if progress:
            progress(k / n)
    return Zp[:, :B].T


def batch_metrics(Z, nX, schedule, limits, seconds):
    """BatchResult from the monitored states Z (B, nX + accumulators) after the last step:
    metrics over the samples t_0 .. t_n, as for a single flight (the steps counted
    t_0 .. t_{n-1}; the final sample is checked and counted here, with the same rule).
    ``seconds``: the wall time to report."""
    a = dict(zip(ACCUMULATORS, Z[:, nX:].T))
    n, B = schedule.n_steps, Z.shape[0]
    e_final = position_errors(Z[:, :3], np.repeat(schedule.ref[n:n + 1], B, axis=0))
    final_codes = np.array(divergence_rule(limits).map(B)(
        Z[:, :N_STATE].T, e_final[None, :], magnitude(Z[:, N_STATE:nX])[None, :])).ravel()
    tail_n = schedule.tail[n]
    metrics = []
    for b in range(B):
        code, at = int(a["code"][b]), a["diverged_at"][b]
        sums = [a[k][b] for k in ("count", "sum_sq", "max", "count_tail", "sum_sq_tail", "last")]
        if not code and final_codes[b]:
            code, at = int(final_codes[b]), schedule.t[n]
        elif not code:          # the final sample counts
            e = e_final[b]
            sums = [sums[0] + 1, sums[1] + e * e, max(sums[2], e), sums[3] + tail_n,
                    sums[4] + tail_n * e * e, e]
        cause = DivergenceCause(code) if code else None
        metrics.append(metrics_from_sums(*sums, diverged_at=at, cause=cause, limits=limits))
    field = lambda name: np.array([getattr(m, name) for m in metrics], dtype=float)
    return BatchResult(
        rms_position_error=field("rms_position_error"),
        max_position_error=field("max_position_error"),
        rms_position_error_tail=field("rms_position_error_tail"),
        final_position_error=field("final_position_error"),
        diverged=np.array([m.diverged for m in metrics], dtype=bool),
        diverged_at=np.array([m.diverged_at if m.diverged else np.nan for m in metrics]),
        diverged_cause=[m.diverged_cause for m in metrics],
        final_state=Z[:, :nX].copy(), seconds=seconds)
