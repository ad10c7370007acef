"""Pieces the ID baselines (:mod:`nfarm.learning.baselines`) are built of, beside scikit-learn's
own estimators: its boosting and MLP regressors checking a time limit (:func:`timed_learners`),
boosted trees as arrays and back (:func:`trees_state`, :func:`read_trees`, :func:`forest_values`)
and two least squares over every joint's rows (:class:`StackedLeastSquares`,
:class:`PerJointLeastSquares`).

**Time limits.** A sweep cell runs in a worker's thread, where nothing can stop a fit from
outside; the iterative learners check the caller's deadline (:func:`nfarm.infra.limits.time_limit`)
once per iteration — boosting before each boosting iteration, the MLP after each epoch —
through two hooks of scikit-learn's loops that change no arithmetic (the fits are bit-identical
to the plain estimators', ``tests/test_baselines.py``).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from ..infra.limits import check_time
from ..infra.reading import Validator

__all__ = ["timed_learners", "trees_state", "read_trees", "forest_values", "StackedLeastSquares",
           "PerJointLeastSquares", "TREE_FIELDS"]

#: The node arrays of a saved tree.
TREE_FIELDS = ("feature", "threshold", "left", "right", "leaf", "value", "missing_left")


@functools.cache
def timed_learners():
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


def trees_state(model) -> dict:
    """The arrays a fitted ``MultiOutputRegressor`` of single-output boosted regressors predicts
    with: per joint its baseline and every tree's nodes (:data:`TREE_FIELDS`)."""
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


def forest_values(trees: list[dict], baseline: float, X: np.ndarray) -> np.ndarray:
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


def read_trees(v: Validator, state: Any, k: int, n: int, max_trees: int) -> dict:
    """A saved boosting ``state`` checked (through ``v``): ``n`` joints of at most ``max_trees``
    trees over ``k`` features, each node's children later nodes of its tree (no loop)."""
    v.mapping(state, "state", {"joints": True})
    joints = v.sequence(state["joints"], "state.joints", min_len=n, max_len=n)
    out = []
    for j, joint in enumerate(joints):
        at = f"state.joints[{j}]"
        v.mapping(joint, at, {"baseline": True, "trees": True})
        trees = v.sequence(joint["trees"], f"{at}.trees", max_len=max_trees)
        read = []
        for t, tree in enumerate(trees):
            where = f"{at}.trees[{t}]"
            v.mapping(tree, where, dict.fromkeys(TREE_FIELDS, True))
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


class StackedLeastSquares:
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


class PerJointLeastSquares:
    """``y_j ≈ X_j θ_j`` per joint by least squares (``X (N, n, k)``, ``y (N, n)``)."""

    def fit(self, X, y):
        self.coef_ = np.stack([np.linalg.lstsq(X[:, j], y[:, j], rcond=None)[0] for j in range(y.shape[1])])
        return self

    def predict(self, X):
        return np.einsum("njk,jk->nj", X, self.coef_)
