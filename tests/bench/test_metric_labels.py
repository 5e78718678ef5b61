"""The harness reads each metric's label, unit, flags, digits and kind from the metric registry
(socialzoo.core.metrics): the tables, the figures, the humans' tables and the results store."""

import math
import re

import pytest

from socialzoo.bench import figures, human_metrics, tables
from socialzoo.bench.store import ResultsStore
from socialzoo.core.metrics import METRICS, axis_label, metric, names, table_heading


def _rows(n=6):
    rows = []
    for i in range(n):
        row = {"policy": "ref", "map": "gdc1", "test_set": "gdc1-test"}
        for name in names("action_selection"):
            kind = metric(name).kind
            row[name] = (i % 2 == 0) if kind == "bool" else i if kind == "int" else 0.1 * i + 0.123456
        rows.append(row)
    return rows


def test_tables_take_headings_and_flags_from_the_registry():
    for name, heading in tables.TABLE_METRICS:
        assert heading == table_heading(name)
    table_names = [n for n, _ in tables.TABLE_METRICS]
    assert tables.SUCCESS_ONLY == tuple(n for n in table_names if metric(n).success_only) == ("time_to_goal",)
    assert tables.COUNT_METRICS == tuple(n for n in table_names if metric(n).count)
    assert tables.COUNT_METRICS == ("human_collisions", "wall_collisions")


def test_summary_markdown_prints_registry_headings_and_digits():
    text = tables.summary_markdown(tables.summarize(_rows()))
    for name, heading in tables.TABLE_METRICS:
        section = text.split(f"## {heading[0].upper() + heading[1:]}\n", 1)[1].split("\n## ", 1)[0]
        cell = section.splitlines()[3].split(" | ")[1]
        mean = cell.split(" ")[0]
        assert mean == "n/a" or len(mean.split(".")[1]) == metric(name).digits, (name, cell)


def test_figures_take_axis_labels_from_the_registry(tmp_path, monkeypatch):
    pytest.importorskip("matplotlib")
    assert figures.METRIC_PANELS == tuple((n, axis_label(n)) for n, _ in figures.METRIC_PANELS)
    seen = []
    monkeypatch.setattr(
        figures, "save_figure", lambda fig, *a: seen.extend(ax.get_ylabel() for ax in fig.axes) or []
    )
    figures.plot_metrics(tables.summarize(_rows()), tmp_path)
    assert seen == [axis_label(n) for n, _ in figures.METRIC_PANELS]
    assert seen[2] == "time to goal, s (successes)"


def test_humans_tables_take_headings_digits_and_counts_from_the_registry():
    assert human_metrics.HUMAN_METRIC_KEYS == names("humans")
    for key, (label, digits) in human_metrics.HUMAN_METRIC_LABELS.items():
        assert (label, digits) == (metric(key).heading, metric(key).digits)
    assert human_metrics._COUNT_KEYS == tuple(k for k in names("humans") if metric(k).count)


def test_store_columns_take_the_registered_kind(tmp_path):
    # The CrowdNav task reports flags and counts as floats: the columns still hold a flag and a count.
    with ResultsStore(tmp_path / "r.sqlite") as store:
        store.add(
            [
                {
                    "policy": "p",
                    "map": "m",
                    "test_set": "t",
                    "scenario_index": 0,
                    "seed": 1,
                    "config_hash": "h",
                    "package_version": "0",
                    "metrics": {"success": 1.0, "steps": 12.0, "navigation_time": math.nan, "mine": 2},
                }
            ]
        )
        row = store.rows()[0]
        assert row["success"] is True and row["steps"] == 12 and isinstance(row["steps"], int)
        assert math.isnan(row["navigation_time"]) and row["mine"] == 2  # unregistered: its value's kind
        bad = {"policy": "p", "map": "m", "test_set": "t", "scenario_index": 1, "seed": 1}
        bad |= {"config_hash": "h", "package_version": "0", "metrics": {"collision": 0.5}}
        with pytest.raises(
            TypeError, match=re.escape("metric 'collision' is registered as a flag (bool), got 0.5")
        ):
            store.add([bad])
    assert "collision" in METRICS
