# Every target sets up .venv on first use: torch==2.13.0 (the CPU build) first, then the package.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

CHROMIUM := /usr/bin/chromium
# apt-get needs root: sudo when make runs as another user.
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: run test lint bench venv clean chromium

venv: $(STAMP)

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet torch==2.13.0
	$(PY) -m pip install --quiet -e ".[train,plot,ray,dev]"
	touch $(STAMP)

run: $(STAMP)
	$(VENV)/bin/socialzoo benchmark --quick --out results

lint: $(STAMP)
	$(VENV)/bin/ruff check socialzoo tests benchmarks tools
	$(VENV)/bin/mypy

# The episode viewer's browser test needs Debian's chromium (driven by Playwright from the dev extra).
chromium:
	@test -x $(CHROMIUM) || { \
		echo "installing Debian's chromium for the browser test"; \
		$(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get update -qq && \
		$(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium; \
	}

test: $(STAMP) chromium lint
	$(VENV)/bin/pytest -q -n 2 tests

bench: $(STAMP)
	$(PY) benchmarks/world_throughput.py

clean:
	rm -rf $(VENV) results build *.egg-info
