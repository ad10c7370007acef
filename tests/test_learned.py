"""Learned inverse kinematics (nfarm.learning.learned): encodings are faithful charts of the poses, a
small seeded training reaches a stated error, save/load is bit for bit, batching follows the
library's rule, and every bad input is one clear error before any work."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from nfarm.study.regions import ik_samples

from nfarm.study.study_files import load_study
from nfarm.model.kinematics import fk
from nfarm.learning import hybrid
from nfarm.learning.encoding import FEATURE_NAMES
from nfarm.learning.learned import ENCODINGS, LearnedIK, encode, out_of_plane
from nfarm.infra.paths import PARAMS
from nfarm.infra.reading import ParamsError, with_content_digest
from nfarm.model.robot import load_robot
from nfarm.model.rotations import quat_to_matrix

STUDY = load_study(PARAMS / "studies" / "intelbot5.yaml")
ROBOT = STUDY.robot
with warnings.catch_warnings():          # the Puma's published inertias are not physical
    warnings.simplefilter("ignore")
    PUMA = load_robot(PARAMS / "robots" / "puma560.yaml")
SMALL = dict(encoding="arm_plane", n_mfs=[1, 2, 2, 2, 2, 1], epochs=8,
             joint_options=[{"n_mfs": 1}, {}, {}, {}, {"n_mfs": 1}])


def wrap(angle):
    return np.angle(np.exp(1j * angle))


@pytest.fixture(scope="module")
def data():
    return {split: ik_samples(STUDY.ik_region, n, seed)
            for split, n, seed in (("train", 1500, 1), ("val", 300, 2), ("test", 500, 3))}


@pytest.fixture(scope="module")
def fitted(data):
    return LearnedIK(**SMALL).fit(ROBOT, data["train"], data["val"])


# -- encodings ---------------------------------------------------------------------------------


def test_quaternion_is_kept_on_one_hemisphere(data):
    T = data["test"]["T"]
    X = encode(T, "quat_xyz")
    assert X.shape == (len(T), 7) and (X[:, 0] >= 0).all()
    np.testing.assert_allclose(np.linalg.norm(X[:, :4], axis=1), 1, atol=1e-12)
    np.testing.assert_allclose(quat_to_matrix(X[:, :4]), T[:, :3, :3], atol=1e-12)
    np.testing.assert_array_equal(X[:, 4:], T[:, :3, 3])


def test_axes_encoding_determines_the_pose(data):
    T = data["test"]["T"]
    X = encode(T, "axes_xyz")
    p, a, n = X[:, :3], X[:, 3:6], X[:, 6:]
    R = np.stack([n, np.cross(a, n), a], axis=-1)
    np.testing.assert_allclose(R, T[:, :3, :3], atol=1e-12)
    np.testing.assert_array_equal(p, T[:, :3, 3])


def test_arm_plane_encoding_is_the_arms_own_coordinates(data):
    """For intelbot5 in its region: the azimuth is q1, the roll is q5 less a constant, the
    pitch is q2 + q3 + q4 (mod 2π), and the approach axis stays in the arm's plane."""
    q, T = data["test"]["q"], data["test"]["T"]
    X = encode(T, "arm_plane")
    np.testing.assert_allclose(X[:, 0], q[:, 0], atol=1e-12)
    np.testing.assert_allclose(X[:, 1], np.hypot(T[:, 0, 3], T[:, 1, 3]))
    np.testing.assert_allclose(X[:, 3] ** 2 + X[:, 4] ** 2, 1, atol=1e-12)
    pitch = np.arctan2(X[:, 4], X[:, 3])
    np.testing.assert_allclose(wrap(pitch - q[:, 1:4].sum(axis=1)), 0, atol=1e-9)
    offset = wrap(X[:, 5] - q[:, 4])
    np.testing.assert_allclose(wrap(offset - offset[0]), 0, atol=1e-9)
    assert out_of_plane(T).max() < 1e-12


def test_encodings_are_batched_over_leading_axes(data):
    T = data["test"]["T"][:6].reshape(2, 3, 4, 4)
    for name, d in ENCODINGS.items():
        X = encode(T, name)
        assert X.shape == (2, 3, d)
        np.testing.assert_array_equal(encode(T[1, 2], name), X[1, 2])


def test_arm_plane_refuses_an_arm_whose_tool_leaves_the_plane():
    q = np.random.default_rng(0).uniform(PUMA.qlim[:, 0], PUMA.qlim[:, 1], (200, 6))
    poses = {"T": fk(PUMA, q), "q": q}
    assert out_of_plane(poses["T"]).max() > 0.1
    with pytest.raises(ValueError, match=r"encoding 'arm_plane' needs the tool's approach axis "
                                         r"in the vertical plane .* use 'axes_xyz'"):
        LearnedIK(encoding="arm_plane").fit(PUMA, poses)


def test_angular_inputs_are_unwrapped_about_their_centre(data):
    """A region straddling ±180° of roll is not cut: the roll input of the fitted model spans
    the region's roll range (180° here), not the whole circle."""
    model = LearnedIK(encoding="arm_plane", n_mfs=1, epochs=1).fit(ROBOT, data["train"])
    roll_span = model.encoder_.input_span_[5]
    np.testing.assert_allclose(roll_span, np.ptp(data["train"]["q"][:, 4]), rtol=1e-9)


# -- training and prediction -----------------------------------------------------------------


def test_small_seeded_training_reaches_a_stated_error(fitted, data):
    """1 500 poses, 16 rules per pitch joint, 8 epochs: under 3° RMSE on every joint, and the
    two joints that are linear maps of the arm-plane inputs (q1, q5) to rounding."""
    q_hat = fitted.predict(data["test"]["T"])
    rmse = np.degrees(np.sqrt(np.mean((q_hat - data["test"]["q"]) ** 2, axis=0)))
    assert (rmse < 3.0).all(), rmse
    assert rmse[0] < 1e-8 and rmse[4] < 1e-8, rmse


def test_the_dissertation_encoding_trains_too(data):
    """The dissertation's set-up (7 inputs, 2 bell functions each: 128 rules, 1 024 consequent
    parameters per joint) on 1 500 poses: it learns (on held-out poses every joint's error is
    below that of predicting the training mean, which knows nothing of the pose), and falls far
    short of the arm-plane encoding (tens of degrees where that reaches 3°)."""
    model = LearnedIK(encoding="quat_xyz", n_mfs=2, epochs=2).fit(ROBOT, data["train"])
    assert model.models_[0].rules_.shape == (128, 7)
    test = data["test"]["q"]
    rmse = np.degrees(np.sqrt(np.mean((model.predict(data["test"]["T"]) - test) ** 2, axis=0)))
    knowing_nothing = np.degrees(np.sqrt(np.mean((data["train"]["q"].mean(axis=0) - test) ** 2, axis=0)))
    assert (rmse < knowing_nothing).all(), (rmse, knowing_nothing)
    assert rmse.max() > 10.0, rmse                            # tens of degrees


def test_prediction_is_batched_over_leading_axes(fitted, data):
    T = data["test"]["T"][:6]
    flat = fitted.predict(T)
    assert flat.shape == (6, 5)
    np.testing.assert_array_equal(fitted.predict(T.reshape(2, 3, 4, 4)), flat.reshape(2, 3, 5))
    single = fitted.predict(T[4])
    assert single.shape == (5,)
    # One pose goes through matrix-vector kernels, a batch through matrix-matrix ones: the last
    # bits may differ by CPU (measured on an AMD EPYC: 1.1e-15 rad, 40 ulp).
    np.testing.assert_allclose(single, flat[4], rtol=0, atol=1e-13)
    assert fitted.predict(np.zeros((0, 4, 4))).shape == (0, 5)


def test_fast_prediction_equals_the_training_path(fitted, data):
    X = fitted.encoder_.transform(data["test"]["T"])
    for model in fitted.models_:
        Xp = X if model.premise_inputs is None else X[:, model.premise_inputs]
        slow = hybrid.network_outputs(model.mf, Xp, X, model.mfs_, model.rules_, model.consequents_)
        np.testing.assert_allclose(model._predict_fast(X)[0], slow, rtol=0, atol=1e-12)


def test_describe_names_encoding_rules_and_errors(fitted):
    text = fitted.describe()
    assert "encoding 'arm_plane' (6 inputs: azimuth, r, z, cos_pitch, sin_pitch, roll)" in text
    assert "joint 2: grid partition, gbell functions, 16 rules" in text
    assert "joint 1: grid partition, gbell functions, 1 rule," in text
    assert "validation RMSE" in text


# -- persistence -------------------------------------------------------------------------------


def test_save_and_load_reproduce_predictions_bit_for_bit(fitted, data, tmp_path):
    path = fitted.save(tmp_path / "ik")
    assert path.name == "learned_ik.json" and not list((tmp_path / "ik").glob("*.tmp*"))
    loaded = LearnedIK.load(tmp_path / "ik", ROBOT)
    T = data["test"]["T"]
    np.testing.assert_array_equal(loaded.predict(T), fitted.predict(T))
    assert loaded.describe() == fitted.describe()
    assert loaded.get_params() == fitted.get_params()
    assert json.loads(path.read_text())["robot_params_sha256"] == fitted.robot_hash_


def test_loading_for_another_robot_is_refused(fitted, tmp_path):
    fitted.save(tmp_path)
    with pytest.raises(ParamsError, match=r"learned_ik.json: robot_params_sha256: trained for "
                                          r"robot 'intelbot5' with other parameters than "
                                          r"'puma560'.*retrain"):
        LearnedIK.load(tmp_path, PUMA)


@pytest.mark.parametrize("field, value, message", [
    ("format", "nfarm-anfis-1", r"format: must be 'nfarm-learned-ik-1'"),
    ("encoding", "euler", r"encoding: must be one of quat_xyz, axes_xyz, arm_plane"),
    ("n_joints", 4, r"n_joints: must be 5 for intelbot5, got 4"),
    ("input_span", [1, 1, 0, 1, 1, 1], r"input_span: must hold spans in \(1e-12, 1e\+06\]"),
    ("input_span", [1, 1, 1e-300, 1, 1, 1], r"input_span: must hold spans in \(1e-12, 1e\+06\]"),
    ("input_lo", [1e308, 0, 0, 0, 0, 0], r"input_lo: must hold numbers within ±1e\+06"),
    ("angle_centre", [40.0, 0.0], r"angle_centre: must hold angles within \[-2π, 2π\] rad"),
    ("chart", [np.diag([2.0, 1, 1, 1]).tolist(), np.eye(4).tolist()], r"chart\[0\]: must be a rigid transform"),
    ("chart", [np.eye(4).tolist(), np.diag([1.0, 1, -1, 1]).tolist()], r"chart\[1\]: must be a rigid transform"),
    ("max_out_of_plane", 7.0, r"max_out_of_plane: must be <= 3.14"),
    ("input_lo", [0, 0, 0], r"input_lo: must be a list of 6 numbers"),
    ("angle_centre", [0.0], r"angle_centre: must be a list of 2 numbers"),
    ("joint_options", [{}] * 3, r"joint_options: must be a list of 5 items"),
    ("anfis_options", {"n_mf": 2}, r"anfis_options.n_mf: unknown field"),
    ("models", [], r"models: must be a list of 5 items"),
    ("extra", 1, r"extra: unknown field"),
])
def test_an_edited_model_file_is_one_clear_error(fitted, tmp_path, field, value, message):
    """Every field is validated, even in a file whose content hash was recomputed after the
    edit (as a determined user could)."""
    data = fitted.to_dict()
    data[field] = value
    (tmp_path / "learned_ik.json").write_text(json.dumps(with_content_digest(data)))
    with pytest.raises(ParamsError, match=message):
        LearnedIK.load(tmp_path, ROBOT)


@pytest.mark.parametrize("edit", [
    lambda d: d["input_lo"].__setitem__(0, d["input_lo"][0] + 1e-9),
    lambda d: d["models"][2]["state"]["consequents"][0].__setitem__(0, 0.0),
    lambda d: d.__setitem__("max_out_of_plane", 0.5),
    lambda d: d.pop("content_sha256"),
    lambda d: d.__setitem__("content_sha256", "0" * 64),
])
def test_a_model_edited_after_it_was_saved_is_refused(fitted, tmp_path, edit):
    path = fitted.save(tmp_path)
    data = json.loads(path.read_text())
    edit(data)
    path.write_text(json.dumps(data))
    with pytest.raises(ParamsError, match=r"learned_ik.json: content_sha256: (does not match the file's content|missing)"):
        LearnedIK.load(tmp_path, ROBOT)


def test_a_damaged_model_file_is_one_clear_error(fitted, tmp_path):
    fitted.save(tmp_path)
    text = (tmp_path / "learned_ik.json").read_text()
    (tmp_path / "learned_ik.json").write_text(text[: len(text) // 2])
    with pytest.raises(ParamsError, match=r"learned_ik.json"):
        LearnedIK.load(tmp_path, ROBOT)
    with pytest.raises(ParamsError, match=r"file not found"):
        LearnedIK.load(tmp_path / "missing", ROBOT)


# -- bad input ---------------------------------------------------------------------------------


def bad_T(kind, T):
    T = T.copy()
    if kind == "nan":
        T[3, 0, 3] = np.nan
    elif kind == "last_row":
        T[2, 3, 0] = 1.0
    elif kind == "not_rotation":
        T[1, :3, :3] *= 2
    return T


@pytest.mark.parametrize("kind, message", [
    ("nan", r"NaN"), ("last_row", r"last row"), ("not_rotation", r"rotation"),
])
def test_predict_refuses_what_is_not_a_rigid_transform(fitted, data, kind, message):
    with pytest.raises(ValueError, match=message):
        fitted.predict(bad_T(kind, data["test"]["T"][:5]))


@pytest.mark.parametrize("T", [np.zeros((3, 3)), np.zeros((2, 4, 3)), "pose", [[1, 2], [3, 4]]])
def test_predict_refuses_wrong_shapes(fitted, T):
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 4, 4\)"):
        fitted.predict(T)


def test_predict_before_fit_is_an_error():
    with pytest.raises(ValueError, match=r"not fitted yet"):
        LearnedIK().predict(np.eye(4))


@pytest.mark.parametrize("kwargs, message", [
    (dict(encoding="euler"), r"encoding must be one of quat_xyz, axes_xyz, arm_plane"),
    (dict(n_mf=2), r"unknown ANFIS option 'n_mf'"),
    (dict(joint_options=[{}] * 4), r"joint_options must be None or a list of 5 mappings"),
    (dict(joint_options={"n_mfs": 1}), r"joint_options must be None or a list of 5 mappings"),
    (dict(joint_options=[{"epoch": 1}] + [{}] * 4), r"joint_options\[0\]: unknown ANFIS option 'epoch'"),
    (dict(joint_options=[{"n_mfs": 0}] + [{}] * 4), r"joint 1: .*n_mfs"),
    (dict(epochs=-1), r"joint 1: .*epochs"),
])
def test_fit_refuses_bad_options_before_any_work(data, kwargs, message):
    with pytest.raises(ValueError, match=message):
        LearnedIK(**kwargs).fit(ROBOT, data["train"])


@pytest.mark.parametrize("change, message", [
    (lambda d: {"T": d["T"]}, r"train must be a mapping with arrays 'T' \(N, 4, 4\) and 'q'"),
    (lambda d: {"T": d["T"], "q": d["q"][:-1]}, r"train: T must be \(N, 4, 4\) with one pose per row of q"),
    (lambda d: {"T": d["T"], "q": d["q"][:, :4]}, r"train: q must be a \(N, 5\) array"),
    (lambda d: {"T": d["T"], "q": np.where(np.arange(5) == 2, np.nan, d["q"])}, r"train: q contains NaN"),
    (lambda d: {"T": bad_T("not_rotation", d["T"]), "q": d["q"]}, r"train: .*rotation"),
    (lambda d: [d["T"], d["q"]], r"train must be a mapping"),
])
def test_fit_refuses_bad_data_before_any_work(data, change, message):
    with pytest.raises(ValueError, match=message):
        LearnedIK(**SMALL).fit(ROBOT, change(data["train"]))


def test_threads_share_the_chunks_without_changing_a_bit(fitted, data):
    T = np.resize(data["test"]["T"], (40_000, 4, 4))      # three chunks
    one = fitted.predict(T, threads=1)
    np.testing.assert_array_equal(fitted.predict(T, threads=3), one)
    np.testing.assert_array_equal(fitted.predict(T), one)
    for bad in (0, 1.5, True, "2"):
        with pytest.raises(ValueError, match=r"threads must be a whole number >= 1"):
            fitted.predict(T[:2], threads=bad)
    T = T.copy()
    T[39_000, 0, 0] += 1e-3                        # a bad pose in the last chunk, checked by a thread
    with pytest.raises(ValueError, match=r"T_target\[39000\]: rotation is not orthonormal"):
        fitted.predict(T, threads=2)


# -- learned inverse dynamics ------------------------------------------------------------------

from nfarm.study.id_trajectories import random_trajectories  # noqa: E402
from nfarm.model.dynamics import inertial_parameters, rnea  # noqa: E402
from nfarm.learning.learned_id import LearnedID, id_features, regressor_columns  # noqa: E402


@pytest.fixture(scope="module")
def id_data():
    def split(count, seed):
        d = random_trajectories(ROBOT, STUDY.id, count, seed)
        d["tau"] = rnea(ROBOT, d["q"], d["qd"], d["qdd"])
        return d
    return {"train": split(6, 1), "val": split(2, 2), "test": split(2, 3)}


def nrmse(tau_hat, tau):
    return np.sqrt(((tau_hat - tau) ** 2).mean(axis=0)) / tau.std(axis=0)


@pytest.mark.parametrize("inputs, widths", [("own", [3] * 5), ("all", [15] * 5), ("trig", [25] * 5),
                                             ("regressor", [34, 38, 28, 17, 8])])
def test_id_input_sets(id_data, inputs, widths):
    d = id_data["test"]
    X = id_features(ROBOT, d["q"], d["qd"], d["qdd"], inputs)
    assert [x.shape for x in X] == [(len(d["q"]), w) for w in widths]
    if inputs == "own":
        np.testing.assert_array_equal(X[2], np.column_stack([d["q"][:, 2], d["qd"][:, 2], d["qdd"][:, 2]]))
    if inputs == "regressor":        # τ_j = Y_j π over the parameters of links j..n
        pi = inertial_parameters(ROBOT)
        tau = np.column_stack([x @ pi[cols] for x, cols in zip(X, regressor_columns(ROBOT))])
        np.testing.assert_allclose(tau, rnea(ROBOT, d["q"], d["qd"], d["qdd"]), rtol=0, atol=1e-12)


def test_regressor_inputs_learn_rigid_body_torques_to_rounding(id_data):
    """With each joint's regressor row as inputs, one rule (least squares) is exact: held-out
    NRMSE below 1e-6 on every joint from six training trajectories (measured ~1e-11)."""
    model = LearnedID(inputs="regressor", n_mfs=1, epochs=2).fit(ROBOT, id_data["train"])
    d = id_data["test"]
    assert (nrmse(model.predict(d["q"], d["qd"], d["qdd"]), d["tau"]) < 1e-6).all()


def test_small_seeded_id_training_reaches_a_stated_error(id_data):
    """Six training trajectories, trigonometric inputs, 8 c-means rules, 5 epochs: the
    shoulder's (gravity-dominated) torque fits to NRMSE < 0.2 on the training data, and every
    joint fits better than with one rule (a single linear map of the same inputs). Measured,
    and the reason the study's ID chapter compares input sets: the other joints' torques stay
    above 0.5 here — M(q) q̈ is a product of angle and acceleration terms that few rules on these
    inputs do not capture."""
    d = id_data["train"]
    fits = {}
    for name, options in (("linear", dict(n_mfs=1)),
                          ("rules", dict(partition="fcm", n_rules=8, mf="gauss"))):
        model = LearnedID(inputs="trig", epochs=5, random_state=0, **options).fit(ROBOT, d, id_data["val"])
        fits[name] = nrmse(model.predict(d["q"], d["qd"], d["qdd"]), d["tau"])
    assert fits["rules"][1] < 0.2, fits
    assert (fits["rules"] < fits["linear"]).all(), fits


def test_residual_model_learns_what_rnea_misses(id_data):
    """On torques of an arm with friction and armature, RNEA + a residual ANFIS is closer than
    RNEA alone; a residual model of frictionless data predicts RNEA to the ANFIS's rounding."""
    import dataclasses
    n = ROBOT.n
    rough = dataclasses.replace(ROBOT, viscous=np.full(n, 0.05), coulomb=np.full(n, 0.08),
                                coulomb_velocity=np.full(n, 0.05), armature=np.full(n, 0.01))
    measured = {k: {**v, "tau": rnea(rough, v["q"], v["qd"], v["qdd"], drive=True)}
                for k, v in id_data.items()}
    model = LearnedID(inputs="own", residual=True, n_mfs=2, epochs=5).fit(
        ROBOT, measured["train"], measured["val"])
    d = measured["test"]
    rigid = np.sqrt(((rnea(ROBOT, d["q"], d["qd"], d["qdd"]) - d["tau"]) ** 2).mean(axis=0))
    learned = np.sqrt(((model.predict(d["q"], d["qd"], d["qdd"]) - d["tau"]) ** 2).mean(axis=0))
    assert (learned < 0.5 * rigid).all(), (learned, rigid)


def test_an_identification_residual_anfis_adds_to_the_arm_identified_on_its_training_states(id_data, tmp_path):
    """``residual="identification"``: the identification of the arm as built (its masses refitted, its drives
    identified) fitted first on the training states, the ANFIS on what it leaves; on a built arm whose Coulomb friction is
    smoothed near rest (``coulomb_velocity``), which the identification's ``tanh(q̇ / ε)`` term of the robot file's ε = 0.01 rad/s cannot hold, the sum's RMSE over the joints is below the
    identification's alone; saved, it loads to the same bits, and a file whose θ is missing or whose residual has
    none is refused, naming the field."""
    import dataclasses

    from nfarm.learning.baselines import baseline_id
    from nfarm.study.id_trajectories import TrueArm, true_arm

    built = true_arm(ROBOT, TrueArm(mass_sd=0.1, com_sd=0.005, inertia_sd=0.2), np.random.default_rng(5))
    n = ROBOT.n
    built = dataclasses.replace(built, viscous=np.full(n, 0.05), coulomb=np.full(n, 0.08),
                                coulomb_velocity=np.full(n, 0.05), armature=np.full(n, 0.01))
    measured = {k: {**v, "tau": rnea(built, v["q"], v["qd"], v["qdd"], drive=True)} for k, v in id_data.items()}
    model = LearnedID(inputs="own", residual="identification", n_mfs=2, epochs=5).fit(
        ROBOT, measured["train"], measured["val"])
    alone = baseline_id("identification").fit(ROBOT, measured["train"])
    np.testing.assert_array_equal(model.prior_, alone.state_["coef"])
    d = measured["test"]
    X = (d["q"], d["qd"], d["qdd"])
    rms = lambda tau: np.sqrt(((tau - d["tau"]) ** 2).mean(axis=0))          # noqa: E731
    learned, identified = rms(model.predict(*X)), rms(alone.predict(*X))
    assert learned.sum() < identified.sum(), (learned, identified)
    assert "τ − the identification (residual)" in model.describe()
    path = model.save(tmp_path)
    np.testing.assert_array_equal(LearnedID.load(tmp_path, ROBOT).predict(*X), model.predict(*X))
    import json

    from nfarm.infra.reading import CONTENT_FIELD, ParamsError, with_content_digest
    data = {k: v for k, v in json.loads(path.read_text()).items() if k != CONTENT_FIELD}
    from nfarm.learning.priors import FITTED_LAW
    assert data["drive_law"] == FITTED_LAW                # the identification's law is named: an older file is refused
    path.write_text(json.dumps(with_content_digest({k: v for k, v in data.items() if k != "drive_law"})))
    with pytest.raises(ParamsError, match=r"learned_id.json: drive_law: must be"):
        LearnedID.load(tmp_path, ROBOT)
    for edit in ({"prior": None}, {"residual": True}):
        edited = {**data, **edit}
        if edit.get("residual") is True:            # a nominal residual's file names no drive law: its prior is refused
            edited.pop("drive_law")
        path.write_text(json.dumps(with_content_digest(edited)))
        with pytest.raises(ParamsError, match=r"learned_id.json: prior\b"):
            LearnedID.load(tmp_path, ROBOT)
    with pytest.raises(ValueError, match=r"residual must be false \(no prior\), true"):
        LearnedID(inputs="own", residual="identified", n_mfs=1, epochs=1).fit(ROBOT, measured["train"])


def test_id_save_load_batching_and_bad_input(id_data, tmp_path):
    model = LearnedID(inputs="trig", partition="fcm", n_rules=4, mf="gauss", epochs=2,
                      random_state=0).fit(ROBOT, id_data["train"])
    d = id_data["test"]
    flat = model.predict(d["q"][:6], d["qd"][:6], d["qdd"][:6])
    assert flat.shape == (6, 5)
    np.testing.assert_array_equal(model.predict(d["q"][:6].reshape(2, 3, 5), d["qd"][:6].reshape(2, 3, 5),
                                                d["qdd"][:6].reshape(2, 3, 5)), flat.reshape(2, 3, 5))
    # As for the IK: other BLAS kernels for one sample; this fcm model's consequents amplify the
    # difference (measured on an AMD EPYC: 1.9e-12 N·m on 0.106 N·m, relative 1.8e-11).
    np.testing.assert_allclose(model.predict(d["q"][4], d["qd"][4], d["qdd"][4]), flat[4], rtol=1e-9, atol=1e-12)
    still = np.zeros(5)                                       # one velocity for every sample: broadcast
    np.testing.assert_array_equal(model.predict(d["q"][:6], still, d["qdd"][:6]),
                                  model.predict(d["q"][:6], np.tile(still, (6, 1)), d["qdd"][:6]))
    path = model.save(tmp_path)
    loaded = LearnedID.load(tmp_path, ROBOT)
    np.testing.assert_array_equal(loaded.predict(d["q"], d["qd"], d["qdd"]),
                                  model.predict(d["q"], d["qd"], d["qdd"]))
    np.testing.assert_array_equal(LearnedID.load(path, ROBOT).predict(d["q"], d["qd"], d["qdd"]),
                                  model.predict(d["q"], d["qd"], d["qdd"]))        # or the file itself
    assert loaded.describe() == model.describe() and path.name == "learned_id.json"
    with pytest.raises(ParamsError, match=r"robot_params_sha256: trained for robot 'intelbot5'"):
        LearnedID.load(tmp_path, PUMA)
    data = json.loads(path.read_text())
    data["input_lo"] = data["input_lo"][:2]
    path.write_text(json.dumps(data))
    with pytest.raises(ParamsError, match=r"content_sha256: does not match"):
        LearnedID.load(tmp_path, ROBOT)
    path.write_text(json.dumps(with_content_digest(data)))
    with pytest.raises(ParamsError, match=r"input_lo: must be a list of 5 items|input_lo: .*5"):
        LearnedID.load(tmp_path, ROBOT)
    with pytest.raises(ValueError, match=r"qd must have shape \(\.\.\., 5\)"):
        model.predict(d["q"][:2], d["qd"][:2, :4], d["qdd"][:2])
    with pytest.raises(ValueError, match=r"must be finite"):
        model.predict(np.full(5, np.nan), np.zeros(5), np.zeros(5))
    with pytest.raises(ValueError, match=r"do not broadcast"):
        model.predict(d["q"][:3], d["qd"][:2], d["qdd"][:2])


@pytest.mark.parametrize("kwargs, change, message", [
    (dict(inputs="torques"), None, r"inputs must be one of own, all, trig, affine_generic, affine, affine_generic_drives, affine_drives, regressor"),
    (dict(residual="yes"), None, r"residual must be false \(no prior\), true or .nominal. \(Newton–Euler.s nominal model\) or .identification. \(the identification of the arm as built\), got .yes."),
    (dict(n_mfs=0), None, r"joint 1: .*n_mfs"),
    ({}, lambda d: {k: v for k, v in d.items() if k != "tau"}, r"train must be a mapping with arrays 'q', 'qd', 'qdd', 'tau'"),
    ({}, lambda d: {**d, "qd": d["qd"][:-1]}, r"train: q, qd, qdd, tau must have one row per sample"),
    ({}, lambda d: {**d, "tau": np.where(np.arange(5) == 1, np.nan, d["tau"])}, r"train: tau contains NaN"),
])
def test_id_fit_refuses_bad_input_before_any_work(id_data, kwargs, change, message):
    train = id_data["train"] if change is None else change(id_data["train"])
    with pytest.raises(ValueError, match=message):
        LearnedID(**kwargs).fit(ROBOT, train)


# -- the model cache ---------------------------------------------------------------------------

from nfarm.learning.model_cache import fit_cached  # noqa: E402


@pytest.mark.parametrize("kind", ["ik", "id"])
def test_fit_cached_reuses_only_what_was_fitted_on_the_same_inputs(kind, data, id_data, tmp_path):
    """Made, then reused with bit-identical predictions; other options, other data or a
    damaged stamp retrain; a model of the other kind never answers for this one."""
    if kind == "ik":
        make = lambda **o: LearnedIK(**{**SMALL, "epochs": 2, **o})                    # noqa: E731
        train, val, other = data["train"], data["val"], {k: v[:-5] for k, v in data["train"].items()}
        inputs = (data["test"]["T"],)
    else:
        make = lambda **o: LearnedID(inputs="own", n_mfs=2, epochs=2, **o)              # noqa: E731
        train, val, other = id_data["train"], id_data["val"], {k: v[:-5] for k, v in id_data["train"].items()}
        inputs = tuple(id_data["test"][k] for k in ("q", "qd", "qdd"))
    model, how = fit_cached(make(), ROBOT, train, val, tmp_path)
    assert how == "made" and (tmp_path / "inputs.sha256").is_file()
    again, how = fit_cached(make(), ROBOT, train, val, tmp_path)
    assert how == "reused"
    np.testing.assert_array_equal(again.predict(*inputs), model.predict(*inputs))
    assert fit_cached(make(mf="gauss"), ROBOT, train, val, tmp_path)[1] == "made"
    assert fit_cached(make(mf="gauss"), ROBOT, other, val, tmp_path)[1] == "made"
    (tmp_path / "inputs.sha256").write_text("0" * 64 + "\n")
    assert fit_cached(make(mf="gauss"), ROBOT, other, val, tmp_path)[1] == "made"
    assert fit_cached(make(mf="gauss"), ROBOT, other, val, tmp_path)[1] == "reused"
    with pytest.raises(TypeError, match="must be a LearnedIK, a LearnedID, a RivalIK or a BaselineID"):
        fit_cached(object(), ROBOT, train, val, tmp_path)


def test_fit_cached_does_not_reuse_a_model_trained_in_another_numerical_environment(
        data, tmp_path, monkeypatch):
    options = dict(SMALL, epochs=1)
    monkeypatch.setenv("NPY_DISABLE_CPU_FEATURES", "X86_V4")
    assert fit_cached(LearnedIK(**options), ROBOT, data["train"], None, tmp_path)[1] == "made"
    assert fit_cached(LearnedIK(**options), ROBOT, data["train"], None, tmp_path)[1] == "reused"
    monkeypatch.delenv("NPY_DISABLE_CPU_FEATURES")
    assert fit_cached(LearnedIK(**options), ROBOT, data["train"], None, tmp_path)[1] == "made"


def test_the_arm_chart_describes_an_arm_whose_tool_is_off_its_roll_axis(tmp_path):
    """intelbot5 needs no chart (its tool point is on its roll axis and its base the world);
    the SO-101's tool point is 7.9 mm off its roll axis and its base axis points down: in the
    world its approach axis leaves the arm's plane by degrees, in its chart by less than 0.2°
    (the CAD model's sub-millimetre offsets). A model fitted with a chart saves and loads it."""
    from nfarm.learning.learned import arm_chart
    assert arm_chart(ROBOT) is None
    so101 = load_robot(PARAMS / "robots" / "so101.yaml")
    chart = arm_chart(so101)
    study = load_study(PARAMS / "studies" / "so101.yaml")
    data = ik_samples(study.ik_region, 400, 5)
    assert np.degrees(out_of_plane(data["T"]).max()) > 5
    assert np.degrees(out_of_plane(data["T"], chart).max()) < 0.2
    np.testing.assert_allclose(chart[1][:3, 3], [-0.0079, 0.0002, 0.0], atol=2e-4)
    model = LearnedIK(**{**SMALL, "epochs": 2}, max_out_of_plane=np.radians(0.5)).fit(so101, data)
    model.save(tmp_path)
    again = LearnedIK.load(tmp_path, so101)
    np.testing.assert_array_equal(again.encoder_.chart_, chart)
    np.testing.assert_array_equal(again.predict(data["T"]), model.predict(data["T"]))
    with pytest.raises(ValueError, match="leave it by up to"):
        LearnedIK(**{**SMALL, "epochs": 2}).fit(so101, data)


def test_a_tool_frame_in_ros_convention_gets_a_rigid_chart(tmp_path):
    """ROS tool frames put x along the approach axis (here intelbot5's tool turned so): the chart
    takes the tool axis along the roll axis and the tool's y across it, is rigid, keeps the arm's
    plane, and a model fitted with it saves and loads (it failed with "chart[1]: must be a rigid
    transform": the tool's x made perpendicular to itself)."""
    import dataclasses
    from nfarm.learning.learned import arm_chart
    Ry = np.array([[0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
    ros = dataclasses.replace(ROBOT, tool=ROBOT.tool @ Ry)       # x' = z: the approach
    chart = arm_chart(ros)
    for T in chart:
        np.testing.assert_allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-12)
        assert np.linalg.det(T[:3, :3]) > 0
    region = dataclasses.replace(STUDY.ik_region, robot=ros)
    data = ik_samples(region, 400, 5)
    assert np.degrees(out_of_plane(data["T"], chart).max()) < 1e-6
    model = LearnedIK(**{**SMALL, "epochs": 2}).fit(ros, data)
    model.save(tmp_path)
    again = LearnedIK.load(tmp_path, ros)
    np.testing.assert_array_equal(again.predict(data["T"]), model.predict(data["T"]))
    # The same arm with either tool frame: the same inputs up to the encoder's own scaling.
    plain = LearnedIK(**{**SMALL, "epochs": 2}).fit(ROBOT, ik_samples(STUDY.ik_region, 400, 5))
    np.testing.assert_allclose(model.predict(data["T"]), plain.predict(fk(ROBOT, data["q"])), atol=1e-9)


# -- inputs that cannot be right ---------------------------------------------------------------


def test_poses_far_outside_the_training_data_are_predicted_with_a_warning(fitted, data):
    from nfarm.learning.learned import OutsideTrainingWarning
    import warnings
    T = data["test"]["T"][:3].copy()
    with warnings.catch_warnings():
        warnings.simplefilter("error", OutsideTrainingWarning)
        inside = fitted.predict(T)                       # the region's own test poses: no warning
    T[1, :3, 3] += [1e3, 0.0, 0.0]
    with pytest.warns(OutsideTrainingWarning, match=r"1 of 3 poses lie beyond the training data's input range by "
                                                    r"more than 0.5 of it \(up to .*; first: pose 1\)"):
        far = fitted.predict(T)
    np.testing.assert_array_equal(far[[0, 2]], inside[[0, 2]])
    with warnings.catch_warnings():
        warnings.simplefilter("error", OutsideTrainingWarning)
        fitted.predict(T, far=np.inf)
    for bad in (-1.0, float("nan"), True, "0.5"):
        with pytest.raises(ValueError, match=r"far must be a number >= 0"):
            fitted.predict(T, far=bad)
    with pytest.raises(ValueError, match=r"got complex numbers"):
        fitted.predict(T.astype(complex))


def test_the_outside_training_warning_carries_its_counts_as_fields():
    """What the message states, a reader (chapter 7) reads as fields, the farthest unrounded."""
    import pickle
    import warnings
    from nfarm.learning.per_joint import OutsideTrainingWarning, warn_far
    beyond = np.array([0.0, 0.25, 0.75, 3.14159, 0.5])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", OutsideTrainingWarning)
        warn_far(beyond, 0.5, "states")
        warn_far(beyond, np.inf, "states")                       # none beyond: no warning
    [w] = caught
    m = w.message
    assert isinstance(m, OutsideTrainingWarning)
    assert (m.count, m.total, m.what, m.far, m.how_far, m.first) == (2, 5, "states", 0.5, 3.14159, 2)
    assert str(m) == ("2 of 5 states lie beyond the training data's input range by more than 0.5 of it "
                      "(up to 3.14; first: state 2): predicted by extrapolation")
    again = pickle.loads(pickle.dumps(m))                          # e.g. from a worker process
    assert (str(again), again.count, again.how_far) == (str(m), 2, 3.14159)


def test_states_far_outside_the_training_data_warn_and_overflowing_ones_are_refused(id_data):
    from nfarm.learning.learned import OutsideTrainingWarning
    import warnings
    d = id_data["val"]
    model = LearnedID(inputs="affine_generic", n_mfs=1, epochs=1).fit(ROBOT, id_data["train"])   # products of q̇
    q, qd, qdd = d["q"][:4].copy(), d["qd"][:4].copy(), d["qdd"][:4].copy()
    with warnings.catch_warnings():
        warnings.simplefilter("error", OutsideTrainingWarning)
        model.predict(q, qd, qdd)
    qd[2] = 10 * np.abs(d["qd"]).max(axis=0)          # ten times the fastest validation state
    with pytest.warns(OutsideTrainingWarning, match=r"1 of 4 states lie beyond .*first: state 2\)"):
        model.predict(q, qd, qdd)
    qd[3] = 1e200
    with warnings.catch_warnings():
        warnings.simplefilter("error")                    # no RuntimeWarning from numpy either
        with pytest.raises(ValueError, match=r"the torques of 1 of 4 states overflow \(first: state 3, its inputs "
                                             r".* training ranges beyond"):
            model.predict(q, qd, qdd)
    with pytest.raises(ValueError, match=r"q, qd, qdd must be finite|must be real|complex"):
        model.predict(q.astype(complex), qd, qdd)


def test_the_learned_ik_and_its_baselines_see_the_same_inputs(data):
    """One PoseEncoder for both: the same chart, unwrapping and scaling, bit for bit."""
    from nfarm.learning.encoding import PoseEncoder
    from nfarm.learning.learned import Baseline
    model = LearnedIK(**{**SMALL, "encoding": "arm_plane", "epochs": 1}).fit(ROBOT, data["train"])
    base = Baseline("linear", encoding="arm_plane").fit(ROBOT, data["train"])
    plain = PoseEncoder("arm_plane").fit(ROBOT, data["train"]["T"])
    T = data["test"]["T"]
    np.testing.assert_array_equal(model.encoder_.transform(T), base.encoder_.transform(T))
    np.testing.assert_array_equal(plain.transform(T), base.encoder_.transform(T))
    with pytest.raises(ValueError, match="this PoseEncoder is not fitted yet: call fit"):
        PoseEncoder().transform(T)


def test_the_pose_encoder_is_public_batched_and_saved_with_the_model(data, tmp_path):
    """The encoder's names, batching and fields: a LearnedIK file holds them at its top level,
    under the keys it always had, and they rebuild the encoder bit for bit."""
    from nfarm.learning.encoding import PoseEncoder
    so101 = load_robot(PARAMS / "robots" / "so101.yaml")
    so101_poses = fk(so101, np.zeros((1, so101.n)))
    encoder = PoseEncoder("arm_plane", max_out_of_plane=0.5).fit(so101, so101_poses)
    assert encoder.chart_ is not None and repr(encoder) == "PoseEncoder(encoding='arm_plane', max_out_of_plane=0.5)"
    for name, d in ENCODINGS.items():
        encoder = PoseEncoder(name).fit(ROBOT, data["train"]["T"])
        assert encoder.feature_names_ == FEATURE_NAMES[name] and len(encoder.feature_names_) == d
        T = data["test"]["T"][:6]
        np.testing.assert_array_equal(encoder.transform(T.reshape(2, 3, 4, 4)).reshape(6, d), encoder.transform(T))
        again = PoseEncoder.from_dict(json.loads(json.dumps(encoder.to_dict())))
        np.testing.assert_array_equal(again.transform(T), encoder.transform(T))
    model = LearnedIK(**{**SMALL, "epochs": 1}).fit(ROBOT, data["train"])
    saved = json.loads(model.save(tmp_path).read_text())
    assert {"encoding", "max_out_of_plane", "angle_centre", "input_lo", "input_span"} <= set(saved)
    assert "chart" not in saved                                  # intelbot5's chart is the identity
    with pytest.raises(ValueError, match=r"save takes a directory \(the model is written into it as "
                                         r"learned_ik.json\), got the file name"):
        model.save(tmp_path / "model.json")
