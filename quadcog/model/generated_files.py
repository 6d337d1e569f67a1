"""Read generated/: the manifest, the contract of the generated functions written into it by
derive/contract.py, the integrity of every file, the CasADi functions."""
from collections import namedtuple
from collections.abc import Collection
import hashlib
import json
import os
from pathlib import Path, PurePosixPath
import re
from typing import Any

from quadcog.errors import GeneratedFilesError
from quadcog.paths import generated_dir, shipped_generated_dir

__all__ = ["MANIFEST", "C_SOURCE", "COVERED", "Contract", "read_manifest", "read_contract",
           "imported_contract", "required_files", "verify", "load_casadi_function"]

MANIFEST = "manifest.json"
C_SOURCE = "c/quadcog_gen.c"
_HEX64 = re.compile(r"[0-9a-f]{64}")


def _fix(folder: str | os.PathLike[str]) -> str:
    """What to do about a bad generated folder: reinstall a package, re-derive a checkout."""
    if Path(folder).resolve() == shipped_generated_dir().resolve():
        return "reinstall quadcog (pip install --force-reinstall quadcog)"
    return "run `make derive` to regenerate it"


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def read_manifest(folder: str | os.PathLike[str] | None = None) -> dict[str, Any]:
    """The manifest of a generated folder, its shape checked.

    Parameters
    ----------
    folder : str or os.PathLike, optional
        The generated folder (default ``quadcog.paths.generated_dir()``).

    Returns
    -------
    dict
        The manifest: "files" {relative path: SHA-256 hex}, "functions" {name: ...},
        "vectors" {name: entries}, "outputs" [names].

    Raises
    ------
    GeneratedFilesError
        The manifest is missing, unreadable or malformed.
    """
    folder = Path(folder or generated_dir())
    path = folder / MANIFEST
    if not path.is_file():
        raise GeneratedFilesError(f"{path} is missing; {_fix(folder)}")
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, RecursionError) as e:      # bad JSON or UTF-8, absurd nesting
        raise GeneratedFilesError(f"{path} is corrupted ({type(e).__name__}: "
                                  f"{str(e)[:200]}); {_fix(folder)}") from None
    except OSError as e:
        raise GeneratedFilesError(f"{path} cannot be read ({e.strerror}); {_fix(folder)}") \
            from None
    bad = lambda what: GeneratedFilesError(f"{path} is corrupted: {what}; {_fix(folder)}")
    if not isinstance(manifest, dict):
        raise bad(f"expected a JSON object, got {type(manifest).__name__}")
    for key in ("files", "functions", "vectors"):
        if not isinstance(manifest.get(key), dict):
            raise bad(f"expected an object {key!r} (name -> entry), got "
                      f"{type(manifest.get(key)).__name__ if key in manifest else 'nothing'}")
    for rel, digest in manifest["files"].items():
        parts = PurePosixPath(rel).parts
        if not parts or rel.startswith("/") or "\\" in rel or any(
                p in ("", ".", "..") for p in parts) or rel != "/".join(parts):
            raise bad(f"'files' entry {rel[:100]!r} is not a relative path inside the folder")
        if not (isinstance(digest, str) and _HEX64.fullmatch(digest)):
            raise bad(f"'files' entry {rel!r} has no SHA-256 (64 hex digits), got "
                      f"{str(digest)[:80]!r}")
    if not isinstance(manifest.get("outputs"), list):
        raise bad("expected a list 'outputs' (the names of y)")
    return manifest


Contract = namedtuple("Contract", "vectors outputs functions")
Contract.__doc__ = """The public contract of the generated functions, as derive/ wrote it.

Parameters
----------
vectors : dict of str to tuple of str
    {argument name: entry names}, e.g. ``vectors["x"]`` the 12 state names.
outputs : tuple of str
    The names of y, the feedback-linearization outputs.
functions : dict
    {name: (inputs ((argument, length), ...), outputs ((name, shape), ...))}.
"""


def read_contract(folder: str | os.PathLike[str] | None = None) -> Contract:
    """The Contract recorded in the manifest of ``folder``.

    Parameters
    ----------
    folder : str or os.PathLike, optional
        The generated folder (default ``quadcog.paths.generated_dir()``).

    Returns
    -------
    Contract
        Its vectors, outputs and function signatures.

    Raises
    ------
    GeneratedFilesError
        The manifest is missing, malformed or has no readable contract.
    """
    folder = Path(folder or generated_dir())
    manifest = read_manifest(folder)
    try:
        functions = {
            name: (tuple((str(a), int(n)) for a, n in spec["inputs"]),
                   tuple((str(o), tuple(int(k) for k in shape)) for o, shape in spec["outputs"]))
            for name, spec in manifest["functions"].items()}
        vectors = {name: tuple(map(str, entries)) for name, entries in manifest["vectors"].items()}
        return Contract(vectors, tuple(map(str, manifest["outputs"])), functions)
    except (ValueError, KeyError, TypeError, AttributeError) as e:
        raise GeneratedFilesError(f"{folder / MANIFEST} has no readable contract ({e!r}); "
                                  f"{_fix(folder)}") from None


_IMPORTED: list[Contract] = []


def imported_contract() -> Contract:
    """The Contract of ``generated_dir()`` read once, when quadcog is imported.

    Returns
    -------
    Contract
        The vectors and signatures this runtime works with (``quadcog.model.conventions``
        holds it).

    Raises
    ------
    GeneratedFilesError
        The manifest is missing, malformed or has no readable contract.
    """
    if not _IMPORTED:
        _IMPORTED.append(read_contract())
    return _IMPORTED[0]


# Subfolders the manifest covers (besides the top-level files); others, such as embedded/,
# are written and checked by their own exporters.
COVERED = ("c", "casadi")


def _files_in(folder: Path) -> set[str]:
    """Relative paths of the files of a generated folder that the manifest must list."""
    out = set()
    for p in [*folder.iterdir(), *(q for sub in COVERED if (folder / sub).is_dir()
                                   for q in (folder / sub).rglob("*"))]:
        rel = p.relative_to(folder)
        if p.is_file() and rel.as_posix() != MANIFEST:
            out.add(rel.as_posix())
    return out


def required_files(folder: str | os.PathLike[str] | None = None) -> set[str]:
    """The files the runtime reads.

    Parameters
    ----------
    folder : str or os.PathLike, optional
        The generated folder (default ``quadcog.paths.generated_dir()``).

    Returns
    -------
    set of str
        Relative paths: the C source and one CasADi file per function of its contract.

    Raises
    ------
    GeneratedFilesError
        The manifest is missing, malformed or has no readable contract.
    """
    return {C_SOURCE} | {f"casadi/{name}.casadi" for name in read_contract(folder).functions}


def verify(folder: str | os.PathLike[str] | None = None,
           only: Collection[str] | None = None) -> dict[str, Any]:
    """Check the SHA-256 of every generated file (or of the names in ``only``) against the
    manifest.

    The manifest must list every file of the folder and every file the runtime reads, so
    removing an entry (or emptying "files") does not switch a check off; and the folder's
    vectors must be the ones this runtime was imported with.

    Parameters
    ----------
    folder : str or os.PathLike, optional
        The generated folder (default ``quadcog.paths.generated_dir()``).
    only : collection of str, optional
        Relative paths whose SHA-256 to check (default: all listed).

    Returns
    -------
    dict
        The manifest (as ``read_manifest``).

    Raises
    ------
    GeneratedFilesError
        Naming the file that is missing, unlisted, unreadable or does not match, or the
        vectors that differ, and what to do about it.
    """
    folder = Path(folder or generated_dir())
    manifest = read_manifest(folder)
    listed = manifest["files"]
    CONTRACT = imported_contract()
    theirs = read_contract(folder)
    if theirs.vectors != CONTRACT.vectors or theirs.outputs != CONTRACT.outputs:
        raise GeneratedFilesError(
            f"{folder / MANIFEST} orders the vectors {theirs.vectors} (outputs "
            f"{theirs.outputs}), but quadcog was imported with {CONTRACT.vectors} (outputs "
            f"{CONTRACT.outputs}) from {generated_dir()}; {_fix(folder)}")
    required = required_files(folder)
    try:
        present = _files_in(folder)
    except OSError as e:
        raise GeneratedFilesError(f"{folder} cannot be read ({e.strerror}); {_fix(folder)}") \
            from None
    for rel in sorted(required | present):
        if rel not in listed:
            where = folder / rel
            raise GeneratedFilesError(
                f"{where} is not listed in {folder / MANIFEST} (its 'files' entry was removed "
                f"or the file was added by hand), so it cannot be checked; {_fix(folder)}")
    for rel, digest in listed.items():
        if only is not None and rel not in only:
            continue
        path = folder / rel
        if not path.is_file():
            raise GeneratedFilesError(
                f"{path} is missing (listed in {MANIFEST}"
                + ("" if rel in required or rel in present else
                   ", a name the derivation never writes: the manifest may be corrupted")
                + f"); {_fix(folder)}")
        try:
            ok = _sha256(path) == digest
        except OSError as e:
            raise GeneratedFilesError(f"{path} cannot be read ({e.strerror}); {_fix(folder)}") \
                from None
        if not ok:
            raise GeneratedFilesError(
                f"{path} does not match its SHA-256 in {MANIFEST} (edited or corrupted); "
                f"{_fix(folder)}")
    return manifest


def load_casadi_function(name: str, folder: str | os.PathLike[str] | None = None) -> Any:
    """One generated function through CasADi's serializer (checked against the manifest).

    Parameters
    ----------
    name : str
        A function of the contract, e.g. ``"dynamics"``.
    folder : str or os.PathLike, optional
        The generated folder (default ``quadcog.paths.generated_dir()``).

    Returns
    -------
    casadi.Function
        The SX Function.

    Raises
    ------
    GeneratedFilesError
        ``casadi/<name>.casadi`` fails the manifest check or cannot be loaded.
    """
    import casadi as ca
    folder = Path(folder or generated_dir())
    rel = f"casadi/{name}.casadi"
    verify(folder, only={rel})
    try:
        return ca.Function.load(str(folder / rel))
    except RuntimeError as e:
        raise GeneratedFilesError(f"{folder / rel} cannot be loaded ({str(e).splitlines()[-1]}); "
                                  f"{_fix(folder)}") from None
