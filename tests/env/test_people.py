"""Mixed crowds in the env (EnvConfig.people): models per person in every interface, counterfactual
rows without the robot and what the robot costs people, group intrusions, named errors."""

import numpy as np
import pytest

from socialzoo.agents import make_policy
from socialzoo.env.config import EnvConfig
from socialzoo.env.metrics import SUMMARY_KEYS
from socialzoo.env.people import COST_KEYS, _group_crossings, without_robots
from socialzoo.env.registration import BENCHMARK_IDS
from socialzoo.env.tasks.action_selection import ActionSelectionTask
from socialzoo.env.world import step_world
from socialzoo.humans.models import LEARNED, ORCA, SOCIAL_FORCE, PeopleConfig
from socialzoo.scenarios.generator import ScenarioConfig
from socialzoo.scenarios.scenario_sets import TestSet

SMALL = {"map": "open_room", "max_steps": 120, "scenario": {"min_humans": 6, "max_humans": 8}}
BENCHMARK_ID = next(iter(BENCHMARK_IDS))  # the training map's id, at its current version
ROOM_SET = TestSet("open_room", 5, 8, ScenarioConfig(min_humans=6, max_humans=8))


def task_of(batch=3, **people):
    config = EnvConfig().replace(**SMALL, people=people)
    task = ActionSelectionTask(config, batch)
    task.reset_rows(np.arange(batch), ROOM_SET.scenarios(range(batch), task.map))
    return task


def run(task, steps):
    policy = make_policy("goalone")
    for _ in range(steps):
        task.step(policy.act(task.obs, task))


def test_default_people_are_the_benchmarks_and_add_no_metrics():
    task = task_of()
    assert task.core.people.keys == ()
    assert (task.core.state.human_model == SOCIAL_FORCE).all() and (task.core.state.human_group == -1).all()
    run(task, 5)
    assert list(task.episode_metrics([0])[0]) == list(SUMMARY_KEYS)


def test_a_mix_assigns_models_per_scenario_seed():
    task = task_of(batch=4, models="sf@0.5+orca@0.5")
    state = task.core.state
    for row in range(4):
        present = state.human_model[row][state.human_mask[row]]
        n = len(present)
        assert sorted(np.bincount(present, minlength=2)[:2]) == sorted([(n + 1) // 2, n // 2])
    again = task_of(batch=4, models="sf@0.5+orca@0.5")
    assert np.array_equal(again.core.state.human_model, state.human_model)
    run(task, 20)
    assert np.isfinite(task.core.state.human_pos).all()


@pytest.mark.parametrize("models", ["orca", "sf@0.5+orca@0.5"])
def test_kinds_are_each_rows_assignment_and_minus_one_in_empty_slots(models):
    from socialzoo.humans.models import assign_models

    people = task_of(batch=2, models=models).core.people
    rng = np.random.default_rng(5)
    seeds, counts = rng.integers(0, 10**6, 9).tolist(), [0, people.max_humans, *rng.integers(0, 9, 7)]
    kinds = people.kinds(seeds, counts)
    assert kinds.shape == (9, people.max_humans) and kinds.dtype == np.int64
    for row, (seed, n) in enumerate(zip(seeds, counts, strict=True)):
        assert kinds[row, :n].tolist() == assign_models(people.parts, n, seed).tolist()
        assert (kinds[row, n:] == -1).all()
    assert people.kinds([], []).shape == (0, people.max_humans)
    with pytest.raises(ValueError, match="2 seeds but 1 head counts"):
        people.kinds([1, 2], [3])


@pytest.mark.parametrize("models", ["sf", "orca", "sf@0.5+orca@0.5"])
def test_models_of_kinds_are_the_models_of_seeds_and_counts(models):
    people = task_of(batch=2, models=models).core.people
    rng = np.random.default_rng(6)
    seeds, counts = rng.integers(0, 10**6, 6).tolist(), [0, people.max_humans, *rng.integers(0, 9, 4)]
    models_of = people.models_of(people.kinds(seeds, counts))
    assert models_of.dtype == np.int8
    assert np.array_equal(models_of, people.models(seeds, counts))
    assert (models_of[0] == 0).all()  # empty slots: social force


def test_counterfactual_rows_step_as_the_scenario_without_its_robot():
    task = task_of(models="sf@0.5+orca@0.5", counterfactual=True)
    alone = without_robots(task.core.state)
    run(task, 30)
    cfg = task.config.world
    for _ in range(30):
        b = alone.batch_size
        alone, _ = step_world(alone, task.core.walls, cfg, np.zeros((b, 0, 2)), np.zeros((b, 0), bool))
    np.testing.assert_array_equal(task.core.people.ghost.human_pos, alone.human_pos)
    np.testing.assert_array_equal(task.core.people.ghost.human_vel, alone.human_vel)
    # With the robot the people walk otherwise (it is among them).
    assert not np.array_equal(task.core.state.human_pos, alone.human_pos)


def test_people_who_do_not_see_the_robot_lose_no_time():
    config = EnvConfig().replace(
        **SMALL, people={"models": "orca", "counterfactual": True}, world={"orca": {"robot_visible": False}}
    )
    task = ActionSelectionTask(config, 2)
    task.reset_rows(np.arange(2), ROOM_SET.scenarios(range(2), task.map))
    run(task, 120)
    for summary in task.episode_metrics([0, 1]):
        assert set(COST_KEYS) <= set(summary)
        assert summary["people_time_lost"] == 0.0 and summary["people_extra_distance"] == 0.0


def test_the_robot_costs_visible_people_time():
    task = task_of(batch=4, models="sf", counterfactual=True)
    run(task, 120)
    summaries = task.episode_metrics(np.arange(4))
    lost = [s["people_time_lost"] for s in summaries]
    assert all(np.isfinite(lost)) and max(np.abs(lost)) > 0.0
    assert all(s["people_time_lost_max"] >= s["people_time_lost"] for s in summaries)


def test_group_intrusion_counts_a_robot_passing_between_two_members():
    state = without_robots(task_of(batch=1).core.state)
    before = state.copy()
    before.human_mask[0, :2] = True
    before.human_group[0, :2] = 0
    before.human_pos[0, :2] = [[2.0, 1.0], [2.0, 2.0]]
    before.robot_pose = np.array([[[1.5, 1.5, 0.0]]])
    after = before.copy()
    after.robot_pose = np.array([[[2.5, 1.5, 0.0]]])
    assert _group_crossings(before, after).tolist() == [[1]]
    after.robot_pose = np.array([[[2.5, 3.5, 0.0]]])  # beside the pair, not between
    assert _group_crossings(before, after).tolist() == [[0]]
    after.human_group[0, 1] = -1  # strangers
    after.robot_pose = np.array([[[2.5, 1.5, 0.0]]])
    assert _group_crossings(before, after).tolist() == [[0]]


def test_groups_report_intrusions_and_survive_compaction():
    task = task_of(batch=3, models="groups", counterfactual=True)
    assert (task.core.state.human_group[task.core.state.human_mask] >= 0).any()
    run(task, 20)
    small = task.compact([2, 0])
    run(task, 20)
    run(small, 20)
    np.testing.assert_equal(small.episode_metrics([0, 1]), task.episode_metrics([2, 0]))
    assert "group_intrusions" in task.episode_metrics([0])[0]


def learned_config(path, **changes):
    return {**SMALL, "people": {"models": f"sf@0.5+learned:{path}@0.5"}, **changes}


def test_learned_people_are_driven_by_the_env_in_every_interface(walker_policy_path, write_walker, tmp_path):
    import gymnasium

    import socialzoo  # noqa: F401  (registers the ids)
    from socialzoo.env.parallel import parallel_env
    from socialzoo.env.vector import ActionSelectionVectorEnv

    kwargs = learned_config(walker_policy_path)
    env = gymnasium.make(BENCHMARK_ID, **kwargs).unwrapped
    env.reset(seed=3)
    state = env.core.state
    assert (state.human_model[state.human_mask] == LEARNED).sum() >= 3
    for _ in range(3):
        env.step(0)
    vector = ActionSelectionVectorEnv(2, **kwargs)
    vector.reset(seed=3)
    vector.step(np.zeros(2, dtype=np.int64))
    assert (vector.core.state.human_model == LEARNED).any()
    parallel = parallel_env(**kwargs)
    parallel.reset(seed=3)
    parallel.step({agent: 0 for agent in parallel.agents})
    assert (parallel.core.state.human_model == LEARNED).any()
    # Slow walkers (actions tanh(0.5) of their preferred speed) walk slower than the others.
    slow = write_walker(tmp_path / "slow.safetensors", speed=0.5)
    task = task_of(batch=2, models=f"learned:{slow}")
    run(task, 80)
    speed = np.linalg.norm(task.core.state.human_vel, axis=-1)[task.core.state.human_mask]
    assert speed.mean() < 0.7


def test_learned_people_in_the_torchrl_env(walker_policy_path):
    pytest.importorskip("torchrl")
    from socialzoo.env.torchrl_env import SocialNavTorchEnv

    env = SocialNavTorchEnv(batch_size=2, seed=0, **learned_config(walker_policy_path))
    td = env.reset()
    assert (env.core.state.human_model == LEARNED).any()
    assert td is not None


def test_orca_people_in_the_gymnasium_env():
    import gymnasium

    import socialzoo  # noqa: F401

    env = gymnasium.make(BENCHMARK_ID, **SMALL, people={"models": "orca"}).unwrapped
    env.reset(seed=0)
    assert (env.core.state.human_model[env.core.state.human_mask] == ORCA).all()
    _, _, _, _, info = env.step(0)
    assert "reached" in info
    # A people spec alone, as the CrowdNav task and the CLI take it (it was refused: "must be a
    # PeopleConfig"); as an override it changes the models only.
    spec = gymnasium.make(BENCHMARK_ID, **SMALL, people="orca").unwrapped
    assert spec.config.people == env.config.people
    counting = EnvConfig().replace(people={"counterfactual": True})
    assert counting.replace(people="orca").people == PeopleConfig(models="orca", counterfactual=True)
    assert EnvConfig(people="groups").people == PeopleConfig(models="groups")


def test_bad_people_fail_naming_them_before_any_state(tmp_path, walker_policy_path):
    with pytest.raises(ValueError, match="unknown model 'ghosts'"):
        EnvConfig().replace(people={"models": "ghosts"})
    with pytest.raises(ValueError, match=r"the shares sum to 1\.2, not 1"):
        EnvConfig().replace(people={"models": "sf@0.6+orca@0.6"})
    with pytest.raises(ValueError, match=r"OrcaConfig\.radius must be > 0"):
        EnvConfig().replace(world={"orca": {"radius": -0.1}})
    with pytest.raises(ValueError, match="no such learned policy file"):
        EnvConfig().replace(people={"models": f"learned:{tmp_path / 'none.safetensors'}"})
    with pytest.raises(ValueError, match="is a folder, not a learned policy file"):
        EnvConfig().replace(people={"models": f"learned:{tmp_path}"})
    with pytest.raises(ValueError, match="counterfactual needs people the env drives itself"):
        EnvConfig().replace(num_learned_humans=2, people={"counterfactual": True})
    # Learned-human agents among recorded people (socialzoo/Recorded-v4 with num_learned_humans):
    # the recording placed their slots' people, and the learner's actions were silently ignored.
    for models in ("replay", "hybrid:sf", "replay@0.5+sf@0.5"):
        with pytest.raises(ValueError, match="on their recorded tracks, where num_learned_humans = 2"):
            EnvConfig().replace(num_learned_humans=2, people={"models": models})
    # A file of the wrong kind: a robot policy, not a learned human policy.
    from socialzoo.env.policy_file import PolicyFileError, current_env_version, save_policy_file

    robot = tmp_path / "robot.safetensors"
    header = {"policy": "ppo", "network": {}, "observation": {}, "training": {}}
    save_policy_file(robot, {"w": np.zeros(1)}, {**header, "env_id": f"socialzoo/X-v{current_env_version()}"})
    config = EnvConfig().replace(**SMALL, people={"models": f"learned:{robot}"})
    with pytest.raises(PolicyFileError, match="not a learned human policy"):
        ActionSelectionTask(config, 1)
