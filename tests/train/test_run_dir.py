"""A training run's folder records its arguments and refuses to mix two runs."""

import json
from dataclasses import dataclass, replace
from pathlib import Path

import pytest

from socialzoo.train.run_dir import RunDir, RunDirError, checkpoint_steps, plain


@dataclass(frozen=True, kw_only=True)
class Args:
    steps: int = 10
    seed: int = 0
    out: Path = Path("x")
    progress: bool = True


def test_run_json_records_args_command_and_seed(tmp_path):
    run = RunDir(tmp_path, "ppo", Args(seed=5))
    record = json.loads((tmp_path / "run.json").read_text())
    assert record["algo"] == "ppo" and record["seed"] == 5 and record["args"]["out"] == "x"
    assert record["command"] and record["finished"] is None and not run.finished
    run.finish(wall_seconds=1.5)
    again = RunDir(tmp_path, "ppo", Args(seed=5, progress=False), volatile=("progress",))
    assert again.finished and again.record["results"] == {"wall_seconds": 1.5}


def test_other_arguments_are_refused(tmp_path):
    RunDir(tmp_path, "ppo", Args())
    with pytest.raises(RunDirError, match="seed differ"):
        RunDir(tmp_path, "ppo", replace(Args(), seed=1))
    with pytest.raises(RunDirError, match="ppo run"):
        RunDir(tmp_path, "dqn", Args())


@dataclass(frozen=True, kw_only=True)
class LfdArgs:
    demos: Path
    out: Path
    seed: int = 0


def test_a_folder_moved_with_its_inputs_holds_the_same_run(tmp_path):
    """A work folder (run and demonstrations) moved elsewhere: the input at the same place
    relative to `out` is the same input; one that moved on its own is not."""
    old, new = tmp_path / "old", tmp_path / "new"
    RunDir(old / "lfd/bc", "bc", LfdArgs(demos=old / "demos/d.npz", out=old / "lfd/bc")).finish()
    old.rename(new)
    moved = LfdArgs(demos=new / "demos/d.npz", out=new / "lfd/bc")
    assert RunDir(new / "lfd/bc", "bc", moved, volatile=("out",), inputs=("demos",)).finished
    elsewhere = replace(moved, demos=tmp_path / "other/d.npz")
    with pytest.raises(RunDirError, match="demos differ"):
        RunDir(new / "lfd/bc", "bc", elsewhere, volatile=("out",), inputs=("demos",))
    # An argument not declared an input is compared as written, and the seed still counts.
    with pytest.raises(RunDirError, match="demos differ"):
        RunDir(new / "lfd/bc", "bc", moved, volatile=("out",))
    with pytest.raises(RunDirError, match="seed differ"):
        RunDir(new / "lfd/bc", "bc", replace(moved, seed=1), volatile=("out",), inputs=("demos",))


def test_checkpoints_are_listed_by_step(tmp_path):
    run = RunDir(tmp_path, "ppo", Args())
    for step in (4000, 2000):
        run.checkpoint_path(step, ".safetensors").write_text("")
    assert [s for s, _ in run.checkpoints(".safetensors")] == [2000, 4000]


def test_checkpoint_steps():
    assert checkpoint_steps(84000, 2000)[:2] == [2000, 4000] and len(checkpoint_steps(84000, 2000)) == 42
    assert checkpoint_steps(5000, 2000) == [2000, 4000, 5000]
    with pytest.raises(ValueError):
        checkpoint_steps(0, 2000)


def test_plain_turns_dataclasses_paths_and_tuples_into_json():
    assert plain({"a": (Path("p"), Args())}) == {
        "a": ["p", {"steps": 10, "seed": 0, "out": "x", "progress": True}]
    }
