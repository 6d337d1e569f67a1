"""The report as a PDF (report/pdf.py) and its verification table (report/verify.py, from
the identities of report/identities.py).

The PDF tests need pdflatex (Debian: texlive-latex-base, texlive-latex-recommended); they are
skipped without it, and CI installs it. They fail on a LaTeX error and on an overfull box
wider than 10 pt.
"""
from pathlib import Path
import re
import shutil
import struct
import subprocess
import sys
import zlib

import pytest

from report import identities, verify
from report import pdf as build_report

ROOT = Path(__file__).resolve().parent.parent
REPORT = ROOT / "generated" / "report.tex"

needs_pdflatex = pytest.mark.skipif(
    shutil.which("pdflatex") is None,
    reason="pdflatex is not installed (apt-get install --no-install-recommends "
           "texlive-latex-base texlive-latex-recommended); CI installs it")

_ROW = re.compile(r"^(?P<identity>.+?) & (?P<points>\d+) & (?P<value>\$[^$]*\$) & "
                  r"(?P<bound>.+?) & (?P<verdict>ok|\\textbf\{FAILED\}) \\\\$")


def _number(tex):
    """'$0$' or '$1.2\\times10^{-13}$' (or '$10^{-12}$') as a float."""
    tex = tex.strip("$ ")
    mo = re.fullmatch(r"(?:(?P<m>-?[0-9.]+)(?:\\times)?)?(?:10\^\{(?P<e>-?\d+)\})?", tex)
    assert mo and (mo.group("m") or mo.group("e")), f"not a number: {tex!r}"
    return float(mo.group("m") or 1) * 10.0 ** int(mo.group("e") or 0)


def parse_table(text):
    """The rows of a verification fragment: (identity, points, value, bound, ok)."""
    rows = []
    for line in text.splitlines():
        mo = _ROW.match(line)
        if mo:
            bound = mo.group("bound")
            rows.append((mo.group("identity"), int(mo.group("points")),
                         _number(mo.group("value")),
                         _number(bound.replace(r"$\le$", "").replace(">", "")),
                         mo.group("verdict") == "ok"))
    return rows


def _png(path, width=6, height=4):
    """A tiny RGB PNG, written without any imaging library."""
    def chunk(tag, data):
        return (struct.pack(">I", len(data)) + tag + data
                + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF))
    raw = b"".join(b"\x00" + bytes([30, 90, 200]) * width for _ in range(height))
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"\x89PNG\r\n\x1a\n"
                     + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
                     + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def _fake_paper(folder):
    """What `quadcog paper` writes: a fragment with a section, a table and figures."""
    _png(folder / "fig6" / "flight.png")
    (folder / "report_fragment.tex").write_text(
        "\\section{The paper's claims, reproduced}\n"
        "\\begin{center}\\small\\begin{tabular}{p{1.4cm}p{4.4cm}rr}\n"
        "\\toprule figure & claim & tail RMS (m) & holds \\\\ \\midrule\n"
        "Fig.~6 & adaptive FL stabilizes a CoG change & 0.012 & yes \\\\\n"
        "\\bottomrule\\end{tabular}\\end{center}\n"
        "\\begin{figure}[p]\\centering\\includegraphics[width=0.5\\linewidth]"
        "{paper/fig6/flight.png}\\caption{Fig.~6.}\\end{figure}\n")


def _pdf_text(pdf):
    if shutil.which("pdftotext") is None:
        return None
    return subprocess.run(["pdftotext", str(pdf), "-"], capture_output=True, text=True,
                          check=True).stdout


# --- the verification table ----------------------------------------------------------------------

@pytest.fixture(scope="module")
def verification_fragment(tmp_path_factory):
    """`python -m report.verify` run for real, with few points."""
    out = tmp_path_factory.mktemp("verify") / "verification.tex"
    res = subprocess.run([sys.executable, "-m", "report.verify", "--out", str(out),
                          "--points", "12", "--seed", "7"], cwd=ROOT, capture_output=True,
                         text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    return out.read_text()


def test_verification_table_comes_from_a_run(verification_fragment):
    rows = parse_table(verification_fragment)
    skipped = verification_fragment.count("skipped: no C compiler")      # C vs VM, no compiler
    assert len(rows) + skipped == len(identities.CHECKS), verification_fragment
    assert "at 12 random admissible points (seed 7)" in verification_fragment
    for identity, points, value, bound, ok in rows:
        assert points == 12, identity
        assert ok, identity
        assert value == value and value >= 0, identity          # a real, finite float
    errors = [(i, v, b) for i, _, v, b, _ in rows if "eigenvalue" not in i]
    assert all(v <= b for _, v, b in errors), errors
    assert any(v > 0 for _, v, _ in errors), "every error exactly zero: not a real run?"
    (eig,) = [v for i, _, v, _, _ in rows if "eigenvalue" in i]
    assert eig > 0


def test_verification_values_are_the_run_values(model):
    """The table prints what run() measured (rounded), and marks a failure."""
    results = identities.run(5, seed=3, model=model)
    assert all(r.ok for r in results), [(r.check.tex, r.value) for r in results if not r.ok]
    text = verify.table(results, 3, model.backend, 0.1)
    rows = parse_table(text)
    measured = [r for r in results if not r.skipped]
    assert len(rows) == len(measured)
    for r, (_, _, value, _, _) in zip(measured, rows):
        assert value == pytest.approx(r.value, rel=0.06, abs=1e-300), r.check.tex
    bad = identities.Result(identities.CHECKS[0], 5, 1.0, False)
    assert r"\textbf{FAILED}" in verify.table([bad], 3, "c", 0.1)


def test_verification_figures_for_the_docs(model):
    """verification.json (what docs/tour/report.md quotes, through its tracked copy
    docs/measured/verification.json) holds each identity's error, the largest of the "max"
    kind and the machine; the published copy lists the identities there are now."""
    import json
    results = identities.run(5, seed=3, model=model)
    data = verify.summary(results, 5, 3, 0.1)
    errors = [r.value for r in results if not r.skipped and r.check.kind == "max"]
    assert data["largest_error"] == max(errors) > 0
    assert [i["identity"] for i in data["identities"]] == [c.tex for c in identities.CHECKS]
    assert data["n_identities"] == len(identities.CHECKS) and "cores" in data["machine"]
    published = json.loads((ROOT / "docs" / "measured" / "verification.json").read_text())
    assert [i["identity"] for i in published["identities"]] == [c.tex for c in identities.CHECKS], (
        "report/identities.py changed: make report && python bench/publish.py verify")


def test_generated_report_has_no_run_numbers():
    """generated/report.tex is deterministic: the run's results are \\input from files."""
    text = REPORT.read_text()
    assert r"\IfFileExists{verification.tex}{\input{verification.tex}}" in text
    assert r"\IfFileExists{paper/report_fragment.tex}" in text
    assert r"\IfFileExists{analysis/report_fragment.tex}" in text
    assert r"\input{paper/report_fragment.tex}" in text
    assert "make report" in text and "make paper" in text
    assert "UTC" not in text and "seed" not in text


# --- the log parser, and errors that need no pdflatex -------------------------------------------

LOG = r"""(./report.tex
LaTeX2e <2022-11-01>
(./verification.tex
Overfull \hbox (12.3pt too wide) in paragraph at lines 3--4
[]\OT1/cmr/m/n/10 a wide (line
 []

)
Overfull \hbox (4.0pt too wide) detected at line 161
[]
 []

(./paper/report_fragment.tex
Overfull \hbox (25.5pt too wide) in alignment at lines 7--9
 [] []
)
Output written on report.pdf (6 pages, 1234 bytes).
"""


def test_overfull_parser():
    found = build_report.parse_overfull(LOG)
    assert [(o.points, o.file, o.lines) for o in found] == [
        (12.3, "./verification.tex", (3, 4)), (4.0, "./report.tex", (161, 161)),
        (25.5, "./paper/report_fragment.tex", (7, 9))]


def test_refuses_to_build_into_generated(tmp_path):
    with pytest.raises(build_report.BuildError, match="refusing to build into"):
        build_report.build(REPORT, ROOT / "generated" / "pdf", paper=None)
    assert not (ROOT / "generated" / "pdf").exists()


def test_missing_pdflatex_says_how_to_install(tmp_path, monkeypatch):
    monkeypatch.setattr(build_report, "find_pdflatex", lambda: None)
    with pytest.raises(build_report.BuildError) as e:
        build_report.build(REPORT, tmp_path / "r", paper=None)
    assert "apt-get install" in str(e.value) and "texlive-latex-base" in str(e.value)
    assert build_report.main(["--out", str(tmp_path / "r"), "--paper", str(tmp_path)]) == 1


# --- the PDF --------------------------------------------------------------------------------------

@needs_pdflatex
def test_report_pdf_builds_without_run_results(tmp_path):
    result = build_report.build(REPORT, tmp_path / "report", paper=None)
    assert result.pdf.is_file() and result.pages >= 3
    assert result.pages <= 12, "the report should stay a few pages"
    assert result.largest_overfull <= build_report.MAX_OVERFULL
    assert not result.verification and not result.paper
    text = _pdf_text(result.pdf)
    if text is not None:
        assert "make report" in text and "make paper" in text
        assert "Where the paper" in text and "Zero dynamics" in text


@needs_pdflatex
def test_report_pdf_with_verification_and_paper(tmp_path, verification_fragment):
    build = tmp_path / "report"
    build.mkdir()
    (build / "verification.tex").write_text(verification_fragment)
    paper = tmp_path / "paper"
    _fake_paper(paper)
    result = build_report.build(REPORT, build, paper=paper)
    assert result.verification and result.paper
    assert (build / "paper" / "fig6" / "flight.png").is_file()
    assert result.largest_overfull <= build_report.MAX_OVERFULL, result.overfull
    text = _pdf_text(result.pdf)
    if text is not None:
        assert "largest error" in text and "claims, reproduced" in text
        assert "run make report" not in text.replace("\n", " ")


@needs_pdflatex
def test_build_fails_on_overfull_box(tmp_path):
    tex = tmp_path / "wide.tex"
    tex.write_text("\\documentclass{article}\\begin{document}\n"
                   "\\noindent\\mbox{a very wide box \\rule{1.2\\textwidth}{1pt}}\n\n"
                   "\\end{document}\n")
    with pytest.raises(build_report.BuildError) as e:
        build_report.build(tex, tmp_path / "out", paper=None)
    message = str(e.value)
    assert "overfull box" in message and "pt too wide" in message
    assert "a very wide box" in message, message          # the offending source line


@needs_pdflatex
def test_build_fails_on_latex_error(tmp_path):
    tex = tmp_path / "broken.tex"
    tex.write_text("\\documentclass{article}\\begin{document}\n\\nosuchcommand\n"
                   "\\end{document}\n")
    with pytest.raises(build_report.BuildError, match="Undefined control sequence"):
        build_report.build(tex, tmp_path / "out", paper=None)


@needs_pdflatex
def test_command_line_build(tmp_path):
    out = tmp_path / "report"
    res = subprocess.run([sys.executable, "-m", "report.pdf", "--out", str(out),
                          "--paper", str(tmp_path / "no-paper")], cwd=ROOT,
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    assert (out / "report.pdf").is_file() and "largest overfull box" in res.stdout
