"""generated/ is what derive/ produces, byte for byte, whatever the hash seed."""
import json
import os
import shutil
from pathlib import Path
import subprocess
import sys

import pytest

from conftest import background_dir, background_job, background_result
from derive.compare import diff_trees, is_foreign
from derive.manifest import derive_sources, sha256

ROOT = Path(__file__).resolve().parent.parent
GENERATED = ROOT / "generated"


def _derive(out, seed):
    """Start `python -m derive --out out` under hash seed ``seed``; returns the process."""
    env = dict(os.environ, PYTHONHASHSEED=str(seed))
    return subprocess.Popen([sys.executable, "-m", "derive", "--out", str(out), "--quiet"],
                            cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)


def _derive_twice():
    """Two derivations at once (independent processes), under hash seeds 1 and 4242; started
    in the background at collection (conftest.background_job)."""
    a, b = background_dir("derive-seed-1"), background_dir("derive-seed-4242")
    runs = [_derive(a, 1), _derive(b, 4242)]
    for proc in runs:
        _, err = proc.communicate(timeout=300)
        assert proc.returncode == 0, err
    return a, b


background_job("golden: two derivations", __file__, "fresh", lambda: _derive_twice)


@pytest.fixture(scope="module")
def fresh():
    return background_result("golden: two derivations")


@pytest.mark.slow
def test_generated_is_fresh(fresh):
    diff = diff_trees(GENERATED, fresh[0])
    assert not diff, f"generated/ is stale; run `make derive`. Diff:\n{diff}"


@pytest.mark.slow
def test_reproducible_across_hash_seeds(fresh):
    diff = diff_trees(fresh[0], fresh[1])
    assert not diff, f"two derivations differ:\n{diff}"


@pytest.mark.slow
def test_diff_is_readable(tmp_path, fresh):
    """A stale file shows up as a unified diff naming the file and the changed line."""
    import shutil
    stale = tmp_path / "gen"
    shutil.copytree(fresh[0], stale)
    tex = stale / "report.tex"
    tex.write_text(tex.read_text().replace("Kinematics", "Kinematix", 1))
    diff = diff_trees(stale, fresh[0])
    assert "report.tex" in diff and "-\\section{Kinematix}" in diff and "+\\section{Kinematics}" in diff


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
    harmless = ["report/build.py", "README.md", "tests/test_golden.py", "derive/__main__.py"]
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
    assert {"pipeline.py", "newton_euler.py", "export.py", "report.py", "report.tex"} <= names
    assert not names & {"__main__.py", "__init__.py"}
