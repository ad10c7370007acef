"""The learned-IK contest's rivals of ANFIS (chapter 6): scikit-learn and SciPy learners on the
same encoded, scaled pose inputs as :class:`nfarm.learning.learned.LearnedIK`, one model for all
joints, each saved as JSON (no pickle) and loaded back to predict the same bits.

Kinds and their options (:data:`KINDS`, the defaults):

* ``"knn"`` — k nearest training poses, weighted by inverse distance (``neighbors``,
  ``weights``; ``sklearn.neighbors.KNeighborsRegressor``);
* ``"rbf"`` — polyharmonic-spline interpolation over the ``neighbors`` nearest training poses
  with a degree-1 polynomial (degree 2 for ``quintic``; ``kernel``: ``thin_plate_spline``, ``cubic``, ``quintic`` or
  ``linear``; ``smoothing``; ``scipy.interpolate.RBFInterpolator``);
* ``"mlp"`` — a multilayer perceptron (``hidden`` layer widths, ``activation``, L2 penalty
  ``alpha``, Adam's ``learning_rate``) on standardised joint angles, trained epoch by epoch
  (``sklearn.neural_network.MLPRegressor.partial_fit``) for at most ``max_epochs``, keeping the
  epoch of least validation RMSE and stopping once it has not fallen by ``min_improvement`` of
  its least value for ``patience`` epochs — the rule the ANFIS's early stopping follows, on the
  same validation poses;
* ``"kernel_ridge"`` — kernel ridge regression with a Gaussian kernel
  ``exp(−gamma·‖x − x'‖²)`` approximated by ``components`` Nyström landmarks (the
  approximate Gaussian process of the contest; ``sklearn.kernel_approximation.Nystroem``, then
  ``sklearn.linear_model.Ridge`` with ``alpha``) on standardised joint angles.

Outputs are the joint angles [rad]. Every random draw (the MLP's initialisation and batches, the
Nyström landmarks) comes from ``random_state``.

**Structures** (:data:`STRUCTURES`): by default (``"whole"``) one model learns all the joints. With
``"arm"`` a rival gets the structure the contest's ANFIS in the arm's plane has
(:class:`nfarm.learning.learned.LearnedIK` with ``shared_joints`` the pitch joints, one linear rule
for the first and last joints, ``pitch_closure``): for an arm of ``n`` joints on the
``"arm_plane"`` encoding, the first and the last joint are affine maps of the inputs (least
squares, what a one-rule first-order Sugeno model is), the pitch joints ``q[1:n-1]`` are learned by
the one model, and the last pitch joint is predicted from the target's pitch
(:func:`nfarm.learning.learned.fit_pitch_closure`) — the same outputs learned, the same joints
computed, so that a contest of the two judges the learners (chapter 6). :meth:`RivalIK.without_closure`
keeps the learned last pitch joint instead (the closure's ablation, chapter 7).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any

import numpy as np

from .. import __version__
from ..infra.reading import Validator, json_ready, show
from ..model.robot import Robot, robot_hash
from ..solvers.ik import check_targets
from .encoding import ENCODINGS, PoseEncoder
from .estimator import SavedModel, check_robot
from .hybrid import least_squares
from .learned import close_pitch, fit_pitch_closure, ik_pairs, read_closure

__all__ = ["RivalIK", "KINDS", "STRUCTURES", "FILE_NAME", "FORMAT"]

FILE_NAME = "rival_ik.json"
FORMAT = "nfarm-rival-ik-1"

#: Each kind's options and their defaults.
KINDS: dict[str, dict[str, Any]] = {
    "knn": {"neighbors": 5, "weights": "distance"},
    "rbf": {"neighbors": 32, "kernel": "thin_plate_spline", "smoothing": 0.0},
    "mlp": {"hidden": [128, 128], "activation": "relu", "alpha": 1e-4, "learning_rate": 1e-3,
            "batch_size": 200, "max_epochs": 300, "patience": 10, "min_improvement": 0.0},
    "kernel_ridge": {"components": 2000, "gamma": 10.0, "alpha": 1e-6},
}
#: How the joints are computed: one model for all (``"whole"``) or the ANFIS's structure (``"arm"``, module docstring).
STRUCTURES = ("whole", "arm")
_RBF_KERNELS = ("thin_plate_spline", "cubic", "quintic", "linear")
_ACTIVATIONS = {"relu": lambda a: np.maximum(a, 0, out=a), "tanh": lambda a: np.tanh(a, out=a)}


def _checked_options(kind: Any, options: Any) -> dict:
    """``options`` over ``kind``'s defaults, each checked; one-line ``ValueError`` otherwise."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {show(kind)}")
    options = {} if options is None else options
    if not isinstance(options, Mapping):
        raise ValueError(f"options must be a mapping of {kind} options, got {show(options)}")
    unknown = sorted(set(options) - set(KINDS[kind]))
    if unknown:
        raise ValueError(f"{kind}: unknown option {unknown[0]!r}; valid: {', '.join(KINDS[kind])}")
    o = {**KINDS[kind], **options}

    def whole(name: str, lo: int, hi: int) -> None:
        x = o[name]
        if isinstance(x, bool) or not isinstance(x, (int, np.integer)) or not lo <= x <= hi:
            raise ValueError(f"{kind}: {name} must be a whole number in [{lo}, {hi}], got {show(x)}")

    def positive(name: str, zero: bool = False) -> None:
        x = o[name]
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x) \
                or not (x >= 0 if zero else x > 0):
            raise ValueError(f"{kind}: {name} must be a finite number {'>= 0' if zero else '> 0'}, got {show(x)}")

    if kind in ("knn", "rbf"):
        whole("neighbors", 1, 10_000)
    if kind == "knn" and o["weights"] not in ("uniform", "distance"):
        raise ValueError(f"knn: weights must be 'uniform' or 'distance', got {show(o['weights'])}")
    if kind == "rbf":
        if o["kernel"] not in _RBF_KERNELS:
            raise ValueError(f"rbf: kernel must be one of {', '.join(_RBF_KERNELS)}, got {show(o['kernel'])}")
        positive("smoothing", zero=True)
    if kind == "mlp":
        hidden = o["hidden"]
        if isinstance(hidden, (str, bytes)) or not isinstance(hidden, (list, tuple)) or not 1 <= len(hidden) <= 8 \
                or not all(isinstance(h, (int, np.integer)) and not isinstance(h, bool) and 1 <= h <= 4096
                           for h in hidden):
            raise ValueError(f"mlp: hidden must be 1 to 8 layer widths in [1, 4096], got {show(hidden)}")
        if o["activation"] not in _ACTIVATIONS:
            raise ValueError(f"mlp: activation must be one of {', '.join(_ACTIVATIONS)}, got {show(o['activation'])}")
        positive("alpha", zero=True)
        positive("learning_rate")
        whole("batch_size", 1, 1_000_000)
        whole("max_epochs", 1, 100_000)
        whole("patience", 1, 100_000)
        positive("min_improvement", zero=True)
        if o["min_improvement"] >= 1:
            raise ValueError(f"mlp: min_improvement must be below 1 (a share of the least error), got {show(o['min_improvement'])}")
        o["hidden"] = [int(h) for h in hidden]
    if kind == "kernel_ridge":
        whole("components", 1, 50_000)
        positive("gamma")
        positive("alpha")
    return o


class RivalIK(SavedModel):
    """A rival of the learned IK (module docstring; scikit-learn conventions).

    Args:
        kind: ``"knn"``, ``"rbf"``, ``"mlp"`` or ``"kernel_ridge"``.
        encoding: how a pose becomes inputs (:data:`nfarm.learning.encoding.ENCODINGS`), as the
            learned IK's.
        options: the kind's options over its defaults (:data:`KINDS`).
        max_out_of_plane: the ``"arm_plane"`` encoder's check [rad] (by default none, π).
        random_state: the seed of every random draw.
        structure: ``"whole"`` (one model learns every joint) or ``"arm"`` (the ANFIS's
            structure: module docstring; ``"arm_plane"`` only).
        closure_tolerance: for ``"arm"``, the pitch closure's largest residual [rad] on the
            training poses (:func:`nfarm.learning.learned.fit_pitch_closure`).
        affine_ridge: for ``"arm"``, the ridge on the first and last joints' least squares,
            relative to the normal matrix's mean diagonal — the one-rule ANFIS's least squares
            (:func:`nfarm.learning.hybrid.least_squares`, one rule), so that with the contest
            ANFIS's ridge (1e-8) those joints are the ANFIS's to the last bits.
        pitch_closure: for ``"arm"``, close the last pitch joint from the target's pitch (the
            structure's; ``False``: keep the model's own prediction of it, as
            :meth:`without_closure` does).

    Learned attributes: ``encoder_``, ``n_joints_``, ``robot_hash_``, ``robot_name_``,
    ``fit_seconds_``, ``epochs_`` (the MLP's epochs run; else 0) and ``best_epoch_`` (the
    MLP's kept epoch; else 0), ``learned_`` (the joints the model learns, 0-based), ``affine_``
    (``None``, or ``(d + 1, 2)``: the first and last joints' affine maps of the scaled inputs and
    1) and ``closure_`` (``None`` or the pitch closure), and the kind's state (``X_``, ``Y_`` for the neighbour methods;
    ``weights_`` and ``biases_`` for the MLP; ``landmarks_ (m, d)``, ``coef_ (m, n)`` (the ridge's
    weights with the Nyström normalisation folded in) and ``intercept_`` for kernel ridge; ``y_mean_`` and ``y_scale_`` for the standardised kinds).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> from nfarm.model.kinematics import fk
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> q = np.random.default_rng(0).uniform(-0.5, 0.5, (2000, 5))
        >>> model = RivalIK("rbf", "quat_xyz", {"neighbors": 16}).fit(robot, {"T": fk(robot, q), "q": q})
        >>> bool(np.abs(model.predict(fk(robot, q[:3])) - q[:3]).max() < 1e-6)   # it interpolates
        True
    """

    _fitted = "encoder_"

    file_name, file_format, what = FILE_NAME, FORMAT, "rival IK"

    def __init__(self, kind: str = "rbf", encoding: str = "arm_plane", options: Mapping | None = None,
                 max_out_of_plane: float = math.pi, random_state: int | None = None, structure: str = "whole",
                 closure_tolerance: float = 1e-4, affine_ridge: float = 1e-8, pitch_closure: bool = True):
        self.kind = kind
        self.encoding = encoding
        self.options = options
        self.max_out_of_plane = max_out_of_plane
        self.random_state = random_state
        self.structure = structure
        self.closure_tolerance = closure_tolerance
        self.affine_ridge = affine_ridge
        self.pitch_closure = pitch_closure

    # -- fitting ------------------------------------------------------------------------------

    def fit(self, robot: Robot, train: Mapping, val: Mapping | None = None) -> "RivalIK":
        """Fit on ``train`` (``T (N, 4, 4)``, ``q (N, n)``); ``val`` (the same) is used by the
        MLP only, to keep its best epoch and stop early.

        Raises:
            ValueError: bad options or data, before any training; an MLP without ``val``.
        """
        o = _checked_options(self.kind, self.options)
        if self.encoding not in ENCODINGS:
            raise ValueError(f"encoding must be one of {', '.join(ENCODINGS)}, got {show(self.encoding)}")
        if self.structure not in STRUCTURES:
            raise ValueError(f"structure must be one of {', '.join(STRUCTURES)}, got {show(self.structure)}")
        if self.structure == "arm" and (self.encoding != "arm_plane" or robot.n < 3):
            raise ValueError(f"structure 'arm' needs the 'arm_plane' encoding and at least 3 joints, got "
                             f"{show(self.encoding)} and {robot.n}")
        T, q = ik_pairs(train, robot, "train")
        if self.kind == "mlp" and val is None:
            raise ValueError("an mlp rival keeps its best epoch on validation poses: give val")
        d = ENCODINGS[self.encoding]
        if self.kind == "rbf" and o["kernel"] == "quintic" and o["neighbors"] < (d + 1) * (d + 2) // 2:
            raise ValueError(f"rbf: the quintic kernel's degree-2 polynomial needs neighbors >= "
                             f"{(d + 1) * (d + 2) // 2} for the {d} inputs of {self.encoding!r}, got {o['neighbors']}")
        self.encoder_ = PoseEncoder(self.encoding, self.max_out_of_plane)
        X = self.encoder_.fit_transform(robot, T)
        start = time.perf_counter()
        self.epochs_ = self.best_epoch_ = 0
        self.learned_, self.affine_, self.closure_ = list(range(robot.n)), None, None
        if self.structure == "arm":
            if not isinstance(self.pitch_closure, bool):
                raise ValueError(f"pitch_closure must be true or false, got {show(self.pitch_closure)}")
            closure = fit_pitch_closure(self.encoder_, X, q, self.closure_tolerance)   # checks the arm either way
            self.closure_ = closure if self.pitch_closure else None
            self.learned_ = list(range(1, robot.n - 1))
            if isinstance(self.affine_ridge, bool) or not isinstance(self.affine_ridge, (int, float)) \
                    or not 0 <= self.affine_ridge < 1:
                raise ValueError(f"affine_ridge must be a number in [0, 1), got {show(self.affine_ridge)}")
            self.affine_ = least_squares(np.ones((len(X), 1)), np.column_stack([X, np.ones(len(X))]),
                                         q[:, [0, robot.n - 1]], ridge=float(self.affine_ridge))
        y = q[:, self.learned_]
        if self.kind in ("knn", "rbf"):
            self.X_, self.Y_ = X, y
        else:
            self.y_mean_, self.y_scale_ = y.mean(axis=0), np.where(y.std(axis=0) > 0, y.std(axis=0), 1.0)
            Z = (y - self.y_mean_) / self.y_scale_
            if self.kind == "mlp":
                T_val, q_val = ik_pairs(val, robot, "val")
                self._fit_mlp(o, X, Z, self.encoder_.transform(T_val),
                              (q_val[:, self.learned_] - self.y_mean_) / self.y_scale_)
            else:
                self._fit_kernel_ridge(o, X, Z)
        self._build(o)
        self.fit_seconds_ = time.perf_counter() - start
        self.n_joints_, self.robot_hash_, self.robot_name_ = robot.n, robot_hash(robot), robot.name
        return self

    def _fit_mlp(self, o: dict, X, Z, X_val, Z_val) -> None:
        import warnings

        from sklearn.exceptions import ConvergenceWarning
        from sklearn.neural_network import MLPRegressor

        net = MLPRegressor(hidden_layer_sizes=tuple(o["hidden"]), activation=o["activation"], alpha=o["alpha"],
                           learning_rate_init=o["learning_rate"], batch_size=o["batch_size"],
                           random_state=self.random_state, shuffle=True)
        best, since, reference = math.inf, 0, math.inf
        for epoch in range(o["max_epochs"]):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ConvergenceWarning)
                net.partial_fit(X, Z)
            self.epochs_ = epoch + 1
            error = float(np.sqrt(np.mean((net.predict(X_val) - Z_val) ** 2)))
            if error < best:                     # the epoch kept: the least error
                best, self.best_epoch_ = error, epoch
                self.weights_ = [w.copy() for w in net.coefs_]
                self.biases_ = [b.copy() for b in net.intercepts_]
            if error < reference * (1.0 - o["min_improvement"]):     # a fall large enough to count
                reference, since = error, 0
            else:
                since += 1
                if since >= o["patience"]:
                    break

    def _fit_kernel_ridge(self, o: dict, X, Z) -> None:
        from sklearn.kernel_approximation import Nystroem
        from sklearn.linear_model import Ridge

        nystroem = Nystroem(kernel="rbf", gamma=o["gamma"], n_components=min(o["components"], len(X)),
                            random_state=self.random_state).fit(X)
        self.landmarks_ = nystroem.components_
        ridge = Ridge(alpha=o["alpha"]).fit(self._kernel(X, o["gamma"]) @ nystroem.normalization_.T, Z)
        # The features' normalisation folded into the weights: one (m, n) matrix to keep.
        self.coef_, self.intercept_ = nystroem.normalization_.T @ ridge.coef_.T, ridge.intercept_

    def _kernel(self, X: np.ndarray, gamma: float) -> np.ndarray:
        """``K(X, landmarks) (N, m)``, the Gaussian kernel of scaled inputs ``X (N, d)``."""
        d2 = (X ** 2).sum(1)[:, None] - 2 * X @ self.landmarks_.T + (self.landmarks_ ** 2).sum(1)[None, :]
        return np.exp(-gamma * np.maximum(d2, 0))

    def _build(self, o: dict) -> None:
        """The neighbour methods' search structures (rebuilt, deterministically, on load)."""
        self.options_ = o
        if self.kind == "knn":
            from sklearn.neighbors import KNeighborsRegressor
            self.knn_ = KNeighborsRegressor(n_neighbors=min(o["neighbors"], len(self.X_)),
                                            weights=o["weights"]).fit(self.X_, self.Y_)
        elif self.kind == "rbf":
            from scipy.interpolate import RBFInterpolator
            # The lowest polynomial degree that makes each kernel's interpolant unique.
            self.rbf_ = RBFInterpolator(self.X_, self.Y_, neighbors=min(o["neighbors"], len(self.X_)),
                                        kernel=o["kernel"], smoothing=o["smoothing"],
                                        degree=2 if o["kernel"] == "quintic" else 1)

    # -- prediction ---------------------------------------------------------------------------

    def without_closure(self) -> "RivalIK":
        """A copy of the fitted model that keeps its learned last pitch joint instead of the pitch
        closure (the closure's ablation, chapter 7); a model without a closure comes back as a copy."""
        import copy

        self._check_fitted()
        model = copy.copy(self)
        model.__dict__.update(copy.deepcopy({k: v for k, v in self.__dict__.items() if not k.endswith("_")}))
        model.pitch_closure, model.closure_ = False, None
        return model

    def predict(self, T_0e) -> np.ndarray:
        """Joint angles ``(..., n)`` [rad] for tool poses ``T_0e (..., 4, 4)``."""
        self._check_fitted()
        T = check_targets(T_0e, 1e-6)
        X = self.encoder_.transform(T.reshape(-1, 4, 4))
        y = self._learned(X)
        if self.affine_ is None:
            return y.reshape(*T.shape[:-2], self.n_joints_)
        n = self.n_joints_
        q = np.empty((len(X), n))
        q[:, self.learned_] = y
        q[:, [0, n - 1]] = np.column_stack([X, np.ones(len(X))]) @ self.affine_
        if self.closure_ is not None:
            close_pitch(self.closure_, self.encoder_, X, q)
        return q.reshape(*T.shape[:-2], n)

    def _learned(self, X: np.ndarray) -> np.ndarray:
        """The learned joints' angles ``(N, len(learned_))`` [rad] of scaled inputs ``X``."""
        if self.kind == "knn":
            q = self.knn_.predict(X)
        elif self.kind == "rbf":
            q = self.rbf_(X)
        else:
            if self.kind == "mlp":
                a = X
                for k, (W, b) in enumerate(zip(self.weights_, self.biases_)):
                    a = a @ W + b
                    if k < len(self.weights_) - 1:
                        _ACTIVATIONS[self.options_["activation"]](a)
            else:
                a = self._kernel(X, self.options_["gamma"]) @ self.coef_ + self.intercept_
            q = a * self.y_scale_ + self.y_mean_
        return q

    # -- persistence --------------------------------------------------------------------------

    _STATE = {"knn": ("X", "Y"), "rbf": ("X", "Y"), "mlp": ("y_mean", "y_scale"),
              "kernel_ridge": ("y_mean", "y_scale", "landmarks", "coef", "intercept")}

    def to_dict(self) -> dict:
        """The model as JSON-ready fields (its options, the robot's name and hash, the encoder
        and the kind's state)."""
        self._check_fitted()
        state = {k: json_ready(getattr(self, f"{k}_")) for k in self._STATE[self.kind]}
        if self.kind == "mlp":
            state["weights"] = [json_ready(w) for w in self.weights_]
            state["biases"] = [json_ready(b) for b in self.biases_]
        structure = {} if self.structure == "whole" else {
            "structure": self.structure, "closure_tolerance": self.closure_tolerance, "affine_ridge": self.affine_ridge,
            "pitch_closure": self.pitch_closure,
            "affine": json_ready(self.affine_), "closure": json_ready(self.closure_)}
        return {"format": FORMAT, "nfarm_version": __version__, "kind": self.kind, **structure,
                "options": json_ready(self.options_), "random_state": self.random_state,
                "robot": self.robot_name_, "robot_params_sha256": self.robot_hash_, "n_joints": self.n_joints_,
                "fit_seconds": self.fit_seconds_, "epochs": self.epochs_, "best_epoch": self.best_epoch_,
                "state": state, **self.encoder_.to_dict()}

    @classmethod
    def from_dict(cls, data: Any, robot: Robot, source: str = "<dict>") -> "RivalIK":
        v = Validator(source)
        keys = ("format", "nfarm_version", "kind", "options", "random_state", "robot", "robot_params_sha256",
                "n_joints", "fit_seconds", "epochs", "best_epoch", "state", "encoding", "max_out_of_plane",
                "angle_centre", "input_lo", "input_span")
        v.mapping(data, "", {**dict.fromkeys(keys, True), "chart": False,
                             **dict.fromkeys(("structure", "closure_tolerance", "affine_ridge", "pitch_closure", "affine",
                                              "closure"), False)})
        kind = v.choice(data["kind"], "kind", tuple(KINDS))
        structure = v.choice(data.get("structure", "whole"), "structure", STRUCTURES)
        try:
            options = _checked_options(kind, data["options"])
        except ValueError as exc:
            v.fail("options", str(exc))
        check_robot(v, data, robot)
        n = v.integer(data["n_joints"], "n_joints", lo=robot.n, hi=robot.n)
        encoder = PoseEncoder.from_dict(data, source)
        d = len(encoder.input_lo_)
        seed = None if data["random_state"] is None else v.integer(data["random_state"], "random_state", lo=0)
        model = cls(kind, encoder.encoding, options, encoder.max_out_of_plane, seed, structure)
        model.encoder_, model.n_joints_, model.robot_hash_ = encoder, n, data["robot_params_sha256"]
        model.learned_, model.affine_, model.closure_ = list(range(n)), None, None
        if structure == "arm":
            if encoder.encoding != "arm_plane" or n < 3:
                v.fail("structure", f"'arm' needs the 'arm_plane' encoding and at least 3 joints, got "
                                    f"{show(encoder.encoding)} and {n}")
            for key in ("closure_tolerance", "affine_ridge", "affine", "closure"):
                if key not in data:
                    v.fail(key, "is required with structure 'arm'")
            # the ranges fit accepts: (0, π) and [0, 1)
            model.closure_tolerance = v.number(data["closure_tolerance"], "closure_tolerance", lo=0, hi=math.pi, lo_open=True)
            if model.closure_tolerance >= math.pi:
                v.fail("closure_tolerance", f"must be below pi, got {show(data['closure_tolerance'])}")
            model.affine_ridge = v.number(data["affine_ridge"], "affine_ridge", lo=0, hi=1)
            if model.affine_ridge >= 1:
                v.fail("affine_ridge", f"must be below 1, got {show(data['affine_ridge'])}")
            model.pitch_closure = v.boolean(data.get("pitch_closure", True), "pitch_closure")
            model.learned_ = list(range(1, n - 1))
            model.affine_ = v.array(data["affine"], "affine", (d + 1, 2))
            model.closure_ = read_closure(v, data["closure"], n) if model.pitch_closure else None
            if not model.pitch_closure and data["closure"] is not None:
                v.fail("closure", "must be null when pitch_closure is false")
        elif any(key in data for key in ("closure_tolerance", "affine_ridge", "pitch_closure", "affine", "closure")):
            v.fail("structure", "closure_tolerance, affine_ridge, pitch_closure, affine and closure belong to structure 'arm'")
        n_out = len(model.learned_)
        model.robot_name_ = data["robot"]
        model.fit_seconds_ = v.number(data["fit_seconds"], "fit_seconds", lo=0)
        model.epochs_ = v.integer(data["epochs"], "epochs", lo=0)
        model.best_epoch_ = v.integer(data["best_epoch"], "best_epoch", lo=0)
        state = data["state"]
        wanted = cls._STATE[kind] + (("weights", "biases") if kind == "mlp" else ())
        v.mapping(state, "state", dict.fromkeys(wanted, True))
        if kind in ("knn", "rbf"):
            model.X_ = v.array(state["X"], "state.X", (None, d))
            model.Y_ = v.array(state["Y"], "state.Y", (len(model.X_), n_out))
        else:
            model.y_mean_ = v.array(state["y_mean"], "state.y_mean", (n_out,))
            model.y_scale_ = v.array(state["y_scale"], "state.y_scale", (n_out,))
        if kind == "mlp":
            widths = [d, *options["hidden"], n_out]
            weights = v.sequence(state["weights"], "state.weights", min_len=len(widths) - 1, max_len=len(widths) - 1)
            biases = v.sequence(state["biases"], "state.biases", min_len=len(widths) - 1, max_len=len(widths) - 1)
            model.weights_ = [v.array(w, f"state.weights[{k}]", (widths[k], widths[k + 1])) for k, w in enumerate(weights)]
            model.biases_ = [v.array(b, f"state.biases[{k}]", (widths[k + 1],)) for k, b in enumerate(biases)]
        if kind == "kernel_ridge":
            model.landmarks_ = v.array(state["landmarks"], "state.landmarks", (None, d))
            m = len(model.landmarks_)
            model.coef_ = v.array(state["coef"], "state.coef", (m, n_out))
            model.intercept_ = v.array(state["intercept"], "state.intercept", (n_out,))
        model._build(options)
        return model
