"""generated/ is what derive/ produces, byte for byte, whatever the hash seed; the commands
``python -m derive --if-stale`` and ``--check`` end to end. One derivation in all: the
``--if-stale`` run of a stale copy (in the background, from collection on), whose output is then
what ``--check`` compares (its own derivation replaced by a copy of that one)."""
import json
import os
from pathlib import Path
import shutil
import subprocess
import sys

from conftest import background_dir, background_job, background_result
import pytest

from derive.compare import diff_trees, is_foreign
from derive.manifest import derive_sources, sha256

ROOT = Path(__file__).resolve().parent.parent
GENERATED = ROOT / "generated"


def _derive(*args, seed=1):
    env = dict(os.environ, PYTHONHASHSEED=str(seed))
    return subprocess.run([sys.executable, "-m", "derive", *map(str, args)],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)


def _stale_copy(folder):
    """A copy of generated/ with one changed line in report.tex."""
    shutil.copytree(GENERATED, folder)
    tex = folder / "report.tex"
    tex.write_text(tex.read_text().replace("Kinematics", "Kinematix", 1))
    return folder


def test_if_stale_skips_a_fresh_folder(tmp_path):
    fresh = tmp_path / "gen"
    shutil.copytree(GENERATED, fresh)
    before = {p: p.stat().st_mtime_ns for p in fresh.rglob("*") if p.is_file()}
    res = _derive("--if-stale", "--out", fresh)
    assert res.returncode == 0 and "is up to date" in res.stdout, res.stderr
    assert {p: p.stat().st_mtime_ns for p in fresh.rglob("*") if p.is_file()} == before


def _rederive():
    """The one derivation: ``--if-stale`` of a stale copy, under another hash seed than the
    default (generated/ was written under a random one)."""
    stale = _stale_copy(background_dir("golden") / "gen")
    return lambda: (_derive("--if-stale", "--out", stale, "--quiet", seed=4242), stale)


background_job("golden: derive a stale copy", __file__, "rederived", _rederive, lane="derive")


@pytest.fixture(scope="module")
def rederived():
    """(the finished --if-stale run, the folder it rewrote)."""
    return background_result("golden: derive a stale copy")


@pytest.mark.slow              # one derivation (SymPy), about 9 s of CPU
def test_if_stale_regenerates_to_generated(rederived):
    """An edited file makes the folder stale; --if-stale derives it again, and the result is
    generated/ byte for byte: generated/ is fresh, whatever the hash seed."""
    res, folder = rederived
    assert res.returncode == 0, res.stderr
    diff = diff_trees(GENERATED, folder)
    assert not diff, f"generated/ is stale; run `make derive`. Diff:\n{diff}"


@pytest.mark.slow
def test_check_reports_a_stale_file_with_a_diff(rederived, tmp_path, monkeypatch, capsys):
    """--check writes nothing, exits 1 and shows a unified diff of the one changed line and
    nothing else. Its derivation is the one above (copied in place of a second run), so this
    checks what --check does with a derivation: the comparison, the message, no writes."""
    import derive.__main__ as cli
    res, folder = rederived
    assert res.returncode == 0, res.stderr
    derived = []

    def generate(out, echo):
        derived.append(out)
        shutil.copytree(folder, out, dirs_exist_ok=True)

    monkeypatch.setattr(cli, "generate", generate)
    stale = _stale_copy(tmp_path / "gen")
    before = (stale / "report.tex").read_bytes()
    assert cli.main(["--check", "--out", str(stale), "--quiet"]) == 1
    assert len(derived) == 1 and Path(derived[0]) != stale     # derived elsewhere
    diff = capsys.readouterr().err
    assert "is stale; run `make derive`" in diff
    assert "-\\section{Kinematix}" in diff and "+\\section{Kinematics}" in diff
    changed = [line for line in diff.splitlines()
               if line.startswith(("+", "-")) and not line.startswith(("+++", "---"))]
    assert len(changed) == 2, diff
    assert (stale / "report.tex").read_bytes() == before


def test_headers():
    for path in GENERATED.rglob("*"):
        if not path.is_file() or path.suffix == ".casadi" or is_foreign(path.relative_to(GENERATED)):
            continue     # .casadi is CasADi's own serialization: a header would break it
        first = path.read_text().splitlines()[0]
        if path.suffix == ".json":
            assert json.loads(path.read_text())["_comment"].startswith("DO NOT EDIT"), path
        else:
            assert "DO NOT EDIT" in first and "make derive" in first, (path, first)


def test_manifest_hashes_and_versions():
    import casadi
    import sympy
    manifest = json.loads((GENERATED / "manifest.json").read_text())
    files = {p.relative_to(GENERATED).as_posix() for p in GENERATED.rglob("*")
              if p.is_file() and p.name != "manifest.json" and not is_foreign(p.relative_to(GENERATED))}
    assert set(manifest["files"]) == files
    for rel, digest in manifest["files"].items():
        assert sha256(GENERATED / rel) == digest, rel
    assert manifest["sources"] == derive_sources(), "derive/ changed since generated/; make derive"
    assert manifest["versions"]["sympy"] == sympy.__version__
    assert manifest["versions"]["casadi"] == casadi.__version__
    for name, info in manifest["functions"].items():
        assert info["instructions"] > 0, name


def test_staleness_follows_exactly_the_sources_of_generated(tmp_path):
    """Editing the PDF builder, the README, a test or derive's command line leaves generated/
    fresh; editing a module of the derivation or the report template makes it stale."""
    from derive.manifest import is_fresh, source_files
    for part in ("derive", "generated", "report", "tests"):
        shutil.copytree(ROOT / part, tmp_path / part,
                        ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "README.md", tmp_path / "README.md")
    derive_dir, out = tmp_path / "derive", tmp_path / "generated"
    assert is_fresh(out, derive_dir)
    harmless = ["report/pdf.py", "README.md", "tests/test_golden.py", "derive/__main__.py"]
    for rel in harmless:
        with open(tmp_path / rel, "a") as fh:
            fh.write("\n# edited\n")
        assert is_fresh(out, derive_dir), f"editing {rel} made generated/ stale"
    for rel in ("derive/newton_euler.py", "derive/templates/report.tex", "derive/contract.py"):
        path = tmp_path / rel
        original = path.read_bytes()
        path.write_bytes(original + b"\n")
        assert not is_fresh(out, derive_dir), f"editing {rel} did not make generated/ stale"
        path.write_bytes(original)
        assert is_fresh(out, derive_dir)
    # exactly: every module that derive/pipeline.py imports, and nothing derive does not run
    names = {p.name for p in source_files(derive_dir)}
    assert {"pipeline.py", "newton_euler.py", "export.py", "latex.py", "report.tex"} <= names
    assert not names & {"__main__.py", "__init__.py"}
