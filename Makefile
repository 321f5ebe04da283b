# cylfric: two-command set-up on a machine with only python3.
#   make demo   creates .venv, installs cylfric, runs `cylfric demo`
#   make test   creates .venv, installs cylfric[test], runs the test suite
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test bench lint clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	$(PY) -m compileall -q src  # byte code once: PYTHONDONTWRITEBYTECODE machines would compile cylfric in every process
	touch $(STAMP)

demo: $(STAMP)
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
