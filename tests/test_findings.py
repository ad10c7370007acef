"""nfarm.publishing.findings: the study's findings in words, read back from the published tables."""

from __future__ import annotations

import pytest

from nfarm.publishing.findings import PublishedResults
from nfarm.study.paired import Paired, paired_table
from nfarm.study.rows import Row, long_table

IK = "inverse kinematics"


def _row(method, metric, unit, value, width=0.1):
    return Row(IK, method, "", metric, unit, value, value - width, value + width, 200, 0.95, "poses")


def _results(tmp_path, rows, pairs):
    long_table(rows).save(tmp_path, "07_summary")
    paired_table(pairs).save(tmp_path, "07_paired")
    return PublishedResults(tmp_path / "tables")


def _pair(method, against, metric, unit, difference, low, high):
    return Paired(IK, method, against, metric, unit, difference, low, high, 200, 0.95, "poses")


@pytest.mark.parametrize("low, high, words", [(-0.8, -0.6, "better than the rival by 0.7 mm (paired interval 0.6 to 0.8)"),
                                              (0.6, 0.8, "worse than the rival by 0.7 mm (paired interval 0.6 to 0.8)"),
                                              (-0.2, 1.6, "not shown to differ from the rival (paired interval of the "
                                                          "difference -0.2 to 1.6 mm)")])
def test_gap_said_follows_the_side_of_zero_the_paired_interval_lies_on(tmp_path, low, high, words):
    d = -0.7 if high < 0 else 0.7
    results = _results(tmp_path, [_row("A", "position p95", "mm", 1.0), _row("B", "position p95", "mm", 1.7)],
                       [_pair("A", "B", "position p95", "mm", d, low, high)])
    assert results.gap_said("A", "B", "position p95", IK, "the rival") == words
    assert results.order("A", "B", "position p95") == (-1 if high < 0 else 1 if low > 0 else 0)


def test_sides_claim_no_orientation_where_a_structure_sets_it(tmp_path):
    rows = [_row("A", "position p95", "mm", 0.6), _row("B", "position p95", "mm", 1.3),
            _row("A", "orientation p95", "deg", 9e-6, 1e-6), _row("B", "orientation p95", "deg", 0.02, 0.005)]
    pairs = [_pair("A", "B", "position p95", "mm", -0.7, -0.8, -0.6),
             _pair("A", "B", "orientation p95", "deg", -0.02, -0.025, -0.015)]
    text = _results(tmp_path, rows, pairs).sides("A", "B", "the ANFIS", "the rival")
    assert text.startswith("the ANFIS is better on position p95 (0.6 (0.5–0.7) mm against 1.3 (1.2–1.4) mm)")
    assert "orientation p95 (" not in text and text.endswith("orientation not compared: a structure, not a learner, sets it")


def test_sides_name_a_metric_where_the_other_is_better(tmp_path):
    rows = [_row("A", "position p95", "mm", 1.6), _row("B", "position p95", "mm", 1.0),
            _row("A", "orientation p95", "deg", 0.05, 0.01), _row("B", "orientation p95", "deg", 0.05, 0.01)]
    pairs = [_pair("A", "B", "position p95", "mm", 0.6, 0.5, 0.7), _pair("A", "B", "orientation p95", "deg", 0, -0.01, 0.01)]
    text = _results(tmp_path, rows, pairs).sides("A", "B", "the ANFIS", "the rival")
    assert "**the rival is better** on position p95" in text and "no difference shown on orientation p95" in text


def _verdict_row(gap, low, high, verdict, value=(1.0, 0.9, 1.1), rival=(2.0, 1.8, 2.2)):
    return {"gap": gap, "gap_low": low, "gap_high": high, "verdict": verdict,
            **{f"anfis_{k}": str(v) for k, v in zip(("value", "low", "high"), value)},
            **{f"rival_{k}": str(v) for k, v in zip(("value", "low", "high"), rival)}}


@pytest.mark.parametrize("shifted, same", [(("-1.1", "-1.4", "-0.8", "ANFIS better"), True),
                                           (("-0.2", "-0.9", "0.5", "no difference shown"), False)])
def test_shifted_in_words_reads_both_rows_and_says_where_the_intervals_lie(shifted, same):
    from nfarm.publishing.findings import shifted_in_words
    main = _verdict_row("-1", "-1.2", "-0.8", "ANFIS better (Holm)")
    text = shifted_in_words(_verdict_row(*shifted), main, rival="kernel ridge", described="targets beyond the box")
    assert "targets beyond the box" in text and "1.0 mm (0.9–1.1)" in text and "kernel ridge, 2.0 mm (1.8–2.2)" in text
    assert f"**{shifted[3]}**, against -1 mm (-1.2 to -0.8), ANFIS better (Holm)" in text
    assert ("the paired interval lies on the same side of 0 on both." in text) == same
    assert ("on the shifted population the paired interval holds 0, on the test split it excludes 0" in text) == (not same)
    assert text.endswith("the shifted one is a single comparison.)")


def test_shifted_id_in_words_reads_each_pair_and_the_family_size():
    from nfarm.publishing.findings import shifted_id_in_words
    row = lambda task, gap, low, high, verdict, n="": {**_verdict_row(gap, low, high, verdict), "task": task,   # noqa: E731
                                                      "anfis": "ANFIS, affine", "rival": "ridge", "comparisons": n}
    pairs = [(row("rigid-body inverse dynamics, shifted population", "0.5", "0.2", "0.9", "rival better", "3"),
              row("rigid-body inverse dynamics", "0.3", "0.1", "0.4", "rival better (Holm)")),
             (row("measured arm, every tier, shifted population", "0.1", "-0.2", "0.4", "no difference shown", "3"),
              row("measured arm, every tier", "-1", "-1.5", "-0.5", "ANFIS better (Holm)"))]
    text = shifted_id_in_words(pairs, described="40 trajectories run 1.5 times as fast")
    assert text.startswith("**Faster trajectories.**") and "40 trajectories run 1.5 times as fast" in text
    assert "rigid-body inverse dynamics: ANFIS, affine 1.0 % (0.9–1.1), ridge 2.0 % (1.8–2.2)" in text
    assert "the gap 0.5 (0.2 to 0.9) points: **rival better**, against 0.3 (0.1 to 0.4)" in text
    assert "the paired interval on the same side of 0 on both" in text
    assert "**the paired interval holds 0 on the shifted trajectories, on the test split it excludes 0**" in text
    assert text.endswith("the shifted ones over their own 3.)")
    assert shifted_id_in_words([], described="x") == ""


def test_joint_groups_in_words_says_what_the_verdict_judges():
    from nfarm.publishing.findings import joint_groups_in_words
    both = joint_groups_in_words({"rigid-dominated": [False, True, True], "friction-dominated": [True, False, False]},
                                 ["yaw", "shoulder", "elbow"], "arm")
    assert "on shoulder, elbow (rigid-dominated)" in both and "exceeds it on yaw (friction-dominated)" in both
    only = joint_groups_in_words({"rigid-dominated": [False, False], "friction-dominated": [True, True]}, ["a", "b"], "s")
    assert "on every joint (a, b)" in only and "not what it learned of the rigid body's dynamics" in only
