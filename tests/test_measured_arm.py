"""The measured arm is a built arm, not the model (nfarm.study.id_trajectories.true_arm,
with_payload, current_sensed; nfarm.study.datasets.built_arm): its links are drawn once from the
study's seed and stay physically valid, a payload obeys statics and Pinocchio's inertia algebra,
the torque is read in counts of the motor current, and the study file's rules have bad files."""

from __future__ import annotations

import copy
import dataclasses

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from nfarm.infra.paths import PARAMS
from nfarm.infra.reading import ParamsError
from nfarm.model.dynamics import rnea
from nfarm.model.kinematics import fk, jacobian
from nfarm.model.robot import load_robot
from nfarm.study import datasets
from nfarm.study.id_trajectories import TrueArm, current_sensed, true_arm, with_payload
from nfarm.study.study_files import load_study, redrawn, study_from_dict

ROBOTS = ["intelbot5", "so101"]


@pytest.fixture(scope="module", params=ROBOTS)
def robot(request):
    return load_robot(PARAMS / "robots" / f"{request.param}.yaml")


def test_a_built_arm_keeps_its_geometry_and_valid_inertias(robot):
    spec = TrueArm(mass_sd=0.3, com_sd=0.01, inertia_sd=0.3)       # large draws: the clipping must hold
    built = true_arm(robot, spec, np.random.default_rng(3))
    for key in ("a", "alpha", "d", "offset", "qlim", "viscous", "armature"):
        np.testing.assert_array_equal(getattr(built, key), getattr(robot, key))
    assert (np.abs(built.mass / robot.mass - 1) <= 3 * 0.3 + 1e-12).all() and (built.mass > 0).all()
    assert (np.abs(built.com - robot.com) <= 0.03 + 1e-12).all()
    assert not np.allclose(built.mass, robot.mass) and not np.allclose(built.com, robot.com)
    for I in built.inertia:                                        # positive definite, triangle inequalities
        w = np.linalg.eigvalsh(I)
        assert (w > 0).all() and w[0] + w[1] >= w[2] * (1 - 1e-12)      # eigvalsh sorts them
    same = true_arm(robot, spec, np.random.default_rng(3))
    np.testing.assert_array_equal(same.inertia, built.inertia)
    nominal = true_arm(robot, TrueArm(), np.random.default_rng(3))
    np.testing.assert_array_equal(nominal.mass, robot.mass)
    np.testing.assert_array_equal(nominal.com, robot.com)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), mass=st.floats(0.01, 2.0))
def test_a_payload_holds_statically_what_the_tip_force_says(seed, mass):
    """At rest a payload m at the tool point adds Jᵀ f with f = −m g (the tool holds it up)."""
    robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
    q = robot.qlim[:, 0] + (robot.qlim[:, 1] - robot.qlim[:, 0]) * np.random.default_rng(seed).random((4, robot.n))
    zero = np.zeros_like(q)
    wrench = np.concatenate([-mass * robot.gravity, np.zeros(3)])
    np.testing.assert_allclose(rnea(with_payload(robot, mass), q, zero, zero),
                               rnea(robot, q, zero, zero, f_tip=wrench), rtol=1e-10, atol=1e-12)
    # and the same through the Jacobian, an independent path
    np.testing.assert_allclose(rnea(with_payload(robot, mass), q, zero, zero) - rnea(robot, q, zero, zero),
                               np.einsum("...ij,i->...j", jacobian(robot, q), wrench), rtol=1e-10, atol=1e-12)


def test_a_payload_combines_inertias_as_pinocchio_does(robot):
    pin = pytest.importorskip("pinocchio")
    loaded = with_payload(robot, 0.15)
    last = pin.Inertia(float(robot.mass[-1]), robot.com[-1].copy(), robot.inertia[-1].copy())
    point = pin.Inertia(0.15, robot.tool[:3, 3].copy(), np.zeros((3, 3)))
    both = last + point
    assert loaded.mass[-1] == pytest.approx(both.mass, rel=1e-14)
    np.testing.assert_allclose(loaded.com[-1], both.lever, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(loaded.inertia[-1], both.inertia, rtol=1e-10, atol=1e-15)
    np.testing.assert_array_equal(loaded.mass[:-1], robot.mass[:-1])
    assert with_payload(robot, 0.0) is robot


def test_a_current_reading_comes_in_counts():
    rng = np.random.default_rng(0)
    tau = rng.normal(size=(2000, 3))
    count = np.array([0.004, 0.01, 0.02])
    offset = np.array([0.01, -0.02, 0.0])
    read = current_sensed(tau, np.random.default_rng(1), noise=np.full(3, 0.005), torque_per_count=count, offset=offset)
    np.testing.assert_allclose(read / count, np.round(read / count), atol=1e-9)
    error = read - tau - offset
    assert (np.abs(error.mean(axis=0)) < 0.002).all()
    np.testing.assert_allclose(error.std(axis=0), np.sqrt(0.005 ** 2 + count ** 2 / 12), rtol=0.1)
    plain = current_sensed(tau, np.random.default_rng(1), noise=np.full(3, 0.005))
    np.testing.assert_array_equal(plain, tau + 0.005 * np.random.default_rng(1).standard_normal(tau.shape))


@pytest.mark.parametrize("name", ROBOTS)
def test_each_draw_of_the_data_is_another_arm_built_and_a_reader_rebuilds_it_from_the_seed(name):
    """Issue 65: a finalist's spread over its draws covers the arm as built. Draw k's arm is the study
    file's with its seed plus k (a reader rebuilds it by editing the seed), another draw of the same
    declared tolerances: its links and offsets differ from draw 0's, its geometry and drives do not."""
    study = load_study(PARAMS / "studies" / f"{name}.yaml")
    arm, offset = datasets.built_arm(study)
    assert not np.allclose(arm.mass, study.robot.mass)
    assert np.abs(offset).max() > 0 and np.abs(offset).max() <= 3 * study.id.offset_sd.max()
    again, offset_again = datasets.built_arm(redrawn(study, 3))
    assert not np.allclose(again.mass, arm.mass) and not np.allclose(again.inertia, arm.inertia)
    assert not np.allclose(offset_again, offset)
    np.testing.assert_array_equal(again.a, arm.a)
    np.testing.assert_array_equal(again.d, arm.d)
    np.testing.assert_array_equal(again.viscous, arm.viscous)
    relative = np.abs(again.mass / study.robot.mass - 1)
    assert relative.max() <= 3 * study.id.true_arm.mass_sd + 1e-12, "within the declared tolerances"
    other = yaml.safe_load((PARAMS / "studies" / f"{name}.yaml").read_text())
    other["seed"] = study.seed + 3
    rebuilt, rebuilt_offset = datasets.built_arm(study_from_dict(other))
    np.testing.assert_array_equal(rebuilt.inertia, again.inertia)
    np.testing.assert_array_equal(rebuilt_offset, offset_again)
    without = copy.deepcopy(other)
    del without["id"]["measured"]
    with pytest.raises(ValueError, match="declares no measured arm"):
        datasets.built_arm(study_from_dict(without))


BAD = [
    (("true_arm", "mass_sd"), 0.4, r"id.measured.true_arm.mass_sd"),
    (("true_arm", "inertia_sd"), -0.1, r"id.measured.true_arm.inertia_sd"),
    (("true_arm", "payload_kg"), "heavy", r"id.measured.true_arm.payload_kg"),
    (("true_arm", "spin"), 1, r"id.measured.true_arm.*spin"),
    (("sensor", "current_per_count_a"), 0, r"id.measured.sensor.current_per_count_a"),
    (("sensor", "torque_constant_nm_a"), [1, 2], r"id.measured.sensor.torque_constant_nm_a"),
    (("sensor", "offset_sd_nm"), -1, r"id.measured.sensor.offset_sd_nm"),
]


@pytest.mark.parametrize("where, value, message", BAD)
def test_a_bad_measured_arm_is_refused_in_one_line(where, value, message):
    data = yaml.safe_load((PARAMS / "studies" / "intelbot5.yaml").read_text())
    data["id"]["measured"][where[0]][where[1]] = value
    with pytest.raises(ParamsError, match=message) as caught:
        study_from_dict(data, source="bad.yaml")
    assert "\n" not in str(caught.value)


def test_a_built_arm_without_a_sensor_has_no_offsets():
    data = yaml.safe_load((PARAMS / "studies" / "intelbot5.yaml").read_text())
    del data["id"]["measured"]["sensor"]
    study = study_from_dict(data)
    assert study.id.torque_per_count is None
    _, offset = datasets.built_arm(study)
    np.testing.assert_array_equal(offset, np.zeros(study.robot.n))
    assert dataclasses.is_dataclass(study.id.true_arm)
