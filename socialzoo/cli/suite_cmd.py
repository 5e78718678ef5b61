"""`socialzoo suite`: policies x the scenario suite's scenarios x seeds into a results store, with a
policy x scenario table and heatmap per metric, replay pages and a static results page."""

from __future__ import annotations

import argparse
from typing import Any

from socialzoo.cli import command_help, fail
from socialzoo.cli.arg_types import add_backend_arguments, comma_list, count, given, out_dir, positive_int
from socialzoo.cli.benchmark_cmd import _policy_specs

# Comma-separated names, lower-cased.
_names = comma_list("names", str.lower)


def register(subparsers: Any) -> None:
    """Add `suite`."""
    parser = subparsers.add_parser(
        "suite",
        help=command_help("suite"),
        description=(
            "Evaluate policies on the scenario suite (the 25 scenarios of Francis et al. 2025, Fig. 7): each "
            "policy on cases 0..N-1 of each scenario family's test split (its val split where the task has no "
            "test split for it yet). Episodes go to DIR/results.sqlite as they finish; a rerun reads them and "
            "an interrupted run resumes. Writes, per metric, DIR/tables/METRIC.csv and .md (policy x "
            "scenario, mean with its 95% interval) and DIR/heatmaps/METRIC.png; DIR/suite.csv, suite.md, "
            "config.json, replay pages in DIR/replays/ and the static page DIR/results.html."
        ),
    )
    parser.add_argument(
        "--policies",
        type=_policy_specs,
        default=None,
        help="comma-separated policies: registry names or NAME:PATH for a policy file (default goalone,ref; "
        "with --task crowdnav: orca,social_force)",
    )
    parser.add_argument(
        "--scenarios",
        type=_names,
        default=None,
        help="comma-separated scenarios: Fig. 7 letters (a-y), suite names (frontal_approach, ...) or any "
        "registered scenario family's name, MODULE:NAME for one that MODULE registers (default: all 25 of "
        "the suite)",
    )
    parser.add_argument(
        "--task",
        choices=("action_selection", "crowdnav"),
        default="action_selection",
        help="the task that plays them: action_selection (sub-policies, the default) or crowdnav "
        "(velocity control)",
    )
    parser.add_argument(
        "--seeds", type=positive_int, default=30, help="cases per policy and scenario (default 30)"
    )
    parser.add_argument("--out", type=out_dir, required=True, help="output directory")
    add_backend_arguments(parser, "episodes")
    parser.add_argument(
        "--replays",
        type=count,
        default=1,
        help="replay pages per scenario and policy: its first K episodes, failed ones first "
        "(default 1; 0: none)",
    )
    parser.add_argument(
        "--metrics",
        type=_names,
        default=None,
        help="comma-separated metrics of the tables and heatmaps (default: the headline metrics the episodes hold); "
        "with the action-selection task, people_time_lost, people_time_lost_max or people_extra_distance play "
        "each scenario beside a twin without the robot to measure them",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(
        func=run_suite_command,
        resume_hint="the finished episodes are kept in the results store: the same command resumes",
    )


def run_suite_command(args: argparse.Namespace) -> int:
    """Run `socialzoo suite`; returns the exit status (2 for a bad name or option)."""
    from socialzoo.bench.figures import pyplot
    from socialzoo.bench.runner import RayAddressError
    from socialzoo.bench.store import StoreError
    from socialzoo.bench.suite import SuiteConfig, SuiteError, run_suite
    from socialzoo.bench.tables import interval_text, policy_labels

    try:  # the heatmaps' library, before the episodes
        pyplot()
    except ModuleNotFoundError as err:
        return fail("suite", err)
    chosen: dict[str, Any] = {
        "task": args.task,
        "seeds": args.seeds,
        "backend": args.backend,
        "address": args.address,
        "batch_size": args.batch_size,
        "replays": args.replays,
        "workers": args.workers if args.workers is not None or args.backend == "ray" else 2,
        **given(args, "policies", "scenarios", "metrics"),
    }
    try:
        config = SuiteConfig(**chosen)
        result = run_suite(config, args.out, progress=not args.no_progress, say=print)
    except (SuiteError, StoreError, RayAddressError) as err:
        return fail("suite", err)
    print(
        f"{result.played} episodes played, {result.reused} read from the store, in {result.seconds:.1f} s "
        f"({len(result.policies)} policies x {len(result.scenarios)} scenarios x {config.seeds} seeds)"
    )
    labels = policy_labels(result.policies)
    if "success" in result.metrics:
        width = max(len(s.label) for s in result.scenarios)
        print(f"  {'success, %':<{width}}  " + "  ".join(f"{labels[p]:>22}" for p in result.policies))
        for s in result.scenarios:
            cells = [interval_text(result.entry(p, s.name), "success", 1, 100.0) for p in result.policies]
            print(f"  {s.label:<{width}}  " + "  ".join(f"{c:>22}" for c in cells))
    print(f"results in {args.out}: {args.out / 'results.html'}")
    return 0
