"""Experiment 1, RL data efficiency: the training part (the reproduce command calls these).

`train_curve_runs` trains PPO and DQN with the paper's set-up (84,000 steps, a checkpoint every
2,000) into one folder each; `socialzoo.bench.rl_curves.rl_curves` then evaluates every checkpoint.
`train_to_match` trains PPO on for longer, for `socialzoo.bench.rl_curves.steps_to_match` (the
steps PPO needs to reach Ref's success, measured on validation scenarios).

    runs = train_curve_runs("results/rl")               # {"ppo": results/rl/ppo, "dqn": ...}
    rl_curves(runs, "results/rl")                       # rl_curves.csv, rl_curves.{png,pdf}
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from socialzoo.train import trainer_args, trainer_function

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
    total_steps: int = 500_000,
    checkpoint_every: int = 50_000,
    seed: int = 0,
    progress: bool = True,
    **changes: Any,
) -> Path:
    """Train PPO (its defaults otherwise) for `total_steps` with a checkpoint every
    `checkpoint_every` steps into out_dir/ppo_long; returns the run folder."""
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
