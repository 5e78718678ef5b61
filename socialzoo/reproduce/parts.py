"""The runner of each part of the reproduction (socialzoo.reproduce.plan.PARTS).

Every part composes pieces that store their items as they finish, so a part is resumable:

- demos: Ref's demonstrations (socialzoo.bench.demonstrations, chunk by chunk).
- rl-curves: PPO and DQN training runs (socialzoo.train, checkpoints) and every checkpoint on the
  first gdc1-test scenarios (socialzoo.studies.rl_curves, one stored trial at a time).
- lfd: BC and GAIL at each demonstration size and PIPS, then the LfD table (socialzoo.studies.lfd).
- performance / transfer: the seven policies on gdc1-test / ghc3-test (socialzoo.bench.experiment).

A training run folder that holds a finished run of the same arguments is not trained again (the
trainers' RunDir; PIPS by its sidecar), so a part that needs policies of an earlier part trains
only what is missing. Each part returns how many items it made (0: everything was read back).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from socialzoo.reproduce.backend import Backend, run_tasks
from socialzoo.reproduce.ledger import Ledger
from socialzoo.reproduce.paper import PAPER_POLICIES

logger = logging.getLogger(__name__)

DEMOS_FILE = "ref_demos.npz"
RL_ALGOS: tuple[str, ...] = ("ppo", "dqn")
LFD_TRAINERS: tuple[str, ...] = ("bc", "gail")


@dataclass(frozen=True)
class Context:
    """How the parts run.

    Attributes:
        ledger: the work folder and its settings.
        backend: "local" or "ray".
        progress: show progress bars.
    """

    ledger: Ledger
    backend: Backend = "local"
    progress: bool = True

    @property
    def settings(self) -> Any:
        """The run's settings."""
        return self.ledger.settings

    @property
    def ray(self) -> bool:
        """True on the Ray backend (trainings run without progress bars there)."""
        return self.backend == "ray"


# ---------------------------------------------------------------------------- trainings


def _finished(name: str, args: Any) -> bool:
    """True when trainer `name`'s output already holds a finished run of these arguments."""
    from socialzoo.train import trainer_spec
    from socialzoo.train.skeleton import finished_run

    return finished_run(trainer_spec(name), args)


def train_task(item: tuple[str, Any]) -> str:
    """Train one policy (name, trainer arguments) unless finished; returns its file. A Ray task."""
    name, args = item
    from socialzoo.train import trainer_function

    return str(trainer_function(name)(args))


def _train(ctx: Context, items: list[tuple[str, Any]]) -> tuple[list[Path], int]:
    """Train the items (in parallel on Ray); returns (their files, how many were trained now)."""
    todo = sum(not _finished(name, args) for name, args in items)
    files = run_tasks(train_task, items, backend=ctx.backend, workers=ctx.settings.workers)
    return [Path(f) for f in files], todo


def rl_items(ctx: Context) -> list[tuple[str, Any]]:
    """PPO and DQN: the paper's 84,000 steps with a checkpoint every 2,000 (or the quick ones)."""
    from socialzoo.train import trainer_args

    s = ctx.settings
    return [
        (
            algo,
            trainer_args(algo)(
                out=ctx.ledger.path("rl", algo),
                seed=s.seed,
                total_steps=s.rl_total_steps,
                checkpoint_every=s.rl_checkpoint_every,
                progress=ctx.progress and not ctx.ray,
                **dict(s.rl_overrides.get(algo, {})),
            ),
        )
        for algo in RL_ALGOS
    ]


def demos_path(ctx: Context) -> Path:
    """The demonstration file of this run."""
    return ctx.ledger.path("demos", DEMOS_FILE)


def lfd_items(ctx: Context, sizes: tuple[int, ...] | None = None) -> list[tuple[str, Any]]:
    """BC and GAIL at each demonstration size (all of them, or `sizes`), and PIPS."""
    from socialzoo.studies.lfd_training import LfdTrainConfig
    from socialzoo.train.pips import PipsArgs

    s = ctx.settings
    config = LfdTrainConfig(
        demos=demos_path(ctx),
        root=ctx.ledger.path("lfd"),
        algos=LFD_TRAINERS,
        sizes=s.lfd_sizes,
        seed=s.seed,
        overrides={k: v for k, v in s.lfd_overrides.items() if k in LFD_TRAINERS},
        progress=ctx.progress and not ctx.ray,
    )
    items: list[tuple[str, Any]] = [
        (algo, config.args(algo, size)) for algo in LFD_TRAINERS for size in (sizes or s.lfd_sizes)
    ]
    pips = PipsArgs(
        demos=str(demos_path(ctx)),
        out=str(ctx.ledger.path("lfd", f"pips_{s.pips_steps}", "pips.json")),
        steps=s.pips_steps,
        seed=s.seed,
        **dict(s.lfd_overrides.get("pips", {})),
    )
    return [*items, ("pips", pips)]


# ---------------------------------------------------------------------------- parts


def run_demos(ctx: Context) -> int:
    """Record (or resume, or confirm) Ref's demonstrations; returns 1 if anything was recorded."""
    from socialzoo.bench.demonstrations import DemoConfig, record_demonstrations

    s = ctx.settings
    path = demos_path(ctx)
    if path.is_file():
        return 0
    path.parent.mkdir(parents=True, exist_ok=True)
    config = DemoConfig(
        episodes=s.demo_episodes,
        chunk_episodes=min(25, s.demo_episodes),
        batch_size=s.batch_size if s.name == "quick" else 64,
        env_overrides=dict(s.demo_env_overrides),
    )
    record_demonstrations(path, config, progress=ctx.progress)
    return 1


def _store_size(path: Path) -> int:
    from socialzoo.bench.store import ResultsStore

    if not path.is_file():
        return 0
    with ResultsStore(path) as store:
        return len(store)


def run_rl_curves(ctx: Context) -> int:
    """Train PPO and DQN, evaluate every checkpoint; returns the trainings and trials made."""
    from socialzoo.studies.rl_curves import STORE_NAME, rl_curves

    s = ctx.settings
    _, trained = _train(ctx, rl_items(ctx))
    out = ctx.ledger.path("rl", "curves")
    before = _store_size(out / STORE_NAME)
    rl_curves(
        {algo: ctx.ledger.path("rl", algo) for algo in RL_ALGOS},
        out,
        trials=s.curve_trials,
        workers=s.workers,
        batch_size=s.batch_size,
        progress=ctx.progress,
        figure=False,
        env_overrides=dict(s.eval_env_overrides),
        backend=ctx.backend,
    )
    return trained + _store_size(out / STORE_NAME) - before


def run_lfd(ctx: Context) -> int:
    """Demonstrations, BC and GAIL at every size, PIPS, then the LfD table; returns items made."""
    from socialzoo.studies.lfd import run_lfd_evaluation

    s = ctx.settings
    made = run_demos(ctx)
    items = lfd_items(ctx)
    files, trained = _train(ctx, items)
    policies = {(name, int(args.steps)): path for (name, args), path in zip(items, files, strict=True)}
    result = run_lfd_evaluation(
        policies,
        ctx.ledger.path("lfd", "eval"),
        trials=s.lfd_trials,
        workers=s.workers,
        batch_size=s.batch_size,
        env_overrides=dict(s.eval_env_overrides),
        progress=ctx.progress,
        backend=ctx.backend,
    )
    return made + trained + result.computed


def final_policies(ctx: Context) -> tuple[dict[str, Path], int]:
    """The learned policies of the performance experiments (PPO, DQN, BC and GAIL on the largest
    demonstration set, PIPS), training what is missing; returns (name -> file, trainings made)."""
    s = ctx.settings
    made = run_demos(ctx)
    lfd = [(n, a) for n, a in lfd_items(ctx, (s.lfd_largest,))]
    items = rl_items(ctx) + lfd
    files, trained = _train(ctx, items)
    return {name: path for (name, _), path in zip(items, files, strict=True)}, made + trained


def _benchmark(ctx: Context, map_name: str, trials: int, folder: str) -> int:
    from socialzoo.bench.experiment import BenchmarkConfig, run_benchmark

    s = ctx.settings
    files, made = final_policies(ctx)
    config = BenchmarkConfig(
        policies=PAPER_POLICIES,
        maps=(map_name,),
        trials=trials,
        backend=ctx.backend,
        workers=s.workers,
        batch_size=s.batch_size,
        env_overrides=dict(s.eval_env_overrides),
        policy_kwargs={name: {"path": str(path)} for name, path in files.items()},
    )
    result = run_benchmark(config, ctx.ledger.path(folder), progress=ctx.progress, figures=False)
    return made + result.computed


def run_performance(ctx: Context) -> int:
    """The seven policies on the first `performance_trials` gdc1-test scenarios."""
    return _benchmark(ctx, "gdc1", ctx.settings.performance_trials, "performance")


def run_transfer(ctx: Context) -> int:
    """The seven policies on the first `transfer_trials` ghc3-test scenarios."""
    return _benchmark(ctx, "ghc3", ctx.settings.transfer_trials, "transfer")


PART_RUNNERS: dict[str, Callable[[Context], int]] = {
    "demos": run_demos,
    "rl-curves": run_rl_curves,
    "lfd": run_lfd,
    "performance": run_performance,
    "transfer": run_transfer,
}
