"""`socialzoo crowdnav eval|replay`: the CrowdNav task's policies on its fixed cases.

socialzoo crowdnav eval --policies orca,social_force,crowdnav --out results/crowdnav
socialzoo crowdnav replay --policies orca,crowdnav --case 3 --out crowdnav.html
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path
from typing import Any

from socialzoo.cli import command_help
from socialzoo.cli.arg_types import positive_int

TABLE_COLUMNS = (
    "policy",
    "episodes",
    "success_rate",
    "collision_rate",
    "timeout_rate",
    "navigation_time",
    "path_length",
    "discomfort_frequency",
    "min_separation",
    "intrusion_ratio",
    "discounted_return",
    "mean_force",
    "mean_blame",
)


def register(subparsers: Any) -> None:
    """Add `crowdnav` with its actions eval and replay."""
    parser = subparsers.add_parser(
        "crowdnav",
        help=command_help("crowdnav"),
        description="The CrowdNav task (socialzoo/CrowdNav-v1 and its variants): evaluate policies on its "
        "fixed validation or test cases, or write an episode viewer page.",
    )
    sub = parser.add_subparsers(dest="crowdnav_command", required=True, metavar="ACTION")
    for name, text in (
        ("eval", "success, collision, time and comfort on the fixed cases"),
        ("replay", "an episode page"),
    ):
        action = sub.add_parser(name, help=text)
        action.add_argument(
            "--policies",
            default="orca,social_force",
            help="comma-separated: orca, social_force, crowdnav (the shipped file) or crowdnav:PATH",
        )
        action.add_argument(
            "--variant", default="", help="the task's variant ('' CrowdNav's own; 20, Unicycle, ...)"
        )
        action.add_argument("--split", choices=("val", "test"), default="test", help="the fixed cases")
        action.add_argument(
            "--out", type=Path, required=True, help="output folder (eval) or .html file (replay)"
        )
    evaluate, replay = sub.choices["eval"], sub.choices["replay"]
    evaluate.add_argument("--cases", type=positive_int, default=None, help="first N cases (default all)")
    evaluate.add_argument("--batch-size", type=positive_int, default=100, help="rows stepped together")
    evaluate.add_argument("--no-figures", action="store_true", help="skip success.png/pdf")
    evaluate.set_defaults(func=run_eval)
    replay.add_argument("--case", type=int, default=0, help="the case to play")
    replay.set_defaults(func=run_replay)


def _setup(args: argparse.Namespace) -> tuple[Any, list[tuple[str, Any, Any]]]:
    """(the variant's config, [(spec, policy, the config it acts in)]): a learned policy acts with
    the action kind it was trained with, an engineered one with velocities (its own output)."""
    from socialzoo.agents import make_policy
    from socialzoo.env.crowd_config import CrowdNavConfig
    from socialzoo.env.tasks.crowdnav import observation_space

    specs = [p.strip() for p in args.policies.split(",") if p.strip()]
    if not specs:
        raise ValueError("--policies names no policy")
    config = CrowdNavConfig.variant(args.variant)
    policies = []
    for spec in specs:
        policy = make_policy(spec, task="crowdnav", observation_space=observation_space(config))
        kind = getattr(policy, "action_kind", "continuous")
        policies.append((spec, policy, config.replace(action=kind)))
    return config, policies


def run_eval(args: argparse.Namespace) -> int:
    """Run `socialzoo crowdnav eval`; returns the exit status. Episodes go to the benchmark's results
    store (OUT/results.sqlite, socialzoo.bench.crowd_store) as they end: a rerun plays only the
    cases it lacks for each policy."""
    from socialzoo.bench.crowd_store import STORE_FILE, evaluate_crowd_stored
    from socialzoo.bench.store import StoreError

    try:
        config, policies = _setup(args)
    except ValueError as err:
        print(f"socialzoo crowdnav eval: error: {err}", file=sys.stderr)
        return 2
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for spec, policy, acting in policies:
        try:
            result, played = evaluate_crowd_stored(
                out / STORE_FILE, spec, policy, acting, args.split, args.cases, args.batch_size
            )
        except StoreError as err:
            print(f"socialzoo crowdnav eval: error: {err}", file=sys.stderr)
            return 2
        summary = result.summary
        rows.append({"policy": spec, **summary})
        print(
            f"{spec}: success {summary['success_rate']:.3f} collision {summary['collision_rate']:.3f} "
            f"timeout {summary['timeout_rate']:.3f} time {summary['navigation_time']:.2f} s "
            f"({played} of {summary['episodes']} episodes played now, the others read from the store)"
        )
    files = write_crowd_tables(rows, out, config, args.split)
    if not args.no_figures:
        from socialzoo.bench.figures import plot_success

        task = f"CrowdNav{args.variant} {args.split}"
        bars = [
            {
                "policy": r["policy"],
                "map": task,
                "success_rate": r["success_rate"],
                "success_ci_low": r["success_ci"][0],
                "success_ci_high": r["success_ci"][1],
            }
            for r in rows
        ]
        files += plot_success(bars, out, interval="95% CI")
    print(f"socialzoo crowdnav eval: wrote {', '.join(str(f) for f in files)}")
    return 0


def write_crowd_tables(rows: list[dict[str, Any]], out: Path, config: Any, split: str) -> list[Path]:
    """crowdnav.csv (TABLE_COLUMNS and intervals) and crowdnav.md (a readable table)."""
    csv_path = out / "crowdnav.csv"
    with csv_path.open("w", newline="") as f:
        writer = csv.writer(f)
        header = [c for c in TABLE_COLUMNS] + ["success_ci_low", "success_ci_high"]
        writer.writerow(header)
        for r in rows:
            writer.writerow([r.get(c) for c in TABLE_COLUMNS] + list(r["success_ci"]))
    where = (
        f"{config.map} with the benchmark's scenarios, up to {config.slots} {config.humans} people"
        if config.map is not None
        else f"{config.cases.layout}, {config.cases.num_humans} {config.humans} people"
    )
    lines = [
        f"CrowdNav task ({where}, {config.robot.kinematics} robot, "
        f"{'visible' if config.robot_visible else 'invisible'}), {split} cases",
        "",
        "| policy | success [95% CI] | collision | timeout | nav time (s) | path (m) | discomfort "
        "| min sep. (m) | force |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        low, high = r["success_ci"]
        lines.append(
            f"| {r['policy']} | {r['success_rate']:.3f} [{low:.3f}, {high:.3f}] | {r['collision_rate']:.3f} | "
            f"{r['timeout_rate']:.3f} | {r['navigation_time']:.2f} | {r['path_length']:.2f} | "
            f"{r['discomfort_frequency']:.3f} | {r['min_separation']:.3f} | {r['mean_force']:.4f} |"
        )
    md_path = out / "crowdnav.md"
    md_path.write_text("\n".join(lines) + "\n")
    return [csv_path, md_path]


def run_replay(args: argparse.Namespace) -> int:
    """Run `socialzoo crowdnav replay`; returns the exit status."""
    from socialzoo.bench.crowd_replay import crowd_scene, record_crowd_episode
    from socialzoo.render.replay_html import write_replay_html

    try:
        config, policies = _setup(args)
        traces = [
            record_crowd_episode(p.act, spec, acting, args.split, args.case) for spec, p, acting in policies
        ]
    except ValueError as err:
        print(f"socialzoo crowdnav replay: error: {err}", file=sys.stderr)
        return 2
    title = f"CrowdNav{args.variant} {args.split} case {args.case}"
    path = write_replay_html(args.out, crowd_scene(config, traces, title), traces, view="map")
    print(f"socialzoo crowdnav replay: wrote {path} ({', '.join(f'{t.label}: {t.outcome}' for t in traces)})")
    return 0
