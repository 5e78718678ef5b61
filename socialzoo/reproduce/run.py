"""The whole reproduction: run the chosen parts in order (each timed and resumable), then copy the small results out
and write the tables, figures and REPRODUCTION.md."""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from socialzoo.reproduce.backend import Backend, check_backend
from socialzoo.reproduce.ledger import Ledger
from socialzoo.reproduce.parts import PART_RUNNERS
from socialzoo.reproduce.plan import PARTS, REFERENCE_PART, Settings, parse_parts, reference_sets
from socialzoo.reproduce.report import write_report
from socialzoo.reproduce.results import collect
from socialzoo.reproduce.runs import Context

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class ReproduceResult:
    """What a reproduction produced.

    Attributes:
        out_dir: DIR.
        work_dir: DIR/<hash>/, the stored items.
        report: DIR/REPRODUCTION.md.
        made: items made by each part run now (0: all read back).
    """

    out_dir: Path
    work_dir: Path
    report: Path
    made: dict[str, int]


def reproduce(
    out_dir: str | Path,
    settings: Settings,
    *,
    parts: Sequence[str] | str | None = None,
    backend: Backend = "local",
    progress: bool = True,
    on_part: Callable[[str, int], None] | None = None,
    reference: bool | str | Sequence[str] = False,
) -> ReproduceResult:
    """Run `parts` (default: all, in PARTS order) of the reproduction into out_dir.

    Args:
        out_dir: DIR: items go to DIR/<settings hash>/, the report to DIR.
        settings: what to train and evaluate (socialzoo.reproduce.plan).
        parts: part names or a comma-separated string.
        backend: "local" or "ray" (trainings and evaluations as Ray tasks).
        progress: show progress bars.
        on_part: called with (part, items made) after each part.
        reference: then run the reference part (REFERENCE_PART): PPO and DQN trained and
            evaluated with the reference code's quirks, reported beside ours and the paper's. True:
            every quirk together; quirk set names (comma-separated or a sequence: "all" or one
            switch of socialzoo.env.quirks.ReferenceQuirks): each set on its own.

    Raises:
        ValueError: an unknown part, backend or quirk.
        socialzoo.reproduce.ledger.SettingsMismatch: DIR/<hash>/ holds other settings.
    """
    chosen = parse_parts(parts if parts is None or isinstance(parts, str) else list(parts))
    check_backend(backend)
    ledger = Ledger(out_dir, settings)
    sets = reference_sets(reference)
    ctx = Context(ledger, backend=backend, progress=progress, reference=sets or ("all",))
    made = {}
    for part in (*PARTS, REFERENCE_PART):
        if part not in chosen and not (sets and part == REFERENCE_PART):
            continue
        logger.info("reproduce: part %s (%s)", part, ledger.work)
        with ledger.timed(part, backend) as session:
            made[part] = PART_RUNNERS[part](ctx)
            session["computed"] = made[part]
        collect(ledger, out_dir, chosen)
        write_report(out_dir, figures=False)
        if on_part is not None:
            on_part(part, made[part])
    collect(ledger, out_dir, chosen)
    report = write_report(out_dir)
    return ReproduceResult(Path(out_dir), ledger.work, report, made)
