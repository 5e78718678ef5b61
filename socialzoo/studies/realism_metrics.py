"""How a model's walks compare with the recorded people's: ADE and FDE, the distributions of speeds and of
nearest-neighbour distances, contacts, and every metric of a model on a scene's cases."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from socialzoo.core.config import WorldConfig
from socialzoo.studies.realism_cases import Cases, SceneTracks, constant_velocity, truth
from socialzoo.studies.realism_simulation import HUMAN_RADIUS, ModelSpec, simulate

# Two people nearer than twice their radius touch.
COLLISION_DISTANCE = 2 * HUMAN_RADIUS


def nearest_other(scene: SceneTracks, cases: Cases, pred: np.ndarray) -> np.ndarray:
    """(n, 1 + max frames) the distance of a subject walked along `pred` (n, 1 + max frames, 2) to
    the nearest other recorded person present, m (inf: nobody)."""
    out = np.full(pred.shape[:2], np.inf)
    g = scene.grid
    for i, (k, s, t) in enumerate(
        zip(cases.person.tolist(), cases.start.tolist(), cases.frames.tolist(), strict=True)
    ):
        block = g[:, s : s + t + 1]
        d = np.hypot(*(block - pred[i, : t + 1][None]).transpose(2, 0, 1))
        d[k] = np.inf
        out[i, : t + 1] = np.where(np.isnan(d), np.inf, d).min(0)
    return out


def displacement(pred: np.ndarray, true: np.ndarray, use: np.ndarray | None = None) -> tuple[float, float]:
    """(ADE, FDE), m: the mean over cases of the mean distance over frames 1.. (those `use` marks,
    (n, F)), and of the distance at each case's last frame."""
    d = np.hypot(*(pred - true).transpose(2, 0, 1))[:, 1:]
    valid = ~np.isnan(d) if use is None else ~np.isnan(d) & use[:, 1:]
    if not len(d):
        return math.nan, math.nan
    per = np.where(valid, d, 0.0).sum(1) / np.maximum(valid.sum(1), 1)
    last = (~np.isnan(d)).sum(1) - 1
    final = d[np.arange(len(d)), np.maximum(last, 0)]
    ok = valid.any(1)
    return float(per[ok].mean()) if ok.any() else math.nan, float(np.nanmean(final))


def frame_speeds(pos: np.ndarray, dt: float, use: np.ndarray | None = None) -> np.ndarray:
    """The speeds between consecutive frames (both marked by `use` and recorded), m/s, flat."""
    step = np.hypot(*np.diff(pos, axis=1).transpose(2, 0, 1)) / dt
    ok = ~np.isnan(step)
    if use is not None:
        ok &= use[:, 1:] & use[:, :-1]
    return step[ok]


def wasserstein(a: np.ndarray, b: np.ndarray) -> float:
    """The first Wasserstein distance between two samples (nan if either is empty)."""
    from scipy.stats import wasserstein_distance

    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    return float(wasserstein_distance(a, b)) if len(a) and len(b) else math.nan


def contact_rate(nearest: np.ndarray, use: np.ndarray) -> float:
    """The share of cases with a frame (of `use`) within COLLISION_DISTANCE of someone."""
    hit = ((nearest < COLLISION_DISTANCE) & use).any(1)
    return float(hit.mean()) if len(hit) else math.nan


@dataclass
class SceneResult:
    """A model's numbers on one scene (see METRICS), with the raw speeds for the figures."""

    scene: str
    model: str
    metrics: dict[str, float]
    speeds: np.ndarray


# name, heading, digits
METRICS: tuple[tuple[str, str, int], ...] = (
    ("ade", "ADE 4.8 s (m)", 3),
    ("fde", "FDE 4.8 s (m)", 3),
    ("track_ade", "track ADE (m)", 3),
    ("track_fde", "track FDE (m)", 3),
    ("speed_w1", "speed W1 (m/s)", 3),
    ("nn_w1", "NN dist W1 (m)", 3),
    ("contact_rate", "contacts (share of people)", 3),
    ("windows", "windows", 0),
    ("people", "people", 0),
)


def evaluate_model(
    scene: SceneTracks,
    windows: Cases,
    tracks: Cases,
    model: ModelSpec,
    base: WorldConfig | None = None,
    progress: Callable[[int], None] | None = None,
) -> SceneResult:
    """Every metric of `model` on a scene's cases (docs/humans.md, "Realism against recorded people")."""
    true_w, true_t = truth(scene, windows), truth(scene, tracks)
    if model.name == "cv":
        pred_w = constant_velocity(scene, windows)
        pred_t = constant_velocity(scene, tracks)
        use_t = ~np.isnan(pred_t[..., 0])
        near_t = nearest_other(scene, tracks, pred_t)
        if progress is not None:
            progress(len(windows) + len(tracks))
    else:
        pred_w = simulate(scene, windows, model, base, progress=progress).pos
        rollout = simulate(scene, tracks, model, base, progress=progress)
        pred_t, use_t, near_t = rollout.pos, rollout.present, rollout.others
    ade, fde = displacement(pred_w, true_w)
    track_ade, track_fde = displacement(pred_t, true_t, use_t)
    # The recorded distributions over the frames the model's person is on the scene too (a modelled
    # person that reaches its exit early leaves there): a frame the model never walks is not held
    # against it.
    rec_use = ~np.isnan(true_t[..., 0]) & use_t
    speeds = frame_speeds(pred_t, scene.dt, use_t)
    rec_speeds = frame_speeds(true_t, scene.dt, rec_use)
    rec_near = nearest_other(scene, tracks, true_t)
    metrics = {
        "ade": ade,
        "fde": fde,
        "track_ade": track_ade,
        "track_fde": track_fde,
        "speed_w1": wasserstein(speeds, rec_speeds),
        "nn_w1": wasserstein(near_t[use_t], rec_near[rec_use]),
        "contact_rate": contact_rate(near_t, use_t),
        "windows": float(len(windows)),
        "people": float(len(tracks)),
    }
    return SceneResult(scene.name, model.name, metrics, speeds)


def recorded_reference(scene: SceneTracks, windows: Cases, tracks: Cases) -> SceneResult:
    """The recorded people themselves (zero errors): their speeds and contact rate, for reference. An
    error is 0 where the models are measured and NaN where they are not (a scene without a 4.8 s window
    has no windowed error), so that the reference row is blank where the models' rows are."""
    true_t = truth(scene, tracks)
    use = ~np.isnan(true_t[..., 0])
    near = nearest_other(scene, tracks, true_t)
    metrics = {name: 0.0 for name, _, _ in METRICS}
    windowed, tracked = (0.0 if len(cases) else math.nan for cases in (windows, tracks))
    metrics.update(ade=windowed, fde=windowed, track_ade=tracked, track_fde=tracked)
    metrics.update(contact_rate=contact_rate(near, use), windows=math.nan, people=float(len(tracks)))
    return SceneResult(scene.name, "recorded", metrics, frame_speeds(true_t, scene.dt, use))
