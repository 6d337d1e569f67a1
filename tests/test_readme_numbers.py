"""The README's measured tables are copies of files that commands wrote (bench/publish.py);
the paper table is compared with a fresh run in tests/test_paper.py."""
from pathlib import Path
import importlib.util

ROOT = Path(__file__).resolve().parent.parent


def _publish():
    spec = importlib.util.spec_from_file_location("publish", ROOT / "bench" / "publish.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_bench_table_is_the_published_bench_run():
    pub = _publish()
    readme = (ROOT / "README.md").read_text()
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


def test_make_bench_writes_into_out_not_the_tracked_file():
    text = (ROOT / "bench" / "run.py").read_text()
    assert 'ROOT / "out" / "bench" / "results.md"' in text
    assert 'ROOT / "bench" / "results.md"' not in text
