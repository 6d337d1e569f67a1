"""Publish measured tables into the documentation pages: the block between
``<!-- BEGIN <name> -->`` and ``<!-- END <name> -->`` of the block's page (``PAGES``) becomes
the table of a file a command wrote, so the published numbers are copied from runs, never typed.

    python bench/publish.py bench  [FILE]   # default out/bench/results.md (make bench);
                                            # also copies FILE to bench/results.md
    python bench/publish.py paper  [FILE]   # default out/paper/readme_table.md (quadcog paper)
    python bench/publish.py beyond [FILE]   # default out/paper/beyond/beyond.md (quadcog paper)
    python bench/publish.py targets [FILE]  # default out/targets/targets.md (quadcog targets)

tests/test_readme_numbers.py checks that the pages' blocks are those files' tables.
"""
from pathlib import Path
import re
import shutil
import sys

ROOT = Path(__file__).resolve().parent.parent
SOURCES = {"bench": ROOT / "out" / "bench" / "results.md",
           "paper": ROOT / "out" / "paper" / "readme_table.md",
           "beyond": ROOT / "out" / "paper" / "beyond" / "beyond.md",
           "targets": ROOT / "out" / "targets" / "targets.md"}
# the page that holds each block
PAGES = {"bench": ROOT / "docs" / "performance.md",
         "paper": ROOT / "docs" / "tour" / "paper.md",
         "beyond": ROOT / "docs" / "tour" / "beyond.md",
         "targets": ROOT / "docs" / "targets.md"}


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
    """The text between the BEGIN/END markers of ``name`` in a page (stripped)."""
    mo = re.search(rf"<!-- BEGIN {name} -->\n(.*?)\n<!-- END {name} -->", readme_text, re.S)
    if not mo:
        raise SystemExit(f"the page has no <!-- BEGIN {name} --> ... <!-- END {name} --> block")
    return mo.group(1).strip()


def machine_of(text):
    """The first line of prose after the title of a results file: where and when it ran."""
    for line in text.splitlines():
        if line.strip() and not line.startswith(("#", "|")):
            return line.strip()
    return ""


def publish(name, source, readme=None):
    """Replace block ``name`` of ``readme`` (default: its page, ``PAGES[name]``) by the table
    of ``source``."""
    readme = Path(readme) if readme is not None else PAGES[name]
    table = table_of(Path(source).read_text())
    if not table:
        raise SystemExit(f"{source}: no Markdown table")
    text = readme.read_text()
    block(text, name)                       # the markers must exist
    text = re.sub(rf"(<!-- BEGIN {name} -->\n).*?(\n<!-- END {name} -->)",
                  lambda mo: mo.group(1) + table + mo.group(2), text, flags=re.S)
    if f"<!-- BEGIN {name}-machine -->" in text:   # the machine the figures came from
        machine = machine_of(Path(source).read_text())
        text = re.sub(rf"(<!-- BEGIN {name}-machine -->\n).*?(<!-- END {name}-machine -->)",
                      lambda mo: mo.group(1) + machine + "\n" + mo.group(2), text, flags=re.S)
    readme.write_text(text)
    if name == "bench":
        target = ROOT / "bench" / "results.md"
        if Path(source).resolve() != target.resolve():
            shutil.copyfile(source, target)
    print(f"{readme}: block {name} now holds the table of {source}")


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3) or sys.argv[1] not in SOURCES:
        raise SystemExit(__doc__)
    publish(sys.argv[1], sys.argv[2] if len(sys.argv) == 3 else SOURCES[sys.argv[1]])
