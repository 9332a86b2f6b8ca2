# ecdsim: the two quick-start targets work on a fresh machine with only Python >= 3.11 and make.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP_RUN := $(VENV)/.installed-run
STAMP_DEMO := $(VENV)/.installed-demo
STAMP_TEST := $(VENV)/.installed-test
DEMO_DIR ?= ecdsim-demo

.PHONY: demo test lint typecheck pytest browser bench validate fuzz portability clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# Reinstall whenever the package metadata changes.
$(STAMP_RUN): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e .
	touch $@

# The demo installs the extras too, so that every command the README shows
# (ecdsim montecarlo, ecdsim app, ecdsim export-fmu) works after make demo, and compiles
# the numba kernels ahead (ecdsim precompile: a first run would otherwise wait for them).
$(STAMP_DEMO): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[montecarlo,app,fmu]'
	touch $@ $(STAMP_RUN)

$(STAMP_TEST): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $@ $(STAMP_RUN) $(STAMP_DEMO)

demo: $(STAMP_DEMO)
	$(BIN)/ecdsim precompile
	$(BIN)/ecdsim demo --out $(DEMO_DIR)

lint: $(STAMP_TEST)
	$(BIN)/ruff check src tests benchmarks validation
	$(BIN)/ruff format --check src tests benchmarks validation
	$(BIN)/python scripts/code_metrics.py

typecheck: $(STAMP_TEST)
	$(BIN)/mypy

# The explorer's browser tests drive Debian's chromium: install it when missing, or stop
# at once naming the package (they are never skipped). They also run axe-core, which
# scripts/ensure-axe.sh installs with npm (pinned) into .venv/axe.
browser:
	@bash scripts/ensure-chromium.sh
	@bash scripts/ensure-axe.sh
	@bash scripts/ensure-cc.sh

pytest: $(STAMP_TEST) browser
	$(BIN)/python -m pytest

test: browser lint typecheck pytest

# One table of every bench file's cases, ecdsim and its baseline interleaved (the machines
# are shared and noisy); writes benchmarks/results.json. BENCH_OPTIONS=--quick for a short
# run. The web and Monte Carlo benchmarks need the test extra (fastapi, dask, pyarrow).
# BENCH_BASELINE=REF (a checkout folder or a git ref) compares the dynamic benchmarks of
# this checkout with that baseline instead, each side in its own processes, interleaved
# (benchmarks/bench_before.py; BENCH_OPTIONS=--full for bench_dynamic's full sizes).
BENCH_OPTIONS ?=
BENCH_BASELINE ?=
bench: $(STAMP_TEST)
ifneq ($(BENCH_BASELINE),)
	$(BIN)/python benchmarks/bench_before.py $(BENCH_BASELINE) $(BENCH_OPTIONS)
else
	$(BIN)/python benchmarks/run.py $(BENCH_OPTIONS)
endif

# The long fuzz campaign (docs/fuzzing.md): FUZZ_EXAMPLES random examples per target and
# per API operation (schemathesis, all checks); make test runs the same file short and seeded.
FUZZ_EXAMPLES ?= 500
fuzz: $(STAMP_TEST)
	ECDSIM_FUZZ_EXAMPLES=$(FUZZ_EXAMPLES) $(BIN)/python -m pytest tests/test_fuzz.py -p no:cacheprovider

# The validation suite against independent references (validation/); writes docs/validation.md
# and exits non-zero if any check fails.
validate: $(STAMP_TEST)
	$(BIN)/python -m validation --out docs/validation.md

# The portability matrix (docs/reproducibility.md): the suite under NUMBA_CPU_NAME=generic,
# OPENBLAS_CORETYPE=Prescott and Haswell, and OPENBLAS_NUM_THREADS=1, one run each (about
# four times make pytest). PORTABILITY_TESTS narrows it, e.g. tests/test_examples_fixed.py.
PORTABILITY_TESTS ?=
portability: $(STAMP_TEST) browser
	bash scripts/portability.sh $(PORTABILITY_TESTS)

clean:
	rm -rf $(VENV) $(DEMO_DIR) build dist src/*.egg-info .mypy_cache .pytest_cache .ruff_cache .portability
