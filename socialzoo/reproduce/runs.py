"""The protocol's training runs: every seed's trainer arguments and run folders, and whether a run has finished
(read by the parts that train and by the seed results that aggregate them)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from socialzoo.reproduce.backend import Backend
from socialzoo.reproduce.ledger import Ledger

DEMOS_FILE = "ref_demos.npz"
RL_ALGOS: tuple[str, ...] = ("ppo", "dqn")
LFD_TRAINERS: tuple[str, ...] = ("bc", "gail")
# The folder, inside a benchmark part's, of the later seeds' learned policies.
SEEDS_FOLDER = "seeds"
# The folder, in the work folder, of the seed results (socialzoo.reproduce.seeds.write_seed_results).
SEEDS_DIR = "seeds"


@dataclass(frozen=True)
class Context:
    """How the parts run.

    Attributes:
        ledger: the work folder and its settings.
        backend: "local" or "ray".
        progress: show progress bars.
        reference: the quirk sets of the reference part (socialzoo.env.quirks.ReferenceQuirks.named).
    """

    ledger: Ledger
    backend: Backend = "local"
    progress: bool = True
    reference: tuple[str, ...] = ("all",)

    @property
    def settings(self) -> Any:
        """The run's settings."""
        return self.ledger.settings

    @property
    def pooled(self) -> bool:
        """True when trainings run in other processes (Ray tasks, or several local workers), where
        they show no progress bars."""
        return self.backend == "ray" or self.settings.workers > 1


def finished(name: str, args: Any) -> bool:
    """True when trainer `name`'s output already holds a finished run of these arguments."""
    from socialzoo.train import trainer_spec
    from socialzoo.train.skeleton import finished_run

    return finished_run(trainer_spec(name), args)


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


# The folder of the reference part (`socialzoo reproduce --reference`) in the work folder, and its
# table of every reference-quirks policy's success (one row per quirk set, experiment, policy and
# seed). Every quirk together (ALL_QUIRKS) lives in reference/, one quirk alone in reference/alone/<name>/.
REFERENCE_FOLDER = "reference"
REFERENCE_FILE = "reference.csv"
ALONE_FOLDER = "alone"
# The trainers whose training reads the env's reward, retrained with the reference code's quirks;
# BC, GAIL (its reward is the discriminator's) and PIPS learn from Ref's actions alone.
REFERENCE_TRAINERS: tuple[str, ...] = RL_ALGOS


def quirk_set(row: Mapping[str, Any]) -> str:
    """The quirk set of a reference.csv row (rows written before one quirk could run alone have
    every quirk on)."""
    from socialzoo.env.quirks import ALL_QUIRKS

    return str(row.get("quirks") or ALL_QUIRKS)


def reference_folder(ctx: Context, quirks: str, *parts: str) -> Path:
    """A path in the folder of quirk set `quirks` (socialzoo.env.quirks.ReferenceQuirks.named)."""
    from socialzoo.env.quirks import ALL_QUIRKS

    where = () if quirks == ALL_QUIRKS else (ALONE_FOLDER, quirks)
    return ctx.ledger.path(REFERENCE_FOLDER, *where, *parts)


def reference_trainers(quirks: str) -> tuple[str, ...]:
    """The trainers quirk set `quirks` reaches: those that read the reward when it changes the env
    a learner trains in, else PPO alone when it changes PPO's evaluation, else none."""
    from socialzoo.env.quirks import ReferenceQuirks

    chosen = ReferenceQuirks.named(quirks)
    if chosen.trains:
        return REFERENCE_TRAINERS
    return ("ppo",) if chosen.ppo_eval_without_normalisation else ()


def reference_rl_items(
    ctx: Context, seeds: tuple[int, ...] | None = None, quirks: str = "all"
) -> list[tuple[str, Any]]:
    """The trainings of quirk set `quirks` (reference_trainers) for every seed, as `rl_items` with
    the set in the env config's `quirks`, in its folder's rl/<run>/. A set that changes no training
    env (PPO's evaluation quirk alone) trains nothing of its own: its items are the default runs."""
    import dataclasses

    from socialzoo.env.quirks import ALL_QUIRKS, ReferenceQuirks

    chosen = ReferenceQuirks.named(quirks)
    trainers = reference_trainers(quirks)
    defaults = [(algo, args) for algo, args in rl_items(ctx, seeds) if algo in trainers]
    if not chosen.trains:
        return defaults
    # Every quirk together keeps the record its runs have always had (every switch named); one quirk
    # alone names just that switch.
    switches = dataclasses.asdict(chosen) if quirks == ALL_QUIRKS else {quirks: True}
    items = []
    for algo, args in defaults:
        env = {**dict(args.env_overrides), "quirks": switches}
        out = reference_folder(ctx, quirks, "rl", Path(args.out).name)
        items.append((algo, dataclasses.replace(args, out=out, env_overrides=env)))
    return items


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


def lfd_eval_dir(ctx: Context, seed: int) -> Path:
    """The LfD evaluation folder of one seed's policies (lfd/eval for the first seed)."""
    return ctx.ledger.path("lfd", run_name("eval", seed, ctx.settings))
