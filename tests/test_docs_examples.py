"""Every Python and shell block of README.md and docs/ runs, as a reader would paste it.

Each ```python block runs alone in a fresh interpreter (so a missing import fails, as it would
on paste), each ```sh / ```bash block in bash with ``-e`` (a failing command fails the test),
both in an empty temporary folder where ``.venv`` points at this interpreter's environment
(the blocks say ``.venv/bin/quadcog``, as in a checkout) and ``generated`` at the checkout's
(read only). There is no ``tests/data`` there: a block reads the sample logs that ship in the
package (``quadcog.logs.samples``), as a reader with a wheel would. An HTML comment on the
line before a block changes that:

- ``<!-- norun: why -->``: not run (a run of minutes, a command that needs root or a board);
- ``<!-- slow -->``: run, marked ``slow``;
- ``<!-- output -->`` before a ```text block: that block is what the block before it prints
  (compared exactly; ``python docs/fill_outputs.py`` writes it from a run, so numbers shown
  as output are never typed).

A block in another language (toml, c, text) is not run. The TOML of the sweep pages is checked
by tests/test_docsite.py.
"""
from dataclasses import dataclass
import os
from pathlib import Path
import re
import subprocess
import sys

from conftest import background_dir, background_job, background_result
import pytest

ROOT = Path(__file__).resolve().parent.parent
RUNNABLE = {"python": "python", "py": "python", "sh": "sh", "bash": "sh", "console": "sh"}
FENCE = re.compile(r"^(?P<indent>[ \t]*)```(?P<lang>[\w+-]*)[^\n]*\n(?P<body>.*?)^(?P=indent)```[ \t]*$",
                   re.M | re.S)
MARK = re.compile(r"<!--\s*(norun|slow|output)\b[^>]*-->\s*$")
TIMEOUT = 300
READ_ONLY = ("generated",)       # linked into the block's folder (not tests/data: a wheel has none)


@dataclass
class Block:
    """One fenced block of a page: its language, text, first line and marker."""
    page: str
    line: int
    lang: str
    text: str
    mark: str | None
    output: str | None = None         # the ```text block marked <!-- output --> after it


def pages() -> list[Path]:
    """README.md and every page under docs/."""
    return [ROOT / "README.md"] + sorted((ROOT / "docs").rglob("*.md"))


def blocks_of(path: Path) -> list[Block]:
    """The fenced blocks of a page, with the output block attached to the block it shows."""
    text = path.read_text(encoding="utf-8")
    found: list[Block] = []
    for mo in FENCE.finditer(text):
        before = text[:mo.start()].rstrip("\n").rsplit("\n", 1)[-1]
        mark = MARK.search(before)
        indent = len(mo.group("indent"))
        body = "\n".join(line[indent:] for line in mo.group("body").splitlines()) + "\n"
        name = path.relative_to(ROOT).as_posix() if path.is_relative_to(ROOT) else str(path)
        found.append(Block(name, text.count("\n", 0, mo.start()) + 1,
                           mo.group("lang").lower(), body, mark.group(1) if mark else None))
    out: list[Block] = []
    for b in found:
        if b.mark == "output":
            if not out or b.lang != "text":
                raise AssertionError(f"{b.page}:{b.line}: <!-- output --> must mark a ```text "
                                     f"block right after a runnable block")
            out[-1].output = b.text
        else:
            out.append(b)
    return out


def runnable() -> list[Block]:
    """The blocks the tests run."""
    return [b for p in pages() for b in blocks_of(p)
            if b.lang in RUNNABLE and b.mark != "norun"]


def run_block(block: Block, folder: Path) -> subprocess.CompletedProcess:
    """Run one block in ``folder`` and return the finished process (stdout and stderr)."""
    venv = folder / ".venv"
    if not venv.exists():
        venv.symlink_to(Path(sys.prefix), target_is_directory=True)
        # read-only inputs that the pages name by their path in a checkout
        for rel in READ_ONLY:
            (folder / rel).parent.mkdir(parents=True, exist_ok=True)
            (folder / rel).symlink_to(ROOT / rel, target_is_directory=True)
    env = dict(os.environ, MPLBACKEND="Agg", COLUMNS="96",
               PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}")
    if RUNNABLE[block.lang] == "python":
        script = folder / "block.py"
        script.write_text(block.text)
        cmd = [sys.executable, str(script)]
    else:
        script = folder / "block.sh"
        script.write_text(block.text)
        cmd = ["bash", "-e", "-o", "pipefail", str(script)]
    return subprocess.run(cmd, cwd=folder, env=env, capture_output=True, text=True,
                          timeout=TIMEOUT)


def _param(b: Block):
    marks = [pytest.mark.slow] if b.mark == "slow" else []
    return pytest.param(b, id=f"{b.page}:{b.line}", marks=marks)


def _job(block: Block):
    """The background job of one block: a subprocess in a folder of its own, started at
    collection on a lane of its own (conftest.background_job), so the blocks run while the
    other tests do."""
    def prepare():
        folder = background_dir("docs-block")
        return lambda: run_block(block, folder)
    return prepare


for _b in runnable():
    background_job(f"docs block {_b.page}:{_b.line}", __file__,
                   f"test_block_runs[{_b.page}:{_b.line}]", _job(_b), lane="docs")


@pytest.mark.parametrize("block", [_param(b) for b in runnable()])
def test_block_runs(block):
    done = background_result(f"docs block {block.page}:{block.line}")
    assert done.returncode == 0, (f"{block.page}:{block.line} ({block.lang}) exited "
                                  f"{done.returncode}\n--- block\n{block.text}--- stdout\n"
                                  f"{done.stdout[-3000:]}--- stderr\n{done.stderr[-3000:]}")
    if block.output is not None:
        assert done.stdout == block.output, (
            f"{block.page}:{block.line}: the output shown differs from the run's; "
            f"`python docs/fill_outputs.py` rewrites it\n--- shown\n{block.output}--- run\n"
            f"{done.stdout}")


def test_the_pages_have_runnable_blocks():
    """The scan finds the blocks (a broken pattern would make every test above vanish), and
    every marker is one of the three."""
    blocks = [b for p in pages() for b in blocks_of(p)]
    langs = {b.lang for b in blocks}
    assert {"python", "sh", "toml"} <= langs, langs
    assert len(runnable()) >= 20
    for p in pages():
        for n, line in enumerate(p.read_text().splitlines(), 1):
            if re.search(r"<!--\s*(no-?run|skip|slow|output)", line):
                assert MARK.search(line), f"{p}:{n}: unknown marker {line.strip()}"


def test_block_scanner_on_a_page(tmp_path):
    """Indented fences (in a list) are dedented, markers and outputs attach to their block."""
    page = tmp_path / "p.md"
    page.write_text("- a list\n\n  ```python\n  print(1)\n  ```\n\n<!-- output -->\n```text\n1\n"
                    "```\n\n<!-- norun: minutes -->\n```sh\nmake paper\n```\n\n```toml\na = 1\n"
                    "```\n")
    blocks = blocks_of(page)
    assert [(b.lang, b.mark) for b in blocks] == [("python", None), ("sh", "norun"),
                                                  ("toml", None)]
    assert blocks[0].text == "print(1)\n" and blocks[0].output == "1\n"
