"""One estimator class per learner (issue 67): every learned-IK rival (nfarm.learning.ik_rivals)
and every ID baseline (nfarm.learning.baselines) is its own class with flat scikit-learn
parameters, registered under the name sweep files give it. Its parameters round-trip and clone,
each one changes the fit it names, a saved model loads into its class and predicts the same bits
(also one saved before the change), a file of an unknown learner is refused in one line, and a new
learner is one class: registered, it is built by name, saved, loaded, cached and labelled."""

from __future__ import annotations

import inspect
import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.base import clone

from nfarm.infra.paths import PARAMS, ROOT
from nfarm.infra.reading import CONTENT_FIELD, ParamsError, with_content_digest
from nfarm.learning.baselines import BASELINES, BaselineID, baseline_id, label, load_id_model, option_names
from nfarm.learning.ik_rivals import RIVALS, KNNRival, RBFRival, RivalIK, rival_ik
from nfarm.learning.model_cache import fit_cached
from nfarm.model.dynamics import rnea
from nfarm.study import contest
from nfarm.study.id_trajectories import random_trajectories
from nfarm.study.regions import ik_samples
from nfarm.study.study_files import load_study

STUDY = load_study(PARAMS / "studies" / "intelbot5.yaml")
ROBOT = STUDY.robot
OLD = ROOT / "tests" / "data" / "models_before_67"

#: Small options of every registered learner (a fit of a second or less).
IK_SMALL = {"knn": {"neighbors": 3}, "rbf": {"neighbors": 16}, "mlp": {"hidden": [8], "max_epochs": 3},
            "kernel_ridge": {"components": 50, "gamma": 2.0}}
ID_SMALL = {"linear": {}, "ridge": {"basis": "generic_linear"}, "kernel": {"n_components": 20},
            "boosting": {"max_iter": 3, "max_leaf_nodes": 4}, "mlp": {"hidden": [8], "max_iter": 5}, "friction": {},
            "identification": {}}
CLASSES = [*RIVALS.values(), *BASELINES.values()]


@pytest.fixture(scope="module")
def poses():
    return {split: ik_samples(STUDY.ik_region, n, seed) for split, n, seed in (("train", 300, 1), ("val", 100, 2))}


@pytest.fixture(scope="module")
def states():
    def split(count, seed):
        d = random_trajectories(ROBOT, STUDY.id, count, seed)
        return {k: d[k][::4] for k in ("q", "qd", "qdd")} | {"tau": rnea(ROBOT, *(d[k][::4] for k in ("q", "qd", "qdd")))}
    return {"train": split(4, 1), "val": split(2, 2)}


def test_every_registered_learner_has_small_options_here():
    assert set(IK_SMALL) == set(RIVALS) and set(ID_SMALL) == set(BASELINES)
    assert list(RIVALS)[:4] == ["knn", "rbf", "mlp", "kernel_ridge"]          # the sweep files' names, kept
    assert list(BASELINES)[:7] == ["linear", "ridge", "kernel", "boosting", "mlp", "friction", "identification"]


# -- parameters -------------------------------------------------------------------------------


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_each_class_stores_its_flat_parameters_unchanged_and_clones(cls):
    registry, name = (RIVALS, cls.kind) if issubclass(cls, RivalIK) else (BASELINES, cls.learner)
    assert registry[name] is cls and isinstance(cls.label, str) and cls.label
    model = cls()
    params = model.get_params()
    assert list(params) == cls._param_names() and set(cls.hyper_params()) <= set(params)
    assert cls(**params).get_params() == params
    for key in params:                                  # stored as given: the very object
        marker = object()
        assert getattr(cls(**{key: marker}), key) is marker
    twin = clone(model)
    assert type(twin) is cls and twin is not model and twin.get_params() == params
    assert repr(model) == f"{cls.__name__}()"
    with pytest.raises(ValueError, match=rf"^unknown parameter 'colour' for {cls.__name__}; valid: "):
        model.set_params(colour=1)


_VALUES = st.one_of(st.integers(-5, 5000), st.floats(allow_nan=False, width=64), st.booleans(), st.none(),
                    st.text(max_size=8), st.lists(st.integers(1, 64), max_size=4))


@settings(max_examples=30)
@given(data=st.data())
def test_set_params_and_get_params_round_trip_for_any_values(data):
    cls = data.draw(st.sampled_from(CLASSES), label="class")
    names = cls._param_names()
    changed = data.draw(st.dictionaries(st.sampled_from(names), _VALUES, max_size=len(names)), label="changed")
    model = cls().set_params(**changed)
    assert model.get_params() == {**cls().get_params(), **changed}
    assert type(model)(**model.get_params()).get_params() == model.get_params()
    assert clone(model).get_params() == model.get_params()


def test_set_params_neighbors_changes_the_fit_it_names(poses):
    T = poses["val"]["T"]
    model = KNNRival(neighbors=1).fit(ROBOT, poses["train"])
    one = model.predict(T)
    nine = model.set_params(neighbors=9).fit(ROBOT, poses["train"]).predict(T)
    assert not np.array_equal(one, nine) and model.knn_.n_neighbors == 9
    np.testing.assert_array_equal(nine, KNNRival(neighbors=9).fit(ROBOT, poses["train"]).predict(T))
    np.testing.assert_array_equal(nine, rival_ik("knn", options={"neighbors": 9}).fit(ROBOT, poses["train"]).predict(T))
    rbf = RBFRival(neighbors=8).fit(ROBOT, poses["train"])
    assert not np.array_equal(rbf.predict(T), clone(rbf).set_params(neighbors=24).fit(ROBOT, poses["train"]).predict(T))


# -- saving -----------------------------------------------------------------------------------


def _same_content(a: dict, b: dict) -> bool:
    return json.loads(json.dumps(a)) == json.loads(json.dumps(b))


@pytest.mark.parametrize("kind, structure", [(k, s) for k in IK_SMALL for s in ("whole", "arm")])
def test_every_rival_saved_and_loaded_predicts_the_same_bits(kind, structure, poses, tmp_path):
    model = rival_ik(kind, "arm_plane", IK_SMALL[kind], structure=structure, random_state=2)
    assert model.fit(ROBOT, poses["train"], poses["val"]) is model
    loaded = RivalIK.load(model.save(tmp_path), ROBOT)
    assert type(loaded) is RIVALS[kind] and loaded.get_params() == model.get_params()
    np.testing.assert_array_equal(loaded.predict(poses["val"]["T"]), model.predict(poses["val"]["T"]))
    assert _same_content(loaded.to_dict(), model.to_dict())


@pytest.mark.parametrize("learner", list(ID_SMALL))
def test_every_baseline_saved_and_loaded_predicts_the_same_bits(learner, states, tmp_path):
    model = baseline_id(learner, ID_SMALL[learner], residual=learner == "friction", random_state=2)
    assert model.fit(ROBOT, states["train"], states["val"]) is model
    loaded = load_id_model(model.save(tmp_path), ROBOT)
    assert type(loaded) is BASELINES[learner] and loaded.get_params() == model.get_params()
    X = (states["val"]["q"], states["val"]["qd"], states["val"]["qdd"])
    np.testing.assert_array_equal(loaded.predict(*X), model.predict(*X))
    assert _same_content(loaded.to_dict(), model.to_dict())


#: The old files whose predictions use the drive law, whose Coulomb column was sign(qd) then (and no zero offset): refused,
#: not loaded
DRIVE_LAW_OLD = ("friction", "identification")


@pytest.mark.parametrize("directory", DRIVE_LAW_OLD)
def test_a_model_saved_with_the_old_coulomb_column_is_refused_in_one_line(directory):
    """The friction identification and the identification saved while their Coulomb column was ``sign q̇`` would predict
    other torques near rest with today's ``tanh(q̇/ε)``: refused, naming the field, with what to do."""
    from nfarm.infra.reading import ParamsError

    with pytest.raises(ParamsError, match=r"baseline_id.json: drive_law: must be 'tanh\(qd/coulomb_velocity\) \+ offset', got "
                                          r"nothing \(the field is missing\).*sign\(qd\).*refit it"):
        load_id_model(OLD / directory, ROBOT)


@pytest.mark.parametrize("directory", sorted(p.name for p in OLD.iterdir() if p.is_dir() and p.name not in DRIVE_LAW_OLD))
def test_a_model_saved_before_the_classes_loads_into_its_class_bit_for_bit(directory):
    """The JSON of one RivalIK with a ``kind`` and one BaselineID with a ``learner`` (before issue
    67; tests/data/models_before_67/README.md): loaded into the learner's class, it predicts what
    it predicted then — to the last bits numpy's SIMD kernels choose by CPU (bit for bit under the
    report's pinned kernels, `make report`'s REPORT_ENV) — and saved again it writes the same fields."""
    expected = np.load(OLD / "predictions.npz")
    path = next((OLD / directory).glob("*.json"))
    if path.name == "rival_ik.json":
        model = RivalIK.load(OLD / directory, ROBOT)
        assert type(model) is RIVALS[json.loads(path.read_text())["kind"]]
        predicted = model.predict(expected["T"])
    else:
        model = load_id_model(OLD / directory, ROBOT)
        assert type(model) is BASELINES[json.loads(path.read_text())["learner"]]
        predicted = model.predict(expected["state_q"], expected["state_qd"], expected["state_qdd"])
    np.testing.assert_allclose(predicted, expected[directory], rtol=1e-12, atol=1e-12)
    old = {k: v for k, v in json.loads(path.read_text()).items() if k not in (CONTENT_FIELD, "nfarm_version")}
    new = {k: v for k, v in model.to_dict().items() if k != "nfarm_version"}
    if "options" in old:        # options added since (kernel ridge's length_scales, issue 64) saved at their defaults
        defaults = inspect.signature(type(model)).parameters
        added = set(new["options"]) - set(old["options"])
        assert {k: new["options"][k] for k in added} == {k: defaults[k].default for k in added}
        old["options"] = {**old["options"], **{k: new["options"][k] for k in added}}
    assert _same_content(new, old)


@pytest.mark.parametrize("field, value, saved_by, rule", [
    ("kind", "svm", "knn", "kind: must be one of knn, rbf, mlp, kernel_ridge, got 'svm'"),
    ("learner", "forest", "linear", "learner: must be one of linear, ridge, kernel, boosting, mlp, friction, "
                                    "identification, got 'forest'"),
], ids=["rival", "baseline"])
def test_a_file_of_an_unknown_learner_is_refused_in_one_line(field, value, saved_by, rule, poses, states, tmp_path):
    if field == "kind":
        model, load = rival_ik(saved_by).fit(ROBOT, poses["train"]), RivalIK.load
    else:
        model, load = baseline_id(saved_by).fit(ROBOT, states["train"]), load_id_model
    path = model.save(tmp_path)
    data = json.loads(path.read_text())
    data[field] = value
    path.write_text(json.dumps(with_content_digest({k: v for k, v in data.items() if k != CONTENT_FIELD})))
    with pytest.raises(ParamsError) as caught:
        load(tmp_path, ROBOT)
    assert str(caught.value) == f"{path}: {rule}"          # one line: the file, the field, the rule
    with pytest.raises(ValueError, match=rf"^{field} must be one of .*, got '{value}'$"):
        (rival_ik if field == "kind" else baseline_id)(value)


def test_a_file_of_another_class_is_refused_by_a_class_that_is_not_its_own(poses, tmp_path):
    path = rival_ik("knn").fit(ROBOT, poses["train"]).save(tmp_path)
    assert type(KNNRival.load(path, ROBOT)) is KNNRival
    with pytest.raises(ParamsError, match=r"rival_ik.json: kind: must be 'rbf' \(a RBFRival\), got 'knn'$"):
        RBFRival.load(path, ROBOT)


@pytest.mark.parametrize("make, message", [
    (lambda: rival_ik("knn", options={"k": 3}), r"^knn: unknown option 'k'; valid: neighbors, weights$"),
    (lambda: rival_ik("knn", options=[3]), r"^options must be a mapping of knn options, got \[3\]$"),
    (lambda: rival_ik("knn", colour=1), r"^unknown parameter 'colour' for KNNRival; valid: neighbors, weights, encoding"),
    (lambda: baseline_id("linear", {"alpha": 1.0}), r"^unknown option 'alpha' for learner 'linear'; valid: none$"),
], ids=["rival option", "rival options", "rival parameter", "baseline option"])
def test_the_factories_refuse_an_unknown_option_in_one_line(make, message):
    with pytest.raises(ValueError, match=message):
        make()


# -- a new learner: one class -----------------------------------------------------------------


class _Constant(RivalIK):
    """A scratch rival: each learned joint's training mean, shrunk toward 0 by ``shrink``."""

    kind, label = "constant", "the training mean"
    _state_keys = ("mean",)

    def __init__(self, shrink: float = 0.0, *, encoding="arm_plane", max_out_of_plane=math.pi, random_state=None,
                 structure="whole", closure_tolerance=1e-4, affine_ridge=1e-8, pitch_closure=True):
        self.shrink = shrink
        super().__init__(encoding=encoding, max_out_of_plane=max_out_of_plane, random_state=random_state,
                         structure=structure, closure_tolerance=closure_tolerance, affine_ridge=affine_ridge,
                         pitch_closure=pitch_closure)

    def _checked(self):
        if not 0 <= self.shrink <= 1:
            raise ValueError(f"constant: shrink must be in [0, 1], got {self.shrink!r}")
        return {"shrink": self.shrink}

    def _learn(self, o, X, y, X_val, y_val):
        self.mean_ = (1 - o["shrink"]) * y.mean(axis=0)

    def _predict(self, X):
        return np.broadcast_to(self.mean_, (len(X), len(self.mean_))).copy()

    def _state(self):
        return {"mean": self.mean_.tolist()}

    def _read_state(self, v, state, d, n_out, o):
        self.mean_ = v.array(state["mean"], "state.mean", (n_out,))


class _Mean(BaselineID):
    """A scratch baseline: each joint's training mean torque (of the residual, with ``residual``)."""

    learner, label = "mean", "the training mean torque"

    def __init__(self, shrink: float = 0.0, *, residual: bool = False, random_state: int = 0):
        self.shrink = shrink
        super().__init__(residual=residual, random_state=random_state)

    def _features(self, q, qd, qdd):
        return np.ones((len(q), 1))

    def _estimator(self, options):
        from sklearn.dummy import DummyRegressor
        return DummyRegressor()

    def _state_of(self, model):
        return {"constant": (1 - self.shrink) * np.ravel(model.constant_)}

    def _predict_state(self, state, X):
        return np.broadcast_to(state["constant"], (len(X), len(state["constant"])))

    def _read_state(self, v, state, k, n, options):
        v.mapping(state, "state", {"constant": True})
        return {"constant": v.array(state["constant"], "state.constant", (n,))}


@pytest.fixture
def scratch():
    """The two scratch learners registered for one test, and removed after it."""
    RIVALS.register(_Constant)
    BASELINES.register(_Mean)
    yield
    del RIVALS["constant"], BASELINES["mean"]


def test_a_new_learner_is_one_registered_class(scratch, poses, states, tmp_path):
    """Registered, a scratch rival and a scratch baseline are built by name, fitted in both
    structures, saved, loaded by the base classes, cached, found among chapter 6's saved rivals and
    named in words — with no other edit of the library."""
    T = poses["val"]["T"]
    for structure in ("whole", "arm"):
        model = rival_ik("constant", options={"shrink": 0.5}, structure=structure).fit(ROBOT, poses["train"])
        loaded = RivalIK.load(model.save(tmp_path / structure), ROBOT)
        assert type(loaded) is _Constant and loaded.options_ == {"shrink": 0.5}
        np.testing.assert_array_equal(loaded.predict(T), model.predict(T))
    assert contest.label("constant") == "the training mean"
    assert contest.label("constant:arm") == "the training mean in the ANFIS's structure"
    model.save(tmp_path / "models" / "ik_contest" / "constant_arm")
    assert list(contest.saved_rivals(ROBOT, tmp_path / "models")) == ["constant:arm"]
    cached = [fit_cached(_Constant(shrink=0.25), ROBOT, poses["train"], None, tmp_path / "cache") for _ in range(2)]
    assert [how for _, how in cached] == ["made", "reused"] and type(cached[1][0]) is _Constant
    with pytest.raises(ValueError, match=r"^constant: shrink must be in \[0, 1\], got 2$"):
        rival_ik("constant", options={"shrink": 2}).fit(ROBOT, poses["train"])

    mean = baseline_id("mean", {"shrink": 0.5}, residual=True).fit(ROBOT, states["train"])
    again = load_id_model(mean.save(tmp_path / "id"), ROBOT)
    X = (states["val"]["q"], states["val"]["qd"], states["val"]["qdd"])
    assert type(again) is _Mean
    np.testing.assert_array_equal(again.predict(*X), mean.predict(*X))
    assert "shrink" in option_names() and label({"learner": "mean", "shrink": 0.5}) == "mean (shrink=0.5)"
    assert contest.id_label("nominal model + learned:mean") == "nominal model + learned: the training mean torque"


def test_a_name_is_one_class_and_a_class_needs_its_name():
    before = list(RIVALS)
    with pytest.raises(ValueError, match=r"learned-IK rival: kind 'knn' is KNNRival's, not Other's"):
        RIVALS.register(type("Other", (_Constant,), {"kind": "knn"}))
    with pytest.raises(ValueError, match=r"Other: a learned-IK rival learner needs its kind"):
        RIVALS.register(type("Other", (RivalIK,), {}))
    assert RIVALS.register(KNNRival) is KNNRival and list(RIVALS) == before      # the same class again: no change


@pytest.mark.parametrize("base, data", [(RivalIK, "poses"), (BaselineID, "states")])
def test_a_base_class_is_not_a_learner_of_its_own(base, data, request):
    with pytest.raises(TypeError, match=rf"^{base.__name__} is not a .* of its own: fit one of "):
        base().fit(ROBOT, request.getfixturevalue(data)["train"])
