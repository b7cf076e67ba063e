# Two commands on a fresh machine: `make demo` and `make test` (see README.md).
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test bench examples clean system-packages

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

# Reinstall when the project's dependency list changes.
$(STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install --quiet -e '.[test,bench,dask]'
	touch $(STAMP)

# The main job: every FMU into fmus/, then the disk-drive seek through the co-simulation master
# for each candidate command beside the CasADi time-optimal move.
demo: $(STAMP)
	$(PY) -m shapefmu build
	$(PY) -m shapefmu compare models/disk_drive.toml --distance 0.05 --plot results/compare_disk_drive.png
	@echo "demo outputs: FMUs in fmus/, plots in results/ (compare_disk_drive*.png)"

# Debian packages the tests need (gcc, valgrind), installed when missing; oneTBB for ecospy is a wheel.
system-packages:
	@bash .ci/system-packages

# One worker per core, each taking whole test files (a file's fixtures, FMUs built once, stay in one worker).
test: $(STAMP) system-packages
	$(PY) -m pytest -q -n auto --dist loadfile

# Every paper's script: the design layer's (examples/<topic>.py) and the FMU path's (paper00*_fmu.py).
examples: $(STAMP)
	@for script in examples/*.py; do echo "== $$script"; $(PY) $$script || exit 1; done

bench: $(STAMP)
	@for script in benchmarks/*.py; do echo "== $$script"; $(PY) $$script || exit 1; done

clean:
	rm -rf $(VENV) results fmus/*.fmu build src/*.egg-info
