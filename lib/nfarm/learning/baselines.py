"""Model-free baselines for learned inverse dynamics, from scikit-learn (chapters 06 and 07).

What an engineer would try before a fuzzy system, each fed states ``q, q̇, q̈`` and nothing of
the arm's masses or lengths (:data:`LEARNERS`):

* ``"linear"`` — ordinary least squares on ``[q, q̇, q̈]``: the floor any learner must beat;
* ``"ridge"`` — ridge regression on a feature basis of :mod:`nfarm.learning.bases` (``basis``:
  ``"generic"``, 1 386 features for five joints; ``"chain"``, with the sums of parallel joints,
  3 213) — torque affine in ``q̈``, quadratic in ``q̇``, trigonometric in ``q``;
* ``"kernel"`` — kernel ridge regression with a Gaussian kernel, approximated by Nyström's
  method (``n_components`` landmarks, ``gamma``) on standardised ``sin q, cos q, q̇, q̈``;
* ``"boosting"`` — gradient-boosted trees per joint (``HistGradientBoostingRegressor``:
  ``max_iter``, ``learning_rate``, ``max_leaf_nodes``) on the same inputs;
* ``"mlp"`` — a multilayer perceptron (``hidden`` layer widths, ``alpha``, at most ``max_iter``
  epochs of Adam) on the same inputs; given validation states, it keeps the epoch of least
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

Fitted baselines are not saved: they are comparison rows, refitted from their options and seed
wherever a chapter needs them (the sweeps cache their metrics), and a scikit-learn model could
only be stored as a pickle, which this project never hands to a user.

**Time limits.** A sweep cell runs in a worker's thread, where nothing can stop a fit from
outside; the iterative learners check the caller's deadline (:func:`nfarm.infra.limits.time_limit`)
once per iteration — boosting before each boosting iteration, the MLP after each epoch —
through two hooks of scikit-learn's loops that change no arithmetic (the fits are bit-identical
to the plain estimators', ``tests/test_baselines.py``). The one-step learners (least squares,
ridge, kernel ridge) are bounded by their sizes instead: the options' upper limits below.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..infra.limits import check_time
from ..model.dynamics import rnea
from ..model.robot import Robot
from .bases import BASES, basis
from .estimator import Estimator
from .learned_id import id_states

__all__ = ["LEARNERS", "BaselineID", "DEFAULTS", "OPTION_NAMES", "label"]

#: Each learner's options and their defaults.
DEFAULTS: dict[str, dict[str, Any]] = {
    "linear": {},
    "ridge": {"basis": "generic", "alpha": 1e-6},
    "kernel": {"n_components": 1000, "gamma": 0.1, "alpha": 1e-6},
    "boosting": {"max_iter": 300, "learning_rate": 0.1, "max_leaf_nodes": 31},
    "mlp": {"hidden": [128, 128], "alpha": 1e-4, "max_iter": 200, "patience": 10},
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


def label(params: Mapping) -> str:
    """``"ridge (basis=chain, alpha=1e-06)"``: a learner and the options ``params`` gives it
    (a sweep cell's flat parameters; ``None`` and other keys are left out)."""
    given = {k: params[k] for k in OPTION_NAMES if params.get(k) is not None}
    return params["learner"] + (" (" + ", ".join(f"{k}={v}" for k, v in given.items()) + ")" if given else "")


def _smooth_inputs(q, qd, qdd) -> np.ndarray:
    return np.concatenate([np.sin(q), np.cos(q), qd, qdd], axis=1)


class BaselineID(Estimator):
    """One scikit-learn learner of the torques of every joint (scikit-learn conventions).

    Args:
        learner: one of :data:`LEARNERS`.
        options: the learner's options (:data:`DEFAULTS` for the rest).
        residual: learn ``τ − rnea(q, q̇, q̈)`` instead of ``τ``.
        random_state: seed of every random draw.

    Learned attributes: ``model_``, ``robot_``, ``y_mean_``, ``y_scale_``, ``fit_seconds_``,
    ``n_features_`` (inputs the learner sees), ``epochs_`` and ``best_epoch_`` (the MLP stopped
    early on validation states; ``None`` otherwise).
    """

    _fitted = "model_"

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
            from ..model.dynamics import regressor
            n = q.shape[1]
            drives = np.zeros((len(q), n, 3 * n))
            for j in range(n):
                drives[:, j, 3 * j:3 * j + 3] = np.stack([qdd[:, j], qd[:, j], np.sign(qd[:, j])], axis=-1)
            return np.concatenate([regressor(self.robot_, q, qd, qdd), drives], axis=-1)
        if self.learner == "ridge":
            return basis(self.robot_, q, qd, qdd, self.options_["basis"])[:, 1:]
        return _smooth_inputs(q, qd, qdd)

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
        y = self.model_.predict(self._features(q, qd, qdd)).reshape(len(q), -1)
        tau = y * self.y_scale_ + self.y_mean_
        if self.residual:
            tau = tau + rnea(self.robot_, q, qd, qdd)
        return tau


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
