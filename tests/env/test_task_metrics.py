"""Every metric a task's summary reports is in the registry (socialzoo.core.metrics), in the order
of the task's keys, with values of the registered kind."""

import math

import numpy as np

from socialzoo.agents import make_policy
from socialzoo.core.metrics import METRICS, metric, names
from socialzoo.env.config import EnvConfig
from socialzoo.env.crowd_outcome import METRIC_KEYS, CrowdNavMetrics, CrowdRewardConfig, judge_step
from socialzoo.env.metrics import SUMMARY_KEYS
from socialzoo.env.people import COST_KEYS, GROUP_KEYS, PEOPLE_KEYS
from socialzoo.env.tasks.action_selection import ActionSelectionTask
from socialzoo.scenarios.generator import ScenarioConfig
from socialzoo.scenarios.scenario_sets import TestSet

ROOM_SET = TestSet("open_room", 5, 8, ScenarioConfig(min_humans=6, max_humans=8))


def _fits(value, kind, floats_for_flags=False):
    """A value of the registered kind (the CrowdNav task reports flags and counts as floats)."""
    if kind == "bool":
        return isinstance(value, bool) or (floats_for_flags and value in (0.0, 1.0))
    if kind == "int":
        return (isinstance(value, int) and not isinstance(value, bool)) or (
            floats_for_flags and float(value).is_integer()
        )
    return isinstance(value, float)


def test_action_selection_summaries_are_registered():
    config = EnvConfig().replace(
        map="open_room",
        max_steps=60,
        scenario={"min_humans": 6, "max_humans": 8},
        people={"models": "groups", "counterfactual": True},
    )
    task = ActionSelectionTask(config, 2)
    task.reset_rows(np.arange(2), ROOM_SET.scenarios(range(2), task.map))
    policy = make_policy("goalone")
    for _ in range(20):
        task.step(policy.act(task.obs, task))
    summaries = task.episode_metrics([0, 1])
    assert list(summaries[0]) == list(SUMMARY_KEYS) + list(PEOPLE_KEYS)
    assert SUMMARY_KEYS == names("action_selection") and PEOPLE_KEYS == GROUP_KEYS + COST_KEYS
    for summary in summaries:
        for key, value in summary.items():
            assert key in METRICS, f"{key} is not in socialzoo.core.metrics.METRICS"
            assert _fits(value, metric(key).kind), (key, value)


def test_crowdnav_summaries_are_registered():
    cfg = CrowdRewardConfig()
    out = judge_step(
        closest=np.array([-0.1, 0.1, 0.5]),
        goal_distance_after=np.array([1.0, 3.0, 0.2]),
        robot_radius=0.3,
        step_start_time=np.array([1.0, 1.0, 1.0]),
        time_limit=25.0,
        cfg=cfg,
        dt=0.25,
    )
    accumulator = CrowdNavMetrics(3, 0.25, 1.0, cfg)
    accumulator.update(out, moved=np.full(3, 0.25), force=np.full(3, 0.1), blame=np.zeros(3))
    summaries = accumulator.summaries(np.arange(3), out)
    assert METRIC_KEYS == names("crowdnav")
    for summary in summaries:
        assert list(summary) == list(METRIC_KEYS)
        for key, value in summary.items():
            assert _fits(value, metric(key).kind, floats_for_flags=True), (key, value)
    assert math.isnan(summaries[0]["navigation_time"]) and metric("navigation_time").success_only


def test_shared_names_mean_one_thing():
    # Both tasks report these; one entry describes them for both.
    shared = set(SUMMARY_KEYS) & set(METRIC_KEYS)
    assert shared == {"success", "steps", "mean_force", "mean_blame"}
    assert all(set(metric(n).sources) == {"action_selection", "crowdnav"} for n in shared)
