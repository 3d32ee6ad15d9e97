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

bench: $(STAMP)
	for f in benchmarks/bench_*.py; do $(BIN)/python $$f || exit 1; done

clean:
	rm -rf $(VENV) reports/*/ .pytest_cache
