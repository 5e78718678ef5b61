"""The Social Action Selection task (SocialGym benchmark, SPEC sections 2 to 9) on the batched core.

R differential-drive robots cross a building among 5 to 25 people and pick, every 0.025 s step, one
of four sub-policies that drive them (GoAlone, Halt, Follow, Pass), or with
robot_action="velocity" their (v, omega) directly. The core (socialzoo.env.core.SocialNavCore)
steps the world, the navigator and the people; the episodes come from the map's seeded scenario
stream (socialzoo.env.scenario_source). Learned-human agents (EnvConfig.num_learned_humans) are
human slots a learner drives, for the multi-agent adapters.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces

from socialzoo.core.state import WorldState
from socialzoo.env.config import EnvConfig
from socialzoo.env.core import SocialNavCore, StepResult
from socialzoo.env.human_agents import human_observation_size
from socialzoo.env.observation import observation_space
from socialzoo.env.scenario_source import ScenarioStream, with_robots
from socialzoo.env.tasks.base import Task, TaskStep, fixed_cases
from socialzoo.maps.map_file import Map
from socialzoo.nav.subpolicies import ACTION_NAMES, NUM_ACTIONS
from socialzoo.scenarios.scenario import Scenario

# The sub-policy given to robots that already left (the core halts them anyway).
HALT = 1
# Per-step info of the learned-human agents: "contact" (within 0.4 m of anyone after the step),
# "present" (the slot holds a person), then the other reward terms of
# socialzoo.env.human_agents.HumanStep.
HUMAN_INFO_KEYS = ("contact", "present", "wall_contact", "waypoint_reached", "speed_error")


class ActionSelectionTask(Task):
    """Social Action Selection over B worlds (see the module docstring).

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

    def __init__(
        self,
        config: EnvConfig | None = None,
        batch_size: int = 1,
        *,
        map_data: Map | None = None,
        **overrides: Any,
    ) -> None:
        self.config = EnvConfig.resolve(config, overrides)
        cfg = self.config
        self.core = SocialNavCore(cfg, batch_size, map_data=map_data)
        num_poses = len(self.core.map.legal_poses)
        if cfg.num_robots > 1 and num_poses < cfg.num_robots + 1:
            raise ValueError(
                f"num_robots={cfg.num_robots} needs at least {cfg.num_robots + 1} legal poses for distinct "
                f"starts; map {self.core.map.name!r} has {num_poses}"
            )
        self.scenarios = ScenarioStream.for_config(self.core.map, batch_size, cfg)
        self.batch_size = batch_size
        self.num_robots = cfg.num_robots
        self.num_human_slots = cfg.max_humans
        self.num_human_agents = cfg.num_learned_humans
        self.observation_space = observation_space(cfg.observation)
        if cfg.robot_action == "subpolicy":
            self.action_space: spaces.Space = spaces.Discrete(NUM_ACTIONS)
        else:
            self.action_space = spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
        if self.num_human_agents:
            size = human_observation_size(cfg.num_human_neighbours)
            self.human_observation_space = spaces.Box(-np.inf, np.inf, (size,), dtype=np.float32)
            self.human_action_space = spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)

    # ------------------------------------------------------------------ episodes
    def seed(self, seed: int | None) -> None:
        """Reseed the rows' scenario streams."""
        self.scenarios.seed(seed)

    def reset(self, rows: np.ndarray, options: dict[str, Any]) -> np.ndarray:
        """Start the rows on their next scenarios, or on the scenarios the options give."""
        rows = np.asarray(rows, dtype=np.intp)
        options = dict(options)
        chosen = fixed_cases(options, rows, self.case_splits(), self.name)
        if chosen is not None:
            test_set = self._case_sets()[chosen[0]]
            if self.config.family is None:
                options["scenarios"] = [test_set.scenario(int(k), self.core.map) for k in chosen[1]]
            else:  # a family's cases: its own scenarios, drawn from the set's seeds
                options["scenarios"] = [self.scenarios.make(test_set.seed(int(k))) for k in chosen[1]]
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
            scenarios = [with_robots(s, self.core.map, self.num_robots) for s in scenarios]
        self.core.reset_rows(rows, scenarios)
        return np.array([int(s.seed) for s in scenarios], dtype=np.uint64)

    def case_splits(self) -> dict[str, int]:
        """The map's validation scenarios ("val", never a test set), and its registered test sets
        ("test" for "<map>-test", and each by its own name, e.g. "gdc1-quick"); a scenario
        family's cases are the family's scenarios of the same seeds."""
        return {name: len(test_set) for name, test_set in self._case_sets().items()}

    def _case_sets(self) -> dict[str, Any]:
        from socialzoo.scenarios.scenario import TEST_SETS, validation_set

        name = self.core.map.name
        sets: dict[str, Any] = {"val": validation_set(name)}
        sets.update({k: v for k, v in TEST_SETS.items() if v.map_name == name})
        if f"{name}-test" in TEST_SETS:
            sets["test"] = TEST_SETS[f"{name}-test"]
        return sets

    def step(self, action: np.ndarray, human_action: np.ndarray | None = None) -> TaskStep:
        """One 0.025 s step of every row (SocialNavCore.step)."""
        b, r = self.batch_size, self.num_robots
        if self.config.robot_action == "subpolicy":
            action = np.asarray(action).reshape(b, r)
        result = self.core.step(action, human_action)
        state = self.core.state
        assert state is not None
        human_info = None
        if self.num_human_agents:
            assert result.human is not None
            human = result.human
            human_info = {
                "contact": human.contact,
                "present": self.human_present(),
                "wall_contact": human.wall_contact,
                "waypoint_reached": human.waypoint_reached,
                "speed_error": human.speed_error,
            }
        return TaskStep(
            reward=result.reward,
            terminated=result.terminated,
            truncated=result.truncated,
            info={key: getattr(result, key) for key in StepResult.INFO_KEYS},
            time_up=state.step_count >= self.config.max_steps,
            human_reward=result.human_reward,
            human_info=human_info,
            detail=result,
        )

    def observations(self) -> np.ndarray:
        """(B, R, D) float32 robot observations (the core's buffer; adapters copy)."""
        return self.core.obs

    def episode_metrics(self, rows: np.ndarray, robot: int = 0) -> list[dict[str, Any]]:
        """The episode metrics (socialzoo.env.metrics.SUMMARY_KEYS and the people's)."""
        return self.core.episode_summaries(rows, robot)

    def compact(self, rows: np.ndarray) -> ActionSelectionTask:
        """A task over the core compacted to `rows` (socialzoo.env.compaction.compact_core: the
        world, plans, carrots, flags, observations and metrics so far); it only finishes them."""
        from socialzoo.env.compaction import compact_core

        new = object.__new__(type(self))
        new.__dict__.update(self.__dict__)
        new.core = compact_core(self.core, rows)
        new.batch_size = new.core.batch_size
        return new

    # ------------------------------------------------------------------ per-robot info
    @property
    def info_keys(self) -> tuple[str, ...]:
        """reached, wall_collision, human_collisions, force, blame, progress, target_human."""
        return StepResult.INFO_KEYS

    def initial_info(self) -> dict[str, Any]:
        """Neutral values (no target: -1)."""
        return StepResult.initial_info()

    def idle_action(self) -> Any:
        """Halt, or a zero velocity."""
        return HALT if self.config.robot_action == "subpolicy" else super().idle_action()

    def action_name(self, row: int = 0, robot: int = 0) -> str | None:
        """The name of the sub-policy robot `robot` of `row` took last (None with velocities)."""
        if self.config.robot_action != "subpolicy":
            return None
        return ACTION_NAMES[int(self.core.prev_action[row, robot])]

    # ------------------------------------------------------------------ learned-human agents
    def human_observations(self) -> np.ndarray | None:
        """(B, L, D_h) float32 (socialzoo.env.human_agents), or None."""
        return self.core.human_obs

    def human_present(self) -> np.ndarray:
        """(B, L) the scenario has a person in each learned slot."""
        state = self.core.state
        assert state is not None
        return state.human_mask[:, self.core.learned]

    # ------------------------------------------------------------------ world view
    @property
    def world_state(self) -> WorldState:
        """The core's WorldState."""
        assert self.core.state is not None
        return self.core.state

    # ------------------------------------------------------------------ the episode viewer
    def action_labels(self) -> tuple[str, ...]:
        """The sub-policies (GoAlone, Halt, Follow, Pass); none with velocity actions."""
        return tuple(ACTION_NAMES) if self.config.robot_action == "subpolicy" else ()

    def viewer_guides(self, row: int = 0) -> tuple[np.ndarray | None, np.ndarray | None]:
        """The carrot and the global plan of robot 0 (the navigator's)."""
        plans = self.core.navigator.plans
        length = int(plans.lengths[row, 0])
        return self.core.carrot[row, 0].copy(), plans.paths[row, 0, :length].copy()

    def viewer_laser(self) -> tuple[Any, Any, float] | None:
        """The config's laser (default LaserConfig()), the map's walls, the people's radius."""
        from socialzoo.core.config import LaserConfig

        world = self.config.world
        return world.laser or LaserConfig(), self.core.walls, world.human.radius

    def viewer_scene(self, title: str, subtitle: str, traces: Any) -> Any:
        """The map's walls and bounds, the robot's footprint, the people's and goal's radii."""
        from socialzoo.render.frames import map_bounds
        from socialzoo.render.replay_data import ReplayScene

        robot, m = self.config.world.robot, self.core.map
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

    def make_renderer(self, render_mode: str, view: str = "follow") -> Any:
        """socialzoo.env.rendering.CoreRenderer of the core."""
        from socialzoo.env.rendering import CoreRenderer

        return CoreRenderer(self.core, render_mode, view=view)
