"""Forward kinematics and Jacobians against Pinocchio, finite differences and known poses."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from conftest import random_chains
from nfarm.model.kinematics import (fk, fk_all, jacobian, manipulability, min_singular_value,
                              numerical_jacobian)
from nfarm.model.pinocchio_ref import pinocchio_model
from nfarm.model.robot import sample_configurations

TOL = 1e-12


def reference(P, q):
    """Pinocchio's fk, fk_all and jacobian, one configuration at a time."""
    q = q.reshape(-1, q.shape[-1])
    return (np.array([P.fk(x) for x in q]), np.array([P.fk_all(x) for x in q]),
            np.array([P.jacobian(x) for x in q]))


def assert_matches_pinocchio(robot, q):
    T, frames, J = reference(pinocchio_model(robot), q)
    np.testing.assert_allclose(fk(robot, q), T, rtol=0, atol=TOL)
    np.testing.assert_allclose(fk_all(robot, q), frames, rtol=0, atol=TOL)
    np.testing.assert_allclose(jacobian(robot, q), J, rtol=0, atol=TOL)


def test_shipped_robots_match_pinocchio(robot):
    assert_matches_pinocchio(robot, sample_configurations(robot, 200, seed=1))


@given(random_chains(), st.integers(0, 2**32 - 1))
def test_random_chains_match_pinocchio(robot, seed):
    q = np.random.default_rng(seed).uniform(-2 * np.pi, 2 * np.pi, (8, robot.n))
    assert_matches_pinocchio(robot, q)


@given(random_chains(), st.integers(0, 2**32 - 1))
def test_jacobian_equals_central_differences(robot, seed):
    q = np.random.default_rng(seed).uniform(-np.pi, np.pi, (3, robot.n))
    np.testing.assert_allclose(jacobian(robot, q), numerical_jacobian(robot, q), atol=1e-8)


def test_numerical_jacobian_is_a_real_check(intelbot5):
    """Swapping two columns of the analytic Jacobian must be caught at the tolerance used."""
    q = np.radians([10, 20, 30, 40, 50])
    J = jacobian(intelbot5, q)
    assert np.abs(J[:, [1, 0, 2, 3, 4]] - numerical_jacobian(intelbot5, q)).max() > 1e-3
    assert np.abs(J - numerical_jacobian(intelbot5, q)).max() < 1e-9


def test_intelbot5_ready_pose(intelbot5):
    """STUDY.md: at q = 0 the tool centre point is at (0.180, 0, 0.195) m, gripper down."""
    T = fk(intelbot5, np.zeros(5))
    np.testing.assert_allclose(T[:3, 3], [0.180, 0.0, 0.195], atol=1e-15)
    np.testing.assert_allclose(T[:3, 2], [0.0, 0.0, -1.0], atol=1e-15)


@pytest.mark.parametrize("batch", [(), (1,), (7,), (2, 3), (3, 1, 4)])
def test_batch_shapes(intelbot5, batch):
    q = sample_configurations(intelbot5, batch, seed=2)
    n = intelbot5.n
    assert fk(intelbot5, q).shape == (*batch, 4, 4)
    assert fk_all(intelbot5, q).shape == (*batch, n + 1, 4, 4)
    assert jacobian(intelbot5, q).shape == (*batch, 6, n)
    assert manipulability(intelbot5, q).shape == batch
    flat = q.reshape(-1, n)
    np.testing.assert_array_equal(fk(intelbot5, q).reshape(-1, 4, 4), fk(intelbot5, flat))


def test_batches_larger_than_a_chunk_are_exact(intelbot5):
    from nfarm.model import kinematics
    q = sample_configurations(intelbot5, 2 * kinematics.CHUNK + 3, seed=3)
    single = np.array([fk(intelbot5, x) for x in q[-5:]])
    np.testing.assert_array_equal(fk(intelbot5, q)[-5:], single)


@pytest.mark.parametrize("bad", [np.zeros(4), np.zeros((3, 6)), np.float64(0.0)])
def test_wrong_q_shape_is_a_clear_error(intelbot5, bad):
    for f in (fk, fk_all, jacobian):
        with pytest.raises(ValueError, match=r"intelbot5: q must have shape \(\.\.\., 5\)"):
            f(intelbot5, bad)


def test_manipulability_is_yoshikawas_measure(robot):
    q = sample_configurations(robot, 50, seed=4)
    J = jacobian(robot, q)
    Jp = J[:, :3]
    np.testing.assert_allclose(manipulability(robot, q),
                               np.sqrt(np.linalg.det(Jp @ np.swapaxes(Jp, 1, 2))), rtol=1e-9)
    full = np.sqrt(np.linalg.det(np.swapaxes(J, 1, 2) @ J)) if robot.n < 6 else \
        np.sqrt(np.abs(np.linalg.det(J @ np.swapaxes(J, 1, 2))))
    np.testing.assert_allclose(manipulability(robot, q, part="full"), full, rtol=1e-8)
    sigma = np.linalg.svd(Jp, compute_uv=False)[:, -1]
    np.testing.assert_allclose(min_singular_value(robot, q), sigma, rtol=1e-12)


def test_intelbot5_singularities(intelbot5):
    """Elbow stretched (q3 = ±90°, upper arm and forearm in line) and the wrist centre on the
    base axis are position singularities: w = 0 there, and only there, along a sweep."""
    q = np.zeros((181, 5))
    q[:, 2] = np.radians(np.arange(-90, 91))
    q[:, 3] = -q[:, 2]  # keep the tool pointing along the forearm: the arm stretches fully
    w = manipulability(intelbot5, q)
    assert w[0] < 1e-12 and w[-1] < 1e-12
    assert np.all(w[1:-1] > 1e-6)
    with pytest.raises(ValueError, match="part must be one of"):
        manipulability(intelbot5, q, part="linear")


@pytest.mark.parametrize("q, kind", [("abcde", "text"), ([True] * 5, "booleans"),
                                     (np.zeros(5) + 1j, "complex numbers"), ([None] * 5, "objects")])
def test_fk_refuses_what_is_not_real_numbers(intelbot5, q, kind):
    """Not cast: a complex angle's imaginary part would be dropped, None would become NaN."""
    with pytest.raises(ValueError, match=f"intelbot5: q must hold real numbers, got {kind}"):
        fk(intelbot5, q)


def test_a_base_places_the_chain_in_the_world(intelbot5):
    """With a base B: poses are B · (the chain's), frame 0 is B, the Jacobian's rows turn with
    B's rotation, and the torques for gravity turned by B equal those without a base; a file
    without a base keeps its hash, one with a bad base is refused."""
    import dataclasses

    from nfarm.model.dynamics import rnea
    from nfarm.infra.reading import ParamsError
    from nfarm.model.robot import robot_from_dict, robot_hash, robot_to_dict
    from nfarm.model.rotations import quat_to_matrix

    rng = np.random.default_rng(7)
    B = np.eye(4)
    B[:3, :3] = quat_to_matrix(rng.normal(size=4))
    B[:3, 3] = [0.3, -0.2, 0.1]
    placed = dataclasses.replace(intelbot5, base=B)
    q = sample_configurations(intelbot5, (20,), rng)
    np.testing.assert_allclose(fk(placed, q), B @ fk(intelbot5, q), atol=1e-12)
    np.testing.assert_allclose(fk_all(placed, q)[:, 0], np.broadcast_to(B, (20, 4, 4)), atol=1e-15)
    R6 = np.kron(np.eye(2), B[:3, :3])
    np.testing.assert_allclose(jacobian(placed, q), R6 @ jacobian(intelbot5, q), atol=1e-12)
    qd, qdd = rng.normal(size=(2, 20, 5))
    np.testing.assert_allclose(rnea(placed, q, qd, qdd, gravity=B[:3, :3] @ intelbot5.gravity),
                               rnea(intelbot5, q, qd, qdd), atol=1e-12)
    f = rng.normal(size=(20, 6))
    extra = rnea(placed, q, qd, qdd, f_tip=f) - rnea(placed, q, qd, qdd)
    np.testing.assert_allclose(extra, np.einsum("nki,nk->ni", jacobian(placed, q), f), atol=1e-12)
    data = robot_to_dict(intelbot5)
    assert "base" not in data and robot_hash(robot_from_dict(data)) == robot_hash(intelbot5)
    assert robot_from_dict(robot_to_dict(placed)).base.tolist() == B.tolist()
    with pytest.raises(ParamsError, match=r"base: .*determinant|base: .*orthonormal"):
        robot_from_dict({**data, "base": np.diag([1.0, 1.0, -1.0, 1.0]).tolist()})


@given(st.integers(0, 2**32 - 1))
def test_dh_transform_is_the_product_of_its_four_motions_batched(seed):
    """A = Rz(θ) Tz(d) Tx(a) Rx(α), the rotations from SciPy, for arguments that broadcast."""
    from scipy.spatial.transform import Rotation

    from nfarm.model.kinematics import dh_transform

    rng = np.random.default_rng(seed)
    a, d = rng.normal(size=(3, 1)), rng.normal(size=(1, 4))
    alpha, theta = rng.uniform(-np.pi, np.pi, (3, 4)), rng.uniform(-np.pi, np.pi)

    def motion(rotation=None, along=None, by=0.0):
        T = np.eye(4)
        if rotation is not None:
            T[:3, :3] = Rotation.from_euler(*rotation).as_matrix()
        if along is not None:
            T["xyz".index(along), 3] = by
        return T

    A = dh_transform(a, alpha, d, theta)
    assert A.shape == (3, 4, 4, 4)
    for i in range(3):
        for j in range(4):
            expected = (motion(("z", theta)) @ motion(along="z", by=d[0, j]) @ motion(along="x", by=a[i, 0])
                        @ motion(("x", alpha[i, j])))
            np.testing.assert_allclose(A[i, j], expected, rtol=0, atol=1e-14)
