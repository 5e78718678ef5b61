"""The metric registry: every entry well-formed, views in registry order, unknown names a named error."""

import dataclasses
import re

import pytest

from socialzoo.core.metrics import (
    METRICS,
    SOURCES,
    Metric,
    UnknownMetricError,
    axis_label,
    describe,
    metric,
    names,
    registered,
    table_heading,
)

UNITS = {"", "s", "m", "m/s", "m/s^2", "m/s^3", "rad", "1/min"}


@pytest.mark.parametrize("name", list(METRICS))
def test_every_entry_is_well_formed(name):
    m = METRICS[name]
    assert m.name == name and name.isidentifier()
    assert m.label == m.label.strip() and m.label[0].islower(), "labels are lowercase phrases"
    assert m.unit in UNITS, f"{name}: an SI unit or '' ({m.unit!r})"
    assert m.unit == "" or not m.label.endswith(f", {m.unit}"), "the unit is not repeated in the label"
    assert m.better in ("higher", "lower", "neither") and m.kind in ("bool", "int", "float")
    assert m.higher_is_better == {"higher": True, "lower": False, "neither": None}[m.better]
    assert m.description[0].isupper() and m.description.endswith("."), f"{name}: a sentence"
    assert set(m.sources) <= set(SOURCES) and m.sources
    assert not m.count or m.kind == "int"
    assert not m.success_only or m.kind == "float", "NaN outside successful episodes"
    assert isinstance(m.digits, int) and 0 <= m.digits <= 6


def test_sources_and_prefixes_agree():
    # The humans' metrics carry a prefix that keeps them apart from the robot's.
    assert all(n.startswith("humans_") for n in names("humans"))
    assert not any(n.startswith("humans_") for s in SOURCES if s != "humans" for n in names(s))
    assert set().union(*(names(s) for s in SOURCES)) == set(METRICS)


def test_a_bad_entry_is_refused_with_its_name():
    good = METRICS["jerk"]
    for change, message in (
        ({"name": "two words"}, "identifier"),
        ({"better": "up"}, "better"),
        ({"kind": "str"}, "kind"),
        ({"sources": ("nowhere",)}, "sources"),
        ({"count": True}, "count"),
        ({"digits": -1}, "digits"),
        ({"description": " "}, "description"),
    ):
        with pytest.raises(ValueError, match=f"Metric .*{message}"):
            dataclasses.replace(good, **change)
    with pytest.raises(ValueError, match="a flag has no unit"):
        Metric(
            name="x", label="x", unit="s", better="lower", kind="bool", description="X.", sources=("humans",)
        )


def test_an_unknown_name_is_a_named_error():
    with pytest.raises(UnknownMetricError, match=r"unknown metric 'time_to_gaol': add it to .*METRICS"):
        metric("time_to_gaol")
    with pytest.raises(KeyError):  # an UnknownMetricError is a KeyError
        metric("nope")
    with pytest.raises(UnknownMetricError, match="'nope'"):
        registered("success", "nope")
    with pytest.raises(UnknownMetricError):
        describe(["nope"])
    with pytest.raises(ValueError, match="source must be one of"):
        names("benchmark")
    assert registered("success", "jerk") == ("success", "jerk")


def test_labels_for_tables_and_axes():
    assert table_heading("time_to_goal") == "time to goal, s (successful episodes only)"
    assert table_heading("mean_force") == "force (mean per step)"
    assert axis_label("time_to_goal") == "time to goal, s (successes)"
    assert axis_label("success") == "success, %"
    assert metric("jerk").heading == "jerk, m/s^3"


def test_describe_is_a_markdown_table_of_every_metric():
    text = describe()
    rows = [line for line in text.splitlines() if line.startswith("| `")]
    assert [re.match(r"\| `(\w+)`", r).group(1) for r in rows] == list(METRICS)
    assert "| `time_to_goal` | s | lower | float | successful episodes only |" in text


@pytest.fixture
def own_metric():
    """A metric of a task written outside the package, registered for the test and removed after it."""
    from socialzoo.core import metrics

    entry = metrics.register_metric(
        name="closest_person_own",
        label="closest person",
        unit="m",
        better="higher",
        kind="float",
        description="The least distance to a person over the episode.",
        sources=("reach_own",),
    )
    yield entry
    del METRICS[entry.name]
    metrics._TASK_SOURCES.discard("reach_own")


def test_a_task_of_one_s_own_registers_its_metric_where_summaries_and_tables_read_it(own_metric):
    from socialzoo.bench.tables import task_layout
    from socialzoo.bench.task_benchmark import summarize, table_entry
    from socialzoo.core.metrics import register_metric

    assert metric("closest_person_own") is own_metric and names("reach_own") == ("closest_person_own",)
    summary = summarize([{"success": 1.0, "closest_person_own": d} for d in (0.5, 1.5)])
    assert summary["closest_person_own"] == pytest.approx(1.0)
    entry = table_entry("p", "reach", "reach-test", summary)
    assert "closest_person_own" in task_layout([entry]).metrics
    with pytest.raises(ValueError, match="registered already"):
        register_metric(**{f.name: getattr(own_metric, f.name) for f in dataclasses.fields(own_metric)})
    with pytest.raises(ValueError, match="sources must be task names"):
        register_metric(name="x_own", sources=("two words",))
    with pytest.raises(ValueError, match=r"Metric 'y_own'.*better"):
        register_metric(
            name="y_own", label="y", unit="", better="up", kind="float", description="Y.", sources=("z_own",)
        )
    with pytest.raises(ValueError, match="source must be one of"):
        names("z_own")  # a refused entry leaves no source behind
