"""`quadcog analyze` end to end, on a small failure map (5 x 5 offsets, 10 s flights): every
file is written and the numbers in analysis.json and the failure-map grid say what the analysis
found (the PD poles, zero dynamics unchanged by r_G, an adaptive law whose Lyapunov residual is
round-off, PD failing with a standing error at every admissible offset off the centre)."""
import json
from pathlib import Path
import subprocess
import sys

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def analysis(tmp_path_factory):
    out = tmp_path_factory.mktemp("analysis")
    res = subprocess.run([sys.executable, "-m", "quadcog", "analyze", "--out", str(out),
                          "--grid", "5", "--duration", "10"], cwd=ROOT, capture_output=True,
                         text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    return out, json.loads((out / "analysis.json").read_text())


def test_every_file_written(analysis):
    out, _ = analysis
    for name in ("analysis.md", "analysis.json", "failure_map.json", "failure_map.npz"):
        assert (out / name).stat().st_size > 0, name
    for name in ("pd_sigma.png", "zero_dynamics.png", "lyapunov.png", "failure_map.png"):
        assert (out / name).stat().st_size > 10_000, name
    assert "## 4. Failure map" in (out / "analysis.md").read_text()


def test_numbers_of_the_analysis(analysis):
    _, a = analysis
    pd = a["pd_design"]
    chosen = np.sort(np.concatenate([np.asarray(v, float) for v in pd["poles"].values()]))
    assert np.allclose(np.sort(np.real(pd["eigenvalues"])), chosen, atol=1e-8)
    assert a["zero_dynamics"]["unchanged_with_r_G"] is True
    assert a["zero_dynamics"]["max_eig_diff_over_r_G"] < 1e-12
    assert a["adaptive"]["design"]["lyapunov_residual_relative"] < 1e-12


def test_failure_map_grid(analysis):
    """Offsets {-17, -8.5, 0, 8.5, 17} cm: only the centre and the four at 8.5 cm on an axis are
    admissible (|r_G| < 10.15 cm); the others are not simulated. PD holds a standing error of
    about 15.6 m per metre of offset, so it fails (> 0.5 m) at all four 8.5 cm offsets."""
    out, _ = analysis
    fm = np.load(out / "failure_map.npz")
    xs, adm = fm["x_G"], fm["admissible"]
    assert np.allclose(xs, [-0.17, -0.085, 0.0, 0.085, 0.17])
    radius = np.hypot(*np.meshgrid(xs, xs))
    assert np.array_equal(adm, radius < 0.1)
    for name in ("pd", "fl", "adaptive"):
        tail = fm[f"{name}_tail_rms"]
        assert np.all(np.isnan(tail[~adm])) and not fm[f"{name}_failed"][~adm].any(), name
        assert tail[2, 2] < 1e-6, name                         # r_G = 0: nothing happens
    on_axis = adm & (radius > 0)
    assert fm["pd_failed"][on_axis].all()
    assert (fm["pd_tail_rms"][on_axis] > 1.0).all()        # 15.6 m/m * 0.085 m = 1.3 m
