"""The study's long summary (nfarm.study.summary): each row's value is the direct statistic of the
held-out errors, its interval holds it, paired differences vanish for a method against itself,
and the table is one line per task, method and metric."""

from __future__ import annotations

import re

import numpy as np
import pytest

from nfarm.study.statistics import trajectory_maxima, trajectory_sums
from nfarm.study.statistics import bootstrap_nrmse
from nfarm.study.summary import (IK_METRICS, ROLE_BEST_BASELINE, ROLE_CHOSEN, ROLE_RECIPE, ROLES, WORST_ID, Row, paired_difference,
                                 published, rows_from_table, abstract_lines, id_rows, ik_difference, ik_rows, largest_difference,
                           interval_text, long_table, read_long_table, resolved_sums, wide_table, with_resolved_worst)
from nfarm.study.sweep import Cell, CellResult, Replicates



def paired_for(tmp_path, rows, **data):
    """The paired differences the abstract needs for ``rows``, computed from the methods' data
    (``ik_errors``, ``id_sums``, ``measured_sums``), saved and read back as chapter 7 does."""
    from nfarm.study.summary import abstract_pairs, paired_rows, paired_table, read_paired
    paired_table(paired_rows(abstract_pairs(rows), draws=300, **data)).save(tmp_path, "07_paired")
    return read_paired(tmp_path / "tables" / "07_paired.csv")

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


def test_the_abstract_reads_every_number_from_the_summary_table(tmp_path):
    rng = np.random.default_rng(4)
    anfis, base = ik_errors(5), {k: v * 3 for k, v in ik_errors(6).items()}
    base["orientation"] = base["orientation"] / 100          # the baseline wins on orientation
    rows = ik_rows("ANFIS, chosen", ROLE_CHOSEN, anfis, draws=300) + \
        ik_rows("RBF", ROLE_BEST_BASELINE, base, draws=300)
    label = np.repeat(np.arange(10), 20)
    tau = rng.normal(size=(200, 2))
    sums = {}
    for name, role, noise in (("ANFIS, model-free", ROLE_CHOSEN, 0.3), ("ridge", ROLE_BEST_BASELINE, 0.01)):
        predicted = tau + rng.normal(0, noise, size=tau.shape)
        sums[name] = trajectory_sums(predicted, tau, label)
        rows += id_rows(name, role, sums[name], trajectory_maxima(predicted, tau, label), ["a", "b"], draws=300)
    long_table(rows).save(tmp_path, "07_summary")
    table = read_long_table(tmp_path / "tables" / "07_summary.csv")
    paired = paired_for(tmp_path, rows, ik_errors={"ANFIS, chosen": anfis, "RBF": base}, id_sums=sums)
    ik_line, id_line = abstract_lines("arm", table, paired)
    chosen_median = next(r for r in table if r["method"] == "ANFIS, chosen" and r["metric"] == "position median")
    three = lambda text: f"{float(text):.3g}"          # noqa: E731 — the abstract writes three digits, as the chapters
    assert (f"{three(chosen_median['value'])} mm ({three(chosen_median['ci_low'])}–"
            f"{three(chosen_median['ci_high'])}, test poses only)") in ik_line     # one model: its interval's kind said
    assert "is better on orientation median" in ik_line and "(paired intervals)" in ik_line
    assert "The ANFIS is better on worst joint RMSE, position median" in ik_line
    assert "ridge" in id_line and "better than the ANFIS" in id_line
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b\n1,2\n", encoding="utf-8")
    with pytest.raises(ValueError, match="not a summary table"):
        read_long_table(bad)
    with pytest.raises(ValueError, match="no paired difference of 'RBF' against 'ANFIS, chosen' on worst joint RMSE"):
        abstract_lines("arm", table, [])          # a comparison without its paired difference: an error


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


def test_the_abstract_leaves_the_joints_below_noise_out_and_names_them(tmp_path):
    rng = np.random.default_rng(5)
    label = np.repeat(np.arange(10), 20)
    tau = rng.normal(size=(200, 2)) * [1.0, 1e-4]
    predicted = tau + rng.normal(0, [0.02, 1e-4], size=tau.shape)
    rows = id_rows("ANFIS, model-free", ROLE_CHOSEN, trajectory_sums(predicted, tau, label),
                   trajectory_maxima(predicted, tau, label), ["a", "b"], resolved=[True, False], draws=300)
    long_table(rows).save(tmp_path, "07_summary")
    (line,) = abstract_lines("arm", read_long_table(tmp_path / "tables" / "07_summary.csv"), [])
    worst = next(r for r in rows if r.metric == WORST_ID)
    assert f"misses by {worst.value:.3g} %" in line and "τ2, whose torque is below the sensor noise, left out" in line


def test_the_abstract_says_where_the_dissertations_recipe_beats_the_chosen_model(tmp_path):
    """A loss to the recipe is not hidden behind the metric the choice was made on."""
    chosen = ik_errors(7)
    recipe = {k: v.copy() for k, v in ik_errors(8).items()}
    recipe["position"] = recipe["position"] / 10                 # the recipe lands the tool closer
    recipe["joint"] = recipe["joint"] * 10                       # but misses the joints by more
    rows = ik_rows("ANFIS, chosen", ROLE_CHOSEN, chosen, draws=300) + \
        ik_rows("ANFIS, dissertation's recipe, region", ROLE_RECIPE, recipe, draws=300) + \
        ik_rows("ANFIS, dissertation's recipe, full range", ROLE_RECIPE,
                {k: 100 * v for k, v in chosen.items()}, draws=300)         # the first listed is the one compared
    long_table(rows).save(tmp_path, "07_summary")
    paired = paired_for(tmp_path, rows, ik_errors={"ANFIS, chosen": chosen, "ANFIS, dissertation's recipe, region": recipe})
    (line,) = abstract_lines("arm", read_long_table(tmp_path / "tables" / "07_summary.csv"), paired)
    assert "it is better than the chosen model on position median" in line
    assert "worst joint RMSE (" not in line.split("it is better")[1]


def test_a_maximum_is_written_without_an_interval(tmp_path):
    long_table(ik_rows("m", "learned", ik_errors(), draws=300)).save(tmp_path, "07_summary")
    rows = {r["metric"]: r for r in read_long_table(tmp_path / "tables" / "07_summary.csv")}
    assert rows["position max"]["ci_low"] == rows["position max"]["ci_high"] == rows["position max"]["level"] == ""
    assert rows["position median"]["ci_low"] and rows["position median"]["level"] == "0.95"


@pytest.mark.parametrize("low, high, target, expected", [
    (1.0, 2.0, 2.0, "✓"),                                  # the whole interval at the target: met
    (1.0, 2.0, 0.5, "✗"),
    (2.0, 3.0, 2.0, "undecided (the interval spans it)"),   # touching from above is not met
    (1.0, 3.0, 2.0, "undecided (the interval spans it)"),
])
def test_a_target_is_judged_on_the_interval_not_the_point(low, high, target, expected):
    from nfarm.study.summary import Row, target_verdict
    row = Row("inverse kinematics", "m", "chosen", "position p95", "mm", (low + high) / 2, low, high, 2000, 0.95, "")
    assert target_verdict(row, target) == expected


def test_a_joint_below_the_noise_is_shown_without_an_interval():
    from nfarm.study.summary import Row, interval_text
    row = Row("inverse dynamics", "m", "chosen", "τ5 wrist_roll (below noise)", "%", 74.6, 61.6, 89.1, 2000, 0.95, "")
    assert interval_text(row) == "75"
    resolved = Row("inverse dynamics", "m", "chosen", "τ4 wrist_flex", "%", 1.3, 1.13, 1.46, 2000, 0.95, "")
    assert interval_text(resolved) == "1.3 (1.13–1.46)"


def test_the_roles_the_abstract_reads_are_the_roles_the_chapters_write(tmp_path):
    """The abstract finds its rows by whole role labels (ROLES): chapter 7 writes each of them by
    the constant's name (never the label retyped, which a rewording would leave behind), its
    published summaries hold each, and a reworded label is not read as the one it resembles."""
    import json
    from nfarm.infra.paths import ROOT
    from nfarm.study import summary
    names = {value: name for name in summary.__all__ if name.startswith("ROLE_")
             for value in [getattr(summary, name)]}
    assert set(names) == set(ROLES) and len(ROLES) == len(set(ROLES))
    chapter = json.loads((ROOT / "notebooks" / "07_testing_error_analysis.ipynb").read_text(encoding="utf-8"))
    source = "".join(line for cell in chapter["cells"] if cell["cell_type"] == "code" for line in cell["source"])
    # the measured arm's roles are set where chapter 7.6's methods are named (nfarm.study.measured_test)
    source += (ROOT / "lib" / "nfarm" / "study" / "measured_test.py").read_text(encoding="utf-8")
    for role in ROLES:
        assert names[role] in source, f"chapter 7 writes no row of role {role!r}"
        assert f'"{role}"' not in source, f"chapter 7 retypes the role {role!r} instead of {names[role]}"
    for table in (ROOT / "figures" / "tables" / "07_summary.csv", ROOT / "figures" / "so101" / "tables" / "07_summary.csv"):
        assert set(ROLES) <= {r["role"] for r in read_long_table(table)}, table
    rows = ik_rows("ANFIS, chosen", ROLE_CHOSEN, ik_errors(9), draws=300) + \
        ik_rows("RBF", ROLE_BEST_BASELINE + ", reworded", ik_errors(10), draws=300)
    long_table(rows).save(tmp_path, "07_summary")
    table = read_long_table(tmp_path / "tables" / "07_summary.csv")
    (line,) = abstract_lines("arm", table, [])
    assert "RBF" not in line and "best baseline" not in line


def test_the_abstract_says_what_the_measured_arm_gives_each_tier(tmp_path):
    """On the measured arm the abstract names the identification of the built arm against the
    ANFIS residual, and the ANFIS alone against Newton–Euler alone — worse, where it is."""
    from nfarm.study.summary import ROLE_FRICTION_ID, ROLE_LEARNED_ALONE, ROLE_NUMERICAL, ROLE_PHYSICS, ROLE_RESIDUAL_BASELINE
    rng = np.random.default_rng(6)
    label = np.repeat(np.arange(12), 25)
    tau = rng.normal(size=(300, 2))
    task = "ID, measured arm"

    sums = {}

    def rows_of(method, role, error, z=None):
        predicted = tau + error * (rng.standard_normal(tau.shape) if z is None else z)
        sums[method] = trajectory_sums(predicted, tau, label)
        return id_rows(method, role, sums[method], trajectory_maxima(predicted, tau, label),
                       ["a", "b"], normalised=False, task=task, draws=300)

    rows = (rows_of("Newton–Euler alone", ROLE_NUMERICAL, 0.1) + rows_of("NE + friction LS", ROLE_FRICTION_ID, 0.05)
            + rows_of("identification of the built arm", ROLE_PHYSICS, 0.01)
            + rows_of("ANFIS alone", ROLE_LEARNED_ALONE, 0.4))
    z = rng.standard_normal(tau.shape)        # the same errors, 8 % smaller: better on every trajectory, by 1.09 times
    rows += rows_of("NE + ANFIS residual", ROLE_CHOSEN, 0.03, z) + rows_of("NE + boosting residual", ROLE_RESIDUAL_BASELINE, 0.0276, z)
    # The study's ≤ 5 % target on the measured spread: over the resolved joints and over every joint
    target = lambda method, role, metric, v: Row(task, method, role, metric, "%", v, 0.9 * v, 1.1 * v, 300, 0.95, "")  # noqa: E731
    rows += [target("Newton–Euler alone", ROLE_NUMERICAL, "worst NRMSE", 25.0),
             target("NE + friction LS", ROLE_FRICTION_ID, "worst NRMSE", 12.0),
             target("ANFIS alone", ROLE_LEARNED_ALONE, "worst NRMSE", 60.0),
             target("NE + boosting residual", ROLE_RESIDUAL_BASELINE, "worst NRMSE", 4.6),   # reaches 5.06: not met
             target("identification of the built arm", ROLE_PHYSICS, "worst NRMSE", 3.0),
             target("NE + ANFIS residual", ROLE_CHOSEN, "worst NRMSE", 4.7),          # its interval reaches 5.17: not met
             target("identification of the built arm", ROLE_PHYSICS, "worst NRMSE, every joint", 30.0),
             target("NE + ANFIS residual", ROLE_CHOSEN, "worst NRMSE, every joint", 40.0)]
    long_table(rows).save(tmp_path, "07_summary")
    paired = paired_for(tmp_path, rows, measured_sums=sums)
    (line,) = abstract_lines("arm", read_long_table(tmp_path / "tables" / "07_summary.csv"), paired)
    # judged by the target's metric (as the verdict), Newton–Euler alone's N·m beside it
    assert re.search(r"by the worst resolved joint's NRMSE against the measured torques' spread: Newton–Euler alone "
                     r"leaves 25 % \(22\.5–27\.5\) \([^)]*N·m[^)]*\) on its worst joint\)", line), line
    assert "identifying the built arm's masses and drives on the known geometry leaves 3 %" in line
    assert line.split("identifying the built arm")[1].split(";")[0].endswith("better than the ANFIS residual")
    assert "the best ANFIS without the rigid-body model (ANFIS alone) leaves" in line
    assert re.search(r"\(ANFIS alone\) leaves [^;]*?, worse than Newton–Euler alone; ", line), line
    # a rival residual within a few per cent of the ANFIS's: no "leaves about the same as its error" beside a verdict
    assert re.search(r"the best other learner as a residual, NE \+ boosting residual: [^;]*?, better than the ANFIS "
                     r"residual\. ", line), line
    assert "about the same as its error" not in line, line
    assert ("target on the measured spread, over the joints a sensor resolves: met by identification of the built arm."
            in line)
    assert line.endswith("over every joint, the noise-level ones included: met by none (best identification of the "
                         "built arm, 30 % (27–33)).")


# -- the verdict -------------------------------------------------------------------------------


def test_a_verdict_ranks_the_anfis_and_reads_the_paired_interval(tmp_path):
    from nfarm.study.summary import conclusion, read_verdicts, read_warm_starts, targets_met, task_verdict, verdict_table

    ik = task_verdict("arm A", "inverse kinematics", "position p95", "mm", {"ANFIS": 0.9, "RBF": 4.9, "kNN": 31.0}, "ANFIS",
                 (-4.0, -4.2, -3.8), {"ANFIS": "3 of 3", "RBF": "2 of 3"}, exact="the closed form")
    assert (ik.best, ik.rank, ik.compared, ik.rival, ik.rival_value, ik.verdict) == ("ANFIS", 1, 3, "RBF", 4.9, "ANFIS better")
    idv = task_verdict("arm A", "rigid-body inverse dynamics", WORST_ID, "%", {"ANFIS": 2.5, "ridge": 1e-7}, "ANFIS",
                  (2.5, 2.1, 2.9))
    tie = task_verdict("arm B", "measured arm, generic", "worst NRMSE", "%", {"generic: ANFIS": 30.0, "generic: MLP": 28.0},
                       "generic: ANFIS",
                  (2.0, -1.0, 5.0))
    assert (idv.rank, idv.verdict, tie.verdict) == (2, "rival better", "no difference shown")
    with pytest.raises(ValueError, match="must be one of at least two methods compared"):
        task_verdict("arm", "t", "m", "mm", {"ANFIS": 1.0}, "ANFIS", (0, 0, 0))
    verdict_table([ik, idv, tie], floors={"%": 1e-6}).save(tmp_path, "07_verdict")
    rows = read_verdicts(tmp_path / "tables" / "07_verdict.csv")
    assert [r["verdict"] for r in rows] == ["ANFIS better", "rival better", "no difference shown"]
    assert rows[1]["best"] == "ridge" and rows[1]["best_value"] == "< 1e-6"       # noise level, shown as such
    warm = [{"start": "home (the dissertation's)", "targets": "2000", "mean iterations": "5.99", "max iterations": "9"},
            {"start": "ANFIS prediction", "targets": "2000", "mean iterations": "2.07", "max iterations": "3"},
            {"start": "RBF interpolation (contest) prediction", "targets": "2000", "mean iterations": "2.24",
             "max iterations": "4"},
            {"start": "closed form (the region's solution)", "targets": "2000", "mean iterations": "0.00",
             "max iterations": "0"}]
    said = conclusion(rows, {"arm A": warm})
    assert len(said) == 5 and all(s.count(". ") == 0 for s in said), said        # five sentences at most
    assert said[0] == ("ANFIS is better than every other method it was compared with, beyond the paired interval, on "
                       "inverse kinematics (arm A, by 4 mm of position p95).")
    assert said[1] == ("Another method is better than ANFIS, beyond the paired interval, on rigid-body inverse dynamics "
                       f"(arm A: ridge, by 2.5 percentage points of {WORST_ID}); and no difference between ANFIS and its "
                       "best rival is shown (the paired interval, or Holm's correction for the arm's comparisons) on "
                       "measured arm, generic (arm B: MLP, 2 (-1 to 5) percentage points).")    # the tier not repeated
    assert said[2] == ("What the ANFIS gives the exact solver, as measured: started from its prediction, "
                       "Levenberg–Marquardt needs on average 2.07 (at most 3) iterations against 5.99 (at most 9) from "
                       "the home pose and 2.24 (at most 4) from the prediction of RBF interpolation (arm A); from the "
                       "closed form's solution, none; whether such a start saves seconds depends on what the "
                       "prediction costs, which chapter 7 times on the reader's machine."), said[2]
    assert said[3] == ("The study's targets the ANFIS meets on the whole interval: inverse kinematics (arm A) 3 of 3.")
    assert said[4] == ("What to use, by the held-out data: inverse kinematics, the closed form (exact; of the learned "
                       "methods, ANFIS); rigid-body inverse dynamics, ridge.")
    assert conclusion(rows)[2] == said[3]                   # without chapter 7's starts, no such sentence
    (tmp_path / "starts.csv").write_text("start,targets\nhome,10\n")
    with pytest.raises(ValueError, match="starts.csv: not a table of LM's starts: columns mean iterations missing"):
        read_warm_starts(tmp_path / "starts.csv")
    (tmp_path / "bad.csv").write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match="bad.csv: not a verdict table: columns arm, task"):
        read_verdicts(tmp_path / "bad.csv")
    row = Row("t", "m", ROLE_CHOSEN, "position p95", "mm", 4.0, 3.0, 5.0, 100, 0.95, "")
    assert targets_met([row, row], [10.0, 4.5]) == "1 of 2"


def test_the_verdict_is_judged_over_seeds_and_units_and_shown_in_a_readers_words(tmp_path):
    """Two methods whose seeds differ by a constant: the gap's interval is that constant; a method
    whose seeds scatter gets a wider interval than one seed's; the table keeps the configuration,
    the display shows each value with its interval in plain words; a pruned method (one seed) is
    paired on the seed both have."""
    from nfarm.study.summary import (read_verdicts, reader_label, seed_comparison, task_verdict, verdict_display,
                                     verdict_table)

    rng = np.random.default_rng(7)
    base = np.abs(rng.normal(size=(1, 30, 1 + 3 * 2))) + 1.0
    scatter = np.array([1.0, 1.5, 2.0, 2.5, 3.0])[:, None, None]
    a = np.repeat(base, 5, axis=0)
    a[..., 1:3] *= scatter                                   # the ANFIS's squared errors vary by seed
    b = a.copy()
    b[..., 1:3] *= 4.0                                       # the rival's: four times each seed's, RMSE twice
    est, gap = seed_comparison({"ANFIS (affine)": a, "ridge (basis=chain, alpha=1e-06)": b}, "ANFIS (affine)",
                               "ridge (basis=chain, alpha=1e-06)", WORST_ID, normalised=False, draws=300)
    assert gap.high < 0 and est["ANFIS (affine)"].seeds == 5 and gap.seeds == 5
    one = seed_comparison({"x": a[:1], "y": b}, "x", "y", WORST_ID, normalised=False, draws=300)
    assert one[1].seeds == 1 and one[0]["x"].seeds == 1
    assert est["ANFIS (affine)"].high - est["ANFIS (affine)"].low > 2 * (one[0]["x"].high - one[0]["x"].low)
    with pytest.raises(ValueError, match="the same test units"):
        seed_comparison({"x": a, "y": b[:, :10]}, "x", "y", WORST_ID, normalised=False, draws=300)
    v = task_verdict("arm", "rigid-body inverse dynamics", WORST_ID, "N·m", {n: e.value for n, e in est.items()},
                     "ANFIS (affine)", (gap.value, gap.low, gap.high),
                     intervals={n: (e.low, e.high) for n, e in est.items()}, interval="two-level, 5 seeds × 30")
    verdict_table([v]).save(tmp_path, "07_verdict")
    rows = read_verdicts(tmp_path / "tables" / "07_verdict.csv")
    assert rows[0]["rival"] == "ridge (basis=chain, alpha=1e-06)" and rows[0]["interval"] == "two-level, 5 seeds × 30"
    shown_ = verdict_display(rows)[0]
    assert shown_[3].startswith(f"ANFIS, {rows[0]['anfis_value']} ({rows[0]['anfis_low']}–{rows[0]['anfis_high']}) N·m")
    assert shown_[4].startswith("ridge regression on the chain's trigonometric basis, ")
    exact = {**rows[0], "rival_value": "< 1e-6", "rival_low": "< 1e-6", "rival_high": "< 1e-6"}
    assert verdict_display([exact])[0][4] == "ridge regression on the chain's trigonometric basis, < 1e-6 N·m"
    assert reader_label("ANFIS, dissertation's design (own, assumed)") == "ANFIS, dissertation's design (own, assumed)"
    assert reader_label("ANFIS, structure-informed (affine)") == "ANFIS, structure-informed"


def test_the_abstract_judges_on_the_paired_interval_where_the_unpaired_ones_overlap(tmp_path):
    """Two methods whose errors share most of their variation (the same hard poses): their
    intervals overlap, but every resample of the same poses puts one below the other — the
    abstract says so, as the paired interval does."""
    shared = ik_errors(12)
    better = {k: v * 0.97 for k, v in shared.items()}           # 3 % better on every pose
    rows = ik_rows("ANFIS, chosen", ROLE_CHOSEN, better, draws=300) + ik_rows("RBF", ROLE_BEST_BASELINE, shared, draws=300)
    get = {(r.method, r.metric): r for r in rows}
    a, b = get["ANFIS, chosen", "position median"], get["RBF", "position median"]
    assert a.high > b.low                                       # unpaired: the intervals overlap
    long_table(rows).save(tmp_path, "07_summary")
    paired = paired_for(tmp_path, rows, ik_errors={"ANFIS, chosen": better, "RBF": shared})
    (line,) = abstract_lines("arm", read_long_table(tmp_path / "tables" / "07_summary.csv"), paired)
    assert "The ANFIS is better on worst joint RMSE, position median, position p95" in line
    row = next(p for p in paired if p["metric"] == "position median")          # RBF less the ANFIS
    assert (row["method"], row["against"]) == ("RBF", "ANFIS, chosen")
    assert float(row["ci_low"]) > 0 and row["spread"] == "paired bootstrap over 500 test poses"


def test_pooled_rows_pool_a_method_over_its_seeds_and_keep_a_method_trained_once():
    """The value is the metric of every seed's errors pooled; its two-level interval is wider than the
    one-level interval of one seed when the seeds differ; a method with one model, and a maximum, stay."""
    from nfarm.study.summary import ik_seed_values, pooled_rows
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
    from nfarm.study.summary import pooled_rows
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
    from nfarm.study.statistics import nrmse_from_sums
    direct = 100 * nrmse_from_sums(total)
    np.testing.assert_allclose([pooled[f"τ{j + 1} NRMSE"].value for j in range(2)], direct[:2], rtol=1e-12)
    np.testing.assert_allclose(pooled[WORST_ID].value, direct[:2].max(), rtol=1e-12)
    assert pooled["τ3 NRMSE (below noise)"].spread.startswith("two-level") and pooled["largest error"].n == 0
    np.testing.assert_allclose(pooled["τ3 NRMSE (below noise)"].value, direct[2], rtol=1e-12)


def test_pooled_pairs_pair_the_seeds_and_stand_a_method_with_one_model_beside_each():
    """Seed s of each method on the same draw; a method with one model (Newton–Euler alone, or one trained once)
    as it is beside each seed's model; a pair of two one-model methods as it was. The difference is the metric
    of one side's pooled rows less the other's."""
    from nfarm.study.statistics import nrmse_from_sums
    from nfarm.study.summary import Paired, pooled_pairs
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


def test_the_abstract_reads_the_rows_pooled_over_the_seeds_and_says_each_interval_s_kind(tmp_path):
    """The index and the PDF state chapter 7's published summary (07_summary, 07_paired): rows pooled over the
    seeds are stated as such; an interval over the test units alone (a method trained once, or an older chapter 7's
    table of the chapter's seed) is marked "test poses only"."""
    from nfarm.publishing import report
    from nfarm.publishing.abstract import abstract_answers
    from nfarm.study.summary import (abstract_pairs, ik_seed_values, paired_rows, paired_table, pooled_pairs, pooled_rows,
                                     read_paired)

    seeds = [ik_errors(s) for s in range(3)]
    for s, e in enumerate(seeds):
        e["position"] = e["position"] * (1 + 2 * s)
    rival = [ik_errors(10 + s) for s in range(3)]
    rows = ik_rows("ANFIS, chosen", ROLE_CHOSEN, seeds[0], draws=300) + ik_rows("RBF", ROLE_BEST_BASELINE, rival[0], draws=300)
    paired = paired_rows(abstract_pairs(rows), ik_errors={"ANFIS, chosen": seeds[0], "RBF": rival[0]}, draws=300)
    long_table(rows).save(tmp_path, "07_summary")
    paired_table(paired).save(tmp_path, "07_paired")
    arms = [report.Edition("arm", "sa.yaml", "ra.yaml", True)]
    (seed_0,) = abstract_answers(tmp_path, arms)
    values = {("inverse kinematics", "ANFIS, chosen"): ik_seed_values(seeds), ("inverse kinematics", "RBF"): ik_seed_values(rival)}
    pooled = published(pooled_rows(rows, values, draws=300))
    long_table(pooled).save(tmp_path, "07_summary")
    paired_table(pooled_pairs(paired, values, draws=300)).save(tmp_path, "07_paired")
    (line,) = abstract_lines("arm", read_long_table(tmp_path / "tables" / "07_summary.csv"),
                             read_paired(tmp_path / "tables" / "07_paired.csv"))
    assert abstract_answers(tmp_path, arms) == [line] and line != seed_0
    p95 = next(r for r in pooled if r.method == "ANFIS, chosen" and r.metric == "position p95")
    assert f"{interval_text(p95)}".split(" (")[0] + " mm" in line and f"{p95.value:.3g} mm" not in seed_0
    assert "test poses only" in seed_0 and "test poses only" not in line, "each interval's kind said beside it"


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


def test_a_paired_difference_is_read_either_way_round_or_refused():
    rows = [{"task": "t", "method": "a", "against": "b", "metric": "m", "difference": "-0.5", "ci_low": "-0.75",
             "ci_high": "-0.25"}]
    assert paired_difference(rows, "t", "a", "b", "m") == (-0.5, -0.75, -0.25)
    assert paired_difference(rows, "t", "b", "a", "m") == (0.5, 0.25, 0.75)
    with pytest.raises(ValueError, match="no paired difference of 'a' against 'c'"):
        paired_difference(rows, "t", "a", "c", "m")


def test_the_abstract_names_methods_in_words_a_reader_knows(tmp_path):
    """Internal configurations stay in the tables: the abstract says "ANFIS in the arm's plane", not
    "ANFIS, chosen (arm_plane)"; "RBF interpolation", not "RBF interpolation (contest)"."""
    anfis, rival = ik_errors(1), {k: 2 * v for k, v in ik_errors(2).items()}
    rows = ik_rows("ANFIS, chosen (arm_plane)", ROLE_CHOSEN, anfis, draws=300) + \
        ik_rows("RBF interpolation (contest)", ROLE_BEST_BASELINE, rival, draws=300)
    paired = paired_for(tmp_path, rows, ik_errors={"ANFIS, chosen (arm_plane)": anfis, "RBF interpolation (contest)": rival})
    long_table(rows).save(tmp_path, "07_summary")
    (line,) = abstract_lines("arm", read_long_table(tmp_path / "tables" / "07_summary.csv"), paired)
    assert "the chosen model, ANFIS in the arm's plane, misses" in line and "RBF interpolation, is better" in line
    assert "arm_plane" not in line and "(contest)" not in line
