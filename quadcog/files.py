"""Writing the files of a run: all or nothing, strict JSON, streaming CSV.

``RunFiles`` writes every file of a run under a temporary name in the output folder and renames
them into place together only when all of them are complete (with Ctrl-C held off during the
renames), so an interrupted or failed run leaves the previous run's files as they were and no
mix of the two. ``strict_json`` writes ``null`` where a number is not finite (JSON has no NaN
or Infinity). ``write_csv`` formats the rows block by block, so memory does not grow with the
length of the run beyond the arrays it is given.
"""
from collections.abc import Iterator, Sequence
import contextlib
import csv
import json
import math
import numbers
import os
from pathlib import Path
import platform
import signal
import stat as stat_mod
import threading
from types import TracebackType
from typing import Any, Literal, TextIO

import numpy as np
import numpy.typing as npt

from quadcog.errors import InputError, QuadcogError

__all__ = ["input_file", "CSV_BLOCK", "CSV_DECIMALS", "plain_value", "strict_json", "rounded", "write_csv",
           "plot_text", "RunFiles", "atomic_write", "atomic_write_bytes", "output_path",
           "replacing", "read_json", "MAX_JSON_BYTES", "MAX_JSON_DEPTH", "cpu_model",
           "run_stamp"]

CSV_BLOCK = 1024            # rows formatted at a time
CSV_DECIMALS = 10           # values are rounded to this many decimals ...
_ROUND_BELOW = 1e290        # ... when that cannot overflow (|v| * 10^10 < float max)


def plain_value(value: Any) -> Any:
    """``value`` as plain JSON data: numpy scalars and arrays to Python numbers and lists,
    non-finite floats to None.

    Parameters
    ----------
    value : object
        Nested dicts, lists, tuples, arrays, numbers, paths and strings.

    Returns
    -------
    object
        The same structure of dicts (str keys), lists, bools, ints, floats (finite) or None,
        strings and whatever else was given as it was.
    """
    if isinstance(value, dict):
        return {str(k): plain_value(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [plain_value(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, Path):
        return str(value)
    return value


def strict_json(value: Any) -> str:
    """JSON text of ``value`` (indented, newline-terminated).

    Parameters
    ----------
    value : object
        Anything ``plain_value`` turns into JSON data.

    Returns
    -------
    str
        Standard JSON only, ``null`` where a number is NaN or infinite.
    """
    return json.dumps(plain_value(value), indent=2, allow_nan=False) + "\n"


def rounded(block: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """``block`` rounded to CSV_DECIMALS decimals where that is exact arithmetic.

    np.round multiplies by 10^decimals, which overflows for |v| above ~1e298: those stay as
    they are.

    Parameters
    ----------
    block : numpy.ndarray
        Floats of any shape.

    Returns
    -------
    numpy.ndarray
        A new array of the same shape.
    """
    with np.errstate(over="ignore", invalid="ignore"):
        return np.where(np.abs(block) < _ROUND_BELOW, np.round(block, CSV_DECIMALS), block)


def write_csv(fh: TextIO, header: Sequence[str], columns: Sequence[npt.NDArray[Any]],
              n_rows: int) -> None:
    """Write ``header`` and ``n_rows`` rows to the text file ``fh``.

    Rows are formatted CSV_BLOCK at a time (Python's float repr after rounding), so the extra
    memory is one block.

    Parameters
    ----------
    fh : file object
        A text file open for writing.
    header : sequence of str
        The column names (the first line).
    columns : sequence of numpy.ndarray
        Arrays of shape (n_rows,) or (n_rows, k), concatenated side by side.
    n_rows : int
        The number of rows to write.

    Returns
    -------
    None
        The rows are written to ``fh``.
    """
    writer = csv.writer(fh, lineterminator="\n")
    writer.writerow(header)
    for start in range(0, n_rows, CSV_BLOCK):
        stop = min(start + CSV_BLOCK, n_rows)
        block = np.hstack([np.asarray(c[start:stop], dtype=float).reshape(stop - start, -1)
                           for c in columns])
        writer.writerows(rounded(block).tolist())


@contextlib.contextmanager
def _no_interrupt() -> Iterator[None]:
    """Hold off SIGINT (Ctrl-C) and SIGTERM for the block; they are delivered right after."""
    main = threading.current_thread() is threading.main_thread()
    if main and hasattr(signal, "pthread_sigmask"):
        old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
        try:
            yield
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)
    else:
        yield


def plot_text(text: object) -> str:
    """``text`` shown literally in a matplotlib title or label.

    ``$`` would start mathtext, and a stray one makes savefig fail.

    Parameters
    ----------
    text : object
        A title or label (converted with ``str``).

    Returns
    -------
    str
        The text with every ``$`` escaped.
    """
    return str(text).replace("$", r"\$")


RUN_FILES = ("metrics.json", "vehicle.json", "trajectory.csv", "trajectory.parquet",
             "flight.png", "flight.gif")
"""Every file `quadcog run` may write into its folder: a run owns them all, so a new run
removes those of an earlier run that it does not write itself."""
COMPLETE_MARKER = "metrics.json"
"""The file whose presence says a run folder is complete: removed first and renamed into
place last, so a folder caught half-way (even by SIGKILL) never looks complete."""


class RunFiles:
    """The files of one run in folder ``out``, committed together.

    Use as a context manager: ``path(name)`` gives the temporary path to write ``name`` to;
    when the block ends without an exception, the files of ``owned`` that this run did not
    write are removed (they belong to an earlier run) and every file is renamed to its final
    name, ``COMPLETE_MARKER`` last; on any exception (Ctrl-C and SIGTERM included) the
    temporary files are removed and the folder keeps what it had.

    Parameters
    ----------
    out : str or os.PathLike
        The run folder (created when missing).
    owned : tuple of str
        Names of the files that belong to a run (default ``RUN_FILES``); ``()`` to add
        files without removing any.

    Returns
    -------
    RunFiles
    """

    def __init__(self, out: str | os.PathLike[str], owned: tuple[str, ...] = RUN_FILES) -> None:
        self.out = Path(out)
        self.owned = tuple(owned)
        self._pending: dict[str, Path] = {}

    def __enter__(self) -> "RunFiles":
        try:
            self.out.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise QuadcogError(f"{self.out}: cannot create the output folder ({e.strerror})") \
                from None
        if not self.out.is_dir():
            raise QuadcogError(f"{self.out}: not a folder")
        return self

    def path(self, name: str | os.PathLike[str]) -> Path:
        """Where to write the file ``name``.

        Parameters
        ----------
        name : str or os.PathLike
            The file's final name in the folder (a directory part is dropped).

        Returns
        -------
        pathlib.Path
            A hidden temporary name in the same folder, with the same suffix (so that writers
            that go by the suffix, like savefig, still work).
        """
        name = Path(name).name
        tmp = self.out / f".{Path(name).stem}.partial-{os.getpid()}{Path(name).suffix}"
        self._pending[name] = tmp
        return tmp

    def __exit__(self, kind: type[BaseException] | None, value: BaseException | None,
                 tb: TracebackType | None) -> Literal[False]:
        if kind is None:
            try:
                with _no_interrupt():
                    self._commit()
            except BaseException:
                self._discard()
                raise
        else:
            self._discard()
        return False

    def _commit(self):
        for name, tmp in self._pending.items():
            if not tmp.is_file():
                raise QuadcogError(f"{self.out / name}: was not written (internal error)")
        names = list(self._pending)
        for name in names:                  # only regular files are replaced
            if os.path.lexists(self.out / name):
                output_path(self.out / name, "run file", QuadcogError)
        marked = self.owned and COMPLETE_MARKER in self.owned
        if marked:
            with contextlib.suppress(FileNotFoundError):
                (self.out / COMPLETE_MARKER).unlink()
        for stale in self.owned:
            if stale not in self._pending:
                with contextlib.suppress(OSError):     # a link, a folder, ...: left alone
                    if stat_mod.S_ISREG(os.lstat(self.out / stale).st_mode):
                        (self.out / stale).unlink()
        last = [n for n in names if n == COMPLETE_MARKER] if marked else []
        for name in [n for n in names if n not in last] + last:
            os.replace(self._pending[name], self.out / name)

    def _discard(self):
        for tmp in self._pending.values():
            with contextlib.suppress(OSError):
                tmp.unlink()


def output_path(path: object, what: str = "output file", error: type[Exception] = InputError,
                protect: Sequence[str | os.PathLike[str]] = ()) -> Path:
    """``path`` checked as a file that may be replaced: a non-empty str or os.PathLike whose
    folder exists, that is not a folder, not a symbolic link, FIFO, device or socket (only a
    regular file is ever replaced), and none of ``protect`` (the command's own input files).

    Parameters
    ----------
    path : object
        What the caller passed.
    what : str
        What the file is, for the message (``"--json"``, ``"write_log path"``).
    error : type, optional
        Exception class raised (default quadcog.InputError).
    protect : sequence of str or os.PathLike
        Files that must not be overwritten (the inputs).

    Returns
    -------
    pathlib.Path
        The path.

    Raises
    ------
    InputError
        (or ``error``) naming the path and why it is refused; nothing is written.
    """
    if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)):
        raise error(f"{what}: expected a file name (str or os.PathLike), got "
                    f"{type(path).__name__} {path!r:.60}")
    target = Path(os.fspath(path))
    if not str(path) or target.name in ("", ".", ".."):
        raise error(f"{what}: expected a file name, got {str(path)!r}")
    folder = target.parent
    if not folder.is_dir():
        raise error(f"{what} {target}: the folder {folder} does not exist (create it first)")
    try:
        st = os.lstat(target)
    except FileNotFoundError:
        st = None
    except OSError as e:
        raise error(f"{what} {target}: cannot be checked ({e.strerror})") from None
    if st is not None:
        mode = st.st_mode
        kinds = ((stat_mod.S_ISDIR, "a folder"), (stat_mod.S_ISLNK, "a symbolic link"),
                 (stat_mod.S_ISFIFO, "a FIFO (named pipe)"), (stat_mod.S_ISCHR, "a device"),
                 (stat_mod.S_ISBLK, "a device"), (stat_mod.S_ISSOCK, "a socket"))
        for test, kind in kinds:
            if test(mode):
                raise error(f"{what} {target}: is {kind}; quadcog replaces only regular files "
                            "(give the name of a new or regular file)")
        for other in protect:
            with contextlib.suppress(OSError):
                if os.path.samefile(target, other):
                    raise error(f"{what} {target}: is the input file {other}; it would be "
                                "overwritten (give another file name)")
    return target


@contextlib.contextmanager
def replacing(path: object, what: str = "output file", error: type[Exception] = InputError,
              protect: Sequence[str | os.PathLike[str]] = ()) -> Iterator[Path]:
    """Write a file all or nothing: yields a hidden temporary path in the same folder (same
    suffix), renamed onto ``path`` when the block ends without an exception (Ctrl-C held off
    during the rename); on any exception the temporary file is removed and ``path`` keeps
    what it had. ``path`` is checked first (``output_path``).

    Parameters
    ----------
    path : object
        The file to write.
    what : str
        What the file is, for messages.
    error : type, optional
        Exception class raised for a refused path or a failed write (default InputError).
    protect : sequence of str or os.PathLike
        Input files that must not be overwritten.

    Yields
    ------
    pathlib.Path
        Where to write the content.

    Raises
    ------
    InputError
        (or ``error``) for a refused path, or an OSError while writing (disk full, no
        permission), naming the file.
    """
    import tempfile
    target = output_path(path, what, error, protect)
    try:
        fd, name = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.",
                                    suffix=f".partial{target.suffix}")
    except OSError as e:
        raise error(f"{what} {target}: cannot write in {target.parent} ({e.strerror})") \
            from None
    tmp = Path(name)
    try:
        # mkstemp makes the file 0600: give it the mode a plain open() would (or the old file's)
        os.fchmod(fd, stat_mod.S_IMODE(os.stat(target).st_mode) if target.exists()
                  else 0o666 & ~_umask())
    except OSError:
        pass
    finally:
        os.close(fd)
    try:
        try:
            yield tmp
            with _no_interrupt():
                output_path(target, what, error, protect)   # nothing took its place meanwhile
                os.replace(tmp, target)
        except OSError as e:
            raise error(f"{what} {target}: cannot be written ({e.strerror or e})") from None
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def atomic_write(path: str | os.PathLike[str], text: str, what: str = "output file",
                 error: type[Exception] = InputError,
                 protect: Sequence[str | os.PathLike[str]] = ()) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename (all or nothing;
    ``replacing``).

    Parameters
    ----------
    path : str or os.PathLike
        The file to write: a new or a regular file (``output_path``).
    text : str
        Its new content.
    what : str
        What the file is, for messages.
    error : type, optional
        Exception class raised (default quadcog.InputError).
    protect : sequence of str or os.PathLike
        Input files that must not be overwritten.

    Returns
    -------
    None
        ``path`` holds ``text`` after the rename.
    """
    with replacing(path, what, error, protect) as tmp:
        tmp.write_text(text, encoding="utf-8")


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes, what: str = "output file",
                       error: type[Exception] = InputError,
                       protect: Sequence[str | os.PathLike[str]] = ()) -> None:
    """Write ``data`` to ``path`` all or nothing (``replacing``).

    Parameters
    ----------
    path : str or os.PathLike
        The file to write: a new or a regular file (``output_path``).
    data : bytes
        Its new content.
    what : str
        What the file is, for messages.
    error : type, optional
        Exception class raised (default quadcog.InputError).
    protect : sequence of str or os.PathLike
        Input files that must not be overwritten.

    Returns
    -------
    None
        ``path`` holds ``data`` after the rename.
    """
    with replacing(path, what, error, protect) as tmp:
        tmp.write_bytes(data)


MAX_JSON_BYTES = 64 * 2 ** 20      # the JSON files quadcog reads are kilobytes
MAX_JSON_DEPTH = 64                # nesting: quadcog's own files nest 3 deep


def _reject_constant(name):
    raise ValueError(f"{name} is not a JSON number (JSON has no NaN or Infinity)")


def _depth(text: str) -> int:
    """The deepest nesting of brackets in JSON text, outside strings (a linear scan)."""
    depth = deepest = 0
    in_string = escaped = False
    for ch in text:
        if in_string:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == '"':
                in_string = False
        elif ch == '"':
            in_string = True
        elif ch in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif ch in "]}":
            depth -= 1
    return deepest


def input_file(path: object, what: str, error: type[Exception] = InputError,
               where: str | None = None) -> Path:
    """``path`` checked as a file to read: a non-empty str or os.PathLike that is not a
    folder, a FIFO, a device or a socket (opening a FIFO blocks until a writer comes; a
    device never ends). A path that does not exist is returned (the reader says so).

    Parameters
    ----------
    path : object
        What the caller passed.
    what : str
        What the file is, for the message (``"a flight log file"``).
    error : type, optional
        Exception class raised (default quadcog.InputError).
    where : str, optional
        The argument's name, for a value that is not a path (default ``what``).

    Returns
    -------
    pathlib.Path
        The path.

    Raises
    ------
    InputError
        (or ``error``) naming the path, or the argument and the value given.
    """
    text = None if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)) \
        else os.fspath(path)
    if not isinstance(text, str) or not text.strip():
        raise error(f"{where or what}: expected the path of {what} (a str or os.PathLike), "
                    f"got {type(path).__name__} {path!r:.60}")
    p = Path(text)
    if p.is_dir():
        raise error(f"{p}: is a folder; expected {what}")
    if p.exists() and not p.is_file():     # a FIFO or a device would block or never end
        raise error(f"{p}: is not a regular file (a FIFO, a device or a socket); expected "
                    f"{what}")
    return p


def read_json(path: str | os.PathLike[str], what: str = "JSON file",
              error: type[Exception] = InputError) -> Any:
    """The data of a JSON file written by quadcog (or by hand), refused with ``error``
    naming the file when it is not such data: unreadable, not UTF-8, not JSON, over
    ``MAX_JSON_BYTES``, nested deeper than ``MAX_JSON_DEPTH`` (Python's parser would recurse
    until RecursionError), holding NaN or Infinity, or an integer of more digits than Python
    converts (4300).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        What the file is, for the message.
    error : type, optional
        Exception class raised (default quadcog.InputError).

    Returns
    -------
    object
        The parsed JSON value.

    Raises
    ------
    InputError
        (or ``error``) naming the file and what is wrong.
    """
    if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)) or not str(path):
        raise error(f"{what}: expected a file name (str or os.PathLike), got "
                    f"{type(path).__name__} {path!r:.60}")
    p = Path(path)
    if p.exists() and not p.is_file():      # a folder, a FIFO or a device: never read
        raise error(f"{p}: is not a regular file; expected a {what}")
    try:
        size = p.stat().st_size
        if size > MAX_JSON_BYTES:
            raise error(f"{p}: {size:,} bytes; a {what} is at most {MAX_JSON_BYTES:,}")
        text = p.read_bytes().decode("utf-8")
    except OSError as e:
        raise error(f"{p}: cannot read the {what} ({e.strerror})") from None
    except UnicodeDecodeError as e:
        raise error(f"{p}: the {what} is not UTF-8 text (byte {e.start})") from None
    if _depth(text) > MAX_JSON_DEPTH:
        raise error(f"{p}: the {what} nests more than {MAX_JSON_DEPTH} levels deep; not a "
                    "file quadcog writes")
    try:
        return json.loads(text, parse_constant=_reject_constant)
    except (ValueError, RecursionError) as e:       # bad JSON, huge integers
        raise error(f"{p}: the {what} is not valid JSON ({str(e)[:200]})") from None


def cpu_model() -> str:
    """The CPU's model name, as /proc/cpuinfo gives it.

    Returns
    -------
    str
        E.g. "AMD EPYC 7763 64-Core Processor"; ``platform.processor()`` or the architecture
        where there is no /proc/cpuinfo.
    """
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith(("model name", "Model", "Hardware")):
                return line.partition(":")[2].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def run_stamp() -> str:
    """Where and when a run measured: the line a command writes beside its figures, which the
    documentation copies with them (``bench/publish.py``).

    Returns
    -------
    str
        E.g. "on AMD EPYC 7763 64-Core Processor (x86_64), 2 cores, 2026-12-01".
    """
    import datetime
    day = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d")
    return f"on {cpu_model()} ({platform.machine()}), {os.cpu_count()} cores, {day}"
