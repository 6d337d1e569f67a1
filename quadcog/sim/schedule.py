"""What a run's steps read, sampled once per run: the Schedule.

Step k starts at t_k = k dt. Everything that changes with time comes from the schedule: the
reference row, the CoG (``r_G(t_k) = cog_scale_k * r_G(vehicle) + cog_k``), the payloads on
board (their summed inertial parameters about O), the disturbance wrench, the step length (0
for padding steps, which change nothing) and whether the sample is in the tail of the
metrics. The compiled steps take these as named inputs (``STEP_INPUTS``),
never as columns of one table.
"""
from collections.abc import Callable, Iterable
from dataclasses import dataclass
import operator
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing as npt

from quadcog import config, validate
from quadcog.model.conventions import R_G
from quadcog.model.inertial_parameters import N_PI
from quadcog.numerics import repeated_row
from quadcog.sim.timeline import CogProfile, PayloadProfile, wrench_table
from quadcog.trajectories.analytic import REF_SIZE, Trajectory

__all__ = ["STEP_INPUTS", "tail_start", "cog_at", "truth_parameters", "Schedule", "check_time"]

# (name, rows) of the per-step inputs of the compiled steps, in their order
STEP_INPUTS = (("t", 1), ("dt", 1), ("ref", REF_SIZE), ("cog", 3), ("cog_scale", 1),
               ("payload", N_PI), ("wrench", 6), ("tail", 1))


def check_time(duration: Any, dt: Any) -> tuple[float, float]:
    """The checked duration and step of a run.

    Parameters
    ----------
    duration : float
        The run's duration (s).
    dt : float
        The step (s).

    Returns
    -------
    duration : float
        The duration (s).
    dt : float
        The step (s).

    Raises
    ------
    quadcog.InputError
        Unless both are positive numbers, dt <= duration and the step count is within
        ``config.defaults["simulate.max_steps"]``.
    """
    duration = validate.positive(duration, "duration", "s")
    dt = validate.positive(dt, "dt", "s")
    if dt > duration:
        validate.fail("dt", f"a step no longer than the duration ({duration!r} s)", dt)
    validate.step_count(duration, dt, int(config.get("simulate.max_steps")))
    return duration, dt


def tail_start(duration: float) -> float:
    """Time from which the tail metrics count: the last ``metrics.tail_fraction``.

    Parameters
    ----------
    duration : float
        The run's duration (s).

    Returns
    -------
    float
        The start of the tail (s).

    Raises
    ------
    quadcog.InputError
        ``duration`` not a positive number (s).
    """
    return (1 - config.get("metrics.tail_fraction")) * validate.positive(duration, "duration",
                                                                          "s")


def cog_at(r_vehicle: Any, cog_scale: Any, cog: Any) -> Any:
    """The CoG r_G at a step: ``cog_scale * r_vehicle + cog``.

    The one place where r_G(t) is formed. Numpy arrays (any leading shape, broadcast) or
    CasADi symbols.

    Parameters
    ----------
    r_vehicle : (..., 3) numpy.ndarray or casadi.SX
        The vehicle's own CoG offset (m, body frame).
    cog_scale : float, numpy.ndarray or casadi.SX
        Its scale at the step (1 for single flights).
    cog : (..., 3) numpy.ndarray or casadi.SX
        The CoG profile's offset at the step (m).

    Returns
    -------
    (..., 3) numpy.ndarray or casadi.SX
        r_G (m, body frame).
    """
    return cog_scale * r_vehicle + cog


def truth_parameters(P: Any, cog_scale: Any, cog: Any) -> Any:
    """The truth parameter vector at a step: P with r_G = ``cog_at(r_G(P), ...)``.

    Parameters
    ----------
    P : (14,) numpy.ndarray or casadi.SX
        The vehicle's parameter vector.
    cog_scale : float, numpy.ndarray or casadi.SX
        The scale of the vehicle's own r_G at the step.
    cog : (3,) numpy.ndarray or casadi.SX
        The CoG profile's offset at the step (m).

    Returns
    -------
    (14,) numpy.ndarray or casadi.SX
        P with the step's r_G (a copy for numpy).
    """
    r = cog_at(P[R_G], cog_scale, cog)
    if isinstance(P, np.ndarray):
        out = P.copy()
        out[R_G] = r
        return out
    return ca.vertcat(P[:R_G.start], r)


def _scales(cog_scale: Callable[[float], float], t: npt.NDArray[np.floating[Any]]
            ) -> npt.NDArray[np.float64]:
    """``cog_scale(t_k)`` at every sample, each a finite real number (a string or NaN is
    named with its time). Plain finite floats (what the batch's checked shape gives) are
    taken at once; anything else is checked value by value."""
    values = [cog_scale(tk) for tk in t]
    if not all(type(v) is float for v in values):
        values = [validate.real(v, f"cog_scale({validate.plain(float(tk))})")
                  for v, tk in zip(values, t)]
    scale = np.array(values, dtype=float)
    bad = np.flatnonzero(~np.isfinite(scale))
    if bad.size:
        k = int(bad[0])
        validate.fail(f"cog_scale({validate.plain(float(t[k]))})", "a finite real number",
                      values[k])
    return scale


@dataclass(frozen=True)
class Schedule:
    """The per-step inputs of one run, sampled at t_0 .. t_n (N = n + 1 samples).

    Arrays are C-contiguous, so a block of rows is one column-major CasADi matrix per input.
    Build it with ``Schedule.build``.

    Parameters
    ----------
    t : (N,) numpy.ndarray
        Sample times (s).
    dt : (N,) numpy.ndarray
        The length of the step starting there (s; 0 for padding).
    ref : (N, 14) numpy.ndarray
        Reference rows (``quadcog.trajectories.analytic``).
    cog : (N, 3) numpy.ndarray
        The CoG profile (m, body frame).
    cog_scale : (N,) numpy.ndarray
        Scale of the vehicle's own r_G (1 for single flights).
    payload : (N, 10) numpy.ndarray
        Summed inertial parameters about O of the payloads on board
        (``quadcog.model.inertial_parameters.PI_NAMES``; zeros: none).
    wrench : (N, 6) numpy.ndarray
        Disturbance force (N, ground axes) and moment (N m, body axes).
    tail : (N,) numpy.ndarray
        1.0 where the sample counts for the tail metrics.
    constant_reference : bool
        Every reference row is the same (the trajectory says so: ``Trajectory.constant``).
    """
    t: np.ndarray
    dt: np.ndarray
    ref: np.ndarray
    cog: np.ndarray
    cog_scale: np.ndarray
    payload: np.ndarray
    wrench: np.ndarray
    tail: np.ndarray
    constant_reference: bool = False

    @classmethod
    def build(cls, trajectory: Trajectory, duration: float, dt: float,
              cog: CogProfile | None = None, disturbances: Iterable[Any] | None = (),
              cog_scale: Callable[[float], float] | None = None,
              payloads: PayloadProfile | None = None) -> "Schedule":
        """Sample a run.

        Parameters
        ----------
        trajectory : Trajectory
            The reference.
        duration : float
            The run's duration (s, checked by the caller).
        dt : float
            The step (s, checked by the caller).
        cog : CogProfile, optional
            The CoG changes (default none).
        disturbances : sequence of Disturbance
            Wrench pulses (or what ``as_disturbances`` accepts).
        cog_scale : callable, optional
            ``cog_scale(t)``, the scale of the vehicle's own r_G at time t (s); None for 1.
        payloads : PayloadProfile, optional
            The payloads carried over time (default none).

        Returns
        -------
        Schedule
            The per-step inputs at t_k = k dt, k = 0 .. round(duration / dt).

        Raises
        ------
        quadcog.InputError
            An argument of the wrong kind (``check_time`` for the duration and step), or a
            ``cog_scale`` value that is not a finite number.
        """
        if not isinstance(trajectory, Trajectory):
            validate.fail("trajectory", "a quadcog Trajectory "
                          "(quadcog.trajectories.registry.as_trajectory)", trajectory)
        duration, dt = check_time(duration, dt)
        if cog is not None and not isinstance(cog, CogProfile):
            validate.fail("cog", "None or a CogProfile", cog)
        if payloads is not None and not isinstance(payloads, PayloadProfile):
            validate.fail("payloads", "None or a PayloadProfile", payloads)
        if cog_scale is not None and not callable(cog_scale):
            validate.fail("cog_scale", "None or a function of time t (s)", cog_scale)
        n = int(round(duration / dt))
        t = np.arange(n + 1) * dt
        cog = cog if cog is not None else CogProfile()
        scale = np.ones(n + 1) if cog_scale is None else _scales(cog_scale, t)
        arrays = dict(t=t, dt=np.full(n + 1, float(dt)), ref=trajectory.sample(t),
                      cog=cog.sample(t), cog_scale=scale,
                      payload=(payloads.sample(t) if payloads else np.zeros((n + 1, N_PI))),
                      wrench=wrench_table(disturbances, t),
                      tail=(t >= tail_start(duration) - 1e-12).astype(float))
        return cls(**{k: np.ascontiguousarray(v, dtype=float) for k, v in arrays.items()},
                   constant_reference=trajectory.constant)

    @property
    def n_steps(self) -> int:
        """Number of steps n (samples N = n + 1)."""
        return self.t.size - 1

    def r_G(self, r_vehicle: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The CoG at every sample.

        Parameters
        ----------
        r_vehicle : (3,) array_like
            The vehicle's own CoG offset (m, body frame).

        Returns
        -------
        (N, 3) numpy.ndarray
            r_G (m) at every sample.

        Raises
        ------
        quadcog.InputError
            ``r_vehicle`` not 3 finite numbers.
        """
        r = validate.vector(r_vehicle, "r_vehicle", 3)
        if (self.cog_scale == 1.0).all():     # a single flight's: 1 * r is r, one pass fewer
            out = repeated_row(r, self.cog.shape[0])    # r + cog, without numpy's per-row loop
            out += self.cog
            return out
        return cog_at(r[None, :], self.cog_scale[:, None], self.cog)

    def padded(self, multiple: int) -> "Schedule":
        """A schedule whose step count is a multiple of ``multiple``.

        Padding steps repeat the last sample with dt = 0 and tail = 0, so they change neither
        state nor sums.

        Parameters
        ----------
        multiple : int
            The step count to pad to a multiple of (e.g. ``CHUNK``).

        Returns
        -------
        Schedule
            This schedule when no padding is needed, else a padded copy.

        Raises
        ------
        quadcog.InputError
            ``multiple`` not an integer in [1, ``config.defaults["simulate.max_steps"]``].
        """
        # padding adds fewer than `multiple` steps: at most a run's most (a bigger multiple
        # asked for memory no run has)
        multiple = validate.integer(multiple, "multiple", lo=1,
                                    hi=int(config.get("simulate.max_steps")))
        n_pad = -(-self.n_steps // multiple) * multiple - self.n_steps
        if n_pad == 0:
            return self
        out = {}
        for name, _ in STEP_INPUTS:
            a = getattr(self, name)
            out[name] = np.ascontiguousarray(np.concatenate([a, np.repeat(a[-1:], n_pad, 0)]))
        out["dt"][self.t.size - 1:] = 0.0
        out["tail"][self.t.size:] = 0.0
        return Schedule(**out, constant_reference=self.constant_reference)

    def rows(self, start: int, stop: int, *extra: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Steps start .. stop - 1 as one C-contiguous array of rows.

        The layout of ``quadcog.sim.closed_loop.packed``.

        Parameters
        ----------
        start : int
            First step.
        stop : int
            One past the last step.
        *extra : (N, k) array_like
            Further per-step arrays, appended to each row.

        Returns
        -------
        (stop - start, n_row) numpy.ndarray
            The per-step inputs side by side in ``STEP_INPUTS`` order, then ``extra``.

        Raises
        ------
        quadcog.InputError
            ``start``, ``stop`` not steps with 0 <= start < stop <= N.
        """
        start, stop = self._span(start, stop, empty=False)
        parts = [a.reshape(stop - start, -1) for a in self.block(start, stop)]
        parts += [np.asarray(a, dtype=float)[start:stop].reshape(stop - start, -1)
                  for a in extra]
        return np.ascontiguousarray(np.hstack(parts))

    def matrices(self, start: int, stop: int) -> list[npt.NDArray[np.float64]]:
        """The per-step inputs of steps start .. stop - 1 as CasADi-shaped matrices.

        For the mapped CasADi functions.

        Parameters
        ----------
        start : int
            First step.
        stop : int
            One past the last step.

        Returns
        -------
        list of numpy.ndarray
            One (rows, stop - start) matrix per input, in ``STEP_INPUTS`` order.

        Raises
        ------
        quadcog.InputError
            ``start``, ``stop`` not steps with 0 <= start <= stop <= N.
        """
        return [a.T if a.ndim == 2 else a[None, :] for a in self.block(start, stop)]

    def _span(self, start: Any, stop: Any, empty: bool = True) -> tuple[int, int]:
        """``start``, ``stop`` as ints with 0 <= start <= stop <= N (a slice of the samples;
        ``start < stop`` unless ``empty``)."""
        n = self.t.size
        what = f"steps 0 <= start {'<=' if empty else '<'} stop <= {n}"
        if isinstance(start, (bool, np.bool_)) or isinstance(stop, (bool, np.bool_)):
            validate.fail("start, stop", what, (start, stop))
        try:
            first, last = operator.index(start), operator.index(stop)
        except TypeError:
            validate.fail("start, stop", what, (start, stop))
        if not (0 <= first <= last <= n and (empty or first < last)):
            validate.fail("start, stop", what, (start, stop))
        return first, last

    def block(self, start: int, stop: int) -> list[npt.NDArray[np.float64]]:
        """The per-step inputs of steps start .. stop - 1 (views, no copies).

        Parameters
        ----------
        start : int
            First step.
        stop : int
            One past the last step.

        Returns
        -------
        list of numpy.ndarray
            C-contiguous (stop - start, ...) arrays in ``STEP_INPUTS`` order.

        Raises
        ------
        quadcog.InputError
            ``start``, ``stop`` not steps with 0 <= start <= stop <= N.
        """
        start, stop = self._span(start, stop)
        return [getattr(self, name)[start:stop] for name, _ in STEP_INPUTS]
