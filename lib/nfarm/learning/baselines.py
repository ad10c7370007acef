"""Model-free baselines for learned inverse dynamics, from scikit-learn (chapters 06 and 07).

What an engineer would try before a fuzzy system, each fed states ``q, q̇, q̈`` and nothing of
the arm's masses or lengths (:data:`LEARNERS`):

* ``"linear"`` — ordinary least squares on ``[q, q̇, q̈]``: the floor any learner must beat;
* ``"ridge"`` — ridge regression on a feature basis of :mod:`nfarm.learning.bases` (``basis``:
  ``"generic"``, 1 386 features for five joints; ``"chain"``, with the sums of parallel joints,
  3 213) — torque affine in ``q̈``, quadratic in ``q̇``, trigonometric in ``q``;
* ``"kernel"`` — kernel ridge regression with a Gaussian kernel, approximated by Nyström's
  method (``n_components`` landmarks, ``gamma``) on standardised ``sin, cos`` of the angles,
  ``q̇, q̈``: with ``angles="joints"`` the joint angles (what every arm has: the *generic* tier),
  with ``angles="chain"`` the joint angles and the sums of every stretch of parallel joints
  (:func:`nfarm.learning.bases.angle_sums`: which axes are parallel, the *structure-informed*
  tier's knowledge, the inputs its ANFIS and its ridge on the chain basis get);
* ``"boosting"`` — gradient-boosted trees per joint (``HistGradientBoostingRegressor``:
  ``max_iter``, ``learning_rate``, ``max_leaf_nodes``) on the same inputs (``angles`` too);
* ``"mlp"`` — a multilayer perceptron (``hidden`` layer widths, ``alpha``, at most ``max_iter``
  epochs of Adam) on the same inputs (``angles`` too); given validation states, it keeps the epoch of least
  validation error and stops ``patience`` epochs after it — the early stopping the ANFIS gets, on
  the same validation trajectories;
* ``"friction"`` — not a learner but the identification any engineer tries first on a real
  arm: with ``residual=True``, per joint, least squares of ``τ − rnea`` on that joint's
  ``[q̈_j, q̇_j, sign q̇_j]`` — armature, viscous and Coulomb friction (chapter 06.8);
* ``"identification"`` — the full identification of a built arm whose geometry is known
  (Atkeson, An & Hollerbach 1986; the *identification* tier): one least squares of ``τ`` over
  every joint on the rigid-body regressor ``Y(q, q̇, q̈)`` (:func:`nfarm.model.dynamics.regressor`,
  the inertial parameters shared by all joints' rows) and each joint's ``[q̈_j, q̇_j, sign q̇_j]``
  (armature, viscous and Coulomb friction) — it refits the masses, centres of mass and
  inertias where the built arm differs from the model. Columns are scaled to unit norm and
  the minimum-norm solution is kept (the regressor's columns are not all identifiable).

Targets are standardised per joint (each joint's error then counts alike, as in the NRMSE the
chapters report), inputs too where the learner is not scale-free. Every random draw comes from
``random_state``; a fit is a function of its options, data (and the MLP's validation states) and seed.
With ``residual=True`` a baseline learns ``τ − rnea`` and predicts ``rnea + learned``.

**Saving.** A fitted baseline is saved as JSON (:meth:`BaselineID.save`, no pickle): once fitted,
each learner's arithmetic is read out of the scikit-learn estimator into arrays — the scaler's
means and scales, the linear and ridge weights, the Nyström landmarks and normalisation, every
boosted tree's splits and leaf values, the perceptron's layers — and :meth:`BaselineID.predict`
computes from those arrays with the operations scikit-learn's ``predict`` performs, in its order,
so a fitted and a loaded model predict the same bits (``tests/test_baselines.py`` checks both
against scikit-learn's own ``predict``). :func:`load_id_model` reads any saved learned-ID model of
this package (a :class:`BaselineID` or a :class:`~nfarm.learning.learned_id.LearnedID`).

**Time limits.** A sweep cell runs in a worker's thread, where nothing can stop a fit from
outside; the iterative learners check the caller's deadline (:func:`nfarm.infra.limits.time_limit`)
once per iteration — boosting before each boosting iteration, the MLP after each epoch —
through two hooks of scikit-learn's loops that change no arithmetic (the fits are bit-identical
to the plain estimators', ``tests/test_baselines.py``). The one-step learners (least squares,
ridge, kernel ridge) are bounded by their sizes instead: the options' upper limits below.
"""

from __future__ import annotations

import functools
import os
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..infra.limits import check_time
from ..infra.reading import ParamsError, Validator, json_ready
from ..model.dynamics import regressor, rnea
from ..model.robot import Robot, robot_hash
from .bases import BASES, angle_sums, basis
from .estimator import SavedModel, check_robot
from .learned_id import ID_FILE_NAME, ID_FORMAT, LearnedID, id_states

__all__ = ["LEARNERS", "ANGLES", "BaselineID", "DEFAULTS", "OPTION_NAMES", "label", "load_id_model", "FILE_NAME", "FORMAT"]

FILE_NAME = "baseline_id.json"
FORMAT = "nfarm-baseline-id-1"

#: Each learner's options and their defaults.
DEFAULTS: dict[str, dict[str, Any]] = {
    "linear": {},
    "ridge": {"basis": "generic", "alpha": 1e-6},
    "kernel": {"n_components": 1000, "gamma": 0.1, "alpha": 1e-6, "angles": "joints"},
    "boosting": {"max_iter": 300, "learning_rate": 0.1, "max_leaf_nodes": 31, "angles": "joints"},
    "mlp": {"hidden": [128, 128], "alpha": 1e-4, "max_iter": 200, "patience": 10, "angles": "joints"},
    "friction": {},
    "identification": {},
}
LEARNERS = tuple(DEFAULTS)
#: Every learner's option names, in the order of :data:`DEFAULTS`.
OPTION_NAMES = tuple(dict.fromkeys(k for options in DEFAULTS.values() for k in options))
#: The largest value of each integer option: a Nyström kernel of ``n_components`` landmarks
#: holds an ``(N, n_components)`` matrix and cannot be stopped once started; boosting's trees
#: and the MLP's widths bound the work of one iteration, which the time limit cannot split.
MAXIMA = {"n_components": 10_000, "max_iter": 100_000, "max_leaf_nodes": 4_096, "hidden": 4_096, "patience": 100_000}
#: The angles whose ``sin, cos`` the kernel, boosting and the MLP see (module docstring).
ANGLES = ("joints", "chain")


def label(params: Mapping) -> str:
    """``"ridge (basis=chain, alpha=1e-06)"``: a learner and the options ``params`` gives it
    (a sweep cell's flat parameters; ``None`` and other keys are left out)."""
    given = {k: params[k] for k in OPTION_NAMES if params.get(k) is not None}
    return params["learner"] + (" (" + ", ".join(f"{k}={v}" for k, v in given.items()) + ")" if given else "")


def _smooth_inputs(angles, qd, qdd) -> np.ndarray:
    """``(N, 2K + 2n)``: ``sin, cos`` of ``angles (N, K)``, then ``q̇, q̈ (N, n)``."""
    return np.concatenate([np.sin(angles), np.cos(angles), qd, qdd], axis=1)


class BaselineID(SavedModel):
    """One scikit-learn learner of the torques of every joint (scikit-learn conventions).

    Args:
        learner: one of :data:`LEARNERS`.
        options: the learner's options (:data:`DEFAULTS` for the rest).
        residual: learn ``τ − rnea(q, q̇, q̈)`` instead of ``τ``.
        random_state: seed of every random draw.

    Learned attributes: ``state_`` (the fitted arithmetic as arrays, what :meth:`predict` uses
    and :meth:`save` writes), ``model_`` (the scikit-learn estimator, after :meth:`fit` only),
    ``robot_``, ``y_mean_``, ``y_scale_``, ``fit_seconds_``, ``n_features_`` (inputs the learner
    sees), ``epochs_`` and ``best_epoch_`` (the MLP stopped early on validation states; ``None``
    otherwise).

    Example:
        >>> from nfarm.model.robot import load_robot
        >>> from nfarm.infra.paths import PARAMS
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> rng = np.random.default_rng(0)
        >>> q, qd, qdd = (rng.uniform(-1, 1, (400, robot.n)) for _ in range(3))
        >>> train = {"q": q, "qd": qd, "qdd": qdd, "tau": rnea(robot, q, qd, qdd)}
        >>> model = BaselineID("ridge", {"basis": "chain"}).fit(robot, train)
        >>> float(np.abs(model.predict(q, qd, qdd) - train["tau"]).max()) < 1e-6
        True
    """

    _fitted = "state_"

    file_name, file_format, what = FILE_NAME, FORMAT, "baseline ID"

    def __init__(self, learner: str = "ridge", options: Mapping | None = None, residual: bool = False,
                 random_state: int = 0):
        self.learner = learner
        self.options = options
        self.residual = residual
        self.random_state = random_state

    def _options(self) -> dict:
        if self.learner not in LEARNERS:
            raise ValueError(f"learner must be one of {', '.join(LEARNERS)}, got {self.learner!r}")
        given = dict(self.options or {})
        unknown = sorted(set(given) - set(DEFAULTS[self.learner]))
        if unknown:
            valid = ", ".join(DEFAULTS[self.learner]) or "none"
            raise ValueError(f"unknown option {unknown[0]!r} for learner {self.learner!r}; valid: {valid}")
        options = {**DEFAULTS[self.learner], **given}
        for key in ("alpha", "gamma", "learning_rate"):
            if key in options and not (isinstance(options[key], (int, float)) and options[key] > 0
                                       and np.isfinite(options[key])):
                raise ValueError(f"{self.learner}: {key} must be a positive number, got {options[key]!r}")
        for key in ("n_components", "max_iter", "max_leaf_nodes", "patience"):
            if key in options and not (isinstance(options[key], (int, np.integer))
                                       and not isinstance(options[key], bool) and 2 <= options[key] <= MAXIMA[key]):
                raise ValueError(f"{self.learner}: {key} must be an integer from 2 to {MAXIMA[key]:,}, "
                                 f"got {options[key]!r}")
        if "angles" in options and options["angles"] not in ANGLES:
            raise ValueError(f"{self.learner}: angles must be one of {', '.join(ANGLES)}, got {options['angles']!r}")
        if "basis" in options and options["basis"] not in BASES:
            raise ValueError(f"{self.learner}: basis must be one of {', '.join(BASES)}, got {options['basis']!r}")
        if "hidden" in options:
            hidden = options["hidden"]
            if isinstance(hidden, (int, str)) or not all(isinstance(h, (int, np.integer)) and not isinstance(h, bool)
                                                         and 1 <= h <= MAXIMA["hidden"] for h in hidden) \
                    or not hidden or len(hidden) > 16:
                raise ValueError(f"mlp: hidden must be a list of 1 to 16 layer widths from 1 to "
                                 f"{MAXIMA['hidden']:,}, got {hidden!r}")
        return options

    def _features(self, q, qd, qdd) -> np.ndarray:
        if self.learner == "linear":
            return np.concatenate([q, qd, qdd], axis=1)
        if self.learner == "friction":
            return np.stack([qdd, qd, np.sign(qd)], axis=-1)                 # (N, n, 3)
        if self.learner == "identification":                                 # (N, n, 10 n + 3 n)
            n = q.shape[1]
            own = np.stack([qdd, qd, np.sign(qd)], axis=-1)                  # (N, n, 3): joint j's drive terms
            drives = (np.eye(n)[None, :, :, None] * own[:, :, None, :]).reshape(len(q), n, 3 * n)
            return np.concatenate([regressor(self.robot_, q, qd, qdd), drives], axis=-1)
        if self.learner == "ridge":
            return basis(self.robot_, q, qd, qdd, self.options_["basis"])[:, 1:]
        return _smooth_inputs(q if self.options_["angles"] == "joints" else angle_sums(self.robot_, q), qd, qdd)

    def _estimator(self, options: dict):
        from sklearn.kernel_approximation import Nystroem
        from sklearn.linear_model import LinearRegression, Ridge
        from sklearn.multioutput import MultiOutputRegressor
        from sklearn.pipeline import make_pipeline
        from sklearn.preprocessing import StandardScaler

        HistGradientBoostingRegressor, MLPRegressor = _timed_learners()

        seed = self.random_state
        if self.learner == "friction":
            return _PerJointLeastSquares()
        if self.learner == "identification":
            return _StackedLeastSquares()
        if self.learner == "linear":
            return LinearRegression()
        if self.learner == "ridge":
            return make_pipeline(StandardScaler(), Ridge(alpha=options["alpha"], solver="cholesky"))
        if self.learner == "kernel":
            return make_pipeline(StandardScaler(),
                                 Nystroem(kernel="rbf", gamma=options["gamma"],
                                          n_components=options["n_components"], random_state=seed),
                                 Ridge(alpha=options["alpha"], solver="cholesky"))
        if self.learner == "boosting":
            return MultiOutputRegressor(HistGradientBoostingRegressor(
                max_iter=options["max_iter"], learning_rate=options["learning_rate"],
                max_leaf_nodes=options["max_leaf_nodes"], early_stopping=False, random_state=seed))
        return make_pipeline(StandardScaler(), MLPRegressor(
            hidden_layer_sizes=tuple(options["hidden"]), alpha=options["alpha"],
            max_iter=options["max_iter"], early_stopping=False, random_state=seed, tol=0.0,
            n_iter_no_change=options["max_iter"] + 1))

    def fit(self, robot: Robot, train: Mapping, val: Mapping | None = None) -> "BaselineID":
        """Fit on ``train`` (arrays ``q, qd, qdd, tau (N, n)``); the MLP stops early on ``val``
        (the same arrays) when it is given, and trains ``max_iter`` epochs when not.

        Raises:
            ValueError: an unknown learner or option, or bad data, before any work.
        """
        import warnings

        from sklearn.exceptions import ConvergenceWarning


        options = self._options()
        if not isinstance(self.residual, bool):
            raise ValueError(f"residual must be True or False, got {self.residual!r}")
        if self.learner == "friction" and not self.residual:
            raise ValueError("learner 'friction' identifies the drives beside Newton–Euler: give residual=True")
        if self.learner == "identification" and self.residual:
            raise ValueError("learner 'identification' fits the whole torque, the masses included: give residual=False")
        q, qd, qdd, tau = id_states(train, robot, "train")
        self.robot_, self.options_ = robot, options
        target = tau - rnea(robot, q, qd, qdd) if self.residual else tau
        if self.learner in ("friction", "identification"):      # a physical law: no offset, no scaling
            self.y_mean_, self.y_scale_ = np.zeros(robot.n), np.ones(robot.n)
        else:
            self.y_mean_ = target.mean(axis=0)
            self.y_scale_ = np.where(target.std(axis=0) > 0, target.std(axis=0), 1.0)
        X = self._features(q, qd, qdd)
        self.n_features_ = X.shape[-1]
        start = time.perf_counter()
        Z = (target - self.y_mean_) / self.y_scale_
        self.epochs_ = self.best_epoch_ = None
        with warnings.catch_warnings():
            # A budget of epochs is the design: reaching it is not a failure.
            warnings.simplefilter("ignore", ConvergenceWarning)
            if self.learner == "mlp" and val is not None:
                vq, vqd, vqdd, vtau = id_states(val, robot, "val")
                v_target = vtau - rnea(robot, vq, vqd, vqdd) if self.residual else vtau
                self.model_ = self._early_stopped_mlp(options, X, Z, self._features(vq, vqd, vqdd),
                                                      (v_target - self.y_mean_) / self.y_scale_)
            else:
                self.model_ = self._estimator(options).fit(X, Z)
        self.fit_seconds_ = time.perf_counter() - start
        self.state_ = _state_of(self.learner, self.model_)
        return self

    def _early_stopped_mlp(self, options: dict, X, Z, X_val, Z_val):
        """The MLP trained epoch by epoch (``partial_fit``: one pass of Adam over shuffled
        batches, as ``fit`` makes), its weights those of the epoch of least validation RMSE,
        stopped ``patience`` epochs after it or at ``max_iter``; sets ``epochs_`` and
        ``best_epoch_`` (0-based)."""
        from sklearn.pipeline import make_pipeline
        from sklearn.preprocessing import StandardScaler

        _, MLPRegressor = _timed_learners()
        scaler = StandardScaler().fit(X)
        net = MLPRegressor(hidden_layer_sizes=tuple(options["hidden"]), alpha=options["alpha"],
                           random_state=self.random_state, shuffle=True)
        Xs, Xv = scaler.transform(X), scaler.transform(X_val)
        best, since, weights = np.inf, 0, None
        for epoch in range(options["max_iter"]):
            net.partial_fit(Xs, Z)
            self.epochs_ = epoch + 1
            error = float(np.sqrt(np.mean((net.predict(Xv).reshape(Z_val.shape) - Z_val) ** 2)))
            if error < best:
                best, since, self.best_epoch_ = error, 0, epoch
                weights = ([w.copy() for w in net.coefs_], [b.copy() for b in net.intercepts_])
            else:
                since += 1
                if since >= options["patience"]:
                    break
        net.coefs_, net.intercepts_ = weights
        return make_pipeline(scaler, net)

    def predict(self, q, qd, qdd) -> np.ndarray:
        """Torques ``(N, n)`` [N·m] for states ``(N, n)``."""
        self._check_fitted()

        q, qd, qdd = id_states({"q": q, "qd": qd, "qdd": qdd}, self.robot_, "states", tau=False)
        y = _predict_state(self.learner, self.state_, self._features(q, qd, qdd)).reshape(len(q), -1)
        tau = y * self.y_scale_ + self.y_mean_
        if self.residual:
            tau = tau + rnea(self.robot_, q, qd, qdd)
        return tau

    # -- persistence --------------------------------------------------------------------------

    def to_dict(self) -> dict:
        """The model as JSON-ready fields: its options, the robot's name and hash, the targets'
        scaling and the learner's arrays (``state``)."""
        self._check_fitted()
        return {"format": FORMAT, "nfarm_version": __version__, "learner": self.learner,
                "options": json_ready(self.options_), "residual": self.residual, "random_state": self.random_state,
                "robot": self.robot_.name, "robot_params_sha256": robot_hash(self.robot_), "n_joints": self.robot_.n,
                "n_features": int(self.n_features_), "y_mean": json_ready(self.y_mean_),
                "y_scale": json_ready(self.y_scale_), "fit_seconds": float(self.fit_seconds_),
                "epochs": self.epochs_, "best_epoch": self.best_epoch_, "state": json_ready(self.state_)}

    @classmethod
    def from_dict(cls, data: Any, robot: Robot, source: str = "<dict>") -> "BaselineID":
        v = Validator(source)
        keys = ("format", "nfarm_version", "learner", "options", "residual", "random_state", "robot",
                "robot_params_sha256", "n_joints", "n_features", "y_mean", "y_scale", "fit_seconds", "epochs",
                "best_epoch", "state")
        v.mapping(data, "", dict.fromkeys(keys, True))
        learner = v.choice(data["learner"], "learner", LEARNERS)
        check_robot(v, data, robot)
        n = v.integer(data["n_joints"], "n_joints", lo=robot.n, hi=robot.n)
        model = cls(learner, v.mapping(data["options"], "options", dict.fromkeys(DEFAULTS[learner], True)),
                    residual=v.boolean(data["residual"], "residual"),
                    random_state=v.integer(data["random_state"], "random_state", lo=0))
        try:
            options = model._options()
        except ValueError as exc:
            v.fail("options", str(exc))
        if learner == "friction" and not model.residual or learner == "identification" and model.residual:
            v.fail("residual", f"learner {learner!r} {'needs' if learner == 'friction' else 'refuses'} residual=true")
        model.robot_, model.options_ = robot, options
        model.n_features_ = v.integer(data["n_features"], "n_features", lo=1, hi=10_000_000)
        model.y_mean_ = v.array(data["y_mean"], "y_mean", (n,))
        model.y_scale_ = v.array(data["y_scale"], "y_scale", (n,))
        if not (model.y_scale_ > 0).all():
            v.fail("y_scale", "must hold positive numbers")
        model.fit_seconds_ = v.number(data["fit_seconds"], "fit_seconds", lo=0)
        model.epochs_ = None if data["epochs"] is None else v.integer(data["epochs"], "epochs", lo=1)
        model.best_epoch_ = None if data["best_epoch"] is None else v.integer(data["best_epoch"], "best_epoch", lo=0)
        q = np.zeros((1, n))
        expected = model._features(q, q, q).shape[-1]      # the features this learner computes for the robot
        if model.n_features_ != expected:
            v.fail("n_features", f"must be {expected} for learner {learner!r} on {robot.name}, got {model.n_features_}")
        model.state_ = _read_state(v, learner, data["state"], expected, n, options)
        return model


def load_id_model(directory: str | os.PathLike, robot: Robot) -> "BaselineID | LearnedID":
    """The learned-ID model saved in ``directory`` for ``robot``: a :class:`BaselineID`
    (``baseline_id.json``) or a :class:`~nfarm.learning.learned_id.LearnedID` (``learned_id.json``),
    whichever the directory holds (or the file named). Either predicts torques ``(N, n)`` [N·m]
    with ``predict(q, qd, qdd)``.

    Raises:
        ParamsError: neither file is there, or the file is damaged, edited or of another robot.
    """
    path = Path(directory)
    for cls, name in ((BaselineID, FILE_NAME), (LearnedID, ID_FILE_NAME)):
        if path.name == name or (path / name).is_file():
            return cls.load(path, robot)
    raise ParamsError(f"{path}: holds no saved learned-ID model ({FILE_NAME} or {ID_FILE_NAME})")


# -- the fitted arithmetic as arrays ------------------------------------------------------------

_TREE_FIELDS = ("feature", "threshold", "left", "right", "leaf", "value", "missing_left")


def _state_of(learner: str, model) -> dict:
    """The arrays ``model`` (the fitted scikit-learn estimator of ``learner``) predicts with."""
    if learner in ("friction", "identification"):
        return {"coef": model.coef_}
    if learner == "linear":
        return {"coef": model.coef_, "intercept": np.atleast_1d(model.intercept_)}
    if learner == "boosting":
        joints = []
        for est in model.estimators_:
            trees = []
            for (predictor,) in est._predictors:           # one tree per iteration (a single output)
                nodes = predictor.nodes
                trees.append({"feature": nodes["feature_idx"].astype(int), "threshold": nodes["num_threshold"],
                              "left": nodes["left"].astype(int), "right": nodes["right"].astype(int),
                              "leaf": nodes["is_leaf"].astype(int), "value": nodes["value"],
                              "missing_left": nodes["missing_go_to_left"].astype(int)})
            joints.append({"baseline": float(np.ravel(est._baseline_prediction)[0]), "trees": trees})
        return {"joints": joints}
    scaler, *rest, last = list(model.named_steps.values())
    state = {"mean": scaler.mean_, "scale": scaler.scale_}
    if learner == "ridge":
        return {**state, "coef": last.coef_, "intercept": np.atleast_1d(last.intercept_)}
    if learner == "kernel":
        (nystroem,) = rest
        return {**state, "landmarks": nystroem.components_, "normalization": nystroem.normalization_,
                "gamma": float(nystroem.gamma), "coef": last.coef_, "intercept": np.atleast_1d(last.intercept_)}
    return {**state, "weights": list(last.coefs_), "biases": list(last.intercepts_)}         # mlp


def _forest(trees: list[dict]) -> list:
    """scikit-learn's compiled tree predictors (``TreePredictor``, the class its
    ``HistGradientBoostingRegressor`` predicts with) rebuilt from the saved node arrays: numerical
    splits only (``x <= threshold`` goes left, a missing value where ``missing_left`` says)."""
    from sklearn.ensemble._hist_gradient_boosting.common import PREDICTOR_RECORD_DTYPE, X_BITSET_INNER_DTYPE
    from sklearn.ensemble._hist_gradient_boosting.predictor import TreePredictor

    no_bitsets = np.zeros((0, 8), dtype=X_BITSET_INNER_DTYPE)
    forest = []
    for tree in trees:
        nodes = np.zeros(len(tree["leaf"]), dtype=PREDICTOR_RECORD_DTYPE)
        nodes["feature_idx"], nodes["num_threshold"], nodes["value"] = tree["feature"], tree["threshold"], tree["value"]
        nodes["left"], nodes["right"] = tree["left"], tree["right"]
        nodes["is_leaf"], nodes["missing_go_to_left"] = tree["leaf"], tree["missing_left"]
        forest.append(TreePredictor(nodes, no_bitsets, no_bitsets))
    return forest


def _forest_values(trees: list[dict], baseline: float, X: np.ndarray) -> np.ndarray:
    """One joint's boosted prediction for each row of ``X (N, k)``: the baseline plus every tree's
    leaf value, added in the trees' order as scikit-learn's ``predict`` adds them (its compiled
    traversal, one thread; about 40× faster than a traversal in NumPy, which costs ~0.2 ms a
    state for 300 trees)."""
    X = np.ascontiguousarray(X, dtype=float)
    no_categories, feature_map = np.zeros((0, 8), dtype=np.uint32), np.zeros(X.shape[1], dtype=np.uint32)
    raw = np.zeros(len(X))
    raw += baseline
    for predictor in _forest(trees):
        raw += predictor.predict(X, no_categories, feature_map, 1)
    return raw


def _predict_state(learner: str, state: dict, X: np.ndarray) -> np.ndarray:
    """The scaled targets for features ``X``, computed from ``state`` as scikit-learn's ``predict``
    computes them (the same operations in the same order)."""
    if learner == "friction":
        return np.einsum("njk,jk->nj", X, state["coef"])
    if learner == "identification":
        return X @ state["coef"]
    if learner == "linear":
        return X @ state["coef"].T + state["intercept"]
    if learner == "boosting":
        return np.column_stack([_forest_values(joint["trees"], joint["baseline"], X) for joint in state["joints"]])
    Xs = (X - state["mean"]) / state["scale"]
    if learner == "ridge":
        return Xs @ state["coef"].T + state["intercept"]
    if learner == "kernel":
        from sklearn.metrics.pairwise import rbf_kernel

        features = rbf_kernel(Xs, state["landmarks"], gamma=state["gamma"]) @ state["normalization"].T
        return features @ state["coef"].T + state["intercept"]
    a = Xs
    for k, (W, b) in enumerate(zip(state["weights"], state["biases"])):
        a = a @ W
        a += b
        if k < len(state["weights"]) - 1:
            np.maximum(a, 0, out=a)
    return a


def _read_state(v: Validator, learner: str, state: Any, k: int, n: int, options: dict) -> dict:
    """A saved ``state`` validated for ``learner`` with ``k`` features and ``n`` joints."""
    if learner in ("friction", "identification"):
        v.mapping(state, "state", {"coef": True})
        return {"coef": v.array(state["coef"], "state.coef", (n, 3) if learner == "friction" else (k,))}
    if learner == "linear":
        v.mapping(state, "state", {"coef": True, "intercept": True})
        return {"coef": v.array(state["coef"], "state.coef", (n, k)),
                "intercept": v.array(state["intercept"], "state.intercept", (n,))}
    if learner == "boosting":
        v.mapping(state, "state", {"joints": True})
        joints = v.sequence(state["joints"], "state.joints", min_len=n, max_len=n)
        out = []
        for j, joint in enumerate(joints):
            at = f"state.joints[{j}]"
            v.mapping(joint, at, {"baseline": True, "trees": True})
            trees = v.sequence(joint["trees"], f"{at}.trees", max_len=options["max_iter"])
            read = []
            for t, tree in enumerate(trees):
                where = f"{at}.trees[{t}]"
                v.mapping(tree, where, dict.fromkeys(_TREE_FIELDS, True))
                ints = {f: v.array(tree[f], f"{where}.{f}", (None,), integer=True)
                        for f in ("feature", "left", "right", "leaf", "missing_left")}
                floats = {f: v.array(tree[f], f"{where}.{f}", (None,)) for f in ("threshold", "value")}
                m = len(ints["leaf"])
                if m == 0 or any(len(a) != m for a in (*ints.values(), *floats.values())):
                    v.fail(where, "must hold equally long, non-empty node arrays")
                inner = np.flatnonzero(ints["leaf"] == 0)
                idx = np.arange(m)
                if not np.isin(ints["leaf"], (0, 1)).all() or not np.isin(ints["missing_left"], (0, 1)).all():
                    v.fail(f"{where}.leaf", "leaf and missing_left must hold 0 or 1")
                if ((ints["feature"][inner] < 0) | (ints["feature"][inner] >= k)).any():
                    v.fail(f"{where}.feature", f"must name features 0 to {k - 1}")
                for f in ("left", "right"):
                    child = ints[f][inner]
                    if ((child <= idx[inner]) | (child >= m)).any():
                        v.fail(f"{where}.{f}", "must name a later node of the tree")
                read.append({**ints, **floats})
            out.append({"baseline": v.number(joint["baseline"], f"{at}.baseline"), "trees": read})
        return {"joints": out}
    scaled = {"mean": True, "scale": True}
    if learner == "ridge":
        v.mapping(state, "state", {**scaled, "coef": True, "intercept": True})
        read = {"coef": v.array(state["coef"], "state.coef", (n, k)),
                "intercept": v.array(state["intercept"], "state.intercept", (n,))}
    elif learner == "kernel":
        v.mapping(state, "state", {**scaled, "landmarks": True, "normalization": True, "coef": True,
                                   "intercept": True, "gamma": True})
        landmarks = v.array(state["landmarks"], "state.landmarks", (None, k))
        m = len(landmarks)
        read = {"landmarks": landmarks, "normalization": v.array(state["normalization"], "state.normalization", (m, m)),
                "coef": v.array(state["coef"], "state.coef", (n, m)),
                "intercept": v.array(state["intercept"], "state.intercept", (n,)),
                "gamma": v.number(state["gamma"], "state.gamma", lo=0, lo_open=True)}
    else:
        v.mapping(state, "state", {**scaled, "weights": True, "biases": True})
        widths = [k, *options["hidden"], n]
        layers = len(widths) - 1
        weights = v.sequence(state["weights"], "state.weights", min_len=layers, max_len=layers)
        biases = v.sequence(state["biases"], "state.biases", min_len=layers, max_len=layers)
        read = {"weights": [v.array(w, f"state.weights[{i}]", (widths[i], widths[i + 1])) for i, w in enumerate(weights)],
                "biases": [v.array(b, f"state.biases[{i}]", (widths[i + 1],)) for i, b in enumerate(biases)]}
    read["mean"] = v.array(state["mean"], "state.mean", (k,))
    read["scale"] = v.array(state["scale"], "state.scale", (k,))
    if not (read["scale"] > 0).all():
        v.fail("state.scale", "must hold positive numbers")
    return read


@functools.cache
def _timed_learners():
    """scikit-learn's boosting and MLP regressors, checking the time limit once per iteration
    (:func:`nfarm.infra.limits.check_time`) and otherwise unchanged."""
    from sklearn.ensemble import HistGradientBoostingRegressor
    from sklearn.neural_network import MLPRegressor

    class _TimedLoss:
        """The boosting fit's loss, checking the time before each iteration's gradients."""

        def __init__(self, loss):
            self.loss = loss

        def __getattr__(self, name):
            if name == "loss":              # not yet set (a copy being built)
                raise AttributeError(name)
            return getattr(self.loss, name)

        def gradient(self, *args, **kwargs):
            check_time("boosting: an iteration")
            return self.loss.gradient(*args, **kwargs)

        def gradient_hessian(self, *args, **kwargs):
            check_time("boosting: an iteration")
            return self.loss.gradient_hessian(*args, **kwargs)

    class TimedHistGradientBoostingRegressor(HistGradientBoostingRegressor):
        def _get_loss(self, sample_weight):
            return _TimedLoss(super()._get_loss(sample_weight))

    class TimedMLPRegressor(MLPRegressor):
        def _update_no_improvement_count(self, *args, **kwargs):
            check_time("mlp: an epoch")
            return super()._update_no_improvement_count(*args, **kwargs)

    return TimedHistGradientBoostingRegressor, TimedMLPRegressor


class _StackedLeastSquares:
    """``y ≈ X θ`` with one ``θ`` for every joint's rows (``X (N, n, k)``, ``y (N, n)``): the
    least squares of the rows stacked, columns scaled to unit norm, minimum-norm solution."""

    def fit(self, X, y):
        A = X.reshape(-1, X.shape[-1])
        norms = np.linalg.norm(A, axis=0)
        norms = np.where(norms > 0, norms, 1.0)
        self.coef_ = np.linalg.lstsq(A / norms, y.reshape(-1), rcond=None)[0] / norms
        return self

    def predict(self, X):
        return X @ self.coef_


class _PerJointLeastSquares:
    """``y_j ≈ X_j θ_j`` per joint by least squares (``X (N, n, k)``, ``y (N, n)``)."""

    def fit(self, X, y):
        self.coef_ = np.stack([np.linalg.lstsq(X[:, j], y[:, j], rcond=None)[0] for j in range(y.shape[1])])
        return self

    def predict(self, X):
        return np.einsum("njk,jk->nj", X, self.coef_)
