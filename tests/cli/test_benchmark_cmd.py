"""`socialzoo benchmark` end to end on tiny runs, and `socialzoo demos`."""

import json

import numpy as np
import pytest

from socialzoo.agents.demonstrations import load_demonstrations, parts_dir
from socialzoo.bench.experiment import QUICK_POLICIES
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
    trials = 2 * 4 * len(QUICK_POLICIES)
    assert f"{trials} trials run, 0 read from the store" in text
    names = {p.name for p in out.iterdir()}
    expected = {"results.sqlite", "config.json", "summary.csv", "summary.md", "ref_episode.gif"}
    expected |= {f"{stem}.{fmt}" for stem in ("success", "metrics") for fmt in ("png", "pdf")}
    assert expected <= names
    rows = (out / "summary.csv").read_text().splitlines()
    assert rows[0].startswith("policy,map,test_set,trials,success_rate,success_ci_low,success_ci_high,")
    assert [r.split(",")[:4] for r in rows[1:]] == [
        [policy, m, f"{m}-quick", "4"] for policy in QUICK_POLICIES for m in ("gdc1", "ghc3")
    ]
    markdown = (out / "summary.md").read_text()
    assert "| policy | test (gdc1) | paper test | transfer (ghc3) | paper transfer |" in markdown
    config = json.loads((out / "config.json").read_text())
    assert config["benchmark"]["env_overrides"] == {"max_steps": 80}
    assert len(config["test_sets"]["gdc1-quick"]["seeds"]) == 4
    assert config["package_version"]
    # Run again: everything is read back from the store. Without figures, the older run's figures
    # go (they would not match the new tables); the user's own files in the folder stay.
    (out / "notes.png").write_bytes(b"mine")
    assert socialzoo_main([*argv[:-1], "--no-figures", "--no-progress"]) == 0
    assert f"0 trials run, {trials} read from the store" in capsys.readouterr().out
    assert not {f"{s}.{f}" for s in ("success", "failures", "metrics") for f in ("png", "pdf")} & {
        p.name for p in out.iterdir()
    }
    assert (out / "notes.png").read_bytes() == b"mine"


def test_a_rerun_without_the_gif_removes_the_older_one(tmp_path, capsys):
    # The quick benchmark animates a Ref episode; a rerun into the same folder that does not (without
    # --quick) left the older GIF beside tables it does not belong to.
    out = tmp_path / "results"
    argv = ["benchmark", "--maps", "gdc1", "--policies", "goalone", "--trials", "2", "--max-steps", "40"]
    argv += ["--workers", "1", "--no-figures", "--no-progress", "--out", str(out)]
    assert socialzoo_main([*argv, "--quick"]) == 0
    assert (out / "ref_episode.gif").is_file() and "ref_episode.gif" in capsys.readouterr().out
    (out / "mine.gif").write_bytes(b"mine")
    assert socialzoo_main(argv) == 0
    assert "ref_episode.gif" not in capsys.readouterr().out
    assert sorted(p.name for p in out.iterdir()) == [
        "config.json", "mine.gif", "results.sqlite", "summary.csv", "summary.md"
    ]  # fmt: skip


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


def test_benchmark_on_a_map_file_stores_its_test_set_and_reuses_it(tmp_path, rooms_path, capsys):
    out = tmp_path / "results"
    argv = ["benchmark", "--policies", "goalone", "--maps", rooms_path, "--trials", "3", "--max-steps", "60"]
    argv += ["--workers", "1", "--batch-size", "3", "--out", str(out), "--no-progress", "--no-figures"]
    assert socialzoo_main(argv) == 0
    assert "3 trials run, 0 read from the store" in capsys.readouterr().out
    stored = json.loads((out / "test_sets" / "rooms-test.json").read_text())
    assert stored["format"] == "socialzoo-testset/1" and stored["map"] == rooms_path
    assert len(stored["map_sha256"]) == 64 and len(stored["scenarios"]) == 3
    rows = (out / "summary.csv").read_text().splitlines()
    assert rows[1].split(",")[:4] == ["goalone", "rooms", "rooms-test", "3"]
    # A rerun reads the trials back; a longer one adds scenarios 3 and 4 to the stored set.
    assert socialzoo_main(argv) == 0
    assert "0 trials run, 3 read from the store" in capsys.readouterr().out
    longer = [*argv]
    longer[longer.index("3")] = "5"
    assert socialzoo_main(longer) == 0
    assert "2 trials run, 3 read from the store" in capsys.readouterr().out
    again = json.loads((out / "test_sets" / "rooms-test.json").read_text())
    assert again["scenarios"][:3] == stored["scenarios"] and len(again["scenarios"]) == 5
    # The map changed since: its stored test set is refused, naming the file.
    data = json.loads(open(rooms_path).read())
    data["legal_poses"] = data["legal_poses"][::-1]
    changed = tmp_path / "rooms.json"
    changed.write_text(json.dumps(data))
    moved = [changed.as_posix() if a == rooms_path else a for a in argv]
    assert socialzoo_main(moved) == 2
    assert "rooms-test.json: this test set was generated on map" in capsys.readouterr().err


def test_task_config_fields_are_read_as_json_or_text_and_nest_by_dots():
    import argparse

    from socialzoo.cli.arg_types import config_field, task_config

    fields = [
        config_field("family=recorded_zara1"),
        config_field('humans={"models": "hybrid:orca", "react_radius": 3}'),
        config_field("reward.discomfort_dist=0.3"),
        config_field("reward.success_reward=1"),
        config_field("robot_visible=true"),
    ]
    assert task_config(fields) == {
        "family": "recorded_zara1",
        "humans": {"models": "hybrid:orca", "react_radius": 3},
        "reward": {"discomfort_dist": 0.3, "success_reward": 1},
        "robot_visible": True,
    }
    with pytest.raises(argparse.ArgumentTypeError, match="KEY=VALUE"):
        config_field("family")
    with pytest.raises(ValueError, match="reward is given a value and fields at once"):
        task_config([("reward", 1), ("reward.discomfort_dist", 0.3)])


def test_task_config_names_a_family_that_a_module_of_one_s_own_registers(tmp_path, capsys, monkeypatch):
    """docs/recorded.md: a recording of one's own, registered as a family by one's own module, is
    benchmarked and replayed with --task-config family=MODULE:NAME, as --family takes it. The value was
    handed to the config as it was, which refused it (not a registered family), the module never
    imported."""
    from socialzoo.scenarios.catalogue import FAMILIES

    monkeypatch.setenv("SOCIALZOO_DATA_DIR", str(tmp_path))
    rows = [
        f"{10 * (k + 3 * p)}\t{p}\t{-4.0 + p + 0.3 * k}\t{0.7 * p}\n" for p in range(4) for k in range(25)
    ]
    (tmp_path / "my_tracks.txt").write_text("".join(rows))
    (tmp_path / "my_scene_own.py").write_text(
        "from socialzoo.data.tracks import read_tracks\n"
        "from socialzoo.scenarios.catalogue import register_family\n"
        "from socialzoo.scenarios.recorded import RecordedScene\n"
        f"register_family(RecordedScene(read_tracks({str(tmp_path / 'my_tracks.txt')!r}), name='recorded_own'))\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    env = ["--maps", "socialzoo/CrowdNavRecorded-v3", "--task-config", "family=my_scene_own:recorded_own"]
    try:
        argv = ["benchmark", *env, "--policies", "orca", "--trials", "1", "--no-figures", "--no-progress"]
        assert socialzoo_main([*argv, "--out", str(tmp_path / "out")]) == 0
        table = (tmp_path / "out" / "crowdnav.md").read_text()
        assert table.startswith("socialzoo/CrowdNavRecorded-v3, family=recorded_own, test cases")
        argv = [
            "replay",
            "--env",
            "socialzoo/Recorded-v4",
            *env[2:],
            "--policy",
            "goalone",
            "--max-steps",
            "10",
        ]
        assert socialzoo_main([*argv, "--out", str(tmp_path / "own.html")]) == 0
        assert "1 episode(s) on socialzoo/Recorded-v4, test case 0" in capsys.readouterr().out
    finally:
        FAMILIES.pop("recorded_own", None)
    argv = [
        "benchmark",
        "--maps",
        "socialzoo/CrowdNavRecorded-v3",
        "--policies",
        "orca",
        "--out",
        str(tmp_path),
    ]
    assert socialzoo_main([*argv, "--task-config", "family=no_such_module_own:recorded_own"]) == 2
    assert "cannot import 'no_such_module_own'" in capsys.readouterr().err


def test_a_task_id_whose_split_holds_no_cases_says_so(tmp_path, capsys, monkeypatch):
    """A recording of one person has one eligible track, which goes to train (the test split takes at
    most half): without --trials the error read "0 cases asked of the test split, which holds 0"."""
    from socialzoo.data.tracks import Recording, Track
    from socialzoo.scenarios.catalogue import FAMILIES, register_family
    from socialzoo.scenarios.recorded import RecordedScene

    monkeypatch.setenv("SOCIALZOO_DATA_DIR", str(tmp_path))
    alone = Track(0, 0, np.linspace([0.0, 0.0], [8.0, 0.0], 30))
    register_family(
        RecordedScene(Recording(name="alone", dt=0.4, num_frames=30, tracks=(alone,), source="test"))
    )
    argv = ["benchmark", "--maps", "socialzoo/CrowdNavRecorded-v3", "--task-config", "family=recorded_alone"]
    try:
        assert socialzoo_main([*argv, "--policies", "orca", "--out", str(tmp_path), "--no-figures"]) == 2
    finally:
        FAMILIES.pop("recorded_alone", None)
    err = capsys.readouterr().err
    assert "the test split of family recorded_alone holds no cases" in err


def test_task_config_needs_a_task_id(tmp_path, capsys):
    argv = ["benchmark", "--task-config", "family=x", "--out", str(tmp_path)]
    assert socialzoo_main(argv) == 2
    assert "name the id in --maps" in capsys.readouterr().err
    argv = [
        "benchmark",
        "--maps",
        "socialzoo/CrowdNav-v1",
        "--task-config",
        "famly=x",
        "--out",
        str(tmp_path),
    ]
    assert socialzoo_main([*argv, "--policies", "orca"]) == 2
    assert "unexpected keyword argument 'famly'" in capsys.readouterr().err


def test_a_task_id_takes_max_steps_where_its_config_has_it(tmp_path, capsys):
    # --max-steps was silently dropped for a task id; a task whose config has no max_steps (CrowdNav's
    # time limit is time_limit, s) refuses it naming its fields.
    argv = ["benchmark", "--maps", "socialzoo/CrowdNav-v1", "--policies", "orca", "--trials", "1"]
    assert socialzoo_main([*argv, "--max-steps", "5", "--out", str(tmp_path / "c")]) == 2
    assert "'max_steps'" in (err := capsys.readouterr().err) and "time_limit" in err
    toy = ["benchmark", "--maps", "socialzoo/ActionSelection-v2", "--policies", "goalone", "--trials", "1"]
    assert socialzoo_main([*toy, "--max-steps", "3", "--out", str(tmp_path / "a")]) == 0
    from socialzoo.bench.store import ResultsStore

    with ResultsStore(tmp_path / "a" / "results.sqlite") as store:
        assert [row["steps"] for row in store.rows()] == [3]  # the episode stopped at the override


def test_a_task_id_takes_its_config_field_cases(tmp_path, capsys):
    # CrowdNav's config has a field `cases` (the case generator: num_humans, circle_radius, ...), and
    # the benchmark passed the config to evaluate_stored as keywords beside its own `cases` (the count):
    # `--task-config cases.num_humans=3` ended in a TypeError traceback ("got multiple values for
    # argument 'cases'"), though `socialzoo replay --env` took it.
    argv = [
        "benchmark",
        "--maps",
        "socialzoo/CrowdNav-v1",
        "--policies",
        "orca",
        "--trials",
        "1",
        "--no-figures",
    ]
    assert socialzoo_main([*argv, "--task-config", "cases.num_humans=3", "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    from socialzoo.bench.store import ResultsStore

    with ResultsStore(tmp_path / "results.sqlite") as store:
        (row,) = store.rows()
        assert store.config(row["config_hash"])["task"]["cases"]["num_humans"] == 3


@pytest.mark.parametrize(
    "backend",
    [["--backend", "ray"], ["--backend", "ray", "--address", "10.255.255.1:6379"], ["--workers", "4"]],
)
def test_a_task_id_refuses_the_backend_options_it_would_not_use(tmp_path, capsys, backend):
    # A task id's cases are played in this process: --backend ray, an --address nothing answers at and
    # --workers ran locally in one process without a word.
    argv = ["benchmark", "--maps", "socialzoo/CrowdNav-v1", "--policies", "orca", "--trials", "1"]
    assert socialzoo_main([*argv, *backend, "--no-figures", "--out", str(tmp_path)]) == 2
    assert "--backend, --address and --workers are options of the benchmark maps" in capsys.readouterr().err
    assert not (tmp_path / "results.sqlite").exists()


def test_an_interrupted_benchmark_ends_in_a_line_not_a_traceback(tmp_path, capsys, monkeypatch):
    import socialzoo.bench.experiment as experiment

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(experiment, "run_benchmark", interrupted)
    argv = ["benchmark", "--policies", "goalone", "--maps", "gdc1", "--trials", "2", "--out", str(tmp_path)]
    assert socialzoo_main(argv) == 130
    err = capsys.readouterr().err
    assert err == (
        "socialzoo benchmark: interrupted; the finished trials are kept in the results store: "
        "the same command resumes\n"
    )
    with pytest.raises(KeyboardInterrupt):  # --verbose keeps the traceback
        socialzoo_main(["-v", *argv])


def test_a_terminated_benchmark_ends_as_an_interrupted_one(tmp_path, capsys, monkeypatch):
    """SIGTERM (kill, a job scheduler) killed the command outright: status -15, no line, and the
    multiprocessing resource tracker's "leaked semaphore" warning. It now ends as Ctrl-C does, with
    the shell's 128 + 15, and the caller's own SIGTERM handler is back afterwards."""
    import os
    import signal
    import time

    import socialzoo.bench.experiment as experiment

    def terminated(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)  # the handler raises within this sleep
        raise AssertionError("SIGTERM did not stop the run")

    monkeypatch.setattr(experiment, "run_benchmark", terminated)
    before = signal.getsignal(signal.SIGTERM)
    argv = ["benchmark", "--policies", "goalone", "--maps", "gdc1", "--trials", "2", "--out", str(tmp_path)]
    assert socialzoo_main(argv) == 143
    assert capsys.readouterr().err == (
        "socialzoo benchmark: interrupted; the finished trials are kept in the results store: "
        "the same command resumes\n"
    )
    assert signal.getsignal(signal.SIGTERM) is before


def test_a_killed_worker_ends_the_benchmark_in_a_line(tmp_path, capsys, monkeypatch):
    from concurrent.futures.process import BrokenProcessPool

    import socialzoo.bench.experiment as experiment

    def worker_killed(*args, **kwargs):
        raise BrokenProcessPool("A process in the process pool was terminated abruptly")

    monkeypatch.setattr(experiment, "run_benchmark", worker_killed)
    argv = ["benchmark", "--policies", "goalone", "--maps", "gdc1", "--trials", "2", "--out", str(tmp_path)]
    assert socialzoo_main(argv) == 1
    err = capsys.readouterr().err
    assert err.startswith("socialzoo benchmark: error: a worker process was killed")
    assert err.endswith("the same command resumes\n") and err.count("\n") == 1


def test_a_copy_of_a_shipped_map_file_has_its_registered_sets_and_an_edited_one_its_own(tmp_path, capsys):
    """`--maps` a shipped map's file (any copy of its contents) is that map's benchmark: its registered
    test set, as the env's "test" split is; an edited copy, even under the shipped name, is an imported
    map with a generated set, in the env and in the benchmark alike."""
    from socialzoo.env.config import EnvConfig
    from socialzoo.env.tasks import make_task
    from socialzoo.maps.map_file import load_map
    from socialzoo.scenarios.scenario_sets import CUSTOM_TEST_SEED, TEST_SETS

    shipped = load_map("gdc1")
    copy = tmp_path / "copy" / "gdc1.json"
    copy.parent.mkdir()
    copy.write_text(json.dumps(shipped.to_json(), indent=1))  # another layout, the same contents
    data = shipped.to_json()
    data["legal_poses"] = data["legal_poses"][::-1]
    edited = tmp_path / "edited.json"
    edited.write_text(json.dumps(data))  # still named "gdc1"
    registered = TEST_SETS["gdc1-test"]

    def first_test_seed(path):
        task = make_task("action_selection", 1, EnvConfig(map=str(path)))
        return int(task.reset(np.arange(1), {"split": "test", "cases": [0]})[0])

    for path, base_seed in ((copy, registered.base_seed), (edited, CUSTOM_TEST_SEED)):
        out = tmp_path / f"out-{path.stem}"
        argv = [
            "benchmark",
            "--policies",
            "goalone",
            "--maps",
            str(path),
            "--trials",
            "2",
            "--max-steps",
            "20",
        ]
        argv += ["--workers", "1", "--batch-size", "2", "--out", str(out), "--no-progress", "--no-figures"]
        assert socialzoo_main(argv) == 0, capsys.readouterr().err
        (test_set,) = json.loads((out / "config.json").read_text())["test_sets"].values()
        assert test_set["base_seed"] == base_seed
        assert (out / "test_sets").exists() == (base_seed == CUSTOM_TEST_SEED)
        assert first_test_seed(path) == test_set["seeds"][0]
    assert first_test_seed(copy) == registered.seed(0)
    # The shipped map and its copy are one test set: refused, not counted twice.
    argv = ["benchmark", "--policies", "goalone", "--maps", f"gdc1,{copy}", "--out", str(tmp_path / "both")]
    assert socialzoo_main(argv) == 2
    assert "both give test set 'gdc1-test'" in capsys.readouterr().err


def test_two_map_files_of_one_name_are_refused_before_any_test_set_is_made(tmp_path, capsys):
    # Two imported buildings both named "twin" (their name field) in one --maps: the first one's test
    # set was generated into OUT/test_sets/twin-test.json, then the second's was refused as "generated
    # on map 'a.json' ...: use another --out directory", advice that the next run would meet again.
    from socialzoo.maps.map_file import load_map

    data = {**load_map("open_room").to_json(), "name": "twin"}
    (tmp_path / "a.json").write_text(json.dumps(data))
    data["walls"] = [*data["walls"], [4.0, 4.0, 4.5, 4.5]]
    (tmp_path / "b.json").write_text(json.dumps(data))
    maps = f"{tmp_path / 'a.json'},{tmp_path / 'b.json'}"
    argv = ["benchmark", "--policies", "goalone", "--maps", maps, "--trials", "2", "--no-figures"]
    assert socialzoo_main([*argv, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "both give test set 'twin-test' (one map, or two of one name)" in err and "sha256" not in err
    assert not (tmp_path / "out" / "test_sets").exists()


def test_task_ids_of_one_name_in_two_namespaces_get_folders_of_their_own():
    # a/X-v0 and b/X-v0 both wrote to OUT/X-v0, the second run's tables over the first's.
    from socialzoo.cli.benchmark_cmd import _id_folders

    ids = ["socialzoo/CrowdNav-v1", "mine/ToyReach-v0", "my_tasks:theirs/ToyReach-v0", "mine/ToyReach-v0"]
    assert _id_folders(ids) == {
        "socialzoo/CrowdNav-v1": "CrowdNav-v1",
        "mine/ToyReach-v0": "mine_ToyReach-v0",
        "my_tasks:theirs/ToyReach-v0": "my_tasks_theirs_ToyReach-v0",
    }


def test_humans_learned_alone_are_the_shipped_humans(tmp_path, capsys):
    """`--humans learned` names the shipped humans' file, as several --humans and `humans report`
    read it; one spec was refused with "name the learned policy file as learned:PATH", so the
    docs' command had to name socialzoo/agents/shipped/humans.safetensors, a path in a checkout."""
    from socialzoo.cli.humans_cmd import shipped_humans

    out = tmp_path / "out"
    small = ["--trials", "1", "--max-steps", "20", "--workers", "1", "--no-figures", "--no-progress"]
    argv = ["benchmark", "--policies", "goalone", "--maps", "open_room", "--humans", "learned", *small]
    assert socialzoo_main([*argv, "--out", str(out)]) == 0, capsys.readouterr().err
    recorded = json.loads((out / "config.json").read_text())
    assert recorded["benchmark"]["humans"] == f"learned:{shipped_humans()}"


def test_a_recorded_scene_not_fetched_ends_in_one_line_naming_the_file(tmp_path, monkeypatch, capsys):
    """`socialzoo benchmark --maps socialzoo/CrowdNavRecorded-v3 --task-config family=recorded_zara1`
    before `socialzoo data fetch` ended in a FileNotFoundError traceback (the task reads the scene
    when it is built, outside the command's own error handling); every command now says it in one
    line, exit status 2, and --verbose keeps the traceback."""
    monkeypatch.setenv("SOCIALZOO_DATA_DIR", str(tmp_path / "empty"))
    argv = ["benchmark", "--maps", "socialzoo/CrowdNavRecorded-v3", "--task-config", "family=recorded_zara1"]
    argv += ["--policies", "orca", "--trials", "1", "--no-figures", "--out", str(tmp_path / "out")]
    assert socialzoo_main(argv) == 2
    err = capsys.readouterr().err
    assert (
        err.startswith("socialzoo benchmark: error: scene 'zara1' is not fetched") and "Traceback" not in err
    )
    assert "crowds_zara01.txt" in err and "socialzoo data fetch eth-ucy" in err
    assert not (tmp_path / "out").exists()
    with pytest.raises(FileNotFoundError):
        socialzoo_main(["-v", *argv])
