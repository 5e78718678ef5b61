# Every target sets up .venv on first use: torch==2.13.0 (the CPU build) first, then the package.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

CHROMIUM := /usr/bin/chromium
# apt-get needs root: sudo when make runs as another user.
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: run test lint bench venv clean clean-kernels chromium policies docs

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

# Retrain every shipped action-selection policy with the recorded commands and seeds (needed after an
# env version bump: policy files trained on another version of the benchmark env are refused). Training
# scenarios only: PPO/DQN train on the gdc1 training stream, BC/GAIL/DAgger/PIPS on Ref demonstrations
# recorded on it. The shipped DQN normalises observations (chosen on validation scenarios; the paper's
# did not). The other shipped files (crowdnav, suite_crowdnav, humans) are not retrained here: each
# NAME.run.json records its own command. About 17 minutes on 2 idle cores (PPO 94 s, DQN 293 s,
# demos ~3 min, BC 47 s, GAIL 98 s, DAgger 4.5 min, PIPS 17 s).
SHIP := runs/shipped
policies: $(STAMP)
	$(VENV)/bin/socialzoo train ppo --out $(SHIP)/ppo --seed 0 --no-progress
	$(VENV)/bin/socialzoo train dqn --out $(SHIP)/dqn --seed 0 --normalize --no-progress
	$(VENV)/bin/socialzoo demos --episodes 125 --out $(SHIP)/ref_demos.npz --no-progress
	$(VENV)/bin/socialzoo train bc --demos $(SHIP)/ref_demos.npz --steps 155400 --seed 0 --out $(SHIP)/bc --no-progress
	$(VENV)/bin/socialzoo train gail --demos $(SHIP)/ref_demos.npz --steps 155400 --seed 0 --out $(SHIP)/gail --no-progress
	$(VENV)/bin/socialzoo train dagger --demos $(SHIP)/ref_demos.npz --seed 0 --out $(SHIP)/dagger --no-progress
	mkdir -p $(SHIP)/pips
	$(VENV)/bin/socialzoo train pips --demos $(SHIP)/ref_demos.npz --out $(SHIP)/pips/pips.json
	for algo in ppo dqn bc gail dagger; do \
		cp $(SHIP)/$$algo/$$algo.safetensors socialzoo/agents/shipped/$$algo.safetensors && \
		cp $(SHIP)/$$algo/run.json socialzoo/agents/shipped/$$algo.run.json || exit 1; \
	done
	cp $(SHIP)/pips/pips.json $(SHIP)/pips/pips.train.json socialzoo/agents/shipped/

clean: clean-kernels
	rm -rf $(VENV) results build site *.egg-info

# numba's cached kernels (DEVELOPERS.md, Compiled kernels: a cache does not see a change in another file).
clean-kernels:
	find socialzoo -name '*.nbi' -delete -o -name '*.nbc' -delete
