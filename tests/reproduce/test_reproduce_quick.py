"""`socialzoo reproduce --quick` end to end (one shared run), its report, the notebook, and the
committed REPRODUCTION.md against its committed results."""

import json
from pathlib import Path

import pytest

from socialzoo.bench.store import ResultsStore
from socialzoo.cli import main
from socialzoo.reproduce.paper import PAPER_POLICIES, PAPER_SUCCESS
from socialzoo.reproduce.plan import PARTS, quick_settings, settings_hash
from socialzoo.reproduce.publish import PUBLISHED_DIR, publish, regenerate_report
from socialzoo.reproduce.results import load

ROOT = Path(__file__).resolve().parents[2]
FIGURES = ("success", "metrics", "rl_curves", "lfd")
TABLES = ("performance", "transfer", "lfd", "rl_curves")


def test_quick_run_writes_every_table_figure_and_the_report(quick_run):
    for name in FIGURES:
        for fmt in ("png", "pdf"):
            assert (quick_run / "figures" / f"{name}.{fmt}").stat().st_size > 1000
    for name in TABLES:
        assert (quick_run / "tables" / f"{name}.md").is_file() and (
            quick_run / "tables" / f"{name}.csv"
        ).is_file()
    text = (quick_run / "REPRODUCTION.md").read_text()
    assert "socialzoo reproduce --out DIR --quick" in text and "--quick` settings" in text
    results = load(quick_run / "results")
    assert set(results["timings"]) == set(PARTS) and all(t["finished"] for t in results["timings"].values())
    for part in PARTS:
        assert f"| {part} |" in text
    assert [r["policy"] for r in results["performance"]] == list(PAPER_POLICIES)


def test_report_numbers_come_from_the_stored_trials(quick_run):
    work = quick_run / settings_hash(quick_settings())
    results = load(quick_run / "results")
    for experiment, index in (("performance", 0), ("transfer", 1)):
        with ResultsStore(work / experiment / "results.sqlite") as store:
            trials = store.rows()
        table = (quick_run / "tables" / f"{experiment}.md").read_text()
        for row in results[experiment]:
            mine = [t for t in trials if t["policy"] == row["policy"]]
            assert len(mine) == row["trials"] == quick_settings().performance_trials
            assert row["success_rate"] == pytest.approx(sum(bool(t["success"]) for t in mine) / len(mine))
            assert f"| {100 * row['success_rate']:.1f} [" in table
            assert f"| {PAPER_SUCCESS[row['policy']][index]:.1f} |" in table
    # The report is a function of the results folder alone.
    assert regenerate_report(quick_run) == (quick_run / "REPRODUCTION.md").read_text()


def test_rerun_repeats_nothing(quick_run, capsys):
    work = quick_run / settings_hash(quick_settings())
    sizes = {}
    for store_path in sorted(work.rglob("*.sqlite")):
        with ResultsStore(store_path) as store:
            sizes[store_path] = len(store)
    assert (
        main(["reproduce", "--out", str(quick_run), "--quick", "--no-progress", "--only", "lfd,performance"])
        == 0
    )
    out = capsys.readouterr().out
    assert "lfd done (0 items made)" in out and "performance done (0 items made)" in out
    for store_path, size in sizes.items():
        with ResultsStore(store_path) as store:
            assert len(store) == size


def test_bad_only_names_the_part(tmp_path, capsys):
    assert main(["reproduce", "--out", str(tmp_path), "--only", "rl,lfd"]) == 2
    err = capsys.readouterr().err
    assert "'rl'" in err and "rl-curves" in err
    assert not any(tmp_path.iterdir())


def test_bad_reference_quirk_names_it(tmp_path, capsys):
    assert main(["reproduce", "--out", str(tmp_path), "--reference", "x_only"]) == 2
    err = capsys.readouterr().err
    assert "--reference" in err and "'x_only'" in err and "goal_distance_x_only" in err
    assert not any(tmp_path.iterdir())


def test_publish_writes_a_report_that_regenerates(quick_run, tmp_path):
    report = publish(quick_run, tmp_path)
    text = report.read_text()
    assert f"]({PUBLISHED_DIR}/figures/success.png)" in text
    assert (tmp_path / PUBLISHED_DIR / "results" / "run.json").is_file()
    assert regenerate_report(tmp_path / PUBLISHED_DIR, PUBLISHED_DIR + "/") == text


def test_committed_reproduction_matches_its_results():
    """The committed REPRODUCTION.md is regenerated exactly from the committed results."""
    published = ROOT / PUBLISHED_DIR
    if not (published / "results" / "run.json").is_file():
        pytest.skip("no published reproduction in this checkout")
    assert regenerate_report(published, PUBLISHED_DIR + "/") == (ROOT / "REPRODUCTION.md").read_text()


def test_notebook_draws_the_quick_results(quick_run, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    monkeypatch.setenv("SOCIALZOO_REPRODUCTION_DIR", str(quick_run))
    path = ROOT / "notebooks" / "reproduce_paper.ipynb"
    cells = json.loads(path.read_text())["cells"]
    assert all(not c.get("outputs") for c in cells if c["cell_type"] == "code")  # stripped
    namespace: dict = {}
    for cell in cells:
        if cell["cell_type"] == "code":
            exec(compile("".join(cell["source"]), path.name, "exec"), namespace)
    assert namespace["DIR"] == quick_run
    assert set(namespace["drawn"]) == set(FIGURES) and set(namespace["tables"]) == set(TABLES)


def test_a_damaged_run_record_is_named_in_one_line(tmp_path, capsys):
    # Found truncating a PPO run's run.json in a work folder: the rerun ended in a RunDirError
    # traceback (exit status 1) where a damaged timings or settings file is one line (exit status 2).
    from socialzoo.reproduce.plan import quick_settings, settings_hash

    record = tmp_path / settings_hash(quick_settings()) / "rl" / "ppo" / "run.json"
    record.parent.mkdir(parents=True)
    record.write_text('{"trunc')
    assert main(["reproduce", "--out", str(tmp_path), "--quick", "--only", "rl-curves", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("socialzoo reproduce: error: ") and f"{record}: not a run record" in err
    assert len(err.splitlines()) == 1
