"""mypy (settings in pyproject.toml) over the runtime package: the type hints of the public API
are checked against the code, so a hint that lies (a function annotated to return an array that
returns None on a path, an argument passed where another type is declared) fails the suite."""
from pathlib import Path
import shutil
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _mypy():
    exe = Path(sys.executable).with_name("mypy")
    return str(exe) if exe.exists() else shutil.which("mypy")


@pytest.mark.slow
def test_mypy_is_clean(tmp_path):
    assert _mypy(), "mypy is missing: it comes with the dev extra (pip install -e '.[dev]')"
    res = subprocess.run([_mypy(), "--cache-dir", str(tmp_path / "cache"), "quadcog"],
                         cwd=ROOT, capture_output=True, text=True)
    assert res.returncode == 0, res.stdout[-6000:] + res.stderr[-2000:]
