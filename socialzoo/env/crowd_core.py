"""The batched core of the CrowdNav task: B rows of a velocity-controlled robot among people,
stepped through the one world step (socialzoo.env.world.step_world).

A decision step takes each row's action (a velocity, or one of CrowdNav's 81 actions), turns it
into the robot's command, advances the world `physics_substeps` steps, judges the step as CrowdNav
does (socialzoo.env.crowd_outcome: the closest approach along every substep, the goal, the time
limit), accumulates the episode metrics and builds the joint-state observation. Rows are reset by
the adapters (socialzoo.env.crowd_env) with cases from socialzoo.env.crowd_source.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from socialzoo.core.config import HumanConfig, WorldConfig
from socialzoo.core.robot import world_velocity
from socialzoo.core.state import WorldState
from socialzoo.core.walls import WallIndex
from socialzoo.env.crowd_config import CrowdNavConfig, discrete_actions
from socialzoo.env.crowd_observation import JointState, joint_state
from socialzoo.env.crowd_outcome import CrowdNavMetrics, CrowdOutcome, closest_boundary_distance, judge_step
from socialzoo.env.world import step_world
from socialzoo.nav.scenarios import Scenario, scenarios_to_state


@dataclass(frozen=True)
class CrowdStep:
    """What one decision step gives back for B rows.

    Attributes:
        observation: the joint state after the step.
        outcome: the step's judgement (reward, success, collision, timeout, terminated, truncated).
        wall_collision: (B,) the robot touched a wall (counted as a collision).
        metrics: the metrics of the episodes that ended, by row.
    """

    observation: JointState
    outcome: CrowdOutcome
    wall_collision: np.ndarray
    metrics: dict[int, dict[str, float]]


class CrowdNavCore:
    """B rows of the CrowdNav task.

    Args:
        config: the task.
        batch_size: B.
        walls: the wall index (None: the open arena, or the config's map's walls).
    """

    def __init__(self, config: CrowdNavConfig, batch_size: int, walls: WallIndex | None = None) -> None:
        if not isinstance(batch_size, int) or isinstance(batch_size, bool) or batch_size < 1:
            raise ValueError(f"CrowdNavCore: batch_size must be an int >= 1, got {batch_size!r}")
        self.config = config
        self.batch_size = batch_size
        if walls is None:
            walls = _map_walls(config.map)
        self.walls = walls
        cases = config.cases
        self.world = WorldConfig(
            dt=config.physics_dt,
            robot=config.robot,
            human=HumanConfig(radius=cases.human_radius),
            human_collision_distance=config.robot.radius + cases.human_radius,  # type: ignore[operator]
        )
        self.radius_sum = float(config.robot.radius) + cases.human_radius  # type: ignore[arg-type]
        self.action_table = np.array(discrete_actions(config.robot)) if config.action == "discrete" else None
        self.state: WorldState | None = None
        self.time = np.zeros(batch_size)
        self.metrics = CrowdNavMetrics(batch_size, config.time_step, config.preferred_speed, config.reward)
        self.cases: list[Scenario | None] = [None] * batch_size
        self.observation: JointState | None = None

    # ------------------------------------------------------------------ reset
    def reset_rows(self, rows: np.ndarray | list[int], cases: list[Scenario]) -> JointState:
        """Start new episodes in `rows` from `cases` (one per row); returns the observation of all rows."""
        rows = np.asarray(rows, dtype=np.intp).reshape(-1)
        if len(rows) != len(cases):
            raise ValueError(f"reset_rows got {len(rows)} rows but {len(cases)} cases")
        if np.any((rows < 0) | (rows >= self.batch_size)):
            raise ValueError(f"reset_rows: rows {rows.tolist()} outside 0..{self.batch_size - 1}")
        fresh = scenarios_to_state(cases, num_robots=1, max_humans=self.config.slots)
        if self.state is None:
            self.state = WorldState.concatenate([fresh.rows(0)] * self.batch_size)
        if fresh.human_route.shape[2] > self.state.human_route.shape[2]:
            self.state = WorldState.concatenate([self.state, fresh.rows(0)]).rows(slice(0, self.batch_size))
        self.state.set_rows(rows, fresh)
        for row, case in zip(rows.tolist(), cases, strict=True):
            self.cases[row] = case
        self.time[rows] = 0.0
        self.metrics.reset_rows(rows)
        self.observation = self._observe()
        return self.observation

    # ------------------------------------------------------------------ step
    def commands(self, action: np.ndarray) -> np.ndarray:
        """(B, 1, 2) robot commands of the actions, checked before anything changes.

        Raises:
            ValueError: a wrong shape, a NaN or infinite value, a velocity outside [-1, 1], or an
                index outside the discrete actions; the message names the row.
        """
        b = self.batch_size
        action = np.asarray(action)
        robot = self.config.robot
        if self.action_table is not None:
            flat = action.reshape(-1) if action.size == b else action
            if flat.shape != (b,) or not np.issubdtype(flat.dtype, np.integer):
                raise ValueError(
                    f"CrowdNav: discrete actions must be {b} integers, got {action.dtype} {action.shape}"
                )
            bad = np.flatnonzero((flat < 0) | (flat >= len(self.action_table)))
            if len(bad):
                top = len(self.action_table) - 1
                raise ValueError(
                    f"CrowdNav: action {int(flat[bad[0]])} of row {int(bad[0])} is not in 0..{top}"
                )
            chosen = self.action_table[flat]
            if robot.kinematics == "unicycle":  # (speed, turn per step) -> (v, omega)
                chosen = np.stack((chosen[:, 0], chosen[:, 1] / self.config.time_step), axis=-1)
            return chosen[:, None, :]
        action = np.asarray(action, dtype=np.float64).reshape(b, -1) if action.size == 2 * b else action
        if action.shape != (b, 2):
            raise ValueError(f"CrowdNav: velocity actions must have shape {(b, 2)}, got {np.shape(action)}")
        bad = ~np.isfinite(action).all(axis=1) | (np.abs(action) > 1.0).any(axis=1)
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise ValueError(
                f"CrowdNav: velocity action {action[row].tolist()} of row {row} is not finite in [-1, 1]"
            )
        v_pref = self.config.preferred_speed
        if robot.kinematics == "holonomic":
            return (action * v_pref)[:, None, :]
        speed = (action[:, 0] + 1.0) * 0.5 * v_pref
        omega = action[:, 1] * robot.max_rotation / self.config.time_step
        return np.stack((speed, omega), axis=-1)[:, None, :]

    def step(self, action: np.ndarray) -> CrowdStep:
        """Advance every row one decision step (rows whose episode ended wait to be reset)."""
        if self.state is None:
            raise RuntimeError("CrowdNavCore: reset_rows before step")
        command = self.commands(action)
        cfg = self.config
        closest = np.full(self.batch_size, np.inf)
        wall = np.zeros(self.batch_size, dtype=bool)
        moved = np.zeros(self.batch_size)
        start_time = self.time.copy()
        state = self.state
        dt = cfg.physics_dt
        for _ in range(cfg.physics_substeps):
            before = state
            state, events = step_world(
                before, self.walls, self.world, command, robot_visible=cfg.robot_visible
            )
            shift = state.robot_pose[:, 0, :2] - before.robot_pose[:, 0, :2]
            moved += np.hypot(shift[:, 0], shift[:, 1])
            gap = closest_boundary_distance(
                before.robot_pose[:, 0, :2],
                shift / dt,
                before.human_pos,
                before.human_vel,
                self.radius_sum,
                before.human_mask,
                dt,
            )
            closest = np.minimum(closest, gap)
            wall |= events.robot_wall[:, 0]
        self.state = state
        self.time += cfg.time_step
        goal = state.robot_goal[:, 0, :2] - state.robot_pose[:, 0, :2]
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
        self.metrics.update(outcome, moved)
        ended = np.flatnonzero(outcome.terminated | outcome.truncated)
        summaries = self.metrics.summaries(ended, outcome)
        for row, summary in zip(ended.tolist(), summaries, strict=True):
            summary["wall_collision"] = float(wall[row] and outcome.collision[row])
        self.observation = self._observe()
        return CrowdStep(
            observation=self.observation,
            outcome=outcome,
            wall_collision=wall & outcome.collision,
            metrics=dict(zip(ended.tolist(), summaries, strict=True)),
        )

    def _observe(self) -> JointState:
        s = self.state
        assert s is not None
        robot = self.config.robot
        return joint_state(
            robot_pos=s.robot_pose[:, 0, :2],
            robot_goal=s.robot_goal[:, 0, :2],
            robot_vel=world_velocity(s.robot_pose[:, 0], s.robot_vel[:, 0], robot),
            robot_heading=s.robot_pose[:, 0, 2],
            robot_radius=float(robot.radius),  # type: ignore[arg-type]
            preferred_speed=self.config.preferred_speed,
            unicycle=robot.kinematics == "unicycle",
            human_pos=s.human_pos,
            human_vel=s.human_vel,
            human_radius=self.config.cases.human_radius,
            human_mask=s.human_mask,
        )

    def render_state(self) -> dict[str, Any]:
        """Row 0's robot, goal and people, for drawing."""
        s = self.state
        assert s is not None
        return {
            "robot": s.robot_pose[0, 0].copy(),
            "goal": s.robot_goal[0, 0, :2].copy(),
            "humans": s.human_pos[0][s.human_mask[0]].copy(),
        }


def _map_walls(map_name: str | None) -> WallIndex:
    """The open arena's empty wall index, or the map's."""
    if map_name is None:
        return WallIndex(np.zeros((0, 4)))
    from socialzoo.nav.maps import load_map

    return load_map(map_name).wall_index
