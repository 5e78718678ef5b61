"""The SB3 VecEnv over the batched core: SB3's conventions and checks, and equal to the single env."""

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.env_checker import _check_box_obs, _check_unsupported_spaces
from stable_baselines3.common.env_checker import check_env as sb3_check_env
from stable_baselines3.common.vec_env import VecCheckNan, VecMonitor, VecNormalize
from stable_baselines3.common.vec_env.util import obs_space_info

import socialzoo  # noqa: F401  (registers the ids)
from socialzoo.env.registration import BENCHMARK_IDS
from socialzoo.env.sb3_vec import SB3VecEnv
from socialzoo.env.vector import ActionSelectionVectorEnv

GDC1_ID = next(i for i, kw in BENCHMARK_IDS.items() if kw["map"] == "gdc1")
SHORT = {"max_steps": 40, "scenario": {"min_humans": 5, "max_humans": 8}}
# Episodes on the open room end at the goal (GoAlone reaches it in about 210 steps).
ROOM = {"map": "open_room", "family": "circle_crossing", "max_steps": 400}


def _single_trace(env, seed, actions):
    """(obs, reward, done, terminal obs or None, truncated-by-time, metrics or None) per step of a
    single env that restarts (without a seed) whenever an episode ends, as SB3's autoreset does."""
    obs, _ = env.reset(seed=seed)
    trace = [obs]
    for a in actions:
        obs, reward, terminated, truncated, info = env.step(int(a))
        done = terminated or truncated
        last = obs if done else None
        if done:
            obs, _ = env.reset()
        trace.append((obs, np.float32(reward), done, last, truncated and not terminated, info.get("metrics")))
    return trace


def _row_trace(venv, seed, actions, row):
    venv.seed(seed)
    obs = venv.reset()
    trace = [obs[row]]
    for a in actions:
        obs, rewards, dones, infos = venv.step(np.full(venv.num_envs, a))
        info = infos[row]
        trace.append(
            (
                obs[row],
                rewards[row],
                bool(dones[row]),
                info.get("terminal_observation"),
                info.get("TimeLimit.truncated", False),
                info.get("metrics"),
            )
        )
    return trace


def _assert_same(a, b):
    np.testing.assert_array_equal(a[0], b[0])
    for i, (x, y) in enumerate(zip(a[1:], b[1:], strict=True)):
        np.testing.assert_array_equal(x[0], y[0], err_msg=f"obs of step {i}")
        assert x[1:3] == y[1:3], f"reward/done of step {i}: {x[1:3]} != {y[1:3]}"
        if x[3] is None:
            assert y[3] is None
        else:
            np.testing.assert_array_equal(x[3], y[3], err_msg=f"terminal observation of step {i}")
        assert x[4] == y[4], f"truncation of step {i}"
        assert _same_metrics(x[5], y[5]), f"metrics of step {i}: {x[5]} != {y[5]}"


def _same_metrics(a, b):
    if a is None or b is None:
        return a is b
    return a.keys() == b.keys() and all(
        type(a[k]) is type(b[k]) and (a[k] == b[k] or (a[k] != a[k] and b[k] != b[k])) for k in a
    )


@pytest.mark.parametrize(("overrides", "steps", "action_seed"), [(SHORT, 130, 0), (ROOM, 500, None)])
def test_row_zero_plays_the_single_envs_transitions(overrides, steps, action_seed):
    """Row 0 of the VecEnv seeded s = gymnasium.make(id) reset with s, then without a seed, across
    episodes that end by time (gdc1) and at the goal (open room, GoAlone)."""
    actions = (
        np.random.default_rng(action_seed).integers(0, 4, steps)
        if action_seed is not None
        else np.zeros(steps, dtype=np.int64)
    )
    single = _single_trace(gym.make(GDC1_ID, **overrides), 7, actions)
    row = _row_trace(SB3VecEnv(3, **overrides), 7, actions, 0)
    _assert_same(single, row)
    dones = [step[2] for step in single[1:]]
    assert sum(dones) >= 2, "the trace must cross at least two episode ends"
    ends = [step for step in single[1:] if step[2]]
    if overrides is SHORT:
        assert all(step[4] for step in ends)  # time limit
    else:
        assert not any(step[4] for step in ends) and all(step[5]["success"] for step in ends)


def test_every_row_plays_its_vector_env_rows_episode():
    """Row i of the SB3 VecEnv = row i of ActionSelectionVectorEnv with the same seed, and a single
    env replaying that row's scenario."""
    actions = np.random.default_rng(3).integers(0, 4, 45)
    venv = SB3VecEnv(4, **SHORT)
    venv.seed(11)
    obs = venv.reset()
    vector = ActionSelectionVectorEnv(4, **SHORT)
    vobs, _ = vector.reset(seed=11)
    np.testing.assert_array_equal(obs, vobs)
    scenario = venv.vector_env.core.scenarios[2]
    single = gym.make(GDC1_ID, **SHORT)
    sobs, _ = single.reset(options={"scenario": scenario})
    np.testing.assert_array_equal(obs[2], sobs)
    single_done = False
    for a in actions:
        batch = np.full(4, a)
        obs, rewards, dones, infos = venv.step(batch)
        vobs, vrew, vterm, vtrunc, _ = vector.step(batch)
        np.testing.assert_array_equal(obs, vobs)
        np.testing.assert_array_equal(rewards, vrew.astype(np.float32))
        np.testing.assert_array_equal(dones, vterm | vtrunc)
        if not single_done:
            sobs, sreward, sterm, strunc, _ = single.step(int(a))
            single_done = sterm or strunc
            assert rewards[2] == np.float32(sreward) and dones[2] == single_done
            np.testing.assert_array_equal(infos[2]["terminal_observation"] if single_done else obs[2], sobs)
    assert single_done


def test_sb3_conventions_shapes_and_infos():
    venv = SB3VecEnv(5, **SHORT)
    keys, shapes, dtypes = obs_space_info(venv.observation_space)  # SB3's own space parsing
    assert keys == [None] and shapes[None] == (107,) and dtypes[None] == np.float32
    assert isinstance(venv.action_space, gym.spaces.Discrete) and venv.action_space.n == 4
    venv.seed(0)
    obs = venv.reset()
    assert obs.shape == (5, 107) and obs.dtype == np.float32
    assert len(venv.reset_infos) == 5 and all("scenario_seed" in i for i in venv.reset_infos)
    seen_done = False
    for _ in range(SHORT["max_steps"]):
        obs, rewards, dones, infos = venv.step(np.random.default_rng(0).integers(0, 4, 5))
        assert obs.shape == (5, 107) and rewards.shape == (5,) and dones.shape == (5,)
        assert rewards.dtype == np.float32 and dones.dtype == bool
        assert isinstance(infos, list) and len(infos) == 5
        assert all(venv.observation_space.contains(o) for o in obs)
        for done, info in zip(dones, infos, strict=True):
            assert ("terminal_observation" in info) == bool(done)
            if done:
                seen_done = True
                assert venv.observation_space.contains(info["terminal_observation"])
                assert isinstance(info["TimeLimit.truncated"], bool)
                assert isinstance(info["metrics"]["success"], bool) and isinstance(
                    info["metrics"]["steps"], int
                )
    assert seen_done


def test_dict_observations_end_episodes_with_a_dict_terminal_observation():
    """CrowdNav's observation="dict" (SB3's MultiInputPolicy): a row whose episode ended gets its
    last observation as a dict of that row's arrays. step raised KeyError(0) on the first end
    (it indexed the dict of (B, ...) arrays by the row)."""
    venv = SB3VecEnv(2, task="crowdnav", observation="dict", time_limit=2.0)
    single = gym.make("socialzoo/CrowdNav-v1", observation="dict", time_limit=2.0)
    venv.seed(3)
    venv.reset()
    obs, _ = single.reset(seed=3)
    actions = np.zeros((2, 2), np.float32)
    for _ in range(20):
        _, _, dones, infos = venv.step(actions)
        obs, _, terminated, truncated, _ = single.step(actions[0])
        assert bool(dones[0]) == (terminated or truncated)
        if dones[0]:
            break
    last = infos[0]["terminal_observation"]
    assert venv.observation_space.contains(last)
    assert last.keys() == obs.keys() and all(np.array_equal(last[k], obs[k]) for k in obs)


def test_it_renders_its_rows_as_sb3_vec_envs_do():
    """render_mode="rgb_array" (a TaskVectorEnv keyword) gives SB3's get_images (one frame per row,
    what VecVideoRecorder and VecEnv.render tile); the VecEnv kept render_mode None and had no
    get_images (NotImplementedError), so render() warned and drew nothing."""
    from stable_baselines3.common.vec_env.base_vec_env import tile_images

    venv = SB3VecEnv(2, task="crowdnav", render_mode="rgb_array")
    assert venv.render_mode == "rgb_array" and venv.get_attr("render_mode") == ["rgb_array"] * 2
    venv.seed(0)
    venv.reset()
    venv.step(np.zeros((2, 2), np.float32))
    images = venv.get_images()
    assert len(images) == 2 and all(
        np.array_equal(i, venv.vector_env.draw("rgb_array", row=k)) for k, i in enumerate(images)
    )
    assert np.array_equal(venv.render(), tile_images(images))
    assert SB3VecEnv(1, task="crowdnav").render_mode is None


def test_reset_infos_hold_the_tasks_own_reset_info():
    """CrowdNav's reset info is "case_seed": SB3's reset_infos used to call it "scenario_seed"."""
    venv = SB3VecEnv(3, task="crowdnav")
    venv.seed(4)
    venv.reset()
    _, info = venv.vector_env.reset(seed=4)
    assert venv.reset_infos == [{"case_seed": int(seed)} for seed in info["case_seed"]]


def test_passes_sb3_checks_and_wrappers():
    """SB3's env checker on the single env, its space checks on the VecEnv's spaces, and the
    wrappers training uses: VecCheckNan (raises on NaN or inf), VecMonitor, VecNormalize."""
    sb3_check_env(gym.make(GDC1_ID, **SHORT).unwrapped, warn=True)
    venv = SB3VecEnv(3, **SHORT)
    _check_box_obs(venv.observation_space)
    _check_unsupported_spaces(gym.make(GDC1_ID, **SHORT).unwrapped, venv.observation_space, venv.action_space)
    wrapped = VecNormalize(VecMonitor(VecCheckNan(venv, raise_exception=True)))
    wrapped.seed(1)
    wrapped.reset()
    episodes = 0
    for _ in range(2 * SHORT["max_steps"] + 1):
        obs, _, dones, infos = wrapped.step(np.ones(3, dtype=np.int64))
        assert np.all(np.abs(obs) <= wrapped.clip_obs)
        for done, info in zip(dones, infos, strict=True):
            if done:
                episodes += 1
                assert info["episode"]["l"] == SHORT["max_steps"]  # VecMonitor's record
    assert episodes == 6


def test_seeding_is_reproducible_and_sb3_plumbing():
    a, b = SB3VecEnv(2, **SHORT), SB3VecEnv(2, **SHORT)
    assert a.seed(4) == [4, 4]
    b.seed(4)
    np.testing.assert_array_equal(a.reset(), b.reset())
    for _ in range(10):
        np.testing.assert_array_equal(a.step(np.array([0, 3]))[0], b.step(np.array([0, 3]))[0])
    b.seed(5)
    assert not np.array_equal(a.reset(), b.reset())
    assert a.get_attr("config") == [a.config, a.config] and a.get_attr("render_mode", 1) == [None]
    assert a.env_is_wrapped(gym.Wrapper) == [False, False]
    assert len(a.env_method("reset", seed=3)) == 2
    a.set_attr("render_mode", None)
    with pytest.raises(ValueError, match="all rows"):
        a.set_attr("render_mode", None, indices=[0])


def test_the_callers_actions_are_left_alone_across_autoresets():
    """SB3 stores the array it passed to step() in its rollout buffer after the step."""
    venv = SB3VecEnv(3, max_steps=5)
    venv.seed(0)
    venv.reset()
    for _ in range(5):
        actions = np.array([3, 2, 1])
        _, _, dones, _ = venv.step(actions)
    assert dones.all()
    np.testing.assert_array_equal(actions, [3, 2, 1])


def test_bad_use_fails_clearly():
    with pytest.raises(ValueError, match="num_envs"):
        SB3VecEnv(0)
    with pytest.raises(RuntimeError, match="reset"):
        SB3VecEnv(2, **SHORT).step(np.zeros(2, dtype=np.int64))
    venv = SB3VecEnv(2, **SHORT)
    venv.reset()
    with pytest.raises(ValueError, match="actions"):
        venv.step(np.array([0, 1, 2]))


def test_set_options_reach_the_next_reset():
    # Found probing SB3's VecEnv API: set_options({"split": "val", ...}) was dropped at reset(), so
    # a model evaluated on validation cases played training scenarios without a word.
    venv, vector = SB3VecEnv(2, max_steps=40), ActionSelectionVectorEnv(2, max_steps=40)
    options = {"split": "val", "cases": [3, 1]}
    venv.set_options(options)
    expected, _ = vector.reset(seed=0, options=options)
    np.testing.assert_array_equal(venv.reset(), expected)
    assert not np.array_equal(venv.reset(), expected)  # options are used once, as SB3's are
    venv.set_options([{"split": "val", "case": 0}, {"split": "val", "case": 1}])
    with pytest.raises(ValueError, match="one dict for all rows"):
        venv.reset()
