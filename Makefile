# Two commands from a fresh clone: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
RUNTIME := $(VENV)/.installed-runtime
DEV := $(VENV)/.installed-dev

# Compiled XLA programs persist between runs of the demo and the tests: a second `make test` or
# `make demo` skips most of the compile time (the largest part of both on a CPU). Benchmarks
# compile afresh, so the compile times they report are real. `make clean` empties the cache.
# Every program is kept, however quick its compile: within one `make test` the two pytest
# workers and the command-line tests' subprocesses reuse each other's programs.
demo test test-slow test-all papers: export JAX_COMPILATION_CACHE_DIR ?= $(CURDIR)/.cache/jax
demo test test-slow test-all papers: export JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS ?= 0

.PHONY: setup demo test test-slow test-all papers bench clean

setup: $(DEV)

# The demo needs what the package imports; the tests and benchmarks also need the peers they
# compare against (torch, pytorch-kinematics, OR-Tools, crcmod: the `dev` extra).
$(RUNTIME): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e .
	touch $(RUNTIME)

# torch is installed first, pinned to the CPU build, so that pytorch-kinematics does not pull
# a CUDA build.
$(DEV): $(RUNTIME)
	$(PY) -m pip install -q torch==2.13.0
	$(PY) -m pip install -q -e '.[dev]'
	touch $(DEV)

demo: $(RUNTIME)
	$(PY) experiments/pipeline.py

test: $(DEV)
	$(PY) -m pytest -q -n 2 -m "not slow"

# The slow end-to-end and acceptance runs (about 3 min on 2 cores after `make test`); CI runs both.
test-slow: $(DEV)
	$(PY) -m pytest -q -n 2 -m slow

test-all: $(DEV)
	$(PY) -m pytest -q -n 2

# Every table and figure of the three papers, theirs beside ours: docs/reproduction.md and
# docs/img/papers/ (about 2 min on 2 cores with a warm compilation cache, 25 min cold).
papers: $(DEV)
	$(PY) experiments/papers.py

bench: $(DEV)
	@for b in benchmarks/*.py; do echo "== $$b"; $(PY) $$b || exit 1; done

clean:
	rm -rf $(VENV) outputs multirun .pytest_cache .cache
