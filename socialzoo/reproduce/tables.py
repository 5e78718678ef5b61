"""The paper's tables, ours beside the paper's, built from the loaded results (socialzoo.reproduce.results.load):
each table is a list of rows (written as CSV) and Markdown."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from functools import partial
from pathlib import Path
from typing import Any

from socialzoo.bench.tables import interval_text, number_text, policy_label, remove_outputs, write_csv
from socialzoo.reproduce.paper import EXPERIMENT_MAPS, PAPER_POLICIES, PAPER_SUCCESS


def outside(paper: float | None, low: float, high: float) -> bool:
    """True when the paper's number lies outside our interval [low, high] (same units).

    A table row's "differs" is this, against our 90% interval.
    """
    if paper is None or not (math.isfinite(low) and math.isfinite(high)):
        return False
    return not low <= paper <= high


def experiment_table(rows: Sequence[Mapping[str, Any]], experiment: str) -> list[dict[str, Any]]:
    """The performance or transfer table: per policy, success with its interval beside the paper's,
    force, blame and time to goal (our means with 90% intervals; the paper gives figures only)."""
    _, index = EXPERIMENT_MAPS[experiment]
    by_policy = {str(r["policy"]): r for r in rows}
    out = []
    for policy in [p for p in PAPER_POLICIES if p in by_policy]:
        r = by_policy[policy]
        paper = PAPER_SUCCESS[policy][index]
        out.append(
            {
                "policy": policy,
                "trials": int(r["trials"]),
                "success_pct": 100 * r["success_rate"],
                "success_ci_low_pct": 100 * r["success_ci_low"],
                "success_ci_high_pct": 100 * r["success_ci_high"],
                "paper_success_pct": paper,
                "differs": outside(paper, 100 * r["success_ci_low"], 100 * r["success_ci_high"]),
                "mean_force": r["mean_force_mean"],
                "mean_blame": r["mean_blame_mean"],
                "time_to_goal_s": r["time_to_goal_mean"],
                "average_step_reward": r["average_step_reward_mean"],
                "_row": r,
            }
        )
    return out


def experiment_markdown(table: Sequence[Mapping[str, Any]]) -> str:
    """The performance or transfer table as Markdown."""
    lines = [
        "| policy | trials | success % [90% CI] | paper success % | force | blame | time to goal, s | differs |",
        "|---|---:|---|---:|---|---|---|---|",
    ]
    for t in table:
        r = t["_row"]
        lines.append(
            f"| {policy_label(t['policy'])} | {t['trials']:,} | {interval_text(r, 'success', 1, 100.0)} "
            f"| {t['paper_success_pct']:.1f} | {interval_text(r, 'mean_force', 4)} "
            f"| {interval_text(r, 'mean_blame', 4)} "
            f"| {interval_text(r, 'time_to_goal', 1)} | {'yes' if t['differs'] else ''} |"
        )
    return "\n".join(lines)


def lfd_table(rows: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """The LfD table: per policy and demonstration size, success and average step reward beside
    the paper's."""
    out = []
    for r in rows:
        paper_success = r.get("paper_success_pct", math.nan)
        out.append(
            {
                "policy": r["policy"],
                "demonstration_steps": int(r["demonstration_steps"]),
                "trials": int(r["trials"]),
                "success_pct": 100 * r["success_rate"],
                "success_ci_low_pct": 100 * r["success_ci_low"],
                "success_ci_high_pct": 100 * r["success_ci_high"],
                "paper_success_pct": paper_success,
                "average_step_reward": r["average_step_reward"],
                "paper_average_step_reward": r.get("paper_average_step_reward", math.nan),
                "differs": outside(
                    paper_success if math.isfinite(paper_success) else None,
                    100 * r["success_ci_low"],
                    100 * r["success_ci_high"],
                ),
                "_row": r,
            }
        )
    return out


def lfd_markdown(table: Sequence[Mapping[str, Any]]) -> str:
    """The LfD table as Markdown."""
    lines = [
        "| policy | demonstration steps | trials | success % [90% CI] | paper success % "
        "| average step reward | paper reward | differs |",
        "|---|---:|---:|---|---:|---:|---:|---|",
    ]
    for t in table:
        r = t["_row"]
        lines.append(
            f"| {policy_label(str(t['policy']))} | {t['demonstration_steps']:,} | {t['trials']} "
            f"| {interval_text(r, 'success', 1, 100.0)} "
            f"| {number_text(t['paper_success_pct'], 0)} | {number_text(t['average_step_reward'], 3)} "
            f"| {number_text(t['paper_average_step_reward'], 2)} | {'yes' if t['differs'] else ''} |"
        )
    return "\n".join(lines)


def curves_table(rows: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """The RL curves in brief: each run's first and last checkpoint and its best, and the reference
    policies, on the curve scenarios (the curves themselves are the figure)."""
    out = []
    for label in dict.fromkeys(str(r["label"]) for r in rows):
        points = sorted(
            (r for r in rows if r["label"] == label and math.isfinite(r["step"])), key=lambda r: r["step"]
        )
        refs = [r for r in rows if r["label"] == label and not math.isfinite(r["step"])]
        chosen = [("reference", refs[0])] if refs else []
        if points:
            best = max(points, key=lambda r: r["success_rate"])
            chosen += [("first", points[0]), ("best", best), ("last", points[-1])]
        for which, r in chosen:
            out.append(
                {
                    "policy": label,
                    "checkpoint": which,
                    "step": int(r["step"]) if math.isfinite(r["step"]) else None,
                    "trials": int(r["trials"]),
                    "success_pct": 100 * r["success_rate"],
                    "success_ci_low_pct": 100 * r["success_ci_low"],
                    "success_ci_high_pct": 100 * r["success_ci_high"],
                    "time_to_goal_s": r["time_to_goal_mean"],
                    "average_step_reward": r["average_step_reward_mean"],
                    "_row": r,
                }
            )
    return out


def curves_markdown(table: Sequence[Mapping[str, Any]]) -> str:
    """The RL curves table as Markdown."""
    lines = [
        "| policy | checkpoint | step | trials | success % [90% CI] | time to goal, s | average step reward |",
        "|---|---|---:|---:|---|---|---|",
    ]
    for t in table:
        r = t["_row"]
        step = f"{t['step']:,}" if t["step"] is not None else ""
        lines.append(
            f"| {policy_label(str(t['policy']))} | {t['checkpoint']} | {step} | {t['trials']} "
            f"| {interval_text(r, 'success', 1, 100.0)} | {interval_text(r, 'time_to_goal', 1)} "
            f"| {interval_text(r, 'average_step_reward', 4)} |"
        )
    return "\n".join(lines)


def build_tables(results: Mapping[str, Any]) -> dict[str, tuple[list[dict[str, Any]], str]]:
    """name -> (rows, Markdown) of every table the results allow ("performance", "transfer",
    "lfd", "rl_curves")."""
    builders: dict[str, tuple[Callable[..., list[dict[str, Any]]], Callable[..., str]]] = {
        **{e: (partial(experiment_table, experiment=e), experiment_markdown) for e in EXPERIMENT_MAPS},
        "lfd": (lfd_table, lfd_markdown),
        "rl_curves": (curves_table, curves_markdown),
    }
    tables = {name: table(results[name]) for name, (table, _) in builders.items() if results.get(name)}
    return {name: (rows, builders[name][1](rows)) for name, rows in tables.items()}


# Every table build_tables may make, by name.
TABLE_NAMES: tuple[str, ...] = (*EXPERIMENT_MAPS, "lfd", "rl_curves")


def write_tables(tables: Mapping[str, tuple[list[dict[str, Any]], str]], out_dir: str | Path) -> list[Path]:
    """Each table as NAME.csv and NAME.md in out_dir; the files of the other TABLE_NAMES are removed
    (an earlier run's in the same folder, of parts these results lack)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    remove_outputs(out, set(TABLE_NAMES) - set(tables), ("csv", "md"))
    files = []
    for name, (rows, markdown) in tables.items():
        plain = [{k: v for k, v in r.items() if not k.startswith("_")} for r in rows]
        files.append(write_csv(plain, out / f"{name}.csv"))
        (out / f"{name}.md").write_text(markdown + "\n")
        files.append(out / f"{name}.md")
    return files
