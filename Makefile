# wearcast: `make run` serves the API with the example fleet; `make test` runs the default suite.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
TYPES  := .typecheck/wearcast
HOST   ?= 127.0.0.1
PORT   ?= 8000

.PHONY: run test test-all lint typecheck bench demo clean

$(STAMP): pyproject.toml
	@$(PYTHON) -c 'import sys; assert sys.version_info >= (3, 11), "wearcast needs Python 3.11+"'
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	@touch $(STAMP)

run: $(STAMP)
	$(BIN)/wearcast serve --host $(HOST) --port $(PORT) --load-example

test: lint
	$(BIN)/python -m pytest

test-all: $(STAMP)
	$(BIN)/python -m pytest -m ''

# mypy sees the installed package layout (wearcast.physics -> physics/ ...) through a tree of
# links, so every cross-module import is typed instead of resolving to Any.
$(TYPES)/__init__.py:
	mkdir -p $(TYPES)
	for p in physics statistics service migrations; do ln -sfn ../../$$p $(TYPES)/$$p; done
	touch $@

lint: $(STAMP) $(TYPES)/__init__.py
	$(BIN)/ruff check physics statistics service tests benchmarks examples docs
	MYPYPATH=.typecheck $(BIN)/mypy -p wearcast.physics -p wearcast.statistics -p wearcast.service

demo: $(STAMP)
	$(BIN)/wearcast demo

bench: $(STAMP)
	@for b in benchmarks/bench_*.py; do echo "== $$b"; $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(VENV) data .pytest_cache .typecheck
