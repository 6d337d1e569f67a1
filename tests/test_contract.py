"""The contract of the generated functions is defined once (derive/contract.py) and the runtime
follows it through the manifest: in a temporary copy of derive/, quadcog/ and generated/, an
argument is renamed, an output renamed and a function added; after `python -m derive` the
copied runtime, unchanged, checks arguments by the new names and evaluates the new function."""
import json
import os
from pathlib import Path
import shutil
import subprocess
import sys

from conftest import background_dir, background_job, background_result
import pytest

ROOT = Path(__file__).resolve().parent.parent
SKIP = shutil.ignore_patterns("__pycache__")

EDITS = [
    ('"vartheta"', '"nu_dot_cmd"'),                       # an argument (a vector) renamed
    ('("xdot", lambda d: d.xdot)', '("x_dot", lambda d: d.xdot)'),     # an output renamed
    ('\nFUNCTIONS = (\n', '\nFUNCTIONS = (\n    FunctionSpec("weight", ("x", "p"), '
                          '(("f_G", lambda d: d.body.f_G),), "the weight in body axes"),\n'),
]

PROBE = """
import json, numpy as np, quadcog
from quadcog.model.conventions import rotation_matrix
m = quadcog.load()
x = np.array([0.1, 0.2, 0.3, 0.3, -0.2, 0.7, 0, 0, 0, 0, 0, 0])
p = quadcog.default_parameters(m=0.9)
weight = m.call("weight", x, p)
try:
    m.regressor(x, np.zeros(5), p)
    message = None
except quadcog.InputError as e:
    message = str(e)
print(json.dumps({"file": quadcog.__file__, "folder": str(m.folder),
                  "functions": m.functions, "weight": weight.tolist(),
                  "expected": (rotation_matrix(*x[3:6]).T @ [0, 0, -0.9 * 9.81]).tolist(),
                  "dynamics_out": m.casadi_function("dynamics").name_out(),
                  "message": message}))
"""


def _edit_and_derive():
    """Copy derive/, quadcog/ and generated/, apply EDITS, run `python -m derive` there:
    (folder, environment, the derive's CompletedProcess). Started in the background at
    collection (conftest.background_job): it is a subprocess and files only."""
    tmp_path = background_dir("contract")
    for part in ("derive", "quadcog", "generated"):
        shutil.copytree(ROOT / part, tmp_path / part, ignore=SKIP)
    spec = tmp_path / "derive" / "contract.py"
    text = spec.read_text()
    for old, new in EDITS:
        assert old in text, f"the test's edit no longer applies: {old!r}"
        text = text.replace(old, new)
    spec.write_text(text)
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(Path.home()),
           "PYTHONPATH": str(tmp_path), "CC": "no-such-compiler"}     # the VM: nothing to build
    res = subprocess.run([sys.executable, "-m", "derive", "--quiet"], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=300)
    return tmp_path, env, res


background_job("contract: edited derive", __file__, "test_runtime_follows_the_contract_in_derive",
               lambda: _edit_and_derive)


@pytest.mark.slow
def test_runtime_follows_the_contract_in_derive():
    tmp_path, env, res = background_result("contract: edited derive")
    assert res.returncode == 0, res.stderr
    manifest = json.loads((tmp_path / "generated" / "manifest.json").read_text())
    assert "nu_dot_cmd" in manifest["vectors"] and "weight" in manifest["functions"]
    res = subprocess.run([sys.executable, "-W", "ignore", "-c", PROBE], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert Path(out["file"]).is_relative_to(tmp_path) and Path(out["folder"]) == \
        tmp_path / "generated"
    assert out["functions"]["regressor"][0] == [["x", 12], ["nu_dot_cmd", 6], ["p", 14]]
    assert out["functions"]["weight"] == [[["x", 12], ["p", 14]], [["f_G", [3]]]]
    assert out["dynamics_out"] == ["x_dot"]
    assert out["message"] and out["message"].startswith("nu_dot_cmd: expected an array of shape (6,)")
    assert max(abs(a - b) for a, b in zip(out["weight"], out["expected"])) < 1e-12
