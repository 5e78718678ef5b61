"""Experiment 1, RL data efficiency: the training part (the reproduce command calls these)."""

from __future__ import annotations

import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from socialzoo.core.files import json_text, write_text_atomic
from socialzoo.train import trainer_args, trainer_function

if TYPE_CHECKING:
    from socialzoo.scenarios.scenario_sets import TestSet

CURVE_ALGOS = ("ppo", "dqn")


def train_curve_runs(
    out_dir: str | Path,
    *,
    algos: Sequence[str] = CURVE_ALGOS,
    seed: int = 0,
    progress: bool = True,
    **changes: Any,
) -> dict[str, Path]:
    """Train each algorithm with its defaults (the paper's set-up) into out_dir/<algo>.

    The paper's set-up: 84,000 steps, a checkpoint every 2,000; `socialzoo.studies.rl_curves.rl_curves` then
    evaluates every checkpoint.

    Args:
        out_dir: parent folder of the runs.
        algos: trainer names.
        seed: the runs' seed.
        progress: show progress bars.
        **changes: Args fields applied to every trainer (e.g. total_steps=84_000).

    Returns:
        label -> run folder. Finished runs of the same arguments are not repeated.
    """
    runs = {}
    for algo in algos:
        args = trainer_args(algo)(out=Path(out_dir) / algo, seed=seed, progress=progress, **changes)
        trainer_function(algo)(args)
        runs[algo] = Path(args.out)
    return runs


def train_to_match(
    out_dir: str | Path,
    *,
    total_steps: int = 600_000,
    checkpoint_every: int = 50_000,
    seed: int = 0,
    progress: bool = True,
    **changes: Any,
) -> Path:
    """Train PPO (its defaults otherwise) for `total_steps` with a checkpoint every
    `checkpoint_every` steps into out_dir/ppo_long; returns the run folder.

    For `socialzoo.studies.rl_curves.steps_to_match` (the steps PPO needs to reach Ref's success, measured on
    validation scenarios).
    """
    args = trainer_args("ppo")(
        out=Path(out_dir) / "ppo_long",
        seed=seed,
        total_steps=total_steps,
        checkpoint_every=checkpoint_every,
        progress=progress,
        **changes,
    )
    trainer_function("ppo")(args)
    return Path(args.out)


STEPS_FILE = "steps_to_ref.json"


def steps_to_reference(
    out_dir: str | Path,
    *,
    total_steps: int = 600_000,
    checkpoint_every: int = 50_000,
    trials: int = 200,
    reference: str = "ref",
    seed: int = 0,
    workers: int = 2,
    batch_size: int = 64,
    progress: bool = True,
    figure: bool = True,
    validation: TestSet | None = None,
    env_overrides: Mapping[str, Any] | None = None,
    **changes: Any,
) -> dict[str, Any]:
    """Beyond the paper: how many training steps PPO needs to reach `reference`'s success.

    Trains PPO for `total_steps` (train_to_match; a finished run is reused), evaluates every
    checkpoint and the reference on the first `trials` validation scenarios
    (socialzoo.studies.rl_curves.VALIDATION_SET, never a test set), and writes out_dir/steps_to_ref.json
    (the answer with the settings and the command), steps_to_ref.csv (one row per checkpoint) and,
    with `figure`, steps_to_ref.{png,pdf} (the curves with the reference as a line).
    `validation` and `env_overrides` replace the validation scenarios and the evaluation env's
    settings (tests use small ones); `changes` are PPO arguments.

    Returns:
        the JSON record: "steps" (first checkpoint at or above the reference's success rate, None if
        none), "steps_ci" (first whose 90% interval reaches it), "reference", "checkpoints", settings.
    """
    from socialzoo.studies.rl_curves import VALIDATION_SET, plot_curves, steps_to_match

    validation = validation or VALIDATION_SET
    out = Path(out_dir)
    run = train_to_match(
        out,
        total_steps=total_steps,
        checkpoint_every=checkpoint_every,
        seed=seed,
        progress=progress,
        **changes,
    )
    found = steps_to_match(
        run,
        out,
        reference=reference,
        validation=validation,
        trials=trials,
        workers=workers,
        batch_size=batch_size,
        progress=progress,
        env_overrides=env_overrides,
    )
    record = {
        **found,
        "run": str(run),
        "total_steps": total_steps,
        "checkpoint_every": checkpoint_every,
        "trials": trials,
        "validation_set": validation.name,
        "seed": seed,
        "changes": changes,
        "command": " ".join(sys.argv),
    }
    write_text_atomic(out / STEPS_FILE, json_text(record, indent=1, default=str) + "\n")
    if figure:
        plot_curves(found["checkpoints"], out, [found["reference"]], stem="steps_to_ref")
    return record
