"""Publish measured figures into the documentation pages, copied from the files that commands
wrote, never typed:

- a table: the block between ``<!-- BEGIN <name> -->`` and ``<!-- END <name> -->`` of the page
  ``PAGES[name]`` becomes the table of the file (a Markdown file's first table, a JSON file's
  ``"table"``), and ``<!-- BEGIN <name>-machine -->`` the line that says where it ran;
- a number in the prose of any page (README.md, docs/): ``<!-- value <name> <key> <format>
  -->9.1e-13<!-- /value -->`` becomes the entry ``<key>`` of the JSON file (a ``/``-separated
  path; list entries by index) in the Python format ``<format>`` (``.1e``, ``.0%``, ``d``;
  ``.1f*100`` scales first: metres as centimetres). The page renders the number alone.

Each file is also copied to ``COPIES[name]`` (tracked), which tests/test_readme_numbers.py
checks every block and value against, so a page that disagrees with its command fails there.

    python bench/publish.py bench             # every out/bench/results-ISA.md (make bench)
    python bench/publish.py bench-avx2 [FILE] # one ISA's (QUADCOG_KERNEL_ISA=avx2 make bench)
    python bench/publish.py paper    [FILE]   # default out/paper/readme_table.md (quadcog paper)
    python bench/publish.py beyond   [FILE]   # default out/paper/beyond/beyond.md (quadcog paper)
    python bench/publish.py analysis [FILE]   # default out/analysis/analysis.json (quadcog analyze)
    python bench/publish.py verify   [FILE]   # default out/report/verification.json (make report)
    python bench/publish.py embedded [FILE]   # default out/embedded/costs.json (make embedded)
    python bench/publish.py targets  [FILE]   # default out/targets/targets.md (quadcog targets)
    python bench/publish.py crazyflie [FILE]  # default out/crazyflie/side-by-side.md (make crazyflie)
    python bench/publish.py crazyflie-real [FILE]  # out/crazyflie/real-flights.md (make crazyflie)
    python bench/publish.py geometric [FILE]  # out/geometric/geometric.json
                                              # (python -m quadcog.studies.geometric)
    python bench/publish.py objcode  [FILE]   # default out/bench/objcode.md (bench/objcode.py)
    python bench/publish.py precision-float32 [FILE]   # out/bench/precision-float32.md,
    python bench/publish.py precision-isa     [FILE]   # ... -isa.md and -fma.md
    python bench/publish.py precision-fma     [FILE]   # (python bench/precision.py)
    python bench/publish.py px4-speed    [FILE]   # out/px4/speed.md, identify.md, side.md
    python bench/publish.py px4-identify [FILE]   # (make px4)
    python bench/publish.py px4-side     [FILE]
    python bench/publish.py aqb         [FILE]   # default out/aqb/aqb.json (make bench-aqb)
    python bench/publish.py aqb-physics [FILE]   # out/aqb/physics.json (make bench-aqb)
    python bench/publish.py aqb-flaws   [FILE]   # out/aqb/flaws.json (make bench-aqb)
"""
import json
from pathlib import Path
import re
import shutil
import sys

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "out"
# the ISAs whose `make bench` table docs/performance.md keeps, each with its machine
BENCH_ISAS = ("avx512", "avx2")
SOURCES = {**{f"bench-{isa}": OUT / "bench" / f"results-{isa}.md" for isa in BENCH_ISAS},
           "paper": OUT / "paper" / "readme_table.md",
           "beyond": OUT / "paper" / "beyond" / "beyond.md",
           "analysis": OUT / "analysis" / "analysis.json",
           "verify": OUT / "report" / "verification.json",
           "embedded": OUT / "embedded" / "costs.json",
           "targets": OUT / "targets" / "targets.md",
           "crazyflie": OUT / "crazyflie" / "side-by-side.md",
           "crazyflie-real": OUT / "crazyflie" / "real-flights.md",
           "geometric": OUT / "geometric" / "geometric.json",
           "objcode": OUT / "bench" / "objcode.md",
           **{f"precision-{p}": OUT / "bench" / f"precision-{p}.md"
              for p in ("float32", "isa", "fma")},
           **{f"px4-{p}": OUT / "px4" / f"{p}.md" for p in ("speed", "identify", "side")},
           "aqb": OUT / "aqb" / "aqb.json", "aqb-physics": OUT / "aqb" / "physics.json",
           "aqb-flaws": OUT / "aqb" / "flaws.json"}
# the page that holds each table block
PAGES = {**{f"bench-{isa}": ROOT / "docs" / "performance.md" for isa in BENCH_ISAS},
         "paper": ROOT / "docs" / "tour" / "paper.md",
         "beyond": ROOT / "docs" / "tour" / "beyond.md",
         "embedded": ROOT / "docs" / "tour" / "flight-controller.md",
         "targets": ROOT / "docs" / "targets.md",
         "objcode": ROOT / "docs" / "performance.md",
         "crazyflie": ROOT / "docs" / "crazyflie.md",
         "crazyflie-real": ROOT / "docs" / "crazyflie.md",
         "geometric": ROOT / "docs" / "tour" / "geometric.md",
         **{f"precision-{p}": ROOT / "docs" / "performance.md" for p in ("float32", "isa", "fma")},
         **{f"px4-{p}": ROOT / "docs" / "px4.md" for p in ("speed", "identify", "side")},
         **{name: ROOT / "docs" / "aqb.md" for name in ("aqb", "aqb-physics", "aqb-flaws")}}
# the tracked copy of each published file (paper and beyond: tests/test_paper.py reruns them)
MEASURED = ROOT / "docs" / "measured"
COPIES = {**{f"bench-{isa}": ROOT / "bench" / f"results-{isa}.md" for isa in BENCH_ISAS},
          "analysis": MEASURED / "analysis.json",
          "verify": MEASURED / "verification.json",
          "embedded": MEASURED / "embedded.json",
          "objcode": MEASURED / "objcode.md",
          "crazyflie": MEASURED / "crazyflie.md",
          "crazyflie-real": MEASURED / "crazyflie-real.md",
          "geometric": MEASURED / "geometric.json",
          **{f"precision-{p}": MEASURED / f"precision-{p}.md" for p in ("float32", "isa", "fma")},
          **{f"px4-{p}": MEASURED / f"px4-{p}.md" for p in ("speed", "identify", "side")},
          **{name: MEASURED / f"{name}.json" for name in ("aqb", "aqb-physics", "aqb-flaws")}}
VALUE = re.compile(r"<!-- value (?P<name>[\w-]+) (?P<key>[^>]+?) (?P<format>\S+) -->"
                   r"(?P<text>[^<]*)<!-- /value -->")


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


# The last column of a bench table, when it is named so, is shown as numbered notes under the
# table: in the page's column (720 px at 1280 px) the long notes pushed the table to 888 px,
# the notes off-screen (issue 32). The file a command wrote keeps its column.
NOTE_HEADERS = ("note", "notes")


def _cells(line):
    return [c.strip() for c in re.split(r"(?<!\\)\|", line.strip())[1:-1]]


def page_table(table):
    """``table`` as a page shows it: a last column named ``note`` keeps only each note's
    number (``[N]``, under the header ``[n]``; one number for one text), and the notes follow
    the table as a numbered list (``N. text``)."""
    lines = table.splitlines()
    if len(lines) < 3 or _cells(lines[0])[-1].lower() not in NOTE_HEADERS:
        return table
    rows, notes = [], []
    for k, line in enumerate(lines):
        cells = _cells(line)
        if k == 1:
            last = cells[-1]
        elif k == 0:
            last = "[n]"          # as narrow as the numbers: a bold "note" would break
        elif cells[-1]:
            if cells[-1] not in notes:
                notes.append(cells[-1])
            last = f"[{notes.index(cells[-1]) + 1}]"
        else:
            last = ""
        rows.append("| " + " | ".join(cells[:-1] + [last]) + " |")
    listed = "\n".join(f"{n}. {text}" for n, text in enumerate(notes, 1))
    return "\n".join(rows) + ("\n\nNotes:\n\n" + listed if notes else "")


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


def entry(data, key):
    """The entry of JSON data at a ``/``-separated key (list entries by index)."""
    for part in key.split("/"):
        data = data[int(part)] if isinstance(data, list) else data[part]
    return data


def formatted(value, spec):
    """``value`` in a Python format spec, ``SPEC*SCALE`` or ``SPEC/SCALE`` scaled first
    (``.1f*100``: metres as centimetres), exponents as prose writes them (``1.8e-3``)."""
    mo = re.fullmatch(r"(?P<spec>[^*/]*)(?:(?P<op>[*/])(?P<scale>[-\d.e]+))?", spec)
    if mo.group("op"):
        scale = float(mo.group("scale"))
        value = value * scale if mo.group("op") == "*" else value / scale
    return re.sub(r"e([+-])0*(\d)", lambda e: "e" + e.group(1).replace("+", "") + e.group(2),
                  format(value, mo.group("spec")))


def values(text, name, data):
    """``text`` with every ``<!-- value name ... -->`` marker filled in from ``data``; and the
    list of (key, shown, published) where the text showed another number."""
    changed = []

    def fill(mo):
        if mo.group("name") != name:
            return mo.group(0)
        shown = formatted(entry(data, mo.group("key")), mo.group("format"))
        if shown != mo.group("text"):
            changed.append((mo.group("key"), mo.group("text"), shown))
        return mo.group(0).replace(f"-->{mo.group('text')}<!--", f"-->{shown}<!--", 1)

    return VALUE.sub(fill, text), changed


def read(source):
    """(table, machine line, JSON data or None) of a file a command wrote."""
    if not Path(source).is_file():
        raise SystemExit(f"{source}: no such file; run the command that writes it first "
                         "(this script's docstring names each)")
    text = Path(source).read_text()
    if Path(source).suffix == ".json":
        data = json.loads(text)
        return data.get("table", ""), data.get("machine", ""), data
    return table_of(text), machine_of(text), None


def publish(name, source, readme=None):
    """Replace block ``name`` of ``readme`` (default: its page, ``PAGES[name]``) by the table
    of ``source``, fill in the values of ``source`` on every page (with ``readme`` given: on
    that page only) and copy ``source`` to ``COPIES[name]``."""
    table, machine, data = read(source)
    page = Path(readme) if readme is not None else PAGES.get(name)
    if page is not None and (name in PAGES or f"<!-- BEGIN {name} -->" in page.read_text()):
        table = table_of(table)
        if not table:
            raise SystemExit(f"{source}: no Markdown table")
        table = page_table(table)
        text = page.read_text()
        block(text, name)                       # the markers must exist
        text = re.sub(rf"(<!-- BEGIN {name} -->\n).*?(\n<!-- END {name} -->)",
                      lambda mo: mo.group(1) + table + mo.group(2), text, flags=re.S)
        if f"<!-- BEGIN {name}-machine -->" in text:   # the machine the figures came from
            text = re.sub(rf"(<!-- BEGIN {name}-machine -->\n).*?(<!-- END {name}-machine -->)",
                          lambda mo: mo.group(1) + machine + "\n" + mo.group(2), text, flags=re.S)
        page.write_text(text)
        print(f"{page}: block {name} now holds the table of {source}")
    if data is not None:
        for each in [Path(readme)] if readme is not None else pages():
            text, changed = values(each.read_text(), name, data)
            if changed:
                each.write_text(text)
            for key, old, new in changed:
                print(f"{each}: {name} {key}: {old} -> {new}")
    if name in COPIES:
        target = COPIES[name]
        if Path(source).resolve() != target.resolve():
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(source, target)


def pages():
    """The pages that may hold values: those whose blocks the tests run."""
    sys.path[:0] = [str(ROOT), str(ROOT / "tests")]
    from tests.test_docs_examples import pages as docs_pages
    return docs_pages()


if __name__ == "__main__":
    if sys.argv[1:] == ["bench"]:         # each ISA's table that a run wrote
        found = [f"bench-{isa}" for isa in BENCH_ISAS if SOURCES[f"bench-{isa}"].is_file()]
        if not found:
            raise SystemExit("no out/bench/results-ISA.md: run make bench first")
        for name in found:
            publish(name, SOURCES[name])
        raise SystemExit(0)
    if len(sys.argv) not in (2, 3) or sys.argv[1] not in SOURCES:
        raise SystemExit(__doc__)
    publish(sys.argv[1], sys.argv[2] if len(sys.argv) == 3 else SOURCES[sys.argv[1]])
