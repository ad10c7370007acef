"""The learned-IK contest's learners: ANFIS's best shot (shared premises for the pitch joints, the
pitch closure) in nfarm.learning.learned, the rivals of nfarm.learning.ik_rivals, and the
``ik_contest`` job that judges them at the tool."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from nfarm.infra.paths import PARAMS
from nfarm.infra.reading import ParamsError
from nfarm.learning.anfis import ANFIS, fit_shared
from nfarm.learning.ik_rivals import RIVALS as REGISTERED, RivalIK, rival_ik
from nfarm.learning.learned import LearnedIK, ik_errors
from nfarm.model.kinematics import fk
from nfarm.study.regions import ik_samples
from nfarm.study.study_files import load_study

STUDY = load_study(PARAMS / "studies" / "intelbot5.yaml")
ROBOT = STUDY.robot
LINEAR = {"partition": "grid", "n_mfs": 1}
BEST_SHOT = dict(encoding="arm_plane", partition="fcm", n_rules=6, mf="gauss", epochs=4, ridge=1e-8,
                 joint_options=[LINEAR, {}, {}, {}, LINEAR], shared_joints=[1, 2, 3], random_state=0)


@pytest.fixture(scope="module")
def data():
    return {split: ik_samples(STUDY.ik_region, n, seed)
            for split, n, seed in (("train", 1200, 1), ("val", 300, 2))}


@pytest.fixture(scope="module")
def closed(data):
    return LearnedIK(**BEST_SHOT, pitch_closure=True).fit(ROBOT, data["train"], data["val"])


# -- ANFIS's best shot --------------------------------------------------------------------------


def test_shared_joints_train_one_multiple_output_anfis(data):
    model = LearnedIK(**BEST_SHOT).fit(ROBOT, data["train"], data["val"])
    X = model.encoder_.transform(data["train"]["T"])
    Xv = model.encoder_.transform(data["val"]["T"])
    options = {k: v for k, v in BEST_SHOT.items() if k not in ("encoding", "joint_options", "shared_joints")}
    alone = fit_shared(ANFIS(**options, feature_names=model.encoder_.feature_names_), X,
                       data["train"]["q"][:, [1, 2, 3]], Xv, data["val"]["q"][:, [1, 2, 3]])
    for j, m in zip((1, 2, 3), alone):       # the same premises and consequents, bit for bit
        np.testing.assert_array_equal(model.models_[j].consequents_, m.consequents_)
    np.testing.assert_array_equal(model.models_[1].mfs_initial_[0], model.models_[3].mfs_initial_[0])


def test_the_pitch_closure_makes_the_tools_pitch_exact(closed, data):
    """q2 + q3 + q4 is the tool's pitch for intelbot5 (sign +1): with the closure the
    predicted pitch sum is the target's to rounding, whatever the planar models' errors."""
    assert closed.closure_["sign"] == 1 and closed.closure_["joint"] == 3
    T = data["val"]["T"]
    q = closed.predict(T)
    e = ik_errors(ROBOT, q, data["val"]["q"], T)
    pitch = q[:, 1:4].sum(axis=1) - data["val"]["q"][:, 1:4].sum(axis=1)
    assert np.abs(np.angle(np.exp(1j * pitch))).max() < 1e-12
    # What is left of the orientation error: q1's and q5's one-rule maps, biased by the ridge only
    assert np.degrees(e["orientation"]).max() < 1e-3
    assert 1e3 * e["position"].max() > 1e-3             # the planar models are not exact
    unclosed = np.column_stack([m.predict(closed.encoder_.transform(T)) for m in closed.models_])
    np.testing.assert_array_equal(q[:, [0, 1, 2, 4]], unclosed[:, [0, 1, 2, 4]])


def test_the_closure_is_saved_and_loaded_bit_for_bit(closed, data, tmp_path):
    closed.save(tmp_path)
    again = LearnedIK.load(tmp_path, ROBOT)
    assert again.closure_ == closed.closure_ and again.shared_joints == [1, 2, 3]
    np.testing.assert_array_equal(again.predict(data["val"]["T"]), closed.predict(data["val"]["T"]))


def test_an_edited_closure_is_refused(closed, tmp_path):
    from nfarm.infra.reading import with_content_digest

    path = closed.save(tmp_path)
    content = json.loads(path.read_text())
    content.pop("content_sha256", None)
    content["closure"]["sign"] = 2
    path.write_text(json.dumps(with_content_digest(content)))
    with pytest.raises(ParamsError, match=r"learned_ik.json: closure: joint must be 3 and sign 1 or -1"):
        LearnedIK.load(tmp_path, ROBOT)


def test_a_pose_set_that_breaks_the_pitch_identity_is_refused(data):
    """Reaching back over the base turns the azimuth by 180°: the joints' pitch sum is then
    π − φ, not φ + c — the closure must refuse rather than predict the wrong branch."""
    rng = np.random.default_rng(0)
    q = rng.uniform(ROBOT.qlim[:, 0], ROBOT.qlim[:, 1], (800, 5))
    with pytest.raises(ValueError, match=r"^pitch_closure: joints 2-4's angles do not sum to the tool's pitch"):
        LearnedIK(**BEST_SHOT, pitch_closure=True, max_out_of_plane=math.pi).fit(ROBOT, {"T": fk(ROBOT, q), "q": q})


@pytest.mark.parametrize("kwargs, message", [
    ({"shared_joints": [1]}, r"shared_joints must be None or at least two distinct joint indices in \[0, 5\)"),
    ({"shared_joints": [1, 1]}, r"shared_joints must be None or at least two distinct"),
    ({"shared_joints": [0, 1]}, r"shared_joints: joint 2's options differ from joint 1's"),
    ({"pitch_closure": True, "encoding": "quat_xyz"}, r"pitch_closure needs the 'arm_plane' encoding"),
    ({"pitch_closure": True, "closure_tolerance": 0}, r"closure_tolerance must be in \(0, pi\) rad"),
])
def test_bad_best_shot_options_are_one_clear_error_before_training(data, kwargs, message):
    with pytest.raises(ValueError, match=message):
        LearnedIK(**{**BEST_SHOT, **kwargs}).fit(ROBOT, data["train"])


# -- the rivals ---------------------------------------------------------------------------------

RIVALS = [("knn", {"neighbors": 3}), ("rbf", {"neighbors": 16}), ("rbf", {"neighbors": 32, "kernel": "quintic"}),
          ("mlp", {"hidden": [32, 32], "max_epochs": 300, "patience": 10}),
          ("kernel_ridge", {"components": 200, "gamma": 5.0}),
          ("kernel_ridge", {"length_scales": "fitted", "subset": 150})]


@pytest.fixture(scope="module", params=RIVALS, ids=lambda r: f"{r[0]}-{len(r[1])}")
def rival(request, data):
    kind, options = request.param
    return rival_ik(kind, "arm_plane", options, random_state=0).fit(ROBOT, data["train"], data["val"])


def test_every_rival_learns_the_map_well_beyond_a_constant(rival, data):
    """Each rival's joint RMSE on validation poses is below half the joints' own spread (the
    RMSE of predicting the mean): it has learned the map, whatever its kind. Measured on these
    1 200 poses: 0.38 for three nearest neighbours' worst joint, 0.22 or less for the others."""
    q = rival.predict(data["val"]["T"])
    rmse = np.sqrt(((q - data["val"]["q"]) ** 2).mean(axis=0))
    assert (rmse < data["val"]["q"].std(axis=0) / 2).all()


def test_every_rival_is_saved_and_loaded_bit_for_bit(rival, data, tmp_path):
    rival.save(tmp_path)
    again = RivalIK.load(tmp_path, ROBOT)
    np.testing.assert_array_equal(again.predict(data["val"]["T"]), rival.predict(data["val"]["T"]))
    # The saved options are the fitted ones, every default written out (a later change of a
    # default cannot change a saved model)
    assert type(again) is type(rival) and again.options_ == rival.options_
    assert set(again.options_) == set(rival.hyper_params())
    assert {k: v for k, v in again.get_params().items() if k not in again.options_} == \
        {k: v for k, v in rival.get_params().items() if k not in rival.options_}


def test_the_mlp_keeps_its_best_validation_epoch_and_predicts_as_scikit_learn(data):
    """The saved forward pass is scikit-learn's on the kept weights; the kept epoch is the one of
    least validation error, and training stopped ``patience`` epochs after it (or at the cap)."""
    from sklearn.neural_network import MLPRegressor

    model = rival_ik("mlp", "arm_plane", {"hidden": [16, 16], "max_epochs": 40, "patience": 3},
                     random_state=0).fit(ROBOT, data["train"], data["val"])
    assert model.epochs_ == 40 or model.epochs_ == model.best_epoch_ + 1 + 3
    net = MLPRegressor(hidden_layer_sizes=(16, 16))
    net.coefs_, net.intercepts_ = model.weights_, model.biases_
    net.n_layers_, net.out_activation_, net.activation = 4, "identity", "relu"
    net.n_outputs_ = 5
    X = model.encoder_.transform(data["val"]["T"])
    np.testing.assert_allclose(model.predict(data["val"]["T"]),
                               net.predict(X) * model.y_scale_ + model.y_mean_, rtol=0, atol=1e-12)


@pytest.mark.parametrize("patience", [2, 4])
def test_the_mlp_counts_only_falls_of_min_improvement(data, patience):
    """A ``min_improvement`` no fall can reach (all but the whole error) leaves only the first
    epoch as the reference: training stops ``patience`` epochs after it, whatever the errors do,
    and keeps the least of those epochs; an impossible share is refused in one line."""
    model = rival_ik("mlp", "arm_plane", {"hidden": [16, 16], "max_epochs": 40, "patience": patience,
                                          "min_improvement": 1 - 1e-12}, random_state=0).fit(ROBOT, data["train"], data["val"])
    assert model.epochs_ == 1 + patience and 0 <= model.best_epoch_ <= patience
    with pytest.raises(ValueError, match="mlp: min_improvement must be below 1"):
        rival_ik("mlp", "arm_plane", {"min_improvement": 1.0}).fit(ROBOT, data["train"], data["val"])


def test_kernel_ridge_equals_scikit_learns_nystroem_and_ridge(data):
    from sklearn.kernel_approximation import Nystroem
    from sklearn.linear_model import Ridge
    from sklearn.pipeline import make_pipeline

    model = rival_ik("kernel_ridge", "arm_plane", {"components": 150, "gamma": 4.0, "alpha": 1e-6},
                     random_state=3).fit(ROBOT, data["train"])
    X = model.encoder_.transform(data["train"]["T"])
    Z = (data["train"]["q"] - model.y_mean_) / model.y_scale_
    pipe = make_pipeline(Nystroem(gamma=4.0, n_components=150, random_state=3), Ridge(alpha=1e-6)).fit(X, Z)
    Xv = model.encoder_.transform(data["val"]["T"])
    np.testing.assert_allclose(model.predict(data["val"]["T"]), pipe.predict(Xv) * model.y_scale_ + model.y_mean_,
                               rtol=0, atol=1e-8)


@pytest.mark.filterwarnings("ignore::sklearn.exceptions.ConvergenceWarning")    # the reference's own fit
@pytest.mark.parametrize("structure", ["whole", "arm"])
def test_kernel_ridge_with_fitted_length_scales_is_scikit_learns_gaussian_process(data, structure):
    """The fitted configuration's hyper-parameters are those scikit-learn's Gaussian process finds on
    the same subset (inputs divided by their spread), and its prediction is that process's
    posterior mean on all the training poses, computed by scikit-learn with those hyper-parameters."""
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

    from nfarm.learning.ik_rivals import GP_BOUNDS

    model = rival_ik("kernel_ridge", "arm_plane", {"length_scales": "fitted", "subset": 120}, random_state=5,
                     structure=structure).fit(ROBOT, data["train"])
    X = model.encoder_.transform(data["train"]["T"])
    Z = (data["train"]["q"][:, model.learned_] - model.y_mean_) / model.y_scale_
    spread = X.std(axis=0)
    pick = np.sort(np.random.default_rng(5).permutation(len(X))[:120])
    kernel = (ConstantKernel(1.0, GP_BOUNDS["amplitude"]) * RBF(np.ones(X.shape[1]), GP_BOUNDS["length_scale"])
              + WhiteKernel(1e-4, GP_BOUNDS["noise"]))
    found = GaussianProcessRegressor(kernel, random_state=5).fit(X[pick] / spread, Z[pick]).kernel_
    np.testing.assert_allclose(model.length_scales_, spread * found.k1.k2.length_scale, rtol=1e-12)
    assert model.amplitude_ == pytest.approx(found.k1.k1.constant_value, rel=1e-12)
    fixed = (ConstantKernel(model.amplitude_, "fixed") * RBF(model.length_scales_, "fixed")
             + WhiteKernel(model.noise_, "fixed"))
    process = GaussianProcessRegressor(fixed, optimizer=None).fit(X, Z)
    Xv = model.encoder_.transform(data["val"]["T"])
    np.testing.assert_allclose(model._predict(Xv), process.predict(Xv), rtol=0, atol=1e-6)   # the learned joints, standardised
    assert {k: model.options_[k] for k in ("length_scales", "subset", "restarts")} == \
        {"length_scales": "fitted", "subset": 120, "restarts": 0}


def test_a_fitted_kernel_ridge_predicts_in_blocks_as_at_once(data, monkeypatch):
    model = rival_ik("kernel_ridge", "arm_plane", {"length_scales": "fitted", "subset": 80},
                     random_state=1).fit(ROBOT, data["train"])
    whole = model.predict(data["val"]["T"])
    monkeypatch.setattr(type(model), "PREDICT_ROWS", 7)
    # not bit for bit: BLAS sums a block's products in another order, and a near-interpolating
    # process's weights are large and of both signs (1e-9 rad is 1e-7 degrees)
    np.testing.assert_allclose(model.predict(data["val"]["T"]), whole, rtol=0, atol=1e-9)


@pytest.mark.parametrize("options, message", [
    ({"length_scales": "per_input"}, r"^kernel_ridge: length_scales must be 'shared' or 'fitted', got 'per_input'$"),
    ({"length_scales": "fitted", "subset": 1}, r"^kernel_ridge: subset must be a whole number in \[2, 5000\], got 1$"),
    ({"length_scales": "fitted", "restarts": -1}, r"^kernel_ridge: restarts must be a whole number in \[0, 20\], got -1$"),
])
def test_bad_gaussian_process_options_are_one_clear_error(data, options, message):
    with pytest.raises(ValueError, match=message):
        rival_ik("kernel_ridge", "arm_plane", options).fit(ROBOT, data["train"])


def test_a_gaussian_process_on_more_poses_than_it_can_hold_is_refused_before_any_work(data, monkeypatch):
    from nfarm.learning import ik_rivals

    monkeypatch.setattr(ik_rivals, "GP_MAX_POSES", 100)
    with pytest.raises(ValueError, match=r"^kernel_ridge: length_scales 'fitted' solves on every training pose exactly, "
                                         r"at most 100 \(an N x N kernel of 0 MB\), got \d+; for more, length_scales "
                                         r"'shared' \(Nystrom\)$"):
        rival_ik("kernel_ridge", "arm_plane", {"length_scales": "fitted", "subset": 50}).fit(ROBOT, data["train"])


@pytest.mark.parametrize("options, drop, add, message", [
    ({"length_scales": "fitted", "subset": 60}, "length_scales", None,
     r"state.length_scales: is required with length_scales 'fitted'"),
    ({"components": 40, "gamma": 2.0}, None, ("noise", 1e-6),
     r"state: length_scales, amplitude and noise belong to length_scales 'fitted'"),
    ({"length_scales": "fitted", "subset": 60}, None, ("length_scales", [1.0, -1.0, 1.0, 1.0, 1.0, 1.0]),
     r"state.length_scales: must be > 0"),
])
def test_a_saved_kernel_ridge_with_the_wrong_state_for_its_length_scales_is_refused(data, options, drop, add, message):
    saved = rival_ik("kernel_ridge", "arm_plane", options, random_state=0).fit(ROBOT, data["train"]).to_dict()
    if drop:
        del saved["state"][drop]
    if add:
        saved["state"][add[0]] = add[1]
    with pytest.raises(ParamsError, match=message):
        RivalIK.from_dict(saved, ROBOT, "rival_ik.json")


@pytest.mark.parametrize("kind, options, message", [
    ("svm", {}, r"^kind must be one of knn, rbf, mlp, kernel_ridge, got 'svm'$"),
    ("knn", {"k": 3}, r"^knn: unknown option 'k'; valid: neighbors, weights$"),
    ("knn", {"neighbors": 0}, r"^knn: neighbors must be a whole number in \[1, 10000\], got 0$"),
    ("rbf", {"kernel": "gaussian"}, r"^rbf: kernel must be one of thin_plate_spline, cubic, quintic, linear"),
    ("mlp", {"hidden": []}, r"^mlp: hidden must be 1 to 8 layer widths"),
    ("mlp", {"learning_rate": float("nan")}, r"^mlp: learning_rate must be a finite number > 0"),
    ("kernel_ridge", {"gamma": -1.0}, r"^kernel_ridge: gamma must be a finite number > 0"),
])
def test_bad_rival_options_are_one_clear_error_before_any_work(data, kind, options, message):
    with pytest.raises(ValueError, match=message):
        rival_ik(kind, "arm_plane", options).fit(ROBOT, data["train"], data["val"])


def test_an_mlp_without_validation_poses_is_refused(data):
    with pytest.raises(ValueError, match="an mlp rival keeps its best epoch on validation poses: give val"):
        rival_ik("mlp").fit(ROBOT, data["train"])


def test_a_rival_loaded_for_another_robot_is_refused(data, tmp_path):
    from nfarm.model.robot import load_robot

    rival_ik("knn", "arm_plane").fit(ROBOT, data["train"]).save(tmp_path)
    so101 = load_robot(PARAMS / "robots" / "so101.yaml")
    with pytest.raises(ParamsError, match=r"rival_ik.json: robot_params_sha256: trained for robot 'intelbot5'"):
        RivalIK.load(tmp_path, so101)


def test_every_kind_is_covered():
    assert {k for k, _ in RIVALS} == set(REGISTERED)


def test_a_quintic_rbf_with_too_few_neighbours_is_refused_in_one_line(data):
    with pytest.raises(ValueError, match=r"^rbf: the quintic kernel's degree-2 polynomial needs neighbors >= 28 "
                                         r"for the 6 inputs of 'arm_plane', got 16$"):
        rival_ik("rbf", "arm_plane", {"neighbors": 16, "kernel": "quintic"}).fit(ROBOT, data["train"])


# -- the contest's rules (nfarm.study.contest) --------------------------------------------------


def _result(learner, encoding, seed, p95, orientation=0.1, seconds=1.0, **options):
    from nfarm.study.sweep import CellResult
    from nfarm.study.sweep_files import Cell

    params = {"learner": learner, "encoding": encoding, "options": options, "seed": seed, "split": "val"}
    return CellResult(Cell(params, f"{learner}{encoding}{seed}{sorted(options.items())}"), "ok",
                      {"position_p95_mm": p95, "orientation_p95_deg": orientation, "fit_seconds": seconds},
                      seconds, "w")


def test_each_contestant_is_chosen_on_its_seed_0_validation_by_the_tool_metrics():
    from nfarm.study import contest

    results = [_result("anfis", "arm_plane", 0, 2.0, n_rules=8), _result("anfis", "arm_plane", 0, 1.0, n_rules=64),
               _result("anfis", "arm_plane", 1, 0.1, n_rules=8),          # another draw: not a choice
               _result("anfis", "quat_xyz", 0, 9.0, mf="gbell"),
               _result("rbf", "arm_plane", 0, 1.0, 0.5, neighbors=32), _result("rbf", "arm_plane", 0, 1.0, 0.2, neighbors=64)]
    chosen = contest.choose(results)
    assert list(chosen) == ["anfis:arm_plane", "anfis:quat_xyz", "rbf"]
    assert chosen["anfis:arm_plane"].cell.params["options"] == {"n_rules": 64}
    assert chosen["rbf"].cell.params["options"] == {"neighbors": 64}      # the orientation breaks the tie
    # configurations, fits, poses × passes (no poses in these records), training and cells' seconds
    assert contest.budgets(results) == {"anfis:arm_plane": (2, 2, 0, 2.0, 2.0), "anfis:quat_xyz": (1, 1, 0, 1.0, 1.0),
                                        "rbf": (2, 2, 0, 2.0, 2.0)}
    # In contention: the two best, and those within twice the best's p95 (the recipe's 9 mm is not)
    assert contest.contending(chosen) == ["anfis:arm_plane", "rbf"]
    assert contest.contending(chosen, keep_within=10) == ["anfis:arm_plane", "rbf", "anfis:quat_xyz"]
    assert [(contest.family(p), p["seed"]) for p in contest.spread_params(chosen, (1, 2))] == \
        [("anfis:arm_plane", 1), ("anfis:arm_plane", 2), ("rbf", 1), ("rbf", 2)]


def test_successive_halving_promotes_each_contestants_best_two_to_all_the_poses():
    from nfarm.study import contest

    rung = [_result("anfis", "arm_plane", 0, p95, n_rules=n) for n, p95 in ((8, 4.0), (16, 2.0), (32, 3.0), (64, 1.0))]
    rung += [_result("rbf", "arm_plane", 0, 1.0, neighbors=32), _result("knn", "arm_plane", 1, 0.5, neighbors=3)]
    promoted = contest.promoted_params(rung, keep=2)
    assert [(contest.family(p), p["options"], p["fraction"]) for p in promoted] == \
        [("anfis:arm_plane", {"n_rules": 16}, 1.0), ("anfis:arm_plane", {"n_rules": 64}, 1.0),
         ("rbf", {"neighbors": 32}, 1.0)]                # seed 1 is not a choice; a lone configuration goes on
    assert [p["options"] for p in contest.promoted_params(rung, keep=1)][:1] == [{"n_rules": 64}]
    assert len(contest.promoted_params(rung)) == 2 * contest.PROMOTED      # the two contestants of seed 0
    # The budget counts configurations, not rungs: a promoted configuration is one tried, its seconds added
    from nfarm.study.sweep import CellResult
    from nfarm.study.sweep_files import Cell
    again = [CellResult(Cell(p, f"full{k}"), "ok", {"position_p95_mm": p95, "orientation_p95_deg": 0.1, "fit_seconds": 4.0},
                        4.0, "w") for k, (p, p95) in enumerate(zip(promoted[:2], (1.5, 0.9)))]
    assert contest.budgets(rung[:4] + again)["anfis:arm_plane"] == (4, 6, 0, 12.0, 12.0)     # 4 configurations, 6 fits
    assert contest.choose(again)["anfis:arm_plane"].cell.params["options"] == {"n_rules": 64}


def test_standings_rank_by_the_mean_over_seeds_and_gaps_are_paired():
    from nfarm.study import contest

    a = [_result("anfis", "arm_plane", s, p, n_rules=64) for s, p in enumerate((1.0, 1.2, 0.8))]
    b = [_result("rbf", "arm_plane", s, p, neighbors=64) for s, p in enumerate((1.1, 1.0, 1.0))]
    chosen = contest.choose(a + b)
    ranked = contest.standings(chosen, a[1:] + b[1:])
    assert [contest.family(g.cell.params) for g in ranked] == ["anfis:arm_plane", "rbf"]   # 1.0 < 1.033
    pruned = _result("knn", "arm_plane", 0, 0.9, neighbors=5)     # better on seed 0, but one draw only
    assert [contest.family(g.cell.params) for g in contest.standings({**chosen, "knn": pruned}, a[1:] + b[1:])] == \
        ["anfis:arm_plane", "rbf", "knn"]
    mean, low, high = contest.paired_gap(ranked[0], ranked[1])
    assert (low, high) == pytest.approx((-0.2, 0.2)) and mean == pytest.approx(-1 / 30)   # contains 0: no difference
    with pytest.raises(ValueError, match=r"paired_gap needs the same seeds, got \[0, 1, 2\] and \[0\]"):
        contest.paired_gap(ranked[0], contest.standings(contest.choose(b), [])[0])
    assert contest.label("rbf") == "RBF interpolation"


def test_the_saved_rivals_are_ranked_as_the_contest_ranks(data, tmp_path):
    """Chapters 7 and 8 pick the best frozen rival by the contest's rule on validation poses."""
    from nfarm.study import contest

    knn = rival_ik("knn", "arm_plane", {"neighbors": 3}).fit(ROBOT, data["train"])
    rbf = rival_ik("rbf", "arm_plane", {"neighbors": 16}).fit(ROBOT, data["train"])
    knn.save(tmp_path / "ik_contest" / "knn")
    rbf.save(tmp_path / "ik_contest" / "rbf")
    rivals = contest.saved_rivals(ROBOT, tmp_path)
    assert sorted(rivals) == ["knn", "rbf"]
    p95 = {kind: np.percentile(ik_errors(ROBOT, m.predict(data["val"]["T"]), data["val"]["q"], data["val"]["T"])["position"], 95)
           for kind, m in rivals.items()}
    assert contest.rival_ranking(ROBOT, rivals, data["val"]) == sorted(p95, key=p95.get)
    assert contest.saved_rivals(ROBOT, tmp_path / "none") == {}


def test_the_saved_rivals_ranked_from_the_contests_records_as_by_predicting_them(data, tmp_path):
    """Chapter 7 ranks the frozen rivals by the validation metrics chapter 6 recorded beside each
    (contest.save_validation, saved_ranking), not by predicting the validation poses again: the same
    order as rival_ranking's for the same models, the orientation deciding a tie in position, and
    ``None`` (rank them again) where a record is missing or damaged."""
    from nfarm.study import contest

    rivals = {}
    for kind, options in (("knn", {"neighbors": 3}), ("rbf", {"neighbors": 16}), ("knn:arm", {"neighbors": 1})):
        rivals[kind] = rival_ik(kind.split(":")[0], "arm_plane", options).fit(ROBOT, data["train"])
        e = ik_errors(ROBOT, rivals[kind].predict(data["val"]["T"]), data["val"]["q"], data["val"]["T"])
        contest.save_validation(tmp_path / "ik_contest" / kind.replace(":", "_"),
                                _result(kind, "arm_plane", 0, float(np.percentile(e["position"], 95) * 1e3),
                                        float(np.degrees(np.percentile(e["orientation"], 95)))))
    assert contest.saved_ranking(tmp_path, rivals) == contest.rival_ranking(ROBOT, rivals, data["val"])
    assert len(set(contest.saved_ranking(tmp_path, rivals))) == 3
    contest.save_validation(tmp_path / "ik_contest" / "a", _result("rbf", "arm_plane", 0, 1.0, orientation=0.2))
    contest.save_validation(tmp_path / "ik_contest" / "b", _result("rbf", "arm_plane", 0, 1.0, orientation=0.1))
    assert contest.saved_ranking(tmp_path, ["a", "b"]) == ["b", "a"]
    assert contest.saved_ranking(tmp_path, ["a", "missing"]) is None
    (tmp_path / "ik_contest" / "a" / contest.VALIDATION_FILE).write_text('{"position_p95_mm": 1.0}')
    assert contest.saved_ranking(tmp_path, ["a", "b"]) is None


def test_a_choice_at_the_edge_of_its_search_is_named():
    """A chosen value that is the least or the greatest of three or more tried is at the search's edge; an option
    with two values, a list or a flag is not judged."""
    from nfarm.study import contest

    rung = [_result("kernel_ridge", "arm_plane", 0, p95, gamma=g, components=1000, hidden=[8], flag=True)
            for g, p95 in ((1.0, 2.0), (3.0, 3.0), (10.0, 5.0))]
    rung += [_result("rbf", "arm_plane", 0, p95, neighbors=n, kernel="cubic") for n, p95 in ((32, 4.0), (64, 3.0), (128, 3.5))]
    rung += [_result("knn", "arm_plane", 0, p95, neighbors=n) for n, p95 in ((3, 9.0), (5, 8.0))]
    chosen = contest.choose(rung)
    assert contest.at_edge(rung, chosen) == {"kernel_ridge": [("gamma", 1.0, "smallest")]}
    # seed 1's cells are not the search
    assert contest.at_edge(rung + [_result("rbf", "arm_plane", 1, 1.0, neighbors=16, kernel="cubic")], chosen) == \
        {"kernel_ridge": [("gamma", 1.0, "smallest")]}
