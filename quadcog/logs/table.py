"""Flight logs as tables with named columns: CSV and Parquet.

The columns are ``t_s`` (s) and, for each standard signal, its columns
(``quadcog.logs.signals.signal_columns``: ``position_x_m``, ``roll_rad``,
``motor_command_m1``, ...), already in SI units and quadcog's frames. A signal is read when all
its columns are there; every column (signal or not) is also kept under its name in ``raw``.
Time is taken as written, shifted to start at 0 (``meta["time_offset_s"]`` is the first
``t_s``); rows are not resampled. An empty cell, ``nan``, text, or time that does not increase
is refused with the row and column named: a cell is a plain decimal number in ASCII (an
optional sign, digits, a point, an exponent: ``-1.5e-3``), optionally quoted; ``#`` is not a
comment, and ``1_000`` or digits of other scripts are refused, not read, as is a number
beyond the float range either way (``1e400``, or ``1e-400``, which would read as 0). A CSV
file is UTF-8 text; a byte-order mark in front of it is dropped.

Every source's cells then pass one check (``_check_cells``), in the type the file holds:
finite, a float not below the normal range of its type (a Parquet float32 subnormal too),
an integer not beyond 2^53 (``quadcog.logs.limits.EXACT_INTEGER``: float64 would change its
digits). Column names appear once (a CSV header's, a Parquet schema's). A Parquet file's pages
are checked against their CRC-32 where it has them (the writer writes them).
"""
from collections import Counter
import csv
import io
import math
import os
from pathlib import Path
import re
from types import ModuleType
import warnings

import numpy as np

from quadcog.errors import LogError, LogFormatError, LogSignalError
from quadcog.files import CSV_BLOCK, replacing
from quadcog.logs.access import log_path, writer_path
from quadcog.logs.flightlog import FlightLog
from quadcog.logs.limits import EXACT_INTEGER
from quadcog.logs.signals import SIGNALS, TIME_COLUMN, signal_columns, table_columns
from quadcog.validate import fail, import_extra

__all__ = ["read_table", "write_table", "require_pyarrow", "TABLE_FORMATS"]

TABLE_FORMATS = ("csv", "parquet")          # the formats of LOG_FORMATS that are tables



def require_pyarrow() -> ModuleType:
    """The ``pyarrow.parquet`` module, or a typed error giving the install command.

    Returns
    -------
    module
        ``pyarrow.parquet``.

    Raises
    ------
    MissingDependencyError
        pyarrow is not installed.
    """
    return import_extra("sweep", "pyarrow.parquet")


def _table_format(fmt, where):
    """``fmt`` as one of ``TABLE_FORMATS`` (a str, numpy's str_ too)."""
    if not isinstance(fmt, str) or fmt not in TABLE_FORMATS:
        fail(where, f"one of {', '.join(map(repr, TABLE_FORMATS))}", fmt, LogError)
    return str(fmt)


def _check_cells(path, name, a):
    """Refuse a column's cell that is not a finite number, a nonzero float below the normal
    range of its type (a subnormal: digits lost, as a CSV cell below ``FLOAT_TINY`` would
    be) or an integer beyond ``EXACT_INTEGER`` (float64 would change its last digits); every
    table source goes through here, in the type its file holds."""
    bad = ~np.isfinite(a)
    if bad.any():
        i = int(np.argmax(bad))
        raise LogFormatError(f"{path}: column {name!r}, data row {i + 1}: "
                             f"{float(a[i])!r} is not a finite number")
    if a.dtype.kind in "iu":
        big = (a > EXACT_INTEGER) | (a < -EXACT_INTEGER)
        if big.any():
            i = int(np.argmax(big))
            raise LogFormatError(f"{path}: column {name!r}, data row {i + 1}: the integer "
                                 f"{int(a[i])} is beyond 2^53 in magnitude, where a float64 "
                                 "no longer holds every integer (its last digits would be "
                                 "lost); expected a number of a flight log")
    if a.dtype.kind == "f":
        tiny = float(np.finfo(a.dtype).tiny)
        small = (a != 0) & (np.abs(a) < tiny)
        if small.any():
            i = int(np.argmax(small))
            raise LogFormatError(f"{path}: column {name!r}, data row {i + 1}: "
                                 f"{float(a[i])!r} is below the range of a {a.dtype} (a "
                                 f"subnormal: a nonzero magnitude is at least {tiny:.4g}); "
                                 "expected a normal number or 0")


def _from_columns(path, fmt, columns, meta):
    """A FlightLog of {column name: 1-D numeric array}, each checked (``_check_cells``) in
    the type the file holds, then taken as float64; the time column, strictly increasing."""
    if TIME_COLUMN not in columns:
        raise LogFormatError(f"{path}: no time column {TIME_COLUMN!r}; columns are "
                             f"{', '.join(columns) or 'none'}")
    for name, a in columns.items():
        _check_cells(path, name, a)
    columns = {name: np.asarray(a, dtype=np.float64) for name, a in columns.items()}
    t_abs = columns[TIME_COLUMN]
    if t_abs.size < 2:
        raise LogFormatError(f"{path}: {t_abs.size} data rows; a flight log needs at least 2")
    with np.errstate(over="ignore", invalid="ignore"):     # checked below, in the log's terms
        steps = np.diff(t_abs)
        t_rel = t_abs - t_abs[0]
    if not np.isfinite(t_rel).all():
        raise LogFormatError(f"{path}: column {TIME_COLUMN!r} runs from {float(t_abs[0])!r} s "
                             f"to {float(t_abs[-1])!r} s, a span beyond the range of a float; "
                             "expected the times of one flight (s)")
    if not (steps > 0).all():
        i = int(np.argmax(steps <= 0))
        raise LogFormatError(f"{path}: column {TIME_COLUMN!r} is not strictly increasing: data "
                             f"row {i + 2} has {float(t_abs[i + 1])!r} s after "
                             f"{float(t_abs[i])!r} s")
    signals = {}
    for name in SIGNALS:
        cols = signal_columns(name)
        present = [c for c in cols if c in columns]
        if not present:
            continue
        if len(present) < len(cols):
            missing = [c for c in cols if c not in columns]
            raise LogFormatError(f"{path}: signal {name!r} has columns {present} but lacks "
                                 f"{missing}; expected all of {list(cols)}")
        a = np.column_stack([columns[c] for c in cols])
        signals[name] = a[:, 0] if not SIGNALS[name].shape else a
    raw = {k: v for k, v in columns.items() if k != TIME_COLUMN}
    meta = dict(meta, time_offset_s=repr(float(t_abs[0])))
    return FlightLog(str(path), fmt, t_rel, signals, raw, meta)


# UTF-8; a byte-order mark in front (spreadsheets' "CSV UTF-8") is dropped, not read as the
# start of the first column's name
READ_ENCODING = "utf-8-sig"

# The longest cell read: a float64 written with every digit takes 24 characters; anything
# much longer is not a number (Python's csv module stops at 131,072 with its own error).
MAX_CELL = 1000
FLOAT_MAX = float(np.finfo(np.float64).max)
# The smallest normal float: a nonzero cell below it reads as 0.0 or a subnormal (digits
# lost), so it is refused as the cell beyond FLOAT_MAX is
FLOAT_TINY = float(np.finfo(np.float64).tiny)
# Text that may hold such a cell: a number below 1e-307 has an exponent of 3 digits or, with
# one of at most 2, a run of over 200 zeros after its point (false alarms only cost the
# cell-by-cell reading, which decides)
_TINY_EXPONENT = re.compile(r"[eE]-[0-9]{3}")
_TINY_ZEROS = "0" * 200

# A plain decimal number, the one form of cell read (float() also takes "1_000", other
# scripts' digits and surrounding Unicode blanks; numpy's parser takes "#" as a comment)
_NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
# nan and inf, read so that the log's check refuses them with their place (_from_columns)
_NOT_FINITE = re.compile(r"[+-]?(?:nan|inf|infinity)", re.IGNORECASE)
# The characters of plain numbers, separators, quotes and line breaks: numpy's fast parser
# is used only on text of these alone, anything else goes cell by cell through _cells
_PLAIN_BYTES = b'0123456789eE+-.,"\r\n \t'


def _may_underflow(text):
    """Whether ``text`` may hold a nonzero number below ``FLOAT_TINY`` (linear: C searches)."""
    return _TINY_ZEROS in text or _TINY_EXPONENT.search(text) is not None


def _plain(text):
    """Whether ``text`` has only ``_PLAIN_BYTES`` (bytes.translate: C speed, linear)."""
    return text.isascii() and not text.encode("ascii").translate(None, _PLAIN_BYTES)


def _read_csv(path):
    """Header by the csv module, data rows by numpy's C parser (time and memory linear in
    the file: one float64 per cell); a file it cannot parse is read again cell by cell to
    name the first bad cell."""
    try:
        with open(path, newline="", encoding=READ_ENCODING) as f:
            header, lines_before = _header(path, f)
            rest = f.read()
        ok = _plain(rest) and not _may_underflow(rest)
        if ok:
            try:
                with warnings.catch_warnings():      # a header without rows: said below
                    warnings.simplefilter("ignore", UserWarning)
                    data = np.loadtxt(io.StringIO(rest), delimiter=",", dtype=np.float64,
                                      ndmin=2, quotechar='"', comments=None)
                # a cell beyond the float range reads as inf: named by _cells as written
                ok = (data.shape[1] == len(header) or data.size == 0) and \
                    bool(np.isfinite(data).all())
            except (ValueError, OverflowError):
                ok = False
        del rest
        if not ok:        # read again cell by cell: names the first bad cell
            data = _cells(path, header, lines_before)
    except UnicodeDecodeError as e:
        raise LogFormatError(f"{path}: not a text (UTF-8) CSV file ({e.reason} at byte "
                             f"{e.start})") from None
    data = data.reshape(-1, len(header))
    cols = {h: data[:, j].copy() for j, h in enumerate(header)}
    return _from_columns(path, "csv", cols, {"columns": str(len(header))})


def _header(path, f):
    """The header row (names stripped) of an open CSV file, and the lines it took."""
    count = 0
    for line in f:
        count += 1
        if line.strip(" ,\r\n\t"):
            break
    else:
        raise LogFormatError(f"{path}: empty CSV file; expected a header row with "
                             f"{TIME_COLUMN!r} and signal columns")
    if len(line) > MAX_CELL * 100_000:
        raise LogFormatError(f"{path}: line {count} (the header) has {len(line):,} characters")
    try:
        cells = next(csv.reader([line]))
    except csv.Error as e:
        raise LogFormatError(f"{path}: line {count} (the header) is not CSV ({e})") from None
    header = [c.strip() for c in cells]
    long = [c for c in header if len(c) > MAX_CELL]
    if long:
        raise LogFormatError(f"{path}: the header has a column name of {len(long[0]):,} "
                             f"characters ({long[0][:20]!r}...); expected names of at most "
                             f"{MAX_CELL}")
    _check_names(path, header)
    return header, count


def _check_names(path, names):
    """Refuse a table whose columns repeat a name (which column would be the signal?)."""
    seen = Counter(names)
    dup = sorted(c for c, k in seen.items() if k > 1)
    if dup:
        raise LogFormatError(f"{path}: repeated column names {dup[:10]}; expected each "
                             "column once")


def _cells(path, header, skip):
    """The data rows as floats, cell by cell: the first bad cell raises with its place."""
    rows = []
    with open(path, newline="", encoding=READ_ENCODING) as f:
        for _ in range(skip):
            next(f)
        reader = csv.reader(f)
        while True:
            try:
                row = next(reader)
            except StopIteration:
                break
            except csv.Error as e:
                raise LogFormatError(f"{path}: line {skip + reader.line_num}: not CSV ({e}); "
                                     f"expected numbers of at most {MAX_CELL} characters") \
                    from None
            line = skip + reader.line_num
            if not row or (len(row) == 1 and not row[0].strip(" \t")):
                continue            # a blank line (a row of empty cells is refused below)
            if len(row) != len(header):
                raise LogFormatError(f"{path}: line {line} has {len(row)} cells, the header "
                                     f"{len(header)}")
            rows.append([_cell(path, line, header[j], cell) for j, cell in enumerate(row)])
    return np.array(rows, dtype=np.float64).reshape(len(rows), len(header))


def _cell(path, line, column, cell):
    """The float of one CSV cell: a plain decimal number (``_NUMBER``) within the float
    range (zero, or a magnitude within ``FLOAT_TINY``..``FLOAT_MAX``), or nan/inf (refused
    later with its place), else a LogFormatError naming it."""
    text = cell.strip(" \t")
    where = f"{path}: line {line}, column {column!r}"
    if len(text) > MAX_CELL:
        raise LogFormatError(f"{where}: a cell of {len(text):,} characters; expected a number")
    shown = repr(text) if len(text) <= 40 else f"{text[:40]!r}... ({len(text):,} characters)"
    if _NUMBER.fullmatch(text):
        value = float(text)
        if not math.isfinite(value):
            raise LogFormatError(f"{where}: {shown} is beyond the range of a float (magnitude "
                                 f"at most {FLOAT_MAX:.4g}): not a finite number")
        mantissa = text.partition("e")[0].partition("E")[0]
        if abs(value) < FLOAT_TINY and mantissa.strip("+-.0"):      # nonzero digits
            raise LogFormatError(f"{where}: {shown} is below the range of a float (a nonzero "
                                 f"magnitude at least {FLOAT_TINY:.4g}): it would read as "
                                 f"{value!r}")
        return value
    if _NOT_FINITE.fullmatch(text):
        return float(text)
    raise LogFormatError(f"{where}: {shown} is not a number; expected a plain decimal number "
                         "(ASCII digits, an optional sign, point and exponent: -1.5e-3)")


def _read_parquet(path):
    pq = require_pyarrow()
    import pyarrow as pa
    try:
        # the names first: pyarrow reads a table of repeated names, then cannot tell its
        # columns apart; the pages' CRC-32 checked where the file has them (write_table
        # writes them): a damaged value is refused, not read
        _check_names(path, pq.read_schema(path).names)
        table = pq.read_table(path, page_checksum_verification=True)
    except UnicodeDecodeError as e:         # a column name or path that is not UTF-8
        raise LogFormatError(f"{path}: not a readable Parquet file (a name in its schema is "
                             f"not UTF-8 text: {e.reason} at byte {e.start})") from None
    except (pa.ArrowException, OSError) as e:
        reason = (str(e).strip().splitlines() or [type(e).__name__])[0]
        raise LogFormatError(f"{path}: not a readable Parquet file ({reason})") from None
    cols = {}
    for name in table.column_names:
        col = table.column(name)
        if not (pa.types.is_floating(col.type) or pa.types.is_integer(col.type)):
            raise LogFormatError(f"{path}: column {name!r} has type {col.type}; expected "
                                 "numbers")
        if col.null_count:
            i = int(np.flatnonzero(np.asarray(col.is_null()))[0])
            raise LogFormatError(f"{path}: column {name!r}, data row {i + 1} is empty (null)")
        cols[name] = np.asarray(col.to_numpy())     # checked in its own type
    return _from_columns(path, "parquet", cols, {"columns": str(len(cols))})


def read_table(path: str | os.PathLike, fmt: str) -> FlightLog:
    """Read a CSV or Parquet flight log.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    fmt : str
        ``"csv"`` or ``"parquet"``.

    Returns
    -------
    FlightLog
        The table's signals, time ``t`` (s) from the ``t_s`` column.

    Raises
    ------
    LogFormatError
        No ``t_s`` column, a cell that is not a finite number (or a nonzero number that
        would read as 0 or a subnormal), time not strictly increasing,
        a signal with only some of its columns, a damaged file.
    MissingDependencyError
        Parquet without pyarrow.
    LogError
        ``path`` not a path or a file that cannot be opened, ``fmt`` not ``"csv"`` or
        ``"parquet"``.
    """
    path = log_path(path, "read_table: path")
    fmt = _table_format(fmt, "read_table: fmt")
    try:
        return _read_csv(path) if fmt == "csv" else _read_parquet(path)
    except OSError as e:            # the CSV file cannot be opened (Parquet's: pyarrow's)
        raise LogError(f"{path}: cannot open the flight log ({e.strerror})") from None


def write_table(log: FlightLog, path: str | os.PathLike, fmt: str) -> Path:
    """Write a log's ``t`` and standard signals as a CSV or Parquet table.

    Parameters
    ----------
    log : FlightLog
        The log; its raw variables are not written.
    path : str or os.PathLike
        The file to write (replaced if it exists).
    fmt : str
        ``"csv"`` (numbers written with every digit: read back exactly; a subnormal,
        below ``FLOAT_TINY`` in magnitude, is written as 0, which the reader takes, where
        it refuses the subnormal) or ``"parquet"`` (float64 columns, subnormals written as
        0 likewise, each page with its CRC-32, which the reader checks).

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    LogSignalError
        A time that is a subnormal (written as 0 it would repeat the time before).
    LogError
        ``log`` not a FlightLog, ``path`` not a file that may be replaced, ``fmt`` not
        ``"csv"`` or ``"parquet"``.
    """
    path = writer_path(log, path, "write_table")
    fmt = _table_format(fmt, "write_table: fmt")
    names = table_columns(log.signals)
    tiny = (log.t != 0) & (np.abs(log.t) < FLOAT_TINY)
    if tiny.any():        # written as 0 it would repeat a time, which the reader refuses
        k = int(np.argmax(tiny))
        raise LogSignalError(f"{log.source}: time t = {float(log.t[k])!r} s at sample {k} is "
                             f"below the range of a float (a subnormal, at most "
                             f"{FLOAT_TINY:.4g} s from 0); cannot write it as {fmt}",
                             source=log.source)
    blocks = [log.t[:, None]] + [log.signals[n].reshape(log.n_samples, -1)
                                for n in SIGNALS if n in log.signals]
    data = np.hstack(blocks)
    pq = require_pyarrow() if fmt == "parquet" else None
    # a subnormal as 0: every table reader refuses subnormals (_check_cells)
    data = np.where(np.abs(data) < FLOAT_TINY, np.copysign(0.0, data), data)
    with replacing(path, "write_log path", LogError) as tmp:
        if pq is None:
            with open(tmp, "w", newline="", encoding="utf-8") as f:
                w = csv.writer(f, lineterminator="\n")
                w.writerow(names)
                for start in range(0, len(data), CSV_BLOCK):
                    w.writerows([[repr(float(x)) for x in row]
                                 for row in data[start:start + CSV_BLOCK].tolist()])
        else:
            import pyarrow as pa
            pq.write_table(pa.table({n: data[:, j] for j, n in enumerate(names)}), tmp,
                           write_page_checksum=True)        # the reader checks them
    return Path(path)
