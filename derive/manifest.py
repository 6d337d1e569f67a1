"""generated/manifest.json: versions, the contract of the generated functions (which the
runtime reads), the hash of every generated file and of every source that shapes them, and the
instruction count of every exported function.

The sources are exactly the modules that ``derive.pipeline`` imports, directly or through each
other, plus the templates: editing anything else (the PDF builder, the README, a test, the
command line of ``python -m derive``) never makes generated/ stale.
"""
import ast
import hashlib
import json
from pathlib import Path
import platform

import casadi
import sympy

from derive.compare import is_foreign
from derive.contract import describe
from derive.headers import NOTICE

DERIVE_DIR = Path(__file__).parent
MANIFEST = "manifest.json"
ENTRY = "pipeline"           # the module whose import closure writes generated/


def sha256(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _local_imports(path):
    """Names of the derive modules that the module at ``path`` imports (``from derive.x
    import ...``, ``from derive import x`` or their relative forms)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if not isinstance(node, ast.ImportFrom):
            continue
        if node.level == 1:
            module = node.module
        elif node.level == 0 and node.module and node.module.split(".")[0] == "derive":
            module = node.module.partition(".")[2]
        else:
            continue
        if module:
            names.add(module.split(".")[0])
        else:
            names.update(alias.name for alias in node.names)
    return names


def source_files(derive_dir=DERIVE_DIR):
    """The files whose content shapes generated/: the import closure of ``pipeline`` inside
    ``derive_dir`` and everything under its templates/ folder; sorted paths."""
    derive_dir = Path(derive_dir)
    seen, todo = set(), [ENTRY]
    while todo:
        name = todo.pop()
        path = derive_dir / f"{name}.py"
        if name in seen or not path.is_file():
            continue
        seen.add(name)
        todo.extend(_local_imports(path))
    files = [derive_dir / f"{name}.py" for name in seen]
    files += [p for p in (derive_dir / "templates").rglob("*") if p.is_file()]
    return sorted(files)


def derive_sources(derive_dir=DERIVE_DIR):
    """{path relative to the repository root: SHA-256} of ``source_files``."""
    derive_dir = Path(derive_dir)
    return {p.relative_to(derive_dir.parent).as_posix(): sha256(p)
            for p in source_files(derive_dir)}


def build_manifest(out_dir, functions):
    out_dir = Path(out_dir)
    files = sorted(p for p in out_dir.rglob("*") if p.is_file() and p.name != MANIFEST
                   and not is_foreign(p.relative_to(out_dir)))
    contract = describe(functions)
    for name, fn in functions.items():
        contract["functions"][name]["instructions"] = fn.n_instructions()
    return {
        "_comment": NOTICE,
        "versions": {
            "python": ".".join(platform.python_version_tuple()[:2]),
            "sympy": sympy.__version__,
            "casadi": casadi.__version__,
        },
        "vectors": contract["vectors"],
        "outputs": contract["outputs"],
        "functions": contract["functions"],
        "files": {p.relative_to(out_dir).as_posix(): sha256(p) for p in files},
        "sources": derive_sources(),
    }


def write_manifest(out_dir, functions):
    text = json.dumps(build_manifest(out_dir, functions), indent=2) + "\n"
    (Path(out_dir) / MANIFEST).write_text(text)


def is_fresh(out_dir, derive_dir=DERIVE_DIR):
    """True when the manifest's source hashes equal ``derive_dir``'s sources now and every
    generated file matches its hash."""
    path = Path(out_dir) / MANIFEST
    try:
        manifest = json.loads(path.read_text())
        files_ok = all(sha256(Path(out_dir) / rel) == digest
                       for rel, digest in manifest["files"].items())
    except (OSError, ValueError, KeyError):
        return False
    return files_ok and manifest.get("sources") == derive_sources(derive_dir)
