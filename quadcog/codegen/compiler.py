"""Compile C sources into shared libraries in a cache, atomically, safely in parallel, and never
hand out a library that was not verified.

The cache key is the SHA-256 of the source, the compiler's identity and the flags, so a
changed source, compiler or flag never reuses a stale library. After a successful build the
SHA-256 of the library itself is recorded beside it (``<name>.so.sha256``) and checked before
every load: a truncated, damaged or planted ``.so`` (one the cache did not build, or changed
since) is rebuilt, never opened (opening a truncated library can kill the process with SIGBUS).

A cache folder that cannot be used (read-only, a file in its place, a folder where the library
should be) gives one ``QuadcogWarning`` and a private temporary cache for this process, which
is removed at exit. Build folders are temporary folders removed on any error, Ctrl-C
included; those of builds killed outright are removed by the next build in the same cache.
"""
import atexit
from collections.abc import Sequence
import contextlib
import fcntl
import functools
import hashlib
import os
from pathlib import Path
import shutil
import socket
import subprocess
import tempfile
import time
import warnings

from quadcog.errors import CompileError, QuadcogWarning
from quadcog.paths import cache_dir

__all__ = ["FLAGS", "DIGEST_SUFFIX", "find_compiler", "library_path", "file_digest",
           "is_verified", "remove_stale_build_folders", "compile_library"]

# -fno-math-errno lets sqrt inline and changes no value (errno is never read here).
FLAGS = ("-O3", "-fno-math-errno", "-shared", "-fPIC")
DIGEST_SUFFIX = ".sha256"
_BUILD_PREFIX = ".build-"
_STALE_AFTER = 24 * 3600.0     # s; build folders of another host are removed after this
_UNNAMED_STALE_AFTER = 3600.0  # s; ... and those without an owner (earlier versions)


def find_compiler() -> str | None:
    """The C compiler.

    Returns
    -------
    str or None
        Path of $CC (default ``cc``), or None when there is no C compiler.
    """
    return shutil.which(os.environ.get("CC", "cc"))


@functools.lru_cache(maxsize=None)
def _compiler_identity(cc):
    try:
        out = subprocess.run([cc, "--version"], capture_output=True, text=True, timeout=30)
        return out.stdout.splitlines()[0] if out.stdout else cc
    except (OSError, subprocess.SubprocessError):
        return cc


@contextlib.contextmanager
def _exclusive(lock_path):
    with open(lock_path, "a+") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def library_path(source_bytes: bytes, stem: str, cc: str, flags: Sequence[str] = FLAGS,
                 folder: str | os.PathLike[str] | None = None) -> Path:
    """Where the library built from ``source_bytes`` lives in the cache.

    Parameters
    ----------
    source_bytes : bytes
        The C source.
    stem : str
        Name of the library.
    cc : str
        The compiler (its ``--version`` is part of the key).
    flags : sequence of str, optional
        Compiler flags (part of the key).
    folder : str or os.PathLike, optional
        The cache folder (default ``quadcog.paths.cache_dir()``).

    Returns
    -------
    pathlib.Path
        ``<folder>/<stem>-<key>.so``, the key a SHA-256 of source, compiler and flags.
    """
    key = hashlib.sha256(source_bytes + b"\0" + _compiler_identity(cc).encode()
                         + b"\0" + " ".join(flags).encode()).hexdigest()[:20]
    return Path(folder or cache_dir()) / f"{stem}-{key}.so"


def file_digest(path: str | os.PathLike[str]) -> str:
    """SHA-256 of a file's contents.

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    str
        64 hex digits.
    """
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _digest_path(lib):
    return lib.with_name(lib.name + DIGEST_SUFFIX)


def is_verified(lib: Path) -> bool:
    """Whether ``lib`` is a library the cache built and nobody changed since.

    Parameters
    ----------
    lib : pathlib.Path
        A library path in the cache.

    Returns
    -------
    bool
        True when ``lib`` is a regular file whose SHA-256 is the one recorded after its build.
    """
    try:
        recorded = _digest_path(lib).read_text().strip()
        return lib.is_file() and not lib.is_symlink() and file_digest(lib) == recorded
    except (OSError, UnicodeDecodeError):
        return False


# -- the fallback when the cache folder cannot be used ------------------------------------
_private: Path | None = None
_warned: set[Path] = set()


def _private_cache():
    """A temporary cache folder of this process, removed at exit."""
    global _private
    if _private is None:
        _private = Path(tempfile.mkdtemp(prefix="quadcog-cache-"))
        atexit.register(shutil.rmtree, _private, ignore_errors=True)
    return _private


def _warn_once(folder, why):
    if folder not in _warned:
        _warned.add(folder)
        warnings.warn(f"compile cache {folder} cannot be used ({why}); building into a "
                      f"temporary folder for this process instead (set $QUADCOG_CACHE_DIR to "
                      f"a writable folder to keep the builds)", QuadcogWarning, stacklevel=4)


def _reason(e):
    return f"{e.strerror or type(e).__name__}: {e.filename}" if isinstance(e, OSError) else str(e)


# -- build folders --------------------------------------------------------------------------
def _build_folder_owner(name):
    """(host, pid) encoded in a build folder's name, or None."""
    parts = name[len(_BUILD_PREFIX):].split("-")
    if len(parts) < 3 or not parts[-2].isdigit():
        return None
    return "-".join(parts[:-2]), int(parts[-2])


def _alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:                 # exists, owned by someone else
        return True
    return True


def remove_stale_build_folders(folder: str | os.PathLike[str]) -> list[Path]:
    """Remove build folders left by builds that were killed.

    Those are the ones whose process is gone (same host), or older than a day (another host)
    or an hour (no owner in the name, from earlier versions).

    Parameters
    ----------
    folder : str or os.PathLike
        The cache folder.

    Returns
    -------
    list of pathlib.Path
        The paths removed.
    """
    removed: list[Path] = []
    host = socket.gethostname()
    try:        # ours, and the unnamed ones of earlier versions (.<stem>-build-*)
        entries = [*Path(folder).glob(_BUILD_PREFIX + "*"), *Path(folder).glob(".*-build-*")]
    except OSError:
        return removed
    for path in entries:
        owner = _build_folder_owner(path.name) if path.name.startswith(_BUILD_PREFIX) else None
        try:
            age = time.time() - path.stat().st_mtime
        except OSError:
            continue
        if owner is not None and owner[0] == host:
            dead = not _alive(owner[1])
        else:
            dead = age > (_STALE_AFTER if owner else _UNNAMED_STALE_AFTER)
        if dead and path.is_dir():
            shutil.rmtree(path, ignore_errors=True)
            removed.append(path)
    return removed


def _compile(source_bytes, stem, cc, flags, folder):
    """Compile in a build folder inside ``folder``; returns (library, digest) still in the
    build folder, which the caller renames into place and then removes."""
    tmp = Path(tempfile.mkdtemp(dir=folder, prefix=f"{_BUILD_PREFIX}{socket.gethostname()}-"
                                                   f"{os.getpid()}-"))
    try:
        src = tmp / f"{stem}.c"
        src.write_bytes(source_bytes)
        lib = tmp / f"{stem}.so"
        cmd = [cc, *flags, str(src), "-o", str(lib), "-lm"]
        try:
            res = subprocess.run(cmd, capture_output=True, text=True)
        except OSError as e:        # not an OSError of the cache folder: do not fall back
            raise CompileError(f"`{cc}` cannot be run ({e.strerror or e})") from None
        if res.returncode != 0:
            raise CompileError(f"`{' '.join(cmd)}` failed with exit code {res.returncode}:\n"
                               f"{res.stderr[-4000:]}")
        digest = file_digest(lib)
        _digest_path(lib).write_text(digest + "\n")
        return tmp, lib, digest
    except BaseException:           # Ctrl-C included: leave nothing behind
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _build_into(source_bytes, stem, cc, flags, out):
    """Build the library ``out`` under the cache lock unless a verified one appeared."""
    out.parent.mkdir(parents=True, exist_ok=True)
    if out.is_dir() and not out.is_symlink():
        raise IsADirectoryError(21, "a folder is in the library's place", str(out))
    with _exclusive(out.parent / f"{out.stem}.lock"):
        if is_verified(out):
            return out
        # without a recorded digest (a library of an earlier version, or one put there by
        # hand) the library is simply rebuilt; with one that does not match, it was damaged
        if (out.exists() or out.is_symlink()) and _digest_path(out).exists():
            warnings.warn(f"cached library {out} does not match the SHA-256 recorded when it "
                          f"was built (damaged, replaced or left by an older quadcog); "
                          f"rebuilding it", QuadcogWarning, stacklevel=4)
        remove_stale_build_folders(out.parent)
        tmp, lib, _ = _compile(source_bytes, stem, cc, flags, out.parent)
        try:
            # the library first, then its digest: a reader never verifies a half-written file
            os.replace(lib, out)
            os.replace(_digest_path(lib), _digest_path(out))
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    return out


def compile_library(source_bytes: bytes, stem: str, cc: str | None = None,
                    flags: Sequence[str] = FLAGS,
                    folder: str | os.PathLike[str] | None = None) -> Path:
    """Build (or find, verified, in the cache) the shared library of one C translation unit.

    Parameters
    ----------
    source_bytes : bytes
        The C source.
    stem : str
        Name of the library (``<stem>-<key>.so``).
    cc : str, optional
        The compiler (default ``find_compiler()``).
    flags : sequence of str, optional
        Compiler flags (part of the cache key).
    folder : str or os.PathLike, optional
        The cache folder (default ``quadcog.paths.cache_dir()``).

    Returns
    -------
    pathlib.Path
        A library whose SHA-256 matches the one recorded after its build. Concurrent callers
        wait on a lock; the library appears by an atomic rename.

    Raises
    ------
    CompileError
        No compiler, or the compiler failed.
    """
    cc = cc or find_compiler()
    if cc is None:
        raise CompileError("no C compiler found (looked for $CC or `cc` on PATH)")
    out = library_path(source_bytes, stem, cc, flags, folder)
    if is_verified(out):
        return out
    try:
        return _build_into(source_bytes, stem, cc, flags, out)
    except OSError as e:            # read-only, a file as the folder, a folder as the library
        _warn_once(out.parent, _reason(e))
    private = _private_cache() / out.name
    if is_verified(private):
        return private
    return _build_into(source_bytes, stem, cc, flags, private)
