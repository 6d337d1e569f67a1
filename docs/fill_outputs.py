"""Fill in the output blocks of the docs from runs: every ```text block marked
``<!-- output -->`` becomes what the block before it prints (tests/test_docs_examples.py
checks that they agree), so the numbers shown as output are never typed.

    python docs/fill_outputs.py [PAGE...]     # default: README.md and every page of docs/
"""
from pathlib import Path
import re
import sys
import tempfile

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]       # tests/: its conftest, as pytest has it

from tests.test_docs_examples import blocks_of, pages, run_block  # noqa: E402

__all__ = ["fill"]

OUTPUT = re.compile(r"^(?P<indent>[ \t]*)<!-- output -->\n(?P=indent)```text\n(?P<body>.*?)"
                    r"^(?P=indent)```", re.M | re.S)


def fill(page: Path) -> int:
    """Rewrite the output blocks of one page from fresh runs.

    Parameters
    ----------
    page : pathlib.Path
        A Markdown page.

    Returns
    -------
    int
        The number of output blocks rewritten.
    """
    text = page.read_text()
    n = 0
    for block in blocks_of(page):
        if block.output is None:
            continue
        with tempfile.TemporaryDirectory() as folder:
            done = run_block(block, Path(folder))
        if done.returncode != 0:
            raise SystemExit(f"{page}:{block.line} failed:\n{done.stderr}")
        offset = sum(len(x) + 1 for x in text.splitlines()[:block.line - 1])
        mo = OUTPUT.search(text, offset)
        indent = mo.group("indent")
        shown = "".join(indent + line + "\n" if line else "\n"
                        for line in done.stdout.splitlines())
        text = text[:mo.start("body")] + shown + text[mo.end("body"):]
        n += 1
    page.write_text(text)
    return n


if __name__ == "__main__":
    for page in [Path(p).resolve() for p in sys.argv[1:]] or pages():
        n = fill(page)
        if n:
            print(f"{page}: {n} output block(s) filled in")
