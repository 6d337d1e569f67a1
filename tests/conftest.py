"""Shared fixtures: seeded samplers of admissible parameter sets and states."""
import numpy as np
import pytest

import quadcog
from quadcog.conventions import IDX

N_POINTS = 200       # every identity is checked at this many random points at least


def random_parameters(rng):
    """An admissible parameter set: m, g, I_O > 0, c >= 0, I_G positive definite."""
    while True:
        p = np.empty(14)
        p[IDX["m"]] = rng.uniform(0.3, 2.0)
        p[IDX["g"]] = rng.uniform(9.0, 10.5)
        p[IDX["Ixx"]:IDX["Izz"] + 1] = rng.uniform(0.003, 0.05, 3)
        p[IDX["c_x"]:IDX["c_psi"] + 1] = rng.uniform(0.0, 0.5, 6)
        p[IDX["x_G"]:] = rng.uniform(-0.1, 0.1, 3)
        if np.linalg.eigvalsh(quadcog.inertia_about_cog(p))[0] > 1e-4:
            return p


def random_state(rng):
    x = np.empty(12)
    x[0:3] = rng.uniform(-5, 5, 3)
    x[3:5] = rng.uniform(-1.2, 1.2, 2)        # away from the Euler singularity
    x[5] = rng.uniform(-np.pi, np.pi)
    x[6:9] = rng.uniform(-3, 3, 3)
    x[9:12] = rng.uniform(-3, 3, 3)
    return x


def random_input(rng):
    return np.concatenate([[rng.uniform(0, 20)], rng.uniform(-1, 1, 3)])


@pytest.fixture(scope="session")
def model():
    return quadcog.load()


@pytest.fixture(scope="session")
def points():
    """N_POINTS seeded (x, U, p, vartheta) tuples."""
    rng = np.random.default_rng(20110828)
    return [(random_state(rng), random_input(rng), random_parameters(rng),
             rng.uniform(-5, 5, 6)) for _ in range(N_POINTS)]


@pytest.fixture(scope="session")
def derived():
    """The SymPy derivation (tests may import SymPy; the runtime may not)."""
    from derive.model import derive_model
    return derive_model()


def assert_close(actual, expected, rtol, what, point=None):
    """|actual - expected|_max <= rtol * max(1, |expected|_max), with a readable message."""
    actual, expected = np.asarray(actual, float), np.asarray(expected, float)
    scale = max(1.0, float(np.max(np.abs(expected))))
    err = float(np.max(np.abs(actual - expected)))
    assert err <= rtol * scale, (
        f"{what}: max abs error {err:.3e} > {rtol:g} * {scale:.3g}"
        + (f" at point {point}" if point is not None else "")
        + f"\nactual:\n{actual}\nexpected:\n{expected}")
    return err / scale
