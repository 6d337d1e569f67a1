# quadcog: `make paper` (set up, derive if stale, compile, reproduce the paper) and `make test`.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed-stamp

# AdaptiveQuadBench (make aqb, make bench-aqb): its targets are phony too
.PHONY: aqb bench-aqb
.PHONY: all setup derive derive-if-stale check-generated compile tour paper analyze report test bench bench-peers mutations embedded crazyflie crazyflie-app docs docs-figures targets clean

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

# The suite on every core up to TEST_WORKERS (pytest-xdist), each test file on one worker so
# that a module's fixture (the paper's flights, a compiled export) is built once.
# TEST_WORKERS=0 runs it in this process.
TEST_WORKERS ?= 4
test: $(STAMP)
	$(PY) -m pytest -n auto --maxprocesses $(TEST_WORKERS) --dist loadfile

# The Crazyflie firmware's five controllers against quadcog's laws on the Crazyflie 2.1, and
# the firmware PID against the CrazyPAD flights (docs/crazyflie.md; under a minute; needs a
# firmware tree and the CrazyPAD data beside the repository); the page's tables are copied.
crazyflie: compile
	$(PY) bench/crazyflie.py $(OUT)/crazyflie/side-by-side.md
	$(PY) bench/publish.py crazyflie $(OUT)/crazyflie/side-by-side.md
	$(PY) bench/crazyflie_real.py $(OUT)/crazyflie/real-flights.md
	$(PY) bench/publish.py crazyflie-real $(OUT)/crazyflie/real-flights.md

# Timing tables (no assertions); writes out/bench/results-ISA.md, ISA the kernel build (QUADCOG_KERNEL_ISA=avx2 pins one;
# `python bench/publish.py bench` copies each into docs/performance.md and bench/).
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

# AdaptiveQuadBench and its RotorPy fork (docs/aqb.md): the `aqb` extra's PyPI packages, the
# vendor tarball (or $$QUADCOG_AQB, a checkout of your own) copied into quadcog's cache with the
# CPU fixes applied to that copy, then both trees pip install -e'd (the fork replaces PyPI's
# rotorpy, which `make bench-peers` installs under the same name).
aqb: $(STAMP)
	$(PY) -m pip install --quiet -e '.[aqb]'
	$(PY) -m quadcog.aqb setup > $(VENV)/.aqb-folders
	$(PY) -m pip install --quiet --no-deps $$(sed 's/^/-e /' $(VENV)/.aqb-folders)

# AdaptiveQuadBench's payload experiment (AQB_TRIALS trials, when2fail to intensity 2, delay
# margin) for its peers and quadcog's laws, one process per controller; then the same trials
# in both simulators. Writes out/aqb/*.json; `python bench/publish.py aqb` and
# `python bench/publish.py aqb-physics` put the tables into docs/aqb.md. Hours on 2 cores.
AQB_TRIALS ?= 100
AQB_ARGS ?=
bench-aqb: aqb compile
	$(PY) bench/aqb_suite.py --trials $(AQB_TRIALS) $(AQB_ARGS)
	$(PY) bench/aqb_physics.py --trials $(AQB_TRIALS) $(AQB_ARGS)

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

# quadcog's laws (composite, payload_adaptive) as out-of-tree controller apps of the Crazyflie
# firmware: built into cf2.elf by the firmware's own Makefiles (in quadcog's cache; the tree is
# $(QUADCOG_CRAZYFLIE_FIRMWARE) or shared/vendor/crazyflie-firmware.tar.xz beside the
# checkout), with the flash
# and RAM they add, instructions per call on the Cortex-M4 (QEMU) against the 500 Hz budget,
# and their host agreement with quadcog's law; needs $(ARM_PACKAGES). A few minutes the first
# time (two full firmware builds), seconds from the cache.
crazyflie-app: $(STAMP)
	$(PY) -m quadcog.embedded.crazyflie_report
# PX4 in the loop (docs/px4.md): build PX4's px4_sitl_default into quadcog's cache, once per tree
# (the tree: PX4=PATH, else $$QUADCOG_PX4, else shared/vendor/px4-autopilot.tar.xz next to the checkout); pip
# installs the build's Python packages (quadcog.px4.tree.BUILD_PACKAGES) where missing.
.PHONY: px4-build px4
px4-build: $(STAMP)
	$(PY) -c 'import sys; from quadcog.px4.tree import main; sys.exit(main())' $(PX4)

# The PX4 tables (speed, identification on PX4's ULogs, side by side): out/px4/px4.md
px4: px4-build
	mkdir -p $(OUT)/px4
	$(PY) bench/px4.py --out $(OUT)/px4 | tee $(OUT)/px4/px4.md

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
