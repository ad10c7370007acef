"""Chapter 6's summary (nfarm.study.training_summary): what it chose, against the study's target
and the best baseline, with the measured arm's tiers where the study has one."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm.study import contest
from nfarm.study.chosen_models import ChosenIK
from nfarm.study.id_comparison_report import torque_reading
from nfarm.study.sweep import Cell, CellResult, Replicates
from nfarm.study.training_summary import summary_prose

READING = torque_reading(np.array([[-1.0, -2.0], [1.0, 2.0]]), None, ["a", "b"])


def group(metric_values, **params):
    return Replicates(tuple(CellResult(Cell({**params, "seed": s}, f"{sorted(params.items())}{s}"), "ok", dict(m), 1.0, "w")
                            for s, m in enumerate(metric_values)))


def ik(p95s, encoding):
    return group([{"position_p95_mm": p, "position_p50_mm": p / 2} for p in p95s], learner="anfis", encoding=encoding)


def id_(worsts, **params):
    return group([{"worst_nrmse": w} for w in worsts], **params)


@pytest.mark.parametrize("anfis, baseline, says", [
    ([0.02, 0.04], [0.5, 0.6], "met in every seed. The best scikit-learn baseline, multilayer perceptron (hidden=[8]), reaches 55 % (50–60 %): "
                               "the ANFIS is better."),
    ([0.03, 0.06], [0.06, 0.07], "met on average. The best scikit-learn baseline, multilayer perceptron (hidden=[8]), reaches 6.5 % (6–7 %): "
                                 "no difference shown by the seeds' ranges."),
    ([0.3, 0.4], [0.01, 0.02], "not met. The best scikit-learn baseline, multilayer perceptron (hidden=[8]), reaches 1.5 % (1–2 %): "
                               "**the baseline is better**."),
])
def test_the_summary_judges_the_chosen_models_on_validation(anfis, baseline, says):
    leader, plane = ik([1.0, 1.2], "quat_xyz"), ik([2.0, 2.4], "arm_plane")
    chosen = ChosenIK("anfis:arm_plane", None, {}, {}, plane)
    best = id_(anfis, inputs="affine", partition="grid", n_mfs=2)
    base = {("generic", "mlp"): id_(baseline, learner="mlp", hidden=[8])}
    lines = summary_prose(chosen, [leader, plane], READING, best, base).split("\n")
    assert len(lines) == 3 and lines[-1].startswith("* Every choice here was made on validation data")
    assert lines[0] == ("* **Inverse kinematics**: ANFIS in the arm's plane, chosen in the contest of section 6.1, reaches a "
                        "95th-percentile tool position error of **2.2 (2–2.4) mm** and a median of 1.1 (1–1.2) mm on "
                        "validation (mean and range over 2 seeds); the contest's leader is ANFIS, the dissertation's 7 "
                        "inputs at 1.1 (1–1.2) mm.")
    assert lines[1].startswith("* **Inverse dynamics without the arm's parameters**: the best ANFIS, affine: partition=grid, "
                               "n_mfs=2, misses by") and lines[1].endswith(says)
    chosen_leads = ChosenIK("anfis:arm_plane", None, {}, {}, plane)
    assert summary_prose(chosen_leads, [plane, leader], READING, best, base).split("\n")[0].endswith(
        "(mean and range over 2 seeds); it leads the contest.")


def test_the_summary_names_each_tiers_best_on_the_measured_arm():
    seed0 = [CellResult(Cell({"learner": learner, "options": options, "seed": 0, "split": "val"}, learner), "ok",
                        {"worst_nrmse": w, "worst_rmse": w, "fit_seconds": 1.0}, 1.0, "w")
             for learner, options, w in [("anfis", {"inputs": "affine_generic"}, 0.4), ("ridge", {"basis": "generic"}, 0.3),
                                         ("anfis", {"inputs": "regressor_drives"}, 0.05)]]
    plane = ik([2.0], "arm_plane")
    text = summary_prose(ChosenIK("anfis:arm_plane", None, {}, {}, plane), [plane], READING, id_([0.02], inputs="affine"),
                         {("generic", "mlp"): id_([0.5], learner="mlp")}, contest.id_contest(seed0), np.array([0.005, 0.002]))
    assert text.split("\n")[2] == ("* **The measured arm** (validation, worst resolved joint's NRMSE against the measured "
                                   "spread): generic, best ridge regression (30 %); identification, best ANFIS (5 %); "
                                   "the sensor noise is 0.005 N·m.")
