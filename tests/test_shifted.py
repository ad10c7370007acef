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
from nfarm.model.dynamics import rnea
from nfarm.study.shifted import (beyond_box, boundary_distance, describe, describe_id, faster, shifted_id, shifted_ik,
                                 shifted_readings)
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
    ("id_trajectories", 0, r"shifted.id_trajectories"),
    ("id_speed", 1.0, r"shifted.id_speed"),
    ("id_speed", "fast", r"shifted.id_speed"),
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


@pytest.mark.parametrize("arm", STUDIES)
def test_the_shifted_trajectories_run_faster_than_any_the_models_met(arm):
    """Beyond the generator's bounds every split keeps (speeds up to id_speed times them, accelerations
    up to its square), within the joints' limits; the model's torques, and the built arm's readings
    on the states its encoders give, different from the model's; the same draws from the same seed."""
    study = load_study(PARAMS / "studies" / f"{arm}.yaml")
    s, settings = study.shifted, study.id
    data = shifted_id(study)
    assert len(np.unique(data["trajectory"])) == s.id_trajectories
    speed, accel = np.abs(data["qd"]).max(axis=0), np.abs(data["qdd"]).max(axis=0)
    assert (speed <= s.id_speed * settings.max_velocity * (1 + 1e-9)).all()
    assert (accel <= s.id_speed ** 2 * settings.max_acceleration * (1 + 1e-9)).all()
    assert (speed > settings.max_velocity).any() and (accel > settings.max_acceleration).any()
    assert ((data["q"] >= study.robot.qlim[:, 0]) & (data["q"] <= study.robot.qlim[:, 1])).all()
    np.testing.assert_array_equal(data["tau"], rnea(study.robot, data["q"], data["qd"], data["qdd"]))
    assert {"tau_measured", "tau_payload", "q_measured", "qd_measured", "qdd_measured"} <= set(data)
    assert not np.allclose(data["tau_measured"], data["tau"]) and not np.array_equal(data["q_measured"], data["q"])
    again = shifted_id(study)
    for k in data:
        np.testing.assert_array_equal(again[k], data[k])
    assert f"{s.id_trajectories} trajectories" in describe_id(study) and f"{s.id_speed:g} times as fast" in describe_id(study)


def test_a_draws_models_meet_the_shifted_trajectories_as_the_arm_built_for_that_draw_reads_them():
    """Issue 65: draw 0's readings are the population's own; draw 1's are the arm built for draw 1 on
    the same states (its rigid body and drives, within its sensor's noise), not chapter 5's arm."""
    from nfarm.model.dynamics import stribeck_drive_torques
    from nfarm.study.study_files import redrawn

    study = load_study(PARAMS / "studies" / "intelbot5.yaml")
    data = shifted_id(study)
    np.testing.assert_array_equal(shifted_readings(study, data, 0)["tau_measured"], data["tau_measured"])
    other = shifted_readings(study, data, 1)["tau_measured"]
    noise_sd = np.sqrt(study.id.noise ** 2 + study.id.torque_per_count ** 2 / 12)

    def error(draw):
        arm, offset = datasets.built_arm(redrawn(study, draw))
        rigid = rnea(arm, data["q"], data["qd"], data["qdd"])
        return other - rigid - offset - stribeck_drive_torques(arm, data["qd"], data["qdd"], rigid, **study.id.friction)

    np.testing.assert_allclose(error(1).std(axis=0), noise_sd, rtol=0.25)
    assert (np.sqrt(np.mean(error(0) ** 2, axis=0)) > 2 * noise_sd).any()
    params = json.loads(json.dumps(study.params))
    del params["id"]["measured"]
    with pytest.raises(ValueError, match="no shifted ID population of a measured arm"):
        shifted_readings(study_from_dict(params, source="rigid.yaml"), data, 1)


def test_the_shifted_trajectories_are_drawn_apart_from_the_test_split():
    """Their own seed: no trajectory of the shifted population is one of the test split's sped up."""
    study = load_study(PARAMS / "studies" / "intelbot5.yaml")
    from nfarm.study.id_trajectories import random_trajectories
    from nfarm.study.regions import STREAMS
    # the test split's own draws (its seed and stream, nfarm.study.datasets), sped up as the shifted population is
    test = random_trajectories(study.robot, faster(study.id, study.shifted.id_speed), study.shifted.id_trajectories,
                               np.random.SeedSequence([datasets.split_seed(study, "test"), STREAMS["id"], 2]))
    assert not np.allclose(test["q"][:50], shifted_id(study)["q"][:50])


def test_faster_compresses_the_timing_and_refuses_a_bad_speed():
    settings = load_study(PARAMS / "studies" / "so101.yaml").id
    f = faster(settings, 3.0)
    np.testing.assert_allclose(f.max_acceleration, 9 * settings.max_acceleration)
    assert f.segment_time == pytest.approx(tuple(t / 3 for t in settings.segment_time)) and f.dt == settings.dt
    for bad in (0, -1.0, True, "2"):
        with pytest.raises(ValueError, match="speed must be a positive number"):
            faster(settings, bad)


def test_a_study_without_shifted_trajectories_declares_none():
    study = load_study(PARAMS / "studies" / "intelbot5.yaml")
    params = json.loads(json.dumps(study.params))
    for k in ("id_trajectories", "id_speed", "id_declared"):
        params["shifted"].pop(k)
    without = study_from_dict(params, source="ik-only.yaml")
    assert without.shifted.id_trajectories is None and describe_id(without) == "no shifted ID population"
    with pytest.raises(ValueError, match=r"ik-only.yaml: shifted: id_trajectories: the study declares no shifted ID"):
        shifted_id(without)
