"""Sweep results as Arrow tables (pyarrow, the ``sweep`` extra)."""
from quadcog.errors import QuadcogError

__all__ = ["require_pyarrow", "to_arrow"]


def require_pyarrow():
    """The pyarrow module, or a QuadcogError saying how to install it."""
    try:
        import pyarrow
        import pyarrow.parquet  # noqa: F401
        return pyarrow
    except ImportError:
        raise QuadcogError("writing sweep results needs pyarrow: pip install 'quadcog[sweep]'") \
            from None


def to_arrow(columns):
    """A pyarrow Table of {name: numpy array}."""
    pa = require_pyarrow()
    arrays = []
    for v in columns.values():
        arrays.append(pa.array(v.tolist() if v.dtype.kind == "U" else v))
    return pa.table(arrays, names=list(columns))
