"""Every public name of quadcog is documented (classes, functions and their public methods)."""
import inspect

import quadcog


def _public(obj):
    return [n for n in dir(obj) if not n.startswith("_")]


def test_every_public_name_has_a_docstring():
    missing = []
    for name in _public(quadcog):
        obj = getattr(quadcog, name)
        if inspect.ismodule(obj) or not (inspect.isclass(obj) or callable(obj)):
            continue
        if not (inspect.getdoc(obj) or "").strip():
            missing.append(name)
        if inspect.isclass(obj):
            for meth in _public(obj):
                attr = inspect.getattr_static(obj, meth)
                if isinstance(attr, (staticmethod, classmethod)):
                    attr = attr.__func__
                if inspect.isfunction(attr) and attr.__qualname__.startswith(obj.__name__ + "."):
                    if not (inspect.getdoc(attr) or "").strip():
                        missing.append(f"{name}.{meth}")
    assert not missing, f"undocumented public names: {missing}"


def test_module_docstrings():
    import pkgutil
    missing = [m.name for m in pkgutil.walk_packages(quadcog.__path__, "quadcog.")
               if not m.name.endswith("__main__")
               and not (inspect.getdoc(__import__(m.name, fromlist=["_"])) or "").strip()]
    assert not missing, missing
