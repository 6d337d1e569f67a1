"""Bad input: untranslatable atoms, damaged generated/, wrong shapes and parameters."""
import dataclasses
import json
from pathlib import Path
import shutil

import numpy as np
import pytest
import sympy as sp

from derive import pipeline
from derive.__main__ import main as derive_main
from derive.manifest import sha256
from derive.to_casadi import UnsupportedAtomError
import quadcog
from quadcog.model.generated_files import read_manifest

ROOT = Path(__file__).resolve().parent.parent
GENERATED = ROOT / "generated"


def _tree_hashes(folder):
    return {p.relative_to(folder).as_posix(): sha256(p) for p in folder.rglob("*") if p.is_file()}


@pytest.mark.parametrize("atom", [sp.sign(sp.Symbol("phi", real=True)),
                                  sp.Piecewise((1, sp.Symbol("z", real=True) > 0), (0, True)),
                                  sp.Symbol("stray")])
def test_untranslatable_atom_stops_derive(monkeypatch, tmp_path, capsys, atom, derived):
    target = tmp_path / "generated"
    shutil.copytree(GENERATED, target)
    before = _tree_hashes(target)

    def tampered(log=None):
        """The suite's derivation (derived once) with the atom in b, on copies: what
        derive_model would return if the atom were in the derivation."""
        outputs = dataclasses.replace(derived.outputs,
                                      b=derived.outputs.b + sp.Matrix([atom, 0, 0, 0]))
        return dataclasses.replace(derived, outputs=outputs)

    monkeypatch.setattr(pipeline, "derive_model", tampered)
    assert derive_main(["--out", str(target), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "'drift'" in err and str(atom) in err, err
    assert _tree_hashes(target) == before, "generated/ was modified by a failed derive"
    assert not list(tmp_path.glob(".generated-*")), "temporary folder left behind"
    with pytest.raises(UnsupportedAtomError):
        pipeline.generate(tmp_path / "other", echo=None)


@pytest.fixture
def damaged(tmp_path):
    folder = tmp_path / "generated"
    shutil.copytree(GENERATED, folder)
    return folder


@pytest.mark.parametrize("rel", ["c/quadcog_gen.c", "casadi/drift.casadi", "manifest.json"])
def test_missing_generated_file(damaged, rel):
    (damaged / rel).unlink()
    with pytest.raises(quadcog.GeneratedFilesError, match="make derive") as e:
        quadcog.load(damaged)
    assert Path(rel).name in str(e.value)


@pytest.mark.parametrize("rel", ["c/quadcog_gen.c", "casadi/dynamics.casadi", "report.tex"])
def test_corrupted_generated_file(damaged, rel):
    path = damaged / rel
    path.write_bytes(path.read_bytes()[:-50] + b"garbage")
    with pytest.raises(quadcog.GeneratedFilesError, match="make derive") as e:
        quadcog.load(damaged)
    assert Path(rel).name in str(e.value)


def test_corrupted_manifest(damaged):
    (damaged / "manifest.json").write_text("{not json")
    with pytest.raises(quadcog.GeneratedFilesError, match="manifest.json.*make derive"):
        quadcog.load(damaged)


def test_unloadable_casadi_file_with_matching_hash(damaged):
    """Even a file whose hash was updated gives a quadcog error, not a CasADi traceback."""
    rel = "casadi/drift.casadi"
    (damaged / rel).write_text("not a casadi function")
    manifest = read_manifest(damaged)
    manifest["files"][rel] = sha256(damaged / rel)
    (damaged / "manifest.json").write_text(json.dumps(manifest))
    model = quadcog.load(damaged)
    with pytest.raises(quadcog.GeneratedFilesError, match="drift.casadi.*make derive"):
        model.casadi_function("drift")


def test_wrong_shapes_and_values(model):
    p = quadcog.default_parameters()
    with pytest.raises(quadcog.InputError, match=r"x: expected an array of shape \(12,\), got shape \(3,\)"):
        model.dynamics(np.zeros(3), np.zeros(4), p)
    with pytest.raises(quadcog.InputError, match=r"U\[2\]: expected a finite number, got nan"):
        model.dynamics(np.zeros(12), [1, 0, np.nan, 0], p)
    with pytest.raises(quadcog.InputError, match=r"p: expected an array of shape \(14,\)"):
        model.mass_matrix(np.ones(13))
    with pytest.raises(quadcog.InputError, match="out for M must have shape"):
        model.mass_matrix(p, out=np.zeros((5, 5)))


@pytest.mark.parametrize("override, message", [
    ({"m": -1.0}, "m = -1.0 must be > 0"),
    ({"Izz": 0.0}, "Izz = 0.0 must be > 0"),
    ({"c_x": -0.1}, "c_x = -0.1 must be >= 0"),
    ({"z_G": 0.5}, "inertia about the CoG keeps only"),
])
def test_inadmissible_parameters(model, override, message):
    p = quadcog.HUMMINGBIRD.parameters()
    p[quadcog.PARAM_NAMES.index(next(iter(override)))] = next(iter(override.values()))
    with pytest.raises(quadcog.ParameterError, match=message):
        model.mass_matrix(p)
    with pytest.raises(quadcog.ParameterError, match=message):
        quadcog.default_parameters(**override)


def test_unknown_parameter_name():
    with pytest.raises(quadcog.InputError, match="unknown parameter 'mass'"):
        quadcog.default_parameters(mass=1.0)


def test_out_argument_reuses_memory(model):
    p, x = quadcog.default_parameters(), np.zeros(12)
    out = np.empty(12)
    res = model.dynamics(x, [6.0, 0, 0, 0], p, out=out)
    assert res is out and out[8] == pytest.approx(6.0 / p[0] - p[1])
    A, B = np.empty((12, 12)), np.empty((12, 4))
    lin = model.linearization(x, [6.0, 0, 0, 0], p, out=(A, B))
    assert lin.A is A and lin.B is B and B[8, 0] == pytest.approx(1 / p[0])
