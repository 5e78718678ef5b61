"""The CrowdNav velocity task (Chen et al. 2019, vita-epfl/CrowdNav) and its variants on the batched core, with
CrowdNav's settings as the defaults (socialzoo.env.crowd_config.CrowdNavConfig; docs/crowdnav.md)."""

from __future__ import annotations

import math
from typing import Any, ClassVar, cast

import numpy as np

from socialzoo.core.jit import kernel
from socialzoo.core.robot import world_velocity
from socialzoo.core.state import WorldState
from socialzoo.core.walls import WallIndex
from socialzoo.env.core import BatchedCore
from socialzoo.env.crowd_actions import action_space, discrete_actions, turn_rows, velocity_commands
from socialzoo.env.crowd_config import CrowdNavConfig, resolve_config
from socialzoo.env.crowd_observation import (
    JointState,
    joint_state,
    nearest_people,
    observation_space,
    with_signals,
)
from socialzoo.env.crowd_outcome import CrowdNavMetrics, CrowdOutcome, judge_step, track_approach
from socialzoo.env.crowd_source import CrowdCaseSource, write_cases
from socialzoo.env.observation import nearest_door
from socialzoo.env.outcome import STILL_SPEED
from socialzoo.env.reward import RewardConfig, force_and_blame
from socialzoo.env.tasks.base import Task, TaskStep, batch_actions, fixed_cases
from socialzoo.maps.map_file import load_map
from socialzoo.nav.local_planner import LocalPlannerConfig
from socialzoo.scenarios.crowd_cases import CrowdCase, case_scenario
from socialzoo.scenarios.scenario import Scenario

# The per-step info of a robot: its closest approach to anyone during the step (m, negative: an
# overlap), the benchmark's social force and blame terms after it, whether it collided with a person
# (or another robot) or with a wall; at reset nothing approached or touched yet.
INITIAL_INFO: dict[str, Any] = {
    "closest": float("inf"),
    "force": 0.0,
    "blame": 0.0,
    "human_collisions": 0,
    "wall_collision": False,
}
# CrowdNav's people cover their last metre in about a second: their preferred speed is the distance
# to the goal per this time, capped at their preferred speed (s).
_ARRIVAL_TIME = 1.0


class CrowdNavTask(Task):
    """The CrowdNav task over B rows of R robots.

    A robot chooses its velocity (or one of CrowdNav's 81 actions) every 0.25 s to cross an open arena,
    a building among the benchmark's people (the Walls variant), or a scenario family's map among its
    scripted people (CrowdNavConfig.family: the guidelines' suite, socialzoo/CrowdNavSuite-v2). The task
    turns each action into the robot's command, advances the core `physics_substeps` world steps per
    decision, judges the step as CrowdNav judges it (socialzoo.env.crowd_outcome: the closest approach
    along every substep, the goal, the time limit), accumulates the episode metrics and builds each
    robot's joint-state observation (socialzoo.env.crowd_observation; with CrowdNavConfig.signals also
    each person's gesture and the nearest door). Training episodes are CrowdNav's training cases drawn
    per row (socialzoo.env.crowd_source); `reset` options {"split": "val"|"test", "case": k} or
    {"cases": [...]} play fixed cases (case_splits).

    CrowdNav's task has one robot (R = 1); with several, each robot sees the others as people, a robot
    whose episode ended stands still where it is, and the row's episode lasts until every robot's has
    ended. Per-robot arrays are flat over (B, R), row-major: robot r of row b is entry b * R + r.

    Args:
        config: a CrowdNavConfig (default CrowdNav's task).
        batch_size: B.
        **overrides: CrowdNavConfig fields as plain values, or variant=NAME.
    """

    name: ClassVar[str] = "crowdnav"
    render_fps: ClassVar[int] = 4
    render_modes: ClassVar[tuple[str, ...]] = ("human", "rgb_array")
    reset_info_key: ClassVar[str] = "case_seed"
    neutral_info: ClassVar[dict[str, Any]] = INITIAL_INFO

    def __init__(self, config: CrowdNavConfig | None = None, batch_size: int = 1, **overrides: Any) -> None:
        self.config = cfg = resolve_config(config, overrides)
        m = load_map(cfg.map) if cfg.map is not None else None
        # Among walls the robot is guided along its route (the benchmark robot's navigator, without
        # recovery: the learner drives): it sees the route's carrot as its goal and the route left
        # as its goal distance.
        self.core = BatchedCore(
            batch_size,
            cfg.num_robots,
            cfg.slots,
            cfg.world,
            WallIndex(np.zeros((0, 4))) if m is None else m.wall_index,
            m=m,
            people=cfg.people,
            planner=LocalPlannerConfig() if m is not None else None,
            robot_visible=cfg.robot_visible,
            contacts_in_step=True,  # the recorded measures' contacts are the judgement's
        )
        self.source = CrowdCaseSource(cfg, batch_size)
        self.batch_size = batch_size
        self.num_robots = r = cfg.num_robots
        self.num_human_slots = cfg.slots
        self.observation_space = observation_space(cfg)
        self.action_space = action_space(cfg)
        self.action_table = np.array(discrete_actions(cfg.robot)) if cfg.action == "discrete" else None
        self._ray_angles = np.linspace(0.0, 2.0 * np.pi, cfg.wall_rays, endpoint=False)
        self._ray_directions = np.stack((np.cos(self._ray_angles), np.sin(self._ray_angles)), axis=-1)
        # Observation slots: the people, then the other robots (each robot's own slot left out).
        radius = float(cfg.robot.radius)  # type: ignore[arg-type]
        slot_radius = np.concatenate((np.full(cfg.slots, cfg.cases.human_radius), np.full(r - 1, radius)))
        self.radius_sum = radius + slot_radius
        self._radius_sum_rows = np.broadcast_to(self.radius_sum, (batch_size * r, len(slot_radius)))
        # Every robot's slot radii, as one array: the observations of any rows read a prefix of it.
        self._slot_radius_rows = np.tile(slot_radius, (batch_size * r, 1))
        self._blame_horizon = RewardConfig().blame_horizon
        # (B R,) the angle of each robot's observation frame (x towards the goal it sees), rad:
        # goal-frame velocity actions are turned by it into the world frame.
        self.frame_angle = np.zeros(batch_size * r)
        self.time = np.zeros(batch_size)
        self.case_seed = np.zeros(batch_size, dtype=np.uint64)  # benchmark scenario seeds use all 64 bits
        self.metrics = CrowdNavMetrics(batch_size * r, cfg.time_step, cfg.preferred_speed, cfg.reward)
        self.observation: JointState | None = None
        # Metrics of the robots whose episode ended, by flat index (row * R + robot).
        self._ended: dict[int, dict[str, Any]] = {}

    # ------------------------------------------------------------------ episodes
    def seed(self, seed: int | None, rows: np.ndarray | None = None) -> None:
        """Reseed the training streams of `rows` (default all; CrowdNav's training split only)."""
        self.source.seed(seed, rows)

    def reset(self, rows: np.ndarray, options: dict[str, Any]) -> np.ndarray:
        """Start the rows on their next training cases, or on fixed validation or test cases."""
        rows = np.asarray(rows, dtype=np.intp)
        # An autoreset passes no options: the split sizes (a recorded scene's split of its tracks)
        # are looked up only when options may name fixed cases.
        chosen = fixed_cases(dict(options), rows, self.case_splits(), self.name) if options else None
        if chosen is not None:
            cases: list[Scenario] | list[CrowdCase] = self.source.fixed(chosen[0], chosen[1])  # type: ignore[arg-type]
        else:
            cases = self.source.next(rows)
        self.reset_rows(rows, cases)
        for k in self.core.robot_rows(rows).tolist():
            self._ended.pop(k, None)
        return self.case_seed[rows].copy()

    def reset_rows(self, rows: np.ndarray, cases: list[Scenario] | list[CrowdCase]) -> None:
        """Start new episodes in `rows` from `cases` (one per row: Scenarios, or the arena's
        CrowdCases, written straight into the state once it exists)."""
        core = self.core
        seeds = [c.seed for c in cases]
        if len(cases) and isinstance(cases[0], CrowdCase) and core.state is not None:
            rows = core.check_rows(rows, len(cases))  # core.reset_rows checks them on the other path
            n = cases[0].human_starts.shape[0]
            models = core.people.models(seeds, [n] * len(cases))
            write_cases(core.state, rows, cases, self.config.cases.human_speed, models)  # type: ignore[arg-type]
            core.start_rows(rows, [None] * len(rows))
        else:
            if len(cases) and isinstance(cases[0], CrowdCase):
                cases = [case_scenario(c, self.config.cases) for c in cases]  # type: ignore[arg-type]
            rows = core.reset_rows(rows, cases)  # type: ignore[arg-type]
        self.case_seed[rows] = seeds
        self.time[rows] = 0.0
        self.metrics.reset_rows(core.robot_rows(rows))
        if self.observation is None or len(rows) == self.batch_size:
            self.observation = self._observe()
        else:
            # Only the reset rows' robots see anything new.
            fresh = self._observe(rows)
            robots = core.robot_rows(rows)
            self.observation.buffer[robots] = fresh.buffer
            self.observation.mask[robots] = fresh.mask

    def case_splits(self) -> dict[str, int]:
        """CrowdNav's validation and test cases (100 and 500); among walls the map's validation
        scenarios and its registered test set; with a scenario family the family's own "val" and
        "test" splits (socialzoo.env.crowd_source.CrowdCaseSource.case_splits)."""
        return self.source.case_splits()

    def step(self, action: np.ndarray, human_action: np.ndarray | None = None) -> TaskStep:
        """One decision step: the actions become commands, the world advances `physics_substeps`
        steps, and each robot's step is judged as CrowdNav judges it (socialzoo.env.crowd_outcome:
        the closest approach along every substep, the goal, the time limit; a wall contact is a
        collision). Robots whose episode ended stand still until their row is reset."""
        if human_action is not None:
            raise ValueError(
                f"{self.name}: the task has no learned-human agents, but human actions were given"
            )
        core, cfg = self.core, self.config
        core.check_reset()
        command = self.commands(action)
        b, r = self.batch_size, self.num_robots
        closest = np.full(b * r, np.inf)
        wall = np.zeros(b * r, dtype=bool)
        moved = np.zeros(b * r)
        dt = cfg.physics_dt
        for _ in range(cfg.physics_substeps):
            before = core.state
            assert before is not None
            if cfg.map is None and cfg.family is None:
                self._arrive(before)
            events = core.step(command)
            after = core.state
            assert after is not None
            robot_before = before.robot_pose[..., :2].reshape(b * r, 2)
            robot_after = after.robot_pose[..., :2].reshape(b * r, 2)
            # The other robots move at their velocity through the step (none with one robot).
            others_vel = (robot_after - robot_before).reshape(b, r, 2) / dt if r > 1 else None
            pos, vel, mask = core.others(before, others_vel)
            track_approach(
                closest, moved, robot_before, robot_after, pos, vel, self._radius_sum_rows, mask, dt
            )
            wall |= events.robot_wall.reshape(b * r)
        if core.navigator is not None:
            core.follow_routes()
        # A wall contact is a collision of the task (CrowdNav's arena has none).
        np.minimum(closest, -1e-9, out=closest, where=wall)
        goal_distance = core.goal_distance()
        if core.script.active:  # a robot escorting a person arrives only with that person
            goal_distance = np.where(core.escort_ok(), goal_distance, np.inf)
        outcome = judge_step(
            closest,
            goal_distance.reshape(b * r),
            float(cfg.robot.radius),  # type: ignore[arg-type]
            core.per_robot(self.time),
            np.minimum(cfg.time_limit, core.per_robot(core.time_limit)),
            cfg.reward,
            cfg.time_step,
            core.done.reshape(b * r),
        )
        self.time += cfg.time_step
        # The step's social force and blame terms per robot (the viewer draws them).
        force, blame = self._force_and_blame()
        self.metrics.update(outcome, moved, force, blame)
        over = outcome.terminated | outcome.truncated
        ended = np.flatnonzero(over)
        summaries = self.metrics.summaries(ended, outcome) if len(ended) else []
        for k, summary in zip(ended.tolist(), summaries, strict=True):
            summary["wall_collision"] = float(wall[k] and outcome.collision[k])
            self._ended[k] = summary
        if core.replay.active and len(ended):  # against the recording (socialzoo.env.replay)
            arrival = [summary["navigation_time"] for summary in summaries]
            for summary, extra in zip(
                summaries, core.replay.summaries(ended // r, arrival, ended % r), strict=True
            ):
                summary.update(extra)
        core.end_episodes(over.reshape(b, r))
        self.observation = self._observe()
        wall_collision = wall & outcome.collision
        truncated = outcome.truncated.reshape(b, r)
        return TaskStep(
            reward=outcome.reward.reshape(b, r),
            terminated=outcome.terminated.reshape(b, r),
            truncated=truncated,
            info={
                "closest": outcome.closest.reshape(b, r),
                "force": force.reshape(b, r),
                "blame": blame.reshape(b, r),
                "human_collisions": (outcome.collision & ~wall_collision).astype(np.int64).reshape(b, r),
                "wall_collision": wall_collision.reshape(b, r),
            },
            time_up=cast(np.ndarray, truncated.any(axis=1)),  # (B,): numpy's stub allows a scalar
        )

    def commands(self, action: np.ndarray) -> np.ndarray:
        """(B, R, 2) robot commands of the actions, checked before anything changes. Actions are
        (B, R, 2) velocities or (B, R) indices; with one robot also (B, 2) or (B,).

        Raises:
            ValueError: a wrong shape, a NaN or infinite value, a velocity outside [-1, 1], or an
                index outside the discrete actions (socialzoo.env.tasks.base.batch_actions); the
                message names the row and the robot.
        """
        b, r = self.batch_size, self.num_robots
        action = np.asarray(action)
        robot = self.config.robot
        if self.action_table is not None:
            shaped = action.reshape(b, r) if action.size == b * r else action
            index = batch_actions(self.action_space, shaped, (b, r), "CrowdNav")
            chosen = self.action_table[index.reshape(-1)]
            if robot.kinematics == "unicycle":  # (speed, turn per step) -> (v, omega)
                chosen = np.stack((chosen[:, 0], chosen[:, 1] / self.config.time_step), axis=-1)
            else:
                chosen = self._to_world(chosen)
            return chosen.reshape(b, r, 2)
        if action.shape not in ((b, r, 2),) + (((b, 2),) if r == 1 else ()):
            raise ValueError(
                f"CrowdNav: velocity actions must have shape {(b, r, 2)}, got {np.shape(action)}"
            )
        action = np.asarray(action, dtype=np.float64).reshape(b * r, 2)
        unicycle = robot.kinematics == "unicycle"
        command = np.empty((b * r, 2))
        k = velocity_commands(
            action, unicycle, self.config.preferred_speed, robot.max_rotation, self.config.time_step, command
        )
        if k >= 0:
            row, robot_index = divmod(k, r)
            raise ValueError(
                f"CrowdNav: velocity action {action[k].tolist()} of row {row}'s robot {robot_index} "
                "is not finite in [-1, 1]"
            )
        return (command if unicycle else self._to_world(command)).reshape(b, r, 2)

    def _to_world(self, velocity: np.ndarray) -> np.ndarray:
        """(B R, 2) holonomic velocities in the action frame -> the world frame."""
        return velocity if self.config.action_frame == "world" else self._turn(velocity, 1.0)

    def to_action_frame(self, velocity: np.ndarray) -> np.ndarray:
        """(B, R, 2) world-frame velocities -> the frame of the robots' velocity actions."""
        if self.config.action_frame == "world":
            return velocity
        b, r = velocity.shape[:2]
        return self._turn(velocity.reshape(b * r, 2), -1.0).reshape(b, r, 2)

    def _turn(self, velocity: np.ndarray, sign: float) -> np.ndarray:
        """(B R, 2) velocities turned by `sign` times each robot's frame angle."""
        out = np.empty(velocity.shape)
        turn_rows(velocity, np.cos(self.frame_angle), np.sin(self.frame_angle), sign, out)
        return out

    def _arrive(self, s: WorldState) -> None:
        """CrowdNav's people slow down on their last metre and stop at their goal: the preferred
        velocity is the goal's offset per second, capped at the preferred speed (its ORCA policy's
        `velocity / speed if speed > 1 else velocity` at v_pref 1). Written into the state's
        preferred speeds before each step; the arena's routes are one point, the goal."""
        _arrival_speeds(
            s.human_route, s.human_pos, s.human_mask, self.config.cases.human_speed, s.human_pref_speed
        )

    def _force_and_blame(self) -> tuple[np.ndarray, np.ndarray]:
        """(B R,) the benchmark's social force and blame terms of each robot after the step
        (SPEC section 9; every person counts: the task's robot sees everyone)."""
        core, s = self.core, self.core.state
        assert s is not None
        n = self.batch_size * self.num_robots
        vel = world_velocity(s.robot_pose, s.robot_vel, self.config.robot).reshape(n, 2)
        still = np.hypot(vel[:, 0], vel[:, 1]) < STILL_SPEED
        pos = s.robot_pose[..., :2].reshape(n, 2)
        people, seen = core.per_robot(s.human_pos), core.per_robot(s.human_mask)
        return force_and_blame(pos, vel, still, people, seen, np.full(n, -1), self._blame_horizon)

    # ------------------------------------------------------------------ the joint state
    def _wall_points(self, pos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(points (N, K, 2), seen (N, K)): where each robot's K scan rays first hit a wall within
        wall_range (world frame; a ray that hits nothing is not seen)."""
        n, k = len(pos), len(self._ray_angles)
        walls = self.core.walls
        if k == 0 or walls.num_walls == 0:
            return np.zeros((n, k, 2)), np.zeros((n, k), dtype=bool)
        angles = np.broadcast_to(self._ray_angles, (n, k))
        ranges = walls.cast_rays(pos, angles, self.config.wall_range)
        points = pos[:, None, :] + ranges[..., None] * self._ray_directions
        return points, ranges < self.config.wall_range

    def _observe(self, rows: np.ndarray | None = None) -> JointState:
        """The joint state of every robot (of `rows` only, when given)."""
        core = self.core
        s = core.state
        assert s is not None

        def of_rows(array: np.ndarray) -> np.ndarray:  # a reset's few rows take only what is read
            return array if rows is None else array.take(rows, 0)

        robot_pose = of_rows(s.robot_pose)
        b, r = len(robot_pose), self.num_robots
        robot = self.config.robot
        velocity = world_velocity(robot_pose, of_rows(s.robot_vel), robot)
        pos, vel, mask = core.others(s, velocity, rows)
        radius = self._slot_radius_rows[: len(mask)]
        robot_pos = robot_pose[..., :2].reshape(b * r, 2)
        observed = None
        if self.config.observed_people is not None:
            pos, vel, mask, radius, observed = self._nearest_people(robot_pos, pos, vel, mask, radius)
        if self.config.wall_rays:
            points, seen = self._wall_points(robot_pos)
            pos = np.concatenate((pos, points), axis=1)
            vel = np.concatenate((vel, np.zeros_like(points)), axis=1)
            mask = np.concatenate((mask, seen), axis=1)
            radius = np.concatenate((radius, np.zeros(seen.shape)), axis=1)
        guided = core.navigator is not None
        goal = (of_rows(core.carrot) if guided else of_rows(s.robot_goal)[..., :2]).reshape(b * r, 2)
        offset = goal - robot_pos
        angle = np.arctan2(offset[:, 1], offset[:, 0])
        self.frame_angle[slice(None) if rows is None else core.robot_rows(rows)] = angle
        observation = joint_state(
            robot_pos=robot_pos,
            robot_goal=goal,
            robot_vel=velocity.reshape(b * r, 2),
            robot_heading=robot_pose[..., 2].reshape(b * r),
            robot_radius=float(robot.radius),  # type: ignore[arg-type]
            preferred_speed=self.config.preferred_speed,
            unicycle=robot.kinematics == "unicycle",
            human_pos=pos,
            human_vel=vel,
            human_radius=radius,
            human_mask=mask,
        )
        if guided:  # the goal distance is the route's length left, not the carrot's distance
            observation.robot[:, 0] = of_rows(core.route_left).reshape(b * r)
        if self.config.signals:
            observation = self._with_signals(observation, robot_pos, angle, rows, observed)
        return observation

    def _nearest_people(
        self, robot_pos: np.ndarray, pos: np.ndarray, vel: np.ndarray, mask: np.ndarray, radius: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The observed slots' (pos, vel, mask, radius) with the people's H slots replaced by the
        observed_people nearest (crowd_observation.nearest_people), and those people's slots."""
        h = self.num_human_slots
        seen, present = nearest_people(robot_pos, pos[:, :h], mask[:, :h], self.config.observed_people or h)

        def people_first(values: np.ndarray, picked: np.ndarray | None = None) -> np.ndarray:
            if picked is None:
                index = seen.reshape(seen.shape + (1,) * (values.ndim - 2))
                picked = np.take_along_axis(values[:, :h], index, 1)
            return np.concatenate((picked, values[:, h:]), 1)

        return (
            people_first(pos), people_first(vel), people_first(mask, present),
            people_first(np.ascontiguousarray(radius)), seen,
        )  # fmt: skip

    def _with_signals(
        self,
        observation: JointState,
        robot_pos: np.ndarray,
        angle: np.ndarray,
        rows: np.ndarray | None,
        observed: np.ndarray | None = None,
    ) -> JointState:
        """The joint state with each person slot's gesture and the nearest door, in the frame of
        each robot (x towards the goal it sees, at `angle`; socialzoo.env.crowd_observation.with_signals)."""
        core, script = self.core, self.core.script
        pick = slice(None) if rows is None else rows
        signal = np.zeros(observation.mask.shape)
        people = core.per_robot(script.signal[pick])
        if observed is not None:  # the observed people's (CrowdNavConfig.observed_people)
            people = np.take_along_axis(people, observed, 1)
        signal[:, : people.shape[1]] = people  # the people's slots come first
        offset, closed = nearest_door(
            robot_pos, core.per_robot(script.doors[pick]), core.per_robot(script.closed[pick])
        )
        c, s = np.cos(angle), np.sin(angle)
        door = np.stack(
            (c * offset[:, 0] + s * offset[:, 1], c * offset[:, 1] - s * offset[:, 0], closed), axis=-1
        )
        return with_signals(observation, signal, door)

    def observations(self) -> Any:
        """(B, R, D) float32 flat joint states, or the dict layout of (B, R, ...) arrays."""
        observation, b, r = self.observation, self.batch_size, self.num_robots
        assert observation is not None
        if self.config.observation == "flat":
            flat = observation.flat()
            return flat.reshape(b, r, flat.shape[-1])
        return {k: v.reshape((b, r) + v.shape[1:]) for k, v in observation.as_dict().items()}

    def episode_metrics(self, rows: np.ndarray, robot: int = 0) -> list[dict[str, Any]]:
        """The metrics of each robot's episode (socialzoo.env.crowd_outcome.CrowdNavMetrics): the
        one that ended, or the one running so far (neither success, collision nor timeout yet; an
        adapter that cuts it short, a ParallelEnv's max_cycles, reads it)."""
        flats = np.asarray(rows, dtype=np.intp).reshape(-1) * self.num_robots + robot
        return [self._ended[k] if k in self._ended else self._running(k) for k in flats.tolist()]

    def _running(self, flat: int) -> dict[str, Any]:
        """The metrics so far of robot `flat` (row * R + robot), whose episode has not ended."""
        size = self.batch_size * self.num_robots
        clear = np.zeros(size, dtype=bool)
        running = CrowdOutcome(
            reward=np.zeros(size),
            success=clear,
            collision=clear,
            timeout=clear,
            terminated=clear,
            truncated=clear,
            closest=np.full(size, np.inf),
            discomfort=clear,
        )
        summary = self.metrics.summaries(np.array([flat]), running)[0]
        summary["wall_collision"] = 0.0
        row, robot = divmod(flat, self.num_robots)
        if self.core.replay.recorded[row]:
            summary.update(self.core.replay.summaries([row], [float("nan")], robot)[0])
        return summary

    # ------------------------------------------------------------------ per-robot info
    def idle_action(self) -> Any:
        """Stop: action 0, a zero velocity, or a unicycle's speed 0 (the lowest of its range)."""
        if self.config.action == "discrete":
            return 0
        if self.config.robot.kinematics == "unicycle":
            return np.array([-1.0, 0.0])
        return np.zeros(2)

    # ------------------------------------------------------------------ world view
    @property
    def frames_per_second(self) -> float:
        """One frame per decision step (config.time_step; 4 at CrowdNav's 0.25 s), however many
        physics substeps it takes."""
        return 1.0 / self.config.time_step

    def make_renderer(self, render_mode: str, view: str = "follow", **frame: Any) -> Any:
        """socialzoo.env.rendering.CoreRenderer of the task. In the open (the arena, a recorded
        scene) the frames show no walls, and the map view shows the arena's cases with 1 m to
        spare, or a family's scenes (a recorded scene's) around the robots' starts and goals and
        the people's routes of the rows' scenarios when it is made, with 1 m to spare (5 m around
        the origin before any reset)."""
        from socialzoo.env.rendering import CoreRenderer
        from socialzoo.maps.map_file import Map

        world_map = self.core.map
        if world_map is None:
            cases = self.config.cases
            half = cases.square_width / 2 if cases.layout == "square_crossing" else cases.circle_radius
            reach = half + 1.0 if self.config.family is None else 5.0
            region = (-reach, -reach, reach, reach)
            places = [
                np.concatenate([s.robot_starts[:, :2], s.robot_goals[:, :2], s.human_spawn, *s.human_routes])
                for s in self.core.scenarios
                if s is not None
            ]
            if self.config.family is not None and places:
                low, high = (
                    np.min([p.min(0) for p in places], 0) - 1.0,
                    np.max([p.max(0) for p in places], 0) + 1.0,
                )
                region = (float(low[0]), float(low[1]), float(high[0]), float(high[1]))
            world_map = Map(
                name="open",
                walls=np.zeros((0, 4)),
                nodes=np.zeros((0, 2)),
                edges=np.zeros((0, 2), dtype=np.int64),
                legal_poses=np.zeros((0, 3)),
                region=region,
            )
        return CoreRenderer(self, render_mode, view=view, world_map=world_map, **frame)

    def viewer_scene(self, title: str, subtitle: str, traces: Any) -> Any:
        """The arena (or the map's walls) around every trace; the robot's disc (its radius, drawn as
        a square of its diameter); the people's radius."""
        import dataclasses

        scene = super().viewer_scene(title, subtitle, traces)
        radius = float(self.config.robot.radius)  # type: ignore[arg-type]
        return dataclasses.replace(
            scene,
            map_name=self.config.map or "arena",
            robot_length=2.0 * radius,
            robot_width=2.0 * radius,
            robot_radius=radius,
            human_radius=self.config.cases.human_radius,
            goal_radius=float(self.config.robot.radius),  # type: ignore[arg-type]
        )


@kernel
def _arrival_speeds(route, pos, mask, speed, out):  # type: ignore[no-untyped-def]
    """CrowdNavTask._arrive into out (B, H): each present person's distance to its route's first
    point per _ARRIVAL_TIME, capped at `speed` (a NaN distance kept, as np.minimum keeps it); 0 for
    an empty slot."""
    for b in range(mask.shape[0]):
        for h in range(mask.shape[1]):
            if not mask[b, h]:
                out[b, h] = 0.0
                continue
            ox, oy = route[b, h, 0, 0] - pos[b, h, 0], route[b, h, 0, 1] - pos[b, h, 1]
            reach = math.sqrt(ox * ox + oy * oy) / _ARRIVAL_TIME
            out[b, h] = speed if speed < reach else reach
