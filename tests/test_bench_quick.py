"""bench/run.py's smallest configuration runs (no timing is asserted: the machine is shared):
the machine rows, the FMA roofline, the scale table at 10 flights, and peers that are not
installed reported as absent, never with a number."""
import importlib.util
from pathlib import Path
import shutil
import sys

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture
def run(monkeypatch):
    monkeypatch.setattr(sys, "path", list(sys.path))          # run.py inserts the root
    spec = importlib.util.spec_from_file_location("bench_run_quick", ROOT / "bench" / "run.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    monkeypatch.setattr(mod, "rows", [])
    return mod


@pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")
def test_smallest_configuration(run):
    from bench.machine import machine
    m = machine()
    assert m["isa"] in ("avx512", "avx2", "sse2", "portable") and m["compiler"] != "none"
    assert "-ffp-contract=off" in m["flags"]
    roof = run.bench_vector_limits(200.0, seconds=0.05)
    assert roof["flops"] > 0
    out = run.bench_scale((10, 20), duration=0.05)
    assert [n for n, *_ in out] == [10, 20]
    names = [r[0] for r in run.rows]
    assert any(n.startswith("roofline:") for n in names)
    assert "scale: 10 flights x 0.05 s" in names
    ratio = next(r for r in run.rows if r[0] == "vector step: operation rate (1 thread, CPU time)")
    assert ratio[3].endswith("x roofline")


def test_absent_peers_are_reported_absent(run, monkeypatch):
    for name in ("crazyflow", "rotorpy", "jax", "torch", "numba"):
        monkeypatch.setitem(sys.modules, name, None)          # import raises ImportError
    run.bench_crazyflow(10, 5, 1.0)
    run.bench_rotorpy_batched(10, 0.01, 1.0)
    run.bench_rotorpy(0.015)
    run.bench_numba(10, 1.0)
    assert [r[1] for r in run.rows] == ["absent"] * 4
    assert all("not installed" in r[5] for r in run.rows)


@pytest.mark.parametrize("script", sorted(p.name for p in (ROOT / "bench").glob("*.py")))
def test_every_bench_script_imports(script, monkeypatch):
    """An import that a refactoring broke (bench/precision.py imported a name the sweeps no
    longer had) fails here, not only when someone regenerates the docs' tables."""
    monkeypatch.setattr(sys, "path", list(sys.path))
    spec = importlib.util.spec_from_file_location(f"bench_{script[:-3]}", ROOT / "bench" / script)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)          # module level only: main() is not called


def test_a_failed_aqb_rerun_keeps_the_earlier_result(tmp_path):
    """bench/aqb_suite.py --controllers X reruns X: a run that fails (here a controller no
    registry has; without AdaptiveQuadBench installed, at once) must leave X's earlier
    result and no partial file; it deleted it before the run."""
    import json
    import subprocess
    earlier = {"controller": "qc-none", "trials": 1, "error": "an earlier result"}
    kept = tmp_path / "qc-none.json"
    kept.write_text(json.dumps(earlier))
    done = subprocess.run([sys.executable, str(ROOT / "bench" / "aqb_suite.py"), "--trials",
                           "1", "--controllers", "qc-none", "--out", str(tmp_path)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert json.loads(kept.read_text()) == earlier
    assert not list(tmp_path.glob("*.part")) and not list(tmp_path.glob(".*"))
    assert "qc-none failed; its earlier result is kept" in done.stdout
    table = json.loads((tmp_path / "aqb.json").read_text())["table"]
    assert "| qc-none | 1 | failed to run" in table
