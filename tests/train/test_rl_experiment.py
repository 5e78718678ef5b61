"""Experiment 1's training part: one run folder per algorithm, finished runs not repeated."""

import json

from socialzoo.train.rl_experiment import train_curve_runs

TINY = {"map": "open_room", "family": "circle_crossing", "max_steps": 100, "total_steps": 200}


def test_one_run_per_algorithm_with_checkpoints(tmp_path):
    runs = train_curve_runs(
        tmp_path, algos=("ppo",), seed=2, progress=False, checkpoint_every=100, num_envs=4, n_steps=25, **TINY
    )
    assert runs == {"ppo": tmp_path / "ppo"}
    record = json.loads((tmp_path / "ppo" / "run.json").read_text())
    assert record["seed"] == 2 and record["results"]["checkpoints"] == [
        "step_000000100.safetensors",
        "step_000000200.safetensors",
    ]
    stamp = (tmp_path / "ppo" / "ppo.safetensors").stat().st_mtime_ns
    train_curve_runs(
        tmp_path, algos=("ppo",), seed=2, progress=False, checkpoint_every=100, num_envs=4, n_steps=25, **TINY
    )
    assert (tmp_path / "ppo" / "ppo.safetensors").stat().st_mtime_ns == stamp
