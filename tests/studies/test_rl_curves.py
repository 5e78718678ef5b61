"""Experiment 1's evaluation: every checkpoint of a run on the same scenarios, stored as trials
finish, resumed and read back, written as a CSV and a figure; the validation helper refuses test sets."""

import csv
import itertools

import numpy as np
import pytest

import socialzoo.studies.rl_curves as rl
from socialzoo.agents.mlp import MlpPolicy
from socialzoo.bench.store import ResultsStore
from socialzoo.env.policy_file import current_env_version
from socialzoo.scenarios.generator import ScenarioConfig
from socialzoo.scenarios.scenario_sets import TestSet

FAST = {"max_steps": 150}


@pytest.fixture(scope="module")
def scenarios(rooms_map_path):
    return TestSet(str(rooms_map_path), 5, 6, ScenarioConfig(min_humans=2, max_humans=4), name="rooms-val")


def _fake_run(folder, steps, prefer):
    """A run folder whose checkpoint at each step prefers one action (a one-layer net)."""
    for step, action in zip(steps, prefer, strict=True):
        bias = np.full(4, -5.0)
        bias[action] = 5.0
        policy = MlpPolicy(
            "ppo", [(np.zeros((4, 107)), bias)], "tanh", {"layout": "paper", "num_human_slots": 25}
        )
        header = {
            "env_id": f"socialzoo/ActionSelection-v{current_env_version()}",
            "training": {"steps": step},
        }
        policy.save(folder / "checkpoints" / f"step_{step:09d}.safetensors", header)
    return folder


def test_curves_per_checkpoint_with_bands_csv_and_figure(tmp_path, scenarios):
    run = _fake_run(tmp_path / "run", [2000, 4000], prefer=[1, 0])  # Halt, then GoAlone
    result = rl.rl_curves(
        {"ppo": run},
        tmp_path / "out",
        test_set=scenarios,
        trials=4,
        references=("goalone",),
        workers=1,
        progress=False,
        env_overrides=FAST,
    )
    assert [(r["label"], r["step"], r["trials"]) for r in result.rows] == [("ppo", 2000, 4), ("ppo", 4000, 4)]
    halt, go = result.rows
    assert halt["success_rate"] == 0.0 and go["success_rate"] == result.references[0]["success_rate"] > 0
    assert go["success_ci_low"] <= go["success_rate"] <= go["success_ci_high"]
    assert result.references[0]["label"] == "goalone"
    names = {p.name for p in result.files}
    assert {"curves.sqlite", "rl_curves.csv", "rl_curves.png", "rl_curves.pdf"} <= names
    with (tmp_path / "out" / "rl_curves.csv").open() as f:
        table = list(csv.DictReader(f))
    assert [row["policy"] for row in table] == ["goalone", "ppo@2000", "ppo@4000"]


def test_trials_are_stored_as_they_finish_and_never_rerun(tmp_path, scenarios, monkeypatch):
    run = _fake_run(tmp_path / "run", [2000], prefer=[0])
    asked = []
    real = rl.evaluate

    def counting(trials, *args, **kwargs):
        asked.append(len(trials))
        return real(trials, *args, **kwargs)

    monkeypatch.setattr(rl, "evaluate", counting)
    kwargs = {"references": (), "workers": 1, "progress": False, "env_overrides": FAST, "figure": False}
    rl.rl_curves({"ppo": run}, tmp_path / "out", test_set=scenarios, trials=2, **kwargs)
    with ResultsStore(tmp_path / "out" / "curves.sqlite") as store:
        assert len(store) == 2
    # A longer run reuses the stored trials; a repeated one runs nothing.
    rl.rl_curves({"ppo": run}, tmp_path / "out", test_set=scenarios, trials=3, **kwargs)
    rl.rl_curves({"ppo": run}, tmp_path / "out", test_set=scenarios, trials=3, **kwargs)
    assert asked == [2, 1, 0]
    # A changed checkpoint file is a new policy: its trials are run again.
    _fake_run(tmp_path / "run", [2000], prefer=[1])
    rl.rl_curves({"ppo": run}, tmp_path / "out", test_set=scenarios, trials=3, **kwargs)
    assert asked[-1] == 3


def test_steps_to_match_uses_validation_scenarios_only(tmp_path, scenarios):
    run = _fake_run(tmp_path / "run", [1000, 2000, 3000], prefer=[1, 3, 0])
    found = rl.steps_to_match(
        run,
        tmp_path / "out",
        reference="goalone",
        validation=scenarios,
        trials=3,
        workers=1,
        progress=False,
        env_overrides=FAST,
    )
    assert found["steps"] == 3000 and found["reference"]["label"] == "goalone"
    assert [r["step"] for r in found["checkpoints"]] == [1000, 2000, 3000]
    test_like = TestSet("gdc1", 20220001, 10, name="gdc1-test")
    with pytest.raises(ValueError, match="validation scenarios"):
        rl.steps_to_match(run, tmp_path / "out2", validation=test_like)
    assert rl.VALIDATION_SET.base_seed not in {ts.base_seed for ts in rl_test_sets()}


def rl_test_sets():
    from socialzoo.scenarios.scenario_sets import TEST_SETS

    return TEST_SETS.values()


def test_a_folder_without_checkpoints_is_refused(tmp_path):
    with pytest.raises(FileNotFoundError, match="no checkpoints"):
        rl.run_checkpoints(tmp_path)


def test_bench_does_not_import_train():
    """Layers: cli -> train -> bench; the evaluation side never reaches up into the trainers."""
    import ast
    import pathlib

    import socialzoo.bench

    for path in itertools.chain(pathlib.Path(socialzoo.bench.__file__).parent.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
            if isinstance(node, ast.ImportFrom):
                names = [node.module or ""]
            assert not any(n.startswith(("socialzoo.train", "socialzoo.cli")) for n in names), path
