"""The Social Action Selection task (SocialGym benchmark, SPEC sections 2 to 9) on the batched core."""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces

from socialzoo.env.config import EnvConfig
from socialzoo.env.core import BatchedCore
from socialzoo.env.human_agents import (
    HumanStep,
    action_velocities,
    human_observation_size,
    human_observations,
    human_step,
)
from socialzoo.env.metrics import EpisodeMetrics
from socialzoo.env.observation import Signals, build_observation, nearest_door, observation_space
from socialzoo.env.outcome import RobotOutcome, followed_human, robot_outcome
from socialzoo.env.scenario_source import ScenarioStream, with_robots
from socialzoo.env.tasks.base import Task, TaskStep, fixed_cases
from socialzoo.env.world import StepEvents
from socialzoo.maps.map_file import Map, load_map
from socialzoo.nav.recovery import RecoveryConfig, backoff_commands
from socialzoo.nav.subpolicies import ACTION_NAMES, GO_ALONE, NUM_ACTIONS, check_actions, subpolicy_commands
from socialzoo.scenarios.scenario import Scenario

# The sub-policy given to robots that already left (the core halts them anyway).
HALT = 1
# How far a scenario given to reset may reach beyond the map's walls and graph, m.
_MAP_MARGIN = 1.0
# Per-step info of the learned-human agents: "contact" (within 0.4 m of anyone after the step),
# "present" (the slot holds a person), then the other reward terms of
# socialzoo.env.human_agents.HumanStep.
HUMAN_INFO_KEYS = ("contact", "present", "wall_contact", "waypoint_reached", "speed_error")
# The per-step info of a robot (TaskStep.info: StepResult fields), neutral at reset (no target: -1);
# force and blame leave out the followed human during Follow only.
INITIAL_INFO: dict[str, Any] = {
    "reached": False,
    "wall_collision": False,
    "human_collisions": 0,
    "force": 0.0,
    "blame": 0.0,
    "progress": 0.0,
    "target_human": -1,
}


@dataclass(frozen=True)
class StepResult(RobotOutcome):
    """One step of every robot (and learned human) of the batch: the robots' outcome
    (socialzoo.env.outcome.RobotOutcome: reward, terms, goal, collisions, episode end) and more.

    Attributes:
        obs: (B, R, D) float32 robot observations after the step.
        target_human: (B, R) human followed or passed this step, -1 for none.
        human_obs: (B, L, D_h) learned-human observations, or None without learned humans.
        human_reward: (B, L) learned-human rewards, or None.
        events: the world's collision events of the step.
        human: the learned humans' reward terms and contacts (HumanStep), or None.
    """

    obs: np.ndarray
    target_human: np.ndarray
    human_obs: np.ndarray | None
    human_reward: np.ndarray | None
    events: StepEvents
    human: HumanStep | None = None


class ActionSelectionTask(Task):
    """Social Action Selection over B worlds (below).

    R differential-drive robots cross a building among 5 to 25 people and pick, every 0.025 s step,
    one of four sub-policies that drive them (GoAlone, Halt, Follow, Pass), or with
    robot_action="velocity" their (v, omega) directly. The core (socialzoo.env.core.BatchedCore)
    steps the world, the people, the navigator (with recovery) and the robots' sight; the task
    turns each action into the robot's command (socialzoo.nav.subpolicies, the navigator's back-off
    for a recovering robot), builds the observation (socialzoo.env.observation), judges the step
    (socialzoo.env.outcome: reward, goal, episode end) and keeps the episode metrics
    (socialzoo.env.metrics, and the people's, socialzoo.env.people). The episodes come from the
    map's seeded scenario stream (socialzoo.env.scenario_source), or a scenario family's
    (EnvConfig.family); with EnvConfig.signals the observation also carries what the scenario's
    script shows (each human slot's gesture and the nearest door, socialzoo.env.observation's
    signal block). Learned-human agents (EnvConfig.num_learned_humans) are human slots a learner
    drives, for the multi-agent adapters (socialzoo.env.human_agents).

    Args:
        config: an EnvConfig (default: the benchmark on gdc1).
        batch_size: B.
        map_data: an already loaded Map instead of config.map.
        **overrides: EnvConfig fields as plain values (nested configs as dicts).

    Reset options: {"split": name, "cases": [k, ...]} the cases of a validation or test set
    (case_splits); {"scenario": Scenario} replays a scenario in the one row being reset (robots
    beyond its own get poses as the stream gives them); {"scenarios": [...]} one per reset row.
    """

    name: ClassVar[str] = "action_selection"
    render_modes: ClassVar[tuple[str, ...]] = ("human", "rgb_array")
    render_fps: ClassVar[int] = 40
    reset_info_key: ClassVar[str] = "scenario_seed"
    neutral_info: ClassVar[dict[str, Any]] = INITIAL_INFO

    def __init__(
        self,
        config: EnvConfig | None = None,
        batch_size: int = 1,
        *,
        map_data: Map | None = None,
        **overrides: Any,
    ) -> None:
        self.config = cfg = EnvConfig.resolve(config, overrides)
        if map_data is not None and not isinstance(map_data, Map):  # e.g. --task-config map_data=x
            raise ValueError(f"map_data must be a loaded Map (config.map names a file), got {map_data!r}")
        m = map_data if map_data is not None else load_map(cfg.map_name)
        b, r = batch_size, cfg.num_robots
        self.core = BatchedCore(
            b,
            r,
            cfg.max_humans,
            cfg.world,
            m.wall_index,
            m=m,
            people=cfg.people,
            planner=cfg.planner,
            recovery=RecoveryConfig(),
            sight_lines=True,
        )
        num_poses = len(m.legal_poses)
        if r > 1 and num_poses < r + 1:
            raise ValueError(
                f"num_robots={r} needs at least {r + 1} legal poses for distinct starts; map {m.name!r} "
                f"has {num_poses}"
            )
        self.map = m
        self.scenarios = ScenarioStream.for_config(m, b, cfg)
        self.batch_size = b
        self.num_robots = r
        self.num_human_slots = cfg.max_humans
        self.num_human_agents = cfg.num_learned_humans
        self.observation_space = observation_space(cfg.observation, cfg.signals)
        if cfg.robot_action == "subpolicy":
            self.action_space: spaces.Space = spaces.Discrete(NUM_ACTIONS)
        else:
            self.action_space = spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
        if self.num_human_agents:
            size = human_observation_size(cfg.num_human_neighbours)
            self.human_observation_space = spaces.Box(-np.inf, np.inf, (size,), dtype=np.float32)
            self.human_action_space = spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
        self.metrics = EpisodeMetrics(b * r, cfg.metrics)
        self.learned = np.arange(cfg.num_learned_humans)
        self.speeds = np.array([cfg.world.robot.max_speed, cfg.world.robot.max_angular_speed])
        self.prev_action = np.zeros((b, r), dtype=np.int64)
        self._map_box: tuple[np.ndarray, np.ndarray] | None = None  # _check_on_map's, on first use
        self.target_human = np.full((b, r), -1, dtype=np.intp)
        self.obs = np.zeros((b, r, cfg.observation_size), dtype=np.float32)
        self.human_obs: np.ndarray | None = None

    # ------------------------------------------------------------------ episodes
    def seed(self, seed: int | None, rows: np.ndarray | None = None) -> None:
        """Reseed the scenario streams of `rows` (default all; Task.seed)."""
        self.scenarios.seed(seed, rows)

    def reset(self, rows: np.ndarray, options: dict[str, Any]) -> np.ndarray:
        """Start the rows on their next scenarios, or on the scenarios the options give."""
        rows = np.asarray(rows, dtype=np.intp)
        m = self.map
        options = dict(options)
        chosen = fixed_cases(options, rows, self.case_splits(), self.name)
        if chosen is not None:
            options["scenarios"] = self.scenarios.cases(*chosen)
        scenarios = options.pop("scenarios", None)
        one = options.pop("scenario", None)
        if one is not None:
            if len(rows) != 1:
                raise ValueError(f"options['scenario'] replays one row, but {len(rows)} rows are reset")
            scenarios = [one]
        if scenarios is None:
            scenarios = self.scenarios.next(rows)
        else:
            for scenario in scenarios:
                if not isinstance(scenario, Scenario):
                    raise TypeError(f"options['scenario'] must be a Scenario, got {type(scenario).__name__}")
            if len(scenarios) != len(rows):
                raise ValueError(f"options['scenarios']: {len(scenarios)} for {len(rows)} rows")
            if chosen is None:  # one's own scenarios: made for this map?
                self._check_on_map(scenarios)
            scenarios = [with_robots(s, m, self.num_robots) for s in scenarios]
        self.reset_rows(rows, scenarios)
        return np.array([int(s.seed) for s in scenarios], dtype=np.uint64)

    def _check_on_map(self, scenarios: list[Scenario]) -> None:
        """Refuse a given scenario with a point beyond the map's walls and graph (by _MAP_MARGIN):
        most likely one made for another map (reset(options={"scenario": ...}) takes any Scenario)."""
        if self._map_box is None:
            corners = np.vstack((self.map.walls.reshape(-1, 2), self.map.nodes))
            self._map_box = (corners.min(axis=0) - _MAP_MARGIN, corners.max(axis=0) + _MAP_MARGIN)
        low, high = self._map_box
        for scenario in scenarios:
            where = scenario.first_outside(low, high)
            if where is not None:
                raise ValueError(
                    f"options['scenario']: the {where} of scenario {scenario.family} seed {scenario.seed} "
                    f"(made for map {scenario.map_name!r}) lies outside map {self.map.name!r} "
                    f"({low[0]:.1f}..{high[0]:.1f} x {low[1]:.1f}..{high[1]:.1f} m): a scenario of another map?"
                )

    def reset_rows(self, rows: np.ndarray, scenarios: list[Scenario]) -> None:
        """Start new episodes in `rows` from `scenarios` (one per row, with the task's robots)."""
        core = self.core
        rows = core.check_rows(rows, len(scenarios))
        if len(rows) == 0:
            return
        core.reset_rows(rows, scenarios)
        assert core.state is not None
        self.prev_action[rows] = 0
        self.target_human[rows] = -1
        pose, goal = core.state.robot_pose[rows], core.state.robot_goal[rows][..., :2]
        self.metrics.reset(core.robot_rows(rows), pose.reshape(-1, 3), goal.reshape(-1, 2))
        self._observe(rows)

    def case_splits(self) -> dict[str, int]:
        """The stream's fixed case sets (socialzoo.env.scenario_source.ScenarioStream.case_sets: the
        map's validation scenarios and registered test sets, or a scenario family's own splits; a
        family without splits plays the map's sets' seeds as its scenarios)."""
        return self.scenarios.case_sizes()

    def step(self, action: np.ndarray, human_action: np.ndarray | None = None) -> TaskStep:
        """Advance every row one 0.025 s step.

        Args:
            action: (B, R) int sub-policy indices, or (B, R, 2) floats in [-1, 1] with
                robot_action="velocity".
            human_action: (B, L, 2) desired velocities in [-1, 1] (times the preferred speed and
                config.human_action_scale) for the L learned humans, in the frame
                config.human_action_frame names; required when config.num_learned_humans > 0.

        Returns:
            The TaskStep, its detail the StepResult. Robots whose episode ended halt and keep their
            final pose; their reward is 0 until their row is reset.

        Raises:
            RuntimeError: a row was never reset.
            ValueError: an action outside its space (naming the value and index), before any
                state changes.
        """
        core, cfg = self.core, self.config
        core.check_reset()
        b, r = self.batch_size, self.num_robots
        subpolicy = cfg.robot_action == "subpolicy"
        if subpolicy:
            action = np.asarray(action).reshape(b, r)
        desired, learned = self._human_drive(human_action)
        command, halt, target = self.robot_commands(action)
        halt = halt | core.done
        # Robots driving their plan (GoAlone, not halted): the navigator's recovery watches them.
        moving = (action == GO_ALONE) & ~halt if subpolicy else np.zeros((b, r), dtype=bool)
        command = self._backoff(command, moving)
        was_done = core.done
        before = core.state
        events = core.step(command, halt, desired, learned)
        after = core.state
        # check_reset passed; the task's planner gives its core a navigator.
        assert before is not None and after is not None and core.navigator is not None
        core.follow_routes(moving)
        if subpolicy:
            # A copy: reset_rows zeroes rows of prev_action, which must never write into the
            # caller's action array (a TorchRL rollout's recorded actions, a user's buffer).
            self.prev_action = np.array(action, dtype=np.int64)
        self.target_human = target
        visible = self._observe(np.arange(b))
        skip = followed_human(action, target, cfg.robot_action)
        may_arrive = core.escort_ok() if core.script.active else None
        # A recorded scene's episode has its own time budget (socialzoo.scenarios.recorded).
        budget = core.time_limit
        max_steps = (
            np.ceil(budget / cfg.dt - 1e-9) if core.replay.active and np.isfinite(budget).any() else None
        )
        out = robot_outcome(before, after, events, visible, skip, halt, was_done, cfg, may_arrive, max_steps)
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
            route_left=core.route_left.reshape(-1),
            halted=(halt | ~np.any(command != 0.0, axis=-1) if not subpolicy else halt).reshape(-1),
            rerouted=core.navigator.rerouted.reshape(-1),
        )
        core.end_episodes(out.terminated | out.truncated)
        human = None
        if len(self.learned):
            human = human_step(
                before, after, self.learned, core.walls, events.human_blocked, cfg.human_reward
            )
        result = StepResult(
            **vars(out),
            obs=self.obs,
            target_human=target,
            human_obs=self.human_obs,
            human_reward=None if human is None else human.reward,
            events=events,
            human=human,
        )
        human_info = None
        if human is not None:
            present = self.human_present()
            human_info = {k: present if k == "present" else getattr(human, k) for k in HUMAN_INFO_KEYS}
        return TaskStep(
            reward=result.reward,
            terminated=result.terminated,
            truncated=result.truncated,
            info={key: getattr(result, key) for key in INITIAL_INFO},
            time_up=after.step_count >= cfg.max_steps,
            human_reward=result.human_reward,
            human_info=human_info,
            detail=result,
        )

    def robot_commands(self, action: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(command (B, R, 2), halt (B, R), target_human (B, R)) for robot actions: the sub-policies'
        commands, or with velocity actions (v, omega) as fractions of the robot's top speeds.

        Raises:
            ValueError: an action outside the action space, naming the value and its row.
        """
        core = self.core
        state = core.state
        assert state is not None
        b, r = self.batch_size, self.num_robots
        if self.config.robot_action == "velocity":
            action = _unit_actions(action, (b, r, 2), "velocity actions", "velocity action")
            return action * self.speeds, np.zeros((b, r), dtype=bool), np.full((b, r), -1, dtype=np.intp)
        flat = check_actions(np.asarray(action).reshape(-1), b * r)
        human_pos, human_vel, human_mask = core.others(state)
        # The latest observation saw this very state: its visibility serves target selection.
        # Other robots (appended after the humans) are never Follow or Pass targets.
        visible = np.zeros(human_mask.shape, dtype=bool)
        visible[:, : core.visible.shape[1]] = core.visible
        command, halt, target = subpolicy_commands(
            flat,
            state.robot_pose.reshape(b * r, 3),
            state.robot_vel.reshape(b * r, 2),
            core.carrot.reshape(b * r, 2),
            human_pos,
            human_vel,
            human_mask,
            core.walls,
            self.config.subpolicy,
            self.config.planner,
            self.config.world.robot,
            self.config.dt,
            visible,
        )
        return command.reshape(b, r, 2), halt.reshape(b, r), target.reshape(b, r)

    def _backoff(self, command: np.ndarray, moving: np.ndarray) -> np.ndarray:
        """Commands (B, R, 2) with those of recovering robots (the navigator's back-off) in place
        of their planner's, for robots still driving their plan."""
        core = self.core
        # A planner's core (navigator, wall field) after a reset.
        assert core.navigator is not None and core.field is not None and core.state is not None
        rows, robots = np.nonzero(core.navigator.backing_off & moving)
        if len(rows) == 0:
            return command
        human_pos, _, human_mask = core.others(core.state)
        flat = rows * self.num_robots + robots
        command = command.copy()
        command[rows, robots] = backoff_commands(
            core.state.robot_pose[rows, robots],
            core.field,
            self.config.planner.wall_distance,
            core.navigator.recovery or RecoveryConfig(),
            human_pos[flat],
            human_mask[flat],
        )
        return command

    def _human_drive(self, human_action: np.ndarray | None) -> tuple[np.ndarray | None, np.ndarray | None]:
        """(desired velocity (B, H, 2), learned mask (B, H)) for the learned humans, or (None, None)."""
        num = len(self.learned)
        if num == 0:
            if human_action is not None:
                raise ValueError("human actions given, but config.num_learned_humans is 0")
            return None, None
        if human_action is None:
            raise ValueError(
                f"config.num_learned_humans = {num}: human_action of shape (B, {num}, 2) is required"
            )
        action = _unit_actions(human_action, (self.batch_size, num, 2), "human_action", "human action")
        s = self.core.state
        assert s is not None
        desired = np.zeros(s.human_pos.shape)
        desired[:, self.learned] = action_velocities(
            s, self.learned, action, self.config.human_action_frame, self.config.human_action_scale
        )
        learned = np.zeros(s.human_mask.shape, dtype=bool)
        learned[:, self.learned] = True
        return desired, learned & s.human_mask

    def _observe(self, rows: np.ndarray) -> np.ndarray:
        """Recompute the observations (of every row; `rows` are stored) and who each robot sees;
        returns the visibility (B*R, H)."""
        core = self.core
        s = core.state
        assert s is not None
        b, r = self.batch_size, self.num_robots
        visible = core.see()
        obs = build_observation(
            self.config.observation,
            s.robot_pose.reshape(b * r, 3),
            s.robot_vel.reshape(b * r, 2),
            s.robot_goal[..., :2].reshape(b * r, 2),
            core.carrot.reshape(b * r, 2),
            self.prev_action.reshape(-1),
            core.per_robot(s.human_pos),
            core.per_robot(s.human_vel),
            visible,
            self._signals() if self.config.signals else None,
            theta_index=self.config.quirks.human_theta_index,
        ).reshape(b, r, -1)
        self.obs[rows] = obs[rows]
        if len(self.learned):
            human_obs = human_observations(s, core.walls, self.learned, self.config.num_human_neighbours)
            if self.human_obs is None:
                self.human_obs = human_obs
            else:
                self.human_obs[rows] = human_obs[rows]
        return visible

    def _signals(self) -> Signals:
        """What each robot (B R) observes of the scripts: the people's gestures, the nearest door."""
        core, script = self.core, self.core.script
        assert core.state is not None
        pos = core.state.robot_pose[..., :2].reshape(-1, 2)
        offset, closed = nearest_door(pos, core.per_robot(script.doors), core.per_robot(script.closed))
        return Signals(core.per_robot(script.signal), offset, closed)

    def _min_human_distance(self) -> np.ndarray:
        """(B*R,) centre distance from each robot to the nearest present human, inf for none."""
        s = self.core.state
        assert s is not None
        diff = s.robot_pose[:, :, None, :2] - s.human_pos[:, None, :, :]
        dist2 = np.where(s.human_mask[:, None, :], (diff**2).sum(-1), np.inf)
        return np.sqrt(dist2.min(axis=-1, initial=np.inf)).reshape(-1)

    def observations(self) -> np.ndarray:
        """(B, R, D) float32 robot observations (the task's buffer; adapters copy)."""
        return self.obs

    def episode_metrics(self, rows: np.ndarray, robot: int = 0) -> list[dict[str, Any]]:
        """Episode metrics (socialzoo.env.metrics.SUMMARY_KEYS) of `rows` for one robot, and the
        people's metrics the config asks for (socialzoo.env.people.People.keys)."""
        rows = np.asarray(rows, dtype=np.intp).reshape(-1)
        summaries = self.metrics.summaries(rows * self.num_robots + robot)
        people = self.core.people
        if people.keys:
            for summary, extra in zip(summaries, people.summaries(rows, robot), strict=True):
                summary.update(extra)
        replay = self.core.replay
        if replay.recorded[rows].any():  # against the recording (socialzoo.env.replay)
            arrival = [s["time_to_goal"] if s["success"] else float("nan") for s in summaries]
            for summary, extra in zip(summaries, replay.summaries(rows, arrival, robot), strict=True):
                summary.update(extra)
        return summaries

    def compact(self, rows: np.ndarray) -> ActionSelectionTask:
        """A task over the core compacted to `rows` (socialzoo.env.compaction.compact_core: the
        world, plans, carrots, sight, flags and the people so far) with the task's own rows of
        them (previous actions, followed humans, observations, metrics); it only finishes them."""
        from socialzoo.env.compaction import compact_core, copy_rows

        index = np.asarray(rows, dtype=np.intp).reshape(-1)
        new = copy.copy(self)
        new.core = compact_core(self.core, index)
        new.batch_size = new.core.batch_size
        for name in ("prev_action", "target_human", "obs"):
            setattr(new, name, getattr(self, name)[index].copy())
        if self.human_obs is not None:
            new.human_obs = self.human_obs[index].copy()
        new.metrics = copy.copy(self.metrics)
        new.metrics.batch_size = len(index) * self.num_robots
        copy_rows(self.metrics, new.metrics, self.core.robot_rows(index), self.metrics.batch_size)
        return new

    # ------------------------------------------------------------------ per-robot info
    def idle_action(self) -> Any:
        """Halt, or a zero velocity."""
        return HALT if self.config.robot_action == "subpolicy" else super().idle_action()

    def action_name(self, row: int = 0, robot: int = 0) -> str | None:
        """The name of the sub-policy robot `robot` of `row` took last (None with velocities)."""
        if self.config.robot_action != "subpolicy":
            return None
        return ACTION_NAMES[int(self.prev_action[row, robot])]

    # ------------------------------------------------------------------ learned-human agents
    def human_observations(self) -> np.ndarray | None:
        """(B, L, D_h) float32 (socialzoo.env.human_agents), or None."""
        return self.human_obs

    def human_present(self) -> np.ndarray:
        """(B, L) the scenario has a person in each learned slot."""
        state = self.core.state
        assert state is not None
        return state.human_mask[:, self.learned]

    # ------------------------------------------------------------------ the episode viewer
    def action_labels(self) -> tuple[str, ...]:
        """The sub-policies (GoAlone, Halt, Follow, Pass); none with velocity actions."""
        return tuple(ACTION_NAMES) if self.config.robot_action == "subpolicy" else ()

    def viewer_laser(self) -> tuple[Any, Any, float] | None:
        """The config's laser (default LaserConfig()), the map's walls, the people's radius."""
        from socialzoo.core.config import LaserConfig

        world = self.config.world
        return world.laser or LaserConfig(), self.core.walls, world.human.radius

    def viewer_scene(self, title: str, subtitle: str, traces: Any) -> Any:
        """The map's walls and bounds, the robot's footprint, the people's and goal's radii."""
        from socialzoo.render.frames import map_bounds
        from socialzoo.render.replay_data import ReplayScene

        robot, m = self.config.world.robot, self.map
        return ReplayScene(
            title=title,
            subtitle=subtitle,
            map_name=m.name,
            walls=m.walls,
            bounds=map_bounds(m),
            robot_length=robot.length,
            robot_width=robot.width,
            human_radius=self.config.world.human.radius,
            goal_radius=self.config.goal_radius,
            action_names=self.action_labels(),
        )

    @property
    def frames_per_second(self) -> float:
        """One frame per step, the world's dt (40 at the benchmark's 0.025 s)."""
        return 1.0 / self.config.dt

    def make_renderer(self, render_mode: str, view: str = "follow", **frame: Any) -> Any:
        """socialzoo.env.rendering.CoreRenderer of the task."""
        from socialzoo.env.rendering import CoreRenderer

        return CoreRenderer(self, render_mode, view=view, **frame)


def _unit_actions(values: Any, shape: tuple[int, ...], name: str, item: str) -> np.ndarray:
    """float64 actions of `shape` in [-1, 1]; anything else raises naming `name` (a wrong shape)
    or `item` and its index (a value outside)."""
    action = np.asarray(values, dtype=np.float64)
    if action.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {action.shape}")
    bad = ~np.isfinite(action) | (np.abs(action) > 1.0)
    if bad.any():
        where = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(f"{item} {action[where]!r} at index {where} is not in [-1, 1]")
    return action
