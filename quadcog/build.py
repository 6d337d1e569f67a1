"""Compile C sources into shared libraries in a cache, atomically and safely in parallel.

The cache key is the SHA-256 of the source, the compiler's identity and the flags, so a
changed source, compiler or flag never reuses a stale library.
"""
import contextlib
import fcntl
import functools
import hashlib
import os
from pathlib import Path
import shutil
import subprocess
import tempfile

from .errors import CompileError
from .paths import cache_dir

# -fno-math-errno lets sqrt inline and changes no value (errno is never read here).
FLAGS = ("-O3", "-fno-math-errno", "-shared", "-fPIC")


def find_compiler():
    """Path of $CC (default ``cc``), or None when there is no C compiler."""
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


def library_path(source_bytes, stem, cc, flags=FLAGS, folder=None):
    """Where the library built from ``source_bytes`` lives in the cache."""
    key = hashlib.sha256(source_bytes + b"\0" + _compiler_identity(cc).encode()
                         + b"\0" + " ".join(flags).encode()).hexdigest()[:20]
    return Path(folder or cache_dir()) / f"{stem}-{key}.so"


def compile_library(source_bytes, stem, cc=None, flags=FLAGS, folder=None):
    """Build (or find in the cache) the shared library of one C translation unit.

    Returns its path. Concurrent callers wait on a lock; the library appears by an
    atomic rename, so nobody ever loads a half-written file.
    """
    cc = cc or find_compiler()
    if cc is None:
        raise CompileError("no C compiler found (looked for $CC or `cc` on PATH)")
    out = library_path(source_bytes, stem, cc, flags, folder)
    if out.is_file():
        return out
    out.parent.mkdir(parents=True, exist_ok=True)
    with _exclusive(out.with_suffix(".lock")):
        if out.is_file():
            return out
        with tempfile.TemporaryDirectory(dir=out.parent, prefix=f".{stem}-build-") as tmp:
            src = Path(tmp) / f"{stem}.c"
            src.write_bytes(source_bytes)
            tmp_lib = Path(tmp) / f"{stem}.so"
            cmd = [cc, *flags, str(src), "-o", str(tmp_lib), "-lm"]
            res = subprocess.run(cmd, capture_output=True, text=True)
            if res.returncode != 0:
                raise CompileError(f"`{' '.join(cmd)}` failed with exit code {res.returncode}:\n"
                                   f"{res.stderr[-4000:]}")
            os.replace(tmp_lib, out)
    return out
