"""Argument checks shared by the public helpers of quadcog.identification.

Each check takes the value and ``where`` (``"function: argument"``) and raises
``IdentificationError`` (a ``quadcog.InputError``) in quadcog.validate's grammar
(``"{where}: expected {what}, got {value}"``) before any computation.
"""
import numbers
import os
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from quadcog.errors import IdentificationError
from quadcog.validate import array, fail, plain

__all__ = ["vehicle", "rotor_model", "text", "path", "sequence", "rows", "block_index", "mask"]


def vehicle(value: object, where: str) -> None:
    """Refuse anything but a quadcog Vehicle.

    Parameters
    ----------
    value : object
        What was passed.
    where : str
        ``"function: argument"``, the start of the message.

    Raises
    ------
    IdentificationError
        ``value`` is not a Vehicle.
    """
    from quadcog.vehicles.vehicle import Vehicle
    if not isinstance(value, Vehicle):
        fail(where, "a quadcog Vehicle", value, IdentificationError)


def rotor_model(value: object, where: str) -> None:
    """Refuse a rotor model that is neither None, a name (str) nor a RotorModel (the name
    itself is checked where it is looked up).

    Parameters
    ----------
    value : object
        What was passed.
    where : str
        ``"function: argument"``, the start of the message.

    Raises
    ------
    IdentificationError
        ``value`` of another type.
    """
    from quadcog.vehicles.rotor_model import RotorModel
    if value is not None and not isinstance(value, (str, RotorModel)):
        fail(where, "a RotorModel, a name of quadcog.vehicles.rotor_model.ROTOR_MODELS or "
             "None", value, IdentificationError)


def text(value: object, where: str) -> str:
    """A ``str`` (numpy's str_ too), returned as a plain str.

    Parameters
    ----------
    value : object
        What was passed.
    where : str
        ``"function: argument"``, the start of the message.

    Returns
    -------
    str
        ``value``.

    Raises
    ------
    IdentificationError
        ``value`` is not a string.
    """
    if not isinstance(value, str):
        fail(where, "a str", value, IdentificationError)
    return str(value)


def path(value: object, where: str) -> Path:
    """A file or folder path: a non-empty str or os.PathLike (not bytes).

    Parameters
    ----------
    value : object
        What was passed.
    where : str
        ``"function: argument"``, the start of the message.

    Returns
    -------
    pathlib.Path
        ``Path(value)``.

    Raises
    ------
    IdentificationError
        Not a path, or an empty one (``Path("")`` is the working folder).
    """
    if not isinstance(value, (str, os.PathLike)) or isinstance(value, bytes) \
            or not os.fspath(value):
        fail(where, "a path (a non-empty str or pathlib.Path)", value, IdentificationError)
    return Path(value)


def sequence(value: object, where: str, kind: type | tuple[type, ...], what: str,
             min_items: int = 0) -> list[Any]:
    """A list or tuple whose items are all of ``kind``.

    Parameters
    ----------
    value : object
        What was passed.
    where : str
        ``"function: argument"``, the start of the message; a bad item is ``where[i]``.
    kind : type or tuple of type
        The items' type.
    what : str
        The items' name in messages (``"FlightLog"``).
    min_items : int, optional
        The fewest items accepted.

    Returns
    -------
    list
        The items.

    Raises
    ------
    IdentificationError
        Not a list or tuple (a str, a generator), too few items, an item of another type.
    """
    expected = f"a list or tuple of {what}" + (f" (at least {min_items})" if min_items else "")
    if not isinstance(value, (list, tuple)) or len(value) < min_items:
        fail(where, expected, value, IdentificationError)
    for i, item in enumerate(value):
        if not isinstance(item, kind):
            fail(f"{where}[{i}]", f"a {what}", item, IdentificationError)
    return list(value)


def rows(value: object, where: str, columns: int | None = None, min_rows: int = 0,
         n_rows: int | None = None, ndim: int | None = None) -> npt.NDArray[np.float64]:
    """A finite real array (float64 copy) of one row per sample or block: (B,) or (B, ...).

    Parameters
    ----------
    value : object
        What was passed.
    where : str
        ``"function: argument"``, the start of the message.
    columns : int, optional
        The array is (B, columns).
    min_rows : int, optional
        The fewest rows B accepted.
    n_rows : int, optional
        The exact number of rows B.
    ndim : int, optional
        The exact number of dimensions (default: at least 1).

    Returns
    -------
    numpy.ndarray of float64
        The array.

    Raises
    ------
    IdentificationError
        Not real numbers (bools, complex, strings, objects, masked entries), NaN or inf, or
        another shape.
    """
    if columns is not None:
        shape_text = f"shape (B, {columns})"
    elif ndim == 1:
        shape_text = "shape (B,)"
    else:
        shape_text = "shape (B, ...)"
    need = ([f"B = {n_rows}"] if n_rows is not None else []) + \
        ([f"B >= {min_rows}"] if min_rows and n_rows is None else [])
    what = f"an array of {shape_text}" + (f" with {', '.join(need)}" if need else "")
    a = array(value, where, what=what, error=IdentificationError)   # type: ignore[arg-type]
    if (a.ndim < 1 or (ndim is not None and a.ndim != ndim)
            or (columns is not None and (a.ndim != 2 or a.shape[1] != columns))
            or a.shape[0] < min_rows or (n_rows is not None and a.shape[0] != n_rows)):
        raise IdentificationError(f"{where}: expected {what}, got shape {a.shape}"
                                  + (f" ({plain(value)})" if a.size <= 8 else ""))
    return a


def block_index(value: object, where: str) -> npt.NDArray[np.intp]:
    """Block numbers (n,): integers from -1 (no block) to n - 1.

    Parameters
    ----------
    value : object
        What was passed (an integer array, or a list or tuple of ints).
    where : str
        ``"function: argument"``, the start of the message.

    Returns
    -------
    numpy.ndarray of intp
        The block numbers.

    Raises
    ------
    IdentificationError
        Not integers (bools, floats, ...), not one-dimensional, or a number outside -1 .. n - 1
        (a block without samples has no mean).
    """
    what = "a 1-D array of integer block numbers, -1 (no block) to n - 1"
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "iu" or value.ndim != 1 or np.ma.is_masked(value):
            fail(where, what, value, IdentificationError)
        n = len(value)
        if n and (int(value.min()) < -1 or int(value.max()) > n - 1):
            fail(where, what, value, IdentificationError)
        return np.asarray(value, dtype=np.intp)
    if not isinstance(value, (list, tuple)):
        fail(where, what, value, IdentificationError)
    n = len(value)
    for i, v in enumerate(value):
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Integral) \
                or not -1 <= int(v) <= n - 1:
            fail(f"{where}[{i}]", f"an integer block number in [-1, {n - 1}]", v,
                 IdentificationError)
    return np.array([int(v) for v in value], dtype=np.intp)


def mask(value: object, where: str, n: int) -> npt.NDArray[np.bool_]:
    """A boolean mask of ``n`` samples with at least one True.

    Parameters
    ----------
    value : object
        What was passed.
    where : str
        ``"function: argument"``, the start of the message.
    n : int
        The log's samples.

    Returns
    -------
    numpy.ndarray of bool
        ``value``.

    Raises
    ------
    IdentificationError
        Not a bool array of shape (n,) (integers would index samples, not mask them), or
        selecting no sample.
    """
    what = f"a bool array of shape ({n},) selecting at least one sample"
    if not isinstance(value, np.ndarray) or value.dtype != np.bool_ or value.shape != (n,) \
            or np.ma.is_masked(value) or not value.any():
        fail(where, what, value, IdentificationError)
    return np.asarray(value)
