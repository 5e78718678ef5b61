"""The batched environment core: B worlds with R robots each, stepped together.

Every adapter steps this one class: the Gymnasium benchmark env (B = 1), the Gymnasium VectorEnv,
the PettingZoo ParallelEnv and the evaluation runner. It turns actions into robot commands (the
sub-policies), steps the world, tracks global plans, and computes observations, rewards,
terminations and episode metrics, all as arrays over (B, R). The reward and the episode end are
socialzoo.env.outcome's; StepResult carries them and the per-step info every adapter reports.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any, ClassVar

import numpy as np

from socialzoo.env.config import EnvConfig
from socialzoo.env.human_agents import HumanStep, action_velocities, human_observations, human_step
from socialzoo.env.metrics import EpisodeMetrics
from socialzoo.env.observation import build_observation
from socialzoo.env.outcome import followed_human, robot_outcome
from socialzoo.env.people import People
from socialzoo.env.world import StepEvents, robot_velocity_vectors, step_world
from socialzoo.env.world_rows import BatchedWorld, route_navigator
from socialzoo.maps.map_file import Map, load_map
from socialzoo.nav.recovery import RecoveryConfig, backoff_commands
from socialzoo.nav.sight_cache import SightCache
from socialzoo.nav.subpolicies import GO_ALONE, check_actions, subpolicy_commands
from socialzoo.scenarios.scenario import Scenario


@dataclass(frozen=True)
class StepResult:
    """One step of every robot (and learned human) of the batch.

    Attributes:
        obs: (B, R, D) float32 robot observations after the step.
        reward: (B, R) rewards; 0 for robots whose episode had already ended.
        terminated: (B, R) the episode ended this step: goal reached or wall collision.
        truncated: (B, R) the time limit ended the episode this step.
        reached: (B, R) goal within goal_radius after the step.
        wall_collision: (B, R) footprint touches a wall after the step.
        human_collisions: (B, R) int number of humans within the collision distance.
        force, blame, progress: (B, R) reward terms before weighting (SPEC section 9); force
            and blame leave out the followed human during Follow only.
        target_human: (B, R) human followed or passed this step, -1 for none.
        human_obs: (B, L, D_h) learned-human observations, or None without learned humans.
        human_reward: (B, L) learned-human rewards, or None.
        events: the world's collision events of the step.
        human: the learned humans' reward terms and contacts (HumanStep), or None.
    """

    obs: np.ndarray
    reward: np.ndarray
    terminated: np.ndarray
    truncated: np.ndarray
    reached: np.ndarray
    wall_collision: np.ndarray
    human_collisions: np.ndarray
    force: np.ndarray
    blame: np.ndarray
    progress: np.ndarray
    target_human: np.ndarray
    human_obs: np.ndarray | None
    human_reward: np.ndarray | None
    events: StepEvents
    human: HumanStep | None = None

    # The per-step info keys of a robot, in the order `info` gives them.
    INFO_KEYS: ClassVar[tuple[str, ...]] = (
        "reached",
        "wall_collision",
        "human_collisions",
        "force",
        "blame",
        "progress",
        "target_human",
    )

    def info(self, row: int = 0, robot: int = 0) -> dict[str, Any]:
        """The per-step info dict of one robot: plain Python values under INFO_KEYS."""
        return {
            "reached": bool(self.reached[row, robot]),
            "wall_collision": bool(self.wall_collision[row, robot]),
            "human_collisions": int(self.human_collisions[row, robot]),
            "force": float(self.force[row, robot]),
            "blame": float(self.blame[row, robot]),
            "progress": float(self.progress[row, robot]),
            "target_human": int(self.target_human[row, robot]),
        }

    def info_arrays(self, robot: int = 0) -> dict[str, np.ndarray]:
        """The per-step info of robot `robot` of every row: (B,) array copies under INFO_KEYS."""
        return {key: getattr(self, key)[:, robot].copy() for key in self.INFO_KEYS}

    @classmethod
    def initial_info(cls) -> dict[str, Any]:
        """A robot's info at reset: INFO_KEYS with neutral values (no target: -1)."""
        return {
            "reached": False,
            "wall_collision": False,
            "human_collisions": 0,
            "force": 0.0,
            "blame": 0.0,
            "progress": 0.0,
            "target_human": -1,
        }


class SocialNavCore(BatchedWorld):
    """B social-navigation worlds stepped as one batch (the action-selection task's core).

    Args:
        config: the environment configuration.
        batch_size: B.
        map_data: an already loaded map (default: load config.map).

    Call `reset_rows` for every row before the first `step`.
    """

    def __init__(self, config: EnvConfig, batch_size: int, map_data: Map | None = None) -> None:
        super().__init__(batch_size, config.num_robots, config.max_humans)
        self.config = config
        self.map = map_data if map_data is not None else load_map(config.map)
        self.walls = self.map.wall_index
        self.field, self.navigator = route_navigator(
            self.map, batch_size, config.num_robots, config.planner, RecoveryConfig()
        )
        self.graph = self.navigator.graph
        self.metrics = EpisodeMetrics(batch_size * config.num_robots, config.metrics)
        # Which model drives each person, counterfactual rows, the people's metrics.
        self.people = People(config, batch_size, self.map)
        self.learned = np.arange(config.num_learned_humans)
        b, r = batch_size, config.num_robots
        self.carrot = np.zeros((b, r, 2))
        self.prev_action = np.zeros((b, r), dtype=np.int64)
        self.target_human = np.full((b, r), -1, dtype=np.intp)
        self.done = np.zeros((b, r), dtype=bool)
        self.obs = np.zeros((b, r, config.observation.size), dtype=np.float32)
        self.human_obs: np.ndarray | None = None
        # (B*R, H) which humans each robot saw in its latest observation.
        self.visible = np.zeros((b * r, config.max_humans), dtype=bool)
        # Sight lines are re-tested only when they may have changed since the last step.
        self.sight = (
            SightCache(self.walls, self.field, b * r, config.max_humans) if self.walls.num_walls else None
        )
        self.scenarios: list[Scenario | None] = [None] * b
        self._ever_reset = np.zeros(b, dtype=bool)

    # ------------------------------------------------------------------ reset
    def reset_rows(self, rows: np.ndarray | list[int], scenarios: list[Scenario]) -> None:
        """Start new episodes in `rows` from `scenarios` (one per row)."""
        rows = self.check_rows(rows, len(scenarios))
        if len(rows) == 0:
            return
        scenarios, models = self.people.prepare(list(scenarios))
        fresh = self.write_rows(rows, scenarios, models)
        assert self.state is not None
        self.people.reset(rows, fresh)
        for row, scenario in zip(rows, scenarios, strict=True):
            self.scenarios[row] = scenario
        self._ever_reset[rows] = True
        pose = fresh.robot_pose
        goal = fresh.robot_goal[..., :2]
        self.navigator.reset(rows, pose[..., :2], goal)
        self.prev_action[rows] = 0
        self.target_human[rows] = -1
        self.done[rows] = False
        robot_rows = self.robot_rows(rows)
        if self.sight is not None:
            self.sight.forget(robot_rows)
        self.metrics.reset(robot_rows, pose.reshape(-1, 3), goal.reshape(-1, 2))
        carrot = self.navigator.update(self.state.robot_pose[..., :2])
        self.carrot[rows] = carrot[rows]
        self._observe(rows)

    # ------------------------------------------------------------------ step
    @cached_property
    def _speeds(self) -> np.ndarray:
        robot = self.config.world.robot
        return np.array([robot.max_speed, robot.max_angular_speed])

    def robot_commands(self, action: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(command (B, R, 2), halt (B, R), target_human (B, R)) for robot actions.

        Raises:
            ValueError: an action outside the action space, naming the value and its row.
        """
        assert self.state is not None
        b, r = self.batch_size, self.num_robots
        state = self.state
        if self.config.robot_action == "velocity":
            action = np.asarray(action, dtype=np.float64)
            if action.shape != (b, r, 2):
                raise ValueError(f"velocity actions must have shape {(b, r, 2)}, got {action.shape}")
            bad = ~np.isfinite(action) | (np.abs(action) > 1.0)
            if bad.any():
                where = tuple(int(i) for i in np.argwhere(bad)[0])
                raise ValueError(f"velocity action {action[where]!r} at index {where} is not in [-1, 1]")
            command = action * self._speeds
            halt = np.zeros((b, r), dtype=bool)
            return command, halt, np.full((b, r), -1, dtype=np.intp)
        flat = check_actions(np.asarray(action).reshape(-1), b * r)
        human_pos, human_vel, human_mask = self._robot_obstacles()
        # The latest observation saw this very state: its visibility serves target selection.
        # Other robots (appended after the humans) are never Follow or Pass targets.
        visible = np.zeros(human_mask.shape, dtype=bool)
        visible[:, : self.visible.shape[1]] = self.visible
        command, halt, target = subpolicy_commands(
            flat,
            state.robot_pose.reshape(b * r, 3),
            state.robot_vel.reshape(b * r, 2),
            self.carrot.reshape(b * r, 2),
            human_pos,
            human_vel,
            human_mask,
            self.walls,
            self.config.subpolicy,
            self.config.planner,
            self.config.world.robot,
            self.config.dt,
            visible,
        )
        return command.reshape(b, r, 2), halt.reshape(b, r), target.reshape(b, r)

    def _robot_obstacles(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per robot (B*R rows): the humans, and with several robots the other robots too.

        Other robots are appended after the humans, so human indices keep their meaning.
        """
        assert self.state is not None
        s = self.state
        r = self.num_robots
        if r == 1:
            return s.human_pos, s.human_vel, s.human_mask
        b, h = s.human_pos.shape[:2]
        pos = np.concatenate((s.human_pos, s.robot_pose[..., :2]), axis=1)
        vel = np.concatenate((s.human_vel, robot_velocity_vectors(s)), axis=1)
        mask = np.concatenate((s.human_mask, np.ones((b, r), dtype=bool)), axis=1)
        mask = np.repeat(mask, r, axis=0)
        own = np.tile(np.arange(r), b)
        mask[np.arange(b * r), h + own] = False
        return np.repeat(pos, r, axis=0), np.repeat(vel, r, axis=0), mask

    def step(self, robot_action: np.ndarray, human_action: np.ndarray | None = None) -> StepResult:
        """Advance every row one step.

        Args:
            robot_action: (B, R) int sub-policy indices, or (B, R, 2) floats in [-1, 1] with
                robot_action="velocity".
            human_action: (B, L, 2) desired velocities in [-1, 1] (times the preferred speed and
                config.human_action_scale) for the L learned humans, in the frame config.human_action_frame names;
                required when config.num_learned_humans > 0.

        Returns:
            The StepResult. Robots whose episode ended halt and keep their final pose; their
            reward is 0 until their row is reset.

        Raises:
            RuntimeError: a row was never reset.
            ValueError: an action outside its space (naming the value and index), before any
                state changes.
        """
        if self.state is None or not self._ever_reset.all():
            raise RuntimeError("reset every row (reset_rows) before calling step")
        cfg = self.config
        before = self.state
        b, r = self.batch_size, self.num_robots
        desired, learned = self._human_drive(human_action)
        desired, learned = self.people.drive(before, desired, learned)
        command, halt, target = self.robot_commands(robot_action)
        halt = halt | self.done
        # Robots driving their plan (GoAlone, not halted): the navigator's recovery watches them.
        moving = np.zeros((b, r), dtype=bool)
        if cfg.robot_action == "subpolicy":
            moving = (np.asarray(robot_action).reshape(b, r) == GO_ALONE) & ~halt
        command = self._backoff(command, moving)
        command = np.where(self.done[..., None], 0.0, command)
        after, events = step_world(before, self.walls, cfg.world, command, halt, desired, learned)
        # A robot whose episode ended stays exactly where it stopped (the halting step's motion
        # model would still carry it half a step).
        after.robot_pose = np.where(self.done[..., None], before.robot_pose, after.robot_pose)
        self.state = after
        self.carrot = self.navigator.update(
            after.robot_pose[..., :2], moving, cfg.dt, after.human_pos, after.human_mask
        )
        if cfg.robot_action == "subpolicy":
            # A copy: reset_rows zeroes rows of prev_action, which must never write into the
            # caller's action array (a TorchRL rollout's recorded actions, a user's buffer).
            self.prev_action = np.array(robot_action, dtype=np.int64).reshape(b, r)
        self.target_human = target
        visible = self._observe(np.arange(b))

        skip = followed_human(robot_action, target, cfg.robot_action)
        out = robot_outcome(before, after, events, visible, skip, halt, self.done, cfg)
        self.metrics.update(
            robot_pose=after.robot_pose.reshape(b * r, 3),
            robot_vel=after.robot_vel.reshape(b * r, 2),
            reward=out.reward.reshape(-1),
            force=out.force.reshape(-1),
            blame=out.blame.reshape(-1),
            human_collisions=out.human_collisions.reshape(-1),
            wall_collision=out.wall_collision.reshape(-1),
            min_human_distance=self._min_human_distance(),
            reached=out.reached.reshape(-1),
            done=(out.terminated | out.truncated).reshape(-1),
            dt=cfg.dt,
            route_left=self.navigator.route_left.reshape(-1),
            halted=self._halted(halt, command).reshape(-1),
            rerouted=self.navigator.rerouted.reshape(-1),
        )
        was_done = self.done
        self.done = self.done | out.terminated | out.truncated
        self.people.step(before, after, was_done, self.done)
        human = None
        if len(self.learned):
            human = human_step(
                before, after, self.learned, self.walls, events.human_blocked, cfg.human_reward
            )
        return StepResult(
            obs=self.obs,
            reward=out.reward,
            terminated=out.terminated,
            truncated=out.truncated,
            reached=out.reached,
            wall_collision=out.wall_collision,
            human_collisions=out.human_collisions,
            force=out.force,
            blame=out.blame,
            progress=out.progress,
            target_human=target,
            human_obs=self.human_obs,
            human_reward=None if human is None else human.reward,
            events=events,
            human=human,
        )

    def _backoff(self, command: np.ndarray, moving: np.ndarray) -> np.ndarray:
        """Commands (B, R, 2) with those of recovering robots (the navigator's back-off) in place
        of their planner's, for robots still driving their plan."""
        rows, robots = np.nonzero(self.navigator.backing_off & moving)
        if len(rows) == 0:
            return command
        assert self.state is not None
        human_pos, _, human_mask = self._robot_obstacles()
        flat = rows * self.num_robots + robots
        command = command.copy()
        command[rows, robots] = backoff_commands(
            self.state.robot_pose[rows, robots],
            self.field,
            self.config.planner.wall_distance,
            self.navigator.recovery or RecoveryConfig(),
            human_pos[flat],
            human_mask[flat],
        )
        return command

    def _halted(self, halt: np.ndarray, command: np.ndarray) -> np.ndarray:
        """(B, R) robots the policy halted this step: the sub-policies' halt, or with velocity
        actions a zero command (the stuck metric's clock pauses for them)."""
        if self.config.robot_action == "velocity":
            return halt | ~np.any(command != 0.0, axis=-1)
        return halt

    def _human_drive(self, human_action: np.ndarray | None) -> tuple[np.ndarray | None, np.ndarray | None]:
        """(desired velocity (B, H, 2), learned mask (B, H)) for the learned humans, or (None, None)."""
        assert self.state is not None
        num = len(self.learned)
        if num == 0:
            if human_action is not None:
                raise ValueError("human actions given, but config.num_learned_humans is 0")
            return None, None
        if human_action is None:
            raise ValueError(
                f"config.num_learned_humans = {num}: human_action of shape (B, {num}, 2) is required"
            )
        action = np.asarray(human_action, dtype=np.float64)
        if action.shape != (self.batch_size, num, 2):
            raise ValueError(f"human_action must have shape {(self.batch_size, num, 2)}, got {action.shape}")
        bad = ~np.isfinite(action) | (np.abs(action) > 1.0)
        if bad.any():
            where = tuple(int(i) for i in np.argwhere(bad)[0])
            raise ValueError(f"human action {action[where]!r} at index {where} is not in [-1, 1]")
        s = self.state
        desired = np.zeros(s.human_pos.shape)
        desired[:, self.learned] = action_velocities(
            s, self.learned, action, self.config.human_action_frame, self.config.human_action_scale
        )
        learned = np.zeros(s.human_mask.shape, dtype=bool)
        learned[:, self.learned] = True
        return desired, learned & s.human_mask

    # ------------------------------------------------------------------ observe
    def _observe(self, rows: np.ndarray) -> np.ndarray:
        """Recompute observations (all rows are computed; `rows` are stored). Returns visibility (B*R, H)."""
        assert self.state is not None
        s = self.state
        b, r = self.batch_size, self.num_robots
        pose = s.robot_pose.reshape(b * r, 3)
        human_pos = np.repeat(s.human_pos, r, axis=0) if r > 1 else s.human_pos
        human_vel = np.repeat(s.human_vel, r, axis=0) if r > 1 else s.human_vel
        human_mask = np.repeat(s.human_mask, r, axis=0) if r > 1 else s.human_mask
        if self.sight is None:
            visible = np.array(human_mask, dtype=bool)
        else:
            visible = self.sight.visible(pose[:, :2], human_pos, human_mask)
        self.visible = visible
        obs = build_observation(
            self.config.observation,
            pose,
            s.robot_vel.reshape(b * r, 2),
            s.robot_goal[..., :2].reshape(b * r, 2),
            self.carrot.reshape(b * r, 2),
            self.prev_action.reshape(-1),
            human_pos,
            human_vel,
            visible,
        ).reshape(b, r, -1)
        self.obs[rows] = obs[rows]
        if len(self.learned):
            human_obs = human_observations(s, self.walls, self.learned, self.config.num_human_neighbours)
            if self.human_obs is None:
                self.human_obs = human_obs
            else:
                self.human_obs[rows] = human_obs[rows]
        return visible

    def _min_human_distance(self) -> np.ndarray:
        """(B*R,) centre distance from each robot to the nearest present human, inf for none."""
        assert self.state is not None
        s = self.state
        diff = s.robot_pose[:, :, None, :2] - s.human_pos[:, None, :, :]
        dist2 = np.where(s.human_mask[:, None, :], (diff**2).sum(-1), np.inf)
        return np.sqrt(dist2.min(axis=-1, initial=np.inf)).reshape(-1)

    # ------------------------------------------------------------------ results
    def episode_summaries(self, rows: np.ndarray | list[int], robot: int = 0) -> list[dict]:
        """Episode metrics (socialzoo.env.metrics.SUMMARY_KEYS) of `rows` for one robot, and the
        people's metrics the config asks for (socialzoo.env.people.People.keys)."""
        rows = np.asarray(rows, dtype=np.intp).reshape(-1)
        summaries = self.metrics.summaries(rows * self.num_robots + robot)
        if self.people.keys:
            for summary, extra in zip(summaries, self.people.summaries(rows, robot), strict=True):
                summary.update(extra)
        return summaries
