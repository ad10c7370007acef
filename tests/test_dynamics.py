"""Inverse dynamics against Pinocchio and against identities of rigid-body mechanics."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given
from hypothesis import strategies as st

from conftest import random_chains
import dataclasses
import math

from nfarm.model.dynamics import (coriolis, gravity_torques, inertial_parameters, joint_drive_torques, stribeck_drive_torques,
                            mass_matrix, regressor, rnea)
from nfarm.model.kinematics import jacobian
from nfarm.model.pinocchio_ref import pinocchio_model
from nfarm.infra.reading import ParamsError
from nfarm.model.robot import robot_from_dict, robot_hash, robot_to_dict, sample_configurations
from nfarm.solvers.trajectory import quintic

RTOL = 1e-10


def states(robot, count, seed):
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, (count, robot.n))
    return q, rng.normal(size=(count, robot.n)) * 2, rng.normal(size=(count, robot.n)) * 5


def assert_close(actual, expected):
    scale = max(1.0, float(np.abs(expected).max()))
    np.testing.assert_allclose(actual, expected, rtol=0, atol=RTOL * scale)


def full(M_upper):
    return np.triu(M_upper) + np.triu(M_upper, 1).T


def check_against_pinocchio(robot, seed):
    P = pinocchio_model(robot)
    m, d = P.model, P.data
    q, qd, qdd = states(robot, 20, seed)
    assert_close(rnea(robot, q, qd, qdd), np.array([pin.rnea(m, d, *x) for x in zip(q, qd, qdd)]))
    assert_close(mass_matrix(robot, q), np.array([full(pin.crba(m, d, x)) for x in q]))
    assert_close(gravity_torques(robot, q), np.array([pin.computeGeneralizedGravity(m, d, x) for x in q]))
    zero = np.zeros(robot.n)
    expected_c = np.array([pin.rnea(m, d, a, b, zero) - pin.computeGeneralizedGravity(m, d, a) for a, b in zip(q, qd)])
    assert_close(coriolis(robot, q, qd), expected_c)


def test_shipped_robots_match_pinocchio(robot):
    check_against_pinocchio(robot, seed=1)


@given(random_chains(), st.integers(0, 2**32 - 1))
def test_random_chains_match_pinocchio(robot, seed):
    check_against_pinocchio(robot, seed)


def test_puma560_published_gravity_check_values(puma560):
    """Corke's published Puma 560 check (Robotics Toolbox, puma560 model): at q = (0, π/4, −π, 0, π/4, 0), g ≈ (0, 31.64, 6.035, 0, 0.0283, 0)."""
    for q3 in (-np.pi, np.pi):
        g = gravity_torques(puma560, [0, np.pi / 4, q3, 0, np.pi / 4, 0])
        np.testing.assert_allclose(g, [0, 31.64, 6.035, 0, 0.0283, 0], atol=5e-3)


def test_tip_wrench_adds_jacobian_transpose(robot):
    """τ(f_tip) − τ(0) = Jᵀ f_tip (virtual work), and Pinocchio's external forces agree."""
    q, qd, qdd = states(robot, 10, 3)
    wrench = np.random.default_rng(4).normal(size=(10, 6)) * [10, 10, 10, 1, 1, 1]
    difference = rnea(robot, q, qd, qdd, f_tip=wrench) - rnea(robot, q, qd, qdd)
    assert_close(difference, np.einsum("mki,mk->mi", jacobian(robot, q), wrench))
    P = pinocchio_model(robot)
    frame = P.model.frames[P.tool_id]
    for k in range(3):
        pin.framesForwardKinematics(P.model, P.data, q[k])
        oMf = P.data.oMf[P.tool_id]
        on_robot = pin.Force(-wrench[k, :3], -wrench[k, 3:])                 # world-aligned, at the tool
        at_tool = pin.SE3(oMf.rotation, np.zeros(3)).actInv(on_robot)         # tool axes
        at_joint = frame.placement.act(at_tool)                               # parent joint frame
        fext = [pin.Force.Zero() for _ in range(P.model.njoints)]
        fext[frame.parentJoint] = at_joint
        expected = pin.rnea(P.model, P.data, q[k], qd[k], qdd[k], fext)
        assert_close(rnea(robot, q[k], qd[k], qdd[k], f_tip=wrench[k]), expected)


def test_mass_matrix_is_symmetric_positive_definite(robot):
    M = mass_matrix(robot, sample_configurations(robot, 200, 5))
    np.testing.assert_allclose(M, np.swapaxes(M, -1, -2), atol=1e-14)
    assert np.linalg.eigvalsh(M).min() > 0


def test_kinetic_energy_rate_equals_power_of_non_gravity_torques(intelbot5):
    """Along any motion, d/dt ½ q̇ᵀ M q̇ = q̇ᵀ (τ − g(q)) (the Coriolis terms do no work)."""
    trajectory = quintic(np.zeros(5), np.radians([80, 40, -70, 50, 120]), 0, 0, 0.0, 2.0, 1e-3)
    q, qd, qdd = trajectory.q, trajectory.qd, trajectory.qdd
    tau = rnea(intelbot5, q, qd, qdd)
    kinetic = 0.5 * np.einsum("ki,kij,kj->k", qd, mass_matrix(intelbot5, q), qd)
    rate = np.gradient(kinetic, trajectory.t)
    power = np.einsum("ki,ki->k", qd, tau - gravity_torques(intelbot5, q))
    np.testing.assert_allclose(rate[2:-2], power[2:-2], atol=1e-5 * np.abs(power).max())


def test_batch_shapes_and_broadcasting(intelbot5):
    q = sample_configurations(intelbot5, (2, 3), 6)
    assert rnea(intelbot5, q, np.zeros(5), np.zeros(5)).shape == (2, 3, 5)
    assert mass_matrix(intelbot5, q).shape == (2, 3, 5, 5)
    assert rnea(intelbot5, np.zeros(5), np.zeros(5), np.zeros(5)).shape == (5,)
    single = rnea(intelbot5, q[1, 2], q[0, 0], q[0, 1])
    np.testing.assert_array_equal(rnea(intelbot5, q, q[0, 0], q[0, 1])[1, 2], single)


def test_gravity_override(intelbot5):
    q = sample_configurations(intelbot5, 5, 7)
    zero = np.zeros(5)
    np.testing.assert_allclose(rnea(intelbot5, q, zero, zero, gravity=np.zeros(3)), 0, atol=1e-15)
    np.testing.assert_allclose(rnea(intelbot5, q, zero, zero, gravity=2 * intelbot5.gravity),
                               2 * gravity_torques(intelbot5, q), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("kwargs, message", [
    (dict(q=np.zeros(4)), r"q must have shape \(\.\.\., 5\)"),
    (dict(qd=np.zeros((2, 5)), q=np.zeros((3, 5))), r"batch shapes do not broadcast"),
    (dict(gravity=[0, 9.81]), r"gravity must be 3 finite numbers"),
    (dict(f_tip=np.zeros(3)), r"f_tip must have shape \(\.\.\., 6\)"),
])
def test_bad_input(intelbot5, kwargs, message):
    args = dict(q=np.zeros(5), qd=np.zeros(5), qdd=np.zeros(5)) | kwargs
    with pytest.raises(ValueError, match=message):
        rnea(intelbot5, args.pop("q"), args.pop("qd"), args.pop("qdd"), **args)


# -- joint drives: armature and friction -----------------------------------------------------


def with_drives(robot, seed=0, friction=True):
    rng = np.random.default_rng(seed)
    n = robot.n
    return dataclasses.replace(
        robot, armature=rng.uniform(0.01, 0.2, n),
        viscous=rng.uniform(0.05, 0.5, n) if friction else np.zeros(n),
        coulomb=rng.uniform(0.05, 0.8, n) if friction else np.zeros(n),
        coulomb_velocity=rng.uniform(0.005, 0.05, n))


def test_armature_matches_pinocchio(intelbot5, puma560):
    """Pinocchio's rnea adds model.armature · q̈: the same robot with armature only."""
    for robot in (intelbot5, puma560):
        driven = with_drives(robot, friction=False)
        P = pinocchio_model(driven, armature=True)
        assert np.array_equal(P.model.armature, driven.armature)
        q, qd, qdd = states(robot, 20, 1)
        expected = np.array([pin.rnea(P.model, P.data, *x) for x in zip(q, qd, qdd)])
        assert_close(rnea(driven, q, qd, qdd, drive=True), expected)
        assert_close(rnea(driven, q, qd, qdd), rnea(robot, q, qd, qdd))      # off by default


def test_drive_torques_follow_the_formula_joint_by_joint(intelbot5):
    driven = with_drives(intelbot5, seed=2)
    q, qd, qdd = states(intelbot5, 30, 3)
    expected = np.array([[driven.armature[i] * b[i] + driven.viscous[i] * a[i] +
                          driven.coulomb[i] * math.tanh(a[i] / driven.coulomb_velocity[i])
                          for i in range(intelbot5.n)] for a, b in zip(qd, qdd)])
    np.testing.assert_allclose(joint_drive_torques(driven, qd, qdd), expected, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(rnea(driven, q, qd, qdd, drive=True) - rnea(driven, q, qd, qdd),
                               expected, rtol=0, atol=1e-12)


def test_friction_dissipates_and_is_smooth_at_rest(intelbot5):
    driven = with_drives(intelbot5, seed=4)
    zero = np.zeros(intelbot5.n)
    qd = np.random.default_rng(5).normal(size=(200, intelbot5.n)) * 2
    friction = joint_drive_torques(driven, qd, zero)
    assert (qd * friction >= 0).all(), "friction never does positive work"
    # Far above the smoothing speed Coulomb friction is τ_c sign(q̇); at rest its slope is
    # b + τ_c/ε (central differences).
    fast = np.full(intelbot5.n, 50.0) * np.sign(qd[0])
    np.testing.assert_allclose(joint_drive_torques(driven, fast, zero),
                               driven.viscous * fast + driven.coulomb * np.sign(fast), rtol=1e-12)
    h = 1e-6
    slope = (joint_drive_torques(driven, zero + h, zero) - joint_drive_torques(driven, zero - h, zero)) / (2 * h)
    np.testing.assert_allclose(slope, driven.viscous + driven.coulomb / driven.coulomb_velocity, rtol=1e-6)


def test_drive_fields_load_validate_and_keep_old_hashes(intelbot5):
    data = robot_to_dict(intelbot5)
    assert not any(k in j for j in data["joints"] for k in ("viscous", "coulomb", "armature")), \
        "a robot without drive terms writes none (its hash, data sets and models stay valid)"
    assert robot_hash(robot_from_dict(data)) == robot_hash(intelbot5)
    data["joints"][1].update(viscous=0.3, coulomb=0.5, coulomb_velocity=0.02, armature=0.04)
    loaded = robot_from_dict(data)
    assert (loaded.viscous[1], loaded.coulomb[1], loaded.armature[1]) == (0.3, 0.5, 0.04)
    assert loaded.viscous[0] == 0 and loaded.coulomb_velocity[0] == 0.01
    assert robot_to_dict(loaded)["joints"][1]["armature"] == 0.04
    assert robot_hash(loaded) != robot_hash(intelbot5)
    for key, value, rule in (("viscous", -0.1, ">= 0"), ("coulomb", "x", "must be a number"),
                             ("coulomb_velocity", 0, "> 0"), ("armature", float("nan"), "finite")):
        bad = robot_to_dict(intelbot5)
        bad["joints"][2][key] = value
        with pytest.raises(ParamsError, match=rf"joints\[2\]\.{key}: .*{rule}"):
            robot_from_dict(bad, source="x.yaml")


# -- the dynamic regressor ---------------------------------------------------------------------

#: Pinocchio orders a link's inertia Ixx, Ixy, Iyy, Ixz, Iyz, Izz; nfarm Ixx, Ixy, Ixz, Iyy, Iyz, Izz.
_PIN_ORDER = np.array([0, 1, 2, 3, 4, 5, 7, 6, 8, 9])


def check_regressor(robot, seed):
    P = pinocchio_model(robot)
    q, qd, qdd = states(robot, 8, seed)
    Y = regressor(robot, q, qd, qdd)
    perm = np.concatenate([10 * k + _PIN_ORDER for k in range(robot.n)])
    expected = np.array([pin.computeJointTorqueRegressor(P.model, P.data, *x)
                         .reshape(robot.n, -1)[:, perm] for x in zip(q, qd, qdd)])
    assert_close(Y, expected)
    assert_close(Y @ inertial_parameters(robot), rnea(robot, q, qd, qdd))


def test_regressor_matches_pinocchio(robot):
    check_regressor(robot, seed=3)


@given(random_chains(), st.integers(0, 2**32 - 1))
def test_random_chains_regressor_matches_pinocchio(robot, seed):
    check_regressor(robot, seed)


def test_regressor_is_linear_in_any_masses(intelbot5):
    """The same regressor gives the torques of the arm with other masses, centres and
    inertias (the geometry alone decides Y), and has the batch shapes of rnea."""
    rng = np.random.default_rng(4)
    n = intelbot5.n
    A = rng.normal(size=(n, 3, 3)) * 0.01
    other = dataclasses.replace(intelbot5, mass=rng.uniform(0.1, 2.0, n),
                                com=rng.normal(size=(n, 3)) * 0.05,
                                inertia=A @ np.swapaxes(A, 1, 2) + 1e-4 * np.eye(3))
    q, qd, qdd = states(intelbot5, 6, 5)
    Y = regressor(intelbot5, q.reshape(2, 3, n), qd.reshape(2, 3, n), qdd.reshape(2, 3, n))
    assert Y.shape == (2, 3, n, 10 * n)
    assert_close(Y @ inertial_parameters(other), rnea(other, q, qd, qdd).reshape(2, 3, n))
    assert regressor(intelbot5, q[0], qd[0], qdd[0]).shape == (n, 10 * n)


def test_stribeck_friction_reduces_to_the_tanh_law_and_dissipates(intelbot5):
    driven = with_drives(intelbot5, seed=6)
    q, qd, qdd = states(intelbot5, 40, 7)
    load = rnea(intelbot5, q, qd, qdd)
    # bit for bit: a study without Stribeck or load terms keeps its data
    np.testing.assert_array_equal(stribeck_drive_torques(driven, qd, qdd, load), joint_drive_torques(driven, qd, qdd))
    law = dict(stribeck=2 * driven.coulomb, stribeck_velocity=np.full(intelbot5.n, 0.2),
               load_coefficient=np.full(intelbot5.n, 0.1))
    zero = np.zeros_like(qd)
    friction = stribeck_drive_torques(driven, qd, zero, load, **law)
    assert (qd * friction >= 0).all(), "friction never does positive work"
    # just above the smoothing speed the friction is near its breakaway level plus the load share;
    # far above the Stribeck speed, the Coulomb level plus the load share
    slow = 5 * driven.coulomb_velocity
    near_rest = stribeck_drive_torques(driven, slow, np.zeros(intelbot5.n), load[0], **law) - driven.viscous * slow
    np.testing.assert_allclose(near_rest, (2 * driven.coulomb * np.exp(-(slow / 0.2) ** 2)
                                           + driven.coulomb * (1 - np.exp(-(slow / 0.2) ** 2))
                                           + 0.1 * np.abs(load[0])) * np.tanh(5.0), rtol=1e-12)
    fast = np.full(intelbot5.n, 30.0)
    np.testing.assert_allclose(stribeck_drive_torques(driven, fast, np.zeros(intelbot5.n), load[0], **law),
                               driven.viscous * fast + driven.coulomb + 0.1 * np.abs(load[0]), rtol=1e-12)
