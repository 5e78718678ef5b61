"""`socialzoo benchmark` end to end on tiny runs, and `socialzoo demos` (recording, resuming)."""

import json

import numpy as np
import pytest

from socialzoo.agents import demonstrations
from socialzoo.agents.demonstrations import DemoConfig, load_demonstrations, parts_dir, record_demonstrations
from socialzoo.cli import main as socialzoo_main


def test_benchmark_end_to_end(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    out = tmp_path / "results"
    argv = [
        "benchmark",
        "--quick",
        "--trials",
        "4",
        "--max-steps",
        "80",
        "--workers",
        "1",
        "--batch-size",
        "4",
    ]
    argv += ["--out", str(out), "--no-progress"]
    assert socialzoo_main(argv) == 0
    text = capsys.readouterr().out
    assert "16 trials run, 0 read from the store" in text
    names = {p.name for p in out.iterdir()}
    expected = {"results.sqlite", "config.json", "summary.csv", "summary.md", "ref_episode.gif"}
    expected |= {f"{stem}.{fmt}" for stem in ("success", "metrics") for fmt in ("png", "pdf")}
    assert expected <= names
    rows = (out / "summary.csv").read_text().splitlines()
    assert rows[0].startswith("policy,map,test_set,trials,success_rate,success_ci_low,success_ci_high,")
    assert [r.split(",")[:4] for r in rows[1:]] == [
        ["goalone", "gdc1", "gdc1-quick", "4"],
        ["goalone", "ghc3", "ghc3-quick", "4"],
        ["ref", "gdc1", "gdc1-quick", "4"],
        ["ref", "ghc3", "ghc3-quick", "4"],
    ]
    markdown = (out / "summary.md").read_text()
    assert "| policy | test (gdc1) | paper test | transfer (ghc3) | paper transfer |" in markdown
    config = json.loads((out / "config.json").read_text())
    assert config["benchmark"]["env_overrides"] == {"max_steps": 80}
    assert len(config["test_sets"]["gdc1-quick"]["seeds"]) == 4
    assert config["package_version"]
    # Run again: everything is read back from the store.
    assert socialzoo_main([*argv[:-1], "--no-figures", "--no-progress"]) == 0
    assert "0 trials run, 16 read from the store" in capsys.readouterr().out


def test_benchmark_bad_names(tmp_path, capsys):
    out = tmp_path / "results"
    assert socialzoo_main(["benchmark", "--policies", "goalone,robocop", "--out", str(out)]) == 2
    assert "unknown policy 'robocop'" in capsys.readouterr().err
    assert socialzoo_main(["benchmark", "--maps", "narnia", "--out", str(out)]) == 2
    assert "unknown map 'narnia'" in capsys.readouterr().err
    assert not out.exists()


@pytest.fixture
def rooms_path(rooms_map_path):
    return str(rooms_map_path)


def test_demos_command(tmp_path, rooms_path, capsys):
    out = tmp_path / "ref_demos.npz"
    argv = ["demos", "--episodes", "3", "--out", str(out), "--map", rooms_path, "--max-steps", "60"]
    assert socialzoo_main([*argv, "--chunk-episodes", "2", "--batch-size", "2", "--no-progress"]) == 0
    assert "3 episodes" in capsys.readouterr().out
    arrays, meta = load_demonstrations(out)
    assert arrays["obs"].shape == arrays["next_obs"].shape and arrays["obs"].dtype == np.float32
    assert arrays["episode_ids"].tolist() == [0, 1, 2]
    assert len(arrays["action"]) == int(arrays["episode_lengths"].sum())
    assert (arrays["terminated"] | arrays["truncated"]).sum() == 3
    assert meta["policy_config"]["corridor_half_width"] == 0.62 and len(meta["scenario_seeds"]) == 3
    assert not parts_dir(out).exists()


def test_interrupted_recording_resumes(tmp_path, rooms_path, monkeypatch):
    config = DemoConfig(
        map=rooms_path, episodes=5, chunk_episodes=2, batch_size=2, env_overrides={"max_steps": 50}
    )
    whole = record_demonstrations(tmp_path / "whole.npz", config)

    real_write = demonstrations._write_npz
    calls = []

    def dying_write(path, arrays):
        calls.append(path)
        if len(calls) == 2:
            raise KeyboardInterrupt
        real_write(path, arrays)

    monkeypatch.setattr(demonstrations, "_write_npz", dying_write)
    target = tmp_path / "resumed.npz"
    with pytest.raises(KeyboardInterrupt):
        record_demonstrations(target, config)
    monkeypatch.setattr(demonstrations, "_write_npz", real_write)
    partial, _ = load_demonstrations(target)  # the finished chunk is readable already
    assert partial["episode_ids"].tolist() == [0, 1]
    record_demonstrations(target, config)
    a, meta_a = load_demonstrations(whole)
    b, meta_b = load_demonstrations(target)
    assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)
    assert meta_a["config_hash"] == meta_b["config_hash"]
    other = DemoConfig(map=rooms_path, episodes=4, chunk_episodes=2, env_overrides={"max_steps": 50})
    with pytest.raises(demonstrations.DemonstrationError, match="another config"):
        record_demonstrations(target, other)


def test_policy_names_keep_the_case_of_their_file():
    from socialzoo.cli.benchmark_cmd import _names

    assert _names("Ref, PIPS:/Runs/A.json ,goalone") == ("ref", "pips:/Runs/A.json", "goalone")
