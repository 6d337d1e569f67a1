"""The exported controllers on a Cortex-M4 (QEMU mps2-an386): cross-compiled with the strict
flags, fed 2,000 recorded states and references of a host flight (fig6, around the CoG step),
compared with the host build of the same harness and code; cost within the goal.

Tolerance (quadcog.embedded.target.TARGET_RTOL): both builds use IEEE-754 arithmetic in the
same order (-std=c99 turns off FMA contraction), so the differences come from the math
libraries (newlib vs glibc sinf, cosf, atan2f: each within a couple of ulps, not bit-equal). The
law amplifies those by its conditioning (4x4 solve, inverse of the inertia about the estimated
CoG), and c accumulates them over the steps: measured at most 9e-6 of each output's largest
magnitude in float32 and 2e-14 in double. The bounds are 1e-4 (float32, about 800 ulps) and
1e-11 (double), an order of magnitude above what is measured.
"""
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
import tempfile

from conftest import background_job, background_result
import numpy as np
import pytest

from quadcog.controllers import make_controller
from quadcog.embedded import make_embedded as build
from quadcog.embedded import target

pytestmark = [pytest.mark.slow, pytest.mark.skipif(
    bool(target.missing_tools()),
    reason=f"needs {target.DEBIAN_PACKAGES} (CI installs them: .ci/run)")]


def _run_one(name, precision, nc, data):
    """Build one module for the target and the host, run both: one entry of ``runs``."""
    module = build.embedded_dir() / precision
    elf = target.build_target(module, name, nc, data, data)
    exe = target.build_host_harness(module, name, nc, data, data)
    return dict(nc=nc, target=target.parse_output(target.run_qemu(elf), precision, nc),
                host=target.parse_output(target.run_host(exe), precision, nc),
                size=target.object_cost(data / f"quadcog_{name}.o"))


def _start_runs():
    """In the main thread: the recording (a simulation) and the state sizes; returns the
    builds and runs, which are subprocesses and files only (conftest.background_job starts
    them at collection). Nothing to do without the tools: the module is skipped."""
    if target.missing_tools():
        return lambda: None
    x, ref, dt = build.recording()
    assert len(x) >= 2000
    nc = {name: make_controller(name).n_state for name in build.CONTROLLERS}

    def work():
        """Two at a time: QEMU counts instructions with -icount, so the costs do not depend
        on the load."""
        jobs = {}
        with tempfile.TemporaryDirectory() as tmp, ThreadPoolExecutor(max_workers=2) as pool:
            for precision in ("float32", "double"):
                data = Path(tmp) / precision
                data.mkdir()
                target.write_data(data / "harness_data.h", x, ref, dt, precision)
                for name in build.CONTROLLERS:
                    jobs[name, precision] = pool.submit(_run_one, name, precision, nc[name],
                                                        data)
            return {key: job.result() for key, job in jobs.items()}
    return work


background_job("embedded: target and host runs", __file__, "runs", _start_runs)


@pytest.fixture(scope="module")
def runs():
    """Each committed module, run once on the target and once on the host."""
    return background_result("embedded: target and host runs")


@pytest.mark.parametrize("precision", ["float32", "double"])
@pytest.mark.parametrize("name", build.CONTROLLERS)
def test_target_matches_host_build(runs, name, precision):
    r = runs[name, precision]
    (U, c, info), (U_h, c_h, _) = r["target"], r["host"]
    assert U.shape == U_h.shape == (2000, 4) and np.isfinite(U).all()
    rtol = target.target_rtol(name, precision)
    assert target.relative_difference(U, U_h) <= rtol
    assert target.relative_difference(c, c_h, per_column=False) <= rtol
    if r["nc"]:
        assert np.max(np.abs(c_h)) > 0.01        # the estimate moved: the update ran on target
    # the calibration loop of known length is counted exactly by the icount timer
    assert info["calibration_counted"] == info["calibration_true"] == 200000


def test_cost(runs):
    """No data or bss (no globals), measured stack at least the static frame, and the float32
    adaptive step within the 10,000-instruction goal; float32 far cheaper than double."""
    for (name, precision), r in runs.items():
        info = r["target"][2]
        assert r["size"]["data"] == r["size"]["bss"] == 0, (name, precision)
        assert info["stack_bytes"] >= r["size"]["stack"] > 0, (name, precision)
        assert 0 < info["instructions_mean"] <= info["instructions_max"]
    assert runs["adaptive", "float32"]["target"][2]["instructions_max"] <= 10000
    assert (runs["adaptive", "double"]["target"][2]["instructions_mean"]
            > 5 * runs["adaptive", "float32"]["target"][2]["instructions_mean"])


def test_published_costs_are_these_runs(runs):
    """The cost table of docs/tour/flight-controller.md (docs/measured/embedded.json, copied
    from `make embedded` by bench/publish.py) is what these runs measure: sizes, stack and
    the instruction counts, which QEMU's -icount makes exact on any host."""
    import json
    published = json.loads((Path(__file__).resolve().parent.parent / "docs" / "measured"
                            / "embedded.json").read_text())
    seen = set()
    for row in published["rows"]:
        r = runs[row["controller"], row["precision"]]
        size, info = r["size"], r["target"][2]
        measured = dict(flash=size["text"] + size["data"], ram=size["data"] + size["bss"],
                        stack_static=size["stack"], stack_measured=info["stack_bytes"],
                        instructions_mean=info["instructions_mean"],
                        instructions_max=info["instructions_max"])
        assert {k: row[k] for k in measured} == measured, (
            f"{row['controller']} {row['precision']}: the published costs are not this run's; "
            "run make embedded, then python bench/publish.py embedded")
        seen.add((row["controller"], row["precision"]))
    assert seen == set(runs)
