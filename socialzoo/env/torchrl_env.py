"""A native TorchRL multi-agent environment: B worlds of the batched core stepped as one EnvBase."""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from gymnasium import spaces
from tensordict import TensorDict, TensorDictBase
from torchrl.data import Bounded, Categorical, Composite, Unbounded
from torchrl.envs import EnvBase

from socialzoo.core.validation import check_int, check_seed
from socialzoo.env.gym_env import TaskAdapter
from socialzoo.env.parallel import STATE_HUMAN_SIZE, STATE_ROBOT_SIZE, global_state
from socialzoo.env.tasks.action_selection import HUMAN_INFO_KEYS
from socialzoo.env.tasks.base import TaskStep
from socialzoo.env.torchrl_single import box_observation, reset_rows, vector_action_spec

ROBOT = "robot"
HUMAN = "human"
_DONE_KEYS = ("done", "terminated", "truncated")


class SocialNavTorchEnv(TaskAdapter, EnvBase):
    """B worlds of R robots and L learned humans (plus scripted humans) as a TorchRL EnvBase.

    ## Description
    The multi-agent view of B worlds, with the agents stacked in the groups "robot" and "human"
    ("Keys and TorchRL Conventions" below lists every key); the same transitions as TorchRL's PettingZooWrapper
    over `SocialNavParallelEnv`, without a per-agent Python loop.

    ## Action Space
    ("robot", "action"): (B, R) int64 sub-policies (Discrete(4)), or (B, R, 2) velocities in
    [-1, 1] with robot_action="velocity"; absent when `robot_policy` drives the robots.
    ("human", "action"): (B, L, 2) desired velocities in [-1, 1] (x the preferred speed).

    ## Observation Space
    ("robot", "observation") (B, R, D) float32, the benchmark observation; ("human",
    "observation") (B, L, D_h) float32 (socialzoo.env.human_agents); "state" (B, 8 R + 5 H)
    float32, the global state (SocialNavParallelEnv.state is float64: float32 rounds positions
    to steps of up to 0.5 m on maps at UTM-sized coordinates); (group, "mask") (B, n) bool, the agents that act.

    ## Rewards
    ("robot", "reward") (B, R, 1): the benchmark reward; ("human", "reward") (B, L, 1): the
    weighted terms of config.human_reward (see `SocialNavParallelEnv`).

    ## Starting State
    Each reset row starts on the next scenario of its seeded stream (as `SocialNavParallelEnv`).

    ## Episode End
    (group, "done" | "terminated" | "truncated") (B, n, 1) per agent; the row's "done" (B, 1)
    when its last robot has left (goal, wall or time limit).

    ## Keys and TorchRL Conventions
    The task is stepped directly (no PettingZoo, no per-agent Python loop), with batch_size [B]
    and the agents stacked in two groups by their name prefix, as TorchRL's PettingZooWrapper
    groups the ParallelEnv's "robot_i" and "human_j":

        ("robot", "observation")  (B, R, D) float32      ("human", "observation")  (B, L, D_h) float32
        ("robot", "action")       (B, R) int64 sub-policy, or (B, R, 2) velocity in [-1, 1]
        ("human", "action")       (B, L, 2) desired velocity in [-1, 1] (x preferred speed)
        ("robot", "reward")       (B, R, 1)              ("human", "reward")       (B, L, 1)
        (group, "done" | "terminated" | "truncated")  (B, n, 1) bool
        (group, "mask")           (B, n) bool: the agent acts (alive; for humans also present)
        (group, "info", key)      (B, n) float32 per-step info
        "state"                   (B, 8 R + 5 H) float32 global state (SocialNavParallelEnv.state)
        "done", "terminated", "truncated"  (B, 1) bool: the row's episode ended

    The transitions are those of `PettingZooWrapper(SocialNavParallelEnv(...), use_mask=True,
    return_state=True, done_on_any=False)` for the same seed (tests/env/test_torchrl_env.py checks
    it), with one deliberate difference: ("human", "mask") is False for empty human slots (the
    wrapper keeps them as live agents with zero observations), so learners can leave them out.

    - Agents that left: a robot leaves on the step it terminates (goal, wall) or is truncated
      (time limit); afterwards its observation and reward are zeros, its mask False and its done,
      terminated and truncated flags all True, as the PettingZooWrapper reports a dead agent.
      Learned humans never terminate; they are truncated at the time limit and on the step the
      last robot of their world leaves. The root flags are the `all` of every agent's flags
      (done_on_any=False): a row is done when its episode ended.
    - Partial resets: `reset` reads the root "_reset" entry (B, 1) that TorchRL's collectors and
      `rollout(break_when_any_done=False)` / `step_and_maybe_reset` write for done rows, and
      starts a new episode in those rows only, from each row's own seeded scenario stream; the
      other rows go on untouched. So finished rows are reset automatically by TorchRL's
      machinery, while the ("next", ...) entries of a done step keep the last observation of the
      finished episode. Group-level "_reset" entries are ignored (a world resets as a whole).
      Without any "_reset", every row is reset.
    - Seeding: `set_seed(s)` seeds the scenario streams: row 0 of any batch plays the episodes of
      a SocialNavParallelEnv reset with seed s, row i those of SeedSequence(s).spawn(B)[i].
    - A row whose episode ended and was not reset keeps stepping with every agent dead.
    - `robot_policy` (anything with the Policy protocol's `act(obs, task)`, e.g.
      socialzoo.agents.make_policy("ref")): the robots then have no action entry but still report
      observations, rewards and flags.

    ## Arguments
    Args:
        config: an EnvConfig (default: the benchmark's, on gdc1); overrides as keyword arguments.
        batch_size: B, the worlds stepped together.
        robot_policy: None (robot actions come in the tensordict), or an object with
            `act(obs (B, R, D), task) -> (B, R)` that drives the robots inside the env.
        seed: seeds the scenario streams (None: fresh entropy, kept in `stream_seed`).
        map_data: an already loaded Map instead of config.map.
        device: torch device of the tensors (the simulation runs in numpy on the CPU).
        **overrides: EnvConfig fields as plain values (nested configs as dicts).

    Raises:
        ValueError: bad config overrides, batch size, too few legal poses for the robots, or a
            robot observation that is not one Box (CrowdNav: observation="flat").

    ## Version History
    The action-selection ids' (socialzoo.env.registration's module docstring).
    """

    def __init__(
        self,
        config: Any = None,
        *,
        batch_size: int = 1,
        robot_policy: Any = None,
        seed: int | None = None,
        device: str | torch.device = "cpu",
        task: Any = "action_selection",
        **kwargs: Any,
    ) -> None:
        check_int("SocialNavTorchEnv", "batch_size", batch_size, low=1)
        if robot_policy is not None and not callable(getattr(robot_policy, "act", None)):
            raise ValueError(
                f"SocialNavTorchEnv: robot_policy must have act(obs, task), got {type(robot_policy).__name__}"
            )
        super().__init__(device=device, batch_size=torch.Size([batch_size]))
        self.task = box_observation(self.task_class(task)(config, batch_size, **kwargs), type(self).__name__)
        self.config = self.task.config
        self.robot_policy = robot_policy
        self.num_robots = self.task.num_robots
        self.num_humans = self.task.num_human_agents
        self.stream_seed: int | None = None
        b, r = batch_size, self.num_robots
        # Agents still in their episode, per row: robots (B, R); humans leave with the episode (B,).
        self._robot_alive = np.zeros((b, r), dtype=bool)
        self._row_alive = np.zeros(b, dtype=bool)
        self._make_specs()
        self._set_seed(seed)

    @property
    def group_map(self) -> dict[str, list[str]]:
        """Group name -> agent names, as PettingZooWrapper.group_map."""
        groups = {ROBOT: [f"robot_{i}" for i in range(self.num_robots)]}
        if self.num_humans:
            groups[HUMAN] = [f"human_{j}" for j in range(self.num_humans)]
        return groups

    # ------------------------------------------------------------------ specs
    def _make_specs(self) -> None:
        task = self.task
        b, r, h = self.batch_size[0], self.num_robots, self.num_humans
        obs = Composite(shape=(b,))
        action = Composite(shape=(b,))
        reward = Composite(shape=(b,))
        done = Composite(shape=(b,))

        def flags(n: int) -> Composite:
            return Composite(
                {k: Categorical(2, shape=(b, n, 1), dtype=torch.bool) for k in _DONE_KEYS}, shape=(b, n)
            )

        def info(keys: tuple[str, ...], n: int) -> Composite:
            return Composite({k: Unbounded(shape=(b, n), dtype=torch.float32) for k in keys}, shape=(b, n))

        assert task.observation_space.shape is not None  # a Box (box_observation)
        obs[ROBOT] = Composite(
            observation=Unbounded(shape=(b, r, *task.observation_space.shape), dtype=torch.float32),
            mask=Categorical(2, shape=(b, r), dtype=torch.bool),
            info=info(task.info_keys, r),
            shape=(b, r),
        )
        reward[ROBOT] = Composite(reward=Unbounded(shape=(b, r, 1), dtype=torch.float32), shape=(b, r))
        done[ROBOT] = flags(r)
        if self.robot_policy is None:
            space = task.action_space
            if isinstance(space, spaces.Discrete):
                robot_action: Any = Categorical(int(space.n), shape=(b, r), dtype=torch.int64)
            else:
                robot_action = vector_action_spec(space, (b, r))
            action[ROBOT] = Composite(action=robot_action, shape=(b, r))
        if h:
            assert task.human_observation_space is not None and task.human_observation_space.shape is not None
            obs[HUMAN] = Composite(
                observation=Unbounded(shape=(b, h, *task.human_observation_space.shape), dtype=torch.float32),
                mask=Categorical(2, shape=(b, h), dtype=torch.bool),
                info=info(HUMAN_INFO_KEYS, h),
                shape=(b, h),
            )
            action[HUMAN] = Composite(
                action=Bounded(-1.0, 1.0, shape=(b, h, 2), dtype=torch.float32), shape=(b, h)
            )
            reward[HUMAN] = Composite(reward=Unbounded(shape=(b, h, 1), dtype=torch.float32), shape=(b, h))
            done[HUMAN] = flags(h)
        state_size = STATE_ROBOT_SIZE * r + STATE_HUMAN_SIZE * task.num_human_slots
        obs["state"] = Unbounded(shape=(b, state_size), dtype=torch.float32)
        for k in _DONE_KEYS:
            done[k] = Categorical(2, shape=(b, 1), dtype=torch.bool)
        self.observation_spec = obs
        self.action_spec = action
        self.reward_spec = reward
        self.done_spec = done

    # ------------------------------------------------------------------ seeding, reset
    def _set_seed(self, seed: int | None) -> None:
        seed = check_seed(type(self).__name__ + ".set_seed", seed)
        if seed is None:
            seed = int(np.random.SeedSequence().entropy)  # type: ignore[arg-type]
        self.task.seed(seed)
        self.stream_seed = seed

    def _reset(self, tensordict: TensorDictBase | None = None, **kwargs: Any) -> TensorDictBase:
        b = self.batch_size[0]
        reset = None if tensordict is None else tensordict.get("_reset", None)
        if reset is None:
            rows = np.arange(b)
        else:
            rows = reset_rows(reset, b, type(self).__name__)
        task = self.task
        if len(rows):
            task.reset(rows, {})
            self._robot_alive[rows] = True
            self._row_alive[rows] = True
        zeros_r = np.zeros((b, self.num_robots), dtype=bool)
        out: dict[str, Any] = {
            ROBOT: {
                "observation": np.where(self._robot_alive[..., None], task.observations(), 0.0).astype(
                    np.float32
                ),
                "mask": self._robot_alive.copy(),
                "info": self._robot_info(None),
                **self._flags(zeros_r, zeros_r, zeros_r),
            },
            "state": global_state(task.world_state, np.float32),
        }
        if self.num_humans:
            human_obs = task.human_observations()
            assert human_obs is not None
            zeros_h = np.zeros((b, self.num_humans), dtype=bool)
            out[HUMAN] = {
                "observation": human_obs.copy(),
                "mask": self._human_mask(),
                "info": self._human_info(None),
                **self._flags(zeros_h, zeros_h, zeros_h),
            }
        for k in _DONE_KEYS:
            out[k] = np.zeros((b, 1), dtype=bool)
        return self._to_tensordict(out)

    # ------------------------------------------------------------------ step
    def _step(self, tensordict: TensorDictBase) -> TensorDictBase:
        task = self.task
        b, r, h = self.batch_size[0], self.num_robots, self.num_humans
        shape = (b, r) + tuple(task.action_space.shape or ())
        if self.robot_policy is not None:
            robot_action = np.asarray(self.robot_policy.act(task.observations(), task)).reshape(shape)
        else:
            robot_action = tensordict.get((ROBOT, "action")).detach().cpu().numpy().reshape(shape)
        human_action = None
        if h:
            human_action = tensordict.get((HUMAN, "action")).detach().cpu().numpy().astype(np.float64)
        robot_was = self._robot_alive.copy()
        row_was = self._row_alive.copy()
        step = task.step(robot_action, human_action)

        robot_term = step.terminated & robot_was
        robot_trunc = step.truncated & robot_was
        leaving = robot_term | robot_trunc
        self._robot_alive = robot_was & ~leaving
        ended = row_was & ~self._robot_alive.any(axis=1)
        self._row_alive = row_was & ~ended
        dead_r = ~robot_was
        out: dict[str, Any] = {
            ROBOT: {
                "observation": np.where(robot_was[..., None], task.observations(), 0.0).astype(np.float32),
                "reward": np.where(robot_was, step.reward, 0.0)[..., None].astype(np.float32),
                "mask": self._robot_alive.copy(),
                "info": self._robot_info(step, robot_was),
                **self._flags(leaving | dead_r, robot_term | dead_r, robot_trunc | dead_r),
            },
            "state": global_state(task.world_state, np.float32),
        }
        # The row's flags: every agent's (done_on_any=False).
        root = {k: out[ROBOT][k].all(axis=(1, 2)) for k in _DONE_KEYS}
        if h:
            human_obs = task.human_observations()
            assert human_obs is not None and step.human_reward is not None
            live = row_was[:, None].repeat(h, axis=1)
            trunc = live & (step.time_up | ended)[:, None]
            dead_h = ~live
            out[HUMAN] = {
                "observation": np.where(live[..., None], human_obs, 0.0).astype(np.float32),
                "reward": np.where(live, step.human_reward, 0.0)[..., None].astype(np.float32),
                "mask": self._human_mask(),
                "info": self._human_info(step, live),
                **self._flags(trunc | dead_h, dead_h, trunc | dead_h),
            }
            for k in _DONE_KEYS:
                root[k] &= out[HUMAN][k].all(axis=(1, 2))
        for k in _DONE_KEYS:
            out[k] = root[k][:, None]
        return self._to_tensordict(out)

    # ------------------------------------------------------------------ pieces
    def _human_mask(self) -> np.ndarray:
        """(B, L) learned humans that act: present in the scenario and their episode running."""
        return self.task.human_present() & self._row_alive[:, None]

    @staticmethod
    def _flags(done: np.ndarray, terminated: np.ndarray, truncated: np.ndarray) -> dict[str, np.ndarray]:
        return {k: v[..., None] for k, v in zip(_DONE_KEYS, (done, terminated, truncated), strict=True)}

    def _robot_info(self, step: TaskStep | None, live: np.ndarray | None = None) -> dict[str, np.ndarray]:
        b, r = self.batch_size[0], self.num_robots
        keys = self.task.info_keys
        if step is None:
            neutral = self.task.initial_info()
            return {k: np.full((b, r), float(neutral.get(k, 0.0)), dtype=np.float32) for k in keys}
        assert live is not None
        return {k: np.where(live, step.info[k], 0.0).astype(np.float32) for k in keys}

    def _human_info(self, step: TaskStep | None, live: np.ndarray | None = None) -> dict[str, np.ndarray]:
        present = self.task.human_present()
        if step is None or step.human_info is None:
            zeros = np.zeros(present.shape, dtype=np.float32)
            return {k: (present.astype(np.float32) if k == "present" else zeros) for k in HUMAN_INFO_KEYS}
        assert live is not None
        return {k: np.where(live, step.human_info[k], 0.0).astype(np.float32) for k in HUMAN_INFO_KEYS}

    def _to_tensordict(self, data: dict[str, Any]) -> TensorDictBase:
        b = self.batch_size[0]

        def convert(node: dict[str, Any], shape: tuple[int, ...]) -> TensorDict:
            fields: dict[str, Any] = {}
            for key, value in node.items():
                if isinstance(value, dict):
                    n = self.num_robots if key == ROBOT else self.num_humans
                    fields[key] = convert(value, shape if key == "info" else (b, n))
                else:
                    fields[key] = torch.from_numpy(np.ascontiguousarray(value))
            return TensorDict(fields, batch_size=shape, device=self.device)

        return convert(data, (b,))
