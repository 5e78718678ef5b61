"""Scenario streams: one per env, built from its config, the same episodes whatever the batch."""

from __future__ import annotations

from socialzoo.env.config import EnvConfig
from socialzoo.env.scenario_source import ScenarioStream
from socialzoo.nav.maps import load_map


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
