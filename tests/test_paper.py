"""The paper's claims as assertions (thresholds justified in README, "The paper's claims")."""
import json

import numpy as np
import pytest

from quadcog.studies.paper import run_paper

pytestmark = pytest.mark.slow      # the seven paper flights with their figures, once


@pytest.fixture(scope="module")
def summary(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    rows = run_paper(out, progress=False, beyond=False)   # beyond: tests/test_beyond.py
    return {r["scenario"]: r for r in rows}, out


def test_balanced_pd_and_fl_track(summary):
    rows, _ = summary
    for name in ("fig3a", "fig3b"):
        assert not rows[name]["diverged"]
        assert rows[name]["rms_position_error_tail"] < 0.05, rows[name]


def test_pd_and_fl_fail_after_a_cog_step(summary):
    rows, _ = summary
    for name in ("fig4", "fig5"):
        r = rows[name]
        assert r["diverged"] or r["rms_position_error_tail"] > 0.5, r
        # say plainly when the "failure" is a standing error rather than a crash
        assert (r["holds"] == "partly") == (not r["diverged"])


@pytest.mark.parametrize("name", ["fig6", "fig7", "fig8"])
def test_adaptive_recovers_and_estimates(summary, name):
    r = summary[0][name]
    assert not r["diverged"] and r["rms_position_error_tail"] < 0.10, r
    r_hat, r_G = np.array(r["r_hat_final"][:2]), np.array(r["r_G_final"][:2])
    assert np.all(np.abs(r_hat - r_G) <= np.maximum(0.1 * np.abs(r_G), 0.003)), (r_hat, r_G)


def test_outputs_written(summary):
    rows, out = summary
    data = json.loads((out / "summary.json").read_text())
    assert [d["figure"] for d in data] == ["Fig. 3(a)", "Fig. 3(b)", "Fig. 4", "Fig. 5",
                                           "Fig. 6", "Fig. 7", "Fig. 8"]
    md = (out / "summary.md").read_text()
    assert "partly" in md and "standing position error" in md
    assert (out / "cog_step_comparison.png").stat().st_size > 10_000
    for name in rows:
        assert (out / name / "flight.png").is_file() and (out / name / "trajectory.csv").is_file()
    tex = (out / "report_fragment.tex").read_text()
    assert "\\includegraphics" in tex and "paper/fig6/flight.png" in tex


def test_readme_table_matches_a_fresh_run(summary):
    """Each number of the README's paper table is the fresh run's within its printed rounding
    (tail RMS 0.1 mm, max 1 mm, divergence time 10 ms), and the verdicts are the same."""
    from pathlib import Path
    import re
    rows, out = summary
    readme = (Path(__file__).resolve().parent.parent / "docs" / "tour" / "paper.md").read_text()
    block = re.search(r"<!-- BEGIN paper -->\n(.*?)\n<!-- END paper -->", readme, re.S).group(1)
    fresh = {r["figure"]: r for r in rows.values()}
    lines = [l for l in block.splitlines()[2:]]
    assert len(lines) == len(fresh)
    for line in lines:
        figure, _, tail, peak, holds = [c.strip() for c in line.strip("|").split("|")]
        r = fresh[figure]
        assert holds.strip("*") == r["holds"], figure
        assert abs(float(peak) - r["max_position_error"]) <= 0.0005 + 1e-12, figure
        if r["diverged"]:
            t = float(re.match(r"diverged at ([0-9.]+) s", tail).group(1))
            assert abs(t - r["diverged_at"]) <= 0.005 + 1e-12, figure
        else:
            assert abs(float(tail) - r["rms_position_error_tail"]) <= 0.00005 + 1e-12, figure
