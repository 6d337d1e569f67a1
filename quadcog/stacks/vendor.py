"""Third-party source trees: where one is, and unpacking a vendor tarball into the cache.

A tree is found, in this order, from an argument (a folder), an environment variable naming a
folder, or a tarball in the vendor folder (``$QUADCOG_VENDOR_DIR``, else ``shared/vendor`` beside
the repository) unpacked into ``quadcog.paths.cache_dir()/vendor/<name>-<sha256[:16]>``. The
user's tree is only ever read: builds happen in the cache.
"""
from collections.abc import Iterable, Sequence
import hashlib
import os
from pathlib import Path
import shutil
import tarfile
import tempfile

from quadcog.codegen.compiler import file_digest
from quadcog.errors import StackError
from quadcog.paths import cache_dir

__all__ = ["VENDOR_ENV", "vendor_dir", "unpack_tarball", "find_tree", "tree_digest"]

VENDOR_ENV = "QUADCOG_VENDOR_DIR"


def vendor_dir() -> Path:
    """The folder of the vendor tarballs.

    Returns
    -------
    pathlib.Path
        ``$QUADCOG_VENDOR_DIR``, else ``shared/vendor`` beside the repository that holds the
        package (it may not exist).
    """
    env = os.environ.get(VENDOR_ENV)
    if env:
        return Path(env)
    return Path(__file__).resolve().parents[3] / "shared" / "vendor"


def unpack_tarball(tarball: str | os.PathLike[str], folder: str | os.PathLike[str] | None = None
                   ) -> Path:
    """Unpack a tarball into the cache, once per content.

    Parameters
    ----------
    tarball : str or os.PathLike
        A ``.tar``, ``.tar.gz`` or ``.tar.xz`` file.
    folder : str or os.PathLike, optional
        Where to unpack (default ``cache_dir() / "vendor"``).

    Returns
    -------
    pathlib.Path
        The folder ``<stem>-<sha256[:16]>`` holding the tarball's content (renamed into place
        when complete, so a half-unpacked folder is never returned).

    Raises
    ------
    quadcog.StackError
        The tarball is missing or cannot be read.
    """
    path = Path(tarball)
    if not path.is_file():
        raise StackError(f"tarball {str(path)!r}: not found")
    stem = path.name.split(".tar")[0]
    out = Path(folder) if folder is not None else cache_dir() / "vendor"
    target = out / f"{stem}-{file_digest(path)[:16]}"
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
        raise StackError(f"tarball {str(path)!r}: cannot be unpacked into {str(out)!r} "
                         f"({e})") from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return target


def find_tree(argument: str | os.PathLike[str] | None, env: str, tarball: str, inner: str,
              markers: Sequence[str], what: str, get: str) -> Path:
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

    Returns
    -------
    pathlib.Path
        The tree's root (resolved).

    Raises
    ------
    quadcog.StackError
        The argument or the variable names a folder that is not such a tree (the message
        names the first missing marker), or there is neither a folder nor the tarball.
    """
    for value, where in ((argument, "argument"), (os.environ.get(env), f"${env}")):
        if value is None or value == "":
            continue
        root = Path(value).expanduser()
        if not root.is_dir():
            raise StackError(f"{where}: {str(root)!r} is not a folder; expected a {what} "
                             f"({get})")
        missing = [m for m in markers if not (root / m).is_file()]
        if missing:
            raise StackError(f"{where}: {str(root)!r} is not a {what}: it has no {missing[0]} "
                             f"(expected {', '.join(markers)}; {get})")
        return root.resolve()
    candidate = vendor_dir() / tarball
    if candidate.is_file():
        return (unpack_tarball(candidate) / inner).resolve()
    raise StackError(f"no {what}: pass one as an argument, set ${env}, or put {tarball} in "
                     f"{str(vendor_dir())!r} (${VENDOR_ENV}); {get}")


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
