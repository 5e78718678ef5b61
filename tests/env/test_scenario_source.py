"""Scenario streams: one per env, built from its config, the same episodes whatever the batch."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from socialzoo.env.config import EnvConfig
from socialzoo.env.scenario_source import ScenarioStream
from socialzoo.maps.map_file import load_map
from socialzoo.scenarios.catalogue import FAMILIES, register_family
from socialzoo.scenarios.families import Layout, LayoutFamily


def test_for_config_follows_robots_family_and_scenario_settings():
    m = load_map("hallway")
    cfg = EnvConfig(map="hallway", num_robots=2).replace(scenario={"min_humans": 2, "max_humans": 3})
    stream = ScenarioStream.for_config(m, 3, cfg)
    stream.seed(7)
    scenarios = stream.next([0, 1, 2])
    assert all(s.num_robots == 2 and s.family == "benchmark" for s in scenarios)
    assert all(2 <= s.num_humans <= 3 for s in scenarios)
    family = ScenarioStream.for_config(m, 1, cfg.replace(family="overtaking", num_robots=1))
    family.seed(7)
    (s,) = family.next([0])
    assert s.family == "overtaking" and s.num_robots == 1


def test_row_zero_matches_a_single_stream():
    m = load_map("hallway")
    cfg = EnvConfig(map="hallway")
    batch, single = ScenarioStream.for_config(m, 4, cfg), ScenarioStream.for_config(m, 1, cfg)
    batch.seed(3)
    single.seed(3)
    for _ in range(3):
        assert batch.next([0])[0].seed == single.next([0])[0].seed


class TinyFamily(LayoutFamily):
    """A new family is one class: the robot walks the hallway, one person stands in its way."""

    name = "test_tiny"
    map_name = "hallway"
    description = "one person walks slowly towards the robot"

    def layout(self, m, rng):
        poses = np.asarray(m.legal_poses)[:, :2]
        a, b = poses[0], poses[-1]
        mid = (a + b) / 2 + rng.uniform(-0.2, 0.2, size=2)
        return Layout(a, b, mid[None], a[None], np.array([0.3]))


@pytest.fixture
def tiny():
    family = register_family(TinyFamily)  # the one registration line
    yield family
    del FAMILIES[family.name]


def test_a_new_family_is_one_class_and_one_registration_line(tiny):
    env = gym.make("socialzoo/ActionSelection-v2", map="hallway", family="test_tiny")
    env.reset(seed=4)
    state = env.unwrapped.core.state
    stream = ScenarioStream.for_config(load_map("hallway"), 2, EnvConfig(map="hallway", family="test_tiny"))
    stream.seed(4)
    (s,) = stream.next([0])  # row 0 of a stream seeded 4: the env's first episode
    assert s.family == "test_tiny" and s.num_humans == 1
    np.testing.assert_array_equal(state.robot_pose[0, 0, :2], s.robot_starts[0, :2])
    np.testing.assert_array_equal(state.human_pos[0, :1], s.human_spawn)
    for _ in range(5):
        env.step(env.action_space.sample())
    env.close()
