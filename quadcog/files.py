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
import re
import signal
import stat as stat_mod
import threading
from types import TracebackType
from typing import Any, Literal, TextIO

import numpy as np
import numpy.typing as npt

from quadcog.errors import InputError, QuadcogError

__all__ = ["input_file", "path_kind", "same_file", "check_outputs", "one_line", "make_folder",
           "creatable_folder", "remove_made", "CSV_BLOCK", "CSV_DECIMALS", "plain_value",
           "strict_json", "rounded", "write_csv", "plot_text", "RunFiles", "atomic_write",
           "atomic_write_bytes", "save_figure", "output_path", "replacing", "read_json",
           "MAX_JSON_BYTES", "MAX_JSON_DEPTH", "cpu_model", "run_stamp"]

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
    protect : sequence of str or os.PathLike
        The command's input files: none of them is replaced or removed (checked again at
        the commit; commands check up front with ``check_outputs``).

    Returns
    -------
    RunFiles
    """

    def __init__(self, out: str | os.PathLike[str], owned: tuple[str, ...] = RUN_FILES,
                 protect: Sequence[str | os.PathLike[str]] = ()) -> None:
        self.out = Path(out)
        self.owned = tuple(owned)
        self.protect = tuple(protect)
        self._pending: dict[str, Path] = {}
        self._made: list[Path] = []

    def __enter__(self) -> "RunFiles":
        self._made = make_folder(self.out, "output folder", QuadcogError)
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
        for name in names:                  # only regular files are replaced, never an input
            if os.path.lexists(self.out / name):
                output_path(self.out / name, "run file", QuadcogError, self.protect)
        for stale in self.owned:            # an earlier run's file that is an input stays
            if stale not in self._pending and any(same_file(self.out / stale, p)
                                                  for p in self.protect):
                raise QuadcogError(f"run file {_describe(self.out / stale)}: is an input of "
                                   "this command; it would be removed (give another --out)")
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
        remove_made(self._made)


def make_folder(path: str | os.PathLike[str], what: str = "--out",
                error: type[Exception] = QuadcogError) -> list[Path]:
    """Create the folder ``path`` and its missing parents.

    Parameters
    ----------
    path : str or os.PathLike
        The folder.
    what : str
        What it is, for the message (``"--out"``).
    error : type, optional
        Exception class raised (default QuadcogError).

    Returns
    -------
    list of pathlib.Path
        The folders this call created, deepest first (for ``remove_made`` when the command
        then fails before writing anything).

    Raises
    ------
    QuadcogError
        (or ``error``) naming the folder when it cannot be made.
    """
    target = Path(path)
    missing = []
    for folder in [target, *target.parents]:
        if os.path.lexists(folder):
            break
        missing.append(folder)
    try:
        target.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        remove_made(missing)
        raise error(f"{what} {one_line(str(path))}: cannot create the folder "
                    f"({e.strerror})") from None
    return missing


def creatable_folder(path: str | os.PathLike[str], what: str = "--out",
                     error: type[Exception] = QuadcogError) -> Path:
    """``path`` checked, before any work, as a folder that exists or can be made: its
    nearest existing ancestor must be a folder this process may write in.

    Parameters
    ----------
    path : str or os.PathLike
        The folder.
    what : str
        What it is, for the message (``"--out"``).
    error : type, optional
        Exception class raised (default QuadcogError).

    Returns
    -------
    pathlib.Path
        The path; nothing is created.

    Raises
    ------
    QuadcogError
        (or ``error``) naming the folder and the ancestor that stops it.
    """
    target = Path(path)
    if target.is_dir():
        return target
    for ancestor in target.parents:
        if os.path.lexists(ancestor):
            if not ancestor.is_dir():
                raise error(f"{what} {_describe(target)}: cannot create the folder "
                            f"({_describe(ancestor)} is not a folder)")
            if not os.access(ancestor, os.W_OK | os.X_OK):
                raise error(f"{what} {_describe(target)}: cannot create the folder (no "
                            f"permission to write in {_describe(ancestor)})")
            break
    return target


def remove_made(folders: Sequence[Path]) -> None:
    """Remove the folders of ``make_folder`` that are still empty, deepest first (a failed
    command leaves no empty folders behind; one that something else wrote into stays).

    Parameters
    ----------
    folders : sequence of pathlib.Path
        As ``make_folder`` returned them.

    Returns
    -------
    None
    """
    for folder in folders:
        try:
            folder.rmdir()
        except OSError:         # not empty (or gone): the ones above are not empty either
            return


def one_line(text: object, digits: int = 30, word: int = 300) -> str:
    """``text`` as one printable line: control and other unprintable characters (a newline
    in a file name) escaped as ``repr`` would, integers of more than ``digits`` digits
    shortened to their first digits and their length, and any other run of more than
    ``word`` characters without a space (a name or path of thousands of characters given on
    the command line) shortened to its start, its length and its end.

    Parameters
    ----------
    text : object
        A message or a value (converted with ``str``).
    digits : int
        The longest run of digits kept as it is.
    word : int
        The longest run of characters without a space kept as it is (at least 40).

    Returns
    -------
    str
        The line, with no line break in it.
    """
    line = "".join(ch if ch.isprintable() or ch == " " else repr(ch)[1:-1]
                   for ch in str(text))
    line = re.sub(r"\d{%d,}" % (digits + 1),
                  lambda m: f"{m.group()[:12]}...({len(m.group())} digits)", line)
    keep = max(int(word), 40)
    return re.sub(r"\S{%d,}" % (keep + 1),
                  lambda m: f"{m.group()[:keep * 2 // 3]}...({len(m.group())} characters)..."
                            f"{m.group()[-(keep // 4):]}", line)


def _describe(path: str | os.PathLike[str]) -> str:
    """``path`` for a message: as given, with line breaks and long numbers shortened."""
    return one_line(os.fspath(path))


def path_kind(path: str | os.PathLike[str]) -> str | None:
    """What ``path`` is when it is not a regular file one can read, in words.

    Parameters
    ----------
    path : str or os.PathLike
        Any path.

    Returns
    -------
    str or None
        None for a regular file (or a link to one), or for a path that does not exist and is
        not a link; else "a folder", "a FIFO (named pipe)", "a device", "a socket", "a
        symbolic link that loops", "a symbolic link to a missing file", or "a path that
        cannot be checked (reason)".
    """
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return "a symbolic link to a missing file" if os.path.islink(path) else None
    except ValueError:                  # os.stat: "embedded null byte"
        return "a path with a null byte (no file has one)"
    except OSError as e:
        import errno
        if e.errno == errno.ELOOP:
            return "a symbolic link that loops (leads back to itself)"
        return f"a path that cannot be checked ({e.strerror})"
    kinds = ((stat_mod.S_ISREG, None), (stat_mod.S_ISDIR, "a folder"),
             (stat_mod.S_ISFIFO, "a FIFO (named pipe)"), (stat_mod.S_ISCHR, "a device"),
             (stat_mod.S_ISBLK, "a device"), (stat_mod.S_ISSOCK, "a socket"))
    for test, kind in kinds:
        if test(mode):
            return kind
    return "not a regular file"


def same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """Whether the paths ``a`` and ``b`` are one file: the same path once resolved
    (symbolic links followed, ``..`` removed; for files that do not exist yet too), or the
    same inode (a hard link, a bind mount).

    Parameters
    ----------
    a : str or os.PathLike
        A path.
    b : str or os.PathLike
        Another path.

    Returns
    -------
    bool
        True when writing one would change the other.
    """
    try:
        if Path(a).resolve() == Path(b).resolve():
            return True
    except (OSError, RuntimeError):     # a symbolic link loop
        pass
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):       # one of them does not exist: not the same file
        return False


def check_outputs(outputs: Sequence[tuple[str, str | os.PathLike[str]]],
                  inputs: Sequence[tuple[str, str | os.PathLike[str]]] = (),
                  error: type[Exception] = InputError,
                  folders: Sequence[tuple[str, str | os.PathLike[str]]] = ()) -> None:
    """Refuse, before any work, a command whose outputs overwrite its inputs or each other.

    Every output is compared with every input and with every other output (``same_file``:
    resolved paths, symbolic links followed, and inodes), and each output that exists must
    be a regular file (``output_path``'s rule); its folder need not exist yet.

    Parameters
    ----------
    outputs : sequence of (str, path)
        (what names it in a message, the file): ``("--json", "r.json")``,
        ``("--out (its metrics.json)", "out/metrics.json")``.
    inputs : sequence of (str, path)
        The files the command reads, named the same way.
    error : type, optional
        Exception class raised (default quadcog.InputError).
    folders : sequence of (str, path)
        Output folders the command writes anything into (a sweep's chunks): no input may lie
        under them.

    Returns
    -------
    None

    Raises
    ------
    InputError
        (or ``error``) naming both files and the options they came from.
    """
    seen: list[tuple[str, str | os.PathLike[str]]] = []
    for what, path in outputs:
        for other_what, other in seen:
            if same_file(path, other):
                raise error(f"{what} {_describe(path)}: is the same file as {other_what} "
                            f"{_describe(other)}; one would overwrite the other (give "
                            "different names)")
            for a, b, a_what, b_what in ((path, other, what, other_what),
                                         (other, path, other_what, what)):
                if same_file(a, Path(b).parent):
                    raise error(f"{a_what} {_describe(a)}: is the folder of {b_what} "
                                f"{_describe(b)}; one cannot be both a file and a folder "
                                "(give different names)")
        seen.append((what, path))
        for in_what, source in inputs:
            if same_file(path, source):
                raise error(f"{what} {_describe(path)}: is the same file as {in_what} "
                            f"{_describe(source)}, which this command reads; it would be "
                            "overwritten (give another output name or folder)")
        if os.path.lexists(path):
            _check_replaceable(Path(path), what, error)
    for what, folder in folders:
        for in_what, source in inputs:
            with contextlib.suppress(OSError, RuntimeError):
                if Path(folder).resolve() in Path(source).resolve().parents:
                    raise error(f"{what} {_describe(folder)}: holds {in_what} "
                                f"{_describe(source)}, which this command reads; it could "
                                "be overwritten (give another output folder)")


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
    text = os.fspath(path)
    if "\0" in text:                    # os.stat would raise "embedded null byte"
        raise error(f"{what}: expected a file name without a null byte, got "
                    f"{one_line(repr(text))}")
    target = Path(text)
    # Path() drops a trailing "/" (and reads "" as "."): judge the text as given
    if not text or target.name in ("", ".", "..") or str(text).endswith(("/", os.sep)):
        raise error(f"{what}: expected a file name (not a folder), got "
                    f"{one_line(repr(str(text)))}")
    folder = target.parent
    if not folder.is_dir():
        raise error(f"{what} {_describe(target)}: the folder {_describe(folder)} does not "
                    "exist (create it first)")
    _check_replaceable(target, what, error)
    for other in protect:
        if same_file(target, other):
            raise error(f"{what} {_describe(target)}: is the input file {_describe(other)}; "
                        "it would be overwritten (give another file name)")
    return target


def _check_replaceable(target: Path, what: str, error: type[Exception]) -> None:
    """Refuse ``target`` when it exists and is not a regular file (never replaced)."""
    try:
        st = os.lstat(target)
    except FileNotFoundError:
        return
    except ValueError:                  # os.lstat: "embedded null byte"
        raise error(f"{what} {_describe(target)}: holds a null byte; no file name can") from None
    except OSError as e:
        raise error(f"{what} {_describe(target)}: cannot be checked ({e.strerror})") from None
    kinds = ((stat_mod.S_ISDIR, "a folder"), (stat_mod.S_ISLNK, "a symbolic link"),
             (stat_mod.S_ISFIFO, "a FIFO (named pipe)"), (stat_mod.S_ISCHR, "a device"),
             (stat_mod.S_ISBLK, "a device"), (stat_mod.S_ISSOCK, "a socket"))
    for test, kind in kinds:
        if test(st.st_mode):
            raise error(f"{what} {_describe(target)}: is {kind}; quadcog replaces only "
                        "regular files (give the name of a new or regular file)")


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


def save_figure(fig: Any, path: str | os.PathLike[str], what: str = "figure",
                error: type[Exception] = InputError, **savefig: Any) -> Path:
    """``fig.savefig`` all or nothing (``replacing``): never through a link, FIFO or device,
    and a failed or interrupted draw leaves the old file.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or os.PathLike
        The file; its suffix is the format (``.png`` without one).
    what : str
        What the file is, for messages.
    error : type, optional
        Exception class raised (default quadcog.InputError).
    **savefig
        Passed on to ``Figure.savefig`` (``dpi``, ``bbox_inches``).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    with replacing(path, what, error) as tmp:
        fig.savefig(tmp, format=Path(os.fspath(path)).suffix[1:] or "png", **savefig)
    return Path(path)


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
               where: str | None = None, must_exist: bool = False, hint: str = "") -> Path:
    """``path`` checked as a file to read: a non-empty str or os.PathLike that is not a
    folder, a FIFO, a device, a socket or a symbolic link that loops or leads nowhere
    (opening a FIFO blocks until a writer comes; a device never ends). A path that does not
    exist is returned (the reader says so) unless ``must_exist``.

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
    must_exist : bool
        Refuse a path that does not exist too.
    hint : str
        Appended to the message for a folder (``"; a folder of samples is sample:NAME"``).

    Returns
    -------
    pathlib.Path
        The path.

    Raises
    ------
    InputError
        (or ``error``) naming the path (line breaks escaped) and what it is, or the
        argument and the value given.
    """
    text = None if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)) \
        else os.fspath(path)
    if not isinstance(text, str) or not text.strip():
        raise error(f"{where or what}: expected the path of {what} (a str or os.PathLike), "
                    f"got {type(path).__name__} {path!r:.60}")
    p = Path(text)
    kind = path_kind(p)         # a FIFO or a device would block or never end
    if kind == "a folder":
        raise error(f"{_describe(p)}: is a folder; expected {what}{hint}")
    if kind is not None:
        raise error(f"{_describe(p)}: is {kind}, not a regular file; expected {what}")
    if must_exist and not p.exists():
        raise error(f"{_describe(p)}: no such file; expected {what}")
    return p


def read_json(path: str | os.PathLike[str], what: str = "JSON file",
              error: type[Exception] = InputError) -> Any:
    """The data of a JSON file written by quadcog (or by hand), refused with ``error``
    naming the file when it is not such data: unreadable, not UTF-8, not JSON, over
    ``MAX_JSON_BYTES``, nested deeper than ``MAX_JSON_DEPTH`` (Python's parser would recurse
    until RecursionError), holding NaN or Infinity, an integer of more digits than Python
    converts (4300), or an object that gives a key twice (at any depth; ``json`` would keep
    the last value in silence).

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
    if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)) or not str(path) \
            or "\0" in os.fspath(path):
        raise error(f"{what}: expected a file name (str or os.PathLike, no null byte), got "
                    f"{type(path).__name__} {path!r:.60}")
    p = Path(path)
    if p.exists() and not p.is_file():      # a folder, a FIFO or a device: never read
        raise error(f"{p}: is not a regular file; expected the {what}")
    try:
        size = p.stat().st_size
        if size > MAX_JSON_BYTES:
            raise error(f"{p}: {size:,} bytes; expected the {what} in at most "
                        f"{MAX_JSON_BYTES:,}")
        text = p.read_bytes().decode("utf-8")
    except OSError as e:
        raise error(f"{p}: cannot read the {what} ({e.strerror})") from None
    except UnicodeDecodeError as e:
        raise error(f"{p}: the {what} is not UTF-8 text (byte {e.start})") from None
    if _depth(text) > MAX_JSON_DEPTH:
        raise error(f"{p}: the {what} nests more than {MAX_JSON_DEPTH} levels deep; not a "
                    "file quadcog writes")
    try:
        return json.loads(text, parse_constant=_reject_constant, object_pairs_hook=_pairs)
    except _RepeatedKey as e:
        raise error(f"{p}: key {one_line(repr(e.args[0]))}: expected once in the {what}, got "
                    "it twice (JSON would keep the last value and drop the first)") from None
    except (ValueError, RecursionError) as e:       # bad JSON, huge integers
        raise error(f"{p}: the {what} is not valid JSON ({str(e)[:200]})") from None


class _RepeatedKey(Exception):
    """A JSON object gave this key twice (``read_json`` names the file)."""


def _pairs(items: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object from its pairs as written, or _RepeatedKey."""
    seen: set[str] = set()
    for key, _ in items:
        if key in seen:
            raise _RepeatedKey(key)
        seen.add(key)
    return dict(items)


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
