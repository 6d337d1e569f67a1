"""Compile any CasADi Function to C through the build cache; the VM when there is no compiler."""
import warnings

import casadi as ca

from quadcog.codegen.compiler import compile_library, find_compiler
from quadcog.errors import CompileError, QuadcogWarning

_warned = False


def compile_function(fn, flags=None):
    """A compiled (external) equivalent of ``fn``, built once per source and cached on disk.

    Without a C compiler, ``fn`` itself is returned (CasADi's virtual machine) with a warning.
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
    kwargs = {} if flags is None else {"flags": flags}
    lib = compile_library(gen.dump().encode(), fn.name(), cc, **kwargs)
    return external(fn.name(), lib)


def external(name, lib):
    """The function ``name`` of the verified library ``lib`` (from ``compile_library``)."""
    try:
        return ca.external(name, str(lib))
    except RuntimeError as e:
        raise CompileError(f"{lib}: cannot load {name!r} ({str(e).strip().splitlines()[-1]})") \
            from None


_in_process = {}


def cached_compile(key, build):
    """``compile_function(build())``, built once per process for the hashable ``key`` (the
    compiled library itself is also cached on disk by its source)."""
    if key not in _in_process:
        _in_process[key] = compile_function(build())
    return _in_process[key]
