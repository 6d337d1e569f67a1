"""The scenarios that ship inside the package (``quadcog/scenarios/*.toml``), addressable by
name: ``quadcog run fig6 --out DIR``, ``quadcog scenarios``. ``scenario_path`` is the one
lookup from a name or a path to a scenario file; everything that accepts a scenario uses it."""
from importlib import resources
from pathlib import Path
import tomllib

SUFFIX = ".toml"


def _folder():
    return Path(str(resources.files("quadcog") / "scenarios"))


def scenario_names():
    """Names of the shipped scenarios (their file names without ``.toml``), sorted."""
    return tuple(sorted(p.stem for p in _folder().glob(f"*{SUFFIX}")))


def shipped_scenarios():
    """{name: description} of the shipped scenarios, in name order."""
    out = {}
    for name in scenario_names():
        data = tomllib.loads((_folder() / f"{name}{SUFFIX}").read_text(encoding="utf-8"))
        out[name] = str(data.get("description", ""))
    return out


def scenario_path(spec):
    """The scenario file that ``spec`` (a str or a path) stands for.

    Parameters
    ----------
    spec : str or os.PathLike
        A path to a scenario file, or the name of a shipped scenario (``"fig6"`` or
        ``"fig6.toml"``, no folder part). An existing file wins over a shipped name.

    Returns
    -------
    pathlib.Path
        The file to read. A path that exists but is not a file (a folder) is returned as is,
        so that reading it reports what it is.

    Raises
    ------
    quadcog.scenarios.scenario.ScenarioError
        When ``spec`` is neither an existing path nor a shipped name; the message lists the
        shipped names.
    """
    path = Path(spec)
    if path.is_file():
        return path
    if path.name == str(spec):                       # a bare name, no folder part
        name = path.name[:-len(SUFFIX)] if path.name.endswith(SUFFIX) else path.name
        if name in scenario_names():
            return _folder() / f"{name}{SUFFIX}"
    if path.exists():
        return path
    from quadcog.scenarios.scenario import ScenarioError
    raise ScenarioError(f"{spec}: no such scenario file, and no shipped scenario of that name "
                        f"(shipped: {', '.join(scenario_names())}; `quadcog scenarios` lists "
                        f"them)")
