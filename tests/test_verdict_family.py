"""The verdict as one family of comparisons: the paired gap's bootstrap p-value agrees with its
interval, Holm's adjustment is Holm's procedure, and a difference stands only where both say so."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nfarm.study.statistics import bootstrap_p, bootstrap_seeds, distinct_resamples, holm
from nfarm.publishing.conclusion import conclusion
from nfarm.study.result_tables import read_verdicts
from nfarm.study.verdict_rows import FAMILY_ALPHA, NO_DIFFERENCE, p_text, task_verdict, verdict_table, with_holm


def holm_procedure(p: np.ndarray, alpha: float) -> set[int]:
    """Holm (1979) as he states it: step through the p-values from the least, rejecting the k-th
    (from 1) while it is at most alpha / (m - k + 1); stop at the first that is not."""
    rejected = set()
    for k, i in enumerate(np.argsort(p, kind="stable"), start=1):
        if p[i] > alpha / (len(p) - k + 1):
            break
        rejected.add(int(i))
    return rejected


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(0, 1), min_size=1, max_size=12), st.sampled_from([0.01, 0.05, 0.1]))
def test_holms_adjusted_p_values_reject_what_his_procedure_rejects(p, alpha):
    p = np.array(p)
    adjusted = holm(p)
    assert ((adjusted >= p) & (adjusted <= 1)).all()
    # strict "<" against alpha on the adjusted values is the procedure's "<=" on the raw ones but at ties
    assert {i for i in range(len(p)) if adjusted[i] <= alpha} == holm_procedure(p, alpha)


def test_holm_refuses_what_is_no_p_value():
    with pytest.raises(ValueError, match="p-values must be finite numbers in"):
        holm([0.1, float("nan")])
    with pytest.raises(ValueError, match="p-values must be finite numbers in"):
        holm([1.5])


@pytest.mark.parametrize("shift", [-0.8, -0.05, 0.0, 0.3])
def test_the_bootstrap_p_value_and_the_interval_agree_on_zero(shift):
    """A 95 % percentile interval excludes 0 exactly where p < 0.05 (up to the percentile's
    interpolation between two resamples, which no case here falls in)."""
    rng = np.random.default_rng(7)
    values = rng.normal(shift, 1.0, size=(5, 200, 1)) + rng.normal(0, 0.1, size=(5, 1, 1))
    est = bootstrap_seeds(values, lambda X: X[..., 0].mean(axis=1), draws=2000, seed=3)
    excludes = est.high < 0 or est.low > 0
    assert excludes == (est.p_zero < 0.05), (est.low, est.high, est.p_zero)
    assert 0 <= est.p_zero <= 1


def test_the_p_value_counts_each_side_and_ignores_nan():
    assert bootstrap_p(np.array([-1.0, 1.0])) == 1.0
    assert bootstrap_p(np.array([np.nan, 1.0, 2.0, -1.0, 3.0])) == pytest.approx(0.5)
    assert bootstrap_p(np.zeros(10)) == 1.0                                  # the same model: nothing shown
    assert np.allclose(bootstrap_p(np.array([[1.0, -1.0], [2.0, -2.0]])), [0.0, 0.0])


def test_an_outer_bootstrap_over_five_seeds_has_126_resamples():
    assert [distinct_resamples(n) for n in (1, 2, 3, 5)] == [1, 3, 10, 126]
    # brute force: every multiset of n seeds drawn with replacement
    from itertools import combinations_with_replacement
    assert all(distinct_resamples(n) == sum(1 for _ in combinations_with_replacement(range(n), n)) for n in range(1, 7))


def _verdict(task, gap, p, anfis="ANFIS", rival="R"):
    return task_verdict("arm", task, "m", "mm", {anfis: 1.0, rival: 1.0 + gap[0]}, anfis, gap, p=p, draws=2000)


def test_a_difference_stands_only_where_the_interval_and_holm_both_show_it(tmp_path):
    verdicts = with_holm([_verdict("a", (-1.0, -1.4, -0.6), 0.0, rival="R1"),
                          _verdict("b", (-0.2, -0.39, -0.01), 0.03, rival="R2"),      # 3 · 0.03 > 0.05
                          _verdict("c", (0.5, -0.1, 1.1), 0.4, rival="R3"),
                          _verdict("c, every tier", (-1.0, -1.4, -0.6), 0.0, rival="R1")])   # a's test again
    assert [v.comparisons for v in verdicts] == [3, 3, 3, 3]
    assert [v.verdict for v in verdicts] == ["ANFIS better", f"{NO_DIFFERENCE} (Holm)", NO_DIFFERENCE, "ANFIS better"]
    assert verdicts[1].holm_p == pytest.approx(0.06) and verdicts[1].holm_p >= FAMILY_ALPHA
    verdict_table(verdicts).save(tmp_path, "07_verdict")
    rows = read_verdicts(tmp_path / "tables" / "07_verdict.csv")
    assert [(r["p"], r["holm_p"], r["comparisons"]) for r in rows] == [
        ("< 0.001", "< 0.001", "3"), ("0.03", "0.06", "3"), ("0.4", "0.4", "3"), ("< 0.001", "< 0.001", "3")]
    assert p_text(float("nan"), 2000) == "" and p_text(0.5, 0) == "0.5"


def test_no_method_is_recommended_on_a_tie(tmp_path):
    tie = task_verdict("arm B", "inverse kinematics", "position p95", "mm", {"ANFIS": 1.0, "RBF": 1.1}, "ANFIS",
                       (-0.1, -0.3, 0.1), p=0.4, draws=2000)
    verdict_table(with_holm([tie])).save(tmp_path, "07_verdict")
    said = conclusion(read_verdicts(tmp_path / "tables" / "07_verdict.csv"))
    assert said[-1] == "What to use, by the held-out data: inverse kinematics, ANFIS or RBF (no difference shown)."
    assert not any("ANFIS is better" in s for s in said)
    assert math.isclose(tie.p, 0.4)
