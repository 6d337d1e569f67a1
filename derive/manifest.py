"""generated/manifest.json: versions, hashes of every generated file and derive/ source,
and the instruction count of every exported function."""
import hashlib
import json
from pathlib import Path
import platform

import casadi
import sympy

from .compare import is_foreign
from .headers import NOTICE

DERIVE_DIR = Path(__file__).parent
MANIFEST = "manifest.json"


def sha256(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def derive_sources():
    """Every file the derivation is made from, relative to the repository root."""
    files = sorted(p for p in DERIVE_DIR.rglob("*")
                   if p.is_file() and "__pycache__" not in p.parts)
    return {p.relative_to(DERIVE_DIR.parent).as_posix(): sha256(p) for p in files}


def build_manifest(out_dir, functions):
    out_dir = Path(out_dir)
    files = sorted(p for p in out_dir.rglob("*") if p.is_file() and p.name != MANIFEST
                   and not is_foreign(p.relative_to(out_dir)))
    return {
        "_comment": NOTICE,
        "versions": {
            "python": ".".join(platform.python_version_tuple()[:2]),
            "sympy": sympy.__version__,
            "casadi": casadi.__version__,
        },
        "functions": {name: {"inputs": fn.name_in(), "outputs": fn.name_out(),
                             "instructions": fn.n_instructions()}
                      for name, fn in functions.items()},
        "files": {p.relative_to(out_dir).as_posix(): sha256(p) for p in files},
        "sources": derive_sources(),
    }


def write_manifest(out_dir, functions):
    text = json.dumps(build_manifest(out_dir, functions), indent=2) + "\n"
    (Path(out_dir) / MANIFEST).write_text(text)


def is_fresh(out_dir):
    """True when the manifest's source hashes equal derive/ now and every file matches."""
    path = Path(out_dir) / MANIFEST
    try:
        manifest = json.loads(path.read_text())
        files_ok = all(sha256(Path(out_dir) / rel) == digest
                       for rel, digest in manifest["files"].items())
    except (OSError, ValueError, KeyError):
        return False
    return files_ok and manifest.get("sources") == derive_sources()
