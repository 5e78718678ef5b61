"""Confidence intervals for benchmark tables and figures: Student-t for means, Wilson score for success rates and
bootstrap (BCa) for mean counts per episode (90% by default, as in the paper); numpy and scipy."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from statistics import NormalDist

import numpy as np

from socialzoo.core.validation import check_int

CONFIDENCE = 0.9
# Bootstrap resamples of a count interval: the Monte Carlo error of its 5% and 95% quantiles is
# then about 1% of the interval's width.
BOOTSTRAP_RESAMPLES = 10_000
# Binomial draws per chunk of resamples (bounds the memory of a count interval).
_CHUNK_DRAWS = 1 << 20


@dataclass(frozen=True)
class Interval:
    """An estimate with a two-sided confidence interval.

    Attributes:
        value: the estimate (a mean or a rate); NaN without data.
        low, high: interval bounds; NaN when they cannot be computed (fewer than 2 values for a mean).
        n: number of values the estimate is based on.
    """

    value: float
    low: float
    high: float
    n: int

    def entry(self, name: str, value: str = "mean") -> dict[str, float]:
        """The interval as a summary entry's keys: "<name>_<value>", "<name>_ci_low", "<name>_ci_high"."""
        return {f"{name}_{value}": self.value, f"{name}_ci_low": self.low, f"{name}_ci_high": self.high}


def _check_confidence(confidence: float) -> None:
    if not (isinstance(confidence, (int, float)) and 0.0 < confidence < 1.0):
        raise ValueError(f"confidence must be a number in (0, 1), got {confidence!r}")


def betainc(a: float, b: float, x: float) -> float:
    """Regularized incomplete beta function I_x(a, b), a, b > 0, 0 <= x <= 1 (scipy.special.betainc)."""
    from scipy.special import betainc as regularized

    return float(regularized(a, b, min(max(x, 0.0), 1.0)))


def student_t_cdf(t: float, df: float) -> float:
    """P(T <= t) for Student's t with `df` degrees of freedom (scipy.stats.t)."""
    from scipy.stats import t as student_t

    return float(student_t.cdf(t, df))


@lru_cache(maxsize=4096)
def student_t_ppf(q: float, df: float) -> float:
    """The q-quantile of Student's t with `df` > 0 degrees of freedom (scipy.stats.t)."""
    from scipy.stats import t as student_t

    if not 0.0 < q < 1.0:
        raise ValueError(f"student_t_ppf: q must be in (0, 1), got {q!r}")
    return float(student_t.ppf(q, df))


def mean_interval(
    values: np.ndarray | list[float], confidence: float = CONFIDENCE, *, infinite: bool = False
) -> Interval:
    """Mean of the finite values with a Student-t confidence interval.

    NaN values (e.g. time to goal of a failed episode) are left out; n counts the rest.

    Args:
        values: numbers.
        confidence: two-sided level, e.g. 0.9.
        infinite: an infinity is a value (e.g. the time to collision of an episode never on a
            collision course), not a gap: with one among the values the mean is that infinity
            (NaN for both signs) and the bounds NaN. False: infinities are left out as NaN is.

    Returns:
        Interval(mean, mean - t * s / sqrt(n), mean + t * s / sqrt(n), n), with s the sample
        standard deviation and t the (1 + confidence) / 2 quantile with n - 1 degrees of
        freedom. Bounds are NaN for n < 2, the mean is NaN for n = 0.
    """
    _check_confidence(confidence)
    x = np.asarray(values, dtype=np.float64).reshape(-1)
    if infinite and np.isinf(x).any():
        x = x[~np.isnan(x)]
        with np.errstate(invalid="ignore"):  # inf - inf: NaN, as documented
            return Interval(float(x.mean()), math.nan, math.nan, len(x))
    x = x[np.isfinite(x)]
    n = len(x)
    if n == 0:
        return Interval(math.nan, math.nan, math.nan, 0)
    mean = float(x.mean())
    if n == 1:
        return Interval(mean, math.nan, math.nan, 1)
    half = student_t_ppf(0.5 + 0.5 * confidence, n - 1) * float(x.std(ddof=1)) / math.sqrt(n)
    return Interval(mean, mean - half, mean + half, n)


def rate_interval(successes: int, n: int, confidence: float = CONFIDENCE) -> Interval:
    """Success rate with a Wilson score interval.

    The Wilson interval stays inside [0, 1] and behaves at rates near 0 and 1 (GoAlone succeeds
    in nearly every episode), where the normal interval collapses to a point.

    Args:
        successes: number of successes, 0 <= successes <= n.
        n: number of trials.
        confidence: two-sided level.

    Returns:
        Interval(successes / n, low, high, n); all NaN for n = 0.

    Raises:
        ValueError: counts out of range.
    """
    _check_confidence(confidence)
    if not (0 <= successes <= n):
        raise ValueError(f"rate_interval: need 0 <= successes <= n, got successes={successes!r}, n={n!r}")
    if n == 0:
        return Interval(math.nan, math.nan, math.nan, 0)
    z = NormalDist().inv_cdf(0.5 + 0.5 * confidence)
    p = successes / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1.0 - p) / n + z * z / (4 * n * n)) / denom
    return Interval(p, max(0.0, centre - half), min(1.0, centre + half), n)


def count_interval(
    values: np.ndarray | list[float],
    confidence: float = CONFIDENCE,
    *,
    rng: np.random.Generator,
    resamples: int = BOOTSTRAP_RESAMPLES,
) -> Interval:
    """Mean count per episode (collision steps) with a bootstrap (BCa) interval.

    Counts are skewed and clumped (most episodes have none, a collision lasts several steps), so
    a Student-t interval reaches below 0 and a Poisson interval, which assumes independent
    events, is too narrow. The bootstrap resamples whole episodes, so it follows the counts' real
    spread, and its bounds are means of resampled episodes: they never leave the range of the
    data, never below 0. The bounds are the bias-corrected and accelerated (BCa, Efron 1987)
    quantiles of the resampled means, which cover better than the plain percentile ones when the
    counts are skewed and n is small. Drawing how often each distinct value is resampled (a
    multinomial over the distinct values) gives the same distribution as drawing episodes, at a
    fraction of the cost.

    With no count at all the resamples would collapse to [0, 0]; the upper bound is then the
    exact Poisson (Garwood) bound for zero events, -ln((1 - confidence) / 2) / n (3.0 / n at 90%).

    NaN values are left out; n counts the rest.

    Args:
        values: non-negative numbers, one per episode.
        confidence: two-sided level, e.g. 0.9.
        rng: the generator of the resamples (seed it for reproducible tables).
        resamples: number of bootstrap resamples.

    Returns:
        Interval(mean, low, high, n) with 0 <= low <= mean <= high; bounds NaN for n < 2, the
        mean NaN for n = 0.

    Raises:
        ValueError: a negative value, a bad confidence or resample count.
    """
    _check_confidence(confidence)
    check_int("count_interval", "resamples", resamples, low=1)
    x = np.asarray(values, dtype=np.float64).reshape(-1)
    x = x[np.isfinite(x)]
    if np.any(x < 0):
        raise ValueError(f"count_interval: counts must be >= 0, got {float(x.min())!r}")
    n = len(x)
    if n == 0:
        return Interval(math.nan, math.nan, math.nan, 0)
    mean = float(x.mean())
    if n == 1:
        return Interval(mean, math.nan, math.nan, 1)
    if mean == 0.0:
        return Interval(0.0, 0.0, -math.log(0.5 - 0.5 * confidence) / n, n)
    distinct, frequency = np.unique(x, return_counts=True)
    if len(distinct) == 1:
        return Interval(mean, mean, mean, n)
    chunk = max(1, _CHUNK_DRAWS // len(distinct))
    means = np.empty(resamples)
    for start in range(0, resamples, chunk):
        stop = min(resamples, start + chunk)
        draws = rng.multinomial(n, frequency / n, size=stop - start)
        means[start:stop] = draws @ distinct / n
    levels = _bca_levels(means, mean, x, confidence)
    low, high = (float(q) for q in np.quantile(means, levels))
    # The quantiles bracket the mean for any real data; min/max keep the promise exact.
    return Interval(mean, max(0.0, min(low, mean)), max(high, mean), n)


def _bca_levels(means: np.ndarray, mean: float, x: np.ndarray, confidence: float) -> list[float]:
    """The BCa quantile levels of bootstrap means of `x` for a two-sided `confidence` interval.

    Bias correction z0 from the share of resampled means below the sample mean; acceleration
    from the jackknife of the mean, which is the sample skewness / (6 sqrt(n)).
    """
    normal = NormalDist()
    size = len(means)
    below = (np.count_nonzero(means < mean) + 0.5 * np.count_nonzero(means == mean)) / size
    z0 = normal.inv_cdf(min(max(below, 1.0 / size), 1.0 - 1.0 / size))
    dev = x - mean
    accel = float((dev**3).sum() / (6.0 * float((dev**2).sum()) ** 1.5))
    levels = []
    for q in (0.5 - 0.5 * confidence, 0.5 + 0.5 * confidence):
        z = z0 + normal.inv_cdf(q)
        denom = 1.0 - accel * z
        levels.append(normal.cdf(z0 + z / denom) if denom > 0 else 1.0)
    return levels
