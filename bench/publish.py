"""Publish measured tables into README.md: the block between
``<!-- BEGIN <name> -->`` and ``<!-- END <name> -->`` becomes the table of a file a command
wrote, so the README's numbers are copied from runs, never typed.

    python bench/publish.py bench  [FILE]   # default out/bench/results.md (make bench);
                                            # also copies FILE to bench/results.md
    python bench/publish.py paper  [FILE]   # default out/paper/readme_table.md (quadcog paper)
    python bench/publish.py beyond [FILE]   # default out/paper/beyond/beyond.md (quadcog paper)

tests/test_readme_numbers.py checks that the README's blocks are those files' tables.
"""
from pathlib import Path
import re
import shutil
import sys

ROOT = Path(__file__).resolve().parent.parent
SOURCES = {"bench": ROOT / "out" / "bench" / "results.md",
           "paper": ROOT / "out" / "paper" / "readme_table.md",
           "beyond": ROOT / "out" / "paper" / "beyond" / "beyond.md"}


def table_of(text):
    """The first Markdown table (consecutive lines starting with '|') of ``text``."""
    lines, found = [], False
    for line in text.splitlines():
        if line.startswith("|"):
            lines.append(line)
            found = True
        elif found:
            break
    return "\n".join(lines)


def block(readme_text, name):
    """The text between the BEGIN/END markers of ``name`` in the README (stripped)."""
    mo = re.search(rf"<!-- BEGIN {name} -->\n(.*?)\n<!-- END {name} -->", readme_text, re.S)
    if not mo:
        raise SystemExit(f"README.md has no <!-- BEGIN {name} --> ... <!-- END {name} --> block")
    return mo.group(1).strip()


def publish(name, source, readme=ROOT / "README.md"):
    """Replace block ``name`` of ``readme`` by the table of ``source``."""
    table = table_of(Path(source).read_text())
    if not table:
        raise SystemExit(f"{source}: no Markdown table")
    text = readme.read_text()
    block(text, name)                       # the markers must exist
    text = re.sub(rf"(<!-- BEGIN {name} -->\n).*?(\n<!-- END {name} -->)",
                  lambda mo: mo.group(1) + table + mo.group(2), text, flags=re.S)
    readme.write_text(text)
    if name == "bench":
        target = ROOT / "bench" / "results.md"
        if Path(source).resolve() != target.resolve():
            shutil.copyfile(source, target)
    print(f"README.md: block {name} now holds the table of {source}")


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3) or sys.argv[1] not in SOURCES:
        raise SystemExit(__doc__)
    publish(sys.argv[1], sys.argv[2] if len(sys.argv) == 3 else SOURCES[sys.argv[1]])
