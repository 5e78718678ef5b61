"""The CrowdNav task's Gymnasium adapters: API conformance, multi-step determinism, the batch
equals single envs, fixed cases, and bad input refused before anything changes."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import socialzoo  # noqa: F401  (registers the ids)
from socialzoo.env.gym_env import CrowdNavEnv
from socialzoo.env.registration import CROWD_IDS
from socialzoo.env.vector import CrowdNavVectorEnv

VARIANTS = ["SocialForce", ""]


def _rollout(env, seed, steps=40):
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    trace = [obs.copy()]
    for _ in range(steps):
        obs, reward, terminated, truncated, _ = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
        trace.append(np.append(obs, reward))
        if terminated or truncated:
            obs, _ = env.reset()
    return np.concatenate(trace)


@pytest.mark.parametrize("variant", VARIANTS)
def test_every_variant_id_passes_gymnasiums_checker(variant):
    env = gym.make(f"socialzoo/CrowdNav{variant}-v1")
    check_env(env.unwrapped, skip_render_check=True)
    assert set(CROWD_IDS) >= {
        "socialzoo/CrowdNav-v1",
        "socialzoo/CrowdNavWalls-v1",
        "socialzoo/CrowdNav20-v1",
    }


@pytest.mark.parametrize("variant", VARIANTS)
def test_rollouts_repeat_bit_for_bit_over_many_steps(variant):
    a = _rollout(CrowdNavEnv(variant=variant), seed=3)
    np.testing.assert_array_equal(a, _rollout(CrowdNavEnv(variant=variant), seed=3))
    assert not np.array_equal(a, _rollout(CrowdNavEnv(variant=variant), seed=4))


@pytest.mark.parametrize("observation", ["flat", "dict"])
def test_a_batch_row_plays_what_a_single_env_plays(observation):
    vec = CrowdNavVectorEnv(3, variant="SocialForce", observation=observation)
    single = CrowdNavEnv(variant="SocialForce", observation=observation)

    def same(a, b):
        for key in a if observation == "dict" else [None]:
            np.testing.assert_array_equal(a if key is None else a[key], b if key is None else b[key])

    def row(values, k):
        return {key: v[k] for key, v in values.items()} if observation == "dict" else values[k]

    obs, _ = vec.reset(seed=5)
    one, _ = single.reset(seed=5)
    same(row(obs, 0), one)
    rng = np.random.default_rng(0)
    ends = 0
    for _ in range(120):  # row 0's first episode ends within its time limit (100 steps)
        actions = rng.uniform(-1, 1, (3, 2)).astype(np.float32)
        obs, reward, terminated, truncated, info = vec.step(actions)
        one, r, te, tr, _ = single.step(actions[0])
        assert (terminated[0], truncated[0], reward[0]) == (te, tr, r)
        if te or tr:
            ends += 1
            same(row(info["final_obs"], 0), one)  # the ended episode's last observation
            one, _ = single.reset()
        if "final_obs" in info:  # zeros in the rows that did not end
            final = info["final_obs"]
            for v in final.values() if observation == "dict" else [final]:
                assert not v[~(terminated | truncated)].any()
        same(row(obs, 0), one)
    assert ends


def test_fixed_cases_are_crowdnavs_and_end_with_metrics():
    env = CrowdNavEnv(variant="SocialForce", action="discrete")
    _, info = env.reset(options={"split": "test", "case": 7})
    assert info["case_seed"] == 1007
    for _ in range(200):
        _, _, terminated, truncated, info = env.step(0)  # stand still
        if terminated or truncated:
            break
    assert "metrics" in info and info["metrics"]["steps"] <= 97
    vec = CrowdNavVectorEnv(2, variant="SocialForce")
    _, info = vec.reset(options={"split": "val", "cases": [0, 99]})
    assert info["case_seed"].tolist() == [0, 99]


def test_the_cases_are_drawn_for_the_tasks_robot_and_reward():
    # CrowdNav reads [robot] radius and [reward] discomfort_dist for its spawn spacing too: a larger
    # robot must never start inside a person, nor a wider discomfort zone hold anyone at the start.
    for overrides in ({"robot": {"radius": 0.7}}, {"reward": {"discomfort_dist": 0.5}}):
        env = CrowdNavEnv(**overrides)
        config = env.unwrapped.task.config
        assert config.cases.robot_radius == config.robot.radius
        assert config.cases.discomfort_dist == config.reward.discomfort_dist
        for case in range(30):
            env.reset(options={"split": "test", "case": case})
            s = env.unwrapped.task.world_state
            gap = np.hypot(*(s.human_pos[0] - s.robot_pose[0, 0, :2]).T) - config.robot.radius - 0.3
            assert gap.min() >= config.reward.discomfort_dist, (overrides, case)
    with pytest.raises(ValueError, match=r"cases\.robot_radius \(0\.4\) must equal robot\.radius"):
        CrowdNavEnv(cases={"robot_radius": 0.4})


def test_bad_actions_and_configs_are_refused_before_any_change():
    vec = CrowdNavVectorEnv(2, variant="SocialForce")
    vec.reset(seed=0)
    before = vec.core.state.copy()
    for bad in (np.array([[np.nan, 0.0], [0.0, 0.0]]), np.array([[2.0, 0.0], [0.0, 0.0]]), np.zeros((3, 2))):
        with pytest.raises(ValueError, match="action"):
            vec.step(bad)
    with pytest.raises(ValueError, match="CrowdNavVectorEnv: actions must be numbers"):
        vec.step(np.array([["a", "b"], ["c", "d"]]))  # was numpy's "could not convert string to float"
    np.testing.assert_array_equal(vec.core.state.robot_pose, before.robot_pose)
    np.testing.assert_array_equal(vec.core.state.human_pos, before.human_pos)
    with pytest.raises(ValueError, match="variant"):
        CrowdNavEnv(variant="Stadium")
    with pytest.raises(ValueError, match="human_radius"):
        CrowdNavEnv(cases={"human_radius": -0.3})
    with pytest.raises(ValueError, match="humans"):
        CrowdNavEnv(humans="boids")
    with pytest.raises(ValueError, match="action_frame"):
        CrowdNavEnv(action_frame="robot")
    with pytest.raises(ValueError, match="wall_rays"):
        CrowdNavEnv(wall_rays=-1)
    discrete = CrowdNavEnv(action="discrete")
    discrete.reset(seed=0)
    with pytest.raises(ValueError, match=r"0\.\.80"):
        discrete.step(81)


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (
            {"cases": {"num_human": 5}},
            r"CrowdNavConfig\.cases: unknown field\(s\) \['num_human'\]; known: .*'num_humans'",
        ),
        ({"robot": {"radious": 0.3}}, r"CrowdNavConfig\.robot: unknown field\(s\) \['radious'\]"),
        ({"reward": {"gama": 0.9}}, r"CrowdNavConfig\.reward: unknown field\(s\) \['gama'\]"),
        (
            {"cases": "circle_crossing"},
            r"CrowdNavConfig\.cases must be a CrowdCaseConfig .*'circle_crossing'",
        ),
        ({"robot": 0.3}, r"CrowdNavConfig\.robot must be a RobotConfig .*0\.3"),
        ({"reward": None}, r"CrowdNavConfig\.reward must be a CrowdRewardConfig .*None"),
        ({"robot_visible": "no"}, r"CrowdNavConfig\.robot_visible must be a bool, got 'no'"),
    ],
)
def test_a_bad_nested_config_names_its_field(overrides, message):
    # A misspelt nested field was a bare TypeError of the nested class (a traceback from
    # `socialzoo replay --task-config cases.foo=1`), a nested config of the wrong type an
    # AttributeError, and robot_visible was reported as OrcaConfig's.
    with pytest.raises(ValueError, match=message):
        gym.make("socialzoo/CrowdNav-v1", **overrides)


@pytest.mark.parametrize("action", ["continuous", "discrete"])
def test_the_torchrl_env_passes_its_spec_check_and_matches_the_vector_env(action):
    pytest.importorskip("torchrl")
    import torch
    from torchrl.envs.utils import check_env_specs

    from socialzoo.env.torchrl_single import CrowdNavTorchEnv

    env = CrowdNavTorchEnv(3, variant="SocialForce", action=action, categorical_action_encoding=True)
    check_env_specs(env)
    env.set_seed(11)
    td = env.reset()
    vec = CrowdNavVectorEnv(3, variant="SocialForce", action=action)
    obs, _ = vec.reset(seed=11)
    np.testing.assert_array_equal(td["observation"].numpy(), obs)
    rng = np.random.default_rng(1)
    for _ in range(5):
        a = rng.integers(0, 81, 3) if action == "discrete" else rng.uniform(-1, 1, (3, 2)).astype(np.float32)
        td["action"] = torch.as_tensor(a)
        td = env.step(td)
        obs, reward, terminated, truncated, _ = vec.step(a)
        np.testing.assert_allclose(td["next", "reward"].numpy()[:, 0], reward, rtol=1e-6)
        if (terminated | truncated).any():
            break
        np.testing.assert_array_equal(td["next", "observation"].numpy(), obs)
        td = td["next"].clone()


def test_several_robots_pass_pettingzoos_tests_and_repeat_over_many_steps():
    from pettingzoo.test import parallel_api_test, parallel_seed_test

    from socialzoo.env.parallel import CrowdNavParallelEnv, parallel_crowd_env

    env = parallel_crowd_env(num_robots=3, variant="SocialForce")
    parallel_api_test(env, num_cycles=100)
    parallel_seed_test(lambda: CrowdNavParallelEnv(num_robots=3, variant="SocialForce"))

    def rollout(seed):
        env = CrowdNavParallelEnv(num_robots=2, variant="SocialForce", action="discrete")
        obs, _ = env.reset(seed=seed)
        trace = [obs["robot_0"]]
        rng = np.random.default_rng(seed)
        while env.agents:
            obs, rewards, _, _, infos = env.step({a: int(rng.integers(81)) for a in env.agents})
            trace += [*obs.values(), np.array(list(rewards.values()))]
        return np.concatenate(trace), infos

    a, infos = rollout(7)
    np.testing.assert_array_equal(a, rollout(7)[0])
    assert all("metrics" in info for info in infos.values())
    assert CrowdNavParallelEnv(num_robots=2).observation_space("robot_0").shape == (6 + 8 * 6,)
    with pytest.raises(ValueError, match="num_robots"):
        CrowdNavVectorEnv(2, num_robots=2)


@pytest.mark.parametrize("frame", ["goal", "world"])
def test_a_velocity_action_is_taken_in_its_frame(frame):
    # CrowdNav++'s arena places start and goal at random: (1, 0) heads for the goal in the goal
    # frame (the observation's), and along +x in the world frame.
    env = CrowdNavEnv(variant="20", action_frame=frame)
    obs, _ = env.reset(seed=2)
    start = env.core.state.robot_pose[0, 0, :2].copy()
    goal = env.core.state.robot_goal[0, 0, :2]
    env.step(np.array([1.0, 0.0], dtype=np.float32))
    moved = env.core.state.robot_pose[0, 0, :2] - start
    expected = (goal - start) / np.linalg.norm(goal - start) if frame == "goal" else np.array([1.0, 0.0])
    np.testing.assert_allclose(moved / np.linalg.norm(moved), expected, atol=1e-9)
    assert obs[0] == pytest.approx(np.linalg.norm(goal - start), abs=1e-5)


def test_among_walls_the_robot_sees_its_route_and_the_walls_its_scan_hits():
    env = CrowdNavEnv(variant="Walls")
    config = env.config
    h, k = config.slots, config.wall_rays
    assert env.observation_space.shape == (6 + 8 * (h + k),)
    obs, _ = env.reset(seed=1)
    core = env.core
    for _ in range(12):
        pos = core.state.robot_pose[0, 0, :2]
        # The goal distance is the route's length left (at least the straight distance), the x
        # axis points at the route's carrot.
        straight = np.linalg.norm(core.state.robot_goal[0, 0, :2] - pos)
        assert obs[0] == pytest.approx(core.route_left[0, 0], rel=1e-6) and obs[0] >= straight - 1e-6
        carrot = core.carrot[0, 0] - pos
        assert env.task.frame_angle[0] == pytest.approx(np.arctan2(carrot[1], carrot[0]))
        # Every seen wall slot lies on a wall, within the scan's range, still and of radius 0.
        slots = obs[6 : 6 + 7 * (h + k)].reshape(h + k, 7)[h:]
        seen = obs[6 + 7 * (h + k) :][h:] == 1
        assert seen.any()
        c, s = np.cos(env.task.frame_angle[0]), np.sin(env.task.frame_angle[0])
        world = pos + np.stack(
            (c * slots[seen, 0] - s * slots[seen, 1], s * slots[seen, 0] + c * slots[seen, 1]), -1
        )
        _, distance = core.walls.nearest(world)
        assert np.all(distance < 1e-3) and np.all(slots[seen, 5] <= config.wall_range)
        assert np.all(slots[seen, 2:5] == 0)
        obs, _, terminated, truncated, _ = env.step(np.array([0.5, 0.0], dtype=np.float32))
        assert not (terminated or truncated)


def test_the_crowdnav_task_takes_the_people_spec():
    from socialzoo.humans.models import ORCA, SOCIAL_FORCE

    mixed = CrowdNavVectorEnv(2, variant="20", humans="sf@0.5+orca@0.5", physics_substeps=1)
    mixed.reset(seed=0)
    state = mixed.core.state
    for row in range(2):
        models = state.human_model[row][state.human_mask[row]]
        assert (models == SOCIAL_FORCE).sum() == 10 and (models == ORCA).sum() == 10
    again = CrowdNavVectorEnv(2, variant="20", humans="sf@0.5+orca@0.5", physics_substeps=1)
    again.reset(seed=0)
    np.testing.assert_array_equal(again.core.state.human_model, state.human_model)  # from each case's seed
    assert CrowdNavEnv(humans="social_force").task.config.humans == "social_force"  # the spec's alias of sf
    for spec, match in (
        ("groups", "walk by"),
        ("learned:x.safetensors", "walk by"),
        ("hybrid:learned:x.safetensors", "learned people, hybrid or not, .* action-selection task's"),
        ("boids", "unknown model"),
    ):
        with pytest.raises(ValueError, match=match):
            CrowdNavEnv(humans=spec)


@pytest.mark.parametrize(
    "overrides",
    [{}, {"num_robots": 2}, {"variant": "Walls"}, {"variant": "Walls", "num_robots": 2}],
    ids=["one robot", "two robots", "walls", "walls, two robots"],
)
def test_a_reset_observes_its_rows_as_the_whole_batch_is_observed(overrides):
    from socialzoo.env.tasks.crowdnav import CrowdNavTask

    task = CrowdNavTask(None, 4, **overrides)
    task.seed(3)
    task.reset(np.arange(4), {})
    rng = np.random.default_rng(0)
    for _ in range(3):
        task.step(rng.uniform(-1, 1, (4, task.num_robots, 2)))
    # The reset rows' robots are observed alone (a take of their rows), the others kept from the step.
    task.reset(np.array([2, 0]), {})
    partial, mask, angle = (
        task.observation.buffer.copy(),
        task.observation.mask.copy(),
        task.frame_angle.copy(),
    )
    whole = task._observe()
    np.testing.assert_array_equal(partial, whole.buffer)
    np.testing.assert_array_equal(mask, whole.mask)
    np.testing.assert_array_equal(angle, task.frame_angle)


@pytest.mark.parametrize("overrides", [{}, {"variant": "Walls"}], ids=["arena cases", "scenarios"])
def test_reset_rows_refuses_rows_outside_the_batch_before_any_change(overrides):
    from socialzoo.env.tasks.crowdnav import CrowdNavTask

    task = CrowdNavTask(None, 4, **overrides)
    task.seed(3)
    task.reset(np.arange(4), {})
    cases = task.source.next(np.array([1, 2]))
    seeds, pose = task.case_seed.copy(), task.core.state.robot_pose.copy()
    with pytest.raises(ValueError, match=r"outside 0..3"):
        task.reset_rows(np.array([1, 4]), cases)
    with pytest.raises(ValueError, match="got 1 rows but 2 scenarios"):
        task.reset_rows(np.array([1]), cases)
    np.testing.assert_array_equal(task.case_seed, seeds)
    np.testing.assert_array_equal(task.core.state.robot_pose, pose)


def test_a_map_without_a_registered_test_set_plays_the_generated_one_as_its_test_split(
    rooms_map_path, tmp_path
):
    # `socialzoo benchmark --maps socialzoo/CrowdNavWalls-v1 --task-config map=PATH` on an imported
    # building ended in "split must be one of ['val'], got 'test'".
    from socialzoo.bench.task_benchmark import TaskId
    from socialzoo.bench.test_sets import stored_test_set
    from socialzoo.scenarios.scenario_sets import CUSTOM_TEST_SEED, map_case_sets

    sets = map_case_sets("rooms")
    assert sets["test"].base_seed == CUSTOM_TEST_SEED and sets["val"].name == "rooms-val"
    assert map_case_sets("gdc1")["test"].name == "gdc1-test" and "gdc1-quick" in map_case_sets("gdc1")
    generated = stored_test_set(str(rooms_map_path), tmp_path, 2)  # the maps benchmark's set
    for env_id in ("socialzoo/CrowdNavWalls-v1", "socialzoo/ActionSelection-v2"):
        task = TaskId.of(env_id).make(2, map=str(rooms_map_path))
        assert task.case_splits()["test"] == 2000
        task.reset(np.arange(2), {"split": "test", "cases": [0, 1]})
        np.testing.assert_allclose(
            task.core.state.robot_goal[:, 0, :2], [s.robot_goal[:2] for s in generated.stored[:2]]
        )
