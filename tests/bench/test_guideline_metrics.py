"""Table I's metrics (socialzoo.bench.guideline_metrics) on hand-made trajectories, each against a
value worked out by hand in the test."""

import math

import numpy as np
import pytest

from socialzoo.bench.guideline_metrics import (
    GUIDELINE_KEYS,
    GuidelineParams,
    Trajectories,
    episode_metrics,
    guideline_metrics,
    time_to_collision,
    wall_distances,
)
from socialzoo.core.metrics import metric, names

FAR = [100.0, 0.0]  # a goal never reached


def line(*xs, y=0.0):
    return np.array([[x, y] for x in xs], dtype=float)


def test_every_registered_metric_is_computed_in_registry_order():
    found = episode_metrics(dt=1.0, robot_pos=line(0, 1), goal=FAR)
    assert tuple(found) == GUIDELINE_KEYS == names("guidelines")
    for name, value in found.items():
        kind = metric(name).kind
        assert isinstance(value, {"bool": bool, "int": int, "float": float}[kind]), name


def test_velocity_acceleration_and_jerk_from_positions():
    # dt 0.5; displacements 0.5, 1, 1.5, 1 -> step speeds 1, 2, 3, 2 m/s; the robot starts at rest
    # (speed 0 at sample 0), so accelerations (s_k - s_(k-1)) / dt = 2, 2, 2, -2 and jerks
    # (a_k - a_(k-1)) / dt = 0, 0, -8.
    found = episode_metrics(dt=0.5, robot_pos=line(0, 0.5, 1.5, 3.0, 4.0), goal=FAR)
    assert (found["gl_velocity_min"], found["gl_velocity_avg"], found["gl_velocity_max"]) == (1, 2, 3)
    assert (found["gl_acceleration_min"], found["gl_acceleration_avg"], found["gl_acceleration_max"]) == (
        -2,
        1,
        2,
    )
    assert (found["gl_jerk_min"], found["gl_jerk_max"]) == (-8, 0)
    assert found["gl_jerk_avg"] == pytest.approx(-8 / 3)
    assert found["gl_path_length"] == pytest.approx(4.0)
    assert found["gl_stalled_time"] == 0


def test_given_velocities_are_used_as_they_are():
    # Velocities (3, 4) then (0, 0): speeds 5 and 0; a given start velocity of 5 -> accelerations
    # (5 - 5) / 1 = 0 and (0 - 5) / 1 = -5; one jerk (-5 - 0) / 1 = -5; one stalled step of 1 s.
    vel = np.array([[3.0, 4.0], [3.0, 4.0], [0.0, 0.0]])
    found = episode_metrics(dt=1.0, robot_pos=line(0, 5, 5), robot_vel=vel, goal=FAR)
    assert (found["gl_velocity_min"], found["gl_velocity_max"]) == (0, 5)
    assert (found["gl_acceleration_min"], found["gl_acceleration_max"]) == (-5, 0)
    assert found["gl_jerk_min"] == found["gl_jerk_max"] == -5
    assert found["gl_stalled_time"] == 1.0


def test_success_time_to_goal_spl_and_the_episode_ending_at_the_goal():
    # (0,0) -> (1,0) -> (1,1) -> (2,1), the goal (radius 0.1): path 3 m in 3 steps of 0.5 s. The log
    # goes on to (3,1), (4,1), with a person overlapping the robot at (4,1): after the goal, so
    # neither the path nor the collision counts.
    pos = np.array([[0, 0], [1, 0], [1, 1], [2, 1], [3, 1], [4, 1]], dtype=float)
    people = np.array([[[9, 9]]] * 5 + [[[4, 1]]], dtype=float)
    kw = dict(dt=0.5, robot_pos=pos, goal=[2, 1], goal_radius=0.1, people_pos=people)
    found = episode_metrics(**kw)
    assert found["gl_success"] and not found["gl_timeout"]
    assert found["gl_time_to_goal"] == 1.5 and found["gl_aggregated_time"] == 1.5
    assert found["gl_path_length"] == 3.0 and found["gl_human_collisions"] == 0
    # SPL = l / max(p, l): the straight line l = sqrt(5) = 2.236 over p = 3 -> 0.745.
    assert found["gl_spl"] == pytest.approx(math.sqrt(5) / 3)
    # A given shortest path of 2 m: 2 / 3.
    assert episode_metrics(shortest_path=2.0, **kw)["gl_spl"] == pytest.approx(2 / 3)
    # A path shorter than the shortest one (the goal radius cuts it): capped at 1.
    assert episode_metrics(shortest_path=5.0, **kw)["gl_spl"] == 1.0
    # A human contact flag at sample 1, before the goal: no success, SPL 0, no time to goal.
    flags = np.array([False, True, False, False, False, False])
    failed = episode_metrics(human_contact=flags, **kw)
    assert not failed["gl_success"] and failed["gl_spl"] == 0.0 and math.isnan(failed["gl_time_to_goal"])
    assert failed["gl_human_collisions"] == 1 and failed["gl_collisions"] == 1
    assert not failed["gl_timeout"]  # a collision is not a timeout
    assert failed["gl_aggregated_time"] == 1.5  # the goal was still reached at 1.5 s


def test_timeout_needs_the_time_limit():
    # Five samples every 0.5 s: the log lasts 2 s, the goal is never reached, nothing is hit.
    kw = dict(dt=0.5, robot_pos=line(0, 1, 2, 3, 4), goal=FAR)
    assert episode_metrics(**kw)["gl_timeout"]  # no limit given: it ended with neither
    assert episode_metrics(time_limit=2.0, **kw)["gl_timeout"]
    assert not episode_metrics(time_limit=10.0, **kw)["gl_timeout"]  # cut short, not timed out
    found = episode_metrics(**kw)
    assert not found["gl_success"] and found["gl_spl"] == 0.0 and math.isnan(found["gl_aggregated_time"])


def test_people_gaps_personal_space_and_collisions():
    # The robot (radius 0.3) stands at the origin. Person A (radius 0.2) at x = 2, 1, 0.4, 2: gaps
    # |x| - 0.5 = 1.5, 0.5, -0.1, 1.5. Person B is present at samples 2 and 3 only, at y = 0.6 and
    # 0.45: gaps 0.1 and -0.05. Contacts: A at sample 2, B at sample 3 -> 2 collisions. Samples
    # complying with 0.5 m of personal space: 0 and 1 (a gap of exactly 0.5 complies) -> 2 / 4.
    people = np.array(
        [
            [[2.0, 0.0], [0.0, 0.0]],
            [[1.0, 0.0], [0.0, 0.0]],
            [[0.4, 0.0], [0.0, 0.6]],
            [[2.0, 0.0], [0.0, 0.45]],
        ]
    )
    mask = np.array([[True, False], [True, False], [True, True], [True, True]])
    kw = dict(dt=1.0, robot_pos=line(0, 0, 0, 0), goal=FAR, robot_radius=0.3, people_radius=0.2)
    found = episode_metrics(people_pos=people, people_mask=mask, **kw)
    assert found["gl_min_distance_to_human"] == pytest.approx(-0.1)
    assert found["gl_personal_space_compliance"] == 0.5
    assert found["gl_human_collisions"] == 2 and found["gl_collisions"] == 2
    assert found["gl_stalled_time"] == 3.0  # three steps standing still
    # Per-person radii: B of radius 0.0 -> its gaps 0.3 and 0.15, no contact: 1 collision.
    found = episode_metrics(people_pos=people, people_mask=mask, **{**kw, "people_radius": [0.2, 0.0]})
    assert found["gl_human_collisions"] == 1
    # A contact lasting several samples counts once; two separate contacts count twice.
    flags = np.array([True, True, False, True])
    assert episode_metrics(people_pos=people, human_contact=flags, **kw)["gl_human_collisions"] == 2
    # Nobody: no distance, full compliance, no time to collision.
    alone = episode_metrics(**kw)
    assert math.isnan(alone["gl_min_distance_to_human"]) and math.isnan(alone["gl_min_time_to_collision"])
    assert alone["gl_personal_space_compliance"] == 1.0


def test_time_to_collision_of_discs_at_constant_velocity():
    # Head on: 5 m apart, closing at 2 m/s, touching at 0.5 m: (5 - 0.5) / 2 = 2.25 s.
    assert time_to_collision(np.array([5.0, 0.0]), np.array([-2.0, 0.0]), np.array(0.5)) == 2.25
    # Offset by 0.3 m: |(5 - t, 0.3)| = 0.5 -> 5 - t = 0.4 -> t = 4.6 s.
    assert time_to_collision(np.array([5.0, 0.3]), np.array([-1.0, 0.0]), np.array(0.5)) == pytest.approx(4.6)
    # Offset by 0.6 m > 0.5: never; moving apart: never; overlapping already: 0.
    assert time_to_collision(np.array([5.0, 0.6]), np.array([-1.0, 0.0]), np.array(0.5)) == np.inf
    assert time_to_collision(np.array([5.0, 0.0]), np.array([1.0, 0.0]), np.array(0.5)) == np.inf
    assert time_to_collision(np.array([0.3, 0.0]), np.array([1.0, 0.0]), np.array(0.5)) == 0.0


def test_minimum_time_to_collision_over_the_episode():
    # The robot (0,0) -> (1,0) at 1 m/s, a person (5,0) -> (4,0) at 1 m/s towards it: at sample 0
    # they are 5 m apart, (5 - 0.5) / 2 = 2.25 s; at sample 1, 3 m: (3 - 0.5) / 2 = 1.25 s.
    robot, person = line(0, 1), line(5, 4)[:, None, :]
    kw = dict(dt=1.0, robot_pos=robot, goal=FAR, people_pos=person, robot_radius=0.3, people_radius=0.2)
    given = dict(robot_vel=[[1, 0], [1, 0]], people_vel=[[[-1, 0]], [[-1, 0]]])
    assert episode_metrics(**kw, **given)["gl_min_time_to_collision"] == 1.25
    # From positions: no velocity at sample 0 for the person, (-1, 0) at sample 1: 1.25 s again.
    assert episode_metrics(**kw)["gl_min_time_to_collision"] == 1.25
    # A person walking alongside never meets the robot.
    beside = line(0, 1, y=2.0)[:, None, :]
    assert episode_metrics(**{**kw, "people_pos": beside})["gl_min_time_to_collision"] == np.inf


def test_overlapping_discs_are_0_s_from_contact_without_velocities():
    # A log without velocities starts in contact (a collision at t = 0): the person overlaps the
    # robot at sample 0, where no velocity of theirs is known, then steps away. The time to
    # collision at an overlap is 0 whatever the velocities (it was inf, beside a negative gap).
    robot = line(0, 0.5, 1.0)
    person = line(0.3, 3.0, 3.0, y=3.0)[:, None, :]
    person[0, 0] = [0.3, 0.0]
    kw = dict(dt=0.5, robot_pos=robot, goal=FAR, people_pos=person, robot_radius=0.3, people_radius=0.2)
    found = episode_metrics(**kw)
    assert found["gl_min_distance_to_human"] == pytest.approx(-0.2)
    assert found["gl_human_collisions"] == 1 and found["gl_min_time_to_collision"] == 0.0
    # The same for a person who appears overlapping the robot later, with nothing before.
    mask = np.array([[False], [True], [True]])
    late = np.array([[[9.0, 9.0]], [[0.6, 0.0]], [[3.0, 3.0]]])
    found = episode_metrics(**{**kw, "people_pos": late, "people_mask": mask})
    assert found["gl_min_distance_to_human"] == pytest.approx(-0.4)
    assert found["gl_min_time_to_collision"] == 0.0
    # A person present at one sample only, apart: no time to collision (no velocity), as before.
    apart = np.array([[[9.0, 9.0]], [[3.0, 0.0]], [[9.0, 9.0]]])
    mask = np.array([[False], [True], [False]])
    assert math.isnan(
        episode_metrics(**{**kw, "people_pos": apart, "people_mask": mask})["gl_min_time_to_collision"]
    )


def test_clearing_distance_and_wall_collisions():
    # Walls y = 1 for x in [-1, 1] and x = 3 for y in [-5, 5]; the robot (radius 0.3) at (0,0),
    # (0,0.5), (0,0.8), (2,0.8): nearest wall distances 1, 0.5, 0.2, min(|(1,0.2)|, 1) = 1, so
    # clearances 0.7, 0.2, -0.1, 0.7: min -0.1, mean 1.5 / 4 = 0.375, one wall collision.
    walls = np.array([[-1, 1, 1, 1], [3, -5, 3, 5]], dtype=float)
    pos = np.array([[0, 0], [0, 0.5], [0, 0.8], [2, 0.8]])
    assert wall_distances(pos, walls) == pytest.approx([1.0, 0.5, 0.2, 1.0])
    found = episode_metrics(dt=1.0, robot_pos=pos, goal=FAR, walls=walls, robot_radius=0.3)
    assert found["gl_clearing_distance_min"] == pytest.approx(-0.1)
    assert found["gl_clearing_distance_avg"] == pytest.approx(0.375)
    assert found["gl_wall_collisions"] == 1 and found["gl_collisions"] == 1
    # Precomputed distances give the same; no walls: no clearing distance, no wall collision.
    same = episode_metrics(
        dt=1.0, robot_pos=pos, goal=FAR, wall_distance=[1.0, 0.5, 0.2, 1.0], robot_radius=0.3
    )
    assert same["gl_clearing_distance_avg"] == pytest.approx(0.375) and same["gl_wall_collisions"] == 1
    none = episode_metrics(dt=1.0, robot_pos=pos, goal=FAR)
    assert math.isnan(none["gl_clearing_distance_min"]) and none["gl_wall_collisions"] == 0


def test_failure_to_progress_and_stalled_time():
    # dt 1, a window of 2 s, 0.25 m of progress needed; the goal at x = 10, the robot at x = 0, 1,
    # 1, 1, 1, 2, 2, 2, 2: distances left 10, 9, 9, 9, 9, 8, 8, 8, 8. Windows (start, 2 more):
    # [10,9,9] progress; [9,9,9] none; [9,9,9] none; [9,9,8] progress; [9,8,8] progress; [8,8,8]
    # none; [8,8,8] none -> two stretches without progress. Speeds 1,0,0,0,1,0,0,0: 6 s stalled.
    params = GuidelineParams(progress_time=2.0, progress_distance=0.25)
    found = episode_metrics(params, dt=1.0, robot_pos=line(0, 1, 1, 1, 1, 2, 2, 2, 2), goal=[10, 0])
    assert found["gl_failure_to_progress"] == 2
    assert found["gl_stalled_time"] == 6.0
    # The default 10 s window does not fit in 8 s: no failure.
    assert (
        episode_metrics(dt=1.0, robot_pos=line(0, 1, 1, 1, 1, 2, 2, 2, 2), goal=[10, 0])[
            "gl_failure_to_progress"
        ]
        == 0
    )
    # Nor does a window of 1e308 s (`socialzoo metrics --progress-time 1e308`): its length in
    # samples, 1e308 / dt, overflowed to inf and round(inf) raised OverflowError.
    huge = GuidelineParams(progress_time=1e308)
    assert episode_metrics(huge, dt=0.5, robot_pos=line(0, 1, 1), goal=[10, 0])["gl_failure_to_progress"] == 0
    # Progress measured along a given route distance: 10, 9.9, 9.8, ... falls 0.2 per 2 s < 0.25.
    left = 10 - 0.1 * np.arange(9)
    found = episode_metrics(params, dt=1.0, robot_pos=line(*range(9)), goal=[10, 0], goal_distance=left)
    assert found["gl_failure_to_progress"] == 1


def test_other_robots_collisions_and_aggregated_time():
    # The robot reaches its goal (2,0) at sample 2 (dt 1). Other robot A keeps away and reaches its
    # goal (0,5) at sample 4; other robot B (no goal: outside the cooperative set) is 0.5 m beside
    # the robot at samples 0, 1 and 3 (gap 0.5 - 0.3 - 0.3 = -0.1: contact). AT = max(2, 4) = 4 s.
    robot = line(0, 1, 2, 2, 2)
    a = np.array([[0, 9], [0, 8], [0, 7], [0, 6], [0, 5]], dtype=float)
    b = np.array([[0, 0.5], [1, 0.5], [5, 5], [2, 0.5], [5, 5]], dtype=float)
    others = np.stack([a, b], axis=1)
    goals = np.array([[0, 5], [np.nan, np.nan]])
    kw = dict(dt=1.0, robot_pos=robot, goal=[2, 0], others_pos=others, others_goal=goals)
    found = episode_metrics(**kw)
    # B overlaps at samples 0 and 1 (one contact), not at 2; sample 3 is after the robot's goal.
    assert found["gl_robot_collisions"] == 1 and found["gl_collisions"] == 1 and not found["gl_success"]
    assert found["gl_aggregated_time"] == 4.0
    # A never reaching its goal: no aggregated time.
    never = episode_metrics(**{**kw, "others_goal": np.array([[0, -5], [np.nan, np.nan]])})
    assert math.isnan(never["gl_aggregated_time"])


def test_contact_flags_count_without_the_bodies_positions():
    # A simulator that logs its contact flags but not the people (or the other robots) still had
    # those contacts: the robot touches someone at samples 1-2 and another robot at sample 3 of its
    # way to (3, 0): two collisions and no success, as with the bodies' positions given.
    kw = dict(dt=1.0, robot_pos=line(0, 1, 2, 3), goal=[3, 0])
    human = np.array([False, True, True, False])
    found = episode_metrics(human_contact=human, **kw)
    assert found["gl_human_collisions"] == 1 and found["gl_collisions"] == 1 and not found["gl_success"]
    assert math.isnan(found["gl_time_to_goal"])
    robot = np.array([False, False, False, True])
    found = episode_metrics(robot_contact=robot, **kw)
    assert found["gl_robot_collisions"] == 1 and not found["gl_success"]
    assert episode_metrics(**kw)["gl_success"]


def test_a_batch_is_its_episodes_one_by_one():
    # Two episodes of 5 and 3 samples padded to 5 give what each gives alone.
    rng = np.random.default_rng(0)
    pos = rng.normal(size=(2, 5, 2)).cumsum(axis=1)
    people = rng.normal(size=(2, 5, 3, 2)) * 2
    walls = np.array([[-5, -5, 5, -5], [-5, 5, 5, 5]], dtype=float)
    batch = guideline_metrics(
        Trajectories(
            dt=0.25, robot_pos=pos, goal=[[3, 3], [0, 0]], length=[5, 3], people_pos=people, walls=walls
        )
    )
    for i, n in enumerate((5, 3)):
        alone = episode_metrics(
            dt=0.25, robot_pos=pos[i, :n], goal=[[3, 3], [0, 0]][i], people_pos=people[i, :n], walls=walls
        )
        for name, value in alone.items():
            assert batch[name][i] == pytest.approx(value, nan_ok=True), name


def test_bad_arrays_and_params_are_named_errors():
    with pytest.raises(ValueError, match="dt must be a number > 0"):
        episode_metrics(dt=0.0, robot_pos=line(0, 1), goal=FAR)
    with pytest.raises(ValueError, match=r"robot_pos must have shape \(B, N, 2\)"):
        guideline_metrics(Trajectories(dt=1.0, robot_pos=np.zeros((1, 3)), goal=[FAR]))
    with pytest.raises(ValueError, match="people_pos must have shape"):
        episode_metrics(dt=1.0, robot_pos=line(0, 1), goal=FAR, people_pos=np.zeros((2, 2)))
    with pytest.raises(ValueError, match="length must be"):
        guideline_metrics(Trajectories(dt=1.0, robot_pos=np.zeros((1, 3, 2)), goal=[FAR], length=[4]))
    with pytest.raises(ValueError, match=r"GuidelineParams\.progress_time must be > 0"):
        GuidelineParams(progress_time=0.0)
    with pytest.raises(ValueError, match=r"GuidelineParams\.personal_space must be a finite number"):
        GuidelineParams(personal_space=float("nan"))
