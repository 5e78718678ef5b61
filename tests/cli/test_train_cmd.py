"""`socialzoo train`: inputs the trainer finds bad are usage errors (exit status 2) naming them."""

import json

import numpy as np
import pytest

from socialzoo.agents.demonstrations import DEMO_FORMAT
from socialzoo.cli import main
from socialzoo.train.ppo import PPOArgs
from socialzoo.train.run_dir import RunDir


def test_an_unknown_map_is_a_usage_error(tmp_path, capsys):
    argv = ["train", "ppo", "--out", str(tmp_path / "run"), "--map", "nomap", "--no-progress"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("socialzoo train ppo: error: ") and "unknown map 'nomap'" in err


def test_a_missing_demonstration_file_is_a_usage_error(tmp_path, capsys):
    demos = tmp_path / "none.npz"
    assert main(["train", "bc", "--out", str(tmp_path / "run"), "--demos", str(demos), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("socialzoo train bc: error: ") and str(demos) in err


def _demos(path, policy="ref", layout="paper"):
    """A demonstration file of 6 steps in 2 episodes (zeros), recorded by `policy`."""
    n = 6
    meta = {
        "format": DEMO_FORMAT,
        "config": {"policy": policy},
        "env_config": {"observation": {"layout": layout}},
    }
    np.savez_compressed(
        path, obs=np.zeros((n, 107), np.float32), action=np.arange(n, dtype=np.int64) % 4,
        next_obs=np.zeros((n, 107), np.float32), reward=np.zeros(n, np.float32),
        terminated=np.zeros(n, bool), truncated=np.zeros(n, bool),
        episode=np.repeat(np.arange(2, dtype=np.int64), 3), episode_ids=np.arange(2, dtype=np.int64),
        episode_seeds=np.arange(2, dtype=np.uint64), episode_lengths=np.full(2, 3, np.int64),
        metadata=np.array(json.dumps(meta)),
    )  # fmt: skip
    return path


@pytest.mark.parametrize(
    ("trainer", "policy", "layout", "extra", "message"),
    [
        ("bc", "ref", "paper", ["--no-progress"], "holds 6 demonstration steps, 155400 asked"),
        ("dagger", "goalone", "paper", ["--steps", "6", "--no-progress"], "DAgger's expert is Ref"),
        ("pips", "ref", "crowdnav", [], "PIPS reads the paper observation layout"),
    ],
)
def test_demonstrations_a_trainer_cannot_learn_from_are_a_usage_error(
    tmp_path, capsys, trainer, policy, layout, extra, message
):
    # Found following docs/imitation.md with a short recording (`socialzoo demos --episodes 2`, then
    # `socialzoo train dagger --demos FILE`): a ValueError traceback, exit status 1.
    demos = _demos(tmp_path / "d.npz", policy, layout)
    out = tmp_path / ("pips.json" if trainer == "pips" else "run")
    assert main(["train", trainer, "--demos", str(demos), "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"socialzoo train {trainer}: error: ") and message in err
    assert not out.exists()


def test_a_folder_holding_a_run_of_other_arguments_is_a_usage_error(tmp_path, capsys):
    # Found rerunning `socialzoo train ppo` into a finished run's folder with another --total-steps:
    # a RunDirError traceback, exit status 1.
    out = tmp_path / "run"
    RunDir(out, "ppo", PPOArgs(out=out, total_steps=4000))
    before = (out / "run.json").read_text()
    assert main(["train", "ppo", "--out", str(out), "--total-steps", "2000", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("socialzoo train ppo: error: ") and "total_steps differ" in err
    assert (out / "run.json").read_text() == before


@pytest.mark.parametrize("steps", ["0", "x"])
def test_bad_numbers_are_usage_errors(tmp_path, steps):
    with pytest.raises(SystemExit) as exit_:
        code = main(["train", "ppo", "--out", str(tmp_path), "--total-steps", steps])
        raise SystemExit(code)
    assert exit_.value.code == 2


SB3_TRAINERS = ["crowdnav", "dqn", "ppo"]
TORCH_TRAINERS = ["bc", "cotrain", "dagger", "gail", "humans", "people-bc"]


@pytest.mark.parametrize(
    ("trainer", "seed", "high"),
    [(t, "4294967296", 2**32 - 1) for t in SB3_TRAINERS]
    + [(t, "18446744073709551616", 2**64 - 1) for t in TORCH_TRAINERS]
    + [("people-bc", "-1", 2**64 - 1)],
)
def test_a_seed_out_of_range_is_a_usage_error(tmp_path, capsys, trainer, seed, high):
    # `socialzoo train ppo --seed 4294967296` trained until SB3 seeded numpy's legacy generator
    # ("Seed must be between 0 and 2**32 - 1"), --seed 2**64 until torch.manual_seed ("Overflow when
    # unpacking long long"): tracebacks, exit status 1. people-bc did not check its seed at all:
    # --seed -1 was numpy's "expected non-negative integer".
    assert main(["train", trainer, "--seed", seed, "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"socialzoo train {trainer}: error: ") and "Traceback" not in err
    assert f"seed must be an int in [0, {high}], got {seed}" in err
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("trainer", ["bc", "gail", "dagger", "pips"])
def test_more_demonstration_steps_than_recorded_is_a_usage_error(small_demos, tmp_path, trainer, capsys):
    # Found running `socialzoo train bc --steps 2000` on a 1,600-step recording: a ValueError
    # traceback, exit status 1 (PIPS used the 1,600 steps and said nothing).
    out = tmp_path / ("run/pips.json" if trainer == "pips" else "run")
    argv = ["train", trainer, "--demos", str(small_demos), "--steps", "10000000", "--out", str(out)]
    assert main([*argv, *([] if trainer == "pips" else ["--no-progress"])]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"socialzoo train {trainer}: error: ")
    assert f"{small_demos} holds " in err and "10000000 asked" in err
    assert not (tmp_path / "run").exists()


def test_each_trainer_is_listed_with_a_whole_sentence():
    # `socialzoo train --help` listed dagger as "DAgger with Ref as the expert, on BC's fit
    # (socialzoo.train.bc.Args: every round fits with" and pips as "Arguments of `socialzoo train
    # pips`. The defaults are the paper's set-up: the first 3,500": the first line of a summary
    # that ran on.
    from socialzoo.train import TRAINERS, trainer_args

    for name in TRAINERS:
        doc = (trainer_args(name).__doc__ or "").strip().splitlines()
        assert doc and doc[0].endswith(".") and (len(doc) == 1 or not doc[1].strip()), name


def test_a_family_that_does_not_fit_the_map_is_a_usage_error(tmp_path, capsys):
    # Found running `socialzoo train ppo --family frontal_approach --map gdc1`: the first reset,
    # inside the run, raised "gdc1.json: no corridor ..." (a traceback, exit status 1) and left
    # run.json and tensorboard/ behind.
    out = tmp_path / "run"
    argv = [
        "train",
        "ppo",
        "--family",
        "frontal_approach",
        "--map",
        "gdc1",
        "--out",
        str(out),
        "--no-progress",
    ]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("socialzoo train ppo: error: ")
    assert "family 'frontal_approach' does not fit map 'gdc1'" in err and "no corridor" in err
    assert not out.exists()


def test_every_trainer_that_shows_progress_can_be_silenced(tmp_path):
    # `socialzoo train ppo-finetune` drew a progress display (440,000 steps by default) that no
    # option turned off: `--no-progress`, which every other trainer with one takes, was refused.
    from socialzoo.cli import build_parser
    from socialzoo.cli.dataclass_args import dataclass_from_namespace
    from socialzoo.train import TRAINERS

    for name in sorted(set(TRAINERS) - {"pips"}):  # PIPS shows no progress display: it logs its stages
        argv = ["train", name, "--out", str(tmp_path / name), "--no-progress"]
        args = build_parser(argv).parse_args(argv + (["--init", "dagger"] if name == "ppo-finetune" else []))
        assert dataclass_from_namespace(args.trainer_class, args).progress is False, name
