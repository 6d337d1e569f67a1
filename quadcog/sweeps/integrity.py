"""What makes a sweep folder trustworthy: chunks that prove which sweep and which rows they
hold, and one writer at a time.

Every chunk file carries, in its Parquet schema metadata, the fingerprint of the expanded
sweep (``Sweep.fingerprint``), its chunk index, the indices of its flights, its row count and
a SHA-256 of its content (``content_checksum``). A resumed sweep re-reads each chunk it finds
and keeps it only when all of these match what this sweep would write there
(``verify_chunk``); anything else (a chunk of another sweep, another chunk's rows, a row
missing or twice, an edited cell, a damaged file) is flown again, and the sweep says so.

``SweepLock`` is ``out/.sweep.lock``, created exclusively and holding the writer's pid and
process start time: a second sweep into the same folder refuses while the first runs; a lock
whose process is gone (killed) is stale and taken over, with a message.
"""
from collections.abc import Callable, Sequence
import contextlib
import hashlib
import json
import os
from pathlib import Path
import socket
from typing import Any

import numpy as np

from quadcog.errors import SweepLockedError

__all__ = ["META_KEY", "LOCK_NAME", "content_checksum", "chunk_metadata", "verify_chunk",
           "columns_of_table", "SweepLock"]

META_KEY = b"quadcog.chunk"     # Parquet schema metadata key of a chunk's identity
LOCK_NAME = ".sweep.lock"


def _cell(v):
    """A JSON-able exact form of one cell: floats by their repr (bit-exact, NaN kept)."""
    if isinstance(v, float):
        return repr(v)
    return v


def content_checksum(table: Any) -> str:
    """SHA-256 of a pyarrow Table's column names, types and every cell.

    Parameters
    ----------
    table : pyarrow.Table
        The chunk's table.

    Returns
    -------
    str
        64 hex digits; equal for two tables exactly when names, types and cells (floats bit
        for bit, by their shortest repr) are equal.
    """
    h = hashlib.sha256()
    for name in table.column_names:
        col = table.column(name)
        h.update(json.dumps([name, str(col.type), [_cell(v) for v in col.to_pylist()]])
                 .encode())
    return h.hexdigest()


def chunk_metadata(table: Any, fingerprint: str, chunk: int, flights: Sequence[int]) -> dict:
    """The schema metadata that identifies a chunk file.

    Parameters
    ----------
    table : pyarrow.Table
        The chunk's rows.
    fingerprint : str
        ``Sweep.fingerprint()`` of the sweep that flew it.
    chunk : int
        Its chunk index.
    flights : list of int
        The flight indices of its rows, in order.

    Returns
    -------
    dict
        ``{META_KEY: JSON bytes}`` to merge into the table's schema metadata.
    """
    return {META_KEY: json.dumps({"fingerprint": fingerprint, "chunk": int(chunk),
                                  "flights": [int(f) for f in flights],
                                  "rows": int(table.num_rows),
                                  "checksum": content_checksum(table)}).encode()}


def verify_chunk(path: str | os.PathLike[str], fingerprint: str, chunk: int,
                 flights: Sequence[int]) -> tuple[Any, str | None]:
    """The table of a chunk file when it is this sweep's chunk ``chunk``, else the reason.

    Parameters
    ----------
    path : path
        The chunk file.
    fingerprint : str
        This sweep's ``Sweep.fingerprint()``.
    chunk : int
        The chunk index expected in the file.
    flights : list of int
        The flight indices expected, in order.

    Returns
    -------
    (pyarrow.Table or None, str or None)
        The table and None when every check passes; None and the reason otherwise.
    """
    import pyarrow.parquet as pq
    try:
        table = pq.read_table(path)
    except Exception as e:      # noqa: BLE001 - any damage (pyarrow raises many kinds)
        return None, f"unreadable ({type(e).__name__}: {str(e)[:120]})"
    meta = (table.schema.metadata or {}).get(META_KEY)
    if meta is None:
        return None, "no record of which sweep wrote it"
    try:
        meta = json.loads(meta)
        checks = [("sweep", meta["fingerprint"], fingerprint),
                  ("chunk index", meta["chunk"], chunk),
                  ("flights", meta["flights"], list(flights)),
                  ("row count", meta["rows"], len(flights))]
    except (ValueError, KeyError, TypeError):
        return None, "its record of which sweep wrote it is damaged"
    for what, found, expected in checks:
        if found != expected:
            return None, f"{what} differs (another sweep's or another chunk's file)"
    if table.num_rows != len(flights):
        return None, f"it has {table.num_rows} rows, expected {len(flights)}"
    if "flight" not in table.column_names or \
            table.column("flight").to_pylist() != list(flights):
        return None, "its rows are not the flights of this chunk"
    if content_checksum(table) != meta.get("checksum"):
        return None, "its content does not match its checksum (edited or damaged)"
    return table, None


def columns_of_table(table: Any) -> dict:
    """{name: numpy array} of a chunk table; text columns as numpy str arrays (dtype 'U'), so
    a resumed chunk and a freshly flown one are the same arrays.

    Parameters
    ----------
    table : pyarrow.Table
        A chunk's rows, one per flight.

    Returns
    -------
    dict of str to numpy.ndarray
        {column: (rows,) array}.
    """
    out = {}
    for name in table.column_names:
        a = table.column(name).to_numpy(zero_copy_only=False)
        if a.dtype == object:
            a = np.array(a.tolist(), dtype=str)
        out[name] = a
    return out


def _start_time(pid):
    """The process's start time (clock ticks since boot, /proc) or None where unknown: a
    recycled pid has another."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
        return int(stat.rsplit(")", 1)[1].split()[19])
    except (OSError, ValueError, IndexError):
        return None


def _alive(pid, start):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    now = _start_time(pid)
    return start is None or now is None or now == start


class SweepLock:
    """``out/.sweep.lock`` held while a sweep writes into ``out`` (a context manager).

    Parameters
    ----------
    out : path
        The sweep's results folder (must exist).
    say : callable(str), optional
        Where to report a stale lock taken over (default: nowhere).

    Raises
    ------
    SweepLockedError
        Another live process holds the lock; the message names its pid.
    """

    def __init__(self, out: "str | os.PathLike",
                 say: "Callable[[str], None] | None" = None) -> None:
        self.path = Path(out) / LOCK_NAME
        self._say = say or (lambda text: None)
        self._held = False

    def __enter__(self):
        me = {"pid": os.getpid(), "start": _start_time(os.getpid()),
              "host": socket.gethostname()}
        for _ in range(3):
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                try:
                    other = json.loads(self.path.read_text())
                    pid, start = int(other["pid"]), other.get("start")
                    host = other.get("host", me["host"])
                except (OSError, ValueError, KeyError, TypeError):
                    pid, start, host = None, None, me["host"]
                if pid is not None and host != me["host"]:
                    raise SweepLockedError(
                        f"{self.path.parent}: a sweep on host {host!r} (pid {pid}) is writing "
                        f"into this folder ({self.path}); wait for it, or delete the lock file "
                        f"if it is no longer running") from None
                if pid is not None and pid != me["pid"] and _alive(pid, start):
                    raise SweepLockedError(
                        f"{self.path.parent}: another sweep (pid {pid}) is writing into this "
                        f"folder ({self.path}); wait for it to end or choose another --out") \
                        from None
                self._say(f"removing the stale lock {self.path} (pid "
                          f"{pid if pid is not None else 'unreadable'}: no longer running)")
                with contextlib.suppress(FileNotFoundError):
                    self.path.unlink()
                continue
            with os.fdopen(fd, "w") as fh:
                fh.write(json.dumps(me) + "\n")
            self._held = True
            return self
        raise SweepLockedError(f"{self.path}: cannot take the lock (it keeps reappearing)")

    def __exit__(self, kind, value, tb):
        if self._held:
            with contextlib.suppress(OSError):
                self.path.unlink()
            self._held = False
        return False

