"""Cache-keyed builds of third-party C with quadcog's own C: several translation units
compiled (two at a time) and linked into one shared library in ``quadcog.paths.cache_dir()``,
never in the third party's tree; a failed build raises with the compiler's first error line.

The key is a SHA-256 of every source's bytes, the key parts the caller adds (e.g. the digest of
the headers of the tree), the flags and the compiler's identity; the library's own SHA-256 is
recorded beside it and checked before use (``quadcog.codegen.compiler.is_verified``).
"""
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
import contextlib
import fcntl
import hashlib
import os
from pathlib import Path
import re
import shutil
import subprocess
import tempfile

from quadcog.codegen.compiler import DIGEST_SUFFIX, file_digest, find_compiler, is_verified
from quadcog.errors import StackError
from quadcog.paths import cache_dir

__all__ = ["Source", "first_error_line", "build_library", "c_function"]

Source = tuple[str, bytes]          # (file name for messages and objects, C text)


def first_error_line(stderr: str) -> str:
    """The compiler's first error line (``file:line:col: error: ...``), else its first line.

    Parameters
    ----------
    stderr : str
        What the compiler or linker wrote.

    Returns
    -------
    str
        One line.
    """
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    for ln in lines:
        if re.search(r"\b(fatal )?error\b", ln):
            return ln.strip()
    return lines[0].strip() if lines else "(no message)"


@contextlib.contextmanager
def _locked(path):
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
    with _locked(out_dir / f"{out.stem}.lock"):
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
