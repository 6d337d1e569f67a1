"""mypy (settings in pyproject.toml) over the runtime package: the type hints of the public API
are checked against the code, so a hint that lies (a function annotated to return an array that
returns None on a path, an argument passed where another type is declared) fails the suite."""
from pathlib import Path
import shutil
import subprocess
import sys

from conftest import background_dir, background_job, background_result
import pytest

ROOT = Path(__file__).resolve().parents[1]


def _mypy():
    exe = Path(sys.executable).with_name("mypy")
    return str(exe) if exe.exists() else shutil.which("mypy")


def _run_mypy():
    """mypy, a subprocess started at collection on a lane of its own (conftest.background_job)."""
    folder = background_dir("mypy")
    return lambda: subprocess.run([_mypy(), "--cache-dir", str(folder / "cache"), "quadcog"],
                                  cwd=ROOT, capture_output=True, text=True)


background_job("mypy", __file__, "test_mypy_is_clean", _run_mypy, lane="tools")


@pytest.mark.slow
def test_mypy_is_clean():
    assert _mypy(), "mypy is missing: it comes with the dev extra (pip install -e '.[dev]')"
    res = background_result("mypy")
    assert res.returncode == 0, res.stdout[-6000:] + res.stderr[-2000:]
