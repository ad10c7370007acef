"""Data sets for learned IK and ID (nfarm.study.datasets): they obey the models, lie where declared,
keep their splits apart, are reproducible byte for byte, refuse the wrong robot or study, and
every study-file rule has a bad file."""

from __future__ import annotations

import copy
import json
import os

import numpy as np
import pytest
import yaml

from nfarm.solvers import workspace
from nfarm.study import datasets, id_trajectories, study_files
from nfarm.study.datasets import build_datasets, inputs_hash, load
from nfarm.study.regions import IKRegion, check_single_valued
from nfarm.study.id_trajectories import measured_states, random_trajectories
from nfarm.study.jobs import study_sized
from nfarm.study.study_files import load_study, study_from_dict
from nfarm.model.dynamics import rnea, stribeck_drive_torques
from nfarm.model.kinematics import fk
from nfarm.infra.paths import PARAMS
from nfarm.infra.reading import ParamsError
from nfarm.model.robot import load_robot, robot_from_dict, robot_to_dict

STUDY = PARAMS / "studies" / "intelbot5.yaml"
BASE = yaml.safe_load(STUDY.read_text())


def small_study():
    data = copy.deepcopy(BASE)
    data["ik"]["sizes"] = {"train": 300, "val": 100, "test": 200}
    data["ik"]["check"] = {"targets": 50, "starts": 8}
    data["id"]["trajectories"] = {"train": 6, "val": 2, "test": 3}
    return data


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("data")
    study = study_from_dict(small_study(), source="small.yaml")
    return study, out, build_datasets(study, out)


def test_the_shipped_study_loads():
    study = load_study(STUDY)
    assert study.robot.name == "intelbot5" and study.ik_sizes["train"] >= 5_000
    assert study.ik_region.box.shape == (5, 2)


def test_reach_keeps_the_tool_in_front_of_the_base():
    """With the reach bound the tool's azimuth is the base angle q1 (the arm never reaches back
    over its base); with the distance bound alone it is not, for some draws."""
    study = study_from_dict(small_study())
    region = study.ik_region
    q = region.sample(2000, 0)
    p = fk(study.robot, q)[:, :3, 3]
    np.testing.assert_allclose(np.arctan2(p[:, 1], p[:, 0]), q[:, 0], atol=1e-9)
    assert (p[:, 0] * np.cos(q[:, 0]) + p[:, 1] * np.sin(q[:, 0]) >= region.reach[0]).all()
    distance_only = IKRegion(study.robot, region.box, radial=(region.reach[0], None),
                             height=region.height)
    q = distance_only.sample(2000, 0)
    p = fk(study.robot, q)[:, :3, 3]
    behind = np.abs(np.angle(np.exp(1j * (np.arctan2(p[:, 1], p[:, 0]) - q[:, 0])))) > 3
    assert behind.mean() > 0.05
    assert not region.contains(q[behind]).any()
    with pytest.raises(ValueError, match="reach filter needs the poses' configurations"):
        region.contains_pose(fk(study.robot, q))


def test_reach_needs_a_base_joint_about_z(tmp_path):
    data = robot_to_dict(load_robot(PARAMS / "robots" / "intelbot5.yaml"))
    data["convention"] = "modified"
    data["joints"][0]["alpha"] = 0.5
    (tmp_path / "robot.yaml").write_text(yaml.safe_dump(data))
    study = small_study()
    study["robot_file"] = str(tmp_path / "robot.yaml")
    with pytest.raises(ParamsError, match=r"ik.region.reach_m: needs joint 1 to turn about the "
                                          r"base z axis"):
        study_from_dict(study)


def test_stored_data_obey_the_models(built):
    study, out, made = built
    assert [p.name for p, status in made] == [f"{k}_{s}.npz" for k in ("ik", "id", "ik_full")
                                              for s in ("train", "val", "test")]
    for split in ("train", "val", "test"):
        ik = load(out / f"ik_{split}.npz", study.robot, study)
        assert ik["q"].shape == (study.ik_sizes[split], 5)
        np.testing.assert_allclose(ik["T"], fk(study.robot, ik["q"]), rtol=0, atol=1e-12)
        assert study.ik_region.contains(ik["q"]).all(), "q inside the region"
        idd = load(out / f"id_{split}.npz", study.robot, study)
        np.testing.assert_allclose(idd["tau"], rnea(study.robot, idd["q"], idd["qd"], idd["qdd"]),
                                   rtol=0, atol=1e-12)
        assert set(np.unique(idd["trajectory"])) == set(range(study.id.trajectories[split]))
        assert ((idd["q"] >= study.robot.qlim[:, 0]) & (idd["q"] <= study.robot.qlim[:, 1])).all()
        assert (np.abs(idd["qd"]) <= study.id.max_velocity).all()
        assert (np.abs(idd["qdd"]) <= study.id.max_acceleration).all()
        # The "measured" torques: the built arm's rigid body (not the model's) + its drives + its
        # zero offsets + noise of the stated size, read in counts of the motor current.
        arm, offset = datasets.built_arm(study)
        rigid = rnea(arm, idd["q"], idd["qd"], idd["qdd"])
        assert np.abs(rigid - idd["tau"]).max() > 2 * study.id.noise.max(), "the built arm is not the model"
        counts = idd["tau_measured"] / study.id.torque_per_count
        np.testing.assert_allclose(counts, np.round(counts), rtol=0, atol=1e-6)
        noise = idd["tau_measured"] - rigid - offset - stribeck_drive_torques(
            arm, idd["qd"], idd["qdd"], rigid, **study.id.friction)
        count = study.id.torque_per_count
        noise_sd = np.sqrt(study.id.noise ** 2 + count ** 2 / 12)     # the reading's counts add a uniform error
        assert ("tau_payload" in idd) == (split == "test")
        if split == "test":        # the payload case: more torque where the payload hangs off the tool
            loaded = idd["tau_payload"] - idd["tau_measured"]
            assert np.sqrt(np.mean(loaded[:, 1] ** 2)) > 10 * noise_sd[1]
        # ... on states the arm knows: encoder angles on its counts, filtered derivatives near the truth
        step = 2 * np.pi / study.id.encoder_counts
        np.testing.assert_allclose(idd["q_measured"] / step, np.round(idd["q_measured"] / step), atol=1e-9)
        assert np.abs(idd["q_measured"] - idd["q"]).max() <= step / 2 + 1e-12
        assert np.sqrt(np.mean((idd["qd_measured"] - idd["qd"]) ** 2)) < 0.05 * idd["qd"].std()
        assert noise.shape == idd["tau"].shape
        np.testing.assert_allclose(noise.std(axis=0), noise_sd, rtol=0.2)
        assert np.abs(noise.mean(axis=0)).max() < 4 * noise_sd.max() / np.sqrt(len(noise))
        full = load(out / f"ik_full_{split}.npz", study.robot, study)
        assert not study.ik_region.contains(full["q"]).all(), "the full range is wider"


def _sensor_error(study, draw, data, tau_measured):
    """What a reading adds to the rigid body, drives and offsets of the arm built for ``draw``."""
    from nfarm.study.study_files import redrawn
    arm, offset = datasets.built_arm(redrawn(study, draw))
    rigid = rnea(arm, data["q"], data["qd"], data["qdd"])
    return tau_measured - rigid - offset - stribeck_drive_torques(arm, data["qd"], data["qdd"], rigid, **study.id.friction)


def test_a_draws_models_are_judged_on_the_test_states_as_the_arm_built_for_it_reads_them(built):
    """Issue 65: the test split is never redrawn, but a draw's models were trained on another built
    arm, so its readings of the same states are that arm's (datasets.held_out_readings): draw 0's are
    the split's own; draw 2's differ from them by the arms' difference, within the sensor's noise of
    the arm built for draw 2 and not of chapter 5's, and draw 2's payload case is its own too."""
    from nfarm.study.datasets import held_out_readings
    study, out, _ = built
    test = load(out / "id_test.npz", study.robot, study)
    own = held_out_readings(study, 0, test)
    np.testing.assert_array_equal(own["tau_measured"], test["tau_measured"])
    np.testing.assert_array_equal(own["tau_payload"], test["tau_payload"])
    other = held_out_readings(study, 2, test)
    assert set(other) == {"tau_measured", "tau_payload"}
    noise_sd = np.sqrt(study.id.noise ** 2 + study.id.torque_per_count ** 2 / 12)
    np.testing.assert_allclose(_sensor_error(study, 2, test, other["tau_measured"]).std(axis=0), noise_sd, rtol=0.25)
    wrong = np.sqrt(np.mean(_sensor_error(study, 0, test, other["tau_measured"]) ** 2, axis=0))
    assert (wrong > 2 * noise_sd).any(), "draw 2's readings are not chapter 5's arm's"
    assert not np.allclose(other["tau_payload"] - other["tau_measured"], own["tau_payload"] - own["tau_measured"])
    np.testing.assert_array_equal(held_out_readings(study, 2, test)["tau_measured"], other["tau_measured"])   # seeded
    with pytest.raises(ValueError, match="declares no measured arm"):
        unmeasured = copy.deepcopy(small_study())
        del unmeasured["id"]["measured"]
        held_out_readings(study_from_dict(unmeasured), 1, test)


def test_splits_are_disjoint(built):
    study, out, _ = built
    q = {s: load(out / f"ik_{s}.npz", study.robot)["q"] for s in ("train", "val", "test")}
    rows = np.concatenate(list(q.values()))
    assert len(np.unique(rows, axis=0)) == len(rows)
    t = {s: load(out / f"id_{s}.npz", study.robot) for s in ("train", "val", "test")}
    starts = [tuple(d["q"][d["trajectory"] == j][0]) for d in t.values()
              for j in np.unique(d["trajectory"])]
    assert len(set(starts)) == len(starts), "no trajectory in two splits"


def test_id_trajectories_are_smooth_and_consistent():
    """Velocities and accelerations are the derivatives of the positions: central differences
    on the same trajectories sampled 20 times finer (dt does not change the random draws)."""
    import dataclasses
    study = study_from_dict(small_study())
    fine = dataclasses.replace(study.id, dt=study.id.dt / 20)
    d = random_trajectories(study.robot, fine, 3, 0)
    coarse = random_trajectories(study.robot, study.id, 3, 0)
    np.testing.assert_array_equal(coarse["q"][coarse["t"] == 0], d["q"][d["t"] == 0])
    dt = fine.dt
    for j in range(3):
        k = np.flatnonzero(d["trajectory"] == j)
        q, qd, qdd = d["q"][k], d["qd"][k], d["qdd"][k]
        np.testing.assert_allclose((q[2:] - q[:-2]) / (2 * dt), qd[1:-1], atol=1e-5)
        # Accelerations are continuous but the jerk jumps at via points: there the central
        # difference is off by O(dt · jump); elsewhere it is O(dt²).
        error = np.abs((qd[2:] - qd[:-2]) / (2 * dt) - qdd[1:-1])
        assert np.percentile(error, 99) < 1e-4 and error.max() < 0.05
        assert np.allclose(qd[0], 0) and np.allclose(d["t"][k][0], 0)


def test_same_seed_same_bytes_and_reuse(built, tmp_path):
    study, out, _ = built
    again = build_datasets(study, tmp_path)
    for (a, _), (b, _) in zip(build_datasets(study, out), again):
        assert a.read_bytes() == b.read_bytes()
        assert json.loads(a.with_suffix(".json").read_text())["npz_sha256"] == \
            json.loads(b.with_suffix(".json").read_text())["npz_sha256"]
    assert {status for _, status in build_datasets(study, tmp_path)} == {"reused"}
    other = small_study()
    other["seed"] = 1
    changed = build_datasets(study_from_dict(other), tmp_path)
    assert {status for _, status in changed} == {"made"}


def test_a_mismatched_robot_or_study_is_refused(built):
    study, out, _ = built
    params = robot_to_dict(study.robot)
    params["joints"][1]["mass"] = 0.36
    heavier = robot_from_dict(params, source="heavier.yaml")
    with pytest.raises(ParamsError, match=r"ik_train.json: robot_params_sha256: made for robot "
                                          r"'intelbot5' with other parameters than 'intelbot5' "
                                          r"\(heavier.yaml\): regenerate with `python -m nfarm "
                                          r"datasets small.yaml`"):
        load(out / "ik_train.npz", heavier)
    other = small_study()
    other["ik"]["sizes"]["train"] = 301
    with pytest.raises(ParamsError, match=r"study: made from other study parameters: "
                                          r"ik.sizes.train \(300 → 301\)"):
        load(out / "ik_train.npz", study.robot, study_from_dict(other))
    with pytest.raises(ParamsError, match=r"file not found"):
        load(out / "nothing.npz", study.robot)


def test_a_changed_npz_is_refused(built, tmp_path):
    study, out, _ = built
    for name in ("ik_val.npz", "ik_val.json"):
        (tmp_path / name).write_bytes((out / name).read_bytes())
    data = bytearray((tmp_path / "ik_val.npz").read_bytes())
    data[-100] ^= 1
    (tmp_path / "ik_val.npz").write_bytes(bytes(data))
    with pytest.raises(ParamsError, match=r"npz_sha256: ik_val.npz is not the file this "
                                          r"description was written for"):
        load(tmp_path / "ik_val.npz", study.robot)


def test_an_interrupted_write_leaves_no_file(built, tmp_path, monkeypatch):
    study, _, _ = built

    def fail(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(datasets, "rnea", fail)
    with pytest.raises(KeyboardInterrupt):
        build_datasets(study, tmp_path)
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == ["ik_test.json", "ik_test.npz", "ik_train.json", "ik_train.npz",
                    "ik_val.json", "ik_val.npz"], "only complete files, each with its description"


def test_region_contains_and_samples(intelbot5):
    region = load_study(STUDY).ik_region
    for method in ("sobol", "uniform"):
        q = region.sample(1000, 3, method=method)
        assert q.shape == (1000, 5) and region.contains(q).all()
        np.testing.assert_array_equal(q, region.sample(1000, 3, method=method))
    q = region.sample(7, 0)
    assert region.contains(q[None]).shape == (1, 7) and region.contains(q[0]).shape == ()
    assert not region.contains(intelbot5.qlim[:, 1] * 0.999)


@pytest.mark.parametrize("study_name", ["intelbot5", "so101"])
def test_the_shipped_regions_are_single_valued_and_the_full_range_is_not(study_name):
    study = load_study(PARAMS / "studies" / f"{study_name}.yaml")
    inside = check_single_valued(study.ik_region, 20_000, seed=1, batch=7_000)
    assert inside.method == "closed form" and (inside.inside == 1).all() and inside.fraction == 0
    assert (inside.solutions >= 1).all() and inside.solutions.max() <= 4
    full = check_single_valued(IKRegion.full(study.robot), 3000, seed=1)
    assert full.fraction > 0.2 and full.solutions.max() <= 4
    k = full.offenders[0]
    np.testing.assert_allclose(fk(study.robot, full.q_second[k]), fk(study.robot, full.q[k]),
                               atol=1e-9)
    assert np.abs(full.q_second[k] - full.q[k]).max() > 1e-3


def test_lm_counts_no_more_solutions_than_exist_and_never_a_fifth():
    """The LM route finds a subset of the closed form's solutions; distinct by wrapped angular
    distance, it never counts one solution twice (rounding to a grid counted 5 and 6)."""
    study = load_study(STUDY)
    full = IKRegion.full(study.robot)
    exact = check_single_valued(full, 300, seed=1)
    lm = check_single_valued(full, 300, 16, seed=1, method="lm")
    np.testing.assert_array_equal(exact.q, lm.q)
    assert (lm.solutions <= exact.solutions).all() and lm.solutions.max() <= 4
    assert (lm.inside <= exact.inside).all() and lm.solved.mean() > 4
    assert not (lm.second & ~exact.second).any()
    with pytest.raises(ValueError, match="method must be 'auto', 'closed form' or 'lm'"):
        check_single_valued(full, 10, method="exact")


def bad(path, value):
    data = small_study()
    *head, last = path
    target = data
    for key in head:
        target = target[key]
    if value is KeyError:
        del target[last]
    else:
        target[last] = value
    return data


@pytest.mark.parametrize("path, value, message", [
    (("name",), "", r"name: must be a non-empty string"),
    (("robot_file",), "params/robots/none.yaml", r"robot_file: cannot load the robot: .*none.yaml: file not found"),
    (("seed",), -1, r"seed: must be >= 0, got -1"),
    (("seed",), 1.5, r"seed: must be a whole number, got 1.5"),
    (("test_seed",), 1.5, r"test_seed: must be a whole number, got 1.5"),
    (("test_seed",), "fresh", r"test_seed: must be a whole number, got 'fresh'"),
    (("sead",), 1, r"sead: unknown field \(did you mean 'seed'\?\)"),
    (("ik",), KeyError, r"ik: required field is missing"),
    (("ik", "region", "joints_deg"), [[-80, 80]] * 4, r"ik.region.joints_deg: must be a list of 5 items, got 4"),
    (("ik", "region", "joints_deg", 0), [80, -80], r"ik.region.joints_deg\[0\]: must satisfy lo < hi"),
    (("ik", "region", "joints_deg", 1), [-100, 60], r"ik.region.joints_deg\[1\]: must lie within joint 2's limits \[-90, 90\] deg"),
    (("ik", "region", "joints_deg", 2), ["a", 1], r"ik.region.joints_deg\[2\]\[0\]: must be a number"),
    (("ik", "region", "radial_m"), [-0.1, None], r"ik.region.radial_m\[0\]: must be >= 0"),
    (("ik", "region", "height_m"), [0.3, 0.1], r"ik.region.height_m: must satisfy lo < hi"),
    (("ik", "region", "reach_m"), [0.2, 0.1], r"ik.region.reach_m: must satisfy lo < hi"),
    (("ik", "region", "reach_m"), [50, 60], r"ik.region: no pose of 8,192 drawn in the joint box passes its task-space filters"),
    (("ik", "region", "height_m"), [-9.0, -8.0], r"ik.region: no pose of 8,192 drawn .* the arm cannot reach it"),
    (("ik", "region", "approach"), {"axis": [0, 0, 0], "max_angle_deg": 30}, r"approach.axis: must not be the zero vector"),
    (("ik", "region", "approach"), {"axis": [0, 0, -1], "max_angle_deg": 0}, r"approach.max_angle_deg: must be > 0"),
    (("ik", "region", "approach"), {"axis": [0, 0, -1]}, r"approach.max_angle_deg: required field is missing"),
    (("ik", "sampler"), "halton", r"ik.sampler: must be one of sobol, uniform, got 'halton'"),
    (("ik", "sizes", "train"), 0, r"ik.sizes.train: must be >= 1, got 0"),
    (("ik", "sizes"), {"train": 1, "val": 1}, r"ik.sizes.test: required field is missing"),
    (("ik", "check", "starts"), 0, r"ik.check.starts: must be >= 1"),
    (("ik", "full_range"), "yes", r"ik.full_range: must be true or false, got 'yes'"),
    (("id", "via_points"), 1, r"id.via_points: must be >= 2, got 1"),
    (("id", "segment_time_s"), [0, 1], r"id.segment_time_s\[0\]: must be > 0, got 0.0"),
    (("id", "segment_time_s"), [1.5, 1.0], r"id.segment_time_s: must satisfy lo < hi, got \[1.5, 1.0\]"),
    (("id", "segment_time_s"), [None, 1.0], r"id.segment_time_s\[0\]: must be a number, got None"),
    (("id", "segment_time_s"), [1.0], r"id.segment_time_s: must be a list of 2 items, got 1"),
    (("id", "dt_s"), 5.0, r"id.dt_s: must be <= 0.6 \(the shortest segment, id.segment_time_s\), got 5.0"),
    (("id", "dt_s"), 0, r"id.dt_s: must be > 0, got 0.0"),
    (("id", "margin_deg"), 100, r"id.margin_deg: must leave room inside the narrowest joint range"),
    (("id", "max_velocity_deg_s"), [1, 2, 3], r"id.max_velocity_deg_s: must be a list of 5 items, got 3"),
    (("id", "max_acceleration_deg_s2"), -5, r"id.max_acceleration_deg_s2: must be > 0, got -5.0"),
    (("id", "trajectories", "val"), 2.5, r"id.trajectories.val: must be a whole number"),
    (("id", "measured", "viscous"), -0.1, r"id.measured.viscous: must be >= 0, got -0.1"),
    (("id", "measured", "coulomb"), [0.1] * 4, r"id.measured.coulomb: must be a list of 5 items"),
    (("id", "measured", "coulomb_velocity_deg_s"), 0, r"id.measured.coulomb_velocity_deg_s: must be > 0"),
    (("id", "measured", "noise_nm"), KeyError, r"id.measured.noise_nm: required field is missing"),
    (("id", "measured", "armature_kg"), 1, r"id.measured.armature_kg: unknown field"),
    (("id", "measured", "stribeck"), 0.01, r"id.measured.stribeck: the breakaway friction must be at least the Coulomb"),
    (("id", "measured", "stribeck_velocity_deg_s"), KeyError, r"id.measured: stribeck needs stribeck_velocity_deg_s"),
    (("id", "measured", "load_coefficient"), 1.5, r"id.measured.load_coefficient: must be < 1"),
    (("id", "measured", "encoder_counts"), 8, r"id.measured.encoder_counts: must be >= 16"),
    (("id", "measured", "filter_window"), 8, r"id.measured.filter_window: must be an odd number of samples, got 8"),
    # values that overflow the data sets, work the machine cannot hold (budget: 4 GiB, set below)
    (("id", "measured", "noise_nm"), 1.7e308, r"id.measured.noise_nm: must be <= 1e\+06, got 1.7e\+308"),
    (("id", "measured", "viscous"), [0.1, 0.1, 1e300, 0.1, 0.1], r"id.measured.viscous\[2\]: must be <= 1e\+06"),
    (("ik", "sizes", "train"), 50_000_000, r"ik.sizes.train: 50,000,000 IK poses would take about 27.9 GiB while "
                                           r"made, over the memory budget of 4 GiB"),
    (("ik", "sizes", "test"), 8_000_000, r"ik.sizes.test: 8,000,000 IK poses would take about 4.47 GiB"),
    (("id", "trajectories", "train"), 1_000_000, r"id.trajectories.train: 1,000,000 trajectories of about "
                                                 r"[\d,]+ samples each would take about [\d,.]+ GiB"),
    (("id", "dt_s"), 1e-9, r"id.trajectories.train: \d+ trajectories of about [\d,]+ samples each would take"),
    (("id", "segment_time_s"), [1e6, 2e6], r"id.trajectories.train: .* over the memory budget"),
    (("id", "max_velocity_deg_s"), 1e-9, r"id.trajectories.train: .* over the memory budget"),
    (("id", "via_points"), 10_000, r"id.trajectories.train: .* over the memory budget"),
])
def test_every_study_rule_has_a_bad_file(tmp_path, path, value, message, monkeypatch):
    monkeypatch.setenv("NFARM_MEMORY_GB", "4")
    file = tmp_path / "bad.yaml"
    file.write_text(yaml.safe_dump(bad(path, value)))
    with pytest.raises(ParamsError, match=message) as caught:
        load_study(file)
    assert str(caught.value).startswith(f"{file}: ") and "\n" not in str(caught.value)


def test_check_params_accepts_study_files():
    import subprocess
    import sys
    run = subprocess.run([sys.executable, "-m", "nfarm", "check-params", str(STUDY)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0 and "ok (study 'intelbot5 study' of intelbot5" in run.stdout


def test_robot_hash_ignores_layout_but_not_values(tmp_path):
    source = PARAMS / "robots" / "intelbot5.yaml"
    robot = load_robot(source)
    (tmp_path / "same.yaml").write_text("# a comment\n" + source.read_text())
    from nfarm.model.robot import robot_hash
    assert robot_hash(load_robot(tmp_path / "same.yaml")) == robot_hash(robot)
    params = robot_to_dict(robot)
    params["joints"][0]["d"] += 1e-12
    assert robot_hash(robot_from_dict(params)) != robot_hash(robot)


def _yaw_pitch_elbow(upper: float, fore: float):
    """Base yaw, shoulder and elbow pitch with full turns: the tool reaches every point at a
    distance between |upper − fore| and upper + fore from the shoulder."""
    def joint(a, alpha):
        return {"a": a, "alpha": alpha, "d": 0.0, "offset": 0.0, "qlim": [-np.pi, np.pi],
                "mass": 1.0, "com": [0, 0, 0], "inertia": [0.01, 0.01, 0.01, 0, 0, 0]}
    return robot_from_dict({"name": "ype", "convention": "standard", "gravity": [0, 0, -9.81],
                            "joints": [joint(0.0, np.pi / 2), joint(upper, 0.0), joint(fore, 0.0)]})


@pytest.mark.parametrize("upper, fore", [(1.0, 1.0), (2.0, 1.0)])
def test_workspace_volume_of_a_spherical_shell(upper, fore):
    robot = _yaw_pitch_elbow(upper, fore)
    outer, inner = upper + fore, abs(upper - fore)
    exact = 4 / 3 * np.pi * (outer ** 3 - inner ** 3)
    est = workspace.workspace_volume(robot, outer, n_points=1500, seed=2, restarts=8)
    assert est.points == 1500 and est.reach == outer
    assert abs(est.volume - exact) <= 4 * max(est.std_error, 0.01 * exact), (est, exact)


def test_reach_is_measured_from_the_first_joint_s_origin():
    from nfarm.solvers.workspace import reach, workspace_points
    robot = _yaw_pitch_elbow(2.0, 1.0)
    assert 2.99 < reach(workspace_points(robot, 20_000, 0), robot) <= 3.0 + 1e-12


@pytest.mark.parametrize("learned_ik, message", [
    ({"n_mfs": 0}, r"study.yaml: learned_ik.n_mfs: must be >= 1, got 0"),
    ({"n_mfs": [1, 4, "x"]}, r"learned_ik.n_mfs\[2\]: must be a whole number, got 'x'"),
    ({"epochs": [30, 30]}, r"learned_ik.epochs: must be a list of 5 items, got 2"),
    ({"epochs": 2.5}, r"learned_ik.epochs: must be a whole number, got 2.5"),
    ({"rules": 4}, r"learned_ik.rules: unknown field \(allowed: n_mfs, epochs\)"),
])
def test_bad_learned_ik_sections_are_one_line_errors(tmp_path, learned_ik, message):
    data = yaml.safe_load((PARAMS / "studies" / "intelbot5.yaml").read_text())
    data["learned_ik"] = learned_ik
    path = tmp_path / "study.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ParamsError, match=message):
        load_study(path)


def test_learned_ik_sets_the_chosen_size_and_not_the_data():
    plain = load_study(PARAMS / "studies" / "intelbot5.yaml")
    data = copy.deepcopy(plain.params)
    data["learned_ik"] = {"n_mfs": [1, 4, 4, 4, 4, 1], "epochs": [1, 2, 3, 4, 5]}
    sized = study_files.study_from_dict(data, "x.yaml")
    assert inputs_hash(sized) == inputs_hash(plain)          # the data sets are the same files
    chosen = study_sized(sized, {"n_mfs": 3, "epochs": 30, "joint_options": [{"n_mfs": 1}, {}, {}, {}, {}]})
    assert chosen["n_mfs"] == [1, 4, 4, 4, 4, 1]
    assert chosen["joint_options"] == [{"n_mfs": 1, "epochs": 1}, *({"epochs": e} for e in (2, 3, 4, 5))]
    assert study_sized(plain, {"n_mfs": 3}) == {"n_mfs": 3}


def test_measured_states_read_an_encoder_and_differentiate_like_a_drive():
    """A cubic motion is read to the encoder's counts; the Savitzky–Golay derivatives of the
    readings are the motion's own to within the quantisation's effect, trajectory by trajectory."""
    t = np.arange(0, 2, 0.02)
    q = np.column_stack([0.3 * t ** 3 - t, np.sin(t)])
    both = np.concatenate([q, q[::-1] + 0.1])
    label = np.repeat([0, 1], len(t))
    q_read, qd, qdd = measured_states(both, label, 0.02, 4096, 9)
    step = 2 * np.pi / 4096
    assert np.abs(q_read - both).max() <= step / 2 + 1e-15
    exact = np.column_stack([0.9 * t ** 2 - 1, np.cos(t)])
    # a count between two samples is step/dt = 0.077 rad/s; the filter brings it under a third of that
    assert np.abs(qd[:len(t)] - exact)[5:-5].max() < step / 0.02 / 3   # rad/s, away from the ends
    assert np.abs(qdd[:len(t), 0] - 1.8 * t)[5:-5].max() < step / 0.02 ** 2 / 10   # rad/s² (a count: 3.8)
    # no derivative runs across the boundary between trajectories
    np.testing.assert_allclose(qd[len(t):], measured_states(both[len(t):], label[len(t):], 0.02, 4096, 9)[1])


def test_seed_like_trajectories_are_the_dissertation_s_cubics():
    """Rest to rest over 6 s, every 0.2 s (31 states), ends within the limits less the margin."""
    study = load_study(STUDY)
    d = id_trajectories.seed_like_trajectories(study.robot, study.id, 4, 3)
    assert d["q"].shape == (4 * 31, study.robot.n) and np.array_equal(np.bincount(d["trajectory"]), [31] * 4)
    np.testing.assert_allclose(d["t"][:31], np.arange(31) * 0.2, atol=1e-12)
    ends = d["qd"].reshape(4, 31, -1)[:, [0, -1]]
    np.testing.assert_allclose(ends, 0.0, atol=1e-12)
    lo, hi = study.robot.qlim[:, 0] + study.id.margin, study.robot.qlim[:, 1] - study.id.margin
    assert ((d["q"] >= lo - 1e-12) & (d["q"] <= hi + 1e-12)).all()
    again = id_trajectories.seed_like_trajectories(study.robot, study.id, 4, 3)
    np.testing.assert_array_equal(again["q"], d["q"])


def test_a_redrawn_study_draws_new_training_data_and_keeps_the_test_set(built, tmp_path):
    from nfarm.study.datasets import dataset_dir, load
    from nfarm.study.study_files import redrawn
    study, out, _ = built
    assert redrawn(study, 0) is study
    again = redrawn(study, 2)
    assert again.seed == study.seed + 2 and again.draw == 2 and inputs_hash(again) != inputs_hash(study)
    assert dataset_dir(again, out) == dataset_dir(study, out) / "draw2"
    made = build_datasets(again, out)
    assert {p.name for p, _ in made} == {f"{k}_{s}.npz" for k in ("ik", "id", "ik_full") for s in ("train", "val")}
    own, new = load(out / "id_train.npz", study.robot, study), load(out / "draw2" / "id_train.npz", study.robot, again)
    assert not np.array_equal(own["q"][:10], new["q"][:10])
    # Draw k is the study with seed + k: a reader reproduces it from the study file.
    assert again.data_params == {**study.data_params, "seed": study.seed + 2}
    for bad in (-1, 1.5, True):
        with pytest.raises(ValueError, match="draw must be a non-negative integer"):
            redrawn(study, bad)


def test_the_memory_budget_is_half_the_machine_or_what_nfarm_memory_gb_says(monkeypatch):
    from nfarm.study.study_files import memory_budget
    monkeypatch.delenv("NFARM_MEMORY_GB", raising=False)
    assert memory_budget() == 0.5 * os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    monkeypatch.setenv("NFARM_MEMORY_GB", "0.25")
    assert memory_budget() == 2 ** 28
    for bad in ("lots", "-1", "0", "nan", "inf"):
        monkeypatch.setenv("NFARM_MEMORY_GB", bad)
        with pytest.raises(ParamsError, match=r"NFARM_MEMORY_GB: must be a positive number of GiB"):
            memory_budget()
    monkeypatch.setenv("NFARM_MEMORY_GB", "0.01")            # a small machine refuses the shipped study
    with pytest.raises(ParamsError, match=r"intelbot5.yaml: id.trajectories.train: 160 trajectories of about "
                                          r"1,339 samples each would take about 0.201 GiB while made, over the "
                                          r"memory budget of 0.01 GiB"):
        load_study(PARAMS / "studies" / "intelbot5.yaml")


def test_a_region_too_narrow_for_its_size_is_refused_once_a_million_draws_say_so():
    """The filters' acceptance after a million draws predicts the draws a size needs: a size
    out of reach is refused then, not after max_draws: the refusal counts the draws it made,
    about a million of the hundred million allowed (its time: ``benchmarks/bench_deadlines.py``)."""
    study = load_study(STUDY)
    region = study.ik_region
    with pytest.raises(ValueError, match=r"accepted [\d,]+ of 1,04\d,\d+ draws, too few for the 50,000,000 asked "
                                         r"for within 100,000,000 draws: widen them"):
        region.sample(50_000_000, 0)


def test_a_fresh_test_seed_redraws_the_test_split_alone(built, tmp_path):
    """``test_seed`` draws the held-out set apart: changing it alone changes every test file's
    arrays (new poses, new trajectories, new sensor noise) and leaves the training and
    validation files byte for byte, so a fresh final test set leaves every model and choice as
    it was."""
    study, out, _ = built
    data = small_study()
    data["test_seed"] = study.test_seed + 1
    fresh = study_from_dict(data, source="small.yaml")
    out2 = tmp_path / "fresh"
    build_datasets(fresh, out2)
    for kind in ("ik", "id", "ik_full"):
        for split in ("train", "val"):
            a = load(out / f"{kind}_{split}.npz", study.robot, study)
            b = load(out2 / f"{kind}_{split}.npz", fresh.robot, fresh)
            assert all(np.array_equal(a[k], b[k]) for k in a), (kind, split)
        a = load(out / f"{kind}_test.npz", study.robot, study)
        b = load(out2 / f"{kind}_test.npz", fresh.robot, fresh)
        key = "q" if kind != "id" else "tau_measured"
        assert a[key].shape[1:] == b[key].shape[1:] and not np.array_equal(a[key][:len(b[key])], b[key][:len(a[key])])
    assert datasets.split_seed(fresh, "test") == fresh.test_seed != fresh.seed == datasets.split_seed(fresh, "val")
    with pytest.raises(ParamsError, match=r"small.yaml: test_seed: must be >= 0, got -1"):
        study_from_dict({**data, "test_seed": -1}, source="small.yaml")
