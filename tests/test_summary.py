"""The study's long summary (nfarm.summary): each row's value is the direct statistic of the
held-out errors, its interval holds it, paired differences vanish for a method against itself,
and the table is one line per task, method and metric."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm.statistics import trajectory_maxima, trajectory_sums
from nfarm.summary import (IK_METRICS, abstract_lines, id_rows, ik_difference, ik_rows, largest_difference, long_table,
                           read_long_table,
                           wide_table)


def ik_errors(seed=0, n=500, joints=5):
    rng = np.random.default_rng(seed)
    return {"joint": rng.normal(0, 0.01, (n, joints)), "position": rng.exponential(1e-3, n),
            "orientation": rng.exponential(1e-3, n)}


def test_ik_rows_are_the_direct_statistics_with_intervals_that_hold_them():
    e = ik_errors()
    rows = ik_rows("m", "learned", e, draws=300)
    assert [r.metric for r in rows] == [m for m, _ in IK_METRICS]
    direct = [np.degrees(np.sqrt((e["joint"] ** 2).mean(axis=0))).max(),
              1e3 * np.median(e["position"]), 1e3 * np.percentile(e["position"], 95), 1e3 * e["position"].max(),
              np.degrees(np.median(e["orientation"])), np.degrees(np.percentile(e["orientation"], 95)),
              np.degrees(e["orientation"].max())]
    np.testing.assert_allclose([r.value for r in rows], direct, rtol=1e-12)
    assert all(r.low <= r.value <= r.high and r.n == 300 and "500 test poses" in r.spread for r in rows)
    assert [r.metric for r in ik_rows("lm", "reference", e, joint=False, draws=300)] == [m for m, _ in IK_METRICS[1:]]


def test_a_method_against_itself_differs_by_nothing_and_a_worse_one_by_a_positive_interval():
    e = ik_errors()
    same = ik_difference(e, e, draws=300)
    assert np.all(same.value == 0) and np.all(same.low == 0) and np.all(same.high == 0)
    worse = {k: 2 * v for k, v in e.items()}
    diff = ik_difference(worse, e, draws=300)
    assert np.all(diff.low > 0)
    with pytest.raises(ValueError, match="same poses"):
        ik_difference(e, ik_errors(n=400), draws=300)


def test_id_rows_give_each_joint_the_worst_and_the_largest_error():
    rng = np.random.default_rng(1)
    label = np.repeat(np.arange(12), 30)
    tau = rng.normal(size=(len(label), 3))
    predicted = tau + rng.normal(0, 0.1, size=tau.shape)
    sums, maxima = trajectory_sums(predicted, tau, label), trajectory_maxima(predicted, tau, label)
    rows = id_rows("m", "learned", sums, maxima, ["a", "b", "c"], draws=300)
    assert [r.metric for r in rows] == ["τ1 NRMSE", "τ2 NRMSE", "τ3 NRMSE", "worst joint NRMSE", "largest error"]
    nrmse = 100 * np.sqrt(((predicted - tau) ** 2).mean(axis=0)) / tau.std(axis=0)
    np.testing.assert_allclose([r.value for r in rows[:3]], nrmse, rtol=1e-10)
    assert rows[3].value == pytest.approx(nrmse.max()) and rows[4].value == np.abs(predicted - tau).max()
    assert rows[4].high == rows[4].value and rows[4].low <= rows[4].value
    raw = id_rows("m", "learned", sums, maxima, ["a", "b", "c"], normalised=False, draws=300)
    assert raw[0].unit == "N·m" and raw[3].metric == "worst joint RMSE"
    assert largest_difference(maxima, maxima, draws=300).value == 0
    with pytest.raises(ValueError, match="maxima must be"):
        id_rows("m", "learned", sums, maxima[:, :2], ["a", "b", "c"], draws=300)


def test_the_long_table_has_one_line_per_task_method_and_metric():
    e = ik_errors()
    rows = ik_rows("a", "learned", e, draws=300) + ik_rows("b", "baseline", ik_errors(2), draws=300)
    table = long_table(rows, floors={"mm": 1e-6})
    lines = table.to_csv().splitlines()
    assert lines[0] == "task,method,role,metric,unit,value,ci_low,ci_high,n,level,spread"
    assert len(lines) == 1 + 2 * len(IK_METRICS)
    wide = wide_table(rows, "inverse kinematics")
    assert len(wide.rows) == 2 and len(wide.columns) == 2 + len(IK_METRICS)


def test_the_abstract_reads_every_number_from_the_summary_table(tmp_path):
    rng = np.random.default_rng(4)
    anfis, base = ik_errors(5), {k: v * 3 for k, v in ik_errors(6).items()}
    base["orientation"] = base["orientation"] / 100          # the baseline wins on orientation
    rows = ik_rows("ANFIS, chosen", "learned (chosen)", anfis, draws=300) + \
        ik_rows("RBF", "best baseline (on validation)", base, draws=300)
    label = np.repeat(np.arange(10), 20)
    tau = rng.normal(size=(200, 2))
    for name, role, noise in (("ANFIS, model-free", "learned (chosen)", 0.3), ("ridge", "best baseline (on validation)", 0.01)):
        predicted = tau + rng.normal(0, noise, size=tau.shape)
        rows += id_rows(name, role, trajectory_sums(predicted, tau, label), trajectory_maxima(predicted, tau, label),
                        ["a", "b"], draws=300)
    long_table(rows).save(tmp_path, "07_summary")
    table = read_long_table(tmp_path / "tables" / "07_summary.csv")
    ik_line, id_line = abstract_lines("arm", table)
    chosen_median = next(r for r in table if r["method"] == "ANFIS, chosen" and r["metric"] == "position median")
    assert f"{chosen_median['value']} mm ({chosen_median['ci_low']}–{chosen_median['ci_high']})" in ik_line
    assert "is better beyond both intervals on orientation median" in ik_line
    assert "The ANFIS is better on worst joint RMSE, position median" in ik_line
    assert "ridge" in id_line and "better than the ANFIS" in id_line
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b\n1,2\n", encoding="utf-8")
    with pytest.raises(ValueError, match="not a summary table"):
        read_long_table(bad)
