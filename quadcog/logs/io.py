"""``read_log`` and ``write_log``: one entry point for every log format, and the detection of
a file's format from its content (the magic bytes), then its extension."""
import os
from pathlib import Path
from typing import TYPE_CHECKING

from quadcog.errors import LogError, LogFormatError
from quadcog.logs.access import log_path, writer_path
from quadcog.logs.signals import LOG_FORMATS
from quadcog.validate import plain

if TYPE_CHECKING:
    from quadcog.logs.flightlog import FlightLog

__all__ = ["read_log", "write_log", "detect_format"]

# The first bytes of each binary format (a CSV file is text and has none).
CRAZYFLIE_MAGIC = b"\xbc"
ULOG_MAGIC = b"ULog\x01\x12\x35"
PARQUET_MAGIC = b"PAR1"
_EXTENSIONS = {".csv": "csv", ".parquet": "parquet", ".pq": "parquet", ".ulg": "ulog",
               ".ulog": "ulog", ".bin": "crazyflie-usd"}


def _check_format(fmt, where):
    if not isinstance(fmt, str) or fmt not in LOG_FORMATS:
        raise LogError(f"{where}: format {plain(fmt)} is not one of {LOG_FORMATS}")
    return fmt


def detect_format(path: str | os.PathLike) -> str:
    """The format of a log file, from its first bytes, else its extension.

    Parameters
    ----------
    path : str or os.PathLike
        An existing file.

    Returns
    -------
    str
        One of ``LOG_FORMATS``: ``"crazyflie-usd"`` (first byte 0xBC), ``"ulog"`` (ULog
        magic), ``"parquet"`` (``PAR1``), else by extension (``.csv``, ``.parquet``, ``.pq``,
        ``.ulg``, ``.bin``).

    Raises
    ------
    LogError
        The file cannot be opened; ``LogFormatError`` when it is empty or nothing identifies
        its format.
    """
    path = log_path(path, "detect_format: path")
    try:
        with open(path, "rb") as f:
            head = f.read(len(ULOG_MAGIC))
    except OSError as e:
        raise LogError(f"{path}: cannot open the flight log ({e.strerror})") from None
    if not head:
        raise LogFormatError(f"{path}: empty file; expected a flight log in one of "
                             f"{LOG_FORMATS}")
    if head.startswith(CRAZYFLIE_MAGIC):
        return "crazyflie-usd"
    if head.startswith(ULOG_MAGIC):
        return "ulog"
    if head.startswith(PARQUET_MAGIC):
        return "parquet"
    if path.suffix.lower() in _EXTENSIONS:
        return _EXTENSIONS[path.suffix.lower()]
    raise LogFormatError(
        f"{path}: unknown log format (first bytes {head[:4].hex(' ')}, extension "
        f"{path.suffix!r}); expected a Crazyflie uSD log (0xBC), a ULog file, Parquet, or a "
        "'.csv' file; or pass format=")


def read_log(path: str | os.PathLike, format: str | None = None) -> "FlightLog":
    """Read a flight log into standard signals (SI, quadcog's frames) on one time base.

    Parameters
    ----------
    path : str or os.PathLike
        The log file.
    format : str, optional
        One of ``LOG_FORMATS``; default: detected from the content (Crazyflie magic byte
        0xBC, ULog magic, Parquet magic), then the extension.

    Returns
    -------
    FlightLog
        Its signals in SI units and quadcog's frames, time ``t`` (s) from 0.

    Raises
    ------
    LogError
        Unreadable file; ``LogFormatError`` (damaged content), ``LogCRCError`` (Crazyflie CRC
        mismatch); ``MissingDependencyError`` for Parquet without pyarrow.
    """
    path = log_path(path, "read_log: path")
    fmt = detect_format(path) if format is None else _check_format(format, f"read_log({path})")
    if not path.is_file():
        raise LogError(f"{path}: no such flight log file")
    if fmt == "crazyflie-usd":
        from quadcog.logs.crazyflie import read_usd
        return read_usd(path)
    if fmt == "ulog":
        from quadcog.logs.ulog import read_ulog
        return read_ulog(path)
    from quadcog.logs.table import read_table
    return read_table(path, fmt)


def write_log(log: "FlightLog", path: str | os.PathLike, format: str) -> Path:
    """Write a flight log that ``read_log`` reads back to the same signals (to the format's
    precision).

    Parameters
    ----------
    log : FlightLog
        The log to write (its standard signals; raw variables are not copied).
    path : str or os.PathLike
        The file to write (replaced if it exists).
    format : str
        One of ``LOG_FORMATS``. ``"crazyflie-usd"`` and ``"ulog"`` write the raw variables
        and topics a real log has, in the source's units and frames (float32 values, integer
        motor commands and millivolts for the Crazyflie); ``"csv"`` and ``"parquet"`` the
        signal columns in float64.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    InputError
        Unknown format, or ``log`` is not a FlightLog; ``LogSignalError`` when the format
        cannot carry the log (e.g. a Crazyflie log without position).
    """
    fmt = _check_format(format, f"write_log({path!r:.80})")
    # checked before any work: a folder, a link, a FIFO or a device is never replaced
    path = writer_path(log, path, "write_log")
    if fmt == "crazyflie-usd":
        from quadcog.logs.crazyflie import write_usd
        return write_usd(log, path)
    if fmt == "ulog":
        from quadcog.logs.ulog import write_ulog
        return write_ulog(log, path)
    from quadcog.logs.table import write_table
    return write_table(log, path, fmt)
