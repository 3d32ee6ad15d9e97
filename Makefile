# mvtk: two entry points.  `make report` runs the smart-beam study to an HTML report,
# `make test` lints and runs the whole test suite.  Both create .venv on first use.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
OUT    ?= reports/smart_beam

.PHONY: report test lint bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[all]'
	touch $(STAMP)

report: $(STAMP)
	$(BIN)/mvtk run data/smart_beam/study.toml --out $(OUT)

lint: $(STAMP)
	$(BIN)/ruff check mvtk tests benchmarks data

test: $(STAMP) lint
	$(BIN)/python -m pytest

# every benchmark in its own process, one JSON summary (figures, peer ratios, load) in
# reports/bench.json; the peers need `pip install -e '.[bench,cholmod]'` (openseespy
# also Debian's libblas3 liblapack3)
bench: $(STAMP)
	$(BIN)/python benchmarks/_summary.py --out reports/bench.json

clean:
	rm -rf $(VENV) reports/*/ .pytest_cache
