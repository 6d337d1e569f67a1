"""The files that ship inside the package, addressable by name, and the one TOML reader.

Scenarios (``quadcog/scenarios/*.toml``: ``quadcog run fig6``, ``quadcog scenarios``) and sweep
files (``quadcog/sweeps/*.toml``: ``quadcog sweep failure-map``) are found by ``find_file``,
the one lookup from a name or a path to a file; ``read_toml`` is the one reader, whose errors
name the file and say what is wrong with it.
"""
from importlib import resources
import os
from pathlib import Path
import re
import sys
import tomllib
from typing import Any

from quadcog.errors import InputError, ScenarioError, SweepError
from quadcog.files import one_line, path_kind
from quadcog.validate import plain

__all__ = ["SUFFIX", "SHIPPED", "shipped_folder", "shipped_names", "find_file", "read_toml",
           "scenario_names", "scenario_path", "shipped_scenarios", "display_name",
           "huge_integer"]

SUFFIX = ".toml"
# kind of file -> (folder inside the package, the error class of its messages)
SHIPPED: dict[str, tuple[str, type[InputError]]] = {
    "scenario": ("scenarios", ScenarioError),
    "sweep": ("sweeps", SweepError),
}


def shipped_folder(kind: str) -> Path:
    """The folder of the shipped files of a kind.

    Parameters
    ----------
    kind : str
        'scenario' or 'sweep'.

    Returns
    -------
    pathlib.Path
        The folder inside the installed package.
    """
    return Path(str(resources.files("quadcog") / SHIPPED[kind][0]))


def shipped_names(kind: str) -> tuple[str, ...]:
    """The names of the shipped files of a kind (file names without ``.toml``).

    Parameters
    ----------
    kind : str
        'scenario' or 'sweep'.

    Returns
    -------
    tuple of str
        Sorted.
    """
    return tuple(sorted(p.stem for p in shipped_folder(kind).glob(f"*{SUFFIX}")))


def find_file(spec: str | os.PathLike[str], kind: str) -> Path:
    """The file that ``spec`` stands for: a path, or the name of a shipped file.

    Parameters
    ----------
    spec : str or os.PathLike
        A path to a file, or the name of a shipped file of ``kind`` (``"fig6"`` or
        ``"fig6.toml"``, no folder part). An existing file wins over a shipped name.
    kind : str
        'scenario' or 'sweep'.

    Returns
    -------
    pathlib.Path
        The file to read. A path that exists but is not a file (a folder) is returned as is,
        so that reading it reports what it is.

    Raises
    ------
    quadcog.errors.ScenarioError or quadcog.errors.SweepError
        When ``spec`` is neither an existing path nor a shipped name; the message lists the
        shipped names.
    """
    error = SHIPPED[kind][1]
    if isinstance(spec, bytes) or not isinstance(spec, (str, os.PathLike)) \
            or not os.fspath(spec).strip():     # Path("") is the current folder
        raise error(f"{kind}: expected a {kind} file or the name of a shipped {kind} "
                    f"(`quadcog {kind}s` lists them), got {plain(spec)}")
    path = Path(spec)
    try:
        if path.is_file():
            return path
    except OSError as e:            # a name too long for the file system
        raise error(f"{_shown(spec)}: no such {kind} file ({e.strerror}), and no shipped "
                    f"{kind} of that name (`quadcog {kind}s` lists them)") from None
    if path.name == str(spec):                       # a bare name, no folder part
        name = path.name[:-len(SUFFIX)] if path.name.endswith(SUFFIX) else path.name
        if name in shipped_names(kind):
            return shipped_folder(kind) / f"{name}{SUFFIX}"
    if os.path.lexists(path):       # a link that loops or leads nowhere too: read_toml says so
        return path
    raise error(f"{_shown(spec)}: no such {kind} file, and no shipped {kind} of that name "
                f"(shipped: {', '.join(shipped_names(kind))}; `quadcog {kind}s` lists them)")


def _shown(spec: str | os.PathLike[str]) -> str:
    """A path or name given by the user, for a message: one line, a long one shortened."""
    return one_line(os.fspath(spec), word=120)


def read_toml(path: str | os.PathLike[str],
              error: type[InputError] = ScenarioError) -> dict[str, Any]:
    """A TOML file as a dict, with every failure a typed error naming the file.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    error : type of quadcog.InputError
        The class raised (ScenarioError, SweepError).

    Returns
    -------
    dict
        The parsed file. A byte order mark (as some editors write) is not part of the TOML.

    Raises
    ------
    error
        When the path is a folder, not a regular file (a FIFO, a device) or missing, not
        UTF-8, not valid TOML, nested too deeply to read, holds an integer of more digits than
        Python reads (naming its key), or cannot be read.
    """
    path = Path(path)
    kind = path_kind(path)
    if kind == "a folder":
        raise error(f"{path}: is a folder, not a TOML file")
    if kind is not None:            # a FIFO blocks, a device never ends: never opened
        raise error(f"{path}: is {kind}, not a regular file; expected a TOML file")
    if not path.is_file():
        raise error(f"{path}: no such file")
    text = ""
    try:
        text = path.read_text(encoding="utf-8-sig")
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise error(f"{path}: not valid TOML ({e})") from None
    except RecursionError:
        raise error(f"{path}: arrays or tables nested too deeply to read (expected the flat "
                    f"layout of a scenario or sweep file)") from None
    except UnicodeDecodeError as e:
        raise error(f"{path}: not UTF-8 text ({e.reason} at byte {e.start})") from None
    except OSError as e:
        raise error(f"{path}: cannot be read ({e.strerror})") from None
    except ValueError as e:         # tomllib's int() past Python's digit limit (last: the
        # two decode errors above are ValueErrors too)
        huge = huge_integer(text)
        if huge is None:
            raise error(f"{path}: a value cannot be read ({one_line(e)})") from None
        key, line, digits = huge
        raise error(f"{path}: key {key!r} (line {line}): expected a finite real number, got "
                    f"an integer of {digits} digits") from None


# more digits than int() converts (0: no limit here, then the default's 4300 is the mark)
_HUGE = re.compile(r"[0-9][0-9_]{%d,}" % (getattr(sys, "get_int_max_str_digits", int)()
                                          or 4300))
_KEY = re.compile(r"""([A-Za-z0-9_\-]+|"[^"]*"|'[^']*')\s*=\s*(\{)?""")
_HEADER = re.compile(r"^\s*\[\[?\s*([^\]]+?)\s*\]\]?", re.M)


def huge_integer(text: str) -> tuple[str, int, int] | None:
    """Where TOML text holds an integer longer than Python converts (tomllib then raises a
    plain ValueError that names nothing).

    Parameters
    ----------
    text : str
        The TOML text.

    Returns
    -------
    tuple of (str, int, int) or None
        (the dotted key as near as the line tells it: the table header, the inline tables
        opened on the line and the key; the line number; the number of digits), or None when
        there is no such integer.
    """
    m = _HUGE.search(text)
    if m is None:
        return None
    start = text.rfind("\n", 0, m.start()) + 1
    keys = list(_KEY.finditer(text, start, m.start()))
    # the inline tables opened before it on its line, then its own key
    parts = ([k.group(1).strip("\"'") for k in keys[:-1] if k.group(2)]
             + [keys[-1].group(1).strip("\"'")]) if keys else ["?"]
    headers = _HEADER.findall(text, 0, start)
    key = ".".join(([headers[-1]] if headers else []) + parts)
    return key, text.count("\n", 0, m.start()) + 1, len(m.group().replace("_", ""))


def scenario_names() -> tuple[str, ...]:
    """Names of the shipped scenarios.

    Returns
    -------
    tuple of str
        Their file names without ``.toml``, sorted.
    """
    return shipped_names("scenario")


def shipped_scenarios() -> dict[str, str]:
    """The shipped scenarios with their descriptions.

    Returns
    -------
    dict of str to str
        {name: description}, in name order.
    """
    return {name: str(read_toml(shipped_folder("scenario") / f"{name}{SUFFIX}")
                      .get("description", ""))
            for name in scenario_names()}


def scenario_path(spec: str | os.PathLike[str]) -> Path:
    """The scenario file that ``spec`` stands for (``find_file(spec, "scenario")``).

    Parameters
    ----------
    spec : str or os.PathLike
        A path to a scenario file, or the name of a shipped scenario.

    Returns
    -------
    pathlib.Path
        The file to read.
    """
    return find_file(spec, "scenario")



def display_name(path: str | Path, kind: str = "scenario") -> str:
    """How messages name a file: a shipped file by its name, any other by its path.

    Parameters
    ----------
    path : str or os.PathLike
        The file (from ``find_file``).
    kind : str
        'scenario' or 'sweep'.

    Returns
    -------
    str
        ``"shipped scenario 'fig6'"`` for a file of the package's folder (not the full path of
        an installed package), else the path as given.
    """
    path = Path(path)
    try:
        shipped = path.resolve().parent == shipped_folder(kind).resolve()
    except OSError:
        shipped = False
    if shipped and path.suffix == SUFFIX:
        return f"shipped {kind} '{path.stem}'"
    return str(path)
