# Two commands on a fresh machine: `make demo` and `make test` (see README.md).
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test bench clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

# Reinstall when the project's dependency list changes.
$(STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install --quiet -e '.[test,bench,dask]'
	touch $(STAMP)

demo: $(STAMP)
	$(PY) -m shapefmu design simultaneous --mode 2000:0.01 --mode 3000:0.01
	$(PY) -m shapefmu sensitivity ei --mode 2000:0.01 --vtol 0.05 --plot results/sensitivity_ei.png
	$(PY) examples/multimode_shapers.py
	@echo "demo outputs are in results/"

test: $(STAMP)
	$(PY) -m pytest -q

bench: $(STAMP)
	@for script in benchmarks/*.py; do echo "== $$script"; $(PY) $$script || exit 1; done

clean:
	rm -rf $(VENV) results fmus/*.fmu build src/*.egg-info
