"""The files of quadcog.logs' readers and writers, checked in one place: what a reader
takes for a log file's path (``log_path``) and how it reads one (``read_bytes``), what a writer
takes for its log and its file (``writer_path``). ``read_log``, ``write_log`` and each format's
reader and writer (quadcog.logs.crazyflie, quadcog.logs.ulog, quadcog.logs.table) use them."""
import os
from pathlib import Path

from quadcog.errors import LogError
from quadcog.files import input_file, output_path
from quadcog.validate import fail

__all__ = ["log_path", "read_bytes", "writer_path"]


def log_path(path: object, where: str) -> Path:
    """``path`` checked as a flight log to read: a non-empty str or os.PathLike naming a file
    (not a folder, a FIFO or a device: quadcog.files.input_file). Every reader of
    quadcog.logs checks its path here (an int is no path: ``open(1)`` would read, then close,
    the standard output).

    Parameters
    ----------
    path : object
        What the caller passed.
    where : str
        ``"function: argument"``, the start of the message.

    Returns
    -------
    pathlib.Path
        The path (it may not exist: ``read_bytes`` says so).

    Raises
    ------
    LogError
        Not a path, or a folder, a FIFO, a device.
    """
    if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)) or \
            not isinstance(os.fspath(path), str) or not os.fspath(path):
        fail(where, "the path of a flight log file (str or os.PathLike)", path, LogError)
    return input_file(path, "a flight log file", LogError, where)


def read_bytes(path: Path) -> bytes:
    """The content of a flight log file, or a LogError naming it and the system's reason.

    Parameters
    ----------
    path : pathlib.Path
        A path checked by ``log_path``.

    Returns
    -------
    bytes
        The file's content.

    Raises
    ------
    LogError
        The file cannot be opened or read (missing, no permission, ...).
    """
    try:
        return path.read_bytes()
    except OSError as e:
        raise LogError(f"{path}: cannot open the flight log ({e.strerror})") from None


def writer_path(log: object, path: object, where: str) -> Path:
    """The arguments of every writer of quadcog.logs, checked before a byte is written:
    ``log`` a FlightLog, ``path`` a file that may be replaced (``quadcog.files.output_path``:
    not a folder, a link, a FIFO or a device).

    Parameters
    ----------
    log : object
        What the caller passed as the log.
    path : object
        What the caller passed as the file.
    where : str
        The writer's name, for the message.

    Returns
    -------
    pathlib.Path
        The file to write.

    Raises
    ------
    LogError
        ``log`` not a FlightLog, ``path`` not a file that may be replaced.
    """
    from quadcog.logs.flightlog import FlightLog
    if not isinstance(log, FlightLog):
        fail(f"{where}: log", "a quadcog.logs.FlightLog", log, LogError)
    return output_path(path, f"{where} path", LogError)
