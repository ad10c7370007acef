"""What the model-free baselines of learned inverse dynamics share (chapters 06 and 07), written
once: the states ``q, q̇, q̈`` in, the torques ``τ`` out, optionally as a residual of Newton–Euler,
the targets' standardisation, the checks of every option, and saving and loading as JSON (no
pickle). Each baseline is one subclass of :class:`BaselineID` in :mod:`nfarm.learning.baselines`,
registered in :data:`BASELINES` under the name sweep files give it (``learner: ridge``); import
the baselines from there.

Targets are standardised per joint (each joint's error then counts alike, as in the NRMSE the
chapters report), unless the learner is a physical law (``scaled_targets = False``). Every random
draw comes from ``random_state``; a fit is a function of its options, data (and the MLP's validation
states) and seed. With ``residual=True`` a baseline learns ``τ − rnea`` and predicts ``rnea + learned``; with
``residual="identification"`` it learns what the identification of the arm as built, fitted first on the same
training states, misses (:mod:`nfarm.learning.priors`).

**A baseline's part** (the hooks a subclass writes): ``learner`` and ``label`` (class attributes:
the registry's name, the words of tables and figures), ``__init__`` with its options (then
``residual`` and ``random_state``, keyword-only, passed on to :meth:`BaselineID.__init__`),
``_features`` (the inputs it sees), ``_estimator`` (the scikit-learn estimator, or ``_train`` for a
fit of its own), ``_state_of`` (the fitted arithmetic as arrays), ``_predict_state`` (the scaled
targets from those arrays, as scikit-learn's ``predict`` computes them) and ``_read_state`` (those
arrays read back from a file, checked). Options are checked by name (:meth:`BaselineID._options`):
a new option name brings its own check.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from .. import __version__
from ..infra.arguments import is_integer, is_number
from ..infra.reading import Validator, json_ready, show
from ..model.robot import Robot, robot_hash
from .bases import BASES
from .estimator import Registry, SavedModel, check_robot
from .learned_id import id_states
from .priors import DRIVE_LAW, FITTED_LAW, check_residual, drive_law_field, fit_prior, prior_of, prior_torques, read_drive_law, read_prior

__all__ = ["BaselineID", "Standardised", "BASELINES", "ANGLES", "MAXIMA", "FILE_NAME", "FORMAT", "baseline_id", "smooth_inputs"]

FILE_NAME = "baseline_id.json"
FORMAT = "nfarm-baseline-id-1"

#: The baselines by the name sweep files and saved models give them (``learner``): ``linear``, ``ridge``, …
BASELINES = Registry("ID baseline", "learner")
#: The largest value of each integer option: a Nyström kernel of ``n_components`` landmarks
#: holds an ``(N, n_components)`` matrix and cannot be stopped once started; boosting's trees
#: and the MLP's widths bound the work of one iteration, which the time limit cannot split.
MAXIMA = {"n_components": 10_000, "max_iter": 100_000, "max_leaf_nodes": 4_096, "hidden": 4_096, "patience": 100_000}
#: The angles whose ``sin, cos`` the kernel, boosting and the MLP see (:mod:`nfarm.learning.baselines`), or
#: ``"regressor"``: the rigid-body regressor's columns and the drive terms instead (the identification tier's inputs),
#: or ``"own"``: one model a joint, each on its own ``q_j, q̇_j, q̈_j`` alone (the residual ANFIS's ``own`` inputs).
ANGLES = ("joints", "chain", "regressor", "own")


def smooth_inputs(angles, qd, qdd) -> np.ndarray:
    """``(N, 2K + 2n)``: ``sin, cos`` of ``angles (N, K)``, then ``q̇, q̈ (N, n)``."""
    return np.concatenate([np.sin(angles), np.cos(angles), qd, qdd], axis=1)


def baseline_id(learner: str = "ridge", options: Mapping | None = None, residual: bool | str = False,
                random_state: int = 0) -> "BaselineID":
    """The baseline registered as ``learner`` (:data:`BASELINES`) with its ``options`` (a sweep
    file's) and the common ``residual`` (:data:`nfarm.learning.priors.RESIDUALS`) and ``random_state``.

    Raises:
        ValueError: an unknown learner or option, in one line naming the valid ones.
    """
    cls = BASELINES.of(learner)
    given = dict(options or {})
    unknown = sorted(set(given) - set(cls.hyper_params()))
    if unknown:
        raise ValueError(f"unknown option {unknown[0]!r} for learner {learner!r}; "
                         f"valid: {', '.join(cls.hyper_params()) or 'none'}")
    return cls(**given, residual=residual, random_state=random_state)


#: States a :meth:`BaselineID.predict` computes at a time (its ``rows``).
PREDICT_ROWS = 4096


class BaselineID(SavedModel):
    """The base of the ID baselines: one scikit-learn learner of the torques of every joint
    (module docstring; scikit-learn conventions: ``__init__`` stores its arguments unchanged,
    ``fit`` checks them and returns the baseline).

    Args (common to every baseline, keyword-only in the subclasses):
        residual: learn ``τ − rnea(q, q̇, q̈)`` instead of ``τ`` (``True`` or ``"nominal"``), or
            ``τ`` minus the identification of the arm as built, fitted first on the same training
            states (``"identification"``; :mod:`nfarm.learning.priors`).
        random_state: seed of every random draw.

    Learned attributes: ``state_`` (the fitted arithmetic as arrays, what :meth:`predict` uses
    and :meth:`save` writes), ``prior_`` (the identification's ``θ (14 n,)`` under
    ``residual="identification"``, else ``None``), ``model_`` (the scikit-learn estimator, after :meth:`fit` only),
    ``options_`` (the options checked, as saved), ``robot_``, ``y_mean_``, ``y_scale_``,
    ``fit_seconds_``, ``n_features_`` (inputs the learner sees), ``epochs_`` and ``best_epoch_``
    (the MLP stopped early on validation states, one number for its model or, with ``angles="own"``, a
    list of one a joint; ``None`` otherwise). With ``angles="own"`` ``model_`` is a list of one estimator
    a joint and ``state_`` holds theirs as ``per_joint``.
    """

    _fitted = "state_"
    file_name, file_format, what = FILE_NAME, FORMAT, "baseline ID"

    #: The baseline's name in :data:`BASELINES` (a sweep file's ``learner``) and in words.
    learner: ClassVar[str]
    label: ClassVar[str]
    #: ``False``: a physical law, fitted to the targets as they are (no mean removed, no scaling: its own columns hold any
    #: constant, the reading's zero offset among them).
    scaled_targets: ClassVar[bool] = True
    #: ``True``: a residual of Newton–Euler's nominal model only; ``False``: never a residual;
    #: ``None``: any :data:`~nfarm.learning.priors.RESIDUALS`. The reason, in words, follows the
    #: learner's name in the error.
    residual_only: ClassVar[bool | None] = None
    residual_reason: ClassVar[str] = ""

    def __init__(self, *, residual: bool | str = False, random_state: int = 0):
        self.residual = residual
        self.random_state = random_state

    def _check_prior(self) -> None:
        """Refuse a ``residual`` this learner cannot have, in one line."""
        check_residual(self.residual)
        wanted = {True: "nominal", False: None}.get(self.residual_only)
        if self.residual_only is not None and prior_of(self.residual) != wanted:
            raise ValueError(f"learner {self.learner!r} {self.residual_reason}: give residual={self.residual_only}")

    @classmethod
    def hyper_params(cls) -> list[str]:
        """The baseline's own options (saved as ``options``), in its ``__init__``'s order."""
        common = BaselineID._signature()[0]
        return [name for name in cls._signature()[0] if name not in common]

    def _options(self) -> dict:
        """The options as saved, each checked by its name; one-line ``ValueError`` otherwise."""
        options = {name: getattr(self, name) for name in self.hyper_params()}
        for key in ("alpha", "gamma", "learning_rate"):
            if key in options and not (is_number(options[key], numpy=False) and options[key] > 0
                                       and np.isfinite(options[key])):
                raise ValueError(f"{self.learner}: {key} must be a positive number, got {options[key]!r}")
        for key in ("n_components", "max_iter", "max_leaf_nodes", "patience"):
            if key in options and not (is_integer(options[key]) and 2 <= options[key] <= MAXIMA[key]):
                raise ValueError(f"{self.learner}: {key} must be an integer from 2 to {MAXIMA[key]:,}, "
                                 f"got {options[key]!r}")
        if "angles" in options and options["angles"] not in ANGLES:
            raise ValueError(f"{self.learner}: angles must be one of {', '.join(ANGLES)}, got {options['angles']!r}")
        if "basis" in options and options["basis"] not in BASES:
            raise ValueError(f"{self.learner}: basis must be one of {', '.join(BASES)}, got {options['basis']!r}")
        if "hidden" in options:
            hidden = options["hidden"]
            if isinstance(hidden, (int, str)) or not all(is_integer(h) and 1 <= h <= MAXIMA["hidden"] for h in hidden) \
                    or not hidden or len(hidden) > 16:
                raise ValueError(f"{self.learner}: hidden must be a list of 1 to 16 layer widths from 1 to "
                                 f"{MAXIMA['hidden']:,}, got {hidden!r}")
        return options

    # -- a baseline's part (module docstring) -------------------------------------------------

    def _features(self, q, qd, qdd) -> np.ndarray:
        raise NotImplementedError

    def _estimator(self, options: dict):
        raise NotImplementedError

    def _train(self, options: dict, X, Z, robot: Robot, val: Mapping | None, joint: int | None = None):
        """The fitted estimator of features ``X`` and scaled targets ``Z`` (``val``: the
        validation states, for a learner that stops early on them; ``joint``: the joint whose
        model this is, for a model a joint, :meth:`_per_joint`)."""
        return self._estimator(options).fit(X, Z)

    def _per_joint(self) -> bool:
        """One model a joint, each on its own state (``angles="own"``: features ``(N, n, 3)``)."""
        return self.options_.get("angles") == "own"

    def _state_of(self, model) -> dict:
        raise NotImplementedError

    def _predict_state(self, state: dict, X: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _read_state(self, v: Validator, state: Any, k: int, n: int, options: dict) -> dict:
        raise NotImplementedError

    # -- fitting and prediction ---------------------------------------------------------------

    def fit(self, robot: Robot, train: Mapping, val: Mapping | None = None) -> "BaselineID":
        """Fit on ``train`` (arrays ``q, qd, qdd, tau (N, n)``); the MLP stops early on ``val``
        (the same arrays) when it is given, and trains ``max_iter`` epochs when not.

        Raises:
            ValueError: an unknown learner or option, or bad data, before any work.
        """
        import warnings

        from sklearn.exceptions import ConvergenceWarning

        if not hasattr(type(self), "learner"):
            raise TypeError(f"{type(self).__name__} is not a baseline of its own: fit one of {', '.join(BASELINES)} "
                            f"(nfarm.learning.baselines.BASELINES)")
        options = self._options()
        self._check_prior()
        q, qd, qdd, tau = id_states(train, robot, "train")
        for name in ("state_", "model_"):     # a failed refit leaves no model beside the new prior
            self.__dict__.pop(name, None)
        self.robot_, self.options_ = robot, options
        self.prior_, prior, prior_seconds = fit_prior(robot, self.residual, q, qd, qdd, tau)
        target = tau - prior
        if not self.scaled_targets:      # a physical law: the targets as they are
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
            if self._per_joint():       # joint j's model on its own state and torque alone
                fits, epochs, best = [], [], []
                for j in range(robot.n):
                    self.epochs_ = self.best_epoch_ = None
                    fits.append(self._train(options, X[:, j], Z[:, j:j + 1], robot, val, joint=j))
                    epochs.append(self.epochs_)
                    best.append(self.best_epoch_)
                self.model_ = fits
                self.epochs_, self.best_epoch_ = (None, None) if epochs[0] is None else (epochs, best)
            else:
                self.model_ = self._train(options, X, Z, robot, val)
        self.fit_seconds_ = time.perf_counter() - start + prior_seconds
        self.state_ = ({"per_joint": [self._state_of(m) for m in self.model_]} if self._per_joint()
                       else self._state_of(self.model_))
        return self

    def _drive_law(self) -> str | None:
        """The drive law the predictions use (the saved ``drive_law``): :data:`~nfarm.learning.priors.FITTED_LAW`
        for a least-squares law (the friction identification, the identification) or a learner on the
        identification's residual; :data:`~nfarm.learning.priors.DRIVE_LAW` for a learner on the regressor's
        columns (``angles="regressor"``: the drive terms among its inputs); ``None`` for any other."""
        if type(self).learner in ("friction", "identification") or prior_of(self.residual) == "identification":
            return FITTED_LAW
        return DRIVE_LAW if self.options_.get("angles") == "regressor" else None

    def _validation(self, robot: Robot, val: Mapping) -> tuple[np.ndarray, np.ndarray]:
        """The validation states' features and scaled targets, as the training states'."""
        vq, vqd, vqdd, vtau = id_states(val, robot, "val")
        v_target = vtau - prior_torques(robot, self.residual, vq, vqd, vqdd, self.prior_)
        return self._features(vq, vqd, vqdd), (v_target - self.y_mean_) / self.y_scale_

    def predict(self, q, qd, qdd, *, rows: int = PREDICT_ROWS) -> np.ndarray:
        """Torques ``(N, n)`` [N·m] for states ``(N, n)``, computed ``rows`` states at a time: a
        learner's features (3 213 columns for the rigid-body span's basis) are built for a block of
        states, not for all ``N`` at once, so memory stays bounded whatever ``N`` (issue 63: a
        rigid-body span model predicting the 40 test trajectories, 33 000-40 000 states, at once took
        2.6 CPU-s, most of them page faults, and 0.4 in blocks of 4 096; boosted trees on the regressor's
        147 columns 5.2 and 1.6). The torques are those of one pass up to their last bits (BLAS may sum a
        matrix product's terms in another order for another number of rows: 5.6e-16 N·m at most, measured)."""
        self._check_fitted()
        if not is_integer(rows) or rows < 1:
            raise ValueError(f"rows must be a whole number >= 1, got {rows!r}")
        q, qd, qdd = id_states({"q": q, "qd": qd, "qdd": qdd}, self.robot_, "states", tau=False)
        y = np.empty((len(q), self.robot_.n))
        for start in range(0, len(q), rows):
            block = slice(start, start + rows)
            X = self._features(q[block], qd[block], qdd[block])
            if self._per_joint():
                y[block] = np.column_stack([self._predict_state(state, X[:, j]).reshape(len(X))
                                            for j, state in enumerate(self.state_["per_joint"])])
            else:
                y[block] = self._predict_state(self.state_, X).reshape(len(X), -1)
        return y * self.y_scale_ + self.y_mean_ + prior_torques(self.robot_, self.residual, q, qd, qdd, self.prior_)

    # -- persistence --------------------------------------------------------------------------

    def to_dict(self) -> dict:
        """The model as JSON-ready fields: its learner and options, the robot's name and hash,
        the targets' scaling, the learner's arrays (``state``) and, for ``residual="identification"``,
        the identification it adds to (``prior``: ``θ``; a file of another residual has no such field)."""
        self._check_fitted()
        return {"format": FORMAT, "nfarm_version": __version__, "learner": self.learner,
                "options": json_ready(self.options_), "residual": self.residual, "random_state": self.random_state,
                "robot": self.robot_.name, "robot_params_sha256": robot_hash(self.robot_), "n_joints": self.robot_.n,
                "n_features": int(self.n_features_), "y_mean": json_ready(self.y_mean_),
                "y_scale": json_ready(self.y_scale_), "fit_seconds": float(self.fit_seconds_),
                "epochs": self.epochs_, "best_epoch": self.best_epoch_, "state": json_ready(self.state_),
                **({} if self.prior_ is None else {"prior": json_ready(self.prior_)}),
                **drive_law_field(self._drive_law())}

    @classmethod
    def from_dict(cls, data: Any, robot: Robot, source: str = "<dict>") -> "BaselineID":
        """The baseline saved as ``data`` (:meth:`to_dict`), of the class its ``learner`` names
        in :data:`BASELINES` whatever class this is called on.

        Raises:
            ParamsError: a field missing, unknown or out of its range (named, with ``source``), a
                learner no class is registered as, or a model trained for another robot.
        """
        v = Validator(source)
        keys = ("format", "nfarm_version", "learner", "options", "residual", "random_state", "robot",
                "robot_params_sha256", "n_joints", "n_features", "y_mean", "y_scale", "fit_seconds", "epochs",
                "best_epoch", "state")
        v.mapping(data, "", {**dict.fromkeys(keys, True), "prior": False, "drive_law": False})
        learner = BASELINES[v.choice(data["learner"], "learner", tuple(BASELINES))]
        if not issubclass(learner, cls):
            v.fail("learner", f"must be {cls.learner!r} (a {cls.__name__}), got {show(data['learner'])}")
        check_robot(v, data, robot)
        n = v.integer(data["n_joints"], "n_joints", lo=robot.n, hi=robot.n)
        options = v.mapping(data["options"], "options", dict.fromkeys(learner.hyper_params(), True))
        residual = data["residual"]
        try:
            check_residual(residual)
        except ValueError as exc:
            v.fail("residual", str(exc).removeprefix("residual "))
        model = learner(**options, residual=residual, random_state=v.integer(data["random_state"], "random_state", lo=0))
        try:
            options = model._options()
        except ValueError as exc:
            v.fail("options", str(exc))
        try:
            model._check_prior()
        except ValueError as exc:
            v.fail("residual", str(exc))
        model.robot_, model.options_ = robot, options
        read_drive_law(v, data, model._drive_law())               # before the prior: an older law's has other columns
        model.prior_ = read_prior(v, data, residual, robot)
        model.n_features_ = v.integer(data["n_features"], "n_features", lo=1, hi=10_000_000)
        model.y_mean_ = v.array(data["y_mean"], "y_mean", (n,))
        model.y_scale_ = v.array(data["y_scale"], "y_scale", (n,))
        if not (model.y_scale_ > 0).all():
            v.fail("y_scale", "must hold positive numbers")
        model.fit_seconds_ = v.number(data["fit_seconds"], "fit_seconds", lo=0)
        model.epochs_ = _counts(v, data["epochs"], "epochs", 1, n, model._per_joint())
        model.best_epoch_ = _counts(v, data["best_epoch"], "best_epoch", 0, n, model._per_joint())
        q = np.zeros((1, n))
        expected = model._features(q, q, q).shape[-1]      # the features this learner computes for the robot
        if model.n_features_ != expected:
            v.fail("n_features", f"must be {expected} for learner {model.learner!r} on {robot.name}, "
                                 f"got {model.n_features_}")
        if model._per_joint():
            v.mapping(data["state"], "state", {"per_joint": True})
            joints = v.sequence(data["state"]["per_joint"], "state.per_joint", min_len=n, max_len=n)
            model.state_ = {"per_joint": [model._read_state(v, state, expected, 1, options) for state in joints]}
        else:
            model.state_ = model._read_state(v, data["state"], expected, n, options)
        return model


def _counts(v: Validator, value: Any, name: str, lo: int, n: int, per_joint: bool) -> int | list[int] | None:
    """A saved ``epochs`` or ``best_epoch``: ``None`` (no epochs), a count, or with a model a joint one count a joint."""
    if value is None:
        return None
    if per_joint:
        return [v.integer(x, f"{name}[{j}]", lo=lo) for j, x in enumerate(v.sequence(value, name, min_len=n, max_len=n))]
    return v.integer(value, name, lo=lo)


class Standardised(BaselineID):
    """A baseline on standardised features: its estimator a pipeline whose first step is a
    ``StandardScaler`` (the ridge, the kernel, the MLP). A subclass supplies ``_scaled_state``
    (the arrays of the pipeline's later steps), ``_predict_scaled`` (of standardised ``Xs``) and
    ``_read_scaled`` (the same arrays read back), and names them in ``_state_keys``."""

    _state_keys: ClassVar[tuple[str, ...]] = ()

    def _state_of(self, model) -> dict:
        scaler, *rest, last = list(model.named_steps.values())
        return {"mean": scaler.mean_, "scale": scaler.scale_, **self._scaled_state(rest, last)}

    def _predict_state(self, state: dict, X: np.ndarray) -> np.ndarray:
        return self._predict_scaled(state, (X - state["mean"]) / state["scale"])

    def _read_state(self, v: Validator, state: Any, k: int, n: int, options: dict) -> dict:
        v.mapping(state, "state", {"mean": True, "scale": True, **dict.fromkeys(self._state_keys, True)})
        read = self._read_scaled(v, state, k, n, options)
        read["mean"] = v.array(state["mean"], "state.mean", (k,))
        read["scale"] = v.array(state["scale"], "state.scale", (k,))
        if not (read["scale"] > 0).all():
            v.fail("state.scale", "must hold positive numbers")
        return read

    def _scaled_state(self, rest: list, last) -> dict:
        raise NotImplementedError

    def _predict_scaled(self, state: dict, Xs: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _read_scaled(self, v: Validator, state: Any, k: int, n: int, options: dict) -> dict:
        raise NotImplementedError
