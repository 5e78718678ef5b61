# Every target sets up .venv on first use: torch==2.13.0 (the CPU build) first, then the package.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: run test lint bench venv clean policies

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

test: $(STAMP) lint
	$(VENV)/bin/pytest -q -n 2 tests

bench: $(STAMP)
	$(PY) benchmarks/world_throughput.py

# Retrain the shipped PPO and DQN policies with the recorded seeds (after an env version bump:
# policy files trained on another version of the benchmark env are refused when loaded).
SHIP_SEED ?= 0
policies: $(STAMP)
	for algo in ppo dqn; do \
		$(VENV)/bin/socialzoo train $$algo --out runs/shipped/$$algo --seed $(SHIP_SEED) --no-progress && \
		cp runs/shipped/$$algo/$$algo.safetensors socialzoo/agents/shipped/$$algo.safetensors && \
		cp runs/shipped/$$algo/run.json socialzoo/agents/shipped/$$algo.run.json || exit 1; \
	done

clean:
	rm -rf $(VENV) results build *.egg-info
