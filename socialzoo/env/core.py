"""The batched core below every task: B rows of R robots and H person slots in one WorldState, stepped through the
one world step (socialzoo.env.world.step_world)."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from socialzoo.core.config import WorldConfig
from socialzoo.core.robot import world_velocity
from socialzoo.core.state import WorldState
from socialzoo.core.validation import check_int
from socialzoo.core.walls import WallIndex
from socialzoo.env.people import People
from socialzoo.env.replay import ReplayRunner
from socialzoo.env.script import ScriptRunner
from socialzoo.env.world import StepEvents, robot_human_contacts, step_world
from socialzoo.humans.models import PeopleConfig
from socialzoo.maps.map_file import Map
from socialzoo.nav.distance_field import DistanceField, distance_field
from socialzoo.nav.graph import graph_of
from socialzoo.nav.local_planner import LocalPlannerConfig
from socialzoo.nav.navigator import Navigator, Sight
from socialzoo.nav.recovery import RecoveryConfig
from socialzoo.nav.sight_cache import SightCache
from socialzoo.scenarios.scenario import Scenario
from socialzoo.scenarios.start_state import StartStore, scenarios_to_state


class BatchedCore:
    """B rows of R robots and H person slots, stepped together.

    The core is task-agnostic: it holds the world (the state, the walls, the map), the people and the
    model that drives each (socialzoo.env.people, the learned people the env drives included), the
    robots' navigator on the map's graph (plans, carrots, route left) and their sight (who each robot
    sees, kept from step to step); it resets rows from scenarios and advances the world one step given
    the robots' commands. What a step means belongs to the task (socialzoo.env.tasks): how an action
    becomes a command, the observation, the reward, the episode's end and its metrics. A task reads
    the world's facts here (the step's collision events, goal distances, who is seen) and tells the
    core whose episode ended (`end_episodes`): those robots stand still, exactly where they stopped,
    until their row is reset. Per-robot arrays are (B, R); flat ones are (B R, ...), row-major: robot r
    of row b is b * R + r.

    Args:
        batch_size: B.
        num_robots: R.
        max_humans: H.
        world: the world's parameters (robot, people, collision distance, dt).
        walls: the wall index (an empty one for an open arena).
        m: the map, where there is one (the navigator's graph; walking groups' routes).
        people: the models that drive the people (default: social force only).
        planner: with a planner config, a navigator on the map's graph plans each robot's route
            and keeps its carrot in sight of the planner's wall distance; None: no navigator.
        recovery: the navigator's recovery of robots that make no progress; None: none.
        sight_lines: sight lines hide people behind walls (`see`; needs a planner); without
            them every present person is seen.
        robot_visible: whether the people see and avoid the robots.
        contacts_in_step: the recorded people's contacts with a robot (people_walked_into_robot) are
            the CrowdNav task's, judged during a step, not the world's at its end (ReplayRunner).

    Raises:
        ValueError: a batch size that is not an int >= 1.
        PolicyFileError: the learned people's file is not a learned human policy file.
    """

    def __init__(
        self,
        batch_size: int,
        num_robots: int,
        max_humans: int,
        world: WorldConfig,
        walls: WallIndex,
        *,
        m: Map | None = None,
        people: PeopleConfig | None = None,
        planner: LocalPlannerConfig | None = None,
        recovery: RecoveryConfig | None = None,
        sight_lines: bool = False,
        robot_visible: bool = True,
        contacts_in_step: bool = False,
    ) -> None:
        check_int("BatchedCore", "batch_size", batch_size, low=1)
        b, r = batch_size, num_robots
        people = people or PeopleConfig()
        self.batch_size, self.num_robots, self.max_humans = b, r, max_humans
        self.world, self.walls, self.map = world, walls, m
        self.planner, self.robot_visible = planner, robot_visible
        self.people = People(people, world, b, r, max_humans, walls, m, robot_visible)
        # The world its people walk in: a preset's parameters, a learned policy file's dynamics (People.world).
        self.world = world = self.people.world
        robot = world.robot
        door_reach = robot.radius if robot.radius is not None else robot.half_width
        # Who waits, signals or follows a robot, whom each robot escorts, doors (socialzoo.env.script).
        self.script = ScriptRunner(b, r, max_humans, world.dt, float(door_reach))
        # Recorded people: tracks, hybrid people's reactions, the measures against the recording
        # (socialzoo.env.replay).
        self.replay = ReplayRunner(
            self.people.config,
            b,
            r,
            max_humans,
            world.dt,
            world.human_collision_distance,
            robot_visible=robot_visible,
            contacts_in_step=contacts_in_step,
        )
        self.field: DistanceField | None = None
        self.navigator: Navigator | None = None
        if planner is not None:
            assert m is not None, "a navigator plans on a map's graph"
            # The map's wall distance field (cached per map, as its graph) keeps carrots in sight
            # of the planner's wall distance and clears sight lines far from walls.
            self.field = distance_field(
                m.wall_index, planner.field_resolution, planner.field_range, planner.field_pad
            )
            sight = Sight(self.field, planner.wall_distance)
            self.navigator = Navigator(graph_of(m), b, r, sight=sight, recovery=recovery)
        # Sight lines are re-tested only when they may have changed since the last step.
        self.sight = (
            SightCache(walls, self.field, b * r, max_humans)
            if sight_lines and self.field is not None and walls.num_walls
            else None
        )
        self.state: WorldState | None = None
        # The state before the latest step.
        self.before: WorldState | None = None
        self.carrot = np.zeros((b, r, 2))
        self.visible = np.zeros((b * r, max_humans), dtype=bool)
        self.done = np.zeros((b, r), dtype=bool)
        self.scenarios: list[Scenario | None] = [None] * b
        # The starts of the scenarios the rows are reset from again and again (a recorded scene's).
        self.starts = StartStore(r, max_humans)
        self._ever_reset = np.zeros(b, dtype=bool)
        # For each robot, the other robots of its row.
        self._others = np.array([[j for j in range(r) if j != k] for k in range(r)], dtype=np.intp).reshape(
            r, r - 1
        )

    # ------------------------------------------------------------------ reset
    def check_rows(self, rows: np.ndarray | Sequence[int], count: int) -> np.ndarray:
        """`rows` as an index array, refused (ValueError) unless one per scenario and in 0..B-1."""
        rows = np.asarray(rows, dtype=np.intp).reshape(-1)
        if len(rows) != count:
            raise ValueError(f"reset_rows got {len(rows)} rows but {count} scenarios")
        if ((rows < 0) | (rows >= self.batch_size)).any():
            raise ValueError(f"reset_rows: rows {rows.tolist()} outside 0..{self.batch_size - 1}")
        return rows

    def robot_rows(self, rows: np.ndarray) -> np.ndarray:
        """The flat robot indices (row * R + robot) of `rows`."""
        if self.num_robots == 1:  # each row's one robot: its flat index is the row (a reset asks often)
            return np.array(rows, dtype=np.intp).reshape(-1)
        return (np.asarray(rows)[:, None] * self.num_robots + np.arange(self.num_robots)).reshape(-1)

    def reset_rows(self, rows: np.ndarray | Sequence[int], scenarios: Sequence[Scenario]) -> np.ndarray:
        """Start new episodes in `rows` from `scenarios` (one per row), their people driven by the
        models the people config assigns from each scenario's seed (walking groups formed). Returns
        the rows as the index array check_rows makes of them."""
        rows = self.check_rows(rows, len(scenarios))
        if len(rows) == 0:
            return rows
        scenarios, kinds = self.people.prepare(list(scenarios))
        models = self.people.models_of(kinds)
        if self.state is None:
            # Rows not reset yet hold the first row's start (a step needs every row reset first).
            first = scenarios_to_state(scenarios[:1], self.num_robots, self.max_humans)
            first.human_model[:] = models[:1]
            self.state = WorldState.concatenate([first] * self.batch_size)
        self.starts.write(self.state, rows, scenarios)  # the route axis widens for a longer route
        self.state.human_model[rows] = models
        self.start_rows(rows, scenarios, kinds)
        return rows

    def start_rows(
        self, rows: np.ndarray, scenarios: Sequence[Scenario | None], kinds: np.ndarray | None = None
    ) -> None:
        """Start new episodes in `rows` whose state is written (by `reset_rows`, or by a task's own
        faster writer: CrowdNav's arena cases, with None for their scenarios): the people's
        bookkeeping, the robots' plans and carrots, their sight lines and done flags. kinds: (len(rows),
        H) each slot's index into the people spec's parts (People.kinds) where the caller drew them."""
        state = self.state
        assert state is not None
        for row, scenario in zip(rows.tolist(), scenarios, strict=True):
            self.scenarios[row] = scenario
        self._ever_reset[rows] = True
        self.done[rows] = False
        self.people.reset(rows, state)
        self.script.reset(rows, scenarios, state)
        if self.replay.wanted(scenarios):
            if kinds is None:
                counts = [0 if s is None else s.num_humans for s in scenarios]
                kinds = self.people.kinds([0 if s is None else s.seed for s in scenarios], counts)
            self.replay.reset(rows, scenarios, state, kinds)
        else:
            self.replay.release(rows)
        if self.navigator is not None:
            self.navigator.reset(rows, state.robot_pose[rows][..., :2], state.robot_goal[rows][..., :2])
            self.carrot[rows] = self.navigator.update(state.robot_pose[..., :2])[rows]
        if self.sight is not None:
            self.sight.forget(self.robot_rows(rows))

    # ------------------------------------------------------------------ step
    def check_reset(self) -> None:
        """Raise RuntimeError unless every row has been reset."""
        if self.state is None or not self._ever_reset.all():
            raise RuntimeError("reset every row (reset_rows) before calling step")

    def step(
        self,
        command: np.ndarray,
        halt: np.ndarray | None = None,
        desired: np.ndarray | None = None,
        learned: np.ndarray | None = None,
    ) -> StepEvents:
        """Advance every row one world step (world.dt); `state` is then the world after it.

        Args:
            command: (B, R, 2) robot commands (socialzoo.env.world.step_world).
            halt: (B, R) robots stopped at once (default none). Robots whose episode ended halt
                anyway and stay exactly where they stopped.
            desired: (B, H, 2) desired velocities of people a task's learners drive, m/s, or None.
            learned: (B, H) the people `desired` drives, or None.

        Returns:
            The step's collision events.

        Raises:
            RuntimeError: a row was never reset.
        """
        self.check_reset()
        before = self.state
        assert before is not None
        desired, learned = self.people.drive(before, desired, learned)
        done = self.done if self.done.any() else None
        if done is not None:
            halt = done if halt is None else halt | done
            command = np.where(done[..., None], 0.0, command)
        scripted = self.script.active
        replayed = self.replay.active  # read once: each read scans the rows
        stepping = before
        if scripted:
            speeds = self.script.speeds(before)
            if speeds is not before.human_pref_speed:
                stepping = dataclasses.replace(before, human_pref_speed=speeds)
        after, events = step_world(
            stepping, self.walls, self.world, command, halt, desired, learned, self.robot_visible,
            sparse_people=replayed, human_contacts=not replayed,
        )  # fmt: skip
        if scripted:
            at_door = self.script.settle(before, after)
            if at_door.any():
                events = dataclasses.replace(events, robot_wall=events.robot_wall | at_door)
        if done is not None:
            # The halting step's motion model would still carry a differential robot half a step.
            after.robot_pose = np.where(done[..., None], before.robot_pose, after.robot_pose)
        if replayed:
            robot_vel = world_velocity(after.robot_pose, after.robot_vel, self.world.robot)
            self.replay.settle(after, robot_vel)
            # Contacts with the people where the recording put them.
            events = dataclasses.replace(events, robot_human=robot_human_contacts(after, self.world))
            self.replay.account(before, after, robot_vel, self.done)
        self.before, self.state = before, after
        return events

    def follow_routes(self, moving: np.ndarray | None = None) -> None:
        """Each robot's carrot on its plan after a step (a robot that strayed is replanned); with
        `moving` (B, R), the robots that drove their plan this step, the recovery watches them."""
        assert self.navigator is not None and self.state is not None
        s = self.state
        if moving is None:
            self.carrot = self.navigator.update(s.robot_pose[..., :2])
        else:
            self.carrot = self.navigator.update(
                s.robot_pose[..., :2], moving, self.world.dt, s.human_pos, s.human_mask
            )

    def end_episodes(self, ended: np.ndarray) -> None:
        """Mark the robots (B, R) whose episode ended on the latest step: they stand still until their
        row is reset. The people's bookkeeping (group intrusions, counterfactual rows) counts the step."""
        assert self.before is not None and self.state is not None
        was_done = self.done
        self.done = self.done | ended
        self.people.step(self.before, self.state, was_done, self.done)

    # ------------------------------------------------------------------ world facts
    def per_robot(self, array: np.ndarray) -> np.ndarray:
        """A per-row array (B, ...) once for each robot: (B R, ...) (the array itself when R = 1)."""
        return np.repeat(array, self.num_robots, axis=0) if self.num_robots > 1 else array

    def see(self) -> np.ndarray:
        """(B R, H) the people each robot sees now (kept as `visible`): every present person, less
        those behind a wall with sight lines."""
        s = self.state
        assert s is not None
        mask = self.per_robot(s.human_mask)
        if self.sight is None:
            self.visible = np.array(mask, dtype=bool)
        else:
            pos = s.robot_pose[..., :2].reshape(-1, 2)
            self.visible = self.sight.visible(pos, self.per_robot(s.human_pos), mask)
        return self.visible

    def others(
        self, s: WorldState, robot_vel: np.ndarray | None = None, rows: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(pos, vel, mask) of who each robot keeps clear of in the state `s` (B rows; with `rows`, an
        index array, those rows only): the people, then the other robots at `robot_vel` (B, R, 2),
        or (len(rows), R, 2) (default: their velocity in `s`), (B R, H + R - 1, ...) with each
        robot's own slot left out; the people's (B, H, ...) when R = 1."""
        # A reset's few rows: only the arrays read here are taken, not a sub-state of every field.
        pos, vel, mask = (
            (s.human_pos, s.human_vel, s.human_mask)
            if rows is None
            else (s.human_pos.take(rows, 0), s.human_vel.take(rows, 0), s.human_mask.take(rows, 0))
        )
        b, r = len(mask), self.num_robots
        if r == 1:
            return pos, vel, mask
        robot_pose = s.robot_pose if rows is None else s.robot_pose.take(rows, 0)
        if robot_vel is None:
            own = s.robot_vel if rows is None else s.robot_vel.take(rows, 0)
            robot_vel = world_velocity(robot_pose, own, self.world.robot)
        others = self._others
        pos = np.concatenate((np.repeat(pos[:, None], r, 1), robot_pose[:, others, :2]), 2)
        vel = np.concatenate((np.repeat(vel[:, None], r, 1), robot_vel[:, others]), 2)
        mask = np.concatenate((np.repeat(mask[:, None], r, 1), np.ones((b, r, r - 1), dtype=bool)), 2)
        return pos.reshape(b * r, -1, 2), vel.reshape(b * r, -1, 2), mask.reshape(b * r, -1)

    def escort_ok(self) -> np.ndarray:
        """(B, R) whether each robot's goal may count as reached now: the person it escorts (if any)
        is in its place and was kept there all the way (socialzoo.scenarios.script.Script)."""
        assert self.state is not None
        return self.script.escort_ok(self.state)

    @property
    def time_limit(self) -> np.ndarray:
        """(B,) each row's own time budget, s (a recorded scene's; inf: the task's)."""
        return self.replay.time_limit

    def goal_distance(self) -> np.ndarray:
        """(B, R) each robot's straight distance to its goal, m."""
        assert self.state is not None
        pos, goal = self.state.robot_pose[..., :2], self.state.robot_goal[..., :2]
        return np.hypot(goal[..., 0] - pos[..., 0], goal[..., 1] - pos[..., 1])

    @property
    def route_left(self) -> np.ndarray:
        """(B, R) each robot's route length left at its latest carrot, m (the navigator's)."""
        assert self.navigator is not None
        return self.navigator.route_left

    def seen_goal(self) -> tuple[np.ndarray, np.ndarray]:
        """((B, R, 2) the goal each robot heads for, (B, R) its distance, m): with a navigator the
        route's carrot and the route's length left, else the goal itself and its straight distance."""
        assert self.state is not None
        if self.navigator is not None:
            return self.carrot, self.route_left
        return self.state.robot_goal[..., :2], self.goal_distance()
