"""Third-party C trees and their builds: the one place that finds a tree, unpacks a vendor
tarball, keys a cache by content and reads a compiler's first error line.

A tree is found, in this order, from an argument (a folder, or a tarball when the caller
accepts one), an environment variable naming a folder, or a tarball in the vendor folder
(``$QUADCOG_VENDOR_DIR``, else ``shared/vendor`` beside the repository). A tarball is unpacked
once per content into ``quadcog.paths.cache_dir()``, keyed by its SHA-256. The user's tree is
only ever read: builds happen in the cache. Both the flight stacks in the loop
(``quadcog.stacks``, ``quadcog.crazyflie``) and the firmware builds of the embedded exports
(``quadcog.embedded.crazyflie_firmware``) use this module; its errors are
``quadcog.StackError`` (the embedded builds raise its subclass ``FirmwareError``).

Builds (``build_library``): several translation units compiled (two at a time) and linked
into one shared library in the cache; the key is a SHA-256 of every source's bytes, the key
parts the caller adds (e.g. the digest of the headers of the tree), the flags and the
compiler's identity; the library's own SHA-256 is recorded beside it and checked before use
(``quadcog.codegen.compiler.is_verified``).
"""
from collections.abc import Iterable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
import contextlib
import fcntl
import hashlib
import os
from pathlib import Path
import re
import shutil
import subprocess
import tarfile
import tempfile

from quadcog.codegen.compiler import DIGEST_SUFFIX, file_digest, find_compiler, is_verified
from quadcog.errors import StackError
from quadcog.paths import cache_dir
from quadcog.validate import plain

__all__ = ["VENDOR_ENV", "SKIP_FOLDERS", "Source", "vendor_dir", "unpack_tarball", "check_tree",
           "locate_tree", "find_tree", "tree_digest", "tree_hash", "first_error_line",
           "locked", "build_library", "c_function"]

VENDOR_ENV = "QUADCOG_VENDOR_DIR"
SKIP_FOLDERS = frozenset({".git", "build", "__pycache__"})   # not part of a tree's content
Source = tuple[str, bytes]          # (file name for messages and objects, C text)


def vendor_dir() -> Path:
    """The folder of the vendor tarballs.

    Returns
    -------
    pathlib.Path
        ``$QUADCOG_VENDOR_DIR`` (``~`` expanded), else ``shared/vendor`` beside the
        repository that holds the package (it may not exist).
    """
    env = os.environ.get(VENDOR_ENV)
    if env:
        return Path(env).expanduser()       # a "~" the shell did not expand (quoted)
    return Path(__file__).resolve().parents[3] / "shared" / "vendor"


def unpack_tarball(tarball: str | os.PathLike[str], folder: str | os.PathLike[str] | None = None,
                   name: str | None = None, error: type[StackError] = StackError) -> Path:
    """Unpack a tarball into the cache, once per content.

    Parameters
    ----------
    tarball : str or os.PathLike
        A ``.tar``, ``.tar.gz`` or ``.tar.xz`` file.
    folder : str or os.PathLike, optional
        Where to unpack (default ``cache_dir() / "vendor"``).
    name : str, optional
        The unpacked folder's name (default ``<stem>-<sha256[:16]>``); it must change with
        the content.
    error : type of StackError
        The error raised (a subclass for a caller's own, e.g. ``FirmwareError``).

    Returns
    -------
    pathlib.Path
        The folder ``folder / name`` holding the tarball's content (renamed into place when
        complete, so a half-unpacked folder is never returned).

    Raises
    ------
    quadcog.StackError
        The tarball is missing or cannot be read (``error``).
    """
    path = Path(tarball)
    if not path.is_file():
        raise error(f"tarball {str(path)!r}: not found")
    stem = path.name.split(".tar")[0]
    out = Path(folder) if folder is not None else cache_dir() / "vendor"
    target = out / (name if name is not None else f"{stem}-{file_digest(path)[:16]}")
    if target.is_dir():
        return target
    out.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=out, prefix=f".unpack-{stem}-"))
    try:
        with tarfile.open(path) as tar:
            tar.extractall(tmp, filter="data")
        try:
            os.replace(tmp, target)
        except OSError:             # another process unpacked it first
            if not target.is_dir():
                raise
    except (OSError, tarfile.TarError) as e:
        raise error(f"tarball {str(path)!r}: cannot be unpacked into {str(out)!r} "
                         f"({e})") from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return target


def check_tree(path: str | os.PathLike[str], where: str, markers: Sequence[str], what: str,
               get: str, error: type[StackError] = StackError) -> Path:
    """``path`` when it is a tree of this kind.

    Parameters
    ----------
    path : str or os.PathLike
        The folder.
    where : str
        Where it came from (an argument's name, ``"$VAR"``), first in the message.
    markers : sequence of str
        Files (relative to the root) that every such tree has.
    what : str
        The tree's name for messages, e.g. ``"Crazyflie firmware tree"``.
    get : str
        How to get one, for messages (e.g. a ``git clone`` line).
    error : type of StackError
        The error raised.

    Returns
    -------
    pathlib.Path
        The folder, resolved.

    Raises
    ------
    quadcog.StackError
        Not a folder, or a marker is missing (the message names them): ``error``.
    """
    root = Path(path).expanduser()
    if not root.is_dir():
        raise error(f"{where} = {str(path)!r} is not a folder; expected a {what} ({get})")
    missing = [m for m in markers if not (root / m).is_file()]
    if missing:
        raise error(f"{where} = {str(path)!r} is not a {what}: it has no "
                         f"{', '.join(missing)} (expected {', '.join(markers)}; {get})")
    return root.resolve()


def locate_tree(argument: str | os.PathLike[str] | None, env: str, tarball: str,
                markers: Sequence[str], what: str, get: str, tarball_argument: bool = False,
                argument_name: str = "argument", error: type[StackError] = StackError
                ) -> tuple[Path, bool]:
    """Where a third-party tree is: a folder (checked) or a tarball, not yet unpacked.

    Parameters
    ----------
    argument : str or os.PathLike or None
        A folder the caller named (checked first); with ``tarball_argument`` also a tarball.
    env : str
        An environment variable that may name the folder.
    tarball : str
        The tarball's file name in ``vendor_dir()``.
    markers : sequence of str
        Files (relative to the root) that every such tree has.
    what : str
        The tree's name for messages.
    get : str
        How to get one, for messages.
    tarball_argument : bool
        Accept a tarball file as the argument.
    argument_name : str
        The argument's name in messages.
    error : type of StackError
        The error raised.

    Returns
    -------
    tuple of (pathlib.Path, bool)
        The folder or the tarball (resolved), and whether it is a tarball.

    Raises
    ------
    quadcog.StackError
        The argument is not a path (``""``, bytes, a number), the argument or the variable
        names a folder that is not such a tree, or there is neither a folder nor the
        tarball.
    """
    # an empty path would name the current folder, bytes or a number no folder: refused, not
    # passed over to the environment or the tarball
    if argument is not None and (not isinstance(argument, (str, os.PathLike))
                                 or not isinstance(os.fspath(argument), str)
                                 or not os.fspath(argument)):
        raise error(f"{argument_name}: expected None or the path of a {what}, got "
                    f"{plain(argument)}")
    if (tarball_argument and argument is not None and Path(argument).is_file()
            and tarfile.is_tarfile(argument)):
        return Path(argument).resolve(), True
    for value, where in ((argument, argument_name), (os.environ.get(env), f"${env}")):
        if value is None or value == "":
            continue
        return check_tree(value, where, markers, what, get, error), False
    candidate = vendor_dir() / tarball
    if candidate.is_file():
        return candidate.resolve(), True
    raise error(f"no {what}: pass one ({argument_name}), set ${env}, or put {tarball} in "
                f"{str(vendor_dir())!r} (${VENDOR_ENV}); {get}")


def find_tree(argument: str | os.PathLike[str] | None, env: str, tarball: str, inner: str,
              markers: Sequence[str], what: str, get: str,
              argument_name: str = "argument") -> Path:
    """The root of a third-party tree: from the argument, the environment, or the tarball.

    Parameters
    ----------
    argument : str or os.PathLike or None
        A folder the caller named (checked first).
    env : str
        An environment variable that may name the folder.
    tarball : str
        The tarball's file name in ``vendor_dir()``.
    inner : str
        The folder inside the tarball that is the tree's root.
    markers : sequence of str
        Files (relative to the root) that every such tree has.
    what : str
        The tree's name for messages, e.g. ``"Crazyflie firmware tree"``.
    get : str
        How to get one, for messages (e.g. a ``git clone`` line).
    argument_name : str
        The argument's name in messages.

    Returns
    -------
    pathlib.Path
        The tree's root (resolved); a tarball's is in ``cache_dir() / "vendor"``.

    Raises
    ------
    quadcog.StackError
        The argument is not a path, the argument or the variable names a folder that is not
        such a tree (the message names the first missing marker), or there is neither a
        folder nor the tarball.
    """
    path, is_tarball = locate_tree(argument, env, tarball, markers, what, get,
                                   argument_name=argument_name)
    return (unpack_tarball(path) / inner).resolve() if is_tarball else path


def tree_digest(root: str | os.PathLike[str], files: Iterable[str | os.PathLike[str]]) -> str:
    """SHA-256 over the relative names and contents of files of a tree.

    Parameters
    ----------
    root : str or os.PathLike
        The tree's root.
    files : iterable of str or os.PathLike
        Files (absolute, or relative to root), in any order; missing ones count as missing.

    Returns
    -------
    str
        Hex digest; it changes when any of the files changes, appears or disappears.
    """
    root = Path(root)
    h = hashlib.sha256()
    for f in sorted({str(Path(f).relative_to(root)) if Path(f).is_absolute() else str(f)
                     for f in files}):
        h.update(f.encode() + b"\0")
        p = root / f
        h.update(p.read_bytes() if p.is_file() else b"\0missing\0")
    return h.hexdigest()


def tree_hash(tree: str | os.PathLike[str], skip: Iterable[str] = SKIP_FOLDERS) -> str:
    """The hex SHA-256 of all of a tree's file names and contents (symlinks by target).

    Parameters
    ----------
    tree : str or os.PathLike
        The folder.
    skip : iterable of str
        Folder names left out wherever they are (default ``SKIP_FOLDERS``).

    Returns
    -------
    str
        64 hex digits.
    """
    skip = set(skip)
    h = hashlib.sha256()
    tree = Path(tree)
    for dirpath, dirnames, filenames in os.walk(tree):
        dirnames[:] = sorted(d for d in dirnames if d not in skip)
        for f in sorted(filenames):
            path = Path(dirpath) / f
            h.update(str(path.relative_to(tree)).encode() + b"\0")
            if path.is_symlink():
                h.update(b"->" + os.readlink(path).encode())
            elif path.is_file():
                h.update(path.read_bytes())
            h.update(b"\0")
    return h.hexdigest()


def first_error_line(log: str) -> str:
    """The compiler's first error line of what a compiler, linker or make wrote.

    Parameters
    ----------
    log : str
        Its output.

    Returns
    -------
    str
        The first ``file:line[:col]: [fatal ]error:`` line, else the first line with
        ``error``, else make's first ``***`` line, else the last line (stripped).
    """
    lines = [ln for ln in log.splitlines() if ln.strip()]
    for pattern in (r":\d+(:\d+)?: (fatal )?error:", r"\berror\b", r"\*\*\*"):
        for line in lines:
            if re.search(pattern, line, re.IGNORECASE):
                return line.strip()
    return lines[-1].strip() if lines else "(no output)"


@contextlib.contextmanager
def locked(path: str | os.PathLike[str]) -> Iterator[None]:
    """Hold an exclusive lock on a file (across processes) for a ``with`` block.

    Parameters
    ----------
    path : str or os.PathLike
        The lock file (created when missing).

    Yields
    ------
    None
        While the lock is held.
    """
    with open(path, "a+") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def _run(cmd, what):
    try:
        res = subprocess.run(cmd, capture_output=True, text=True)
    except OSError as e:
        raise StackError(f"`{cmd[0]}` cannot be run ({e.strerror or e}); install a C compiler "
                         "(e.g. `apt-get install gcc`) or set $CC") from None
    if res.returncode != 0:
        raise StackError(f"building {what} failed: {first_error_line(res.stderr)}\n"
                         f"(command: {' '.join(cmd)})")


def build_library(name: str, sources: Sequence[Source], flags: Sequence[str],
                  key_parts: Sequence[str] = (), folder: str | os.PathLike[str] | None = None
                  ) -> Path:
    """Compile and link C sources into one verified shared library in the cache.

    Parameters
    ----------
    name : str
        The library's stem (``<name>-<key>.so``) and its name in messages.
    sources : sequence of (str, bytes)
        Translation units: a file name (unique among them) and the C text. Third-party files
        are read by the caller and passed as text; headers come from the include flags.
    flags : sequence of str
        Compiler flags (include folders, defines, optimization); ``-fPIC`` is added.
    key_parts : sequence of str
        More of the key: digests of what the sources include.
    folder : str or os.PathLike, optional
        The cache folder (default ``cache_dir() / "stacks"``).

    Returns
    -------
    pathlib.Path
        The library.

    Raises
    ------
    quadcog.StackError
        No C compiler (the message says how to get one), or a compile or link error (with the
        compiler's first error line).
    """
    cc = find_compiler()
    if cc is None:
        raise StackError(f"building {name}: no C compiler found (looked for $CC or `cc` on "
                         "PATH); install one, e.g. `apt-get install gcc`")
    h = hashlib.sha256()
    for part in (cc, *flags, *key_parts):
        h.update(part.encode() + b"\0")
    for fname, text in sources:
        h.update(fname.encode() + b"\0" + text + b"\0")
    out_dir = Path(folder) if folder is not None else cache_dir() / "stacks"
    out = out_dir / f"{name}-{h.hexdigest()[:20]}.so"
    if is_verified(out):
        return out
    out_dir.mkdir(parents=True, exist_ok=True)
    with locked(out_dir / f"{out.stem}.lock"):
        if is_verified(out):
            return out
        tmp = Path(tempfile.mkdtemp(dir=out_dir, prefix=f".build-{name}-"))
        try:
            def compile_one(item):
                fname, text = item
                src = tmp / fname
                src.write_bytes(text)
                obj = src.with_suffix(".o")
                _run([cc, *flags, "-fPIC", "-c", str(src), "-o", str(obj)], f"{name} ({fname})")
                return str(obj)
            with ThreadPoolExecutor(max_workers=2) as pool:
                objects = list(pool.map(compile_one, sources))
            lib = tmp / out.name
            _run([cc, "-shared", *objects, "-o", str(lib), "-lm"], f"{name} (link)")
            digest = file_digest(lib)
            os.replace(lib, out)
            out.with_name(out.name + DIGEST_SUFFIX).write_text(digest + "\n")
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    return out


def c_function(text: str, signature: str, where: str) -> str:
    """The definition of one C function, cut from a source file's text by brace matching.

    Parameters
    ----------
    text : str
        The C file's text.
    signature : str
        The start of the definition up to the name and its ``(``, e.g.
        ``"static void batteryCompensation("``; whitespace is matched loosely.
    where : str
        The file's name, for messages.

    Returns
    -------
    str
        From the signature to its closing brace.

    Raises
    ------
    quadcog.StackError
        The definition is not in the text.
    """
    pattern = r"\s+".join(re.escape(p) for p in signature.split())
    for m in re.finditer(pattern, text):
        open_at = text.find("{", m.end())
        head = text[m.end():open_at]
        if open_at < 0 or ";" in head:         # a declaration, not the definition
            continue
        depth = 0
        for k in range(open_at, len(text)):
            depth += {"{": 1, "}": -1}.get(text[k], 0)
            if depth == 0:
                return text[m.start():k + 1]
    raise StackError(f"{where}: no definition of `{signature.strip()}...)`; this firmware "
                     "differs from the one quadcog knows")
