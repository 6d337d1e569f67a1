# quadcog: `make paper` (set up, derive if stale, compile, reproduce the paper) and `make test`.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed-stamp

.PHONY: all setup derive derive-if-stale check-generated compile tour paper analyze test bench clean

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

# The main job: the paper's figures and claims, the analysis, then the report.
paper: compile
	$(PY) -m quadcog paper --out $(OUT)/paper
	$(PY) -m quadcog analyze --out $(OUT)/analysis

analyze: compile
	$(PY) -m quadcog analyze --out $(OUT)/analysis

test: $(STAMP)
	$(PY) -m pytest

# Timing tables (no assertions); writes bench/results.md.
bench: compile
	$(PY) bench/run.py

clean:
	rm -rf $(VENV) .pytest_cache quadcog.egg-info
