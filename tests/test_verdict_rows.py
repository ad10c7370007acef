"""The study's targets and verdict (nfarm.study.verdict_rows): a target is met on the whole
interval; a verdict ranks the ANFIS among the methods compared and reads the paired interval, and
the verdict table reads back as it was written."""

from __future__ import annotations

import pytest

from nfarm.study.result_tables import read_verdicts
from nfarm.study.rows import ROLE_CHOSEN, WORST_ID, Row
from nfarm.study.verdict_rows import target_verdict, targets_met, task_verdict, verdict_table


def published_verdicts(tmp_path):
    """Three verdicts (an ANFIS win, a loss and a tie, on two arms), written as chapter 7 writes
    them and read back: ``(verdicts, rows)``."""
    ik = task_verdict("arm A", "inverse kinematics", "position p95", "mm", {"ANFIS": 0.9, "RBF": 4.9, "kNN": 31.0}, "ANFIS",
                 (-4.0, -4.2, -3.8), {"ANFIS": "3 of 3", "RBF": "2 of 3"}, exact="the closed form")
    idv = task_verdict("arm A", "rigid-body inverse dynamics", WORST_ID, "%", {"ANFIS": 2.5, "ridge": 1e-7}, "ANFIS",
                  (2.5, 2.1, 2.9))
    tie = task_verdict("arm B", "measured arm, generic", "worst NRMSE", "%", {"generic: ANFIS": 30.0, "generic: MLP": 28.0},
                       "generic: ANFIS",
                  (2.0, -1.0, 5.0))
    verdict_table([ik, idv, tie], floors={"%": 1e-6}).save(tmp_path, "07_verdict")
    return (ik, idv, tie), read_verdicts(tmp_path / "tables" / "07_verdict.csv")


@pytest.mark.parametrize("low, high, target, expected", [
    (1.0, 2.0, 2.0, "✓"),                                  # the whole interval at the target: met
    (1.0, 2.0, 0.5, "✗"),
    (2.0, 3.0, 2.0, "undecided (the interval spans it)"),   # touching from above is not met
    (1.0, 3.0, 2.0, "undecided (the interval spans it)"),
])
def test_a_target_is_judged_on_the_interval_not_the_point(low, high, target, expected):
    row = Row("inverse kinematics", "m", "chosen", "position p95", "mm", (low + high) / 2, low, high, 2000, 0.95, "")
    assert target_verdict(row, target) == expected


def test_a_verdict_ranks_the_anfis_and_reads_the_paired_interval(tmp_path):
    (ik, idv, tie), rows = published_verdicts(tmp_path)
    assert (ik.best, ik.rank, ik.compared, ik.rival, ik.rival_value, ik.verdict) == ("ANFIS", 1, 3, "RBF", 4.9, "ANFIS better")
    assert (idv.rank, idv.verdict, tie.verdict) == (2, "rival better", "no difference shown")
    with pytest.raises(ValueError, match="must be one of at least two methods compared"):
        task_verdict("arm", "t", "m", "mm", {"ANFIS": 1.0}, "ANFIS", (0, 0, 0))
    assert [r["verdict"] for r in rows] == ["ANFIS better", "rival better", "no difference shown"]
    assert rows[1]["best"] == "ridge" and rows[1]["best_value"] == "< 1e-6"       # noise level, shown as such
    row = Row("t", "m", ROLE_CHOSEN, "position p95", "mm", 4.0, 3.0, 5.0, 100, 0.95, "")
    assert targets_met([row, row], [10.0, 4.5]) == "1 of 2"
