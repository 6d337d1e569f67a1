"""Checks of values that come from outside (API arguments, scenario files): one set, shared.

Every check takes the value and ``where``, the name the caller knows it by (an argument such
as ``"duration"``, or ``"fig6.toml: key 'duration'"`` for a scenario file), and returns the
value converted (``float``, a float64 array, ...). A bad value raises ``error`` (default
``quadcog.InputError``) with the message ``"{where}: expected {what}, got {value}"``, the
value written as a plain number (``1e-09``, ``nan``, ``[1.0, 2.0]``), never a numpy repr.

Numbers are real and finite: ``bool`` and ``numpy.bool_`` are not numbers here (``True`` is
not 1 s), strings, complex values (whose imaginary part numpy would drop), ``None`` and
integers beyond the float range are refused; ``numpy`` integer and float scalars
(``np.int64(1)``, ``np.float32(0.5)``) are accepted.
"""
from collections.abc import Callable, Iterable, Sequence
import math
import numbers
import operator
from types import ModuleType
from typing import Any, NoReturn

import numpy as np
import numpy.typing as npt

from quadcog.errors import InputError, QuadcogError

__all__ = ["plain", "fail", "real", "positive", "nonnegative", "integer", "flag", "choice",
           "array", "vector", "poles", "step_count", "BYTES_PER_STEP", "require_extra", "import_extra",
           "user_function"]

_MAX_ITEMS_SHOWN = 8


def plain(value: object) -> str:
    """``value`` written for a message: plain numbers, short lists, a type name otherwise.

    Parameters
    ----------
    value : object
        Any value a caller passed.

    Returns
    -------
    str
        Plain numbers (``1e-09``, ``nan``, never a numpy repr), short lists and tuples of
        them, a shortened string repr, or a description such as ``"a table with keys a, b"``.
    """
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, (np.timedelta64, np.datetime64)):     # numpy calls the first Integral
        return f"a numpy {type(value).__name__} ({value})"
    if isinstance(value, numbers.Integral):
        text = str(int(value))
        return text if len(text) <= 24 else f"an integer of {len(text.lstrip('-'))} digits"
    if isinstance(value, numbers.Real):
        return repr(float(value))
    if isinstance(value, numbers.Complex):
        return repr(complex(value))
    if isinstance(value, (str, bytes)):
        text = repr(value)
        return text if len(text) <= 60 else text[:57] + "...'"
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "biufc" and value.size <= _MAX_ITEMS_SHOWN:
            return plain(value.tolist())
        return f"an array of shape {value.shape} and dtype {value.dtype}"
    if isinstance(value, (list, tuple)):
        if len(value) > _MAX_ITEMS_SHOWN:
            return f"a {type(value).__name__} of {len(value)} items"
        inner = ", ".join(plain(v) for v in value)
        if isinstance(value, list):
            return f"[{inner}]"
        return f"({inner}{',' if len(value) == 1 else ''})"
    if isinstance(value, dict):
        return "a table" if not value else f"a table with keys {', '.join(map(str, value))}"
    if value is None:
        return "None"
    if callable(value):
        return f"the callable {getattr(value, '__name__', type(value).__name__)}"
    return f"a {type(value).__name__}"


def fail(where: str, what: str, value: object,
         error: type[Exception] = InputError) -> NoReturn:
    """Raise ``error("{where}: expected {what}, got {plain(value)}")``.

    Parameters
    ----------
    where : str
        The argument name or scenario key, the start of the message.
    what : str
        What was expected, e.g. ``"a positive number (s)"``.
    value : object
        What was given (written with ``plain``).
    error : type, optional
        Exception class raised (default quadcog.InputError).

    Raises
    ------
    InputError
        Always (or ``error``).
    """
    raise error(f"{where}: expected {what}, got {plain(value)}")


def _is_real_scalar(value):
    """A real number that is not a bool (Python or numpy); 0-d real arrays count."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        return value.dtype.kind in "iuf"
    # numpy registers timedelta64 as an integer: a duration of unknown unit is no number here
    return (isinstance(value, numbers.Real)
            and not isinstance(value, (bool, np.bool_, np.timedelta64, np.datetime64)))


def _describe(lo, hi, lo_open, hi_open, unit):
    if lo is None and hi is None:
        text = "a finite real number"
    elif lo == 0 and hi is None:
        text = "a positive number" if lo_open else "a number >= 0"
    elif hi is None:
        text = f"a number {'>' if lo_open else '>='} {plain(lo)}"
    elif lo is None:
        text = f"a number {'<' if hi_open else '<='} {plain(hi)}"
    else:
        text = (f"a number in {'(' if lo_open else '['}{plain(lo)}, {plain(hi)}"
                f"{')' if hi_open else ']'}")
    return f"{text} ({unit})" if unit else text


def real(value: object, where: str, lo: float | None = None, hi: float | None = None,
         lo_open: bool = False, hi_open: bool = False, unit: str | None = None,
         error: type[Exception] = InputError) -> float:
    """A finite real number as ``float``, optionally within bounds.

    Parameters
    ----------
    value : object
        What the caller passed.
    where : str
        The argument name or scenario key, used as the start of the message.
    lo : float, optional
        Bounds (None: unbounded on that side).
    hi : float, optional
        Bounds (None: unbounded on that side).
    lo_open : bool, optional
        Make ``lo`` / ``hi`` strict bounds (default: inclusive).
    hi_open : bool, optional
        Make ``lo`` / ``hi`` strict bounds (default: inclusive).
    unit : str, optional
        Unit named in the message, e.g. ``"s"``.
    error : type, optional
        Exception class raised (a subclass of quadcog.InputError).

    Returns
    -------
    float
        ``value`` as a Python float.

    Raises
    ------
    InputError
        (or ``error``) when ``value`` is not a finite real number within the bounds.
    """
    what = _describe(lo, hi, lo_open, hi_open, unit)
    if not _is_real_scalar(value):
        fail(where, what, value, error)
    try:
        x = float(value)                # type: ignore[arg-type]  # a real number (checked above)
    except OverflowError:               # an int beyond the float range
        fail(where, what, value, error)
    if not math.isfinite(x):
        fail(where, what, value, error)
    if lo is not None and (x < lo or (lo_open and x == lo)):
        fail(where, what, value, error)
    if hi is not None and (x > hi or (hi_open and x == hi)):
        fail(where, what, value, error)
    return x


def positive(value: object, where: str, unit: str | None = None,
             error: type[Exception] = InputError) -> float:
    """A finite number > 0 as ``float``.

    Parameters
    ----------
    value : object
        What the caller passed.
    where : str
        The argument name or scenario key, used as the start of the message.
    unit : str, optional
        Unit named in the message, e.g. ``"s"``.
    error : type, optional
        Exception class raised (default quadcog.InputError).

    Returns
    -------
    float
        ``value`` as a Python float.

    Raises
    ------
    InputError
        (or ``error``) when ``value`` is not a finite number > 0.
    """
    return real(value, where, lo=0.0, lo_open=True, unit=unit, error=error)


def nonnegative(value: object, where: str, unit: str | None = None,
                error: type[Exception] = InputError) -> float:
    """A finite number >= 0 as ``float``.

    Parameters
    ----------
    value : object
        What the caller passed.
    where : str
        The argument name or scenario key, used as the start of the message.
    unit : str, optional
        Unit named in the message, e.g. ``"s"``.
    error : type, optional
        Exception class raised (default quadcog.InputError).

    Returns
    -------
    float
        ``value`` as a Python float.

    Raises
    ------
    InputError
        (or ``error``) when ``value`` is not a finite number >= 0.
    """
    return real(value, where, lo=0.0, unit=unit, error=error)


def integer(value: object, where: str, lo: int | None = None, hi: int | None = None,
            error: type[Exception] = InputError) -> int:
    """An ``int`` (Python or numpy integer, not a bool, not a float) within [lo, hi].

    Parameters
    ----------
    value : object
        What the caller passed.
    where : str
        The argument name or scenario key, used as the start of the message.
    lo : int, optional
        Inclusive bounds (None: unbounded on that side).
    hi : int, optional
        Inclusive bounds (None: unbounded on that side).
    error : type, optional
        Exception class raised (default quadcog.InputError).

    Returns
    -------
    int
        ``value`` as a Python int.

    Raises
    ------
    InputError
        (or ``error``) when ``value`` is not an integer within the bounds.
    """
    bounds = (f" >= {lo}" if hi is None else f" in [{lo}, {hi}]") if lo is not None else (
        f" <= {hi}" if hi is not None else "")
    what = f"an integer{bounds}"
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        fail(where, what, value, error)
    n = operator.index(value)
    if (lo is not None and n < lo) or (hi is not None and n > hi):
        fail(where, what, value, error)
    return n


def flag(value: object, where: str, error: type[Exception] = InputError) -> bool:
    """``True`` or ``False`` (Python or numpy bool), as ``bool``; 0 and 1 are refused.

    Parameters
    ----------
    value : object
        What the caller passed.
    where : str
        The argument name or scenario key, used as the start of the message.
    error : type, optional
        Exception class raised (default quadcog.InputError).

    Returns
    -------
    bool
        ``value`` as a Python bool.

    Raises
    ------
    InputError
        (or ``error``) when ``value`` is not a bool.
    """
    if not isinstance(value, (bool, np.bool_)):
        fail(where, "true or false", value, error)
    return bool(value)


def choice(value: object, where: str, options: Iterable[Any],
           error: type[Exception] = InputError) -> Any:
    """``value`` if it equals one of ``options`` (and has the same type: 1 is not True).

    Safe for unhashable values (a list or a table given where a name is expected).

    Parameters
    ----------
    value : object
        What the caller passed.
    where : str
        The argument name or scenario key, used as the start of the message.
    options : iterable
        The accepted values, listed in the message.
    error : type, optional
        Exception class raised (default quadcog.InputError).

    Returns
    -------
    object
        ``value`` itself.

    Raises
    ------
    InputError
        (or ``error``) when ``value`` is none of ``options``.
    """
    for option in options:
        if type(value) is type(option) and value == option:
            return value
    listed = ", ".join(repr(o) for o in options)
    fail(where, f"one of {listed}", value, error)


def _walk(value, where, index, error, what):
    """Check every leaf of nested lists/tuples: real numbers, not bools; returns the shape."""
    if isinstance(value, (list, tuple)):
        shapes = {(_walk(v, where, index + (i,), error, what)) for i, v in enumerate(value)}
        if len(shapes) > 1:
            fail(where, f"{what} (a rectangular array; the rows differ in length)", value, error)
        return (len(value),) + (shapes.pop() if shapes else ())
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "iuf":
            fail(_at(where, index), what, value, error)
        return value.shape
    if not _is_real_scalar(value):
        fail(_at(where, index), "a real number", value, error)
    try:
        float(value)
    except OverflowError:
        fail(_at(where, index), "a number within the float range", value, error)
    return ()


def _at(where, index):
    return f"{where}[{', '.join(map(str, index))}]" if index else where


def _shape_text(shape):
    dims = ["any" if d is None else str(d) for d in shape]
    return f"({dims[0]},)" if len(dims) == 1 else f"({', '.join(dims)})"


def array(value: npt.ArrayLike, where: str, shape: Sequence[int | None] | None = None,
          finite: bool = True, what: str | None = None,
          error: type[Exception] = InputError) -> npt.NDArray[np.float64]:
    """A float64 array (a new copy) of real numbers.

    Parameters
    ----------
    value : array_like
        Nested lists/tuples or an ndarray of real numbers (ints, floats; not bools, not
        complex, not strings).
    where : str
        Name for messages; a bad entry is named ``where[i, j]``.
    shape : tuple of int or None, optional
        Expected shape; ``None`` entries match any length (``(None, 14)``: any number of rows
        of 14). Omitted: any shape.
    finite : bool, optional
        Refuse NaN and infinities (default).
    what : str, optional
        What to call the expected value in messages (default e.g. "an array of shape (3,)").
    error : type, optional
        Exception class raised (default quadcog.InputError).

    Returns
    -------
    numpy.ndarray of float64
        A new array of ``shape``.

    Raises
    ------
    InputError
        (or ``error``) naming the bad entry, the shape or the type.
    """
    what = what or ("an array of real numbers" if shape is None
                    else f"an array of shape {_shape_text(shape)}")
    if isinstance(value, (str, bytes, dict, bool, np.bool_)) or value is None:
        fail(where, what, value, error)
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "iuf":
            kind = {"b": "booleans", "c": "complex numbers"}.get(value.dtype.kind,
                                                                 f"dtype {value.dtype}")
            fail(where, f"{what} of real numbers, not {kind}", value, error)
        if np.ma.is_masked(value):      # np.array would take the data under the mask
            raise error(f"{where}: expected {what}, got a masked array with "
                        f"{int(np.ma.count_masked(value))} masked entries")
    elif isinstance(value, (list, tuple)):
        _walk(value, where, (), error, what)
    elif not _is_real_scalar(value):
        fail(where, what, value, error)
    try:
        a = np.array(value, dtype=float)
    except OverflowError:           # an integer beyond the float range
        fail(where, f"{what} of numbers within the float range", value, error)
    if shape is not None and (a.ndim != len(shape) or any(
            d is not None and d != n for d, n in zip(shape, a.shape))):
        raise error(f"{where}: expected {what}, got shape {a.shape}"
                    + (f" ({plain(value)})" if a.size <= _MAX_ITEMS_SHOWN else ""))
    if finite:
        bad = ~np.isfinite(a)
        if bad.any():
            k = np.unravel_index(int(np.argmax(bad)), a.shape) if a.ndim else ()
            raise error(f"{_at(where, tuple(int(i) for i in k))}: expected a finite number, "
                        f"got {plain(a[k] if a.ndim else float(a))}")
    return a


def vector(value: npt.ArrayLike, where: str, n: int, finite: bool = True,
           error: type[Exception] = InputError) -> npt.NDArray[np.float64]:
    """A float64 vector of shape (n,); a column (n, 1) is accepted and flattened.

    Parameters
    ----------
    value : (n,) or (n, 1) array_like
        Real numbers (not bools, not complex, not strings).
    where : str
        Name for messages; a bad entry is named ``where[i]``.
    n : int
        The length expected.
    finite : bool, optional
        Refuse NaN and infinities (default).
    error : type, optional
        Exception class raised (default quadcog.InputError).

    Returns
    -------
    (n,) numpy.ndarray of float64
        A new array.

    Raises
    ------
    InputError
        (or ``error``) naming the bad entry, the shape or the type.
    """
    a = array(value, where, None, finite=False, what=f"an array of shape ({n},)", error=error)
    if a.shape not in ((n,), (n, 1)):
        raise error(f"{where}: expected an array of shape ({n},), got shape {a.shape}"
                    + (f" ({plain(value)})" if a.size <= _MAX_ITEMS_SHOWN else ""))
    a = a.reshape(n)
    if finite:
        bad = np.flatnonzero(~np.isfinite(a))
        if bad.size:
            raise error(f"{where}[{bad[0]}]: expected a finite number, got {plain(a[bad[0]])}")
    return a


def poles(value: object, where: str, n: int,
          error: type[Exception] = InputError) -> npt.NDArray[np.complex128]:
    """``n`` closed-loop poles (1/s) as a complex array.

    Parameters
    ----------
    value : (n,) sequence or numpy.ndarray
        Real numbers or complex ones in conjugate pairs, all finite with negative real part
        (strings, bools, NaN refused), in 1/s.
    where : str
        Name for messages; a bad entry is named ``where[k]``.
    n : int
        The number of poles expected.
    error : type, optional
        Exception class raised (default quadcog.InputError).

    Returns
    -------
    (n,) numpy.ndarray of complex128
        The poles (1/s).

    Raises
    ------
    InputError
        (or ``error``) naming the bad pole, the count, or a missing conjugate.
    """
    what = f"{n} finite poles with negative real part (complex ones in conjugate pairs)"
    items = value.tolist() if isinstance(value, np.ndarray) else value
    if not isinstance(items, (list, tuple)) or len(items) != n:
        fail(where, what, value, error)
    out = []
    for k, v in enumerate(items):
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Complex):
            fail(f"{where}[{k}]", "a real or complex number", v, error)
        try:
            z = complex(v)
        except OverflowError:
            fail(f"{where}[{k}]", "a number within the float range", v, error)
        if not (math.isfinite(z.real) and math.isfinite(z.imag) and z.real < 0):
            fail(f"{where}[{k}]", "a finite pole with negative real part", v, error)
        out.append(z)
    p = np.array(out, dtype=complex)
    if not np.allclose(np.sort_complex(p), np.sort_complex(p.conj()), rtol=1e-12, atol=0):
        fail(where, what, value, error)
    return p


# Memory one simulated step of one flight costs: the schedule (37 numbers), state and
# controller state, input, reference and the result arrays handed out. Measured: 512 B per
# step at the peak of a 60 s adaptive figure-8 run (tracemalloc) with a 27-number schedule,
# plus the 10 numbers of the payloads' pi; rounded up.
BYTES_PER_STEP = 656


def step_count(duration: float, dt: float, max_steps: int, where: str | None = None,
               error: type[Exception] = InputError) -> int:
    """The number of steps ``round(duration / dt)``, refused when it is not finite or above
    ``max_steps``; the message gives the count and the memory it would take.

    Parameters
    ----------
    duration : float
        Length of the run (s), already checked to be a positive float.
    dt : float
        Step (s), already checked to be a positive float.
    max_steps : int
        The most steps allowed (``quadcog.config.defaults["simulate.max_steps"]``).
    where : str, optional
        Put in front of the message (e.g. the scenario file).
    error : type, optional
        Exception class raised (default quadcog.InputError).

    Returns
    -------
    int
        ``round(duration / dt)``.

    Raises
    ------
    InputError
        (or ``error``) when the count is not finite or above ``max_steps``, giving the memory
        it would take (``BYTES_PER_STEP`` per step).
    """
    n = duration / dt
    if not math.isfinite(n) or n > max_steps:
        count = (f"{n:.3g} steps, about {_bytes(n * BYTES_PER_STEP)} of memory"
                 if math.isfinite(n) else "more steps than a float can count")
        raise error(f"{where + ': ' if where else ''}duration / dt = {plain(duration)} s / "
                    f"{plain(dt)} s gives {count}; expected at most {max_steps:,} steps "
                    f"(about {_bytes(max_steps * BYTES_PER_STEP)}): raise dt or shorten the "
                    f"duration")
    return int(round(n))


def _bytes(b):
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"):
        if b < 1024 or unit == "EiB":
            return f"{b:.3g} {unit}"
        b /= 1024




def require_extra(extra: str, *modules: str) -> None:
    """Check that an optional extra's packages are installed, before any work starts.

    Parameters
    ----------
    extra : str
        The name of the extra in pyproject.toml (``"sweep"``).
    *modules : str
        The modules the extra provides (``"pyarrow"``, ``"dask"``).

    Returns
    -------
    None

    Raises
    ------
    quadcog.errors.MissingDependencyError
        Naming the missing modules and the install command.
    """
    import importlib.util

    from quadcog.errors import MissingDependencyError
    missing = [m for m in modules if importlib.util.find_spec(m) is None]
    if missing:
        raise MissingDependencyError(_missing_text(extra, missing))


def _missing_text(extra: str, missing: Sequence[str]) -> str:
    return (f"{', '.join(missing)} not installed: this needs the '{extra}' extra; install it "
            f"with: pip install 'quadcog[{extra}]' (or pip install {' '.join(missing)})")


def import_extra(extra: str, module: str) -> ModuleType:
    """Import a module of an optional extra, or say how to install it.

    Parameters
    ----------
    extra : str
        The name of the extra in pyproject.toml (``"sweep"``).
    module : str
        The module to import (``"pyarrow.parquet"``).

    Returns
    -------
    module
        The imported module.

    Raises
    ------
    quadcog.errors.MissingDependencyError
        Naming the missing package and the install command.
    """
    import sys

    from quadcog.errors import MissingDependencyError
    top = module.split(".")[0]
    require_extra(extra, top)
    try:
        __import__(module)
    except ImportError:             # found but not importable (a broken install)
        raise MissingDependencyError(_missing_text(extra, [top])) from None
    return sys.modules[module]


def user_function(f: Callable[..., Any], name: str) -> Callable[..., Any]:
    """``f`` (a function the user passed) wrapped so that what it raises is an InputError.

    The wrapper calls ``f`` with its arguments; a quadcog error passes through, any other
    exception becomes ``InputError("{name}({arguments}) raised {type}: {message}")`` with
    the exception as its cause (KeyboardInterrupt and SystemExit are not exceptions here).

    Parameters
    ----------
    f : callable
        The user's function (a progress callback, a CoG shape, a trajectory).
    name : str
        What to call it in messages, e.g. ``"progress"``.

    Returns
    -------
    callable
        ``f`` with its failures named.
    """
    def call(*args: Any) -> Any:
        try:
            return f(*args)
        except QuadcogError:
            raise
        except Exception as e:         # the user's code failed: say where, keep the cause
            shown = ", ".join(plain(a) for a in args)
            raise InputError(f"{name}({shown}) raised {type(e).__name__}: {e}") from e
    return call
