"""Compile any CasADi Function to C through the build cache; the VM when there is no compiler."""
from collections.abc import Callable, Hashable, Sequence
import os
from typing import Any
import warnings

import casadi as ca

from quadcog.codegen.compiler import compile_library, find_compiler
from quadcog.errors import CompileError, QuadcogWarning

__all__ = ["compile_function", "external", "cached_compile"]

_warned = False


def compile_function(fn: ca.Function, flags: Sequence[str] | None = None) -> ca.Function:
    """A compiled (external) equivalent of ``fn``, built once per source and cached on disk.

    Parameters
    ----------
    fn : casadi.Function
        Any CasADi Function (SX or MX).
    flags : sequence of str, optional
        Compiler flags (default ``quadcog.codegen.compiler.FLAGS``).

    Returns
    -------
    casadi.Function
        The external Function of the compiled library; without a C compiler, ``fn`` itself
        (CasADi's virtual machine) with a warning.

    Raises
    ------
    CompileError
        The compiler failed or the library cannot be loaded.
    """
    global _warned
    cc = find_compiler()
    if cc is None:
        if not _warned:
            warnings.warn("no C compiler: running CasADi functions in the virtual machine "
                          "(slower)", QuadcogWarning, stacklevel=2)
            _warned = True
        return fn
    gen = ca.CodeGenerator(f"{fn.name()}.c")
    gen.add(fn)
    kwargs: dict[str, Any] = {} if flags is None else {"flags": flags}
    lib = compile_library(gen.dump().encode(), fn.name(), cc, **kwargs)
    return external(fn.name(), lib)


def external(name: str, lib: str | os.PathLike[str]) -> ca.Function:
    """The function ``name`` of the verified library ``lib`` (from ``compile_library``).

    Parameters
    ----------
    name : str
        The function's name in the library.
    lib : str or os.PathLike
        The shared library.

    Returns
    -------
    casadi.Function
        The external Function.

    Raises
    ------
    CompileError
        The library cannot be loaded or has no function ``name``.
    """
    try:
        return ca.external(name, str(lib))
    except RuntimeError as e:
        raise CompileError(f"{lib}: cannot load {name!r} ({str(e).strip().splitlines()[-1]})") \
            from None


_in_process: dict[Hashable, Any] = {}


def cached_compile(key: Hashable, build: Callable[[], ca.Function]) -> ca.Function:
    """``compile_function(build())``, built once per process for the hashable ``key``.

    The compiled library itself is also cached on disk by its source.

    Parameters
    ----------
    key : hashable
        What identifies the Function in this process.
    build : callable
        ``build() -> casadi.Function``, called only the first time for ``key``.

    Returns
    -------
    casadi.Function
        The compiled Function (or the VM one without a C compiler).
    """
    if key not in _in_process:
        _in_process[key] = compile_function(build())
    return _in_process[key]
