"""The scenario suite's evaluation (socialzoo.bench.suite): scenarios by letter or name, the task of a
family, episodes stored under a task id benchmark's keys and read back on a rerun, tables, replays.

Stand-ins: the suite's families are being written; these tests register shipped families under
suite names (monkeypatch), or name them on their own (a registered family outside the suite).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from socialzoo.bench.suite import (
    SuiteConfig,
    SuiteError,
    plan_suite,
    replay_choices,
    resolve_scenarios,
    run_suite,
    suite_env_id,
    suite_metrics,
    suite_task,
)
from socialzoo.bench.suite_page import card_html
from socialzoo.bench.task_benchmark import TaskId
from socialzoo.scenarios import catalogue
from socialzoo.scenarios.families import Crossing, Doorway
from socialzoo.scenarios.suite import SUITE_NAMES

FAST = ("crossing", "doorway")  # about 400-480 steps per episode


class FrontalStandIn(Doorway):
    """The doorway family under suite scenario (a)'s name."""

    name = "frontal_approach"


class ObstructionStandIn(Crossing):
    """The crossing family under suite scenario (b)'s name."""

    name = "pedestrian_obstruction"


@pytest.fixture
def stand_ins(monkeypatch):
    """Suite scenarios a and b registered as stand-ins (shipped families renamed)."""
    monkeypatch.setitem(catalogue.FAMILIES, "frontal_approach", FrontalStandIn())
    monkeypatch.setitem(catalogue.FAMILIES, "pedestrian_obstruction", ObstructionStandIn())


def test_scenarios_by_letter_suite_name_or_family_in_order_once(stand_ins):
    chosen = resolve_scenarios(["B", "a", "frontal_approach", "doorway"])
    assert [s.name for s in chosen] == ["pedestrian_obstruction", "frontal_approach", "doorway"]
    assert [s.label for s in chosen] == ["b. Pedestrian obstruction", "a. Frontal approach", "doorway"]
    assert chosen[1].map_name == "doorway" and chosen[2].letter == ""


def test_an_unknown_scenario_is_named_with_what_is_known(stand_ins):
    with pytest.raises(SuiteError) as err:
        resolve_scenarios(["a", "narnia", "zz"])
    text = str(err.value)
    assert "'narnia', 'zz'" in text and "a frontal_approach" in text and "hallway_head_on" in text


def test_a_suite_scenario_not_registered_yet_is_named(monkeypatch):
    monkeypatch.delitem(catalogue.FAMILIES, "blind_corner", raising=False)
    with pytest.raises(SuiteError, match=r"i\. blind_corner not registered .*registered: .*doorway"):
        resolve_scenarios(["doorway", "i"])


def test_the_task_of_a_family():
    import gymnasium as gym

    (scenario,) = resolve_scenarios(["doorway"])
    for name, fallback in (
        ("action_selection", {"map": "doorway", "family": "doorway", "max_steps": 2400}),
        ("crowdnav", {"family": "doorway"}),
    ):
        task = suite_task(name, scenario)
        assert task.env_id == suite_env_id(name) and task.task == name
        if task.env_id in gym.registry:  # the registered id's config, with the family
            assert task.kwargs == {**TaskId.of(task.env_id).kwargs, "family": "doorway"}
        else:
            assert task.kwargs == fallback
    assert suite_env_id("action_selection").startswith("socialzoo/Suite-v")
    assert suite_env_id("crowdnav").startswith("socialzoo/CrowdNavSuite-v")
    assert suite_task("action_selection", scenario).make(1).config.family == "doorway"


def test_crowdnav_plays_families_or_says_clearly_that_it_cannot_yet():
    from dataclasses import fields

    from socialzoo.env.crowd_config import CrowdNavConfig

    config = SuiteConfig(task="crowdnav", scenarios=("crossing",), seeds=2)
    if "family" not in {f.name for f in fields(CrowdNavConfig)}:
        with pytest.raises(SuiteError, match="no `family` field yet"):
            plan_suite(config)
        return
    units, _ = plan_suite(config)
    assert [(u.spec, u.task.task, u.config.family) for u in units] == [
        ("orca", "crowdnav", "crossing"),
        ("social_force", "crowdnav", "crossing"),
    ]


def test_bad_configs_are_named():
    with pytest.raises(SuiteError, match=r"SuiteConfig\.seeds must be an int >= 1, got 0"):
        SuiteConfig(seeds=0)
    with pytest.raises(SuiteError, match="unknown policy 'robocop'"):
        SuiteConfig(policies=("ref", "robocop"))
    with pytest.raises(SuiteError, match="unknown metric 'happiness'"):
        SuiteConfig(metrics=("happiness",))
    with pytest.raises(SuiteError, match="duplicates"):
        SuiteConfig(scenarios=("a", "a"))
    with pytest.raises(
        SuiteError, match="the action_selection task's episodes hold no metric navigation_time"
    ):
        plan_suite(SuiteConfig(metrics=("success", "navigation_time"), scenarios=("doorway",)))
    with pytest.raises(SuiteError, match="policy 'orca' acts in task 'crowdnav'"):
        plan_suite(SuiteConfig(policies=("orca",), scenarios=("doorway",)))


@pytest.mark.parametrize(("task", "policy"), [("action_selection", "goalone"), ("crowdnav", "orca")])
def test_table_i_metrics_can_be_chosen(task, policy):
    # Every suite episode holds Table I's gl_* metrics (the default tables show some of them), but
    # --metrics gl_spl was refused: "the action_selection task's episodes hold no metric gl_spl".
    chosen = ("success", "gl_spl", "gl_velocity_avg")
    units, _ = plan_suite(SuiteConfig(task=task, policies=(policy,), metrics=chosen, scenarios=("doorway",)))
    assert len(units) == 1
    with pytest.raises(SuiteError, match=f"the {task} task's episodes hold no metric humans_goal_rate"):
        plan_suite(
            SuiteConfig(task=task, policies=(policy,), metrics=("humans_goal_rate",), scenarios=("doorway",))
        )


def test_what_the_robot_costs_the_people_can_be_chosen_as_the_scenario_cards_recommend(tmp_path):
    """16 scenario cards list people_time_lost among their metrics of interest, but `socialzoo suite
    --metrics people_time_lost` was refused ("the action_selection task's episodes hold no metric"): the
    suite never played the counterfactual twin without the robot that measures it. Asking for it now
    plays the twins (the action-selection task's people.counterfactual), stored apart from plain runs."""
    from socialzoo.env.people import COST_KEYS
    from socialzoo.scenarios.cards import suite_cards

    recommended = {name for card in suite_cards() for name in card.metrics if name in COST_KEYS}
    assert recommended  # the cards do recommend them
    chosen = ("success", *sorted(recommended))
    config = SuiteConfig(policies=("goalone",), scenarios=("narrow_hallway",), seeds=2, workers=1, replays=0)
    with_twins = run_suite(dataclasses.replace(config, metrics=chosen), tmp_path / "twins")
    plain = run_suite(dataclasses.replace(config, metrics=("success",)), tmp_path / "plain")
    (entry,) = with_twins.entries
    assert all(math.isfinite(entry[f"{name}_mean"]) for name in recommended)
    assert entry["people_time_lost_mean"] > 0  # the robot delays the person it meets in the hallway
    assert with_twins.units[0].digest != plain.units[0].digest  # not one another's stored episodes
    (alone,) = plain.entries  # the robot's episodes are the same, every number of them
    np.testing.assert_equal({k: entry[k] for k in alone}, alone)
    with pytest.raises(SuiteError, match="the crowdnav task's episodes hold no metric people_time_lost"):
        plan_suite(
            dataclasses.replace(config, task="crowdnav", policies=("orca",), metrics=("people_time_lost",))
        )


def test_the_other_task_reruns_into_the_same_folder(tmp_path):
    # The store holds one column per metric of any episode it has seen: after an action-selection
    # run, the CrowdNav task's rows read back None for the action-selection ints (reached, stuck,
    # ...), and evaluate_stored's float(None) was a TypeError traceback.
    def config(task, policy):
        return SuiteConfig(
            task=task,
            policies=(policy,),
            scenarios=("doorway",),
            seeds=1,
            workers=1,
            replays=0,
            metrics=("success",),
        )

    run_suite(config("action_selection", "goalone"), tmp_path / "both")
    mixed = run_suite(config("crowdnav", "orca"), tmp_path / "both")
    alone = run_suite(config("crowdnav", "orca"), tmp_path / "alone")
    assert mixed.played == alone.played == 1
    # The same numbers; the action-selection floats the store holds are NaN beside them.
    (together,), (apart,) = mixed.entries, alone.entries
    np.testing.assert_equal({k: together[k] for k in apart}, apart)
    assert all(math.isnan(v) for k, v in together.items() if k not in apart)


def test_more_seeds_than_the_split_holds_write_nothing(tmp_path):
    out = tmp_path / "suite"
    with pytest.raises(
        SuiteError, match=r"doorway: 100000 seeds asked of the (val|test) split, which holds \d+"
    ):
        run_suite(SuiteConfig(scenarios=("doorway",), seeds=100_000), out)
    assert not out.exists()


def test_run_stores_resumes_and_equals_the_task_benchmarks_episodes(tmp_path):
    from socialzoo.bench.task_benchmark import evaluate_stored

    config = SuiteConfig(
        policies=("goalone", "ref"),
        scenarios=FAST,
        seeds=2,
        workers=1,
        batch_size=4,
        replays=0,
        metrics=("success", "time_to_goal"),
    )
    said: list[str] = []
    first = run_suite(config, tmp_path / "suite", say=said.append)
    assert (first.played, first.reused) == (8, 0)
    assert [(e["policy"], e["map"], e["trials"]) for e in first.entries] == [
        (p, s, 2) for p in ("goalone", "ref") for s in FAST
    ]
    assert first.metrics == ["success", "time_to_goal"]
    for unit in first.units:  # the test split, else the task's first split, said so
        note = f"{unit.scenario.name}: the action_selection task has no test split for it yet; played on its "
        assert unit.split == "test" or f"{note}{unit.split} cases 0-1" in said
    again = run_suite(config, tmp_path / "suite")
    assert (again.played, again.reused) == (0, 8)
    assert again.entries == first.entries
    # The backend's episodes are those the task benchmark plays itself, under the same keys.
    for unit in first.units:
        mine, _ = evaluate_stored(
            tmp_path / "suite" / "results.sqlite", unit.task, unit.spec, unit.policy, unit.split, 2
        )
        alone, played = evaluate_stored(
            tmp_path / "alone.sqlite", unit.task, unit.spec, unit.policy, unit.split, 2
        )
        assert played == 2
        np.testing.assert_equal(mine, alone)
    # More seeds play only the new cases.
    more = run_suite(SuiteConfig(**{**config.to_json(), "seeds": 3}), tmp_path / "suite")
    assert (more.played, more.reused) == (4, 8)
    # Another --metrics: the tables and heatmap of the metric left out go; the user's own files stay.
    (tmp_path / "suite" / "heatmaps" / "notes.png").write_bytes(b"mine")
    run_suite(SuiteConfig(**{**config.to_json(), "seeds": 3, "metrics": ("success",)}), tmp_path / "suite")
    assert sorted(p.name for p in (tmp_path / "suite" / "heatmaps").iterdir()) == ["notes.png", "success.png"]
    assert sorted(p.name for p in (tmp_path / "suite" / "tables").iterdir()) == ["success.csv", "success.md"]


def test_a_rerun_with_fewer_policies_and_scenarios_keeps_only_its_replay_pages(tmp_path):
    # The older run's pages of a policy and a scenario left out stayed beside this run's tables.
    def config(policies, scenarios):
        return SuiteConfig(
            policies=policies, scenarios=scenarios, seeds=1, workers=1, replays=1, metrics=("success",)
        )

    out = tmp_path / "suite"
    first = run_suite(config(("goalone", "ref"), FAST), out)
    assert len(first.replays) == 4
    (out / "replays" / "crossing" / "notes.html").write_text("mine")
    again = run_suite(config(("goalone",), ("crossing",)), out)
    pages = sorted(p.relative_to(out).as_posix() for p in (out / "replays").rglob("*.html"))
    assert pages == sorted([r.path for r in again.replays] + ["replays/crossing/notes.html"])
    assert len(again.replays) == 1 and not (out / "replays" / "doorway").exists()


def test_replays_are_the_failures_first_then_successes_in_case_order():
    episodes = [{"case": k, "success": s} for k, s in enumerate([True, False, True, False, False])]
    assert [e["case"] for e in replay_choices(episodes, 1)] == [1]
    assert [e["case"] for e in replay_choices(episodes, 2)] == [1, 3]
    assert [e["case"] for e in replay_choices(episodes, 4)] == [0, 1, 3, 4]
    assert [e["case"] for e in replay_choices(episodes[:1], 3)] == [0]
    assert replay_choices(episodes, 0) == []


def test_metrics_are_those_every_entry_holds_or_those_chosen():
    entries = [
        {"policy": "ref", "map": "a", "success_rate": 1.0, "time_to_goal_mean": 9.0, "jerk_mean": 1.0},
        {"policy": "ref", "map": "b", "success_rate": 0.5, "time_to_goal_mean": math.nan},
    ]
    # Unless chosen: the headline metrics the entries hold, else everything they hold.
    assert suite_metrics(entries) == ["success"]
    without_headline = [{k: v for k, v in e.items() if k != "success_rate"} for e in entries]
    assert suite_metrics(without_headline) == ["time_to_goal"]
    assert suite_metrics(entries, ("time_to_goal",)) == ["time_to_goal"]
    with pytest.raises(SuiteError, match="no metric jerk; they hold success, time_to_goal"):
        suite_metrics(entries, ("jerk",))


def test_a_card_renders_as_html_whatever_its_shape():
    assert card_html(None) == ""
    assert "&lt;b&gt;" in card_html("<b>text</b>")
    assert "<dt>map</dt><dd>hallway</dd>" in card_html({"map": "hallway"})
    cards = pytest.importorskip("socialzoo.scenarios.cards")
    try:
        card = cards.load_card("frontal_approach")
    except ValueError as err:
        pytest.skip(f"the card does not load: {err}")
    text = card_html(card)
    assert "<dt>defining event</dt>" in text and "oncoming pedestrian" in text


def test_every_suite_scenario_has_a_task_once_registered(stand_ins):
    # The ids are built from the names alone: every suite name is a valid env id kwarg.
    assert len(SUITE_NAMES) == 25
    for scenario in resolve_scenarios(["a", "b"]):
        assert suite_task("action_selection", scenario).kwargs["family"] == scenario.name


def test_an_infinite_time_to_collision_counts_in_the_mean_the_table_and_the_heatmap(monkeypatch, tmp_path):
    """An episode never on a collision course has gl_min_time_to_collision inf, the best value; the
    suite's mean used to leave it out as if undefined: robot crowding, GoAlone, seeds 100-101 (inf and
    1.61 s) read "1.61", and leaving a group (inf, inf) read "n/a"."""
    from types import SimpleNamespace

    import socialzoo.bench.suite_page as suite_page
    from socialzoo.bench.tables import interval_text
    from socialzoo.bench.task_benchmark import summarize, table_entry

    name = "gl_min_time_to_collision"
    entries = {
        scenario: table_entry("goalone", scenario, "test", summarize([{name: v} for v in values]))
        for scenario, values in (("y", [math.inf, 1.61]), ("q", [math.inf, math.inf]), ("a", [3.0, 4.0]))
    }
    assert entries["y"][f"{name}_mean"] == math.inf
    assert [interval_text(e, name, 2) for e in entries.values()] == ["inf", "inf", "3.50 [-2.85, 9.85]"]
    # NaN (nobody there) is still no value.
    assert summarize([{name: v} for v in (math.nan, 1.0, 2.0)])[name] == 1.5

    figures = []
    monkeypatch.setattr(suite_page, "save_figure", lambda fig, *a, **k: figures.append(fig) or [tmp_path])
    result = SimpleNamespace(
        scenarios=[SimpleNamespace(name=s, label=s) for s in entries],
        policies=["goalone"],
        entry=lambda policy, scenario: entries[scenario],
    )
    suite_page.plot_heatmap(result, name, tmp_path)
    ax = figures[0].axes[0]
    assert [t.get_text() for t in ax.texts] == ["inf", "inf", "3.50"]
    shown = ax.images[0].get_array()
    assert not np.ma.getmaskarray(shown).any()  # coloured as the best end of the scale, not grey
    assert shown[0, 0] == shown[0, 1] == ax.images[0].norm.vmax > shown[0, 2] == 3.5


def test_a_count_has_the_maps_tables_bootstrap_interval_never_below_zero():
    """The registry's counts (gl_collisions, ...) got a Student-t interval in the suite's tables: GoAlone's
    collisions on entering an elevator over 3 seeds (1, 0, 0) read "0.33 [-1.10, 1.77]", and 6 seeds
    without a collision "0.00 [0.00, 0.00]", where `socialzoo benchmark`'s tables give counts the BCa
    bootstrap (docs/benchmark.md) that the registry promises (Metric.count)."""
    from socialzoo.bench import tables
    from socialzoo.bench.stats import mean_interval
    from socialzoo.bench.task_benchmark import summarize

    name = "gl_collisions"
    some = summarize([{name: v} for v in (1, 0, 0)])
    low, high = some[f"{name}_ci"]
    assert 0.0 <= low <= some[name] <= high
    none = summarize([{name: 0}] * 6)
    assert none[f"{name}_ci"] == [0.0, pytest.approx(-math.log(0.025) / 6)]
    # The maps' tables' interval, from the same cell's generator.
    rows = [
        {"policy": "goalone", "map": "entering_elevator", "test_set": "t", "success": True, name: v}
        for v in (1, 0, 0)
    ]
    (maps,) = tables.summarize(rows, confidence=0.95, metrics=(name,))
    cell = summarize([{name: v} for v in (1, 0, 0)], cell=("goalone", "entering_elevator"))
    assert cell[f"{name}_ci"] == [maps[f"{name}_ci_low"], maps[f"{name}_ci_high"]]
    # Other numbers keep their Student-t interval.
    t = mean_interval([1.0, 2.0, 3.0], 0.95)
    assert summarize([{"gl_path_length": v} for v in (1.0, 2.0, 3.0)])["gl_path_length_ci"] == [t.low, t.high]


def test_a_module_that_cannot_be_a_module_is_named():
    # `socialzoo suite --scenarios .x:fam` ended in a TypeError traceback from importlib (a relative
    # name), and `--scenarios :a` printed "error: Empty module name" without the name given.
    with pytest.raises(SuiteError, match=r"scenario family \.x:fam: cannot import '\.x'"):
        resolve_scenarios([".x:fam"])
    with pytest.raises(SuiteError, match="scenario family :a: cannot import ''"):
        resolve_scenarios([":a"])
