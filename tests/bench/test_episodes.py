"""The evaluation loop of every task (socialzoo.bench.episodes.play_cases) and the fixed-case reset
option every task reads ({"split": name, "cases": [...]})."""

from __future__ import annotations

import numpy as np
import pytest

from socialzoo.agents import make_policy
from socialzoo.bench.episodes import play_cases
from socialzoo.env.tasks import make_task

TOY = "toy_task:ToyReachTask"


def forward(obs: np.ndarray, core: object) -> np.ndarray:
    return np.zeros(len(obs), dtype=np.int64)


def test_a_batch_plays_the_same_episodes_as_one_row_at_a_time():
    batched = play_cases(TOY, forward, "test", [4, 0, 7, 2], batch_size=3, max_steps=60)
    alone = [play_cases(TOY, forward, "test", [k], batch_size=1, max_steps=60)[0] for k in (4, 0, 7, 2)]
    assert [e["case"] for e in batched] == [4, 0, 7, 2]
    np.testing.assert_equal(batched, alone)  # NaN (time to goal of a failure) equals NaN
    assert {"success", "steps", "seed"} <= set(batched[0])


def test_the_loop_serves_the_action_selection_and_crowdnav_tasks():
    ref = make_policy("ref")
    episodes = play_cases("action_selection", ref.act, "gdc1-quick", [0, 1], batch_size=2, max_steps=80)
    from socialzoo.scenarios.scenario_sets import get_test_set

    assert [e["seed"] for e in episodes] == [get_test_set("gdc1-quick").seed(k) for k in (0, 1)]
    orca = make_policy("orca", task="crowdnav")
    crowd = play_cases("crowdnav", orca.act, "val", [3], batch_size=1)
    assert crowd[0]["case"] == 3 and "success" in crowd[0]


def test_fixed_case_options_are_checked_naming_the_split_and_the_cases():
    task = make_task(TOY, 2)
    with pytest.raises(ValueError, match=r"split must be one of \['test'\]"):
        task.reset(np.arange(2), {"split": "val", "cases": [0, 1]})
    with pytest.raises(ValueError, match=r"holds 20 cases; got \[20\]"):
        task.reset(np.arange(2), {"split": "test", "cases": [0, 20]})
    with pytest.raises(ValueError, match="2 rows to reset but 1 cases"):
        task.reset(np.arange(2), {"split": "test", "cases": [0]})
    # Whole indices only: 1.5 and True were truncated to cases 1, None and "x" were numpy's errors.
    for cases in ([0, 1.5], [True, 0], [None, 0], ["x", 0]):
        with pytest.raises(ValueError, match="must be whole case indices"):
            task.reset(np.arange(2), {"split": "test", "cases": cases})
    with pytest.raises(ValueError, match=r"holds 20 cases; got \[0, 10{30}\]"):
        task.reset(np.arange(2), {"split": "test", "cases": [0, 10**30]})
    task.reset(np.arange(2), {"split": "test", "cases": np.array([3, 4])})
    with pytest.raises(ValueError, match="twice"):
        play_cases(TOY, forward, "test", [1, 1])
