"""`socialzoo reproduce --out DIR [--quick] [--seeds K] [--only PARTS] [--reference [QUIRKS]] [--backend B]
[--no-progress]`: the paper's experiments, their tables and figures, and DIR/REPRODUCTION.md (socialzoo.reproduce)."""

from __future__ import annotations

import argparse
from typing import Any

from socialzoo.cli import command_help, fail
from socialzoo.cli.arg_types import out_dir, positive_int


def register(subparsers: Any) -> None:
    """Add `reproduce`."""
    from socialzoo.reproduce.plan import PARTS

    parser = subparsers.add_parser(
        "reproduce",
        help=command_help("reproduce"),
        description="Run the paper's protocol: Ref demonstrations, PPO/DQN curves, the LfD table, "
        "performance on gdc1-test and transfer on ghc3-test for the seven policies. Every item is "
        "stored as it finishes under DIR/<settings hash>/; a rerun continues where it stopped.",
    )
    parser.add_argument("--out", type=out_dir, required=True, help="output folder DIR")
    parser.add_argument("--quick", action="store_true", help="a small version of everything (minutes)")
    parser.add_argument(
        "--seeds",
        type=positive_int,
        default=1,
        metavar="K",
        help="train every learned policy with K seeds (seed, seed+1, ...) and report the aggregates over them",
    )
    parser.add_argument(
        "--seed-trials",
        type=int,
        default=None,
        metavar="N",
        help="evaluate the seeds after the first on the first N scenarios of each test set in the "
        "performance and transfer parts (default: all of them)",
    )
    parser.add_argument(
        "--only", default=None, metavar="PARTS", help=f"comma-separated parts to run, of: {','.join(PARTS)}"
    )
    parser.add_argument("--backend", default="local", choices=("local", "ray"), help="where tasks run")
    parser.add_argument(
        "--workers",
        type=int,
        default=None,
        metavar="N",
        help="trainings side by side and evaluation processes (or Ray CPUs of a local Ray); default 2 "
        "(--quick: 1); changes no result",
    )
    parser.add_argument(
        "--reference",
        nargs="?",
        const="all",
        default=None,
        metavar="QUIRKS",
        help="then train PPO and DQN with the reference code's quirks (SPEC section 11: x-only goal "
        "distance, the reward 'distance gained + bonus'; PPO evaluated without its normalisation) "
        "and evaluate them with the quirks on, reported as their own columns. QUIRKS: comma-separated "
        "quirk sets, each run on its own: 'all' (every quirk together, the default) or one switch of "
        "ReferenceQuirks alone (e.g. goal_distance_x_only,reward_distance_plus_bonus)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bars")
    parser.add_argument(
        "--publish",
        default=None,
        metavar="REPO",
        help="then copy the results, tables and figures into REPO/results/reproduction/ and write "
        "REPO/REPRODUCTION.md",
    )
    parser.set_defaults(
        func=run_reproduce_command,
        resume_hint="the finished items are kept: the same command continues where it stopped",
    )


def _interrupt_on_signals() -> None:
    """Make SIGINT raise KeyboardInterrupt even where the shell ignores it (a command started with
    `&`), so a stopped run records the time of its interrupted part (SIGTERM does so for every
    command: socialzoo.cli.main)."""
    import signal

    signal.signal(signal.SIGINT, signal.default_int_handler)


def run_reproduce_command(args: argparse.Namespace) -> int:
    """Run `socialzoo reproduce`; returns the exit status (2 for bad arguments or mixed settings)."""
    from socialzoo.reproduce.ledger import LedgerError
    from socialzoo.reproduce.plan import full_settings, parse_parts, quick_settings, reference_sets
    from socialzoo.reproduce.run import reproduce
    from socialzoo.train.run_dir import RunDirError

    try:
        parts = parse_parts(args.only)
    except ValueError as err:
        return fail("reproduce", f"--only: {err}")
    try:
        reference = reference_sets(args.reference)
    except ValueError as err:
        return fail("reproduce", f"--reference: {err}")
    try:
        volatile = {} if args.workers is None else {"workers": args.workers}
        settings = (quick_settings if args.quick else full_settings)(
            seeds=args.seeds, seed_trials=args.seed_trials, **volatile
        )
    except ValueError as err:
        return fail("reproduce", err)
    _interrupt_on_signals()

    def report(part: str, made: int) -> None:
        print(f"socialzoo reproduce: {part} done ({made} items made)", flush=True)

    try:
        result = reproduce(
            args.out,
            settings,
            parts=parts,
            backend=args.backend,
            progress=not args.no_progress,
            on_part=report,
            reference=reference,
        )
    except (LedgerError, RunDirError) as err:
        # Mixed settings, an unreadable settings, timings or training run record (each named).
        return fail("reproduce", err)
    print(f"socialzoo reproduce: items in {result.work_dir}; report {result.report}")
    if args.publish is not None:
        from socialzoo.reproduce.publish import publish

        print(f"socialzoo reproduce: published {publish(args.out, args.publish)}")
    return 0
