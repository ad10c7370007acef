"""The learned-IK contest's rivals of ANFIS (chapter 6): scikit-learn and SciPy learners on the
same encoded, scaled pose inputs as :class:`nfarm.learning.learned.LearnedIK`, one model for all
joints (or the ANFIS's structure), each saved as JSON (no pickle) and loaded back to predict the
same bits. One class per rival, each registered in :data:`RIVALS` under the name sweep files give
it; what they share (the encoding, the structure, the checks of the common arguments, saving) is
:class:`~nfarm.learning.ik_rival_base.RivalIK`'s (:mod:`nfarm.learning.ik_rival_base`).

* ``"knn"`` (:class:`KNNRival`) — k nearest training poses, weighted by inverse distance
  (``neighbors``, ``weights``; ``sklearn.neighbors.KNeighborsRegressor``);
* ``"rbf"`` (:class:`RBFRival`) — polyharmonic-spline interpolation over the ``neighbors``
  nearest training poses with a degree-1 polynomial (degree 2 for ``quintic``; ``kernel``:
  ``thin_plate_spline``, ``cubic``, ``quintic`` or ``linear``; ``smoothing``;
  ``scipy.interpolate.RBFInterpolator``);
* ``"mlp"`` (:class:`MLPRival`) — a multilayer perceptron (``hidden`` layer widths,
  ``activation``, L2 penalty ``alpha``, Adam's ``learning_rate``) on standardised joint angles,
  trained epoch by epoch (``sklearn.neural_network.MLPRegressor.partial_fit``) for at most
  ``max_epochs``, keeping the epoch of least validation RMSE and stopping once it has not fallen
  by ``min_improvement`` of its least value for ``patience`` epochs — the rule the ANFIS's early
  stopping follows, on the same validation poses;
* ``"kernel_ridge"`` (:class:`KernelRidgeRival`) — kernel ridge regression with a Gaussian kernel
  on standardised joint angles: ``exp(−gamma·‖x − x'‖²)`` approximated by ``components`` Nyström
  landmarks (``sklearn.kernel_approximation.Nystroem``, then ``sklearn.linear_model.Ridge`` with
  ``alpha``), or (``length_scales="fitted"``) a Gaussian process with one length scale per input,
  its hyper-parameters by maximum marginal likelihood on ``subset`` poses
  (``sklearn.gaussian_process.GaussianProcessRegressor``), its posterior mean exact on all of them.

Outputs are the joint angles [rad]. Every random draw (the MLP's initialisation and batches, the
Nyström landmarks, a Gaussian process's subset and restarts) comes from ``random_state``. A new rival is one class here (its hyper-parameters,
``kind``, ``label`` and the hooks the base module's docstring lists, under ``@RIVALS.register``) and
its cells in ``params/sweeps/ik_contest.yaml``.

Example:
    >>> from nfarm.infra.paths import PARAMS
    >>> from nfarm.model.robot import load_robot
    >>> from nfarm.model.kinematics import fk
    >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
    >>> q = np.random.default_rng(0).uniform(-0.5, 0.5, (2000, 5))
    >>> model = RBFRival(neighbors=16, encoding="quat_xyz").fit(robot, {"T": fk(robot, q), "q": q})
    >>> bool(np.abs(model.predict(fk(robot, q[:3])) - q[:3]).max() < 1e-6)   # it interpolates
    True
    >>> model.get_params()["neighbors"], RIVALS["rbf"] is RBFRival, rival_ik("rbf", options={"neighbors": 16})
    (16, True, RBFRival(neighbors=16))
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..infra.arguments import is_integer
from ..infra.reading import Validator, json_ready, show
from .ik_rival_base import FILE_NAME, FORMAT, RIVALS, STRUCTURES, RivalIK, finite_number, rival_ik, whole_number

__all__ = ["RivalIK", "RIVALS", "STRUCTURES", "FILE_NAME", "FORMAT", "rival_ik",
           "KNNRival", "RBFRival", "MLPRival", "KernelRidgeRival", "GP_BOUNDS"]

_RBF_KERNELS = ("thin_plate_spline", "cubic", "quintic", "linear")
#: The bounds of a fitted Gaussian process's hyper-parameters (:class:`KernelRidgeRival`,
#: ``length_scales="fitted"``): the kernel's variance ``s²`` and noise variance ``σ²`` of the
#: standardised angles, the length scales of inputs divided by their spread.
GP_BOUNDS = {"amplitude": (1e-2, 1e5), "length_scale": (1e-2, 1e3), "noise": (1e-10, 1e-1)}
#: The most poses a fitted Gaussian process's marginal likelihood is computed on (its ``subset``).
GP_MAX_SUBSET = 5000
#: The most training poses a fitted Gaussian process solves on exactly: its ``N × N`` kernel matrix
#: (800 MB at 10 000 poses); more poses want the shared length scales (Nyström).
GP_MAX_POSES = 10_000
_ACTIVATIONS = {"relu": lambda a: np.maximum(a, 0, out=a), "tanh": lambda a: np.tanh(a, out=a)}


class _Neighbours(RivalIK):
    """A rival that keeps the training poses (``X_ (N, d)``, ``Y_ (N, len(learned_))``) and
    searches them (``_build``, rebuilt on load)."""

    _state_keys = ("X", "Y")

    def _learn(self, o, X, y, X_val, y_val) -> None:
        self.X_, self.Y_ = X, y

    def _state(self) -> dict:
        return {"X": json_ready(self.X_), "Y": json_ready(self.Y_)}

    def _read_state(self, v: Validator, state, d: int, n_out: int, o: dict) -> None:
        self.X_ = v.array(state["X"], "state.X", (None, d))
        self.Y_ = v.array(state["Y"], "state.Y", (len(self.X_), n_out))


@RIVALS.register
class KNNRival(_Neighbours):
    """k nearest neighbours (module docstring). Learned: the training poses ``X_``, ``Y_`` and
    ``knn_`` (the fitted ``KNeighborsRegressor``)."""

    kind, label = "knn", "k nearest neighbours"

    def __init__(self, neighbors: int = 5, weights: str = "distance", *, encoding: str = "arm_plane",
                 max_out_of_plane: float = math.pi, random_state: int | None = None, structure: str = "whole",
                 closure_tolerance: float = 1e-4, affine_ridge: float = 1e-8, pitch_closure: bool = True):
        self.neighbors = neighbors
        self.weights = weights
        super().__init__(encoding=encoding, max_out_of_plane=max_out_of_plane, random_state=random_state,
                         structure=structure, closure_tolerance=closure_tolerance, affine_ridge=affine_ridge,
                         pitch_closure=pitch_closure)

    def _checked(self) -> dict:
        whole_number(self.kind, "neighbors", self.neighbors, 1, 10_000)
        if self.weights not in ("uniform", "distance"):
            raise ValueError(f"knn: weights must be 'uniform' or 'distance', got {show(self.weights)}")
        return {"neighbors": self.neighbors, "weights": self.weights}

    def _build(self, o: dict) -> None:
        from sklearn.neighbors import KNeighborsRegressor
        self.knn_ = KNeighborsRegressor(n_neighbors=min(o["neighbors"], len(self.X_)),
                                        weights=o["weights"]).fit(self.X_, self.Y_)

    def _predict(self, X):
        return self.knn_.predict(X)


@RIVALS.register
class RBFRival(_Neighbours):
    """Polyharmonic-spline interpolation (module docstring). Learned: the training poses ``X_``,
    ``Y_`` and ``rbf_`` (the ``RBFInterpolator``)."""

    kind, label = "rbf", "RBF interpolation"

    def __init__(self, neighbors: int = 32, kernel: str = "thin_plate_spline", smoothing: float = 0.0, *,
                 encoding: str = "arm_plane", max_out_of_plane: float = math.pi, random_state: int | None = None,
                 structure: str = "whole", closure_tolerance: float = 1e-4, affine_ridge: float = 1e-8,
                 pitch_closure: bool = True):
        self.neighbors = neighbors
        self.kernel = kernel
        self.smoothing = smoothing
        super().__init__(encoding=encoding, max_out_of_plane=max_out_of_plane, random_state=random_state,
                         structure=structure, closure_tolerance=closure_tolerance, affine_ridge=affine_ridge,
                         pitch_closure=pitch_closure)

    def _checked(self) -> dict:
        whole_number(self.kind, "neighbors", self.neighbors, 1, 10_000)
        if self.kernel not in _RBF_KERNELS:
            raise ValueError(f"rbf: kernel must be one of {', '.join(_RBF_KERNELS)}, got {show(self.kernel)}")
        finite_number(self.kind, "smoothing", self.smoothing, zero=True)
        return {"neighbors": self.neighbors, "kernel": self.kernel, "smoothing": self.smoothing}

    def _check_inputs(self, o: dict, d: int) -> None:
        if o["kernel"] == "quintic" and o["neighbors"] < (d + 1) * (d + 2) // 2:
            raise ValueError(f"rbf: the quintic kernel's degree-2 polynomial needs neighbors >= "
                             f"{(d + 1) * (d + 2) // 2} for the {d} inputs of {self.encoding!r}, got {o['neighbors']}")

    def _build(self, o: dict) -> None:
        from scipy.interpolate import RBFInterpolator
        # The lowest polynomial degree that makes each kernel's interpolant unique.
        self.rbf_ = RBFInterpolator(self.X_, self.Y_, neighbors=min(o["neighbors"], len(self.X_)),
                                    kernel=o["kernel"], smoothing=o["smoothing"],
                                    degree=2 if o["kernel"] == "quintic" else 1)

    def _predict(self, X):
        return self.rbf_(X)


@RIVALS.register
class MLPRival(RivalIK):
    """A multilayer perceptron kept at its best validation epoch (module docstring; ``fit`` needs
    ``val``). Learned: ``weights_`` and ``biases_`` (the kept epoch's layers), ``epochs_``,
    ``best_epoch_`` (0-based), ``y_mean_``, ``y_scale_``."""

    kind, label = "mlp", "multilayer perceptron"
    standardised, needs_val = True, True
    _state_keys = ("weights", "biases")

    def __init__(self, hidden: Sequence[int] = (128, 128), activation: str = "relu", alpha: float = 1e-4,
                 learning_rate: float = 1e-3, batch_size: int = 200, max_epochs: int = 300, patience: int = 10,
                 min_improvement: float = 0.0, *, encoding: str = "arm_plane", max_out_of_plane: float = math.pi,
                 random_state: int | None = None, structure: str = "whole", closure_tolerance: float = 1e-4,
                 affine_ridge: float = 1e-8, pitch_closure: bool = True):
        self.hidden = hidden
        self.activation = activation
        self.alpha = alpha
        self.learning_rate = learning_rate
        self.batch_size = batch_size
        self.max_epochs = max_epochs
        self.patience = patience
        self.min_improvement = min_improvement
        super().__init__(encoding=encoding, max_out_of_plane=max_out_of_plane, random_state=random_state,
                         structure=structure, closure_tolerance=closure_tolerance, affine_ridge=affine_ridge,
                         pitch_closure=pitch_closure)

    def _checked(self) -> dict:
        hidden = self.hidden
        if isinstance(hidden, (str, bytes)) or not isinstance(hidden, (list, tuple)) or not 1 <= len(hidden) <= 8 \
                or not all(is_integer(h) and 1 <= h <= 4096
                           for h in hidden):
            raise ValueError(f"mlp: hidden must be 1 to 8 layer widths in [1, 4096], got {show(hidden)}")
        if self.activation not in _ACTIVATIONS:
            raise ValueError(f"mlp: activation must be one of {', '.join(_ACTIVATIONS)}, got {show(self.activation)}")
        finite_number(self.kind, "alpha", self.alpha, zero=True)
        finite_number(self.kind, "learning_rate", self.learning_rate)
        whole_number(self.kind, "batch_size", self.batch_size, 1, 1_000_000)
        whole_number(self.kind, "max_epochs", self.max_epochs, 1, 100_000)
        whole_number(self.kind, "patience", self.patience, 1, 100_000)
        finite_number(self.kind, "min_improvement", self.min_improvement, zero=True)
        if self.min_improvement >= 1:
            raise ValueError(f"mlp: min_improvement must be below 1 (a share of the least error), "
                             f"got {show(self.min_improvement)}")
        return {"hidden": [int(h) for h in hidden], "activation": self.activation, "alpha": self.alpha,
                "learning_rate": self.learning_rate, "batch_size": self.batch_size, "max_epochs": self.max_epochs,
                "patience": self.patience, "min_improvement": self.min_improvement}

    def _learn(self, o, X, Z, X_val, Z_val) -> None:
        import warnings

        from sklearn.exceptions import ConvergenceWarning
        from sklearn.neural_network import MLPRegressor

        net = MLPRegressor(hidden_layer_sizes=tuple(o["hidden"]), activation=o["activation"], alpha=o["alpha"],
                           learning_rate_init=o["learning_rate"], batch_size=o["batch_size"],
                           random_state=self.random_state, shuffle=True)
        best, since, reference = math.inf, 0, math.inf
        # Trained in single precision, as neural networks are (1.7-1.8x faster than double for the 256- and
        # 512-unit layers, measured on 2 cores); the kept weights then predict in double (_predict).
        X32, Z32, X_val32 = (np.asarray(a, dtype=np.float32) for a in (X, Z, X_val))
        for epoch in range(o["max_epochs"]):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ConvergenceWarning)
                net.partial_fit(X32, Z32)
            self.epochs_ = epoch + 1
            error = float(np.sqrt(np.mean((net.predict(X_val32) - Z_val) ** 2)))
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

    def _predict(self, X):
        a = X
        for k, (W, b) in enumerate(zip(self.weights_, self.biases_)):
            a = a @ W + b
            if k < len(self.weights_) - 1:
                _ACTIVATIONS[self.options_["activation"]](a)
        return a

    def _state(self) -> dict:
        return {"weights": [json_ready(w) for w in self.weights_], "biases": [json_ready(b) for b in self.biases_]}

    def _read_state(self, v: Validator, state, d: int, n_out: int, o: dict) -> None:
        widths = [d, *o["hidden"], n_out]
        weights = v.sequence(state["weights"], "state.weights", min_len=len(widths) - 1, max_len=len(widths) - 1)
        biases = v.sequence(state["biases"], "state.biases", min_len=len(widths) - 1, max_len=len(widths) - 1)
        self.weights_ = [v.array(w, f"state.weights[{k}]", (widths[k], widths[k + 1])) for k, w in enumerate(weights)]
        self.biases_ = [v.array(b, f"state.biases[{k}]", (widths[k + 1],)) for k, b in enumerate(biases)]


@RIVALS.register
class KernelRidgeRival(RivalIK):
    """Kernel ridge regression with a Gaussian kernel (module docstring), in one of two ways
    (``length_scales``):

    * ``"shared"`` — one width for every input, ``exp(−gamma·‖x − x'‖²)``, approximated by
      ``components`` Nyström landmarks, the ridge's ``alpha`` given;
    * ``"fitted"`` — a Gaussian process: one length scale per input,
      ``k(x, x') = s²·exp(−½ Σ_i ((x_i − x'_i)/ℓ_i)²)`` plus a noise variance ``σ²``, these
      ``d + 2`` hyper-parameters chosen by maximising the log marginal likelihood on ``subset``
      training poses drawn with ``random_state`` (``sklearn.gaussian_process.GaussianProcessRegressor``,
      L-BFGS-B from ``ℓ = 1`` on inputs divided by their spread, ``restarts`` more starts drawn
      in the bounds :data:`GP_BOUNDS`), then the posterior mean on **all** training poses
      exactly, ``f(x) = k(x, X) (K + σ²I)⁻¹ Z`` (a Cholesky solve; ``components``, ``gamma`` and
      ``alpha`` unused). Its cost grows as ``subset³`` an iteration and ``N³`` once, its memory as
      ``N²`` (at most :data:`GP_MAX_POSES` training poses).

    Learned: ``landmarks_ (m, d)`` (the Nyström landmarks; fitted: every training pose, divided by
    ``length_scales_``), ``coef_ (m, n)`` (the weights with the Nyström normalisation, or
    ``s²``, folded in), ``intercept_``, ``y_mean_``, ``y_scale_``; fitted, also ``length_scales_
    (d,)`` (in the inputs' units), ``amplitude_`` (``s²``) and ``noise_`` (``σ²``, of the
    standardised angles).

    Example (a Gaussian process on 300 poses, its six length scales fitted on 200 of them):
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> from nfarm.model.kinematics import fk
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> q = np.random.default_rng(0).uniform(-0.5, 0.5, (300, 5))
        >>> model = KernelRidgeRival(length_scales="fitted", subset=200, random_state=0).fit(robot, {"T": fk(robot, q), "q": q})
        >>> bool(np.abs(model.predict(fk(robot, q[:50])) - q[:50]).max() < 0.01), model.length_scales_.shape
        (True, (6,))
    """

    kind, label = "kernel_ridge", "kernel ridge / Gaussian process"
    standardised = True
    _state_keys = ("landmarks", "coef", "intercept")
    _optional_state_keys = ("length_scales", "amplitude", "noise")
    #: Prediction's rows at a time (bounds the ``(rows, m)`` kernel matrix).
    PREDICT_ROWS = 2048

    def __init__(self, components: int = 2000, gamma: float = 10.0, alpha: float = 1e-6, *,
                 length_scales: str = "shared", subset: int = 500, restarts: int = 0,
                 encoding: str = "arm_plane", max_out_of_plane: float = math.pi, random_state: int | None = None,
                 structure: str = "whole", closure_tolerance: float = 1e-4, affine_ridge: float = 1e-8,
                 pitch_closure: bool = True):
        self.components = components
        self.gamma = gamma
        self.alpha = alpha
        self.length_scales = length_scales
        self.subset = subset
        self.restarts = restarts
        super().__init__(encoding=encoding, max_out_of_plane=max_out_of_plane, random_state=random_state,
                         structure=structure, closure_tolerance=closure_tolerance, affine_ridge=affine_ridge,
                         pitch_closure=pitch_closure)

    def _checked(self) -> dict:
        if self.length_scales not in ("shared", "fitted"):
            raise ValueError(f"kernel_ridge: length_scales must be 'shared' or 'fitted', got {show(self.length_scales)}")
        whole_number(self.kind, "components", self.components, 1, 50_000)
        finite_number(self.kind, "gamma", self.gamma)
        finite_number(self.kind, "alpha", self.alpha)
        whole_number(self.kind, "subset", self.subset, 2, GP_MAX_SUBSET)
        whole_number(self.kind, "restarts", self.restarts, 0, 20)
        return {"components": self.components, "gamma": self.gamma, "alpha": self.alpha,
                "length_scales": self.length_scales, "subset": self.subset, "restarts": self.restarts}

    def _learn(self, o, X, Z, X_val, Z_val) -> None:
        if o["length_scales"] == "fitted":
            self._learn_process(o, X, Z)
            return
        from sklearn.kernel_approximation import Nystroem
        from sklearn.linear_model import Ridge

        nystroem = Nystroem(kernel="rbf", gamma=o["gamma"], n_components=min(o["components"], len(X)),
                            random_state=self.random_state).fit(X)
        self.landmarks_ = nystroem.components_
        self.length_scales_ = self.amplitude_ = self.noise_ = None
        ridge = Ridge(alpha=o["alpha"]).fit(self._kernel(X, o["gamma"]) @ nystroem.normalization_.T, Z)
        # The features' normalisation folded into the weights: one (m, n) matrix to keep.
        self.coef_, self.intercept_ = nystroem.normalization_.T @ ridge.coef_.T, ridge.intercept_

    def _learn_process(self, o, X, Z) -> None:
        """The Gaussian process's hyper-parameters on a subset, then its posterior mean on all of ``X``."""
        import warnings

        if len(X) > GP_MAX_POSES:
            raise ValueError(f"kernel_ridge: length_scales 'fitted' solves on every training pose exactly, at most "
                             f"{GP_MAX_POSES} (an N x N kernel of {8 * GP_MAX_POSES ** 2 / 1e6:.0f} MB), got {len(X)}; "
                             f"for more, length_scales 'shared' (Nystrom)")

        from scipy.linalg import cho_factor, cho_solve
        from sklearn.exceptions import ConvergenceWarning
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

        spread = X.std(axis=0)
        spread = np.where(spread > 0, spread, 1.0)
        pick = np.sort(np.random.default_rng(self.random_state).permutation(len(X))[:min(o["subset"], len(X))])
        kernel = (ConstantKernel(1.0, GP_BOUNDS["amplitude"]) * RBF(np.ones(X.shape[1]), GP_BOUNDS["length_scale"])
                  + WhiteKernel(1e-4, GP_BOUNDS["noise"]))
        with warnings.catch_warnings():         # a length scale at its bound: an input the angles do not vary with
            warnings.simplefilter("ignore", ConvergenceWarning)
            process = GaussianProcessRegressor(kernel, n_restarts_optimizer=o["restarts"],
                                               random_state=self.random_state).fit(X[pick] / spread, Z[pick])
        fitted = process.kernel_
        self.length_scales_ = spread * fitted.k1.k2.length_scale
        self.amplitude_, self.noise_ = float(fitted.k1.k1.constant_value), float(fitted.k2.noise_level)
        self.landmarks_ = X / self.length_scales_
        K = self._kernel(X / self.length_scales_, 0.5)
        K *= self.amplitude_
        K[np.diag_indices_from(K)] += self.noise_ + process.alpha      # scikit-learn's own jitter too
        factor = cho_factor(K, lower=True, overwrite_a=True, check_finite=False)
        self.coef_ = self.amplitude_ * cho_solve(factor, Z, check_finite=False)
        self.intercept_ = np.zeros(Z.shape[1])

    def _kernel(self, X: np.ndarray, gamma: float) -> np.ndarray:
        """``K(X, landmarks) (N, m)``, the Gaussian kernel ``exp(−gamma·‖x − l‖²)`` of scaled inputs ``X (N, d)``."""
        d2 = X @ self.landmarks_.T
        d2 *= -2
        d2 += (X ** 2).sum(1)[:, None]
        d2 += (self.landmarks_ ** 2).sum(1)[None, :]
        np.maximum(d2, 0, out=d2)
        d2 *= -gamma
        return np.exp(d2, out=d2)

    def _predict(self, X):
        fitted = self.length_scales_ is not None
        gamma = 0.5 if fitted else self.options_["gamma"]
        out = np.empty((len(X), self.coef_.shape[1]))
        for start in range(0, len(X), self.PREDICT_ROWS):
            block = X[start:start + self.PREDICT_ROWS]
            out[start:start + len(block)] = self._kernel(block / self.length_scales_ if fitted else block, gamma) @ self.coef_
        return out + self.intercept_

    def _state(self) -> dict:
        fitted = {} if self.length_scales_ is None else {
            "length_scales": json_ready(self.length_scales_), "amplitude": self.amplitude_, "noise": self.noise_}
        return {**{k: json_ready(getattr(self, f"{k}_")) for k in self._state_keys}, **fitted}

    def _read_state(self, v: Validator, state, d: int, n_out: int, o: dict) -> None:
        self.landmarks_ = v.array(state["landmarks"], "state.landmarks", (None, d))
        m = len(self.landmarks_)
        self.coef_ = v.array(state["coef"], "state.coef", (m, n_out))
        self.intercept_ = v.array(state["intercept"], "state.intercept", (n_out,))
        self.length_scales_ = self.amplitude_ = self.noise_ = None
        if o["length_scales"] == "fitted":
            for key in self._optional_state_keys:
                if key not in state:
                    v.fail(f"state.{key}", "is required with length_scales 'fitted'")
            self.length_scales_ = v.array(state["length_scales"], "state.length_scales", (d,))
            if not (self.length_scales_ > 0).all():
                v.fail("state.length_scales", "must be > 0")
            self.amplitude_ = v.number(state["amplitude"], "state.amplitude", lo=0, lo_open=True)
            self.noise_ = v.number(state["noise"], "state.noise", lo=0)
        elif any(key in state for key in self._optional_state_keys):
            v.fail("state", "length_scales, amplitude and noise belong to length_scales 'fitted'")
