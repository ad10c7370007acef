"""Chapter 6's summary: what it chose, in a few lines of Markdown — the learned IK the contest
chose, the best ANFIS for the inverse dynamics without the arm's parameters against the study's
target (:data:`nfarm.study.verdict_rows.ID_TARGET_PCT`) and the best scikit-learn baseline, and each
tier's best on the measured arm. Every number is a validation number: chapter 7 reads the test
set once, with the chosen models frozen.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from . import contest
from .chosen_models import ChosenIK
from .id_comparison_report import TorqueReading, baseline_winner, baseline_words, same
from .id_contest_report import pct
from .ik_contest_report import mm_text, seeds_text
from .verdict_rows import ID_TARGET_PCT
from .sweep import Replicates

__all__ = ["summary_prose"]


def summary_prose(chosen_ik: ChosenIK, ranked: Sequence[Replicates], reading: TorqueReading, id_best: Replicates,
                  base_best: Mapping[tuple[str, str], Replicates], idc: contest.IDContest | None = None, noise=None) -> str:
    """The chapter's summary as Markdown bullets: the chosen learned IK (``chosen_ik``) and the
    contest's leader (``ranked``: the standings), the chosen ANFIS for the rigid-body ID
    (``id_best``) and the best baseline (of ``base_best``, each learner's best in each tier, the rigid-body span aside), and, given the
    measured arm's contest ``idc``, each tier's best with the sensor noise (``noise (n,)`` [N·m])."""
    row, leader = chosen_ik.standing, ranked[0]
    fmt, seeds_range = reading.fmt, reading.seeds_range
    chosen = (f"* **Inverse kinematics**: {contest.label(chosen_ik.name)}, chosen in the contest of section 6.1, reaches a "
              f"95th-percentile tool position error of **{seeds_text(row, 'position_p95_mm', mm_text)} mm** and a median "
              f"of {seeds_text(row, 'position_p50_mm', mm_text)} mm on validation (mean and range over {row.n} seeds); ")
    chosen += ("it leads the contest." if row is leader else
               f"the contest's leader is {contest.label(contest.family(leader.cell.params))} at "
               f"{seeds_text(leader, 'position_p95_mm', mm_text)} mm.")
    winner = baseline_winner(base_best)
    worst = id_best.metrics["worst_nrmse"]
    lines = [chosen,
             f"* **Inverse dynamics without the arm's parameters**: the best ANFIS, "
             f"{reading.label(id_best.cell.params, reading.keys)}, misses by **{fmt(worst)} %** of the torque spread on its "
             f"worst joint ({reading.worst}; {seeds_range(id_best)} % over the seeds) — the study's target of "
             f"{ID_TARGET_PCT:g} % "
             + ("met in every seed" if id_best.high("worst_nrmse") <= ID_TARGET_PCT / 100 else
                "met on average" if worst <= ID_TARGET_PCT / 100 else "not met")
             + f". The best scikit-learn baseline, {baseline_words(winner.cell.params)}, reaches "
               f"{fmt(winner.metrics['worst_nrmse'])} % ({seeds_range(winner)} %): "
             + ("no difference shown by the seeds' ranges." if same(winner, id_best) else
                "**the baseline is better**." if winner.metrics["worst_nrmse"] < worst else "the ANFIS is better.")]
    if idc is not None:
        lines.append(
            "* **The measured arm** (validation, worst resolved joint's NRMSE against the measured spread): "
            + "; ".join(f"{tier}, best {contest.id_label(contest.id_family(idc.winner(tier).cell.params)).split(': ', 1)[1]} "
                        f"({pct(idc.winner(tier).metrics['worst_nrmse'])} %)" for tier in idc.tiers)
            + f"; the sensor noise is {np.max(noise):.3g} N·m.")
    lines.append("* Every choice here was made on validation data; chapter 7 reads the test set once, with the chosen "
                 "models frozen.")
    return "\n".join(lines)
