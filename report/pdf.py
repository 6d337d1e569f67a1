"""``python -m report.pdf``: build generated/report.tex into a PDF with pdflatex.

The build happens in a folder of its own (``out/report/`` by default; never in generated/):
report.tex is copied there, ``out/paper`` (the results of ``quadcog paper``) is copied to
``<build>/paper`` when it exists, and a ``verification.tex`` already in the build folder
(written by ``python -m report.verify``) is picked up by the report. pdflatex runs twice
(nonstopmode, halt-on-error). The build fails, printing what is wrong, on a LaTeX error and on
any overfull box wider than ``--max-overfull`` pt (10 by default).

    python -m report.pdf --out out/report
"""
import argparse
from dataclasses import dataclass, field
import os
from pathlib import Path
import re
import shutil
import subprocess
import sys

ROOT = Path(__file__).resolve().parent.parent
GENERATED = ROOT / "generated"
DEFAULT_OUT = ROOT / "out" / "report"
DEFAULT_PAPER = ROOT / "out" / "paper"
DEFAULT_ANALYSIS = ROOT / "out" / "analysis"
# what the report needs of out/paper and out/analysis: the fragments and the figures (not the
# trajectories, which would double the size of out/)
COPIED = (".tex", ".png")
COPY_MARKER = ".copied-by-report"   # in the copies of results that a build may remove
JOB = "report"
MAX_OVERFULL = 10.0        # pt
APT_INSTALL = ("apt-get update && apt-get install -y --no-install-recommends "
               "texlive-latex-base texlive-latex-recommended poppler-utils")

_OVERFULL = re.compile(
    r"^Overfull \\hbox \((?P<pt>[0-9.]+)pt too wide\) "
    r"(?:in paragraph at lines (?P<a>\d+)--(?P<b>\d+)|detected at line (?P<n>\d+)"
    r"|in alignment at lines (?P<c>\d+)--(?P<d>\d+))")


class BuildError(Exception):
    """The PDF could not be built, or it has overfull boxes; the message says why."""


@dataclass
class Overfull:
    points: float
    file: str            # the source file the lines refer to, as pdflatex named it
    lines: tuple         # (first, last) line in that file
    log: str             # the log's description of the box, and what it holds


@dataclass
class Build:
    pdf: Path
    pages: int
    overfull: list = field(default_factory=list)     # every overfull box, any width
    paper: bool = False                               # paper/report_fragment.tex included
    analysis: bool = False                            # analysis/report_fragment.tex included
    verification: bool = False                        # verification.tex included

    @property
    def largest_overfull(self):
        return max((o.points for o in self.overfull), default=0.0)


def find_pdflatex():
    return shutil.which("pdflatex")


def _inside(path, folder):
    try:
        path.resolve().relative_to(folder.resolve())
        return True
    except ValueError:
        return False


def _current_files(log_lines):
    """For each log line, the innermost file pdflatex was reading at its start.

    pdflatex writes '(./file.tex' when it opens a file and ')' when it closes it; the text
    of box warnings (which may hold unbalanced parentheses) is skipped.
    """
    stack, out, skip = [], [], False
    for line in log_lines:
        out.append(next((f for f in reversed(stack) if f), JOB + ".tex"))
        if line.startswith(("Overfull", "Underfull")):
            skip = True
            continue
        if skip:
            skip = bool(line.strip())
            continue
        for mo in re.finditer(r"\((?P<file>\.?/?[^\s()]+\.(?:tex|sty|cls|cfg|def|fd|clo|aux))"
                              r"|\(|\)", line):
            if mo.group(0) == ")":
                if stack:
                    stack.pop()
            elif mo.group("file"):
                stack.append(mo.group("file"))
            else:
                stack.append(None)
    return out


def parse_overfull(log_text):
    """Every 'Overfull \\hbox' of a pdflatex log, with the file and lines it comes from."""
    lines = log_text.splitlines()
    files = _current_files(lines)
    found = []
    for k, line in enumerate(lines):
        mo = _OVERFULL.match(line)
        if not mo:
            continue
        first = int(mo.group("a") or mo.group("n") or mo.group("c"))
        last = int(mo.group("b") or mo.group("n") or mo.group("d"))
        detail = [line]
        for extra in lines[k + 1:k + 4]:
            if not extra.strip():
                break
            detail.append(extra)
        found.append(Overfull(float(mo.group("pt")), files[k], (first, last), "\n".join(detail)))
    return found


def _errors(log_text):
    """The '! ...' error messages of a log, each with the lines after it."""
    lines = log_text.splitlines()
    out = []
    for k, line in enumerate(lines):
        if line.startswith("!") or re.match(r"^\S+:\d+: ", line):
            context = [line]
            for extra in lines[k + 1:k + 6]:
                if not extra.strip() or extra.startswith("Here is how much"):
                    break
                context.append(extra)
            out.append("\n".join(context))
    return out


def _source(folder, overfull, width=100):
    """The source lines an overfull box comes from, shortened to ``width`` characters."""
    name = overfull.file[2:] if overfull.file.startswith("./") else overfull.file
    path = Path(name) if Path(name).is_absolute() else folder / name
    try:
        text = path.read_text(errors="replace").splitlines()
    except OSError:
        return f"    ({overfull.file} is not readable)"
    first, last = overfull.lines
    shown = []
    for n in range(first, min(last, first + 5) + 1):
        if 1 <= n <= len(text):
            s = text[n - 1]
            shown.append(f"    {name}:{n}: {s if len(s) <= width else s[:width] + ' ...'}")
    return "\n".join(shown)


def _run_pdflatex(pdflatex, folder, timeout):
    cmd = [pdflatex, "-interaction=nonstopmode", "-halt-on-error", "-file-line-error",
           f"{JOB}.tex"]
    try:
        res = subprocess.run(cmd, cwd=folder, capture_output=True, text=True, errors="replace",
                             timeout=timeout, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        raise BuildError(f"pdflatex did not finish within {timeout} s in {folder}")
    log_path = folder / f"{JOB}.log"
    log = log_path.read_text(errors="replace") if log_path.exists() else res.stdout
    if res.returncode != 0:
        errors = _errors(log) or [res.stdout[-2000:]]
        raise BuildError(f"pdflatex failed (exit {res.returncode}) on {folder / JOB}.tex; "
                         f"full log: {log_path}\n" + "\n\n".join(errors[:5]))
    return log


def _a_copy(folder):
    """Whether ``folder`` is a copy of results made by ``_copy_results`` (its marker; before
    the marker, a copy held only .tex and .png files, report_fragment.tex among them)."""
    if (folder / COPY_MARKER).is_file():
        return True
    files = [f for f in folder.rglob("*") if not f.is_dir()]
    return (folder / "report_fragment.tex").is_file() and all(
        f.is_file() and not f.is_symlink() and f.suffix in COPIED for f in files)


def _copy_results(src, target):
    """Replace folder ``target`` by the .tex and .png files of ``src`` (when ``src`` has a
    report_fragment.tex); returns whether it did.

    Only a copy this function made (it holds ``COPY_MARKER``) is ever removed: ``--out out``
    with the default ``--paper out/paper`` removed the paper's own results, and ``--out ~``
    would have removed any folder named paper there. ``src`` that is ``target`` is used in
    place."""
    if src is not None and Path(src).exists() and Path(src).resolve() == target.resolve():
        return (target / "report_fragment.tex").is_file()
    if src is not None and (_inside(target, Path(src)) or _inside(Path(src), target)):
        raise BuildError(f"the results {src} and their copy {target} overlap: give --out a "
                         "folder of its own, such as out/report")
    if os.path.lexists(target):
        if target.is_symlink() or not target.is_dir() or not _a_copy(target):
            raise BuildError(f"{target}: exists and is not a copy made by the report; the "
                             "report copies results there, so give --out a folder of its own, "
                             "such as out/report")
        shutil.rmtree(target)
    if src is None or not (Path(src) / "report_fragment.tex").is_file():
        return False
    for f in Path(src).rglob("*"):
        if f.is_file() and f.suffix in COPIED:
            dest = target / f.relative_to(src)
            dest.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(f, dest)
    (target / COPY_MARKER).write_text("copied by report/pdf.py; removed by the next build\n")
    return True


def build(tex=GENERATED / "report.tex", out=DEFAULT_OUT, paper=DEFAULT_PAPER,
          max_overfull=MAX_OVERFULL, timeout=300, analysis=DEFAULT_ANALYSIS):
    """Build ``tex`` into ``out``/report.pdf; returns a Build, raises BuildError."""
    tex, out = Path(tex), Path(out)
    if _inside(out, GENERATED):
        raise BuildError(f"refusing to build into {out}: generated/ holds only what "
                         "`make derive` writes; use a folder such as out/report")
    if not tex.is_file():
        raise BuildError(f"{tex} does not exist; run `make derive` first")
    pdflatex = find_pdflatex()
    if pdflatex is None:
        raise BuildError("pdflatex is not installed. On Debian or Ubuntu, as root:\n"
                         f"  {APT_INSTALL}")
    out.mkdir(parents=True, exist_ok=True)
    if tex.resolve() != (out / f"{JOB}.tex").resolve():
        shutil.copyfile(tex, out / f"{JOB}.tex")
    for stale in (f"{JOB}.aux", f"{JOB}.pdf", f"{JOB}.out", f"{JOB}.toc"):
        (out / stale).unlink(missing_ok=True)
    has_paper = _copy_results(paper, out / "paper")
    has_analysis = _copy_results(analysis, out / "analysis")
    for _ in range(2):            # the second run resolves references and longtable widths
        log = _run_pdflatex(pdflatex, out, timeout)
    overfull = parse_overfull(log)
    pages = re.search(r"Output written on \S+ \((\d+) pages?", log)
    result = Build(out / f"{JOB}.pdf", int(pages.group(1)) if pages else 0, overfull,
                   has_paper, has_analysis, (out / "verification.tex").is_file())
    too_wide = [o for o in overfull if o.points > max_overfull]
    if too_wide:
        report = "\n\n".join(f"{o.points:.1f} pt too wide, {o.file} lines "
                             f"{o.lines[0]}-{o.lines[1]}:\n{_source(out, o)}\n  log: "
                             + o.log.replace("\n", "\n       ") for o in too_wide)
        raise BuildError(f"{len(too_wide)} overfull box(es) wider than {max_overfull:g} pt in "
                         f"{out / JOB}.pdf (log: {out / JOB}.log):\n\n{report}")
    return result


def render_png(pdf, resolution=80):
    """Render every page of ``pdf`` to PNG beside it (pdftoppm); returns the PNG paths."""
    pdftoppm = shutil.which("pdftoppm")
    if pdftoppm is None:
        raise BuildError("pdftoppm is not installed (Debian package poppler-utils)")
    pdf = Path(pdf)
    for old in pdf.parent.glob(f"{pdf.stem}-page-*.png"):
        old.unlink()
    subprocess.run([pdftoppm, "-r", str(resolution), "-png", str(pdf),
                    str(pdf.parent / f"{pdf.stem}-page")], check=True)
    return sorted(pdf.parent.glob(f"{pdf.stem}-page-*.png"))


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m report.pdf", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT,
                    help="build folder (default: out/report); the PDF is OUT/report.pdf")
    ap.add_argument("--tex", type=Path, default=GENERATED / "report.tex",
                    help="the report to build (default: generated/report.tex)")
    ap.add_argument("--paper", type=Path, default=DEFAULT_PAPER,
                    help="results of `quadcog paper`, copied to OUT/paper when they exist "
                         "(default: out/paper)")
    ap.add_argument("--analysis", type=Path, default=DEFAULT_ANALYSIS,
                    help="results of `quadcog analyze`, copied to OUT/analysis when they exist "
                         "(default: out/analysis)")
    ap.add_argument("--max-overfull", type=float, default=MAX_OVERFULL,
                    help="fail on overfull boxes wider than this many pt (default: 10)")
    ap.add_argument("--png", action="store_true",
                    help="also render every page to OUT/report-page-N.png (pdftoppm)")
    args = ap.parse_args(argv)
    try:
        result = build(args.tex, args.out, args.paper, args.max_overfull,
                       analysis=args.analysis)
        pngs = render_png(result.pdf) if args.png else []
    except BuildError as e:
        sys.stderr.write(f"report.pdf: error: {e}\n")
        return 1
    print(f"wrote {result.pdf} ({result.pages} pages; largest overfull box "
          f"{result.largest_overfull:.1f} pt, limit {args.max_overfull:g} pt)")
    print("  verification table: " + ("included" if result.verification else
          "absent (run `python -m report.verify --out "
          f"{args.out / 'verification.tex'}`, or `make report`)"))
    print("  paper results: " + ("included" if result.paper else
          f"absent ({args.paper}/report_fragment.tex not found; run `make paper`)"))
    print("  analysis: " + ("included" if result.analysis else
          f"absent ({args.analysis}/report_fragment.tex not found; run `make analyze`)"))
    if pngs:
        print(f"  pages as PNG: {pngs[0].parent}/{result.pdf.stem}-page-*.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
