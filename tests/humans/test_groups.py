"""Walking groups: the group forces (Moussaid et al. 2010), the groups a scenario forms, and groups
that walk together in the world."""

import math

import numpy as np

from socialzoo.core.config import GroupConfig, WorldConfig
from socialzoo.env.world import step_world
from socialzoo.humans.group_formation import draw_group_sizes, with_groups
from socialzoo.humans.groups import add_group_accelerations
from socialzoo.maps.map_file import load_map
from socialzoo.scenarios.generator import ScenarioConfig, generate_scenario
from socialzoo.scenarios.scenario import Scenario
from socialzoo.scenarios.start_state import scenarios_to_state


def forces(pos, target, group, cfg=None, vel=None):
    cfg = cfg or GroupConfig()
    pos = np.asarray(pos, float)[None]
    accel = np.zeros_like(pos)
    vel = np.zeros_like(pos) if vel is None else np.asarray(vel, float)[None]
    add_group_accelerations(
        pos,
        vel,
        np.asarray(target, float)[None],
        np.asarray(group)[None],
        np.ones(pos.shape[:2], bool),
        cfg,
        accel,
    )
    return accel[0]


def test_a_straggler_is_pulled_back_and_the_others_are_held():
    # A pair 3 m apart, both walking +x: each is pulled towards the centre, beyond (2 - 1) / 2 m.
    f = forces([[0.0, 0.0], [3.0, 0.0]], [[10.0, 0.0], [10.0, 0.0]], [0, 0], GroupConfig(gaze=0.0))
    soft = 0.5 * (math.tanh(1.5 - 0.5) + 1)
    np.testing.assert_allclose(f, [[3.0 * soft * 1.5, 0.0], [-3.0 * soft * 1.5, 0.0]])


def test_members_too_close_push_apart_and_strangers_feel_nothing():
    cfg = GroupConfig(coherence=0.0, gaze=0.0)
    f = forces([[0.0, 0.0], [0.3, 0.0], [5.0, 5.0]], [[9, 0], [9, 0], [9, 0]], [0, 0, -1], cfg)
    np.testing.assert_allclose(f, [[-0.3, 0.0], [0.3, 0.0], [0.0, 0.0]])


def test_gaze_slows_a_member_whose_friends_fall_behind():
    # The friend is straight behind: 180 degrees from the walking direction, 90 outside the view.
    cfg = GroupConfig(coherence=0.0, repulsion=0.0)
    vel = [[1.2, 0.0], [1.0, 0.0]]
    f = forces([[0.0, 0.0], [-1.0, 0.0]], [[9.0, 0.0], [9.0, 0.0]], [0, 0], cfg, vel)
    np.testing.assert_allclose(f[0], [-4.0 * math.pi / 2 * 1.2, 0.0], atol=1e-12)
    np.testing.assert_allclose(f[1], [0.0, 0.0], atol=1e-12)  # the friend ahead is in view


def test_scenarios_form_groups_the_same_way_every_time():
    m = load_map("gdc1")
    scenario = generate_scenario(m, 5, ScenarioConfig(min_humans=12, max_humans=12))
    members = np.arange(scenario.num_humans) < 9
    grouped = with_groups(scenario, m, members, (0.6, 0.3, 0.1))
    assert grouped == with_groups(scenario, m, members, (0.6, 0.3, 0.1))
    group = grouped.human_group
    assert (group[~members] == -1).all()
    for leader in np.unique(group[group >= 0]):
        people = np.flatnonzero(group == leader)
        assert 2 <= len(people) <= 4 and people[0] == leader
        assert all(np.array_equal(grouped.human_routes[k], grouped.human_routes[leader]) for k in people)
        assert len(set(grouped.human_speed[people])) == 1
        assert np.linalg.norm(grouped.human_spawn[people] - grouped.human_spawn[leader], axis=1).max() < 2.5
    assert Scenario.from_json(grouped.to_json()) == grouped
    assert "human_group" not in scenario.to_json()
    assert with_groups(scenario, m, np.zeros(scenario.num_humans, bool), (1, 0, 0)) is scenario
    assert sum(draw_group_sizes(9, (0.6, 0.3, 0.1), np.random.default_rng(0))) == 9


def test_groups_walk_together_in_the_world():
    m = load_map("gdc1")
    scenario = generate_scenario(m, 5, ScenarioConfig(min_humans=12, max_humans=12))
    members = np.ones(scenario.num_humans, bool)
    grouped = with_groups(scenario, m, members, (1.0, 0.0, 0.0))
    state = scenarios_to_state([grouped])
    loose = scenarios_to_state([grouped])
    loose.human_group[:] = -1
    world = WorldConfig()
    cmd = np.zeros((1, 1, 2))
    spread, loose_spread = [], []
    for _ in range(800):
        state, _ = step_world(state, m.wall_index, world, cmd)
        loose, _ = step_world(loose, m.wall_index, world, cmd)
        for s, out in ((state, spread), (loose, loose_spread)):
            pairs = [np.linalg.norm(s.human_pos[0, k] - s.human_pos[0, k + 1]) for k in range(0, 12, 2)]
            out.append(np.mean(pairs))
    assert np.mean(spread[200:]) < 1.5
    assert np.mean(spread[200:]) < np.mean(loose_spread[200:])
