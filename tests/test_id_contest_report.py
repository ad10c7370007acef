"""The measured arm's learned-ID contest as chapter 6.8 writes it down (nfarm.study.id_contest_report):
its tables, the finalists' error against the training states, and the tiers' verdicts, on a
contest made up here."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from nfarm.model.dynamics import rnea  # noqa: E402
from nfarm.model.robot import load_robot  # noqa: E402
from nfarm.study import contest  # noqa: E402
from nfarm.study import id_contest_report as report  # noqa: E402
from nfarm.study.sweep import Cell, CellResult  # noqa: E402

ROBOT = load_robot("params/robots/intelbot5.yaml")
NOISE = np.full(ROBOT.n, 0.005)


def result(learner, seed, nrmse, stride=2, samples=1500, **options):
    params = {"learner": learner, "options": options, "seed": seed, "split": "val", "stride": stride}
    return CellResult(Cell(params, f"{learner}{seed}{stride}{sorted(options.items())}"), "ok",
                      {"worst_nrmse": nrmse, "worst_rmse": 10 * nrmse, "rmse": [nrmse] * ROBOT.n, "fit_seconds": 1.0,
                       "train_samples": samples}, 2.0, "w")


@pytest.fixture
def idc():
    seed0 = [result("anfis", 0, 0.30, inputs="affine_generic"), result("ridge", 0, 0.20, basis="generic"),
             result("mlp", 0, 0.25, hidden=[8]), result("friction", 0, 0.10, residual=True)]
    spread = [result("anfis", 1, 0.40, inputs="affine_generic"), result("ridge", 1, 0.22, basis="generic")]
    return contest.id_contest(seed0, spread)


def test_the_contest_table_marks_each_tiers_best_and_the_pruned(idc):
    rows = {row[1]: row for row in report.contest_table(idc).rows}
    assert rows["ridge regression ◀"][5:] == ["21", "20–22", "2.1", 2]
    assert rows["ANFIS"][5:7] == ["35", "30–40"]
    assert rows["multilayer perceptron"][6] == "pruned after seed 0"
    assert rows["friction identification (least squares) ◀"][0] == "nominal model + learned"
    budget = report.budget_table(idc)
    # no epochs: one pass; the seconds measured (1 s training, 2 s the cell)
    assert budget.rows[0] == ["generic: ANFIS", 1, 1, "1,500", 1.0, 2.0] and "same on any machine" in budget.caption
    assert budget.columns[-2:] == ["training [s] (measured)", "cells [s] (measured)"]


def test_newton_euler_alone_is_judged_on_the_measured_torques():
    rng = np.random.default_rng(0)
    q, qd, qdd = rng.normal(size=(3, 50, ROBOT.n))
    offset = np.linspace(0.1, 0.5, ROBOT.n)
    val = {"q": q, "qd": qd, "qdd": qdd, "tau": rnea(ROBOT, q, qd, qdd), "tau_measured": rnea(ROBOT, q, qd, qdd) + offset}
    np.testing.assert_allclose(report.newton_euler_rmse(ROBOT, val), offset, rtol=1e-12)
    # The measured arm's states, where the data hold them, are what its learners (and Newton–Euler) see
    seen = report.measured_validation({**val, "q_measured": q + 1.0})
    assert np.array_equal(seen["q"], q + 1.0) and np.array_equal(seen["qd"], qd) and seen["tau"] is val["tau_measured"]


def test_the_joints_table_sets_the_finalists_beside_the_noise_and_the_spread(idc):
    tau = np.zeros((4, ROBOT.n))
    tau[:, 0], tau[:, -1] = [-1, 1, -1, 1], [-1e-4, 1e-4, -1e-4, 1e-4]    # the last joint below the noise
    table = report.joints_table(idc, {"tau_measured": tau, "q": tau, "qd": tau, "qdd": tau}, np.full(ROBOT.n, 0.1), NOISE)
    assert table.columns[-2] == f"τ{ROBOT.n} [N·m] (below noise)" and table.columns[2] == "τ1 [N·m]"
    assert [row[0] for row in table.rows] == ["Newton–Euler alone", "generic: ANFIS", "generic: ridge regression",
                                              "nominal model + learned: friction identification (least squares)",
                                              "sensor noise σ", "measured torque's spread (standard deviation)"]
    assert table.rows[2][2] == "0.21" and table.rows[-1][2] == "1"


def test_the_finalists_error_against_the_training_states(idc):
    sizes = [result("anfis", 0, 0.5, stride=8, samples=375, inputs="affine_generic"),
             result("ridge", 0, 0.1, stride=8, samples=375, basis="generic")]
    curves = report.size_curves(idc, sizes)
    assert curves["generic: ANFIS"] == [(375, 50.0), (1500, 30.0)]
    fig, caption = report.sizes_figure(curves, "arm", [8], 2)
    assert caption.endswith("(seed 0; every 8th and 2nd state of the training trajectories, the contest's every 2nd)")
    plt.close(fig)
    text = report.contest_prose(idc, curves, np.full(ROBOT.n, 0.3), NOISE)
    assert text.startswith("In the **generic** tier the ANFIS reaches 35 % (30–40 over 2 seeds) against the tier's best "
                           "rival, ridge regression, at 21 % (20–22): paired seed by seed, the ANFIS is **worse than** it "
                           "(difference 10 to 18 percentage points).")
    assert "On 1,500 training states (seed 0) the ANFIS reaches 30 % and ridge regression 20 %: the same order" in text
    assert "In the nominal model + learned tier only friction identification (least squares) " \
           "competes, at 10 %." in text
    assert "Newton–Euler alone misses the validation torques by up to 0.3 N·m; best of all is nominal model + learned: " \
           "friction identification (least squares) at 10 % (1 N·m on the worst joint;" in text
    assert report.nominal_anfis(idc) is None


def test_best_of_all_leaves_the_rigid_body_span_aside(idc):
    """Issue 65: ridge on the chain basis, best of all on validation, is an identification in disguise — the
    sentence names the best of the others and says the span is aside; the span's lone learner is named once."""
    seed0 = [result("anfis", 0, 0.30, inputs="affine_generic"), result("ridge", 0, 0.20, basis="generic"),
             result("ridge", 0, 0.01, basis="chain_drives"), result("friction", 0, 0.10, residual=True)]
    with_span = contest.id_contest(seed0)
    curves = {name: [(1500, 30.0)] for name in ("generic: ANFIS", "generic: ridge regression")}
    text = report.contest_prose(with_span, curves, np.full(ROBOT.n, 0.3), NOISE)
    assert "In the rigid-body span tier only ridge regression competes, at 1 %." in text
    assert "best of all is nominal model + learned: friction identification (least squares) at 10 % (1 N·m on the " \
           "worst joint; the rigid-body span, an identification in disguise, aside)" in text


def test_the_residual_anfis_is_the_nominal_tiers_anfis_finalist():
    seed0 = [result("anfis", 0, 0.1, inputs="own", residual=True), result("boosting", 0, 0.2, residual=True)]
    idc = contest.id_contest(seed0)
    assert report.nominal_anfis(idc).cell.params["learner"] == "anfis"

    class Joint:
        loss_curve_ = val_loss_curve_ = [0.02, 0.01]
        best_epoch_ = 1

    class Residual:
        models_ = [Joint()] * ROBOT.n

    assert report.pct(0.0123) == "1.23" and report.worst_ends(idc.pair("nominal model + learned")[1]) == "20–20"
    fig, caption = report.residual_figure(Residual(), report.nominal_anfis(idc), ROBOT, NOISE, seed=3)
    assert fig._suptitle.get_text() == f"{ROBOT.name}: residual ANFIS, inputs=own, seed 3"   # residual: the tier says it
    assert len([line for line in fig.axes[0].get_lines() if line.get_linestyle() == ":"]) == ROBOT.n + 1   # each σ, its key
    assert "sensor noise" in caption
    plt.close(fig)


def test_the_prose_names_a_choice_at_the_edge_of_a_search_of_three_values():
    """Given the tuning round's cells, a learner whose chosen value is an end of three or more tried is named (the
    identification + learned tier's four configurations a learner); two configurations bracket nothing: not judged."""
    seed0 = [result("anfis", 0, 0.30, inputs="affine_generic"), result("anfis", 0, 0.32, inputs="own"),
             *(result("ridge", 0, value, basis="generic", alpha=alpha) for alpha, value in ((1.0, 0.25), (100.0, 0.22),
                                                                                           (1.0e4, 0.20))),
             result("mlp", 0, 0.26, hidden=[8]), result("mlp", 0, 0.24, hidden=[16])]
    idc = contest.id_contest(seed0)
    curves = {name: [(1500, 30.0)] for name in ("generic: ANFIS", "generic: ridge regression")}
    text = report.contest_prose(idc, curves, np.full(ROBOT.n, 0.3), NOISE, seed0)
    assert " At the edge of what its search tried: generic: ridge regression, alpha=10000.0 (the largest tried; the step " \
           "from 100.0 moved the validation score by +9.1 %). Where the last step moved the score by less than 1 % the " \
           "search is flat there" in text                                   # (0.22 - 0.20) / 0.22: not flat
    flat = [r for r in seed0 if r.cell.params["options"].get("alpha") != 1.0e4] + [
        result("ridge", 0, 0.2195, basis="generic", alpha=1.0e4)]
    assert "alpha=10000.0 (the largest tried; the step from 100.0 moved the validation score by 0.23 %: flat)" in \
        report.contest_prose(contest.id_contest(flat), curves, np.full(ROBOT.n, 0.3), NOISE, flat)
    assert "hidden" not in text                                             # two widths: no edge judged
    inside = [r for r in seed0 if r.cell.params["options"].get("alpha") != 1.0e4]
    assert report.contest_prose(contest.id_contest(inside), curves, np.full(ROBOT.n, 0.3), NOISE, inside).endswith(
        " No learner's chosen value lies at the edge of a search of three or more values.")
    assert "edge" not in report.contest_prose(idc, curves, np.full(ROBOT.n, 0.3), NOISE)      # no cells given: nothing said


def test_the_prose_says_which_learners_add_nothing_to_the_identification():
    """On the identification's residual, a learner whose chosen configuration scores within 1 % of the identification
    alone adds nothing; one below it is named with its score."""
    seed0 = [result("identification", 0, 0.1453), result("anfis", 0, 0.20, inputs="regressor_drives"),
             result("anfis", 0, 0.125, inputs="own", residual="identification"),
             result("ridge", 0, 0.1453, basis="generic_drives", alpha=1e8, residual="identification"),
             result("mlp", 0, 0.1454, hidden=[4, 4], residual="identification"),
             result("boosting", 0, 0.086, residual="identification")]
    idc = contest.id_contest(seed0)
    curves = {contest.id_label(name): [(1500, 30.0)] for name in idc.chosen}
    text = report.contest_prose(idc, curves, np.full(ROBOT.n, 0.3), NOISE, seed0)
    assert " On validation (seed 0) the identification alone reaches 14.5 %. On its residual, ridge regression and " \
           "multilayer perceptron do no better than it (within 1 %): on the inputs they are given here, they add nothing " \
           "the identification lacks. The ANFIS's chosen configuration sees each joint's own state alone, one model a " \
           "joint: a structure these rivals, on every joint's state, are not given. Learners that improve on it: ANFIS " \
           "12.5 % and gradient-boosted trees 8.6 %." in text
    assert "identification alone" not in report.contest_prose(idc, curves, np.full(ROBOT.n, 0.3), NOISE)
    # with a rival on each joint's own state in the tier, the ANFIS's structure is not its alone: nothing said of it
    given = seed0 + [result("mlp", 0, 0.088, hidden=[32, 32], angles="own", residual="identification")]
    text = report.contest_prose(contest.id_contest(given), curves, np.full(ROBOT.n, 0.3), NOISE, given)
    assert "not given" not in text and "multilayer perceptron 8.8 %" in text


def test_a_boosting_fit_counts_a_pass_a_tree_of_each_joint():
    """Gradient boosting sweeps every training state once a tree: its budget counts ``max_iter`` passes for each joint,
    not one (a fit in closed form, one)."""
    seed0 = [result("boosting", 0, 0.1, max_iter=300, learning_rate=0.05), result("ridge", 0, 0.2, basis="generic")]
    spent = contest.budgets(seed0, family_of=contest.id_family)
    assert spent["generic:boosting"].pose_passes == 1500 * 300 * ROBOT.n
    assert spent["generic:ridge"].pose_passes == 1500


def test_a_search_along_a_number_compares_configurations_of_one_design():
    """The ANFIS's grid over q̇ ever finer beside one of fuzzy c-means rules: the grid's resolution is judged among the
    grids alone (the c-means configuration sets no ``n_mfs``), its last step from [1, 7, 2] flat."""
    grid = [result("anfis", 0, value, inputs="own", residual="identification", partition="grid", n_mfs=mfs)
            for mfs, value in (([1, 5, 2], 0.1260), ([1, 7, 2], 0.1250), ([1, 11, 2], 0.1248))]
    seed0 = grid + [result("anfis", 0, 0.1458, inputs="all", residual="identification", partition="fcm", n_rules=8),
                    result("boosting", 0, 0.0860, residual="identification")]
    idc = contest.id_contest(seed0)
    assert contest.at_edge(seed0, idc.chosen, family_of=contest.id_family) == {
        "identification + learned:anfis": [("n_mfs", [1, 11, 2], "largest")]}
    curves = {contest.id_label(name): [(1500, 30.0)] for name in idc.chosen}
    assert "identification + learned: ANFIS, n_mfs=[1, 11, 2] (the largest tried; the step from [1, 7, 2] moved the " \
           "validation score by 0.16 %: flat)" in report.contest_prose(idc, curves, np.full(ROBOT.n, 0.3), NOISE, seed0)
