"""What a run's steps read, sampled once per run: the Schedule.

Step k starts at t_k = k dt. Everything that changes with time comes from the schedule: the
reference row, the CoG (``r_G(t_k) = cog_scale_k * r_G(vehicle) + cog_k``), the disturbance
wrench, the step length (0 for padding steps, which change nothing) and whether the sample is in
the tail of the metrics. The compiled steps take these as named inputs (``STEP_INPUTS``),
never as columns of one table.
"""
from dataclasses import dataclass

import casadi as ca
import numpy as np

from quadcog import config
from quadcog.model.conventions import R_G
from quadcog.sim.timeline import CogProfile, wrench_table
from quadcog.trajectories.analytic import REF_SIZE

# (name, rows) of the per-step inputs of the compiled steps, in their order
STEP_INPUTS = (("t", 1), ("dt", 1), ("ref", REF_SIZE), ("cog", 3), ("cog_scale", 1),
               ("wrench", 6), ("tail", 1))


def tail_start(duration):
    """Time (s) from which the tail metrics count: the last ``metrics.tail_fraction``."""
    return (1 - config.defaults["metrics.tail_fraction"]) * duration


def cog_at(r_vehicle, cog_scale, cog):
    """The CoG r_G (m) at a step: ``cog_scale * r_vehicle + cog``; numpy arrays (any leading
    shape) or CasADi symbols. The one place where r_G(t) is formed."""
    return cog_scale * r_vehicle + cog


def truth_parameters(P, cog_scale, cog):
    """The truth parameter vector at a step: P (14,) with r_G = ``cog_at(r_G(P), ...)``
    (numpy or CasADi)."""
    r = cog_at(P[R_G], cog_scale, cog)
    if isinstance(P, np.ndarray):
        out = P.copy()
        out[R_G] = r
        return out
    return ca.vertcat(P[:R_G.start], r)


@dataclass(frozen=True)
class Schedule:
    """The per-step inputs of one run, sampled at t_0 .. t_n (N = n + 1 samples).

    t (N,) s; dt (N,) s (the length of the step starting there; 0 for padding); ref (N, 14);
    cog (N, 3) m (the CoG profile); cog_scale (N,) (1 for single flights); wrench (N, 6);
    tail (N,) 1.0 where the sample counts for the tail metrics. Arrays are C-contiguous, so a
    block of rows is one column-major CasADi matrix per input.
    """
    t: np.ndarray
    dt: np.ndarray
    ref: np.ndarray
    cog: np.ndarray
    cog_scale: np.ndarray
    wrench: np.ndarray
    tail: np.ndarray

    @classmethod
    def build(cls, trajectory, duration, dt, cog=None, disturbances=(), cog_scale=None):
        """Sample a run: ``trajectory`` (a Trajectory), ``duration`` and ``dt`` (s, checked by
        the caller), ``cog`` (a CogProfile or None), ``disturbances`` (Disturbance pulses),
        ``cog_scale`` (a function of t, or None for 1)."""
        n = int(round(duration / dt))
        t = np.arange(n + 1) * dt
        cog = cog if cog is not None else CogProfile()
        scale = (np.ones(n + 1) if cog_scale is None
                 else np.array([float(cog_scale(tk)) for tk in t]))
        arrays = dict(t=t, dt=np.full(n + 1, float(dt)), ref=trajectory.sample(t),
                      cog=cog.sample(t), cog_scale=scale,
                      wrench=wrench_table(disturbances, t),
                      tail=(t >= tail_start(duration) - 1e-12).astype(float))
        return cls(**{k: np.ascontiguousarray(v, dtype=float) for k, v in arrays.items()})

    @property
    def n_steps(self):
        """Number of steps n (samples N = n + 1)."""
        return self.t.size - 1

    def r_G(self, r_vehicle):
        """(N, 3) r_G at every sample for a vehicle whose own offset is ``r_vehicle`` (3,)."""
        return cog_at(np.asarray(r_vehicle, float)[None, :], self.cog_scale[:, None], self.cog)

    def padded(self, multiple):
        """A schedule whose step count is a multiple of ``multiple``: padding steps repeat the
        last sample with dt = 0 and tail = 0, so they change neither state nor sums."""
        n_pad = -(-self.n_steps // multiple) * multiple - self.n_steps
        if n_pad == 0:
            return self
        out = {}
        for name, _ in STEP_INPUTS:
            a = getattr(self, name)
            out[name] = np.ascontiguousarray(np.concatenate([a, np.repeat(a[-1:], n_pad, 0)]))
        out["dt"][self.t.size - 1:] = 0.0
        out["tail"][self.t.size:] = 0.0
        return Schedule(**out)

    def rows(self, start, stop, *extra):
        """Steps start .. stop - 1 as one (stop - start, n_row) C-contiguous array: the
        per-step inputs side by side in ``STEP_INPUTS`` order, then the ``extra`` arrays
        (N, k) (the layout of ``quadcog.sim.closed_loop.packed``)."""
        parts = [a.reshape(stop - start, -1) for a in self.block(start, stop)]
        parts += [np.asarray(a, dtype=float)[start:stop].reshape(stop - start, -1)
                  for a in extra]
        return np.ascontiguousarray(np.hstack(parts))

    def matrices(self, start, stop):
        """The per-step inputs of steps start .. stop - 1 as CasADi-shaped matrices (rows x
        steps, one per input in ``STEP_INPUTS`` order), for the mapped CasADi functions."""
        return [a.T if a.ndim == 2 else a[None, :] for a in self.block(start, stop)]

    def block(self, start, stop):
        """The per-step inputs of steps start .. stop - 1 as a list of C-contiguous arrays in
        ``STEP_INPUTS`` order (views, no copies)."""
        return [getattr(self, name)[start:stop] for name, _ in STEP_INPUTS]
