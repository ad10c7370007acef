"""The chosen ID models as chapter 6.7 and 6.9 write them down (nfarm.study.id_chosen_report):
how their training went, the models table, the dissertation's trajectories against the study's,
and the store's note, on models made up here."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from nfarm.study import id_chosen_report as report  # noqa: E402
from nfarm.study.chosen_models import ChosenID, ChosenModels  # noqa: E402
from nfarm.study.id_chosen_report import SeedLikeData  # noqa: E402
from nfarm.study.id_comparison_report import torque_reading  # noqa: E402
from nfarm.study.sweep import Cell, CellResult, Replicates  # noqa: E402

# Three joints, the third below the sensor noise; torque spreads 1, 2 and 0.001 N·m
READING = torque_reading(np.array([[-1.0, -2.0, -0.001], [1.0, 2.0, 0.001]]), np.array([0.01] * 3), ["a", "b", "c"])


class Joint:
    def __init__(self, val, train=None):
        self.val_loss_curve_, self.loss_curve_ = list(val), list(train if train is not None else val)
        self.best_epoch_ = int(np.argmin(val))
        self.mfs_, self.consequents_ = [np.zeros(4)], np.zeros((2, 3))


class Model:
    def __init__(self, curves, seconds=(2.0, 2.4)):
        self.models_, self.fit_seconds_ = [Joint(c) for c in curves], list(seconds)


def group(worsts, **params):
    params = {"inputs": "affine", "stride": 4, **params}
    return Replicates(tuple(CellResult(Cell({**params, "seed": s}, f"{sorted(params.items())}{s}"), "ok",
                                       {"worst_nrmse": w}, 1.0, "w") for s, w in enumerate(worsts)))


def chosen_with(model, best=None):
    return ChosenID(best or group([0.02, 0.03]), {"inputs": "affine", "n_mfs": 2}, 4, model,
                    Model([[0.5]] * 3), Model([[1e-12]] * 3))


@pytest.mark.parametrize("curves, says", [
    ([[0.4]] * 3, "The model trains one epoch: the least squares of its consequents are the whole fit."),
    ([[0.4, 0.5, 0.6]] * 3, "None of the 2 epochs after the first lowers a joint's validation error"),
    ([[0.4, 0.39]] * 2 + [[1.0, 0.1]], "lower a joint's validation error by at most 2.5 % of the first epoch's (a): "
                                       "the first epoch's least squares of the consequents do nearly all the learning"),
    ([[0.4, 0.2]] * 3, "by at most 50 % of the first epoch's (a)."),
])
def test_the_curves_prose_says_what_the_epochs_after_the_first_did(curves, says):
    # joint c's fall from 1.0 to 0.1 is below the noise: not read
    assert says in report.curves_prose(chosen_with(Model(curves)), READING)


def test_the_curves_figure_shows_the_resolved_joints_in_percent_of_their_spread():
    fig, caption = report.curves_figure(chosen_with(Model([[0.4, 0.2]] * 3)), READING, "arm")
    assert caption.endswith("(structure-informed), one per joint (τ3, below the sensor noise, left out)")
    assert fig._suptitle.get_text() == "arm: affine: n_mfs=2 (structure-informed)"
    plt.close(fig)


def test_the_models_table_gives_each_configurations_range_or_one_run():
    chosen = chosen_with(Model([[0.04, 0.02], [0.05, 0.04], [9.0, 8.0]]))
    results = [group([0.02, 0.03], n_mfs=2), group([0.5, 0.6], inputs="own", n_mfs=3)]
    table = report.models_table(READING, chosen, results, {"q": np.zeros((40, 3))}, {"inputs": "own", "n_mfs": 3},
                                {"inputs": "regressor", "n_mfs": 1}, seed=0)
    chosen_row, design, identification = table.rows
    assert chosen_row[0] == "chosen, structure-informed: affine: n_mfs=2"
    assert chosen_row[1:] == [2, 3 * 10, "10", "2", "2", "800000", "2", "2–3"]    # NRMSE = kept RMSE / spread, in %
    assert design[-1] == "50–60" and identification[-1] == "one run" and identification[-2] == "< 1e-6"


def test_the_largest_speed_and_the_distinct_cells():
    np.testing.assert_allclose(report.largest_deg({"qdd": np.array([[np.pi, -2 * np.pi]])}, "qdd"), [180.0, 360.0])
    a, b = group([0.1, 0.2]).runs
    b_again = CellResult(b.cell, "ok", {"worst_nrmse": 9.0}, 1.0, "w")
    cells = report.distinct_cells([a, b], [b_again])
    assert len(cells) == 2 and cells[1] is b_again                      # a cell two lists hold counts once


def seed_like(cubic_worsts):
    slow = {"q": np.zeros((10, 3)), "qd": np.full((10, 3), 0.1), "qdd": np.full((10, 3), 0.2)}
    fast = {"q": np.zeros((10, 3)), "qd": np.full((10, 3), 1.0), "qdd": np.full((10, 3), 4.0)}
    groups = {"model_free": group(cubic_worsts, seed_like={"duration_s": 6.0}),
              "dissertation": group([0.7, 0.8], inputs="own", seed_like={"duration_s": 6.0})}
    return SeedLikeData(groups, slow, fast)


@pytest.mark.parametrize("cubic, says", [
    ([0.5, 0.6], ": the dissertation's data do not teach the dynamics the arm meets in faster motion."),
    ([0.025, 0.05], ": no difference shown by the seeds' ranges."),
    ([0.025], ": within the range of the study-trained seeds."),
    ([0.01], "when trained on this study's data."),
])
def test_the_dissertations_trajectories_are_judged_against_the_studys(cubic, says):
    text = report.seed_like_prose(READING, seed_like(cubic), group([0.02, 0.03]), {"duration_s": 6.0})
    assert text.startswith(f"Cubics from rest to rest over 6 s move slowly: their largest acceleration is "
                           f"{np.degrees(0.2):.3g} °/s² against {np.degrees(4.0):.3g} °/s²")
    assert text.endswith(says)


def test_the_seed_like_table_sets_the_two_trainings_side_by_side():
    class Study:
        class id:
            via_points, dt = 8, 0.02

    data = seed_like([0.5, 0.6])
    chosen = chosen_with(Model([[0.04, 0.02], [0.05, 0.04], [9.0, 8.0]]))
    table = report.seed_like_table(READING, data, chosen, [group([0.02, 0.03], n_mfs=2)], {"inputs": "own", "n_mfs": 9},
                                   {"duration_s": 6.0, "dt_s": 0.2}, Study, id_stride=4)
    assert table.columns[1:] == ["the dissertation's way (cubic, 6 s, dt 0.2 s)",
                                 "this study's (quintic through 8 via points, dt 0.02 s, one state in 4)"]
    assert table.rows[0] == ["training states", "10", "10"] and table.rows[1][1:] == [f"{np.degrees(0.1):.3g}", "57.3"]
    assert table.rows[3][1:] == ["55 (50–60)", "2.5 (2–3)"]
    assert table.rows[4][1:] == ["75 (70–80)", "50 (one run)"]     # the design's own run: no configuration in the sweep


def test_the_note_says_where_the_models_and_cells_are(tmp_path):
    chosen = chosen_with(Model([[0.4]] * 3))
    note = report.models_note(ChosenModels(tmp_path / "m"), chosen, None, group([1, 2, 3]).runs, tmp_path / "sweeps")
    assert "took 4 s when they were made. The 3 sweep cells this chapter shows are in " in note
    assert ", the residual ANFIS of section 6.8 10 s. " in report.models_note(ChosenModels(tmp_path), chosen,
                                                                              Model([[0.1]], seconds=(10.0,)), [])
