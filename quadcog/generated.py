"""Read generated/: the manifest, integrity of every file, the CasADi functions."""
import hashlib
import json
from pathlib import Path

import casadi as ca

from .conventions import FUNCTIONS
from .errors import GeneratedFilesError
from .paths import generated_dir, shipped_generated_dir

MANIFEST = "manifest.json"
C_SOURCE = "c/quadcog_gen.c"


def _fix(folder):
    """What to do about a bad generated folder: reinstall a package, re-derive a checkout."""
    if Path(folder).resolve() == shipped_generated_dir().resolve():
        return "reinstall quadcog (pip install --force-reinstall quadcog)"
    return "run `make derive` to regenerate it"


def _sha256(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


def read_manifest(folder=None):
    """The manifest as a dict; GeneratedFilesError when missing or unreadable."""
    folder = Path(folder or generated_dir())
    path = folder / MANIFEST
    if not path.is_file():
        raise GeneratedFilesError(f"{path} is missing; {_fix(folder)}")
    try:
        manifest = json.loads(path.read_text())
        manifest["files"], manifest["functions"]
    except (ValueError, KeyError, TypeError) as e:
        raise GeneratedFilesError(f"{path} is corrupted ({e}); {_fix(folder)}") from None
    return manifest


def verify(folder=None, only=None):
    """Check the SHA-256 of every generated file (or of the names in ``only``)."""
    folder = Path(folder or generated_dir())
    manifest = read_manifest(folder)
    missing = [f for f in FUNCTIONS if f not in manifest["functions"]]
    if missing:
        raise GeneratedFilesError(
            f"{folder / MANIFEST} lists no function {missing[0]!r}; {_fix(folder)}")
    for rel, digest in manifest["files"].items():
        if only is not None and rel not in only:
            continue
        path = folder / rel
        if not path.is_file():
            raise GeneratedFilesError(f"{path} is missing; {_fix(folder)}")
        if _sha256(path) != digest:
            raise GeneratedFilesError(
                f"{path} does not match its SHA-256 in {MANIFEST} (edited or corrupted); {_fix(folder)}")
    return manifest


def load_casadi_function(name, folder=None):
    """One generated function through CasADi's serializer (checked against the manifest)."""
    folder = Path(folder or generated_dir())
    rel = f"casadi/{name}.casadi"
    verify(folder, only={rel})
    try:
        return ca.Function.load(str(folder / rel))
    except RuntimeError as e:
        raise GeneratedFilesError(f"{folder / rel} cannot be loaded ({str(e).splitlines()[-1]}); "
                                  f"{_fix(folder)}") from None
