"""Shared fixtures: seeded samplers of admissible parameter sets and states."""
import numpy as np
import pytest

import quadcog
from quadcog.sampling import random_points

N_POINTS = 200       # every identity is checked at this many random points at least


@pytest.fixture(scope="session")
def model():
    return quadcog.load()


@pytest.fixture(scope="session")
def points():
    """N_POINTS seeded (x, U, p, vartheta) tuples."""
    return random_points(N_POINTS)


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
