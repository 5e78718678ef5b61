"""Behaviour cloning: it imitates Ref on held-out demonstrations, its file acts as the TorchRL actor
did, and its run folder holds what a run must record."""

import json
from pathlib import Path

import numpy as np
import pytest

from socialzoo.agents import make_policy
from socialzoo.agents.demonstrations import load_demonstrations
from socialzoo.agents.mlp import MlpPolicy
from socialzoo.train.bc import Args, train


def _split(path, held_out_episodes):
    """Steps of all episodes but the last `held_out_episodes`, and the held-out rest."""
    arrays, _ = load_demonstrations(path)
    steps = int(arrays["episode_lengths"][:-held_out_episodes].sum())
    return steps, arrays["obs"][steps:], arrays["action"][steps:]


def _args(small_demos, tmp_path, **changes):
    base = dict(
        demos=small_demos, steps=None, hidden=(64, 64), epochs=1, min_updates=300, batch_size=128,
        out=tmp_path / "bc", checkpoint_every=100, progress=False,
    )  # fmt: skip
    return Args(**{**base, **changes})


@pytest.fixture(scope="module")
def trained(small_demos, tmp_path_factory):
    steps, held_obs, held_act = _split(small_demos, 3)
    path = train(_args(small_demos, tmp_path_factory.mktemp("run"), steps=steps))
    return path, held_obs, held_act


def test_bc_agrees_with_ref_on_held_out_demonstrations(trained):
    path, held_obs, held_act = trained
    assert len(held_act) > 300
    agreement = (MlpPolicy.load(path).act(held_obs) == held_act).mean()
    assert agreement > 0.9, agreement
    # The registry resolves "bc:PATH" to the same policy.
    np.testing.assert_array_equal(make_policy(f"bc:{path}").act(held_obs), MlpPolicy.load(path).act(held_obs))


def test_run_folder_records_the_run(trained):
    path, _, _ = trained
    run = path.parent
    record = json.loads((run / "run.json").read_text())
    assert record["algo"] == "bc" and record["seed"] == 0 and record["finished"]
    assert record["args"]["hidden"] == [64, 64] and record["command"]
    assert record["results"]["updates"] == 300 and 0.0 < record["results"]["wall_seconds"]
    assert [p.name for p in sorted((run / "checkpoints").iterdir())] == [
        "step_000000100.safetensors", "step_000000200.safetensors", "step_000000300.safetensors"
    ]  # fmt: skip
    assert list((run / "tensorboard").glob("events.out.tfevents.*"))
    header = MlpPolicy.load(path).header
    assert header["policy"] == "bc" and header["training"]["demonstrations"]["policy"] == "ref"
    # The demonstrations as run.json names them (relative to the run folder), never the machine's
    # absolute path, which the header held.
    assert header["training"]["demonstrations"]["file"] == record["args"]["demos"]
    assert not Path(record["args"]["demos"]).is_absolute()
    assert header["env_id"].startswith("socialzoo/ActionSelection-v")


def test_a_finished_run_is_not_repeated_and_other_arguments_are_refused(small_demos, trained):
    from socialzoo.train.run_dir import RunDirError

    path, _, _ = trained
    run = path.parent
    recorded = json.loads((run / "run.json").read_text())["args"]
    assert recorded["out"] == "." and not Path(recorded["demos"]).is_absolute()
    given = {**recorded, "demos": run / recorded["demos"], "out": run}  # its paths: from the run folder
    stamp = path.stat().st_mtime_ns
    assert train(Args(**given)) == path and path.stat().st_mtime_ns == stamp
    with pytest.raises(RunDirError, match=r"seed"):
        train(Args(**{**given, "seed": 1}))


def test_a_work_folder_moved_with_its_demonstrations_is_not_trained_again(small_demos, tmp_path):
    """`socialzoo reproduce` keeps the demonstrations beside the runs; a copied work folder holds
    finished runs, since the demonstrations lie where they lay relative to the run."""
    import shutil

    work = tmp_path / "work"
    (work / "demos").mkdir(parents=True)
    shutil.copy(small_demos, work / "demos" / "ref.npz")
    first = train(_args(work / "demos" / "ref.npz", work, min_updates=100, checkpoint_every=100))
    shutil.copytree(work, tmp_path / "moved")
    moved = tmp_path / "moved"
    again = _args(moved / "demos" / "ref.npz", moved, min_updates=100, checkpoint_every=100)
    stamp = (moved / "bc" / "bc.safetensors").stat().st_mtime_ns
    assert train(again) == moved / "bc" / "bc.safetensors"
    assert (moved / "bc" / "bc.safetensors").stat().st_mtime_ns == stamp  # not trained again
    assert (moved / "bc" / "bc.safetensors").read_bytes() == first.read_bytes()


def test_asking_for_more_steps_than_recorded_names_the_file(small_demos, tmp_path):
    with pytest.raises(ValueError, match=r"ref\.npz holds \d+ demonstration steps, 10000000 asked"):
        train(_args(small_demos, tmp_path, steps=10_000_000))


def test_bad_arguments_name_the_field():
    with pytest.raises(ValueError, match=r"bc Args\.epochs must be an int >= 1"):
        Args(epochs=0)
    with pytest.raises(ValueError, match=r"bc Args\.lr"):
        Args(lr=-1.0)
    # Non-finite numbers are refused too (an infinite learning rate used to pass the bound check).
    for bad in (float("inf"), float("nan")):
        with pytest.raises(ValueError, match=r"bc Args\.lr must be a finite number"):
            Args(lr=bad)
    # More checkpoint evaluations than the map has validation scenarios (1,000) ended the run in a
    # traceback at its first checkpoint, after training up to it.
    with pytest.raises(
        ValueError, match=r"bc Args\.eval_trials \(1001\) is more than the 1000 validation cases"
    ):
        Args(eval_trials=1001)
