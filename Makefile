# The two set-up commands: `make test` and `make demo`. Each creates .venv from
# pyproject.toml when it is missing or older than pyproject.toml.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: test demo bench lint kernels clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[all,test]"
	$(PY) -m moveability.compiled.build
	touch $(STAMP)

# the ahead-of-time compiled kernels, rebuilt when a kernel's source changed (three
# to four minutes on two cores; without them, or when stale, numba's JIT runs the kernels: see
# src/moveability/compiled/__init__.py)
kernels: $(STAMP)
	$(PY) -m moveability.compiled.build

lint: $(STAMP)
	$(VENV)/bin/ruff check src tests benchmarks examples
	$(VENV)/bin/mypy

# one worker per core; a test file stays on one worker (module fixtures, README order)
test: lint kernels
	$(VENV)/bin/pytest -n auto --dist loadfile

demo: kernels
	$(PY) examples/demo.py

bench: kernels
	$(PY) benchmarks/bench_tree.py
	$(PY) benchmarks/bench_analysis.py
	$(PY) benchmarks/bench_mechanisms.py
	$(PY) benchmarks/bench_sweep.py
	$(PY) benchmarks/bench_counts.py
	$(PY) benchmarks/bench_speed.py
	$(PY) benchmarks/bench_constraints.py
	$(PY) benchmarks/bench_delta.py

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache .hypothesis
	rm -f src/moveability/compiled/_aot.*
