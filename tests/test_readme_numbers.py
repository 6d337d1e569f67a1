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


def test_bench_tables_are_the_published_bench_runs():
    """One table per ISA (an AVX-512 and an AVX2 build), each the copy of its run's file."""
    pub = _publish()
    for isa in pub.BENCH_ISAS:
        readme = pub.PAGES[f"bench-{isa}"].read_text()
        copy = (ROOT / "bench" / f"results-{isa}.md").read_text()
        assert pub.block(readme, f"bench-{isa}") == pub.page_table(pub.table_of(copy))
        assert f"kernels built for {isa}" in pub.machine_of(copy)


def test_publish_replaces_only_its_block(tmp_path):
    pub = _publish()
    readme = tmp_path / "README.md"
    readme.write_text("intro\n<!-- BEGIN paper -->\n| old |\n<!-- END paper -->\nrest\n")
    src = tmp_path / "t.md"
    src.write_text("# title\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\ntext\n")
    pub.publish("paper", src, readme)
    assert readme.read_text() == ("intro\n<!-- BEGIN paper -->\n| a | b |\n|---|---|\n| 1 | 2 |"
                                  "\n<!-- END paper -->\nrest\n")


def test_page_table_moves_the_notes_below_the_table():
    """A bench table's note column becomes numbers and a numbered list (one number for one
    text); a table without a note column is left as it is."""
    pub = _publish()
    table = ("| measurement | value | note |\n|---|---|---|\n| a | 1 | long text, a \\| pipe |\n"
             "| b | 2 |  |\n| c | 3 | other |\n| d | 4 | long text, a \\| pipe |")
    assert pub.page_table(table) == (
        "| measurement | value | [n] |\n| --- | --- | --- |\n| a | 1 | [1] |\n| b | 2 |  |\n"
        "| c | 3 | [2] |\n| d | 4 | [1] |\n\nNotes:\n\n1. long text, a \\| pipe\n2. other")
    plain = "| a | b |\n|---|---|\n| 1 | 2 |"
    assert pub.page_table(plain) == plain


def test_make_bench_writes_into_out_not_the_tracked_file(tmp_path, monkeypatch):
    """`make bench` (bench/run.py's main, its measurements stubbed, its root moved to a
    temporary folder) writes the table into out/bench/results-ISA.md and nothing into bench/."""
    monkeypatch.setattr(sys, "path", list(sys.path))          # run.py inserts the root
    spec = importlib.util.spec_from_file_location("bench_run", ROOT / "bench" / "run.py")
    run = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(run)
    for name in ("bench_single_call", "bench_controllers", "bench_op_estimate",
                 "bench_vector_limits", "bench_rotorpy_batched", "bench_rotorpy",
                 "bench_scale", "bench_crazyflow", "bench_numba", "bench_isa",
                 "bench_float32"):
        monkeypatch.setattr(run, name, lambda *args: None)
    monkeypatch.setattr(run, "bench_flight", lambda: (None, None, 0.015))
    monkeypatch.setattr(run, "bench_batch", lambda n: (1.0, 1.0))
    monkeypatch.setattr(run, "rows", [("a measurement", "1.5", "s", "", "", "")])
    monkeypatch.setattr(run, "ROOT", tmp_path)
    monkeypatch.setattr(sys, "argv", ["run.py"])
    tracked = {p: p.read_bytes() for p in (ROOT / "bench").glob("results-*.md")}
    run.main()
    from bench.machine import machine
    written = (tmp_path / "out" / "bench" / f"results-{machine()['isa']}.md").read_text()
    assert "| a measurement | 1.5 | s |" in written
    assert not (tmp_path / "bench").exists()
    assert {p: p.read_bytes() for p in (ROOT / "bench").glob("results-*.md")} == tracked


def test_bench_figures_name_their_machine():
    """The published bench table says which machine and day it came from: the line the run
    wrote above its table, copied with it."""
    pub = _publish()
    for isa in pub.BENCH_ISAS:
        page = pub.PAGES[f"bench-{isa}"].read_text()
        machine = pub.block(page, f"bench-{isa}-machine")
        assert machine == pub.machine_of((ROOT / "bench" / f"results-{isa}.md").read_text())
        assert "cores" in machine and "20" in machine


# -- numbers in the prose: <!-- value NAME KEY FORMAT -->...<!-- /value --> (bench/publish.py) --

def _markers():
    """(page, name, key, format, text) of every value marker of the pages the tests run."""
    from test_docs_examples import pages
    pub = _publish()
    return [(page, mo.group("name"), mo.group("key"), mo.group("format"), mo.group("text"))
            for page in pages() for mo in pub.VALUE.finditer(page.read_text())]


def test_every_number_marked_in_the_prose_is_its_commands():
    """Each number marked on a page is the entry of the file its command wrote (the tracked
    copy, docs/measured/), in the marker's format: a number edited by hand, or a run
    published without the pages, fails here."""
    import json
    pub = _publish()
    markers = _markers()
    assert {"analysis", "verify", "embedded"} <= {m[1] for m in markers} and len(markers) >= 25
    wrong = []
    for page, name, key, fmt, text in markers:
        assert name in pub.COPIES, f"{page}: no published file for value {name!r}"
        shown = pub.formatted(pub.entry(json.loads(pub.COPIES[name].read_text()), key), fmt)
        if shown != text:
            wrong.append(f"{page.name}: {name} {key}: the page says {text!r}, the run {shown!r}")
    assert not wrong, ("\n".join(wrong) + "\n(after a new run: python bench/publish.py NAME)")


def test_every_published_file_names_its_machine():
    """The tracked copies say where and when they ran (the benchmark figures' machine), and
    the pages show that line beside the figures."""
    pub = _publish()
    for name, copy in pub.COPIES.items():
        _, machine, _ = pub.read(copy)
        assert "cores" in machine and "20" in machine, (name, machine)
    page = pub.PAGES["embedded"].read_text()
    table, machine, _ = pub.read(pub.COPIES["embedded"])
    assert pub.block(page, "embedded") == pub.table_of(table)
    assert pub.block(page, "embedded-machine") == machine


def test_publish_fills_in_the_values_of_a_run(tmp_path):
    """publish() rewrites the text of each marker of its name (not of another name) from the
    JSON a command wrote, formats and scales as the marker says, and copies the file."""
    import json
    pub = _publish()
    src = tmp_path / "run.json"
    src.write_text(json.dumps({"machine": "on a test machine, 2 cores, 2026-01-01",
                               "a": {"b": [0.5, 0.0123]}, "n": 437, "e": 0.00181}))
    page = tmp_path / "page.md"
    page.write_text("x <!-- value run a/b/1 .2f*100 -->9.99<!-- /value --> cm, "
                    "<!-- value run n d -->1<!-- /value --> of them, "
                    "<!-- value run a/b/0 .0% -->?<!-- /value -->, "
                    "<!-- value run e .1e -->0<!-- /value -->, "
                    "<!-- value other n d -->7<!-- /value -->\n")
    pub.COPIES["run"] = tmp_path / "copy" / "run.json"
    try:
        pub.publish("run", src, page)
    finally:
        del pub.COPIES["run"]
    assert page.read_text() == ("x <!-- value run a/b/1 .2f*100 -->1.23<!-- /value --> cm, "
                                "<!-- value run n d -->437<!-- /value --> of them, "
                                "<!-- value run a/b/0 .0% -->50%<!-- /value -->, "
                                "<!-- value run e .1e -->1.8e-3<!-- /value -->, "
                                "<!-- value other n d -->7<!-- /value -->\n")
    assert (tmp_path / "copy" / "run.json").read_text() == src.read_text()


def test_every_published_markdown_table_is_its_tracked_copy():
    """bench/publish.py's precision tables (bench/precision.py) and the bench table: each
    block of a page equals the table of the file the command wrote (its tracked copy)."""
    pub = _publish()
    checked = []
    for name, copy in pub.COPIES.items():
        if copy.suffix != ".md" or name not in pub.PAGES:
            continue
        page = pub.PAGES[name].read_text()
        assert pub.block(page, name) == pub.page_table(pub.table_of(copy.read_text())), name
        machine = pub.machine_of(copy.read_text())
        if f"<!-- BEGIN {name}-machine -->" in page:
            assert pub.block(page, f"{name}-machine") == machine, name
        checked.append(name)
    assert {"bench-avx512", "bench-avx2", "objcode", "precision-float32", "precision-isa",
            "precision-fma"} <= set(checked)
