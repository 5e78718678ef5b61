"""Count intervals: never below 0, always around the mean, honest on all-zero data, BCa bounds
worked out by hand and checked against scipy, and about 90% coverage on clumped counts like
collision steps."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from socialzoo.bench.stats import count_interval, mean_interval


def rng(seed=0):
    return np.random.default_rng(seed)


def test_the_issue_case_stays_at_or_above_zero():
    # 100 episodes, 8 collision steps in 3 of them: the t interval reaches below 0.
    counts = [0] * 97 + [5, 2, 1]
    assert mean_interval(counts).low < 0
    ci = count_interval(counts, rng=rng())
    assert ci.value == 0.08 and ci.n == 100
    assert 0.0 <= ci.low < 0.08 < ci.high


def test_bca_bounds_of_a_small_case_worked_by_hand():
    # One episode in ten has one collision step: a resample's mean is Binomial(10, 0.1) / 10.
    # Share below the mean 0.349 + half the ties 0.387 / 2: z0 = 0.107; acceleration
    # sum(dev^3) / (6 sum(dev^2)^1.5) = 0.72 / (6 * 0.9^1.5) = 0.141. Upper level
    # Phi(z0 + (z0 + 1.645) / (1 - 0.141 (z0 + 1.645))) = 0.992, between P(<= 3) = 0.987 and
    # P(<= 4) = 0.998: 0.4. Lower level 0.123 < P(0) = 0.349: 0.
    ci = count_interval([0] * 9 + [1], rng=rng())
    assert (ci.value, ci.low, ci.high, ci.n) == (0.1, 0.0, 0.4, 10)


def test_agrees_with_scipy_bca_on_clumped_counts():
    from scipy.stats import bootstrap

    gen = rng(3)
    counts = np.where(gen.random(300) < 0.1, gen.geometric(0.3, 300), 0)
    ci = count_interval(counts, rng=rng(1), resamples=20_000)
    ref = bootstrap(
        (counts,), np.mean, confidence_level=0.9, n_resamples=20_000, method="BCa", random_state=rng(2)
    ).confidence_interval
    assert ci.low == pytest.approx(ref.low, abs=0.015)
    assert ci.high == pytest.approx(ref.high, abs=0.015)
    assert ci.high - ci.low > 0.1


def test_all_zero_counts_get_the_zero_event_poisson_bound():
    ci = count_interval([0] * 100, rng=rng())
    assert (ci.value, ci.low) == (0.0, 0.0)
    assert ci.high == pytest.approx(-math.log(0.05) / 100, abs=1e-15)  # 2.996 / n
    assert count_interval([0] * 100, 0.95, rng=rng()).high == pytest.approx(-math.log(0.025) / 100)


def test_edge_cases_and_bad_input():
    assert math.isnan(count_interval([], rng=rng()).value)
    one = count_interval([3], rng=rng())
    assert one.value == 3 and math.isnan(one.low) and math.isnan(one.high)
    assert count_interval([1, np.nan, 3], rng=rng()).n == 2
    flat = count_interval([2] * 5, rng=rng())
    assert flat.low == flat.high == 2.0
    a, b = count_interval([0, 0, 4, 1], rng=rng(7)), count_interval([0, 0, 4, 1], rng=rng(7))
    assert a == b
    with pytest.raises(ValueError, match=r"counts must be >= 0, got -1\.0"):
        count_interval([0, -1, 2], rng=rng())
    with pytest.raises(ValueError, match="resamples"):
        count_interval([0, 1], rng=rng(), resamples=0)
    with pytest.raises(ValueError, match="confidence"):
        count_interval([0, 1], 1.0, rng=rng())


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(0, 400), min_size=2, max_size=150), st.integers(0, 2**32 - 1))
def test_never_below_zero_and_always_around_the_mean(counts, seed):
    ci = count_interval(counts, rng=rng(seed), resamples=500)
    assert ci.value == pytest.approx(np.mean(counts))
    assert 0.0 <= ci.low <= ci.value <= ci.high
    assert ci.high <= max(max(counts), -math.log(0.05) / len(counts)) + 1e-12


def test_coverage_on_clumped_collision_counts():
    # 6% of episodes collide, for 1 + Geometric steps (mean 4): overdispersed like real contacts.
    gen = rng(11)
    p_hit, mean_len = 0.06, 4.0
    truth = p_hit * mean_len
    covered = 0
    trials = 300
    for _ in range(trials):
        hit = gen.random(200) < p_hit
        counts = np.where(hit, gen.geometric(1 / mean_len, 200), 0)
        ci = count_interval(counts, rng=gen, resamples=1000)
        covered += ci.low <= truth <= ci.high
    assert 0.82 <= covered / trials <= 0.96


def test_an_infinity_is_a_value_where_asked():
    assert mean_interval([math.inf, 1.0, math.nan, 2.0]).value == 1.5  # left out by default
    kept = mean_interval([math.inf, 1.0, math.nan, 2.0], infinite=True)
    assert kept.value == math.inf and kept.n == 3 and math.isnan(kept.low) and math.isnan(kept.high)
    assert math.isnan(mean_interval([math.inf, -math.inf], infinite=True).value)
    assert mean_interval([1.0, 3.0], infinite=True) == mean_interval([1.0, 3.0])
