"""Damaged manifests: every way of switching a check off, or of breaking the manifest's shape,
ends in a GeneratedFilesError that names the file and what to do."""
import json
import shutil

import pytest

import quadcog
from quadcog.model.generated_files import required_files, verify

GENERATED = quadcog.paths.generated_dir()


@pytest.fixture
def damaged(tmp_path):
    folder = tmp_path / "generated"
    shutil.copytree(GENERATED, folder)
    return folder


def _edit_manifest(folder, change):
    path = folder / "manifest.json"
    manifest = json.loads(path.read_text())
    change(manifest)
    path.write_text(json.dumps(manifest))


def _edit_c(folder):
    """An edited C file: one coefficient changed, so it would compute wrong numbers."""
    c = folder / "c" / "quadcog_gen.c"
    text = c.read_text()
    c.write_text(text.replace("+", "-", 1))


@pytest.mark.parametrize("change, message", [
    (lambda m: m["files"].pop("c/quadcog_gen.c"), r"quadcog_gen.c is not listed in .*manifest"),
    (lambda m: m.update(files={}), r"is not listed in .*manifest.json"),
    (lambda m: m["files"].pop("casadi/drift.casadi"), r"drift.casadi is not listed"),
    (lambda m: m["files"].pop("report.tex"), r"report.tex is not listed"),
])
def test_removing_an_entry_does_not_switch_the_check_off(damaged, change, message):
    _edit_c(damaged)
    _edit_manifest(damaged, change)
    with pytest.raises(quadcog.GeneratedFilesError, match=message + ".*make derive"):
        quadcog.load(damaged)


@pytest.mark.parametrize("change, message", [
    (lambda m: m.update(files=list(m["files"])), "expected an object 'files'.*got list"),
    (lambda m: m.update(functions=3), "expected an object 'functions'.*got int"),
    (lambda m: m.pop("files"), "expected an object 'files'.*got nothing"),
    (lambda m: m["files"].update({"../../etc/passwd": "0" * 64}),
     "'files' entry .* is not a relative path"),
    (lambda m: m["files"].update({"/etc/passwd": "0" * 64}),
     "'files' entry .* is not a relative path"),
    (lambda m: m["files"].update({"c/quadcog_gen.c": 42}),
     "'files' entry .* has no SHA-256.*got '42'"),
    (lambda m: m["files"].update({"c/quadcog_gen.c": "abc"}), "'files' entry .* has no SHA-256"),
])
def test_malformed_manifest(damaged, change, message):
    _edit_manifest(damaged, change)
    with pytest.raises(quadcog.GeneratedFilesError, match="manifest.json is corrupted: " + message):
        quadcog.load(damaged)


def test_corrupted_path_is_named_as_such(damaged):
    """A corrupted name in 'files' no longer reports only a missing file: the real file is
    named as unlisted."""
    def rename(m):
        m["files"]["c/quadcog_gXn.c"] = m["files"].pop("c/quadcog_gen.c")
    _edit_manifest(damaged, rename)
    with pytest.raises(quadcog.GeneratedFilesError,
                       match=r"c/quadcog_gen.c is not listed .*entry was removed"):
        quadcog.load(damaged)
    (damaged / "c" / "quadcog_gen.c").unlink()
    with pytest.raises(quadcog.GeneratedFilesError, match=r"quadcog_gen.c is not listed"):
        quadcog.load(damaged)


@pytest.mark.parametrize("content", [b"[" * 100000 + b"]" * 100000, b"\xff\xfe{}", b"[1, 2]",
                                     b"null"])
def test_unreadable_manifest_content(damaged, content):
    (damaged / "manifest.json").write_bytes(content)
    with pytest.raises(quadcog.GeneratedFilesError, match="manifest.json is corrupted"):
        quadcog.load(damaged)


def test_added_file_is_refused_and_shipped_folder_is_complete(damaged):
    verify(GENERATED)
    assert required_files() <= set(json.loads((GENERATED / "manifest.json").read_text())["files"])
    (damaged / "casadi" / "extra.casadi").write_text("planted")
    with pytest.raises(quadcog.GeneratedFilesError, match="extra.casadi is not listed"):
        quadcog.load(damaged)
