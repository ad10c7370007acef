"""What an encoding gives before any learning (nfarm.study.ablation, chapter 7's credit table): a
least-squares linear map of the encoding's inputs, exact where the joint is linear in them and
honest where it is not."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm.infra.paths import PARAMS
from nfarm.learning.learned import ik_errors
from nfarm.model.kinematics import fk
from nfarm.model.robot import load_robot, sample_configurations
from nfarm.study.ablation import linear_on_encoding

ROBOT = load_robot(PARAMS / "robots" / "intelbot5.yaml")


@pytest.fixture(scope="module")
def poses():
    q = sample_configurations(ROBOT, 3000, 3) * 0.2          # one branch about home (the front, elbow up)
    return {"T": fk(ROBOT, q), "q": q}


def test_the_arm_plane_gives_the_base_joint_and_the_roll_linearly_and_nothing_else(poses):
    floor = linear_on_encoding(ROBOT, "arm_plane", poses)
    q = floor.predict(poses["T"])
    joint = np.degrees(np.sqrt(((q - poses["q"]) ** 2).mean(axis=0)))
    assert joint[0] < 1e-9 and joint[4] < 1e-9                      # the azimuth and the roll
    assert joint[1:4].min() > 0.05                                  # the pitch joints: not linear in the inputs
    # the dissertation's seven inputs give no joint linearly
    seven = linear_on_encoding(ROBOT, "quat_xyz", poses)
    assert np.degrees(np.abs(seven.predict(poses["T"]) - poses["q"])).max(axis=0).min() > 0.05
    tool = ik_errors(ROBOT, q, poses["q"], poses["T"])["position"]
    assert np.median(tool) > 1e-4                                   # [m]: a linear map is not an IK


def test_bad_training_data_is_refused_in_one_line(poses):
    with pytest.raises(ValueError, match=r"must be \(N, 4, 4\) and \(N, 5\)"):
        linear_on_encoding(ROBOT, "arm_plane", {"T": poses["T"], "q": poses["q"][:10]})
    with pytest.raises(ValueError, match="encoding must be one of"):
        linear_on_encoding(ROBOT, "euler", poses)
