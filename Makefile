# Every target sets up .venv on first use: torch==2.13.0 (the CPU build) first, then the package.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

CHROMIUM := /usr/bin/chromium
# apt-get needs root: sudo when make runs as another user.
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: run test lint bench venv clean chromium policies docs

venv: $(STAMP)

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet torch==2.13.0
	$(PY) -m pip install --quiet -e ".[train,plot,ray,dev,docs]"
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

# The documentation site (docs/*.md and the API reference from the docstrings) into site/.
docs: $(STAMP)
	$(VENV)/bin/mkdocs build --strict --site-dir site

bench: $(STAMP)
	$(PY) benchmarks/world_throughput.py

# Retrain the shipped PPO and DQN policies with their recorded commands and seeds (needed after an
# env version bump: policy files trained on another version of the benchmark env are refused).
# The shipped DQN normalises observations (chosen on validation scenarios; the paper's DQN did not).
PPO_SHIP ?= --seed 0
DQN_SHIP ?= --seed 0 --normalize
policies: $(STAMP)
	$(VENV)/bin/socialzoo train ppo --out runs/shipped/ppo $(PPO_SHIP) --no-progress
	$(VENV)/bin/socialzoo train dqn --out runs/shipped/dqn $(DQN_SHIP) --no-progress
	mkdir -p socialzoo/agents/shipped
	for algo in ppo dqn; do \
		cp runs/shipped/$$algo/$$algo.safetensors socialzoo/agents/shipped/$$algo.safetensors && \
		cp runs/shipped/$$algo/run.json socialzoo/agents/shipped/$$algo.run.json || exit 1; \
	done

clean:
	rm -rf $(VENV) results build site *.egg-info
