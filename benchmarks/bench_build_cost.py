"""The clean build's dominant cost, so that the next change that raises it is seen (issue 63).

Two tables:

1. **Where the sweep cells' CPU went** in the last build of this checkout (``build/sweeps``: each
   cell records the CPU its thread used, ``cpu_seconds``, beside its wall seconds, which on a
   shared machine are not its cost): by sweep, arm, learner and training size (the contest's
   first rung, a quarter of the poses, or the full size), largest first, with each row's share.
   Nothing built: the table says so.
2. **The two engines the contests spend most on, timed**: the learned-IK contest's ANFIS in the arm's
   plane at 128 rules (its configuration in ``params/sweeps/ik_contest.yaml``, the study's training
   poses of intelbot5, one BLAS thread as a sweep cell trains), a fixed number of epochs; beside it, in
   the same run, the multilayer perceptron of two 256-unit layers, for as many epochs (once the study was
   cut to 5 000 training poses, the MLPs of both contests took the largest share of the sweep cells'
   CPU: table 1 says what they take now). Seconds and CPU seconds per epoch, and their ratio: a change to either
   engine shows in the ratio whatever the machine's speed.

About 2 minutes on one core (the data sets are built first if this checkout has none).
"""

from __future__ import annotations

import collections
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import yaml
from threadpoolctl import threadpool_limits

import common  # noqa: F401  (sets sys.path like `make bench`)
from nfarm.infra.paths import BUILD, PARAMS
from nfarm.learning.ik_rivals import RivalIK
from nfarm.learning.learned import LearnedIK
from nfarm.presentation.tables import Table
from nfarm.study import datasets
from nfarm.study.study_files import load_study

EPOCHS = 8
RULES = 128


def attribution(sweeps: Path = BUILD / "sweeps") -> Table | None:
    """Table 1, or ``None`` when no sweep cell was recorded with its CPU."""
    groups: dict[tuple, list[float]] = collections.defaultdict(lambda: [0, 0.0, 0.0])
    for path in sweeps.glob("*/*/cell.json"):
        try:
            record = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if "cpu_seconds" not in record or not isinstance(record.get("params"), dict):
            continue
        p = record["params"]
        learner = p.get("learner", record.get("job", ""))
        if learner == "anfis" and p.get("encoding"):
            learner += f" ({p['encoding']})"
        arm = Path(str(p.get("study_file", ""))).stem
        size = "first rung" if p.get("fraction", 1.0) < 1 else f"stride {p['stride']}" if p.get("stride", 1) != 1 \
            else "full size"
        group = groups[(record["sweep"], arm, learner, size)]
        group[0] += 1
        group[1] += float(record["cpu_seconds"])
        group[2] += float(record.get("seconds", 0.0))
    if not groups:
        return None
    total = sum(g[1] for g in groups.values())
    rows = [[*key, g[0], g[1], g[2], 100 * g[1] / total]
            for key, g in sorted(groups.items(), key=lambda kv: -kv[1][1])]
    rows.append(["all", "", "", "", sum(g[0] for g in groups.values()), total, sum(g[2] for g in groups.values()), 100.0])
    return Table(["sweep", "arm", "learner", "size", "cells", "CPU [s]", "wall [s]", "share of CPU [%]"], rows,
                 floatfmt=["", "", "", "", "", ".0f", ".0f", ".1f"])


def _contest_options(learner: str, match) -> dict:
    sweep = yaml.safe_load((PARAMS / "sweeps" / "ik_contest.yaml").read_text(encoding="utf-8"))
    found = [dict(c["options"]) for c in sweep["cells"] if c["learner"] == learner and match(c)]
    if not found:
        raise SystemExit(f"params/sweeps/ik_contest.yaml: cells: no {learner} cell of the configuration this benchmark "
                         f"times (bench_build_cost.py, dominant_cell): update the benchmark's choice")
    return found[0]


def _timed(fit) -> tuple[float, float, object]:
    wall, cpu = time.perf_counter(), time.thread_time()
    model = fit()
    return time.perf_counter() - wall, time.thread_time() - cpu, model


def dominant_cell() -> Table:
    study = load_study(PARAMS / "studies" / "intelbot5.yaml")
    datasets.build_datasets(study)
    directory = datasets.dataset_dir(study)
    train, val = (datasets.load(directory / f"ik_{s}.npz", study.robot, study) for s in ("train", "val"))
    anfis = _contest_options("anfis", lambda c: c.get("encoding") == "arm_plane" and c["options"]["n_rules"] == RULES)
    anfis.update(epochs=EPOCHS, patience=None, min_improvement=0.0)   # a fixed number of epochs: no stopping
    mlp = _contest_options("mlp", lambda c: c["options"]["hidden"] == [256, 256] and "structure" not in c["options"]
                           and c["options"].get("alpha", 1e-4) == 1e-4)
    mlp.update(max_epochs=EPOCHS, patience=EPOCHS + 1)
    plane = {"max_out_of_plane": math.radians(0.5)}
    rows = []
    with threadpool_limits(1):
        a_wall, a_cpu, a = _timed(lambda: LearnedIK("arm_plane", **plane, **anfis, random_state=0)
                                  .fit(study.robot, train, val))
        m_wall, m_cpu, m = _timed(lambda: RivalIK("mlp", "arm_plane", mlp, **plane, random_state=0)
                                  .fit(study.robot, train, val))
    a_epochs = max(len(model.loss_curve_) for model in a.models_)
    m_epochs = EPOCHS
    rows.append([f"ANFIS in the arm's plane, {RULES} rules (the contest's)", f"{len(train['q']):,}", a_epochs,
                 a_wall / a_epochs, a_cpu / a_epochs, 1.0])
    rows.append(["multilayer perceptron, 256 × 256 (the contest's)", f"{len(train['q']):,}", m_epochs,
                 m_wall / m_epochs, m_cpu / m_epochs, (m_cpu / m_epochs) / (a_cpu / a_epochs)])
    return Table(["fit", "training poses", "epochs", "s / epoch", "CPU s / epoch", "CPU per epoch against the ANFIS's"],
                 rows, floatfmt=["", "", "", ".3f", ".3f", ".2f"])


def main() -> None:
    table = attribution()
    if table is None:
        print("bench_build_cost: no sweep cells with their CPU in build/sweeps (run `make report` first); "
              "timing the dominant cell only", file=sys.stderr)
    else:
        print("Where the sweep cells' CPU went in the last build (build/sweeps):\n")
        print(table.to_markdown())
        print()
    print(dominant_cell().to_markdown())


if __name__ == "__main__":
    main()
