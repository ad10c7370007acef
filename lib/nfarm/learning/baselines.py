"""Model-free baselines for learned inverse dynamics, from scikit-learn (chapters 06 and 07).

What an engineer would try before a fuzzy system, each fed states ``q, q̇, q̈`` and what its tier
knows — nothing of the arm, which of its axes are parallel, or (``angles="regressor"``) its geometry
through the rigid-body regressor, never its masses; one class per learner, registered in :data:`BASELINES` under the
name sweep files give it (what they share is :class:`~nfarm.learning.id_baseline_base.BaselineID`'s,
:mod:`nfarm.learning.id_baseline_base`):

* ``"linear"`` (:class:`LinearID`) — ordinary least squares on ``[q, q̇, q̈]``: the floor any
  learner must beat;
* ``"ridge"`` (:class:`RidgeID`) — ridge regression on a feature basis of :mod:`nfarm.learning.bases`
  (``basis``: ``"generic"``, 1 386 features for five joints; ``"chain"``, with the sums of parallel
  joints, 3 213) — torque affine in ``q̈``, quadratic in ``q̇``, trigonometric in ``q``;
* ``"kernel"`` (:class:`KernelID`) — kernel ridge regression with a Gaussian kernel, approximated
  by Nyström's method (``n_components`` landmarks, ``gamma``) on standardised ``sin, cos`` of the
  angles, ``q̇, q̈``: with ``angles="joints"`` the joint angles (what every arm has: the *generic*
  tier), with ``angles="chain"`` the joint angles and the sums of every stretch of parallel joints
  (:func:`nfarm.learning.bases.angle_sums`: which axes are parallel, the *structure-informed*
  tier's knowledge, the inputs its ANFIS and its ridge on the ANFIS's columns, ``chain_linear``, get), with
  ``angles="regressor"`` every joint's row of the rigid-body regressor and its drive terms
  (:func:`regressor_inputs`: the geometry known, the *identification* tier's knowledge), with
  ``angles="own"`` each joint's own ``q_j, q̇_j, q̈_j`` alone, one model a joint (the
  structure of the residual ANFIS's ``inputs="own"``; the residual tiers);
* ``"boosting"`` (:class:`BoostingID`) — gradient-boosted trees per joint
  (``HistGradientBoostingRegressor``: ``max_iter``, ``learning_rate``, ``max_leaf_nodes``) on the
  same inputs (``angles`` too);
* ``"mlp"`` (:class:`MLPID`) — a multilayer perceptron (``hidden`` layer widths, ``alpha``, at most
  ``max_iter`` epochs of Adam) on the same inputs (``angles`` too); given validation states, it keeps
  the epoch of least validation error and stops ``patience`` epochs after it — the early stopping
  the ANFIS gets, on the same validation trajectories;
* ``"friction"`` (:class:`FrictionID`) — not a learner but the identification any engineer tries
  first on a real arm: a residual only, per joint, least squares of ``τ − rnea`` on that joint's
  ``[q̈_j, q̇_j, tanh(q̇_j / ε_j), 1]`` — armature, viscous and Coulomb friction, the robot file's drive
  law, and the torque reading's zero offset (:func:`nfarm.learning.priors.law_terms`; chapter 06.8);
* ``"identification"`` (:class:`IdentificationID`) — the full identification of a built arm whose
  geometry is known (Atkeson, An & Hollerbach 1986; the *identification* tier): one least squares of
  ``τ`` over every joint on the rigid-body regressor ``Y(q, q̇, q̈)`` (:func:`nfarm.model.dynamics.regressor`,
  the inertial parameters shared by all joints' rows) and each joint's ``[q̈_j, q̇_j, tanh(q̇_j / ε_j), 1]``
  (armature, viscous and Coulomb friction, the robot file's drive law, and the reading's zero offset) — it refits the
  masses, centres of mass and inertias where the built arm differs from the model. Columns are scaled to unit norm and
  the minimum-norm solution is kept (the regressor's columns are not all identifiable).

**Saving.** A fitted baseline is saved as JSON (:meth:`BaselineID.save`, no pickle): once fitted,
each learner's arithmetic is read out of the scikit-learn estimator into arrays — the scaler's
means and scales, the linear and ridge weights, the Nyström landmarks and normalisation, every
boosted tree's splits and leaf values, the perceptron's layers — and :meth:`BaselineID.predict`
computes from those arrays with the operations scikit-learn's ``predict`` performs, in its order,
so a fitted and a loaded model predict the same bits (``tests/test_baselines.py`` checks both
against scikit-learn's own ``predict``). :func:`load_id_model` reads any saved learned-ID model of
this package (a :class:`BaselineID` or a :class:`~nfarm.learning.learned_id.LearnedID`).

**Time limits.** Boosting and the MLP check a sweep cell's deadline once per iteration
(:mod:`nfarm.learning.baseline_parts`); the one-step learners (least squares, ridge, kernel ridge)
are bounded by their sizes instead (:data:`~nfarm.learning.id_baseline_base.MAXIMA`).

A new baseline is one class here (its options, ``learner``, ``label`` and the hooks the base
module's docstring lists, under ``@BASELINES.register``) and its cells in a sweep file.

Example:
    >>> from nfarm.model.robot import load_robot
    >>> from nfarm.infra.paths import PARAMS
    >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
    >>> rng = np.random.default_rng(0)
    >>> q, qd, qdd = (rng.uniform(-1, 1, (400, robot.n)) for _ in range(3))
    >>> train = {"q": q, "qd": qd, "qdd": qdd, "tau": rnea(robot, q, qd, qdd)}
    >>> model = RidgeID(basis="chain").fit(robot, train)
    >>> float(np.abs(model.predict(q, qd, qdd) - train["tau"]).max()) < 1e-6
    True
    >>> baseline_id("ridge", {"basis": "chain"}), BASELINES["ridge"] is RidgeID, label({"learner": "ridge", "alpha": 0.01})
    (RidgeID(basis='chain'), True, 'ridge (alpha=0.01)')
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from ..infra.reading import ParamsError, Validator
from ..model.dynamics import rnea
from ..model.robot import Robot
from .baseline_parts import (PerJointLeastSquares, StackedLeastSquares, forest_values, read_trees, timed_learners,
                             trees_state)
from .bases import angle_sums, basis
from .id_baseline_base import (ANGLES, BASELINES, FILE_NAME, FORMAT, MAXIMA, BaselineID, Standardised, baseline_id,
                               smooth_inputs)
from .learned_id import ID_FILE_NAME, LearnedID, id_features
from .priors import identification_columns, law_terms

__all__ = ["BaselineID", "BASELINES", "ANGLES", "MAXIMA", "FILE_NAME", "FORMAT", "baseline_id", "option_names", "label",
           "load_id_model", "regressor_inputs", "LinearID", "RidgeID", "KernelID", "BoostingID", "MLPID", "FrictionID",
           "IdentificationID"]

_timed_learners = timed_learners        # looked up here at each fit (a test swaps it for the plain estimators)


def option_names() -> tuple[str, ...]:
    """Every registered baseline's option names, in the order of :data:`BASELINES`."""
    return tuple(dict.fromkeys(k for cls in BASELINES.values() for k in cls.hyper_params()))


def label(params: Mapping) -> str:
    """``"ridge (basis=chain, alpha=1e-06)"``: a learner and the options ``params`` gives it
    (a sweep cell's flat parameters; ``None`` and other keys are left out)."""
    given = {k: params[k] for k in option_names() if params.get(k) is not None}
    return params["learner"] + (" (" + ", ".join(f"{k}={v}" for k, v in given.items()) + ")" if given else "")


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


@BASELINES.register
class LinearID(BaselineID):
    """Least squares on ``[q, q̇, q̈]`` (module docstring)."""

    learner, label = "linear", "least squares on the states"

    def __init__(self, *, residual: bool | str = False, random_state: int = 0):
        super().__init__(residual=residual, random_state=random_state)

    def _features(self, q, qd, qdd):
        return np.concatenate([q, qd, qdd], axis=1)

    def _estimator(self, options):
        from sklearn.linear_model import LinearRegression
        return LinearRegression()

    def _state_of(self, model):
        return {"coef": model.coef_, "intercept": np.atleast_1d(model.intercept_)}

    def _predict_state(self, state, X):
        return X @ state["coef"].T + state["intercept"]

    def _read_state(self, v: Validator, state, k, n, options):
        v.mapping(state, "state", {"coef": True, "intercept": True})
        return {"coef": v.array(state["coef"], "state.coef", (n, k)),
                "intercept": v.array(state["intercept"], "state.intercept", (n,))}


@BASELINES.register
class RidgeID(Standardised):
    """Ridge regression on a feature basis (module docstring)."""

    learner, label = "ridge", "ridge regression"
    _state_keys = ("coef", "intercept")

    def __init__(self, basis: str = "generic", alpha: float = 1e-6, *, residual: bool | str = False, random_state: int = 0):
        self.basis = basis
        self.alpha = alpha
        super().__init__(residual=residual, random_state=random_state)

    def _features(self, q, qd, qdd):
        return basis(self.robot_, q, qd, qdd, self.options_["basis"])[:, 1:]

    def _estimator(self, options):
        from sklearn.linear_model import Ridge
        from sklearn.pipeline import make_pipeline
        from sklearn.preprocessing import StandardScaler
        return make_pipeline(StandardScaler(), Ridge(alpha=options["alpha"], solver="cholesky"))

    def _scaled_state(self, rest, last):
        return {"coef": last.coef_, "intercept": np.atleast_1d(last.intercept_)}

    def _predict_scaled(self, state, Xs):
        return Xs @ state["coef"].T + state["intercept"]

    def _read_scaled(self, v: Validator, state, k, n, options):
        return {"coef": v.array(state["coef"], "state.coef", (n, k)),
                "intercept": v.array(state["intercept"], "state.intercept", (n,))}


class _SmoothInputs:
    """The ``sin, cos`` of the joint angles (``angles="joints"``) or of them and their sums over
    parallel joints (``"chain"``), then ``q̇, q̈`` (:func:`~nfarm.learning.id_baseline_base.smooth_inputs`);
    or (``"regressor"``, the identification tier's knowledge) every joint's row of the rigid-body
    regressor and its drive terms, side by side (:func:`regressor_inputs`); or (``"own"``) each
    joint's own ``q_j, q̇_j, q̈_j``, ``(N, n, 3)``, one model a joint — the inputs of the residual
    ANFIS's ``own`` set, so that a rival gets the ANFIS's structure too."""

    def _features(self, q, qd, qdd):
        if self.options_["angles"] == "regressor":
            return regressor_inputs(self.robot_, q, qd, qdd)
        if self.options_["angles"] == "own":
            return np.stack([q, qd, qdd], axis=-1)
        return smooth_inputs(q if self.options_["angles"] == "joints" else angle_sums(self.robot_, q), qd, qdd)


def regressor_inputs(robot: Robot, q, qd, qdd) -> np.ndarray:
    """``(N, F)``: what the identification of a built arm sees, as one learner's inputs — every joint
    j's row of the rigid-body regressor ``Y(q, q̇, q̈)`` on the columns its torque depends on and its
    drive terms ``q̈_j, q̇_j, tanh(q̇_j / ε_j)`` (:func:`nfarm.learning.learned_id.id_features`,
    ``"regressor_drives"``), side by side: ``F = Σ_j (c_j + 3)``, 140 for intelbot5. A learner on these
    knows the geometry, as the identification does, and may learn what is not linear in them.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> q = np.zeros((3, robot.n))
        >>> regressor_inputs(robot, q, q, q).shape
        (3, 140)
    """
    return np.concatenate(id_features(robot, q, qd, qdd, "regressor_drives"), axis=1)


@BASELINES.register
class KernelID(_SmoothInputs, Standardised):
    """Nyström kernel ridge regression (module docstring)."""

    learner, label = "kernel", "kernel ridge (Nyström)"
    _state_keys = ("landmarks", "normalization", "coef", "intercept", "gamma")

    def __init__(self, n_components: int = 1000, gamma: float = 0.1, alpha: float = 1e-6, angles: str = "joints", *,
                 residual: bool | str = False, random_state: int = 0):
        self.n_components = n_components
        self.gamma = gamma
        self.alpha = alpha
        self.angles = angles
        super().__init__(residual=residual, random_state=random_state)

    def _estimator(self, options):
        from sklearn.kernel_approximation import Nystroem
        from sklearn.linear_model import Ridge
        from sklearn.pipeline import make_pipeline
        from sklearn.preprocessing import StandardScaler
        return make_pipeline(StandardScaler(),
                             Nystroem(kernel="rbf", gamma=options["gamma"], n_components=options["n_components"],
                                      random_state=self.random_state),
                             Ridge(alpha=options["alpha"], solver="cholesky"))

    def _scaled_state(self, rest, last):
        (nystroem,) = rest
        return {"landmarks": nystroem.components_, "normalization": nystroem.normalization_,
                "gamma": float(nystroem.gamma), "coef": np.atleast_2d(last.coef_), "intercept": np.atleast_1d(last.intercept_)}

    def _predict_scaled(self, state, Xs):
        from sklearn.metrics.pairwise import rbf_kernel

        features = rbf_kernel(Xs, state["landmarks"], gamma=state["gamma"]) @ state["normalization"].T
        return features @ state["coef"].T + state["intercept"]

    def _read_scaled(self, v: Validator, state, k, n, options):
        landmarks = v.array(state["landmarks"], "state.landmarks", (None, k))
        m = len(landmarks)
        return {"landmarks": landmarks, "normalization": v.array(state["normalization"], "state.normalization", (m, m)),
                "coef": v.array(state["coef"], "state.coef", (n, m)),
                "intercept": v.array(state["intercept"], "state.intercept", (n,)),
                "gamma": v.number(state["gamma"], "state.gamma", lo=0, lo_open=True)}


@BASELINES.register
class BoostingID(_SmoothInputs, BaselineID):
    """Gradient-boosted trees per joint (module docstring); saved as every tree's node arrays."""

    learner, label = "boosting", "gradient-boosted trees"

    def __init__(self, max_iter: int = 300, learning_rate: float = 0.1, max_leaf_nodes: int = 31,
                 angles: str = "joints", *, residual: bool | str = False, random_state: int = 0):
        self.max_iter = max_iter
        self.learning_rate = learning_rate
        self.max_leaf_nodes = max_leaf_nodes
        self.angles = angles
        super().__init__(residual=residual, random_state=random_state)

    def _estimator(self, options):
        from sklearn.multioutput import MultiOutputRegressor

        HistGradientBoostingRegressor, _ = _timed_learners()
        return MultiOutputRegressor(HistGradientBoostingRegressor(
            max_iter=options["max_iter"], learning_rate=options["learning_rate"],
            max_leaf_nodes=options["max_leaf_nodes"], early_stopping=False, random_state=self.random_state))

    def _state_of(self, model):
        return trees_state(model)

    def _predict_state(self, state, X):
        return np.column_stack([forest_values(joint["trees"], joint["baseline"], X) for joint in state["joints"]])

    def _read_state(self, v: Validator, state, k, n, options):
        return read_trees(v, state, k, n, options["max_iter"])


@BASELINES.register
class MLPID(_SmoothInputs, Standardised):
    """A multilayer perceptron, stopped early on validation states when given (module docstring)."""

    learner, label = "mlp", "multilayer perceptron"
    _state_keys = ("weights", "biases")

    def __init__(self, hidden: Sequence[int] = (128, 128), alpha: float = 1e-4, max_iter: int = 200,
                 patience: int = 10, angles: str = "joints", *, residual: bool | str = False, random_state: int = 0):
        self.hidden = hidden
        self.alpha = alpha
        self.max_iter = max_iter
        self.patience = patience
        self.angles = angles
        super().__init__(residual=residual, random_state=random_state)

    def _estimator(self, options):
        from sklearn.pipeline import make_pipeline
        from sklearn.preprocessing import StandardScaler

        _, MLPRegressor = _timed_learners()
        return make_pipeline(StandardScaler(), MLPRegressor(
            hidden_layer_sizes=tuple(options["hidden"]), alpha=options["alpha"],
            max_iter=options["max_iter"], early_stopping=False, random_state=self.random_state, tol=0.0,
            n_iter_no_change=options["max_iter"] + 1))

    def _train(self, options, X, Z, robot, val, joint=None):
        """Without ``val``: ``max_iter`` epochs. With it: trained epoch by epoch (``partial_fit``:
        one pass of Adam over shuffled batches, as ``fit`` makes), its weights those of the epoch
        of least validation RMSE, stopped ``patience`` epochs after it or at ``max_iter``; sets
        ``epochs_`` and ``best_epoch_`` (0-based)."""
        if Z.ndim == 2 and Z.shape[1] == 1:     # a model a joint: one output, as scikit-learn wants it (1-D)
            Z = Z[:, 0]
        if val is None:
            return super()._train(options, X, Z, robot, val, joint)
        from sklearn.pipeline import make_pipeline
        from sklearn.preprocessing import StandardScaler

        X_val, Z_val = self._validation(robot, val)
        if joint is not None:                   # a model a joint: its own inputs and torque
            X_val, Z_val = X_val[:, joint], Z_val[:, joint:joint + 1]
        _, MLPRegressor = _timed_learners()
        scaler = StandardScaler().fit(X)
        net = MLPRegressor(hidden_layer_sizes=tuple(options["hidden"]), alpha=options["alpha"],
                           random_state=self.random_state, shuffle=True)
        # Trained in single precision, as neural networks are (1.2x faster for two layers of 64 on 5 000 states,
        # 2026-12-03; the IK rivals' wider MLP gains more, it says how much); the kept weights then predict in
        # double (_predict_scaled).
        Xs, Xv = scaler.transform(X).astype(np.float32), scaler.transform(X_val).astype(np.float32)
        Z32 = np.asarray(Z, dtype=np.float32)
        best, since, weights = np.inf, 0, None
        for epoch in range(options["max_iter"]):
            net.partial_fit(Xs, Z32)
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

    def _scaled_state(self, rest, last):
        return {"weights": list(last.coefs_), "biases": list(last.intercepts_)}

    def _predict_scaled(self, state, Xs):
        a = Xs
        for k, (W, b) in enumerate(zip(state["weights"], state["biases"])):
            a = a @ W
            a += b
            if k < len(state["weights"]) - 1:
                np.maximum(a, 0, out=a)
        return a

    def _read_scaled(self, v: Validator, state, k, n, options):
        widths = [k, *options["hidden"], n]
        layers = len(widths) - 1
        weights = v.sequence(state["weights"], "state.weights", min_len=layers, max_len=layers)
        biases = v.sequence(state["biases"], "state.biases", min_len=layers, max_len=layers)
        return {"weights": [v.array(w, f"state.weights[{i}]", (widths[i], widths[i + 1])) for i, w in enumerate(weights)],
                "biases": [v.array(b, f"state.biases[{i}]", (widths[i + 1],)) for i, b in enumerate(biases)]}


class _LeastSquaresLaw(BaselineID):
    """A physical law fitted by least squares (the targets as they are: its zero-offset column is its constant): its
    ``coef`` is all it keeps."""

    scaled_targets = False

    def _state_of(self, model):
        return {"coef": model.coef_}


@BASELINES.register
class FrictionID(_LeastSquaresLaw):
    """Each joint's armature, viscous and Coulomb friction beside Newton–Euler (module docstring;
    a residual only)."""

    learner, label = "friction", "friction identification (least squares)"
    residual_only, residual_reason = True, "identifies the drives beside Newton–Euler"

    def __init__(self, *, residual: bool = True, random_state: int = 0):
        super().__init__(residual=residual, random_state=random_state)

    def _features(self, q, qd, qdd):
        return law_terms(self.robot_, qd, qdd)                            # (N, n, 4)

    def _estimator(self, options):
        return PerJointLeastSquares()

    def _predict_state(self, state, X):
        return np.einsum("njk,jk->nj", X, state["coef"])

    def _read_state(self, v: Validator, state, k, n, options):
        v.mapping(state, "state", {"coef": True})
        return {"coef": v.array(state["coef"], "state.coef", (n, 4))}


@BASELINES.register
class IdentificationID(_LeastSquaresLaw):
    """The built arm's inertial parameters and drives by one least squares (module docstring;
    never a residual)."""

    learner, label = "identification", "identification of the built arm (least squares)"
    residual_only, residual_reason = False, "fits the whole torque, the masses included"

    def __init__(self, *, residual: bool = False, random_state: int = 0):
        super().__init__(residual=residual, random_state=random_state)

    def _features(self, q, qd, qdd):                                      # (N, n, 10 n + 4 n)
        return identification_columns(self.robot_, q, qd, qdd)

    def _estimator(self, options):
        return StackedLeastSquares()

    def _predict_state(self, state, X):
        return X @ state["coef"]

    def _read_state(self, v: Validator, state, k, n, options):
        v.mapping(state, "state", {"coef": True})
        return {"coef": v.array(state["coef"], "state.coef", (k,))}
