"""Confidence intervals on known numbers, and the summary CSV / Markdown / figures."""

import itertools
import math

import numpy as np
import pytest

from socialzoo.bench.stats import mean_interval, rate_interval, student_t_cdf, student_t_ppf
from socialzoo.bench.tables import (
    PAPER_LAYOUT,
    policy_labels,
    read_summary_csv,
    summarize,
    summary_markdown,
    write_summary_csv,
)


@pytest.mark.parametrize(
    ("q", "df", "expected"),
    [
        (0.95, 1, 6.313751514675037),  # scipy.stats.t.ppf
        (0.95, 4, 2.1318467863266495),
        (0.95, 29, 1.6991270265334972),
        (0.975, 10, 2.228138851986274),
        (0.95, 1999, 1.6456162481872625),
    ],
)
def test_t_quantiles(q, df, expected):
    assert student_t_ppf(q, df) == pytest.approx(expected, abs=1e-9)
    assert student_t_ppf(1 - q, df) == pytest.approx(-expected, abs=1e-9)
    assert student_t_cdf(expected, df) == pytest.approx(q, abs=1e-12)


def test_mean_interval_known_numbers():
    # mean 3, sample sd sqrt(2.5), n 5: half-width t(0.95, 4) * sqrt(2.5 / 5).
    ci = mean_interval([1.0, 2.0, 3.0, 4.0, 5.0])
    half = 2.1318467863266495 * math.sqrt(0.5)
    assert (ci.value, ci.n) == (3.0, 5)
    assert ci.low == pytest.approx(3.0 - half, abs=1e-12)
    assert ci.high == pytest.approx(3.0 + half, abs=1e-12)
    # NaN values are left out; one value has no interval; none has no mean.
    assert mean_interval([1.0, np.nan, 5.0]).n == 2
    one = mean_interval([2.0])
    assert one.value == 2.0 and math.isnan(one.low) and math.isnan(one.high)
    assert math.isnan(mean_interval([]).value)
    flat = mean_interval([0.5] * 4)
    assert flat.low == flat.high == 0.5
    wider = mean_interval([1.0, 2.0, 3.0, 4.0, 5.0], confidence=0.95)
    assert wider.low < ci.low


def test_wilson_interval_known_numbers():
    ci = rate_interval(89, 100)  # scipy.stats.binomtest(89, 100).proportion_ci(0.9, "wilson")
    assert ci.value == 0.89
    assert ci.low == pytest.approx(0.8279141735549224, abs=1e-12)
    assert ci.high == pytest.approx(0.9315385042342016, abs=1e-12)
    full = rate_interval(100, 100)
    assert full.high == 1.0 and full.low == pytest.approx(0.9736572792168257, abs=1e-12)
    assert rate_interval(0, 10).low == 0.0
    assert math.isnan(rate_interval(0, 0).value)
    with pytest.raises(ValueError, match="successes"):
        rate_interval(5, 3)
    with pytest.raises(ValueError, match="confidence"):
        rate_interval(1, 3, confidence=1.5)


def rows_for(policy, map_name, successes, n):
    rows = []
    for i in range(n):
        ok = i < successes
        rows.append(
            {
                "policy": policy,
                "map": map_name,
                "test_set": f"{map_name}-quick",
                "success": ok,
                "time_to_goal": 10.0 + i if ok else (50.0 if i % 2 else math.nan),
                "mean_force": 0.1 * (i % 3),
                "mean_blame": 0.2,
                "human_collisions": 0,
                "min_human_distance": math.nan if i == 0 else 1.0,
            }
        )
    return rows


def test_summary_rows_and_csv(tmp_path):
    rows = rows_for("ref", "ghc3", 3, 4) + rows_for("goalone", "gdc1", 4, 5) + rows_for("ref", "gdc1", 2, 4)
    summary = summarize(rows, policies=["goalone", "ref"], maps=["gdc1", "ghc3"])
    assert [(e["policy"], e["map"], e["trials"]) for e in summary] == [
        ("goalone", "gdc1", 5),
        ("ref", "gdc1", 4),
        ("ref", "ghc3", 4),
    ]
    ref_gdc1 = summary[1]
    assert ref_gdc1["success_rate"] == 0.5
    # Time to goal over successful episodes only (10 and 11), never the failures' 50.
    assert ref_gdc1["time_to_goal_mean"] == 10.5 and ref_gdc1["time_to_goal_n"] == 2
    assert ref_gdc1["mean_force_mean"] == pytest.approx(np.mean([0.0, 0.1, 0.2, 0.0]))
    assert ref_gdc1["min_human_distance_mean"] == 1.0  # the NaN is left out
    assert math.isnan(ref_gdc1["jerk_mean"])  # a metric the rows lack

    path = write_summary_csv(summary, tmp_path / "summary.csv")
    header = path.read_text().splitlines()[0].split(",")
    assert header == PAPER_LAYOUT.csv_columns()
    assert header[:7] == [
        "policy",
        "map",
        "test_set",
        "trials",
        "success_rate",
        "success_ci_low",
        "success_ci_high",
    ]
    for metric in ("mean_force", "mean_blame", "time_to_goal", "personal_space_intrusion_time"):
        assert {f"{metric}_mean", f"{metric}_ci_low", f"{metric}_ci_high"} <= set(header)
    back = read_summary_csv(path)
    assert back[1]["success_rate"] == 0.5 and back[1]["trials"] == 4
    assert back[0]["success_ci_low"] == summary[0]["success_ci_low"]  # floats round-trip exactly
    assert math.isnan(back[1]["jerk_mean"])


def test_markdown_has_the_paper_table(tmp_path):
    summary = summarize(rows_for("goalone", "gdc1", 9, 10) + rows_for("goalone", "ghc3", 8, 10))
    text = summary_markdown(summary)
    assert "| policy | test (gdc1) | paper test | transfer (ghc3) | paper transfer |" in text
    line = next(x for x in text.splitlines() if x.startswith("| GoAlone") and "97.5" in x)
    assert "90.0 [" in line and "97.3" in line
    assert "successful episodes only" in text
    assert "(n=9)" in text


def test_count_metrics_get_intervals_that_stay_at_or_above_zero(tmp_path):
    rows = rows_for("ref", "gdc1", 50, 100)
    for i, row in enumerate(rows):
        row["human_collisions"] = (5, 2, 1)[i] if i < 3 else 0  # the 0.08 [-0.02, 0.18]
        row["wall_collisions"] = 0
    (entry,) = summarize(rows)
    assert entry["human_collisions_mean"] == 0.08
    assert 0.0 <= entry["human_collisions_ci_low"] < 0.08 < entry["human_collisions_ci_high"]
    assert entry["wall_collisions_ci_low"] == 0.0
    assert entry["wall_collisions_ci_high"] == pytest.approx(-math.log(0.05) / 100)
    # Other means keep their Student-t interval.
    assert entry["mean_force_ci_low"] == mean_interval([r["mean_force"] for r in rows]).low
    # Seeded per cell: the same numbers again, and when another policy joins the table.
    again = summarize(rows + rows_for("goalone", "gdc1", 9, 10))[0]
    for key in ("human_collisions_ci_low", "human_collisions_ci_high"):
        assert again[key] == entry[key]
    assert summarize(rows, seed=1)[0]["human_collisions_ci_high"] != entry["human_collisions_ci_high"]
    text = summary_markdown([entry])
    footer = text[text.index("## Intervals") :]
    assert "Wilson" in footer and "Student-t" in footer
    assert "human collision steps, wall collision steps): bias-corrected and accelerated (BCa)" in footer
    assert "0.08 [0.0" in text


def test_figures_are_written(tmp_path):
    pytest.importorskip("matplotlib")
    from socialzoo.bench.figures import plot_summary

    summary = summarize(
        rows_for("goalone", "gdc1", 9, 10) + rows_for("ref", "gdc1", 7, 10) + rows_for("ref", "ghc3", 6, 10)
    )
    files = plot_summary(summary, tmp_path)
    assert sorted(p.name for p in files) == [
        "failures.pdf", "failures.png", "metrics.pdf", "metrics.png", "success.pdf", "success.png",
    ]  # fmt: skip
    assert all(p.stat().st_size > 1000 for p in files)


def test_figures_keep_their_text_apart_and_inside(monkeypatch):
    """Learned policies' labels (with their file names) overran each other under the bars, and a
    map's name over a bar of 100% failures ran out of the axes into the title. One policy that
    never succeeds (time to goal NaN) and a single trial draw too."""
    pytest.importorskip("matplotlib")
    from socialzoo.bench import figures

    figs = {}

    def keep(fig, out_dir, stem, formats=(), dpi=150):
        figs[stem] = fig
        return []

    monkeypatch.setattr(figures, "save_figure", keep)
    policies = [
        "ppo:runs/a/final_model.safetensors",
        "dagger:runs/b/dagger_policy.safetensors",
        "goalone",
        "ref",
    ]
    rows = [
        r
        for p in policies
        for m in ("gdc1", "imported_building")
        for r in rows_for(p, m, 0 if p == "goalone" else 1, 1)
    ]
    figures.plot_summary(summarize(rows), "unused")
    for stem, fig in figs.items():
        renderer = fig.canvas.get_renderer()
        for ax in fig.axes:
            ticks = [t.get_window_extent(renderer) for t in ax.get_xticklabels() if t.get_text()]
            for left, right in itertools.pairwise(ticks):
                assert left.x1 < right.x0, f"{stem}: tick labels overlap"
            frame = ax.get_window_extent(renderer)
            for text in ax.texts:
                box = text.get_window_extent(renderer)
                assert frame.y0 - 1 <= box.y0 and box.y1 <= frame.y1 + 1, (
                    f"{stem}: {text.get_text()} out of the axes"
                )
        figures.pyplot().close(fig)


def test_failures_by_cause_in_the_summary_and_markdown():
    rows = [{**r, "stuck": False} for r in rows_for("goalone", "gdc1", 6, 10)]
    # Failed episodes 6..9: a wall (with a human contact too: the wall comes first), a human
    # collision, one stuck, one timeout while moving; a stuck episode that succeeded counts as one.
    rows[6].update(wall_collisions=1, human_collisions=2)
    rows[7].update(human_collisions=3, stuck=True)
    rows[8].update(stuck=True)
    rows[0].update(stuck=True)
    summary = summarize(rows)
    e = summary[0]
    shares = {c: e[f"failure_{c}_rate"] for c in ("wall_collision", "human_collision", "stuck", "timeout")}
    assert shares == {"wall_collision": 0.1, "human_collision": 0.1, "stuck": 0.1, "timeout": 0.1}
    assert e["failure_stuck_ci_low"] < 0.1 < e["failure_stuck_ci_high"]
    assert e["stuck_mean"] == pytest.approx(0.3)  # the stuck metric over every episode
    assert {f"failure_{c}_rate" for c in shares} <= set(PAPER_LAYOUT.csv_columns())
    text = summary_markdown(summary)
    assert "## Failures by cause (% of episodes)" in text
    assert "| GoAlone | gdc1 | 60.0 | 10.0 | 10.0 | 10.0 | 10.0 |" in text


def test_files_of_one_name_get_labels_that_tell_them_apart():
    one, two = "dagger:/runs/s1/dagger.safetensors", "dagger:runs/s2/dagger.safetensors"
    labels = policy_labels(["ref", one, two, "bc:a.safetensors"])
    assert labels == {
        "ref": "Ref",
        one: "DAgger (s1/dagger.safetensors)",
        two: "DAgger (s2/dagger.safetensors)",
        "bc:a.safetensors": "BC (a.safetensors)",
    }
    assert policy_labels(["dagger:x/a/p.safetensors", "dagger:y/a/p.safetensors"]) == {
        "dagger:x/a/p.safetensors": "DAgger (x/a/p.safetensors)",
        "dagger:y/a/p.safetensors": "DAgger (y/a/p.safetensors)",
    }
    # In the summary every table row names its file.
    text = summary_markdown(summarize(rows_for(one, "gdc1", 8, 10) + rows_for(two, "gdc1", 6, 10)))
    assert (
        text.count("| DAgger (s1/dagger.safetensors) |")
        == text.count("| DAgger (s2/dagger.safetensors) |")
        > 3
    )


def test_one_writer_writes_a_task_ids_tables_in_its_layout(tmp_path):
    from socialzoo.bench.tables import read_summary_csv, task_layout, write_tables
    from socialzoo.bench.task_benchmark import summarize as summarize_task
    from socialzoo.bench.task_benchmark import table_entry

    episodes = [
        {
            "success": float(i < 3),
            "collision": float(i >= 3),
            "navigation_time": 9.0 + i if i < 3 else math.nan,
        }
        for i in range(5)
    ]
    entry = table_entry("orca", "CrowdNav-v1", "crowdnav-test", summarize_task(episodes))
    layout = task_layout([entry])
    assert layout.metrics == ("success", "collision", "navigation_time") and not layout.paper
    csv_path, md_path = write_tables([entry], tmp_path, name="crowdnav", title="t", layout=layout)
    (back,) = read_summary_csv(csv_path)  # the summary's columns, read by the same reader
    assert back["trials"] == 5 and back["success_rate"] == 0.6 and back["collision_mean"] == 0.4
    assert back["navigation_time_mean"] == 10.0 and back["success_ci_low"] < 0.6 < back["success_ci_high"]
    lines = md_path.read_text().splitlines()
    assert lines[:3] == ["t", "", "| policy | success (rate) | collision (rate) | navigation time, s |"]
    assert lines[4].startswith("| orca | 0.600 [0.") and lines[4].endswith("| 0.400 | 10.00 |")
