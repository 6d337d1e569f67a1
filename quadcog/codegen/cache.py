"""What quadcog's cache holds, and clearing it (`quadcog cache`).

The cache (``quadcog.paths.cache_dir()``) grows with use and nothing else removes from it:
one compiled library per generated function, law, kernel build and vehicle, PX4's SITL build
(about 0.5 GB), the Crazyflie firmware's workspace, AdaptiveQuadBench's patched copy. Each
entry is keyed by the hash of what made it, so removing one only costs its rebuild the next
time it is needed (seconds for a library, minutes for PX4). An entry whose build lock is
held by another process (a build under way) is left alone and reported as busy.

Entries: a compiled library is its ``STEM-KEY.so`` with its ``.so.sha256`` and ``.lock``
beside it (kind "libraries"); each folder under a top-level folder (``px4/KEY``,
``aqb/KEY``, ``crazyflie/...``, ``stacks/...``, ``vendor/...``) is one entry of that kind.
Nothing else in the folder is quadcog's: it is neither listed nor removed, so a cache folder
set by mistake to one of the user's (``QUADCOG_CACHE_DIR=$HOME``) loses nothing of theirs.
"""
from collections.abc import Iterable
import dataclasses
import fcntl
import os
from pathlib import Path
import re
import shutil
import stat

from quadcog.errors import InputError
from quadcog.paths import cache_dir

__all__ = ["CacheEntry", "KINDS", "LIBRARIES", "clear", "entries", "human_size"]

LIBRARIES = "libraries"     # the kind of the top-level compiled libraries
# the kinds quadcog writes: only these folders, and the files of compiled libraries, are
# ever listed or removed (QUADCOG_CACHE_DIR set to a folder of the user's, their home say,
# must not lose the user's files to `quadcog cache --clear`)
KINDS = (LIBRARIES, "px4", "aqb", "crazyflie", "stacks", "vendor", "docs-equations")
# a compiled library's files: STEM-KEY.so (KEY: 20 hex digits, compiler.library_path) and,
# beside it, STEM-KEY.so.sha256, STEM-KEY.lock and the STEM-KEY.so.* of a build under way
_LIBRARY_FILE = re.compile(r"(?P<stem>.+-[0-9a-f]{20})(\.so(\..+)?|\.lock)")
# the lock files that builds hold while they write an entry (compiler.py, px4/tree.py)
_LOCK_NAMES = ("lock",)


@dataclasses.dataclass(frozen=True)
class CacheEntry:
    """One removable entry of the cache.

    Parameters
    ----------
    name : str
        Its path relative to the cache folder (a library's without ``.so``).
    kind : str
        ``LIBRARIES`` or the top-level folder it is in ("px4", "aqb", ...).
    size : int
        Bytes on disk (files and links themselves, links not followed).
    modified : float
        The newest modification time of its files (seconds since the epoch).
    paths : tuple of pathlib.Path
        What removing it removes.
    """

    name: str
    kind: str
    size: int
    modified: float
    paths: tuple[Path, ...]


def _walk(path: Path) -> tuple[int, float]:
    """(bytes, newest mtime) of a file or folder, symbolic links not followed."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return 0, 0.0
    size, newest = (0 if stat.S_ISDIR(st.st_mode) else st.st_size), st.st_mtime
    if stat.S_ISDIR(st.st_mode):
        for root, dirs, files in os.walk(path, followlinks=False):
            for name in dirs + files:
                try:
                    s = os.lstat(os.path.join(root, name))
                except FileNotFoundError:       # removed while we walk
                    continue
                if not stat.S_ISDIR(s.st_mode):
                    size += s.st_size
                newest = max(newest, s.st_mtime)
    return size, newest


def _entry(name: str, kind: str, paths: Iterable[Path]) -> CacheEntry:
    paths = tuple(p for p in paths if os.path.lexists(p))
    walked = [_walk(p) for p in paths]
    return CacheEntry(name, kind, sum(s for s, _ in walked),
                      max((m for _, m in walked), default=0.0), paths)


def entries(folder: str | os.PathLike[str] | None = None) -> list[CacheEntry]:
    """The cache's entries, libraries first, then each folder's, by name.

    Parameters
    ----------
    folder : path-like, optional
        The cache folder (default ``quadcog.paths.cache_dir()``).

    Returns
    -------
    list of CacheEntry
        Empty when the folder does not exist.

    Raises
    ------
    InputError
        When ``folder`` exists and is not a folder.
    """
    root = Path(folder) if folder is not None else cache_dir()
    if not os.path.lexists(root):
        return []
    if not root.is_dir() or root.is_symlink():
        raise InputError(f"the cache folder {str(root)!r} is not a folder")
    libs: dict[str, list[Path]] = {}
    folders: list[CacheEntry] = []
    for child in sorted(root.iterdir()):
        if child.is_dir() and not child.is_symlink():
            if child.name not in KINDS:          # not quadcog's: never listed nor removed
                continue
            for sub in sorted(child.iterdir()):
                if sub.name not in _LOCK_NAMES:
                    folders.append(_entry(f"{child.name}/{sub.name}", child.name, [sub]))
            continue
        library = _LIBRARY_FILE.fullmatch(child.name)
        if library and not child.is_dir():
            libs.setdefault(library.group("stem"), []).append(child)
    return [_entry(stem, LIBRARIES, sorted(paths)) for stem, paths in sorted(libs.items())] \
        + folders


def _busy(entry: CacheEntry) -> bool:
    """Whether a build holds this entry's lock now (tried without waiting)."""
    locks = [p for p in entry.paths if p.name.endswith(".lock")]
    locks += [p / n for p in entry.paths if p.is_dir() and not p.is_symlink()
              for n in _LOCK_NAMES if (p / n).is_file()]
    for lock in locks:
        try:
            fh = open(lock, "a+")
        except OSError:
            return True
        with fh:
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                return True
            fcntl.flock(fh, fcntl.LOCK_UN)
    return False


def clear(kinds: Iterable[str] = (), folder: str | os.PathLike[str] | None = None
          ) -> tuple[list[CacheEntry], list[CacheEntry]]:
    """Remove the cache's entries (of ``kinds``, or all), leaving those being built.

    Parameters
    ----------
    kinds : iterable of str
        Kinds to remove (``LIBRARIES``, "px4", "aqb", ...); empty: every kind.
    folder : path-like, optional
        The cache folder (default ``quadcog.paths.cache_dir()``).

    Returns
    -------
    (removed, busy) : two lists of CacheEntry
        What was removed, and what was left because a build holds its lock.

    Raises
    ------
    InputError
        For a kind that is neither one of ``KINDS`` nor a folder of the cache (the message
        lists them).
    """
    if isinstance(kinds, str):
        raise InputError(f"kinds must be a list of kinds, got the string {kinds!r}")
    all_entries = entries(folder)
    wanted = set(kinds)
    known = set(KINDS) | {e.kind for e in all_entries}
    unknown = sorted(wanted - known)
    if unknown:
        raise InputError(f"kinds: no kind {', '.join(map(repr, unknown))} in quadcog's cache; "
                         f"expected some of {', '.join(sorted(known))}")
    removed, busy = [], []
    for e in all_entries:
        if wanted and e.kind not in wanted:
            continue
        if _busy(e):
            busy.append(e)
            continue
        for p in e.paths:
            if p.is_dir() and not p.is_symlink():
                shutil.rmtree(p, ignore_errors=True)
            else:
                try:
                    p.unlink()
                except FileNotFoundError:
                    pass
        removed.append(e)
    return removed, busy


def human_size(n: int) -> str:
    """Bytes as B, KB, MB or GB (powers of 1024), one decimal above bytes.

    Parameters
    ----------
    n : int
        Bytes.

    Returns
    -------
    str
        E.g. "512 B", "3.4 MB".
    """
    for unit, scale in (("GB", 1 << 30), ("MB", 1 << 20), ("KB", 1 << 10)):
        if n >= scale:
            return f"{n / scale:.1f} {unit}"
    return f"{n} B"
