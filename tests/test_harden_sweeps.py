"""Issue 21, sweeps: a resumed sweep verifies every chunk it finds (which sweep, which rows,
the row count, a checksum) and flies again what does not verify; one writer per folder; keys,
sizes, back-end arguments and scheduler addresses refused before any work.

The oracle of every resume test is an uninterrupted run of the same sweep into a fresh folder:
the resumed table must equal it bit for bit."""
import json
import os
from pathlib import Path
import socket
import subprocess
import sys
import threading
import time

from conftest import small_sweep
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
import numpy as np
import pytest

from quadcog import sweep
from quadcog.errors import QuadcogError, SchedulerError, SizeError, SweepError, SweepLockedError
from quadcog.sweeps.integrity import LOCK_NAME, META_KEY, SweepLock, content_checksum
from quadcog.sweeps.scheduler import parse_address, probe_scheduler
from quadcog.sweeps.spec import MAX_FLIGHTS, from_dict

pa = pytest.importorskip("pyarrow")
import pyarrow.parquet as pq  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent

TINY = """
name = "tiny"
scenario = "fig6"
chunk = 2
[set]
duration = 0.3
controller = "fl"
controller_params = {{}}
"cog[0].t" = 0.1
[[dimension]]
key = "cog[0].r[0]"
values = {values}
"""


def _write(folder, values=(0.0, 0.01, 0.02, 0.03, 0.04, 0.05), name="tiny.toml"):
    path = folder / name
    path.write_text(TINY.format(values=json.dumps(list(values))))
    return path


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    folder = tmp_path_factory.mktemp("harden-sweep")
    path = _write(folder)
    ref = folder / "reference"
    sweep(path, ref, progress=False, plots=False)
    return path, ref, (ref / "results.csv").read_bytes()


def _same_table(out, ref):
    a, b = (pq.read_table(Path(d) / "results.parquet") for d in (out, ref))
    assert a.column_names == b.column_names
    for name in a.column_names:
        x, y = (t.column(name).to_numpy(zero_copy_only=False) for t in (a, b))
        if x.dtype.kind in "fib":
            assert x.tobytes() == y.tobytes(), name
        else:
            assert x.tolist() == y.tolist(), name
    assert (Path(out) / "results.csv").read_bytes() == (Path(ref) / "results.csv").read_bytes()


def _copy_folder(src, dst):
    import shutil
    shutil.copytree(src, dst)
    for p in [dst / n for n in ("results.parquet", "results.csv", "summary.json",
                                "summary.md")]:
        p.unlink(missing_ok=True)
    return dst


def _table(path):
    return pq.read_table(path)


def _rewrite(path, table, meta):
    pq.write_table(table.replace_schema_metadata(meta), path)


def _damage_other_chunk(chunks):
    import shutil
    shutil.copy(chunks / "chunk-00000.parquet", chunks / "chunk-00001.parquet")


def _damage_empty(chunks):
    t = _table(chunks / "chunk-00001.parquet")
    _rewrite(chunks / "chunk-00001.parquet", t.slice(0, 0), t.schema.metadata)


def _damage_row_twice(chunks):
    t = _table(chunks / "chunk-00001.parquet")
    _rewrite(chunks / "chunk-00001.parquet", pa.concat_tables([t.slice(0, 1), t.slice(0, 1)]),
             t.schema.metadata)


def _damage_cell(chunks):
    t = _table(chunks / "chunk-00001.parquet")
    k = t.column_names.index("rms_position_error")
    col = pa.array(t.column(k).to_numpy() * 2.0)
    _rewrite(chunks / "chunk-00001.parquet", t.set_column(k, "rms_position_error", col),
             t.schema.metadata)


def _damage_no_record(chunks):
    t = _table(chunks / "chunk-00001.parquet")
    meta = dict(t.schema.metadata)
    del meta[META_KEY]
    _rewrite(chunks / "chunk-00001.parquet", t, meta)


def _damage_bytes(chunks):
    p = chunks / "chunk-00001.parquet"
    p.write_bytes(p.read_bytes()[: 100])


def _damage_foreign(chunks):
    t = _table(chunks / "chunk-00001.parquet")
    meta = dict(t.schema.metadata)
    record = json.loads(meta[META_KEY])
    record["fingerprint"] = "0" * 64
    meta[META_KEY] = json.dumps(record).encode()
    _rewrite(chunks / "chunk-00001.parquet", t, meta)


@pytest.mark.parametrize("damage", [_damage_other_chunk, _damage_empty, _damage_row_twice,
                                    _damage_cell, _damage_no_record, _damage_bytes,
                                    _damage_foreign])
def test_resume_flies_again_what_does_not_verify(tiny, tmp_path, damage, capsys):
    path, ref, _ = tiny
    out = _copy_folder(ref, tmp_path / "out")
    damage(out / "chunks")
    result = sweep(path, out, progress=True, plots=False)
    assert [c for c, _ in result.rejected] == [1]
    assert "chunk-00001.parquet does not verify" in capsys.readouterr().err
    assert result.flown == 2                     # only the rejected chunk's two flights
    _same_table(out, ref)


def test_resume_of_intact_chunks_flies_nothing(tiny, tmp_path):
    path, ref, _ = tiny
    out = _copy_folder(ref, tmp_path / "out")
    result = sweep(path, out, progress=False, plots=False)
    assert result.flown == 0 and result.rejected == []
    _same_table(out, ref)


def test_checksum_changes_with_any_cell_and_not_otherwise(tiny):
    t = _table(tiny[1] / "chunks" / "chunk-00000.parquet")
    assert content_checksum(t) == content_checksum(pa.table(t.to_pydict()))
    col = t.column("final_position_error").to_numpy().copy()
    col[0] = np.nextafter(col[0], np.inf)          # one ulp
    k = t.column_names.index("final_position_error")
    assert content_checksum(t.set_column(k, "final_position_error", pa.array(col))) != \
        content_checksum(t)


def test_sweep_json_of_another_sweep_is_refused(tiny, tmp_path):
    path, ref, _ = tiny
    out = _copy_folder(ref, tmp_path / "out")
    other = _write(tmp_path, values=(0.0, 0.02), name="other.toml")
    with pytest.raises(SweepError, match="different sweep"):
        sweep(other, out, progress=False, plots=False)
    (out / "sweep.json").write_text("{not json")
    with pytest.raises(SweepError, match="different sweep"):
        sweep(path, out, progress=False, plots=False)


def test_a_live_lock_refuses_and_a_stale_one_is_taken_over(tiny, tmp_path, capsys):
    path, ref, _ = tiny
    out = _copy_folder(ref, tmp_path / "out")
    live = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        (out / LOCK_NAME).write_text(json.dumps({"pid": live.pid, "start": None,
                                                 "host": socket.gethostname()}))
        with pytest.raises(SweepLockedError, match=f"pid {live.pid}"):
            sweep(path, out, progress=False, plots=False)
    finally:
        live.kill()
        live.wait()
    (out / LOCK_NAME).write_text(json.dumps({"pid": live.pid, "start": None,
                                             "host": socket.gethostname()}))
    result = sweep(path, out, progress=True, plots=False)      # the pid is gone: stale
    assert "stale lock" in capsys.readouterr().err
    assert result.flown == 0 and not (out / LOCK_NAME).exists()


def test_lock_is_exclusive_and_released(tmp_path):
    with SweepLock(tmp_path):
        assert json.loads((tmp_path / LOCK_NAME).read_text())["pid"] == os.getpid()
        probe = subprocess.run(
            [sys.executable, "-c", "import sys; from quadcog.sweeps.integrity import SweepLock;"
             f"SweepLock({str(tmp_path)!r}).__enter__()"], capture_output=True, text=True,
            cwd=ROOT)
        assert probe.returncode != 0 and "SweepLockedError" in probe.stderr
    assert not (tmp_path / LOCK_NAME).exists()


def test_two_cli_sweeps_into_one_folder_the_second_refuses(tiny, tmp_path):
    path, _, _ = tiny
    out = tmp_path / "busy"
    out.mkdir()
    with SweepLock(out):        # a sweep of this process is writing there
        res = subprocess.run([sys.executable, "-m", "quadcog", "sweep", str(path), "--out",
                              str(out)], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert res.returncode == 2, res.stderr
    assert "another sweep (pid" in res.stderr and "Traceback" not in res.stderr
    assert not (out / "results.csv").exists()




@pytest.mark.parametrize("dims", [
    [{"key": "cog[0].r", "values": [[0.0, 0, 0]]}, {"key": "cog[0].r[0]", "values": [0.0]}],
    [{"key": "vehicle", "values": ["hummingbird"]}, {"key": "vehicle.m", "values": [0.7]}],
    [{"key": "vehicle.m", "values": [0.7]}, {"key": "vehicle", "values": ["hummingbird"]}],
])
def test_overlapping_keys_are_refused(dims):
    with pytest.raises(SweepError, match="overlaps"):
        sweep(small_sweep(dimension=dims), progress=False, plots=False)


@pytest.mark.parametrize("chunk", [0, -1, 1.5, True, "64", [2], {"n": 2}, None])
def test_chunk_of_an_odd_kind_is_refused(chunk):
    with pytest.raises(SweepError, match="chunk"):
        sweep(small_sweep(chunk=chunk), progress=False, plots=False)


@pytest.mark.parametrize("kwargs, error, text", [
    ({"workers": True}, SweepError, "workers"),
    ({"workers": 0}, SweepError, "workers"),
    ({"workers": 2.0}, SweepError, "workers"),
    ({"workers": 10 ** 30}, SizeError, "workers"),
    ({"scheduler": []}, SchedulerError, "scheduler"),
    ({"scheduler": 5}, SchedulerError, "scheduler"),
    ({"scheduler": "tcp://"}, SchedulerError, "no host"),
    ({"out": 5}, SweepError, "out"),
])
def test_backend_arguments_are_refused_before_work(kwargs, error, text, tmp_path):
    t0 = time.perf_counter()
    with pytest.raises(error, match=text):
        sweep(small_sweep(), progress=False, plots=False, **kwargs)
    assert time.perf_counter() - t0 < 5


@pytest.mark.parametrize("dims, samples, size", [
    ([{"key": "cog[0].ramp", "range": {"start": 0, "stop": 0.01, "num": 10 ** 12}}], None,
     "1e+12"),
    ([{"key": "cog[0].ramp", "range": {"start": 0.1, "stop": 1, "step": 1e-12}}], None,
     "9e+11"),
    ([{"key": "cog[0].ramp", "uniform": {"low": 0.1, "high": 1}}], 10 ** 12, "1e+12"),
    ([{"key": "cog[0].ramp", "uniform": {"low": 0.1, "high": 1, "n": 10 ** 12}}], None,
     "1e+12"),
    ([{"key": k, "range": {"start": 0, "stop": 0.01, "num": 10 ** 4}}
      for k in ("cog[0].r[0]", "cog[0].r[1]", "cog[0].r[2]")], None, "1e+12"),
    ([{"key": k, "range": {"start": 0, "stop": 0.01, "num": 3000}}
      for k in ("cog[0].r[0]", "cog[0].r[1]")], None, "9e+06"),
])
def test_sizes_are_refused_before_any_allocation(dims, samples, size):
    extra = {"dimension": dims}
    if samples:
        extra.update(mode="monte-carlo", samples=samples)
    t0 = time.perf_counter()
    with pytest.raises(SizeError, match=r"too large|at most") as e:
        sweep(small_sweep(**extra), progress=False, plots=False)
    assert size in str(e.value)
    assert time.perf_counter() - t0 < 5


@pytest.mark.parametrize("value", [{"a": 1}, [1, "a"], [[0.0, 0], 0.1]])
def test_sweep_values_of_a_table_or_mixed_kinds_are_refused(value):
    dims = [{"key": "cog[0].ramp", "values": value if isinstance(value, list) else [value]}]
    with pytest.raises(SweepError, match="values"):
        sweep(small_sweep(dimension=dims), progress=False, plots=False)


def test_a_rejected_sweep_file_creates_no_out_folder(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('scenario = "fig6"\nchunk = "odd"\n[[dimension]]\nkey = "duration"\n'
                   'values = [1.0]\n')
    out = tmp_path / "never"
    res = subprocess.run([sys.executable, "-m", "quadcog", "sweep", str(bad), "--out", str(out)],
                         capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert res.returncode == 2 and "chunk" in res.stderr and "Traceback" not in res.stderr
    assert not out.exists()


@pytest.mark.parametrize("address, text", [
    ("tcp://", "no host"), ("tcp://127.0.0.1", "no port"), ("http://127.0.0.1:8786", "http"),
    ("tls://127.0.0.1:8786", "certificates"), ("127.0.0.1:99999", "out of range"),
    ("tcp://a b:1", "not an address"), ("", "no host"),
])
def test_scheduler_addresses_of_the_wrong_form(address, text):
    with pytest.raises(SchedulerError, match=text):
        parse_address(address)


def _server(behaviour):
    """A TCP server on 127.0.0.1 (only) that accepts once and then does ``behaviour``."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(1)
    stop = threading.Event()

    def serve():
        srv.settimeout(5)
        try:
            conn, _ = srv.accept()
        except OSError:
            return
        with conn:
            behaviour(conn)
            stop.wait(5)
    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    return srv, stop, f"tcp://127.0.0.1:{srv.getsockname()[1]}"


def test_a_silent_scheduler_is_an_error_after_the_stated_timeout():
    srv, stop, address = _server(lambda conn: None)
    try:
        t0 = time.perf_counter()
        with pytest.raises(SchedulerError, match="no Dask handshake within 0.5 s"):
            probe_scheduler(address, timeout=0.5)
        assert time.perf_counter() - t0 < 3
    finally:
        stop.set()
        srv.close()


def test_a_scheduler_sending_garbage_is_refused_without_allocating_it():
    srv, stop, address = _server(lambda conn: conn.sendall(b"\xff" * 8 + b"junk"))
    try:
        with pytest.raises(SchedulerError, match="not a Dask scheduler"):
            probe_scheduler(address, timeout=2)
    finally:
        stop.set()
        srv.close()


def test_a_real_dask_scheduler_passes_the_probe():
    distributed = pytest.importorskip("distributed")
    import asyncio

    async def run():
        async with distributed.Scheduler(host="127.0.0.1", port=0, dashboard_address=None) as s:
            return await asyncio.get_running_loop().run_in_executor(
                None, probe_scheduler, s.address, 5.0)
    assert asyncio.run(run()).startswith("tcp://127.0.0.1:")


SENSED = TINY.replace('controller = "fl"', 'controller = "fl"\nsensing = {{noise = true, '
                                             'seed = 3}}')


def test_sensing_on_results_do_not_depend_on_workers_or_interruption(tmp_path, monkeypatch):
    path = tmp_path / "sensed.toml"
    path.write_text(SENSED.format(values=json.dumps([0.0, 0.01, 0.02, 0.03])))
    pooled = sweep(path, tmp_path / "pooled", progress=False, plots=False)   # 2 processes
    monkeypatch.setattr(os, "cpu_count", lambda: 1)                          # this process
    alone = sweep(path, None, progress=False, plots=False)
    out = tmp_path / "pooled"
    (out / "chunks" / "chunk-00000.parquet").unlink()                        # "interrupted"
    _damage_cell(out / "chunks")
    resumed = sweep(path, out, progress=False, plots=False)
    assert resumed.flown == 4
    for name, a in alone.columns.items():
        for other in (pooled, resumed):
            b = other.columns[name]
            assert a.dtype == b.dtype and (a.tobytes() == b.tobytes() if a.dtype.kind in "fib"
                                           else a.tolist() == b.tolist()), name
    assert np.isfinite(alone.columns["rms_position_error"]).all()


def test_a_controller_that_cannot_be_designed_is_refused_before_any_flight(tmp_path):
    dims = [{"key": "controller_params.poles_psi", "values": [[-1.0, -2.0], [0.5, 0.5]]}]
    spec = small_sweep(dimension=dims)
    spec["set"]["controller"] = "adaptive"
    out = tmp_path / "never"
    with pytest.raises(SweepError, match=r"poles_psi.*cannot be designed"):
        sweep(spec, out, progress=False, plots=False)
    assert not out.exists()


# -- property: any hostile sweep dict is a typed error or a valid sweep, never a traceback --


HOSTILE = st.one_of(st.none(), st.booleans(), st.integers(-3, 3), st.just(10 ** 13),
                    st.just(10 ** 400), st.floats(), st.text(max_size=4),
                    st.lists(st.one_of(st.floats(), st.integers(), st.just(10 ** 400),
                                       st.text(max_size=2)), max_size=3),
                    st.dictionaries(st.sampled_from(["start", "stop", "num", "step", "low",
                                                     "high", "n", "radius", "plane", "x"]),
                                    st.one_of(st.floats(), st.integers(-2, 10 ** 13),
                                              st.text(max_size=2)), max_size=4))


@settings(derandomize=True, database=None, deadline=None, max_examples=50,
          suppress_health_check=list(HealthCheck))
@given(where=st.sampled_from(["chunk", "seed", "samples", "mode", "threshold", "inadmissible",
                              "name", "key", "values", "range", "uniform", "ball", "set"]),
       value=HOSTILE)
def test_property_hostile_sweep_fields(where, value):
    spec = small_sweep()
    dim = spec["dimension"][0]
    if where in ("key",):
        dim["key"] = value
    elif where in ("values", "range", "uniform", "ball"):
        del dim["values"]
        dim[where] = value
    elif where == "set":
        spec["set"] = value
    else:
        spec[where] = value
    t0 = time.perf_counter()
    try:
        s = from_dict(spec)
    except QuadcogError:
        assert time.perf_counter() - t0 < 5
        return
    assert 1 <= len(s.flights) <= MAX_FLIGHTS
