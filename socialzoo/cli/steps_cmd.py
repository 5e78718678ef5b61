"""`socialzoo steps-to-ref --out DIR`: beyond the paper, the training steps PPO needs to reach Ref's success
(socialzoo.studies.rl_training.steps_to_reference), on validation scenarios of our own seeds, never on a test set."""

from __future__ import annotations

import argparse
from typing import Any

from socialzoo.cli import command_help, fail
from socialzoo.cli.arg_types import out_dir, positive_int


def register(subparsers: Any) -> None:
    """Add `steps-to-ref`."""
    parser = subparsers.add_parser(
        "steps-to-ref",
        help=command_help("steps-to-ref"),
        description="Train PPO (its defaults otherwise) for --total-steps with a checkpoint every "
        "--checkpoint-every steps, evaluate every checkpoint and the reference policy on the first "
        "--trials scenarios of the gdc1 validation set, and report the first checkpoint that succeeds "
        "as often as the reference. Writes DIR/steps_to_ref.json, .csv and .png/.pdf; a finished "
        "training run and stored trials are reused.",
    )
    parser.add_argument("--out", type=out_dir, required=True, help="output directory")
    parser.add_argument("--total-steps", type=positive_int, default=600_000, help="PPO training steps")
    parser.add_argument(
        "--checkpoint-every", type=positive_int, default=50_000, help="steps between checkpoints"
    )
    parser.add_argument(
        "--trials", type=positive_int, default=200, help="validation scenarios per checkpoint"
    )
    parser.add_argument("--reference", default="ref", help="the policy to match (default ref)")
    parser.add_argument("--seed", type=int, default=0, help="the training seed")
    parser.add_argument("--workers", type=positive_int, default=2, help="local evaluation processes")
    parser.add_argument("--no-figures", action="store_true", help="skip steps_to_ref.png/pdf")
    parser.add_argument("--no-progress", action="store_true", help="no progress bars")
    parser.set_defaults(func=run_steps_to_ref)


def describe(record: dict[str, Any]) -> str:
    """One paragraph answering the question from a steps_to_reference record."""
    ref = record["reference"]
    head = (
        f"{ref['label']} succeeds in {100 * ref['success_rate']:.1f}% of {record['trials']} "
        f"{record['validation_set']} scenarios."
    )
    if record["steps"] is None:
        best = max(record["checkpoints"], key=lambda r: r["success_rate"])
        return (
            f"{head} No PPO checkpoint up to {record['total_steps']:,} steps reaches it; the best is "
            f"{100 * best['success_rate']:.1f}% at {best['step']:,} steps."
        )
    ci = record["steps_ci"]
    return f"{head} PPO first reaches it after {record['steps']:,} steps" + (
        f" (its 90% interval first covers it after {ci:,})." if ci is not None else "."
    )


def run_steps_to_ref(args: argparse.Namespace) -> int:
    """Run `socialzoo steps-to-ref`; returns the exit status."""
    from socialzoo.studies.rl_training import steps_to_reference
    from socialzoo.train.run_dir import RunDirError

    if args.total_steps % args.checkpoint_every:
        return fail(
            "steps-to-ref",
            f"--total-steps ({args.total_steps}) must be a multiple of --checkpoint-every ({args.checkpoint_every})",
        )
    try:
        record = steps_to_reference(
            args.out,
            total_steps=args.total_steps,
            checkpoint_every=args.checkpoint_every,
            trials=args.trials,
            reference=args.reference,
            seed=args.seed,
            workers=args.workers,
            progress=not args.no_progress,
            figure=not args.no_figures,
        )
    except (ValueError, KeyError, FileNotFoundError, RunDirError) as err:
        # RunDirError: DIR/ppo_long holds a run of other arguments, or a damaged record (named).
        return fail("steps-to-ref", err)
    print(describe(record))
    print(f"wrote {args.out / 'steps_to_ref.json'}")
    return 0
