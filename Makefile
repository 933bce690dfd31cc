# Two entry points for a fresh machine: `make demo` (set up + run the main job) and
# `make test` (set up + run the test suite). Each creates its own virtual environment.
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin

.PHONY: demo test setup lint bench clean

$(BIN)/activate:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	# The CPU build of PyTorch first (a plain `torch` may pull a multi-GB CUDA build).
	$(BIN)/pip install --quiet torch==2.13.0 || $(BIN)/pip install --quiet torch --index-url https://download.pytorch.org/whl/cpu
	$(BIN)/pip install --quiet -e '.[test]'

setup: $(BIN)/activate

demo: setup
	$(BIN)/lamp warmup   # compile the Numba kernels once (cached), outside the planning time
	$(BIN)/lamp demo

test: setup
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/python -m pytest -q -n 2 --durations=15

lint: setup
	$(BIN)/ruff check src tests benchmarks

clean:
	rm -rf $(VENV) lamp-demo .pytest_cache .hypothesis
