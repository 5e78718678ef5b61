"""Choose a learned-human checkpoint on validation scenarios: the comparison with social-force
humans (socialzoo.studies.human_compare) for every checkpoint of a training run, never a test set."""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from socialzoo.core.files import json_text, write_text_atomic
from socialzoo.scenarios.scenario_sets import TestSet
from socialzoo.studies.human_compare import (
    COLLISION_KEYS,
    POPULATIONS,
    REACH_TOLERANCE,
    ComparisonConfig,
    compare_humans,
    write_comparison_csv,
)
from socialzoo.studies.rl_curves import step_files

SELECTED_FILE = "humans.safetensors"
# Per checkpoint: (column, summary key of the learned population).
COLUMNS: tuple[tuple[str, str], ...] = (
    ("reach_rate", "humans_goal_rate_mean"),
    ("hh_collisions", "humans_hh_collisions_mean"),
    ("hw_collisions", "humans_hw_collisions_mean"),
    ("hr_collisions", "humans_hr_collisions_mean"),
    ("mean_speed", "humans_mean_speed_mean"),
    ("robot_success", "success_rate"),
)


@dataclass(frozen=True)
class Selection:
    """What select_humans found.

    Attributes:
        chosen: the chosen checkpoint file (in the run folder).
        frames: its training frames.
        met: it meets both targets on the validation scenarios.
        rows: one dict per checkpoint (frames, file, the COLUMNS, the targets, the miss score),
            then the social-force row (frames None).
        out_dir: where the selection was written; out_dir/humans.safetensors is the chosen file.
    """

    chosen: Path
    frames: int
    met: bool
    rows: list[dict[str, Any]]
    out_dir: Path


def run_checkpoints(run_dir: str | Path) -> list[tuple[int, Path]]:
    """(frames, file) of every learned-human checkpoint in run_dir/checkpoints, by frames.

    Raises:
        FileNotFoundError: no such folder, or no checkpoint in it (naming the folder).
    """
    return step_files(run_dir, ".humans.safetensors", "learned-human checkpoints")


def training_map(run_dir: str | Path) -> str:
    """The map a run trained on (run_dir/run.json, args.map)."""
    return training_world(run_dir)[0]


def training_world(run_dir: str | Path) -> tuple[str, str | None]:
    """The map and the scenario family (None: the benchmark's scenarios) a run trained on:
    run_dir/run.json's args.map, and its args.family or the family of its env_overrides (a humans
    or cotrain run takes EnvConfig fields there).

    Raises:
        ValueError: no map recorded, or a family that is not a name (naming the file).
    """
    path = Path(run_dir) / "run.json"
    try:
        args = json.loads(path.read_text())["args"]
        map_name = str(args["map"])
        family = args.get("family") or (args.get("env_overrides") or {}).get("family")
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as err:
        raise ValueError(f"{path}: no training map recorded ({err})") from None
    if family is not None and not isinstance(family, str):
        raise ValueError(f"{path}: the recorded scenario family must be a name, got {family!r}")
    return map_name, family


def miss_score(learned: Mapping[str, float], social: Mapping[str, float]) -> float:
    """How far a checkpoint misses the targets: the largest of its reach-rate shortfall below the
    tolerance and its relative excess of each kind of collision; 0 when it meets both."""
    reach_needed = (1 - REACH_TOLERANCE) * social["humans_goal_rate_mean"]
    misses = [max(0.0, reach_needed - learned["humans_goal_rate_mean"]) / max(reach_needed, 1e-9)]
    for key in COLLISION_KEYS:
        mine, theirs = learned[f"{key}_mean"], social[f"{key}_mean"]
        misses.append(max(0.0, mine - theirs) / max(theirs, 1e-9))
    return max(misses)


def select_humans(
    run_dir: str | Path,
    out_dir: str | Path | None = None,
    *,
    trials: int = 100,
    policy: str = "ref",
    workers: int | None = 2,
    batch_size: int = 64,
    test_set: TestSet | None = None,
    env_overrides: Mapping[str, Any] | None = None,
    progress: bool = True,
) -> Selection:
    """Compare every checkpoint of a run with the social-force humans and keep the best one.

    Why: the learned humans' reward is a proxy for what the comparison measures, and a longer run is not
    always closer to the targets (with the default reward, wall contacts grow after the first 100,000-200,000
    frames).

    Runs the comparison for each checkpoint of a run folder (`socialzoo train humans`) on the validation
    scenarios of the training map (socialzoo.scenarios.scenario_sets.validation_set), or for a run trained
    on a scenario family (its run.json's env_overrides "family") on the family's validation cases on that
    map ("<family>-val", socialzoo.bench.test_sets.family_validation_set), and keeps the most
    trained checkpoint that meets both of issue 13's targets there (reach rate within 10% of the social-force
    humans', no more collisions of any kind); when none does, the one that misses them by the least (the
    largest relative excess of collisions, or shortfall of reach rate, smallest). It writes OUT/selection.csv
    and selection.md (every checkpoint's reach rate and collisions), OUT/selection.json, and copies the chosen
    file to OUT/humans.safetensors. The social-force runs are shared by every checkpoint (one results store),
    and every learned run is stored: an interrupted selection resumes where it stopped.

    Args:
        run_dir: a `socialzoo train humans` (or cotrain) run folder.
        out_dir: where to write; run_dir/selection by default.
        trials: validation scenarios per checkpoint (the first of the set).
        policy: the robot's policy spec during the comparison.
        workers: local processes.
        batch_size: env rows per worker.
        test_set: scenarios to use instead of the training map's validation set (for tests);
            a test set ("-test", "-quick") is refused.
        env_overrides: EnvConfig fields for both populations (e.g. {"max_steps": 1600}).
        progress: show progress bars.
    """
    run = Path(run_dir)
    out = Path(out_dir) if out_dir is not None else run / "selection"
    checkpoints = run_checkpoints(run)
    map_name, family = training_world(run)
    if test_set is not None:
        map_name, family = test_set.map_name, getattr(test_set, "family", None) or None
    if test_set is not None and test_set.name.endswith(("-test", "-quick")):
        raise ValueError(
            f"select_humans chooses a checkpoint: use validation scenarios, not {test_set.name!r}"
        )
    # A given family's cases (FamilyCases) are played with the family, as ComparisonConfig.family does.
    given_family = {} if test_set is None or family is None else {"family": family}
    rows: list[dict[str, Any]] = []
    social: dict[str, Any] = {}
    for frames, path in checkpoints:
        config = ComparisonConfig(
            humans=f"learned:{path}",
            policy=policy,
            maps=(map_name,),
            trials=trials,
            validation=test_set is None,
            workers=workers,
            batch_size=batch_size,
            env_overrides={**dict(env_overrides or {}), **given_family},
            family=family if test_set is None else None,
        )
        sets = None if test_set is None else {map_name: test_set}
        result = compare_humans(config, out / "runs", test_sets=sets, progress=progress, figures=False)
        by = {r["population"]: r for r in result.rows}
        if set(by) != set(POPULATIONS):
            raise RuntimeError(f"select_humans: the comparison of {path} has no rows for both populations")
        social = by["social_force"]
        (target,) = result.targets.values()  # one map, under its display name
        rows.append(
            {
                "frames": frames,
                "file": str(path),
                **{col: by["learned"].get(key, float("nan")) for col, key in COLUMNS},
                "reach_met": target["reach"],
                "collisions_met": target["collisions"],
                "met": target["met"],
                "miss": miss_score(by["learned"], social),
            }
        )
    meeting = [r for r in rows if r["met"]]
    best = meeting[-1] if meeting else min(rows, key=lambda r: (r["miss"], -r["frames"]))
    rows.append(
        {"frames": None, "file": "social_force", **{c: social.get(k, float("nan")) for c, k in COLUMNS}}
    )
    chosen = Path(best["file"])
    out.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(chosen, out / SELECTED_FILE)
    scenarios = test_set.name if test_set is not None else f"{family or map_name}-val"

    def from_out(path: str | Path) -> str:
        """A path as the files written in `out` name it: relative to `out`, never the machine's absolute
        one (a selection is shipped and read elsewhere)."""
        return os.path.relpath(path, out)

    # The tables and the record name the checkpoints from `out`; the rows returned keep the paths given.
    written = [{**r, "file": from_out(r["file"])} if r["frames"] is not None else r for r in rows]
    record = {
        "run": from_out(run),
        "map": from_out(map_name) if map_name.endswith(".json") and Path(map_name).is_file() else map_name,
        "scenarios": scenarios,
        "family": family,
        "trials": trials,
        "robot_policy": policy,
        "rule": "the most trained checkpoint meeting both targets; else the one missing them by the least",
        "chosen": {"file": from_out(chosen), "frames": best["frames"], "met": best["met"]},
        "checkpoints": written[:-1],
        "social_force": written[-1],
    }
    write_text_atomic(out / "selection.json", json_text(record, indent=1) + "\n")
    _write_tables(written, written[rows.index(best)], out, scenarios)
    return Selection(chosen, int(best["frames"]), bool(best["met"]), rows, out)


def _write_tables(rows: list[dict[str, Any]], best: dict[str, Any], out: Path, scenarios: str) -> None:
    """selection.csv (every column) and selection.md (a row per checkpoint, the chosen one marked)."""
    write_comparison_csv(rows, out / "selection.csv")
    md = [
        f"# Checkpoint selection on {scenarios} (validation scenarios, not a test set)",
        "",
        "| frames | reach rate | human-human | human-wall | human-robot | mean speed | robot success | targets |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        label = "social-force" if r["frames"] is None else f"{r['frames']:,}"
        if r is best:
            label = f"**{label}** (chosen)"
        targets = "" if r["frames"] is None else ("met" if r["met"] else f"missed by {r['miss']:.0%}")
        md.append(
            f"| {label} | {r['reach_rate']:.3f} | {r['hh_collisions']:.2f} | {r['hw_collisions']:.2f} | "
            f"{r['hr_collisions']:.3f} | {r['mean_speed']:.3f} | {r['robot_success']:.2f} | {targets} |"
        )
    write_text_atomic(out / "selection.md", "\n".join(md) + "\n")
