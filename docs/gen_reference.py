"""The generated pages of the documentation site: scenario and sweep keys, the CLI, the API.

An MkDocs hook (``mkdocs.yml``: ``hooks: [docs/gen_reference.py]``): at every build the pages
below are made from the code, so nothing they list is written twice.

- ``reference/scenario-keys.md``: every key of a scenario file, from the schema
  (``quadcog.scenarios.schema``) and the registries of controllers and trajectories; kinds and
  defaults from the constructors' signatures and the dataclasses, meanings from their
  docstrings (``Parameters``), and for the keys that have no class of their own from
  ``TOP_MEANING`` / ``COG_MEANING`` / ``DISTURBANCE_MEANING`` / ``LIMITS_MEANING`` below.
- ``reference/sweep-keys.md``: every key of a sweep file (``quadcog.sweeps.spec``).
- ``reference/shipped.md``: the shipped scenarios and sweep files with their descriptions.
- ``reference/cli.md``: every command of ``quadcog`` and its options, from the parser.
- ``reference/api/<layer>.md``: ``::: module`` blocks for mkdocstrings, one page per layer.

It also fills the pages' markers: ``<!-- figure NAME -->`` becomes the committed figure
``docs/figures/NAME.png`` with its caption (``docs/figures.py``, the command that makes them),
and ``<!-- equation NAME -->`` the derived expression as display mathematics
(``derive/site.py``, printed by the LaTeX report's printer; computed once per state of
``derive/`` and kept in quadcog's cache). MathJax (the ``django-static-mathjax`` package of the
docs extra, SVG output: no web fonts) is copied into the site, which works offline.

``python docs/gen_reference.py DIR`` writes the same pages into DIR (to read them without a
build). ``tests/test_docsite.py`` checks that every schema key has a meaning here.
"""
import argparse
import dataclasses
import importlib
import importlib.util
import inspect
from pathlib import Path
import pkgutil
import re
import sys
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:               # run as a script or as a hook from any folder
    sys.path.insert(0, str(ROOT))

from quadcog.layers import LAYERS as PACKAGE_LAYERS  # noqa: E402 (after the path set-up)

__all__ = ["TOP_MEANING", "COG_MEANING", "DISTURBANCE_MEANING", "LIMITS_MEANING",
           "SWEEP_MEANING", "DIMENSION_MEANING", "LAYERS", "pages", "parameter_docs",
           "scenario_keys_page", "sweep_keys_page", "cli_page", "shipped_page", "api_pages",
           "on_files", "on_page_markdown", "on_page_content", "breakable_cells", "equations", "figure_block", "MATHJAX",
           "face_page"]

# The meanings of the keys that have no class of their own (the others come from docstrings).
TOP_MEANING = {
    "name": "required; the run's name (its default output folder is out/<name>)",
    "description": "free text (`quadcog scenarios` lists it)",
    "controller": "required; the controller's short name",
    "duration": "required, > 0 (s)",
    "dt": "RK4 step (s); default `quadcog.config.defaults[\"simulate.dt\"]`",
    "path": "execution path: \"compiled\" (default) or \"python\"",
    "initial_offset": "start this far (m) from the reference's first point",
    "stack": "table: fly a flight stack's controller instead of `controller`: `name = "
             "\"crazyflie\"`, `controller` (\"pid\", \"mellinger\", \"indi\", "
             "\"brescianini\", \"lee\" or an out-of-tree folder), `propellers`, "
             "`battery_voltage` (V); `quadcog run` flies it (docs: The Crazyflie firmware in "
             "the loop)",
    "trajectory": "table: the reference; `kind` and its settings (below)",
    "cog": "array of tables: the CoG changes (below); r_G is the vehicle's before the first",
    "payload": "array of tables: payloads attached, moved and dropped (below); the vehicle's own "
               "`payloads` are on board from the start",
    "disturbance": "array of tables: force and moment pulses (below)",
    "vehicle": "table: the truth vehicle (below)",
    "controller_model": "table: what the controller believes, same keys as `[vehicle]`; starts "
                        "from the truth vehicle with r_G = 0 (or its own `preset`); without "
                        "the table, that is the controller's model",
    "controller_params": "table: the settings of the chosen controller (below); switching "
                         "`controller` with `--set` drops those the new one does not take",
    "truth": "table: the effects of the truth model (below)",
    "limits": "table: when a run counts as diverged (below)",
    "sensing": "table: what the controller's measurements suffer (below); without it: perfect "
               "state, no delay",
}
COG_MEANING = {"t": "time of the change (s); entries in time order",
               "r": "the new CoG offset r_G (m, body frame, 3 numbers)",
               "ramp": "duration of a linear ramp to it (s); 0 = a step"}
DISTURBANCE_MEANING = {"t": "start (s)", "duration": "length of the pulse (s)",
                       "force": "force at O (N, ground frame, 3 numbers)",
                       "moment": "moment (N m, body frame, 3 numbers)"}
LIMITS_MEANING = {"max_position_error": "position error that counts as diverged (m)",
                  "max_tilt_deg": "|phi| or |theta| that counts as diverged (deg)"}
VEHICLE_EXTRA = {"preset": "the vehicle to start from: \"hummingbird\" (default), "
                           "\"crazyflie\" or \"x500\"; the other keys change its fields",
                 "identified": "JSON file of `quadcog identify --json`: its r_G becomes the CoG",
                 "file": "a URDF or SDF file (relative to the scenario file) whose vehicle "
                         "replaces the preset ([Your own vehicle](../howto/vehicle.md))"}
SWEEP_MEANING = {
    "name": "the sweep's name", "description": "free text (`quadcog sweeps` lists it)",
    "scenario": "the base scenario: a shipped name, or a path relative to this file",
    "mode": "\"grid\" (every combination, default) or \"monte-carlo\" (`samples` draws)",
    "samples": "number of flights in monte-carlo mode",
    "seed": "seeds every sampled dimension (dimension i draws from (seed, i))",
    "chunk": "flights per chunk: the unit of scheduling, retry and resume",
    "threshold": "tail RMS (m) above which, or a divergence, a flight counts as failed",
    "inadmissible": "grid points with an inadmissible CoG: \"error\" (default) or \"skip\"",
    "set": "table: fixed values by scenario key (`vehicle.m = 0.8`)",
    "dimension": "array of tables: the varied keys, each with `key` and one source (below)",
}
DIMENSION_MEANING = {
    "values": "a list: grid values, or the pool a monte-carlo flight draws from",
    "range": "`{start, stop, num}` or `{start, stop, step}`",
    "uniform": "`{low, high, n}` seeded uniform samples (no `n` in monte-carlo mode)",
    "normal": "`{mean, std, n}` seeded normal samples",
    "ball": "`{radius, n, plane}` CoG offsets uniform inside a ball (`plane = \"xy\"` keeps "
            "z = 0)",
}
# The API pages: one per layer, bottom to top (quadcog/layers.py, which the architecture test
# holds the imports to); the package face (`quadcog`) is on the command-line page's prefixes
LAYERS = {name: (title, [p for p in prefixes if p not in ("quadcog", "quadcog.__main__")])
          for name, title, prefixes in PACKAGE_LAYERS}


def parameter_docs(obj: Any) -> dict[str, str]:
    """The meaning of each parameter in the docstring of a class (and its ``__init__``).

    Parameters
    ----------
    obj : class or function
        Its ``Parameters`` section (numpydoc ``name : type`` with an indented description, or
        ``a, b : description`` on one line) is read; without the section, the whole body.

    Returns
    -------
    dict of str to str
        {parameter name: description, on one line}.
    """
    texts = [inspect.getdoc(obj) or ""]
    if inspect.isclass(obj) and "__init__" in obj.__dict__:
        texts.append(inspect.getdoc(obj.__init__) or "")
    if inspect.isclass(obj):        # a setting inherited from a base class: its meaning there
        texts += [inspect.getdoc(base) or "" for base in obj.__mro__[1:] if base is not object]
    out: dict[str, str] = {}
    for text in texts:
        lines = text.splitlines()
        start = next((i + 2 for i, line in enumerate(lines[:-1])
                      if line.strip() == "Parameters" and set(lines[i + 1].strip()) == {"-"}), 1)
        entry: list[str] | None = None
        names: list[str] = []
        for line in lines[start:]:
            if line.strip() and set(line.strip()) == {"-"}:
                break                                   # the next section's underline
            m = re.match(r"^(\*{0,2}[A-Za-z_]\w*(?:, *[A-Za-z_]\w*)*) ?: ?(.*)$", line)
            if m and not line.startswith(" "):
                _store(out, names, entry)
                names = [n.strip("* ") for n in m.group(1).split(",")]
                entry = [m.group(2).strip()]
            elif entry is not None and line.startswith(" "):
                entry.append(line.strip())
            elif entry is not None and not line.strip():
                continue
            else:
                _store(out, names, entry)
                entry, names = None, []
        _store(out, names, entry)
    return out


def _store(out: dict[str, str], names: list[str], entry: list[str] | None) -> None:
    if not entry:
        return
    head, rest = entry[0], " ".join(entry[1:])
    # numpydoc: 'name : type' then the description (the type is the schema's value column);
    # the older form: 'name : description' continued on indented lines (a head that ends
    # like a sentence part), or 'name : description.' alone
    is_type = bool(rest) and not head.endswith((".", ",", ";", ":"))
    text = (rest or head) if is_type else f"{head} {rest}".strip()
    for name in names:
        out.setdefault(name, text)


def _cell(text: Any) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _value(v: Any) -> str:
    if v is inspect.Parameter.empty or v is dataclasses.MISSING:
        return "required"
    if isinstance(v, bool):
        return f"`{str(v).lower()}`"
    if isinstance(v, float):
        return f"`{v:.6g}`"
    if v is None:
        return "none"
    if isinstance(v, str):
        return f'`"{v}"`'
    if isinstance(v, (tuple, list)):
        return "`[" + ", ".join(_value(x).strip("`") for x in v) + "]`"
    return f"`{v}`"


def _check_words(check: Any) -> str:
    from quadcog.kinds import Kind
    from quadcog.scenarios.schema import CHECK, NUMBER
    for kind, token in CHECK.items():
        if token == check:
            return kind.value
    if check == NUMBER:
        return Kind.NUMBER.value
    return {dict: "a table", list: "an array of tables", str: "a string",
            bool: "true or false"}.get(check, str(check))


def _signature_defaults(cls: type) -> dict[str, Any]:
    out = {}
    for k in reversed(cls.__mro__):
        if "__init__" in k.__dict__ and k is not object:
            for name, p in inspect.signature(k.__init__).parameters.items():
                out[name] = p.default
    return out


def _table(rows: list[tuple[str, ...]], head: tuple[str, ...]) -> str:
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(_cell(c) for c in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def _dataclass_rows(cls: type, schema: dict[str, Any], extra: dict[str, str] | None = None,
                    defaults: Any = None) -> list[tuple[str, ...]]:
    docs = {**parameter_docs(cls), **(extra or {})}
    fields = {f.name: f for f in dataclasses.fields(cls)}
    rows = []
    for key, check in schema.items():
        if defaults is not None and hasattr(defaults, key):
            default = _value(getattr(defaults, key))
        elif key in fields:
            f = fields[key]
            default = _value(f.default if f.default is not dataclasses.MISSING else
                             (f.default_factory() if f.default_factory is not dataclasses.MISSING
                              else dataclasses.MISSING))
        else:
            default = ""
        rows.append((f"`{key}`", _check_words(check), default, docs.get(key, "")))
    return rows


def scenario_keys_page() -> str:
    """The page of every scenario key, from the schema and the registries.

    Returns
    -------
    str
        Markdown.
    """
    from quadcog import config
    from quadcog.controllers.registry import CONTROLLERS
    from quadcog.scenarios import schema
    from quadcog.sim.plant import TruthOptions
    from quadcog.sim.sensing import Sensing
    from quadcog.sim.timeline import PayloadEvent
    from quadcog.vehicles.vehicle import HUMMINGBIRD, Vehicle

    head = ("key", "value", "default", "meaning")
    parts = ["# Scenario keys\n",
             "Generated from `quadcog.scenarios.schema` and the registries of controllers and "
             "trajectories at every build of this site: the list of keys is the list the "
             "scenario parser checks against. The same dotted keys work in `quadcog run "
             "--set KEY=VALUE` and in sweep files (`vehicle.m`, `controller_params.gamma`, "
             "`cog[0].r`, `cog[0].r[1]`). An unknown key, a wrong type or a value out of range "
             "stops with the file, the key, the value and what was expected.\n",
             "## Top level\n",
             _table([(f"`{k}`", _check_words(v), _top_default(k, config), _top_meaning(k))
                     for k, v in schema.TOP.items()], head)]
    parts += ["## `[trajectory]`\n",
              "`kind` is one of " + ", ".join(f'`"{k}"`' for k in schema.trajectory_schema())
              + ". Its other keys are the settings of the kind's class:\n"]
    for kind, (cls, keys) in schema.trajectory_schema().items():
        docs, defaults = parameter_docs(cls), _signature_defaults(cls)
        parts += [f"### `kind = \"{kind}\"` (`{cls.__module__}.{cls.__name__}`)\n",
                  _table([(f"`{k}`", _check_words(v), _value(defaults.get(k, "")),
                           docs.get(k, "")) for k, v in keys.items()], head)]
    parts += ["## `[[cog]]`\n", _table([(f"`{k}`", _check_words(v), "0" if k == "ramp" else
                                         "required", COG_MEANING[k])
                                        for k, v in schema.COG.items()], head)]
    event_docs = parameter_docs(PayloadEvent)
    parts += ["## `[[payload]]`\n",
              "Events in time order (`quadcog.sim.timeline.PayloadEvent`); the truth flies the "
              "airframe with what is on board ([the model, sec. 7.3](../model.md#73-payloads-the-"
              "truth-flies-the-whole-body)).\n",
              _table([(f"`{k}`", _check_words(v), "required" if k in ("t", "action", "name")
                       else ("0" if k == "ramp" else "by action"), event_docs.get(k, ""))
                      for k, v in schema.PAYLOAD.items()], head)]
    parts += ["## `[[disturbance]]`\n",
              _table([(f"`{k}`", _check_words(v), "required" if k in ("t", "duration") else
                       "`[0, 0, 0]`", DISTURBANCE_MEANING[k])
                      for k, v in schema.DISTURBANCE.items()], head)]
    parts += ["## `[vehicle]` and `[controller_model]`\n",
              "Any field of `quadcog.Vehicle`; the default column is the Hummingbird preset's "
              "value.\n",
              _table(_dataclass_rows(Vehicle, schema.VEHICLE, VEHICLE_EXTRA, HUMMINGBIRD), head)]
    parts += ["## `[controller_params]`\n",
              "The settings of the controller named by `controller`, read from its "
              "constructor's signature (so a setting added there is a key at once).\n"]
    for name, keys in schema.controller_params().items():
        cls = CONTROLLERS[name]
        docs, defaults = parameter_docs(cls), _signature_defaults(cls)
        docs.setdefault("Q_scale", "the Lyapunov weight Q as a multiple of the identity")
        parts += [f"### `controller = \"{name}\"` (`quadcog.{cls.__name__}`)\n",
                  _table([(f"`{k}`", _check_words(v), _controller_default(k, defaults),
                           docs.get(k, "")) for k, v in keys.items()], head)]
    parts += ["## `[truth]`\n", "`quadcog.TruthOptions`; the limits and the time constant come "
              "from `[vehicle]`.\n", _table(_dataclass_rows(TruthOptions, schema.TRUTH), head)]
    parts += ["## `[sensing]`\n", "`quadcog.Sensing` (sources of the defaults: "
              "[Sensing](../howto/sensing.md)).\n",
              _table(_dataclass_rows(Sensing, schema.SENSING), head)]
    parts += ["## `[limits]`\n",
              _table([(f"`{k}`", _check_words(v), _value(config.defaults[f"limits.{k}"]),
                       LIMITS_MEANING[k]) for k, v in schema.LIMITS.items()], head)]
    return "\n".join(parts)


def _top_meaning(key: str) -> str:
    if key == "controller":             # the choices, from the registry
        from quadcog.controllers.registry import controller_names
        return TOP_MEANING[key] + ": " + ", ".join(f'`"{n}"`' for n in controller_names())
    return TOP_MEANING[key]


def _controller_default(key: str, defaults: dict[str, Any]) -> str:
    """The default column of a controller setting: "from the vehicle" for those that
    ``quadcog.controllers.design`` derives (their signature default is None or "default")."""
    from quadcog.controllers.design import DERIVED_SETTINGS
    if key == "Q_scale":
        return _value(1.0)
    default = defaults.get(key, "")
    if key in DERIVED_SETTINGS and (default is None or default == "default"):
        return "from the vehicle (`quadcog.controllers.design`)"
    return _value(default)


def _top_default(key: str, config: Any) -> str:
    if key in ("name", "controller", "duration"):
        return "required"
    if key == "dt":
        return _value(config.defaults["simulate.dt"])
    if key == "path":
        return '`"compiled"`'
    return ""


def sweep_keys_page() -> str:
    """The page of every sweep-file key, from ``quadcog.sweeps.spec``.

    Returns
    -------
    str
        Markdown.
    """
    from quadcog.sweeps import spec
    defaults = {"mode": f'`"{spec.MODES[0]}"`', "seed": "", "chunk": _value(spec.DEFAULT_CHUNK),
                "threshold": _value(spec.DEFAULT_THRESHOLD), "inadmissible": '`"error"`',
                "scenario": "required", "name": "required"}
    meaning = dict(SWEEP_MEANING,       # the bounds from the module that checks them
                   chunk=f"{SWEEP_MEANING['chunk']} (1 to {spec.MAX_CHUNK:,})",
                   threshold=f"{SWEEP_MEANING['threshold']} (above 0, at most "
                             f"{spec.MAX_THRESHOLD:g} m)",
                   set=f"{SWEEP_MEANING['set']}; a file path, here or in a dimension's values, "
                       "is relative to this sweep file")
    keys = [k for k in SWEEP_MEANING if k in spec.TOP] + sorted(set(spec.TOP) - set(SWEEP_MEANING))
    return "\n".join([
        "# Sweep keys\n",
        "Generated from `quadcog.sweeps.spec` at every build. A sweep file names a base "
        "scenario and the scenario keys to vary ([Scenario keys](scenario-keys.md)); every "
        "flight is validated like a scenario file. `mode` is one of "
        + ", ".join(f'`"{m}"`' for m in spec.MODES) + ".\n",
        "## Top level\n",
        _table([(f"`{k}`", defaults.get(k, ""), meaning.get(k, "")) for k in keys],
               ("key", "default", "meaning")),
        "## `[[dimension]]`\n",
        "`key` names a scenario value as the scenario file spells it; exactly one source:\n",
        _table([(f"`{s}`", DIMENSION_MEANING.get(s, "")) for s in spec.SOURCES],
               ("source", "meaning")),
    ])


def shipped_page() -> str:
    """The shipped scenarios and sweep files with their descriptions.

    Returns
    -------
    str
        Markdown.
    """
    from quadcog.scenarios.lookup import shipped_names, shipped_scenarios
    from quadcog.sweeps.listing import shipped_sweeps
    return "\n".join([
        "# Shipped scenarios and sweeps\n",
        "Generated from the package's files. `quadcog scenarios` and `quadcog sweeps` list "
        "them, `quadcog scenarios --show NAME` prints one to copy and edit.\n",
        "## Scenarios\n",
        _table([(f"`{n}`", d) for n, d in shipped_scenarios().items()], ("name", "description")),
        "## Sweeps\n",
        _table([(f"`{n}`", d) for n, d in shipped_sweeps().items()], ("name", "description")),
        f"\n{len(shipped_names('scenario'))} scenarios, {len(shipped_names('sweep'))} sweeps.\n",
    ])


def cli_page() -> str:
    """Every command of ``quadcog`` with its help, from the parser.

    Returns
    -------
    str
        Markdown.
    """
    from quadcog.cli import parser
    ap = parser()
    sub = next(a for a in ap._actions if isinstance(a, argparse._SubParsersAction))
    parts = ["# The `quadcog` command\n",
             "Generated from the parser (`quadcog.cli.parser()`) at every build: what "
             "`quadcog COMMAND --help` prints (at 88 columns).\n", "```text\n" + _help(ap) + "```\n"]
    for name, p in sub.choices.items():
        parts += [f"## `quadcog {name}`\n", "```text\n" + _help(p) + "```\n"]
    return "\n".join(parts)


def _help(p: argparse.ArgumentParser) -> str:
    import os
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "90"     # the same width on every machine; argparse wraps at 88
    try:
        return p.format_help()
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old


def _modules(package: str) -> list[str]:
    # a layer may name a package that is not there (yet): the stacks layer's px4, aqb
    if importlib.util.find_spec(package) is None:
        return []
    mod = importlib.import_module(package)
    if not hasattr(mod, "__path__"):
        return [package]
    return [package] + sorted(m.name for m in pkgutil.walk_packages(mod.__path__, package + ".")
                              if not m.name.rsplit(".", 1)[-1].startswith("_"))


def _api_block(module: str) -> str:
    """``::: module``; a package shows its docstring only: the objects it re-exports are
    documented once, where they are defined (``reference/api/quadcog.md`` maps the names)."""
    if hasattr(importlib.import_module(module), "__path__"):
        return f"::: {module}\n    options:\n      members: false\n"
    return f"::: {module}\n"



def _layer_page(module: str) -> str:
    for slug, (_, packages) in LAYERS.items():
        if any(module == p or module.startswith(p + ".") for p in packages):
            return slug
    return "cli"


def face_page() -> str:
    """The page of ``quadcog`` itself: every name ``from quadcog import ...`` gives, linked to
    where it is defined and documented.

    Returns
    -------
    str
        Markdown.
    """
    import quadcog
    rows = []
    for name in quadcog.__all__:
        obj = getattr(quadcog, name)
        module = getattr(obj, "__module__", None) if (inspect.isclass(obj) or callable(obj)) \
            else None
        if module and module.startswith("quadcog") and getattr(obj, "__name__", "") == name:
            # a NamedTuple is not rendered on its own by mkdocstrings: its module's heading
            anchor = module if inspect.isclass(obj) and issubclass(obj, tuple) else \
                f"{module}.{name}"
            target = f"{module}.{name}"
            rows.append((f"`{name}`", f"[`{target}`]({_layer_page(module)}.md#{anchor})"))
        else:
            rows.append((f"`{name}`", f"a value ({type(obj).__name__})"))
    return "\n".join([
        "# quadcog\n",
        "The package's face: `from quadcog import NAME` for every name below, each linked to "
        "the module that defines it (where it is documented, once).\n",
        _table(rows, ("name", "defined in"))])


def api_pages() -> dict[str, str]:
    """The API pages: ``::: module`` for every module of each layer.

    Returns
    -------
    dict of str to str
        {page path under docs/: Markdown}.
    """
    pages = {}
    index = ["# API\n", "From the docstrings (numpydoc), one page per layer; a layer imports "
             "only from the layers above it in this list.\n"]
    for slug, (title, packages) in LAYERS.items():
        mods = [m for p in packages for m in _modules(p)]
        head, _, what = title.partition(": ")   # the nav's label is the part before ':'
        pages[f"reference/api/{slug}.md"] = (f"# {head}\n\n" + (f"{what[:1].upper()}{what[1:]}."
                                                                 "\n\n" if what else "")
                                             + "\n".join(_api_block(m) for m in mods))
        index.append(f"- [{title}]({slug}.md): " + ", ".join(f"`{m}`" for m in mods))
    index.insert(2, "- [quadcog](quadcog.md): every name of `from quadcog import ...` and "
                    "where it is defined")
    pages["reference/api/quadcog.md"] = face_page()
    pages["reference/api/index.md"] = "\n".join(index) + "\n"
    return pages


def pages() -> dict[str, str]:
    """Every generated page.

    Returns
    -------
    dict of str to str
        {page path under docs/: Markdown}.
    """
    return {"reference/scenario-keys.md": scenario_keys_page(),
            "reference/sweep-keys.md": sweep_keys_page(),
            "reference/shipped.md": shipped_page(),
            "reference/cli.md": cli_page(), **api_pages()}


MATHJAX = "assets/mathjax/tex-svg-full.js"        # where the site serves MathJax from
_MARKER = re.compile(r"<!-- (figure|equation) ([\w.-]+) -->")


def _mathjax_file() -> Path:
    import mathjax  # django-static-mathjax (docs extra)
    return Path(mathjax.__file__).parent / "static" / "mathjax" / "es5" / "tex-svg-full.js"


def equations() -> dict[str, str]:
    """The derived displays of ``derive/site.py``, from the cache when ``derive/`` is unchanged.

    Returns
    -------
    dict of str to str
        {name: LaTeX}.
    """
    import hashlib
    import json
    if str(ROOT) not in sys.path:               # mkdocs may have reset the path since import
        sys.path.insert(0, str(ROOT))

    from derive.manifest import derive_sources
    from quadcog.paths import cache_dir
    sources = {**derive_sources(), "derive/site.py": hashlib.sha256(
        (ROOT / "derive" / "site.py").read_bytes()).hexdigest()}
    key = hashlib.sha256(json.dumps(sources, sort_keys=True).encode()).hexdigest()[:16]
    path = cache_dir() / "docs-equations" / f"{key}.json"
    if path.is_file():
        return dict(json.loads(path.read_text()))
    from derive.model import derive_model
    from derive.site import equations as derived
    out = derived(derive_model())
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(out, indent=1))
    tmp.replace(path)
    return out


def _figures() -> Any:
    spec = importlib.util.spec_from_file_location("docs_figures", ROOT / "docs" / "figures.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("docs_figures", mod)
    spec.loader.exec_module(mod)
    return mod


def figure_block(name: str, page: str) -> str:
    """The Markdown of figure ``name`` of ``docs/figures.py`` on ``page``: image and caption.

    Parameters
    ----------
    name : str
        A ``Figure.name``.
    page : str
        The page's path under docs/ (for the relative link).

    Returns
    -------
    str
        A ``<figure>`` with the image and its caption.
    """
    import posixpath
    fig = {f.name: f for f in _figures().FIGURES}[name]
    src = posixpath.relpath(f"figures/{name}.png", posixpath.dirname(page) or ".")
    return (f'<figure markdown="span">\n  ![{fig.shows}: {fig.caption}]({src})\n'
            f"  <figcaption markdown>{fig.caption} (`{fig.shows}`)</figcaption>\n</figure>\n")


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    """MkDocs hook: the figure and equation markers of a page filled in.

    Parameters
    ----------
    markdown : str
        The page's Markdown.
    page : mkdocs.structure.pages.Page
        The page.
    config : mkdocs.config.defaults.MkDocsConfig
        The site's configuration.
    files : mkdocs.structure.files.Files
        The site's files.

    Returns
    -------
    str
        The Markdown with every marker replaced.
    """
    if "<!-- figure " not in markdown and "<!-- equation " not in markdown:
        return markdown
    found = equations() if "<!-- equation " in markdown else {}

    def fill(m: re.Match[str]) -> str:
        kind, name = m.groups()
        if kind == "figure":
            return figure_block(name, page.file.src_uri)
        if name not in found:
            raise KeyError(f"{page.file.src_uri}: no equation {name!r} in derive/site.py")
        return f"\n$$\n{found[name]}\n$$\n"
    return _MARKER.sub(fill, markdown)


_CELL = re.compile(r"(<td[^>]*>)(.*?)(</td>)", re.S)
_CAMEL = re.compile(r"(?<=[a-z]{3})(?=[A-Z][a-z]{2})")       # Euler|Singularity|Error


def breakable_cells(html: str) -> str:
    """``html`` with a line-break opportunity (``<wbr>``) after every underscore in the text
    of its table cells, and between the humps of a CamelCase word: ``add_weight_W1_near_M4``,
    ``payload_adaptive`` or ``EulerSingularityError`` may then wrap, and a
    table of ten columns fits the page's column (688 px at 1280 px; tests/
    test_docsite_reader.py). Tags and their attributes are left as they are.

    Parameters
    ----------
    html : str
        A page's HTML.

    Returns
    -------
    str
        The same HTML, ``<wbr>`` added in the cells' text.
    """
    def cell(m: re.Match[str]) -> str:
        parts = re.split(r"(<[^>]+>)", m.group(2))
        text = "".join(p if p.startswith("<") else _CAMEL.sub("<wbr>", p.replace("_", "_<wbr>"))
                       for p in parts)
        return m.group(1) + text + m.group(3)
    return _CELL.sub(cell, html)


def on_page_content(html: str, page: Any, config: Any, files: Any) -> str:
    """MkDocs hook: the tables' cells made breakable after underscores (``breakable_cells``).

    Parameters
    ----------
    html : str
        The page's HTML.
    page : mkdocs.structure.pages.Page
        The page.
    config : mkdocs.config.defaults.MkDocsConfig
        The site's configuration.
    files : mkdocs.structure.files.Files
        The site's files.

    Returns
    -------
    str
        The HTML with ``<wbr>`` in the cells.
    """
    return breakable_cells(html) if "<td" in html else html


def on_files(files: Any, config: Any) -> Any:
    """MkDocs hook: add the generated pages to the site's files.

    Parameters
    ----------
    files : mkdocs.structure.files.Files
        The site's files.
    config : mkdocs.config.defaults.MkDocsConfig
        The site's configuration.

    Returns
    -------
    mkdocs.structure.files.Files
        With the generated pages.
    """
    from mkdocs.structure.files import File
    for path, text in pages().items():
        files.append(File.generated(config, path, content=text))
    files.append(File.generated(config, MATHJAX, abs_src_path=str(_mathjax_file())))
    return files


if __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "out/docs-generated")
    for path, text in pages().items():
        (out / path).parent.mkdir(parents=True, exist_ok=True)
        (out / path).write_text(text)
        print(f"wrote {out / path}")
