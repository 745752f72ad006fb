# Two entry points, both safe on a fresh machine: `make demo` and `make test`.
# They create .venv, install system packages the project needs (Debian, via deploy/system-deps.sh)
# and the Python package with its dev tools, then run.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: setup demo test test-fast test-narrow lint bench clean

setup: $(STAMP)

$(STAMP): pyproject.toml deploy/system-deps.sh
	bash deploy/system-deps.sh
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[dev]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/livedrummer demo

test: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy
	$(BIN)/pytest -q --durations=15

# The units alone, for a developer between edits (about two minutes on two cores): no test that
# starts processes, sockets, JACK or windows (e2e), none of the pure ones that take seconds
# (slow); marks from tests/markers.py. `make test` runs everything.
test-fast: $(STAMP)
	$(BIN)/pytest -q -m "not e2e and not slow" --durations=10

# The same tests with numpy's SIMD dispatch and OpenBLAS's kernels narrowed (see .ci/narrowed).
test-narrow: $(STAMP)
	.ci/narrowed

bench: $(STAMP)
	$(BIN)/livedrummer bench ingest

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache
