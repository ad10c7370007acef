"""Batched RNEA against Pinocchio: ``pin.rnea`` per sample in a Python loop, and Pinocchio's
own batched entry point ``rneaInParallel`` (C++, OpenMP) on one and on two threads.

Target (issue 4): on 100 000 intelbot5 samples, ≥ 5× the per-sample throughput of the loop.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from common import seconds_per_call
from nfarm.model.dynamics import rnea
from nfarm.infra.paths import PARAMS
from nfarm.model.pinocchio_ref import pinocchio_model
from nfarm.presentation.tables import Table
from nfarm.model.robot import load_robot, sample_configurations

BATCHES = (1, 1_000, 100_000)
PIN_LOOP = 5_000


def main() -> None:
    robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
    ref = pinocchio_model(robot)
    model, data = ref.model, ref.data
    rng = np.random.default_rng(0)
    N = max(BATCHES)
    q = sample_configurations(robot, N, 0)
    qd, qdd = rng.normal(size=q.shape), rng.normal(size=q.shape)

    samples = list(zip(q[:PIN_LOOP], qd[:PIN_LOOP], qdd[:PIN_LOOP]))

    def loop():
        for a, b, c in samples:
            pin.rnea(model, data, a, b, c)

    loop_us = seconds_per_call(loop) / PIN_LOOP * 1e6
    pool = pin.ModelPool(model, 2)
    qT, qdT, qddT = (np.asfortranarray(x.T) for x in (q, qd, qdd))
    rows = []
    for batch in BATCHES:
        args = (q[:batch], qd[:batch], qdd[:batch])
        us = seconds_per_call(lambda: rnea(robot, *args)) / batch * 1e6
        note = f"target ≥ 5×: {'met' if loop_us / us >= 5 else 'NOT met'}" if batch == N else ""
        rows.append(["nfarm rnea (batched numpy)", batch, us, loop_us / us, note])
    rows.append(["pin.rnea, Python loop", PIN_LOOP, loop_us, 1.0, "per sample"])
    for threads in (1, 2):
        us = seconds_per_call(lambda: pin.rneaInParallel(threads, pool, qT, qdT, qddT)) / N * 1e6
        rows.append([f"pin.rneaInParallel ({threads} thread{'s' if threads > 1 else ''})", N, us,
                     loop_us / us, "C++ batch"])
    np.testing.assert_allclose(rnea(robot, q[:100], qd[:100], qdd[:100]),
                               pin.rneaInParallel(1, pool, qT[:, :100], qdT[:, :100], qddT[:, :100]).T,
                               rtol=1e-10, atol=1e-12)
    print(Table(["implementation", "samples", "µs / sample", "speed-up over the loop", "note"], rows,
                floatfmt=["", "", ".3f", ".2f", ""]).to_markdown())


if __name__ == "__main__":
    main()
