"""The architecture as the code has it: layers that import only from below, and no circles.

Every import statement of quadcog/, derive/, report/ and bench/ is read from the source (also
those inside functions: a lazy import is still a dependency), resolved to the module it names
and checked against the order of the layers below. A wrong implementation this catches: a
module that reaches up a layer (``quadcog.model`` importing ``quadcog.sim``), a new import
circle anywhere, derive/ importing the runtime or the runtime importing derive/.
"""
import ast
from pathlib import Path

import pytest

from quadcog.layers import LAYERS as PACKAGE_LAYERS

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("quadcog", "derive", "report", "bench")

# Bottom to top (quadcog/layers.py): a module may import from its own layer and the layers
# before it.
LAYERS = tuple((name, prefixes) for name, _, prefixes in PACKAGE_LAYERS)
# derive/ writes generated/ and never sees the runtime; report/ and bench/ sit on top.
OUTSIDE = {"derive": ("derive",), "report": ("report", "derive", "quadcog"),
           "bench": ("bench", "report", "derive", "quadcog")}


def _modules():
    """{module name: path} of every Python file of the packages."""
    out = {}
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            rel = path.relative_to(ROOT).with_suffix("")
            parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
            out[".".join(parts)] = path
    return out


MODULES = _modules()


def _is_package(name):
    return MODULES[name].name == "__init__.py"


def imports_of(name):
    """The project modules that module ``name`` imports, each with the line it does it on."""
    path = MODULES[name]
    package = name if _is_package(name) else name.rpartition(".")[0]
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                base = ".".join(base + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            # `from pkg import mod` names the module pkg.mod; `from mod import name` names mod
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in MODULES else base
                       for a in node.names]
        else:
            continue
        for target in targets:
            while target and target not in MODULES:     # `import a.b.c` of a non-module tail
                target = target.rpartition(".")[0]
            if target and target != name:
                found.append((target, node.lineno))
    return found


def layer_of(name):
    """(rank, layer name) of a quadcog module: its longest matching prefix in LAYERS."""
    best = None
    for rank, (layer, prefixes) in enumerate(LAYERS):
        for prefix in prefixes:
            if name == prefix or name.startswith(prefix + "."):
                if best is None or len(prefix) > best[2]:
                    best = (rank, layer, len(prefix))
    return best[:2] if best else None


def test_every_runtime_module_has_a_layer():
    missing = [m for m in MODULES if m.startswith("quadcog") and layer_of(m) is None]
    assert not missing, f"modules in no layer of LAYERS: {missing}"


def test_no_module_imports_from_a_layer_above():
    upward = []
    for name in MODULES:
        if not name.startswith("quadcog"):
            continue
        rank, layer = layer_of(name)
        for target, line in imports_of(name):
            if target.split(".")[0] != "quadcog":
                upward.append(f"{MODULES[name].relative_to(ROOT)}:{line} imports {target} "
                              f"(outside the runtime)")
                continue
            trank, tlayer = layer_of(target)
            if trank > rank:
                upward.append(f"{MODULES[name].relative_to(ROOT)}:{line} ({layer}) imports "
                              f"{target} ({tlayer}, a layer above)")
    assert not upward, "\n".join(upward)


@pytest.mark.parametrize("top", sorted(OUTSIDE))
def test_outside_packages_import_only_what_they_may(top):
    bad = [f"{MODULES[n].relative_to(ROOT)}:{line} imports {t}"
           for n in MODULES if n.split(".")[0] == top
           for t, line in imports_of(n) if t.split(".")[0] not in OUTSIDE[top]]
    assert not bad, "\n".join(bad)


def _circles():
    """The strongly connected components of more than one module (Tarjan)."""
    graph = {n: sorted({t for t, _ in imports_of(n)}) for n in MODULES}
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    return out


def test_no_import_circles():
    assert _circles() == []


def test_the_checker_sees_a_circle_and_an_upward_import(monkeypatch):
    """The checks above can fail: a made-up circle and a made-up upward import are found."""
    real = imports_of

    def fake(name):
        extra = {"quadcog.errors": [("quadcog.validate", 1)],
                 "quadcog.validate": [("quadcog.errors", 1)]}
        return real(name) + extra.get(name, [])
    monkeypatch.setitem(globals(), "imports_of", fake)
    assert ["quadcog.errors", "quadcog.validate"] in _circles()
    assert layer_of("quadcog.model.functions")[0] < layer_of("quadcog.sim.flight")[0]
