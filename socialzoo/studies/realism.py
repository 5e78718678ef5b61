"""Which crowd model walks most like real people: each recorded ETH/UCY person walked by a model among the others
replayed, against its own track (issue 37, item 4; protocol: docs/humans.md, "Realism against recorded people")."""

from __future__ import annotations

import dataclasses
import math
import platform
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from socialzoo.bench.progress import progress_bar
from socialzoo.bench.tables import markdown_table as table_lines
from socialzoo.bench.tables import write_csv
from socialzoo.core.files import json_text
from socialzoo.studies.realism_cases import (
    OBS_FRAMES,
    PRED_FRAMES,
    load_tracks,
    sample_persons,
    track_cases,
    window_cases,
)
from socialzoo.studies.realism_metrics import (
    COLLISION_DISTANCE,
    METRICS,
    SceneResult,
    evaluate_model,
    recorded_reference,
)
from socialzoo.studies.realism_simulation import (
    BASE_MODELS,
    GROUP_DISTANCE,
    GROUP_SPEED,
    REALISM_DT,
    model_spec,
    realism_world,
)

SCENES = ("eth", "hotel", "univ", "zara1", "zara2")


@dataclass(frozen=True, kw_only=True)
class RealismConfig:
    """One realism run.

    Attributes:
        scenes: ETH/UCY scene names or track files (PATH or NAME=PATH: socialzoo.data.fetch.load_recording).
        models: model names (model_spec).
        tracks: persons per scene (a seeded sample), None for all.
        seed: the sample's seed.
        cache: the scenes' cache folder (None: socialzoo.data.fetch.data_dir()).
    """

    scenes: tuple[str, ...] = SCENES
    models: tuple[str, ...] = BASE_MODELS
    tracks: int | None = None
    seed: int = 0
    cache: str | None = None

    def __post_init__(self) -> None:
        if not self.scenes:
            raise ValueError("RealismConfig.scenes must name at least one scene")
        if not self.models:
            raise ValueError("RealismConfig.models must name at least one model")
        for name in self.models:
            spec = model_spec(name)
            if spec.people.startswith("learned:"):
                _check_learned(spec.people.partition(":")[2], name)
        if len(set(self.models)) != len(self.models):
            raise ValueError(f"RealismConfig.models has duplicates: {list(self.models)!r}")
        if self.tracks is not None and (not isinstance(self.tracks, int) or self.tracks < 1):
            raise ValueError(f"RealismConfig.tracks must be None or an int >= 1, got {self.tracks!r}")


def _check_learned(path: str, name: str) -> None:
    """Refuse model `name`'s learned policy file when it cannot be loaded, before any scene is walked."""
    from socialzoo.core.files import no_file
    from socialzoo.env.human_policy import LearnedHumanPolicy

    if not Path(path).is_file():
        raise ValueError(f"RealismConfig.models: {name}: {no_file(path, 'learned policy file')}")
    try:
        LearnedHumanPolicy.load(path)
    except ValueError as err:  # PolicyFileError: not a learned human policy, naming the file
        raise ValueError(f"RealismConfig.models: {name}: {err}") from None


def run_realism(
    config: RealismConfig,
    out: Path,
    *,
    progress: bool = True,
    figures: bool = True,
    argv: Sequence[str] | None = None,
) -> list[SceneResult]:
    """Run the study and write out/realism.csv, realism.md, realism.json (the run record) and the
    figures (ade.png, speeds.png); returns every scene's and model's result."""
    out.mkdir(parents=True, exist_ok=True)
    specs = [model_spec(m) for m in config.models]
    scenes = [load_tracks(s, config.cache) for s in config.scenes]
    plan = []
    for scene in scenes:
        persons = sample_persons(scene, config.tracks, config.seed)
        plan.append((scene, window_cases(scene, persons), track_cases(scene, persons)))
    total = sum((len(w) + len(t)) * len(specs) for _, w, t in plan)
    bar = progress_bar(total, "realism", enabled=progress, unit="case")
    results: list[SceneResult] = []
    started = time.perf_counter()
    for scene, windows, tracks in plan:
        results.append(recorded_reference(scene, windows, tracks))
        for spec in specs:
            bar.set_postfix_str(f"{scene.name} {spec.name}")
            results.append(evaluate_model(scene, windows, tracks, spec, progress=bar.update))
    bar.close()
    results.extend(overall(results, [p[0].name for p in plan]))
    write_tables(results, out)
    if figures:
        write_figures(results, out)
    record = {
        "command": " ".join(["socialzoo", *(sys.argv[1:] if argv is None else argv)]),
        "config": dataclasses.asdict(config),
        "seed": config.seed,
        "world": dataclasses.asdict(realism_world()),
        "protocol": {
            "obs_frames": OBS_FRAMES,
            "pred_frames": PRED_FRAMES,
            "world_dt": REALISM_DT,
            "collision_distance": COLLISION_DISTANCE,
            "group_distance": GROUP_DISTANCE,
            "group_speed": GROUP_SPEED,
        },
        "models": {s.name: dataclasses.asdict(s) for s in specs},
        "versions": versions(),
        "seconds": round(time.perf_counter() - started, 1),
    }
    (out / "realism.json").write_text(json_text(record, indent=2, default=str) + "\n")
    return results


def versions() -> dict[str, str]:
    """The versions of python, socialzoo, numpy, numba and scipy."""
    import importlib.metadata as md

    out = {"python": platform.python_version()}
    for pkg in ("socialzoo", "numpy", "numba", "scipy"):
        try:
            out[pkg] = md.version(pkg)
        except md.PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def overall(results: Sequence[SceneResult], scenes: Sequence[str]) -> list[SceneResult]:
    """Per model, the mean over scenes of each metric (counts summed)."""
    out = []
    for model in dict.fromkeys(r.model for r in results):
        mine = [r for r in results if r.model == model and r.scene in scenes]
        metrics = {}
        for name, _, _ in METRICS:
            vals = np.array([r.metrics[name] for r in mine], dtype=float)
            total = np.nansum if name in ("windows", "people") else np.nanmean
            metrics[name] = float(total(vals)) if np.isfinite(vals).any() else math.nan
        out.append(SceneResult("overall", model, metrics, np.concatenate([r.speeds for r in mine])))
    return out


def markdown_table(results: Sequence[SceneResult]) -> str:
    """One Markdown table: a row per scene and model (the overall rows last)."""
    header = ["scene", "model", *(h for _, h, _ in METRICS)]
    rows = [
        [r.scene, r.model]
        + [
            "" if not math.isfinite(r.metrics[name]) else f"{r.metrics[name]:.{digits}f}"
            for name, _, digits in METRICS
        ]
        for r in results
    ]
    return "\n".join(table_lines(header, rows)) + "\n"


def write_tables(results: Sequence[SceneResult], out: Path) -> None:
    """out/realism.csv and out/realism.md (a table per scene and the overall one)."""
    write_csv(
        ({"scene": r.scene, "model": r.model, **r.metrics} for r in results),
        out / "realism.csv",
        ["scene", "model", *(n for n, _, _ in METRICS)],
        blank_nan=False,
    )
    parts = ["# Realism against the recorded people\n"]
    for scene in dict.fromkeys(r.scene for r in results):
        parts.append(f"\n## {scene}\n\n" + markdown_table([r for r in results if r.scene == scene]))
    parts.append("\n## all scenes\n\n" + markdown_table(results))
    (out / "realism.md").write_text("".join(parts))


def write_figures(results: Sequence[SceneResult], out: Path) -> None:
    """out/ade.png (4.8 s ADE per model per scene) and out/speeds.png (speed histograms)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = list(dict.fromkeys(r.scene for r in results))
    models = [m for m in dict.fromkeys(r.model for r in results) if m != "recorded"]
    fig, ax = plt.subplots(figsize=(1.5 + 1.2 * len(scenes), 3.5))
    width = 0.8 / max(len(models), 1)
    for j, model in enumerate(models):
        vals = [
            next((r.metrics["ade"] for r in results if r.scene == s and r.model == model), math.nan)
            for s in scenes
        ]
        ax.bar(np.arange(len(scenes)) + j * width, vals, width, label=model)
    ax.set_xticks(np.arange(len(scenes)) + 0.4 - width / 2, scenes)
    ax.set_ylabel("ADE over 4.8 s (m)")
    ax.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(out / "ade.png", dpi=120)
    plt.close(fig)
    fig, axes = plt.subplots(1, len(scenes), figsize=(3.0 * len(scenes), 2.8), squeeze=False)
    bins = np.linspace(0.0, 3.0, 31)
    for ax, scene in zip(axes[0], scenes, strict=True):
        for r in results:
            if r.scene == scene and len(r.speeds):
                style = {"color": "k", "lw": 2.0} if r.model == "recorded" else {}
                ax.hist(r.speeds, bins=bins, density=True, histtype="step", label=r.model, **style)
        ax.set_title(scene)
        ax.set_xlabel("speed (m/s)")
    axes[0][0].legend(fontsize="x-small")
    fig.tight_layout()
    fig.savefig(out / "speeds.png", dpi=120)
    plt.close(fig)
