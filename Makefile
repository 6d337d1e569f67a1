# quadcog: `make tour` (set up, derive if stale, compile, show) and `make test`.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed-stamp

.PHONY: all setup derive derive-if-stale check-generated compile tour test bench clean

all: tour

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

test: $(STAMP)
	$(PY) -m pytest

# Timing tables (no assertions); writes bench/results.md.
bench: compile
	$(PY) bench/run.py

clean:
	rm -rf $(VENV) .pytest_cache quadcog.egg-info
