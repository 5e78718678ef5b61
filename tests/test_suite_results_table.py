"""tools/suite_results_table.py: the suite's Markdown table from stored outcomes."""

import importlib.util
from pathlib import Path

from socialzoo.bench.stats import rate_interval

ROOT = Path(__file__).resolve().parents[1]


def _tool():
    spec = importlib.util.spec_from_file_location(
        "suite_results_table", ROOT / "tools" / "suite_results_table.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_scenario_a_policy_did_not_play_is_not_a_zero():
    # Two suite folders with different scenarios: ref played both, orca only the frontal approach.
    outcomes = {
        ("ref", "frontal_approach"): ([True, True], [False, False]),
        ("ref", "blind_corner"): ([True, False], [False, True]),
        ("orca", "frontal_approach"): ([False, True], [True, False]),
    }
    rows = {line.split("|")[1].strip(): line for line in _tool().table(outcomes).splitlines()[2:]}
    corner = [c.strip() for c in rows["i. Blind corner"].split("|")[2:-1]]
    assert corner == ["50 / 50", "-"]
    frontal = [c.strip() for c in rows["a. Frontal approach"].split("|")[2:-1]]
    assert frontal == ["100 / 0", "50 / 50"]


def test_a_family_outside_the_suite_is_a_row_under_its_name():
    # `socialzoo suite --scenarios a,crossing` plays any registered family; the table stopped with
    # "KeyError: unknown suite scenario 'crossing'".
    outcomes = {("ref", "frontal_approach"): ([True], [False]), ("ref", "crossing"): ([False], [True])}
    rows = [line.split("|")[1].strip() for line in _tool().table(outcomes).splitlines()[2:]]
    assert rows[:2] == ["a. Frontal approach", "crossing"]


def test_the_last_row_has_the_95_percent_intervals_it_names():
    # The row said "95% CI" (docs/suite.md and the tool's docstring too) but rate_interval's default is the
    # benchmark's 90%: for 6 successes of 6 it gave [0.689, 1.000], where Wilson's 95% interval is [0.610, 1].
    outcomes = {("ref", "frontal_approach"): ([True] * 6, [False] * 6)}
    last = _tool().table(outcomes).splitlines()[-1]
    assert last.startswith("| all (success / collision rate, 95% CI) |")
    low = rate_interval(6, 6, 0.95).low
    assert f"**1.000** [{low:.3f}, 1.000]" in last and f"{low:.3f}" == "0.610"
