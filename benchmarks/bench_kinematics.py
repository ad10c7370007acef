"""Batched fk and jacobian against Pinocchio called per configuration in a Python loop.

Target (issue 2): on 100 000 intelbot5 configurations, fk ≥ 5× and jacobian ≥ 3× the
per-configuration throughput of Pinocchio's loop.
"""

from __future__ import annotations

import pinocchio as pin

from common import seconds_per_call
from nfarm.model.kinematics import fk, jacobian
from nfarm.infra.paths import PARAMS
from nfarm.model.pinocchio_ref import pinocchio_model
from nfarm.presentation.tables import Table
from nfarm.model.robot import load_robot, sample_configurations

BATCHES = (1, 1_000, 100_000)
PIN_LOOP = 2_000  # configurations timed in Pinocchio's per-configuration loop


def main() -> None:
    robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
    ref = pinocchio_model(robot)
    model, data, tool = ref.model, ref.data, ref.tool_id
    q_all = sample_configurations(robot, max(BATCHES), seed=0)

    def pin_fk(qs):
        for q in qs:
            pin.framesForwardKinematics(model, data, q)

    def pin_jac(qs):
        for q in qs:
            pin.computeFrameJacobian(model, data, q, tool, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)

    qs = list(q_all[:PIN_LOOP])
    pin_us = {"fk": seconds_per_call(lambda: pin_fk(qs)) / PIN_LOOP * 1e6,
              "jacobian": seconds_per_call(lambda: pin_jac(qs)) / PIN_LOOP * 1e6}
    targets = {"fk": 5.0, "jacobian": 3.0}
    rows = []
    for name, fn in (("fk", fk), ("jacobian", jacobian)):
        for batch in BATCHES:
            q = q_all[:batch]
            us = seconds_per_call(lambda: fn(robot, q)) / batch * 1e6
            ratio = pin_us[name] / us
            verdict = f"target ≥ {targets[name]:g}×: {'met' if ratio >= targets[name] else 'NOT met'}" \
                if batch == max(BATCHES) else ""
            rows.append([name, batch, us, pin_us[name], ratio, verdict])
    print(Table(["function", "batch", "nfarm µs/config", "Pinocchio loop µs/config",
                 "speed-up", "note"], rows, floatfmt=["", "", ".3f", ".3f", ".2f", ""]
                ).to_markdown())


if __name__ == "__main__":
    main()
