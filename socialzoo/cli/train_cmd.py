"""`socialzoo train <trainer> [options]`: run one of the trainers of socialzoo.train, with options generated from
its argument dataclass (socialzoo.cli.dataclass_args): the same arguments and defaults as `train(Args(...))`."""

from __future__ import annotations

import argparse
import logging
from typing import Any

from socialzoo.cli import command_help, fail

logger = logging.getLogger(__name__)


def _input_errors() -> tuple[type[Exception], ...]:
    """The errors by which a trainer refuses its inputs (each names the input): a run folder holding
    another run, an unreadable demonstration, policy, map or track file, a bad people spec, recorded
    scenes with no people to clone, a Ray address nothing answers at."""
    from socialzoo.agents.demonstrations import DemonstrationError
    from socialzoo.bench.runner import RayAddressError
    from socialzoo.data.fetch import UnknownSceneError
    from socialzoo.data.tracks import TrackFileError
    from socialzoo.env.policy_file import PolicyFileError
    from socialzoo.humans.models import PeopleSpecError
    from socialzoo.maps.map_file import MapError
    from socialzoo.train.people_bc import PeopleDataError
    from socialzoo.train.run_dir import RunDirError

    return (
        RunDirError,
        PeopleDataError,
        DemonstrationError,
        PolicyFileError,
        MapError,
        TrackFileError,
        UnknownSceneError,
        PeopleSpecError,
        RayAddressError,
        FileNotFoundError,
    )


def register(subparsers: Any) -> None:
    """Add `train` with one sub-subcommand per registered trainer."""
    from socialzoo.cli.dataclass_args import add_dataclass_arguments
    from socialzoo.train import TRAINERS, trainer_args

    parser = subparsers.add_parser(
        "train",
        help=command_help("train"),
        description="Train a learned policy. Each trainer writes run.json (arguments, command, seed), "
        "TensorBoard logs and checkpoints beside the policy file.",
    )
    trainers = parser.add_subparsers(dest="trainer", required=True, metavar="TRAINER")
    for name in sorted(TRAINERS):
        cls = trainer_args(name)
        doc = (cls.__doc__ or "").strip().splitlines()
        sub = trainers.add_parser(name, help=doc[0] if doc else name, description=doc[0] if doc else None)
        add_dataclass_arguments(sub, cls)
        sub.set_defaults(func=run_train_command, trainer_class=cls)


def run_train_command(args: argparse.Namespace) -> int:
    """Run `socialzoo train <trainer>`; returns the exit status (2 for bad arguments)."""
    from socialzoo.cli.dataclass_args import dataclass_from_namespace
    from socialzoo.train import trainer_function

    try:
        train_args = dataclass_from_namespace(args.trainer_class, args)
    except (TypeError, ValueError) as err:
        return fail(f"train {args.trainer}", err)
    try:
        path = trainer_function(args.trainer)(train_args)
    except _input_errors() as err:
        # Inputs found bad once the trainer reads them, each named by its loader; a fault inside
        # training keeps its traceback (this one is logged with -v).
        logger.debug("socialzoo train %s failed", args.trainer, exc_info=True)
        return fail(f"train {args.trainer}", err)
    print(f"socialzoo train {args.trainer}: wrote {path}")
    return 0
