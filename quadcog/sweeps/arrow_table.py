"""Sweep results as Arrow tables (pyarrow, the ``sweep`` extra)."""
from types import ModuleType
from typing import Any

from numpy.typing import NDArray

from quadcog.validate import import_extra

__all__ = ["require_pyarrow", "to_arrow"]


def require_pyarrow() -> ModuleType:
    """The pyarrow module (with ``pyarrow.parquet`` loaded).

    Returns
    -------
    module
        ``pyarrow``.

    Raises
    ------
    quadcog.errors.MissingDependencyError
        Without pyarrow, saying how to install it.
    """
    import_extra("sweep", "pyarrow.parquet")
    return import_extra("sweep", "pyarrow")


def to_arrow(columns: dict[str, NDArray[Any]]) -> Any:
    """A pyarrow Table of {name: numpy array}.

    Parameters
    ----------
    columns : dict of str to numpy.ndarray
        {column: (n,) array}; string arrays become string columns.

    Returns
    -------
    pyarrow.Table
        The table (pyarrow ships no type stubs: typed as Any).
    """
    pa = require_pyarrow()
    arrays = []
    for v in columns.values():
        arrays.append(pa.array(v.tolist() if v.dtype.kind == "U" else v))
    return pa.table(arrays, names=list(columns))
