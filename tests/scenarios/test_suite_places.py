"""The suite's families at places (socialzoo.scenarios.suite_places, Fig. 7 i, j, l-o): their
scenarios, and each one's defining event on seeded test episodes of the action-selection task."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from socialzoo.env.tasks import make_task
from socialzoo.maps.map_file import load_map
from socialzoo.scenarios.catalogue import get_family
from socialzoo.scenarios.scenario import Scenario
from socialzoo.scenarios.suite import SUITE_SPLITS
from socialzoo.scenarios.suite_places import map_door

DT = 0.025
GO, HALT = 0, 1
FAMILIES = (
    "blind_corner",
    "narrow_hallway",
    "entering_room",
    "exiting_room",
    "entering_elevator",
    "exiting_elevator",
)
CASES = [0, 1, 2, 3, 4]  # test seeds 100-104


def _rollout(family: str, steps: int, policy: Callable[[int], np.ndarray] | int = GO):
    """Test cases CASES of the family played together: per-step records."""
    task = make_task("action_selection", len(CASES), None, map=get_family(family).map_name, family=family)
    task.reset(np.arange(len(CASES)), {"split": "test", "cases": CASES})
    core = task.core
    rec: dict[str, list] = {"robot": [], "human": [], "visible": [], "closed": [], "wall": []}
    for k in range(steps):
        action = np.full((len(CASES), 1), policy, dtype=np.int64) if isinstance(policy, int) else policy(k)
        step = task.step(action)
        rec["robot"].append(core.state.robot_pose[:, 0, :2].copy())
        rec["human"].append(core.state.human_pos.copy())
        rec["visible"].append(core.see().copy())
        rec["closed"].append(core.script.closed.copy())
        rec["wall"].append(np.asarray(step.detail.wall_collision).reshape(len(CASES), -1)[:, 0].copy())
    return {k: np.array(v) for k, v in rec.items()}


def _scenarios(family: str) -> list[Scenario]:
    f = get_family(family)
    return [f.make(f.case_seed("test", k)) for k in CASES]


@pytest.mark.parametrize("name", FAMILIES)
def test_a_family_makes_legal_deterministic_scenarios_that_save_and_load(name):
    family = get_family(name)
    assert family.splits == SUITE_SPLITS and family.description
    m = load_map(family.map_name)
    for seed in range(100, 105):
        s = family.make(seed)
        assert s == family.make(seed)
        assert Scenario.from_json(s.to_json()) == s
        assert s.family == name and s.map_name == family.map_name
        ends = np.vstack((s.robot_starts[:, :2], s.robot_goals[:, :2]))
        _, dist = m.wall_index.nearest(ends)
        assert np.all(dist >= 0.35), (seed, dist)
        assert np.linalg.norm(ends[0] - ends[1]) > 2.0


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("blind_corner", "needs a corner"),
        ("narrow_hallway", "narrower than 1.8 m"),
        ("entering_room", "needs a door"),
        ("exiting_room", "needs a door"),
        ("entering_elevator", "needs a door"),
        ("exiting_elevator", "needs a door"),
    ],
)
def test_a_map_without_the_place_is_a_named_error(name, message):
    with pytest.raises(ValueError, match=f"plaza.*{message}"):
        get_family(name).make(100, m=load_map("plaza"))


def test_blind_corner_hides_the_person_until_they_are_close():
    # GoAlone drives round the corner; the task's sight lines (core.see()) hide people behind walls.
    rec = _rollout("blind_corner", 400)
    dist = np.linalg.norm(rec["human"][:, :, 0] - rec["robot"], axis=-1)
    seen = rec["visible"][:, :, 0]
    for b in range(len(CASES)):
        first = int(np.argmax(seen[:, b]))
        assert seen[:, b].any() and dist[0, b] > 8.0
        # Unseen all the way from more than 8 m to 2.55-2.7 m (see BlindCorner's docstring), and
        # a second before the first sight they were still about 4 m apart.
        assert not seen[:first, b].any()
        assert 2.4 < dist[first, b] < 2.9
        assert dist[first - int(1.0 / DT), b] > 3.8
        # Timed to meet at the corner: they pass close by each other.
        assert dist[:, b].min() < 1.2


def test_narrow_hallway_they_meet_inside_the_narrow_corridor():
    rec = _rollout("narrow_hallway", 700)
    # The map's corridor runs x 6-16 (maps/README.md).
    robot_in = (rec["robot"][..., 0] > 6.0) & (rec["robot"][..., 0] < 16.0)
    human_in = (rec["human"][:, :, 0, 0] > 6.0) & (rec["human"][:, :, 0, 0] < 16.0)
    close = np.linalg.norm(rec["human"][:, :, 0] - rec["robot"], axis=-1) < 1.5
    assert (robot_in & human_in & close).any(axis=0).all()


def test_entering_room_a_person_leaves_through_the_door_as_the_robot_arrives():
    m = load_map("room")
    door = map_door(m, "entering_room")
    rec = _rollout("entering_room", 600)
    robot_near = np.linalg.norm(rec["robot"] - door.centre, axis=-1) < 3.0
    leaver = door.frame(rec["human"][:, :, 0])
    in_door = (np.abs(leaver[..., 0]) < door.half_width) & (np.abs(leaver[..., 1]) < 0.5)
    assert (in_door & robot_near).any(axis=0).all()
    # It left the room: it was inside and went out into the corridor.
    assert (leaver[0, :, 1] > 1.0).all() and (leaver[..., 1].min(0) < -1.0).all()


def test_exiting_room_a_person_passes_outside_the_door_as_the_robot_comes_out():
    m = load_map("room")
    door = map_door(m, "exiting_room")
    rec = _rollout("exiting_room", 600)
    robot_near = np.linalg.norm(rec["robot"] - door.centre, axis=-1) < 3.0
    frame = door.frame(rec["human"])  # (T, B, H, 2)
    outside = (np.abs(frame[..., 0]) < 1.0) & (frame[..., 1] < 0.0) & (frame[..., 1] > -2.5)
    mask = np.array([np.arange(rec["human"].shape[2]) < s.num_humans for s in _scenarios("exiting_room")])
    assert ((outside & mask).any(-1) & robot_near).any(axis=0).all()
    assert (door.frame(rec["robot"][0])[:, 1] > 0.0).all() and (
        door.frame(rec["robot"][-1])[:, 1] < 0.0
    ).all()


def test_entering_elevator_the_doors_open_on_time_and_those_leaving_are_out_first():
    # The robot waits (Halt) in the lobby: the event is the doors' and the people's.
    door = map_door(load_map("elevator"), "entering_elevator")
    rec = _rollout("entering_elevator", 1000, HALT)
    t = np.arange(1, 1001) * DT
    for b, s in enumerate(_scenarios("entering_elevator")):
        t_open, t_close = s.script.doors[0, 4:]
        np.testing.assert_array_equal(rec["closed"][:, b, 0], (t < t_open) | (t >= t_close))
        depth = door.frame(rec["human"][:, b, : s.num_humans])[..., 1]  # (T, n), > 0 in the car
        leaving, entering = np.flatnonzero(depth[0] > 0.0), np.flatnonzero(depth[0] < 0.0)
        assert len(leaving) >= 1 and s.script.release[leaving].min() == t_open
        assert np.all(s.script.release >= t_open) and np.all(s.script.release[entering] >= t_open + 3.0)
        before = t < t_open
        assert np.abs(depth[before] - depth[0]).max() < 0.05  # nobody moves before the doors open
        out = [t[np.argmax(depth[:, i] < -0.3)] for i in leaving]
        assert all(depth[:, i].min() < -0.3 for i in leaving)
        for i in entering:
            assert depth[:, i].max() > 0.3
            assert t[np.argmax(depth[:, i] > 0.3)] > max(out) > t_open


def test_exiting_elevator_the_robot_cannot_leave_before_the_doors_open():
    door = map_door(load_map("elevator"), "exiting_elevator")
    scenarios = _scenarios("exiting_elevator")
    opens = np.array([s.script.doors[0, 4] for s in scenarios])
    # Driving at once (GoAlone), the robot touches the closed doors: a wall collision before t_open.
    rec = _rollout("exiting_elevator", 200)
    t = np.arange(1, 201) * DT
    hit = rec["wall"].argmax(0)
    assert rec["wall"].any(0).all() and np.all(t[hit] < opens)
    assert (door.frame(rec["robot"])[..., 1] > 0.0).all()

    # Waiting for the doors (Halt until t_open), it gets out without touching them, and the people
    # walk into the car only after the doors open.
    def wait(k: int) -> np.ndarray:
        return np.where(k * DT > opens + 0.2, GO, HALT)[:, None].astype(np.int64)

    rec = _rollout("exiting_elevator", 700, wait)
    t = np.arange(1, 701) * DT
    assert not rec["wall"].any()
    assert (door.frame(rec["robot"][-1])[:, 1] < -1.0).all()
    for b, s in enumerate(scenarios):
        depth = door.frame(rec["human"][:, b, : s.num_humans])[..., 1]
        assert np.all(depth[t < opens[b]] < 0.0)
        entered = depth.max(0) > 0.3
        assert entered.any()
        assert np.all(t[np.argmax(depth[:, entered] > 0.3, axis=0)] > opens[b] + 2.0)
