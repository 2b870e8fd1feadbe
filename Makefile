# Two commands on a fresh machine: `make demo` and `make test`. Each creates .venv when missing.
PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test quick lint typecheck docs unit bench bench-axis bench-classify bench-mesh bench-simplify clean

$(BIN)/python:
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "error: $(PYTHON) not found (medax needs Python 3.11 or newer: make PYTHON=python3.12 ...)"; exit 1; }
	$(PYTHON) -m venv $(VENV)

# constraints.txt pins exact versions of what pyproject.toml only bounds from below
$(STAMP): $(BIN)/python pyproject.toml constraints.txt
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -c constraints.txt -e '.[dev]'
	@touch $(STAMP)

demo: $(STAMP)
	$(BIN)/medax demo

LINTED := $(wildcard src tests benchmarks)

lint: $(STAMP)
	$(BIN)/ruff check $(LINTED)
	$(BIN)/ruff format --check $(LINTED)

typecheck: $(STAMP)
	$(BIN)/mypy

# the documentation site in build/site; --strict: a broken link, page or API reference fails
# (not with --quiet: it drops the warnings before --strict counts them, so nothing failed)
docs: $(STAMP)
	$(BIN)/mkdocs build --strict

# test files spread over the cores, one file per worker at a time (module fixtures built once)
unit: $(STAMP)
	$(BIN)/python -m pytest -n auto --maxprocesses 4 --dist loadfile

test: lint typecheck docs unit

# the tests not marked slow (OCCT-heavy and long ones), on the cores like unit: under a minute
quick: $(STAMP)
	$(BIN)/python -m pytest -n auto --maxprocesses 4 --dist loadfile -m "not slow"

# benchmarks print ratios against peers measured in the same run (not part of `make test`)
bench: bench-axis bench-classify bench-mesh bench-simplify

bench-axis: $(STAMP)
	$(BIN)/python benchmarks/bench_axis.py

bench-classify: $(STAMP)
	$(BIN)/python benchmarks/bench_classify.py

bench-mesh: $(STAMP)
	$(BIN)/python benchmarks/bench_mesh.py

bench-simplify: $(STAMP)
	$(BIN)/python benchmarks/bench_simplify.py

clean:
	rm -rf $(VENV) medax-demo .pytest_cache .mypy_cache .ruff_cache
