"""The study's rows (nfarm.study.rows): each row's value is the direct statistic of the held-out
errors, its interval holds it, the worst joint is taken over the joints a sensor resolves, rows
pool a method over its seeds, and the long table is one line per task, method and metric."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm.study.paired import largest_difference
from nfarm.study.result_tables import read_long_table
from nfarm.study.rows import (IK_METRICS, ROLE_BEST_BASELINE, ROLE_CHOSEN, WORST_ID, Row, id_rows, ik_rows, ik_seed_values,
                              interval_text, long_table, pooled_rows, published, resolved_sums, rows_from_table, wide_table,
                              with_resolved_worst)
from nfarm.study.statistics import bootstrap_nrmse, nrmse_from_sums, trajectory_maxima, trajectory_sums
from nfarm.study.sweep import Cell, CellResult, Replicates


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
    assert all(r.low <= r.value <= r.high and "500 test poses" in r.spread for r in rows)
    # A maximum's percentile interval ends at the maximum itself: shown without one.
    maxima = [r for r in rows if r.metric.endswith(" max")]
    assert len(maxima) == 2 and all(r.low == r.value == r.high and r.n == 0 and "no interval" in r.spread for r in maxima)
    assert all(r.n == 300 and r.low < r.high for r in rows if r not in maxima)
    assert [r.metric for r in ik_rows("lm", "reference", e, joint=False, draws=300)] == [m for m, _ in IK_METRICS[1:]]


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
    assert rows[4].high == rows[4].value == rows[4].low and rows[4].n == 0 and "no interval" in rows[4].spread
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


def test_the_worst_joint_is_taken_over_the_joints_a_sensor_resolves():
    rng = np.random.default_rng(3)
    label = np.repeat(np.arange(12), 30)
    tau = rng.normal(size=(len(label), 3)) * [1.0, 1.0, 1e-4]        # the third joint's torque: below any noise
    predicted = tau + rng.normal(0, [0.05, 0.1, 1e-4], size=tau.shape)   # its NRMSE about 100 %: the worst
    sums, maxima = trajectory_sums(predicted, tau, label), trajectory_maxima(predicted, tau, label)
    resolved = np.array([True, True, False])
    rows = id_rows("m", "learned", sums, maxima, ["a", "b", "c"], resolved=resolved, draws=300)
    assert [r.metric for r in rows] == ["τ1 NRMSE", "τ2 NRMSE", "τ3 NRMSE (below noise)", WORST_ID, "largest error"]
    nrmse = 100 * np.sqrt(((predicted - tau) ** 2).mean(axis=0)) / tau.std(axis=0)
    assert nrmse.argmax() == 2 and rows[3].value == pytest.approx(nrmse[:2].max())
    # The interval is over the same resamples as the whole set's, of the two joints' worst
    sub = bootstrap_nrmse(sums[:, [0, 1, 2, 4, 5, 7, 8]], draws=300)
    assert (rows[3].low, rows[3].high) == pytest.approx((100 * sub.worst_low, 100 * sub.worst_high))
    np.testing.assert_array_equal(resolved_sums(sums, resolved), sums[:, [0, 1, 2, 4, 5, 7, 8]])
    with pytest.raises(ValueError, match="at least one"):
        resolved_sums(sums, [False, False, False])
    with pytest.raises(ValueError, match="at least one"):
        resolved_sums(sums, [True, False])


def test_configurations_are_chosen_by_their_resolved_joints_and_the_cells_are_left_as_they_were():
    def group(*per_seed):
        return Replicates(tuple(CellResult(Cell({"inputs": "x", "seed": k}, f"cell{k}"), "ok",
                                           {"val_nrmse": list(v), "worst_nrmse": max(v)}, 1.0, "w")
                                for k, v in enumerate(per_seed)))
    a = group([0.02, 0.01, 0.7], [0.03, 0.02, 0.8])           # good on the resolved joints, bad on the third
    b = group([0.30, 0.20, 0.5], [0.35, 0.25, 0.6])
    assert a.metrics["worst_nrmse"] > b.metrics["worst_nrmse"]          # every joint: b looks better
    ra, rb = with_resolved_worst([a, b], [True, True, False], "val_nrmse")
    assert ra.metrics["worst_nrmse"] == pytest.approx(0.025) and rb.metrics["worst_nrmse"] == pytest.approx(0.325)
    assert ra.low("worst_nrmse") == 0.02 and ra.high("worst_nrmse") == 0.03
    assert ra.metrics["worst_nrmse_all"] == pytest.approx(0.75)
    assert a.runs[0].metrics["worst_nrmse"] == 0.7                    # the cells' own results untouched
    with pytest.raises(ValueError, match="3 joints, resolved 2"):
        with_resolved_worst([a], [True, False], "val_nrmse")


def test_a_maximum_is_written_without_an_interval(tmp_path):
    long_table(ik_rows("m", "learned", ik_errors(), draws=300)).save(tmp_path, "07_summary")
    rows = {r["metric"]: r for r in read_long_table(tmp_path / "tables" / "07_summary.csv")}
    assert rows["position max"]["ci_low"] == rows["position max"]["ci_high"] == rows["position max"]["level"] == ""
    assert rows["position median"]["ci_low"] and rows["position median"]["level"] == "0.95"


def test_a_joint_below_the_noise_is_shown_without_an_interval():
    row = Row("inverse dynamics", "m", "chosen", "τ5 wrist_roll (below noise)", "%", 74.6, 61.6, 89.1, 2000, 0.95, "")
    assert interval_text(row) == "75"
    resolved = Row("inverse dynamics", "m", "chosen", "τ4 wrist_flex", "%", 1.3, 1.13, 1.46, 2000, 0.95, "")
    assert interval_text(resolved) == "1.3 (1.13–1.46)"


def test_pooled_rows_pool_a_method_over_its_seeds_and_keep_a_method_trained_once():
    """The value is the metric of every seed's errors pooled; its two-level interval is wider than the
    one-level interval of one seed when the seeds differ; a method with one model, and a maximum, stay."""
    seeds = [ik_errors(s) for s in range(4)]
    for s, e in enumerate(seeds):
        e["position"] = e["position"] * (1 + s)                  # the seeds' models differ
    rows = ik_rows("ANFIS", ROLE_CHOSEN, seeds[0], draws=300) + ik_rows("RBF", ROLE_BEST_BASELINE, ik_errors(9), draws=300)
    values = {("inverse kinematics", "ANFIS"): ik_seed_values(seeds),
              ("inverse kinematics", "RBF"): ik_seed_values([ik_errors(9)])}
    pooled = {(r.method, r.metric): r for r in pooled_rows(rows, values, draws=300)}
    before = {(r.method, r.metric): r for r in rows}
    every = 1e3 * np.concatenate([e["position"] for e in seeds])
    p95 = pooled["ANFIS", "position p95"]
    np.testing.assert_allclose(p95.value, np.percentile(every, 95), rtol=1e-12)
    assert p95.low <= p95.value <= p95.high and "4 seeds × 500 test poses" in p95.spread
    assert p95.high - p95.low > before["ANFIS", "position p95"].high - before["ANFIS", "position p95"].low
    assert pooled["ANFIS", "position max"] == before["ANFIS", "position max"]        # a maximum: as it was
    assert all(pooled["RBF", m] == before["RBF", m] for m, _ in IK_METRICS)           # one model: as it was


def test_pooled_rows_pool_the_id_metrics_over_the_resolved_joints():
    rng = np.random.default_rng(2)
    tau = rng.normal(size=(600, 3)) * [1.0, 2.0, 1e-4]
    label = np.repeat(np.arange(12), 50)
    sums = np.stack([trajectory_sums(tau + rng.normal(0, 0.1 * (1 + s), tau.shape), tau, label) for s in range(3)])
    resolved = np.array([True, True, False])
    rows = id_rows("ANFIS", ROLE_CHOSEN, sums[0], trajectory_maxima(tau, tau, label), ["a", "b", "c"],
                   resolved=resolved, draws=300)
    pooled = {r.metric: r for r in pooled_rows(rows, {("inverse dynamics", "ANFIS"): sums},
                                               resolved={"inverse dynamics": resolved}, draws=300)}
    total = sums.sum(axis=(0, 1))
    direct = 100 * nrmse_from_sums(total)
    np.testing.assert_allclose([pooled[f"τ{j + 1} NRMSE"].value for j in range(2)], direct[:2], rtol=1e-12)
    np.testing.assert_allclose(pooled[WORST_ID].value, direct[:2].max(), rtol=1e-12)
    assert pooled["τ3 NRMSE (below noise)"].spread.startswith("two-level") and pooled["largest error"].n == 0
    np.testing.assert_allclose(pooled["τ3 NRMSE (below noise)"].value, direct[2], rtol=1e-12)


@pytest.mark.parametrize("value", [1.23451, 0.0009995, 99.95, 14123.4, 2.5e-7])
def test_a_published_row_reads_back_as_the_chapter_showed_it(tmp_path, value):
    """One source: a row a chapter shows (rounded once to the long table's precision, `published`) is what a page
    reading the published table shows (`rows_from_table`) — no double rounding (1.23451: "1.23" from the value,
    "1.24" from the "1.235" written), a value below its floor still written as such."""
    row = Row("inverse kinematics", "m", ROLE_CHOSEN, "position p95", "mm", value, 0.9 * value, 1.1 * value, 300, 0.95, "s")
    floors = {"mm": 1e-6}
    (shown_row,) = published([row])
    long_table([shown_row], floors=floors).save(tmp_path, "t")
    (read,) = rows_from_table(read_long_table(tmp_path / "tables" / "t.csv"))
    assert interval_text(read, floors) == interval_text(shown_row, floors)
    if value == 1.23451:
        assert interval_text(row, floors).startswith("1.23 ") and interval_text(shown_row, floors).startswith("1.24 ")
