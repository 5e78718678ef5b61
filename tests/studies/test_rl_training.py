"""Experiment 1's training part: one run folder per algorithm, finished runs not repeated."""

import json

import pytest

from socialzoo.studies.rl_training import train_curve_runs

TINY = {"map": "open_room", "family": "circle_crossing", "max_steps": 100, "total_steps": 200}


def test_one_run_per_algorithm_with_checkpoints(tmp_path):
    runs = train_curve_runs(
        tmp_path, algos=("ppo",), seed=2, progress=False, checkpoint_every=100, num_envs=4, n_steps=25, **TINY
    )
    assert runs == {"ppo": tmp_path / "ppo"}
    record = json.loads((tmp_path / "ppo" / "run.json").read_text())
    assert record["seed"] == 2 and record["results"]["checkpoints"] == [
        "checkpoints/step_000000100.safetensors",
        "checkpoints/step_000000200.safetensors",
    ]
    stamp = (tmp_path / "ppo" / "ppo.safetensors").stat().st_mtime_ns
    train_curve_runs(
        tmp_path, algos=("ppo",), seed=2, progress=False, checkpoint_every=100, num_envs=4, n_steps=25, **TINY
    )
    assert (tmp_path / "ppo" / "ppo.safetensors").stat().st_mtime_ns == stamp


def test_steps_to_reference_trains_evaluates_and_writes_the_answer(tmp_path, rooms_map_path):
    from socialzoo.scenarios.generator import ScenarioConfig
    from socialzoo.scenarios.scenario_sets import TestSet
    from socialzoo.studies.rl_training import steps_to_reference

    validation = TestSet(
        str(rooms_map_path), 7, 3, ScenarioConfig(min_humans=1, max_humans=2), name="rooms-val"
    )
    kwargs = {
        "total_steps": 200,
        "checkpoint_every": 100,
        "trials": 2,
        "reference": "goalone",
        "workers": 1,
        "progress": False,
        "validation": validation,
        "env_overrides": {"max_steps": 100},
        "num_envs": 4,
        "n_steps": 25,
        **{k: v for k, v in TINY.items() if k != "total_steps"},
    }
    record = steps_to_reference(tmp_path, **kwargs)
    assert [r["step"] for r in record["checkpoints"]] == [100, 200]
    assert record["reference"]["label"] == "goalone" and record["validation_set"] == "rooms-val"
    rates = [r["success_rate"] for r in record["checkpoints"]]
    ref = record["reference"]["success_rate"]
    expected = next((r["step"] for r in record["checkpoints"] if r["success_rate"] >= ref), None)
    assert record["steps"] == expected and all(0.0 <= x <= 1.0 for x in rates)
    saved = json.loads((tmp_path / "steps_to_ref.json").read_text(), parse_constant=pytest.fail)
    assert saved["steps"] == record["steps"] and saved["total_steps"] == 200
    assert {"steps_to_ref.csv", "steps_to_ref.png", "steps_to_ref.pdf"} <= {
        p.name for p in tmp_path.iterdir()
    }
    # Run again: the finished training is reused, not repeated.
    stamp = (tmp_path / "ppo_long" / "ppo.safetensors").stat().st_mtime_ns
    steps_to_reference(tmp_path, **{**kwargs, "figure": False})
    assert (tmp_path / "ppo_long" / "ppo.safetensors").stat().st_mtime_ns == stamp
