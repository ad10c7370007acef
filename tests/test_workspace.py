"""Singular configurations computed from an arm's geometry (nfarm.solvers.workspace): the elbow's links
in line and the tool point on that line, for every shipped arm in the closed form's class."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm.model.kinematics import fk, fk_all, min_singular_value
from nfarm.infra.paths import PARAMS
from nfarm.model.robot import load_robot
from nfarm.solvers.workspace import near_stretched, singular_configurations


@pytest.mark.parametrize("name, stretched_elbow_deg", [("intelbot5", 90.0), ("so101", -73.82)])
def test_the_stretched_arm_is_singular_and_one_degree_inward_is_not(name, stretched_elbow_deg):
    robot = load_robot(PARAMS / "robots" / f"{name}.yaml")
    named, note = singular_configurations(robot)
    assert note == "" and "arm stretched" in named
    q = named["arm stretched"]
    assert np.degrees(q[2]) == pytest.approx(stretched_elbow_deg, abs=0.01)
    assert np.all((robot.qlim[:, 0] <= q) & (q <= robot.qlim[:, 1]))
    ready = float(min_singular_value(robot, named["ready (q = 0)"], part="full"))
    assert float(min_singular_value(robot, q, part="full")) < 1e-12 * max(ready, 1.0)   # rank lost
    # the tool point on the line through the shoulder and wrist axes (standard DH: frames 1 and 3)
    frames, tool = fk_all(robot, q), fk(robot, q)[:3, 3]
    p2, p4 = frames[1, :3, 3], frames[3, :3, 3]
    u = (p4 - p2) / np.linalg.norm(p4 - p2)
    assert abs(np.dot(frames[1, :3, 2], np.cross(u, tool - p2))) < 1e-12
    near = near_stretched(robot, q, 1.0)
    assert abs(np.degrees(near[2] - q[2])) == pytest.approx(1.0) and robot.qlim[2, 0] <= near[2] <= robot.qlim[2, 1]
    assert float(min_singular_value(robot, near, part="full")) > 1e3 * float(min_singular_value(robot, q, part="full"))


def test_an_arm_outside_the_class_gets_its_ready_pose_and_a_note(puma560):
    named, note = singular_configurations(puma560)
    assert list(named) == ["ready (q = 0)"] and note.startswith("No stretched or folded configuration is computed for")


@pytest.mark.parametrize("degrees", [0, -1, 90, float("nan")])
def test_near_stretched_refuses_a_distance_that_is_not_a_small_angle(degrees):
    robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
    with pytest.raises(ValueError, match=r"must be in \(0, 90\)"):
        near_stretched(robot, np.zeros(robot.n), degrees)
