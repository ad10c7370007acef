"""Learned IK (chapters 06–07): training time of the chosen five models, and prediction speed
against the peers in the same run (LM, RBF interpolation, nearest neighbour).

Targets (issue 11): prediction ≥ 1 000 000 poses/s batched; training of the chosen five
models ≤ 5 min on 2 cores. The chosen options are chapter 06's (`chosen` there).
"""

from __future__ import annotations

import ast
import time

import numpy as np
import papermill

from common import best_of
from nfarm.study import datasets, study_files
from nfarm import ik
from nfarm.learning.learned import Baseline, LearnedIK
from nfarm.infra.paths import NOTEBOOKS, PARAMS
from nfarm.presentation.tables import Table



def chosen_options() -> dict:
    """Chapter 06's `chosen` and `seed` parameters, read from the notebook (one source)."""
    declared = papermill.inspect_notebook(str(NOTEBOOKS / "06_anfis_training.ipynb"))
    return {**ast.literal_eval(declared["chosen"]["default"]),
            "random_state": ast.literal_eval(declared["seed"]["default"])}

N_PREDICT = 1_000_000
N_LM = 2000


def main() -> None:
    study = study_files.load_study(PARAMS / "studies" / "intelbot5.yaml")
    robot = study.robot
    datasets.build_datasets(study)
    directory = datasets.dataset_dir(study)
    train, val, test = (datasets.load(directory / f"ik_{s}.npz", robot, study)
                        for s in ("train", "val", "test"))
    start = time.perf_counter()
    model = LearnedIK(**chosen_options()).fit(robot, train, val)
    train_seconds = time.perf_counter() - start
    T = np.resize(test["T"], (N_PREDICT, 4, 4))
    rows = [["LearnedIK.fit, chosen options", f"{len(train['q']):,} poses", train_seconds, "",
             f"target ≤ 300 s: {'met' if train_seconds <= 300 else 'NOT met'}"]]
    seconds = best_of(lambda: model.predict(T))
    rate = N_PREDICT / seconds
    rows.append(["LearnedIK.predict", f"{N_PREDICT:,} poses", seconds, rate,
                 f"target ≥ 1e6/s: {'met' if rate >= 1e6 else 'NOT met'}"])
    for kind, n in (("nearest", 200_000), ("rbf", 20_000)):
        base = Baseline(kind, "arm_plane").fit(robot, train)
        s = best_of(lambda: base.predict(T[:n]), repeat=1)
        rows.append([f"baseline {kind}", f"{n:,} poses", s, n / s, f"ANFIS {rate / (n / s):.3g}× faster"])
    s = best_of(lambda: ik.solve(robot, test["T"][:N_LM]), repeat=1)
    rows.append(["ik.solve (LM)", f"{N_LM:,} poses", s, N_LM / s, f"ANFIS {rate / (N_LM / s):.3g}× faster"])
    print(Table(["what", "size", "seconds", "poses/s", "note"], rows,
                floatfmt=["", "", ".3g", ".3g", ""]).to_markdown())


if __name__ == "__main__":
    main()
