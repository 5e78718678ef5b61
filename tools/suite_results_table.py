"""The suite's results as one Markdown table for docs/suite.md: per scenario and policy the success
rate and the share of episodes with a collision (the guidelines' count above 0), and over all
scenarios both rates with 95% Wilson intervals, the way robot_sf reports its planner comparison.
A policy that did not play a scenario (its folder ran other scenarios) has "-" there.

    python tools/suite_results_table.py results/suite_as results/suite_crowdnav

Each argument is a `socialzoo suite` output folder: its config.json names each unit's scenario,
policy and config hash, and its results.sqlite holds the episodes.
"""

from __future__ import annotations

import argparse
import json
import sqlite3
from pathlib import Path

from socialzoo.bench.stats import rate_interval
from socialzoo.scenarios.suite import suite_entry

# The last row's intervals: 95%, as robot_sf reports them and as `socialzoo suite`'s own tables are
# (rate_interval's default is the benchmark tables' 90%).
CONFIDENCE = 0.95


def label(scenario: str) -> str:
    """A row's label: "a. Frontal approach" for a suite scenario, the family's name for another
    registered family that `socialzoo suite --scenarios` played."""
    try:
        entry = suite_entry(scenario)
    except KeyError:
        return scenario
    return f"{entry.letter}. {entry.title}"


def unit_outcomes(folder: Path) -> dict[tuple[str, str], tuple[list[bool], list[bool]]]:
    """(policy, scenario) -> (successes, collided) of the folder's stored episodes, in case order."""
    config = json.loads((folder / "config.json").read_text())
    out: dict[tuple[str, str], tuple[list[bool], list[bool]]] = {}
    with sqlite3.connect(folder / "results.sqlite") as db:
        for unit in config["units"]:
            rows = db.execute(
                "SELECT success, gl_collisions FROM trials WHERE policy = ? AND config_hash = ? "
                "AND scenario_index < ? ORDER BY scenario_index",
                (unit["policy"], unit["config_hash"], unit["cases"]),
            ).fetchall()
            out[(unit["policy"], unit["scenario"])] = ([bool(s) for s, _ in rows], [c > 0 for _, c in rows])
    return out


def table(outcomes: dict[tuple[str, str], tuple[list[bool], list[bool]]]) -> str:
    """The Markdown table: scenarios as rows, policies as columns, cells "success % / collision %"."""
    policies = list(dict.fromkeys(p for p, _ in outcomes))
    scenarios = list(dict.fromkeys(s for _, s in outcomes))
    lines = ["| scenario | " + " | ".join(policies) + " |", "|---|" + "---|" * len(policies)]
    for scenario in scenarios:
        cells = []
        for policy in policies:
            success, collided = outcomes.get((policy, scenario), ([], []))
            n = len(success)  # 0: not played (a folder without this scenario), not a 0% success
            cells.append(f"{100 * sum(success) / n:.0f} / {100 * sum(collided) / n:.0f}" if n else "-")
        lines.append(f"| {label(scenario)} | " + " | ".join(cells) + " |")
    totals = []
    for policy in policies:
        success = [x for (p, _), (s, _) in outcomes.items() if p == policy for x in s]
        collided = [x for (p, _), (_, c) in outcomes.items() if p == policy for x in c]
        s = rate_interval(sum(success), len(success), CONFIDENCE)
        c = rate_interval(sum(collided), len(collided), CONFIDENCE)
        totals.append(
            f"**{s.value:.3f}** [{s.low:.3f}, {s.high:.3f}] / **{c.value:.3f}** [{c.low:.3f}, {c.high:.3f}]"
        )
    lines.append(f"| all (success / collision rate, {CONFIDENCE:.0%} CI) | " + " | ".join(totals) + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folders", nargs="+", type=Path, help="socialzoo suite output folders")
    args = parser.parse_args()
    outcomes: dict[tuple[str, str], tuple[list[bool], list[bool]]] = {}
    for folder in args.folders:
        outcomes.update(unit_outcomes(folder))
    print(table(outcomes))


if __name__ == "__main__":
    main()
