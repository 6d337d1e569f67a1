"""Compare two generated folders; a readable unified diff of what differs."""
import difflib
from pathlib import Path

# Sub-folders of generated/ that another generator owns (`make embedded` writes embedded/):
# derive neither compares, lists in the manifest, nor removes them.
FOREIGN = ("embedded",)


def is_foreign(rel):
    """True for a path (relative to generated/) inside a FOREIGN sub-folder."""
    return Path(rel).parts[:1] in [(f,) for f in FOREIGN]


def _files(folder):
    folder = Path(folder)
    return {p.relative_to(folder).as_posix(): p for p in sorted(folder.rglob("*"))
            if p.is_file() and not is_foreign(p.relative_to(folder))}


def diff_trees(expected, actual, max_lines=200):
    """Return '' when the trees are byte-identical, else a unified diff (truncated)."""
    a, b = _files(expected), _files(actual)
    out = []
    for name in sorted(set(a) | set(b)):
        if name not in b:
            out.append(f"only in {expected}: {name}\n")
            continue
        if name not in a:
            out.append(f"only in {actual}: {name}\n")
            continue
        da, db = a[name].read_bytes(), b[name].read_bytes()
        if da == db:
            continue
        try:
            la = da.decode().splitlines(keepends=True)
            lb = db.decode().splitlines(keepends=True)
        except UnicodeDecodeError:
            out.append(f"binary files differ: {name}\n")
            continue
        if max(map(len, la + lb), default=0) > 2000:     # .casadi: one huge line
            out.append(f"files differ: {name} (serialized CasADi function, no text diff)\n")
            continue
        out.extend(difflib.unified_diff(la, lb, f"{expected}/{name}", f"{actual}/{name}"))
    if len(out) > max_lines:
        out = out[:max_lines] + [f"... ({len(out) - max_lines} more diff lines)\n"]
    return "".join(out)
