"""The batched core of the CrowdNav task: B rows of velocity-controlled robots among people, stepped
through the one world step (socialzoo.env.world.step_world).

A decision step takes each robot's action (a velocity, or one of CrowdNav's 81 actions), turns it
into its command, advances the world `physics_substeps` steps, judges the step for each robot as
CrowdNav does (socialzoo.env.crowd_outcome: the closest approach along every substep, the goal,
the time limit), accumulates the episode metrics and builds each robot's joint-state observation.
CrowdNav's task has one robot (R = 1); with several, each robot sees the others as people, a
robot whose episode ended stands still where it is, and the row's episode lasts until every
robot's has ended. Rows are reset by the task (socialzoo.env.tasks.crowdnav) with
cases from socialzoo.env.crowd_source.

Per-robot arrays are flat over (B, R), row-major: robot r of row b is entry b * R + r (with R = 1,
entry b is row b).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from socialzoo.core.config import HumanConfig, OrcaConfig, WorldConfig
from socialzoo.core.robot import world_velocity
from socialzoo.core.state import WorldState
from socialzoo.core.walls import WallIndex
from socialzoo.env.crowd_config import CrowdNavConfig, discrete_actions
from socialzoo.env.crowd_observation import JointState, joint_state
from socialzoo.env.crowd_outcome import CrowdNavMetrics, CrowdOutcome, closest_boundary_distance, judge_step
from socialzoo.env.outcome import STILL_SPEED
from socialzoo.env.reward import RewardConfig, blame_term, social_force_term
from socialzoo.env.world import step_world
from socialzoo.env.world_rows import BatchedWorld, route_navigator
from socialzoo.humans.models import MODEL_IDS, assign_models, parse_people
from socialzoo.nav.navigator import Navigator
from socialzoo.scenarios.crowd_cases import CrowdCase, case_scenario
from socialzoo.scenarios.scenario import Scenario

# CrowdNav's people cover their last metre in about a second: their preferred speed is the distance
# to the goal per this time, capped at their preferred speed (s).
_ARRIVAL_TIME = 1.0


@dataclass(frozen=True)
class CrowdStep:
    """What one decision step gives back, per robot (flat over B x R).

    Attributes:
        observation: each robot's joint state after the step.
        outcome: the step's judgement of each robot (reward, success, collision, timeout, ...);
            a robot whose episode had already ended gets reward 0 and no flags.
        wall_collision: (B R,) the robot touched a wall (counted as a collision).
        metrics: the metrics of the robots whose episode ended on this step, by flat index.
        row_done: (B,) every robot of the row has ended its episode.
    """

    observation: JointState
    outcome: CrowdOutcome
    wall_collision: np.ndarray
    metrics: dict[int, dict[str, float]]
    row_done: np.ndarray


class CrowdNavCore(BatchedWorld):
    """B rows of the CrowdNav task.

    Args:
        config: the task.
        batch_size: B.
        walls: the wall index (None: the open arena, or the config's map's walls).
    """

    def __init__(self, config: CrowdNavConfig, batch_size: int, walls: WallIndex | None = None) -> None:
        super().__init__(batch_size, config.num_robots, config.slots)
        self.config = config
        self.walls = walls if walls is not None else _map_walls(config.map)
        # Among walls the robot is guided along its route (the benchmark robot's navigator): it sees
        # the route's carrot as its goal and the route left as its goal distance.
        self.navigator = _route_navigator(config, batch_size) if config.map is not None else None
        self.carrot = np.zeros((batch_size, config.num_robots, 2))
        self.route_left = np.zeros((batch_size, config.num_robots))
        self._ray_angles = np.linspace(0.0, 2.0 * np.pi, config.wall_rays, endpoint=False)
        self._ray_directions = np.stack((np.cos(self._ray_angles), np.sin(self._ray_angles)), axis=-1)
        # (B R,) the angle of each robot's observation frame (x towards the goal it sees), rad:
        # goal-frame velocity actions are turned by it into the world frame.
        self.frame_angle = np.zeros(batch_size * config.num_robots)
        self.step_force = np.zeros(batch_size * config.num_robots)
        self.step_blame = np.zeros(batch_size * config.num_robots)
        cases = config.cases
        radius = float(config.robot.radius)  # type: ignore[arg-type]
        self.world = WorldConfig(
            dt=config.physics_dt,
            robot=config.robot,
            human=HumanConfig(radius=cases.human_radius),
            human_collision_distance=radius + cases.human_radius,
            # CrowdNav's people: ORCA with its parameters, at the people's own radius and speed.
            orca=dataclasses.replace(
                OrcaConfig.preset("crowdnav"),
                radius=cases.human_radius,
                max_speed=cases.human_speed,
                robot_visible=config.robot_visible,
            ),
        )
        # The people spec's models (config.humans): one for everyone, or a mix per case's seed.
        self._parts = parse_people(config.humans)
        self._model_ids = np.array([MODEL_IDS[p.model] for p in self._parts], dtype=np.int8)
        r = self.num_robots
        # Observation slots: the people, then the other robots (each robot's own slot left out).
        self._others = np.array([[j for j in range(r) if j != k] for k in range(r)], dtype=np.intp).reshape(
            r, r - 1
        )
        slots = config.slots
        self.slot_radius = np.concatenate((np.full(slots, cases.human_radius), np.full(r - 1, radius)))
        self.radius_sum = radius + self.slot_radius
        self.action_table = np.array(discrete_actions(config.robot)) if config.action == "discrete" else None
        self.time = np.zeros(batch_size)
        self.robot_done = np.zeros((batch_size, r), dtype=bool)
        self.metrics = CrowdNavMetrics(
            batch_size * r, config.time_step, config.preferred_speed, config.reward
        )
        # Each row's case (a Scenario; None for an arena case written as arrays) and its seed.
        self.cases: list[Scenario | None] = [None] * batch_size
        self.case_seed = np.zeros(batch_size, dtype=np.uint64)  # benchmark scenario seeds use all 64 bits
        self.observation: JointState | None = None
        self._blame_horizon = RewardConfig().blame_horizon

    # ------------------------------------------------------------------ reset
    def reset_rows(self, rows: np.ndarray | list[int], cases: list[Scenario] | list[CrowdCase]) -> JointState:
        """Start new episodes in `rows` from `cases` (one per row: Scenarios, or the arena's
        CrowdCases, written straight into the state); returns every robot's observation."""
        rows = self.check_rows(rows, len(cases))
        if len(cases) and isinstance(cases[0], CrowdCase) and self.state is not None:
            self._write_cases(rows, cases)  # type: ignore[arg-type]
            return self._after_reset(rows, [None] * len(rows), [c.seed for c in cases])
        if len(cases) and isinstance(cases[0], CrowdCase):
            cases = [case_scenario(c, self.config.cases) for c in cases]  # type: ignore[arg-type]
        models = self._models([c.seed for c in cases], [c.num_humans for c in cases], self.config.slots)  # type: ignore[union-attr]
        self.write_rows(rows, cases, models)  # type: ignore[arg-type]
        return self._after_reset(rows, cases, [c.seed for c in cases])  # type: ignore[arg-type]

    def _after_reset(self, rows: np.ndarray, cases: list[Scenario | None], seeds: list[int]) -> JointState:
        for row, case in zip(rows.tolist(), cases, strict=True):
            self.cases[row] = case
        if self.navigator is not None:
            s = self.state
            assert s is not None
            self.navigator.reset(rows, s.robot_pose[rows][..., :2], s.robot_goal[rows][..., :2])
            self._follow_routes()
        self.case_seed[rows] = seeds
        self.time[rows] = 0.0
        self.robot_done[rows] = False
        self.metrics.reset_rows(self.robot_rows(rows))
        if self.observation is None or len(rows) == self.batch_size:
            self.observation = self._observe()
        else:
            # Only the reset rows' robots see anything new.
            fresh = self._observe(rows)
            robots = self.robot_rows(rows)
            self.observation.buffer[robots] = fresh.flat()  # type: ignore[index]
            self.observation.mask[robots] = fresh.mask
        return self.observation

    def _write_cases(self, rows: np.ndarray, cases: list[CrowdCase]) -> None:
        """Write arena cases into the state's rows: robots on their starts, people on theirs
        with a one-point route to their goals, everyone still (as scenarios_to_state would)."""
        s = self.state
        assert s is not None
        n = cases[0].human_starts.shape[0]
        s.robot_pose[rows] = np.stack([c.robot_starts for c in cases])
        s.robot_goal[rows] = np.stack([c.robot_goals for c in cases])
        s.robot_vel[rows] = 0.0
        s.human_pos[rows] = 0.0
        s.human_pos[rows, :n] = np.stack([c.human_starts for c in cases])
        s.human_vel[rows] = 0.0
        s.human_route[rows] = 0.0
        s.human_route[rows, :n] = np.stack([c.human_goals for c in cases])[:, :, None, :]
        s.human_mask[rows] = False
        s.human_mask[rows, :n] = True
        s.human_pref_speed[rows] = 0.0
        s.human_pref_speed[rows, :n] = self.config.cases.human_speed
        s.human_route_len[rows] = 1
        s.human_waypoint[rows] = 0
        s.human_direction[rows] = 1
        s.step_count[rows] = 0
        s.noise_key[rows] = [c.seed for c in cases]  # the task has no laser to draw noise for
        s.human_model[rows] = self._models([c.seed for c in cases], [n] * len(cases), s.human_model.shape[1])
        s.human_group[rows] = -1

    def _models(self, seeds: list[int], people: list[int], slots: int) -> np.ndarray:
        """(len(seeds), slots) int8 model of every person slot: the people spec's one model, or
        its mix over each case's people assigned from its seed (socialzoo.humans.models)."""
        out = np.full((len(seeds), slots), self._model_ids[0], dtype=np.int8)
        if len(self._parts) > 1:
            for row, (seed, n) in enumerate(zip(seeds, people, strict=True)):
                out[row, :n] = self._model_ids[assign_models(self._parts, n, int(seed))]
        return out

    # ------------------------------------------------------------------ step
    def commands(self, action: np.ndarray) -> np.ndarray:
        """(B, R, 2) robot commands of the actions, checked before anything changes. Actions are
        (B, R, 2) velocities or (B, R) indices; with one robot also (B, 2) or (B,).

        Raises:
            ValueError: a wrong shape, a NaN or infinite value, a velocity outside [-1, 1], or an
                index outside the discrete actions; the message names the row.
        """
        b, r = self.batch_size, self.num_robots
        action = np.asarray(action)
        robot = self.config.robot
        if self.action_table is not None:
            if action.size != b * r or not np.issubdtype(action.dtype, np.integer):
                raise ValueError(
                    f"CrowdNav: discrete actions must be {b} x {r} integers, got {action.dtype} {action.shape}"
                )
            flat = action.reshape(b * r)
            bad = np.flatnonzero((flat < 0) | (flat >= len(self.action_table)))
            if len(bad):
                top = len(self.action_table) - 1
                raise ValueError(
                    f"CrowdNav: action {int(flat[bad[0]])} of robot {int(bad[0])} is not in 0..{top}"
                )
            chosen = self.action_table[flat]
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
        bad = ~np.isfinite(action).all(axis=1) | (np.abs(action) > 1.0).any(axis=1)
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise ValueError(
                f"CrowdNav: velocity action {action[k].tolist()} of robot {k} is not finite in [-1, 1]"
            )
        v_pref = self.config.preferred_speed
        if robot.kinematics == "holonomic":
            return self._to_world(action * v_pref).reshape(b, r, 2)
        speed = (action[:, 0] + 1.0) * 0.5 * v_pref
        omega = action[:, 1] * robot.max_rotation / self.config.time_step
        return np.stack((speed, omega), axis=-1).reshape(b, r, 2)

    def _to_world(self, velocity: np.ndarray) -> np.ndarray:
        """(B R, 2) holonomic velocities in the action frame -> the world frame."""
        if self.config.action_frame == "world":
            return velocity
        c, s = np.cos(self.frame_angle), np.sin(self.frame_angle)
        return np.stack(
            (c * velocity[:, 0] - s * velocity[:, 1], s * velocity[:, 0] + c * velocity[:, 1]), axis=-1
        )

    def to_action_frame(self, velocity: np.ndarray) -> np.ndarray:
        """(B, R, 2) world-frame velocities -> the frame of the robots' velocity actions."""
        if self.config.action_frame == "world":
            return velocity
        b, r = velocity.shape[:2]
        flat = velocity.reshape(b * r, 2)
        c, s = np.cos(self.frame_angle), np.sin(self.frame_angle)
        return np.stack((c * flat[:, 0] + s * flat[:, 1], c * flat[:, 1] - s * flat[:, 0]), axis=-1).reshape(
            b, r, 2
        )

    def step(self, action: np.ndarray) -> CrowdStep:
        """Advance every row one decision step (rows whose episode ended wait to be reset)."""
        if self.state is None:
            raise RuntimeError("CrowdNavCore: reset_rows before step")
        command = self.commands(action)
        cfg = self.config
        b, r = self.batch_size, self.num_robots
        # A robot whose episode ended stands still (CrowdNav's robot stops at its end).
        halt = self.robot_done.copy()
        closest = np.full(b * r, np.inf)
        wall = np.zeros(b * r, dtype=bool)
        moved = np.zeros(b * r)
        start_time = np.repeat(self.time, r)
        state = self.state
        dt = cfg.physics_dt
        for _ in range(cfg.physics_substeps):
            before = state
            if cfg.map is None:
                self._arrive(before)
            state, events = step_world(
                before, self.walls, self.world, command, robot_halt=halt, robot_visible=cfg.robot_visible
            )
            shift = (state.robot_pose[..., :2] - before.robot_pose[..., :2]).reshape(b * r, 2)
            moved += np.hypot(shift[:, 0], shift[:, 1])
            pos, vel, mask = self._others_of(before, shift.reshape(b, r, 2) / dt)
            gap = closest_boundary_distance(
                before.robot_pose[..., :2].reshape(b * r, 2), shift / dt, pos, vel, self.radius_sum, mask, dt
            )
            closest = np.minimum(closest, gap)
            wall |= events.robot_wall.reshape(b * r)
        self.state = state
        self.time += cfg.time_step
        if self.navigator is not None:
            self._follow_routes()
        goal = (state.robot_goal[..., :2] - state.robot_pose[..., :2]).reshape(b * r, 2)
        # A wall contact is a collision of the task (CrowdNav's arena has none).
        closest = np.where(wall, np.minimum(closest, -1e-9), closest)
        outcome = judge_step(
            closest,
            np.hypot(goal[:, 0], goal[:, 1]),
            float(cfg.robot.radius),  # type: ignore[arg-type]
            start_time,
            cfg.time_limit,
            cfg.reward,
            cfg.time_step,
        )
        outcome = _mask_ended(outcome, self.robot_done.reshape(b * r))
        # The step's social force and blame terms per robot (the viewer draws them).
        self.step_force, self.step_blame = self._force_and_blame(state)
        self.metrics.update(outcome, moved, self.step_force, self.step_blame)
        ended = np.flatnonzero(outcome.terminated | outcome.truncated)
        summaries = self.metrics.summaries(ended, outcome)
        for k, summary in zip(ended.tolist(), summaries, strict=True):
            summary["wall_collision"] = float(wall[k] and outcome.collision[k])
        self.robot_done |= (outcome.terminated | outcome.truncated).reshape(b, r)
        self.observation = self._observe()
        return CrowdStep(
            observation=self.observation,
            outcome=outcome,
            wall_collision=wall & outcome.collision,
            metrics=dict(zip(ended.tolist(), summaries, strict=True)),
            row_done=self.robot_done.all(axis=1),
        )

    def _follow_routes(self) -> None:
        """Each robot's carrot and route left on its plan (replanned when it strayed)."""
        assert self.navigator is not None and self.state is not None
        self.carrot = self.navigator.update(self.state.robot_pose[..., :2])
        self.route_left = self.navigator.route_left.copy()

    def seen_goal(self) -> tuple[np.ndarray, np.ndarray]:
        """((B, R, 2) the goal each robot heads for, (B, R) its distance, m): the goal itself in the
        arena; among walls the route's carrot and the route's length left."""
        assert self.state is not None
        pos = self.state.robot_pose[..., :2]
        if self.navigator is not None:
            return self.carrot, self.route_left
        goal = self.state.robot_goal[..., :2]
        return goal, np.hypot(goal[..., 0] - pos[..., 0], goal[..., 1] - pos[..., 1])

    def _wall_points(self, pos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(points (N, K, 2), seen (N, K)): where each robot's K scan rays first hit a wall within
        wall_range (world frame; a ray that hits nothing is not seen)."""
        n, k = len(pos), len(self._ray_angles)
        if k == 0 or self.walls.num_walls == 0:
            return np.zeros((n, k, 2)), np.zeros((n, k), dtype=bool)
        angles = np.broadcast_to(self._ray_angles, (n, k))
        ranges = self.walls.cast_rays(pos, angles, self.config.wall_range)
        points = pos[:, None, :] + ranges[..., None] * self._ray_directions
        return points, ranges < self.config.wall_range

    def _arrive(self, s: WorldState) -> None:
        """CrowdNav's people slow down on their last metre and stop at their goal: the preferred
        velocity is the goal's offset per second, capped at the preferred speed (its ORCA policy's
        `velocity / speed if speed > 1 else velocity` at v_pref 1). Written into the state's
        preferred speeds before each step; the arena's routes are one point, the goal."""
        offset = s.human_route[:, :, 0] - s.human_pos
        distance = np.sqrt(offset[..., 0] ** 2 + offset[..., 1] ** 2)
        s.human_pref_speed[...] = np.where(
            s.human_mask, np.minimum(self.config.cases.human_speed, distance / _ARRIVAL_TIME), 0.0
        )

    def _others_of(self, s: WorldState, robot_vel: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(pos, vel, mask) of what each robot must keep clear of, (B R, slots + R - 1, ...): the
        people (at their velocity at the start of the step), then the other robots (at theirs)."""
        b, r = s.batch_size, self.num_robots
        people_pos = np.broadcast_to(s.human_pos[:, None], (b, r) + s.human_pos.shape[1:])
        people_vel = np.broadcast_to(s.human_vel[:, None], (b, r) + s.human_vel.shape[1:])
        people_mask = np.broadcast_to(s.human_mask[:, None], (b, r, s.human_mask.shape[1]))
        if r == 1:
            return people_pos.reshape(b, -1, 2), people_vel.reshape(b, -1, 2), people_mask.reshape(b, -1)
        robot_pos = s.robot_pose[..., :2][:, self._others]
        other_vel = robot_vel[:, self._others]
        pos = np.concatenate((people_pos, robot_pos), axis=2).reshape(b * r, -1, 2)
        vel = np.concatenate((people_vel, other_vel), axis=2).reshape(b * r, -1, 2)
        mask = np.concatenate((people_mask, np.ones((b, r, r - 1), dtype=bool)), axis=2).reshape(b * r, -1)
        return pos, vel, mask

    def _force_and_blame(self, s: WorldState) -> tuple[np.ndarray, np.ndarray]:
        """(B R,) the benchmark's social force and blame terms of each robot after the step
        (SPEC section 9; every person counts: the task's robot sees everyone)."""
        b, r = self.batch_size, self.num_robots
        velocity = world_velocity(s.robot_pose, s.robot_vel, self.config.robot)
        pos = s.robot_pose[..., :2].reshape(b * r, 2)
        people = np.repeat(s.human_pos, r, axis=0)
        seen = np.repeat(s.human_mask, r, axis=0)
        skip = np.full(b * r, -1)
        force = social_force_term(pos, people, seen, skip)
        vel = velocity.reshape(b * r, 2)
        still = np.hypot(vel[:, 0], vel[:, 1]) < STILL_SPEED
        blame = blame_term(pos, vel, still, people, seen, skip, self._blame_horizon)
        return force, blame

    def _observe(self, rows: np.ndarray | None = None) -> JointState:
        """The joint state of every robot (of `rows` only, when given)."""
        s = self.state
        assert s is not None
        if rows is not None:
            s = s.rows(rows)
        b, r = s.batch_size, self.num_robots
        robot = self.config.robot
        velocity = world_velocity(s.robot_pose, s.robot_vel, robot)
        pos, vel, mask = self._others_of(s, velocity)
        radius = np.broadcast_to(self.slot_radius, mask.shape)
        robot_pos = s.robot_pose[..., :2].reshape(b * r, 2)
        if self.config.wall_rays:
            points, seen = self._wall_points(robot_pos)
            pos = np.concatenate((pos, points), axis=1)
            vel = np.concatenate((vel, np.zeros_like(points)), axis=1)
            mask = np.concatenate((mask, seen), axis=1)
            radius = np.concatenate((radius, np.zeros(seen.shape)), axis=1)
        guided = self.navigator is not None
        goal = (
            (self.carrot if rows is None else self.carrot[rows]) if guided else s.robot_goal[..., :2]
        ).reshape(b * r, 2)
        offset = goal - robot_pos
        self.frame_angle[slice(None) if rows is None else self.robot_rows(rows)] = np.arctan2(
            offset[:, 1], offset[:, 0]
        )
        observation = joint_state(
            robot_pos=robot_pos,
            robot_goal=goal,
            robot_vel=velocity.reshape(b * r, 2),
            robot_heading=s.robot_pose[..., 2].reshape(b * r),
            robot_radius=float(robot.radius),  # type: ignore[arg-type]
            preferred_speed=self.config.preferred_speed,
            unicycle=robot.kinematics == "unicycle",
            human_pos=pos,
            human_vel=vel,
            human_radius=radius,
            human_mask=mask,
        )
        if guided:  # the goal distance is the route's length left, not the carrot's distance
            left = self.route_left if rows is None else self.route_left[rows]
            observation.robot[:, 0] = left.reshape(b * r)
        return observation


def _mask_ended(outcome: CrowdOutcome, done: np.ndarray) -> CrowdOutcome:
    """The outcome with robots that had already ended cleared: no reward, no flags."""
    if not done.any():
        return outcome
    keep = ~done
    return CrowdOutcome(
        reward=np.where(keep, outcome.reward, 0.0),
        success=outcome.success & keep,
        collision=outcome.collision & keep,
        timeout=outcome.timeout & keep,
        terminated=outcome.terminated & keep,
        truncated=outcome.truncated & keep,
        closest=outcome.closest,
        discomfort=outcome.discomfort & keep,
    )


def _route_navigator(config: CrowdNavConfig, batch_size: int) -> Navigator:
    """The benchmark robot's navigator on the config's map (its graph, sight and planner settings),
    without recovery: the learner drives."""
    from socialzoo.maps.map_file import load_map
    from socialzoo.nav.local_planner import LocalPlannerConfig

    assert config.map is not None
    return route_navigator(load_map(config.map), batch_size, config.num_robots, LocalPlannerConfig())[1]


def _map_walls(map_name: str | None) -> WallIndex:
    """The open arena's empty wall index, or the map's."""
    if map_name is None:
        return WallIndex(np.zeros((0, 4)))
    from socialzoo.maps.map_file import load_map

    return load_map(map_name).wall_index
