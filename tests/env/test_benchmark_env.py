"""The single-agent benchmark env and its VectorEnv: conformance, determinism, bad input."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import socialzoo  # noqa: F401  (registers the ids)
from socialzoo.env.gym_env import ActionSelectionEnv
from socialzoo.env.registration import BENCHMARK_IDS, FAMILY_IDS
from socialzoo.env.vector import ActionSelectionVectorEnv

FAST = {"max_steps": 120, "scenario": {"min_humans": 5, "max_humans": 8}}


def rollout(env, seed, actions):
    obs, _ = env.reset(seed=seed)
    trace = [obs]
    for a in actions:
        obs, reward, terminated, truncated, info = env.step(a)
        trace.append((obs, reward, terminated, truncated, sorted(info.items(), key=str)))
        if terminated or truncated:
            obs, _ = env.reset()
            trace.append(obs)
    return trace


def same(a, b):
    if isinstance(a, np.ndarray):
        return a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True)
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, float) and np.isnan(a):
        return isinstance(b, float) and np.isnan(b)
    return a == b


@pytest.mark.parametrize("env_id", list(BENCHMARK_IDS))
def test_gymnasium_check_env_on_registered_ids(env_id):
    env = gym.make(env_id, **FAST)
    check_env(env.unwrapped, skip_render_check=True)
    assert env.unwrapped.observation_space is env.unwrapped.observation_space
    assert env.unwrapped.observation_space.shape == (7 + 4 * 25,)


def test_stable_baselines3_check_env():
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    sb3_check_env(ActionSelectionEnv(map="open_room", **FAST), warn=False)


@pytest.mark.parametrize("env_id", list(FAMILY_IDS))
def test_family_ids_step(env_id):
    env = gym.make(env_id, max_steps=50)
    obs, _ = env.reset(seed=3)
    assert env.observation_space.contains(obs)
    for _ in range(50):
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        assert np.isfinite(reward)
        if terminated or truncated:
            break
    assert terminated or truncated


def test_multi_step_determinism():
    actions = np.random.default_rng(0).integers(0, 4, 300)
    a = rollout(ActionSelectionEnv(**FAST), 11, actions)
    b = rollout(ActionSelectionEnv(**FAST), 11, actions)
    assert same(a, b)
    c = rollout(ActionSelectionEnv(**FAST), 12, actions)
    assert not same(a, c)


def test_vector_rows_equal_single_envs():
    """Row 0 of a VectorEnv seeded s plays the same episode as a single env seeded s."""
    actions = np.random.default_rng(1).integers(0, 4, 100)
    single = ActionSelectionEnv(**FAST)
    obs, _ = single.reset(seed=5)
    vec = ActionSelectionVectorEnv(4, **FAST)
    vobs, _ = vec.reset(seed=5)
    np.testing.assert_array_equal(vobs[0], obs)
    for a in actions:
        obs, reward, terminated, truncated, _ = single.step(int(a))
        batch_actions = np.full(4, int(a))
        vobs, vreward, vterm, vtrunc, info = vec.step(batch_actions)
        assert vreward[0] == reward and vterm[0] == terminated and vtrunc[0] == truncated
        if terminated or truncated:
            np.testing.assert_array_equal(info["final_obs"][0], obs)
            break
        np.testing.assert_array_equal(vobs[0], obs)


def test_vector_env_autoresets_and_reports_metrics():
    vec = gym.make_vec(
        "socialzoo/ActionSelection-v2",
        num_envs=3,
        vectorization_mode="vector_entry_point",
        max_steps=30,
        scenario={"min_humans": 5, "max_humans": 5},
    )
    vec.reset(seed=0)
    for _ in range(30):
        obs, _, terminated, truncated, info = vec.step(np.zeros(3, dtype=np.int64))
    assert truncated.all() or terminated.any()
    assert "final_info" in info and info["final_info"]["metrics"]["steps"].max() == 30
    assert vec.observation_space.contains(obs)


def test_vector_env_leaves_the_callers_actions_alone_across_autoresets():
    """The core keeps the previous actions and zeroes the rows it resets: never in the caller's array."""
    vec = ActionSelectionVectorEnv(3, map="open_room", max_steps=4)
    vec.reset(seed=0)
    for _ in range(4):
        actions = np.array([3, 2, 1], dtype=np.int64)
        _, _, terminated, truncated, _ = vec.step(actions)
    assert (terminated | truncated).all()
    np.testing.assert_array_equal(actions, [3, 2, 1])


@pytest.mark.parametrize("mask", [np.array([True]), np.array([1]), [0, 2], np.array([[True, False, True]])])
def test_vector_reset_mask_of_another_shape_or_dtype_is_refused_before_anything_changes(mask):
    """Row indices ([0, 2]) or one entry per ended row used to reset whichever rows they cast to."""
    vec = ActionSelectionVectorEnv(3, map="open_room", max_steps=40)
    vec.reset(seed=0)
    vec.step(np.zeros(3, dtype=np.int64))
    before = vec.task.observations().copy()
    with pytest.raises(ValueError, match=r"reset_mask.*3 bools, one per row"):
        vec.reset(seed=5, options={"reset_mask": mask})
    np.testing.assert_array_equal(vec.task.observations(), before)
    obs, _ = vec.reset(options={"reset_mask": np.array([False, True, False])})
    np.testing.assert_array_equal(obs[[0, 2]], before[[0, 2], 0])


@pytest.mark.parametrize("env_id", ["socialzoo/ActionSelection-v2", "socialzoo/CrowdNav-v1"])
def test_a_seeded_masked_reset_reseeds_only_the_masked_rows(env_id):
    """As Gymnasium's SyncVectorEnv seeds only the envs it resets; every row's stream was reseeded."""

    def seeds(*resets):
        vec = gym.make_vec(env_id, num_envs=3)
        for seed, mask in resets:
            options = {} if mask is None else {"reset_mask": np.array(mask)}
            _, info = vec.reset(seed=seed, options=options)
        return info[vec.unwrapped.task.reset_info_key]

    untouched = seeds((0, None), (None, [False, True, True]))
    reseeded = seeds((0, None), (5, [True, False, False]), (None, [False, True, True]))
    np.testing.assert_array_equal(reseeded[1:], untouched[1:])  # rows 1 and 2 went on with their streams
    # The masked row plays row 0's episodes of seed 5, as in a batch seeded with 5.
    assert seeds((0, None), (5, [True, False, False]))[0] == seeds((5, None))[0]


def test_episode_end_info_and_step_after_end():
    env = ActionSelectionEnv(map="open_room", max_steps=20)
    env.reset(seed=0)
    for _ in range(20):
        _, _, terminated, truncated, info = env.step(1)
        if terminated or truncated:
            break
    assert truncated and not terminated
    assert info["metrics"]["steps"] == 20 and info["metrics"]["success"] is False
    with pytest.raises(RuntimeError, match="reset"):
        env.step(0)


@pytest.mark.parametrize("bad", [4, -1, 1.5, float("nan"), "go", [0, 1]])
def test_bad_actions_raise_before_anything_changes(bad):
    env = ActionSelectionEnv(map="open_room", max_steps=20)
    env.reset(seed=0)
    before = env.core.state.copy()
    with pytest.raises(ValueError, match="action"):
        env.step(bad)
    np.testing.assert_array_equal(env.core.state.robot_pose, before.robot_pose)
    np.testing.assert_array_equal(env.core.state.human_pos, before.human_pos)


def test_step_before_reset_raises():
    with pytest.raises(RuntimeError, match="reset"):
        ActionSelectionEnv(map="open_room").step(0)


def test_socialgym1_layout():
    env = ActionSelectionEnv(map="open_room", observation={"layout": "socialgym1"}, max_steps=20)
    obs, _ = env.reset(seed=0)
    assert obs.shape == (244,) and env.observation_space.contains(obs)


def test_bad_config_names_the_field():
    with pytest.raises(ValueError, match="max_steps"):
        ActionSelectionEnv(map="open_room", max_steps=0)
    with pytest.raises(ValueError, match="unknown field"):
        ActionSelectionEnv(map="open_room", reward={"w_progres": 1.0})
    with pytest.raises(ValueError, match="num_robots"):
        ActionSelectionEnv(map="open_room", num_robots=2)


def test_replay_a_scenario_through_options():
    env = ActionSelectionEnv(map="open_room", max_steps=50)
    env.reset(seed=4)
    scenario = env.core.scenarios[0]
    a = rollout_from(env, scenario)
    b = rollout_from(ActionSelectionEnv(map="open_room", max_steps=50), scenario)
    assert same(a, b)


def test_a_scenario_of_another_map_is_refused_naming_both_maps():
    # It was replayed without a word: gdc1's coordinates on the doorway's walls.
    env = ActionSelectionEnv(map="gdc1", max_steps=5)
    env.reset(seed=3)
    scenario = env.core.scenarios[0]
    other = ActionSelectionEnv(map="doorway", max_steps=5)
    with pytest.raises(
        ValueError, match=r"of scenario .* \(made for map 'gdc1'\) lies outside map 'doorway'"
    ):
        other.reset(options={"scenario": scenario})
    env.reset(options={"scenario": scenario})  # on its own map it plays


def rollout_from(env, scenario):
    obs, _ = env.reset(options={"scenario": scenario})
    out = [obs]
    for _ in range(50):
        obs, reward, terminated, truncated, _ = env.step(0)
        out.append((obs, reward))
        if terminated or truncated:
            break
    return out


def test_rgb_render():
    env = ActionSelectionEnv(map="open_room", render_mode="rgb_array", max_steps=10)
    env.reset(seed=0)
    env.step(0)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    env.close()


@pytest.mark.parametrize("env_id", list(BENCHMARK_IDS) + list(FAMILY_IDS))
def test_registered_specs_round_trip_through_json(env_id):
    from gymnasium.envs.registration import EnvSpec

    spec = gym.spec(env_id)
    again = EnvSpec.from_json(spec.to_json())
    assert again.id == spec.id and again.kwargs == spec.kwargs and again.entry_point == spec.entry_point


# ---------------------------------------------------------------------------- SPEC 9: who is skipped
PASS, FOLLOW = 3, 2
# One slow human walks ahead of the robot down the hallway: Pass overtakes it, Follow trails it.
OVERTAKING = {"map": "hallway", "family": "overtaking", "max_steps": 300}


def nearest_visible_distance(core, leave_out=-1):
    """Distance from robot 0 of row 0 to the nearest human it sees after the step (inf for none)."""
    s = core.state
    d = np.linalg.norm(s.human_pos[0] - s.robot_pose[0, 0, :2], axis=-1)
    counted = core.visible[0] & (np.arange(len(d)) != leave_out)
    return float(d[counted].min(initial=np.inf))


def test_pass_is_charged_for_the_human_it_passes():
    env = gym.make("socialzoo/ActionSelection-v2", **OVERTAKING)
    env.reset(seed=0)
    core = env.unwrapped.core
    for _ in range(300):
        _, _, terminated, truncated, info = env.step(PASS)
        assert info["action_name"] == "Pass"
        target = info["target_human"]
        if target >= 0:
            passed = float(np.linalg.norm(core.state.human_pos[0, target] - core.state.robot_pose[0, 0, :2]))
            if passed < 0.7 and core.visible[0, target]:
                break
        assert not (terminated or truncated), "the robot never passed its target within 0.7 m"
    d = nearest_visible_distance(core)
    assert d <= passed < 0.7
    assert info["force"] > 0.0
    assert info["force"] == pytest.approx(np.exp(-(d**4)), rel=1e-12)
    assert info["force"] >= np.exp(-(passed**4)) * (1 - 1e-12)
    assert info["blame"] > 0.0


def test_follow_still_skips_its_target():
    env = gym.make("socialzoo/ActionSelection-v2", **OVERTAKING)
    env.reset(seed=0)
    core = env.unwrapped.core
    checked = 0
    for _ in range(200):
        _, _, terminated, truncated, info = env.step(FOLLOW)
        target = info["target_human"]
        if target >= 0 and core.visible[0, target]:
            followed = float(
                np.linalg.norm(core.state.human_pos[0, target] - core.state.robot_pose[0, 0, :2])
            )
            if followed < 1.5:
                other = nearest_visible_distance(core, leave_out=target)
                assert info["force"] == pytest.approx(np.exp(-(other**4)), rel=1e-12, abs=0.0)
                # Were the target counted, the force would be at least exp(-d^4) of it.
                assert info["force"] < np.exp(-(followed**4))
                checked += 1
        if terminated or truncated:
            break
    assert checked > 20


def test_old_env_versions_are_refused_naming_the_new_one():
    for old, new in [
        ("socialzoo/ActionSelection-v1", "socialzoo/ActionSelection-v2"),
        ("socialzoo/ActionSelectionTransfer-v1", "socialzoo/ActionSelectionTransfer-v2"),
        ("socialzoo/HallwayHeadOn-v1", "socialzoo/HallwayHeadOn-v2"),
    ]:
        assert new in gym.registry and old not in gym.registry
        with pytest.warns(DeprecationWarning), pytest.raises(gym.error.DeprecatedEnv, match=new):
            gym.make(old)


def test_infos_share_one_set_of_keys():
    from socialzoo.env.tasks.action_selection import INITIAL_INFO

    env = ActionSelectionEnv(map="open_room", max_steps=5)
    env.reset(seed=0)
    _, _, _, _, info = env.step(0)
    assert set(INITIAL_INFO) <= set(info)
    assert list(env.task.initial_info()) == list(env.task.info_keys) == list(INITIAL_INFO)
    vec = ActionSelectionVectorEnv(2, map="open_room", max_steps=5)
    vec.reset(seed=0)
    *_, vinfo = vec.step(np.zeros(2, dtype=np.int64))
    assert set(INITIAL_INFO) <= set(vinfo)
    assert all(vinfo[key].shape == (2,) for key in INITIAL_INFO)
    assert vinfo["force"][0] == info["force"] and vinfo["target_human"][0] == info["target_human"]


def test_gym_make_on_an_imported_map_file(tmp_path):
    from socialzoo.maps.floorplans import long_corridor
    from socialzoo.maps.repair import repair_map

    plan = long_corridor(120.0)
    m, _ = repair_map("corridor", plan.walls, seed_point=plan.inside)
    path = m.save(tmp_path / "corridor.json")
    env_id = next(iter(BENCHMARK_IDS))  # the training map's id, on another map
    env = gym.make(env_id, map=str(path), scenario={"min_humans": 0, "max_humans": 0})
    env.reset(seed=3)
    start = env.unwrapped.core.state.robot_pose[0, 0, :2].copy()
    goal = env.unwrapped.core.state.robot_goal[0, 0, :2].copy()
    assert abs(goal[0] - start[0]) <= 90.0  # feasible: the 120 m corridor's far pairs are never drawn
    done, info = False, {}
    while not done:
        _, _, terminated, truncated, info = env.step(0)
        done = terminated or truncated
    assert info["metrics"]["success"]
    env.close()
