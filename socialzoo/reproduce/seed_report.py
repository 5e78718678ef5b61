"""REPRODUCTION.md's sections on training seeds and checkpoint choice, from the results' selection.csv, seeds.csv and
improvement.csv (socialzoo.reproduce.seeds); results without them (a single seed made before these existed) get none."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from socialzoo.bench.tables import number_text, policy_label

EXPERIMENT_TITLES = {
    "performance": "gdc1-test",
    "transfer": "ghc3-test",
    "lfd": "LfD, first gdc1-test scenarios",
}


def _pct_interval(r: Mapping[str, Any], name: str, unit: str = "") -> str:
    """A seeds row's "<name>_pct" with its interval: "61.5 [52.0, 70.0]" ("61.5% [...]" with unit "%")."""
    low, high = (number_text(r[f"{name}_ci_{end}_pct"], 1) for end in ("low", "high"))
    return f"{number_text(r[f'{name}_pct'], 1)}{unit} [{low}, {high}]"


def selection_section(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    """The checkpoint each RL run kept, chosen on validation scenarios, beside the last one."""
    if not rows:
        return []
    lines = [
        "## Checkpoint choice by validation",
        "",
        "Each PPO and DQN run evaluates its checkpoints on validation scenarios of gdc1 (`gdc1-val`, "
        "seeds apart from every test set) while it trains; the policy it keeps, the one in the "
        "performance and transfer tables, is its best validation checkpoint (the earliest among equals). "
        "The curve scenarios (gdc1-test) are shown beside it for reading only: they never choose.",
        "",
        "| run | seed | validation scenarios | checkpoints evaluated | kept step | kept: validation % "
        "| kept: curve % | last step | last: validation % | last: curve % |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        last = (
            f"{int(r['last_step']):,}"
            if isinstance(r["last_step"], float) and math.isfinite(r["last_step"])
            else ""
        )
        lines.append(
            f"| rl/{r['run']} | {int(r['seed'])} | {int(r['validation_trials'])} | {int(r['evaluated_checkpoints'])} "
            f"| {int(r['kept_step']):,} | {number_text(100 * r['kept_validation_success'], 1)} "
            f"| {number_text(100 * r['kept_curve_success'], 1)} | {last} "
            f"| {number_text(100 * r['last_validation_success'], 1)} "
            f"| {number_text(100 * r['last_curve_success'], 1)} |"
        )
    return [*lines, ""]


def seeds_table(rows: Sequence[Mapping[str, Any]], experiment: str) -> list[str]:
    """One experiment's aggregates over seeds as Markdown."""
    mine = [r for r in rows if r["experiment"] == experiment]
    if not mine:
        return []
    size = experiment == "lfd"
    lines = [
        f"| policy |{' demonstration steps |' if size else ''} seeds | scenarios | mean success % [95% CI] "
        "| IQM % [95% CI] | seeds' success % | paper % | where the paper falls |",
        f"|---|{'---:|' if size else ''}---:|---:|---|---|---|---:|---|",
    ]
    for r in mine:
        steps = f" {int(r['demonstration_steps']):,} |" if size else ""
        seeds = ", ".join(f"{float(v):.1f}" for v in str(r["seed_success_pct"]).split(";") if v)
        lines.append(
            f"| {policy_label(str(r['policy']))} |{steps} {int(r['seeds'])} | {int(r['scenarios']):,} "
            f"| {_pct_interval(r, 'mean')} | {_pct_interval(r, 'iqm')} "
            f"| {seeds} | {number_text(r['paper_pct'], 1)} | {r['paper_where']} |"
        )
    return lines


def improvement_table(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    """Probability of improvement between pairs of policies as Markdown."""
    if not rows:
        return []
    lines = [
        "| setting | X | Y | seeds X / Y | P(X > Y) [95% CI] |",
        "|---|---|---|---:|---|",
    ]
    for r in rows:
        setting = EXPERIMENT_TITLES.get(str(r["experiment"]), str(r["experiment"]))
        if r["experiment"] == "lfd":
            setting += f", {int(r['demonstration_steps']):,} steps"
        lines.append(
            f"| {setting} | {policy_label(str(r['x']))} | {policy_label(str(r['y']))} "
            f"| {int(r['seeds_x'])} / {int(r['seeds_y'])} "
            f"| {r['probability']:.2f} [{r['ci_low']:.2f}, {r['ci_high']:.2f}] |"
        )
    return lines


def seeds_section(results: Mapping[str, Any], figure: list[str]) -> list[str]:
    """The section on training seeds: aggregates per experiment, improvement, profiles."""
    rows = results.get("seeds", [])
    if not rows:
        return []
    seeds = max(int(r["seeds"]) for r in rows)
    lines = [
        "## Training seeds",
        "",
        f"Every learned policy was trained with {seeds} seeds (each its own run, policy file and trials). "
        "Mean and interquartile mean (IQM: the mean of the middle 50% of the seeds' success rates) "
        "with 95% stratified bootstrap intervals over seeds and scenarios "
        "(socialzoo.bench.aggregates; Agarwal et al. 2021). The paper reports one training run: the "
        "last column says where its number falls among our seeds. GoAlone and Ref are deterministic "
        "(one run; their intervals are over scenarios only). The performance, transfer and LfD "
        "tables above are the first seed's; the RL curves show every seed.",
        "",
    ]
    for experiment in ("performance", "transfer", "lfd"):
        table = seeds_table(rows, experiment)
        if table:
            lines += [f"### {EXPERIMENT_TITLES[experiment]}", "", *table, ""]
    improvement = improvement_table(results.get("improvement", []))
    if improvement:
        lines += [
            "### Probability of improvement",
            "",
            "P(X > Y): the probability that a seed of X succeeds more often than a seed of Y on the same "
            "scenarios (ties count half), with its 95% stratified bootstrap interval.",
            "",
            *improvement,
            "",
        ]
    return [*lines, *figure, ""] if figure else lines


def _seeds_row(rows: Sequence[Mapping[str, Any]], experiment: str, policy: str) -> Mapping[str, Any] | None:
    """The seeds row of a policy in an experiment when several seeds ran, or None."""
    for r in rows:
        if r["experiment"] == experiment and r["policy"] == policy and int(r["seeds"]) > 1:
            return r
    return None


def paper_outside_seeds(rows: Sequence[Mapping[str, Any]], experiment: str, policy: str) -> bool:
    """True when several seeds ran and the paper's number lies below all of them or above all."""
    r = _seeds_row(rows, experiment, policy)
    if r is None:
        return False
    paper = r.get("paper_pct")
    if paper is None or paper == "" or math.isnan(float(paper)):
        return False
    return not float(r["min_pct"]) <= float(paper) <= float(r["max_pct"])


def seed_note(rows: Sequence[Mapping[str, Any]], experiment: str, policy: str) -> str | None:
    """The measured seed spread of a policy in an experiment, for "Where we differ", or None."""
    r = _seeds_row(rows, experiment, policy)
    if r is None:
        return None
    return (
        f"Over {int(r['seeds'])} training seeds: {number_text(r['min_pct'], 1)}% to {number_text(r['max_pct'], 1)}%, "
        f"mean {_pct_interval(r, 'mean', '%')}; "
        f"the paper's number is {r['paper_where']}."
    )
