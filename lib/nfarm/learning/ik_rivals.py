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
from .learned import ik_pairs

__all__ = ["RivalIK", "KINDS", "FILE_NAME", "FORMAT"]

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

    Learned attributes: ``encoder_``, ``n_joints_``, ``robot_hash_``, ``robot_name_``,
    ``fit_seconds_``, ``epochs_`` (the MLP's epochs run; else 0) and ``best_epoch_`` (the
    MLP's kept epoch; else 0), and the kind's state (``X_``, ``Y_`` for the neighbour methods;
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
                 max_out_of_plane: float = math.pi, random_state: int | None = None):
        self.kind = kind
        self.encoding = encoding
        self.options = options
        self.max_out_of_plane = max_out_of_plane
        self.random_state = random_state

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
        if self.kind in ("knn", "rbf"):
            self.X_, self.Y_ = X, q
        else:
            self.y_mean_, self.y_scale_ = q.mean(axis=0), np.where(q.std(axis=0) > 0, q.std(axis=0), 1.0)
            Z = (q - self.y_mean_) / self.y_scale_
            if self.kind == "mlp":
                T_val, q_val = ik_pairs(val, robot, "val")
                self._fit_mlp(o, X, Z, self.encoder_.transform(T_val), (q_val - self.y_mean_) / self.y_scale_)
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

    def predict(self, T_0e) -> np.ndarray:
        """Joint angles ``(..., n)`` [rad] for tool poses ``T_0e (..., 4, 4)``."""
        self._check_fitted()
        T = check_targets(T_0e, 1e-6)
        X = self.encoder_.transform(T.reshape(-1, 4, 4))
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
        return q.reshape(*T.shape[:-2], self.n_joints_)

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
        return {"format": FORMAT, "nfarm_version": __version__, "kind": self.kind,
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
        v.mapping(data, "", {**dict.fromkeys(keys, True), "chart": False})
        kind = v.choice(data["kind"], "kind", tuple(KINDS))
        try:
            options = _checked_options(kind, data["options"])
        except ValueError as exc:
            v.fail("options", str(exc))
        check_robot(v, data, robot)
        n = v.integer(data["n_joints"], "n_joints", lo=robot.n, hi=robot.n)
        encoder = PoseEncoder.from_dict(data, source)
        d = len(encoder.input_lo_)
        seed = None if data["random_state"] is None else v.integer(data["random_state"], "random_state", lo=0)
        model = cls(kind, encoder.encoding, options, encoder.max_out_of_plane, seed)
        model.encoder_, model.n_joints_, model.robot_hash_ = encoder, n, data["robot_params_sha256"]
        model.robot_name_ = data["robot"]
        model.fit_seconds_ = v.number(data["fit_seconds"], "fit_seconds", lo=0)
        model.epochs_ = v.integer(data["epochs"], "epochs", lo=0)
        model.best_epoch_ = v.integer(data["best_epoch"], "best_epoch", lo=0)
        state = data["state"]
        wanted = cls._STATE[kind] + (("weights", "biases") if kind == "mlp" else ())
        v.mapping(state, "state", dict.fromkeys(wanted, True))
        if kind in ("knn", "rbf"):
            model.X_ = v.array(state["X"], "state.X", (None, d))
            model.Y_ = v.array(state["Y"], "state.Y", (len(model.X_), n))
        else:
            model.y_mean_ = v.array(state["y_mean"], "state.y_mean", (n,))
            model.y_scale_ = v.array(state["y_scale"], "state.y_scale", (n,))
        if kind == "mlp":
            widths = [d, *options["hidden"], n]
            weights = v.sequence(state["weights"], "state.weights", min_len=len(widths) - 1, max_len=len(widths) - 1)
            biases = v.sequence(state["biases"], "state.biases", min_len=len(widths) - 1, max_len=len(widths) - 1)
            model.weights_ = [v.array(w, f"state.weights[{k}]", (widths[k], widths[k + 1])) for k, w in enumerate(weights)]
            model.biases_ = [v.array(b, f"state.biases[{k}]", (widths[k + 1],)) for k, b in enumerate(biases)]
        if kind == "kernel_ridge":
            model.landmarks_ = v.array(state["landmarks"], "state.landmarks", (None, d))
            m = len(model.landmarks_)
            model.coef_ = v.array(state["coef"], "state.coef", (m, n))
            model.intercept_ = v.array(state["intercept"], "state.intercept", (n,))
        model._build(options)
        return model
