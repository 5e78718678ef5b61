"""The suite's families on ways (socialzoo.scenarios.suite_ways): each draws its test-split
scenarios deterministically, saves and loads them, starts the robot clear of walls, and its
defining event (docs/suite_scenarios.md) happens on seeded test-split episodes."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pytest

from socialzoo.core.geometry import wall_distances
from socialzoo.env.tasks import make_task
from socialzoo.maps.map_file import load_map
from socialzoo.nav.subpolicies import GO_ALONE, HALT
from socialzoo.scenarios.catalogue import get_family
from socialzoo.scenarios.scenario import Scenario
from socialzoo.scenarios.script import PROCEED, WAIT
from socialzoo.scenarios.suite_ways import STOP_BEFORE, corridor, crossroads

DT = 0.025
WAYS = (
    "frontal_approach",
    "pedestrian_obstruction",
    "pedestrian_overtaking",
    "robot_overtaking",
    "down_path",
    "intersection_no_gesture",
    "intersection_wait",
    "intersection_proceed",
    "narrow_doorway",
    "parallel_flow",
    "circular_crossing",
)
# Test-split cases the event tests play (seeds 100 + k).
CASES = (0, 1, 2, 3, 4)


@dataclass
class Record:
    """An episode batch, step by step: T steps of B rows (world frame, m, m/s).

    Attributes:
        robot: (T, B, 3) the robot's pose.
        pos: (T, B, H, 2) and vel: (T, B, H, 2) the people's (slots past `n` unused).
        signal: (T, B, H) each person's gesture shown; released: (T, B, H).
        done: (T, B) the robot's episode had ended before the step's state.
        n: (B,) people in each row's scenario.
        scenarios: each row's scenario.
    """

    robot: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    signal: np.ndarray
    released: np.ndarray
    done: np.ndarray
    n: np.ndarray
    scenarios: list[Scenario]

    def speed(self) -> np.ndarray:
        """(T, B, H) the people's speeds, m/s."""
        return np.hypot(self.vel[..., 0], self.vel[..., 1])


Policy = Callable[[object], np.ndarray]


def _rollout(family: str, cases=CASES, steps: int = 800, policy: int | Policy = GO_ALONE) -> Record:
    """Play test-split `cases` of `family` in one batch for `steps` steps: every robot takes
    `policy` (an action, or a function of the core giving (B,) actions)."""
    fam = get_family(family)
    b = len(cases)
    task = make_task("action_selection", b, None, map=fam.map_name, family=family, max_steps=2400)
    task.reset(np.arange(b), {"split": "test", "cases": list(cases)})
    core = task.core
    scenarios = [fam.make(fam.case_seed("test", k)) for k in cases]
    n = np.array([len(s.human_spawn) for s in scenarios])
    h = int(n.max())
    for i, s in enumerate(scenarios):  # the rows play the family's test cases
        np.testing.assert_array_equal(core.state.human_pos[i, : n[i]], s.human_spawn)
    out: dict[str, list[np.ndarray]] = {k: [] for k in ("robot", "pos", "vel", "signal", "released", "done")}
    for _ in range(steps):
        action = np.full(b, policy) if isinstance(policy, int) else policy(core)
        done = core.done[:, 0].copy()
        task.step(np.asarray(action, dtype=np.int64).reshape(b, 1))
        state = core.state
        out["robot"].append(state.robot_pose[:, 0].copy())
        out["pos"].append(state.human_pos[:, :h].copy())
        out["vel"].append(state.human_vel[:, :h].copy())
        out["signal"].append(core.script.signal[:, :h].copy())
        out["released"].append(core.script.released[:, :h].copy())
        out["done"].append(done)
    arrays = {k: np.stack(v) for k, v in out.items()}
    return Record(**arrays, n=n, scenarios=scenarios)


def _present(rec: Record) -> np.ndarray:
    """(B, H) which slots hold a person."""
    return np.arange(rec.pos.shape[2])[None] < rec.n[:, None]


def _rows(rec: Record, event: np.ndarray) -> list[int]:
    """The rows where (B,) `event` holds, for failure messages."""
    return [i for i in range(len(rec.n)) if event[i]]


def _head_on(rec: Record, within: float = 3.0) -> np.ndarray:
    """(T, B, H) a person within `within` m in front of the driving robot, walking against its heading."""
    rel = rec.pos - rec.robot[:, :, None, :2]
    heading = np.stack((np.cos(rec.robot[..., 2]), np.sin(rec.robot[..., 2])), -1)[:, :, None]
    ahead = (rel * heading).sum(-1) > 0
    against = (rec.vel * heading).sum(-1) < -0.7 * rec.speed()
    close = np.hypot(rel[..., 0], rel[..., 1]) < within
    return close & ahead & against & (rec.speed() > 0.2) & ~rec.done[..., None] & _present(rec)[None]


# ------------------------------------------------------------------ every family


@pytest.mark.parametrize("name", WAYS)
def test_a_ways_family_is_deterministic_round_trips_and_starts_the_robot_clear(name):
    family = get_family(name)
    assert family.splits["test"].first == 100
    m = load_map(family.map_name)
    walls = np.asarray(m.walls).reshape(-1, 4)
    for seed in range(100, 105):
        s = family.make(seed)
        assert s == family.make(seed) and s.family == name and s.map_name == family.map_name
        assert Scenario.from_json(s.to_json()) == s
        ends = np.concatenate((s.robot_starts[:, :2], s.robot_goals[:, :2]))
        assert wall_distances(ends, walls).min() > 0.5
        assert wall_distances(s.human_spawn, walls).min() >= 0.3
    assert family.make(100) != family.make(101)


def test_a_family_on_a_map_without_its_geometry_is_a_named_error():
    with pytest.raises(ValueError, match=r"open_room.*no corridor"):
        get_family("frontal_approach").make(100, m=load_map("open_room"))
    with pytest.raises(ValueError, match=r"hallway.*no crossing ways"):
        get_family("intersection_wait").make(100, m=load_map("hallway"))
    with pytest.raises(ValueError, match=r"hallway.*needs a door"):
        get_family("narrow_doorway").make(100, m=load_map("hallway"))


# ------------------------------------------------------------------ defining events (GoAlone unless said)


def _coords(origin, u, points):
    """(..., 2) each point's (s, t) from `origin`: along the unit vector u, and to its left, m."""
    rel = np.asarray(points, dtype=np.float64) - origin
    return np.stack((rel @ u, rel @ np.array([-u[1], u[0]])), axis=-1)


def test_frontal_approach_they_meet_head_on_in_the_corridor():
    rec = _rollout("frontal_approach", steps=600)
    c = corridor(load_map("hallway"))
    s, t = np.moveaxis(_coords(c.start, c.u, rec.robot[..., :2]), -1, 0)
    in_corridor = (s > 0) & (s < c.length) & (np.abs(t) < c.half_width)
    met = (_head_on(rec).any(-1) & in_corridor).any(0)
    assert met.all(), _rows(rec, ~met)


def test_pedestrian_obstruction_the_person_stands_in_the_robots_way_as_it_comes_within_2_m():
    rec = _rollout("pedestrian_obstruction", steps=400)
    c = corridor(load_map("hallway"))
    gap = np.hypot(*(rec.pos[:, :, 0] - rec.robot[..., :2]).transpose(2, 0, 1))
    assert (gap < 2.0).any(0).all()
    for i, scenario in enumerate(rec.scenarios):
        k = int(np.argmax(gap[:, i] < 2.0))  # the robot's first step within 2 m of the person
        stop = scenario.human_routes[0][scenario.script.stop[0]]
        person, robot = _coords(c.start, c.u, rec.pos[k, i, 0]), _coords(c.start, c.u, rec.robot[k, i, :2])
        assert not rec.released[k, i, 0] and np.linalg.norm(rec.pos[k, i, 0] - stop) < 0.5
        assert rec.speed()[k, i, 0] < 0.3  # standing (the approaching robot nudges it)
        assert abs(person[1]) < 0.5 and person[0] > robot[0]  # on the robot's line, ahead of it
        assert scenario.script.release[0] >= 10.0


def test_pedestrian_overtaking_the_person_passes_the_robot():
    rec = _rollout("pedestrian_overtaking", steps=700)
    c = corridor(load_map("hallway"))
    person, robot = (
        _coords(c.start, c.u, rec.pos[:, :, 0])[..., 0],
        _coords(c.start, c.u, rec.robot[..., :2])[..., 0],
    )
    assert (person[0] < robot[0] - 2.5).all()
    passed = ((person > robot + 0.3) & ~rec.done).any(0)
    assert passed.all(), _rows(rec, ~passed)


def test_robot_overtaking_the_robot_passes_the_person():
    rec = _rollout("robot_overtaking", steps=700)
    a, b = rec.scenarios[0].robot_starts[0, :2], rec.scenarios[0].robot_goals[0, :2]
    u = (b - a) / np.linalg.norm(b - a)
    person, robot = (rec.pos[:, :, 0] - a) @ u, (rec.robot[..., :2] - a) @ u
    assert (person[0] > robot[0] + 1.5).all()
    passed = ((robot > person + 0.5) & ~rec.done).any(0)
    assert passed.all(), _rows(rec, ~passed)


def test_down_path_someone_meets_the_robot_head_on_and_someone_walks_its_way():
    rec = _rollout("down_path", steps=600)
    rel = rec.pos - rec.robot[:, :, None, :2]
    heading = np.stack((np.cos(rec.robot[..., 2]), np.sin(rec.robot[..., 2])), -1)[:, :, None]
    its_way = (rec.vel * heading).sum(-1) > 0.7 * rec.speed()
    near = np.hypot(rel[..., 0], rel[..., 1]) < 3.0
    alongside = its_way & near & (rec.speed() > 0.2) & ~rec.done[..., None] & _present(rec)[None]
    both = _head_on(rec).any((0, 2)) & alongside.any((0, 2))
    assert both.all(), _rows(rec, ~both)


def _crossings(rec: Record, x) -> np.ndarray:
    """(T - 1, B, H) a person crosses the robot's way's axis inside the crossing, this step."""
    side = np.sign(_coords(x.centre, x.u, rec.pos)[..., 1])
    inside = np.abs(_coords(x.centre, x.u, rec.pos[1:])[..., 0]) < x.cross_half_width
    return (side[1:] != side[:-1]) & inside & _present(rec)[None]


def test_intersection_no_gesture_a_person_crosses_the_centre_while_the_robot_is_within_3_m():
    rec = _rollout("intersection_no_gesture", steps=500)
    x = crossroads(load_map("intersection"))
    robot_near = np.hypot(*(rec.robot[1:, :, :2] - x.centre).transpose(2, 0, 1)) < 3.0
    event = (_crossings(rec, x) & robot_near[..., None]).any((0, 2))
    assert event.all(), _rows(rec, ~event)


def _stood_signalling(rec: Record, gesture: int) -> tuple[np.ndarray, np.ndarray]:
    """((T, B) the person stands on its stop point showing `gesture`, (B,) its stop points)."""
    stop = np.array([s.human_routes[0][s.script.stop[0]] for s in rec.scenarios])
    on_stop = np.hypot(*(rec.pos[:, :, 0] - stop).transpose(2, 0, 1)) < 0.3
    return on_stop & (rec.speed()[..., 0] < 0.1) & (rec.signal[..., 0] == gesture), stop


def _first(event: np.ndarray) -> np.ndarray:
    """(B,) the first step of each row's event (T, B), len(event) where it never happens."""
    return np.where(event.any(0), np.argmax(event, axis=0), len(event))


def test_intersection_wait_the_person_stops_signals_wait_before_the_crossing_then_crosses_first():
    """Even rows: a robot that halts while it is told to wait (and else goes alone); odd rows go alone."""
    x = crossroads(load_map("intersection"))
    polite = np.arange(len(CASES)) % 2 == 0

    def policy(core):
        told = (core.script.signal == WAIT).any(1)
        return np.where(polite & told, HALT, GO_ALONE)

    rec = _rollout("intersection_wait", steps=700, policy=policy)
    standing, stop = _stood_signalling(rec, WAIT)
    lateral = _coords(x.centre, x.u, stop)[..., 1]
    assert (np.abs(lateral) >= x.half_width + STOP_BEFORE - 0.25).all()  # before the crossing
    assert (standing.sum(0) * DT > 1.5).all()  # it signals, standing, for seconds
    stood, crossed = _first(standing), _first(_crossings(rec, x)[..., 0])
    assert (stood < crossed).all() and (crossed < len(rec.pos) - 1).all()
    # It crosses first where the robot waits: the robot is still short of the crossing.
    robot_along = _coords(x.centre, x.u, rec.robot[crossed, np.arange(len(CASES)), :2])[..., 0]
    assert (robot_along[polite] < -x.cross_half_width).all()
    assert all(2.0 <= s.script.wait[0] <= 4.0 and s.script.gesture[0] == WAIT for s in rec.scenarios)


def test_intersection_proceed_the_person_signals_proceed_and_crosses_only_after_the_robot_passed():
    """Even rows go alone: the gate releases the person; odd rows halt: it walks on at 30 s."""
    x = crossroads(load_map("intersection"))
    halt = np.arange(len(CASES)) % 2 == 1
    rec = _rollout("intersection_proceed", steps=1400, policy=lambda core: np.where(halt, HALT, GO_ALONE))
    standing, _ = _stood_signalling(rec, PROCEED)
    gate = rec.scenarios[0].script.gate[0]
    past = ((rec.robot[..., :2] - gate[:2]) @ gate[2:]) > 0
    stood, released, crossed = (
        _first(standing),
        _first(rec.released[..., 0]),
        _first(_crossings(rec, x)[..., 0]),
    )
    robot_past = _first(past)
    assert (standing.sum(0) * DT > 1.5).all() and (stood < released).all()
    assert (crossed < len(rec.pos) - 1).all() and (released < crossed).all()
    assert (released[~halt] == robot_past[~halt]).all()  # let go as the robot passes the gate
    assert (np.abs(released[halt] * DT - 30.0) < 2 * DT).all() and not past[:, halt].any()
    assert all(s.script.gesture[0] == PROCEED and s.script.release[0] == 30.0 for s in rec.scenarios)


def test_narrow_doorway_both_are_within_2_5_m_of_the_door_at_once():
    rec = _rollout("narrow_doorway", steps=450)
    door = np.asarray(load_map("doorway").doors)[:1]
    person, robot = wall_distances(rec.pos[:, :, 0], door), wall_distances(rec.robot[..., :2], door)
    both = ((person < 2.5) & (robot < 2.5) & ~rec.done).any(0)
    assert both.all(), _rows(rec, ~both)


def test_parallel_flow_people_walk_the_robots_way_around_it():
    rec = _rollout("parallel_flow", steps=800)
    rel = rec.pos - rec.robot[:, :, None, :2]
    heading = np.stack((np.cos(rec.robot[..., 2]), np.sin(rec.robot[..., 2])), -1)[:, :, None]
    its_way = ((rec.vel * heading).sum(-1) > 0.7 * rec.speed()) & (rec.speed() > 0.3)
    around = its_way & (np.hypot(rel[..., 0], rel[..., 1]) < 3.0) & ~rec.done[..., None] & _present(rec)[None]
    most = around.sum(-1).max(0)
    assert (most >= 2).all(), most


def test_circular_crossing_everyone_crosses_the_centre():
    rec = _rollout("circular_crossing", steps=500)
    for i, s in enumerate(rec.scenarios):
        centre = (s.robot_starts[0, :2] + s.robot_goals[0, :2]) / 2.0
        n = rec.n[i]
        start = s.human_spawn - centre
        rel = rec.pos[:, i, :n] - centre
        assert ((rel * start).sum(-1) < 0).any(0).all()  # each ends up past the centre
        assert (np.hypot(rel[..., 0], rel[..., 1]).min(0) < 2.0).all()  # through the middle
