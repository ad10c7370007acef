"""Poses held relative to the arm's plane (nfarm.solvers.tool_paths): reached exactly by the closed form
and by LM on both study arms, the reference pose unchanged, bad input refused in one line."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm import ik
from nfarm.solvers.geometric_ik import branch_margins
from nfarm.model.kinematics import fk
from nfarm.infra.paths import ROOT
from nfarm.model.robot import robot_from_dict, sample_configurations
from nfarm.solvers.tool_paths import plane_held_poses

from conftest import load_quietly

ARMS = ["intelbot5", "so101"]


def _arm(name):
    return load_quietly(ROOT / "params" / "robots" / f"{name}.yaml")


def _reference(robot, seed):
    """A configuration [rad] away from its joint limits and from where its branch meets
    another (a bent elbow, the wrist ahead of the base axis): small paths about its tool point
    stay in the pose set."""
    q = sample_configurations(robot, 500, seed)
    lo, hi = robot.qlim[:, 0], robot.qlim[:, 1]
    margins = branch_margins(robot, q)
    ok = ((margins["elbow"] > np.radians(40)) & (margins["wrist"] > 0.08)
          & ((q > lo + 0.2 * (hi - lo)) & (q < hi - 0.2 * (hi - lo))).all(axis=1))
    assert ok.any()
    return q[np.argmax(ok)]


def _line_and_circle(p, radius=0.03, steps=40):
    """A horizontal circle and a slanted line about ``p`` [m]."""
    angle = np.linspace(0, 2 * np.pi, steps)
    circle = p + radius * np.column_stack([np.cos(angle), np.sin(angle), np.zeros(steps)])
    line = p + np.linspace(-1, 1, steps)[:, None] * np.array([0.02, 0.03, 0.02])
    return np.vstack([circle, line])


@pytest.mark.parametrize("name", ARMS)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_every_pose_is_in_the_arms_pose_set(name, seed):
    robot = _arm(name)
    rng = np.random.default_rng(seed)
    q_ref = _reference(robot, seed)
    x = _line_and_circle(fk(robot, q_ref)[:3, 3] + rng.normal(0, 0.002, 3), radius=0.02)
    T = plane_held_poses(robot, q_ref, x)
    np.testing.assert_array_equal(T[:, :3, 3], x)
    R = T[:, :3, :3]
    np.testing.assert_allclose(R @ np.swapaxes(R, 1, 2), np.broadcast_to(np.eye(3), R.shape), atol=1e-14)
    _, pos, rot = ik.closed_form(robot, T).nearest()
    assert pos.max() < 1e-9 and rot.max() < 1e-9
    lm = ik.solve_path(robot, T, q_ref)                   # an independent solver agrees
    assert lm.success.all()


@pytest.mark.parametrize("name", ARMS)
def test_the_reference_pose_is_kept(name):
    robot = _arm(name)
    q_ref = np.radians([20, 10, -30, 40, 15])
    T_ref = fk(robot, q_ref)
    np.testing.assert_allclose(plane_held_poses(robot, q_ref, T_ref[None, :3, 3])[0], T_ref, atol=1e-13)


def _azimuth_turn(T_ref, positions):
    """The simple construction for an arm whose plane contains the world's z axis: ``T_ref``'s
    orientation turned about z by each position's change of azimuth ``atan2(y, x)``."""
    turn = np.arctan2(positions[:, 1], positions[:, 0]) - np.arctan2(T_ref[1, 3], T_ref[0, 3])
    c, s = np.cos(turn), np.sin(turn)
    Rz = np.zeros((len(positions), 3, 3))
    Rz[:, 0, 0], Rz[:, 0, 1], Rz[:, 1, 0], Rz[:, 1, 1], Rz[:, 2, 2] = c, -s, s, c, 1.0
    out = np.tile(np.eye(4), (len(positions), 1, 1))
    out[:, :3, :3] = Rz @ T_ref[:3, :3]
    out[:, :3, 3] = positions
    return out


def test_on_intelbot5_it_is_the_azimuth_turn():
    """intelbot5's plane contains the world's z axis: the general construction is the turn by
    the change of azimuth."""
    robot = _arm("intelbot5")
    q_ref = np.radians([10, 20, 30, -20, 15])
    x = _line_and_circle(fk(robot, q_ref)[:3, 3])
    np.testing.assert_allclose(plane_held_poses(robot, q_ref, x), _azimuth_turn(fk(robot, q_ref), x), atol=1e-12)


def test_where_the_azimuth_turn_leaves_the_so101s_pose_set_this_does_not():
    robot = _arm("so101")
    q_ref = _reference(robot, 0)
    x = _line_and_circle(fk(robot, q_ref)[:3, 3], radius=0.03)
    _, pos_old, _ = ik.closed_form(robot, _azimuth_turn(fk(robot, q_ref), x)).nearest()
    _, pos_new, _ = ik.closed_form(robot, plane_held_poses(robot, q_ref, x)).nearest()
    assert pos_old.max() > 1e-3 and pos_new.max() < 1e-9


def test_bad_input_is_refused_in_one_line():
    robot = _arm("so101")
    q_ref = np.radians([20, 10, -30, 40, 15])
    with pytest.raises(ValueError, match=r"q_ref must be 5 finite joint angles \[rad\], got shape \(4,\)"):
        plane_held_poses(robot, q_ref[:4], np.zeros((1, 3)))
    with pytest.raises(ValueError, match=r"positions must be finite \(K, 3\) \[m\], got shape \(3,\)"):
        plane_held_poses(robot, q_ref, np.zeros(3))
    with pytest.raises(ValueError, match=r"positions must be finite"):
        plane_held_poses(robot, q_ref, np.full((2, 3), np.nan))
    axis = robot.base[:3, 3]                                # on the base axis: the offset cannot be met
    with pytest.raises(ValueError, match=r"positions\[1\] = .* is nearer the base axis than the arm's plane offset"):
        plane_held_poses(robot, q_ref, np.vstack([fk(robot, q_ref)[:3, 3], axis]))
    joint = {"alpha": 0.0, "d": 0.0, "offset": 0.0, "qlim": [-3.0, 3.0], "mass": 1.0,
             "com": [0.0, 0.0, 0.0], "inertia": [0.01, 0.01, 0.01, 0.0, 0.0, 0.0]}
    planar = robot_from_dict({"name": "planar", "convention": "standard", "gravity": [0.0, 0.0, -9.81],
                              "joints": [{**joint, "a": 0.3}, {**joint, "a": 0.2}]})
    with pytest.raises(ValueError, match=r"planar: the second joint's axis is parallel to the first's"):
        plane_held_poses(planar, [0.1, 0.2], np.zeros((1, 3)))


def test_the_poses_are_reached_exactly_where_a_fixed_orientation_is_not():
    """Poses keeping the reference's pitch and roll in the arm's plane along a circle: the
    positions asked, orthonormal, and reached by LM; the reference's orientation moved
    sideways is not."""
    robot = _arm("intelbot5")
    q_ref = np.radians([10, 20, 30, -20, 15])
    T_ref = fk(robot, q_ref)
    angle = np.linspace(0, 2 * np.pi, 24)
    circle = T_ref[:3, 3] + 0.04 * np.column_stack([np.cos(angle), np.sin(angle), 0 * angle])
    T = plane_held_poses(robot, q_ref, circle)
    np.testing.assert_allclose(T[:, :3, 3], circle, atol=1e-15)
    np.testing.assert_allclose(T[:, :3, :3] @ np.swapaxes(T[:, :3, :3], 1, 2), np.broadcast_to(np.eye(3), (24, 3, 3)), atol=1e-15)
    assert ik.solve(robot, T).success.all()
    fixed = T.copy()
    fixed[:, :3, :3] = T_ref[:3, :3]
    assert not ik.solve(robot, fixed[[6, 12]], restarts=4).success.any()
