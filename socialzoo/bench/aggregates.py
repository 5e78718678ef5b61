"""Aggregates over training seeds (Agarwal et al. 2021, "Deep RL at the edge of the statistical precipice"): mean
and IQM with stratified bootstrap intervals, performance profiles and the probability of improvement."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from socialzoo.bench.stats import Interval
from socialzoo.core.validation import check_int

# Intervals over seeds: 95%, as rliable reports them (the per-trial tables keep the paper's 90%).
SEED_CONFIDENCE = 0.95
# Resamples of a seed interval: the Monte Carlo error of a 2.5% quantile is then well under the
# spread the seeds themselves give.
SEED_RESAMPLES = 5_000
# Thresholds of a performance profile (score > tau), success in [0, 1].
PROFILE_TAUS: tuple[float, ...] = tuple(np.round(np.linspace(0.0, 1.0, 21), 2).tolist())

ScoreSet = Sequence[np.ndarray]  # one (K_m, N_m) score matrix per stratum


def _matrices(scores: ScoreSet | np.ndarray) -> list[np.ndarray]:
    """The strata as float64 (K, N) matrices (a single matrix is one stratum).

    Raises:
        ValueError: no stratum, an empty or non-2-D one, or non-finite scores.
    """
    if isinstance(scores, np.ndarray):
        scores = [scores]
    out = []
    for i, s in enumerate(scores):
        m = np.asarray(s, dtype=np.float64)
        if m.ndim != 2 or m.shape[0] < 1 or m.shape[1] < 1:
            raise ValueError(f"stratum {i}: scores must be a (seeds, scenarios) matrix, got shape {m.shape}")
        if not np.isfinite(m).all():
            raise ValueError(f"stratum {i}: scores must be finite")
        out.append(m)
    if not out:
        raise ValueError("no scores: at least one (seeds, scenarios) matrix is needed")
    return out


def iqm(values: np.ndarray | Sequence[float], axis: int | None = None) -> np.ndarray | float:
    """The interquartile mean: the mean after trimming 25% of the values at each end (of 5 values,
    1 at each end; of 4, 1), as rliable's aggregate_iqm; along `axis` (None: all values).

    Robust to one lucky or unlucky seed.
    """
    from scipy.stats import trim_mean

    result = trim_mean(np.asarray(values, dtype=np.float64), 0.25, axis=axis)
    return float(result) if axis is None else np.asarray(result)


def seed_scores(scores: ScoreSet | np.ndarray) -> np.ndarray:
    """Every seed's score (its row mean) over all strata, concatenated: the runs the aggregates
    are computed on."""
    return np.concatenate([m.mean(axis=1) for m in _matrices(scores)])


def resample_seed_scores(
    scores: ScoreSet | np.ndarray, *, resamples: int, rng: np.random.Generator, scenarios: bool = True
) -> np.ndarray:
    """(resamples, runs) seed scores of stratified bootstrap resamples:
    per stratum, the scenarios drawn with replacement (shared by its seeds; `scenarios=False`:
    kept), then its seeds drawn with replacement.

    The seed draw gives the between-seed spread; the scenario draw (shared, since every seed of the
    stratum ran the same scenarios) the finite test set's spread. Strata are resampled independently
    of one another.
    """
    check_int("resample_seed_scores", "resamples", resamples, low=1)
    columns = [_resample_stratum([m], resamples, rng, scenarios)[0] for m in _matrices(scores)]
    return np.concatenate(columns, axis=1)


def _resample_stratum(
    mats: Sequence[np.ndarray], resamples: int, rng: np.random.Generator, scenarios: bool
) -> list[np.ndarray]:
    """(resamples, K) seed scores of each of one stratum's (K, N) matrices (policies on the same N
    scenarios): one scenario draw shared by all of them, then each one's seeds drawn on their own."""
    n = mats[0].shape[1]
    if scenarios and n > 1:
        counts = rng.multinomial(n, np.full(n, 1.0 / n), size=resamples)  # (R, N) draws per scenario
        rates = [counts @ m.T / n for m in mats]  # (R, K): each seed's rate on the resampled scenarios
    else:
        rates = [np.broadcast_to(m.mean(axis=1), (resamples, m.shape[0])) for m in mats]
    return [
        np.take_along_axis(r, rng.integers(0, r.shape[1], size=(resamples, r.shape[1])), axis=1)
        for r in rates
    ]


def _levels(confidence: float) -> list[float]:
    """The two quantiles of a two-sided percentile interval at `confidence`."""
    return [0.5 - 0.5 * confidence, 0.5 + 0.5 * confidence]


@dataclass(frozen=True)
class SeedAggregate:
    """A policy's aggregates over its seeds (on one map, or over several as strata).

    Attributes:
        mean: mean seed score with its stratified bootstrap interval.
        iqm: interquartile mean of the seed scores with its interval.
        seed_scores: each seed's score, in seed order (strata one after another).
        scenarios: scenarios per seed (summed over strata).
    """

    mean: Interval
    iqm: Interval
    seed_scores: tuple[float, ...]
    scenarios: int


def aggregate(
    scores: ScoreSet | np.ndarray,
    *,
    confidence: float = SEED_CONFIDENCE,
    resamples: int = SEED_RESAMPLES,
    rng: np.random.Generator,
    scenarios: bool = True,
) -> SeedAggregate:
    """Mean and IQM of the seed scores with stratified bootstrap intervals (the same resamples
    for both, drawn from `rng`).

    Percentile intervals, 95% by default (rliable's), from `resamples` resamples of a seeded generator.
    """
    mats = _matrices(scores)
    runs = seed_scores(mats)
    samples = resample_seed_scores(mats, resamples=resamples, rng=rng, scenarios=scenarios)
    out = []
    for statistic in (np.mean, iqm):  # each resample's (row's) mean and IQM of its seed scores
        value = float(statistic(runs))
        low, high = np.quantile(statistic(samples, axis=1), _levels(confidence))
        out.append(Interval(value, float(low), float(high), int(runs.size)))
    return SeedAggregate(out[0], out[1], tuple(float(v) for v in runs), sum(m.shape[1] for m in mats))


def performance_profile(
    scores: ScoreSet | np.ndarray,
    taus: Sequence[float] = PROFILE_TAUS,
    *,
    confidence: float = SEED_CONFIDENCE,
    resamples: int = SEED_RESAMPLES,
    rng: np.random.Generator,
    scenarios: bool = True,
) -> list[Interval]:
    """The run-score distribution: for each tau, the share of seed runs whose score exceeds tau,
    with stratified bootstrap bands (rliable's performance profile)."""
    runs = seed_scores(scores)
    samples = resample_seed_scores(scores, resamples=resamples, rng=rng, scenarios=scenarios)
    out = []
    for tau in taus:
        low, high = np.quantile((samples > tau).mean(axis=1), _levels(confidence))
        out.append(Interval(float((runs > tau).mean()), float(low), float(high), int(runs.size)))
    return out


def _improvement(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """P(X > Y) + P(X = Y) / 2 over all pairs of seed scores, per resample: (R, Kx), (R, Ky) -> (R,)."""
    greater = (x[:, :, None] > y[:, None, :]).mean(axis=(1, 2))
    equal = (x[:, :, None] == y[:, None, :]).mean(axis=(1, 2))
    return greater + 0.5 * equal


def probability_of_improvement(
    x: ScoreSet | np.ndarray,
    y: ScoreSet | np.ndarray,
    *,
    confidence: float = SEED_CONFIDENCE,
    resamples: int = SEED_RESAMPLES,
    rng: np.random.Generator,
    scenarios: bool = True,
) -> Interval:
    """The probability that a seed of policy X scores above a seed of policy Y (ties count half;
    the Mann-Whitney statistic), averaged over strata, with a stratified bootstrap interval.

    X and Y give one matrix per stratum each, on the same scenarios (same N per stratum), so a
    scenario resample is shared by both; their seeds are resampled independently.

    Raises:
        ValueError: different numbers of strata, or of scenarios in a stratum.
    """
    xs, ys = _matrices(x), _matrices(y)
    if len(xs) != len(ys) or any(a.shape[1] != b.shape[1] for a, b in zip(xs, ys, strict=True)):
        raise ValueError(
            "probability_of_improvement: X and Y need the same strata and scenarios, got "
            f"{[a.shape for a in xs]} and {[b.shape for b in ys]}"
        )
    values, samples = [], []
    for a, b in zip(xs, ys, strict=True):
        values.append(float(_improvement(a.mean(axis=1)[None, :], b.mean(axis=1)[None, :])[0]))
        pa, pb = _resample_stratum([a, b], resamples, rng, scenarios)
        samples.append(_improvement(pa, pb))
    per_resample = np.mean(samples, axis=0)
    low, high = np.quantile(per_resample, _levels(confidence))
    return Interval(float(np.mean(values)), float(low), float(high), sum(a.shape[0] for a in xs))


def where_in(value: float, seed_values: Sequence[float]) -> str:
    """Where a number (the paper's) falls in a seed distribution, in words: "below all K seeds",
    "above all K seeds", "inside the seeds' range (i of K below it)" or "equal to a seed (...)";
    of a single run: "below our run", "above our run", "equal to our run"."""
    ordered = sorted(float(v) for v in seed_values)
    if not ordered or not math.isfinite(value):
        return "no seeds"
    k = len(ordered)
    if k == 1:
        return (
            "below our run"
            if value < ordered[0]
            else "above our run"
            if value > ordered[0]
            else "equal to our run"
        )
    if value < ordered[0]:
        return f"below all {k} seeds"
    if value > ordered[-1]:
        return f"above all {k} seeds"
    below = sum(v < value for v in ordered)
    if any(math.isclose(v, value, abs_tol=1e-12) for v in ordered):
        return f"equal to a seed ({below} of {k} below it)"
    return f"inside the seeds' range ({below} of {k} below it)"


def cell_generator(seed: int, *names: str) -> np.random.Generator:
    """A generator seeded by `seed` and names (policy, map, ...): a table cell's resamples do not
    change when other cells are added."""
    import zlib

    return np.random.default_rng([seed, *(zlib.crc32(n.encode()) for n in names)])


def score_matrix(per_seed: Sequence[Mapping[int, float]]) -> np.ndarray:
    """A (K, N) score matrix from each seed's {scenario index: score}, columns by scenario index;
    only the scenarios every seed ran are kept (a seed still being evaluated does not shift the
    others' columns).

    Raises:
        ValueError: no seeds, or a seed without scores.
    """
    if not per_seed:
        raise ValueError("score_matrix: no seeds")
    empty = [i for i, scores in enumerate(per_seed) if not scores]
    if empty:
        raise ValueError(f"score_matrix: seed(s) {empty} have no scores")
    common = sorted(set.intersection(*(set(scores) for scores in per_seed)))
    return np.array([[float(scores[i]) for i in common] for scores in per_seed], dtype=np.float64)
