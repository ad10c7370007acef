"""Issue 66: the shifted test population — declared in the study file, drawn apart from the data
sets (their hash leaves it out), just beyond the region, from its own seed."""

from __future__ import annotations

import json

import numpy as np
import pytest

from nfarm.infra.paths import PARAMS
from nfarm.infra.reading import ParamsError
from nfarm.model.kinematics import fk
from nfarm.study import datasets
from nfarm.study.regions import IKRegion
from nfarm.study.shifted import beyond_box, boundary_distance, describe, shifted_ik
from nfarm.study.study_files import load_study, study_from_dict

STUDIES = ("intelbot5", "so101")


@pytest.mark.parametrize("arm", STUDIES)
def test_the_shifted_targets_lie_just_beyond_the_region(arm):
    """Outside the region's box on some joint, within the band beyond it on every joint, within the
    joints' limits, the task-space filters met; the same draws from the same seed."""
    study = load_study(PARAMS / "studies" / f"{arm}.yaml")
    s, region = study.shifted, study.ik_region
    targets = shifted_ik(study)
    q = targets["q"]
    assert q.shape == (s.ik_samples, study.robot.n)
    assert not region.contains(q).any()
    distance = boundary_distance(region, q)
    assert (distance < 0).all() and (distance >= -s.ik_band - 1e-12).all()
    assert ((q >= study.robot.qlim[:, 0]) & (q <= study.robot.qlim[:, 1])).all()
    assert region.contains_pose(targets["T"], q).all()                 # the filters kept
    np.testing.assert_array_equal(targets["T"], fk(study.robot, q))
    np.testing.assert_array_equal(shifted_ik(study)["q"], q)


def test_declaring_a_shifted_population_rebuilds_no_data_set():
    study = load_study(PARAMS / "studies" / "intelbot5.yaml")
    params = json.loads(json.dumps(study.params))
    params.pop("shifted")
    without = study_from_dict(params, source="no-shift.yaml")
    assert without.shifted is None and "shifted" not in study.data_params
    assert datasets.inputs_hash(without) == datasets.inputs_hash(study)
    with pytest.raises(ValueError, match=r"no-shift.yaml: shifted: the study declares no shifted test population"):
        shifted_ik(without)
    assert describe(without) == "no shifted population"


@pytest.mark.parametrize("field, value, rule", [
    ("ik_band", 0.0, r"shifted.ik_band"),
    ("ik_band", 0.7, r"shifted.ik_band"),
    ("ik_samples", 0, r"shifted.ik_samples"),
    ("seed", -1, r"shifted.seed"),
    ("colour", "red", r"shifted.*colour"),
])
def test_a_bad_shifted_section_is_refused_naming_the_field(field, value, rule):
    study = load_study(PARAMS / "studies" / "intelbot5.yaml")
    params = json.loads(json.dumps(study.params))
    params["shifted"][field] = value
    with pytest.raises(ParamsError, match=rule):
        study_from_dict(params, source="bad.yaml")


def test_beyond_box_refuses_a_bad_band_or_a_box_at_the_limits():
    from nfarm.model.robot import load_robot

    robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
    with pytest.raises(ValueError, match=r"band must be in \(0, 0.5\], got 0.6"):
        beyond_box(IKRegion(robot, np.array([[-1.0, 1.0]] * 5)), 10, 0.6, 0)
    with pytest.raises(ValueError, match=r"the region's box lies at every joint's limits"):
        beyond_box(IKRegion.full(robot), 10, 0.05, 0)
