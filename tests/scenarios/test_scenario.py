"""Scenario generation: determinism, invariants, JSON replay, test sets, families, WorldState."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import pickle
from pathlib import Path

import numpy as np
import pytest

from socialzoo.core.config import WorldConfig
from socialzoo.core.state import WorldState, pad_to
from socialzoo.env.world import step_world
from socialzoo.maps import map_file as maps
from socialzoo.maps.map_file import Map
from socialzoo.maps.segments import segments_free
from socialzoo.scenarios.catalogue import FAMILIES, get_family
from socialzoo.scenarios.families import LayoutFamily
from socialzoo.scenarios.generator import ScenarioConfig, generate_scenario
from socialzoo.scenarios.scenario import Scenario, ScenarioError
from socialzoo.scenarios.scenario_sets import TEST_SETS, TestSet, get_test_set
from socialzoo.scenarios.start_state import _NOISE_STREAM, StartStore, scenarios_to_state, write_scenarios


def gdc1() -> Map:
    return maps.load_map("gdc1")


def box(x0: float, y0: float, x1: float, y1: float) -> list[list[float]]:
    return [[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]]


def synthetic(name: str) -> Map:
    """Tiny hand-built maps for edge cases (the two-pose hallway, ...)."""
    if name == "hallway":
        return Map(
            name=name,
            walls=np.array(box(0, 0, 20, 3)),
            nodes=np.array([[1, 1.5], [10, 1.5], [19, 1.5]]),
            edges=np.array([[0, 1], [1, 2]]),
            legal_poses=np.array([[1, 1.5, 0], [19, 1.5, np.pi]]),
        )
    if name == "open_room":
        g = np.array([[x, y] for x in (2.0, 5.0, 8.0) for y in (2.0, 5.0, 8.0)])
        return Map(
            name=name,
            walls=np.array(box(0, 0, 10, 10)),
            nodes=g,
            edges=np.array(
                [
                    [0, 1],
                    [1, 2],
                    [3, 4],
                    [4, 5],
                    [6, 7],
                    [7, 8],
                    [0, 3],
                    [3, 6],
                    [1, 4],
                    [4, 7],
                    [2, 5],
                    [5, 8],
                ]
            ),
            legal_poses=np.array([[1, 1, 0], [9, 9, 0], [1, 9, 0], [9, 1, 0]]),
        )
    if name == "intersection":
        walls = []
        for sx, sy in ((1, 1), (1, -1), (-1, 1), (-1, -1)):  # an L per quadrant: corridors 3 m wide
            walls += [[1.5 * sx, 1.5 * sy, 10 * sx, 1.5 * sy], [1.5 * sx, 1.5 * sy, 1.5 * sx, 10 * sy]]
        walls += [[-10, -1.5, -10, 1.5], [10, -1.5, 10, 1.5], [-1.5, -10, 1.5, -10], [-1.5, 10, 1.5, 10]]
        return Map(
            name=name,
            walls=np.array(walls, dtype=float),
            nodes=np.array([[0, 0], [-9, 0], [9, 0], [0, -9], [0, 9]], dtype=float),
            edges=np.array([[0, 1], [0, 2], [0, 3], [0, 4]]),
            legal_poses=np.array([[-9, 0, 0], [9, 0, np.pi], [0, -8.5, 1.57], [0, 8.5, -1.57]]),
        )
    if name == "doorway":
        walls = [*box(0, 0, 16, 6), [8, 0, 8, 2.4], [8, 3.6, 8, 6]]
        return Map(
            name=name,
            walls=np.array(walls, dtype=float),
            nodes=np.array([[4, 3], [8, 3], [12, 3]]),
            edges=np.array([[0, 1], [1, 2]]),
            legal_poses=np.array([[1.5, 3, 0], [14.5, 3, np.pi], [4, 1.5, 0], [12, 4.5, 0]]),
        )
    raise KeyError(name)


def small_map(name: str) -> Map:
    return maps.load_map(name)


def check_scenario_geometry(m: Map, s: Scenario) -> None:
    """Routes wall-free from the human's start to its goal, spawns on the free side of walls."""
    for k, route in enumerate(s.human_routes):
        assert not m.wall_index.crosses(route[:-1], route[1:]).any(), k
    first = np.array([r[min(1, len(r) - 1)] for r in s.human_routes]).reshape(-1, 2)
    starts = np.array([r[0] for r in s.human_routes]).reshape(-1, 2)
    assert segments_free(m.wall_index, s.human_spawn, first).all()
    assert segments_free(m.wall_index, s.human_spawn, starts).all()


# ---------------------------------------------------------------------------- benchmark generator
def test_same_seed_same_scenario_and_different_seeds_differ() -> None:
    m = gdc1()
    a, b = generate_scenario(m, 123), generate_scenario(m, 123)
    assert a == b
    assert a is not b
    others = [generate_scenario(m, s) for s in range(124, 134)]
    assert all(o != a for o in others)
    assert len({o.human_spawn.tobytes() for o in others}) == len(others)


def test_with_seed_is_a_shallow_copy_under_another_seed() -> None:
    """Scenario.with_seed, which a family that keeps its scenarios calls on every reset, makes what
    copy.copy and a new seed make: the same fields, the same (read-only) arrays, the kept one as it was."""
    import copy

    kept = generate_scenario(gdc1(), 7)
    renamed, reference = kept.with_seed(2**40), copy.copy(kept)
    object.__setattr__(reference, "seed", 2**40)
    assert type(renamed) is Scenario and renamed.seed == 2**40 and kept.seed == 7
    assert vars(renamed).keys() == vars(reference).keys()
    assert all(vars(renamed)[k] is vars(reference)[k] for k in vars(kept) if k != "seed")
    assert renamed == reference and renamed != kept


def test_benchmark_scenarios_follow_the_spec() -> None:
    m = gdc1()
    cfg = ScenarioConfig()
    poses = m.legal_poses
    counts = []
    for seed in range(150):
        s = generate_scenario(m, seed, cfg)
        assert s.map_name == m.name and s.seed == seed and s.family == "benchmark" and s.num_robots == 1
        robot_start = int(np.flatnonzero((poses == s.robot_start).all(1))[0])
        assert not np.array_equal(s.robot_start, s.robot_goal)
        assert cfg.min_humans <= s.num_humans <= cfg.max_humans
        counts.append(s.num_humans)
        assert np.all(s.human_start_index != robot_start)
        assert np.all(s.human_goal_index != s.human_start_index)
        assert np.all((s.human_speed >= cfg.min_speed) & (s.human_speed <= cfg.max_speed))
        start = poses[s.human_start_index, :2]
        goal = poses[s.human_goal_index, :2]
        np.testing.assert_array_equal([r[0] for r in s.human_routes], start)
        np.testing.assert_array_equal([r[-1] for r in s.human_routes], goal)
        assert np.all(np.abs(s.human_spawn - start) <= cfg.spawn_jitter)
        _, dist = m.wall_index.nearest(s.human_spawn)
        on_pose = (s.human_spawn == start).all(1)
        assert np.all(on_pose | (dist >= cfg.spawn_clearance))
        check_scenario_geometry(m, s)
    assert min(counts) == 5 and max(counts) == 25


def test_config_bounds_are_respected() -> None:
    cfg = ScenarioConfig(min_humans=3, max_humans=3, spawn_jitter=0.0, speed_std=0.0, speed_mean=2.0)
    s = generate_scenario(gdc1(), 5, cfg)
    assert s.num_humans == 3
    np.testing.assert_array_equal(s.human_spawn, gdc1().legal_poses[s.human_start_index, :2])
    np.testing.assert_array_equal(s.human_speed, [1.3, 1.3, 1.3])


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"min_humans": 6, "max_humans": 2}, r"min_humans \(6\) exceeds max_humans \(2\)"),
        ({"max_humans": -1}, r"max_humans must be an int >= 0, got -1"),
        ({"min_humans": 2.5}, r"min_humans must be an int >= 0, got 2.5"),
        ({"repeats": 0}, r"repeats must be an int >= 1, got 0"),
        ({"spawn_jitter": -0.1}, r"spawn_jitter must be >= 0, got -0.1"),
        ({"speed_mean": float("nan")}, r"speed_mean must be a finite number, got nan"),
        ({"min_speed": 0.0}, r"min_speed must be > 0, got 0.0"),
        ({"min_speed": 1.5}, r"min_speed \(1.5\) exceeds max_speed \(1.3\)"),
        ({"spawn_tries": True}, r"spawn_tries must be an int >= 1, got True"),
    ],
)
def test_bad_config_raises_naming_field_and_value(kwargs: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=r"ScenarioConfig\." + message):
        ScenarioConfig(**kwargs)  # type: ignore[arg-type]


def test_maps_without_enough_poses_raise() -> None:
    m = gdc1()
    one = dataclasses.replace(m, legal_poses=m.legal_poses[:1])
    with pytest.raises(ValueError, match="at least 2 legal poses, the map has 1"):
        generate_scenario(one, 0)
    empty = Map(
        name="empty",
        walls=np.zeros((0, 4)),
        nodes=np.zeros((0, 2)),
        edges=np.zeros((0, 2), int),
        legal_poses=np.zeros((0, 3)),
    )
    with pytest.raises(ValueError, match="the map has 0"):
        generate_scenario(empty, 0)
    with pytest.raises(ValueError, match="the map has 1"):
        make_family_scenario("hallway_head_on", one, 0)


def test_unreachable_poses_are_never_drawn_and_no_feasible_pair_raises() -> None:
    # A third pose shut in a box: its routes do not exist, so nobody starts or ends there.
    hallway = synthetic("hallway")
    walls = np.concatenate((hallway.walls, box(30, 0, 32, 2)))
    poses = np.concatenate((hallway.legal_poses, [[31.0, 1.0, 0.0]]))
    m = dataclasses.replace(hallway, walls=walls, legal_poses=poses)
    for seed in range(20):
        s = generate_scenario(m, seed, ScenarioConfig(min_humans=10, max_humans=10))
        assert s.robot_start[0] < 30 and s.robot_goal[0] < 30
        assert (s.human_start_index != 2).all() and (s.human_goal_index != 2).all()
    with pytest.raises(ValueError, match=r"map 'hallway': no two legal poses .* at most 10 m"):
        generate_scenario(m, 0, ScenarioConfig(max_route_length=10.0))


def test_feasibility_rule_redraws_only_long_routes() -> None:
    # Four poses along a 60 m corridor: with a 25 m limit only neighbours (20 m apart) are feasible.
    walls = np.array(box(0, 0, 61, 3), dtype=float)
    xs = np.array([0.5, 20.5, 40.5, 60.5])
    m = Map(
        name="corridor",
        walls=walls,
        nodes=np.column_stack((xs, np.full(4, 1.5))),
        edges=np.array([[0, 1], [1, 2], [2, 3]]),
        legal_poses=np.column_stack((xs, np.full(4, 1.5), np.zeros(4))),
    )
    cfg = ScenarioConfig(max_route_length=25.0)
    for seed in range(30):
        s = generate_scenario(m, seed, cfg)
        assert abs(s.robot_goal[0] - s.robot_start[0]) == 20.0
        lengths = [np.linalg.norm(np.diff(r, axis=0), axis=1).sum() for r in s.human_routes]
        assert max(lengths) <= 25.0
        assert generate_scenario(m, seed, cfg) == s
    # Without the limit the same seeds draw far pairs too.
    far = [generate_scenario(m, seed) for seed in range(30)]
    assert any(abs(s.robot_goal[0] - s.robot_start[0]) > 20.0 for s in far)


def test_humans_may_share_poses_on_a_two_pose_map() -> None:
    s = generate_scenario(synthetic("hallway"), 3, ScenarioConfig(min_humans=6, max_humans=6))
    robot_start = int(np.flatnonzero((synthetic("hallway").legal_poses == s.robot_start).all(1))[0])
    np.testing.assert_array_equal(s.human_start_index, [1 - robot_start] * 6)
    np.testing.assert_array_equal(s.human_goal_index, [robot_start] * 6)


# ---------------------------------------------------------------------------- JSON replay
def test_json_round_trip_is_bit_exact(tmp_path: Path) -> None:
    for seed in (0, 1, 2**63 + 5):
        s = generate_scenario(gdc1(), seed)
        back = Scenario.load(s.save(tmp_path / f"s{seed}.json"))
        assert back == s
        for name in ("robot_starts", "robot_goals", "human_spawn", "human_speed"):
            assert getattr(back, name).tobytes() == getattr(s, name).tobytes()
        assert all(a.tobytes() == b.tobytes() for a, b in zip(back.human_routes, s.human_routes, strict=True))
        assert back.seed == seed
    with pytest.raises(ValueError, match="scenario format must be"):
        Scenario.from_json({"format": "other"})
    data = s.to_json()
    del data["human_speed"]
    with pytest.raises(ValueError, match="lacks key 'human_speed'"):
        Scenario.from_json(data)


def test_scenario_arrays_are_read_only_and_validated() -> None:
    s = generate_scenario(gdc1(), 0)
    with pytest.raises(ValueError):
        s.human_spawn[0, 0] = 1.0
    with pytest.raises(ValueError, match=r"robot_goals must have shape \(1, 3\)"):
        dataclasses.replace(s, robot_goals=np.zeros((2, 3)))
    with pytest.raises(ValueError, match="human_routes holds"):
        dataclasses.replace(s, human_routes=s.human_routes[:-1])


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("human_speed", -1.2, r"Scenario.human_speed\[0\] must be >= 0, got -1.2"),
        ("human_speed", 10**400, "Scenario.human_speed holds a number beyond the range of float64"),
        ("human_goal_index", -7, r"Scenario.human_goal_index\[0\] must be >= -1, got -7"),
        ("seed", -5, r"Scenario.seed must be an int in \[0, 2\*\*64\), got -5"),
        ("seed", 1.7, r"Scenario.seed must be an int in \[0, 2\*\*64\), got 1.7"),
        ("seed", 2**64, r"Scenario.seed must be an int in \[0, 2\*\*64\), got 18446744073709551616"),
        ("map_name", 5, "Scenario.map_name must be a string, got 5"),
    ],
)
def test_a_scenario_file_of_impossible_values_is_refused_naming_the_file_and_field(
    tmp_path: Path, key: str, value: object, message: str
) -> None:
    # Each of these loaded and ran: people walking backwards (a negative speed), a seed truncated
    # (1.7 read as 1) or refused only at reset without the file's name (-5, 2**64).
    data = generate_scenario(gdc1(), 0).to_json()
    data[key] = [value] * len(data[key]) if isinstance(data[key], list) else value
    path = tmp_path / "s.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ScenarioError, match=f"s.json: {message}"):
        Scenario.load(path)


# ---------------------------------------------------------------------------- test sets
def test_test_set_scenarios_are_the_same_alone_or_in_a_list() -> None:
    ts = TestSet("gdc1", 77, 12)
    many = ts.scenarios(m=gdc1())
    assert len(many) == 12
    for k in (0, 5, 11):
        assert ts.scenario(k, m=gdc1()) == many[k]
    assert ts.scenarios([11, 5], m=gdc1()) == [many[11], many[5]]
    assert len({s.seed for s in many}) == 12
    assert ts.seed(3) == int(np.random.SeedSequence([77, 3]).generate_state(1, dtype=np.uint64)[0])
    with pytest.raises(IndexError, match=r"scenario 12 is outside 0\.\.11"):
        ts.seed(12)
    with pytest.raises(ValueError, match="is on map 'gdc1', got map 'hallway'"):
        ts.scenario(0, m=synthetic("hallway"))


def test_named_test_sets() -> None:
    assert {name: (t.map_name, t.count) for name, t in TEST_SETS.items()} == {
        "gdc1-test": ("gdc1", 2000),
        "ghc3-test": ("ghc3", 2000),
        "gdc1-quick": ("gdc1", 100),
        "ghc3-quick": ("ghc3", 100),
    }
    assert get_test_set("gdc1-quick").name == "gdc1-quick"
    assert len({t.base_seed for t in TEST_SETS.values()}) == 4
    # Seeds are pinned: changing them changes every published benchmark number.
    assert get_test_set("gdc1-test").seed(0) == int(
        np.random.SeedSequence([20220001, 0]).generate_state(1, dtype=np.uint64)[0]
    )
    with pytest.raises(KeyError, match="unknown test set 'gdc1'"):
        get_test_set("gdc1")
    s = get_test_set("gdc1-quick").scenario(4, m=gdc1())
    check_scenario_geometry(gdc1(), s)


def test_maps_of_one_name_never_share_a_case_set(tmp_path: Path) -> None:
    """An imported map's sets are keyed by its contents: two files of one name, or an edited copy still
    named "gdc1", each have their own val and test sets, and a set's scenarios are its own map's. Keyed
    by the name field, the edited copy's "gdc1-test" and "gdc1-val" were sets on map "gdc1": without a
    map given, they generated the shipped gdc1's scenarios."""
    from socialzoo.scenarios.scenario_sets import CUSTOM_TEST_SEED, map_case_sets, validation_set

    data = gdc1().to_json()
    data["legal_poses"] = data["legal_poses"][::-1]
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    edited = tmp_path / "a" / "floor.json"
    edited.write_text(json.dumps(data))  # still named "gdc1"
    data["walls"] = data["walls"][:-1]
    other = tmp_path / "b" / "floor.json"
    other.write_text(json.dumps(data))
    a, b = (map_case_sets(maps.load_map(str(p))) for p in (edited, other))
    for split in ("val", "test"):
        assert a[split] != b[split] and a[split].name != b[split].name
    assert a["test"].base_seed == CUSTOM_TEST_SEED and a["test"].name.startswith("gdc1-")
    assert a["val"] != validation_set("gdc1") and a["test"].name != "gdc1-test"
    own = a["test"].scenario(0, maps.load_map(str(edited)))
    assert a["test"].scenario(0).to_json() == own.to_json()
    assert map_case_sets(str(edited)) == a  # a reference or its Map: the same sets
    assert map_case_sets(gdc1())["test"] is TEST_SETS["gdc1-test"]


# sha256 of the scenarios' JSON (sort_keys) in index order, computed from the code before the
# feasibility rule existed (commit cb9a195): the benchmark's test sets must never move. The full
# sets (2000 each) are checked every 20th scenario; the quick sets in full.
FROZEN_TEST_SETS = {
    ("gdc1-test", 20): "57599f8d17918399ad84ec618add5d9d1b6e7787ce784f7e458519a83956a4b3",
    ("ghc3-test", 20): "ac5d506f4e905cfa6a4a1ab10b2232b88ffb40c80cb8a85a16d319072d899a80",
    ("gdc1-quick", 1): "971076376d0ec3d97de25ee304348ff7ed3e9ba17f31f1918c84b4c10c96a16e",
    ("ghc3-quick", 1): "a92e65694a45a28d7b20de284b5f46e23d734230bd5727d9cd9e36c6e2e12740",
}


@pytest.mark.parametrize(("name", "stride"), list(FROZEN_TEST_SETS))
def test_benchmark_test_sets_are_bit_identical_to_the_published_ones(name: str, stride: int) -> None:
    ts = get_test_set(name)
    digest = hashlib.sha256()
    for k in range(0, len(ts), stride):
        digest.update(json.dumps(ts.scenario(k).to_json(), sort_keys=True).encode())
    assert digest.hexdigest() == FROZEN_TEST_SETS[(name, stride)]


# ---------------------------------------------------------------------------- WorldState
def test_scenarios_to_state_shapes_masks_and_padding() -> None:
    m = gdc1()
    scenarios = [generate_scenario(m, seed) for seed in range(6)]
    state = scenarios_to_state(scenarios)
    b, h = 6, max(s.num_humans for s in scenarios)
    width = max(len(r) for s in scenarios for r in s.human_routes)
    assert state.robot_pose.shape == (b, 1, 3) and state.robot_goal.shape == (b, 1, 3)
    assert state.human_pos.shape == (b, h, 2) and state.human_route.shape == (b, h, width, 2)
    np.testing.assert_array_equal(state.robot_vel, 0.0)
    np.testing.assert_array_equal(state.human_vel, 0.0)
    np.testing.assert_array_equal(state.step_count, 0)
    np.testing.assert_array_equal(state.human_direction, 1)
    key = np.random.SeedSequence([2, _NOISE_STREAM]).generate_state(1, np.uint64)[0]
    assert state.noise_key.dtype == np.uint64 and state.noise_key[2] == key
    for row, s in enumerate(scenarios):
        n = s.num_humans
        np.testing.assert_array_equal(state.robot_pose[row, 0], s.robot_start)
        np.testing.assert_array_equal(state.robot_goal[row, 0], s.robot_goal)
        assert state.human_mask[row].tolist() == [True] * n + [False] * (h - n)
        np.testing.assert_array_equal(state.human_pos[row, :n], s.human_spawn)
        np.testing.assert_array_equal(state.human_pref_speed[row, :n], s.human_speed)
        for k, route in enumerate(s.human_routes):
            assert state.human_route_len[row, k] == len(route)
            np.testing.assert_array_equal(state.human_route[row, k, : len(route)], route)
            np.testing.assert_array_equal(
                state.human_route[row, k, len(route) :], route[-1][None].repeat(width - len(route), 0)
            )
            assert state.human_waypoint[row, k] == (1 if len(route) > 1 else 0)
        assert np.all(state.human_route_len[row, n:] == 1) and np.all(state.human_waypoint[row, n:] == 0)
    # The state steps, and a row of the batch is the batch of one.
    cfg = WorldConfig()
    new, _ = step_world(state, m.wall_index, cfg, np.zeros((b, 1, 2)))
    alone, _ = step_world(
        scenarios_to_state(scenarios[3:4], max_humans=h), m.wall_index, cfg, np.zeros((1, 1, 2))
    )
    np.testing.assert_array_equal(new.human_pos[3], alone.human_pos[0])
    # A wider route axis asked for is the same state padded by repeating each route's last point.
    wide = scenarios_to_state(scenarios, route_width=width + 3)
    assert wide.human_route.shape == (b, h, width + 3, 2)
    np.testing.assert_array_equal(
        wide.human_route, pad_to(state.human_route, (h, width + 3, 2), "human_route")
    )
    assert scenarios_to_state(scenarios, route_width=2).human_route.shape == state.human_route.shape


def test_write_scenarios_in_place_is_scenarios_to_state() -> None:
    """Rows written into a used state, its slots, route axis and the other rows as they were, hold
    exactly what scenarios_to_state makes of the same scenarios; a longer route widens every row."""
    m = gdc1()
    scenarios = [generate_scenario(m, seed) for seed in range(8)]
    h = max(s.num_humans for s in scenarios) + 2
    state = scenarios_to_state(scenarios[:4], max_humans=h)
    state.human_pos += 1.0  # a stepped state: what the rows held must not show through
    state.human_vel[:] = 0.5
    state.human_waypoint[:] = 3
    state.step_count[:] = 7
    kept = state.rows(np.array([0, 2]))
    rows = np.array([3, 1])
    longest = [max(len(r) for r in s.human_routes) for s in scenarios]
    assert longest[4] > max(longest[:4])  # seed 4's longest route widens the state
    written = [scenarios[4], scenarios[6]]
    write_scenarios(state, rows, written)
    width = state.human_route.shape[2]
    assert width == longest[4]
    fresh = scenarios_to_state(written, max_humans=h, route_width=width)
    kept.human_route = pad_to(kept.human_route, (h, width, 2), "human_route")  # the last point repeated
    for f in dataclasses.fields(state):
        np.testing.assert_array_equal(getattr(state, f.name)[rows], getattr(fresh, f.name), err_msg=f.name)
        np.testing.assert_array_equal(getattr(state, f.name)[[0, 2]], getattr(kept, f.name), err_msg=f.name)
    with pytest.raises(IndexError, match="a row outside the batch"):
        write_scenarios(state, np.array([4]), scenarios[:1])
    fewest = min(scenarios, key=lambda s: s.num_humans)
    with pytest.raises(ValueError, match=f"more than max_humans={fewest.num_humans}"):
        write_scenarios(
            scenarios_to_state([fewest]), np.array([0]), [max(scenarios, key=lambda s: s.num_humans)]
        )


def test_start_store_writes_as_write_scenarios() -> None:
    """A StartStore writes rows exactly as write_scenarios does: scenarios met once (written as
    write_scenarios writes them), then stored and written from the store (renamed copies under new
    seeds, as a family that keeps its scenarios resets from: draws 2 and 6 are all stored), a new
    scenario among stored ones; nothing of another scenario or of a row written before shows through."""
    m = gdc1()
    kept = [generate_scenario(m, seed) for seed in range(6)]
    h = max(s.num_humans for s in kept) + 1
    store = StartStore(1, h)
    state = scenarios_to_state(kept[:1], max_humans=h)
    state = WorldState.concatenate([state] * 4)
    reference = state.rows(np.arange(4))
    draws = [[0, 1, 2], [1, 0, 2], [2, 1, 0], [3, 4, 1], [4, 3, 5], [5, 0, 4], [1, 5, 3]]
    for k, picks in enumerate(draws):
        rows = np.array([3, 0, 2]) if k % 2 else np.array([1, 2, 3])
        scenarios = [kept[i].with_seed(1000 * k + i) for i in picks]
        if k == 5:
            scenarios[1] = generate_scenario(m, 99)  # never met again: written, noted, not stored
        store.write(state, rows, scenarios)
        write_scenarios(reference, rows, scenarios)
        for f in dataclasses.fields(state):
            np.testing.assert_array_equal(getattr(state, f.name), getattr(reference, f.name), err_msg=f.name)
    assert len(store._held) == 6  # every kept scenario stored once, the one-off not
    # A copy (pickled, as a vector env's worker gets it) writes from its own store alike.
    copied_kept, copied = pickle.loads(pickle.dumps((kept, store)))
    again = [copied_kept[i].with_seed(7 + i) for i in (4, 2, 0)]
    copied.write(state, np.array([0, 1, 2]), again)
    write_scenarios(reference, np.array([0, 1, 2]), again)
    assert len(copied._held) == 6 and all(id(s._route_points) in copied._entry for s in again)
    for f in dataclasses.fields(state):
        np.testing.assert_array_equal(getattr(state, f.name), getattr(reference, f.name), err_msg=f.name)


def test_state_rows_by_row_slice_indices_or_mask_are_copies() -> None:
    state = scenarios_to_state([generate_scenario(gdc1(), seed) for seed in range(4)])
    picks = {
        "row": (2, [2]),
        "slice": (slice(1, 3), [1, 2]),
        "indices": (np.array([3, 0, 3]), [3, 0, 3]),
        "list": ([1, -1], [1, 3]),
        "mask": (np.array([True, False, True, False]), [0, 2]),
    }
    for what, (index, want) in picks.items():
        part = state.rows(index)
        for f in dataclasses.fields(state):
            got, full = getattr(part, f.name), getattr(state, f.name)
            np.testing.assert_array_equal(got, full[want], err_msg=f"{what} {f.name}")
            assert not np.shares_memory(got, full), (what, f.name)


def test_scenarios_to_state_with_several_robots_and_errors() -> None:
    s = generate_scenario(gdc1(), 1)
    poses = gdc1().legal_poses
    two = dataclasses.replace(s, robot_starts=poses[[0, 1]], robot_goals=poses[[2, 3]])
    state = scenarios_to_state([two, two], num_robots=2, max_humans=30)
    assert state.robot_pose.shape == (2, 2, 3) and state.human_mask.shape == (2, 30)
    np.testing.assert_array_equal(state.robot_goal[1], poses[[2, 3]])
    assert scenarios_to_state([two]).robot_pose.shape == (1, 1, 3)
    with pytest.raises(ValueError, match=r"scenario 0 \(seed 1\) has 1 robots, 2 requested"):
        scenarios_to_state([s], num_robots=2)
    with pytest.raises(ValueError, match=f"has {s.num_humans} humans, more than max_humans=2"):
        scenarios_to_state([s], max_humans=2)
    with pytest.raises(ValueError, match="at least one scenario"):
        scenarios_to_state([])


# ---------------------------------------------------------------------------- families
def make_family_scenario(name: str, m: Map, seed: int) -> Scenario:
    return get_family(name).make(seed, m=m)


# The shipped layout families (other test modules register families of their own in this process).
MAP_FAMILIES = [
    name
    for name in sorted(FAMILIES)
    if isinstance(get_family(name), LayoutFamily)
    and type(get_family(name)).__module__.startswith("socialzoo.")
]


def test_the_map_families_are_the_six_older_ones_and_the_suites_25() -> None:
    from socialzoo.scenarios.suite import SUITE_NAMES

    older = ["hallway_head_on", "overtaking", "crossing", "doorway", "circle_crossing", "parallel_traffic"]
    assert MAP_FAMILIES == sorted(older + list(SUITE_NAMES))


@pytest.mark.parametrize("name", MAP_FAMILIES)
def test_family_scenarios(name: str) -> None:
    family = get_family(name)
    m = small_map(family.map_name)
    s = make_family_scenario(name, m, 7)
    assert s == make_family_scenario(name, m, 7)
    assert s != make_family_scenario(name, m, 8)
    assert s.family == name and s.num_humans >= 1
    assert np.all(s.human_start_index == -1) and np.all(s.human_goal_index == -1)
    np.testing.assert_array_equal([r[0] for r in s.human_routes], s.human_spawn)
    check_scenario_geometry(m, s)
    _, dist = m.wall_index.nearest(
        np.concatenate((s.human_spawn, s.robot_starts[:, :2], s.robot_goals[:, :2]))
    )
    assert np.all(dist >= 0.3)
    state = scenarios_to_state([s])
    assert state.human_mask.sum() == s.num_humans


def test_family_layouts_mean_what_they_say() -> None:
    head_on = make_family_scenario("hallway_head_on", small_map("hallway"), 1)
    goal_end = np.linalg.norm(head_on.human_spawn - head_on.robot_goal[:2], axis=1)
    start_end = np.linalg.norm(head_on.human_spawn - head_on.robot_start[:2], axis=1)
    assert np.all(goal_end < start_end)
    overtaking = make_family_scenario("overtaking", small_map("hallway"), 1)
    assert overtaking.num_humans == 1 and overtaking.human_speed[0] <= 0.6
    circle = make_family_scenario("circle_crossing", small_map("open_room"), 1)
    ends = np.array([r[-1] for r in circle.human_routes])
    centre = (circle.robot_start[:2] + circle.robot_goal[:2]) / 2
    np.testing.assert_allclose(
        (circle.human_spawn + ends) / 2, np.broadcast_to(centre, ends.shape), atol=1e-9
    )
    with pytest.raises(KeyError, match="unknown scenario family 'stampede'"):
        make_family_scenario("stampede", small_map("hallway"), 0)
