# Two commands on a fresh machine: `make demo` and `make test`. Each installs what it needs.
VENV ?= .venv
PY := $(VENV)/bin/python
OUT ?= demo-output

.PHONY: setup demo test lint format bench clean

setup:
	@bash scripts/bootstrap.sh

demo: setup
	$(VENV)/bin/ontodetect demo -o $(OUT)

test: setup
	$(VENV)/bin/ruff check src tests benchmarks
	$(PY) -m pytest -q -p no:cacheprovider

lint: setup
	$(VENV)/bin/ruff check src tests benchmarks
	$(VENV)/bin/ruff format --check src tests benchmarks

format: setup
	$(VENV)/bin/ruff format src tests benchmarks
	$(VENV)/bin/ruff check --fix src tests benchmarks

bench: setup
	$(PY) -m benchmarks all

clean:
	rm -rf $(VENV) $(OUT) build *.egg-info src/*.egg-info
