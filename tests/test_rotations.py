"""Rotation conversions: round trips, canonical signs, angles near π, and the pose error."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from scipy.spatial.transform import Rotation

from nfarm.model.rotations import (exp_so3, log_so3, matrix_to_quat, matrix_to_rpy, pose_error,
                             quat_to_matrix, quat_to_rpy, rpy_to_matrix, rpy_to_quat)

unit_vectors = arrays(float, 3, elements=st.floats(-1, 1)).filter(
    lambda v: np.linalg.norm(v) > 1e-3).map(lambda v: v / np.linalg.norm(v))
# Angles spread over [0, π], with many right next to π where log maps go wrong.
angles = st.one_of(st.floats(0, np.pi), st.floats(np.pi - 1e-6, np.pi),
                   st.sampled_from([0.0, 1e-12, np.pi - 1e-12, np.pi]))


def rotation(axis, angle):
    return exp_so3(axis * angle)


def assert_rotation(R):
    np.testing.assert_allclose(R @ np.swapaxes(R, -1, -2), np.eye(3), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-14)


@given(unit_vectors, angles)
def test_quaternion_round_trip_and_canonical_sign(axis, angle):
    R = rotation(axis, angle)
    quat = matrix_to_quat(R)
    assert quat[0] >= 0
    np.testing.assert_allclose(np.linalg.norm(quat), 1.0, atol=1e-15)
    np.testing.assert_allclose(quat_to_matrix(quat), R, atol=1e-14)
    np.testing.assert_allclose(quat, [np.cos(angle / 2), *(np.sin(angle / 2) * axis)], atol=1e-12
                               ) if np.cos(angle / 2) > 1e-6 else None


def test_quaternion_of_a_half_turn_is_canonical():
    """w = 0: the sign is fixed by the first non-zero of x, y, z (positive)."""
    for axis in np.eye(3):
        half_turn = 2 * np.outer(axis, axis) - np.eye(3)  # exactly w = 0
        np.testing.assert_array_equal(matrix_to_quat(half_turn), [0.0, *axis])


@given(unit_vectors, angles)
def test_log_exp_round_trip_near_pi(axis, angle):
    R = rotation(axis, angle)
    omega = log_so3(R)
    theta = np.linalg.norm(omega)
    assert 0 <= theta <= np.pi + 1e-12
    np.testing.assert_allclose(theta, angle, atol=1e-9)
    np.testing.assert_allclose(exp_so3(omega), R, atol=1e-12)


@given(arrays(float, 3, elements=st.floats(-np.pi, np.pi)))
def test_rpy_round_trip(rpy):
    R = rpy_to_matrix(rpy)
    assert_rotation(R)
    np.testing.assert_allclose(rpy_to_matrix(matrix_to_rpy(R)), R, atol=1e-12)
    quat = rpy_to_quat(rpy)
    np.testing.assert_allclose(quat, matrix_to_quat(R), atol=1e-15)
    np.testing.assert_allclose(rpy_to_matrix(quat_to_rpy(quat)), R, atol=1e-12)


def test_rpy_is_zyx_and_gimbal_lock_is_handled():
    roll, pitch, yaw = 0.3, -0.4, 1.1
    Rx = np.array([[1, 0, 0], [0, np.cos(roll), -np.sin(roll)], [0, np.sin(roll), np.cos(roll)]])
    Ry = np.array([[np.cos(pitch), 0, np.sin(pitch)], [0, 1, 0], [-np.sin(pitch), 0, np.cos(pitch)]])
    Rz = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
    np.testing.assert_allclose(rpy_to_matrix([roll, pitch, yaw]), Rz @ Ry @ Rx, atol=1e-15)
    locked = rpy_to_matrix([0.2, np.pi / 2, 0.7])
    np.testing.assert_allclose(rpy_to_matrix(matrix_to_rpy(locked)), locked, atol=1e-12)


def test_batched_shapes():
    R = exp_so3(np.random.default_rng(0).normal(size=(2, 3, 3)))
    assert matrix_to_quat(R).shape == (2, 3, 4)
    assert matrix_to_rpy(R).shape == (2, 3, 3)
    assert log_so3(R).shape == (2, 3, 3)
    np.testing.assert_allclose(quat_to_matrix(matrix_to_quat(R)), R, atol=1e-14)


@pytest.mark.parametrize("func, bad", [(matrix_to_quat, np.eye(4)), (quat_to_matrix, np.ones(3)),
                                       (rpy_to_matrix, np.ones(4)), (exp_so3, np.ones(2))])
def test_wrong_shapes_are_clear_errors(func, bad):
    with pytest.raises(ValueError, match="expected"):
        func(bad)


@given(unit_vectors, angles, arrays(float, 3, elements=st.floats(-1, 1)))
def test_pose_error(axis, angle, dp):
    T_b = np.eye(4)
    T_b[:3, :3] = rotation(np.array([0.0, 0.6, 0.8]), 0.9)
    T_b[:3, 3] = [0.1, -0.2, 0.3]
    T_a = np.eye(4)
    T_a[:3, :3] = rotation(axis, angle) @ T_b[:3, :3]
    T_a[:3, 3] = T_b[:3, 3] + dp
    e = pose_error(T_a, T_b)
    np.testing.assert_allclose(e[:3], dp, atol=1e-15)
    np.testing.assert_allclose(exp_so3(e[3:]) @ T_b[:3, :3], T_a[:3, :3], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(e[3:]), angle, atol=1e-9)
    np.testing.assert_allclose(pose_error(T_b, T_b), np.zeros(6), atol=1e-16)


def test_log_map_matches_scipy_everywhere_including_next_to_pi():
    """The hand-written log map against SciPy's as_rotvec, on random rotations and on angles
    within 1e-12 … 0.5 rad of π and of 0, about random axes."""
    rng = np.random.default_rng(7)
    axes = rng.normal(size=(4000, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    gaps = np.concatenate([np.zeros(1), 10.0 ** rng.uniform(-12, np.log10(0.5), 1999)])
    angles = np.concatenate([np.pi - gaps, gaps, rng.uniform(0, np.pi, 0)])
    R = exp_so3(axes[: angles.size] * angles[:, None])
    R = np.concatenate([R, Rotation.random(1000, rng=rng).as_matrix()])
    ours, theirs = log_so3(R), Rotation.from_matrix(R).as_rotvec()
    # At θ = π exactly, ±u are the same rotation: compare the rotations there.
    np.testing.assert_allclose(exp_so3(ours), R, atol=1e-13)
    same_sign = np.einsum("ij,ij->i", ours, theirs) > 0
    np.testing.assert_allclose(ours[same_sign], theirs[same_sign], atol=1e-9)
    assert same_sign.mean() > 0.99


def test_relative_log_matches_scipy():
    """The log of R_a R_bᵀ against SciPy's alone (its exp to build the rotations, its as_rotvec and
    from_rotvec to judge them): random, tiny and next-to-π relative rotations."""
    from nfarm.model.rotations import relative_log_T
    rng = np.random.default_rng(3)
    R_b = Rotation.random(3000, rng=rng).as_matrix()
    delta = np.concatenate([Rotation.random(1000, rng=rng).as_rotvec(),
                            rng.normal(size=(1000, 3)) * 1e-7,
                            exp_axis_angle_near_pi(rng, 1000)])
    R_a = Rotation.from_rotvec(delta).as_matrix() @ R_b
    components = lambda R: np.ascontiguousarray(np.moveaxis(R, 0, -1))  # noqa: E731
    ours = relative_log_T(components(R_a), components(R_b)).T
    relative = R_a @ np.swapaxes(R_b, 1, 2)
    # the same rotation everywhere (at π ± the axis is the same rotation) ...
    np.testing.assert_allclose(Rotation.from_rotvec(ours).as_matrix(), relative, atol=1e-13)
    # ... and SciPy's rotation vector, and the one it was built from, where the log is unique (angle < π)
    np.testing.assert_allclose(ours[:2000], Rotation.from_matrix(relative[:2000]).as_rotvec(), rtol=0, atol=1e-12)
    np.testing.assert_allclose(ours[:2000], delta[:2000], rtol=0, atol=1e-12)
    near_pi = np.linalg.norm(ours[2000:], axis=1)
    np.testing.assert_allclose(near_pi, np.linalg.norm(delta[2000:], axis=1), rtol=0, atol=1e-7)


def exp_axis_angle_near_pi(rng, count):
    axes = rng.normal(size=(count, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    return axes * (np.pi - 10.0 ** rng.uniform(-10, -1, (count, 1)))
