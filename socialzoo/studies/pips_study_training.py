"""PIPS beyond the paper, training half: programs synthesised from 500 / 1,000 / 3,500 / 10,000 demonstration
steps, each with the paper's windowing (20 steps around a change of action) and without it (window 0)."""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from socialzoo.studies.pips_study import STUDY_STEPS, STUDY_WINDOWS, study_program_file
from socialzoo.train.checks import check_sizes
from socialzoo.train.pips import TRAINER, PipsArgs, sidecar_path, train
from socialzoo.train.skeleton import finished_run

logger = logging.getLogger(__name__)

# Arguments a cell sets itself; overrides may not name them.
_CELL_FIELDS = ("demos", "out", "steps", "window", "seed")


@dataclass(frozen=True, kw_only=True)
class PipsStudyConfig:
    """What the PIPS study synthesises.

    Attributes:
        demos: the demonstration file (`socialzoo demos`, training scenarios); the first `steps`
            steps of it are each cell's data.
        root: the study folder; cell (steps, window) goes to <root>/pips_<steps>_w<window>/.
        steps: demonstration steps of the cells.
        windows: windows of the cells (0: no windowing).
        seed: every cell's seed (z3's; the search is deterministic).
        overrides: other PipsArgs fields, the same for every cell, e.g. {"max_depth": 1}.
    """

    demos: Path
    root: Path
    steps: tuple[int, ...] = STUDY_STEPS
    windows: tuple[int, ...] = STUDY_WINDOWS
    seed: int = 0
    overrides: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "demos", Path(self.demos))
        object.__setattr__(self, "root", Path(self.root))
        object.__setattr__(self, "steps", tuple(self.steps))
        object.__setattr__(self, "windows", tuple(self.windows))
        object.__setattr__(self, "overrides", dict(self.overrides))
        for name, low in (("steps", 1), ("windows", 0)):
            check_sizes(self, name, low=low)
            values = getattr(self, name)
            if len(set(values)) != len(values):
                raise ValueError(f"PipsStudyConfig.{name} has duplicates: {values!r}")
        names = {f.name for f in dataclasses.fields(PipsArgs)}
        bad = sorted(set(self.overrides) - (names - set(_CELL_FIELDS)))
        if bad:
            raise ValueError(
                f"PipsStudyConfig.overrides: unknown or per-cell PipsArgs field(s) {bad} "
                f"(a cell sets {list(_CELL_FIELDS)} itself)"
            )
        self.args(self.steps[0], self.windows[0])  # bad values fail now, before any synthesis

    def args(self, steps: int, window: int) -> PipsArgs:
        """The synthesis arguments of one cell."""
        return PipsArgs(
            demos=str(self.demos),
            out=str(study_program_file(self.root, steps, window)),
            steps=steps,
            window=window,
            seed=self.seed,
            **self.overrides,
        )


def train_pips_study(config: PipsStudyConfig) -> dict[tuple[int, int], Path]:
    """Synthesise every (steps, window) cell, skipping finished ones.

    Window 0: every step is an example. Runs `socialzoo.train.pips.train` once per (steps, window) cell into
    <root>/pips_<steps>_w<window>/pips.json (with its .train.json record: arguments, seed, synthesis time),
    all from one demonstration file recorded on training scenarios. A cell whose record holds the same
    arguments is not synthesised again, so an interrupted study resumes cell by cell; a cell of other
    arguments (other overrides) is synthesised again in place.

    Returns:
        (steps, window) -> program file, the mapping socialzoo.studies.pips_study.run_pips_study
        takes.

    Raises:
        FileNotFoundError: the demonstration file does not exist.
    """
    if not config.demos.is_file():
        raise FileNotFoundError(f"PIPS study: no demonstration file {config.demos}")
    files = {}
    for window in config.windows:
        for steps in config.steps:
            args = config.args(steps, window)
            if finished_run(TRAINER, args):
                logger.info("PIPS study: %d steps, window %d: already synthesised", steps, window)
            else:
                # A cell is named by its steps and window only: a study run with other overrides
                # replaces the cell's program rather than being refused for the other arguments.
                sidecar_path(args.out).unlink(missing_ok=True)
                logger.info("PIPS study: synthesising from %d steps, window %d", steps, window)
                train(args)
            files[(steps, window)] = Path(args.out)
    return files
