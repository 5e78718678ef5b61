"""`socialzoo humans compare|select|report|realism|calibrate`: the people of the worlds, one command; and the
people specs of the commands that take them (people_spec)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from socialzoo.cli import command_help, fail
from socialzoo.cli.arg_types import comma_list, count, given, out_dir, positive_int
from socialzoo.cli.dataclass_args import dataclass_from_namespace

SCENES_HELP = (
    "comma-separated scenes (eth, hotel, univ, zara1, zara2) or track files of your own (PATH or NAME=PATH)"
)
# The --scenes, --models and --maps options: tuples, as their configs' fields.
_scenes, _models, _maps = comma_list("scenes"), comma_list("models"), comma_list("maps")


def register(subparsers: Any) -> None:
    """Add `humans` and its subcommands `compare`, `select`, `report`, `realism` and `calibrate`.

    `compare` sets learned humans against social-force humans on the same scenarios, `select` picks the
    checkpoint of a training run that compares best on validation scenarios, `report` shows how each
    crowd model walks, `realism` measures each model against the recorded ETH/UCY people and
    `calibrate` fits the social force's or ORCA's parameters to them.
    """
    parser = subparsers.add_parser("humans", help=command_help("humans"), description=command_help("humans"))
    commands = parser.add_subparsers(dest="humans_command", required=True, metavar="SUBCOMMAND")
    _add_compare(commands)
    _add_select(commands)
    add_report(commands)
    _add_realism(commands)
    _add_calibrate(commands)


def shipped_humans() -> str:
    """The path of the shipped learned humans' policy file.

    `socialzoo benchmark --humans` also reads "learned" alone as this file.
    """
    import socialzoo.agents

    return str(Path(socialzoo.agents.__file__).parent / "shipped" / "humans.safetensors")


def people_spec(spec: str) -> str:
    """A people spec; "learned" alone names the shipped learned humans."""
    return f"learned:{shipped_humans()}" if spec == "learned" else spec


def add_report(commands: Any) -> None:
    """Add `report` to the subcommands of `humans` (`commands`, their subparsers)."""
    report = commands.add_parser(
        "report",
        help="how each crowd model walks, one figure per model and one table",
        description="Walk each model's people on the map's validation scenarios without a robot and write "
        "DIR/report.md, report.csv (speed, local density, reach rate, time to goal, path length ratio, "
        "person-person and person-wall contacts per person-minute; learned models checked against the "
        "learned humans' targets: reach rate within 10% of the social force's, no more wall contacts), "
        "DIR/walk_<model>.png (speed histogram, speed against density beside Weidmann's 1993 curve, time "
        "to goal) and config.json.",
    )
    report.add_argument(
        "--humans",
        type=comma_list("people specs", people_spec),
        default=("sf", "orca", "groups"),
        help="comma-separated people specs: sf, orca, groups, learned (the shipped learned humans), "
        "learned:PATH, or mixes such as sf@0.5+orca@0.5 (default sf,orca,groups)",
    )
    report.add_argument("--map", default="gdc1", help="the map (its validation scenarios; default gdc1)")
    report.add_argument("--scenarios", type=positive_int, default=16, help="scenarios per model (default 16)")
    report.add_argument(
        "--seconds", type=float, default=60.0, help="how long the people walk, s (default 60)"
    )
    report.add_argument("--out", type=out_dir, required=True, help="output directory")
    report.add_argument("--no-figures", action="store_true", help="skip the figures (no matplotlib needed)")
    report.set_defaults(func=run_report)


def run_report(args: argparse.Namespace) -> int:
    """Run `socialzoo humans report`; returns the exit status."""
    from socialzoo.studies.human_report import HumanReportConfig, human_report

    try:
        config = dataclass_from_namespace(HumanReportConfig, args)
        _, files = human_report(config, args.out, figures=not args.no_figures)
    except (ValueError, FileNotFoundError) as err:
        return fail("humans report", err)
    print((args.out / "report.md").read_text())
    print(f"results in {args.out}: " + ", ".join(p.name for p in files))
    return 0


def _add_compare(commands: Any) -> None:
    """Add `humans compare`."""
    parser = commands.add_parser(
        "compare",
        help="learned humans against social-force humans (reach rate, collisions, distances, speed)",
        description="Run the benchmark among social-force humans and among learned humans on the same "
        "scenarios (human metrics on), and write DIR/comparison.md, comparison.csv and comparison.png "
        "with issue 13's targets (reach rate within 10%, no more collisions).",
    )
    parser.add_argument(
        "--humans",
        required=True,
        type=people_spec,
        help="learned:PATH, a learned human policy file, or learned: the shipped learned humans",
    )
    parser.add_argument(
        "--maps", type=_maps, default="gdc1,ghc3", help="comma-separated maps (default gdc1,ghc3)"
    )
    parser.add_argument("--trials", type=positive_int, default=None, help="scenarios per map (default: all)")
    sets = parser.add_mutually_exclusive_group()
    sets.add_argument("--quick", action="store_true", help="the quick test sets (100 scenarios)")
    sets.add_argument(
        "--validation",
        action="store_true",
        help="each map's validation scenarios (<map>-val), never a test set: for choosing settings",
    )
    _add_run_options(parser)
    parser.add_argument("--out", type=out_dir, required=True, help="output directory")
    parser.add_argument("--no-figures", action="store_true", help="skip comparison.png")
    parser.set_defaults(func=run_compare)


def _add_select(commands: Any) -> None:
    """Add `humans select`."""
    parser = commands.add_parser(
        "select",
        help="choose a learned-human checkpoint of a training run on validation scenarios",
        description="Compare every checkpoint of a `socialzoo train humans` run with the social-force "
        "humans on the training map's validation scenarios (a run trained on a scenario family: the family's "
        "validation cases; never a test set), keep the most trained one "
        "that meets both targets (else the one missing them by the least), and write DIR/selection.md, "
        "selection.csv, selection.json and DIR/humans.safetensors (a copy of the chosen checkpoint).",
    )
    parser.add_argument("--run", type=Path, required=True, help="the training run folder")
    parser.add_argument("--out", type=out_dir, default=None, help="output folder (default RUN/selection)")
    parser.add_argument(
        "--trials", type=positive_int, default=100, help="validation scenarios per checkpoint"
    )
    _add_run_options(parser)
    parser.set_defaults(func=run_select)


def _add_realism(commands: Any) -> None:
    """Add `humans realism`."""
    parser = commands.add_parser(
        "realism",
        help="which crowd model walks most like the recorded ETH/UCY people (ADE/FDE, speeds, contacts)",
        description="Walk each recorded person of the scenes by each model among the others replayed "
        "(socialzoo.studies.realism), and write DIR/realism.csv, realism.md, realism.json, ade.png and "
        "speeds.png. The scenes come from the data cache (`socialzoo data fetch eth-ucy`).",
    )
    parser.add_argument("--scenes", type=_scenes, default="eth,hotel,univ,zara1,zara2", help=SCENES_HELP)
    parser.add_argument(
        "--models",
        type=_models,
        default="cv,sf,orca,groups",
        help="comma-separated: cv, sf, orca, groups, learned:PATH, sf-eth-ucy, orca-eth-ucy",
    )
    parser.add_argument("--out", type=out_dir, required=True, help="output directory")
    parser.add_argument("--cache", default=None, help="the scenes' cache folder (default: the data dir)")
    parser.add_argument("--tracks", type=positive_int, default=None, help="persons per scene (default all)")
    parser.add_argument("--seed", type=count, default=0, help="seed of the persons' sample (default 0)")
    parser.add_argument("--no-figures", action="store_true", help="skip the figures")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(func=run_realism)


def _add_calibrate(commands: Any) -> None:
    """Add `humans calibrate`."""
    parser = commands.add_parser(
        "calibrate",
        help="fit the social force's or ORCA's parameters to the recorded ETH/UCY people (CMA-ES)",
        description="Fit a model's parameters to the 4.8 s ADE of recorded people, leave-one-scene-out "
        "and on all scenes (socialzoo.studies.calibration; needs the `cma` package, the train extra), "
        "and write DIR/calibration.md, calibration.csv, calibration.json and the preset fitted on all "
        "scenes, DIR/<model>-eth-ucy.json.",
    )
    parser.add_argument("--model", required=True, choices=("sf", "orca"), help="the model to fit")
    parser.add_argument("--scenes", type=_scenes, default="eth,hotel,univ,zara1,zara2", help=SCENES_HELP)
    parser.add_argument("--out", type=out_dir, required=True, help="output directory")
    parser.add_argument("--cache", default=None, help="the scenes' cache folder (default: the data dir)")
    parser.add_argument(
        "--persons", type=positive_int, default=40, help="persons sampled per scene for the fit (default 40)"
    )
    parser.add_argument("--windows", type=positive_int, default=3, help="windows per person (default 3)")
    parser.add_argument("--generations", type=positive_int, default=6, help="CMA-ES generations (default 6)")
    parser.add_argument(
        "--popsize", type=positive_int, default=6, help="CMA-ES population, 2 or more (default 6)"
    )
    parser.add_argument("--seed", type=count, default=0, help="seed of the samples and CMA-ES (default 0)")
    parser.add_argument("--no-folds", action="store_true", help="fit on all scenes only")
    parser.add_argument("--no-progress", action="store_true", help="no progress output")
    parser.set_defaults(func=run_calibrate)


def run_realism(args: argparse.Namespace) -> int:
    """Run `socialzoo humans realism`; returns the exit status."""
    from socialzoo.data.fetch import UnknownSceneError, check_recordings
    from socialzoo.studies.realism import RealismConfig
    from socialzoo.studies.realism import run_realism as run

    try:
        check_recordings(args.scenes)
        config = dataclass_from_namespace(RealismConfig, args)
        results = run(config, args.out, progress=not args.no_progress, figures=not args.no_figures)
    except (ValueError, UnknownSceneError, FileNotFoundError) as err:
        return fail("humans realism", err)
    for r in results:
        if r.scene == "overall" and r.model != "recorded":
            print(
                f"{r.model}: ADE {r.metrics['ade']:.3f} m, FDE {r.metrics['fde']:.3f} m over 4.8 s (mean of scenes)"
            )
    figures = "" if args.no_figures else ", ade.png, speeds.png"
    print(f"results in {args.out}: realism.md, realism.csv, realism.json{figures}")
    return 0


def run_calibrate(args: argparse.Namespace) -> int:
    """Run `socialzoo humans calibrate`; returns the exit status."""
    from socialzoo.data.fetch import UnknownSceneError, check_recordings
    from socialzoo.studies.calibration import CalibrationConfig, calibrate

    try:
        check_recordings(args.scenes)
        config = dataclass_from_namespace(CalibrationConfig, args, folds=not args.no_folds)
        result = calibrate(config, args.out, progress=not args.no_progress)
    except (ValueError, UnknownSceneError, FileNotFoundError, ImportError) as err:
        return fail("humans calibrate", err)
    for fold in result["folds"]:
        print(
            f"held out {fold['held_out']}: ADE {fold['default_ade']:.3f} m default, "
            f"{fold['fitted_ade']:.3f} m fitted"
        )
    print(f"results in {args.out}: calibration.md, calibration.csv, calibration.json")
    return 0


def _add_run_options(parser: argparse.ArgumentParser) -> None:
    """The options `compare` and `select` share: the robot, the time limit, the workers, progress."""
    parser.add_argument("--policy", default="ref", help="the robot's policy spec (default ref)")
    parser.add_argument("--max-steps", type=positive_int, default=None, help="episode time limit, steps")
    parser.add_argument("--workers", type=positive_int, default=2, help="local processes (default 2)")
    parser.add_argument("--batch-size", type=positive_int, default=64, help="env rows per worker")
    parser.add_argument("--no-progress", action="store_true", help="no progress bars")


def run_compare(args: argparse.Namespace) -> int:
    """Run `socialzoo humans compare`; returns the exit status."""
    from socialzoo.studies.human_compare import ComparisonConfig, compare_humans

    try:
        config = dataclass_from_namespace(ComparisonConfig, args, env_overrides=given(args, "max_steps"))
    except (ValueError, KeyError) as err:
        return fail("humans compare", err)
    result = compare_humans(config, args.out, progress=not args.no_progress, figures=not args.no_figures)
    for map_name, target in result.targets.items():
        print(
            f"{map_name}: reach-rate target {'met' if target['reach'] else 'NOT met'}, "
            f"collision target {'met' if target['collisions'] else 'NOT met'}"
        )
    print(f"results in {args.out}: " + ", ".join(p.name for p in result.files))
    return 0


def run_select(args: argparse.Namespace) -> int:
    """Run `socialzoo humans select`; returns the exit status."""
    from socialzoo.agents import check_policy_spec
    from socialzoo.studies.human_select import run_checkpoints, select_humans, training_map

    try:
        run_checkpoints(args.run)
        training_map(args.run)
        check_policy_spec(args.policy)
        # Its comparison's own checks too (more --trials than the validation set holds), named
        # before any trial runs, as `humans compare` reports them.
        result = select_humans(
            args.run,
            args.out,
            trials=args.trials,
            policy=args.policy,
            workers=args.workers,
            batch_size=args.batch_size,
            env_overrides=given(args, "max_steps"),
            progress=not args.no_progress,
        )
    except (FileNotFoundError, ValueError) as err:
        return fail("humans select", err)
    status = "meets both targets" if result.met else "meets no target set; the closest"
    print(f"chose {result.chosen} ({result.frames:,} frames): {status} on the validation scenarios")
    print(f"results in {result.out_dir}: selection.md, selection.csv, selection.json, humans.safetensors")
    return 0
