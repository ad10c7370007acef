"""The study's targets and its verdict on held-out data (chapter 07's verdict table, read by
chapter 08, the index and the PDF): the targets (:data:`IK_TARGETS`, :data:`ID_TARGET_PCT`) and
whether a row meets one on its whole interval (:func:`target_verdict`, :func:`targets_met`); one
:class:`Verdict` per task and arm (:func:`task_verdict`) with Holm's correction over an arm's
comparisons (:func:`with_holm`); and the verdict table (:func:`verdict_table`, its p-values as
:func:`p_text` writes them), read back with :func:`nfarm.study.result_tables.read_verdicts`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Mapping, Sequence

import numpy as np

from ..presentation.tables import Table, shown
from .result_tables import DIGITS, VERDICT_COLUMNS
from .rows import Row
from .statistics import holm

__all__ = ["IK_TARGETS", "ID_TARGET_PCT", "FAMILY_ALPHA", "NO_DIFFERENCE", "target_verdict", "targets_met",
           "Verdict", "with_holm", "task_verdict", "verdict_table", "p_text"]

#: The study's targets for the learned IK (``docs/STUDY.md``, "The study's targets"): words, the
#: summary metric (:data:`nfarm.study.rows.IK_METRICS`), the upper limit and its unit; each judged on
#: a model's whole interval (:func:`target_verdict`).
IK_TARGETS = (("per-joint RMSE", "worst joint RMSE", 1.0, "°"), ("median position", "position median", 2.0, "mm"),
              ("95th percentile", "position p95", 10.0, "mm"))
#: The study's target for the learned ID: the worst joint's NRMSE, in % of the torque's spread.
ID_TARGET_PCT = 5.0
#: The family-wise error rate the verdict holds over one arm's comparisons (Holm's correction, :func:`with_holm`).
FAMILY_ALPHA = 0.05
#: The verdict's words where no difference is shown: the interval holds 0, or Holm's correction leaves it.
NO_DIFFERENCE = "no difference shown"


def target_verdict(row: Row, target: float) -> str:
    """Whether a metric meets an upper ``target`` (same unit), judged on its interval: ✓ when the
    whole interval is at or below it, ✗ when all of it is above, else undecided — a point value
    just under a target whose interval spans it has not met it.

    Example:
        >>> row = Row("inverse kinematics", "m", "chosen", "position p95", "mm", 9.0, 8.5, 10.5, 2000, 0.95, "")
        >>> target_verdict(row, 10.0), target_verdict(row, 11.0), target_verdict(row, 8.0)
        ('undecided (the interval spans it)', '✓', '✗')
    """
    return "✓" if row.high <= target else "✗" if row.low > target else "undecided (the interval spans it)"


def targets_met(rows: Sequence[Row], limits: Sequence[float]) -> str:
    """``"k of n"``: how many of one method's ``rows`` meet their ``limits`` on the whole
    interval (:func:`target_verdict`)."""
    return f"{sum(target_verdict(r, limit) == '✓' for r, limit in zip(rows, limits))} of {len(limits)}"


@dataclass(frozen=True)
class Verdict:
    """One task's verdict on one arm, on held-out data: the best of the methods compared, the
    ANFIS's best and its rank among them, its paired difference from the best other method
    (``gap``, ANFIS minus rival, with the interval ``gap_low``–``gap_high``), and the study's
    targets each met (``"2 of 3"``; ``""`` where the task has none); ``exact`` names a method that
    solves the task exactly, where one exists (not ranked: the learned methods are compared).
    ``anfis_low``–``anfis_high`` and ``rival_low``–``rival_high`` are the two methods' intervals,
    and ``interval`` says what they and the gap's resampled. ``p`` is the gap's two-sided bootstrap
    p-value of 0, ``holm_p`` the same after Holm's correction over the arm's ``comparisons``
    distinct comparisons (:func:`with_holm`), ``draws`` the resamples (``p``'s resolution is
    ``2 / draws``)."""

    arm: str
    task: str
    metric: str
    unit: str
    best: str
    best_value: float
    anfis: str
    anfis_value: float
    rank: int
    compared: int
    rival: str
    rival_value: float
    gap: float
    gap_low: float
    gap_high: float
    anfis_targets: str = ""
    rival_targets: str = ""
    exact: str = ""
    anfis_low: float = float("nan")
    anfis_high: float = float("nan")
    rival_low: float = float("nan")
    rival_high: float = float("nan")
    interval: str = ""
    p: float = float("nan")
    holm_p: float = float("nan")
    comparisons: int = 0
    draws: int = 0

    @property
    def verdict(self) -> str:
        """``"ANFIS better"``, ``"rival better"`` or ``"no difference shown"``: the paired interval
        against 0 and, once Holm's correction is known (:func:`with_holm`), the corrected p-value
        against :data:`FAMILY_ALPHA` as well — ``"no difference shown (Holm)"`` where the interval
        excludes 0 but the correction for the other comparisons does not let the difference stand."""
        side = "ANFIS better" if self.gap_high < 0 else "rival better" if self.gap_low > 0 else None
        if side is None:
            return NO_DIFFERENCE
        if math.isfinite(self.holm_p) and self.holm_p >= FAMILY_ALPHA:
            return f"{NO_DIFFERENCE} (Holm)"
        return side


def with_holm(verdicts: Sequence[Verdict]) -> list[Verdict]:
    """``verdicts`` (one arm's) with Holm's correction of their p-values over the arm's distinct
    comparisons: a row comparing the same two methods on the same metric as an earlier one (the
    measured arm's "every tier", which repeats its best tier's) is the same test and counts once;
    one on a group of joints (a task ending in "… joints", judged on those joints only) is a test
    of its own. A row without a p-value (NaN) is left out of the family and keeps its interval's verdict.

    Example:
        >>> v = [task_verdict("a", f"t{k}", "m", "mm", {"ANFIS": 1.0, f"R{k}": 2.0}, "ANFIS", (-1.0, -1.5, -0.5),
        ...                   p=p) for k, p in enumerate([0.001, 0.04, 0.02])]
        >>> [(w.comparisons, round(w.holm_p, 3), w.verdict) for w in with_holm(v)]
        [(3, 0.003, 'ANFIS better'), (3, 0.04, 'ANFIS better'), (3, 0.04, 'ANFIS better')]
        >>> [w.verdict for w in with_holm(v[:2] + [replace(v[2], p=0.03)])]
        ['ANFIS better', 'no difference shown (Holm)', 'no difference shown (Holm)']
        >>> [w.comparisons for w in with_holm(v + [replace(v[0], task="t0, every tier")])]   # the same test twice
        [3, 3, 3, 3]
        >>> [w.comparisons for w in with_holm(v + [replace(v[0], task="t0, every tier, rigid-dominated joints")])]
        [4, 4, 4, 4]
    """
    def key(v: Verdict) -> tuple:           # one test per pair of methods, metric and group of joints judged
        group = v.task.rsplit(", ", 1)[-1] if v.task.endswith(" joints") else ""
        return v.arm, v.metric, v.anfis, v.rival, group

    first: dict[tuple, Verdict] = {}
    for v in verdicts:
        if math.isfinite(v.p):
            first.setdefault(key(v), v)
    tests = list(first)
    adjusted = dict(zip(tests, holm(np.array([first[k].p for k in tests])))) if tests else {}
    return [replace(v, holm_p=float(adjusted[key(v)]), comparisons=len(tests)) if key(v) in adjusted else v
            for v in verdicts]


def task_verdict(arm: str, task: str, metric: str, unit: str, values: Mapping[str, float], anfis: str,
            gap: tuple[float, float, float], targets: Mapping[str, str] | None = None, exact: str = "", *,
            intervals: Mapping[str, tuple[float, float]] | None = None, interval: str = "",
            p: float = float("nan"), draws: int = 0) -> Verdict:
    """The :class:`Verdict` of one task: ``values`` every compared method's value of ``metric``
    (lower is better) on held-out data, ``anfis`` the ANFIS among them, ``gap`` its paired
    difference from the best other method ``(value, low, high)``, ``targets`` each method's
    targets met (``"2 of 3"``), ``exact`` the method that solves the task exactly, if any;
    ``intervals`` each method's ``(low, high)`` and ``interval`` what they resampled; ``p`` the
    gap's bootstrap p-value of 0 from ``draws`` resamples (:func:`with_holm` corrects it over the
    arm's comparisons).

    Example:
        >>> v = task_verdict("arm", "IK", "position p95", "mm", {"ANFIS": 0.9, "RBF": 4.9, "kNN": 31.0}, "ANFIS",
        ...             (-4.0, -4.2, -3.8), {"ANFIS": "3 of 3", "RBF": "2 of 3"})
        >>> v.best, v.rank, v.compared, v.rival, v.verdict
        ('ANFIS', 1, 3, 'RBF', 'ANFIS better')
    """
    if anfis not in values or len(values) < 2:
        raise ValueError(f"verdict: {anfis!r} must be one of at least two methods compared, got {list(values)}")
    ranked = sorted(values, key=lambda name: values[name])
    rival = next(name for name in ranked if name != anfis)
    targets, intervals = targets or {}, intervals or {}
    nan = (float("nan"), float("nan"))
    return Verdict(arm, task, metric, unit, ranked[0], float(values[ranked[0]]), anfis, float(values[anfis]),
                   ranked.index(anfis) + 1, len(ranked), rival, float(values[rival]), *map(float, gap), targets.get(anfis, ""),
                   targets.get(rival, ""), exact, *map(float, intervals.get(anfis, nan)),
                   *map(float, intervals.get(rival, nan)), interval, p=float(p), draws=int(draws))


def verdict_table(verdicts: Sequence[Verdict], *, floors: Mapping[str, float] | None = None, caption: str = "") -> Table:
    """The verdicts as one table of :data:`nfarm.study.result_tables.VERDICT_COLUMNS` (machine-readable: chapter 08 and
    the index read it back with :func:`nfarm.study.result_tables.read_verdicts`)."""
    floors = floors or {}
    # three digits of the long tables' four (DIGITS), as every page reading those shows them: no double rounding
    fmt = lambda v, unit: shown(float(format(v, DIGITS)), ".3g", **({"floor": floors[unit]} if unit in floors else {}))   # noqa: E731
    return Table(list(VERDICT_COLUMNS),
                 [[v.arm, v.task, v.metric, v.unit, v.best, fmt(v.best_value, v.unit), v.anfis, fmt(v.anfis_value, v.unit),
                   fmt(v.anfis_low, v.unit), fmt(v.anfis_high, v.unit), v.rank, v.compared, v.rival,
                   fmt(v.rival_value, v.unit), fmt(v.rival_low, v.unit), fmt(v.rival_high, v.unit), fmt(v.gap, v.unit),
                   fmt(v.gap_low, v.unit), fmt(v.gap_high, v.unit), v.interval, v.verdict, v.anfis_targets,
                   v.rival_targets, v.exact, p_text(v.p, v.draws), p_text(v.holm_p, v.draws), v.comparisons or ""]
                  for v in verdicts], caption=caption)


def p_text(p: float, draws: int) -> str:
    """A bootstrap p-value as a table shows it: two digits, or ``< 2/draws`` where no resample
    reached 0 (its resolution); ``""`` where there is none.

    >>> p_text(0.0, 2000), p_text(0.01234, 2000), p_text(float("nan"), 2000)
    ('< 0.001', '0.012', '')
    """
    if not math.isfinite(p):
        return ""
    floor = 2 / draws if draws else 0.0
    return f"< {floor:.2g}" if p < floor or p == 0 else f"{p:.2g}"
