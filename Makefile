# wearcast: `make run` serves the API with the example fleet; `make test` runs the default suite.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
TYPES  := .typecheck/wearcast
HOST   ?= 127.0.0.1
PORT   ?= 8000
# the suites run in one pytest-xdist process per CPU, a test file per process at a time;
# PARALLEL= (empty) runs them in one process
PARALLEL ?= -n auto --dist loadfile

.PHONY: run test test-slow test-all lint typecheck bench demo clean lock worker

# dependencies pinned by requirements.lock (pip constraints), the package itself editable
$(STAMP): pyproject.toml requirements.lock
	@$(PYTHON) -c 'import sys; assert sys.version_info >= (3, 11), "wearcast needs Python 3.11+"'
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -c requirements.lock -e '.[dev]'
	@touch $(STAMP)

# re-pin requirements.lock from a fresh resolution of pyproject.toml
lock:
	rm -rf .venv-lock && $(PYTHON) -m venv .venv-lock
	.venv-lock/bin/python -m pip install --quiet --upgrade pip
	.venv-lock/bin/python -m pip install --quiet -e '.[dev]'
	(sed -n '1,3p' requirements.lock; .venv-lock/bin/python -m pip freeze --exclude-editable \
	  | grep -v '^wearcast') > requirements.lock.new && mv requirements.lock.new requirements.lock
	rm -rf .venv-lock

run: $(STAMP)
	$(BIN)/wearcast serve --host $(HOST) --port $(PORT) --load-example

# job worker processes (with WEARCAST_JOB_QUEUE=dramatiq on the API and a Redis broker)
worker: $(STAMP)
	$(BIN)/wearcast worker

test: lint typecheck
	$(BIN)/python -m pytest $(PARALLEL)

test-slow: $(STAMP)
	$(BIN)/python -m pytest -m slow $(PARALLEL)

test-all: $(STAMP)
	$(BIN)/python -m pytest -m '' $(PARALLEL)

# mypy sees the installed package layout (wearcast.physics -> physics/ ...) through a tree of
# links, so every cross-module import is typed instead of resolving to Any.
$(TYPES)/__init__.py:
	mkdir -p $(TYPES)
	for p in physics statistics service migrations; do ln -sfn ../../$$p $(TYPES)/$$p; done
	touch $@

lint: $(STAMP)
	$(BIN)/ruff check physics statistics service tests benchmarks examples docs

typecheck: $(STAMP) $(TYPES)/__init__.py
	MYPYPATH=.typecheck $(BIN)/mypy -p wearcast.physics -p wearcast.statistics -p wearcast.service

demo: $(STAMP)
	$(BIN)/wearcast demo

bench: $(STAMP)
	@for b in benchmarks/bench_*.py; do echo "== $$b"; $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(VENV) data .pytest_cache .typecheck
