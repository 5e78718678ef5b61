"""`socialzoo crowdnav eval|replay`: the CrowdNav task's policies on its fixed cases, thin aliases: `eval` is
`socialzoo benchmark --maps socialzoo/CrowdNav<variant>-v1` (socialzoo.bench.task_benchmark), `replay` a page."""

from __future__ import annotations

import argparse
from typing import Any

from socialzoo.cli import command_help, fail
from socialzoo.cli.arg_types import out_path, positive_int, split_commas


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
            "--out", type=out_path, required=True, help="output folder (eval) or .html file (replay)"
        )
    evaluate, replay = sub.choices["eval"], sub.choices["replay"]
    evaluate.add_argument("--cases", type=positive_int, default=None, help="first N cases (default all)")
    evaluate.add_argument("--batch-size", type=positive_int, default=100, help="rows stepped together")
    evaluate.add_argument("--no-figures", action="store_true", help="skip success.png/pdf")
    evaluate.add_argument(
        "--observed-people",
        type=positive_int,
        default=None,
        help="the robot observes its K nearest people (CrowdNavConfig.observed_people): a learner "
        "trained with K people on a variant of more slots",
    )
    evaluate.set_defaults(func=run_eval)
    replay.add_argument("--case", type=int, default=0, help="the case to play")
    replay.set_defaults(func=run_replay)


def run_eval(args: argparse.Namespace) -> int:
    """Run `socialzoo crowdnav eval` (the variant's id through socialzoo.bench.task_benchmark);
    returns the exit status. Episodes go to the results store (OUT/results.sqlite) as they end: a
    rerun plays only the cases it lacks for each policy."""
    from socialzoo.bench.store import StoreError
    from socialzoo.bench.task_benchmark import run_task_benchmark
    from socialzoo.env.crowd_variants import crowd_env_id

    specs = list(split_commas(args.policies))
    try:
        if not specs:
            raise ValueError("--policies names no policy")
        _, files = run_task_benchmark(
            crowd_env_id(args.variant),
            specs,
            args.out,
            split=args.split,
            cases=args.cases,
            batch_size=args.batch_size,
            figures=not args.no_figures,
            say=print,
            config={} if args.observed_people is None else {"observed_people": args.observed_people},
        )
    except (ValueError, StoreError) as err:
        return fail("crowdnav eval", err)
    print(f"socialzoo crowdnav eval: wrote {', '.join(str(f) for f in files)}")
    return 0


def run_replay(args: argparse.Namespace) -> int:
    """Run `socialzoo crowdnav replay`: `socialzoo replay --env socialzoo/CrowdNav<variant>-v1`;
    returns the exit status."""
    from socialzoo.cli import main
    from socialzoo.env.crowd_variants import crowd_env_id

    argv = ["replay", "--env", crowd_env_id(args.variant), "--case", str(args.case), "--split", args.split]
    argv += [
        "--policy",
        args.policies,
        "--view",
        "map",
        "--laser-rays",
        "0",
        "--out",
        str(args.out),
    ]
    return main(argv)
