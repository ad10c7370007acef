"""Closed-form IK (every branch of every pose) against nfarm's LM (one solution per pose) and,
when the optional `bench` extra is installed, the Robotics Toolbox's C++ ``ik_LM``, on random
reachable targets of both arms, all in the same run.

Targets (issue 21): ≥ 1e6 poses/s for all branches on 2 cores with numpy alone, and ≥ 50×
nfarm's LM per pose. The closed form is timed on 400 000 poses, LM on 10 000 (its time per
pose does not depend on the batch beyond that), in alternating rounds.
"""

from __future__ import annotations

import os
import time

import numpy as np

from common import best_of
from nfarm.solvers.ik import closed_form, solve
from nfarm.model.kinematics import fk
from nfarm.infra.paths import PARAMS
from nfarm.presentation.tables import Table
from nfarm.model.robot import load_robot, sample_configurations

N_CLOSED = 400_000
N_LM = 10_000
N_RTB = 2_000
ROUNDS = 5
TARGET_RATE, TARGET_RATIO = 1e6, 50.0


def robotics_toolbox(robot, T):
    """Poses per second of the Robotics Toolbox's ``ik_LM`` (C++), per target, or None."""
    try:
        import roboticstoolbox as rtb
        from spatialmath import SE3
    except ImportError:
        return None, None
    links = [rtb.RevoluteDH(a=a, alpha=al, d=d, offset=o, qlim=lim)
             for a, al, d, o, lim in zip(robot.a, robot.alpha, robot.d, robot.offset, robot.qlim)]
    arm = rtb.DHRobot(links, base=SE3(robot.base, check=False), tool=SE3(robot.tool, check=False),
                      name=robot.name).ets()
    ok = 0
    start = time.perf_counter()
    for target in T:
        ok += bool(arm.ik_LM(target, tol=1e-12, ilimit=100, slimit=100, joint_limits=True).success)
    return len(T) / (time.perf_counter() - start), ok / len(T)


def main() -> None:
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    rows = []
    for name in ("intelbot5", "so101"):
        robot = load_robot(PARAMS / "robots" / f"{name}.yaml")
        T = fk(robot, sample_configurations(robot, N_CLOSED, seed=2024))
        closed_form(robot, T[:20_000])                                    # warm up
        solve(robot, T[:200])
        # Rounds that time each solver in turn, so that a busy spell of a shared machine
        # falls on both: the ratio is the median of the rounds', its range beside it.
        cf, cf_1, lm_ = [], [], []
        for _ in range(ROUNDS):
            cf.append(N_CLOSED / best_of(lambda: closed_form(robot, T), repeat=1))
            cf_1.append(N_CLOSED / best_of(lambda: closed_form(robot, T, threads=1), repeat=1))
            lm_.append(N_LM / best_of(lambda: solve(robot, T[:N_LM]), repeat=1))
        ratio, ratio_1 = np.array(cf) / lm_, np.array(cf_1) / lm_
        rate, rate_1, lm_rate = np.median(cf), np.median(cf_1), np.median(lm_)
        result = closed_form(robot, T[:N_LM])
        lm = solve(robot, T[:N_LM])
        found = result.valid.any(-1).mean()
        verdict = ("met" if rate >= TARGET_RATE and np.median(ratio) >= TARGET_RATIO else "NOT met")
        spread = lambda r: f"{np.median(r):.3g} ({r.min():.3g}–{r.max():.3g})"  # noqa: E731
        rows += [
            [name, f"closed form, 4 branches ({cores} threads)", N_CLOSED, rate, 1e6 / rate,
             spread(ratio), f"{found:.2%} with a valid branch; targets ≥ 1e6/s and ≥ 50× LM: {verdict}"],
            [name, "closed form, 4 branches (1 thread)", N_CLOSED, rate_1, 1e6 / rate_1,
             spread(ratio_1), ""],
            [name, "nfarm LM (one solution)", N_LM, lm_rate, 1e6 / lm_rate, "1",
             f"{lm.success_rate:.2%} solved"],
        ]
        rtb_rate, rtb_ok = robotics_toolbox(robot, T[:N_RTB])
        if rtb_rate is None:
            rows.append([name, "Robotics Toolbox ik_LM (C++, one solution)", "", "", "", "",
                         "not installed: .venv/bin/pip install -e '.[bench]'"])
        else:
            rows.append([name, "Robotics Toolbox ik_LM (C++, one solution)", N_RTB, rtb_rate,
                         1e6 / rtb_rate, f"{rtb_rate / lm_rate:.3g}", f"{rtb_ok:.2%} solved, per target"])
    print(Table(["robot", "solver", "targets", "poses / s", "µs / pose",
                 f"× nfarm LM (median of {ROUNDS} rounds, range)", "note"],
                rows, floatfmt=["", "", "", ".3g", ".3g", "", ""]).to_markdown())


if __name__ == "__main__":
    main()
