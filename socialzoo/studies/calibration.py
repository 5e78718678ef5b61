"""Social-force and ORCA parameters fitted to the recorded ETH/UCY people (issue 37, item 5): CMA-ES on the 4.8 s
ADE of socialzoo.studies.realism, leave-one-scene-out, and the presets fitted on all (docs/humans.md)."""

from __future__ import annotations

import dataclasses
import logging
import math
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

# The shipped presets (fitted on all five scenes) live with the crowd models.
from socialzoo.core.files import json_text
from socialzoo.humans.presets import PRESETS as PRESETS

_LOG = logging.getLogger(__name__)

# The fitted parameters of each model: (config section, field, low, high).
PARAMETERS: dict[str, tuple[tuple[str, str, float, float], ...]] = {
    "sf": (
        ("human", "relaxation_time", 0.1, 3.0),
        ("human", "social_strength", 0.3, 30.0),
        ("human", "social_lambda", 0.2, 5.0),
        ("human", "social_gamma", 0.05, 1.5),
    ),
    "orca": (
        ("orca", "neighbor_dist", 0.5, 15.0),
        ("orca", "time_horizon", 0.2, 10.0),
        ("orca", "radius", 0.05, 0.6),
    ),
}
# Mixed with the seed for the fit's and the evaluation's samples.
_FIT_STREAM = 0x666974  # "fit"
_EVAL_STREAM = 0x6576616C  # "eval"


@dataclass(frozen=True, kw_only=True)
class CalibrationConfig:
    """One calibration run (docs/humans.md, "Calibration").

    Attributes:
        model: "sf" or "orca".
        scenes: the scenes (at least 2 for the folds).
        persons: people sampled per scene for a fit.
        windows: windows per sampled person for a fit.
        eval_persons: people sampled per held-out scene for its report.
        eval_windows: windows per person there.
        generations: CMA-ES generations.
        popsize: CMA-ES population, at least 2.
        sigma: CMA-ES initial step in the [0, 1] search space.
        seed: the samples' and CMA-ES's seed.
        folds: run the leave-one-scene-out folds (else only the fit on all scenes).
        cache: the scenes' cache folder.
    """

    model: str
    scenes: tuple[str, ...] = ("eth", "hotel", "univ", "zara1", "zara2")
    persons: int = 40
    windows: int = 3
    eval_persons: int = 80
    eval_windows: int = 6
    generations: int = 6
    popsize: int = 6
    sigma: float = 0.25
    seed: int = 0
    folds: bool = True
    cache: str | None = None

    def __post_init__(self) -> None:
        if self.model not in PARAMETERS:
            raise ValueError(
                f"CalibrationConfig.model must be one of {sorted(PARAMETERS)}, got {self.model!r}"
            )
        if not self.scenes or (self.folds and len(self.scenes) < 2):
            raise ValueError(
                f"CalibrationConfig.scenes: the folds need 2 scenes or more, got {self.scenes!r}"
            )
        for name in ("persons", "windows", "eval_persons", "eval_windows", "generations", "popsize"):
            value = getattr(self, name)
            if not isinstance(value, int) or value < 1:
                raise ValueError(f"CalibrationConfig.{name} must be an int >= 1, got {value!r}")
        if self.popsize < 2:
            # CMA-ES recombines the best half of each generation: cma refuses fewer than 2.
            raise ValueError(f"CalibrationConfig.popsize must be >= 2 (CMA-ES), got {self.popsize!r}")
        if not (0 < self.sigma <= 1):
            raise ValueError(f"CalibrationConfig.sigma must be in (0, 1], got {self.sigma!r}")


def defaults(model: str) -> dict[str, float]:
    """The study world's values of a model's fitted parameters
    (socialzoo.studies.realism_simulation.realism_world)."""
    from socialzoo.studies.realism_simulation import realism_world

    world = realism_world()
    return {
        f"{sec}.{name}": float(getattr(getattr(world, sec), name)) for sec, name, _, _ in PARAMETERS[model]
    }


def to_unit(model: str, values: dict[str, float]) -> np.ndarray:
    """Parameter values to the [0, 1] search space (log-uniform over each range)."""
    return np.array(
        [
            math.log(values[f"{sec}.{name}"] / lo) / math.log(hi / lo)
            for sec, name, lo, hi in PARAMETERS[model]
        ]
    )


def from_unit(model: str, x: Sequence[float] | np.ndarray) -> dict[str, float]:
    """A point of the search space to parameter values."""
    out = {}
    for (sec, name, lo, hi), u in zip(PARAMETERS[model], x, strict=True):
        u = min(max(float(u), 0.0), 1.0)
        out[f"{sec}.{name}"] = lo * (hi / lo) ** u
    return out


def spec_of(model: str, values: dict[str, float], name: str | None = None) -> Any:
    """The realism ModelSpec of `model` with these parameter values."""
    from socialzoo.studies.realism_simulation import ModelSpec

    human = {k.split(".", 1)[1]: v for k, v in values.items() if k.startswith("human.")}
    orca = {k.split(".", 1)[1]: v for k, v in values.items() if k.startswith("orca.")}
    return ModelSpec(name or model, model, human=human, orca=orca)


@dataclass
class _Sample:
    """A scene's sampled windows with their rows built once."""

    scene: Any
    cases: Any
    batches: list[Any]
    true: np.ndarray


def sample_windows(scene: Any, persons: int, windows: int, seed: int) -> Any:
    """Up to `windows` of each of `persons` sampled people's 4.8 s windows, drawn with `seed`."""
    from socialzoo.studies.realism_cases import sample_persons, window_cases

    cases = window_cases(scene, sample_persons(scene, persons, seed))
    rng = np.random.default_rng([int(seed), _FIT_STREAM])
    keep = []
    for k in np.unique(cases.person).tolist():
        mine = np.flatnonzero(cases.person == k)
        keep.append(np.sort(rng.choice(mine, size=min(windows, len(mine)), replace=False)))
    return cases.take(np.sort(np.concatenate(keep)) if keep else np.zeros(0, dtype=np.int64))


def _prepare(scene: Any, cases: Any) -> _Sample:
    from socialzoo.studies.realism_cases import truth
    from socialzoo.studies.realism_simulation import prepare_batches

    return _Sample(scene, cases, prepare_batches(scene, cases, groups=False), truth(scene, cases))


def mean_ade(model: str, values: dict[str, float], samples: Sequence[_Sample]) -> float:
    """The mean over samples (scenes) of the ADE over 4.8 s of `model` with `values`."""
    from socialzoo.studies.realism_metrics import displacement
    from socialzoo.studies.realism_simulation import simulate

    spec = spec_of(model, values)
    scores = []
    for s in samples:
        if len(s.cases) == 0:
            continue
        pred = simulate(s.scene, s.cases, spec, batches=s.batches).pos
        scores.append(displacement(pred, s.true)[0])
    return float(np.mean(scores)) if scores else math.nan


def fit(
    config: CalibrationConfig, samples: Sequence[_Sample], log: Any = None, label: str = ""
) -> tuple[dict[str, float], float, int]:
    """CMA-ES from the defaults; returns (best values, their mean ADE, evaluations)."""
    try:
        import cma
    except ImportError as err:
        raise ImportError(
            "calibration needs the cma package: pip install 'socialzoo[train]' (cma>=3)"
        ) from err

    x0 = to_unit(config.model, defaults(config.model))
    options = {
        "bounds": [0.0, 1.0],
        "popsize": config.popsize,
        "maxiter": config.generations,
        "seed": config.seed + 1,
        "verbose": -9,
    }
    es = cma.CMAEvolutionStrategy(x0.tolist(), config.sigma, options)
    best_x, best_f = x0, mean_ade(config.model, from_unit(config.model, x0), samples)
    evaluations = 1
    while not es.stop():
        xs = es.ask()
        fs = [mean_ade(config.model, from_unit(config.model, x), samples) for x in xs]
        evaluations += len(xs)
        es.tell(xs, fs)
        k = int(np.argmin(fs))
        if fs[k] < best_f:
            best_x, best_f = np.asarray(xs[k]), fs[k]
        if log is not None:
            log(f"{label} generation {es.countiter}: best ADE {best_f:.4f} m")
    return from_unit(config.model, best_x), float(best_f), evaluations


def calibrate(config: CalibrationConfig, out: Path, *, progress: bool = True) -> dict[str, Any]:
    """Run the folds and the fit on all scenes; write out/calibration.{md,csv,json} and
    out/<model>-eth-ucy.json (the preset). Returns the JSON record.

    A fit samples `persons` people of each training scene (seeded) and up to `windows` of each one's 4.8 s
    windows, builds their rows once, and minimises the mean over scenes of their ADE over the parameters of
    PARAMETERS (searched in [0, 1] per parameter, mapped log-uniformly onto its range, from the study's
    defaults). A fold fits on all scenes but one and reports the held-out scene's ADE, defaults against
    fitted, on a larger sample of its windows (`eval_persons`, another seed).

    The parameter sets fitted on all five scenes are socialzoo.humans.presets.PRESETS (the numbers and the
    command in docs/humans.md): socialzoo.studies.realism applies them (`--models sf-eth-ucy,orca-eth-ucy`),
    and every env takes them by name in its people spec.
    """
    from socialzoo.studies.realism import versions
    from socialzoo.studies.realism_cases import OBS_FRAMES, PRED_FRAMES, load_tracks

    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()

    def log(text: str) -> None:
        if progress:
            _LOG.info("[%6.0f s] %s", time.perf_counter() - started, text)

    scenes = {s: load_tracks(s, config.cache) for s in config.scenes}
    fit_samples = {
        s: _prepare(sc, sample_windows(sc, config.persons, config.windows, config.seed))
        for s, sc in scenes.items()
    }
    held_samples = {
        s: _prepare(
            sc, sample_windows(sc, config.eval_persons, config.eval_windows, config.seed + _EVAL_STREAM)
        )
        for s, sc in scenes.items()
        if config.folds
    }
    for what, samples, persons, option in (
        ("fit", fit_samples, config.persons, "--persons"),
        ("held-out", held_samples, config.eval_persons, "CalibrationConfig.eval_persons"),
    ):
        for s, sample in samples.items():
            if not len(sample.cases):
                raise ValueError(
                    f"scene {scenes[s].name!r}: none of the {min(persons, len(scenes[s].first))} people of its "
                    f"{what} sample has a 4.8 s window (seen {OBS_FRAMES + PRED_FRAMES} frames in a row), so it "
                    f"would not count; sample more people ({option}) or leave the scene out"
                )
    base = defaults(config.model)
    folds = []
    if config.folds:
        for held in config.scenes:
            train = [fit_samples[s] for s in config.scenes if s != held]
            values, train_ade, evals = fit(config, train, log, f"fold {held}")
            held_sample = held_samples[held]
            default_ade = mean_ade(config.model, base, [held_sample])
            fitted_ade = mean_ade(config.model, values, [held_sample])
            log(f"fold {held}: held-out ADE {default_ade:.4f} m default, {fitted_ade:.4f} m fitted")
            folds.append(
                {
                    "held_out": scenes[held].name,
                    "train_ade": train_ade,
                    "default_ade": default_ade,
                    "fitted_ade": fitted_ade,
                    "fitted_better": fitted_ade < default_ade,
                    "held_out_windows": len(held_sample.cases),
                    "evaluations": evals,
                    "values": values,
                }
            )
    values, all_ade, evals = fit(config, list(fit_samples.values()), log, "all scenes")
    default_all = mean_ade(config.model, base, list(fit_samples.values()))
    preset: dict[str, Any] = {"model": config.model}
    for key, v in values.items():
        sec, name = key.split(".", 1)
        preset.setdefault(sec, {})[name] = round(v, 4)
    record = {
        "command": " ".join(["socialzoo", *sys.argv[1:]]),
        "config": dataclasses.asdict(config),
        "seed": config.seed,
        "parameters": {f"{s}.{n}": [lo, hi] for s, n, lo, hi in PARAMETERS[config.model]},
        "defaults": base,
        "folds": folds,
        "all": {"values": values, "fitted_ade": all_ade, "default_ade": default_all, "evaluations": evals},
        "preset": preset,
        "versions": versions(),
        "seconds": round(time.perf_counter() - started, 1),
    }
    (out / "calibration.json").write_text(json_text(record, indent=2) + "\n")
    (out / f"{config.model}-eth-ucy.json").write_text(json_text(preset, indent=2) + "\n")
    _write_tables(record, out)
    return record


def _write_tables(record: dict[str, Any], out: Path) -> None:
    """out/calibration.csv and calibration.md: each fold's held-out ADE, defaults against fitted."""
    names = list(record["defaults"])
    lines = ["held_out,default_ade,fitted_ade,fitted_better," + ",".join(names)]
    md = [
        f"# Calibration of {record['config']['model']} (4.8 s ADE, m)\n",
        "| held-out scene | defaults | fitted | better | " + " | ".join(names) + " |",
        "|---|---:|---:|---|" + "---:|" * len(names),
    ]
    for f in record["folds"]:
        vals = [f"{f['values'][n]:.3f}" for n in names]
        lines.append(
            f"{f['held_out']},{f['default_ade']},{f['fitted_ade']},{f['fitted_better']}," + ",".join(vals)
        )
        md.append(
            f"| {f['held_out']} | {f['default_ade']:.3f} | {f['fitted_ade']:.3f} | "
            f"{'yes' if f['fitted_better'] else 'no'} | " + " | ".join(vals) + " |"
        )
    a = record["all"]
    vals = [f"{a['values'][n]:.3f}" for n in names]
    md.append(
        f"| (all, fit sample) | {a['default_ade']:.3f} | {a['fitted_ade']:.3f} | "
        f"{'yes' if a['fitted_ade'] < a['default_ade'] else 'no'} | " + " | ".join(vals) + " |"
    )
    md.append("| defaults | | | | " + " | ".join(f"{record['defaults'][n]:.3f}" for n in names) + " |")
    better = sum(f["fitted_better"] for f in record["folds"])
    if record["folds"]:
        md.append(
            f"\nThe fitted parameters beat the defaults on {better} of {len(record['folds'])} held-out scenes."
        )
    (out / "calibration.csv").write_text("\n".join(lines) + "\n")
    (out / "calibration.md").write_text("\n".join(md) + "\n")
