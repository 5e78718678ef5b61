"""The task interface: what makes one robot task differ from another, over B worlds of R robots."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces


@dataclass(frozen=True)
class TaskStep:
    """One step of every robot (and learned-human agent) of the batch.

    Attributes:
        reward: (B, R) float64 rewards; 0 for robots whose episode had already ended.
        terminated: (B, R) bool, the episode ended this step (goal, collision, ...).
        truncated: (B, R) bool, the time limit ended the episode this step.
        info: per-step info of each robot, key -> (B, R) array (Task.info_keys, in that order).
        time_up: (B,) bool, the row's time limit has passed (learned-human agents leave).
        human_reward: (B, L) float64 rewards of the learned-human agents, or None.
        human_info: per-step info of each learned-human agent, key -> (B, L), or None.
        detail: the task's own record of the step, for tools that know the task (the
            action-selection task's socialzoo.env.tasks.action_selection.StepResult), or None.
    """

    reward: np.ndarray
    terminated: np.ndarray
    truncated: np.ndarray
    info: dict[str, np.ndarray]
    time_up: np.ndarray
    human_reward: np.ndarray | None = None
    human_info: dict[str, np.ndarray] | None = field(default=None)
    detail: Any = None


class Task(ABC):
    """A robot task over B worlds with R robots each (below).

    Arrays are batched: (B, R) per robot, (B, L) per learned-human agent, rows independent.

    Subclasses set `name`, build their config from `config` and plain-value `overrides` (what a
    registered id's kwargs hold), and set `config`, `batch_size`, `num_robots`,
    `observation_space` and `action_space` (one robot's) in `__init__`.

    Class attributes:
        name: the task's registry name (socialzoo.env.tasks.TASKS).
        render_modes: the render modes the task can draw ("rgb_array", "human").
        render_fps: frames per second of one step (`frames_per_second` unless the step is a
            config field).
        num_human_slots: H, person slots of each world (the global state's).
        num_human_agents: L, human slots driven by learners (agents "human_0" ..); 0 for most tasks.
        reset_info_key: the key of the reset info holding each row's scenario seed.
        neutral_info: a robot's per-step info keys, in order, with their values at reset.
    """

    name: ClassVar[str]
    render_modes: ClassVar[tuple[str, ...]] = ()
    render_fps: ClassVar[int] = 4
    reset_info_key: ClassVar[str] = "scenario_seed"
    # A robot's per-step info keys (TaskStep.info), in order, with their values at reset.
    neutral_info: ClassVar[dict[str, Any]] = {}

    config: Any
    batch_size: int
    num_robots: int
    observation_space: spaces.Space
    action_space: spaces.Space
    num_human_slots: int
    num_human_agents: int = 0
    human_observation_space: spaces.Space | None = None
    human_action_space: spaces.Space | None = None

    @abstractmethod
    def __init__(self, config: Any = None, batch_size: int = 1, **overrides: Any) -> None:
        """A task of `batch_size` rows: `config` (the task's config class; None: its defaults) with
        plain-value `overrides` of its fields (and the task's own keyword options, such as map_data).
        What make_task and every adapter call."""

    # ------------------------------------------------------------------ episodes
    @abstractmethod
    def seed(self, seed: int | None, rows: np.ndarray | None = None) -> None:
        """Reseed the training streams of `rows` (default every row) from `seed`: row i gets the
        stream row i of any batch seeded with `seed` plays; the other rows keep theirs."""

    @abstractmethod
    def reset(self, rows: np.ndarray, options: dict[str, Any]) -> np.ndarray:
        """Start new episodes in `rows`; returns each reset row's scenario seed (len(rows),).

        `options` are the adapter's reset options less its own: the task reads those it knows
        (every task: {"split": name, "cases": [k, ...]} or {"split": name, "case": k}, cases of
        case_splits(); a task may add its own, such as a scenario to replay) and ignores any
        other, as Gymnasium's and PettingZoo's envs may (PettingZoo's API test passes one).
        """

    def case_splits(self) -> dict[str, int]:
        """The task's fixed case sets by name (validation and test cases), with their sizes: reset
        options {"split": name, "cases": [k, ...]} start rows on cases k of a split."""
        return {}

    @abstractmethod
    def step(self, action: np.ndarray, human_action: np.ndarray | None = None) -> TaskStep:
        """Advance every row one step with (B, R, *action_space.shape) robot actions (and
        (B, L, 2) learned-human actions). Robots whose episode ended stand still; their reward
        is 0 until their row is reset.

        Raises:
            ValueError: an action outside its space, naming the value and its robot, before any
                state changes.
        """

    @abstractmethod
    def observations(self) -> Any:
        """Every robot's current observation: (B, R, ...) array, or a dict of such arrays."""

    @abstractmethod
    def episode_metrics(self, rows: np.ndarray, robot: int = 0) -> list[dict[str, Any]]:
        """The episode metrics of robot `robot` in each of `rows` (its episode so far, or the
        one that just ended)."""

    def compact(self, rows: np.ndarray) -> Task | None:
        """A task of len(rows) rows that continues the episodes of `rows`, in that order, for an
        evaluation's tail; None when the task cannot (the caller keeps stepping every row)."""
        return None

    @property
    def frames_per_second(self) -> float:
        """Steps per simulated second: the pace of render_mode "human" and the adapters'
        metadata["render_fps"]; the class's `render_fps` (a task whose step is a config field
        gives its own)."""
        return float(self.render_fps)

    # ------------------------------------------------------------------ per-robot info
    @property
    def info_keys(self) -> tuple[str, ...]:
        """The per-step info keys of a robot (TaskStep.info): those of `neutral_info`, in order."""
        return tuple(self.neutral_info)

    def initial_info(self) -> dict[str, Any]:
        """A robot's info at reset: info_keys with neutral values (a copy of `neutral_info`)."""
        return dict(self.neutral_info)

    def robot_info(self, step: TaskStep, row: int, robot: int) -> dict[str, Any]:
        """The per-step info dict of one robot: plain Python values (bool, int, float) under info_keys."""
        return {key: np.asarray(step.info[key][row, robot]).item() for key in self.info_keys}

    def action_name(self, row: int = 0, robot: int = 0) -> str | None:
        """A name for the action robot `robot` of `row` took last (for infos and frames), or None."""
        return None

    def idle_action(self) -> Any:
        """The action given for robots that already left (the task halts them anyway)."""
        return np.zeros(self.action_space.shape, dtype=np.float64)

    # ------------------------------------------------------------------ learned-human agents
    def human_observations(self) -> np.ndarray | None:
        """(B, L, D_h) float32 observations of the learned-human agents, or None without them."""
        return None

    def human_present(self) -> np.ndarray:
        """(B, L) bool: the scenario has a person in each learned-human slot."""
        return np.zeros((self.batch_size, 0), dtype=bool)

    # ------------------------------------------------------------------ world view
    @property
    def world_state(self) -> Any:
        """The batched WorldState (socialzoo.core.state) of the worlds the task steps: by default
        its core's (`self.core.state`, once reset)."""
        state = self.core.state  # type: ignore[attr-defined]
        assert state is not None
        return state

    # ------------------------------------------------------------------ the episode viewer
    def action_labels(self) -> tuple[str, ...]:
        """Names of the task's discrete actions (the viewer's action timeline and legend); empty
        when its actions have no names (velocities, or too many to name)."""
        return ()

    def viewer_guides(self, row: int = 0) -> tuple[np.ndarray | None, np.ndarray | None]:
        """(carrot (2,), global plan (L, 2)) that robot 0 of `row` follows, for the episode viewer
        (socialzoo.bench.replay): the core's navigator's, where it has one; None for either: the
        recorder draws the goal and the straight line from the start."""
        core: Any = getattr(self, "core", None)
        if getattr(core, "navigator", None) is None:
            return None, None
        plans = core.navigator.plans
        length = int(plans.lengths[row, 0])
        return core.carrot[row, 0].copy(), plans.paths[row, 0, :length].copy()

    def viewer_laser(self) -> tuple[Any, Any, float] | None:
        """(LaserConfig, WallIndex, person radius) of the scan the viewer draws, or None."""
        return None

    def viewer_scene(self, title: str, subtitle: str, traces: Any) -> Any:
        """The viewer's ReplayScene (socialzoo.render.replay_data): walls, bounds, body sizes.
        By default the world's walls around every trace's positions."""
        from socialzoo.render.replay_data import ReplayScene

        walls = getattr(getattr(self, "core", None), "walls", None)
        segments = np.zeros((0, 4)) if walls is None else np.asarray(walls.walls).reshape(-1, 4)
        points = np.concatenate(
            [
                np.concatenate((t.robot_pose[:, :2], t.human_pos.reshape(-1, 2), t.goal[None, :2]))
                for t in traces
            ]
            + ([segments.reshape(-1, 2)] if len(segments) else [])
        )
        low, high = points.min(0) - 1.0, points.max(0) + 1.0
        return ReplayScene(
            title=title,
            subtitle=subtitle,
            map_name=self.name,
            walls=segments,
            bounds=(float(low[0]), float(low[1]), float(high[0]), float(high[1])),
            robot_length=0.6,
            robot_width=0.6,
            human_radius=0.3,
            goal_radius=0.5,
            action_names=self.action_labels(),
        )

    def make_renderer(self, render_mode: str, view: str = "follow", **frame: Any) -> Any:
        """A renderer with `render(row=0)` and `close()` for one of `render_modes`; `frame` are the
        frames' options (socialzoo.env.rendering.CoreRenderer's width, height and info lines)."""
        raise ValueError(f"task {self.name!r} cannot render (render_modes {self.render_modes})")

    @classmethod
    def check_render_mode(cls, render_mode: str | None) -> None:
        """Refuse a render mode the task cannot draw, naming the ones it can."""
        if render_mode is not None and render_mode not in cls.render_modes:
            raise ValueError(
                f"render_mode must be None or one of {list(cls.render_modes)} for task {cls.name!r}, "
                f"got {render_mode!r}"
            )


def fixed_cases(
    options: dict[str, Any], rows: np.ndarray, splits: dict[str, int], task: str
) -> tuple[str, np.ndarray] | None:
    """(split, case indices) that reset options name for `rows`, or None when they name none;
    the options' "split", "cases" and "case" are taken out of `options`.

    Raises:
        ValueError: an unknown split, a count of cases other than the rows', or a case outside
            its split.
    """
    split = options.pop("split", None)
    cases = options.pop("cases", None)
    if "case" in options:
        cases = [options.pop("case")]
    if split is None and cases is None:
        return None
    split = "test" if split is None else split
    if split not in splits:
        raise ValueError(f"{task}: options split must be one of {sorted(splits)}, got {split!r}")
    if cases is None:
        raise ValueError(f"{task}: options split {split!r} needs case (one row) or cases (one per row)")
    # Whole numbers only: np.asarray(dtype=int64) would truncate 1.5 to case 1, take True as 1 and
    # fail on None or a string with numpy's words.
    values = np.asarray(cases, dtype=object).reshape(-1)
    if not all(isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_)) for v in values):
        raise ValueError(f"{task}: options case / cases must be whole case indices, got {cases!r}")
    if any(not -(2**63) <= int(v) < 2**63 for v in values):
        raise ValueError(f"{task}: the {split} split holds {splits[split]} cases; got {cases!r}")
    indices = values.astype(np.int64)
    if len(indices) != len(rows):
        raise ValueError(f"{task}: {len(rows)} rows to reset but {len(indices)} cases")
    outside = indices[(indices < 0) | (indices >= splits[split])]
    if len(outside):
        raise ValueError(f"{task}: the {split} split holds {splits[split]} cases; got {outside.tolist()}")
    return split, indices


def agent_action(space: spaces.Space, value: Any, who: str) -> Any:
    """`value` checked against one agent's `space`: one index of a Discrete(n) from an int-like
    value, int64 indices of a MultiDiscrete, or a float64 action of a Box; anything else raises
    naming `who`."""
    if isinstance(space, spaces.Discrete):
        n = int(space.n)
        array = np.asarray(value)
        ok = array.size == 1 and (
            np.issubdtype(array.dtype, np.integer) or np.issubdtype(array.dtype, np.floating)
        )
        if ok:
            scalar = array.reshape(()).item()
            ok = bool(np.isfinite(scalar)) and int(scalar) == scalar and 0 <= int(scalar) < n
        if not ok:
            raise ValueError(f"{who}: action must be one integer in 0..{n - 1}, got {value!r}")
        return int(scalar)
    if isinstance(space, spaces.MultiDiscrete):
        return batch_actions(space, value, (), who)
    if not isinstance(space, spaces.Box):
        raise TypeError(f"{who}: no action check for space {space}")
    try:
        box = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        box = None
    if (
        box is None
        or box.shape != space.shape
        or not np.isfinite(box).all()
        or (box < space.low).any()
        or (box > space.high).any()
    ):
        raise ValueError(
            f"{who}: action must be {space.shape} finite numbers in [{space.low.min()}, {space.high.max()}], "
            f"got {value!r}"
        )
    return box


def batch_actions(space: spaces.Space, values: Any, batch: tuple[int, ...], who: str) -> np.ndarray:
    """A batch of actions of `space` with leading shape `batch` (int64 indices for Discrete and
    MultiDiscrete, float64 for Box); integral floats count as indices. Raises naming `who` and the
    first bad entry (a Box's values are the task's to range-check, or `check_box_batch`'s)."""
    array = np.asarray(values)
    shape = batch + tuple(space.shape or ())
    if isinstance(space, (spaces.Discrete, spaces.MultiDiscrete)):
        if array.shape != shape or not (
            np.issubdtype(array.dtype, np.integer)
            or (
                np.issubdtype(array.dtype, np.floating)
                and np.isfinite(array).all()
                and (array == np.round(array)).all()
            )
        ):
            raise ValueError(f"{who}: actions must be {shape} integers, got {values!r}")
        array = array.astype(np.int64)
        # Each entry's count of choices: n, or the MultiDiscrete's nvec entry of its position.
        counts = np.asarray(space.n if isinstance(space, spaces.Discrete) else space.nvec, dtype=np.int64)
        bad = np.argwhere((array < 0) | (array >= counts))
        if len(bad):
            where = tuple(int(i) for i in bad[0])
            top = int(np.broadcast_to(counts, shape)[where]) - 1
            raise ValueError(f"{who}: action {int(array[where])} at {where} is not in 0..{top}")
        return array
    if array.shape != shape:
        raise ValueError(f"{who}: actions must have shape {shape}, got {array.shape}")
    if not (np.issubdtype(array.dtype, np.number) or array.dtype == np.bool_):
        raise ValueError(f"{who}: actions must be numbers, got {array.dtype} {values!r}")
    return array.astype(np.float64)


def check_box_batch(space: spaces.Box, actions: np.ndarray, who: str) -> None:
    """Raise ValueError naming `who` and the first entry of `actions` (a batch of `space`'s actions,
    float64) that is not a finite number within its own bounds. Apart from batch_actions: the tasks
    check their own ranges in their step, so the adapters of one task need no second check."""
    bad = ~np.isfinite(actions) | (actions < space.low) | (actions > space.high)
    if bad.any():
        where = tuple(int(i) for i in np.argwhere(bad)[0])
        low, high = np.broadcast_to(space.low, actions.shape), np.broadcast_to(space.high, actions.shape)
        raise ValueError(
            f"{who}: action {actions[where]} at {where} is not a finite number in [{low[where]}, {high[where]}]"
        )
