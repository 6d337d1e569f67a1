# quadcog: `make paper` (set up, derive if stale, compile, reproduce the paper) and `make test`.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed-stamp

.PHONY: all setup derive derive-if-stale check-generated compile tour paper analyze report test bench bench-peers mutations embedded docs docs-figures targets clean

OUT ?= out

all: paper

# Create the virtual environment and install quadcog with its test/plot extras.
$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

setup: $(STAMP)

# Rewrite generated/ from derive/ (SymPy); prints the time of every stage.
derive: $(STAMP)
	$(PY) -m derive

derive-if-stale: $(STAMP)
	$(PY) -m derive --if-stale

# Exit 1 with a diff when generated/ is not what derive/ produces.
check-generated: $(STAMP)
	$(PY) -m derive --check

compile: derive-if-stale
	$(PY) -c "import quadcog; m = quadcog.load(); print('compiled backend:', m.backend)"

tour: compile
	$(PY) -m quadcog tour

TEXLIVE := texlive-latex-base texlive-latex-recommended poppler-utils

# The main job: the paper's figures and claims, the analysis, then the report (the PDF when
# pdflatex is there; otherwise it says how to install it, and the rest is kept).
paper: compile
	$(PY) -m quadcog paper --out $(OUT)/paper
	$(PY) -m quadcog analyze --out $(OUT)/analysis
	@if command -v pdflatex >/dev/null; then $(MAKE) --no-print-directory report; else \
	  echo "note: pdflatex not found, so no PDF report; install TeX Live (as root):"; \
	  echo "  apt-get update && apt-get install -y --no-install-recommends $(TEXLIVE)"; \
	  echo "then run: make report"; fi

# The derived report as a PDF: check the generated functions' identities at 200 random points
# (the table in the PDF is filled in from this run), then build generated/report.tex with
# pdflatex into out/report/report.pdf, with out/paper/ when `quadcog paper` has run.
report: $(STAMP)
	@command -v pdflatex >/dev/null || { echo "pdflatex not found; install TeX Live (as root):"; \
	  echo "  apt-get update && apt-get install -y --no-install-recommends $(TEXLIVE)"; exit 1; }
	$(PY) -m report.verify --out $(OUT)/report/verification.tex --points 200
	$(PY) -m report.pdf --out $(OUT)/report --paper $(OUT)/paper --analysis $(OUT)/analysis

analyze: compile
	$(PY) -m quadcog analyze --out $(OUT)/analysis

# The controllers' default settings on every preset against the targets (docs/targets.md):
# about a minute and a half; the page's table is copied from the run.
targets: compile
	$(PY) -m quadcog targets --out $(OUT)/targets
	$(PY) bench/publish.py targets $(OUT)/targets/targets.md

test: $(STAMP)
	$(PY) -m pytest

# Timing tables (no assertions); writes out/bench/results.md (`python bench/publish.py bench`
# copies it into docs/performance.md and bench/results.md).
bench: compile
	$(PY) bench/run.py

# The peers of `make bench` (absent ones are reported absent): torch's CPU build first, then
# the bench extra (RotorPy, crazyflow on JAX). From PyPI a plain torch is a CUDA build of
# several GB; where no CPU build of torch 2.13.0 is at hand (pip says which file it took), take
# PyTorch's CPU index: make bench-peers TORCH_PIP_ARGS='--index-url https://download.pytorch.org/whl/cpu'
TORCH_PIP_ARGS ?=
bench-peers: $(STAMP)
	$(PY) -m pip install $(TORCH_PIP_ARGS) torch==2.13.0
	$(PY) -m pip install -e '.[bench]'

# Would the tests catch wrong physics? Each deliberate mistake (bench/mutations.py --list) is
# applied to a copy of the repository, which runs the physics tests; writes
# out/mutations/results.md and fails when a mutation survives. MUTATIONS_ARGS: e.g.
# --only gravity_sign, --tests tests/test_physics.py.
mutations: $(STAMP)
	$(PY) bench/mutations.py $(MUTATIONS_ARGS)

# The controllers as C99 modules (float32, double) in generated/embedded/, checked with strict
# flags, run on a Cortex-M4 in QEMU; prints the cost table and writes it with the target-vs-host
# differences to $(OUT)/embedded/costs.json (`python bench/publish.py embedded` puts them into
# the docs); needs $(ARM_PACKAGES).
ARM_PACKAGES := gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm
embedded: compile
	$(PY) -m quadcog.embedded --out $(OUT)/embedded

# The documentation site (MkDocs, Material, mkdocstrings) into $(OUT)/docs/; the reference pages
# (scenario and sweep keys, the CLI, the API) are generated at build time by docs/gen_reference.py.
docs: $(STAMP)
	$(VENV)/bin/mkdocs build --strict --site-dir $(OUT)/docs

# The site's figures (docs/figures/*.png, committed) from quadcog's own commands: about two
# minutes; docs/figures.py lists each figure, its command and its caption.
docs-figures: compile
	$(PY) docs/figures.py

clean:
	rm -rf $(VENV) .pytest_cache quadcog.egg-info
