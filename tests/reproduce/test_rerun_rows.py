"""One policy's rows of a published reproduction replaced by a re-run of its seeds: the rows and
aggregates of that policy change, every other row stays byte for byte, Ref's trials must be the
published ones, and the report names the re-run."""

import json

import pytest

from socialzoo.reproduce.rerun_rows import PolicyRerun, RerunError, replace_policy_rows
from socialzoo.reproduce.results import load
from socialzoo.studies.seeds import benchmark_scores

TRIALS, LFD_TRIALS = 3, 2
# Two "seeds" of PIPS: the shipped program, and GoAlone standing in for a second program.
SPECS = {0: "pips", 1: "goalone"}


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    """A benchmark folder with PIPS, GoAlone and Ref on the first scenarios of both test sets."""
    from socialzoo.bench.experiment import BenchmarkConfig, run_benchmark

    folder = tmp_path_factory.mktemp("bench")
    config = BenchmarkConfig(
        policies=("pips", "goalone", "ref"),
        maps=("gdc1", "ghc3"),
        trials=TRIALS,
        quick=True,
        workers=1,
        env_overrides={"max_steps": 400},
    )
    run_benchmark(config, folder, progress=False, figures=False)
    return folder


def _rate(bench, spec, map_name, trials=TRIALS):
    from socialzoo.studies.seeds import benchmark_rows

    rows = [r for r in benchmark_rows(bench, spec) if r["map"] == map_name and r["scenario_index"] < trials]
    return sum(bool(r["success"]) for r in rows) / len(rows)


def _csv(path, header, rows):
    path.write_text("\r\n".join([header, *rows]) + "\r\n")


def published(tmp_path, bench, ref_success=None):
    """A results folder of a 2-seed run whose PIPS rows are stale (success 0.1)."""
    results = tmp_path / "results"
    results.mkdir(parents=True)
    settings = {
        "name": "full",
        "seed": 0,
        "seeds": 2,
        "performance_trials": TRIALS,
        "transfer_trials": TRIALS,
        "lfd_trials": LFD_TRIALS,
        "pips_steps": 3500,
    }
    run = {"settings": settings, "settings_hash": "abc", "command": "socialzoo reproduce --out DIR --seeds 2"}
    run["machine"] = {"cpus": 2, "platform": "test", "python": "3.11"}
    (results / "run.json").write_text(json.dumps(run))
    for experiment, map_name in (("performance", "gdc1"), ("transfer", "ghc3")):
        ref = _rate(bench, "ref", map_name) if ref_success is None else ref_success
        _csv(
            results / f"{experiment}.csv",
            "policy,map,test_set,trials,success_rate",
            [
                f"goalone,{map_name},{map_name}-test,3,0.25",
                f"ref,{map_name},{map_name}-test,3,{ref!r}",
                f"pips,{map_name},{map_name}-test,3,0.1",
            ],
        )
    _csv(
        results / "lfd.csv",
        "policy,demonstration_steps,trials,success_rate,average_step_reward,paper_success_pct",
        ["bc,155400.0,2.0,0.5,0.2,84.0", "pips,3500.0,2.0,0.1,0.1,88.0"],
    )
    _csv(
        results / "seeds.csv",
        "experiment,policy,seeds,seed_success_pct",
        [
            "performance,ref,1,50.00",
            "performance,pips,2,10.00;10.00",
            "transfer,pips,2,10.00;10.00",
            "lfd,bc,2,1.00;2.00",
            "lfd,pips,2,10.00;10.00",
        ],
    )
    _csv(
        results / "improvement.csv",
        "experiment,x,y,probability",
        ["performance,pips,ref,0.0", "performance,bc,gail,0.5", "transfer,pips,ref,0.0"],
    )
    _csv(
        results / "profiles.csv",
        "experiment,policy,tau,share",
        ["performance,pips,0.0,1.0", "performance,pips,0.5,0.0", "performance,ref,0.0,1.0"],
    )
    (results / "training.json").write_text(
        json.dumps([{"run": "lfd/bc_3500", "trainer": "bc"}, {"run": "lfd/pips_3500", "trainer": "pips"}])
    )
    return tmp_path


def rerun(bench, **changes):
    fields = {
        "policy": "pips",
        "seed_specs": SPECS,
        "performance": bench,
        "transfer": bench,
        "ref": bench,
        "commands": ("socialzoo benchmark --policies pips,goalone --maps gdc1 --trials 3",),
        "commit": "abc1234",
        "training": (
            {"run": "pips-s0", "trainer": "pips", "seed": 0},
            {"run": "pips-s1", "trainer": "pips", "seed": 1},
        ),
        "why": "The synthesiser changed.",
    }
    return PolicyRerun(**{**fields, **changes})


def lines(path):
    return path.read_bytes().decode().split("\r\n")


def test_the_policy_rows_are_replaced_and_every_other_row_kept(tmp_path, bench):
    base = published(tmp_path, bench)
    before = {
        name: lines(base / "results" / name) for name in ("performance.csv", "seeds.csv", "improvement.csv")
    }
    replace_policy_rows(base, rerun(bench))
    data = load(base / "results")

    for experiment, map_name in (("performance", "gdc1"), ("transfer", "ghc3")):
        row = next(r for r in data[experiment] if r["policy"] == "pips")
        assert (
            row["success_rate"] == pytest.approx(_rate(bench, "pips", map_name)) and row["trials"] == TRIALS
        )
    after = lines(base / "results" / "performance.csv")
    assert after[:3] == before["performance.csv"][:3] and after[3] != before["performance.csv"][3]

    lfd = {r["policy"]: r for r in data["lfd"]}
    assert lfd["pips"]["trials"] == LFD_TRIALS
    assert lfd["pips"]["success_rate"] == pytest.approx(_rate(bench, "pips", "gdc1", LFD_TRIALS))
    assert lfd["pips"]["paper_success_pct"] == 88.0 and lfd["bc"]["success_rate"] == 0.5

    # Seed rows in their old places, with both seeds' success; the others untouched.
    assert [(r["experiment"], r["policy"]) for r in data["seeds"]] == [
        ("performance", "ref"),
        ("performance", "pips"),
        ("transfer", "pips"),
        ("lfd", "bc"),
        ("lfd", "pips"),
    ]
    expected = ";".join(f"{100 * _rate(bench, spec, 'gdc1'):.2f}" for spec in SPECS.values())
    assert data["seeds"][1]["seed_success_pct"] == expected
    assert lines(base / "results" / "seeds.csv")[4] == before["seeds.csv"][4]
    improvement = {(r["experiment"], r["x"], r["y"]): r["probability"] for r in data["improvement"]}
    assert improvement[("performance", "bc", "gail")] == 0.5
    assert 0.0 <= improvement[("performance", "pips", "ref")] <= 1.0
    profiles = [r for r in data["profiles"] if r["policy"] == "pips"]
    assert len(profiles) > 2 and {r["experiment"] for r in profiles} == {"performance", "transfer", "lfd"}

    assert [t["run"] for t in data["training"]] == ["lfd/bc_3500", "pips-s0", "pips-s1"]
    assert data["run"]["reruns"][0]["commit"] == "abc1234"


def test_a_rerun_must_match_the_published_seeds_and_ref(tmp_path, bench):
    base = published(tmp_path / "a", bench)
    with pytest.raises(RerunError, match=r"seeds \[0, 1\]"):
        replace_policy_rows(base, rerun(bench, seed_specs={0: "pips"}))
    with pytest.raises(RerunError, match="no trials of bc"):
        replace_policy_rows(base, rerun(bench, seed_specs={0: "pips", 1: "bc"}))
    one_more = _rate(bench, "ref", "gdc1") + 1 / TRIALS  # the published Ref won one more scenario
    wrong = published(tmp_path / "b", bench, ref_success=one_more)
    with pytest.raises(RerunError, match="not the published evaluation"):
        replace_policy_rows(wrong, rerun(bench))
    replace_policy_rows(wrong, rerun(bench, ref_tolerance=1))  # within the tolerance it goes in
    wins = round(_rate(bench, "ref", "gdc1") * TRIALS)
    assert load(wrong / "results")["run"]["reruns"][0]["ref_successes"]["gdc1"] == {
        "rerun": wins,
        "published": wins + 1,
        "trials": TRIALS,
    }
    assert benchmark_scores(bench, "pips")  # the folder is a real benchmark run


def test_the_report_names_the_rerun(tmp_path):
    import shutil
    from pathlib import Path

    from socialzoo.reproduce.publish import regenerate_report

    shutil.copytree(Path(__file__).parents[2] / "results" / "reproduction" / "results", tmp_path / "results")
    run_file = tmp_path / "results" / "run.json"
    run = json.loads(run_file.read_text())
    run["reruns"] = [
        {"policy": "pips", "commit": "abc1234", "commands": ["socialzoo train pips"], "why": "New."}
    ]
    run_file.write_text(json.dumps(run))
    report = regenerate_report(tmp_path)
    assert "## Rows re-run after the full run" in report
    assert "- PIPS: New. At commit `abc1234`: `socialzoo train pips`." in report
    # The published kernel-path measurement (tools/kernel_paths.py --csv) closes the re-run section.
    section = report[report.index("## What a re-run may differ by") :]
    assert "| again | as installed |" in section and "| threads-2 | --threads 2 |" in section


def test_reference_rows_of_a_later_run_replace_the_published_ones(tmp_path):
    from socialzoo.reproduce.rerun_rows import replace_reference_rows

    def folder(name, settings_hash, reference, training, timing):
        results = tmp_path / name / "results"
        results.mkdir(parents=True)
        (results / "run.json").write_text(json.dumps({"settings_hash": settings_hash}))
        (results / "reference.csv").write_text(reference)
        (results / "training.json").write_text(json.dumps(training))
        (results / "timings.json").write_text(json.dumps(timing))
        return results

    published = folder(
        "published", "abc",
        "experiment,policy,seed\r\nperformance,dqn,0\r\n",
        [{"run": "rl/dqn", "trainer": "dqn"}, {"run": "reference/rl/dqn", "trainer": "dqn", "old": True}],
        {"performance": {"seconds": 1.0}, "reference": {"seconds": 2.0}},
    )  # fmt: skip
    later_csv = (
        "quirks,experiment,policy,seed\r\nall,performance,dqn,0\r\ngoal_distance_x_only,performance,dqn,0\r\n"
    )
    later_training = [
        {"run": "rl/ppo", "trainer": "ppo"},  # the default run trained again in the reference's work folder
        {"run": "reference/rl/dqn", "trainer": "dqn"},
        {"run": "reference/alone/goal_distance_x_only/rl/dqn", "trainer": "dqn"},
    ]
    later = folder("later", "abc", later_csv, later_training, {"reference": {"seconds": 9.0}})
    replace_reference_rows(published.parent, later)
    assert (published / "reference.csv").read_bytes() == later_csv.encode()
    training = json.loads((published / "training.json").read_text())
    assert training == [{"run": "rl/dqn", "trainer": "dqn"}, *later_training[1:]]
    timings = json.loads((published / "timings.json").read_text())
    assert timings == {"performance": {"seconds": 1.0}, "reference": {"seconds": 9.0}}
    other = folder("other", "xyz", later_csv, later_training, {"reference": {}})
    with pytest.raises(RerunError, match="settings xyz, the published run's are abc"):
        replace_reference_rows(published.parent, other)
    with pytest.raises(RerunError, match="no reference rows"):
        replace_reference_rows(published.parent, tmp_path)


def test_redraw_published_draws_the_committed_report_again(tmp_path):
    """After rows are replaced, the tables, figures and report are drawn again from the published
    results alone: on the committed results that gives the committed REPRODUCTION.md."""
    import shutil
    from pathlib import Path

    from socialzoo.reproduce.publish import PUBLISHED_DIR, redraw_published

    root = Path(__file__).resolve().parents[2]
    shutil.copytree(root / PUBLISHED_DIR / "results", tmp_path / PUBLISHED_DIR / "results")
    report = redraw_published(tmp_path)
    assert report.read_text() == (root / "REPRODUCTION.md").read_text()
    assert (tmp_path / PUBLISHED_DIR / "figures" / "success.png").stat().st_size > 1000
    assert (tmp_path / PUBLISHED_DIR / "tables" / "performance.md").is_file()
