# Two entry points, both safe on a fresh machine: `make demo` and `make test`.
# They create .venv, install system packages the project needs (Debian, via deploy/system-deps.sh)
# and the Python package with its dev tools, then run.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: setup demo test test-fast test-narrow lint bench docs clean

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

# The documentation site, into site/ (git-ignored). The CLI and wire-protocol pages are
# generated from the argparse parsers and livedrummer/protocol/spec.py by a MkDocs hook
# (deploy/docs_hooks.py), so they cannot go stale.
docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict --site-dir site

clean:
	rm -rf site $(VENV) .pytest_cache .mypy_cache .ruff_cache
