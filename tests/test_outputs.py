"""Run outputs: strict JSON, CSV without overflow and in constant memory, all files or none,
plot titles taken literally, Ctrl-C -> one line and exit status 130."""
import csv
import io
import json
import os
from pathlib import Path
import signal
import sys
import tracemalloc

from conftest import interrupt_mid_flight
import numpy as np
import pytest

from quadcog.files import RunFiles, plot_text, strict_json, write_csv
from quadcog.scenarios.scenario import load_scenario, output_files, parse, write_outputs
import quadcog.viz.plots

OUTPUT_FILES = output_files()

ROOT = Path(__file__).resolve().parent.parent


def _no_constants(name):
    raise AssertionError(f"not strict JSON: {name}")


def test_strict_json_has_null_for_non_numbers():
    text = strict_json({"a": float("nan"), "b": [np.float64("inf"), -np.inf, 1.5],
                        "c": np.int64(3), "d": np.bool_(True), "e": np.array([0.25, np.nan])})
    data = json.loads(text, parse_constant=_no_constants)
    assert data == {"a": None, "b": [None, None, 1.5], "c": 3, "d": True, "e": [0.25, None]}


def test_csv_values_round_trip_without_overflow():
    """np.round(-1.22e301, 10) is -inf (it multiplies by 1e10): the CSV must hold the number."""
    values = np.array([-1.22e301, 1.7e308, 0.12345678901234, -3.000000000049, 5e-324, 0.0])
    fh = io.StringIO()
    write_csv(fh, ["t", "v"], [np.arange(values.size), values], values.size)
    rows = list(csv.reader(io.StringIO(fh.getvalue())))
    assert rows[0] == ["t", "v"]
    got = [float(r[1]) for r in rows[1:]]
    expected = [-1.22e301, 1.7e308, round(0.12345678901234, 10), round(-3.000000000049, 10),
                0.0, 0.0]
    assert got == expected and all(np.isfinite(got))


def test_csv_memory_does_not_grow_with_the_run():
    class Sink:
        def write(self, s):
            return len(s)

    peaks = []
    for n in (1_000, 10_000):
        cols = [np.linspace(0, 1, n), np.ones((n, 12)), np.zeros((n, 4))]
        tracemalloc.start()
        write_csv(Sink(), ["c"] * 17, cols, n)
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    # all at once (the old way) would hold 17 Python floats per row: ~4 MB at 10 000 rows
    assert peaks[1] < 1.5 * peaks[0] and peaks[1] < 1.5e6, peaks


@pytest.fixture(scope="module")
def short_run():
    s = load_scenario("fig7")
    s.duration = 0.5
    return s, s.run()


def _snapshot(folder):
    return {p.name: p.read_bytes() for p in Path(folder).iterdir()}


def test_outputs_all_or_none(tmp_path, short_run, monkeypatch):
    scenario, result = short_run
    for name in OUTPUT_FILES:                       # a previous run's files
        (tmp_path / name).write_text(f"previous {name}")
    before = _snapshot(tmp_path)
    for failure in (KeyboardInterrupt, RuntimeError):
        def plot(*args, **kwargs):
            raise failure("while plotting")
        monkeypatch.setattr(quadcog.viz.plots, "plot_flight", plot)
        with pytest.raises(failure):
            write_outputs(result, scenario, tmp_path)
        assert _snapshot(tmp_path) == before        # nothing new, nothing left over
    monkeypatch.undo()
    write_outputs(result, scenario, tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(OUTPUT_FILES)
    metrics = json.loads((tmp_path / "metrics.json").read_text(), parse_constant=_no_constants)
    assert metrics["name"] == "fig7" and metrics["simulated_until"] == pytest.approx(0.5)
    rows = list(csv.reader((tmp_path / "trajectory.csv").open()))
    assert len(rows) == len(result.t) + 1 and float(rows[-1][0]) == pytest.approx(0.5)


def test_mathtext_in_the_scenario_name(tmp_path):
    data = {"name": "a $\\alpha_{$ b", "controller": "fl", "duration": 0.2}
    scenario = parse(data, "math.toml")
    write_outputs(scenario.run(), scenario, tmp_path)
    assert (tmp_path / "flight.png").stat().st_size > 1000
    assert plot_text("a $x$") == r"a \$x\$"


def test_run_files_commit_together(tmp_path):
    with RunFiles(tmp_path / "new") as files:
        files.path("a.txt").write_text("a")
        assert not (tmp_path / "new" / "a.txt").exists()
    assert (tmp_path / "new" / "a.txt").read_text() == "a"


def test_ctrl_c_gives_one_line_and_status_130(tmp_path):
    scenario = tmp_path / "long.toml"
    scenario.write_text('name = "long"\ncontroller = "adaptive"\nduration = 600.0\n'
                        '[trajectory]\nkind = "circle"\n')
    out = tmp_path / "out"
    out.mkdir()
    for name in OUTPUT_FILES:
        (out / name).write_text(f"previous {name}")
    status, stderr = interrupt_mid_flight(
        [sys.executable, "-m", "quadcog", "run", str(scenario), "--out", str(out)],
        signal.SIGINT, group=True, env=dict(os.environ, PYTHONPATH=str(ROOT)),
        start_new_session=True)
    assert status == 130, stderr
    # the bar redraws with \r; what is left of each line after the last one is what shows
    lines = [line.rsplit("\r", 1)[-1] for line in stderr.splitlines()]
    lines = [line for line in lines if line.strip() and "[" not in line]
    assert lines == ["quadcog: interrupted"], stderr           # (the progress bar aside)
    assert "Traceback" not in stderr
    assert {p.name: p.read_text() for p in out.iterdir()} == {
        name: f"previous {name}" for name in OUTPUT_FILES}
