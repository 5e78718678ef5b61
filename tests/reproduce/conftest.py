"""One `socialzoo reproduce --quick` run shared by the reproduction tests (about 1.5 min on 2 cores),
and tiny settings for the tests that interrupt and resume a part."""

import pytest

from socialzoo.reproduce.plan import quick_settings


@pytest.fixture(scope="session")
def quick_run(tmp_path_factory):
    """DIR of a `socialzoo reproduce --quick --no-progress` run (through the command line)."""
    pytest.importorskip("torch")
    pytest.importorskip("torchrl")
    pytest.importorskip("z3")
    from socialzoo.cli import main

    out = tmp_path_factory.mktemp("quick")
    assert main(["reproduce", "--out", str(out), "--quick", "--no-progress"]) == 0
    return out


@pytest.fixture
def tiny_settings():
    """A function (**changes) -> settings smaller than --quick: one checkpoint per RL run, short
    evaluation episodes, one env row per evaluation batch (each trial stored on its own)."""
    return _tiny


def _tiny(**changes):
    base = {
        "rl_total_steps": 200,
        "rl_checkpoint_every": 200,
        "curve_trials": 2,
        "demo_episodes": 1,
        "demo_env_overrides": {"max_steps": 100},
        "eval_env_overrides": {"max_steps": 150},
        "batch_size": 1,
    }
    base.update(changes)
    return quick_settings(**base)
