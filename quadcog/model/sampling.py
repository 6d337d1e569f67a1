"""Seeded random admissible parameter sets, states and inputs (for Monte Carlo and checks)."""
import numpy as np
import numpy.typing as npt

from quadcog.model.conventions import IDX, N_PARAM, N_STATE, NU
from quadcog.model.parameters import is_admissible

__all__ = ["random_parameters", "random_state", "random_input", "random_points"]


def random_parameters(rng: np.random.Generator) -> npt.NDArray[np.float64]:
    """An admissible parameter set.

    Parameters
    ----------
    rng : numpy.random.Generator
        The random source.

    Returns
    -------
    (14,) numpy.ndarray
        p: m in [0.3, 2] kg, g in [9, 10.5] m/s^2, I_O entries in [0.003, 0.05] kg m^2, drag
        in [0, 0.5], r_G in [-0.1, 0.1]^3 m, resampled until it is admissible with the margin
        of ``quadcog.model.parameters``.
    """
    while True:
        p = np.empty(N_PARAM)
        p[IDX["m"]] = rng.uniform(0.3, 2.0)
        p[IDX["g"]] = rng.uniform(9.0, 10.5)
        p[IDX["Ixx"]:IDX["Izz"] + 1] = rng.uniform(0.003, 0.05, 3)
        p[IDX["c_x"]:IDX["c_psi"] + 1] = rng.uniform(0.0, 0.5, 6)
        p[IDX["x_G"]:] = rng.uniform(-0.1, 0.1, 3)
        if is_admissible(p):
            return p


def random_state(rng: np.random.Generator) -> npt.NDArray[np.float64]:
    """A random state.

    Parameters
    ----------
    rng : numpy.random.Generator
        The random source.

    Returns
    -------
    (12,) numpy.ndarray
        x: position in [-5, 5] m, roll and pitch in [-1.2, 1.2] rad (away from the Euler
        singularity), yaw in [-pi, pi], velocities and rates in [-3, 3] (m/s, rad/s).
    """
    x = np.empty(N_STATE)
    x[0:3] = rng.uniform(-5, 5, 3)
    x[3:5] = rng.uniform(-1.2, 1.2, 2)
    x[5] = rng.uniform(-np.pi, np.pi)
    x[NU] = rng.uniform(-3, 3, 6)
    return x


def random_input(rng: np.random.Generator) -> npt.NDArray[np.float64]:
    """A random input.

    Parameters
    ----------
    rng : numpy.random.Generator
        The random source.

    Returns
    -------
    (4,) numpy.ndarray
        U: thrust in [0, 20] N, moments in [-1, 1] N m.
    """
    return np.concatenate([[rng.uniform(0, 20)], rng.uniform(-1, 1, 3)])


def random_points(n: int, seed: int = 20110828) -> list[tuple[npt.NDArray[np.float64], ...]]:
    """Seeded random points of the model.

    Parameters
    ----------
    n : int
        How many.
    seed : int, optional
        Seed of the numpy Generator.

    Returns
    -------
    list of tuple
        n tuples (x (12,), U (4,), p (14,), vartheta (6,)): state, input and parameters as
        ``random_state``, ``random_input``, ``random_parameters``; vartheta a generalized
        acceleration in [-5, 5] (m/s^2, rad/s^2).
    """
    rng = np.random.default_rng(seed)
    return [(random_state(rng), random_input(rng), random_parameters(rng),
             rng.uniform(-5, 5, 6)) for _ in range(n)]
