"""What a reader of the site sees, checked on the sources and on the built site (the build of
tests/test_docsite.py): every figure a page names is shown there, the derived equations are
rendered, lists stay lists, code fits the column, nav labels are the pages' titles, the site
works offline and opened as files, and the defects a reader found do not come back."""
import functools
from html.parser import HTMLParser
import importlib.util
from pathlib import Path
import re

import pytest
import yaml

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
# a file name a page gives that is the reader's own, not one of quadcog's figures
READERS_FILES = {"yours.png"}
# the width of a code block in the content column at 1280 px (Material's monospace at its
# default size): a longer line scrolls, under the copy button
CODE_COLUMNS = 88


def _module(name, path):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


FIGURES = _module("docs_figures", DOCS / "figures.py").FIGURES


def _pages():
    return sorted(p for p in DOCS.rglob("*.md")
                  if "measured" not in p.parts and p.parent.name != "figures")


def _prose(text):
    """The page without its fenced blocks (what a reader reads as text)."""
    return re.sub(r"^\s*```.*?^\s*```", "", text, flags=re.S | re.M)


def _marked(text, kind):
    return set(re.findall(rf"<!-- {kind} ([\w.-]+) -->", text))


def test_every_figure_a_page_names_is_shown_on_it():
    """A page that names `flight.png`, `failure_map.png`, ... shows that figure (the reader
    found 45 pages without one image)."""
    by_name = {f.name: f for f in FIGURES}
    gaps = []
    for page in _pages():
        text = page.read_text()
        shown = {by_name[n].shows for n in _marked(text, "figure") if n in by_name}
        for named in set(re.findall(r"[\w\[\]<>-]+\.png", _prose(text))) - READERS_FILES:
            pattern = re.escape(named).replace(re.escape("<key>"), r"\w+")
            if not any(re.fullmatch(pattern, s) for s in shown):
                gaps.append(f"{page.relative_to(DOCS)} names {named} but shows no such figure")
    assert not gaps, "\n".join(gaps)


def test_the_paper_page_shows_figs_3_to_8():
    text = (DOCS / "tour" / "paper.md").read_text()
    for fig in ("fig3a", "fig3b", "fig4", "fig5", "fig6", "fig7", "fig8"):
        assert f"<!-- figure paper-{fig} -->" in text, fig


def test_every_figure_is_committed_and_on_its_pages():
    names = {f.name for f in FIGURES}
    assert len(names) == len(FIGURES)
    for fig in FIGURES:
        path = DOCS / "figures" / f"{fig.name}.png"
        assert path.is_file() and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", \
            f"{path}: run python docs/figures.py"
        for page in fig.pages:
            assert f"<!-- figure {fig.name} -->" in (DOCS / page).read_text(), (fig.name, page)
    for page in _pages():
        unknown = _marked(page.read_text(), "figure") - names
        assert not unknown, f"{page}: no figure {unknown} in docs/figures.py"
    committed = {p.stem for p in (DOCS / "figures").glob("*.png")}
    assert committed == names, f"stray or missing figures: {committed ^ names}"


def test_equation_markers_name_derived_equations():
    from derive.site import NAMES
    seen = set()
    for page in _pages():
        marks = _marked(page.read_text(), "equation")
        assert marks <= set(NAMES), f"{page}: {marks - set(NAMES)}"
        seen |= marks
    assert {"M", "Phi", "newton_euler", "R"} <= seen
    model = (DOCS / "model.md").read_text()
    derive = (DOCS / "tour" / "derive.md").read_text()
    assert "<!-- equation M -->" in model and "<!-- equation Phi -->" in derive


def _wide_code_lines(name, text):
    """The lines of the fenced blocks of one page that are longer than CODE_COLUMNS."""
    long, inside = [], False
    for k, line in enumerate(text.splitlines(), 1):
        if line.strip().startswith("```"):
            inside = not inside
        elif inside and len(line.rstrip()) > CODE_COLUMNS:
            long.append(f"{name}:{k}: {len(line.rstrip())} columns")
    return long


def test_code_in_the_docs_fits_the_column():
    """No line of a fenced block over CODE_COLUMNS characters, on the written pages and on the
    generated ones (the CLI's help, the keys): at 1280 px the reader found about 50 blocks
    that scroll sideways, the copy button over their text. Output blocks count too."""
    long = [hit for page in _pages()
            for hit in _wide_code_lines(page.relative_to(DOCS).as_posix(), page.read_text())]
    generated = _module("gen_reference", DOCS / "gen_reference.py").pages()
    long += [hit for name, text in generated.items() for hit in _wide_code_lines(name, text)]
    assert not long, "\n".join(long)


def _docstring_code(doc):
    """The lines of a docstring that the API pages show as code: doctest lines, fenced
    blocks, and (before the first numpydoc section) lines indented 4 after a blank line."""
    lines, code, inside, indented = doc.splitlines(), [], False, False
    for i, line in enumerate(lines):
        if i + 1 < len(lines) and re.fullmatch(r"-{3,}", lines[i + 1].strip()):
            break                     # the sections: descriptions are indented prose
        if line.strip().startswith("```"):
            inside = not inside
            continue
        blank_before = i > 0 and not lines[i - 1].strip()
        indented = line.startswith("    ") and (indented or blank_before)
        if inside or indented or line.lstrip().startswith((">>>", "... ")):
            code.append(line)
    return code


def test_docstring_code_fits_the_column():
    """The code in docstrings (rendered as code blocks on the API pages) fits CODE_COLUMNS."""
    import inspect
    gen = _module("gen_reference", DOCS / "gen_reference.py")
    long = []
    for package in ("quadcog",):
        for name in gen._modules(package):
            if name.endswith("__main__"):
                continue
            mod = importlib.import_module(name)
            objs = [mod] + [v for v in vars(mod).values()
                            if (inspect.isclass(v) or inspect.isfunction(v))
                            and getattr(v, "__module__", "") == name]
            objs += [m for c in objs if inspect.isclass(c) for m in vars(c).values()
                     if inspect.isfunction(m)]
            for obj in objs:
                for line in _docstring_code(inspect.getdoc(obj) or ""):
                    if len(line) > CODE_COLUMNS:
                        long.append(f"{name} {getattr(obj, '__qualname__', '')}: {line!r}")
    assert not long, "\n".join(long)


def test_docstring_code_scanner():
    doc = ("Text\n\n    a = 1  # code\n    b = 2\nprose\n    lazy continuation\n\n>>> f()\n"
           "\nParameters\n----------\nx : int\n    indented description\n")
    assert _docstring_code(doc) == ["    a = 1  # code", "    b = 2", ">>> f()"]


def _nav_pairs(nav):
    for entry in nav:
        if isinstance(entry, str):
            continue
        ((label, value),) = entry.items()
        if isinstance(value, list):
            yield from _nav_pairs(value)
        else:
            yield label, value


def test_nav_labels_are_the_page_titles():
    class Loader(yaml.SafeLoader):
        pass
    Loader.add_constructor("!ENV", lambda loader, node: None)
    config = yaml.load((ROOT / "mkdocs.yml").read_text(), Loader=Loader)
    gen = _module("gen_reference", DOCS / "gen_reference.py")
    generated = gen.pages()
    for label, page in _nav_pairs(config["nav"]):
        text = generated.get(page) or (DOCS / page).read_text()
        title = text.splitlines()[0].removeprefix("# ").replace("`", "")
        assert title == label, f"{page}: nav says {label!r}, the page {title!r}"


def test_site_settings_a_reader_needs():
    text = (ROOT / "mkdocs.yml").read_text()
    for setting in ("site_url:", "repo_url:", "use_directory_urls: false", "font: false",
                    "pymdownx.arithmatex"):
        assert setting in text, setting
    start = (DOCS / "getting-started.md").read_text()
    assert "python -m http.server -d out/docs" in start and "mkdocs serve" in start
    # no public address of the repository exists: none is named by default, and the page says
    # where the source is and how a published copy sets its address
    assert "repo_url: !ENV [QUADCOG_REPO_URL, null]" in text
    assert "QUADCOG_REPO_URL=" in start and "built from the `docs/` folder" in start
    for page in [ROOT / "README.md", ROOT / "CITATION.cff", *_pages()]:
        assert not re.search(r"github\.com/[\w-]+/quadcog", page.read_text()), page


def test_shipped_texts_agree_on_the_number_of_laws():
    """"two further laws", "the five laws": the registry holds seven, four beyond the paper."""
    from quadcog.controllers.registry import CONTROLLERS
    words = dict(enumerate(["zero", "one", "two", "three", "four", "five", "six", "seven",
                            "eight", "nine", "ten"]))
    paper = 3                                   # "the three controllers of Palunko and Fierro"
    total, beyond = len(CONTROLLERS), len(CONTROLLERS) - paper
    texts = [(p, p.read_text()) for p in [ROOT / "README.md", *_pages()]]
    for path, text in texts:
        for word in re.findall(r"\b(\w+) (?:further laws|controllers go further|beyond it)",
                               text):
            assert word.lower() == words[beyond], f"{path}: {word!r}"
        for word in re.findall(r"\b(?:the|simulate) (\w+) (?:laws|controllers)\b", text):
            if word.lower() in ("two", "three", "four", "five", "six", "seven"):
                assert word.lower() in (words[total], words[beyond], words[paper]), \
                    f"{path}: {word!r}"


# -- the built site ------------------------------------------------------------------------

class _Counter(HTMLParser):
    """<li> and <img> inside the page's article (not the navigation)."""

    def __init__(self):
        super().__init__()
        self.depth, self.items, self.images, self.math = 0, 0, [], 0

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "article":
            self.depth += 1
        if self.depth:
            if tag == "li":
                self.items += 1
            elif tag == "img":
                self.images.append(attrs.get("src", ""))
            elif "arithmatex" in (attrs.get("class") or ""):
                self.math += 1

    def handle_endtag(self, tag):
        if tag == "article":
            self.depth -= 1


@functools.cache
def _site():
    # one build for every page: a second background_result() call would build the site again
    from conftest import background_result
    import test_docsite  # noqa: F401  (registers the "docs site" job when this file runs alone)
    return background_result("docs site")


def _built(page):
    folder, done = _site()
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return folder / "site" / (page.removesuffix(".md") + ".html")


def _list_items(text):
    return len(re.findall(r"^ *(?:[-*]|\d+\.) \S", _prose(text), flags=re.M))


@pytest.mark.slow
@pytest.mark.parametrize("page", [p.relative_to(DOCS).as_posix() for p in _pages()])
def test_built_page_keeps_its_lists_figures_and_equations(page):
    """Lists in the source are lists in the HTML (on /tour/simulate/ nine bullets after an
    indented code block had merged into one paragraph), every figure marker is an image, and
    every equation marker is mathematics."""
    text = (DOCS / page).read_text()
    html = _built(page)
    counter = _Counter()
    counter.feed(html.read_text())
    assert counter.items >= _list_items(text), \
        f"{page}: {_list_items(text)} list items in the source, {counter.items} in the HTML"
    for name in _marked(text, "figure"):
        assert any(src.endswith(f"figures/{name}.png") for src in counter.images), name
    assert counter.math >= len(_marked(text, "equation")), page


@pytest.mark.slow
def test_built_site_works_offline():
    site = _built("index.md").parent
    assert (site / "assets" / "mathjax" / "tex-svg-full.js").stat().st_size > 1_000_000
    assert "<loc>" in (site / "sitemap.xml").read_text()
    for html in site.rglob("*.html"):
        text = html.read_text()
        assert "fonts.googleapis" not in text and "fonts.gstatic" not in text, html
        assert "cdn.jsdelivr" not in text and "unpkg.com" not in text, html
    face = (site / "reference" / "api" / "quadcog.html").read_text()
    assert "quadcog.sim.flight.simulate" in face


def test_references_to_pages_are_links():
    """"docs/model.md sec. 3.3" in prose is a link on the site ([the model, sec. 3.3](...)),
    not plain text; a command line that names a file (`--update docs/identify.md`) may."""
    plain = []
    for page in _pages():
        text = re.sub(r"\]\([^)]*\)", "]()", _prose(page.read_text()))
        text = re.sub(r"<!--.*?-->", "", text, flags=re.S)
        for m in re.finditer(r"(?<![-\w/])docs/[\w/-]+\.md(?!`:)(`)?(,)?\s*(sec\.)?", text):
            if "--update " in text[max(0, m.start() - 12):m.start()] or \
                    text[m.end():m.end() + 2].startswith(("N`", " N")):
                continue                    # a command line; the notation `docs/model.md sec. N`
            plain.append(f"{page.relative_to(DOCS)}: {m.group(0)!r}")
    assert not plain, "\n".join(plain)


@pytest.mark.slow
def test_api_pages_render_docstrings_not_raw_markup():
    """The controller interface (quadcog.controllers.template) read as one paragraph with its
    Returns as a code block of raw backticks; no API page shows ``double backticks``."""
    site = _built("index.md").parent
    for html in (site / "reference" / "api").glob("*.html"):
        assert "``" not in html.read_text(), html.name
    text = (site / "reference" / "api" / "controllers.html").read_text()
    assert "<li><code>ref</code>" in text


def test_scenario_key_meanings_are_their_own():
    """On the scenario-keys page a controller's keys each have a meaning of their own: none
    empty (adaptive's inherited poles had none), none starting with a leaked type string
    ("float or (3,) sequence of float, optional ..."), no two keys of a table with one text."""
    page = _module("gen_reference", DOCS / "gen_reference.py").scenario_keys_page()
    for table in page.split("\n### ")[1:]:
        meanings = [line.rstrip(" |").split(" | ")[-1] for line in table.splitlines()
                    if line.startswith("| `")]
        assert all(meanings), table.splitlines()[0]
        assert not [m for m in meanings if re.match(r"(float|int|str|bool|sequence|tuple)\b"
                                                     r"[^.]*(, optional|\))", m)], table[:60]
        assert len(set(meanings)) == len(meanings), table.splitlines()[0]


# -- tables fit the column -------------------------------------------------------------------
# At 1280 px (and wider: Material's grid stops at 61rem) the content column is 688 px. A
# table is as narrow as the sum of its columns' longest unbreakable words plus the cells'
# padding (docs/stylesheets/extra.css: no min-width on the header cells, whose words may
# break anywhere; code in a cell breaks anywhere; a cell's text also after "_", between
# CamelCase humps (docs/gen_reference.py breakable_cells) and after a hyphen before a letter).
# TABLE_CHAR: the advance of a character of DejaVu Sans (the fallback of a machine without
# Roboto, wider than Roboto, Helvetica or Arial) at the tables' 12 px, digits (0.64 em) and
# lowercase (0.55 em) mixed; TABLE_PADDING: 2 x 0.9375 em of a cell. Calibrated against
# headless Chromium on every built page (no table wider than its column there), the
# performance page's main table before issue 32's fix estimates over the column.
CONTENT_PX, TABLE_CHAR, TABLE_PADDING = 688, 6.8, 23


def _table_cells(line):
    return [c.strip() for c in re.split(r"(?<!\\)\|", line.strip())[1:-1]]


def _unbreakable(cell, gen):
    cell = re.sub(r"`[^`]*`", " ", cell)                    # code in a cell breaks anywhere
    cell = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", cell).replace("**", "").replace("\\|", "|")
    html = gen.breakable_cells(f"<td>{cell}</td>")[len("<td>"):-len("</td>")]
    return [w for part in html.split("<wbr>") for word in part.split()
            for w in re.split(r"(?<=-)(?=[A-Za-z])", word)]


def _tables(text):
    found = []
    for line in _prose(text).splitlines() + [""]:
        if line.startswith("|"):
            found.append(line)
        elif found:
            yield found
            found = []


def test_tables_fit_the_column():
    """/performance/'s main table was 888 px in the column, its note column off-screen: every
    table of the written and the generated pages fits CONTENT_PX (bench/publish.py puts a
    bench table's notes below it)."""
    gen = _module("gen_reference", DOCS / "gen_reference.py")
    texts = {p.relative_to(DOCS).as_posix(): p.read_text() for p in _pages()} | gen.pages()
    wide = [f"{name}: {_narrowest_px(t, gen):.0f} px: {t[0][:70]}"
            for name, text in texts.items() for t in _tables(text)
            if _narrowest_px(t, gen) > CONTENT_PX]
    assert not wide, "\n".join(wide)
    css = (DOCS / "stylesheets" / "extra.css").read_text()
    assert re.search(r"table:not\(\[class\]\) th \{\s*min-width: 0;\s*overflow-wrap: anywhere;", css)
    assert "font-size: 0.6rem" in css and "td code {\n  overflow-wrap: anywhere;" in css
    assert "stylesheets/extra.css" in (ROOT / "mkdocs.yml").read_text()


def _narrowest_px(table, gen, char=TABLE_CHAR, least=0.0):
    """The narrowest width (px) a Markdown table (its lines) can take on the site; ``char``
    and ``least`` (a column's minimum) for other styles than extra.css's."""
    rows = [_table_cells(line) for line in table]
    width = 0.0
    for i in range(len(rows[0])):
        words = [w for row in rows[2:] if i < len(row) for w in _unbreakable(row[i], gen)]
        width += max(max((len(w) for w in words), default=0) * char + TABLE_PADDING, least)
    return width


def test_the_estimate_finds_the_table_the_reader_found():
    """The bench table as the command writes it (its note column; the tracked
    bench/results-avx512.md) in Material's own style (12.8 px, 100 px at least per column)
    estimates over the column, as the reader measured (888 px); as the page shows it
    (bench/publish.py page_table: notes below) in extra.css's style it fits."""
    gen = _module("gen_reference", DOCS / "gen_reference.py")
    pub = _module("publish", ROOT / "bench" / "publish.py")
    raw = pub.table_of((ROOT / "bench" / "results-avx512.md").read_text()).splitlines()
    assert raw[0].rstrip(" |").endswith("note")
    assert _narrowest_px(raw, gen, char=TABLE_CHAR * 0.64 / 0.6, least=100) > CONTENT_PX
    shown = pub.page_table("\n".join(raw)).split("\n\n")[0].splitlines()
    assert _narrowest_px(shown, gen) <= CONTENT_PX


def test_code_font_fits_88_columns_in_the_column():
    """extra.css's code size: 88 columns of DejaVu Sans Mono (0.602 em, the widest common
    monospace) plus Material's padding (1.1765 em a side) fit CONTENT_PX; Chromium measured
    Material's default (0.85 em of 16 px) at 752 px for 88 columns, 64 px over."""
    css = (DOCS / "stylesheets" / "extra.css").read_text()
    em = float(re.search(r"pre > code \{\s*font-size: ([\d.]+)em;", css).group(1))
    px = 16 * em
    assert CODE_COLUMNS * 0.602 * px + 2 * 1.1765 * px <= CONTENT_PX


def test_headings_are_not_in_the_first_person():
    """/identify/ had "What does not fit, and why I think so" as a heading."""
    found = [f"{p.relative_to(DOCS)}: {line}" for p in _pages()
             for line in _prose(p.read_text()).splitlines()
             if line.startswith("#") and re.search(r"\b(I|we|my|our|us|me)\b", line, re.I)]
    assert not found, "\n".join(found)
