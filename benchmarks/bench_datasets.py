"""Data-set generation (chapter 05): IK samples (region sampling with its task-space filters,
and ``fk``) and ID samples (random quintic trajectories, and ``rnea``), per second.

Target (issue 10): ≥ 1 000 000 IK samples and ≥ 1 000 000 ID samples in ≤ 10 s each on 2
cores. The reference in the same run is the simplest possible generator: uniform joint draws
over the full box and ``fk`` alone (no filters), and ``rnea`` on random states.
"""

from __future__ import annotations

import time

import numpy as np

from common import seconds_per_call  # noqa: F401 — sets the benchmark environment
from nfarm.study.regions import ik_samples
from nfarm.study.study_files import load_study
from nfarm.study.id_trajectories import random_trajectories
from nfarm.model.dynamics import rnea
from nfarm.model.kinematics import fk
from nfarm.infra.paths import PARAMS
from nfarm.presentation.tables import Table
from nfarm.model.robot import sample_configurations

N = 1_000_000


def best_of(fn, repeat: int = 3) -> tuple[float, object]:
    best, value = float("inf"), None
    for _ in range(repeat):
        start = time.perf_counter()
        value = fn()
        best = min(best, time.perf_counter() - start)
    return best, value


def main() -> None:
    study = load_study(PARAMS / "studies" / "intelbot5.yaml")
    robot = study.robot
    rows = []
    seconds, data = best_of(lambda: ik_samples(study.ik_region, N, np.random.default_rng(0)))
    rows.append(["IK: region (Sobol, filters) + fk", len(data["q"]), seconds,
                 f"target ≤ 10 s: {'met' if seconds <= 10 else 'NOT met'}"])
    seconds_ref, _ = best_of(lambda: fk(robot, sample_configurations(robot, N, 0)))
    rows.append(["reference: uniform full box + fk", N, seconds_ref, ""])

    def make_id():
        d = random_trajectories(robot, study.id, 1, np.random.default_rng(0))
        per = len(d["t"])
        count = max(int(np.ceil(N / per * 1.05)), 1)
        d = random_trajectories(robot, study.id, count, np.random.default_rng(0))
        d["tau"] = rnea(robot, d["q"], d["qd"], d["qdd"])
        return d

    seconds, data = best_of(make_id)
    rows.append(["ID: random trajectories + rnea", len(data["t"]), seconds,
                 f"target ≤ 10 s for 1e6: {'met' if seconds * N / len(data['t']) <= 10 else 'NOT met'}"])
    rng = np.random.default_rng(0)
    q = sample_configurations(robot, N, 0)
    qd, qdd = rng.normal(size=q.shape), rng.normal(size=q.shape)
    seconds_ref, _ = best_of(lambda: rnea(robot, q, qd, qdd))
    rows.append(["reference: rnea alone on random states", N, seconds_ref, ""])
    print(Table(["what", "samples", "seconds", "note"], rows,
                floatfmt=["", "", ".2f", ""]).to_markdown())


if __name__ == "__main__":
    main()
