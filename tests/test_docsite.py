"""The documentation site: it builds with --strict (broken links and missing references fail),
its reference pages are generated from the code and list every key, the README stays short,
and the published measured blocks live in the pages that bench/publish.py fills."""
import importlib.util
from pathlib import Path
import re
import shutil
import subprocess
import sys
import tomllib

from conftest import background_dir, background_job, background_result
import pytest

ROOT = Path(__file__).resolve().parent.parent
MKDOCS = Path(sys.executable).parent / "mkdocs"


def _gen():
    spec = importlib.util.spec_from_file_location("gen_reference", ROOT / "docs" / "gen_reference.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _rows(page, heading):
    """The first column of the table under ``heading`` (a line of the page), unquoted."""
    part = page.split(heading + "\n", 1)[1]
    part = part.split("\n#", 1)[0]
    return [re.match(r"\| `([^`]+)`", line).group(1) for line in part.splitlines()
            if re.match(r"\| `", line)]


@pytest.mark.slow
@pytest.mark.skipif(not MKDOCS.exists(), reason="mkdocs not installed (the docs extra)")
def _build_site():
    """The build, a subprocess started at collection on a lane of its own
    (conftest.background_job)."""
    folder = background_dir("site")
    return lambda: (folder, subprocess.run(
        [str(MKDOCS), "build", "--strict", "--site-dir", str(folder / "site")], cwd=ROOT,
        capture_output=True, text=True, timeout=600,
        env={"NO_MKDOCS_2_WARNING": "1", "PATH": str(MKDOCS.parent) + ":/usr/bin:/bin"}))


background_job("docs site", __file__, "test_site_builds_strict", _build_site, lane="tools")


def test_site_builds_strict():
    """`mkdocs build --strict`, as `make docs` runs it: every page and link resolves, every
    ``::: module`` of the API pages is found, every generated page is in the nav."""
    folder, done = background_result("docs site")
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-4000:]
    site = folder / "site"
    # use_directory_urls: false, so that the site also works opened as files
    for page in ("index.html", "reference/scenario-keys.html", "reference/cli.html",
                 "reference/api/sim.html", "howto/controller.html"):
        assert (site / page).is_file(), page
    # the API page shows a docstring of the module it names (mkdocstrings ran)
    api = (site / "reference/api/sim.html").read_text()
    assert "quadcog.sim.flight" in api and "simulate" in api


def test_scenario_keys_page_lists_every_key_of_the_schema():
    """The page lists exactly the keys the parser accepts, table by table, each with a
    meaning (a key added to the schema without one shows up here)."""
    from quadcog.scenarios import schema
    page = _gen().scenario_keys_page()
    assert _rows(page, "## Top level") == list(schema.TOP)
    tables = {"## `[[cog]]`": schema.COG, "## `[[disturbance]]`": schema.DISTURBANCE,
              "## `[vehicle]` and `[controller_model]`": schema.VEHICLE,
              "## `[truth]`": schema.TRUTH, "## `[sensing]`": schema.SENSING,
              "## `[limits]`": schema.LIMITS}
    for heading, keys in tables.items():
        assert _rows(page, heading) == list(keys), heading
    for name, keys in schema.controller_params().items():
        assert _rows(page, f'### `controller = "{name}"` (`quadcog.'
                     + type_name(name) + "`)") == list(keys)
    for kind, (cls, keys) in schema.trajectory_schema().items():
        assert _rows(page, f'### `kind = "{kind}"` (`{cls.__module__}.{cls.__name__}`)') \
            == list(keys)
    # no row without a meaning where the meaning is written in the generator or a dataclass
    for heading in ("## Top level", "## `[[cog]]`", "## `[[disturbance]]`", "## `[limits]`",
                    "## `[truth]`", "## `[sensing]`", "## `[vehicle]` and `[controller_model]`"):
        part = page.split(heading + "\n", 1)[1].split("\n#", 1)[0]
        for line in part.splitlines():
            if line.startswith("| `"):
                assert line.rstrip(" |").split("|")[-1].strip(), f"{heading}: {line}"


def type_name(controller):
    from quadcog.controllers.registry import CONTROLLERS
    return CONTROLLERS[controller].__name__


def test_generated_meanings_name_only_existing_keys():
    """The meanings written in the generator are for keys that exist: one removed from the
    schema is not left documented."""
    from quadcog.scenarios import schema
    from quadcog.sweeps import spec
    gen = _gen()
    assert set(gen.TOP_MEANING) == set(schema.TOP)
    assert set(gen.COG_MEANING) == set(schema.COG)
    assert set(gen.DISTURBANCE_MEANING) == set(schema.DISTURBANCE)
    assert set(gen.LIMITS_MEANING) == set(schema.LIMITS)
    assert set(gen.SWEEP_MEANING) == set(spec.TOP)
    assert set(gen.DIMENSION_MEANING) == set(spec.SOURCES)


def test_cli_page_has_every_command_and_option():
    from quadcog.cli import parser
    page = _gen().cli_page()
    ap = parser()
    sub = next(a for a in ap._actions if a.dest == "command")
    for name, p in sub.choices.items():
        assert f"## `quadcog {name}`" in page, name
        for action in p._actions:
            for flag in action.option_strings:
                assert flag in page, f"{name} {flag}"


def test_api_pages_cover_every_module():
    """Every module of quadcog (but the private ones) is on one API page, under its layer."""
    import pkgutil

    import quadcog
    pages = _gen().api_pages()
    listed = re.findall(r"^::: (\S+)$", "\n".join(pages.values()), flags=re.M)
    assert len(listed) == len(set(listed))
    every = {m.name for m in pkgutil.walk_packages(quadcog.__path__, "quadcog.")
             if not any(part.startswith("_") for part in m.name.split("."))}
    assert every <= set(listed), sorted(every - set(listed))


def test_parameter_docs_reads_numpydoc_and_the_older_form():
    gen = _gen()

    class New:
        """Summary.

        Parameters
        ----------
        a, b : float
            Lengths (m).
        c : str, optional
            A name.

        Returns
        -------
        None
        """

    class Old:
        """Summary.

        Parameters
        ----------
        m : mass (kg), > 0.
        g : gravitational acceleration (m/s^2),
            > 0.
        """
    assert gen.parameter_docs(New) == {"a": "Lengths (m).", "b": "Lengths (m).", "c": "A name."}
    assert gen.parameter_docs(Old) == {"m": "mass (kg), > 0.",
                                       "g": "gravitational acceleration (m/s^2), > 0."}


def test_toml_blocks_are_valid_sweep_or_scenario_files():
    """Every ```toml block of the pages is a sweep file or a scenario file that validates
    (the README once showed a sweep that its own parser refused)."""
    from quadcog.scenarios.scenario import parse
    from quadcog.sweeps.spec import from_dict
    from tests.test_docs_examples import blocks_of, pages
    seen = 0
    for page in pages():
        for b in blocks_of(page):
            if b.lang != "toml":
                continue
            data = tomllib.loads(b.text)
            if "dimension" in data or "scenario" in data:
                from_dict(data, f"{b.page}:{b.line}", folder=ROOT)
            elif "name" in data and "controller" in data:
                parse(data, f"{b.page}:{b.line}")
            seen += 1
    assert seen >= 1


def test_readme_is_short_and_links_into_the_docs():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 150
    for heading in ("## Two commands", "## What it can do", "## Layout", "## How to cite"):
        assert heading in text, heading
    for link in re.findall(r"\]\((docs/[^)#]+)", text):
        assert (ROOT / link).is_file(), link


def test_published_blocks_are_in_the_pages_publish_fills():
    spec = importlib.util.spec_from_file_location("publish", ROOT / "bench" / "publish.py")
    pub = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(pub)
    for name, page in pub.PAGES.items():
        assert pub.block(page.read_text(), name), name
    assert "<!-- BEGIN" not in (ROOT / "README.md").read_text()


def test_make_docs_builds_into_out_docs():
    text = (ROOT / "Makefile").read_text()
    assert re.search(r"^docs: .*\n\t.*mkdocs build --strict --site-dir \$\(OUT\)/docs", text, re.M)
    config = (ROOT / "mkdocs.yml").read_text()
    assert "docstring_style: numpy" in config and "docs/gen_reference.py" in config
    assert shutil.which("true")      # (the build itself: test_site_builds_strict)
