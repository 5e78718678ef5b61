"""The policy x crowd-model matrix (`socialzoo benchmark --humans A,B,...`)."""

import json
import logging
import re
import shutil
import socket

import pytest

from socialzoo.cli import main as socialzoo_main
from socialzoo.scenarios.generator import ScenarioConfig
from socialzoo.scenarios.scenario_sets import TestSet
from socialzoo.studies.crowd_matrix import MatrixConfig, column_folder, column_label, crowd_matrix


@pytest.fixture(scope="module")
def rooms(rooms_map_path):
    return {
        "rooms": TestSet(
            str(rooms_map_path), 7, 20, ScenarioConfig(min_humans=3, max_humans=5), name="rooms-test"
        )
    }


def config(**changes):
    base = dict(
        policies=("goalone", "ref"),
        humans=("sf", "orca"),
        maps=("rooms",),
        trials=2,
        batch_size=4,
        workers=1,
        env_overrides={"max_steps": 80},
    )
    return MatrixConfig(**{**base, **changes})


def test_matrix_runs_every_policy_among_every_crowd_model(rooms, tmp_path):
    result = crowd_matrix(config(), tmp_path, test_sets=rooms, progress=False, figures=False)
    assert [(r["policy"], r["humans"]) for r in result.rows] == [
        ("goalone", "sf"),
        ("ref", "sf"),
        ("goalone", "orca"),
        ("ref", "orca"),
    ]
    for row in result.rows:
        assert row["trials"] == 2 and 0.0 <= row["success_mean"] <= 100.0
        assert row["people_time_lost_mean"] == row["people_time_lost_mean"]  # measured, not NaN
    text = (tmp_path / "matrix.md").read_text()
    assert "people's time lost" in text and "| GoAlone |" in text
    env = next(
        iter(
            json.loads((tmp_path / column_folder("orca") / "config.json").read_text())["env_configs"].values()
        )
    )
    assert env["people"] == {
        "models": "orca",
        "group_sizes": [0.6, 0.3, 0.1],
        "counterfactual": True,
        "react_radius": 1.5,
        "react_time": 2.0,
    }
    # A rerun reads every trial back; without figures it removes an older run's heatmaps.
    (tmp_path / "matrix.png").write_bytes(b"an older run's")
    again = crowd_matrix(config(), tmp_path, test_sets=rooms, progress=False, figures=False)
    assert again.rows == result.rows
    assert not (tmp_path / "matrix.png").exists()


def test_columns_are_found_by_their_people_whatever_their_order(rooms, tmp_path, caplog):
    # Folders were named by position ("0-sf", "1-orca"): reordering --humans ran every column again.
    crowd_matrix(config(), tmp_path, test_sets=rooms, progress=False, figures=False)
    caplog.set_level(logging.INFO, logger="socialzoo.bench.experiment")
    swapped = crowd_matrix(
        config(humans=("orca", "sf")), tmp_path, test_sets=rooms, progress=False, figures=False
    )
    assert [r["humans"] for r in swapped.rows] == ["orca", "orca", "sf", "sf"]
    assert caplog.text.count("4 trials, 4 stored, 0 to run") == 2
    assert sorted(p.name for p in tmp_path.iterdir() if p.is_dir()) == ["orca", "sf"]
    # Folders of an older version, named by position, are renamed and resumed when their config.json
    # records the column's spec; one of another spec is left alone.
    (tmp_path / "sf").rename(tmp_path / "1-sf")
    (tmp_path / "orca").rename(tmp_path / "0-orca")
    shutil.copytree(tmp_path / "0-orca", tmp_path / "0-sf")  # orca's people, in a folder that says sf
    caplog.clear()
    crowd_matrix(config(), tmp_path, test_sets=rooms, progress=False, figures=False)
    assert caplog.text.count("4 trials, 4 stored, 0 to run") == 2
    assert sorted(p.name for p in tmp_path.iterdir() if p.is_dir()) == ["0-sf", "orca", "sf"]


def test_matrix_labels_and_bad_configs(tmp_path):
    assert column_label("sf@0.5+learned:/x/y/h.safetensors@0.5") == "sf@0.5+learned:h.safetensors@0.5"
    assert column_folder("sf") == "sf" and column_folder("sf@0.5+orca@0.5") == "sf@0.5+orca@0.5"
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    for folder, weights in (("a", b"one"), ("b", b"one"), ("", b"two")):
        (tmp_path / folder / "h.safetensors").write_bytes(weights)
    one, same, other = (column_folder(f"learned:{tmp_path / f / 'h.safetensors'}") for f in ("a", "b", ""))
    assert re.fullmatch(r"learned_h\.safetensors-[0-9a-f]{8}", one) and one == same and other != one
    with pytest.raises(ValueError, match="unknown model 'robots'"):
        config(humans=("sf", "robots"))
    with pytest.raises(ValueError, match="no such learned policy file"):
        config(humans=(f"learned:{tmp_path / 'none.safetensors'}",))
    with pytest.raises(ValueError, match="is a folder, not a learned policy file"):
        config(humans=(f"learned:{tmp_path}",))
    with pytest.raises(ValueError, match="must not set people"):
        config(env_overrides={"people": {"models": "orca"}})


def test_cli_benchmark_with_several_humans_writes_the_matrix(rooms_map_path, tmp_path, capsys):
    out = tmp_path / "matrix"
    argv = ["benchmark", "--policies", "goalone", "--maps", str(rooms_map_path), "--trials", "1"]
    argv += ["--max-steps", "40", "--workers", "1", "--batch-size", "1", "--no-figures", "--no-progress"]
    assert socialzoo_main([*argv, "--humans", "sf,groups", "--out", str(out)]) == 0
    assert "# Robot policies x crowd models" in capsys.readouterr().out
    assert (out / "matrix.csv").is_file() and (out / "sf").is_dir() and (out / "groups").is_dir()
    assert socialzoo_main([*argv, "--humans", "sf,orca@0.5", "--out", str(out)]) == 2
    assert "the shares sum to 0.5" in capsys.readouterr().err


def test_cli_matrix_runs_on_the_backend_it_is_given(rooms_map_path, tmp_path, capsys):
    # The matrix dropped --backend and --address: a Ray cluster nothing answers at ran every column locally.
    pytest.importorskip("ray")
    with socket.socket() as s:  # a local port that nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    argv = ["benchmark", "--policies", "goalone", "--maps", str(rooms_map_path), "--trials", "1", "--humans"]
    argv += ["sf,orca", "--backend", "ray", "--address", f"127.0.0.1:{port}", "--out", str(tmp_path / "m")]
    assert socialzoo_main([*argv, "--no-figures", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"socialzoo benchmark: error: cannot reach the Ray cluster at '127.0.0.1:{port}'")
    assert config(backend="ray", workers=None).benchmark("sf").backend == "ray"
