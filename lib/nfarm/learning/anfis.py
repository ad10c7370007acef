"""ANFIS: first-order Takagi–Sugeno fuzzy inference as an adaptive network (Jang 1993).

Five layers, for inputs ``x (n,)`` and rules r = 1..R:

1. membership grades ``μ_ik(x_i)`` (generalised bell or Gaussian, from scikit-fuzzy);
2. firing strengths ``w_r = Π_i μ_{i,k(r,i)}(x_i)`` (product of the rule's antecedents);
3. normalisation ``w̄_r = w_r / Σ_s w_s``;
4. consequents ``w̄_r f_r``, with ``f_r = p_r · x + p_r0``;
5. output ``y = Σ_r w̄_r f_r``.

Training is Jang's hybrid rule (:mod:`nfarm.learning.hybrid`, where its steps, their costs and
what was done about them are written down), once per epoch over the whole batch: **forward**,
the premise (membership) parameters fixed, the output is linear in the consequents, found by
least squares; **backward**, the consequents fixed, the premise parameters take one gradient
step of length k (``Δθ = −k ∇E / ‖∇E‖``), where the step size k grows by ``step_increase``
after four consecutive decreases of the training error and shrinks by ``step_decrease`` after
two consecutive up–down alternations. With validation data the model kept is the one with the
least validation error (MATLAB's ``chkFIS``), and ``patience`` stops training once that error
has not fallen for so many epochs.

Least squares: the consequents solve the normal equations ``(AᵀA + δI) θ = Aᵀy`` by Cholesky,
with a tiny ridge ``δ = ridge · tr(AᵀA)/P``; where they are ill-conditioned (scipy warns) the
design is solved by an orthogonal factorisation instead. ``solver="lstsq"`` always uses the
orthogonal factorisation. Chapter 4 measures both: on Jang's examples they reach the same
errors, and the normal equations are several times faster, which is why they are the default.

Memory is O(N · R) for the layers plus one block of the design ``N × R·(n + 1)`` (summed in
blocks when it would take more than 256 MB) and its normal equations, checked against
``memory_budget`` before any work.

**Premise inputs.** By default every input has membership functions and enters the
consequents. ``premise_inputs`` names the inputs the rules are built over; the others enter the
consequents only (each as if it had one "don't care" function, which cancels in layer 3) —
Takagi and Sugeno's (1985) own form, where the premise and the consequent variables differ.
Chapter 06 learns inverse dynamics this way: rules over the configuration ``q``, consequents
over products of ``q̈``, ``q̇`` and trigonometric functions of ``q``, hundreds of columns.

**Several outputs, shared premises.** :func:`fit_shared` trains one model per output column
whose rules share their membership functions (Jang, Sun & Mizutani 1997, §12.4): one
least-squares factorisation per epoch serves every output, which is most of the cost when the
consequents have hundreds of inputs. Each output's model is an ordinary :class:`ANFIS`.
"""

from __future__ import annotations

import itertools
import math
import os
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from . import hybrid
from .estimator import Estimator, model_file, write_model
from .fuzzy import (MF_TYPES, cluster_params, fcm_memberships, fuzzy_cmeans, grid_params, mf_rows,
                    mf_values, subtractive_clustering)
from ..infra.arguments import check_choice, check_integer, check_number, is_integer
from ..infra.reading import Validator, checked_content, json_ready, load_json, show

__all__ = ["ANFIS", "ANFISMulti", "ANFISWarning", "MF_TYPES", "PARTITIONS", "SOLVERS", "FILE_NAME", "load",
           "fit_shared"]

PARTITIONS = ("grid", "fcm", "subtractive")
SOLVERS = ("normal", "lstsq")
_FORMAT = "nfarm-anfis-1"
#: The file a model is saved as, in the directory given to ``save``.
FILE_NAME = "anfis.json"


# --------------------------------------------------------------------------------------------
# The estimator


class ANFISWarning(UserWarning):
    """A prediction is not backed by the training data (no rule fires)."""


class ANFIS(Estimator):
    """A first-order Sugeno ANFIS for one output, with a scikit-learn estimator interface.

    Args (those after ``partition`` keyword-only):
        n_mfs: membership functions per premise input (int, or one per premise input) for
            ``partition="grid"``.
        mf: ``"gbell"`` (generalised bell, MATLAB's default) or ``"gauss"``.
        partition: ``"grid"`` (every combination of the inputs' functions is a rule, MATLAB's
            ``genfis1``), ``"fcm"`` (one rule per fuzzy c-means cluster of the input–output
            data, ``genfis3``, scikit-fuzzy's ``cmeans`` iteration:
            :func:`nfarm.learning.fuzzy.fuzzy_cmeans`) or ``"subtractive"`` (one rule per
            subtractive cluster, Chiu 1994, ``genfis2``).
        n_rules: clusters (rules) for ``"fcm"``.
        fcm_tolerance: fuzzy c-means stops once its membership matrix changes by less than
            this in an iteration (Frobenius norm over clusters × samples, scikit-fuzzy's
            ``error``), or after ``fcm_max_iter`` iterations. Measured on 3 000 arm-plane poses
            with 20 clusters: 1e-3 stops after 373 iterations and 1e-6 after 757, with the
            objective equal to 7 digits (94.33377 against 94.33375): the default halves the
            partition's cost, which dominated an fcm model's training.
        fcm_samples: fuzzy c-means places its centres on at most this many samples, drawn
            without replacement with ``random_state`` (``None``: all); the memberships and the
            clusters' spreads are then computed on every sample from those centres. The
            iterations cost O(samples × clusters) each. Measured on intelbot5's 20 000
            arm-plane training poses, 20 clusters, 10 epochs, seeds 0–2, one thread: the
            worst joint's validation RMSE is 1.40–1.50° from 3 000 samples against 1.40–1.41°
            from all (1.44–1.62° from 1 000, 1.37–1.54° from 5 000), at a fraction of the
            clustering's cost (``benchmarks/bench_anfis_train.py`` times the phases of a fit).
        radius: cluster radius for ``"subtractive"``, in the unit hypercube of the data.
        epochs: training epochs.
        step_size, step_increase, step_decrease: Jang's step size k and its factors.
        error_goal: stop once the training RMSE is at or below it.
        solver: least squares by ``"normal"`` equations (default) or ``"lstsq"``.
        ridge: relative ridge of the normal equations.
        memory_budget: bytes the N × R × (n + 1) design matrix (and its companions) may take.
        random_state: seed for the clustering partitions.
        feature_names: names of the inputs (default ``x1``, ``x2``, …), used by ``describe``.
        progress: show a progress bar over the epochs (tqdm; in a notebook, a widget).
        premise_inputs: the columns of ``X`` the rules are built over (``None``: all); every
            column enters the consequents.
        patience: stop once the validation error (the training error without validation
            data) has not fallen for this many epochs (``None``: train every epoch); the best
            epoch is kept either way.
        min_improvement: for ``patience``, a fall counts only if it takes the error below its
            least so far by at least this share of it (0: any fall; 0.005: half a per cent —
            Keras's ``min_delta``, relative). Jang's rule can creep down by a hundredth of a
            per cent an epoch for hundreds of epochs; this stops it where it has converged.

    Learned attributes: ``mfs_`` (per premise input, ``(m_i, p)`` parameters),
    ``rules_ (R, n_p)`` (the function of each premise input in each rule),
    ``consequents_ (R, n + 1)``,
    ``mfs_initial_``, ``loss_curve_`` (training RMSE per epoch), ``val_loss_curve_``,
    ``step_size_curve_``, ``best_epoch_``, ``n_features_in_``, ``feature_names_in_``.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> X = rng.uniform(-1, 1, (500, 2))
        >>> y = np.sin(2 * X[:, 0]) * np.cos(X[:, 1])                 # values in [-1, 1]
        >>> model = ANFIS(n_mfs=3, mf="gauss", epochs=20)            # a 3 × 3 grid: 9 rules
        >>> model.fit(X[:400], y[:400])
        ANFIS(n_mfs=3, mf='gauss', epochs=20)
        >>> model.rules_.shape, model.consequents_.shape    # (rules, inputs), (rules, inputs + 1)
        ((9, 2), (9, 3))
        >>> model.predict(X[400:]).shape
        (100,)
        >>> rmse = np.sqrt(np.mean((model.predict(X[400:]) - y[400:]) ** 2))
        >>> bool(rmse < 0.01)               # on 100 points not trained on: within 1 % of the range
        True
    """

    _fitted = "consequents_"

    def __init__(self, n_mfs: int | Sequence[int] = 2, mf: str = "gbell", partition: str = "grid", *,
                 n_rules: int | None = None, radius: float = 0.5, epochs: int = 10,
                 fcm_tolerance: float = 1e-3, fcm_max_iter: int = 1000,
                 fcm_samples: int | None = 3000,
                 step_size: float = 0.01, step_increase: float = 1.1, step_decrease: float = 0.9,
                 error_goal: float = 0.0, solver: str = "normal", ridge: float = 1e-12,
                 memory_budget: float = 2e9, random_state: int | None = None,
                 feature_names: Sequence[str] | None = None, progress: bool = False,
                 premise_inputs: Sequence[int] | None = None, patience: int | None = None,
                 min_improvement: float = 0.0):
        self.n_mfs = n_mfs
        self.mf = mf
        self.partition = partition
        self.n_rules = n_rules
        self.radius = radius
        self.epochs = epochs
        self.fcm_tolerance = fcm_tolerance
        self.fcm_max_iter = fcm_max_iter
        self.fcm_samples = fcm_samples
        self.step_size = step_size
        self.step_increase = step_increase
        self.step_decrease = step_decrease
        self.error_goal = error_goal
        self.solver = solver
        self.ridge = ridge
        self.memory_budget = memory_budget
        self.random_state = random_state
        self.feature_names = feature_names
        self.progress = progress
        self.premise_inputs = premise_inputs
        self.patience = patience
        self.min_improvement = min_improvement

    # -- validation ---------------------------------------------------------------------------

    def _check_options(self, n_features: int) -> list[int]:
        check_choice("mf", self.mf, MF_TYPES)
        check_choice("partition", self.partition, PARTITIONS)
        check_choice("solver", self.solver, SOLVERS)
        for name in ("step_size", "step_increase", "step_decrease", "radius", "memory_budget",
                     "fcm_tolerance"):
            check_number(name, getattr(self, name), 0, None, open_lo=True)
        check_integer("fcm_max_iter", self.fcm_max_iter, 1)
        check_integer("fcm_samples", self.fcm_samples, 2, or_none=True)
        check_integer("epochs", self.epochs, 1)
        check_integer("patience", self.patience, 1, or_none=True)
        check_number("min_improvement", self.min_improvement, 0, 1, open_lo=False)
        for name in ("error_goal", "ridge"):
            check_number(name, getattr(self, name), 0, None, open_lo=False)
        if self.partition == "fcm":
            check_integer("n_rules", self.n_rules, 2,
                          message=f"partition 'fcm' needs n_rules (an integer) >= 2, got {self.n_rules!r}")
        premise = self._premise(n_features)
        if is_integer(self.n_mfs):
            n_mfs = [self.n_mfs] * len(premise)
        elif isinstance(self.n_mfs, (Sequence, np.ndarray)) and not isinstance(self.n_mfs, str):
            n_mfs = list(self.n_mfs)
        else:
            n_mfs = []
        if len(n_mfs) != len(premise) or not all(is_integer(m) and m >= 1 for m in n_mfs):
            raise ValueError(f"n_mfs must be an integer >= 1 or one per premise input ({len(premise)}), "
                             f"got {self.n_mfs!r}")
        if self.feature_names is not None and len(self.feature_names) != n_features:
            raise ValueError(f"feature_names has {len(self.feature_names)} names for {n_features} inputs")
        return [int(m) for m in n_mfs]

    def _premise(self, n_features: int) -> np.ndarray:
        """The premise inputs' column indices (validated)."""
        if self.premise_inputs is None:
            return np.arange(n_features)
        given = self.premise_inputs
        if isinstance(given, (str, bytes)) or not isinstance(given, (Sequence, np.ndarray)) or \
                len(given) == 0 or not all(is_integer(i) and 0 <= i < n_features for i in given) \
                or len(set(int(i) for i in given)) != len(given):
            raise ValueError(f"premise_inputs must be None or distinct column indices in 0..{n_features - 1}, "
                             f"got {given!r}")
        return np.array([int(i) for i in given])

    @staticmethod
    def _check_data(X, y, what: str = "X") -> tuple[np.ndarray, np.ndarray | None]:
        X = np.asarray(X, dtype=float)
        if X.ndim != 2 or X.shape[0] == 0 or X.shape[1] == 0:
            raise ValueError(f"{what} must be a 2-D array (samples, inputs), got shape {X.shape}")
        if not np.isfinite(X).all():
            row = int(np.argmax(~np.isfinite(X).all(axis=1)))
            raise ValueError(f"{what} contains NaN or inf (first in row {row})")
        if y is None:
            return X, None
        y = np.asarray(y, dtype=float)
        if y.ndim == 2 and y.shape[1] == 1:
            y = y[:, 0]
        if y.ndim != 1 or len(y) != len(X):
            raise ValueError(f"y{'' if what == 'X' else '_val'} must have shape ({len(X)},) to match "
                             f"{what}, got {y.shape}")
        if not np.isfinite(y).all():
            raise ValueError(f"y{'' if what == 'X' else '_val'} contains NaN or inf "
                             f"(first at {int(np.argmax(~np.isfinite(y)))})")
        return X, y

    # -- structure ----------------------------------------------------------------------------

    def _initial_structure(self, X, y, n_mfs):
        """Membership functions and rules over the premise columns ``X (N, n_p)``."""
        lo, hi = X.min(axis=0), X.max(axis=0)
        if self.partition == "grid":
            mfs = [grid_params(self.mf, lo[i], hi[i], n_mfs[i]) for i in range(X.shape[1])]
            rules = np.array(list(itertools.product(*(range(m) for m in n_mfs))), dtype=int)
            return mfs, rules
        data = np.column_stack([X, y])
        if self.partition == "fcm":
            sample = data
            if self.fcm_samples is not None and len(data) > self.fcm_samples:
                rng = np.random.default_rng(self.random_state)
                sample = data[np.sort(rng.choice(len(data), self.fcm_samples, replace=False))]
            centres, u, _ = fuzzy_cmeans(sample, self.n_rules, m=2.0, tolerance=self.fcm_tolerance,
                                         max_iter=self.fcm_max_iter, seed=self.random_state)
            if sample is not data:
                u = fcm_memberships(data, centres)
            um = u**2                                               # (c, N), fuzzifier m = 2
            spread = (um[:, :, None] * (X[None] - centres[:, None, :X.shape[1]]) ** 2).sum(1) / um.sum(1)[:, None]
            sigmas = np.sqrt(np.maximum(spread, 1e-12 * (hi - lo) ** 2))      # (c, n)
            centres = centres[:, :X.shape[1]]
        else:
            centres = subtractive_clustering(data, self.radius,
                                             max_centres=self._max_rules(len(X), X.shape[1]))
            if centres is None:
                raise ValueError(
                    f"subtractive clustering with radius {self.radius!r} finds more than "
                    f"{self._max_rules(len(X), X.shape[1])} clusters, more rules than {len(X)} "
                    f"samples of {X.shape[1]} inputs can fit within memory_budget: use a larger "
                    f"radius or more data")
            centres = centres[:, :X.shape[1]]
            sigmas = np.broadcast_to(self.radius * (hi - lo) / math.sqrt(8.0), centres.shape)
        R = len(centres)
        mfs = [cluster_params(self.mf, centres[:, i], sigmas[:, i]) for i in range(X.shape[1])]
        rules = np.tile(np.arange(R)[:, None], (1, X.shape[1]))
        return mfs, rules

    def _bytes_needed(self, N, R, n, n_p=None, k=1):
        """Training memory of ``k`` outputs: the layers (firing strengths, their normalised
        and log forms, the outputs' rule values, the gradient's weights: ``(k + 5) N R``
        numbers, and ``3 N R`` for a bell's derivatives), one block of the consequents'
        design and its normal equations (:mod:`nfarm.learning.hybrid`)."""
        P = R * (n + 1)
        rows = min(N, max(1, hybrid.DESIGN_BYTES // (8 * P)))
        layers = (k + 5 + (3 if self.mf == "gbell" else 0)) * N * R
        return 8.0 * (layers + rows * P + P ** 2 + 2 * P * k)

    # -- fitting ------------------------------------------------------------------------------

    def fit(self, X, y, X_val=None, y_val=None) -> "ANFIS":
        """Train on ``X (N, n)``, ``y (N,)`` (optionally validating on ``X_val``, ``y_val``).

        Raises:
            ValueError: bad data or options, too few samples for the consequent parameters, a
                constant input, or a model that would not fit in ``memory_budget``.
        """
        return self._train(*self._checked(X, y, X_val, y_val, shared=False))[0]

    def _checked(self, X, y, X_val, y_val, shared: bool):
        """The data as ``X (N, n)``, ``Y (N, k)``, the validation data and the functions per
        premise input, checked with the options and the model's size before anything is built."""
        if shared:
            X, _ = self._check_data(X, None)
            Y = _check_outputs(y, len(X), "Y")
        else:
            X, y = self._check_data(X, y)
            Y = y[:, None]
        n = X.shape[1]
        n_mfs = self._check_options(n)
        if (X_val is None) != (y_val is None):
            raise ValueError(f"give both X_val and {'Y' if shared else 'y'}_val, or neither")
        Y_val = None
        if X_val is not None:
            if shared:
                X_val, _ = self._check_data(X_val, None, "X_val")
                Y_val = _check_outputs(y_val, len(X_val), "Y_val", Y.shape[1])
            else:
                X_val, y_val = self._check_data(X_val, y_val, "X_val")
                Y_val = y_val[:, None]
            if X_val.shape[1] != n:
                raise ValueError(f"X_val has {X_val.shape[1]} inputs, X has {n}")
        premise = self._premise(n)
        constant = premise[np.flatnonzero(np.ptp(X[:, premise], axis=0) == 0)]
        if constant.size:
            raise ValueError(f"input {constant[0]} ({self._names(n)[constant[0]]}) is constant: "
                             f"membership functions need a range")
        # Refuse before building anything: the grid and fcm rule counts are known; subtractive
        # clustering stops (with the same error) once it finds more centres than fit.
        if self.partition == "grid":
            self._check_size(len(X), math.prod(n_mfs), n, len(premise), Y.shape[1])
        elif self.partition == "fcm":
            self._check_size(len(X), int(self.n_rules), n, len(premise), Y.shape[1])
        return X, Y, X_val, Y_val, n_mfs

    def _train(self, X, Y, X_val, Y_val, n_mfs) -> list["ANFIS"]:
        """One fitted model per column of ``Y`` (``self`` the first), sharing their premises
        (data checked by :meth:`_checked`)."""
        n = X.shape[1]
        premise = self._premise(n)
        Xp = np.ascontiguousarray(X[:, premise]) if self.premise_inputs is not None else X
        Xp_val = None if X_val is None else (np.ascontiguousarray(X_val[:, premise])
                                             if self.premise_inputs is not None else X_val)
        mfs, rules = self._initial_structure(Xp, Y[:, 0] if Y.shape[1] == 1 else Y, n_mfs)
        options = hybrid.Options(mf=self.mf, epochs=int(self.epochs), step_size=self.step_size,
                                 step_increase=self.step_increase, step_decrease=self.step_decrease,
                                 error_goal=self.error_goal, solver=self.solver, ridge=self.ridge,
                                 patience=self.patience, min_improvement=self.min_improvement,
                                 progress=self.progress)
        outputs, steps = hybrid.train(Xp, X, Y, mfs, rules, options, Xp_val, X_val, Y_val)
        models = [self] + [type(self)(**self.get_params()) for _ in outputs[1:]]
        for model, out in zip(models, outputs):
            model.n_features_in_ = n
            model.feature_names_in_ = np.array(self._names(n), dtype=object)
            model.rules_ = rules
            model.mfs_initial_ = [p.copy() for p in mfs]
            model.loss_curve_, model.val_loss_curve_ = out.loss_curve, out.val_loss_curve
            model.step_size_curve_ = list(steps)
            model.mfs_, model.consequents_, model.best_epoch_ = out.mfs, out.consequents, out.best_epoch
            model.n_epochs_ = len(out.loss_curve)
        return models

    def _max_rules(self, N, n):
        """The most rules that N samples of n inputs can fit within the memory budget."""
        R = N // (n + 1)
        n_p = len(self._premise(n))
        while R > 0 and self._bytes_needed(N, R, n, n_p) > self.memory_budget:
            R = min(R - 1, int(R * 0.9))
        return max(R, 0)

    def _check_size(self, N, R, n, n_p=None, k=1):
        if N < R * (n + 1):
            raise ValueError(f"{N} samples are fewer than the {R * (n + 1)} consequent parameters "
                             f"({R} rules × {n + 1}): use fewer rules or more data")
        need = self._bytes_needed(N, R, n, n_p, k)
        if need > self.memory_budget:
            raise ValueError(f"{N} samples × {R} rules × {n + 1} would need about "
                             f"{need / 1e9:.2f} GB, over memory_budget = "
                             f"{self.memory_budget / 1e9:.2f} GB: use fewer samples or rules, "
                             f"or raise memory_budget")

    def _adapt_step(self, step):
        """Jang's rule on the last five training errors (:func:`nfarm.learning.hybrid.adapted_step`)."""
        return hybrid.adapted_step(step, self.loss_curve_, self.step_increase, self.step_decrease)

    # -- prediction ---------------------------------------------------------------------------

    def _grid_sizes(self) -> list[int] | None:
        """Functions per input when the rules are the full grid in :func:`grid_rules` order
        (the last input varying fastest), else None."""
        sizes = [len(p) for p in self.mfs_]
        if len(self.rules_) == math.prod(sizes) and np.array_equal(
                self.rules_, np.indices(sizes).reshape(len(sizes), -1).T):
            return sizes
        return None

    def _firing(self, X, sizes=None):
        """Firing strengths ``w (R', N)`` of the fitted rules for premise inputs ``X (N, n_p)``, laid out
        rule by rule, for prediction (``sizes``: of a grid, see below).

        Laid out for prediction rather than for training (:func:`nfarm.learning.hybrid.firing`): a grid partition's strengths are built as successive outer products of the
        inputs' grades (``N·R`` products instead of ``N·R·n``), and an input with a single
        function is left out — its grade is a common factor of every rule and cancels in the
        normalisation. Rules in rows make every product run over the ``N`` samples
        (measured: 3.5× faster than samples in rows, where the innermost loops are only
        ``m`` long). Equal to the training path's to rounding (≈1e-16 relative).

        With ``sizes`` given (a grid's), the grades of the grid's last input with more than
        one function are left out as well and returned: ``w (R / m_L, N)`` and ``mu_L (m_L,
        N)`` (``None`` if every input has a single function).
        """
        if sizes is not None:
            inputs = [i for i, m in enumerate(sizes) if m > 1]
            if not inputs:
                return np.ones((1, len(X))), None
            w = None
            for i in inputs[:-1]:
                mu = mf_rows(self.mf, X[:, i], self.mfs_[i])
                w = mu if w is None else (w[:, None, :] * mu[None, :, :]).reshape(-1, len(X))
            last = mf_rows(self.mf, X[:, inputs[-1]], self.mfs_[inputs[-1]])
            return (np.ones((1, len(X))) if w is None else w), last
        w = None
        for i in range(X.shape[1]):
            factor = mf_rows(self.mf, X[:, i], self.mfs_[i])[self.rules_[:, i]]
            w = factor if w is None else np.multiply(w, factor, out=w)
        return w

    def _predict_fast(self, X):
        """Outputs ``(N,)`` and total firing ``(N,)`` of inputs ``X (N, n)`` (validated), in
        blocks of rows whose firing strengths and their companions (about ``8 · R · (n_p + 3)``
        bytes a row) take at most an eighth of ``memory_budget``, so that memory stays bounded
        whatever the rule count and batch size, with eight prediction threads side by side
        (:meth:`nfarm.learning.learned.LearnedIK.predict`). At the default 2 GB a 128-rule model over
        seven inputs predicts up to 24 414 rows in one block, a 20 000-rule one 156."""
        R, n_p = len(self.consequents_), len(self._premise(X.shape[1]))
        rows = max(1, int(self.memory_budget / 8 / (8.0 * R * (n_p + 3))))
        if len(X) <= rows:
            return self._predict_block(X)
        parts = [self._predict_block(X[start:start + rows]) for start in range(0, len(X), rows)]
        return np.concatenate([y for y, _ in parts]), np.concatenate([t for _, t in parts])

    def _predict_block(self, X):
        """:meth:`_predict_fast` on one block:
        ``y = Σ_r w_r (p_r · x + p_r0) / Σ_r w_r``, the rule sum as one matrix product
        ``(Θᵀ w) · [x, 1]`` with the total firing as one more row of it (Θ gains a column of
        ones).

        A grid's last product is never formed: with ``w_(s,k) = w'_s μ_k`` (``k`` the last
        input's function), ``Σ_r Θ_r w_r = Σ_k μ_k (Θ_(·,k)ᵀ w')``, one matrix product on
        the ``R / m_L`` partial strengths and ``m_L`` scaled sums: ``m_L`` times fewer products
        per rule (``benchmarks/bench_anfis.py`` measures the prediction). Equal to the training
        path's outputs to rounding (tested).
        """
        n = X.shape[1]
        theta = np.column_stack([self.consequents_, np.ones(len(self.consequents_))])  # (R, n+2)
        sizes = self._grid_sizes()
        Xp = X if self.premise_inputs is None else X[:, self._premise(n)]
        if sizes is None:
            coefficients = theta.T @ self._firing(Xp)                          # (n + 2, N)
        else:
            w, mu = self._firing(Xp, sizes)
            if mu is None:
                coefficients = theta.T @ w
            else:
                m = len(mu)
                A = theta.reshape(-1, m, n + 2).transpose(1, 2, 0).reshape(m * (n + 2), -1)
                partial = (A @ w).reshape(m, n + 2, len(X))
                coefficients = partial[0] * mu[0]
                for k in range(1, m):
                    coefficients += partial[k] * mu[k]
        total = coefficients[-1]
        y = np.einsum("kn,nk->n", coefficients[:n], X) + coefficients[n]
        return y / np.where(total > 0, total, 1.0), total

    def predict(self, X) -> np.ndarray:
        """Outputs ``(N,)`` for inputs ``X (N, n)``."""
        self._check_fitted()
        X, _ = self._check_data(X, None)
        if X.shape[1] != self.n_features_in_:
            raise ValueError(f"X has {X.shape[1]} inputs, the model was fitted with {self.n_features_in_}")
        y, total = self._predict_fast(X)
        silent = np.flatnonzero(total == 0)
        if silent.size:
            warnings.warn(ANFISWarning(
                f"{silent.size} of {len(X)} inputs (first: row {silent[0]}) fire no rule — "
                f"far outside the training data — and are predicted as 0"), stacklevel=2)
        return y

    def score(self, X, y) -> float:
        """Coefficient of determination R² of the predictions."""
        X, y = self._check_data(X, y)
        residual = ((y - self.predict(X)) ** 2).sum()
        total = ((y - y.mean()) ** 2).sum()
        return float(1.0 - residual / total) if total > 0 else float(residual == 0)

    # -- reading the model --------------------------------------------------------------------

    def _names(self, n):
        return list(self.feature_names) if self.feature_names is not None else [f"x{i + 1}" for i in range(n)]

    def describe(self, output: str = "y", digits: int = 4) -> str:
        """The rules in words: ``IF x1 is MF2 AND x2 is MF1 THEN y = … x1 + … x2 + …``."""
        self._check_fitted()
        names = list(self.feature_names_in_)
        premise_names = [names[i] for i in self._premise(len(names))]
        lines = []
        for r, (antecedent, p) in enumerate(zip(self.rules_, self.consequents_)):
            premise = " AND ".join(f"{name} is MF{k + 1}" for name, k in zip(premise_names, antecedent))
            terms = " ".join(f"{'+' if c >= 0 else '−'} {abs(c):.{digits}g}·{name}" for c, name in zip(p[:-1], names))
            lines.append(f"Rule {r + 1}: IF {premise} THEN {output} = {terms} "
                         f"{'+' if p[-1] >= 0 else '−'} {abs(p[-1]):.{digits}g}".replace("=  + ", "= "))
        return "\n".join(lines)

    def plot_mfs(self, *, points: int = 400):
        """The membership functions of every input, before (dashed) and after training."""
        import matplotlib.pyplot as plt

        self._check_fitted()
        premise = self._premise(self.n_features_in_)
        n = len(premise)
        fig, axes = plt.subplots(1, n, figsize=(3.3 * n, 2.8), layout="constrained", squeeze=False)
        for i, ax in enumerate(axes[0]):
            centres = self.mfs_initial_[i][:, -1]
            span = max(np.ptp(centres), np.abs(self.mfs_initial_[i][:, 0]).max())
            x = np.linspace(centres.min() - 0.6 * span, centres.max() + 0.6 * span, points)
            for k, (before, after) in enumerate(zip(mf_values(self.mf, x, self.mfs_initial_[i]).T,
                                                    mf_values(self.mf, x, self.mfs_[i]).T)):
                ax.plot(x, before, "--", color=f"C{k % 10}", lw=1)
                ax.plot(x, after, "-", color=f"C{k % 10}", lw=1.6, label=f"MF{k + 1}")
            ax.set(title=self.feature_names_in_[premise[i]], ylim=(-0.03, 1.05))
            ax.grid(alpha=0.3)
        axes[0, 0].set_ylabel("membership (dashed: initial)")
        return fig

    # -- persistence --------------------------------------------------------------------------

    def to_dict(self) -> dict:
        self._check_fitted()
        return {"format": _FORMAT, "class": type(self).__name__, "params": json_ready(self.get_params()),
                "state": {"mfs": [p.tolist() for p in self.mfs_], "rules": self.rules_.tolist(),
                          "consequents": self.consequents_.tolist(),
                          "feature_names": list(self.feature_names_in_),
                          "loss_curve": self.loss_curve_, "val_loss_curve": self.val_loss_curve_,
                          "step_size_curve": self.step_size_curve_, "best_epoch": self.best_epoch_,
                          "mfs_initial": [p.tolist() for p in self.mfs_initial_]}}

    @classmethod
    def from_dict(cls, data: Any, source: str = "<dict>") -> "ANFIS":
        """The model that :meth:`to_dict` described, checked like a parameter file: schema,
        shapes, finite values, index ranges (errors name ``source`` and the field)."""
        v = Validator(source)
        _check_header(v, data, cls.__name__, "", ("params", "state"))
        s = v.mapping(data["state"], "state", dict.fromkeys(_STATE_KEYS, True))
        names = [v.string(x, f"state.feature_names[{i}]")
                 for i, x in enumerate(v.sequence(s["feature_names"], "state.feature_names",
                                                  min_len=1, max_len=10_000))]
        n = len(names)
        params = _check_params(v, data["params"], "params", n_features=n)
        model = cls(**params)
        n_p = len(model._premise(n))
        p = 3 if params["mf"] == "gbell" else 2
        mfs = {}
        for key in ("mfs", "mfs_initial"):
            mfs[key] = [v.array(m, f"state.{key}[{i}]", (None, p)) for i, m in
                        enumerate(v.sequence(s[key], f"state.{key}", min_len=n_p, max_len=n_p))]
            for i, m in enumerate(mfs[key]):
                if len(m) == 0 or (m[:, 0] <= 0).any() or (p == 3 and (m[:, 1] <= 0).any()):
                    v.fail(f"state.{key}[{i}]", f"must hold at least one {params['mf']} function "
                                                f"with positive widths{' and slopes' if p == 3 else ''}")
        sizes = np.array([len(m) for m in mfs["mfs"]])
        if not np.array_equal(sizes, [len(m) for m in mfs["mfs_initial"]]):
            v.fail("state.mfs_initial", "must have as many functions per input as state.mfs")
        if isinstance(s["rules"], list) and len(s["rules"]) > MAX_SAVED_RULES:
            v.fail("state.rules", f"holds {len(s['rules']):,} rules, over the {MAX_SAVED_RULES:,} a saved model may "
                                  f"hold (no model here has more than 4 096; each rule costs every prediction)")
        rules = v.array(s["rules"], "state.rules", (None, n_p), integer=True)
        if len(rules) == 0:
            v.fail("state.rules", "must hold at least one rule")
        distinct, first = np.unique(rules, axis=0, return_index=True)
        if len(distinct) < len(rules):
            again = int(np.setdiff1d(np.arange(len(rules)), first)[0])
            v.fail(f"state.rules[{again}]", "repeats an earlier rule: a saved model's rules are distinct")
        bad = (rules < 0) | (rules >= sizes)
        if bad.any():
            r, i = np.argwhere(bad)[0]
            v.fail(f"state.rules[{r}][{i}]", f"must index one of input {i}'s {sizes[i]} "
                                             f"functions (0..{sizes[i] - 1}), got {rules[r, i]}")
        consequents = v.array(s["consequents"], "state.consequents", (len(rules), n + 1))
        if np.abs(consequents).max() > MAX_CONSEQUENT:
            r, c = np.unravel_index(int(np.argmax(np.abs(consequents))), consequents.shape)
            v.fail(f"state.consequents[{r}][{c}]", f"must lie within ±{MAX_CONSEQUENT:g}, got "
                                                   f"{float(consequents[r, c])!r} (a prediction from it overflows)")
        curves = {key: v.array(s[key], f"state.{key}", (None,)).tolist()
                  for key in ("loss_curve", "val_loss_curve", "step_size_curve")}
        if not curves["loss_curve"]:
            v.fail("state.loss_curve", "must hold the training error of at least one epoch")
        best = v.integer(s["best_epoch"], "state.best_epoch", lo=0, hi=len(curves["loss_curve"]) - 1)
        model.mfs_, model.mfs_initial_ = mfs["mfs"], mfs["mfs_initial"]
        model.rules_ = rules.astype(int)
        model.consequents_ = consequents
        model.feature_names_in_ = np.array(names, dtype=object)
        model.n_features_in_ = n
        model.loss_curve_, model.val_loss_curve_ = curves["loss_curve"], curves["val_loss_curve"]
        model.step_size_curve_, model.best_epoch_ = curves["step_size_curve"], best
        model.n_epochs_ = len(model.loss_curve_)
        return model

    def save(self, directory: str | os.PathLike) -> Path:
        """Write the model as ``directory/anfis.json`` (:data:`FILE_NAME`; JSON, atomically) and
        return the file's path; :func:`load` of the directory reproduces its predictions bit for
        bit."""
        return write_model(directory, FILE_NAME, self.to_dict())


def _check_outputs(Y, N: int, what: str, k: int | None = None) -> np.ndarray:
    """``Y`` as a finite ``(N, k)`` array of at least one column, or a one-line error."""
    Y = np.asarray(Y, dtype=float)
    if Y.ndim != 2 or len(Y) != N or Y.shape[1] == 0 or (k is not None and Y.shape[1] != k):
        want = f"({N}, {k})" if k is not None else f"({N}, outputs)"
        raise ValueError(f"{what} must have shape {want}, got {Y.shape}")
    if not np.isfinite(Y).all():
        raise ValueError(f"{what} contains NaN or inf (first in row {int(np.argmax(~np.isfinite(Y).all(axis=1)))})")
    return Y


def fit_shared(model: ANFIS, X, Y, X_val=None, Y_val=None) -> list[ANFIS]:
    """One fitted :class:`ANFIS` per column of ``Y (N, k)``, with ``model``'s parameters, whose
    rules share their membership functions during training (a multiple-output ANFIS, Jang, Sun
    & Mizutani 1997, §12.4; :mod:`nfarm.learning.hybrid`): the premises are built on
    ``[X, Y]`` (fuzzy c-means and subtractive clusters) or on ``X`` (grids) and follow the
    gradient of the outputs' errors each weighed by ``1 / var(y_k)``; each output keeps its own
    consequents and its own best validation epoch (so the returned models' premises are those of
    their best epochs). ``model`` itself becomes the first of them. One least-squares
    factorisation per epoch serves every output: for ``k`` outputs of a model with many
    consequent inputs, about ``k`` times less work than ``k`` separate fits.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> X = rng.uniform(-1, 1, (400, 2))
        >>> Y = np.column_stack([np.sin(2 * X[:, 0]), X[:, 0] * X[:, 1]])
        >>> models = fit_shared(ANFIS(n_mfs=3, mf="gauss", epochs=5), X, Y)
        >>> [bool(np.sqrt(np.mean((m.predict(X) - y) ** 2)) < 0.05) for m, y in zip(models, Y.T)]
        [True, True]
        >>> all(np.array_equal(a, b) for a, b in zip(models[0].mfs_initial_, models[1].mfs_initial_))
        True

    Raises:
        ValueError: as :meth:`ANFIS.fit`, and ``Y`` not ``(N, k)``.
    """
    return model._train(*model._checked(X, Y, X_val, Y_val, shared=True))


class ANFISMulti(Estimator):
    """One :class:`ANFIS` per output column, as the dissertation's one-FIS-per-joint design.

    ``ANFISMulti(**params)`` passes ``params`` to every model; ``models_`` holds them.
    """

    _fitted = "models_"
    _passed_to = ANFIS

    def __init__(self, **params):
        self.params = params

    def fit(self, X, Y, X_val=None, Y_val=None) -> "ANFISMulti":
        Y = np.asarray(Y, dtype=float)
        if Y.ndim != 2:
            raise ValueError(f"Y must be (samples, outputs), got shape {Y.shape}")
        Y_val = None if Y_val is None else np.asarray(Y_val, dtype=float)
        self.models_ = [ANFIS(**self.params).fit(X, Y[:, k], X_val, None if Y_val is None else Y_val[:, k])
                        for k in range(Y.shape[1])]
        return self

    def predict(self, X) -> np.ndarray:
        self._check_fitted()
        return np.column_stack([m.predict(X) for m in self.models_])

    def to_dict(self) -> dict:
        return {"format": _FORMAT, "class": "ANFISMulti", "params": json_ready(self.params),
                "models": [m.to_dict() for m in self.models_]}

    @classmethod
    def from_dict(cls, data: Any, source: str = "<dict>") -> "ANFISMulti":
        v = Validator(source)
        _check_header(v, data, cls.__name__, "", ("params", "models"))
        multi = cls(**_check_params(v, data["params"], "params", n_features=None))
        models = v.sequence(data["models"], "models", min_len=1, max_len=10_000)
        multi.models_ = [ANFIS.from_dict(m, f"{source}: models[{k}]") for k, m in enumerate(models)]
        return multi

    def save(self, directory: str | os.PathLike) -> Path:
        """Write every model as ``directory/anfis.json`` (as :meth:`ANFIS.save`)."""
        return write_model(directory, FILE_NAME, self.to_dict())


#: The most rules a saved model may hold: the largest rule base trained here is 4 096 (a grid of
#: 8 functions on 4 inputs; the contest's clustered bases reach 512); 200 000 edited-in rules took
#: 37 s for 50 poses.
MAX_SAVED_RULES = 65_536
#: The largest consequent coefficient a saved model may hold: trained ones are below 1e4 (inputs
#: are scaled to about unit size), and 1e308 makes every prediction inf.
MAX_CONSEQUENT = 1e100
_STATE_KEYS = ("mfs", "rules", "consequents", "feature_names", "loss_curve", "val_loss_curve",
               "step_size_curve", "best_epoch", "mfs_initial")


def _check_header(v: Validator, data: Any, cls_name: str, at: str, keys: tuple[str, ...]) -> None:
    v.mapping(data, at, {"format": True, "class": True, **dict.fromkeys(keys, True)})
    if data["format"] != _FORMAT:
        v.fail("format", f"must be {_FORMAT!r} (an nfarm ANFIS model), got {show(data['format'])}")
    if data["class"] != cls_name:
        v.fail("class", f"must be {cls_name!r}, got {show(data['class'])}")


def _check_params(v: Validator, params: Any, at: str, n_features: int | None) -> dict:
    """The saved constructor parameters, valid for a model of ``n_features`` inputs."""
    names = ANFIS._param_names()
    v.mapping(params, at, dict.fromkeys(names, False))
    model = ANFIS(**params)
    try:
        if n_features is not None:
            model._check_options(n_features)
        elif model.mf not in MF_TYPES:
            raise ValueError(f"mf must be one of {', '.join(MF_TYPES)}, got {show(model.mf)}")
    except (ValueError, TypeError) as exc:
        v.fail(at, str(exc))
    return model.get_params()


def load(path: str | os.PathLike) -> ANFIS | ANFISMulti:
    """Read a model written by ``save``, checked like a parameter file: ``path`` is the
    directory it was saved into or the file itself (``…/anfis.json``).

    Raises:
        ParamsError: the file is not a regular file of at most 64 MB, not JSON, not a
            valid nfarm ANFIS model, or edited after it was saved (its ``content_sha256``,
            :func:`nfarm.infra.reading.checked_content`); the message names the file and the field.
    """
    path = model_file(path, FILE_NAME)
    data = load_json(path, what="ANFIS model")
    kind = {"ANFIS": ANFIS, "ANFISMulti": ANFISMulti}.get(data.get("class")) \
        if isinstance(data, dict) else None
    if kind is None:
        Validator(str(path)).fail("class" if isinstance(data, dict) else "",
                                  f"must be 'ANFIS' or 'ANFISMulti' (an nfarm ANFIS model), got "
                                  f"{show(data.get('class') if isinstance(data, dict) else data)}")
    return kind.from_dict(checked_content(data, str(path)), str(path))
