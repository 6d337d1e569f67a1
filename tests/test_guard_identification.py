"""Guard of identification's interval of a mean of block means
(quadcog.identification.segments.block_mean_ci95) against a printed Student t table and
against what a 95 % interval means: over many seeded sets of independent normal blocks it
covers the true mean 95 % of the times. (bench/mutations.py: ci95_degrees_of_freedom.)"""
import math

import numpy as np
import pytest

from quadcog.identification.segments import block_mean_ci95


@pytest.mark.parametrize("blocks, t_table", [
    ([1.0, 2.0, 3.0], 4.303),                  # n = 3: t(0.975, 2 dof)
    ([1.0, 3.0, 1.0, 3.0, 1.0, 3.0], 2.571),   # n = 6: t(0.975, 5); neighbours anti-correlated
])
def test_half_width_is_t_of_n_minus_1_times_the_standard_error(blocks, t_table):
    b = np.asarray(blocks)
    n = b.size
    s = math.sqrt(((b - b.mean()) ** 2).sum() / (n - 1))
    mean, half = block_mean_ci95(b)
    assert mean == pytest.approx(b.mean(), rel=1e-15)
    assert half == pytest.approx(t_table * s / math.sqrt(n), rel=2e-4)


def test_the_interval_covers_the_mean_95_percent_of_the_times():
    """20,000 sets of 3 independent normal blocks (as many columns of one call): the true mean
    0 lies in 95 % of the intervals (binomial standard error 0.15 %); t of 3 degrees of
    freedom instead of 2 would cover about 91 %."""
    blocks = np.random.default_rng(11).normal(size=(3, 20_000))
    mean, half = block_mean_ci95(blocks)
    coverage = float(np.mean(np.abs(mean) <= half))
    assert abs(coverage - 0.95) < 0.006, coverage
