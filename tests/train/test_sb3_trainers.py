"""`socialzoo train ppo|dqn`: they learn on an easy scenario family, write a complete run folder,
and refuse bad arguments naming the field."""

import json

import numpy as np
import pytest

from socialzoo.agents import make_policy
from socialzoo.cli import main
from socialzoo.env.policy_file import read_policy_file
from socialzoo.env.sb3_vec import SB3VecEnv
from socialzoo.train import TRAINERS, trainer_args, trainer_function
from socialzoo.train.dqn import DQNArgs
from socialzoo.train.ppo import PPOArgs

# The robot and 4-8 people cross an open room; GoAlone reaches the goal in about 210 steps.
ROOM = {"map": "open_room", "family": "circle_crossing", "max_steps": 400}


def first_episodes(act, rows=24, seed=123):
    """(success rate, mean return) of the first episode of each row, on seeds never trained on."""
    venv = SB3VecEnv(rows, **ROOM)
    venv.seed(seed)
    obs = venv.reset()
    done = np.zeros(rows, dtype=bool)
    success = np.zeros(rows)
    returns = np.zeros(rows)
    while not done.all():
        obs, rewards, dones, infos = venv.step(act(obs))
        returns[~done] += rewards[~done]
        for row in np.flatnonzero(dones & ~done):
            success[row] = infos[row]["metrics"]["success"]
        done |= dones
    return success.mean(), returns.mean()


@pytest.fixture(scope="module")
def random_baseline():
    rng = np.random.default_rng(0)
    return first_episodes(lambda obs: rng.integers(0, 4, len(obs)))


@pytest.mark.parametrize(
    ("algo", "args"),
    [
        ("ppo", {"num_envs": 20, "n_steps": 50, "total_steps": 3000, "checkpoint_every": 1000}),
        (
            "dqn",
            {
                "num_envs": 4,
                "train_freq": 1,
                "scenario_repeats": 1,
                "learning_starts": 500,
                "target_update_interval": 500,
                "exploration_fraction": 0.3,
                "learning_rate": 1e-3,
                "normalize": True,
            },
        ),
    ],
)
def test_learns_over_random_within_a_few_thousand_steps(tmp_path, random_baseline, algo, args):
    cls = trainer_args(algo)
    room = {"map": ROOM["map"], "family": ROOM["family"], "max_steps": ROOM["max_steps"]}
    path = trainer_function(algo)(
        cls(
            **{
                "out": tmp_path,
                "total_steps": 4000,
                "checkpoint_every": 2000,
                "progress": False,
                **room,
                **args,
            }
        )
    )
    policy = make_policy(f"{algo}:{path}")
    success, returns = first_episodes(policy.act)
    random_success, random_returns = random_baseline
    # What the learners maximise is the return; success follows (less for PPO, which also learns
    # to Pass people for the faster progress: the reward has no collision penalty).
    assert returns > random_returns + 40, (returns, random_returns)
    assert success >= random_success + 0.3, (success, random_success)


def test_run_folder_from_the_command_line(tmp_path, monkeypatch, capsys):
    out = tmp_path / "run"
    argv = ["train", "ppo", "--out", str(out), "--total-steps", "400", "--checkpoint-every", "200"]
    argv += ["--num-envs", "8", "--n-steps", "25", "--map", "open_room", "--family", "circle_crossing"]
    argv += ["--max-steps", "100", "--seed", "3", "--no-progress"]
    monkeypatch.setattr("sys.argv", ["/usr/bin/socialzoo", *argv])  # as the console script sees it
    assert main(argv) == 0
    record = json.loads((out / "run.json").read_text())
    assert record["algo"] == "ppo" and record["seed"] == 3 and record["finished"]
    # Paths as the run folder sees them.
    assert record["command"] == "socialzoo " + " ".join(argv).replace(str(out), ".")
    assert record["args"]["out"] == "."
    assert record["args"]["total_steps"] == 400 and record["results"]["env_steps"] == 400
    checkpoints = sorted(p.name for p in (out / "checkpoints").iterdir())
    assert checkpoints == ["step_000000200.safetensors", "step_000000400.safetensors"]
    assert (out / "ppo.safetensors").read_bytes() == (out / "checkpoints" / checkpoints[-1]).read_bytes()
    assert list((out / "tensorboard").glob("events.out.tfevents.*"))
    _, header = read_policy_file(out / "ppo.safetensors")
    assert header["training"]["seed"] == 3 and header["training"]["steps"] == 400
    assert header["normalization"] is not None and header["env_id"] == "socialzoo/CircleCrossing-v2"
    _, first = read_policy_file(out / "checkpoints" / checkpoints[0])
    assert first["training"]["steps"] == 200
    # A finished run of the same arguments is not repeated; other arguments are refused.
    before = (out / "ppo.safetensors").stat().st_mtime_ns
    assert main([*argv[:-1], "--progress"]) == 0
    assert (out / "ppo.safetensors").stat().st_mtime_ns == before
    capsys.readouterr()
    assert main([*argv[:-3], "--seed", "4", "--no-progress"]) == 2
    assert "seed differ" in capsys.readouterr().err


def strings(value):
    """Every string inside plain JSON `value`."""
    if isinstance(value, dict):
        return [s for v in value.values() for s in strings(v)]
    if isinstance(value, list):
        return [s for v in value for s in strings(v)]
    return [value] if isinstance(value, str) else []


def test_the_policy_file_names_paths_as_the_run_record_does(tmp_path):
    # Found reading the header of a policy trained with --map /abs/path/hallway.json: run.json said
    # "../hallway.json", the policy file the machine's absolute path (training.env.map).
    import os
    import shutil

    from socialzoo.maps.map_file import load_map

    map_file = tmp_path / "maps" / "hall.json"
    map_file.parent.mkdir()
    shutil.copyfile(load_map("hallway").path, map_file)
    args = PPOArgs(
        out=tmp_path / "run", map=str(map_file), num_envs=4, n_steps=25, total_steps=100, checkpoint_every=100,
        max_steps=50, progress=False,
    )  # fmt: skip
    path = trainer_function("ppo")(args)
    _, header = read_policy_file(path)
    record = json.loads((tmp_path / "run" / "run.json").read_text())
    assert header["training"]["env"]["map"] == record["args"]["map"] == "../maps/hall.json"
    assert [s for s in strings(header) if os.path.isabs(s)] == []


def test_trainers_are_registered_with_the_papers_defaults():
    assert {"ppo", "dqn"} <= set(TRAINERS)
    ppo, dqn = PPOArgs(), DQNArgs()
    assert (
        ppo.total_steps == dqn.total_steps == 84_000 and ppo.checkpoint_every == dqn.checkpoint_every == 2_000
    )
    assert ppo.map == dqn.map == "gdc1"
    # A family trains on its own map unless one is named (frontal_approach's corridor is not on gdc1).
    assert PPOArgs(family="frontal_approach").map == "hallway"
    assert PPOArgs(family="frontal_approach", map="narrow_hallway").map == "narrow_hallway"
    assert ppo.scenario_repeats == 1 and dqn.scenario_repeats == 20
    assert ppo.num_envs * ppo.n_steps == 2_000 and ppo.normalize and not dqn.normalize
    assert (ppo.learning_rate, ppo.batch_size, ppo.n_epochs, ppo.gamma) == (3e-4, 64, 10, 0.99)
    assert (dqn.learning_rate, dqn.batch_size, dqn.train_freq, dqn.target_update_interval) == (
        1e-4,
        32,
        4,
        10_000,
    )


@pytest.mark.parametrize(
    ("cls", "changes", "message"),
    [
        (PPOArgs, {"total_steps": 0}, "PPOArgs.total_steps must be an int >= 1, got 0"),
        (PPOArgs, {"checkpoint_every": 2_100}, r"PPOArgs.checkpoint_every \(2100\) must be a multiple"),
        (PPOArgs, {"gamma": 1.5}, r"PPOArgs.gamma must be in \[0.0, 1.0\], got 1.5"),
        (PPOArgs, {"net_arch": ()}, "PPOArgs.net_arch"),
        (PPOArgs, {"env_overrides": {"max_stepz": 3}}, "bad training env.*max_stepz"),
        (PPOArgs, {"env_overrides": {"map": "hallway"}}, r"env_overrides sets map \('hallway'\).*\('gdc1'\)"),
        (PPOArgs, {"max_steps": 40, "env_overrides": {"max_steps": 7}}, r"sets max_steps \(7\).*\(40\)"),
        (DQNArgs, {"env_overrides": {"scenario": {"repeats": 5}}}, r"sets scenario_repeats \(5\).*\(20\)"),
        (DQNArgs, {"family": "crossing", "env_overrides": {"family": "doorway"}}, "sets family"),
        (DQNArgs, {"scenario_repeats": 0}, "DQNArgs.scenario_repeats must be an int >= 1, got 0"),
        (DQNArgs, {"exploration_final_eps": -0.1}, "DQNArgs.exploration_final_eps"),
        (DQNArgs, {"family": "nope"}, "family"),
        # A learning rate of 0 trains nothing; the other trainers refused it, these took it.
        (PPOArgs, {"learning_rate": 0.0}, r"PPOArgs.learning_rate must be in \(0.0, 1.0\], got 0.0"),
        (DQNArgs, {"learning_rate": 0.0}, r"DQNArgs.learning_rate must be in \(0.0, 1.0\], got 0.0"),
        # A minibatch larger than what it is drawn from: SB3's PPO took the whole rollout and DQN
        # drew the buffer's transitions again and again, while the record said otherwise.
        (
            PPOArgs,
            {"num_envs": 4, "n_steps": 25, "total_steps": 100, "checkpoint_every": 100, "batch_size": 101},
            r"PPOArgs.batch_size \(101\) must be at most the rollout, num_envs \* n_steps \(100\)",
        ),
        # SB3's PPO normalises each minibatch's advantages: one sample ended the run in an AssertionError.
        (PPOArgs, {"batch_size": 1}, r"PPOArgs.batch_size must be an int >= 2, got 1"),
        (
            DQNArgs,
            {"buffer_size": 10, "batch_size": 32},
            r"DQNArgs.batch_size \(32\) must be at most the replay buffer, buffer_size \(10\)",
        ),
        # No gradient step at all: the "trained" policy was the untrained network.
        (
            DQNArgs,
            {"total_steps": 2000, "learning_starts": 2000},
            r"DQNArgs.learning_starts \(2000\) must be below total_steps \(2000\)",
        ),
        # More than the map's 1,000 validation scenarios ended the run in a traceback at its first
        # checkpoint evaluation, after training up to it (a family's split was checked already).
        (
            PPOArgs,
            {"eval_trials": 1001},
            r"PPOArgs.eval_trials \(1001\) is more than the 1000 validation cases of map 'gdc1'",
        ),
    ],
)
def test_bad_arguments_name_the_field(cls, changes, message):
    with pytest.raises(ValueError, match=message):
        cls(**changes)


@pytest.mark.parametrize("family", ["frontal_approach", "hallway_head_on"])
def test_a_family_run_chooses_its_checkpoints_on_the_familys_validation_cases(monkeypatch, family):
    """With --family the checkpoints are evaluated on the family's "val" split (the action-selection
    task's, for a family with seed splits of its own and for one without), not on "<map>-val"."""
    import socialzoo.bench.runner as runner
    from socialzoo.agents import shipped_policy_file
    from socialzoo.env.config import EnvConfig
    from socialzoo.env.tasks import make_task
    from socialzoo.train import sb3_common
    from socialzoo.train.ppo import TRAINER

    made = {}
    monkeypatch.setattr(
        sb3_common, "run_training", lambda *a, evaluator=None: made.setdefault("e", evaluator)
    )
    played, families = [], []
    run_chunk = runner.run_chunk

    def spy(trials, spec):
        results = run_chunk(trials, spec)
        played.extend(r.seed for r in results)
        families.extend(config.family for config in spec.env_configs.values())
        return results

    monkeypatch.setattr(runner, "run_chunk", spy)
    args = PPOArgs(family=family, map="hallway", eval_trials=2, max_steps=40)
    sb3_common.run_sb3(TRAINER, args)
    made["e"](shipped_policy_file("ppo"))
    task = make_task("action_selection", 2, EnvConfig(map="hallway", family=family))
    expected = task.reset(np.arange(2), {"split": "val", "cases": [0, 1]}).tolist()
    assert played == expected and families == [family]  # a family without splits: the map's seeds
    with pytest.raises(ValueError, match=r"eval_trials \(101\) is more than the 100 validation cases"):
        PPOArgs(family="frontal_approach", map="hallway", eval_trials=101)


@pytest.mark.parametrize("family", [None, "frontal_approach"])
def test_checkpoints_are_evaluated_in_episodes_of_the_training_time_limit(monkeypatch, family):
    """--max-steps is the training env's time limit: the validation episodes that choose the
    checkpoint end at it too, not at the benchmark's 3200."""
    import socialzoo.bench.runner as runner
    from socialzoo.train import sb3_common
    from socialzoo.train.ppo import TRAINER

    made, limits = {}, []
    monkeypatch.setattr(
        sb3_common, "run_training", lambda *a, evaluator=None: made.setdefault("e", evaluator)
    )
    monkeypatch.setattr(
        runner,
        "run_chunk",
        lambda trials, spec: limits.extend(c.max_steps for c in spec.env_configs.values()) or [],
    )
    args = PPOArgs(family=family, eval_trials=2, max_steps=40)
    sb3_common.run_sb3(TRAINER, args)
    made["e"]("unused.safetensors")
    assert limits == [40]
