"""Spreads of the study's compared numbers (chapters 06–08).

Held-out errors are averages over trajectories whose samples are strongly correlated (a
trajectory of 1 000 states at 50 Hz is a handful of independent moves), so their spread is
taken over **trajectories**: the percentile bootstrap (Efron & Tibshirani 1993, ch. 13)
resamples the test trajectories with replacement and recomputes the statistic from per-trajectory
sums (:func:`trajectory_sums`), ``draws`` times from one seeded generator.

The NRMSE of joint j is ``sqrt(SSE_j / N) / std(τ_j)``, the standard deviation taken over the
same (resampled) samples, so a resample's NRMSE is a function of the sums of its trajectories'
``[count, SSE_j, Σ τ_j, Σ τ_j²]``.

Over **seeds** (a sweep's configurations trained on several data draws and initialisations,
:func:`nfarm.study.sweep.by_configuration`) a difference counts when the seeds' ranges do not
overlap (:func:`ranges_separate`): if the two configurations' values came from one
distribution, every value of one would lie below every value of the other with probability
``1 / C(n_a + n_b, n_a)`` — for 5 seeds each, 2 / 252 = 0.8 % either way
(:func:`separation_level`), a test that assumes no distribution.

Over **independent samples** (the test poses of the learned IK, each drawn on its own; or the
per-trajectory maxima of a torque error) :func:`bootstrap_rows` resamples rows with SciPy's
``scipy.stats.bootstrap`` (percentile method, paired columns, batched so that 2 000 resamples of
10 000 poses stay within a few tens of MB). A statistic made of sums and order statistics of
per-row values (the IK metrics: an RMSE, a median, a 95th percentile, a maximum) reads a
resample through the times each row is drawn instead (:func:`bootstrap_counts`,
:func:`resampled_quantile`): no copy of the rows, 20× faster on 10 000 poses, the same
statistic. :func:`tail_ratios` does the same for the question
"does the error grow near a place": the ratio of the median error over the poses nearest to it
to that over the poses farthest from it, for several places on the same resamples.

Over **seeds and test units together** (the headline numbers of chapters 07–08: the models of
five seeds each judged on the same test set) :func:`bootstrap_seeds` resamples the models, then
the units, so an interval covers what varies between trainings as well as the test draw.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.stats

from ..infra.arguments import check_integer

__all__ = ["trajectory_sums", "trajectory_maxima", "nrmse_from_sums", "Interval", "bootstrap_nrmse",
           "worst_difference", "Estimate", "bootstrap_rows", "bootstrap_counts", "resampled_quantile",
           "bootstrap_seeds", "bootstrap_p", "holm", "distinct_resamples", "ranges_separate", "separation_level",
           "TailRatios", "tail_ratio", "tail_ratios", "resolved_joints"]


def trajectory_sums(predicted: np.ndarray, tau: np.ndarray, trajectory: np.ndarray) -> np.ndarray:
    """``(T, 1 + 3n)``: per trajectory (in order of their labels), the sample count, then per
    joint the sum of squared errors, the sum of the torques and the sum of their squares.

    Args:
        predicted, tau: ``(N, n)`` torques [N·m].
        trajectory: ``(N,)`` integer label of each sample's trajectory.
    """
    predicted, tau = np.asarray(predicted, float), np.asarray(tau, float)
    if predicted.shape != tau.shape or predicted.ndim != 2:
        raise ValueError(f"predicted and tau must be (N, n) arrays of one shape, got {predicted.shape} "
                         f"and {tau.shape}")
    labels, index = np.unique(np.asarray(trajectory), return_inverse=True)
    if len(index) != len(tau):
        raise ValueError(f"trajectory must label each of the {len(tau)} samples, got {len(index)} labels")
    columns = np.concatenate([np.ones((len(tau), 1)), (predicted - tau) ** 2, tau, tau ** 2], axis=1)
    sums = np.zeros((len(labels), columns.shape[1]))
    np.add.at(sums, index, columns)
    return sums


def trajectory_maxima(predicted: np.ndarray, tau: np.ndarray, trajectory: np.ndarray) -> np.ndarray:
    """``(T, n)``: per trajectory (in order of their labels) and joint, the largest absolute
    torque error ``max |predicted - tau|`` [N·m] — the rows :func:`bootstrap_rows` resamples for
    the largest error's interval. Arguments as :func:`trajectory_sums`."""
    predicted, tau = np.asarray(predicted, float), np.asarray(tau, float)
    if predicted.shape != tau.shape or predicted.ndim != 2:
        raise ValueError(f"predicted and tau must be (N, n) arrays of one shape, got {predicted.shape} "
                         f"and {tau.shape}")
    labels, index = np.unique(np.asarray(trajectory), return_inverse=True)
    if len(index) != len(tau):
        raise ValueError(f"trajectory must label each of the {len(tau)} samples, got {len(index)} labels")
    maxima = np.zeros((len(labels), tau.shape[1]))
    np.maximum.at(maxima, index, np.abs(predicted - tau))
    return maxima


def nrmse_from_sums(sums: np.ndarray, *, normalised: bool = True) -> np.ndarray:
    """``(..., n)`` NRMSE of the totals ``sums (..., 1 + 3n)`` (already summed over
    trajectories); with ``normalised=False`` the RMSE itself [N·m]."""
    n = (sums.shape[-1] - 1) // 3
    count = sums[..., :1]
    sse, total, squares = sums[..., 1:1 + n], sums[..., 1 + n:1 + 2 * n], sums[..., 1 + 2 * n:]
    if not normalised:
        return np.sqrt(sse / count)
    variance = np.maximum(squares / count - (total / count) ** 2, 0.0)
    return np.sqrt(sse / count) / np.sqrt(np.where(variance > 0, variance, np.nan))


@dataclass(frozen=True)
class Interval:
    """A statistic and its percentile-bootstrap interval over trajectories.

    Attributes:
        value: ``(n,)`` per joint, on the whole test set.
        low, high: ``(n,)`` the interval's ends.
        worst, worst_low, worst_high: the largest joint's value and the interval of the largest
            joint's value (recomputed per resample, so the worst joint may change).
        level, draws, trajectories: the coverage, the resamples and the trajectories resampled.
    """

    value: np.ndarray
    low: np.ndarray
    high: np.ndarray
    worst: float
    worst_low: float
    worst_high: float
    level: float
    draws: int
    trajectories: int


def _check(sums, draws, level) -> np.ndarray:
    sums = np.asarray(sums, float)
    if sums.ndim != 2 or sums.shape[0] < 2 or (sums.shape[1] - 1) % 3:
        raise ValueError(f"sums must be (trajectories >= 2, 1 + 3n), got shape {sums.shape}")
    if not (isinstance(draws, int) and draws >= 100):
        raise ValueError(f"draws must be an integer >= 100, got {draws!r}")
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level!r}")
    return sums


def _resampled(sums: np.ndarray, draws: int, seed: int, normalised: bool = True) -> np.ndarray:
    """``(draws, n)`` NRMSE (or RMSE) of ``draws`` resamples of the trajectories; the resamples
    depend on the seed and the number of trajectories only, so two models' are paired."""
    picks = np.random.default_rng(seed).integers(0, len(sums), size=(draws, len(sums)))
    return nrmse_from_sums(sums[picks].sum(axis=1), normalised=normalised)


def bootstrap_nrmse(sums: np.ndarray, *, draws: int = 2000, level: float = 0.95, seed: int = 0,
                    normalised: bool = True) -> Interval:
    """Per-joint and worst-joint NRMSE (``normalised=False``: RMSE [N·m]) with
    percentile-bootstrap intervals over the rows (trajectories) of ``sums (T, 1 + 3n)``
    (:func:`trajectory_sums`)."""
    sums = _check(sums, draws, level)
    T = len(sums)
    resampled = _resampled(sums, draws, seed, normalised)              # (draws, n)
    value = nrmse_from_sums(sums.sum(axis=0), normalised=normalised)
    tails = [(1 - level) / 2 * 100, (1 + level) / 2 * 100]
    low, high = np.nanpercentile(resampled, tails, axis=0)
    worst_low, worst_high = np.nanpercentile(np.nanmax(resampled, axis=1), tails)
    return Interval(value, low, high, float(np.nanmax(value)), float(worst_low), float(worst_high),
                    level, draws, T)


def worst_difference(sums_a: np.ndarray, sums_b: np.ndarray, *, draws: int = 2000, level: float = 0.95,
                     seed: int = 0, normalised: bool = True) -> tuple[float, float, float]:
    """The worst-joint NRMSE of model a less that of model b on the same test trajectories, and
    the percentile-bootstrap interval of that difference, both models judged on the same
    resamples (paired). An interval that contains 0 is no difference."""
    sums_a, sums_b = _check(sums_a, draws, level), _check(sums_b, draws, level)
    if sums_a.shape != sums_b.shape:
        raise ValueError(f"the two models must be judged on the same trajectories, got sums of shapes "
                         f"{sums_a.shape} and {sums_b.shape}")
    a = np.nanmax(_resampled(sums_a, draws, seed, normalised), axis=1)
    b = np.nanmax(_resampled(sums_b, draws, seed, normalised), axis=1)
    tails = [(1 - level) / 2 * 100, (1 + level) / 2 * 100]
    low, high = np.nanpercentile(a - b, tails)
    value = float(np.nanmax(nrmse_from_sums(sums_a.sum(axis=0), normalised=normalised))
                  - np.nanmax(nrmse_from_sums(sums_b.sum(axis=0), normalised=normalised)))
    return value, float(low), float(high)


@dataclass(frozen=True)
class Estimate:
    """A statistic of independent rows and its percentile-bootstrap interval
    (:func:`bootstrap_rows`): ``value``, ``low`` and ``high`` of the statistic's shape (a float
    for a scalar statistic), ``level`` the coverage, ``draws`` the resamples, ``rows`` the rows
    resampled."""

    value: np.ndarray | float
    low: np.ndarray | float
    high: np.ndarray | float
    level: float
    draws: int
    rows: int
    #: The models (seeds) resampled with the rows (:func:`bootstrap_seeds`); 1: the rows alone.
    seeds: int = 1
    #: The bootstrap's two-sided p-value of 0 for a difference (:func:`bootstrap_p`; its
    #: resolution ``2 / draws``), of the statistic's shape; NaN where it was not computed.
    p_zero: np.ndarray | float = float("nan")


def bootstrap_rows(rows: np.ndarray, statistic, *, draws: int = 2000, level: float = 0.95, seed: int = 0,
                   batch: int = 100) -> Estimate:
    """A statistic of the rows of ``rows (N, k)`` and its percentile-bootstrap interval from
    ``draws`` resamples of the rows with replacement (``scipy.stats.bootstrap``, the generator
    seeded by ``seed``; the same seed and N resample two models' rows alike).

    ``statistic(X)`` maps ``X (b, N, k)`` (``b`` resamples) to ``(b,)`` or ``(b, m)``; the
    resamples are made ``batch`` at a time. The interval of an extreme (a maximum, a high
    percentile of few rows) is the bootstrap's and no better: its upper end is the sample's.
    """
    rows = np.asarray(rows, float)
    if rows.ndim == 1:
        rows = rows[:, None]
    if rows.ndim != 2 or len(rows) < 2 or not np.isfinite(rows).all():
        raise ValueError(f"rows must be a finite (N >= 2, k) array, got shape {rows.shape}")
    if not (isinstance(draws, int) and draws >= 100):
        raise ValueError(f"draws must be an integer >= 100, got {draws!r}")
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level!r}")

    def resampled(*columns, axis=-1):        # scipy hands each column as (b, N), wants (m, b)
        return np.moveaxis(np.asarray(statistic(np.stack(columns, axis=-1))), 0, -1)

    value = np.asarray(statistic(rows[None]))[0]
    result = scipy.stats.bootstrap(tuple(rows.T), resampled, n_resamples=draws, confidence_level=level,
                                   method="percentile", paired=True, vectorized=True, batch=batch,
                                   rng=np.random.default_rng(seed))
    low, high = result.confidence_interval
    scalar = value.ndim == 0
    as_out = (lambda v: float(v)) if scalar else (lambda v: np.asarray(v, float))   # noqa: E731
    return Estimate(as_out(value), as_out(low), as_out(high), level, draws, len(rows))


def bootstrap_counts(n_rows: int, statistic, *, draws: int = 2000, level: float = 0.95, seed: int = 0,
                     batch: int = 100) -> Estimate:
    """A statistic of ``n_rows`` rows read through how often a resample draws each row, and
    its percentile-bootstrap interval from ``draws`` resamples with replacement (``batch`` at a
    time from one generator seeded by ``seed``: the same seed and ``n_rows`` draw two methods'
    rows alike, so a difference of two statistics is paired).

    ``statistic(counts)`` maps ``counts (b, N)`` (integers, each row summing to N; all ones for
    the rows themselves, the value) to ``(b,)`` or ``(b, m)``. For statistics of sums
    (``counts @ x``) and order statistics (:func:`resampled_quantile`) of per-row values this
    costs O(N) a resample and copies no rows, where :func:`bootstrap_rows` gathers them.

    Example:
        >>> x = np.arange(10.0)
        >>> mean = lambda counts: counts @ x / len(x)
        >>> est = bootstrap_counts(10, mean, draws=500)
        >>> est.value, bool(est.low < 4.5 < est.high)
        (4.5, True)
    """
    check_integer("n_rows", n_rows, 2, message=f"n_rows must be a whole number >= 2, got {n_rows!r}")
    check_integer("draws", draws, 100, numpy=False)
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level!r}")
    n = int(n_rows)
    value = np.asarray(statistic(np.ones((1, n), np.int64)))[0]
    rng = np.random.default_rng(seed)
    theta = []
    for start in range(0, draws, batch):
        b = min(batch, draws - start)
        drawn = rng.integers(0, n, size=(b, n)) + n * np.arange(b)[:, None]
        theta.append(np.asarray(statistic(np.bincount(drawn.ravel(), minlength=b * n).reshape(b, n))))
    low, high = np.percentile(np.concatenate(theta), [100 * (1 - level) / 2, 100 * (1 + level) / 2], axis=0)
    scalar = value.ndim == 0
    as_out = (lambda v: float(v)) if scalar else (lambda v: np.asarray(v, float))   # noqa: E731
    return Estimate(as_out(value), as_out(low), as_out(high), level, draws, n)


def resampled_quantile(x_sorted: np.ndarray, running: np.ndarray, q: float) -> np.ndarray:
    """``(b,)``: the ``q``-quantile of each resample, as ``np.percentile(resample, 100 q)``
    computes it (linear between order statistics; ``q = 0.5``: the median, the mean of the two
    middle ones as ``np.median`` takes it; ``q = 1``: the maximum), from the values sorted
    ``x_sorted (N,)`` and ``running (b, N)``, the running sum of each resample's counts
    (:func:`bootstrap_counts`) taken in that sorted order.

    The k-th smallest value of a resample (from 0) is ``x_sorted[j]`` for the first ``j`` whose
    running count exceeds k.

    Example:
        >>> x = np.array([3.0, 1.0, 2.0])
        >>> counts = np.array([[0, 2, 1], [1, 1, 1]])        # resamples {1, 1, 2} and {3, 1, 2}
        >>> order = np.argsort(x)
        >>> resampled_quantile(x[order], np.cumsum(counts[:, order], axis=1), 0.5).tolist()
        [1.0, 2.0]
    """
    if not 0 <= q <= 1:
        raise ValueError(f"q must be in [0, 1], got {q!r}")
    size = running[:, -1]
    h = (size - 1) * q
    lo = np.floor(h).astype(np.int64)
    t = h - lo

    def order(k):
        return x_sorted[np.minimum((running <= k[:, None]).sum(axis=1), len(x_sorted) - 1)]

    a, b = order(lo), order(np.minimum(lo + 1, size - 1))
    if q == 0.5:
        return np.where(t > 0, (a + b) / 2, a)
    diff = b - a                                              # NumPy's lerp, both halves
    return np.where(t >= 0.5, b - diff * (1 - t), a + diff * t)


def bootstrap_seeds(values: np.ndarray, statistic, *, draws: int = 2000, level: float = 0.95, seed: int = 0,
                    batch: int = 10) -> Estimate:
    """A statistic of ``values (S, N, k)`` — ``S`` models (seeds: data draw and initialisation)
    each judged on the same ``N`` test units (poses, or trajectories' sums), ``k`` columns — and
    its two-level percentile-bootstrap interval, which covers what varies between trainings as
    well as the test draw: each resample draws ``S`` models with replacement, then ``N`` units
    with replacement (the same units for every model drawn, so the models stay paired on them),
    and pools the ``S × N`` rows (Davison & Hinkley 1997, §3.8, resampling both stages).

    ``statistic(X)`` maps pooled rows ``X (b, S·N, k)`` to ``(b,)`` or ``(b, m)``, as in
    :func:`bootstrap_rows`; the value is the statistic of all models' rows pooled. Two methods
    are compared paired by giving both as columns (model ``s`` of each trained on the same data
    draw) and a statistic of their difference. ``S = 1`` is :func:`bootstrap_rows`' one-level
    bootstrap (by its own resamples).

    Example:
        >>> rng = np.random.default_rng(1)
        >>> values = rng.normal(size=(5, 400, 1)) + np.arange(5)[:, None, None]   # the seeds differ
        >>> mean = lambda X: X[..., 0].mean(axis=1)
        >>> both = bootstrap_seeds(values, mean, draws=500)
        >>> units = bootstrap_rows(values.reshape(-1, 1), mean, draws=500)           # seeds ignored
        >>> round(both.value, 6) == round(units.value, 6), both.high - both.low > 3 * (units.high - units.low)
        (True, True)
    """
    values = np.asarray(values, float)
    if values.ndim == 2:
        values = values[..., None]
    if values.ndim != 3 or values.shape[0] < 1 or values.shape[1] < 2 or not np.isfinite(values).all():
        raise ValueError(f"values must be a finite (seeds >= 1, units >= 2, k) array, got shape {values.shape}")
    if not (isinstance(draws, int) and draws >= 100):
        raise ValueError(f"draws must be an integer >= 100, got {draws!r}")
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level!r}")
    S, N, k = values.shape
    value = np.asarray(statistic(values.reshape(1, S * N, k)))[0]
    rng = np.random.default_rng(seed)
    resampled = []
    for start in range(0, draws, batch):
        b = min(batch, draws - start)
        models = rng.integers(0, S, size=(b, S))
        units = rng.integers(0, N, size=(b, N))
        pooled = values[models[:, :, None], units[:, None, :]].reshape(b, S * N, k)
        resampled.append(np.asarray(statistic(pooled), float))
    tails = [(1 - level) / 2 * 100, (1 + level) / 2 * 100]
    resampled = np.concatenate(resampled)
    low, high = np.nanpercentile(resampled, tails, axis=0)
    scalar = value.ndim == 0
    as_out = (lambda v: float(v)) if scalar else (lambda v: np.asarray(v, float))   # noqa: E731
    return Estimate(as_out(value), as_out(low), as_out(high), level, draws, N, S, as_out(bootstrap_p(resampled)))


def bootstrap_p(resampled: np.ndarray) -> np.ndarray | float:
    """The two-sided bootstrap p-value of 0 for a difference, from its resamples ``(draws, ...)``:
    twice the smaller share of them on either side of 0, at most 1 (Davison & Hinkley 1997,
    §4.4: the level at which a percentile interval just reaches 0, so that a ``1 − α``
    interval excludes 0 where ``p < α``). Resamples that are NaN are left out. Its resolution
    is ``2 / draws``: a 0 means below that.

    Example:
        >>> float(bootstrap_p(np.array([-3.0, -2.0, -1.0, 1.0]))), float(bootstrap_p(np.array([1.0, 2.0, 3.0])))
        (0.5, 0.0)
    """
    resampled = np.asarray(resampled, float)
    finite = np.isfinite(resampled)
    n = finite.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        below = np.where(finite, resampled <= 0, False).sum(axis=0) / n
        above = np.where(finite, resampled >= 0, False).sum(axis=0) / n
    return np.minimum(1.0, 2 * np.minimum(below, above))


def holm(p_values) -> np.ndarray:
    """Holm's step-down adjustment of ``m`` p-values (Holm 1979): sorted ascending, the k-th
    (from 0) is multiplied by ``m − k``, the running maximum taken, capped at 1. Rejecting where
    the adjusted value is below α holds the family-wise error rate at α for any dependence
    between the tests.

    Example:
        >>> holm([0.01, 0.04, 0.03, 0.005]).round(3).tolist()
        [0.03, 0.06, 0.06, 0.02]
    """
    p = np.asarray(p_values, float).ravel()
    if p.size and (not np.isfinite(p).all() or (p < 0).any() or (p > 1).any()):
        raise ValueError(f"p-values must be finite numbers in [0, 1], got {p.tolist()}")
    adjusted, running = np.empty_like(p), 0.0
    for rank, i in enumerate(np.argsort(p, kind="stable")):
        running = max(running, min(1.0, (len(p) - rank) * p[i]))
        adjusted[i] = running
    return adjusted


def distinct_resamples(n: int) -> int:
    """How many distinct resamples (multisets) ``n`` items drawn with replacement allow:
    ``C(2n − 1, n)`` — why an outer bootstrap over five seeds is coarse.

    >>> distinct_resamples(5)
    126
    """
    return math.comb(2 * n - 1, n)


def ranges_separate(a, b) -> bool:
    """Whether the values of two configurations over their seeds do not overlap (every value
    of one below every value of the other): the rule by which a difference over seeds is
    written as a difference. ``a``, ``b``: 1-D sequences of at least two values."""
    a, b = np.asarray(a, float).ravel(), np.asarray(b, float).ravel()
    if len(a) < 2 or len(b) < 2:
        raise ValueError(f"a spread needs at least two seeds per configuration, got {len(a)} and {len(b)}")
    return bool(a.max() < b.min() or b.max() < a.min())


def separation_level(n_a: int, n_b: int) -> float:
    """The probability that :func:`ranges_separate` holds (either way) for two configurations
    whose ``n_a`` and ``n_b`` values come from one continuous distribution: ``2 / C(n_a + n_b,
    n_a)``."""
    return 2 / math.comb(n_a + n_b, n_a)


@dataclass(frozen=True)
class TailRatios:
    """:func:`tail_ratios`' result for ``k`` candidate causes: each one's ratio and its interval
    (``value``, ``low``, ``high`` of shape ``(k,)``) and, for every pair, the interval of the
    ratio of their ratios (``pair_low[i, j]``, ``pair_high[i, j]`` of ``ratio_i / ratio_j``, from
    the same resamples), at coverage ``level`` from ``draws`` resamples."""

    names: tuple[str, ...]
    value: np.ndarray
    low: np.ndarray
    high: np.ndarray
    pair_low: np.ndarray
    pair_high: np.ndarray
    level: float
    draws: int

    def larger(self, a: str, b: str) -> bool:
        """Whether cause ``a``'s ratio exceeds ``b``'s on the interval (the ratio of ratios > 1)."""
        return bool(self.pair_low[self.names.index(a), self.names.index(b)] > 1)


def _tail_ratio(X: np.ndarray, E: np.ndarray, share: float) -> np.ndarray:
    """``X, E (b, N)`` (NaN in ``X``: no value) → ``(b,)`` median ``E`` of the ``share`` of each
    row's finite ``X`` that is smallest over that of the ``share`` that is largest; NaN for a row
    with no finite ``X`` (a resample that drew no row with a value), without NumPy's warning."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "All-NaN slice", RuntimeWarning)
        lo = np.nanquantile(X, share, axis=1, keepdims=True)
        hi = np.nanquantile(X, 1 - share, axis=1, keepdims=True)
        with np.errstate(invalid="ignore"):
            near = np.nanmedian(np.where(X <= lo, E, np.nan), axis=1)
            far = np.nanmedian(np.where(X >= hi, E, np.nan), axis=1)
    return near / far


def tail_ratio(x, error, share: float = 0.1) -> float:
    """The point value of one cause's ratio (:func:`tail_ratios`, without an interval): the
    median ``error`` of the ``share`` of rows with the smallest ``x`` over that of the ``share``
    with the largest. For rows that are not independent (the samples of a trajectory), where a
    bootstrap over rows would give too narrow an interval.

    Example:
        >>> x = np.linspace(0.0, 1.0, 1000)
        >>> tail_ratio(x, 1 + 4 * (x < 0.1))
        5.0
    """
    return float(_tail_ratio(np.asarray(x, float)[None], np.asarray(error, float)[None], share)[0])


def tail_ratios(causes, error, *, share: float = 0.1, draws: int = 2000, level: float = 0.95,
                seed: int = 0, batch: int = 50) -> TailRatios:
    """How much larger the error is near each candidate cause: for each ``x (N,)`` of
    ``causes`` (a mapping name → distances; NaN where a row has none), the median ``error
    (N,)`` of the ``share`` of the rows with the smallest ``x`` divided by that of the
    ``share`` with the largest, and its percentile-bootstrap interval over the rows (resampled
    with replacement, ``draws`` times from one generator seeded by ``seed``, ``batch`` at a
    time); every cause is computed on the same resamples, so two causes are compared by the
    interval of the ratio of their ratios (:meth:`TailRatios.larger`).

    Example:
        >>> rng = np.random.default_rng(0)
        >>> x = rng.random(2000)
        >>> result = tail_ratios({"near x = 0": x, "unrelated": rng.random(2000)}, 1 + 4 * (x < 0.1), draws=200)
        >>> result.value.round(2).tolist(), result.larger("near x = 0", "unrelated")
        ([5.0, 1.0], True)
    """
    names = tuple(causes)
    if not names:
        raise ValueError("causes must name at least one candidate")
    error = np.asarray(error, float)
    X = np.stack([np.asarray(causes[n], float) for n in names])          # (k, N)
    if error.ndim != 1 or X.shape[1:] != error.shape or len(error) < 2 or not np.isfinite(error).all():
        raise ValueError(f"error must be finite (N >= 2,) and each cause (N,), got {error.shape} and "
                         f"{[np.shape(causes[n]) for n in names]}")
    if not 0 < share < 0.5:
        raise ValueError(f"share must be in (0, 0.5), got {share!r}")
    if not (isinstance(draws, int) and draws >= 100) or not 0 < level < 1:
        raise ValueError(f"draws must be an integer >= 100 and level in (0, 1), got {draws!r}, {level!r}")
    value = _tail_ratio(X, np.broadcast_to(error, X.shape), share)        # (k,), every cause at once
    rng = np.random.default_rng(seed)
    ratios = []
    for start in range(0, draws, batch):
        rows = rng.integers(0, len(error), size=(min(batch, draws - start), len(error)))
        ratios.append(np.stack([_tail_ratio(x[rows], error[rows], share) for x in X], axis=1))
    R = np.concatenate(ratios)                                            # (draws, k)
    tails = (100 * (1 - level) / 2, 100 * (1 + level) / 2)
    low, high = np.nanpercentile(R, tails, axis=0)
    pair_low, pair_high = np.nanpercentile(R[:, :, None] / R[:, None, :], tails, axis=0)
    return TailRatios(names, value, low, high, pair_low, pair_high, level, draws)


def resolved_joints(spread, noise):
    """``(n,)`` bool: the joints whose torque a sensor of the measured arm resolves, i.e. whose
    torque spread (``spread (n,)``, the standard deviation an NRMSE divides by [N·m]) is at
    least the sensor's noise σ (``noise (n,)`` [N·m]; ``None``: no sensor declared, every joint).

    A joint below its noise (the wrist roll of both shipped arms: spread 0.0001–0.0014 N·m
    against σ = 0.005 N·m) has an NRMSE that is a ratio of two numbers no sensor would see; the
    chapters show it but take the **worst joint** — by which ID models are chosen and judged —
    over the resolved joints only. If no joint is resolved, every joint counts (a worst over
    none is undefined).
    """
    spread = np.asarray(spread, float)
    if noise is None:
        return np.ones(spread.shape, bool)
    resolved = spread >= np.asarray(noise, float)
    return resolved if resolved.any() else np.ones(spread.shape, bool)
