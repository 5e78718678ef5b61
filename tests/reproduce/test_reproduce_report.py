"""The report's tables and differences from a synthetic results folder (no training)."""

import json
import math

import pytest

from socialzoo.reproduce.paper import PAPER_LFD_ALL, PAPER_SUCCESS
from socialzoo.reproduce.plan import full_settings
from socialzoo.reproduce.report import EXPLANATIONS, render_reproduction
from socialzoo.reproduce.results import load, write_csv
from socialzoo.reproduce.tables import build_tables, outside


def _summary_row(policy, rate, low, high, trials=2000):
    return {
        "policy": policy,
        "map": "gdc1",
        "test_set": "gdc1-test",
        "trials": trials,
        "success_rate": rate,
        "success_ci_low": low,
        "success_ci_high": high,
        **{
            f"{m}_{k}": v
            for m in ("mean_force", "mean_blame", "time_to_goal", "average_step_reward")
            for k, v in (("mean", 0.5), ("ci_low", 0.4), ("ci_high", 0.6))
        },
    }


@pytest.fixture
def results_dir(tmp_path):
    folder = tmp_path / "results"
    folder.mkdir()
    run = {
        "settings": full_settings().to_json(),
        "settings_hash": "abc",
        "command": "socialzoo reproduce --out DIR",
        "machine": {"cpus": 2, "platform": "test", "python": "3"},
        "demo_steps": 160_000,
    }
    (folder / "run.json").write_text(json.dumps(run))
    (folder / "timings.json").write_text(
        json.dumps(
            {"demos": {"sessions": [{"seconds": 60.0, "finished": True}], "seconds": 60.0, "finished": True}}
        )
    )
    # GoAlone's interval holds the paper's 97.5; Ref's (50-60%) does not hold 89.4.
    write_csv(
        [_summary_row("goalone", 0.97, 0.96, 0.98), _summary_row("ref", 0.55, 0.5, 0.6)],
        folder / "performance.csv",
    )
    lfd = [
        {
            "policy": "pips",
            "demonstration_steps": 3500,
            "trials": 100,
            "success_rate": 0.88,
            "success_ci_low": 0.82,
            "success_ci_high": 0.92,
            "average_step_reward": 0.1,
            "paper_success_pct": 88.0,
            "paper_average_step_reward": 0.16,
        },
    ]
    write_csv(lfd, folder / "lfd.csv")
    return folder


def test_outside():
    assert outside(89.4, 50.0, 60.0) and not outside(55.0, 50.0, 60.0)
    assert not outside(None, 0.0, 1.0) and not outside(1.0, math.nan, 2.0)


def test_tables_put_ours_beside_the_papers(results_dir):
    tables = build_tables(load(results_dir))
    assert set(tables) == {"performance", "lfd"}
    rows, markdown = tables["performance"]
    assert [(r["policy"], r["differs"]) for r in rows] == [("goalone", False), ("ref", True)]
    assert f"| 55.0 [50.0, 60.0] | {PAPER_SUCCESS['ref'][0]:.1f} |" in markdown
    lfd_rows, lfd_md = tables["lfd"]
    assert lfd_rows[0]["paper_success_pct"] == PAPER_LFD_ALL[("pips", 3500)][0] and not lfd_rows[0]["differs"]
    assert "| PIPS | 3,500 | 100 | 88.0 [82.0, 92.0] | 88 |" in lfd_md


def test_report_explains_each_difference_and_marks_missing_parts(results_dir):
    text = render_reproduction(load(results_dir), "published/")
    differences = text.split("## Where we differ")[1]
    assert "performance (gdc1), Ref: ours 55.0% [50.0, 60.0], paper 89.4%." in differences
    assert EXPLANATIONS["ref"] in differences and "- performance (gdc1), GoAlone" not in differences
    assert "| demos | Ref demonstrations | 1 min 00 s | 1 | yes |" in text
    assert (
        "| transfer | transfer on ghc3-test (trains what is missing) | no session recorded | 0 | no |" in text
    )
    assert "| demo steps | 160,000 (125 episodes) | 155,000 |" in text
    assert "](published/figures/success.png)" in text and "*Not run yet.*" in text


def test_load_refuses_a_folder_without_a_run_record(tmp_path):
    with pytest.raises(FileNotFoundError, match="not the results of `socialzoo reproduce`"):
        load(tmp_path)


def test_a_paper_number_outside_the_seeds_range_is_explained(results_dir):
    """GoAlone's paper number is inside its one run's interval, but below every one of 5 seeds:
    "Where we differ" lists it with the seeds' spread; a paper number inside the range is not."""
    from socialzoo.reproduce.report import _differences
    from socialzoo.reproduce.seed_report import paper_outside_seeds

    def row(low, high, paper=97.5):
        return {"experiment": "performance", "policy": "goalone", "seeds": 5, "min_pct": low,
                "max_pct": high, "mean_pct": (low + high) / 2, "mean_ci_low_pct": low,
                "mean_ci_high_pct": high, "paper_pct": paper, "paper_where": "below all 5 seeds"}  # fmt: skip

    assert paper_outside_seeds([row(98.0, 99.0)], "performance", "goalone")
    assert not paper_outside_seeds([row(96.0, 99.0)], "performance", "goalone")
    assert not paper_outside_seeds([row(98.0, 99.0, math.nan)], "performance", "goalone")
    tables = build_tables(load(results_dir))
    listed = "\n".join(_differences(tables, [row(98.0, 99.0)]))
    assert "- performance (gdc1), GoAlone" in listed and "the paper's number is below all 5 seeds" in listed
    assert "- performance (gdc1), GoAlone" not in "\n".join(_differences(tables, [row(96.0, 99.0)]))


def test_a_report_shows_no_table_or_figure_of_an_earlier_run_in_its_folder(results_dir, tmp_path):
    """A rerun into a DIR that held a run of other settings (--seeds 2, then --quick --seeds 3 --only
    demos) kept that run's tables and figures: the report linked its figures, and --publish copied
    them into the repository beside a report saying "Not run yet"."""
    from socialzoo.reproduce.publish import regenerate_report
    from socialzoo.reproduce.report import write_report

    base = results_dir.parent
    (base / "figures").mkdir()
    (base / "tables").mkdir()
    for name in ("rl_curves", "profiles"):  # results_dir has neither curves nor several seeds
        for suffix in ("png", "pdf"):
            (base / "figures" / f"{name}.{suffix}").write_bytes(b"an earlier run's figure")
    for name in ("rl_curves", "transfer"):
        for suffix in ("csv", "md"):
            (base / "tables" / f"{name}.{suffix}").write_text("an earlier run's table")
    between_parts = write_report(base, figures=False).read_text()
    assert "figures/rl_curves.png" not in between_parts and "figures/profiles.png" not in between_parts
    assert "figures/rl_curves.png" not in regenerate_report(base, "published/")
    assert sorted(p.name for p in (base / "tables").iterdir()) == [
        "lfd.csv",
        "lfd.md",
        "performance.csv",
        "performance.md",
    ]
    text = write_report(base).read_text()
    assert sorted(p.stem for p in (base / "figures").glob("*.png")) == ["lfd", "metrics", "success"]
    assert "figures/success.png" in text and "figures/rl_curves.png" not in text
