"""Experiment 2's training half (SPEC section 10, LfD data efficiency): BC and GAIL trained on
155,400 / 116,600 / 77,700 / 38,800 / 3,500 steps of ONE Ref demonstration recording."""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from socialzoo.core.validation import check_int
from socialzoo.studies.lfd import LFD_ALGOS, LFD_SIZES, lfd_run_dir
from socialzoo.train import trainer_args, trainer_function
from socialzoo.train.checks import check_sizes

logger = logging.getLogger(__name__)

# Episodes of the demonstration recording: Ref's gdc1 episodes average about 1,300 steps, so 125
# give a little over the largest size (155,400 steps).
LFD_DEMO_EPISODES = 125


@dataclass(frozen=True, kw_only=True)
class LfdTrainConfig:
    """What the LfD experiment trains.

    Attributes:
        demos: the demonstration file; recorded (Ref on gdc1, `demo_episodes` episodes) if missing.
        root: the experiment folder; run <root>/<algorithm>_<size>/ per policy.
        algos: trainers to run ("bc", "gail").
        sizes: demonstration steps of each run (the first ones of the recording).
        seed: every run's seed.
        demo_episodes: episodes to record when `demos` is missing.
        overrides: per trainer, argument overrides (plain values), e.g. {"gail": {"total_steps": 2e5}}.
        progress: show progress bars.
    """

    demos: Path
    root: Path
    algos: tuple[str, ...] = LFD_ALGOS
    sizes: tuple[int, ...] = LFD_SIZES
    seed: int = 0
    demo_episodes: int = LFD_DEMO_EPISODES
    overrides: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    progress: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "demos", Path(self.demos))
        object.__setattr__(self, "root", Path(self.root))
        object.__setattr__(self, "algos", tuple(self.algos))
        object.__setattr__(self, "sizes", tuple(self.sizes))
        for algo in (*self.algos, *self.overrides):
            trainer_args(algo)  # an unknown trainer raises, listing the known ones
        unknown = sorted(set(self.overrides) - set(self.algos))
        if unknown:
            raise ValueError(f"LfdTrainConfig.overrides names trainers not run: {unknown}")
        check_sizes(self, "sizes")
        check_int("LfdTrainConfig", "demo_episodes", self.demo_episodes, low=1)
        for algo in self.algos:  # bad overrides fail now, not after hours of training
            self.args(algo, self.sizes[0])

    def args(self, algo: str, size: int) -> Any:
        """The trainer arguments of one run."""
        cls = trainer_args(algo)
        names = {f.name for f in dataclasses.fields(cls)}
        extra = dict(self.overrides.get(algo, {}))
        bad = sorted(set(extra) - names)
        if bad:
            raise ValueError(f"LfdTrainConfig.overrides[{algo!r}]: unknown argument(s) {bad}")
        base = {
            "demos": self.demos,
            "steps": size,
            "seed": self.seed,
            "out": lfd_run_dir(self.root, algo, size),
            "progress": self.progress,
        }
        return cls(**{**base, **extra})


def record_lfd_demos(path: str | Path, episodes: int = LFD_DEMO_EPISODES, progress: bool = True) -> Path:
    """Record Ref's demonstrations on gdc1 into `path` (resumes a partial recording)."""
    from socialzoo.bench.demonstrations import DemoConfig, record_demonstrations

    config = DemoConfig(episodes=episodes, chunk_episodes=episodes, batch_size=64)
    return record_demonstrations(path, config, progress=progress)


def train_lfd(config: LfdTrainConfig) -> dict[tuple[str, int], Path]:
    """Record the demonstrations if needed, then train every (algorithm, size).

    Records the demonstrations when the file is missing (about 155,000 steps of Ref on gdc1 scenarios of their
    own seeds), then trains every (algorithm, size) into <root>/<algorithm>_<size>/ with the trainers' own
    defaults plus the given overrides. Each run is skipped when its folder holds a finished run of the same
    arguments, so an interrupted experiment resumes run by run.

    Returns:
        (algorithm, size) -> policy file, the mapping socialzoo.studies.lfd.run_lfd_evaluation takes.
    """
    if not config.demos.exists():
        logger.info("lfd: recording %d Ref episodes into %s", config.demo_episodes, config.demos)
        record_lfd_demos(config.demos, config.demo_episodes, config.progress)
    files = {}
    for algo in config.algos:
        for size in config.sizes:
            logger.info("lfd: %s on %d demonstration steps", algo, size)
            files[(algo, size)] = trainer_function(algo)(config.args(algo, size))
    return files
