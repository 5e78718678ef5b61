"""The suite's families with people in an open area (socialzoo.scenarios.suite_social, Fig. 7 p-u,
w, y): their scenarios, and each one's defining event on seeded test episodes of the
action-selection task."""

from __future__ import annotations

import numpy as np
import pytest

from socialzoo.env.tasks import make_task
from socialzoo.maps.map_file import Map, load_map
from socialzoo.scenarios.catalogue import get_family
from socialzoo.scenarios.scenario import Scenario
from socialzoo.scenarios.script import ACCOMPANY, FOLLOW, LEAD
from socialzoo.scenarios.suite import SUITE_SPLITS

DT = 0.025
GO, HALT = 0, 1
FAMILIES = (
    "joining_group",
    "leaving_group",
    "following_person",
    "leading_person",
    "accompanying_peer",
    "crowd_navigation",
    "perpendicular_flow",
    "robot_crowding",
)
CASES = [0, 1, 2, 3, 4]  # test seeds 100-104


def _rollout(family: str, steps: int, action: int = GO):
    """Test cases CASES of the family played together with one action; per-step records."""
    task = make_task("action_selection", len(CASES), None, map="plaza", family=family)
    task.reset(np.arange(len(CASES)), {"split": "test", "cases": CASES})
    core = task.core
    rec: dict[str, list] = {"robot": [], "human": [], "reached": [], "done": []}
    for _ in range(steps):
        step = task.step(np.full((len(CASES), 1), action, dtype=np.int64))
        rec["robot"].append(core.state.robot_pose[:, 0, :2].copy())
        rec["human"].append(core.state.human_pos.copy())
        rec["reached"].append(np.asarray(step.detail.reached).reshape(len(CASES), -1)[:, 0].copy())
        rec["done"].append(core.done[:, 0].copy())
    rec_arrays = {k: np.array(v) for k, v in rec.items()}
    # The step each episode ended (the last step where it never did).
    done = rec_arrays["done"]
    rec_arrays["end"] = np.where(done.any(0), done.argmax(0), steps - 1)
    return rec_arrays


def _scenarios(family: str) -> list[Scenario]:
    f = get_family(family)
    return [f.make(f.case_seed("test", k)) for k in CASES]


@pytest.mark.parametrize("name", FAMILIES)
def test_a_family_makes_legal_deterministic_scenarios_that_save_and_load(name):
    family = get_family(name)
    assert family.splits == SUITE_SPLITS and family.description and family.map_name == "plaza"
    m = load_map("plaza")
    lo, hi = np.asarray(m.walls).reshape(-1, 2).min(0), np.asarray(m.walls).reshape(-1, 2).max(0)
    for seed in range(100, 105):
        s = family.make(seed)
        assert s == family.make(seed)
        assert Scenario.from_json(s.to_json()) == s
        ends = np.vstack((s.robot_starts[:, :2], s.robot_goals[:, :2], s.human_spawn))
        assert np.all((ends > lo + 0.35) & (ends < hi - 0.35)), seed
        _, dist = m.wall_index.nearest(ends[:2])
        assert np.all(dist >= 0.35)


def test_a_map_without_room_for_the_walk_is_a_named_error():
    box = [[0.0, 0.0, 4.0, 0.0], [4.0, 0.0, 4.0, 4.0], [4.0, 4.0, 0.0, 4.0], [0.0, 4.0, 0.0, 0.0]]
    small = Map(
        name="closet",
        walls=np.array(box),
        nodes=np.array([[2.0, 2.0]]),
        edges=np.zeros((0, 2), dtype=np.int64),
        legal_poses=np.array([[1.0, 1.0, 0.0], [3.0, 3.0, 0.0]]),
    )
    for name in ("following_person", "accompanying_peer", "joining_group"):
        with pytest.raises(ValueError, match="closet"):
            get_family(name).make(100, m=small)


def _circle(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre and radius of the circle through the first three of the points (k, 2)."""
    (ax, ay), (bx, by), (cx, cy) = points[:3]
    d = 2.0 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by))
    ux = ((ax**2 + ay**2) * (by - cy) + (bx**2 + by**2) * (cy - ay) + (cx**2 + cy**2) * (ay - by)) / d
    uy = ((ax**2 + ay**2) * (cx - bx) + (bx**2 + by**2) * (ax - cx) + (cx**2 + cy**2) * (bx - ax)) / d
    centre = np.array([ux, uy])
    return centre, float(np.linalg.norm(points[0] - centre))


def _members(s: Scenario) -> np.ndarray:
    return np.flatnonzero(s.human_group == 0)


def test_joining_group_the_group_stands_and_the_robot_goes_to_its_free_spot():
    scenarios = _scenarios("joining_group")
    rec = _rollout("joining_group", 600)
    for b, s in enumerate(scenarios):
        members = _members(s)
        assert 2 <= len(members) <= 4 and np.all(s.human_group[members] == members[0])
        assert np.all(s.script.release[members] == np.inf)
        # The members never move, whatever the robot and the passers-by do.
        still = np.linalg.norm(rec["human"][:, b, members] - s.human_spawn[members], axis=-1)
        assert still.max() < 0.05
        # The robot's goal is on the members' circle (0.8-1.0 m), at the gap: a spot as far from its
        # neighbours as the neighbours are from each other.
        spots = np.vstack((s.robot_goals[0, :2], s.human_spawn[members]))
        centre, radius = _circle(spots)
        assert 0.8 <= radius <= 1.0
        np.testing.assert_allclose(np.linalg.norm(spots - centre, axis=1), radius, atol=1e-6)
        chord = 2.0 * radius * np.sin(np.pi / (len(members) + 1))
        gaps = np.linalg.norm(s.human_spawn[members] - spots[0], axis=1)
        assert gaps.min() == pytest.approx(chord, abs=1e-6)
    assert rec["reached"].any(0).sum() >= 4  # GoAlone gets there


def test_leaving_group_the_robot_starts_among_the_standing_members():
    scenarios = _scenarios("leaving_group")
    rec = _rollout("leaving_group", 600)
    for b, s in enumerate(scenarios):
        members = _members(s)
        near = np.linalg.norm(s.human_spawn[members] - s.robot_starts[0, :2], axis=1)
        assert (near <= 1.5).sum() >= 2  # its neighbours on the circle
        assert np.linalg.norm(rec["human"][:, b, members] - s.human_spawn[members], axis=-1).max() < 0.05
        assert np.linalg.norm(s.robot_goals[0, :2] - s.human_spawn[members].mean(0)) >= 4.0
    assert rec["reached"].any(0).sum() >= 4


def test_following_person_the_person_walks_its_route_and_stops_at_its_goal():
    scenarios = _scenarios("following_person")
    # The robot stays (Halt): the person walks on its own.
    rec = _rollout("following_person", 1700, HALT)
    for b, s in enumerate(scenarios):
        assert s.script.escort.tolist() == [0] and s.script.escort_kind.tolist() == [FOLLOW]
        np.testing.assert_array_equal(s.script.band, [[0.5, 3.0]])
        stop = s.human_routes[0][s.script.stop[0]]
        walk = np.linalg.norm(stop - s.human_spawn[0])
        assert 12.0 <= walk <= 20.0
        behind = np.linalg.norm(s.robot_starts[0, :2] - s.human_spawn[0])
        assert 1.5 <= behind <= 2.5
        short = np.linalg.norm(s.robot_goals[0, :2] - stop)
        assert 1.0 <= short <= 1.5 + 1e-9
        path = rec["human"][:, b, 0]
        assert np.linalg.norm(path[-1] - stop) < 0.2
        assert np.linalg.norm(path[-int(3.0 / DT) :] - path[-1], axis=1).max() < 0.02  # it stays
        assert 0.6 <= s.human_speed[0] <= 0.9  # a pace every suite robot can keep
    # GoAlone (1.5 m/s) overtakes the person on the way: it never counts its goal, though it waits
    # there until the person stops in the band ahead of it.
    assert not _rollout("following_person", 1000)["reached"].any()


def test_leading_person_the_led_person_follows_the_robot():
    scenarios = _scenarios("leading_person")
    rec = _rollout("leading_person", 800)
    for b, s in enumerate(scenarios):
        assert s.script.follow.tolist() == [0] and s.script.escort_kind.tolist() == [LEAD]
        end = rec["end"][b]
        gap = np.linalg.norm(rec["human"][: end + 1, b, 0] - rec["robot"][: end + 1, b], axis=-1)
        assert 0.9 < gap.min() and gap.max() < 3.0
        walked = np.linalg.norm(rec["human"][end, b, 0] - s.human_spawn[0])
        assert walked > 0.8 * np.linalg.norm(s.robot_goals[0, :2] - s.robot_starts[0, :2]) - 2.0
    assert rec["reached"].any(0).all()


def test_accompanying_peer_the_person_walks_beside_the_robots_route():
    scenarios = _scenarios("accompanying_peer")
    rec = _rollout("accompanying_peer", 1100)
    for b, s in enumerate(scenarios):
        assert s.script.escort_kind.tolist() == [ACCOMPANY]
        a, g = s.robot_starts[0, :2], s.robot_goals[0, :2]
        u = (g - a) / np.linalg.norm(g - a)
        rel = rec["human"][:, b, 0] - a
        side = np.abs(rel @ np.array([-u[1], u[0]]))
        along = rel @ u
        assert 0.7 < side.min() and side.max() < 1.8  # about 1 m to the side all the way
        # It stays by its stop at the end (the robot beside it, at its goal 1 m away, keeps it up to
        # 0.6 m or so off).
        stop = s.human_routes[0][s.script.stop[0]]
        path = rec["human"][:, b, 0]
        assert np.linalg.norm(path[-int(3.0 / DT) :] - stop, axis=1).max() < 0.8
        assert along[-1] > 0.9 * np.linalg.norm(g - a)
        assert 0.6 <= s.human_speed[0] <= 0.9
    # GoAlone drives ahead of the person: it never counts its goal, though the person stops beside it.
    assert not rec["reached"].any()


def _escort_velocity(state, start: np.ndarray, axis: np.ndarray, kind: int) -> np.ndarray:
    """(B, 2) a holonomic robot's world-frame velocity, m/s, that escorts the person of each row
    (a scripted controller of the test): 1.2 m behind the person on its track (FOLLOW), abreast of
    it on the robot's own line (ACCOMPANY), straight on (LEAD: the person keeps up); never past
    the goal."""
    pos, goal = state.robot_pose[:, 0, :2], state.robot_goal[:, 0, :2]
    person, person_vel = state.human_pos[:, 0], state.human_vel[:, 0]
    along = ((person - start) * axis).sum(-1)
    goal_along = ((goal - start) * axis).sum(-1)
    if kind == FOLLOW:
        point = np.where((along - 1.2 > goal_along)[:, None], goal, person - 1.2 * axis)
        feed = person_vel
    elif kind == ACCOMPANY:
        point = start + np.minimum(along, goal_along)[:, None] * axis
        feed = (person_vel * axis).sum(-1)[:, None] * axis
    else:
        point, feed = goal, np.zeros_like(pos)
    return feed + 1.5 * (point - pos)


@pytest.mark.parametrize(
    ("family", "kind"),
    [("following_person", FOLLOW), ("leading_person", LEAD), ("accompanying_peer", ACCOMPANY)],
)
def test_a_robot_that_escorts_its_person_all_the_way_succeeds(family, kind):
    """A controller that keeps the person in its place (the CrowdNav task's holonomic robot, 1 m/s)
    reaches its goal on every case; robots that do not keep it fail (the tests above, below)."""
    cases = list(range(10))
    task = make_task(
        "crowdnav", len(cases), None, variant="Walls", map=None, family=family, time_limit=60.0,
        max_humans=20, action_frame="world",
    )  # fmt: skip
    task.reset(np.arange(len(cases)), {"split": "test", "cases": cases})
    core = task.core
    start = core.state.robot_pose[:, 0, :2].copy()
    axis = core.state.robot_goal[:, 0, :2] - start
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    speed = float(task.config.robot.max_speed)
    success = np.zeros(len(cases), dtype=bool)
    for _ in range(400):
        velocity = _escort_velocity(core.state, start, axis, kind) / speed
        norm = np.linalg.norm(velocity, axis=1, keepdims=True)
        velocity = np.where(norm > 1.0, velocity / np.maximum(norm, 1e-9), velocity)
        was_done = core.done[:, 0].copy()
        step = task.step(velocity[:, None].astype(np.float32))
        ended = step.terminated[:, 0] & ~was_done
        success |= ended & (step.info["human_collisions"][:, 0] == 0) & ~step.info["wall_collision"][:, 0]
        if core.done.all():
            break
    assert success.all(), success
    assert not core.script.escort_lost.any()


@pytest.mark.parametrize("family", ["following_person", "accompanying_peer"])
def test_a_robot_that_halts_20_s_and_then_drives_fails(family):
    """The person walks on while the robot waits: far out of its place, the escort is lost, though
    the robot then reaches its goal with the person there (before: success in every case)."""
    task = make_task("action_selection", len(CASES), None, map="plaza", family=family)
    task.reset(np.arange(len(CASES)), {"split": "test", "cases": CASES})
    reached = np.zeros(len(CASES), dtype=bool)
    at_goal = np.zeros(len(CASES), dtype=bool)
    for t in range(1600):
        step = task.step(np.full((len(CASES), 1), HALT if t < 800 else GO, dtype=np.int64))
        reached |= np.asarray(step.detail.reached).reshape(len(CASES), -1)[:, 0]
        at_goal |= task.core.goal_distance()[:, 0] < task.config.goal_radius
    assert at_goal.all() and not reached.any()
    assert task.core.script.escort_lost[:, 0].all()


def test_crowd_navigation_many_people_come_close_to_the_robot():
    scenarios = _scenarios("crowd_navigation")
    rec = _rollout("crowd_navigation", 700)
    for b, s in enumerate(scenarios):
        assert 10 <= s.num_humans <= 20
        end = rec["end"][b]
        near = np.linalg.norm(
            rec["human"][: end + 1, b, : s.num_humans] - rec["robot"][: end + 1, b, None], axis=-1
        )
        assert (near < 3.0).any(0).sum() >= 5


def test_perpendicular_flow_people_cross_the_robots_line_ahead_of_it():
    scenarios = _scenarios("perpendicular_flow")
    rec = _rollout("perpendicular_flow", 700)
    for b, s in enumerate(scenarios):
        a, g = s.robot_starts[0, :2], s.robot_goals[0, :2]
        u = (g - a) / np.linalg.norm(g - a)
        end = rec["end"][b]
        rel = rec["human"][: end + 1, b, : s.num_humans] - a
        side = rel @ np.array([-u[1], u[0]])
        robot_along = (rec["robot"][: end + 1, b] - a) @ u
        crossed = np.sign(side[1:]) != np.sign(side[:-1])
        ahead = (rel[1:] @ u) > robot_along[1:, None] + 0.3
        assert (crossed & ahead).any(0).sum() >= 2  # people, not one straggler
        # The stream crosses within a 4 m band.
        starts = (s.human_spawn - a) @ u
        assert np.ptp(starts) <= 4.0 + 1e-9


def test_robot_crowding_people_gather_close_round_the_robot():
    scenarios = _scenarios("robot_crowding")
    # The robot drives to its goal (GoAlone) and stops there: the onlookers converge on it.
    rec = _rollout("robot_crowding", 600)
    for b, s in enumerate(scenarios):
        assert 4 <= s.num_humans <= 8 and np.all(s.script.follow == 0)
        assert np.all((s.script.gap >= 0.9) & (s.script.gap <= 1.2))
        start = np.linalg.norm(s.human_spawn - s.robot_starts[0, :2], axis=1)
        assert np.all((start >= 2.0) & (start <= 5.0))
        near = np.linalg.norm(rec["human"][:, b, : s.num_humans] - rec["robot"][:, b, None], axis=-1)
        assert (near < 1.5).sum(1).max() >= 3
