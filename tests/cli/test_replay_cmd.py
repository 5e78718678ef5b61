"""`socialzoo replay`: policies side by side from a seed, and stored benchmark trials re-run and
checked against their stored metrics."""

import json
import re

import pytest

from socialzoo.cli import main as socialzoo_main
from socialzoo.env.metrics import SUMMARY_KEYS


def embedded(path):
    text = path.read_text(encoding="utf-8")
    match = re.search(r'<script type="application/json" id="replay-data">(.*?)</script>', text, re.S)
    return json.loads(match.group(1))


def test_replay_from_a_seed(tmp_path, capsys):
    out = tmp_path / "ep.html"
    argv = ["replay", "--policy", "goalone,ref", "--map", "open_room", "--seed", "3", "--max-steps", "60"]
    assert socialzoo_main([*argv, "--view", "map", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert text.startswith(f"{out}: 2 episode(s) on open_room, seed 3; ")
    assert "  goalone: " in text and "  ref: " in text
    data = embedded(out)
    assert [e["label"] for e in data["episodes"]] == ["goalone", "ref"]
    assert data["view"] == "map" and data["title"] == "goalone vs ref on open_room, scenario seed 3"
    assert all(e["steps"] <= 60 for e in data["episodes"])
    # Repeated --policy is the same as a list; the same seed gives the same file.
    again = tmp_path / "again.html"
    argv_repeated = ["replay", "--policy", "goalone", "--policy", "ref", *argv[3:], "--view", "map"]
    assert socialzoo_main([*argv_repeated, "--out", str(again)]) == 0
    assert again.read_text() == out.read_text()


def test_replay_and_demo_of_a_family_play_on_its_own_map(tmp_path, capsys, monkeypatch):
    # Without --map a family plays on its own map (--map used to default to gdc1, where no family
    # fits): a suite family on its building, and a recorded scene of one's own in its open area.
    import numpy as np

    from socialzoo.data.tracks import Recording, Track
    from socialzoo.scenarios.catalogue import register_family
    from socialzoo.scenarios.recorded import RecordedScene

    monkeypatch.setenv("SOCIALZOO_DATA_DIR", str(tmp_path))
    walkers = [Track(p, 3 * p, np.linspace([-4.0 + p, -5.0], [4.0 - p, 5.0], 30)) for p in range(4)]
    register_family(
        RecordedScene(Recording(name="cli", dt=0.4, num_frames=40, tracks=tuple(walkers), source="test"))
    )
    for family, home in (("frontal_approach", "hallway"), ("recorded_cli", "recorded_cli")):
        out = tmp_path / f"{family}.html"
        argv = ["replay", "--policy", "goalone", "--family", family, "--seed", "100", "--max-steps", "20"]
        assert socialzoo_main([*argv, "--out", str(out)]) == 0
        assert capsys.readouterr().out.startswith(f"{out}: 1 episode(s) on {home}, seed 100; ")
    gif = tmp_path / "episode.gif"
    argv = ["demo", "--policy", "goalone", "--family", "recorded_cli", "--seed", "100", "--max-frames", "3"]
    assert socialzoo_main([*argv, "--out", str(gif)]) == 0
    assert "frames;" in capsys.readouterr().out


def test_a_family_that_a_module_of_one_s_own_registers_is_named_as_module_colon_name(
    tmp_path, capsys, monkeypatch
):
    """docs/architecture.md: a family registered from your own code is then accepted by `socialzoo demo
    --family` and `socialzoo replay --family`; the command's process never imported that code, so the
    name was refused. MODULE:NAME imports MODULE first, as MODULE:ID does for an id."""
    from socialzoo.bench.suite import SuiteError, resolve_scenarios
    from socialzoo.scenarios.catalogue import FAMILIES

    (tmp_path / "my_corridor_own.py").write_text(
        "from socialzoo.scenarios.catalogue import register_family\n"
        "from socialzoo.scenarios.families import HallwayHeadOn\n"
        "class CorridorOwn(HallwayHeadOn):\n"
        "    name = 'corridor_own'\n"
        "register_family(CorridorOwn)\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    out = tmp_path / "own.html"
    argv = ["replay", "--policy", "goalone", "--seed", "2", "--max-steps", "20", "--out", str(out)]
    try:
        assert socialzoo_main([*argv, "--family", "my_corridor_own:corridor_own"]) == 0
        assert capsys.readouterr().out.startswith(f"{out}: 1 episode(s) on hallway, seed 2; ")
        assert embedded(out)["title"] == "goalone on hallway, corridor_own scenario seed 2"
        (scenario,) = resolve_scenarios(["my_corridor_own:corridor_own"])
        assert scenario.name == "corridor_own"
    finally:
        FAMILIES.pop("corridor_own", None)
    assert socialzoo_main([*argv, "--family", "no_such_module_own:corridor_own"]) == 2
    assert "cannot import 'no_such_module_own'" in capsys.readouterr().err
    assert socialzoo_main([*argv, "--family", "my_corridor_own:other_own"]) == 2
    assert "importing 'my_corridor_own' registers no family 'other_own'" in capsys.readouterr().err
    with pytest.raises(SuiteError, match="cannot import 'no_such_module_own'"):
        resolve_scenarios(["no_such_module_own:x"])


def test_replay_options_reach_the_file(tmp_path):
    out = tmp_path / "ep.html"
    argv = ["replay", "--map", "open_room", "--seed", "1", "--max-steps", "30", "--stride", "5"]
    assert socialzoo_main([*argv, "--laser-rays", "7", "--out", str(out)]) == 0
    (episode,) = embedded(out)["episodes"]
    assert episode["label"] == "ref"  # the default policy
    assert episode["frameSteps"][:3] == [0, 5, 10] and len(episode["laser"]["angles"]) == 7
    assert socialzoo_main([*argv, "--laser-rays", "0", "--out", str(out)]) == 0
    assert embedded(out)["episodes"][0]["laser"]["angles"] == []

    # A task id's case: by default a state every 50 ms of its steps, all of the CrowdNav task's.
    argv = ["replay", "--env", "socialzoo/CrowdNav-v1", "--policy", "orca", "--out", str(out)]
    assert socialzoo_main(argv) == 0
    (episode,) = embedded(out)["episodes"]
    assert episode["dt"] == 0.25 and episode["frameSteps"] == list(range(episode["steps"] + 1))
    assert socialzoo_main([*argv, "--stride", "3"]) == 0
    assert embedded(out)["episodes"][0]["frameSteps"][:3] == [0, 3, 6]


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """`socialzoo benchmark` of Ref on two gdc1-quick scenarios, 40 steps each."""
    out = tmp_path_factory.mktemp("bench") / "results"
    argv = ["benchmark", "--quick", "--policies", "ref", "--maps", "gdc1", "--trials", "2"]
    argv += ["--max-steps", "40", "--workers", "1", "--batch-size", "2", "--no-figures", "--no-progress"]
    assert socialzoo_main([*argv, "--out", str(out)]) == 0
    return out


def test_replay_a_stored_trial(tmp_path, results, capsys):
    capsys.readouterr()
    out = tmp_path / "trial.html"
    assert socialzoo_main(["replay", "--results", str(results), "--trial", "1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "gdc1-quick scenario #1" in text
    assert text.count(f"all {len(SUMMARY_KEYS)} metrics match the stored trial") == 1
    data = embedded(out)
    assert [e["label"] for e in data["episodes"]] == ["ref (stored #1)"]
    assert data["episodes"][0]["steps"] == 40
    # A policy the store does not hold runs fresh beside the stored one, on the same scenario.
    argv = ["replay", "--results", str(results), "--trial", "1", "--policy", "goalone,ref"]
    assert socialzoo_main([*argv, "--test-set", "gdc1-quick", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "goalone (not stored): " in text and "not in the store, run fresh" in text
    assert "ref (stored #1): " in text and f"all {len(SUMMARY_KEYS)} metrics match" in text
    fresh, stored = embedded(out)["episodes"]
    assert fresh["label"] == "goalone (not stored)" and fresh["robot"][:3] == stored["robot"][:3]
    assert fresh["humanPos"][:10] == stored["humanPos"][:10]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--results", "x"], "--results and --trial go together"),
        (["--trial", "2"], "--results and --trial go together"),
        (["--results", "x", "--trial", "0", "--seed", "3"], "--seed cannot be combined with --results"),
        (["--results", "nowhere", "--trial", "0"], "no results store"),
        (["--policy", "robocop", "--map", "open_room"], "unknown policy 'robocop'"),
        (["--policy", "ref,goalone", "--policy-path", "a.zip"], "--policy-path goes with a single --policy"),
        (["--policy", "ref,ref"], "names a policy twice"),
        (["--map", "narnia"], "narnia"),
        (["--test-set", "gdc1-quick"], "--test-set goes with --results"),
    ],
)
def test_replay_usage_errors(tmp_path, capsys, argv, message):
    out = tmp_path / "ep.html"
    assert socialzoo_main(["replay", *argv, "--out", str(out)]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_replay_refuses_other_suffixes(tmp_path, capsys):
    assert socialzoo_main(["replay", "--map", "open_room", "--out", str(tmp_path / "ep.gif")]) == 2
    assert "must end in .html" in capsys.readouterr().err


def test_a_trial_on_a_map_file_edited_since_names_the_map(tmp_path, capsys):
    """A benchmark on a map file, then the file edited in place: the replay does not reproduce,
    and says that the map changed (it blamed the code or config)."""
    import json

    from socialzoo.maps.map_file import load_map

    plan = tmp_path / "plan.json"
    load_map("open_room").save(plan)
    out = tmp_path / "results"
    argv = ["benchmark", "--quick", "--policies", "goalone", "--maps", str(plan), "--trials", "1"]
    argv += ["--max-steps", "30", "--workers", "1", "--no-figures", "--no-progress", "--out", str(out)]
    assert socialzoo_main(argv) == 0
    data = json.loads(plan.read_text())
    data["walls"].append([4.0, 4.0, 4.5, 4.5])  # a post in the room
    plan.write_text(json.dumps(data))
    capsys.readouterr()
    socialzoo_main(["replay", "--results", str(out), "--trial", "0", "--out", str(tmp_path / "t.html")])
    assert f"the map {plan} changed since the run stored it (sha256 " in capsys.readouterr().out


def test_a_replay_of_a_file_that_is_no_store_does_not_speak_of_an_output_directory(tmp_path, capsys):
    """--results is read, not written: the store's refusal ended in "choose another output directory"."""
    (tmp_path / "results.sqlite").write_text("not a database")
    argv = ["replay", "--results", str(tmp_path), "--trial", "0", "--out", str(tmp_path / "ep.html")]
    assert socialzoo_main(argv) == 2
    err = capsys.readouterr().err
    assert "is not a socialzoo results store" in err and "choose another directory" in err
    assert "output" not in err
