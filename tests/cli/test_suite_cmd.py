"""`socialzoo suite` end to end on tiny runs: two stand-in families x two engineered policies x two
seeds; a rerun plays nothing; a bad scenario is a named error that writes nothing."""

from __future__ import annotations

import csv
import json

import pytest

from socialzoo.cli import main as socialzoo_main
from socialzoo.scenarios import catalogue
from socialzoo.scenarios.families import Doorway

SCENARIOS = "a,crossing"  # suite scenario (a), a stand-in here, and a family outside the suite
METRICS = ("success", "time_to_goal", "min_human_distance")


class FrontalStandIn(Doorway):
    """The doorway family under suite scenario (a)'s name."""

    name = "frontal_approach"


@pytest.fixture
def stand_in(monkeypatch):
    monkeypatch.setitem(catalogue.FAMILIES, "frontal_approach", FrontalStandIn())


def test_suite_end_to_end_then_resumed(tmp_path, capsys, stand_in):
    pytest.importorskip("matplotlib")
    out = tmp_path / "suite"
    argv = ["suite", "--policies", "goalone,ref", "--scenarios", SCENARIOS, "--seeds", "2", "--out", str(out)]
    argv += ["--workers", "1", "--batch-size", "4", "--metrics", ",".join(METRICS), "--no-progress"]
    assert socialzoo_main(argv) == 0
    text = capsys.readouterr().out
    assert "8 episodes played, 0 read from the store" in text
    record = json.loads((out / "config.json").read_text())
    for unit in record["units"]:  # the test split, else the task's first split, said so
        assert (
            unit["split"] == "test"
            or f"{unit['scenario']}: the action_selection task has no test split" in text
        )
    assert "a. Frontal approach" in text and "100.0 [" in text
    for name in METRICS:
        assert (out / "tables" / f"{name}.md").is_file()
        assert (out / "heatmaps" / f"{name}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with (out / "tables" / "success.csv").open(newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["policy"] for r in rows] == ["goalone", "ref"]
    assert list(rows[0])[:4] == [
        "policy",
        "frontal_approach",
        "frontal_approach_ci_low",
        "frontal_approach_ci_high",
    ]
    assert float(rows[0]["crossing"]) == 1.0 and 0.0 < float(rows[0]["crossing_ci_low"]) < 1.0  # shares
    table = (out / "tables" / "success.md").read_text()
    assert table.splitlines()[2].startswith("| policy | a. Frontal approach | crossing |")
    with (out / "suite.csv").open(newline="") as f:
        long = list(csv.DictReader(f))
    assert [(r["policy"], r["scenario"], r["letter"]) for r in long] == [
        (p, s, letter)
        for p in ("goalone", "ref")
        for s, letter in (("frontal_approach", "a"), ("crossing", ""))
    ]
    page = (out / "results.html").read_text()
    assert page.count("data:image/png;base64,") == len(METRICS)
    replays = sorted(p.relative_to(out).as_posix() for p in (out / "replays").rglob("*.html"))
    assert len(replays) == 4  # every episode succeeded: one success per scenario and policy
    assert all(f'href="{r}"' in page for r in replays)
    assert record["suite"]["seeds"] == 2 and record["package_version"]
    assert {u["task_kwargs"]["family"] for u in record["units"]} == {"frontal_approach", "crossing"}
    stamps = {r: (out / r).stat().st_mtime_ns for r in replays}
    # Again: everything is read from the store, and the replay pages are kept.
    assert socialzoo_main(argv) == 0
    assert "0 episodes played, 8 read from the store" in capsys.readouterr().out
    assert {r: (out / r).stat().st_mtime_ns for r in replays} == stamps


@pytest.mark.parametrize(
    ("scenarios", "message"),
    [
        ("crossing,narnia", "unknown scenario(s) 'narnia'"),
        ("z", "unknown scenario(s) 'z'"),
    ],
)
def test_an_unknown_scenario_is_a_named_error_that_writes_nothing(tmp_path, capsys, scenarios, message):
    out = tmp_path / "suite"
    assert socialzoo_main(["suite", "--scenarios", scenarios, "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert message in err and "a frontal_approach" in err and "registered scenario family" in err
    assert not out.exists()


def test_an_unregistered_suite_scenario_lists_the_registered_ones(tmp_path, capsys, monkeypatch):
    monkeypatch.delitem(catalogue.FAMILIES, "robot_crowding", raising=False)
    out = tmp_path / "suite"
    assert socialzoo_main(["suite", "--scenarios", "crossing,y", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "y. robot_crowding not registered as scenario families yet" in err and "doorway" in err
    assert not out.exists()


def test_bad_options_are_named(tmp_path, capsys):
    out = tmp_path / "suite"
    assert (
        socialzoo_main(["suite", "--policies", "ref,robocop", "--scenarios", "crossing", "--out", str(out)])
        == 2
    )
    assert "unknown policy 'robocop'" in capsys.readouterr().err
    assert (
        socialzoo_main(["suite", "--metrics", "happiness", "--scenarios", "crossing", "--out", str(out)]) == 2
    )
    assert "unknown metric 'happiness'" in capsys.readouterr().err
    assert not out.exists()


def test_an_interrupted_suite_says_that_the_same_command_resumes(tmp_path, capsys, monkeypatch):
    # Ctrl-C said only "interrupted", where the benchmark, the demos and reproduce say how to continue.
    import socialzoo.bench.suite as suite

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(suite, "run_suite", interrupted)
    argv = ["suite", "--policies", "goalone", "--scenarios", "a", "--seeds", "1", "--out", str(tmp_path)]
    assert socialzoo_main(argv) == 130
    assert capsys.readouterr().err == (
        "socialzoo suite: interrupted; the finished episodes are kept in the results store: "
        "the same command resumes\n"
    )
