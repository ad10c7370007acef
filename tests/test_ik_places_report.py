"""nfarm.study.ik_places_report: where the learned IK errs, LM from its guess, and a Cartesian
path — on intelbot5's region, and on errors planted where a cause lies."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.figure import Figure

from nfarm.infra.paths import PARAMS
from nfarm.model.kinematics import fk
from nfarm.solvers import ik
from nfarm.study import ik_places_report as report
from nfarm.study.regions import ik_samples
from nfarm.study.study_files import load_study
from nfarm.study.warm_start import fewer_iterations, warm_starts

STUDY = load_study(PARAMS / "studies" / "intelbot5.yaml")
ROBOT, REGION = STUDY.robot, STUDY.ik_region
BOOT = {"draws": 200, "level": 0.95, "seed": 0}


class Exact:
    """A learned IK that is the closed form's solution (the branch in the region), plus ``dq`` [rad]."""

    def __init__(self, dq: float = 0.0):
        self.dq = dq

    def predict(self, T):
        return ik.closed_form(ROBOT, T).nearest()[0] + self.dq


@pytest.fixture(scope="module")
def test():
    return ik_samples(REGION, 300, 3)


def planted(x, near=10.0):
    """Tool position errors [m] of 1 mm, ``near`` mm on the tenth of the rows with the smallest ``x``."""
    return {"position": np.where(x <= np.quantile(x, 0.1), near, 1.0) * 1e-3}


def test_the_places_are_the_distances_to_the_box_edge_singularities_and_branches(test):
    places = report.error_places(ROBOT, REGION, test["q"])
    q = test["q"][0]
    assert places.edge[0] == pytest.approx(np.degrees(min((q - REGION.box[:, 0]).min(), (REGION.box[:, 1] - q).min())))
    assert places.sigma.shape == (300,) and (places.sigma > 0).all()
    assert list(places.near) == ["elbow from stretched or folded [deg]", "wrist point from the base axis [mm]",
                                 "nearest other solution [deg] (poses that have one)"]
    assert 0 <= places.other_share <= 1


def test_errors_planted_at_the_edge_are_said_to_follow_the_edge(test):
    places = report.error_places(ROBOT, REGION, test["q"])
    rng = np.random.default_rng(0)
    places = report.Places(places.edge, rng.permutation(places.sigma), places.near)   # the singularities unrelated
    e = planted(places.edge)
    ratios = report.near_ratios(places, e, **BOOT)
    assert ratios.value[ratios.names.index(report.EDGE)] == pytest.approx(10.0)
    text = report.causes_prose(ratios)
    assert text.startswith("The tenth of test poses closest to the box's edge has a median error 10 times that of "
                           "the tenth farthest from it")
    assert "The edge matters more" in text
    assert "Neither is a strong cause (both intervals below 1.5)" in report.causes_prose(
        report.near_ratios(places, {"position": np.full(300, 1e-3)}, **BOOT))


def test_the_worst_poses_table_and_the_branch_words(test):
    places = report.error_places(ROBOT, REGION, test["q"])
    e = planted(places.near["elbow from stretched or folded [deg]"], near=5.0)
    e["position"] = e["position"] + np.arange(300) * 1e-9            # a strict order of the worst
    e["joint"] = np.zeros((300, ROBOT.n))
    worst = report.worst_poses(e, 3)
    table = report.worst_table(places, e, count=3)
    assert table.caption.startswith("The chosen ANFIS's three worst test poses")
    assert [r[0] for r in table.rows] == [f"{e['position'][i] * 1e3:.3g}" for i in worst]
    assert all(r[1] == "0" for r in table.rows)
    text = report.branches_prose(places, e, count=3, **BOOT)
    assert text.startswith("Of the 3 test poses with the largest tool error (up to 5 mm)")
    assert "the stretched or folded elbow has a median error 5.0 times that of the tenth farthest (ratio 5–5)" in text
    assert "the box's edge has a median error about the same as that of the tenth farthest (ratio 1–1)" in text
    # the elbow's closeness rises with another solution's (the two branches meet there): the words name it first
    assert "closeness to the stretched or folded elbow" in text.lower()


def test_an_arm_outside_the_closed_forms_class_has_no_branch_table(test):
    places = report.Places(np.ones(3), np.ones(3), None)
    e = {"position": np.ones(3), "joint": np.zeros((3, 5))}
    with pytest.raises(ValueError, match="outside the closed form's class") as caught:
        report.worst_table(places, e)
    assert "\n" not in str(caught.value)


def test_the_figures_come_with_their_captions(test):
    e = {"position": np.full(300, 1e-3)}
    fig, caption = report.error_map_figure(ROBOT.name, test["T"], e)
    assert isinstance(fig, Figure) and caption.startswith("Tool position error of the chosen ANFIS over the region")
    fig, caption = report.predicted_vs_true_figure(test["q"], test["q"] + 0.01, ROBOT.joint_names)
    assert isinstance(fig, Figure) and caption.startswith("Chosen ANFIS on the test set")


def test_the_starts_are_clipped_to_the_limits_and_the_words_read_the_run(test):
    T = test["T"][:20]
    far = Exact(dq=10.0)                          # beyond every joint limit: clipped
    starts, predicted_by = report.lm_starts(ROBOT, T, Exact(), far, "far (contest)", "ANFIS, chosen",
                                            q_closed=test["q"][:20])
    assert list(starts) == [report.DEFAULT_START, "home (the dissertation's)", report.ANFIS_START,
                            "far (contest) prediction", report.CLOSED_START]
    np.testing.assert_allclose(starts["far (contest) prediction"], np.broadcast_to(ROBOT.qlim[:, 1], (20, ROBOT.n)))
    assert predicted_by[report.ANFIS_START] == "ANFIS, chosen"
    warm = warm_starts(ROBOT, T, starts)
    other, ratio = fewer_iterations(warm, report.ANFIS_START, exclude=(report.CLOSED_START,), draws=200)
    prediction_s = {name: 1.0 for name in predicted_by}          # a second per target: no predicted start is fastest
    text = report.warm_start_prose(warm, REGION, other, ratio, prediction_s)
    fastest = min((name for name in warm if name not in predicted_by), key=lambda name: warm[name][1])
    assert text.endswith(f"By total time in this run the fastest start is **{fastest}**.")
    assert f"({warm[report.ANFIS_START][0].iterations.mean():.2f} against {warm[other][0].iterations.mean():.2f};" in text
    assert "from the closed form's solution, none: it is exact" in text


def test_an_exact_learned_ik_follows_the_path_with_lm(tmp_path):
    path = report.follow_path(ROBOT, REGION, Exact(), line_start=[-0.02, 0.0, 0.02], radius=0.02, steps=20,
                              seconds=2.0)
    assert path.T_0e.shape == (20, 4, 4) and path.t[-1] == 2.0 and not path.moved.any()
    centre = fk(ROBOT, REGION.box.mean(axis=1))[:3, 3]
    np.testing.assert_allclose(np.linalg.norm(path.T_0e[10:, :3, 3] - centre, axis=1), 0.02, atol=1e-9)
    rows = report.path_table(path, REGION).rows
    assert [r[:3] for r in rows] == [["ANFIS", 20, "100%"], ["LM", 20, "100%"]]
    assert rows[1][3:] == ["< 1e-6"] * 3
    text = report.path_prose(path, REGION, tmp_path / "07_ik_path.rrd")
    assert text.startswith(f"LM solves {int(path.lm.success.sum())} of the 20 poses of the path")
    with pytest.raises(ValueError, match="steps is 1"):
        report.follow_path(ROBOT, REGION, Exact(), line_start=[0, 0, 0], radius=0.02, steps=1, seconds=1.0)


def test_ratio_said_reads_the_value_then_the_interval():
    ratios = SimpleNamespace(names=["a"], value=np.array([1.02]), low=np.array([0.9]), high=np.array([1.2]))
    assert report.ratio_said(ratios, "a", "the rest") == "about the same as that of the rest (ratio 0.9–1.2)"
