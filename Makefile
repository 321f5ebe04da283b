# cylfric: two-command set-up on a machine with only python3.
#   make demo   creates .venv, installs cylfric (the runtime only), runs `cylfric demo`
#   make test   creates .venv, installs cylfric[test], runs the test suite
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
RUNTIME := $(VENV)/.runtime
STAMP  := $(VENV)/.installed

.PHONY: demo test bench lint clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

# cylfric and what it needs to run (make demo): no test or lint tool
$(RUNTIME): pyproject.toml | $(PY)
	$(PY) -m pip install --quiet -e .
	$(PY) -m compileall -q src  # byte code once: PYTHONDONTWRITEBYTECODE machines would compile cylfric in every process
	touch $(RUNTIME)

# the test and lint tools on top (make test, make lint)
$(STAMP): pyproject.toml $(RUNTIME)
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

demo: $(RUNTIME)
	$(VENV)/bin/cylfric demo --out demo-out

test: $(STAMP)
	$(PY) -m pytest -q -n 2

bench: $(STAMP)
	$(PY) -m pip install --quiet -e '.[test,bench]' || echo "note: numbalsoda (the bench extra) did not install; it builds from source with gfortran (apt-get install gfortran); its baseline is left out"
	$(PY) benchmarks/run.py

lint: $(STAMP)
	$(VENV)/bin/ruff check src tests benchmarks
	$(VENV)/bin/ruff format --check src tests benchmarks
	$(VENV)/bin/mypy
	$(VENV)/bin/lint-imports --no-cache

clean:
	rm -rf $(VENV) demo-out build src/*.egg-info .pytest_cache .hypothesis
