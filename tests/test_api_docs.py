"""The public API as a user and a type checker read it: ``__all__`` in every module, type hints
on every public function and method, and numpydoc ``Parameters`` / ``Returns`` sections, checked
by numpydoc's own validator (the idea of python-control's ``control/tests/docstrings_test.py``).

Wrong implementations this catches: a public function whose docstring forgets a parameter or
names one it no longer has (PR01, PR02), returns something without saying what (RT01), has no
docstring (GL08), or lacks a type hint; a module without ``__all__``, or an ``__all__`` that
names something the module does not define.
"""
import enum
import importlib
import inspect
import pkgutil
import re

import numpydoc.validate
import pytest

import quadcog

# numpydoc error codes that fail the test: no docstring, parameters missing or unknown, a
# returned value without a Returns section, a parameter without a type or description
ERRORS = ("GL08", "PR01", "PR02", "PR04", "PR07", "RT01")


def _modules():
    out = []
    for info in pkgutil.walk_packages(quadcog.__path__, "quadcog."):
        if info.name.startswith("quadcog._generated") or info.name.endswith("__main__"):
            continue
        out.append(info.name)
    return ["quadcog"] + sorted(out)


MODULES = _modules()


def _public(module):
    """(qualified name, object) of every function, class and public method a module exports
    in its ``__all__`` and defines itself."""
    mod = importlib.import_module(module)
    for name in getattr(mod, "__all__", ()):
        obj = getattr(mod, name, None)
        if not (inspect.isfunction(obj) or inspect.isclass(obj)):
            continue
        if getattr(obj, "__module__", None) != module:
            continue                        # re-exported: checked where it is defined
        yield f"{module}.{name}", obj
        if inspect.isclass(obj):
            for attr, member in vars(obj).items():
                if attr.startswith("_") and attr != "__init__":
                    continue
                if isinstance(member, (staticmethod, classmethod)):
                    member = member.__func__
                if inspect.isfunction(member):
                    yield f"{module}.{name}.{attr}", member


API = [item for m in MODULES for item in _public(m)]


@pytest.mark.parametrize("module", MODULES)
def test_every_module_declares_all(module):
    mod = importlib.import_module(module)
    names = getattr(mod, "__all__", None)
    assert names is not None, f"{module} has no __all__"
    missing = [n for n in names if not hasattr(mod, n)]
    assert not missing, f"{module}.__all__ names what it does not define: {missing}"


def _is_init(qualname, obj):
    return qualname.endswith(".__init__")


@pytest.mark.parametrize("qualname, obj", API, ids=[q for q, _ in API])
def test_type_hints(qualname, obj):
    fn = obj.__init__ if inspect.isclass(obj) else obj
    if inspect.isclass(obj) and "__init__" not in vars(obj):
        return                              # dataclass or inherited: fields carry the types
    sig = inspect.signature(fn)
    missing = [p.name for p in sig.parameters.values()
               if p.name not in ("self", "cls") and p.annotation is inspect.Parameter.empty]
    if sig.return_annotation is inspect.Signature.empty:
        missing.append("return")
    assert not missing, f"{qualname}: no type hint for {missing}"


@pytest.mark.parametrize("qualname, obj", [(q, o) for q, o in API if not q.endswith("__init__")],
                         ids=[q for q, _ in API if not q.endswith("__init__")])
def test_numpydoc(qualname, obj):
    result = numpydoc.validate.validate(qualname)
    codes = ERRORS
    if inspect.isclass(obj) and issubclass(obj, enum.Enum):
        codes = tuple(c for c in ERRORS if c not in ("PR01", "PR02"))   # Enum's own signature
    errors = [f"{code}: {msg}" for code, msg in result["errors"] if code in codes]
    assert not errors, f"{qualname}:\n  " + "\n  ".join(errors)


def _own_lines(obj):
    """The names that have a Parameters line of their own (``name : type``), and those that
    share one (``a, b : type``)."""
    texts = [inspect.getdoc(obj) or ""]
    if inspect.isclass(obj) and "__init__" in vars(obj):
        texts.append(inspect.getdoc(obj.__init__) or "")
    own, shared = set(), set()
    for text in texts:
        part = re.split(r"^Parameters\n-+\n", text, flags=re.M)
        if len(part) < 2:
            continue
        body = re.split(r"^\w[\w ]*\n-+\n", part[1], flags=re.M)[0]
        for m in re.finditer(r"^(\*{0,2}[A-Za-z_]\w*(?:, *\*{0,2}[A-Za-z_]\w*)*) ?:", body,
                             flags=re.M):
            names = [n.strip(" *") for n in m.group(1).split(",")]
            (own if len(names) == 1 else shared).update(names)
    return own, shared


@pytest.mark.parametrize("qualname, obj", [(q, o) for q, o in API if not q.endswith("__init__")],
                         ids=[q for q, _ in API if not q.endswith("__init__")])
def test_every_parameter_has_a_line_of_its_own(qualname, obj):
    """Every public name, not a list of them: ``Ixx, Iyy, Izz : float`` documents Iyy only in
    passing, and the docs' tables and search then show one text for three keys."""
    own, shared = _own_lines(obj)
    assert not shared - own, f"{qualname}: {sorted(shared - own)} share a Parameters line"


def test_shared_descriptions_are_filled_in_and_written_once():
    """Model's methods take x and p: their descriptions live once, in
    quadcog.model.shared_docs, and every docstring has them filled in (no placeholder left)."""
    from pathlib import Path

    from quadcog.model import functions
    from quadcog.model.shared_docs import SHARED
    left = [q for q, o in API if "%(" in (o.__doc__ or "") and ".shared_docs." not in q]
    assert not left, left
    assert SHARED["x"].splitlines()[1].strip() in inspect.getdoc(functions.Model.dynamics)
    source = Path(functions.__file__).read_text()
    assert source.count("%(x)s") >= 8 and "State [x, y, z (m)" not in source
