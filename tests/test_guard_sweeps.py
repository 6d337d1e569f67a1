"""Guard of a sweep's summary statistics (quadcog.sweeps.summary.summarize) on a table whose
answers are counted by hand: the tail RMS quantiles of the flights that did not diverge by
the textbook rule (linear interpolation between order statistics, position p (n - 1)), the
survival among the admissible flights only. (bench/mutations.py: sweep_quantile_as_percentile.)"""
from types import SimpleNamespace

import numpy as np
import pytest

from quadcog.sweeps.summary import summarize, summary_markdown


def test_summary_counts_and_quantiles_by_hand():
    # 101 admissible flights that did not diverge, tail RMS 1 .. 101 mm; 3 that diverged; 2
    # whose CoG is not admissible (flown anyway, tail 5 m): in a shuffled order
    tail = np.r_[np.arange(1, 102) * 1e-3, [np.inf] * 3, [5.0, 5.0]]
    diverged = np.r_[[False] * 101, [True] * 3, [False] * 2]
    admissible = np.r_[[True] * 104, [False] * 2]
    order = np.random.default_rng(3).permutation(tail.size)
    threshold = 0.05
    columns = {"controller": np.array(["fl"] * tail.size, dtype=object)[order],
               "admissible": admissible[order], "diverged": diverged[order],
               "rms_position_error_tail": tail[order],
               "failed": (diverged | ~admissible | (tail > threshold))[order]}
    sweep = SimpleNamespace(name="hand", source="<test>", mode="grid", threshold=threshold)
    s = summarize(sweep, columns)
    assert (s["flights"], s["admissible"]) == (106, 104)
    c = s["controllers"]["fl"]
    assert (c["flights"], c["admissible"], c["diverged"], c["survived"]) == (106, 104, 3, 50)
    assert c["survival"] == pytest.approx(50 / 104, rel=1e-15)
    # order statistics x_1 .. x_101 = 1 .. 101 mm: p (n - 1) = 50, 90, 99 land on x_51, x_91,
    # x_100 exactly
    assert c["tail_rms_p50"] == pytest.approx(0.051, rel=1e-12)
    assert c["tail_rms_p90"] == pytest.approx(0.091, rel=1e-12)
    assert c["tail_rms_p99"] == pytest.approx(0.100, rel=1e-12)
    assert c["tail_rms_max"] == pytest.approx(0.101, rel=1e-12)
    text = summary_markdown(s)
    assert "| fl | 104 | 50 | 48.1 % | 3 | 0.051 | 0.091 | 0.1 | 0.101 |" in text
