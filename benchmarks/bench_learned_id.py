"""Learned ID (chapters 06–07): training time of the chosen and the residual models, and
prediction time per sample against the Newton–Euler recursion (``rnea``) in the same run.

Targets (issue 12): training of the chosen models ≤ 5 min on 2 cores; prediction time per
sample reported against ``rnea``. The options are chapter 06's (``id_chosen``,
``id_residual``, ``seed`` there).
"""

from __future__ import annotations

import ast

import numpy as np
import papermill

from common import best_of
from nfarm import datasets
from nfarm.dynamics import regressor, rnea
from nfarm.learned import LearnedID
from nfarm.paths import NOTEBOOKS, PARAMS
from nfarm.report import Table

N_PREDICT = 200_000


def chapter_options() -> dict[str, dict]:
    """Chapter 06's ID options, read from the notebook (one source)."""
    declared = papermill.inspect_notebook(str(NOTEBOOKS / "06_anfis_training.ipynb"))
    seed = ast.literal_eval(declared["seed"]["default"])
    return {key: {**ast.literal_eval(declared[key]["default"]), "random_state": seed}
            for key in ("id_chosen", "id_dissertation", "id_residual")}


def main() -> None:
    study = datasets.load_study(PARAMS / "studies" / "intelbot5.yaml")
    robot = study.robot
    datasets.build_datasets(study)
    directory = datasets.dataset_dir(study)
    train, val, test = (datasets.load(directory / f"id_{s}.npz", robot, study)
                        for s in ("train", "val", "test"))
    options = chapter_options()
    pick = lambda d, key: {**{k: d[k] for k in ("q", "qd", "qdd")}, "tau": d[key]}   # noqa: E731
    rows, models = [], {}
    for name, key in (("id_chosen", "tau"), ("id_dissertation", "tau"), ("id_residual", "tau_measured")):
        seconds = best_of(lambda: models.__setitem__(name, LearnedID(**options[name]).fit(
            robot, pick(train, key), pick(val, key))), repeat=1)
        rows.append([f"LearnedID.fit, {name}", f"{len(train['q']):,} samples", seconds, "",
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
    print(Table(["what", "size", "seconds", "µs per sample", "note"], rows,
                floatfmt=["", "", ".3g", ".3g", ""]).to_markdown())


if __name__ == "__main__":
    main()
