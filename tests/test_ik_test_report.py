"""nfarm.study.ik_test_report: every IK method on the test poses, its tables and its words —
on intelbot5's region, with learned IKs that know the answer to within a known joint offset."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm.infra.paths import PARAMS
from nfarm.study import ik_test_report as report
from nfarm.study.ablation import STRUCTURE_LABELS
from nfarm.study.regions import ik_samples
from nfarm.study.study_files import load_study
from nfarm.study.rows import interval_text

STUDY = load_study(PARAMS / "studies" / "intelbot5.yaml")
ROBOT, REGION = STUDY.robot, STUDY.ik_region
BOOT = {"draws": 200, "level": 0.95, "seed": 0}


class Offset:
    """A learned IK that knows the answer: the joint angles of the known pose nearest ``T``
    (by tool point), plus ``dq`` [rad] on every joint."""

    def __init__(self, data, dq: float, encoding: str = "arm_plane"):
        self.T = np.concatenate([d["T"] for d in data.values()])
        self.q = np.concatenate([d["q"] for d in data.values()])
        self.dq, self.encoding = dq, encoding

    def predict(self, T):
        d = np.linalg.norm(np.asarray(T)[:, None, :3, 3] - self.T[None, :, :3, 3], axis=-1)
        return self.q[d.argmin(axis=1)] + self.dq


@pytest.fixture(scope="module")
def data():
    return {f"ik_{split}": ik_samples(REGION, n, seed) for split, n, seed in (("train", 400, 1), ("val", 60, 2),
                                                                            ("test", 60, 3))}


@pytest.fixture(scope="module")
def models(data):
    return {"learned": Offset(data, 0.01), "recipe": {"ik": Offset(data, 0.05)},
            "rivals": {"knn": Offset(data, 0.03), "rbf": Offset(data, 0.02)}}


@pytest.fixture(scope="module")
def tested(data, models):
    return report.evaluate_ik(ROBOT, REGION, models["learned"], models["recipe"], models["rivals"], data, lm_targets=10)


def test_every_method_is_tested_in_the_tables_order_and_the_best_rival_is_the_closest(tested):
    assert list(tested.methods) == ["ANFIS, chosen (arm_plane)", report.DISS, "k nearest neighbours (contest)",
                                    "RBF interpolation (contest)", report.LM_NAME, report.CLOSED_NAME]
    assert tested.chosen == "ANFIS, chosen (arm_plane)"
    assert (tested.rbf_kind, tested.rbf) == ("rbf", "RBF interpolation (contest)")
    assert list(tested.k) == list(range(10)) and len(tested.errors[report.LM_NAME]["position"]) == 10
    assert tested.closed_share == 1.0             # intelbot5's region holds one of its solutions of every pose
    assert tested.errors[report.CLOSED_NAME]["position"].max() < 1e-9
    np.testing.assert_allclose(tested.errors[tested.chosen]["joint"], 0.01, atol=1e-12)


def test_the_joint_table_shows_each_offset_in_degrees(tested):
    rows = {r[0]: r for r in report.joint_errors_table(tested.errors, ROBOT.n).rows}
    assert rows[tested.chosen][1:] == [60, *["0.573"] * ROBOT.n, "0.573", "0.573"]      # 0.01 rad
    assert rows[report.DISS][2] == "2.86"                                                # 0.05 rad
    assert rows[report.CLOSED_NAME][2] == "< 1e-6"


def test_the_tool_table_and_the_summaries_agree(tested):
    tool = {r[0]: r for r in report.tool_errors_table(tested.errors).rows}
    ik_methods, summary = report.ik_summaries(tested, **BOOT)
    assert [name for name, _ in ik_methods] == [tested.chosen, report.DISS, tested.rbf, report.CLOSED_NAME,
                                               report.LM_NAME]
    assert "worst joint RMSE" not in summary[report.LM_NAME]        # LM's joint "errors" are other branches
    median = float(np.median(tested.errors[tested.chosen]["position"])) * 1e3
    assert tool[tested.chosen][1] == f"{median:.3g}"
    assert summary[tested.chosen]["position median"].value == pytest.approx(median)


def test_the_prose_states_the_computed_numbers(tested):
    _, summary = report.ik_summaries(tested, **BOOT)
    text = report.accuracy_prose(tested, summary, REGION)
    assert f"at most **{interval_text(summary[tested.chosen]['worst joint RMSE'])}°**" in text
    assert f"The strongest baseline on the validation poses, {tested.rbf}, reaches" in text
    assert "per-joint RMSE ≤ 1 ° ✓" in text                           # 0.573°, on a point interval
    outside = 1 - REGION.contains(tested.lm.q).mean()
    assert f"{outside:.0%} of its solutions lie outside the region" in text
    closed = report.closed_form_prose(tested)
    assert closed.startswith("The closed form is exact: on 100.00% of the test poses")


def test_the_closed_form_is_not_spoken_of_for_an_arm_outside_its_class(tested):
    from dataclasses import replace
    without = replace(tested, errors={k: v for k, v in tested.errors.items() if k != report.CLOSED_NAME},
                      closed_share=None)
    assert report.closed_form_prose(without) is None


def test_the_encoding_credit_finds_the_joints_the_arms_plane_gives(tmp_path, data, models, tested):
    recipe = {"ik": Offset(data, 0.05, encoding="arm_plane")}      # one encoding: its rows once
    credit = report.encoding_credit(ROBOT, tested, models["learned"], recipe, models["rivals"], data, tmp_path, **BOOT)
    assert list(credit.errors) == [("arm_plane", report.LINEAR), ("arm_plane", "ANFIS"),
                                   ("arm_plane", f"best rival: {tested.rbf}")]
    table = report.credit_table(credit)
    assert [r[:2] for r in table.rows] == [list(key) for key in credit.errors]
    text = report.credit_prose(credit, ROBOT.joint_names)
    assert "already gives base_yaw and wrist_roll to within < 1e-6°" in text     # linear in the arm's plane
    floor, anfis = credit.rows["arm_plane", report.LINEAR], credit.rows["arm_plane", "ANFIS"]
    assert f"the ANFIS brings the median to {interval_text(anfis['position median'])} mm" in text
    assert floor["position median"].value > anfis["position median"].value
    # The fuzzy c-means ANFIS on the recipe's inputs (chapter 6's contestant, issue 64), where it was saved: its row beside
    # the recipe's, its own errors
    with_fcm = report.encoding_credit(ROBOT, tested, models["learned"], {**recipe, "ik_fcm": Offset(data, 0.02)},
                                      models["rivals"], data, tmp_path, **BOOT)
    assert list(with_fcm.errors) == [("arm_plane", report.LINEAR), ("arm_plane", "ANFIS"),
                                     ("arm_plane", report.ANFIS_FCM), ("arm_plane", f"best rival: {tested.rbf}")]
    np.testing.assert_allclose(with_fcm.errors["arm_plane", report.ANFIS_FCM]["joint"], 0.02, atol=1e-12)
    # ... and said on the seven inputs: the fuzzy c-means ANFIS's median and 95th percentile beside the recipe's
    rows = dict(with_fcm.rows)
    for learner in (report.LINEAR, report.ANFIS, report.ANFIS_FCM):
        rows["quat_xyz", learner] = rows["arm_plane", learner]
    seven = report.Credit(with_fcm.errors, rows, "quat_xyz", with_fcm.rival, with_fcm.moved)
    said = report.credit_prose(seven, ROBOT.joint_names)
    fcm, recipe_rows = rows["quat_xyz", report.ANFIS_FCM], rows["quat_xyz", report.ANFIS]
    assert (f"Given fuzzy c-means rules on those inputs (chapter 6's contestant), the ANFIS lands "
            f"{interval_text(fcm['position median'])} mm away at the median and {interval_text(fcm['position p95'])} mm "
            f"at the 95th percentile, against the recipe's {interval_text(recipe_rows['position p95'])} mm.") in said
    assert "Given fuzzy c-means rules" not in report.credit_prose(credit, ROBOT.joint_names)      # not without it


def test_the_structure_ablation_without_a_structured_model_says_so(tested, data, models):
    structure = report.structure_test(ROBOT, models["learned"], models["rivals"], data, **BOOT)
    assert structure.same_pair is None
    assert [r[:2] for r in report.structure_table(structure).rows] == [
        ["k nearest neighbours", STRUCTURE_LABELS["whole"]], ["RBF interpolation", STRUCTURE_LABELS["whole"]]]
    assert report.structure_prose(structure, **BOOT).startswith("No rival inside the ANFIS's structure")
    empty = report.Structure({}, {}, None)
    assert report.structure_table(empty) is None and report.structure_prose(empty) is None


@pytest.mark.parametrize("change, message", [({"lm_targets": 0}, "lm_targets is 0"),
                                             ({"rivals": {}}, "no rivals")])
def test_a_test_without_lm_targets_or_rivals_is_refused_in_one_line(change, message, data, models):
    args = {"lm_targets": 10, "rivals": models["rivals"], **change}
    with pytest.raises(ValueError, match=message) as caught:
        report.evaluate_ik(ROBOT, REGION, models["learned"], models["recipe"], args["rivals"], data,
                           lm_targets=args["lm_targets"])
    assert "\n" not in str(caught.value)


def test_a_recorded_ranking_is_taken_as_it_is_and_one_of_other_rivals_refused(data, models):
    """Given chapter 6's ranking (contest.saved_ranking), its first is the best rival, even where
    predicting the validation poses would rank otherwise; a ranking of other names is refused."""
    args = (ROBOT, REGION, models["learned"], models["recipe"], models["rivals"], data)
    recorded = report.evaluate_ik(*args, lm_targets=10, ranking=["knn", "rbf"])
    assert recorded.ranking == ("knn", "rbf") and recorded.rbf_kind == "knn"
    assert report.evaluate_ik(*args, lm_targets=10).rbf_kind == "rbf"        # ranked here: the closer
    with pytest.raises(ValueError, match=r"ranking names \['knn'\], not the rivals \['knn', 'rbf'\]"):
        report.evaluate_ik(*args, lm_targets=10, ranking=["knn"])


class Counted(Offset):
    """An :class:`Offset` that counts its predictions."""

    calls = 0

    def predict(self, T):
        type(self).calls += 1
        return super().predict(T)


def test_the_structure_ablation_reuses_the_test_s_predictions_and_ranking(data):
    rivals = {"knn": Counted(data, 0.03), "rbf": Counted(data, 0.02)}
    learned = Offset(data, 0.01)
    tested = report.evaluate_ik(ROBOT, REGION, learned, {"ik": Offset(data, 0.05)}, rivals, data, lm_targets=10)
    before = Counted.calls
    reused = report.structure_test(ROBOT, learned, rivals, data, tested=tested, **BOOT)
    assert Counted.calls == before                       # nothing predicted again
    again = report.structure_test(ROBOT, learned, rivals, data, **BOOT)
    assert Counted.calls == before + 2                   # predicted on the test poses again
    assert list(reused.errors) == list(again.errors) and reused.same_pair == again.same_pair
    for key in reused.errors:
        for field in ("joint", "position", "orientation"):
            np.testing.assert_array_equal(reused.errors[key][field], again.errors[key][field])
    assert tested.ranking == ("rbf", "knn")
