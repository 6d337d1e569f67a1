"""ruff (settings in pyproject.toml) over the code: unused or missing names, unsorted imports,
style. A wrong implementation it catches: a name used but never imported (F821), an import left
behind by a move (F401), code that shadows or redefines a name (F811)."""
from pathlib import Path
import shutil
import subprocess
import sys

ROOT = Path(__file__).resolve().parents[1]


def _ruff():
    exe = Path(sys.executable).with_name("ruff")
    return str(exe) if exe.exists() else shutil.which("ruff")


def test_ruff_is_clean():
    assert _ruff(), "ruff is missing: it comes with the dev extra (pip install -e '.[dev]')"
    res = subprocess.run([_ruff(), "check", "--no-cache", "quadcog", "derive", "report",
                          "bench", "tests"], cwd=ROOT, capture_output=True, text=True)
    assert res.returncode == 0, res.stdout + res.stderr
