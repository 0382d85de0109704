# Two commands on a fresh machine: `make demo` and `make test`. Each installs what it needs,
# from the lock file (requirements.lock): exact versions with hashes.
VENV ?= .venv
PY := $(VENV)/bin/python
OUT ?= demo-output
# The tool that writes the lock, pinned like everything else.
UV_VERSION := 0.13.9

.PHONY: setup demo test lint format bench generalization lock clean

setup:
	@bash scripts/bootstrap.sh

demo: setup
	$(VENV)/bin/ontodetect demo -o $(OUT)

test:
	@bash scripts/bootstrap.sh --with-browser
	$(VENV)/bin/ruff check src tests benchmarks scripts
	$(VENV)/bin/ruff format --check src tests benchmarks scripts
	$(PY) -m pytest -q -p no:cacheprovider

lint: setup
	$(VENV)/bin/ruff check src tests benchmarks scripts
	$(VENV)/bin/ruff format --check src tests benchmarks scripts

format: setup
	$(VENV)/bin/ruff format src tests benchmarks scripts
	$(VENV)/bin/ruff check --fix src tests benchmarks scripts

bench: setup
	$(PY) -m benchmarks all

# The generalization benchmark (docs/benchmarks.md): make generalization REAL=path/to/scannet-dev
generalization:
	@test -n "$(REAL)" || { echo "make generalization REAL=DIR: DIR holds the real labelled scans"; exit 2; }
	@bash scripts/bootstrap.sh --with-furniture
	$(PY) -m benchmarks generalization --real "$(REAL)" --jobs 2

# Refresh requirements.lock from pyproject.toml's ranges (the newest versions they admit, for
# every platform and Python the package supports), then reinstall from it.
# It needs only a virtual environment (not the old lock installed: that fails once
# pyproject.toml asks for something the old lock lacks).
lock:
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install -q "uv==$(UV_VERSION)"
	printf 'setuptools>=77\nwheel\n' | $(VENV)/bin/uv pip compile pyproject.toml - \
		--extra dev --universal --generate-hashes --python-version 3.10 \
		--no-header --quiet -o requirements.lock
	@bash scripts/bootstrap.sh

clean:
	rm -rf $(VENV) $(OUT) build *.egg-info src/*.egg-info
