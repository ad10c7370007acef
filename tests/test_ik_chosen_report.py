"""The chosen learned IK as chapter 6.2–6.3 writes it down (nfarm.study.ik_chosen_report): the
models table, the rule-count search and how the training ended, on models made up here."""

from __future__ import annotations

import copy

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from nfarm.model.robot import load_robot  # noqa: E402
from nfarm.study import ik_chosen_report as report  # noqa: E402
from nfarm.study.chosen_models import ChosenIK, ChosenModels  # noqa: E402
from nfarm.study.sweep import Cell, CellResult, Replicates  # noqa: E402

ROBOT = load_robot("params/robots/intelbot5.yaml")


class Joint:
    """One joint's fitted model: its curves, its kept epoch and its parameters."""

    def __init__(self, val, best=None, train=None):
        self.val_loss_curve_ = list(val)
        self.loss_curve_ = list(train if train is not None else val)
        self.best_epoch_ = int(np.argmin(val)) if best is None else best
        self.mfs_ = [np.zeros((2, 3))]
        self.consequents_ = np.zeros((2, 4))


class Model:
    def __init__(self, joints, closure=None, seconds=(1.2, 3.4)):
        self.models_, self.fit_seconds_ = joints, list(seconds)
        if closure is not None:
            self.closure_ = closure


def run(n_rules, p95, fraction=0.25, learner="anfis", encoding="arm_plane"):
    params = {"learner": learner, "encoding": encoding, "options": {"n_rules": n_rules, "epochs": 20}, "seed": 0,
              "fraction": fraction}
    return CellResult(Cell(params, f"{learner}{n_rules}{fraction}"), "ok",
                      {"position_p95_mm": p95, "position_p50_mm": p95 / 2, "train_samples": 250 if fraction < 1 else 1000,
                       "joint_rmse_deg": [1e-5, 0.5, 0.25, 1e-5, 1e-5]}, 1.0, "w")


def search_of(pairs, promoted):
    rung = [run(n, p) for n, p in pairs] + [run(None, 9.0, learner="rbf", encoding=None)]
    full = [run(n, p / 2, fraction=1.0) for n, p in pairs if n in promoted]
    return report.rule_count_search(rung, full, full_poses=1000)


def test_the_search_orders_the_counts_and_keeps_the_promoted_ones():
    search = search_of([(256, 2.0), (64, 3.0), (128, 2.5)], promoted=(256,))
    assert search.rules == [64, 128, 256] and search.rung_poses == 250
    assert search.at_rung("position_p95_mm") == [3.0, 2.5, 2.0]
    assert search.at_full("position_p95_mm")[:2] == [pytest.approx(np.nan, nan_ok=True)] * 2
    assert search.at_full("position_p95_mm")[2] == 1.0


@pytest.mark.parametrize("pairs, tolerance, says", [
    ([(64, 3.0), (128, 2.0), (256, 2.5)], 0.0, ", and more rules do no better (256 rules 2.5 mm)."),
    ([(64, 3.0), (128, 2.0), (256, 1.0)], 0.0, ", the largest count tried, its doubling still gaining 50%: the contest's "
                                               "budget, not the model, ended the search"),
    ([(64, 3.0), (128, 2.0), (256, 1.9)], 0.1, ", the largest count tried, but its doubling gained 5.0% only: the curve "
                                               "has flattened. The smallest count within 10% of the best is promoted"),
])
def test_the_rule_count_prose_says_why_the_search_stopped(pairs, tolerance, says):
    text = report.rule_count_prose(search_of(pairs, promoted=(128,)), tolerance=tolerance)
    assert text.startswith("Trained on 250 poses, from 64 to 256 rules the 95th percentile goes from 3 to ")
    assert says in text and text.endswith(" On all 1,000 poses: 128 rules 1 mm.")


def test_the_rule_count_figure_draws_the_best_rival_as_a_reference():
    search = search_of([(64, 3.0), (128, 2.0)], promoted=(128,))
    rival = run(None, 1.5, fraction=1.0, learner="rbf", encoding=None)
    ranked = [Replicates((rival,)), Replicates((run(128, 1.0, fraction=1.0),))]
    fig, caption = report.rule_count_figure(search, ranked, {"rbf": rival}, "arm")
    labels = [line.get_label() for line in fig.axes[0].get_lines()]
    assert any(label.startswith("RBF interpolation, 95th percentile") for label in labels)
    assert "(dashed)" in caption and fig.axes[0].get_title() == "arm: the contest's rule counts (seed 0)"
    plt.close(fig)


def test_learned_joints_leave_out_the_exact_ones_and_the_closed_pitch():
    model = Model([Joint([1e-7]), Joint([0.1, 0.05]), Joint([0.2]), Joint([0.3]), Joint([1e-8])], closure={"joint": 3})
    assert report.learned_joints(model) == [1, 2]
    assert report.learned_joints(Model(model.models_)) == [1, 2, 3]
    assert report.learned_joints(model, floor=10.0) == [2]           # 0.1 rad is 5.7°


@pytest.mark.parametrize("options, says", [
    ({"epochs": 5}, "— the limit of 5: early stopping did not end the training"),
    ({"epochs": 50, "patience": 2}, "its last 2 epochs lowered the joints' least validation errors by 0–2 % (none counts"),
    ({"epochs": 50, "patience": 2, "min_improvement": 0.01}, "(a fall counts when it takes the joints' combined error 1.0% "
                                                             "below the last level that counted)."),
    ({"epochs": 50}, "— early stopping ended the training before the limit of 50 epochs."),
])
def test_the_epochs_prose_says_what_ended_the_training(options, says):
    model = Model([Joint([1e-7]), Joint([1.0, 0.5, 0.4, 0.392, 0.3999]), Joint([1.0, 0.5, 0.4, 0.41, 0.42])])
    text = report.epochs_prose(model, options)
    assert text.startswith("The chosen model's learned joints ran 5, 5 epochs and kept epochs 4, 3, where") and says in text


def test_the_models_table_and_note_give_each_models_epochs_parameters_and_errors(tmp_path):
    plane, recipe = run(128, 1.0, fraction=1.0), run(None, 5.0, fraction=1.0, encoding="quat_xyz")
    joints = lambda: [Joint([0.1, 0.02]) for _ in range(5)]      # noqa: E731
    chosen = ChosenIK("anfis:arm_plane", Model(joints()), {"anfis:arm_plane": Model(joints()), "anfis:quat_xyz": Model(joints())},
                      {"ik_full": Model(joints(), seconds=(10.0,))}, Replicates((plane,)))
    contest_chosen = {"anfis:arm_plane": plane, "anfis:quat_xyz": recipe}
    table = report.models_table(chosen, contest_chosen, ROBOT)
    assert [row[0] for row in table.rows] == ["chosen: ANFIS in the arm's plane", "the dissertation's 7 inputs (contest)",
                                              "the dissertation's recipe as it is, full joint ranges"]
    assert table.rows[0][1:] == ["2/2/2/2/2", 5 * (6 + 8), "< 1e-3", "0.5", "0.25", "< 1e-3", "< 1e-3"]
    assert table.rows[2][3:] == [f"{np.degrees(0.02):.3g}"] * 5      # the full-range recipe: from its kept epoch
    assert report.models_table(chosen, contest_chosen, ROBOT, seed=2).rows[0][3:] == ["—"] * 5
    note = report.models_note(ChosenModels(tmp_path / "m"), chosen)
    assert note.endswith("Training the chosen ANFIS took 5 s when it was made, the full-range recipe 10 s.")
    no_full = copy.copy(chosen)
    object.__setattr__(no_full, "recipe", {})
    assert len(report.models_table(no_full, contest_chosen, ROBOT).rows) == 2


def test_the_curves_figure_names_the_closed_joint():
    model = Model([Joint([1e-7]), Joint([0.1, 0.05]), Joint([0.2, 0.1]), Joint([0.3]), Joint([1e-8])], closure={"joint": 3})
    chosen = ChosenIK("anfis:arm_plane", model, {}, {}, None)
    fig, caption = report.curves_figure(chosen, {"options": {"n_rules": 128}}, ROBOT)
    assert caption.endswith("(joints learned to rounding left out; q4 comes from the pitch closure)")
    assert "(n_rules=128)" in fig._suptitle.get_text()
    plt.close(fig)
