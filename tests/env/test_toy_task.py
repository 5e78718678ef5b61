"""A task written in one file (tests/toy_task.py) and registered with one line runs through every
adapter and passes each ecosystem's checker: Gymnasium, SB3, the VectorEnv, PettingZoo, TorchRL."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from socialzoo.agents import POLICIES, register_policy
from socialzoo.env.gym_env import TaskEnv
from socialzoo.env.registration import register_task

TOY = "toy_task:ToyReachTask"
TOY_ID = "socialzoo-test/ToyReach-v0"
register_task(TOY_ID, TOY, max_steps=120)
if "toy_heading" not in POLICIES:
    register_policy("toy_heading", "toy_task:ToyHeadForGoal", task="toy_reach")


def test_gymnasium_check_env_passes_on_the_registered_id():
    from gymnasium.utils.env_checker import check_env

    env = gym.make(TOY_ID)
    check_env(env.unwrapped, skip_render_check=True)
    obs, info = env.reset(seed=0)
    assert obs.shape == (16,) and "scenario_seed" in info


def test_stable_baselines3_check_env_passes():
    from stable_baselines3.common.env_checker import check_env

    check_env(gym.make(TOY_ID).unwrapped)


def test_the_vector_env_autoresets_and_matches_the_single_env_on_row_0():
    vec = gym.make_vec(TOY_ID, num_envs=3, vectorization_mode="vector_entry_point", max_steps=15)
    single = gym.make(TOY_ID, max_steps=15)
    obs, _ = vec.reset(seed=4)
    one, _ = single.reset(seed=4)
    np.testing.assert_array_equal(obs[0], one)
    ended, metrics = 0, {}
    for t in range(20):
        action = np.array([t % 4, 0, 1])
        obs, reward, _, _, info = vec.step(action)
        one, r, term, trunc, _ = single.step(int(action[0]))
        if "final_info" in info:
            metrics = info["final_info"]["metrics"]
        if term or trunc:
            assert info["_final_obs"][0]
            np.testing.assert_array_equal(info["final_obs"][0], one)
            one, _ = single.reset()
            ended += 1
        np.testing.assert_array_equal(obs[0], one)
        assert reward[0] == r
    assert ended >= 1 and "success" in metrics


def test_make_vec_max_episode_steps_truncates_rows_as_timelimit_does_a_single_env():
    """gymnasium.make_vec passes max_episode_steps to the vector entry point (its default mode for
    these ids); the VectorEnv refused it as an unknown config field."""
    vec = gym.make_vec(TOY_ID, num_envs=2, max_episode_steps=4)
    single = gym.make(TOY_ID, max_episode_steps=4)
    obs, _ = vec.reset(seed=1)
    one, _ = single.reset(seed=1)
    for t in range(9):
        obs, reward, term, trunc, info = vec.step(np.array([3, 3]))
        one, r, one_term, one_trunc, _ = single.step(3)
        assert (term[0], trunc[0], reward[0]) == (one_term, one_trunc, r)
        if one_term or one_trunc:
            assert trunc.all() and t % 4 == 3 and info["final_info"]["metrics"]["steps"][0] == 4
            one, _ = single.reset()
        np.testing.assert_array_equal(obs[0], one)
    with pytest.raises(ValueError, match="max_episode_steps"):
        gym.make_vec(TOY_ID, num_envs=2, max_episode_steps=0)


def test_pettingzoo_parallel_api_test_passes_with_two_robots():
    from pettingzoo.test import parallel_api_test

    from socialzoo.env.parallel import TaskParallelEnv

    env = TaskParallelEnv(task=TOY, num_robots=2, max_steps=40)
    parallel_api_test(env, num_cycles=60)
    assert env.possible_agents == ["robot_0", "robot_1"]


def test_torchrl_check_env_specs_passes_single_and_multi_agent():
    pytest.importorskip("torchrl")
    from torchrl.envs.utils import check_env_specs

    from socialzoo.env.torchrl_env import SocialNavTorchEnv
    from socialzoo.env.torchrl_single import TaskTorchEnv

    check_env_specs(TaskTorchEnv(3, task=TOY, max_steps=20), seed=0)
    check_env_specs(SocialNavTorchEnv(task=TOY, batch_size=2, num_robots=2, max_steps=20), seed=0)


def test_seeded_rollouts_repeat_bit_for_bit_over_many_steps():
    def rollout(seed: int) -> list[np.ndarray]:
        env = gym.make(TOY_ID, max_steps=30)
        out = [env.reset(seed=seed)[0]]
        for t in range(70):
            obs, reward, terminated, truncated, _ = env.step(t % 4)
            out += [obs, np.array([reward])]
            if terminated or truncated:
                out.append(env.reset()[0])
        return out

    a, b, c = rollout(5), rollout(5), rollout(6)
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    assert not all(np.array_equal(x, y) for x, y in zip(a, c, strict=False))


def test_socialzoo_benchmark_runs_the_registered_id_with_tables_and_a_figure(tmp_path, capsys):
    from socialzoo.cli import main

    args = [
        "benchmark",
        "--maps",
        TOY_ID,
        "--policies",
        "toy_heading",
        "--trials",
        "6",
        "--out",
        str(tmp_path),
    ]
    assert main(args) == 0
    table = (tmp_path / "toy_reach.md").read_text()
    assert "| toy_heading |" in table and "success (rate)" in table
    assert (tmp_path / "success.png").stat().st_size > 5_000
    assert "6 episodes played, 0 read from the store" in capsys.readouterr().out
    assert (
        main(args) == 0 and "0 episodes played, 6 read from the store" in capsys.readouterr().out
    )  # read back
    # A rerun without figures removes the older run's figure (it would not match the new tables).
    assert main([*args, "--trials", "3", "--no-figures"]) == 0
    assert not (tmp_path / "success.png").exists() and not (tmp_path / "success.pdf").exists()
    assert main([*args[:4], "ref", *args[5:]]) == 2
    assert "acts in task 'action_selection', not 'toy_reach'" in capsys.readouterr().err


def test_socialzoo_replay_writes_a_page_of_a_case_with_the_tasks_own_legend(tmp_path):
    import json
    import re

    from socialzoo.cli import main

    page = tmp_path / "toy.html"
    assert (
        main(["replay", "--env", TOY_ID, "--policy", "toy_heading", "--case", "2", "--out", str(page)]) == 0
    )

    def data(path):
        found = re.search(r'id="replay-data"[^>]*>(.*?)</script>', path.read_text(), re.S)
        return json.loads(found[1])

    toy = data(page)
    assert toy["actions"]["names"] == ["forward", "left", "right", "stop"]
    assert "laser" not in toy["legend"] and "followed / passed" not in toy["legend"]
    velocity = tmp_path / "crowd.html"
    assert main(["replay", "--env", "socialzoo/CrowdNav-v1", "--policy", "orca", "--out", str(velocity)]) == 0
    assert data(velocity)["actions"]["names"] == []  # a velocity task: no sub-policy legend
    # Nor a carrot: without a navigator the recorder keeps the goal there (the legend said "carrot").
    assert "carrot" not in data(velocity)["legend"] and "goal" in data(velocity)["legend"]


def test_socialzoo_demo_animates_a_case_of_any_task_id(tmp_path, capsys):
    """`socialzoo demo` animated only the action-selection task (its episode loop built an
    ActionSelectionTask): a velocity policy on the CrowdNav task, or the toy task's own policy,
    had no animation. It now plays a fixed case of any registered id (--env, --case, --split), with
    the task's own renderer, one frame per step of the CrowdNav task's 0.25 s."""
    import imageio.v3 as iio

    from socialzoo.cli import main

    toy = tmp_path / "toy.gif"
    argv = ["demo", "--env", TOY_ID, "--policy", "toy_heading", "--case", "2", "--stride", "1"]
    assert main([*argv, "--out", str(toy)]) == 0
    said = capsys.readouterr().out
    steps = int(said.rsplit("(", 1)[1].split()[0])
    assert said.startswith(f"{toy}: {steps + 1} frames; ") and 0 < steps <= 120
    assert len(iio.imread(toy, index=None)) == steps + 1
    crowd = tmp_path / "crowd.gif"
    assert (
        main(
            ["demo", "--env", "socialzoo/CrowdNav-v1", "--policy", "orca", "--case", "3", "--out", str(crowd)]
        )
        == 0
    )
    said = capsys.readouterr().out
    steps = int(said.rsplit("(", 1)[1].split()[0])
    frames = iio.imread(crowd, index=None)
    assert len(frames) == steps + 1 and np.ptp(frames) > 0  # every 0.25 s step, and the first state
    # The same case in the viewer ends the same way.
    page = tmp_path / "crowd.html"
    assert (
        main(
            [
                "replay",
                "--env",
                "socialzoo/CrowdNav-v1",
                "--policy",
                "orca",
                "--case",
                "3",
                "--out",
                str(page),
            ]
        )
        == 0
    )
    assert f"({steps} steps)" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "error"),
    [
        (["--env", TOY_ID], f"name the policy to play on {TOY_ID} (--policy)"),
        (
            ["--env", TOY_ID, "--policy", "ref"],
            "policy 'ref' acts in task 'action_selection', not 'toy_reach'",
        ),
        (
            ["--env", TOY_ID, "--policy", "toy_heading", "--map", "gdc1"],
            "--map cannot be combined with --env",
        ),
        (["--policy", "ref", "--case", "1"], "--case cannot be used without --env"),
        (["--env", TOY_ID, "--policy", "toy_heading", "--split", "nosuch"], "nosuch"),
    ],
)
def test_socialzoo_demo_refuses_a_policy_or_options_that_do_not_fit_the_task(tmp_path, capsys, argv, error):
    from socialzoo.cli import main

    out = tmp_path / "x.gif"
    assert main(["demo", *argv, "--out", str(out)]) == 2
    assert error in capsys.readouterr().err and not out.exists()


def test_a_multidiscrete_action_passes_every_adapter_and_checker():
    from gymnasium.utils.env_checker import check_env
    from pettingzoo.test import parallel_api_test
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    from socialzoo.env.parallel import TaskParallelEnv
    from socialzoo.env.vector import TaskVectorEnv

    pair = "toy_task:ToyPairTask"
    register_task("socialzoo-test/ToyPair-v0", pair, max_steps=40)
    check_env(gym.make("socialzoo-test/ToyPair-v0").unwrapped, skip_render_check=True)
    sb3_check_env(gym.make("socialzoo-test/ToyPair-v0").unwrapped)
    vec = TaskVectorEnv(3, task=pair, max_steps=15)
    vec.reset(seed=0)
    vec.action_space.seed(0)
    for _ in range(40):
        vec.step(vec.action_space.sample())
    with pytest.raises(ValueError, match=r"action 3 at \(1, 1\) is not in 0..2"):
        vec.step(np.array([[0, 0], [0, 3], [0, 0]]))
    parallel_api_test(TaskParallelEnv(task=pair, num_robots=2, max_steps=40), num_cycles=60)


def test_torchrl_specs_keep_each_entry_of_a_box_action_s_bounds_and_multidiscrete_choices():
    pytest.importorskip("torchrl")
    from torchrl.envs.utils import check_env_specs

    from socialzoo.env.torchrl_env import SocialNavTorchEnv
    from socialzoo.env.torchrl_single import TaskTorchEnv

    velocity = "toy_task:ToyVelocityTask"
    env = TaskTorchEnv(3, task=velocity, max_steps=20)
    np.testing.assert_array_equal(env.action_spec.space.low[0].numpy(), [0.0, -1.0])  # v never negative
    check_env_specs(env, seed=0)
    check_env_specs(SocialNavTorchEnv(task=velocity, batch_size=2, num_robots=2, max_steps=20), seed=0)
    check_env_specs(TaskTorchEnv(3, task="toy_task:ToyPairTask", max_steps=20), seed=0)
    check_env_specs(
        SocialNavTorchEnv(task="toy_task:ToyPairTask", batch_size=2, num_robots=2, max_steps=20), seed=0
    )


def test_an_evaluation_plays_the_registered_id_s_config_not_the_task_s_defaults():
    from socialzoo.bench.task_benchmark import TaskId

    class Stop:
        def act(self, obs, task=None):
            return np.full(len(obs), 3)

    register_task("socialzoo-test/ToyReachShort-v0", TOY, max_steps=12)
    task = TaskId.of("socialzoo-test/ToyReachShort-v0")
    assert task.make(1).config.max_steps == 12
    # The runner rebuilds the task from the id's resolved config: the toy's own max_steps=300
    # must not override it.
    from socialzoo.bench.episodes import play_cases

    episodes = play_cases(task.task, Stop().act, "test", [0, 1], config=task.make(1).config)
    assert [e["steps"] for e in episodes] == [12, 12]


def test_the_evaluation_plays_a_task_with_a_dict_observation():
    from gymnasium.utils.env_checker import check_env
    from toy_task import ToyHeadForGoal

    from socialzoo.bench.episodes import play_cases

    check_env(TaskEnv(task="toy_task:ToyDictTask"), skip_render_check=True)
    heading = ToyHeadForGoal()
    episodes = play_cases("toy_task:ToyDictTask", lambda obs, task: heading.act(obs["goal"]), "test", [0, 1])
    assert [e["case"] for e in episodes] == [0, 1] and all(e["steps"] > 0 for e in episodes)


def test_the_command_line_reaches_an_id_that_a_module_of_one_s_own_registers(tmp_path, monkeypatch, capsys):
    from socialzoo.cli import main

    (tmp_path / "my_tasks.py").write_text(
        "from socialzoo.env.registration import register_task\n"
        f"register_task('mine/ToyReach-v0', {TOY!r}, max_steps=30)\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    out = tmp_path / "bench"
    args = ["--policies", "toy_heading", "--trials", "2", "--no-figures", "--out", str(out)]
    assert main(["benchmark", "--maps", "my_tasks:mine/ToyReach-v0", *args]) == 0
    assert "| toy_heading |" in (out / "toy_reach.md").read_text()
    page = tmp_path / "mine.html"
    assert (
        main(["replay", "--env", "my_tasks:mine/ToyReach-v0", "--policy", "toy_heading", "--out", str(page)])
        == 0
    )
    capsys.readouterr()
    # Its stored trials name the command that plays them with the module, as the id was given.
    assert main(["replay", "--results", str(out), "--trial", "0", "--out", str(page)]) == 2
    assert "socialzoo replay --env my_tasks:mine/ToyReach-v0 --split test" in capsys.readouterr().err
    assert main(["benchmark", "--maps", "no_such_module:mine/ToyReach-v0", *args]) == 2
    assert "cannot import 'no_such_module'" in capsys.readouterr().err


def test_torchrl_reports_no_success_for_a_task_whose_metrics_have_none():
    pytest.importorskip("torchrl")
    import torch
    from toy_task import ToyReachTask

    from socialzoo.env.torchrl_single import TaskTorchEnv

    class NoSuccess(ToyReachTask):
        def episode_metrics(self, rows, robot=0):
            return [{"steps": m["steps"]} for m in super().episode_metrics(rows, robot)]

    env = TaskTorchEnv(2, task=NoSuccess, max_steps=5)
    td = env.rollout(6, break_when_any_done=False)  # every episode ends on step 5
    assert td["next", "done"].any() and not td["next", "success"].any()
    assert td["next", "success"].dtype == torch.bool


def test_the_viewer_shows_a_metric_that_a_module_of_one_s_own_registers(tmp_path, monkeypatch):
    """docs/architecture.md's metric of a task written outside the package: register_metric said the
    viewer reads it, but the viewer's table listed only VIEWER_METRICS, a tuple bound as a default."""
    from socialzoo.cli import main
    from socialzoo.core import metrics

    (tmp_path / "my_metric_task.py").write_text(
        "from toy_task import ToyReachTask\n"
        "from socialzoo.core.metrics import register_metric\n"
        "from socialzoo.env.registration import register_task\n"
        "class Twice(ToyReachTask):\n"
        "    name = 'toy_twice'\n"
        "    def episode_metrics(self, rows, robot=0):\n"
        "        return [{**m, 'twice_steps_own': 2 * m['steps']} for m in super().episode_metrics(rows, robot)]\n"
        "register_metric(name='twice_steps_own', label='twice the steps', unit='', better='neither',\n"
        "                kind='int', description='Twice the steps.', sources=('toy_twice',))\n"
        "register_task('mine/ToyTwice-v0', 'my_metric_task:Twice', max_steps=20)\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    if "toy_twice_heading" not in POLICIES:
        register_policy("toy_twice_heading", "toy_task:ToyHeadForGoal", task="toy_twice")
    page = tmp_path / "twice.html"
    try:
        argv = ["replay", "--env", "my_metric_task:mine/ToyTwice-v0", "--policy", "toy_twice_heading"]
        assert main([*argv, "--out", str(page)]) == 0
        assert metrics.added_names() == ("twice_steps_own",)
    finally:
        metrics.METRICS.pop("twice_steps_own", None)
        metrics._TASK_SOURCES.discard("toy_twice")
    text = page.read_text()
    assert '["twice_steps_own","twice the steps",' in text.replace(", ", ",")
    assert '"twice_steps_own":40' in text.replace(" ", "")


def test_registering_an_id_again_with_other_kwargs_is_refused():
    """register_task of an id already registered with other kwargs kept the first ones silently
    (gym.make then played max_steps=120 where 30 was asked); the same registration again stays a
    no-op, another one is refused naming the id and both kwargs."""
    register_task(TOY_ID, TOY, max_steps=120)  # the module's own registration, again: nothing changes
    with pytest.raises(
        ValueError,
        match=r"socialzoo-test/ToyReach-v0 is already registered with .*'max_steps': 120.*'max_steps': 30",
    ):
        register_task(TOY_ID, TOY, max_steps=30)
    assert gym.spec(TOY_ID).kwargs["max_steps"] == 120
