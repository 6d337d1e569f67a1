"""The afternoon baseline of `make bench`: a hand-written numba RK4 of the plain rigid body.

What a user writes in an afternoon instead of quadcog: the rigid body with its CoG at the
body origin (no offset, no regressor), ZYX Euler angles, a cascade PD law (position PD to a
tilt, attitude PD to a torque), RK4 at 1 kHz with the law held over the step, flights over
``prange``. It does several times less arithmetic per step than quadcog's adaptive flight
(CoG offset in the dynamics, feedback linearization and its adaptation law), so it is the
floor quadcog's kernel should be compared with, not a like-for-like peer. Flights start
10 cm off their hover point, each at its own offset; every flight must end within 1 mm.
"""
import functools
import math

import numpy as np

__all__ = ["available", "fly"]


def available() -> bool:
    """Whether numba imports here."""
    try:
        import numba  # noqa: F401
    except ImportError:         # the bench extra: pip install -e '.[bench]'
        return False
    return True


@functools.lru_cache(maxsize=None)
def _kernels():
    """The jitted flight loop (numba imported and compiled on first use)."""
    import numba

    @numba.njit(cache=False, fastmath=False, inline="always")
    def _xdot(x, u, m, Ix, Iy, Iz, g, out):
        phi, th, psi = x[3], x[4], x[5]
        p, q, r = x[9], x[10], x[11]
        cf, sf, ct, st = math.cos(phi), math.sin(phi), math.cos(th), math.sin(th)
        cp, sp = math.cos(psi), math.sin(psi)
        T = u[0]
        out[0], out[1], out[2] = x[6], x[7], x[8]
        out[3] = p + (sf * q + cf * r) * st / ct
        out[4] = cf * q - sf * r
        out[5] = (sf * q + cf * r) / ct
        # world acceleration: R(eta) [0, 0, T] / m - g e3 (ZYX)
        out[6] = T / m * (cp * st * cf + sp * sf)
        out[7] = T / m * (sp * st * cf - cp * sf)
        out[8] = T / m * (ct * cf) - g
        out[9] = (u[1] - (Iz - Iy) * q * r) / Ix
        out[10] = (u[2] - (Ix - Iz) * p * r) / Iy
        out[11] = (u[3] - (Iy - Ix) * p * q) / Iz

    @numba.njit(cache=False, fastmath=False, inline="always")
    def _law(x, m, Ix, Iy, Iz, g, u):
        # position PD to accelerations, small-angle tilt, attitude PD to torques
        ax = -4.0 * x[0] - 3.0 * x[6]
        ay = -4.0 * x[1] - 3.0 * x[7]
        az = -4.0 * x[2] - 3.0 * x[8]
        psi = x[5]
        phi_d = (ax * math.sin(psi) - ay * math.cos(psi)) / g
        th_d = (ax * math.cos(psi) + ay * math.sin(psi)) / g
        u[0] = m * (g + az) / (math.cos(x[3]) * math.cos(x[4]))
        u[1] = Ix * (100.0 * (phi_d - x[3]) - 20.0 * x[9])
        u[2] = Iy * (100.0 * (th_d - x[4]) - 20.0 * x[10])
        u[3] = Iz * (25.0 * (0.0 - x[5]) - 10.0 * x[11])

    @numba.njit(parallel=True, cache=False, fastmath=False)
    def _fly(X0, n_steps, dt, m, Ix, Iy, Iz, g):
        n = X0.shape[0]
        out = np.empty_like(X0)
        for i in numba.prange(n):
            x = X0[i].copy()
            u = np.empty(4)
            k1, k2, k3, k4 = np.empty(12), np.empty(12), np.empty(12), np.empty(12)
            y = np.empty(12)
            for _ in range(n_steps):
                _law(x, m, Ix, Iy, Iz, g, u)
                _xdot(x, u, m, Ix, Iy, Iz, g, k1)
                for j in range(12):
                    y[j] = x[j] + 0.5 * dt * k1[j]
                _xdot(y, u, m, Ix, Iy, Iz, g, k2)
                for j in range(12):
                    y[j] = x[j] + 0.5 * dt * k2[j]
                _xdot(y, u, m, Ix, Iy, Iz, g, k3)
                for j in range(12):
                    y[j] = x[j] + dt * k3[j]
                _xdot(y, u, m, Ix, Iy, Iz, g, k4)
                for j in range(12):
                    x[j] += dt / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
            out[i] = x
        return out


    return _fly


def fly(n_flights: int, n_steps: int, threads: int, vehicle, dt: float = 1e-3,
        seed: int = 0) -> np.ndarray:
    """Fly ``n_flights`` hover flights of ``n_steps`` steps on ``threads`` numba threads.

    Parameters
    ----------
    n_flights, n_steps, threads : int
        Flights, RK4 steps of ``dt`` each, numba threads.
    vehicle : quadcog.Vehicle
        Mass and the diagonal inertia (its CoG offset is ignored: this is the plain body).
    dt : float
        Step, s.
    seed : int
        Seed of the initial offsets (uniform in +-0.1 m per axis).

    Returns
    -------
    numpy.ndarray, shape (n_flights, 12)
        Final states (position m, ZYX angles rad, velocity m/s, body rates rad/s).
    """
    if not available():
        raise ImportError("numba is not installed: pip install -e '.[bench]'")
    import numba
    numba.set_num_threads(threads)
    X0 = np.zeros((n_flights, 12))
    X0[:, :3] = np.random.default_rng(seed).uniform(-0.1, 0.1, (n_flights, 3))
    return _kernels()(X0, n_steps, dt, vehicle.m, vehicle.Ixx, vehicle.Iyy, vehicle.Izz, 9.81)
