"""Checkpoint selection on validation scenarios: every checkpoint compared, the rule, the files,
refusals of test sets and of folders without checkpoints."""

import json

import numpy as np
import pytest

from socialzoo.cli import main as socialzoo_main
from socialzoo.scenarios.generator import ScenarioConfig
from socialzoo.scenarios.scenario_sets import TestSet
from socialzoo.studies.human_select import miss_score, run_checkpoints, select_humans


def fake_run(tmp_path, write_walker, speeds):
    """A run folder with one walker checkpoint per speed (tanh(speed) of the preferred speed)."""
    run = tmp_path / "run"
    (run / "checkpoints").mkdir(parents=True)
    (run / "run.json").write_text(json.dumps({"args": {"map": "open_room"}}))
    for i, speed in enumerate(speeds):
        write_walker(run / "checkpoints" / f"step_{1000 * i:09d}.humans.safetensors", speed=speed)
    return run


def test_miss_score_is_zero_when_the_targets_are_met_and_grows_with_the_miss():
    social = {
        "humans_goal_rate_mean": 0.5,
        **{
            f"{k}_mean": 1.0 for k in ("humans_hh_collisions", "humans_hw_collisions", "humans_hr_collisions")
        },
    }
    same = dict(social)
    assert miss_score(same, social) == 0.0
    walls = {**social, "humans_hw_collisions_mean": 1.5}
    assert miss_score(walls, social) == pytest.approx(0.5)
    slow = {**social, "humans_goal_rate_mean": 0.3}  # 0.45 needed
    assert miss_score(slow, social) == pytest.approx(0.15 / 0.45)


def test_select_humans_compares_every_checkpoint_and_keeps_one(rooms_map_path, write_walker, tmp_path):
    # A walker at 0.1 of its preferred speed hardly reaches a goal; one at tanh(3) = 0.995 walks like
    # a social-force human: the selection must not choose the first.
    run = fake_run(tmp_path, write_walker, [0.1, 3.0])
    val = TestSet(str(rooms_map_path), 11, 20, ScenarioConfig(min_humans=3, max_humans=5), name="rooms-val")
    result = select_humans(
        run, trials=3, workers=1, batch_size=3, test_set=val, env_overrides={"max_steps": 400}, progress=False
    )
    assert [r["frames"] for r in result.rows] == [0, 1000, None]
    assert (
        result.frames == 1000 and result.chosen == run / "checkpoints" / "step_000001000.humans.safetensors"
    )
    slow, fast, social = result.rows
    assert slow["reach_rate"] < fast["reach_rate"] and slow["mean_speed"] < fast["mean_speed"]
    assert result.met == fast["met"] and social["file"] == "social_force"
    out = run / "selection"
    assert (out / "humans.safetensors").read_bytes() == result.chosen.read_bytes()
    record = json.loads((out / "selection.json").read_text(), parse_constant=pytest.fail)
    assert record["chosen"]["frames"] == 1000 and record["scenarios"] == "rooms-val"
    # The files it names are the run's, from the selection's folder: no absolute path of this machine
    # (the shipped selection named /work/runs/...).
    assert (
        record["run"] == ".."
        and record["chosen"]["file"] == "../checkpoints/step_000001000.humans.safetensors"
    )
    assert (out / record["chosen"]["file"]).read_bytes() == result.chosen.read_bytes()
    assert str(tmp_path) not in (out / "selection.json").read_text() + (out / "selection.csv").read_text()
    assert (out / record["map"]).resolve() == rooms_map_path.resolve()  # a map file, from there too
    assert len(record["checkpoints"]) == 2 and "(chosen)" in (out / "selection.md").read_text()
    assert (out / "selection.csv").read_text().count("\n") == 4
    # A rerun reads every trial back and chooses the same.
    again = select_humans(
        run, trials=3, workers=1, batch_size=3, test_set=val, env_overrides={"max_steps": 400}, progress=False
    )
    assert again.chosen == result.chosen and str(again.rows) == str(result.rows)


def test_test_sets_and_empty_runs_are_refused(rooms_map_path, write_walker, tmp_path, capsys):
    run = fake_run(tmp_path, write_walker, [3.0])
    quick = TestSet(str(rooms_map_path), 11, 20, name="rooms-quick")
    with pytest.raises(ValueError, match="use validation scenarios, not 'rooms-quick'"):
        select_humans(run, test_set=quick, progress=False)
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(FileNotFoundError, match="no learned-human checkpoints"):
        run_checkpoints(empty)
    assert socialzoo_main(["humans", "select", "--run", str(empty)]) == 2
    assert "no learned-human checkpoints" in capsys.readouterr().err


def test_a_run_trained_on_a_family_is_chosen_on_the_familys_validation_cases(write_walker, tmp_path):
    # A humans run of env_overrides {"family": ...} was compared on "<map>-val", the benchmark's scenarios.
    from socialzoo.env.config import EnvConfig
    from socialzoo.env.tasks.action_selection import ActionSelectionTask

    run = tmp_path / "run"
    write_walker(run / "checkpoints" / "step_000001000.humans.safetensors", speed=3.0)
    args = {"map": "hallway", "env_overrides": {"family": "frontal_approach", "max_steps": 100}}
    (run / "run.json").write_text(json.dumps({"algo": "humans", "args": args}))
    result = select_humans(
        run, trials=2, workers=1, batch_size=2, env_overrides={"max_steps": 100}, progress=False
    )
    record = json.loads((result.out_dir / "selection.json").read_text())
    assert record["scenarios"] == "frontal_approach-val" and record["family"] == "frontal_approach"
    for population in ("social_force", "learned"):
        played = json.loads((result.out_dir / "runs" / population / "config.json").read_text())
        (cases,) = played["test_sets"].values()
        assert played["benchmark"]["env_overrides"]["family"] == "frontal_approach"
        # The cases the action-selection task plays as its "val" split with the family.
        task = ActionSelectionTask(EnvConfig(map="hallway", family="frontal_approach"), 2)
        assert cases["seeds"] == task.reset(np.arange(2), {"split": "val", "cases": [0, 1]}).tolist()
