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


def _project_files():
    """The repository's own text files (what a fresh clone has), without build products."""
    import os
    from pathlib import Path
    root = Path(__file__).resolve().parent.parent
    skip = {".git", ".venv", "out", "build", "dist", "__pycache__", ".pytest_cache", ".ruff_cache",
            ".mypy_cache", ".hypothesis"}
    paths = []
    for folder, dirs, files in os.walk(root):        # not into the skipped folders at all
        top = Path(folder) == root
        dirs[:] = [d for d in dirs if d not in skip and not (top and d.endswith(".egg-info"))]
        paths += [Path(folder) / f for f in files if f not in skip]
    for path in sorted(paths):
        if path.is_file() and path.suffix in (".py", ".md", ".tex", ".toml", ".json", ".h",
                                              ".c", ".txt", ".cfg", ".in", ""):
            yield path.relative_to(root), path.read_text(encoding="utf-8", errors="replace")


def test_nothing_points_outside_the_repository():
    """The model's account is docs/model.md; no file names a developer brief or a path
    outside the checkout."""
    import re
    bad = re.compile(r"MODEL\.md|\.\./shared|/work/|item \d+ of the brief")
    hits = [f"{rel}:{n + 1}: {line.strip()}" for rel, text in _project_files()
            for n, line in enumerate(text.splitlines()) if bad.search(line)
            and rel.as_posix() != "tests/test_docs.py"]
    assert not hits, "\n".join(hits)


def test_model_doc_references_resolve():
    """Every `docs/model.md sec. N[.M]` cited anywhere names a section that exists."""
    from pathlib import Path
    import re
    doc = (Path(__file__).resolve().parent.parent / "docs" / "model.md").read_text()
    sections = set(re.findall(r"^#{2,3} (\d+(?:\.\d+)?)\.? ", doc, flags=re.M))
    assert {"1", "1.3", "2.1", "2.2", "2.3", "2.4", "3.2", "4.1", "4.2", "6"} <= sections
    cite = re.compile(r"docs/model\.md`?,?\s+secs?\.\s+(\d+(?:\.\d+)?(?:(?:,\s*|\s+and\s+)"
                      r"\d+(?:\.\d+)?)*)")
    cited, missing = 0, []
    for rel, text in _project_files():
        for match in cite.finditer(text.replace("\n#", " ").replace("\n", " ")):
            for number in re.findall(r"\d+(?:\.\d+)?", match.group(1)):
                cited += 1
                if number not in sections:
                    missing.append(f"{rel}: sec. {number}")
    assert cited >= 30 and not missing, missing
