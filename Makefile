# mvtk: two entry points.  `make report` runs the smart-beam study to an HTML report,
# `make test` lints and runs the whole test suite.  Both create .venv on first use and
# install only what they need: the report the base package (plus CHOLMOD, a faster
# sparse Cholesky, and Debian's OpenBLAS for it when run as root), the tests also the
# test peers and tools.
# `make docs` builds the documentation site (docs/_build/html).
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
# what the example study needs: the base package (numpy, scipy, pandas, matplotlib,
# xarray, ...) and the optional CHOLMOD factorisation (GPL; never in a plain pip install)
REPORT_STAMP := $(VENV)/.report-stamp
# what the test suite needs on top: file formats, control, dask, the peers and tools
STAMP  := $(VENV)/.installed-stamp
DOCS_STAMP := $(VENV)/.docs-stamp
OUT    ?= reports/smart_beam

.PHONY: report test lint bench docs clean

$(VENV)/bin/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(REPORT_STAMP): pyproject.toml scripts/system_packages.sh | $(VENV)/bin/python
	# Debian's OpenBLAS for CHOLMOD (as root with apt-get; otherwise a hint, never an error)
	bash scripts/system_packages.sh report
	# --no-compile: byte code is written for the modules a run imports, not for all (135 MB)
	$(BIN)/python -m pip install --quiet --no-compile -e '.[cholmod]'
	touch $(REPORT_STAMP)

$(STAMP): pyproject.toml scripts/system_packages.sh | $(VENV)/bin/python
	# OpenBLAS, plus chromium and libblas3/liblapack3 for the browser and OpenSees tests
	bash scripts/system_packages.sh test
	$(BIN)/python -m pip install --quiet -e '.[tdms,control,scale,test,cholmod]'
	# SDynPy is the peer of the correlation tests (MAC, FRAC, MSF); its GUI dependencies
	# (PyQt5, VTK: hundreds of MB) are not needed for that, so it comes without them
	$(BIN)/python -m pip install --quiet --no-deps 'sdynpy>=0.23'
	touch $(STAMP)

$(DOCS_STAMP): pyproject.toml $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[docs,notebooks]'
	touch $(DOCS_STAMP)

report: $(REPORT_STAMP)
	$(BIN)/mvtk run data/smart_beam/study.toml --out $(OUT)

lint: $(STAMP)
	$(BIN)/ruff check mvtk tests benchmarks data docs
	# the package floors of docs/architecture.md (pyproject.toml [tool.importlinter])
	$(BIN)/lint-imports --no-cache

test: $(STAMP) lint
	$(BIN)/python -m pytest

# every benchmark in its own process, one JSON summary (figures, peer ratios, load) in
# reports/bench.json; the peers need `pip install -e '.[bench,cholmod]'` (openseespy
# also Debian's libblas3 liblapack3)
bench: $(STAMP)
	$(BIN)/python benchmarks/_summary.py --out reports/bench.json

# the documentation site: warnings are errors, notebooks executed, links and API checked
docs: $(DOCS_STAMP)
	rm -rf docs/_build/html
	$(BIN)/python -m sphinx -b html -W --keep-going -q docs docs/_build/html
	$(BIN)/python docs/check_site.py docs/_build/html --screenshot tests/artifacts/docs_index.png

clean:
	rm -rf $(VENV) reports/*/ .pytest_cache docs/_build docs/_generated
