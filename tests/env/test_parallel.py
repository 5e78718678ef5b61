"""The PettingZoo ParallelEnv: conformance, determinism, agents leaving, bad input, TorchRL, supersuit."""

from __future__ import annotations

import functools
import types
import warnings

import numpy as np
import pytest
from pettingzoo.test import max_cycles_test, parallel_api_test
from pettingzoo.utils.conversions import parallel_to_aec

from socialzoo.env.parallel import BlackDeath, SocialNavParallelEnv, parallel_env
from socialzoo.maps import map_file as maps
from socialzoo.maps.map_file import Map
from socialzoo.scenarios.scenario import Scenario


def _box(x0: float, y0: float, x1: float, y1: float) -> list[list[float]]:
    return [[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]]


@functools.cache
def stand_in_room() -> Map:
    """A 10 m x 10 m room with a 3 x 3 grid graph: the hand-built scenarios below live in it."""
    nodes = np.array([[x, y] for x in (2.0, 5.0, 8.0) for y in (2.0, 5.0, 8.0)])
    edges = [[0, 1], [1, 2], [3, 4], [4, 5], [6, 7], [7, 8], [0, 3], [3, 6], [1, 4], [4, 7], [2, 5], [5, 8]]
    return Map(
        name="open_room",
        walls=np.array(_box(0, 0, 10, 10), dtype=float),
        nodes=nodes,
        edges=np.array(edges),
        legal_poses=np.array([[1, 1, 0], [9, 9, 0], [1, 9, 0], [9, 1, 0]], dtype=float),
    )


@functools.cache
def room() -> Map:
    """The shipped open_room map once it exists, else the stand-in."""
    return maps.load_map("open_room") if "open_room" in maps.list_maps() else stand_in_room()


FAST = {"max_steps": 200, "scenario": {"min_humans": 1, "max_humans": 5}}


def make(map_data: Map | None = None, **kwargs) -> SocialNavParallelEnv:
    options = {**FAST, **kwargs}
    return parallel_env(map="open_room", map_data=map_data or room(), **options)


def scenario(robots: list[tuple[list[float], list[float]]], humans: int = 1) -> Scenario:
    """A hand-built scenario in the stand-in room; humans walk along y = 8."""
    spawn = np.array([[3.0 + 1.5 * k, 8.0] for k in range(humans)]).reshape(-1, 2)
    return Scenario(
        map_name="open_room",
        seed=7,
        robot_starts=[start for start, _ in robots],
        robot_goals=[goal for _, goal in robots],
        human_spawn=spawn,
        human_start_index=[-1] * humans,
        human_goal_index=[-1] * humans,
        human_routes=tuple(np.array([p, [8.0, 8.0]]) for p in spawn),
        human_speed=[1.0] * humans,
    )


# robot_0 is 1.5 m from its goal (reached in about 30 steps of GoAlone); robot_1 has 8.5 m to go.
NEAR_AND_FAR = [([2.0, 5.0, 0.0], [3.5, 5.0, 0.0]), ([2.0, 2.0, 0.0], [8.0, 8.0, 0.0])]


def same(a, b) -> bool:
    """Exact equality of nested observations / rewards / infos (bit for bit, NaN equal to NaN)."""
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True)
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, float) and np.isnan(a):
        return isinstance(b, float) and np.isnan(b)
    return type(a) is type(b) and a == b


# ---------------------------------------------------------------------------- conformance
@pytest.mark.parametrize(
    ("num_robots", "num_learned_humans", "robot_action"),
    [(1, 0, "subpolicy"), (2, 3, "subpolicy"), (2, 3, "velocity"), (1, 2, "velocity")],
)
def test_parallel_api(num_robots, num_learned_humans, robot_action):
    env = make(num_robots=num_robots, num_learned_humans=num_learned_humans, robot_action=robot_action)
    with warnings.catch_warnings():
        # The API test only warns (UserWarning) about missing or extra keys: make that fail.
        warnings.simplefilter("error", UserWarning)
        parallel_api_test(env, num_cycles=300)


def test_max_cycles():
    def factory(max_cycles: int) -> SocialNavParallelEnv:
        return make(num_robots=2, num_learned_humans=2, max_cycles=max_cycles)

    module = types.SimpleNamespace(
        parallel_env=factory, env=lambda max_cycles: parallel_to_aec(factory(max_cycles))
    )
    max_cycles_test(module)


def test_spaces_are_cached_and_typed():
    env = make(num_robots=2, num_learned_humans=3)
    assert env.possible_agents == ["robot_0", "robot_1", "human_0", "human_1", "human_2"]
    for agent in env.possible_agents:
        assert env.observation_space(agent) is env.observation_space(agent)
        assert env.action_space(agent) is env.action_space(agent)
    assert env.action_space("robot_0").n == 4
    assert env.observation_space("robot_0").shape == (7 + 4 * 25,)
    assert env.action_space("human_0").shape == (2,)
    assert env.observation_space("human_0").shape == (8 + 5 * 6,)
    velocity = make(robot_action="velocity")
    assert velocity.action_space("robot_0").shape == (2,)
    assert env.metadata["name"] == "socialzoo_parallel_v2" and env.metadata["is_parallelizable"]


def test_state_is_the_global_state():
    env = make(num_robots=2, num_learned_humans=1)
    env.reset(seed=0)
    for _ in range(5):
        env.step({a: env.action_space(a).sample() for a in env.agents})
    state = env.state()
    assert state.dtype == np.float64 and env.state_space.contains(state)
    s = env.core.state
    np.testing.assert_array_equal(state[:3], s.robot_pose[0, 0])
    np.testing.assert_array_equal(state[8 + 5 : 8 + 8], s.robot_goal[0, 1])
    humans = state[16:].reshape(-1, 5)
    assert len(humans) == env.config.max_humans
    np.testing.assert_array_equal(humans[:, 4], s.human_mask[0])
    np.testing.assert_array_equal(humans[:, :2], s.human_pos[0])


# ---------------------------------------------------------------------------- determinism
def rollout(env: SocialNavParallelEnv, seed: int, steps: int) -> list:
    """`steps` steps of seeded random actions, resetting (without a seed) whenever agents is empty."""
    rng = np.random.default_rng(123)
    trace: list = list(env.reset(seed=seed))
    for _ in range(steps):
        if not env.agents:
            trace.extend(env.reset())
            continue
        actions = {}
        for agent in env.agents:
            space = env.action_space(agent)
            if hasattr(space, "n"):
                actions[agent] = int(rng.integers(space.n))
            else:
                actions[agent] = rng.uniform(-1, 1, 2).astype(np.float32)
        trace.append(env.step(actions))
        trace.append(env.state())
    return trace


def test_same_seed_same_rollout_bit_for_bit_and_seeds_differ():
    kwargs = {"num_robots": 2, "num_learned_humans": 3, "max_steps": 100}
    a = rollout(make(**kwargs), 11, 300)
    b = rollout(make(**kwargs), 11, 300)
    assert same(a, b)
    c = rollout(make(**kwargs), 12, 300)
    assert not same(a[0], c[0])


def test_unseeded_first_reset_is_recorded_and_replayable():
    env = make(num_robots=2)
    obs, _ = env.reset()
    assert env.stream_seed is not None
    again, _ = make(num_robots=2).reset(seed=env.stream_seed)
    assert same(obs, again)
    replay = make(num_robots=2)
    assert replay.scenario is None  # docs/parallel_env.md: `env.scenario` is the current one
    replayed, _ = replay.reset(seed=999, options={"scenario": env.scenario})
    assert same(obs, replayed)
    with pytest.raises(TypeError, match="Scenario"):
        replay.reset(options={"scenario": "gdc1-0"})


@pytest.mark.parametrize("seed", [-1, 1.5, [1, 2], True])
def test_a_bad_seed_is_refused_by_name_before_anything_changes(seed):
    """Gymnasium's rule (an int >= 0), where numpy's SeedSequence said "expected non-negative integer"
    or took a list; numpy's own integers stay welcome."""
    env = make()
    with pytest.raises(ValueError, match=r"SocialNavParallelEnv.reset: seed must be an int >= 0"):
        env.reset(seed=seed)
    assert env.stream_seed is None
    env.reset(seed=np.int64(3))
    assert env.stream_seed == 3 and type(env.stream_seed) is int


def test_one_robot_plays_the_single_agent_episode():
    """One world, one copy of the dynamics: R = 1 equals ActionSelectionEnv seed for seed."""
    from socialzoo.env.gym_env import ActionSelectionEnv

    single = ActionSelectionEnv(map="open_room", map_data=room(), **FAST)
    multi = make()
    obs, _ = single.reset(seed=4)
    obs_multi, _ = multi.reset(seed=4)
    assert same(obs, obs_multi["robot_0"])
    for action in np.random.default_rng(2).integers(0, 4, 60):
        obs, reward, terminated, truncated, _ = single.step(action)
        out = multi.step({"robot_0": action})
        assert same(obs, out[0]["robot_0"]) and reward == out[1]["robot_0"]
        assert (terminated, truncated) == (out[2]["robot_0"], out[3]["robot_0"])
        if terminated or truncated:
            break


# ---------------------------------------------------------------------------- episode end
def test_robot_leaves_on_reaching_its_goal_and_stands_still():
    env = make(stand_in_room(), num_robots=2, num_learned_humans=2)
    obs, infos = env.reset(options={"scenario": scenario(NEAR_AND_FAR, humans=1)})
    assert infos["human_1"] == {"contact": False, "present": False}
    assert not obs["human_1"].any()
    for _ in range(100):
        out = env.step({a: 0 if a.startswith("robot") else np.zeros(2) for a in env.agents})
        _, rewards, terminations, truncations, infos = out
        assert rewards["human_1"] == 0.0 and not out[0]["human_1"].any()
        if terminations["robot_0"]:
            break
    else:
        pytest.fail("robot_0 did not reach its goal in 100 steps")
    assert not truncations["robot_0"] and infos["robot_0"]["reached"]
    assert rewards["robot_0"] > 90  # the success bonus
    assert infos["robot_0"]["metrics"]["reached"] and infos["robot_0"]["metrics"]["steps"] > 0
    assert "metrics" not in infos["robot_1"]
    assert set(infos["robot_1"]) == set(infos["robot_0"]) - {"metrics"}
    assert env.agents == ["robot_1", "human_0", "human_1"]
    # A robot that left needs no action; one given anyway (even a bad one) is ignored.
    others = {"robot_1": 0, **dict.fromkeys(env.humans, np.zeros(2))}
    obs, rewards, terminations, truncations, infos = env.step({"robot_0": 99, **others})
    assert "robot_0" not in obs and "robot_0" not in rewards
    # It halts at once (the motion model still integrates the last half step) and then stands still.
    assert env.core.state.robot_vel[0, 0].tolist() == [0.0, 0.0]
    pose = env.core.state.robot_pose[0, 0].copy()
    for _ in range(5):
        env.step(others)
    np.testing.assert_array_equal(env.core.state.robot_pose[0, 0], pose)
    assert not any(terminations.values()) and not any(truncations.values())


def test_wall_collision_terminates_and_humans_are_truncated_with_the_last_robot():
    env = make(stand_in_room(), robot_action="velocity", num_learned_humans=1)
    env.reset(options={"scenario": scenario([([0.7, 5.0, np.pi], [8.0, 5.0, 0.0])])})
    for _ in range(40):
        _, _, terminations, truncations, infos = env.step(
            {"robot_0": np.array([1.0, 0.0]), "human_0": np.zeros(2)}
        )
        if not env.agents:
            break
    assert terminations == {"robot_0": True, "human_0": False}
    assert truncations == {"robot_0": False, "human_0": True}
    assert infos["robot_0"]["wall_collision"] and not infos["robot_0"]["metrics"]["success"]
    with pytest.raises(RuntimeError, match="episode has ended"):
        env.step({})


def test_time_limit_and_max_cycles_truncate_everyone():
    for kwargs, steps in (({"max_steps": 7}, 7), ({"max_cycles": 5}, 5)):
        env = make(num_robots=2, num_learned_humans=2, **kwargs)
        env.reset(seed=1)
        step = 0
        while env.agents and step < 20:
            step += 1
            _, _, terminations, truncations, _ = env.step(
                {a: env.action_space(a).sample() for a in env.agents}
            )
        assert step == steps
        assert truncations == dict.fromkeys(env.possible_agents, True)
        assert terminations == dict.fromkeys(env.possible_agents, False)


# ---------------------------------------------------------------------------- bad input
def test_the_state_keeps_world_positions_on_a_map_at_utm_coordinates():
    # A map imported in UTM coordinates: float32 rounded its positions to steps of 0.03 m at
    # x = 5e5 and 0.5 m at y = 4.3e6 (0.15 m off here), so state() no longer matched its world.
    offset = np.array([512_345.678, 4_321_987.654])
    room_ = stand_in_room()
    far = Map(
        name="open_room",
        walls=room_.walls + np.tile(offset, 2),
        nodes=room_.nodes + offset,
        edges=room_.edges,
        legal_poses=room_.legal_poses + np.append(offset, 0.0),
    )
    env = make(far, num_robots=2, num_learned_humans=1)
    env.reset(seed=0)
    for _ in range(3):
        env.step({a: env.action_space(a).sample() for a in env.agents})
    state, s = env.state(), env.core.state
    assert env.state_space.contains(state)
    np.testing.assert_array_equal(state[:3], s.robot_pose[0, 0])
    humans = state[16:].reshape(-1, 5)
    np.testing.assert_array_equal(humans[:, :2], s.human_pos[0])
    assert np.abs(humans[s.human_mask[0], :2] - offset).max() < 20.0  # the people are there too


def test_missing_unknown_and_invalid_actions_raise_before_anything_changes():
    env = make(num_robots=2, num_learned_humans=1)
    with pytest.raises(RuntimeError, match="reset"):
        env.step({})
    env.reset(seed=3)
    state = env.state()
    good = {"robot_0": 0, "robot_1": 0, "human_0": np.zeros(2)}
    with pytest.raises(KeyError, match="robot_1"):
        env.step({"robot_0": 0, "human_0": np.zeros(2)})
    with pytest.raises(KeyError, match="robot_7"):
        env.step({**good, "robot_7": 0})
    bad_cases = [
        ({"robot_1": 4}, "robot_1"),
        ({"robot_0": 1.5}, "robot_0"),
        ({"robot_0": True}, "robot_0"),
        ({"robot_0": [0, 1]}, "robot_0"),
        ({"human_0": np.array([1.5, 0.0])}, "human_0"),
        ({"human_0": np.array([np.nan, 0.0])}, "human_0"),
        ({"human_0": np.zeros(3)}, "human_0"),
    ]
    for change, agent in bad_cases:
        with pytest.raises(ValueError, match=agent):
            env.step({**good, **change})
    velocity = make(robot_action="velocity")
    velocity.reset(seed=3)
    with pytest.raises(ValueError, match="robot_0"):
        velocity.step({"robot_0": np.array([0.0, -1.01])})
    assert env.num_cycles == 0 and velocity.num_cycles == 0
    np.testing.assert_array_equal(env.state(), state)
    env.step(good)
    assert env.num_cycles == 1


def test_bad_constructor_arguments_raise():
    with pytest.raises(ValueError, match="max_cycles"):
        make(max_cycles=0)
    with pytest.raises(ValueError, match="render_mode"):
        make(render_mode="ansi")
    with pytest.raises(ValueError, match="num_learned_humans"):
        make(num_learned_humans=9)
    with pytest.raises(ValueError, match="legal poses"):
        make(stand_in_room(), num_robots=4)


# ---------------------------------------------------------------------------- rendering
def test_render_rgb_array():
    env = make(num_robots=2, render_mode="rgb_array")
    env.reset(seed=0)
    env.step({a: 0 for a in env.agents})
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    env.close()
    silent = make()
    silent.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode"):
        assert silent.render() is None


def test_render_human_window():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")  # no display in tests: the window draws off screen
    env = make(render_mode="human")
    env.reset(seed=0)
    assert env.step({"robot_0": 0})[0]["robot_0"].shape == (107,)
    assert env.render() is None
    env.close()


# ---------------------------------------------------------------------------- TorchRL
def torchrl_wrapper(env: SocialNavParallelEnv, **kwargs):
    from torchrl.envs.libs.pettingzoo import PettingZooWrapper

    return PettingZooWrapper(env=env, use_mask=True, return_state=True, **kwargs)


def test_torchrl_check_env_specs():
    from torchrl.envs.utils import check_env_specs

    wrapped = torchrl_wrapper(make(num_robots=2, num_learned_humans=3, episode_info=False), seed=0)
    assert wrapped.group_map == {"robot": ["robot_0", "robot_1"], "human": ["human_0", "human_1", "human_2"]}
    check_env_specs(wrapped, seed=0)


def test_torchrl_masks_robots_that_left():
    import torch

    env = make(stand_in_room(), num_robots=2, num_learned_humans=1, max_steps=60, episode_info=False)
    wrapped = torchrl_wrapper(env, done_on_any=False)

    def go_alone(td):
        td["robot", "action"] = torch.zeros(2, dtype=torch.int64)
        td["human", "action"] = torch.zeros(1, 2)
        return td

    start = wrapped.reset(options={"scenario": scenario(NEAR_AND_FAR)})
    td = wrapped.rollout(100, go_alone, auto_reset=False, tensordict=start)
    mask = td["next", "robot", "mask"]
    assert len(td) == 60 and td["next", "done"][-1].item()
    assert mask[-1].tolist() == [False, False] and mask[:, 0].sum() < mask[:, 1].sum()
    left = int(mask[:, 0].sum())  # robot_0's terminal step is the first one it is masked out after
    assert td["next", "robot", "terminated"][left, 0].item()
    assert td["next", "robot", "reward"][left, 0].item() > 90


# ---------------------------------------------------------------------------- supersuit, SB3
def test_supersuit_sb3_vec_env():
    import supersuit as ss
    from stable_baselines3.common.vec_env import VecEnv

    # Agents that never leave early: two robots on sub-policies (the planner keeps them off the
    # walls) and an episode too short to reach a goal, so every agent ends at the time limit.
    env = make(num_robots=2, max_steps=20, episode_info=False)
    vec = ss.pettingzoo_env_to_vec_env_v1(env)
    venv = ss.concat_vec_envs_v1(vec, 2, num_cpus=0, base_class="stable_baselines3")
    assert isinstance(venv, VecEnv) and venv.num_envs == 4
    obs = venv.reset()
    assert obs.shape == (4, 7 + 4 * 25)
    for step in range(1, 45):
        obs, rewards, dones, infos = venv.step(np.zeros(4, dtype=np.int64))
        assert obs.shape == (4, 107) and rewards.shape == (4,) and np.isfinite(rewards).all()
        assert dones.all() == (step % 20 == 0)
        if dones.all():
            assert all("terminal_observation" in info for info in infos)


def test_black_death_lets_supersuit_run_past_a_robot_that_left():
    import supersuit as ss

    env = make(stand_in_room(), num_robots=2, max_steps=80, episode_info=False)
    vec = ss.pettingzoo_env_to_vec_env_v1(BlackDeath(env))
    obs, _ = vec.reset(options={"scenario": scenario(NEAR_AND_FAR)})
    dones, alone = [], []
    for _ in range(85):
        obs, rewards, terminations, truncations, _ = vec.step(np.zeros(2, dtype=np.int64))
        dones.append(terminations | truncations)
        if alone and alone[-1] and not dones[-1].any():  # robot_0 had left: black observation, reward 0
            assert not obs[0].any() and rewards[0] == 0.0
        alone.append(env.agents == ["robot_1"])
    dones = np.array(dones)
    assert any(alone)  # robot_0 reached its goal early and left the wrapped env
    # Nobody is done until the episode ends at the time limit (step 80); then a new one starts.
    assert not dones[:79].any() and dones[79].all() and not dones[80:].any()


def test_sb3_ppo_learns_a_few_steps_on_the_supersuit_vec_env():
    import supersuit as ss
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecMonitor

    from socialzoo.train.sb3_common import quiet_logger

    env = make(num_robots=2, max_steps=40, episode_info=False)
    venv = VecMonitor(
        ss.concat_vec_envs_v1(
            ss.pettingzoo_env_to_vec_env_v1(BlackDeath(env)), 2, base_class="stable_baselines3"
        )
    )
    model = PPO("MlpPolicy", venv, n_steps=32, batch_size=64, n_epochs=1, device="cpu")
    model.set_logger(quiet_logger())  # SB3's own logger leaves an empty /tmp/SB3-<date> folder
    model.learn(256)
    assert len(model.ep_info_buffer) > 0
