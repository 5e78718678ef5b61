"""The PIPS study on a tiny setting: one program per (steps, window) from one recording, each cell
skipped once synthesised, evaluated on validation scenarios into a table and a figure."""

import csv
import dataclasses
import json

import pytest

from socialzoo.scenarios.scenario_sets import TestSet, get_test_set
from socialzoo.studies.pips_study import (
    CSV_COLUMNS,
    find_study_programs,
    run_pips_study,
    study_program_file,
)
from socialzoo.studies.pips_study_training import PipsStudyConfig, train_pips_study
from socialzoo.train.pips import read_program_record

pytest.importorskip("z3")

TINY = {
    "max_depth": 0,
    "max_pred_size": 1,
    "pool": 4,
    "partners": 20,
    "solver": "exact",
    "heldout_steps": 200,
}


@pytest.fixture(scope="module")
def rooms_demos(tmp_path_factory, rooms_map_path):
    """Ref on the two-room map: 6 episodes of at most 300 steps."""
    from socialzoo.bench.demonstrations import DemoConfig, record_demonstrations

    path = tmp_path_factory.mktemp("demos") / "ref.npz"
    config = DemoConfig(
        map=str(rooms_map_path), episodes=6, chunk_episodes=6, batch_size=6, env_overrides={"max_steps": 300}
    )
    return record_demonstrations(path, config)


def test_study_synthesises_each_cell_once_and_tabulates_it(rooms_demos, rooms_map_path, tmp_path):
    config = PipsStudyConfig(
        demos=rooms_demos, root=tmp_path / "runs", steps=(300, 900), windows=(10, 0), seed=3, overrides=TINY
    )
    files = train_pips_study(config)
    assert files == {(s, w): study_program_file(tmp_path / "runs", s, w) for s in (300, 900) for w in (10, 0)}
    assert find_study_programs(tmp_path / "runs") == files
    for (steps, window), path in files.items():
        record = read_program_record(path)
        assert record["seed"] == 3 and record["args"]["max_depth"] == 0
        assert (record["args"]["steps"], record["args"]["window"]) == (steps, window)
        assert record["demonstrations"]["steps_spanned"] == steps
        examples = record["demonstrations"]["examples"]
        # Without windowing every step is an example; with it, only the steps near changes.
        assert examples == steps if window == 0 else examples < steps
    stamps = {k: p.stat().st_mtime_ns for k, p in files.items()}
    assert train_pips_study(config) == files
    assert {k: p.stat().st_mtime_ns for k, p in files.items()} == stamps
    # Another argument is another synthesis.
    changed = dataclasses.replace(config, overrides={**TINY, "pool": 5}, steps=(300,), windows=(10,))
    train_pips_study(changed)
    assert json.loads(files[(300, 10)].with_name("pips.train.json").read_text())["args"]["pool"] == 5

    validation = TestSet(str(rooms_map_path), 4242, 3, name="rooms-val")
    out = tmp_path / "eval"
    kwargs = dict(
        trials=2, test_set=validation, batch_size=4, env_overrides={"max_steps": 40}, progress=False
    )
    result = run_pips_study(files, out, **kwargs)
    assert result.computed == 10 and result.reused == 0  # 4 programs and Ref, 2 scenarios each
    ((ref,),) = (result.baselines,)
    assert ref["policy"] == "ref" and ref["trials"] == 2 and ref["demonstration_steps"] is None
    assert [(r["demonstration_steps"], r["window"]) for r in result.rows] == sorted(files)
    for row in result.rows:
        assert row["trials"] == 2 and row["success_ci_low"] <= row["success_rate"] <= row["success_ci_high"]
        assert row["synthesis_seconds"] > 0 and row["seed"] in (3,)
    with (out / "pips_study.csv").open() as f:
        table = list(csv.DictReader(f))
    assert tuple(table[0]) == CSV_COLUMNS and [r["policy"] for r in table] == ["pips"] * 4 + ["ref"]
    md = (out / "pips_study.md").read_text()
    assert "rooms-val" in md and "| 900 | none (every step) |" in md and "| 300 | 10 steps |" in md
    assert "Ref on the same scenarios:" in md
    assert (out / "pips_study.png").stat().st_size > 1000
    again = run_pips_study(files, out, **kwargs)
    assert again.computed == 0 and again.reused == 10 and again.rows == result.rows


def test_the_study_refuses_test_sets_and_bad_configs(rooms_demos, tmp_path):
    program = study_program_file(tmp_path, 500, 20)
    program.parent.mkdir(parents=True)
    program.write_text(json.dumps({"format": "socialzoo-pips/1", "states": {}}))
    with pytest.raises(ValueError, match=r"gdc1-test.*benchmark test set"):
        run_pips_study({(500, 20): program}, tmp_path / "out", test_set=get_test_set("gdc1-test"))
    with pytest.raises(ValueError, match="demonstrations' base seed"):
        run_pips_study({(500, 20): program}, tmp_path / "out", test_set=TestSet("gdc1", 20220100, 5))
    with pytest.raises(ValueError, match="no program file"):
        run_pips_study({(500, 0): tmp_path / "nope.json"}, tmp_path / "out")
    with pytest.raises(ValueError, match=r"per-cell PipsArgs field\(s\) \['window'\]"):
        PipsStudyConfig(demos=rooms_demos, root=tmp_path, overrides={"window": 5})
    with pytest.raises(ValueError, match=r"PipsStudyConfig\.steps must be ints >= 1"):
        PipsStudyConfig(demos=rooms_demos, root=tmp_path, steps=(0,))
    with pytest.raises(ValueError, match=r"PipsArgs\.max_pred_size"):
        PipsStudyConfig(demos=rooms_demos, root=tmp_path, overrides={"max_pred_size": 9})
