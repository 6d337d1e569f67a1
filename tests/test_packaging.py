"""The runtime stands alone: no SymPy import, self-contained C that compiles cleanly."""
import os
from pathlib import Path
import re
import shutil
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parent.parent


def test_import_quadcog_does_not_import_sympy():
    code = ("import sys, quadcog, numpy as np; m = quadcog.load(); "
            "m.dynamics(np.zeros(12), np.zeros(4), quadcog.default_parameters()); "
            "from quadcog import tour; "
            "print('sympy' in sys.modules)")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd="/",
                         env=env)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "False"


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")
def test_c_compiles_without_warnings(tmp_path):
    src = ROOT / "generated" / "c" / "quadcog_gen.c"
    includes = set(re.findall(r"#include\s*[<\"]([^>\"]+)", src.read_text()))
    assert includes <= {"math.h", "string.h", "stdlib.h", "stdio.h"}, includes
    res = subprocess.run(["cc", "-O2", "-shared", "-fPIC", "-Wall", str(src), "-o",
                          str(tmp_path / "lib.so")], capture_output=True, text=True)
    assert res.returncode == 0 and res.stderr == "", res.stderr


def test_header_declares_every_function():
    from quadcog.conventions import FUNCTIONS
    header = (ROOT / "generated" / "c" / "quadcog_gen.h").read_text()
    for name in FUNCTIONS:
        assert re.search(rf"\bint {name}\(const casadi_real\*\* arg", header), name
