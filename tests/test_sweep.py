"""Sweeps: the same table locally, on a Dask LocalCluster, after a SIGKILL and resume, and with
a worker killed mid-sweep; metrics against the single-flight path; bad sweep files."""
import os
from pathlib import Path
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from quadcog import sweep
from quadcog.scenarios.scenario import parse
from quadcog.sweeps import SweepError, load_sweep

pa = pytest.importorskip("pyarrow")
import pyarrow.parquet as pq  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent

# 40 short flights in 20 chunks: two controllers, CoG steps sampled in the rotor plane, ramp
# times sampled (so a chunk holds several batch groups), seeded Monte-Carlo.
SMALL = """
name = "small"
scenario = "fig6"
mode = "monte-carlo"
samples = 40
seed = 7
chunk = 2

[set]
duration = 1.0
controller_params = {}
"cog[0].t" = 0.2

[[dimension]]
key = "controller"
values = ["fl", "adaptive"]

[[dimension]]
key = "cog[0].r"
ball = { radius = 0.08, plane = "xy" }

[[dimension]]
key = "cog[0].ramp"
values = [0.0, 0.3]
"""


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sweep")
    path = folder / "small.toml"
    path.write_text(SMALL)
    local = folder / "local"
    sweep(path, local, progress=False, plots=False)
    return path, pq.read_table(local / "results.parquet"), (local / "results.csv").read_bytes()


def _same(out, small):
    _, table, csv = small
    got = pq.read_table(Path(out) / "results.parquet")
    assert got.schema == table.schema
    for name in table.column_names:              # bit for bit (NaN included)
        a, b = (t.column(name).to_numpy(zero_copy_only=False) for t in (got, table))
        same = a.tobytes() == b.tobytes() if a.dtype.kind in "fib" else a.tolist() == b.tolist()
        assert same, f"column {name} differs"
    assert (Path(out) / "results.csv").read_bytes() == csv


def test_table_has_every_varied_value_and_metric(small):
    path, table, _ = small
    s = load_sweep(path)
    assert table.num_rows == 40 == len(s.flights)
    for c in ["flight", "controller", "cog[0].r[0]", "cog[0].r[1]", "cog[0].r[2]",
              "cog[0].ramp", "admissible", "rms_position_error", "max_position_error",
              "rms_position_error_tail", "final_position_error", "diverged", "diverged_at",
              "failed"]:
        assert c in table.column_names, c
    r = np.column_stack([table.column(f"cog[0].r[{i}]").to_numpy() for i in range(3)])
    assert np.all(np.linalg.norm(r, axis=1) <= 0.08) and np.all(r[:, 2] == 0)
    assert set(table.column("controller").to_pylist()) == {"fl", "adaptive"}
    # seeded: the same file gives the same flights; another seed others
    assert [f.values for f in load_sweep(path).flights] == [f.values for f in s.flights]
    assert [f.values for f in load_sweep(path, seed=8).flights] != [f.values for f in s.flights]


def test_metrics_equal_the_single_flight_path(small):
    path, table, _ = small
    s = load_sweep(path)
    rows = table.to_pylist()
    for k in (0, 1, 2, 3, 17):                    # both controllers, steps and ramps
        m = parse(s.flight_data(s.flights[k])).run().metrics
        for name in ("rms_position_error", "max_position_error", "rms_position_error_tail",
                     "final_position_error"):
            assert rows[k][name] == pytest.approx(getattr(m, name), rel=1e-9, abs=1e-12), \
                (k, name)
        assert rows[k]["diverged"] == m.diverged


def test_resume_after_sigkill_finishes_only_missing_chunks(small, tmp_path):
    path = small[0]
    out = tmp_path / "killed"
    proc = subprocess.Popen([sys.executable, "-m", "quadcog", "sweep", str(path), "--out",
                             str(out)], cwd=ROOT, start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    chunks = out / "chunks"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if chunks.is_dir() and any(chunks.glob("*.parquet")):
            break
        time.sleep(0.005)
    os.killpg(proc.pid, signal.SIGKILL)          # the CLI and its worker processes
    proc.wait()
    kept = {p.name: p.stat().st_mtime_ns for p in chunks.glob("*.parquet")}
    assert 0 < len(kept) < 20, f"{len(kept)} chunks were done at the kill"
    assert not (out / "results.parquet").exists()
    result = sweep(path, out, progress=False, plots=False)
    assert result.flown == 40 - 2 * len(kept)
    for name, mtime in kept.items():              # finished chunks were not redone
        assert (chunks / name).stat().st_mtime_ns == mtime
    _same(out, small)


@pytest.mark.slow
def test_local_cluster_with_a_worker_killed_gives_the_same_table(small, tmp_path):
    """--workers 2 (a Dask LocalCluster of 2 processes); one worker process is SIGKILLed as
    the first chunk comes back, while the other chunks run: Dask runs the lost chunks again."""
    psutil = pytest.importorskip("psutil")
    killed = []

    def kill_a_worker(n_new):
        if killed:
            return
        workers = [p for p in psutil.Process().children()
                   if "spawn_main" in " ".join(p.cmdline())]
        assert len(workers) == 2, [p.cmdline() for p in workers]
        workers[0].send_signal(signal.SIGKILL)
        killed.append(workers[0].pid)

    result = sweep(small[0], tmp_path / "dask", workers=2, progress=kill_a_worker,
                   plots=False)
    assert killed and result.flown == 40
    _same(tmp_path / "dask", small)


BAD = [
    ("unknown key", '[[dimension]]\nkey = "vehicle.mass"\nvalues = [0.6, 0.7]\n',
     "vehicle.mass", "unknown"),
    ("unknown top key", 'sample = 3\n[[dimension]]\nkey = "vehicle.m"\nvalues = [0.6]\n',
     "sample", "unknown"),
    ("empty range", '[[dimension]]\nkey = "vehicle.m"\nrange = { start = 0.7, stop = 0.6, '
     'step = 0.05 }\n', "vehicle.m", "empty range"),
    ("empty linspace", '[[dimension]]\nkey = "cog[0].ramp"\nrange = { start = 0, stop = 1, '
     'num = 0 }\n', "cog[0].ramp", "empty range"),
    ("inadmissible samples", '[[dimension]]\nkey = "cog[0].r"\nball = { radius = 0.15, n = 50 }\n',
     "cog[0].r", "inadmissible"),
    ("inadmissible grid", '[[dimension]]\nkey = "cog[0].r[0]"\nvalues = [0.0, 0.12]\n',
     "cog[0].r[0]", "inadmissible"),
    ("no such array entry", '[[dimension]]\nkey = "cog[3].ramp"\nvalues = [0.1]\n',
     "cog[3].ramp", "no entry 'cog[3]'"),
    ("wrong type", '[[dimension]]\nkey = "controller"\nvalues = ["pid"]\n', "controller",
     "expected one of"),
]


@pytest.mark.parametrize("what, text, key, reason", BAD, ids=[b[0] for b in BAD])
def test_bad_sweep_files_name_file_and_key(tmp_path, what, text, key, reason):
    path = tmp_path / "bad.toml"
    path.write_text('scenario = "fig6"\n' + text)
    with pytest.raises(SweepError) as e:
        load_sweep(path)
    msg = str(e.value)
    assert str(path) in msg and repr(key) in msg and reason in msg, msg


def test_cli_reports_a_bad_sweep_file(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('scenario = "fig6"\n' + BAD[0][1])
    r = subprocess.run([sys.executable, "-m", "quadcog", "sweep", str(path), "--out",
                        str(tmp_path / "o")], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 2 and "vehicle.mass" in r.stderr and "Traceback" not in r.stderr


def test_a_folder_of_another_sweep_is_refused(small, tmp_path):
    out = tmp_path / "o"
    s = load_sweep(small[0], samples=2, chunk=1)
    assert sweep(s, out, progress=False, plots=False).flown == 2
    assert sweep(s, out, progress=False, plots=False).flown == 0      # all there already
    with pytest.raises(SweepError, match="different sweep"):
        sweep(load_sweep(small[0], samples=3, chunk=1), out, progress=False, plots=False)


@pytest.mark.slow
def test_grid_is_every_combination_and_the_failure_map_ships():
    s = load_sweep("failure-map")
    assert len(s.flights) == 3 * 41 * 41
    # admissible: I_G keeps 1 % of I_O in every direction. In the rotor plane, with
    # Ixx = Iyy = I, I_O^-1/2 I_G I_O^-1/2 has eigenvalues 1, 1 - m |r|^2 / I and
    # 1 - m |r|^2 / Izz, so the CoG is admissible iff |r|^2 <= 0.99 I / m.
    r = np.array([[f.values["cog[0].r[0]"], f.values["cog[0].r[1]"]] for f in s.flights])
    adm = np.array([f.admissible for f in s.flights])
    assert np.array_equal(adm, np.hypot(r[:, 0], r[:, 1]) ** 2 <= 0.99 * 0.007 / 0.68)
