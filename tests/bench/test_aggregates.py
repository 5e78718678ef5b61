"""Aggregates over seeds: IQM, stratified bootstrap intervals, performance profiles and the
probability of improvement, against hand-worked cases and scipy.stats.bootstrap."""

import numpy as np
import pytest

from socialzoo.bench.aggregates import (
    aggregate,
    iqm,
    performance_profile,
    probability_of_improvement,
    score_matrix,
    seed_scores,
    where_in,
)


def rng(seed=0):
    return np.random.default_rng(seed)


def test_iqm_by_hand():
    # 5 values: 25% of 5 is 1.25, so one value is trimmed at each end: mean(0.5, 0.6, 0.7).
    assert iqm([1.0, 0.1, 0.6, 0.5, 0.7]) == pytest.approx(0.6)
    # 4 values: one trimmed at each end.
    assert iqm([0.0, 0.2, 0.4, 1.0]) == pytest.approx(0.3)
    assert iqm([0.3]) == pytest.approx(0.3)


def test_seed_bootstrap_by_hand():
    """Two seeds, one at 0% and one at 100% (one scenario each, so only seeds are resampled):
    a resample of 2 seeds has mean 0 w.p. 1/4, 0.5 w.p. 1/2, 1 w.p. 1/4. So the 80% interval
    (10% and 90% quantiles) is [0, 1] and the 40% interval (30%, 70%) is [0.5, 0.5]."""
    scores = np.array([[0.0], [1.0]])
    wide = aggregate(scores, confidence=0.8, resamples=20_000, rng=rng()).mean
    assert (wide.value, wide.low, wide.high, wide.n) == (0.5, 0.0, 1.0, 2)
    narrow = aggregate(scores, confidence=0.4, resamples=20_000, rng=rng()).mean
    assert (narrow.low, narrow.high) == (0.5, 0.5)


def test_scenario_bootstrap_by_hand():
    """One seed that succeeded on one of two scenarios: resampling the scenarios gives 0, 0.5 or 1
    with 1/4, 1/2, 1/4, the same intervals as above; without scenario resampling, none."""
    scores = np.array([[1.0, 0.0]])
    wide = aggregate(scores, confidence=0.8, resamples=20_000, rng=rng()).mean
    assert (wide.low, wide.high) == (0.0, 1.0)
    narrow = aggregate(scores, confidence=0.4, resamples=20_000, rng=rng()).mean
    assert (narrow.low, narrow.high) == (0.5, 0.5)
    fixed = aggregate(scores, resamples=100, rng=rng(), scenarios=False).mean
    assert (fixed.value, fixed.low, fixed.high) == (0.5, 0.5, 0.5)


def test_strata_are_resampled_apart():
    """Two strata of one seed each (0.0 and 1.0): seeds are resampled within a stratum, so every
    resample keeps one of each and the mean is always 0.5; pooled as one stratum it would not be."""
    strata = [np.array([[0.0]]), np.array([[1.0]])]
    interval = aggregate(strata, resamples=1000, rng=rng()).mean
    assert (interval.value, interval.low, interval.high, interval.n) == (0.5, 0.5, 0.5, 2)
    pooled = aggregate(np.array([[0.0], [1.0]]), resamples=1000, rng=rng()).mean
    assert pooled.low == 0.0 and pooled.high == 1.0


def test_seeds_only_matches_scipy_bootstrap():
    from scipy.stats import bootstrap

    rates = np.array([0.42, 0.55, 0.61, 0.48, 0.70, 0.52, 0.66])
    scores = rates[:, None]
    ours_both = aggregate(scores, resamples=20_000, rng=rng(1), scenarios=False)
    for ours, function in ((ours_both.mean, np.mean), (ours_both.iqm, iqm)):
        theirs = bootstrap(
            (rates,),
            lambda x, axis, f=function: f(x, axis=axis),
            method="percentile",
            confidence_level=0.95,
            n_resamples=20_000,
            random_state=2,
        ).confidence_interval
        assert ours.low == pytest.approx(theirs.low, abs=0.01)
        assert ours.high == pytest.approx(theirs.high, abs=0.01)


def test_aggregate_mean_and_iqm():
    scores = np.array([[1, 1, 0, 1], [0, 0, 0, 1], [1, 1, 1, 1], [1, 0, 1, 0], [0, 1, 1, 1]], dtype=float)
    agg = aggregate(scores, resamples=2000, rng=rng())
    assert agg.seed_scores == (0.75, 0.25, 1.0, 0.5, 0.75)
    assert agg.mean.value == pytest.approx(0.65)
    assert agg.iqm.value == pytest.approx(np.mean([0.5, 0.75, 0.75]))
    assert agg.mean.low <= agg.mean.value <= agg.mean.high and agg.scenarios == 4
    assert agg.iqm.low <= agg.iqm.value <= agg.iqm.high
    again = aggregate(scores, resamples=2000, rng=rng())
    assert again == agg  # seeded: reproducible


def test_probability_of_improvement_by_hand():
    # X = (0.5, 0.8), Y = (0.6, 0.6): X wins the two pairs of 0.8, loses the two of 0.5: 2/4.
    x = np.array([[0.5], [0.8]])
    y = np.array([[0.6], [0.6]])
    assert probability_of_improvement(x, y, resamples=100, rng=rng()).value == pytest.approx(0.5)
    # X = (0.6, 0.8), Y = (0.6, 0.4): a tie (1/2) and three wins: 3.5/4.
    assert probability_of_improvement(
        np.array([[0.6], [0.8]]), np.array([[0.6], [0.4]]), resamples=100, rng=rng()
    ).value == pytest.approx(0.875)
    # Always better on shared scenarios: 1, whatever is resampled.
    better = probability_of_improvement(
        np.array([[1, 1, 0.0]]), np.array([[1, 0, 0.0]]), resamples=500, rng=rng()
    )
    assert better.value == 1.0 and better.low >= 0.5
    with pytest.raises(ValueError, match="same strata"):
        probability_of_improvement(np.ones((2, 3)), np.ones((2, 4)), resamples=10, rng=rng())


def test_performance_profile_by_hand():
    scores = np.array([[0.2], [0.5], [0.9], [1.0]])
    profile = performance_profile(scores, (0.0, 0.5, 0.95), resamples=200, rng=rng())
    assert [p.value for p in profile] == [1.0, 0.5, 0.25]
    assert all(p.low <= p.value <= p.high for p in profile)


def test_score_matrix_keeps_common_scenarios():
    m = score_matrix([{0: 1.0, 1: 0.0, 2: 1.0}, {1: 1.0, 0: 1.0}])
    assert m.tolist() == [[1.0, 0.0], [1.0, 1.0]]
    assert seed_scores(m).tolist() == [0.5, 1.0]
    with pytest.raises(ValueError, match="no scores"):
        score_matrix([{0: 1.0}, {}])


def test_where_in_words():
    assert where_in(0.3, [0.4, 0.5]) == "below all 2 seeds"
    assert where_in(0.6, [0.4, 0.5]) == "above all 2 seeds"
    assert where_in(0.45, [0.4, 0.5, 0.6]) == "inside the seeds' range (1 of 3 below it)"
    assert where_in(0.5, [0.4, 0.5, 0.6]) == "equal to a seed (1 of 3 below it)"


def test_bad_scores_are_refused():
    with pytest.raises(ValueError, match="matrix"):
        aggregate(np.ones(3), rng=rng())
    with pytest.raises(ValueError, match="finite"):
        aggregate(np.array([[np.nan]]), rng=rng())
