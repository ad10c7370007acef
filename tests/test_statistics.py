"""Bootstrap spreads over trajectories (nfarm.study.statistics): the sums reproduce the direct NRMSE,
intervals are seeded, contain the estimate and narrow with more trajectories."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm.study.statistics import (bootstrap_nrmse, bootstrap_rows, bootstrap_seeds, nrmse_from_sums, trajectory_maxima, trajectory_sums,
                              worst_difference)


def data(trajectories, seed=0, per=50, n=3):
    rng = np.random.default_rng(seed)
    label = np.repeat(np.arange(trajectories), per)
    tau = rng.normal(size=(len(label), n)) * [1.0, 2.0, 0.5] + rng.normal(size=(trajectories, 1))[label]
    predicted = tau + rng.normal(size=tau.shape) * [0.1, 0.1, 0.2] * (1 + rng.random((trajectories, 1))[label])
    return predicted, tau, label


def test_sums_reproduce_the_direct_nrmse():
    predicted, tau, label = data(12)
    direct = np.sqrt(((predicted - tau) ** 2).mean(axis=0)) / tau.std(axis=0)
    sums = trajectory_sums(predicted, tau, label)
    assert sums.shape == (12, 10)
    np.testing.assert_allclose(nrmse_from_sums(sums.sum(axis=0)), direct, rtol=1e-12)


def test_bootstrap_is_seeded_contains_the_estimate_and_narrows_with_more_trajectories():
    widths = []
    for T in (10, 160):
        sums = trajectory_sums(*data(T))
        a, b = bootstrap_nrmse(sums, seed=1), bootstrap_nrmse(sums, seed=1)
        np.testing.assert_array_equal(a.low, b.low)
        assert (a.low <= a.value).all() and (a.value <= a.high).all()
        assert a.worst_low <= a.worst <= a.worst_high and a.trajectories == T
        widths.append(a.worst_high - a.worst_low)
    assert widths[1] < 0.5 * widths[0], widths


@pytest.mark.parametrize("sums, kwargs, message", [
    (np.ones((1, 4)), {}, r"sums must be \(trajectories >= 2, 1 \+ 3n\)"),
    (np.ones((5, 5)), {}, r"sums must be"),
    (np.ones((5, 4)), {"draws": 10}, r"draws must be an integer >= 100"),
    (np.ones((5, 4)), {"level": 1.5}, r"level must be in \(0, 1\)"),
])
def test_bad_input_is_refused(sums, kwargs, message):
    with pytest.raises(ValueError, match=message):
        bootstrap_nrmse(sums, **kwargs)
    with pytest.raises(ValueError, match="must be \\(N, n\\) arrays of one shape"):
        trajectory_sums(np.ones((3, 2)), np.ones((3, 3)), np.zeros(3))


def test_paired_difference_tells_a_real_gap_from_noise():
    predicted, tau, label = data(40)
    better = tau + 0.5 * (predicted - tau)
    a, b = trajectory_sums(predicted, tau, label), trajectory_sums(better, tau, label)
    value, low, high = worst_difference(a, b, seed=2)
    assert 0 < low <= value <= high                     # a is worse, beyond the spread
    value, low, high = worst_difference(a, a, seed=2)
    assert value == low == high == 0.0                   # the same model: no difference
    with pytest.raises(ValueError, match="same trajectories"):
        worst_difference(a, a[:-1])


def test_ranges_separate_only_when_no_seed_overlaps():
    from nfarm.study.statistics import ranges_separate, separation_level
    assert ranges_separate([1, 2, 3], [3.5, 4, 5]) and ranges_separate([4, 5], [1, 2])
    assert not ranges_separate([1, 2, 4], [3, 5, 6])
    assert separation_level(5, 5) == pytest.approx(2 / 252)
    with pytest.raises(ValueError, match="at least two seeds"):
        ranges_separate([1], [2, 3])
    # Measured on draws from one distribution: separated about as often as the level says.
    rng = np.random.default_rng(0)
    rate = np.mean([ranges_separate(rng.normal(size=5), rng.normal(size=5)) for _ in range(20000)])
    assert rate == pytest.approx(separation_level(5, 5), abs=0.003)


# --------------------------------------------------------------------------------------------
# Independent rows: per-trajectory maxima, test poses


def test_trajectory_maxima_are_each_trajectorys_largest_error():
    rng = np.random.default_rng(3)
    labels = np.repeat([4, 1, 7], [5, 9, 3])
    predicted, tau = rng.normal(size=(17, 2)), rng.normal(size=(17, 2))
    maxima = trajectory_maxima(predicted, tau, labels)
    for row, label in zip(maxima, [1, 4, 7]):
        np.testing.assert_array_equal(row, np.abs(predicted - tau)[labels == label].max(axis=0))
    with pytest.raises(ValueError, match="one shape"):
        trajectory_maxima(predicted, tau[:, :1], labels)


@pytest.mark.parametrize("n", [400, 4000])
def test_bootstrap_of_a_mean_matches_the_normal_interval(n):
    """The percentile interval of a mean of normal rows is close to mean ± 1.96 σ/√N."""
    x = np.random.default_rng(n).normal(2.0, 3.0, size=n)
    est = bootstrap_rows(x, lambda X: X[..., 0].mean(axis=-1), draws=4000, seed=1)
    half = 1.96 * x.std(ddof=1) / np.sqrt(n)
    assert est.value == pytest.approx(x.mean())
    assert est.low == pytest.approx(x.mean() - half, abs=0.15 * half)
    assert est.high == pytest.approx(x.mean() + half, abs=0.15 * half)
    assert (est.rows, est.draws, est.level) == (n, 4000, 0.95)


def test_bootstrap_rows_is_seeded_and_takes_several_statistics():
    rows = np.random.default_rng(0).exponential(size=(500, 3))
    stat = lambda X: np.stack([np.median(X[..., 0], axis=-1), X.max(axis=(-2, -1))], axis=-1)  # noqa: E731
    a, b = (bootstrap_rows(rows, stat, draws=500, seed=5) for _ in range(2))
    np.testing.assert_array_equal(a.low, b.low)
    assert a.value.shape == a.low.shape == (2,)
    assert np.all(a.low <= a.value) and np.all(a.value <= a.high)
    assert a.high[1] == rows.max()            # a maximum's upper end is the sample's
    c = bootstrap_rows(rows, stat, draws=500, seed=6)
    assert not np.array_equal(a.low, c.low)


@pytest.mark.parametrize("rows, kwargs, message", [
    (np.ones((1, 2)), {}, "N >= 2"),
    (np.array([[1.0], [np.nan]]), {}, "finite"),
    (np.ones((5, 2)), {"draws": 10}, "draws"),
    (np.ones((5, 2)), {"level": 1.0}, "level"),
])
def test_bootstrap_rows_refuses_bad_input(rows, kwargs, message):
    with pytest.raises(ValueError, match=message):
        bootstrap_rows(rows, lambda X: X.mean(axis=(-2, -1)), **kwargs)


def test_tail_ratios_find_the_cause_and_call_two_alike_causes_alike():
    from nfarm.study.statistics import tail_ratios
    rng = np.random.default_rng(3)
    n = 4000
    edge, also, noise = rng.random(n), rng.random(n), rng.random(n)
    error = rng.gamma(2.0, size=n) * (1 + 2 * (edge < 0.1))          # three times as large near the edge
    result = tail_ratios({"edge": edge, "other": also, "noise": noise}, error, draws=400, seed=1)
    assert result.low[0] < 3.0 < result.high[0] * 1.5 and result.low[0] > 2.0
    assert result.larger("edge", "other") and result.larger("edge", "noise")
    assert not result.larger("other", "noise") and not result.larger("noise", "other")   # alike: no order
    again = tail_ratios({"edge": edge, "other": also, "noise": noise}, error, draws=400, seed=1)
    np.testing.assert_array_equal(again.pair_low, result.pair_low)                        # seeded


def test_tail_ratios_use_only_the_rows_a_cause_has():
    from nfarm.study.statistics import tail_ratios
    rng = np.random.default_rng(4)
    x = rng.random(2000)
    error = 1 + 4 * (x < 0.1)
    partial = np.where(np.arange(2000) % 2 == 0, x, np.nan)                # half the rows have no value
    result = tail_ratios({"all": x, "half": partial}, error, draws=200)
    np.testing.assert_allclose(result.value, [5.0, 5.0])


def test_tail_ratios_leave_out_a_resample_with_no_value_without_a_warning():
    """A cause few rows have (another solution, on a few poses): some resamples draw none of them;
    their ratio is NaN and left out of the interval, and NumPy's "All-NaN slice" is not printed."""
    import warnings

    from nfarm.study.statistics import tail_ratios
    rng = np.random.default_rng(5)
    x = rng.random(40)
    rare = np.where(np.arange(40) < 2, x, np.nan)                          # two rows of forty have a value
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = tail_ratios({"rare": rare, "all": x}, 1 + x, draws=200, seed=0)
    assert np.isfinite(result.value).all() and np.isfinite(result.low).all()


@pytest.mark.parametrize("causes, error, message", [
    ({}, np.ones(5), "at least one"),
    ({"a": np.ones(4)}, np.ones(5), r"each cause \(N,\)"),
    ({"a": np.ones(5)}, np.array([1, 2, np.nan, 4, 5]), "must be finite"),
])
def test_tail_ratios_refuse_bad_input_in_one_line(causes, error, message):
    from nfarm.study.statistics import tail_ratios
    with pytest.raises(ValueError, match=message):
        tail_ratios(causes, error)


def _mean(X):
    return X[..., 0].mean(axis=1)


def test_two_level_bootstrap_covers_the_seeds_spread_and_pairs_methods():
    """Over seeds and units: with the seeds' means far apart the interval spans them (a one-level
    bootstrap over the units of one seed's model does not); with identical models it is the
    units' spread alone; a method that is another plus a constant differs by exactly that
    constant on every resample (paired by seed and unit); the same seed gives the same bits."""
    rng = np.random.default_rng(3)
    units = rng.normal(size=(1, 300, 1))
    shifted = units + np.array([0.0, 1.0, 2.0, 3.0, 4.0])[:, None, None]         # (5, 300, 1)
    both = bootstrap_seeds(shifted, _mean, draws=1000)
    one = bootstrap_rows(shifted[0], _mean, draws=1000)
    assert both.seeds == 5 and both.rows == 300 and one.seeds == 1
    assert both.low < 1.0 and both.high > 3.0 and both.low <= both.value <= both.high
    assert one.high - one.low < 0.5 < (both.high - both.low) / 4
    same = bootstrap_seeds(np.repeat(units, 5, axis=0), _mean, draws=1000)
    assert same.high - same.low < 0.5
    paired = bootstrap_seeds(np.concatenate([shifted + 0.25, shifted], axis=-1),
                             lambda X: X[..., 0].mean(axis=1) - X[..., 1].mean(axis=1), draws=500)
    assert paired.low == pytest.approx(0.25, abs=1e-12) and paired.high == pytest.approx(0.25, abs=1e-12)
    again = bootstrap_seeds(shifted, _mean, draws=1000)
    assert (again.low, again.high) == (both.low, both.high)
    assert bootstrap_seeds(shifted, _mean, draws=1000, seed=1).low != both.low


@pytest.mark.parametrize("values, kwargs, message", [
    (np.zeros((2, 1, 1)), {}, r"values must be a finite \(seeds >= 1, units >= 2, k\) array, got shape \(2, 1, 1\)"),
    (np.full((2, 5, 1), np.nan), {}, r"values must be a finite"),
    (np.zeros((2, 5, 1)), {"draws": 10}, r"draws must be an integer >= 100, got 10"),
    (np.zeros((2, 5, 1)), {"level": 1.0}, r"level must be in \(0, 1\), got 1.0"),
])
def test_two_level_bootstrap_refuses_bad_input(values, kwargs, message):
    with pytest.raises(ValueError, match=message):
        bootstrap_seeds(values, _mean, **kwargs)


@pytest.mark.parametrize("n", [2, 7, 10, 1000])
@pytest.mark.parametrize("q", [0.0, 0.05, 0.5, 0.95, 1.0])
def test_a_quantile_read_through_counts_is_numpys_of_the_resample(n, q):
    """Order statistics from the times each row is drawn equal NumPy's on the resampled rows
    themselves (ties included), bit for bit."""
    from nfarm.study.statistics import resampled_quantile
    rng = np.random.default_rng(n)
    x = np.round(rng.normal(size=n), 1)                   # ties
    drawn = rng.integers(0, n, size=(50, n))
    counts = np.stack([np.bincount(d, minlength=n) for d in drawn])
    order = np.argsort(x, kind="stable")
    got = resampled_quantile(x[order], np.cumsum(counts[:, order], axis=1), q)
    expected = np.median(x[drawn], axis=1) if q == 0.5 else np.percentile(x[drawn], 100 * q, axis=1)
    np.testing.assert_array_equal(got, expected)


@pytest.mark.parametrize("statistic", ["mean", "p95", "median"])
def test_bootstrap_counts_draws_scipys_resamples_and_intervals(statistic):
    """Against ``scipy.stats.bootstrap`` itself (percentile method, its generator seeded alike, the
    resamples made 100 at a time): the same interval of a mean, a 95th percentile and a median of
    per-row values, to 1e-12 relative, for two seeds; another seed, another interval."""
    import scipy.stats

    from nfarm.study.statistics import bootstrap_counts, resampled_quantile
    x = np.random.default_rng(11).lognormal(size=1500)
    order = np.argsort(x, kind="stable")
    q = {"mean": None, "p95": 0.95, "median": 0.5}[statistic]
    if q is None:
        by_counts = lambda counts: counts @ x / len(x)                       # noqa: E731
        reference = lambda s, axis: np.mean(s, axis=axis)                    # noqa: E731
    else:
        by_counts = lambda counts: resampled_quantile(x[order], np.cumsum(counts[:, order], axis=1), q)  # noqa: E731
        reference = lambda s, axis: np.percentile(s, 100 * q, axis=axis)     # noqa: E731
    intervals = {}
    for seed in (0, 5):
        ours = bootstrap_counts(len(x), by_counts, draws=2000, level=0.9, seed=seed)
        theirs = scipy.stats.bootstrap((x,), reference, n_resamples=2000, confidence_level=0.9, method="percentile",
                                       vectorized=True, batch=100, rng=np.random.default_rng(seed))
        assert ours.value == pytest.approx(reference(x, axis=-1), rel=1e-14)
        np.testing.assert_allclose([ours.low, ours.high], theirs.confidence_interval, rtol=1e-12, atol=0)
        assert ours.low < ours.value < ours.high
        intervals[seed] = (ours.low, ours.high)
    assert intervals[0] != intervals[5]


def test_bootstrap_counts_is_bootstrap_rows_for_a_statistic_of_counts():
    """The same statistic through counts and through the resampled rows: the same value, and,
    the generator drawing the same resamples as SciPy's, the same interval (to rounding of the
    last percentile step)."""
    from nfarm.study.statistics import bootstrap_counts, resampled_quantile
    rng = np.random.default_rng(3)
    x = rng.exponential(size=2000)
    order = np.argsort(x)
    p95 = lambda counts: resampled_quantile(x[order], np.cumsum(counts[:, order], axis=1), 0.95)  # noqa: E731
    by_counts = bootstrap_counts(len(x), p95, draws=2000, seed=1)
    by_rows = bootstrap_rows(x, lambda X: np.percentile(X[..., 0], 95, axis=-1), draws=2000, seed=1)
    assert by_counts.value == by_rows.value == np.percentile(x, 95)
    np.testing.assert_allclose([by_counts.low, by_counts.high], [by_rows.low, by_rows.high], rtol=1e-12, atol=0)
    other = bootstrap_counts(len(x), p95, draws=2000, seed=2)           # other resamples: another interval
    assert (other.low, other.high) != (by_counts.low, by_counts.high)
    again = bootstrap_counts(len(x), p95, draws=2000, seed=1)
    assert (again.low, again.high) == (by_counts.low, by_counts.high)          # seeded
    for bad, message in (({"draws": 10}, "draws must be"), ({"level": 1.0}, "level must be")):
        with pytest.raises(ValueError, match=message):
            bootstrap_counts(len(x), p95, **bad)
    with pytest.raises(ValueError, match="n_rows must be a whole number >= 2"):
        bootstrap_counts(1, p95)
