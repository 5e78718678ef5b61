"""The runner of each part of the reproduction (socialzoo.reproduce.plan.PARTS).

Every part composes pieces that store their items as they finish, so a part is resumable:

- demos: Ref's demonstrations (socialzoo.bench.demonstrations, chunk by chunk).
- rl-curves: PPO and DQN training runs (socialzoo.train, checkpoints) and every checkpoint on the
  first gdc1-test scenarios (socialzoo.studies.rl_curves, one stored trial at a time).
- lfd: BC and GAIL at each demonstration size and PIPS, then the LfD table (socialzoo.studies.lfd).
- performance / transfer: the seven policies on gdc1-test / ghc3-test (socialzoo.bench.experiment),
  and the other seeds' learned policies in <part>/seeds/.

Every learned policy is trained with each of settings.seed_list (`--seeds K`): run folders
"<name>" for the first seed (as with one seed) and "<name>-s<seed>" for the others, each with its
own policy file and trials, so a part resumes seed by seed. Trainings run side by side
(socialzoo.reproduce.backend: `workers` local processes, or Ray tasks). A run that evaluated its
checkpoints on validation scenarios (PPO and DQN, settings.select_trials) keeps its best one
(socialzoo.train.validation.kept_policy): that is the policy of `performance` and `transfer`.

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
        """True on the Ray backend."""
        return self.backend == "ray"

    @property
    def pooled(self) -> bool:
        """True when trainings run in other processes (Ray tasks, or several local workers), where
        they show no progress bars."""
        return self.ray or self.settings.workers > 1


# ---------------------------------------------------------------------------- trainings


def _finished(name: str, args: Any) -> bool:
    """True when trainer `name`'s output already holds a finished run of these arguments."""
    from socialzoo.train import trainer_spec
    from socialzoo.train.skeleton import finished_run

    return finished_run(trainer_spec(name), args)


def train_task(item: tuple[str, Any]) -> str:
    """Train one policy (name, trainer arguments) unless finished; returns its file. A task of
    socialzoo.reproduce.backend.run_tasks (a local process or a Ray task)."""
    name, args = item
    from socialzoo.train import trainer_function

    return str(trainer_function(name)(args))


def _train(ctx: Context, items: list[tuple[str, Any]]) -> tuple[list[Path], int]:
    """Train the items side by side (`workers` local processes or Ray tasks); returns (the policy
    each run keeps, how many were trained now). A run that evaluated its checkpoints on
    validation scenarios keeps its best one (socialzoo.train.validation.kept_policy)."""
    from socialzoo.train.validation import kept_policy

    todo = sum(not _finished(name, args) for name, args in items)
    pending = [(name, args) for name, args in items if not _finished(name, args)]
    if pending:
        run_tasks(train_task, pending, backend=ctx.backend, workers=ctx.settings.workers)
    files = [train_task(item) for item in items]  # finished now: each returns its policy at once
    return [kept_policy(f) for f in files], todo


def run_name(base: str, seed: int, settings: Any) -> str:
    """The folder (and curve label) of one seed's run: `base` for the first seed, as with a single
    seed, and "<base>-s<seed>" for the others."""
    return base if seed == settings.seed else f"{base}-s{seed}"


def rl_items(ctx: Context, seeds: tuple[int, ...] | None = None) -> list[tuple[str, Any]]:
    """PPO and DQN of every seed: the paper's 84,000 steps with a checkpoint every 2,000 (or the
    quick ones), checkpoints evaluated on validation scenarios when settings.select_trials > 0."""
    from socialzoo.train import trainer_args

    s = ctx.settings
    select = {"eval_trials": s.select_trials, "eval_every": s.select_every} if s.select_trials else {}
    return [
        (
            algo,
            trainer_args(algo)(
                out=ctx.ledger.path("rl", run_name(algo, seed, s)),
                seed=seed,
                total_steps=s.rl_total_steps,
                checkpoint_every=s.rl_checkpoint_every,
                progress=ctx.progress and not ctx.pooled,
                **select,
                **dict(s.rl_overrides.get(algo, {})),
            ),
        )
        for seed in (seeds or s.seed_list)
        for algo in RL_ALGOS
    ]


def demos_path(ctx: Context) -> Path:
    """The demonstration file of this run."""
    return ctx.ledger.path("demos", DEMOS_FILE)


def lfd_items(
    ctx: Context, sizes: tuple[int, ...] | None = None, seeds: tuple[int, ...] | None = None
) -> list[tuple[str, Any]]:
    """BC and GAIL at each demonstration size (all of them, or `sizes`), and PIPS, for every seed
    (all of them, or `seeds`), seed by seed."""
    import dataclasses

    from socialzoo.studies.lfd_training import LfdTrainConfig
    from socialzoo.train.pips import PipsArgs

    s = ctx.settings
    items: list[tuple[str, Any]] = []
    for seed in seeds or s.seed_list:
        config = LfdTrainConfig(
            demos=demos_path(ctx),
            root=ctx.ledger.path("lfd"),
            algos=LFD_TRAINERS,
            sizes=s.lfd_sizes,
            seed=seed,
            overrides={k: v for k, v in s.lfd_overrides.items() if k in LFD_TRAINERS},
            progress=ctx.progress and not ctx.pooled,
        )
        for algo in LFD_TRAINERS:
            for size in sizes or s.lfd_sizes:
                folder = ctx.ledger.path("lfd", run_name(f"{algo}_{size}", seed, s))
                items.append((algo, dataclasses.replace(config.args(algo, size), out=folder)))
        pips_folder = run_name(f"pips_{s.pips_steps}", seed, s)
        pips = PipsArgs(
            demos=str(demos_path(ctx)),
            out=str(ctx.ledger.path("lfd", pips_folder, "pips.json")),
            steps=s.pips_steps,
            seed=seed,
            **dict(s.lfd_overrides.get("pips", {})),
        )
        items.append(("pips", pips))
    return items


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
    """Train PPO and DQN (every seed), evaluate every checkpoint; returns the trainings and trials
    made. Curve labels are the run folders' names ("ppo", "ppo-s1", ...): every seed is a curve."""
    from socialzoo.studies.rl_curves import STORE_NAME, rl_curves

    s = ctx.settings
    items = rl_items(ctx)
    _, trained = _train(ctx, items)
    out = ctx.ledger.path("rl", "curves")
    before = _store_size(out / STORE_NAME)
    rl_curves(
        {Path(args.out).name: Path(args.out) for _, args in items},
        out,
        trials=s.curve_trials,
        workers=s.workers,
        batch_size=s.batch_size,
        progress=ctx.progress,
        figure=False,
        env_overrides=dict(s.eval_env_overrides),
        backend=ctx.backend,
    )
    _write_seed_results(ctx)
    return trained + _store_size(out / STORE_NAME) - before


def lfd_eval_dir(ctx: Context, seed: int) -> Path:
    """The LfD evaluation folder of one seed's policies (lfd/eval for the first seed)."""
    return ctx.ledger.path("lfd", run_name("eval", seed, ctx.settings))


def run_lfd(ctx: Context) -> int:
    """Demonstrations, BC and GAIL at every size, PIPS (every seed), then the LfD table of each
    seed (lfd/eval/lfd.csv is the first seed's); returns items made."""
    from socialzoo.studies.lfd import run_lfd_evaluation

    s = ctx.settings
    made = run_demos(ctx)
    items = lfd_items(ctx)
    files, trained = _train(ctx, items)
    for seed in s.seed_list:
        policies = {
            (name, int(args.steps)): path
            for (name, args), path in zip(items, files, strict=True)
            if args.seed == seed
        }
        result = run_lfd_evaluation(
            policies,
            lfd_eval_dir(ctx, seed),
            trials=s.lfd_trials,
            workers=s.workers,
            batch_size=s.batch_size,
            env_overrides=dict(s.eval_env_overrides),
            progress=ctx.progress,
            backend=ctx.backend,
        )
        made += result.computed
    _write_seed_results(ctx)
    return made + trained


def final_policies(ctx: Context) -> tuple[dict[int, dict[str, Path]], int]:
    """The learned policies of the performance experiments (PPO, DQN, BC and GAIL on the largest
    demonstration set, PIPS) of every seed, training what is missing; each run's kept policy
    (its best validation checkpoint where it has one). Returns ({seed: {name: file}}, trainings
    made)."""
    s = ctx.settings
    made = run_demos(ctx)
    items = rl_items(ctx) + lfd_items(ctx, (s.lfd_largest,))
    files, trained = _train(ctx, items)
    out: dict[int, dict[str, Path]] = {seed: {} for seed in s.seed_list}
    for (name, args), path in zip(items, files, strict=True):
        out[int(args.seed)][name] = path
    return out, made + trained


SEEDS_FOLDER = "seeds"


def _benchmark(ctx: Context, map_name: str, trials: int, folder: str) -> int:
    """The seven policies (the learned ones of the first seed) on the first `trials` scenarios of
    the map's test set into <folder>/, and, with several seeds, the other seeds' learned policies
    on the first settings.seed_trials (or `trials`) into <folder>/seeds/."""
    from socialzoo.bench.experiment import BenchmarkConfig, run_benchmark

    s = ctx.settings
    files, made = final_policies(ctx)
    common = {
        "maps": (map_name,),
        "backend": ctx.backend,
        "workers": s.workers,
        "batch_size": s.batch_size,
        "env_overrides": dict(s.eval_env_overrides),
    }
    config = BenchmarkConfig(
        policies=PAPER_POLICIES,
        trials=trials,
        policy_kwargs={name: {"path": str(path)} for name, path in files[s.seed].items()},
        **common,
    )
    result = run_benchmark(config, ctx.ledger.path(folder), progress=ctx.progress, figures=False)
    made += result.computed
    others = [f"{name}:{path}" for seed in s.seed_list[1:] for name, path in files[seed].items()]
    if others:
        config = BenchmarkConfig(
            policies=tuple(others), trials=min(trials, s.seed_trials or trials), **common
        )
        result = run_benchmark(
            config, ctx.ledger.path(folder, SEEDS_FOLDER), progress=ctx.progress, figures=False
        )
        made += result.computed
    _write_seed_results(ctx)
    return made


def run_performance(ctx: Context) -> int:
    """The seven policies on the first `performance_trials` gdc1-test scenarios (and the other
    seeds' learned policies)."""
    return _benchmark(ctx, "gdc1", ctx.settings.performance_trials, "performance")


def run_transfer(ctx: Context) -> int:
    """The seven policies on the first `transfer_trials` ghc3-test scenarios (and the other seeds'
    learned policies)."""
    return _benchmark(ctx, "ghc3", ctx.settings.transfer_trials, "transfer")


def _write_seed_results(ctx: Context) -> None:
    """Rewrite the work folder's seed results (socialzoo.reproduce.seeds) from what is stored."""
    from socialzoo.reproduce.seeds import write_seed_results

    write_seed_results(ctx)


PART_RUNNERS: dict[str, Callable[[Context], int]] = {
    "demos": run_demos,
    "rl-curves": run_rl_curves,
    "lfd": run_lfd,
    "performance": run_performance,
    "transfer": run_transfer,
}
