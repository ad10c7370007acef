"""The model-free scikit-learn baselines of learned inverse dynamics (nfarm.learning.baselines):
seeded functions of their options, the floor and the identification they must bracket, the
friction identification, bad options refused, and the time limit inside their loops."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm.learning.baselines import BASELINES, BaselineID, baseline_id
from nfarm.model.dynamics import rnea
from test_bases import ROBOT, nrmse, random_states, trajectories  # noqa: F401 — the shared data fixtures


# -- scikit-learn baselines --------------------------------------------------------------------

SMALL = {"linear": {}, "ridge": {"basis": "generic"}, "kernel": {"n_components": 50},
         "boosting": {"max_iter": 5}, "mlp": {"hidden": [8], "max_iter": 5}, "friction": {},
         "identification": {}}


@pytest.mark.parametrize("learner", list(BASELINES))
def test_baselines_are_seeded_functions_of_their_options(learner, trajectories):
    train, val = trajectories["train"], trajectories["val"]
    fit = lambda: baseline_id(learner, SMALL[learner], residual=learner == "friction",   # noqa: E731
                              random_state=3).fit(ROBOT, train)
    a, b = fit(), fit()
    pa = a.predict(val["q"], val["qd"], val["qdd"])
    assert pa.shape == val["tau"].shape and np.isfinite(pa).all()
    np.testing.assert_array_equal(pa, b.predict(val["q"], val["qd"], val["qdd"]))
    assert set(BASELINES[learner].hyper_params()) >= set(SMALL[learner])


@pytest.mark.parametrize("learner, options", [*SMALL.items(), ("kernel", {"n_components": 20, "angles": "own"}),
                                              ("mlp", {"hidden": [4], "max_iter": 3, "angles": "own"}),
                                              ("boosting", {"max_iter": 3, "angles": "regressor"})])
def test_a_baseline_predicts_in_blocks_what_it_predicts_at_once(learner, options, trajectories):
    """Issue 63: ``predict`` builds a block of ``rows`` states' features at a time (memory bounded
    whatever the states); the torques are those of one pass, the blocks' edges anywhere (up to the
    last bits a matrix product may sum in another order)."""
    train, val = trajectories["train"], trajectories["val"]
    model = baseline_id(learner, options, residual=learner == "friction", random_state=1).fit(ROBOT, train, val)
    X = (val["q"], val["qd"], val["qdd"])
    once = model.predict(*X, rows=len(val["q"]))
    assert len(val["q"]) > 7 and once.shape == val["tau"].shape
    for rows in (1, 7, len(val["q"]) - 1):
        np.testing.assert_allclose(model.predict(*X, rows=rows), once, rtol=1e-12, atol=1e-12)
    assert model.predict(*(x[:0] for x in X)).shape == (0, ROBOT.n)
    for bad in (0, -3, 2.5, "8"):
        with pytest.raises(ValueError, match="rows must be a whole number >= 1"):
            model.predict(*X, rows=bad)


def test_ridge_on_the_chain_basis_identifies_the_arm_and_the_linear_floor_does_not(random_states):
    train, val = random_states["train"], random_states["val"]
    exact = baseline_id("ridge", {"basis": "chain", "alpha": 1e-9}).fit(ROBOT, train)
    floor = baseline_id("linear").fit(ROBOT, train)
    X = (val["q"], val["qd"], val["qdd"])
    assert nrmse(exact.predict(*X), val["tau"]).max() < 1e-3
    assert nrmse(floor.predict(*X), val["tau"]).max() > 0.3


def test_residual_baseline_adds_newton_euler(trajectories):
    """On torques that are Newton–Euler's plus a viscous term, a linear residual learns the term;
    the friction identification recovers each joint's armature, viscous and Coulomb values and the
    reading's zero offset."""
    train = dict(trajectories["train"])
    train["tau"] = train["tau"] + 0.05 * train["qd"]
    model = baseline_id("linear", residual=True).fit(ROBOT, train)
    v = trajectories["val"]
    np.testing.assert_allclose(model.predict(v["q"], v["qd"], v["qdd"]), v["tau"] + 0.05 * v["qd"], atol=1e-9)
    law = np.array([[0.003, 0.06, 0.05], [0.001, 0.2, 0.02], [0.0, 0.1, 0.0], [0.002, 0.0, 0.08], [0.0, 0.01, 0.01]])
    train["tau"] = trajectories["train"]["tau"] + _drive_law(law, train) + OFFSET
    friction = baseline_id("friction", residual=True).fit(ROBOT, train)
    np.testing.assert_allclose(friction.model_.coef_, np.column_stack([law, OFFSET]), atol=1e-9)


#: Each joint's zero offset of the torque reading [N·m] (a current sensor's uncalibrated zero: chapter 05)
OFFSET = np.array([0.012, -0.004, 0.0, 0.008, -0.015])


def _drive_law(law, d):
    """The drive torques ``(N, n)`` of the robot file's own law (``joint_drive_torques``, independent of the
    identification's columns) with each joint's armature, viscous and Coulomb values a row of ``law (n, 3)``."""
    import dataclasses

    from nfarm.model.dynamics import joint_drive_torques

    drives = dataclasses.replace(ROBOT, armature=law[:, 0], viscous=law[:, 1], coulomb=law[:, 2])
    return joint_drive_torques(drives, d["qd"], d["qdd"])


def test_the_identifications_drive_columns_are_the_robot_files_drive_law(trajectories):
    """``drive_terms`` times each joint's ``[I_a, b, τ_c]`` is ``joint_drive_torques`` of the robot file, its
    smoothing speed ε included (a Coulomb column of ``sign q̇`` is not: it differs near rest)."""
    from nfarm.learning.priors import drive_terms

    d = trajectories["val"]
    law = np.array([[0.003, 0.06, 0.05], [0.001, 0.2, 0.02], [0.0, 0.1, 0.0], [0.002, 0.0, 0.08], [0.0, 0.01, 0.01]])
    np.testing.assert_allclose(np.einsum("njk,jk->nj", drive_terms(ROBOT, d["qd"], d["qdd"]), law), _drive_law(law, d),
                               rtol=1e-12, atol=1e-15)
    slow = {"qd": np.full((1, ROBOT.n), 0.2 * ROBOT.coulomb_velocity), "qdd": np.zeros((1, ROBOT.n))}
    assert not np.allclose(np.einsum("njk,jk->nj", np.stack([slow["qdd"], slow["qd"], np.sign(slow["qd"])], -1), law),
                           _drive_law(law, slow))


def _built_arm_torques(trajectories):
    """The training and validation trajectories with the torques of a built arm (masses, centres
    and inertias off the model's) plus a drive law of the identified form (the robot file's, :func:`_drive_law`)."""
    from nfarm.study.id_trajectories import TrueArm, true_arm

    built = true_arm(ROBOT, TrueArm(mass_sd=0.1, com_sd=0.005, inertia_sd=0.2), np.random.default_rng(5))
    law = np.array([[0.003, 0.06, 0.05], [0.001, 0.2, 0.02], [0.0, 0.1, 0.0], [0.002, 0.0, 0.08], [0.0, 0.01, 0.01]])

    def measured(d):
        return {**d, "tau": rnea(built, d["q"], d["qd"], d["qdd"]) + _drive_law(law, d) + OFFSET}

    return measured(trajectories["train"]), measured(trajectories["val"])


def test_the_identification_refits_a_built_arm_that_the_friction_identification_cannot(trajectories):
    """Torques of a built arm (masses, centres and inertias off the model's) plus a drive law of
    the identified form and a zero offset of each reading: the full identification reproduces them
    to rounding on other trajectories; Newton–Euler with the nominal masses plus the friction
    identification does not, by far more than rounding."""
    train, val = _built_arm_torques(trajectories)
    X = (val["q"], val["qd"], val["qdd"])
    full = baseline_id("identification").fit(ROBOT, train)
    nominal = baseline_id("friction", residual=True).fit(ROBOT, train)
    assert np.abs(full.predict(*X) - val["tau"]).max() < 1e-8 * np.abs(val["tau"]).max()
    assert np.abs(nominal.predict(*X) - val["tau"]).max() > 1e-3 * np.abs(val["tau"]).max()
    with pytest.raises(ValueError, match="learner 'identification' fits the whole torque"):
        baseline_id("identification", residual=True).fit(ROBOT, train)


@pytest.mark.parametrize("learner, options, message", [
    ("forest", None, "learner must be one of linear, ridge, kernel, boosting, mlp, friction, identification, got 'forest'"),
    ("friction", None, "learner 'friction' identifies the drives beside Newton–Euler: give residual=True"),
    ("ridge", {"degree": 2}, "unknown option 'degree' for learner 'ridge'; valid: basis, alpha"),
    ("ridge", {"alpha": -1}, "ridge: alpha must be a positive number, got -1"),
    ("ridge", {"alpha": True}, "ridge: alpha must be a positive number, got True"),
    ("kernel", {"gamma": float("nan")}, "kernel: gamma must be a positive number, got nan"),
    ("ridge", {"basis": "fourier"}, "ridge: basis must be one of"),
    ("kernel", {"n_components": 1.5}, "kernel: n_components must be an integer from 2 to 10,000, got 1.5"),
    ("kernel", {"n_components": 10**6}, "kernel: n_components must be an integer from 2 to 10,000, got 1000000"),
    ("boosting", {"max_iter": 10**9}, "boosting: max_iter must be an integer from 2 to 100,000"),
    ("boosting", {"max_leaf_nodes": True}, "boosting: max_leaf_nodes must be an integer from 2 to 4,096"),
    ("mlp", {"hidden": 32}, "mlp: hidden must be a list of 1 to 16 layer widths"),
    ("mlp", {"hidden": [10**6]}, "mlp: hidden must be a list of 1 to 16 layer widths from 1 to 4,096"),
    ("mlp", {"hidden": [True]}, "mlp: hidden must be a list of 1 to 16 layer widths"),
    ("linear", {"alpha": 1.0}, "unknown option 'alpha' for learner 'linear'; valid: none"),
    ("mlp", {"angles": "sums"}, "mlp: angles must be one of joints, chain, regressor, own, got 'sums'"),
])
def test_bad_baseline_options_are_refused_before_any_work(learner, options, message, trajectories):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        baseline_id(learner, options).fit(ROBOT, trajectories["train"])
    with pytest.raises(ValueError, match="not fitted yet"):
        baseline_id().predict(*np.zeros((3, 2, 5)))


@pytest.mark.parametrize("learner, options", [("boosting", {"max_iter": 12}), ("mlp", {"hidden": [16], "max_iter": 12})])
def test_the_time_limited_learners_compute_what_scikit_learn_does(learner, options, trajectories, monkeypatch):
    """The hooks that check the time limit change no arithmetic: the same predictions, bit for bit,
    as the plain scikit-learn estimators with the same options and seed."""
    from sklearn.ensemble import HistGradientBoostingRegressor
    from sklearn.neural_network import MLPRegressor

    from nfarm.learning import baselines

    train, val = trajectories["train"], trajectories["val"]
    ours = baseline_id(learner, options, random_state=4).fit(ROBOT, train)
    plain = {"boosting": HistGradientBoostingRegressor, "mlp": MLPRegressor}[learner]
    timed = baselines._timed_learners()[learner == "mlp"]
    assert timed is not plain and issubclass(timed, plain)
    monkeypatch.setattr(baselines, "_timed_learners", lambda: (HistGradientBoostingRegressor, MLPRegressor))
    reference = baseline_id(learner, options, random_state=4).fit(ROBOT, train)
    X = (val["q"], val["qd"], val["qdd"])
    np.testing.assert_array_equal(ours.predict(*X), reference.predict(*X))


@pytest.mark.parametrize("learner, options, what", [
    ("boosting", {"max_iter": 100_000, "max_leaf_nodes": 4}, "boosting: an iteration"),
    ("mlp", {"hidden": [4], "max_iter": 100_000}, "mlp: an epoch")])
def test_a_time_limit_stops_an_iterative_baseline_within_an_iteration(learner, options, what, trajectories):
    """A sweep cell's deadline reaches inside scikit-learn's loops (without the hook these fits
    run 100 000 iterations)."""
    from nfarm.infra.limits import TimeLimitError, time_limit

    small = {k: v[:200] for k, v in trajectories["train"].items()}
    with pytest.raises(TimeLimitError, match=f"{what}: over the time limit of 0.2 s"), time_limit(0.2):
        baseline_id(learner, options).fit(ROBOT, small)


@pytest.mark.parametrize("patience", [2, 5])
def test_the_mlp_stops_early_on_the_validation_states_and_keeps_its_best_epoch(patience, trajectories):
    """Given validation states, the MLP keeps the epoch of least validation error and stops
    `patience` epochs after it: the same run cut right after that epoch predicts the same bits."""
    train, val = trajectories["train"], trajectories["val"]
    options = {"hidden": [16], "max_iter": 300, "patience": patience, "alpha": 1e-4}
    model = baseline_id("mlp", options, random_state=1).fit(ROBOT, train, val)
    assert model.epochs_ == 300 or model.epochs_ - model.best_epoch_ - 1 == patience
    assert model.epochs_ > model.best_epoch_ + 1 or model.epochs_ == 300
    X = (val["q"], val["qd"], val["qdd"])
    cut = baseline_id("mlp", {**options, "max_iter": model.best_epoch_ + 1}, random_state=1).fit(ROBOT, train, val)
    assert cut.best_epoch_ == model.best_epoch_
    np.testing.assert_array_equal(cut.predict(*X), model.predict(*X))
    without = baseline_id("mlp", {**options, "max_iter": 5}, random_state=1).fit(ROBOT, train)
    assert without.epochs_ is None and without.model_[-1].n_iter_ == 5       # no validation: the fixed budget
    with pytest.raises(ValueError, match="mlp: patience must be an integer from 2"):
        baseline_id("mlp", {"patience": 0}).fit(ROBOT, train, val)


# -- saving: JSON, the same bits as scikit-learn's predict ---------------------------------------


@pytest.mark.parametrize("learner, residual", [(learner, residual) for learner in BASELINES
                                               for residual in (False, True, "identification")
                                               if (learner, residual) not in (("friction", False), ("friction", "identification"),
                                                                              ("identification", True),
                                                                              ("identification", "identification"))])
def test_a_saved_baseline_predicts_the_bits_scikit_learn_predicts(learner, residual, trajectories, tmp_path):
    """The arrays read out of the fitted estimator predict what the estimator itself predicts, bit
    for bit, and the saved JSON loads back to the same bits (no pickle). (Friction is a residual
    only, the identification never one.)"""
    from nfarm.learning.baselines import load_id_model

    train, val = trajectories["train"], trajectories["val"]
    model = baseline_id(learner, SMALL[learner], residual=residual, random_state=2).fit(ROBOT, train, val)
    X = (val["q"], val["qd"], val["qdd"])
    features = model._features(*X)
    scaled = model.model_.predict(features).reshape(len(val["q"]), -1)           # scikit-learn's own arithmetic
    prior = {False: 0.0, True: rnea(ROBOT, *X)}.get(residual)
    if residual == "identification":            # the identification's own least squares, fitted on the training states
        identified = baseline_id("identification").fit(ROBOT, train)
        np.testing.assert_array_equal(model.prior_, identified.state_["coef"])
        prior = identified.predict(*X)
    expected = scaled * model.y_scale_ + model.y_mean_ + prior
    np.testing.assert_array_equal(model.predict(*X), expected)
    model.save(tmp_path)
    loaded = load_id_model(tmp_path, ROBOT)
    assert isinstance(loaded, BaselineID) and (loaded.learner, loaded.residual, loaded.random_state, loaded.options_) == \
        (model.learner, model.residual, model.random_state, model.options_)
    np.testing.assert_array_equal(loaded.predict(*X), model.predict(*X))
    assert (tmp_path / "baseline_id.json").read_bytes().startswith(b"{")


def test_a_learner_on_the_identifications_residual_learns_only_what_the_identification_misses(trajectories):
    """Torques of a built arm plus its drive law (the identified form) and a term the identification cannot hold,
    linear in the angles (``0.2 q1 − 0.1 q2`` N·m on the first two joints): the identification alone misses it on the
    base joint (NRMSE 0.84 here); least squares on ``[q, q̇, q̈]`` fitted to what the identification leaves — the
    prior refitted on the training states, the learner on the rest — brings that joint below a tenth of it (0.07) and
    the worst joint below both the identification alone and the same learner on Newton–Euler's nominal residual, which
    misses the built arm's masses; the tier says which prior each has."""
    from nfarm.learning.bases import tier_of

    train, val = _built_arm_torques(trajectories)
    extra = lambda d: d["q"] @ np.diag([0.2, -0.1, 0.0, 0.0, 0.0])                  # noqa: E731
    train, val = {**train, "tau": train["tau"] + extra(train)}, {**val, "tau": val["tau"] + extra(val)}
    X = (val["q"], val["qd"], val["qdd"])
    alone = baseline_id("identification").fit(ROBOT, train)
    identified = baseline_id("linear", residual="identification").fit(ROBOT, train)
    nominal = baseline_id("linear", residual=True).fit(ROBOT, train)
    err = {name: nrmse(m.predict(*X), val["tau"]) for name, m in (("alone", alone), ("identified", identified),
                                                                   ("nominal", nominal))}
    assert err["identified"][0] < 0.1 * err["alone"][0]
    assert err["identified"].max() < min(err["alone"].max(), err["nominal"].max())
    np.testing.assert_array_equal(identified.prior_, alone.state_["coef"])      # the prior: that identification
    assert (tier_of({"learner": "linear", "residual": "identification"}), tier_of({"learner": "linear", "residual": True})) \
        == ("identification + learned", "nominal model + learned")


@pytest.mark.parametrize("learner, residual, message", [
    ("ridge", "identified", "residual must be false (no prior), true or 'nominal' (Newton–Euler's nominal model) or "
                            "'identification' (the identification of the arm as built), got 'identified'"),
    ("ridge", 1, "residual must be false (no prior), true"),
    ("friction", "identification", "learner 'friction' identifies the drives beside Newton–Euler: give residual=True"),
    ("identification", "identification", "learner 'identification' fits the whole torque, the masses included: give "
                                          "residual=False"),
])
def test_a_residual_no_prior_names_is_refused_before_any_work(learner, residual, message, trajectories):
    """Refused on its own words even with no data given (the data are checked, and the prior fitted, only after)."""
    for train in (trajectories["train"], {}):
        with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
            baseline_id(learner, residual=residual).fit(ROBOT, train)


def test_a_saved_identification_residual_is_read_with_its_prior_checked(trajectories, tmp_path):
    """The identification's θ is saved beside the learner's arrays: a file without it, or with it where the residual
    is Newton–Euler's, or with an unknown residual, is refused in one line naming the field."""
    import json

    from nfarm.infra.reading import CONTENT_FIELD, ParamsError, with_content_digest
    from nfarm.learning.baselines import load_id_model

    model = baseline_id("ridge", {"basis": "generic"}, residual="identification").fit(ROBOT, trajectories["train"])
    model.save(tmp_path)
    path = tmp_path / "baseline_id.json"
    data = {k: v for k, v in json.loads(path.read_text()).items() if k != CONTENT_FIELD}
    for edit, field in (({"prior": None}, "prior"), ({"prior": data["prior"][:-1]}, "prior"), ({"prior": "θ"}, "prior"),
                        ({"residual": True}, "prior"), ({"residual": True, "prior": None}, "prior"),
                        ({"residual": "learned"}, "residual")):
        edited = {**data, **edit}
        if edit.get("residual") is True:            # a nominal residual's file names no drive law: its prior is refused
            edited.pop("drive_law")
        path.write_text(json.dumps(with_content_digest(edited)))       # edited, as if saved so
        with pytest.raises(ParamsError, match=rf"baseline_id.json: {field}\b"):
            load_id_model(tmp_path, ROBOT)


@pytest.mark.parametrize("learner", ["kernel", "boosting", "mlp"])
def test_the_structure_informed_rivals_see_the_parallel_joints_angle_sums(learner, trajectories, tmp_path):
    """``angles="chain"``: the sin, cos of the joint angles and of every stretch of parallel joints (intelbot5's
    q2+q3, q3+q4, q2+q3+q4), what the structure-informed tier's ANFIS and ridge get — and saved, it predicts the
    same bits."""
    from nfarm.learning.bases import angle_sums, tier_of
    from nfarm.learning.baselines import load_id_model

    train, val = trajectories["train"], trajectories["val"]
    options = {**SMALL[learner], "angles": "chain"}
    model = baseline_id(learner, options, random_state=1).fit(ROBOT, train, val)
    X = (val["q"], val["qd"], val["qdd"])
    sums = angle_sums(ROBOT, val["q"])
    assert sums.shape[1] == ROBOT.n + 3 and model.n_features_ == 2 * sums.shape[1] + 2 * ROBOT.n
    np.testing.assert_array_equal(model._features(*X)[:, :sums.shape[1]], np.sin(sums))
    plain = baseline_id(learner, SMALL[learner], random_state=1).fit(ROBOT, train, val)
    assert plain.n_features_ == 4 * ROBOT.n and not np.array_equal(plain.predict(*X), model.predict(*X))
    assert tier_of({**model.options_, "learner": learner}) == "structure-informed"
    assert tier_of({**plain.options_, "learner": learner}) == "generic"
    model.save(tmp_path)
    np.testing.assert_array_equal(load_id_model(tmp_path, ROBOT).predict(*X), model.predict(*X))


@pytest.mark.parametrize("learner", ["kernel", "boosting", "mlp"])
def test_a_rival_on_each_joints_own_state_has_a_model_a_joint(learner, trajectories, tmp_path):
    """``angles="own"``: joint j's model sees its own ``q_j, q̇_j, q̈_j`` alone (the residual ANFIS's ``own`` inputs), so
    its torque moves with no other joint's state; the MLP stops each joint's model early on that joint's validation
    torque; saved, it predicts the same bits, and a file with fewer joints' models is refused in one line."""
    import json

    from nfarm.infra.reading import CONTENT_FIELD, ParamsError, with_content_digest
    from nfarm.learning.baselines import load_id_model

    train, val = trajectories["train"], trajectories["val"]
    model = baseline_id(learner, {**SMALL[learner], "angles": "own"}).fit(ROBOT, train, val)
    X = [val["q"].copy(), val["qd"].copy(), val["qdd"].copy()]
    before = model.predict(*X)
    for a in X:                                  # every joint's state but the third's moved
        a[:, [0, 1, 3, 4]] = a[::-1][:, [0, 1, 3, 4]]
    after = model.predict(*X)
    np.testing.assert_array_equal(after[:, 2], before[:, 2])
    assert not np.allclose(after[:, 0], before[:, 0]) and model.n_features_ == 3
    assert len(model.state_["per_joint"]) == ROBOT.n
    if learner == "mlp":
        assert len(model.epochs_) == ROBOT.n and all(0 <= b < e for b, e in zip(model.best_epoch_, model.epochs_))
    path = model.save(tmp_path)
    np.testing.assert_array_equal(load_id_model(tmp_path, ROBOT).predict(*X), after)
    data = {k: v for k, v in json.loads(path.read_text()).items() if k != CONTENT_FIELD}
    data["state"] = {"per_joint": data["state"]["per_joint"][:-1]}
    path.write_text(json.dumps(with_content_digest(data)))
    with pytest.raises(ParamsError, match=r"baseline_id.json: state.per_joint: must .*5"):
        load_id_model(tmp_path, ROBOT)


def test_an_edited_or_foreign_baseline_file_is_refused_in_one_line(trajectories, tmp_path):
    import json

    from nfarm.infra.reading import ParamsError, with_content_digest
    from nfarm.learning.baselines import load_id_model
    from nfarm.model.robot import load_robot
    from nfarm.infra.paths import PARAMS

    model = baseline_id("boosting", {"max_iter": 3}).fit(ROBOT, trajectories["train"])
    path = model.save(tmp_path / "m")
    data = json.loads(path.read_text())
    data["state"]["joints"][0]["trees"][0]["value"][0] += 1.0          # an edit without its content hash
    path.write_text(json.dumps(data))
    with pytest.raises(ParamsError, match="does not match the file's content"):
        BaselineID.load(tmp_path / "m", ROBOT)
    # A tree whose child points back to its parent (a loop) is refused even with a valid hash
    data = json.loads(model.save(tmp_path / "n").read_text())
    tree = data["state"]["joints"][0]["trees"][0]
    inner = tree["leaf"].index(0)
    tree["left"][inner] = inner
    (tmp_path / "n" / "baseline_id.json").write_text(json.dumps(with_content_digest(data)))
    with pytest.raises(ParamsError, match=r"baseline_id.json: state.joints\[0\].trees\[0\].left: must name a later node"):
        BaselineID.load(tmp_path / "n", ROBOT)
    with pytest.raises(ParamsError, match="robot_params_sha256: trained for robot"):
        BaselineID.load(model.save(tmp_path / "o"), load_robot(PARAMS / "robots" / "so101.yaml"))
    with pytest.raises(ParamsError, match="holds no saved learned-ID model"):
        load_id_model(tmp_path / "empty", ROBOT)


def test_load_id_model_reads_an_anfis_too(trajectories, tmp_path):
    from nfarm.learning.baselines import load_id_model
    from nfarm.learning.learned_id import LearnedID

    anfis = LearnedID(inputs="own", n_mfs=1, epochs=1).fit(ROBOT, trajectories["train"])
    anfis.save(tmp_path)
    v = trajectories["val"]
    loaded = load_id_model(tmp_path, ROBOT)
    assert isinstance(loaded, LearnedID)
    np.testing.assert_array_equal(loaded.predict(v["q"], v["qd"], v["qdd"]), anfis.predict(v["q"], v["qd"], v["qdd"]))


def test_the_identification_tier_anfis_sees_the_identifications_columns(trajectories):
    """``regressor_drives``: each joint's regressor row and its drive terms. One rule is a per-joint
    least squares on them, so a built arm with a drive law of that form is reproduced to rounding —
    the inputs the identification learner has, given to the ANFIS of its tier."""
    from nfarm.learning.learned_id import LearnedID, id_features
    train, val = _built_arm_torques(trajectories)
    X = (val["q"], val["qd"], val["qdd"])
    with_drives = LearnedID(inputs="regressor_drives", n_mfs=1, epochs=1).fit(ROBOT, train)
    without = LearnedID(inputs="regressor", n_mfs=1, epochs=1).fit(ROBOT, train)
    scale = np.abs(val["tau"]).max()
    assert np.abs(with_drives.predict(*X) - val["tau"]).max() < 1e-6 * scale
    assert np.abs(without.predict(*X) - val["tau"]).max() > 1e-3 * scale
    widths = [f.shape[1] for f in id_features(ROBOT, *X, "regressor_drives")]
    assert widths == [f.shape[1] + 3 for f in id_features(ROBOT, *X, "regressor")]


@pytest.mark.parametrize("learner", ["kernel", "boosting", "mlp"])
def test_the_identification_tiers_rivals_see_every_joints_regressor_row_and_drive_terms(learner, trajectories, tmp_path):
    """``angles="regressor"`` (issue 65): the columns the identification and its ANFIS see of each joint, side by
    side — the identification tier's knowledge given to the kernel, boosting and the MLP; saved, it predicts the
    same bits. On a built arm whose torque is linear in those columns the boosted trees, which must learn that
    map, do far better than on the angles alone."""
    from nfarm.learning.bases import tier_of
    from nfarm.learning.baselines import load_id_model, regressor_inputs
    from nfarm.learning.learned_id import id_features

    train, val = _built_arm_torques(trajectories)
    X = (val["q"], val["qd"], val["qdd"])
    model = baseline_id(learner, {**SMALL[learner], "angles": "regressor"}, random_state=1).fit(ROBOT, train, val)
    rows = id_features(ROBOT, *X, "regressor_drives")
    assert model.n_features_ == sum(r.shape[1] for r in rows) == 140            # intelbot5: 125 regressor columns + 15
    np.testing.assert_array_equal(model._features(*X), np.concatenate(rows, axis=1))
    np.testing.assert_array_equal(regressor_inputs(ROBOT, *X), np.concatenate(rows, axis=1))
    assert tier_of({**model.options_, "learner": learner}) == "identification"
    model.save(tmp_path)
    np.testing.assert_array_equal(load_id_model(tmp_path, ROBOT).predict(*X), model.predict(*X))
    if learner == "boosting":
        options = {"max_iter": 200, "learning_rate": 0.1}
        told = baseline_id(learner, {**options, "angles": "regressor"}, random_state=1).fit(ROBOT, train, val)
        blind = baseline_id(learner, options, random_state=1).fit(ROBOT, train, val)
        assert nrmse(told.predict(*X), val["tau"]).max() < nrmse(blind.predict(*X), val["tau"]).max()


def test_a_failed_refit_leaves_no_model_beside_its_new_prior(trajectories):
    """A refit that fails after the new prior is fitted (here: in the learner's training) leaves the estimator unfitted,
    not the old learner's arrays beside the new identification's θ."""
    model = baseline_id("ridge", {"basis": "generic"}, residual="identification").fit(ROBOT, trajectories["train"])
    d = trajectories["val"]
    model.predict(d["q"], d["qd"], d["qdd"])

    def broken(*args):
        raise RuntimeError("the learner failed")

    model._train = broken
    with pytest.raises(RuntimeError, match="the learner failed"):
        model.fit(ROBOT, trajectories["val"])
    with pytest.raises(ValueError, match="not fitted yet"):
        model.predict(d["q"], d["qd"], d["qdd"])


def test_a_model_of_the_drive_law_names_it_and_one_without_it_is_refused(trajectories, tmp_path):
    """A model whose predictions use the drive terms saves ``drive_law``; a file of one without it (saved while the
    Coulomb column was ``sign q̇``) or a file of another that names one is refused in one line naming the field."""
    import json

    from nfarm.infra.reading import CONTENT_FIELD, ParamsError, with_content_digest
    from nfarm.learning.baselines import load_id_model
    from nfarm.learning.priors import DRIVE_LAW, FITTED_LAW

    for learner, options, residual, law in (("identification", {}, False, FITTED_LAW), ("friction", {}, True, FITTED_LAW),
                                            ("ridge", {"basis": "generic"}, "identification", FITTED_LAW),
                                            ("mlp", {"angles": "regressor", "hidden": [4], "max_iter": 2}, False, DRIVE_LAW),
                                            ("ridge", {"basis": "generic"}, True, None)):
        model = baseline_id(learner, options, residual=residual).fit(ROBOT, trajectories["train"])
        path = model.save(tmp_path / learner / str(residual))
        data = {k: v for k, v in json.loads(path.read_text()).items() if k != CONTENT_FIELD}
        assert data.get("drive_law") == law and ("drive_law" in data) is (law is not None)
        older = ([{k: v for k, v in data.items() if k != "drive_law"}] if law else [{**data, "drive_law": DRIVE_LAW}])
        if law == FITTED_LAW:           # saved before the zero offset: the law without it is refused too
            older.append({**data, "drive_law": DRIVE_LAW})
        for edited in older:
            path.write_text(json.dumps(with_content_digest(edited)))
            with pytest.raises(ParamsError, match=r"baseline_id.json: drive_law: must be"):
                load_id_model(path.parent, ROBOT)
