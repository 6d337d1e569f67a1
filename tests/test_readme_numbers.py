"""The published measured tables (docs pages, bench/publish.py PAGES) are copies of files that
commands wrote; the paper table is compared with a fresh run in tests/test_paper.py."""
import importlib.util
from pathlib import Path
import sys

ROOT = Path(__file__).resolve().parent.parent


def _publish():
    spec = importlib.util.spec_from_file_location("publish", ROOT / "bench" / "publish.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_bench_table_is_the_published_bench_run():
    pub = _publish()
    readme = pub.PAGES["bench"].read_text()
    assert pub.block(readme, "bench") == pub.table_of((ROOT / "bench" / "results.md").read_text())


def test_publish_replaces_only_its_block(tmp_path):
    pub = _publish()
    readme = tmp_path / "README.md"
    readme.write_text("intro\n<!-- BEGIN paper -->\n| old |\n<!-- END paper -->\nrest\n")
    src = tmp_path / "t.md"
    src.write_text("# title\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\ntext\n")
    pub.publish("paper", src, readme)
    assert readme.read_text() == ("intro\n<!-- BEGIN paper -->\n| a | b |\n|---|---|\n| 1 | 2 |"
                                  "\n<!-- END paper -->\nrest\n")


def test_make_bench_writes_into_out_not_the_tracked_file(tmp_path, monkeypatch):
    """`make bench` (bench/run.py's main, its measurements stubbed, its root moved to a
    temporary folder) writes the table into out/bench/results.md and nothing into bench/."""
    monkeypatch.setattr(sys, "path", list(sys.path))          # run.py inserts the root
    spec = importlib.util.spec_from_file_location("bench_run", ROOT / "bench" / "run.py")
    run = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(run)
    for name in ("bench_single_call", "bench_controllers", "bench_op_estimate",
                 "bench_vector_limits", "bench_rotorpy_batched", "bench_rotorpy",
                 "bench_scale", "bench_crazyflow", "bench_isa",
                 "bench_float32"):
        monkeypatch.setattr(run, name, lambda *args: None)
    monkeypatch.setattr(run, "bench_flight", lambda: (None, None))
    monkeypatch.setattr(run, "bench_batch", lambda n: (1.0, 1.0))
    monkeypatch.setattr(run, "rows", [("a measurement", "1.5", "s", "", "", "")])
    monkeypatch.setattr(run, "ROOT", tmp_path)
    monkeypatch.setattr(sys, "argv", ["run.py"])
    tracked = (ROOT / "bench" / "results.md").read_bytes()
    run.main()
    written = (tmp_path / "out" / "bench" / "results.md").read_text()
    assert "| a measurement | 1.5 | s |" in written
    assert not (tmp_path / "bench").exists()
    assert (ROOT / "bench" / "results.md").read_bytes() == tracked


def test_bench_figures_name_their_machine():
    """The published bench table says which machine and day it came from: the line the run
    wrote above its table, copied with it."""
    pub = _publish()
    page = pub.PAGES["bench"].read_text()
    machine = pub.block(page, "bench-machine")
    assert machine == pub.machine_of((ROOT / "bench" / "results.md").read_text())
    assert "cores" in machine and "20" in machine
