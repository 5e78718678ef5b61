"""The seeds study: aggregates per group, probability of improvement, profiles, and the trials of
a benchmark folder by policy."""

import math

import pytest

from socialzoo.studies.seeds import (
    SeedGroup,
    benchmark_scores,
    improvement_rows,
    plot_profiles,
    profile_rows,
    seed_rows,
    write_seed_study,
)


def groups():
    ppo = SeedGroup(
        "performance",
        "ppo",
        "gdc1",
        None,
        (0, 1, 2),
        ({0: 1, 1: 0, 2: 1, 3: 1}, {0: 0, 1: 0, 2: 1, 3: 0}, {0: 1, 1: 1, 2: 1, 3: 0}),
        55.1,
    )
    ref = SeedGroup("performance", "ref", "gdc1", None, (0,), ({0: 1, 1: 1, 2: 1, 3: 0},), 89.4)
    return [ppo, ref]


def test_seed_rows_aggregate_and_place_the_paper():
    rows = seed_rows(groups(), resamples=500)
    ppo = rows[0]
    assert ppo["seed_success_pct"] == "75.00;25.00;75.00" and ppo["seeds"] == 3 and ppo["scenarios"] == 4
    assert ppo["mean_pct"] == pytest.approx(175 / 3)
    assert ppo["iqm_pct"] == pytest.approx(175 / 3)  # 3 seeds: nothing trimmed (int(0.75) = 0)
    assert ppo["mean_ci_low_pct"] <= ppo["mean_pct"] <= ppo["mean_ci_high_pct"]
    assert ppo["paper_where"] == "inside the seeds' range (1 of 3 below it)"
    assert rows[1]["paper_where"] == "above our run"
    assert seed_rows(groups(), resamples=500) == rows  # seeded per cell


def test_improvement_and_profiles():
    rows = improvement_rows(groups(), [("ppo", "ref"), ("ppo", "dqn")], resamples=300)
    assert len(rows) == 1 and rows[0]["x"] == "ppo" and rows[0]["y"] == "ref"
    # PPO seeds 75, 25, 75 against Ref's 75: two ties and a loss -> (0.5 + 0 + 0.5) / 3.
    assert rows[0]["probability"] == pytest.approx(1 / 3)
    profile = profile_rows(groups(), (0.5,), resamples=200)
    assert [(r["policy"], r["share"]) for r in profile] == [("ppo", pytest.approx(2 / 3)), ("ref", 1.0)]


def test_write_seed_study_and_figure(tmp_path):
    files = write_seed_study(groups(), [("ppo", "ref")], tmp_path, resamples=200)
    assert [f.name for f in files] == ["seeds.csv", "improvement.csv", "profiles.csv"]
    assert write_seed_study([], [], tmp_path) == [] and not (tmp_path / "seeds.csv").exists()
    pytest.importorskip("matplotlib")
    rows = profile_rows(groups(), resamples=100)
    for r in rows:
        r["demonstration_steps"] = math.nan  # as read back from the CSV
    assert [p.name for p in plot_profiles(rows, tmp_path)] == ["profiles.png", "profiles.pdf"]


def test_benchmark_scores_reads_a_benchmark_folder(tmp_path):
    from socialzoo.bench.experiment import BenchmarkConfig, run_benchmark

    config = BenchmarkConfig(
        policies=("goalone",),
        maps=("gdc1",),
        trials=2,
        quick=True,
        workers=1,
        env_overrides={"max_steps": 60},
    )
    run_benchmark(config, tmp_path, progress=False, figures=False)
    scores = benchmark_scores(tmp_path, "goalone")
    assert sorted(scores) == [0, 1] and set(scores.values()) <= {0.0, 1.0}
    with pytest.raises(KeyError, match="ref"):
        benchmark_scores(tmp_path, "ref")
