"""Paired comparisons (nfarm.study.paired): a method against itself differs by nothing and a worse
one by a positive interval; pairs over the seeds pair seed with seed and stand a method with one
model beside each; a paired difference is read back either way round."""

from __future__ import annotations

import numpy as np
import pytest

from test_rows import ik_errors

from nfarm.study.paired import Paired, ik_difference, paired_difference, pooled_pairs
from nfarm.study.statistics import nrmse_from_sums, trajectory_sums


def test_a_method_against_itself_differs_by_nothing_and_a_worse_one_by_a_positive_interval():
    e = ik_errors()
    same = ik_difference(e, e, draws=300)
    assert np.all(same.value == 0) and np.all(same.low == 0) and np.all(same.high == 0)
    worse = {k: 2 * v for k, v in e.items()}
    diff = ik_difference(worse, e, draws=300)
    assert np.all(diff.low > 0)
    with pytest.raises(ValueError, match="same poses"):
        ik_difference(e, ik_errors(n=400), draws=300)


def test_pooled_pairs_pair_the_seeds_and_stand_a_method_with_one_model_beside_each():
    """Seed s of each method on the same draw; a method with one model (Newton–Euler alone, or one trained once)
    as it is beside each seed's model; a pair of two one-model methods as it was. The difference is the metric
    of one side's pooled rows less the other's."""
    rng = np.random.default_rng(3)
    tau = rng.normal(size=(400, 2))
    label = np.repeat(np.arange(8), 50)
    model = lambda s, scale: trajectory_sums(tau + rng.normal(0, scale * (1 + 0.2 * s), tau.shape), tau, label)  # noqa: E731
    task, metric = "ID, measured arm", "worst joint RMSE"
    values = {(task, "residual"): np.stack([model(s, 0.1) for s in range(5)]),
              (task, "boosting"): np.stack([model(s, 0.3) for s in range(5)]),
              (task, "Newton–Euler alone"): model(0, 1.0)[None],
              (task, "trained once"): model(0, 0.2)[None]}
    pairs = [Paired(task, a, b, metric, "N·m", 9.0, 8.0, 10.0, 300, 0.95, "one seed")
             for a, b in (("residual", "boosting"), ("residual", "Newton–Euler alone"), ("trained once", "Newton–Euler alone"))]
    out = pooled_pairs(pairs, values, draws=300)
    assert out[0].high < 0 and "5 seeds × 8 test trajectories" in out[0].spread          # better on every draw
    worst = lambda v: nrmse_from_sums(v.sum(axis=(0, 1)), normalised=False).max()        # noqa: E731
    np.testing.assert_allclose(out[0].difference, worst(values[task, "residual"]) - worst(values[task, "boosting"]),
                               rtol=1e-12)
    assert out[1].high < 0 and "5 seeds" in out[1].spread                                # one model beside each seed
    np.testing.assert_allclose(out[1].difference, worst(values[task, "residual"]) - worst(values[task, "Newton–Euler alone"]),
                               rtol=1e-12)
    assert out[2] == pairs[2]                                                            # two one-model methods: as it was
    with pytest.raises(ValueError, match="not a metric pooled"):
        pooled_pairs([Paired(task, "residual", "boosting", "mean error", "N·m", 0, 0, 0, 300, 0.95, "")], values,
                     draws=300)
    with pytest.raises(ValueError, match="give resolved"):
        pooled_pairs([Paired(task, "residual", "boosting", "worst NRMSE", "%", 0, 0, 0, 300, 0.95, "")], values,
                     draws=300)


def test_a_paired_difference_is_read_either_way_round_or_refused():
    rows = [{"task": "t", "method": "a", "against": "b", "metric": "m", "difference": "-0.5", "ci_low": "-0.75",
             "ci_high": "-0.25"}]
    assert paired_difference(rows, "t", "a", "b", "m") == (-0.5, -0.75, -0.25)
    assert paired_difference(rows, "t", "b", "a", "m") == (0.5, 0.25, 0.75)
    with pytest.raises(ValueError, match="no paired difference of 'a' against 'c'"):
        paired_difference(rows, "t", "a", "c", "m")
