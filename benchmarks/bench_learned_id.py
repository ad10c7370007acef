"""Learned ID (chapters 06–07): training time of the model-free, the dissertation's, the
identification and the residual models, and prediction time per sample against the
Newton–Euler recursion (``rnea``) in the same run; and the boosted-trees baseline's prediction
(chapters 06–07's residual and rival) by scikit-learn's compiled traversal, which the library
uses, against the NumPy traversal it used before (:func:`numpy_forest`), bit for bit.

Targets (issue 12): training of each model ≤ 5 min on 2 cores; prediction time per sample
reported against ``rnea``. The options are chapter 06's (``id_identified``, ``id_dissertation``,
``id_residual``, ``id_final_epochs``, ``seed`` there); the model-free ANFIS's rule base is the
cell chapter 06 chooses by validation on intelbot5 (:data:`MODEL_FREE`: affine inputs, eight
rules over the pitch joints, every 16th training state).
"""

from __future__ import annotations

import ast

import numpy as np
import papermill

from common import best_of
from nfarm.study import datasets, study_files
from nfarm.model.dynamics import regressor, rnea
from nfarm.learning.baselines import BaselineID
from nfarm.learning.learned_id import LearnedID
from nfarm.infra.paths import NOTEBOOKS, PARAMS
from nfarm.presentation.tables import Table

N_PREDICT = 200_000
MODEL_FREE = {"inputs": "affine", "partition": "grid", "n_mfs": [1, 2, 2, 2, 1], "mf": "gauss"}
MODEL_FREE_STRIDE = 16


def chapter_options() -> dict[str, dict]:
    """Chapter 06's ID options, read from the notebook (one source)."""
    declared = papermill.inspect_notebook(str(NOTEBOOKS / "06_anfis_training.ipynb"))
    seed = ast.literal_eval(declared["seed"]["default"])
    options = {key: {**ast.literal_eval(declared[key]["default"]), "random_state": seed}
               for key in ("id_identified", "id_dissertation", "id_residual")}
    epochs = ast.literal_eval(declared["id_final_epochs"]["default"])
    return {"id_model_free": {**MODEL_FREE, "epochs": epochs, "random_state": seed}, **options}


N_BOOSTING = 20_000


def numpy_forest(state: dict, X: np.ndarray) -> np.ndarray:
    """The boosted trees' prediction ``(N, n)`` by a traversal in NumPy (the library's before
    scikit-learn's compiled predictor replaced it): one level of every tree at a time."""
    out = np.empty((len(X), len(state["joints"])))
    for j, joint in enumerate(state["joints"]):
        raw = np.zeros(len(X))
        raw += joint["baseline"]
        for tree in joint["trees"]:
            node = np.zeros(len(X), dtype=int)
            while True:
                inner = ~tree["leaf"][node].astype(bool)
                if not inner.any():
                    break
                rows, at = np.flatnonzero(inner), node[inner]
                x = X[rows, tree["feature"][at]]
                left = np.where(np.isnan(x), tree["missing_left"][at].astype(bool), x <= tree["threshold"][at])
                node[rows] = np.where(left, tree["left"][at], tree["right"][at])
            raw += tree["value"][node]
        out[:, j] = raw
    return out


def boosting_rows(robot, train, test) -> list[list]:
    """Chapter 06's residual boosting (300 trees a joint) predicting ``N_BOOSTING`` states both ways."""
    model = BaselineID("boosting", {"max_iter": 300, "learning_rate": 0.1, "max_leaf_nodes": 31},
                       residual=True, random_state=0).fit(robot, {**{k: train[k][::16] for k in ("q", "qd", "qdd")},
                                                                  "tau": train["tau_measured"][::16]})
    X = model._features(*(np.resize(test[k], (N_BOOSTING, robot.n)) for k in ("q", "qd", "qdd")))
    from nfarm.learning.baselines import _predict_state
    before, after = numpy_forest(model.state_, X), _predict_state("boosting", model.state_, X)
    same = "bit-identical" if np.array_equal(before, after) else f"DIFFER by {np.abs(before - after).max():.3g}"
    s_before = best_of(lambda: numpy_forest(model.state_, X)) / N_BOOSTING
    s_after = best_of(lambda: _predict_state("boosting", model.state_, X)) / N_BOOSTING
    return [["boosting trees, NumPy traversal (before)", f"{N_BOOSTING:,} samples", s_before * N_BOOSTING,
             s_before * 1e6, "peer"],
            ["boosting trees, scikit-learn's traversal (now)", f"{N_BOOSTING:,} samples", s_after * N_BOOSTING,
             s_after * 1e6, f"{s_before / s_after:.2g}× faster, {same}"]]


def main() -> None:
    study = study_files.load_study(PARAMS / "studies" / "intelbot5.yaml")
    robot = study.robot
    datasets.build_datasets(study)
    directory = datasets.dataset_dir(study)
    train, val, test = (datasets.load(directory / f"id_{s}.npz", robot, study)
                        for s in ("train", "val", "test"))
    options = chapter_options()
    pick = lambda d, key, step=1: {**{k: d[k][::step] for k in ("q", "qd", "qdd")}, "tau": d[key][::step]}   # noqa: E731
    rows, models = [], {}
    for name, key, step in (("id_model_free", "tau", MODEL_FREE_STRIDE), ("id_identified", "tau", 1),
                            ("id_dissertation", "tau", 1), ("id_residual", "tau_measured", 1)):
        seconds = best_of(lambda: models.__setitem__(name, LearnedID(**options[name]).fit(
            robot, pick(train, key, step), pick(val, key))), repeat=1)
        rows.append([f"LearnedID.fit, {name}", f"{len(train['q'][::step]):,} samples", seconds, "",
                     f"target ≤ 300 s: {'met' if seconds <= 300 else 'NOT met'}"])
    X = [np.resize(test[k], (N_PREDICT, robot.n)) for k in ("q", "qd", "qdd")]
    base = best_of(lambda: rnea(robot, *X)) / N_PREDICT
    rows.append(["rnea (rigid body)", f"{N_PREDICT:,} samples", base * N_PREDICT, base * 1e6, "1 (reference)"])
    s = best_of(lambda: regressor(robot, *X)) / N_PREDICT
    rows.append(["dynamics.regressor", f"{N_PREDICT:,} samples", s * N_PREDICT, s * 1e6, f"{s / base:.3g}× rnea"])
    for name, model in models.items():
        s = best_of(lambda: model.predict(*X)) / N_PREDICT
        rows.append([f"LearnedID.predict, {name}", f"{N_PREDICT:,} samples", s * N_PREDICT, s * 1e6,
                     f"{s / base:.3g}× rnea"])
    rows += boosting_rows(robot, train, test)
    print(Table(["what", "size", "seconds", "µs per sample", "note"], rows,
                floatfmt=["", "", ".3g", ".3g", ""]).to_markdown())


if __name__ == "__main__":
    main()
