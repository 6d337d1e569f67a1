"""The runtime stands alone: no SymPy import, self-contained C that compiles cleanly."""
import json
import os
from pathlib import Path
import re
import shutil
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parent.parent


HEAVY = ("sympy", "scipy.signal", "matplotlib")


def test_import_quadcog_is_light():
    """`import quadcog` imports none of SymPy, scipy.signal, matplotlib (each is imported
    where it is used); loading the model and flying never imports SymPy. Run from a foreign
    directory without PYTHONPATH: the test environment's editable install must work there
    and read the checkout's generated/."""
    code = ("import json, sys, numpy as np; import quadcog; "
            f"after_import = [m for m in {HEAVY!r} if m in sys.modules]; "
            "m = quadcog.load(); m.dynamics(np.zeros(12), np.zeros(4), quadcog.default_parameters()); "
            "from quadcog.studies import tour; quadcog.simulate(quadcog.AdaptiveFeedbackLinearization(), "
            "duration=0.01); "
            "print(json.dumps([after_import, 'sympy' in sys.modules, quadcog.__file__, "
            "str(m.folder)]))")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd="/",
                         env=env)
    assert res.returncode == 0, res.stderr
    after_import, sympy_after_use, where, folder = json.loads(res.stdout)
    assert after_import == [], f"import quadcog imported {after_import}"
    assert not sympy_after_use
    assert Path(where) == ROOT / "quadcog" / "__init__.py"
    assert Path(folder) == ROOT / "generated"


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")
def test_c_compiles_without_warnings(tmp_path):
    src = ROOT / "generated" / "c" / "quadcog_gen.c"
    includes = set(re.findall(r"#include\s*[<\"]([^>\"]+)", src.read_text()))
    assert includes <= {"math.h", "string.h", "stdlib.h", "stdio.h"}, includes
    res = subprocess.run(["cc", "-O2", "-shared", "-fPIC", "-Wall", str(src), "-o",
                          str(tmp_path / "lib.so")], capture_output=True, text=True)
    assert res.returncode == 0 and res.stderr == "", res.stderr


def test_header_declares_every_function():
    from quadcog.model.conventions import FUNCTIONS
    header = (ROOT / "generated" / "c" / "quadcog_gen.h").read_text()
    for name in FUNCTIONS:
        assert re.search(rf"\bint {name}\(const casadi_real\*\* arg", header), name
