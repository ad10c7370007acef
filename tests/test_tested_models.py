"""nfarm.study.tested_models: chapter 7's inputs loaded once, refused in one line when chapter 6 has not run."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm.infra.paths import PARAMS
from nfarm.study import datasets, study_files
from nfarm.study.tested_models import load_tested

STUDY = PARAMS / "studies" / "intelbot5.yaml"


@pytest.fixture(scope="module")
def smoke_data(tmp_path_factory):
    """The smoke study's data sets, built into a temporary directory."""
    where = tmp_path_factory.mktemp("data")
    study = study_files.smoke_study(study_files.load_study(STUDY))
    datasets.build_datasets(study, where)
    return where


def test_an_empty_store_is_refused_in_one_line_naming_chapter_6(smoke_data, tmp_path):
    with pytest.raises(RuntimeError) as caught:
        load_tested(STUDY, smoke=True, data_dir=smoke_data, models_dir=tmp_path / "models")
    message = str(caught.value)
    assert "\n" not in message and message.startswith("chapter 07 tests the models of chapter 06, run it first")


def test_the_exercises_set_up_one_small_model_in_the_arm_s_plane(smoke_data):
    from nfarm.publishing import answers
    ex = answers.ik_exercises(STUDY, smoke=True, data_dir=smoke_data, seed=0)
    assert ex.options["encoding"] == "arm_plane" and ex.notice == ""
    assert ex.T.shape == (ex.test, 4, 4) and (ex.samples, ex.test) == (300, 100)
    assert ex.model.predict(ex.T).shape == (ex.test, 5)
    # the reference answer trains the same model again: the same median to rounding
    again = answers.median_tool_error_mm(ex.robot, ex.data["ik_train"], ex.data["ik_val"], ex.data["ik_test"], ex.options,
                                         ex.samples, 0, ex.test)
    from nfarm.model.kinematics import fk
    import numpy as np
    mine = 1000 * np.median(np.linalg.norm(fk(ex.robot, ex.model.predict(ex.T))[:, :3, 3] - ex.T[:, :3, 3], axis=-1))
    assert mine == pytest.approx(again, rel=1e-12)


def test_chapter_6_s_exercises_get_the_smoke_budgets_and_the_arm_s_plane(smoke_data):
    from nfarm.publishing import answers
    ex = answers.training_exercises(STUDY, smoke=True, data_dir=smoke_data)
    assert (ex.samples, ex.epochs, ex.stride, ex.planar, ex.notice) == (300, 2, 4, True, "")
    assert ex.plane == pytest.approx(np.radians(0.5))
    assert set(ex.data) == {"ik_train", "ik_val", "ik_test", "id_train", "id_val"}
    # a plane that admits nothing: the arm's poses leave it, and the student is told which exercises apply
    tight = answers.training_exercises(STUDY, smoke=True, data_dir=smoke_data, max_out_of_plane_deg=-1.0)
    assert not tight.planar and tight.notice.startswith("intelbot5's tool leaves the arm's vertical plane")
