"""The study's result in one long table (chapters 07 and 08): every method's errors on held-out
data, each metric with its percentile-bootstrap interval, machine-readable.

One :class:`Row` per task, method and metric, with ``value``, ``ci_low``, ``ci_high`` and ``n``
(the resamples) and what was resampled (``spread``):

* **inverse kinematics** (:func:`ik_rows`): the worst joint's RMSE [deg] and the median, 95th
  percentile and largest tool position [mm] and orientation [deg] errors of ``fk(predicted q)``,
  resampling the **test poses** (each drawn on its own, so independent);
* **inverse dynamics** (:func:`id_rows`): each joint's NRMSE [%] (or RMSE [N·m] against measured
  torques), the worst joint's — over the joints whose torque a sensor resolves
  (:func:`nfarm.study.statistics.resolved_joints`) — and the largest absolute torque error [N·m],
  resampling the **test trajectories** (a trajectory's samples are correlated:
  :mod:`nfarm.study.statistics`).

:func:`ik_difference` and :func:`largest_difference` compare two methods on the same resamples
(paired), so a chapter says where a baseline wins only when the interval of the difference
excludes 0. The median and the 95th percentile are the reader's; the maximum is reported because
the worst case is what a controller meets, **without an interval**: the percentile bootstrap of
a sample's maximum has the maximum itself as its upper end (measured: "70.4 (27.7–70.4)"), an
interval that says nothing of how much larger the next test set's worst case could be. Such a
row has ``low == high == value`` and ``n == 0``; comparisons of maxima are made on paired
differences only.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace
from typing import Callable, Mapping, Sequence

import numpy as np

from ..learning.baselines import label as baseline_label
from ..model.robot import Robot
from ..presentation.tables import Table, shown
from ..presentation.wording import times
from .contest import with_tier_finalists
from .statistics import (Estimate, bootstrap_counts, bootstrap_nrmse, bootstrap_rows, bootstrap_seeds, holm,
                         nrmse_from_sums, resampled_quantile, resolved_joints)
from .sweep import Replicates, Sweep, best_by, by_configuration, sweep_results

__all__ = ["ORIENTATION_BY_STRUCTURE_DEG", "orientation_by_structure", "IK_METRICS", "Row", "DIGITS", "SUMMARY_FLOORS", "published", "rows_from_table", "pooled_rows", "pooled_pairs", "ik_rows", "id_rows", "ik_difference", "largest_difference", "ik_seed_values", "seed_comparison", "seed_estimates",
           "long_table", "wide_table", "interval_text", "best_id_baseline",
           "resolved_sums", "bootstrap_resolved", "resolved_on_validation", "with_resolved_worst", "WORST_ID",
           "target_verdict", "IK_TARGETS", "ID_TARGET_PCT", "VERDICT_COLUMNS", "VERDICT_HEAD", "verdict_display", "reader_label", "Verdict", "task_verdict", "targets_met",
           "verdict_table", "read_verdicts", "conclusion", "with_holm", "p_text", "FAMILY_ALPHA", "NO_DIFFERENCE", "ROLES", "ROLE_CHOSEN", "ROLE_RECIPE", "ROLE_BEST_BASELINE", "ROLE_EXACT", "ROLE_LEARNED_ALONE",
           "ROLE_DESIGN", "ROLE_PHYSICS", "ROLE_NUMERICAL", "ROLE_FRICTION_ID", "ROLE_RESIDUAL_BASELINE",
           "ROLE_TIER_ANFIS", "ROLE_TIER_RIVAL", "Paired", "abstract_pairs", "paired_rows", "paired_table",
           "read_paired", "paired_judge", "paired_difference"]

#: The ID rows' worst-joint metric: over the joints a sensor resolves (:func:`id_rows`).
WORST_ID = "worst resolved joint NRMSE"

# The roles of the summary rows :func:`abstract_lines` reads. The chapters write their rows with
# these labels and the abstract finds its rows by them, matched whole: a label reworded on one side
# only is caught by tests/test_summary.py rather than silently dropped from the abstract.
#: The chosen model (IK, ID, and the residual model of the measured arm).
ROLE_CHOSEN = "learned (chosen)"
#: The dissertation's IK recipe (the first such method listed is the one compared).
ROLE_RECIPE = "dissertation's recipe (assumed)"
#: The best baseline, chosen on validation data (IK and ID).
ROLE_BEST_BASELINE = "best baseline (on validation)"
#: The closed-form IK.
ROLE_EXACT = "exact reference"
#: The dissertation's ID design (each joint's own state).
ROLE_DESIGN = "dissertation's design (assumed)"
#: The identification of the inertial parameters on the known geometry.
ROLE_PHYSICS = "physics-informed reference"
#: Newton–Euler alone on the measured arm (and LM in the IK rows).
ROLE_NUMERICAL = "numerical reference"
#: The least-squares friction identification on the measured arm.
ROLE_FRICTION_ID = "baseline (friction identification)"
#: The best learner as a residual on the measured arm, chosen on validation data.
ROLE_RESIDUAL_BASELINE = "baseline (learner as residual, on validation)"
#: The chosen ANFIS trained on the measured torques alone, without Newton–Euler.
ROLE_LEARNED_ALONE = "learned alone (no rigid-body model)"
#: The ANFIS finalist of a tier of prior knowledge on the measured arm (chapter 6.8's contest).
ROLE_TIER_ANFIS = "ANFIS of its tier (on validation)"
#: The best rival of a tier of prior knowledge on the measured arm (chapter 6.8's contest).
ROLE_TIER_RIVAL = "best rival of its tier (on validation)"
#: Every role :func:`abstract_lines` reads.
ROLES = (ROLE_CHOSEN, ROLE_RECIPE, ROLE_BEST_BASELINE, ROLE_EXACT, ROLE_DESIGN, ROLE_PHYSICS, ROLE_NUMERICAL,
         ROLE_FRICTION_ID, ROLE_RESIDUAL_BASELINE, ROLE_LEARNED_ALONE, ROLE_TIER_ANFIS, ROLE_TIER_RIVAL)


# (metric, unit) of the IK rows, in order; the first is left out for a method whose joint angles
# are another branch's (LM: its "errors" reach the same pose).
IK_METRICS = (("worst joint RMSE", "deg"), ("position median", "mm"), ("position p95", "mm"),
              ("position max", "mm"), ("orientation median", "deg"), ("orientation p95", "deg"),
              ("orientation max", "deg"))


@dataclass(frozen=True)
class Row:
    """One method's value of one metric on held-out data and its interval (``low``, ``high``
    at coverage ``level``, from ``n`` resamples of ``spread``); ``n == 0``: a maximum, shown
    without an interval (``low == high == value``)."""

    task: str
    method: str
    role: str
    metric: str
    unit: str
    value: float
    low: float
    high: float
    n: int
    level: float
    spread: str
    arm: str = ""


def _ik_columns(errors: Mapping[str, np.ndarray]) -> np.ndarray:
    """``(N, n + 2)``: each pose's joint errors [deg], tool position [mm] and orientation [deg]
    error (:func:`nfarm.learning.learned.ik_errors`' record)."""
    joint = np.degrees(np.asarray(errors["joint"], float))
    position = 1e3 * np.asarray(errors["position"], float)
    orientation = np.degrees(np.asarray(errors["orientation"], float))
    if joint.ndim != 2 or position.shape != (len(joint),) or orientation.shape != (len(joint),):
        raise ValueError(f"errors must hold joint (N, n), position (N,) and orientation (N,), got shapes "
                         f"{joint.shape}, {position.shape} and {orientation.shape}")
    return np.column_stack([joint, position, orientation])


def _pooled_ik(metric: str) -> tuple[slice, Callable[[np.ndarray], np.ndarray]]:
    """The columns of :func:`_ik_columns` that one IK metric reads, and the metric of pooled rows of
    those columns ``X (b, M, k) -> (b,)``, as :func:`_ik_statistic` computes it."""
    if metric not in [m for m, _ in IK_METRICS]:
        raise ValueError(f"metric must be one of the IK metrics {[m for m, _ in IK_METRICS]}, got {metric!r}")
    if metric == "worst joint RMSE":
        return slice(None, -2), lambda X: np.sqrt((X ** 2).mean(axis=-2)).max(axis=-1)     # noqa: E731
    where, what = metric.split()
    reduce = {"median": lambda x: np.median(x, axis=-1), "p95": lambda x: np.percentile(x, 95, axis=-1),
              "max": lambda x: x.max(axis=-1)}[what]
    return (slice(-2, -1) if where == "position" else slice(-1, None)), lambda X: reduce(X[..., 0])   # noqa: E731


def _ik_statistic(columns: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """``counts (b, N) -> (b, 7)``: the metrics of :data:`IK_METRICS` (as :func:`_pooled_ik`
    computes them) of the rows of ``columns`` (:func:`_ik_columns`, ``(N, n + 2)``) drawn
    ``counts`` times each (:func:`nfarm.study.statistics.bootstrap_counts`): the joint RMSE
    from ``counts @ e²``, the medians, 95th percentiles and maxima as order statistics
    (:func:`nfarm.study.statistics.resampled_quantile`)."""
    squares = columns[:, :-2] ** 2
    tools = []
    for k in (-2, -1):                                           # position, orientation
        order = np.argsort(columns[:, k], kind="stable")
        tools.append((order, columns[order, k]))
    quantile = {"median": 0.5, "p95": 0.95, "max": 1.0}

    def statistic(counts):
        out = {"worst joint RMSE": np.sqrt(counts.astype(float) @ squares / len(columns)).max(axis=-1)}
        for where, (order, x) in zip(("position", "orientation"), tools):
            running = np.cumsum(counts[:, order], axis=1)
            for what, q in quantile.items():
                out[f"{where} {what}"] = resampled_quantile(x, running, q)
        return np.stack([out[metric] for metric, _ in IK_METRICS], axis=-1)
    return statistic


def ik_rows(method: str, role: str, errors: Mapping[str, np.ndarray], *, joint: bool = True,
            task: str = "inverse kinematics", draws: int = 2000, level: float = 0.95,
            seed: int = 0, arm: str = "") -> list[Row]:
    """The IK metrics (:data:`IK_METRICS`) of one method's test-pose ``errors`` with their
    intervals over the poses; ``joint=False`` leaves out the joint RMSE (another branch's);
    ``arm`` names the arm when rows of several go in one table."""
    columns = _ik_columns(errors)
    est = bootstrap_counts(len(columns), _ik_statistic(columns), draws=draws, level=level, seed=seed)
    spread = f"bootstrap over {len(columns):,} test poses"
    extreme = f"the largest of {len(columns):,} test poses (a maximum: no interval)"
    return [Row(task, method, role, metric, unit, float(est.value[k]), float(est.value[k]), float(est.value[k]),
                0, level, extreme, arm) if metric.endswith(" max") else
            Row(task, method, role, metric, unit, float(est.value[k]), float(est.low[k]), float(est.high[k]),
                draws, level, spread, arm)
            for k, (metric, unit) in enumerate(IK_METRICS) if joint or k > 0]


def ik_difference(errors_a: Mapping, errors_b: Mapping, *, draws: int = 2000, level: float = 0.95,
                  seed: int = 0) -> Estimate:
    """Each IK metric of method a less method b's on the **same** test poses, with the paired
    interval (both recomputed on each resample of the poses): ``(7,)`` arrays in the order of
    :data:`IK_METRICS`. An interval that holds 0 is no difference."""
    a, b = _ik_columns(errors_a), _ik_columns(errors_b)
    if a.shape != b.shape:
        raise ValueError(f"the two methods must be judged on the same poses, got {a.shape} and {b.shape}")
    stat_a, stat_b = _ik_statistic(a), _ik_statistic(b)
    return bootstrap_counts(len(a), lambda counts: stat_a(counts) - stat_b(counts),
                            draws=draws, level=level, seed=seed)


def _pooled_worst(resolved, normalised: bool) -> Callable[[np.ndarray], np.ndarray]:
    """``X (b, M, 1 + 3n) -> (b,)``: the worst ``resolved`` joint's NRMSE (RMSE) of pooled trajectory sums."""
    keep = None if resolved is None else np.asarray(resolved, bool)
    def statistic(X):
        per_joint = nrmse_from_sums(X.sum(axis=-2), normalised=normalised)
        return np.nanmax(per_joint if keep is None else per_joint[..., keep], axis=-1)
    return statistic


def ik_seed_values(errors: Sequence[Mapping[str, np.ndarray]]) -> np.ndarray:
    """``(S, N, n + 2)``: each seed's model's IK errors on the same test poses (a list, one
    :func:`nfarm.learning.learned.ik_errors` record per seed), as :func:`seed_comparison` takes
    them."""
    return np.stack([_ik_columns(e) for e in errors])


def seed_comparison(values: Mapping[str, np.ndarray], anfis: str, rival: str, metric: str, *, ik: bool = False,
                    resolved=None, normalised: bool = True, draws: int = 2000, level: float = 0.95,
                    seed: int = 0) -> tuple[dict[str, Estimate], Estimate]:
    """Every method's ``metric`` over its seeds' models and the test units, with the two-level
    interval (:func:`nfarm.study.statistics.bootstrap_seeds`), and the ANFIS's paired difference
    from ``rival`` on the seeds both have (seed ``s`` of each trained on the same draw of data).

    ``values``: method → ``(S, N, k)`` — with ``ik=True`` its seeds' IK errors (:func:`ik_seed_values`;
    ``metric`` one of :data:`IK_METRICS`, e.g. ``"position p95"``), else its seeds' trajectory sums
    (:func:`nfarm.study.statistics.trajectory_sums` stacked; the worst joint's NRMSE over the
    ``resolved`` joints, its RMSE with ``normalised=False``, ``metric`` its name); each method's seeds in the same
    order (a method pruned after seed 0 has one). Returns the estimates by method and the
    difference's (ANFIS minus rival): an interval holding 0 is no difference.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> sums = {m: np.abs(rng.normal(size=(3, 20, 4))) + 1 for m in ("ANFIS", "ridge")}
        >>> sums["ridge"][..., 1] *= 4                       # the ridge's squared errors four times larger
        >>> est, gap = seed_comparison(sums, "ANFIS", "ridge", "worst NRMSE", normalised=False, draws=200)
        >>> bool(gap.high < 0), est["ANFIS"].seeds, gap.seeds
        (True, 3, 3)
    """
    boot = {"draws": draws, "level": level, "seed": seed}
    values, statistic = _seed_metric(values, metric, ik, resolved, normalised)
    estimates = {name: bootstrap_seeds(v, statistic, **boot) for name, v in values.items()}
    a, b = np.asarray(values[anfis], float), np.asarray(values[rival], float)
    common = min(len(a), len(b))
    if a.shape[1:] != b.shape[1:]:
        raise ValueError(f"the two methods must be judged on the same test units, got {a.shape} and {b.shape}")
    width = a.shape[-1]
    gap = bootstrap_seeds(np.concatenate([a[:common], b[:common]], axis=-1),
                          lambda X: statistic(X[..., :width]) - statistic(X[..., width:]), **boot)
    return estimates, gap


def _seed_metric(values: Mapping[str, np.ndarray], metric: str, ik: bool, resolved, normalised: bool):
    """The columns of each method's seed values that ``metric`` reads, and its statistic of pooled rows."""
    columns, statistic = _pooled_ik(metric) if ik else (slice(None), _pooled_worst(resolved, normalised))
    return {name: np.asarray(v, float)[..., columns] for name, v in values.items()}, statistic


def seed_estimates(values: Mapping[str, np.ndarray], metric: str, *, ik: bool = False, resolved=None,
                   normalised: bool = True, draws: int = 2000, level: float = 0.95, seed: int = 0) -> dict[str, Estimate]:
    """Every method's ``metric`` over its seeds' models and the test units, with the two-level
    interval: :func:`seed_comparison`'s estimates without the paired difference (the same
    resamples, so the same numbers)."""
    values, statistic = _seed_metric(values, metric, ik, resolved, normalised)
    return {name: bootstrap_seeds(v, statistic, draws=draws, level=level, seed=seed) for name, v in values.items()}


_PER_JOINT = re.compile(r"τ(?P<joint>\d+) (?P<kind>N?RMSE)( \(below noise\))?")
#: The worst-joint metrics of the ID rows: (normalised, over the resolved joints).
_WORST = {"worst joint NRMSE": (True, False), "worst resolved joint NRMSE": (True, True), "worst joint RMSE": (False, False),
          "worst resolved joint RMSE": (False, True), "worst NRMSE": (True, True), "worst NRMSE, every joint": (True, False)}


def _pooled_metric(task: str, metric: str, resolved) -> tuple[slice, Callable[[np.ndarray], np.ndarray], float]:
    """The columns one summary metric reads of a method's seed values, the statistic of their pooled
    rows ``X (b, M, k) -> (b,)`` and its scale to the row's unit: the IK metrics
    (:data:`IK_METRICS`) of :func:`ik_seed_values`, else an ID metric of trajectory sums (a
    joint's NRMSE [%] or RMSE [N·m]; the worst joint's, over the ``resolved`` joints where the
    metric says so). A maximum, or a metric of no such kind, is a one-line ``ValueError``."""
    if task == "inverse kinematics":
        if metric.endswith(" max"):
            raise ValueError(f"{metric}: a maximum is not pooled over seeds")
        columns, statistic = _pooled_ik(metric)
        return columns, statistic, 1.0
    joint = _PER_JOINT.fullmatch(metric)
    if joint:
        j, normalised = int(joint.group("joint")) - 1, joint.group("kind") == "NRMSE"
        return (slice(None), lambda X: nrmse_from_sums(X.sum(axis=-2), normalised=normalised)[..., j],
                100.0 if normalised else 1.0)
    if metric in _WORST:
        normalised, over_resolved = _WORST[metric]
        if over_resolved and resolved is None:
            raise ValueError(f"{metric!r} ({task}) is over the joints a sensor resolves: give resolved for {task!r}")
        return slice(None), _pooled_worst(resolved if over_resolved else None, normalised), 100.0 if normalised else 1.0
    raise ValueError(f"{metric!r} ({task}) is not a metric pooled over seeds")


def pooled_rows(rows: Sequence[Row], values: Mapping[tuple[str, str], np.ndarray], *,
                resolved: Mapping[str, np.ndarray] | None = None, draws: int = 2000, level: float = 0.95,
                seed: int = 0) -> list[Row]:
    """``rows`` (of the chapter's seed's models) with every method chapter 6 trained over several
    seeds pooled over them: for ``(task, method)`` in ``values`` — ``(S, N, k)``, its seeds' test
    errors (:func:`ik_seed_values`) or trajectory sums, as :func:`seed_comparison` takes them —
    with ``S > 1``, each metric's value over all its seeds' models and the test units, with the
    two-level interval (:func:`nfarm.study.statistics.bootstrap_seeds`; its kind in ``spread``).
    Maxima, and methods with one model (trained once, or exact), are kept as they are: their
    interval is over the test units. ``resolved``: task → the joints a sensor resolves, for the
    worst-joint metrics over them.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> errors = [{"joint": rng.normal(0, 0.01, (50, 2)), "position": rng.random(50) * 1e-3,
        ...            "orientation": rng.random(50) * 1e-3} for _ in range(3)]
        >>> rows = ik_rows("ANFIS", ROLE_CHOSEN, errors[0], draws=200)
        >>> pooled = pooled_rows(rows, {("inverse kinematics", "ANFIS"): ik_seed_values(errors)}, draws=200)
        >>> [r.spread for r in pooled if r.metric in ("position median", "position max")]
        ['two-level bootstrap over 3 seeds × 50 test poses', 'the largest of 50 test poses (a maximum: no interval)']
    """
    resolved = resolved or {}
    out = list(rows)
    for (task, method), v in values.items():
        v = np.asarray(v, float)
        if v.ndim != 3 or len(v) < 2:
            continue
        at = [k for k, r in enumerate(out) if r.task == task and r.method == method and r.n]
        if not at:
            continue
        parts = [_pooled_metric(task, out[k].metric, resolved.get(task)) for k in at]
        est = bootstrap_seeds(v, lambda X: np.stack([f(X[..., c]) for c, f, _ in parts], axis=-1),
                              draws=draws, level=level, seed=seed)
        units = "test poses" if task == "inverse kinematics" else "test trajectories"
        for i, (k, (_, _, scale)) in enumerate(zip(at, parts)):
            out[k] = replace(out[k], value=scale * float(est.value[i]), low=scale * float(est.low[i]),
                             high=scale * float(est.high[i]), n=draws, level=level,
                             spread=f"two-level bootstrap over {len(v)} seeds × {v.shape[1]:,} {units}")
    return out


def pooled_pairs(pairs: Sequence[Paired], values: Mapping[tuple[str, str], np.ndarray], *,
                 resolved: Mapping[str, np.ndarray] | None = None, draws: int = 2000, level: float = 0.95,
                 seed: int = 0) -> list[Paired]:
    """``pairs`` (:func:`paired_rows`, the chapter's seed's) each judged over the seeds (``values``
    as :func:`pooled_rows` takes them) where at least one of the two methods has several: model
    ``s`` of each trained on the same draw of data, on the same test units, the difference with its
    paired two-level interval. A method with one model (trained once, or needing no training, as
    Newton–Euler alone) stands as it is beside each of the other's seeds' models: the comparison
    of the two values :func:`pooled_rows` gives. A pair neither of whose methods has several seeds,
    or one without ``values``, is kept as it is (paired over the test units).

    Example:
        >>> from nfarm.study.statistics import trajectory_sums
        >>> rng = np.random.default_rng(0)
        >>> tau, label = rng.normal(size=(100, 2)), np.repeat(np.arange(5), 20)
        >>> sums = lambda scale: trajectory_sums(tau + rng.normal(0, scale, tau.shape), tau, label)  # noqa: E731
        >>> values = {("ID, measured arm", "residual"): np.stack([sums(0.1) for _ in range(3)]),
        ...           ("ID, measured arm", "Newton–Euler alone"): sums(1.0)[None]}
        >>> p = Paired("ID, measured arm", "residual", "Newton–Euler alone", "worst joint RMSE", "N·m", 0, 0, 0, 0, 0.95, "")
        >>> (gap,) = pooled_pairs([p], values, draws=200)
        >>> bool(gap.high < 0), gap.spread
        (True, 'paired two-level bootstrap over 3 seeds × 5 test trajectories')
    """
    resolved = resolved or {}
    out = []
    for p in pairs:
        a, b = (np.asarray(values[p.task, m], float) if (p.task, m) in values else None for m in (p.method, p.against))
        if a is None or b is None or max(len(a), len(b)) < 2:
            out.append(p)
            continue
        common = min(n for n in (len(a), len(b)) if n > 1)
        a, b = (np.repeat(v, common, axis=0) if len(v) == 1 else v[:common] for v in (a, b))
        if a.shape != b.shape:
            raise ValueError(f"{p.method!r} and {p.against!r} must be judged on the same test units, got "
                             f"{a.shape[1:]} and {b.shape[1:]}")
        columns, statistic, scale = _pooled_metric(p.task, p.metric, resolved.get(p.task))
        a, b = a[..., columns], b[..., columns]
        width = a.shape[-1]
        gap = bootstrap_seeds(np.concatenate([a, b], axis=-1),
                              lambda X: statistic(X[..., :width]) - statistic(X[..., width:]),
                              draws=draws, level=level, seed=seed)
        units = "test poses" if p.task == "inverse kinematics" else "test trajectories"
        out.append(replace(p, difference=scale * float(gap.value), low=scale * float(gap.low),
                           high=scale * float(gap.high), n=draws, level=level,
                           spread=f"paired two-level bootstrap over {common} seeds × {a.shape[1]:,} {units}"))
    return out


def _largest(X):
    return X.max(axis=(-2, -1))


def resolved_sums(sums: np.ndarray, resolved) -> np.ndarray:
    """The columns of ``sums (T, 1 + 3n)`` (:func:`nfarm.study.statistics.trajectory_sums`) of the
    joints ``resolved (n,)`` bool marks: ``(T, 1 + 3k)``, so that a worst joint and its
    interval (:func:`nfarm.study.statistics.bootstrap_nrmse`, ``worst_difference``) are taken over
    those joints, on the same resamples as the whole."""
    sums = np.asarray(sums, float)
    n = (sums.shape[-1] - 1) // 3
    resolved = np.asarray(resolved, bool)
    if resolved.shape != (n,) or not resolved.any():
        raise ValueError(f"resolved must mark at least one of the sums' {n} joints, got {resolved.tolist()}")
    keep = np.flatnonzero(resolved)
    return sums[:, np.concatenate([[0], 1 + keep, 1 + n + keep, 1 + 2 * n + keep])]


def bootstrap_resolved(sums: np.ndarray, resolved=None, **options):
    """:func:`nfarm.study.statistics.bootstrap_nrmse` of ``sums`` with its worst joint (value and
    interval) taken over the ``resolved (n,)`` joints (``None``: every joint), on the same
    resamples; ``options`` as that function's."""
    whole = bootstrap_nrmse(sums, **options)
    if resolved is None or np.all(resolved):
        return whole
    sub = bootstrap_nrmse(resolved_sums(sums, resolved), **options)
    return replace(whole, worst=sub.worst, worst_low=sub.worst_low, worst_high=sub.worst_high)


def id_rows(method: str, role: str, sums: np.ndarray, maxima: np.ndarray, joint_names: Sequence[str], *,
            resolved=None, normalised: bool = True, task: str = "inverse dynamics", draws: int = 2000,
            level: float = 0.95, seed: int = 0, arm: str = "") -> list[Row]:
    """The ID metrics of one method on the test trajectories: each joint's NRMSE [%] (with
    ``normalised=False`` its RMSE [N·m]), the worst joint's, and the largest absolute torque
    error [N·m] (a maximum: no interval), with intervals over the trajectories.
    ``sums (T, 1 + 3n)``: :func:`nfarm.study.statistics.trajectory_sums`; ``maxima (T, n)``:
    :func:`nfarm.study.statistics.trajectory_maxima` of the same trajectories.

    ``resolved (n,)`` bool (:func:`nfarm.study.statistics.resolved_joints`): the joints whose torque a
    sensor resolves. Given, the worst joint is taken over them (metric :data:`WORST_ID`) and
    the others' metrics are marked "(below noise)"; ``None``: over every joint ("worst joint
    NRMSE")."""
    sums, maxima = np.asarray(sums, float), np.asarray(maxima, float)
    if maxima.ndim != 2 or len(maxima) != len(sums) or maxima.shape[1] != len(joint_names):
        raise ValueError(f"maxima must be (trajectories={len(sums)}, joints={len(joint_names)}), got {maxima.shape}")
    ci = bootstrap_nrmse(sums, draws=draws, level=level, seed=seed, normalised=normalised)
    scale, name, unit = (100.0, "NRMSE", "%") if normalised else (1.0, "RMSE", "N·m")
    spread = f"bootstrap over {ci.trajectories} test trajectories"
    below = np.zeros(len(joint_names), bool) if resolved is None else ~np.asarray(resolved, bool)
    rows = [Row(task, method, role, f"τ{j + 1} {name}" + (" (below noise)" if below[j] else ""), unit,
                scale * ci.value[j], scale * ci.low[j], scale * ci.high[j], draws, level, spread, arm)
            for j in range(len(joint_names))]
    worst = bootstrap_resolved(sums, resolved, draws=draws, level=level, seed=seed, normalised=normalised)
    rows.append(Row(task, method, role, f"worst joint {name}" if resolved is None else f"worst resolved joint {name}",
                    unit, scale * worst.worst, scale * worst.worst_low, scale * worst.worst_high, draws, level,
                    spread, arm))
    big = float(maxima.max())
    rows.append(Row(task, method, role, "largest error", "N·m", big, big, big, 0, level,
                    f"the largest over {ci.trajectories} test trajectories (a maximum: no interval)", arm))
    return rows


def with_resolved_worst(groups: Sequence[Replicates], resolved, source: str) -> list[Replicates]:
    """A sweep's configurations (:func:`nfarm.study.sweep.by_configuration`) with each seed's
    ``worst_nrmse`` taken over the ``resolved (n,)`` joints of its per-joint metric ``source``
    (``"val_nrmse"`` of a learned-ID cell, ``"nrmse"`` of a baseline's); the all-joint value
    kept as ``worst_nrmse_all``. Means, ranges and :func:`nfarm.study.sweep.best_by` then choose by
    the joints a sensor resolves — the cells themselves are not touched (their results are
    reused)."""
    resolved = np.asarray(resolved, bool)
    if not resolved.any():
        raise ValueError("resolved must mark at least one joint")

    def run(r):
        if source not in r.metrics:
            return r
        values = np.asarray(r.metrics[source], float)
        if values.shape != resolved.shape:
            raise ValueError(f"{source} of a cell has {values.shape[0]} joints, resolved {len(resolved)}")
        return replace(r, metrics={**r.metrics, "worst_nrmse_all": r.metrics.get("worst_nrmse"),
                                   "worst_nrmse": float(values[resolved].max())})
    return [Replicates(tuple(run(r) for r in g.runs)) for g in groups]


def resolved_on_validation(study, directory) -> np.ndarray:
    """``(n,)`` bool: the joints whose torque spread on the study's ID validation trajectories
    (``id_val.npz`` in ``directory``) reaches its sensor noise (:func:`nfarm.study.statistics.resolved_joints`)
    — fixed on validation data, as every choice is, and used alike by chapters 06–08."""
    from .datasets import load

    val = load(directory / "id_val.npz", study.robot, study)
    return resolved_joints(val["tau"].std(axis=0), study.id.noise)


def largest_difference(maxima_a: np.ndarray, maxima_b: np.ndarray, *, draws: int = 2000, level: float = 0.95,
                       seed: int = 0) -> Estimate:
    """The largest torque error of method a less method b's on the same trajectories, with the
    paired interval over resamples of the trajectories."""
    a, b = np.asarray(maxima_a, float), np.asarray(maxima_b, float)
    if a.shape != b.shape:
        raise ValueError(f"the two methods must be judged on the same trajectories, got {a.shape} and {b.shape}")
    width = a.shape[1]
    return bootstrap_rows(np.hstack([a, b]), lambda X: _largest(X[..., :width]) - _largest(X[..., width:]),
                          draws=draws, level=level, seed=seed)


#: The long tables' precision (:func:`long_table`): what every page that quotes a row reads.
DIGITS = ".4g"

#: Each unit's level of rounding in the summary tables (chapters 07 and 08): a value below it is
#: written as such (``< 1e-06``), not as data — LM's tolerances and a float's rounding in degrees
#: and millimetres, an NRMSE [%] at rounding level, a torque error [N·m] on a spread of about 1 N·m.
SUMMARY_FLOORS = {"deg": 1e-6, "mm": 1e-6, "%": 1e-6, "N·m": 1e-8}


def _floor(row: Row, floors: Mapping[str, float]) -> float:
    return floors.get(row.unit, 0.0)


def published(rows: Sequence[Row]) -> list[Row]:
    """``rows`` with their values and interval ends rounded to the long table's precision
    (:data:`DIGITS`), as :func:`long_table` writes them: a chapter that shows a row (its wide
    table, its prose) then says what every page reading the published table says — the three
    significant digits of a reader's copy are taken from the same four, never from the full value
    on one page and the written one on another (a double rounding: 1.23451 to 1.23 from the value,
    to 1.24 from the "1.235" written).

    Example:
        >>> row = Row("inverse kinematics", "m", "chosen", "position p95", "mm", 1.23451, 1.2, 1.3, 2000, 0.95, "")
        >>> published([row])[0].value
        1.235
    """
    return [replace(r, value=float(format(r.value, DIGITS)), low=float(format(r.low, DIGITS)),
                    high=float(format(r.high, DIGITS))) for r in rows]


def rows_from_table(rows: Sequence[Mapping[str, str]], *, arm: str = "") -> list[Row]:
    """The :class:`Row` objects of a long table's text rows (:func:`read_long_table`), for a
    chapter that shows another's published rows (chapter 08, each arm's ``07_summary.csv``)
    rather than computing them again. A value written below its floor (``< 1e-06``) comes back as
    half that floor, so that it is shown as it was written with the same floors; a row without an
    interval (a maximum) has ``n == 0``.

    Example:
        >>> text = {"task": "inverse kinematics", "method": "m", "role": "chosen", "metric": "position max",
        ...         "unit": "mm", "value": "6.583", "ci_low": "", "ci_high": "", "n": "0", "level": "", "spread": "max"}
        >>> r = rows_from_table([text], arm="intelbot5")[0]
        >>> r.value, r.low, r.n, r.arm
        (6.583, 6.583, 0, 'intelbot5')
    """
    def number(text: str) -> float:
        return 0.5 * float(text[1:]) if text.strip().startswith("<") else float(text)

    out = []
    for r in rows:
        value = number(r["value"])
        n = int(r.get("n") or 0)
        low, high = (number(r["ci_low"]), number(r["ci_high"])) if n else (value, value)
        out.append(Row(r["task"], r["method"], r["role"], r["metric"], r["unit"], value, low, high, n,
                       float(r["level"]) if r.get("level") else 0.95, r.get("spread", ""), arm or r.get("arm", "")))
    return out


def long_table(rows: Sequence[Row], *, floors: Mapping[str, float] | None = None, caption: str = "") -> Table:
    """The machine-readable table: one line per task, method and metric (columns ``task,
    method, role, metric, unit, value, ci_low, ci_high, n, level, spread``). Values below a
    unit's floor (``floors``: unit → level of rounding) are written as such (``< 1e-06``); a
    maximum (``n`` 0) has no interval: its ``ci_low``, ``ci_high`` and ``level`` are empty."""
    floors = floors or {}
    fmt = lambda v, r: shown(v, DIGITS, floor=_floor(r, floors))   # noqa: E731
    arm = any(r.arm for r in rows)          # a column of arms when the rows are of several
    return Table((["arm"] if arm else []) + ["task", "method", "role", "metric", "unit", "value", "ci_low", "ci_high",
                                             "n", "level", "spread"],
                 [([r.arm] if arm else []) + [r.task, r.method, r.role, r.metric, r.unit, fmt(r.value, r),
                                              *((fmt(r.low, r), fmt(r.high, r)) if r.n else ("", "")), r.n,
                                              f"{r.level:g}" if r.n else "", r.spread]
                  for r in rows], caption=caption)


def interval_text(row: Row, floors: Mapping[str, float] | None = None, digits: str = ".3g") -> str:
    """``value (low–high)`` of a row for a reader; one value when the interval is a point. A
    joint whose torque lies below the sensor noise (its metric marked "(below noise)") gets two
    significant digits and no interval: its value is no evidence, and its spread is noise's."""
    floor = _floor(row, floors or {})
    if row.metric.endswith("(below noise)"):
        return shown(row.value, ".2g", floor=floor)
    value, low, high = (shown(v, digits, floor=floor) for v in (row.value, row.low, row.high))
    return value if low == high == value else f"{value} ({low}–{high})"


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


def wide_table(rows: Sequence[Row], task: str, *, floors: Mapping[str, float] | None = None,
               caption: str = "") -> Table:
    """For a reader: one line per method of ``task``, one column per metric, each cell the value
    and its interval (``—`` where a method has no such metric)."""
    chosen = [r for r in rows if r.task == task]
    metrics = list(dict.fromkeys((r.metric, r.unit) for r in chosen))
    methods = list(dict.fromkeys((r.arm, r.method, r.role) for r in chosen))
    cell = {(r.arm, r.method, r.metric): r for r in chosen}
    arm = any(r.arm for r in chosen)
    return Table((["arm"] if arm else []) + ["method", "role", *(f"{m} [{u}]" for m, u in metrics)],
                 [([a] if arm else []) + [m, role, *(interval_text(cell[a, m, metric], floors) if (a, m, metric) in cell
                                                     else "—" for metric, _ in metrics)]
                  for a, m, role in methods], caption=caption)


def best_id_baseline(sweep: Sweep, sweeps_dir=None, *, seed: int = 0, workers: int | None = None,
                     resolved=None, seeds: Sequence[int] | None = None):
    """The best scikit-learn baseline of a baselines sweep (``params/sweeps/id_baselines.yaml``,
    restricted to one arm), as chapter 6.5 chooses it: each learner's best configuration by its
    worst-joint NRMSE on validation with seed 0, where every configuration ran (over the
    ``resolved`` joints, :func:`with_resolved_worst`; ``None``: every joint), the best of those
    (least squares on ``q, q̇, q̈``, the floor, left out), over its seeds (each tier's best ran on
    more, :func:`nfarm.study.contest.with_tier_finalists`: ``seeds``, by default its), and that configuration's run on the
    test split with ``seed`` (run now if it is not in ``sweeps_dir``). Returns ``(name,
    validation Replicates, test CellResult)``, or ``None`` if the sweep holds no learner but the
    floor."""
    unseeded = lambda p: {k: v for k, v in p.items() if k != "seed"}          # noqa: E731
    seed0 = sweep_results(sweep, sweeps_dir, workers=workers)
    if not seed0:
        return None
    joints = np.ones(len(seed0[0].metrics["nrmse"]), bool) if resolved is None else np.asarray(resolved, bool)
    more = {} if seeds is None else {"seeds": tuple(seeds)}
    val = with_resolved_worst(by_configuration(with_tier_finalists(sweep, joints, "nrmse", sweeps_dir, workers=workers,
                                                                   seed0=seed0, **more)), joints, "nrmse")
    learners = [g for learner, g in best_by(val, "learner", "worst_nrmse", seed=0).items() if learner != "linear"]
    if not learners:
        return None
    best = min(learners, key=lambda g: g.values("worst_nrmse")[0])
    config = unseeded(best.cell.params)
    test = sweep_results(sweep.select(lambda p: unseeded(p) == config).restrict(split="test", seed=seed),
                         sweeps_dir, workers=workers)
    return baseline_label(best.cell.params), best, test[0]


# --------------------------------------------------------------------------------------------
# The report's abstract, from the published long tables


def read_long_table(path) -> list[dict[str, str]]:
    """The rows of a long table written by :func:`long_table` (``07_summary.csv``), as dicts
    of its columns' text; a file without the table's columns is refused with a one-line error."""
    import csv
    from pathlib import Path

    path = Path(path)
    with path.open(encoding="utf-8", newline="") as f:
        rows = list(csv.DictReader(f))
    needed = {"task", "method", "role", "metric", "unit", "value", "ci_low", "ci_high"}
    if rows and not needed <= set(rows[0]):
        raise ValueError(f"{path}: not a summary table: columns {', '.join(sorted(needed - set(rows[0])))} missing")
    return rows


def _number(text: str) -> float:
    """A table's value as a number; ``< 1e-06`` (below a floor) as 0."""
    return 0.0 if text.startswith("<") else float(text)


def _three(text: str) -> str:
    """A table's number (written to four significant digits) to three, as the chapters write
    them; ``< 1e-06`` and empty cells as they are."""
    return text if not text or text.startswith("<") else shown(float(text), ".3g")


def _with_interval(row: Mapping[str, str]) -> str:
    """``value unit (low–high)``; an interval over the test units alone (not pooled over seeds:
    :func:`pooled_rows`) says so."""
    value, low, high = (_three(row[k]) for k in ("value", "ci_low", "ci_high"))
    unit = {"deg": "°", "%": " %", "mm": " mm", "N·m": " N·m"}.get(row["unit"], f" {row['unit']}")
    spread = row.get("spread", "")
    kind = "" if not spread or spread.startswith("two-level") else \
        f", test {'poses' if 'poses' in spread else 'trajectories'} only"
    return f"{value}{unit}" if low == high == value or not (low or high) else f"{value}{unit} ({low}–{high}{kind})"


@dataclass(frozen=True)
class Paired:
    """Method ``method`` less method ``against`` on one metric, judged on the same test units
    (poses or trajectories): the ``difference`` and its paired percentile-bootstrap interval
    (``low``, ``high`` at coverage ``level`` from ``n`` resamples of ``spread``); ``n == 0``: a
    maximum, no interval (not judged)."""

    task: str
    method: str
    against: str
    metric: str
    unit: str
    difference: float
    low: float
    high: float
    n: int
    level: float
    spread: str


def _row_text(row) -> Mapping[str, str]:
    """A :class:`Row` as the text fields :func:`abstract_lines` reads (a row read back from a
    long table already is)."""
    if isinstance(row, Row):
        return {"task": row.task, "method": row.method, "role": row.role, "metric": row.metric,
                "unit": row.unit, "value": repr(row.value), "ci_low": repr(row.low) if row.n else "",
                "ci_high": repr(row.high) if row.n else "", "n": str(row.n), "spread": row.spread}
    return row


def paired_judge(paired: Sequence[Mapping[str, str]], floors: Mapping[str, float] = SUMMARY_FLOORS):
    """The comparison :func:`abstract_lines` makes of two rows of one task and metric: -1 when
    ours is lower on the paired interval of ours less theirs (``paired``, rows of
    :func:`paired_table` as text; :func:`paired_difference`), +1 when higher, 0 when the
    interval holds 0, lies within the unit's floor of rounding (``floors``: two models that
    compute a quantity alike, e.g. the orientation both take from the pitch closure, differ by
    1e-15 — not a difference), or either row is a maximum without an interval. A comparison with
    no paired row is an error naming it."""
    def judge(ours: Mapping[str, str], theirs: Mapping[str, str]) -> int:
        if "0" in (ours.get("n"), theirs.get("n")):
            return 0
        _, low, high = paired_difference(paired, ours["task"], ours["method"], theirs["method"], ours["metric"])
        if max(abs(low), abs(high)) <= floors.get(ours.get("unit", ""), 0.0):
            return 0
        return -1 if high < 0 else 1 if low > 0 else 0
    return judge


#: An IK model whose orientation error's 95th percentile stays below this [deg] does not learn the
#: orientation: its structure sets it (the pitch closure and the first and last joints' linear rules
#: of the arm's structure give it to 1e-5°, what a learner of all the joints reaches at best
#: to 1e-2°), so no orientation comparison is claimed for it (issue 64).
ORIENTATION_BY_STRUCTURE_DEG = 1e-3


def orientation_by_structure(rows: Mapping[str, Mapping[str, str]]) -> bool:
    """Whether a method's IK rows (metric → text row) say that its structure, not its learner, sets
    its orientation (:data:`ORIENTATION_BY_STRUCTURE_DEG`, on the upper end of the orientation p95's
    interval).

    Example:
        >>> orientation_by_structure({"orientation p95": {"value": "9e-06", "ci_high": "1e-05", "unit": "deg"}})
        True
        >>> orientation_by_structure({"orientation p95": {"value": "0.02", "ci_high": "0.03", "unit": "deg"}})
        False
    """
    row = rows.get("orientation p95")
    if row is None:
        return False
    top = row.get("ci_high") or row["value"]
    return _number(top) < ORIENTATION_BY_STRUCTURE_DEG


def paired_difference(paired: Sequence[Mapping[str, str]], task: str, method: str, against: str,
                      metric: str) -> tuple[float, float, float]:
    """``method`` less ``against`` on ``metric`` of ``task``, and its paired interval, read from a
    paired table's text rows (:func:`read_paired`; the pair written either way round, its sign
    turned then); a pair the table lacks is a one-line ``ValueError`` naming it.

    Example:
        >>> row = {"task": "t", "method": "a", "against": "b", "metric": "m", "difference": "0.5",
        ...        "ci_low": "0.25", "ci_high": "0.75"}
        >>> paired_difference([row], "t", "b", "a", "m")
        (-0.5, -0.75, -0.25)
    """
    for p in paired:
        if (p["task"], p["metric"]) != (task, metric):
            continue
        if (p["method"], p["against"]) == (method, against):
            return _number(p["difference"]), _number(p["ci_low"]), _number(p["ci_high"])
        if (p["method"], p["against"]) == (against, method):
            return -_number(p["difference"]), -_number(p["ci_high"]), -_number(p["ci_low"])
    raise ValueError(f"no paired difference of {method!r} against {against!r} on {metric} ({task}) in the paired "
                     f"table (07_paired.csv)")


def abstract_pairs(rows) -> list[tuple[str, str, str, str]]:
    """``(task, method, against, metric)`` of every comparison :func:`abstract_lines` makes of
    ``rows`` (:class:`Row` objects or a long table's text rows): the paired differences a
    chapter computes for it (:func:`paired_rows`)."""
    pairs = []

    def record(ours, theirs):
        if "0" not in (ours.get("n"), theirs.get("n")):
            pairs.append((ours["task"], ours["method"], theirs["method"], ours["metric"]))
        return 0
    _abstract("", [_row_text(r) for r in rows], record)
    return list(dict.fromkeys(pairs))


def paired_rows(pairs, *, ik_errors: Mapping[str, Mapping] | None = None,
                id_sums: Mapping[str, np.ndarray] | None = None, resolved=None,
                measured_sums: Mapping[str, np.ndarray] | None = None, measured_resolved=None,
                draws: int = 2000, level: float = 0.95, seed: int = 0) -> list[Paired]:
    """The paired difference of each ``(task, method, against, metric)`` of ``pairs``
    (:func:`abstract_pairs`), each pair judged on the same resamples of the same test units:
    the IK metrics over the test poses (:func:`ik_difference`, from ``ik_errors[name]``); the
    worst (resolved) joint's NRMSE over the test trajectories from ``id_sums[name]``
    (:func:`nfarm.study.statistics.worst_difference`; ``resolved`` as :func:`id_rows` takes it);
    on the measured arm from ``measured_sums[name]`` the worst joint's RMSE, or its NRMSE against
    the measured spread over the ``measured_resolved`` joints ("worst NRMSE", what the study's
    target and the verdict judge) or over every joint ("worst NRMSE, every joint")."""
    from .statistics import worst_difference

    boot = dict(draws=draws, level=level, seed=seed)
    ik_units = {m: u for m, u in IK_METRICS}
    cache = {}
    out = []
    for task, a, b, metric in pairs:
        if task == "inverse kinematics":
            if (a, b) not in cache:
                cache[a, b] = ik_difference(ik_errors[a], ik_errors[b], **boot)
            est, k = cache[a, b], [m for m, _ in IK_METRICS].index(metric)
            value, low, high, unit = est.value[k], est.low[k], est.high[k], ik_units[metric]
            spread = f"paired bootstrap over {est.rows:,} test poses"
        elif task == "inverse dynamics" and metric in (WORST_ID, "worst joint NRMSE"):
            keep = resolved if metric == WORST_ID else None
            sa, sb = (id_sums[x] if keep is None else resolved_sums(id_sums[x], keep) for x in (a, b))
            value, low, high = (100 * v for v in worst_difference(sa, sb, **boot))
            unit, spread = "%", f"paired bootstrap over {len(sa)} test trajectories"
        elif task == "ID, measured arm" and metric == "worst joint RMSE":
            value, low, high = worst_difference(measured_sums[a], measured_sums[b], normalised=False, **boot)
            unit, spread = "N·m", f"paired bootstrap over {len(measured_sums[a])} test trajectories"
        elif task == "ID, measured arm" and metric in ("worst NRMSE", "worst NRMSE, every joint"):
            keep = measured_resolved if metric == "worst NRMSE" else None
            sa, sb = (measured_sums[x] if keep is None else resolved_sums(measured_sums[x], keep) for x in (a, b))
            value, low, high = (100 * v for v in worst_difference(sa, sb, **boot))
            unit, spread = "%", f"paired bootstrap over {len(sa)} test trajectories"
        else:
            raise ValueError(f"no paired difference for {metric!r} of {task!r}")
        out.append(Paired(task, a, b, metric, unit, float(value), float(low), float(high), draws, level, spread))
    return out


def paired_table(pairs: Sequence[Paired], *, floors: Mapping[str, float] | None = None,
                 caption: str = "") -> Table:
    """The paired differences as a table (columns ``task, method, against, metric, unit,
    difference, ci_low, ci_high, n, level, spread``); differences below a unit's floor written
    as such."""
    floors = floors or {}
    fmt = lambda v, p: shown(v, DIGITS, floor=floors.get(p.unit, 0.0))   # noqa: E731
    return Table(["task", "method", "against", "metric", "unit", "difference", "ci_low", "ci_high", "n", "level",
                  "spread"],
                 [[p.task, p.method, p.against, p.metric, p.unit, fmt(p.difference, p), fmt(p.low, p), fmt(p.high, p),
                   p.n, f"{p.level:g}", p.spread] for p in pairs], caption=caption)


def read_paired(path) -> list[dict[str, str]]:
    """The rows of a paired table (:func:`paired_table`, ``07_paired.csv``) as dicts of their
    columns' text; a file without its columns is refused in one line."""
    import csv
    from pathlib import Path

    path = Path(path)
    with path.open(encoding="utf-8", newline="") as f:
        rows = list(csv.DictReader(f))
    needed = {"task", "method", "against", "metric", "ci_low", "ci_high"}
    if rows and not needed <= set(rows[0]):
        raise ValueError(f"{path}: not a paired table: columns {', '.join(sorted(needed - set(rows[0])))} missing")
    return rows



def _times_of(ours: Mapping[str, str], theirs: Mapping[str, str]) -> str:
    """"2.2 times" or "85 % of": ours's value over theirs's, in words (:func:`times`)."""
    return times(_number(ours["value"]) / _number(theirs["value"]))


_VERDICT = {-1: "better than", 1: "worse than", 0: "not shown to differ from"}


def abstract_lines(arm: str, rows: Sequence[Mapping[str, str]],
                   paired: Sequence[Mapping[str, str]]) -> list[str]:
    """Plain-text sentences (one per task) of one arm's answers, every number read from its
    summary rows: the chosen ANFIS, the dissertation's design (assumed), the best baseline and
    the references; every comparison ("better", "worse", "not shown to differ") on the paired
    interval of the two methods' difference over the same test units (``paired``: the rows of
    :func:`paired_table`, as text; :func:`abstract_pairs` lists the ones needed). Rows are
    found by their whole role (:data:`ROLES`)."""
    return _abstract(arm, rows, paired_judge(paired))


def _abstract(arm: str, rows: Sequence[Mapping[str, str]], _compare) -> list[str]:
    """:func:`abstract_lines` with its comparison ``_compare(ours, theirs) -> -1, 0, 1``."""
    def _verdict(ours, theirs):
        return _VERDICT[_compare(ours, theirs)]

    def find(task, role, metric):
        return next((r for r in rows if r["task"] == task and r["role"] == role and r["metric"] == metric), None)

    lines = []
    task = "inverse kinematics"
    chosen = [r for r in rows if r["task"] == task and r["role"] == ROLE_CHOSEN]
    if chosen:
        get = {r["metric"]: r for r in chosen}
        text = (f"{arm}, inverse kinematics: the chosen model, {reader_label(chosen[0]['method'])}, misses by "
                f"{_with_interval(get['worst joint RMSE'])} on its worst joint; the tool lands "
                f"{_with_interval(get['position median'])} from the target at the median, "
                f"{_with_interval(get['position p95'])} at the 95th percentile and "
                f"{_with_interval(get['position max'])} at worst.")
        first = find(task, ROLE_RECIPE, "worst joint RMSE")    # on the region's data: listed first
        recipe = {r["metric"]: r for r in rows if first and r["task"] == task and r["method"] == first["method"]}
        if "worst joint RMSE" in recipe:
            text += (f" The dissertation's recipe (assumed) on the same data: {_with_interval(recipe['worst joint RMSE'])}"
                     f" on its worst joint")
            # no orientation claim where a structure, not a learner, sets either's orientation (issue 64)
            either = orientation_by_structure(get) or orientation_by_structure(recipe)
            better = [f"{m} ({_with_interval(r)} against {_with_interval(get[m])})"
                      for m, r in recipe.items() if m in get and _compare(r, get[m]) < 0
                      and not (either and m.startswith("orientation"))]
            text += ("; it is better than the chosen model on " + "; ".join(better) + " (paired intervals)."
                     if better else ".")
        base = [r for r in rows if r["task"] == task and r["role"] == ROLE_BEST_BASELINE]
        # No orientation claim where the structure, not the learner, sets the orientation (issue 64)
        fixed = orientation_by_structure(get) or orientation_by_structure({r["metric"]: r for r in base})
        if fixed:
            for r in base:       # compared all the same (the paired table keeps every pair), but not claimed
                if r["metric"].startswith("orientation") and r["metric"] in get:
                    _compare(r, get[r["metric"]])
            base = [r for r in base if not r["metric"].startswith("orientation")]
        if base:
            wins = [f"{r['metric']} ({_with_interval(r)} against {_with_interval(get[r['metric']])})"
                    for r in base if r["metric"] in get and _compare(r, get[r["metric"]]) < 0]
            losses = [r["metric"] for r in base if r["metric"] in get and _compare(r, get[r["metric"]]) > 0]
            text += (f" The best baseline on validation, {reader_label(base[0]['method'])}, is better on "
                     + "; ".join(wins) + " (paired intervals)." if wins else
                     f" The best baseline on validation, {reader_label(base[0]['method'])}, is better on no metric (paired "
                     f"intervals).")
            if losses:
                text += f" The ANFIS is better on {', '.join(losses)}."
        if fixed:
            text += (" Their orientation is not compared: where the arm's structure (the pitch closure and linear rules) "
                     "computes it, it is not learned (the chosen model's 95th percentile "
                     f"{_with_interval(get['orientation p95'])}).")
        exact = find(task, ROLE_EXACT, "position max")
        if exact:
            text += f" The closed form is exact (largest tool position error {_with_interval(exact)})."
        lines.append(text)
    task = "inverse dynamics"
    worst = next((m for m in (WORST_ID, "worst joint NRMSE") if find(task, ROLE_CHOSEN, m)), WORST_ID)
    free = find(task, ROLE_CHOSEN, worst)
    if free:
        below = [r["metric"].split()[0] for r in rows if r["task"] == task and r["role"] == ROLE_CHOSEN
                 and r["metric"].endswith("(below noise)")]
        text = (f"{arm}, inverse dynamics without the arm's parameters: the chosen model, {reader_label(free['method'])}, "
                f"misses by {_with_interval(free)} of the worst joint's torque spread (NRMSE"
                + (f"; {' and '.join(below)}, whose torque is below the sensor noise, left out" if below else "")
                + f"), largest error {_with_interval(find(task, ROLE_CHOSEN, 'largest error'))}.")
        base = find(task, ROLE_BEST_BASELINE, worst)
        if base:
            verdict = {-1: "better than the ANFIS", 1: "worse than the ANFIS",
                       0: "not shown to differ from the ANFIS (paired interval)"}[_compare(base, free)]
            text += f" The best baseline on validation, {reader_label(base['method'])}: {_with_interval(base)}, {verdict}."
        recipe = find(task, ROLE_DESIGN, worst)
        if recipe:
            text += f" The dissertation's design (assumed, each joint's own state): {_with_interval(recipe)}."
        ident = find(task, ROLE_PHYSICS, worst)
        if ident:
            text += f" Given the geometry, identifying the inertial parameters: {_with_interval(ident)}."
        lines.append(text)
    task = "ID, measured arm"
    # Judged as the verdict and the study's target judge it: the worst resolved joint's NRMSE against the measured
    # torques' spread; Newton–Euler alone's worst joint RMSE in N·m beside it, for the size of what is left
    nrmse = "worst NRMSE"
    residual = find(task, ROLE_CHOSEN, nrmse)
    if residual:
        alone = find(task, ROLE_NUMERICAL, nrmse)
        alone_nm = find(task, ROLE_NUMERICAL, "worst joint RMSE")
        ls = find(task, ROLE_FRICTION_ID, nrmse)
        learner = find(task, ROLE_RESIDUAL_BASELINE, nrmse)
        text = (f"{arm}, the measured arm (built, not the model; friction; torques from the motor current), by the "
                f"worst resolved joint's NRMSE against the measured torques' spread: Newton–Euler alone leaves "
                f"{_with_interval(alone)}" + (f" ({_with_interval(alone_nm)} on its worst joint)" if alone_nm else "")
                + f", Newton–Euler with an ANFIS residual {_with_interval(residual)}")
        if ls:
            text += f", {_verdict(residual, ls)} the least-squares friction identification ({_with_interval(ls)})"
        built = find(task, ROLE_PHYSICS, nrmse)
        if built:
            text += (f"; identifying the built arm's masses and drives on the known geometry leaves "
                     f"{_with_interval(built)}, {_verdict(built, residual)} the ANFIS residual")
        alone_learned = find(task, ROLE_LEARNED_ALONE, nrmse)
        if alone_learned and alone:
            text += (f"; the best ANFIS without the rigid-body model ({reader_label(alone_learned['method'])}) leaves "
                     f"{_with_interval(alone_learned)}, {_verdict(alone_learned, alone)} Newton–Euler alone")
        if learner:
            text += (f"; the best other learner as a residual, {reader_label(learner['method'])}: {_with_interval(learner)}, "
                     f"{_verdict(learner, residual)} the ANFIS residual")
            ratio = _times_of(residual, learner)
            if _compare(learner, residual) < 0 and ratio != times(1.0):   # "about the same as" beside "better": no
                text += f" (the ANFIS residual leaves {ratio} its error)"
        text += "."
        # The study's ≤ 5 % NRMSE target on the measured torques' spread, with and without the noise-level joints
        for metric, over in (("worst NRMSE", "over the joints a sensor resolves"),
                             ("worst NRMSE, every joint", "over every joint, the noise-level ones included")):
            judged = [r for r in rows if r["task"] == task and r["metric"] == metric]
            if judged:
                met = [reader_label(r["method"]) for r in judged if r.get("n") != "0" and _number(r["ci_high"]) <= 5.0]
                best = min(judged, key=lambda r: _number(r["value"]))
                text += (f" The study's ≤ 5 % target on the measured spread, {over}: "
                         + (f"met by {', '.join(met)}." if met else
                            f"met by none (best {reader_label(best['method'])}, {_with_interval(best)})."))
        lines.append(text)
    return lines


# --------------------------------------------------------------------------------------------
# The study's targets and its verdict

#: The study's targets for the learned IK (``docs/STUDY.md``, "The study's targets"): words, the
#: summary metric (:data:`IK_METRICS`), the upper limit and its unit; each judged on a model's
#: whole interval (:func:`target_verdict`).
IK_TARGETS = (("per-joint RMSE", "worst joint RMSE", 1.0, "°"), ("median position", "position median", 2.0, "mm"),
              ("95th percentile", "position p95", 10.0, "mm"))
#: The study's target for the learned ID: the worst joint's NRMSE, in % of the torque's spread.
ID_TARGET_PCT = 5.0
#: The verdict table's columns (:func:`verdict_table`), as chapter 07 writes them and the index reads them.
VERDICT_COLUMNS = ("arm", "task", "metric", "unit", "best", "best_value", "anfis", "anfis_value", "anfis_low",
                   "anfis_high", "rank", "compared", "rival", "rival_value", "rival_low", "rival_high", "gap", "gap_low",
                   "gap_high", "interval", "verdict", "anfis_targets", "rival_targets", "exact", "p", "holm_p",
                   "comparisons")
#: The family-wise error rate the verdict holds over one arm's comparisons (Holm's correction, :func:`with_holm`).
FAMILY_ALPHA = 0.05
#: The verdict's words where no difference is shown: the interval holds 0, or Holm's correction leaves it.
NO_DIFFERENCE = "no difference shown"


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
    measured arm's "every tier", which repeats its best tier's) is the same test and counts once.
    A row without a p-value (NaN) is left out of the family and keeps its interval's verdict.

    Example:
        >>> v = [task_verdict("a", f"t{k}", "m", "mm", {"ANFIS": 1.0, f"R{k}": 2.0}, "ANFIS", (-1.0, -1.5, -0.5),
        ...                   p=p) for k, p in enumerate([0.001, 0.04, 0.02])]
        >>> [(w.comparisons, round(w.holm_p, 3), w.verdict) for w in with_holm(v)]
        [(3, 0.003, 'ANFIS better'), (3, 0.04, 'ANFIS better'), (3, 0.04, 'ANFIS better')]
        >>> [w.verdict for w in with_holm(v[:2] + [replace(v[2], p=0.03)])]
        ['ANFIS better', 'no difference shown (Holm)', 'no difference shown (Holm)']
        >>> [w.comparisons for w in with_holm(v + [replace(v[0], task="t0, every tier")])]   # the same test twice
        [3, 3, 3, 3]
    """
    key = lambda v: (v.arm, v.metric, v.anfis, v.rival)      # noqa: E731 — one test per pair of methods and metric
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


def targets_met(rows: Sequence[Row], limits: Sequence[float]) -> str:
    """``"k of n"``: how many of one method's ``rows`` meet their ``limits`` on the whole
    interval (:func:`target_verdict`)."""
    return f"{sum(target_verdict(r, limit) == '✓' for r, limit in zip(rows, limits))} of {len(limits)}"


def verdict_table(verdicts: Sequence[Verdict], *, floors: Mapping[str, float] | None = None, caption: str = "") -> Table:
    """The verdicts as one table of :data:`VERDICT_COLUMNS` (machine-readable: chapter 08 and
    the index read it back with :func:`read_verdicts`)."""
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


#: Configuration words a reader knows, and the learners' names in words (:func:`reader_label`).
_CONFIG_WORDS = {"arm_plane": "in the arm's plane", "quat_xyz": "on quaternion and position",
                 "axes_xyz": "on position and two tool axes", "basis=chain": "on the chain's trigonometric basis",
                 "basis=generic": "on the generic basis",
                 "basis=chain_drives": "on the chain's trigonometric basis and the joints' friction terms",
                 "basis=generic_drives": "on the generic basis and the joints' friction terms"}
_LEARNER_WORDS = {"ridge": "ridge regression", "ANFIS, chosen": "ANFIS"}
#: Internal names of input sets and of where a model came from: in the tables, not in prose.
_INTERNAL = {"contest", "affine", "affine_generic", "affine_drives", "affine_generic_drives", "own", "regressor",
             "regressor_drives"}


def reader_label(name: str) -> str:
    """A method's name in words a reader knows, its internal configuration (kept in the tables)
    left out: a trailing parenthesis of options (``basis=chain, alpha=1e-06``), an encoding's or an
    input set's code name, or ``contest``; the configuration words a reader knows are kept.

    Example:
        >>> reader_label("ridge (basis=chain, alpha=1e-06)"), reader_label("ANFIS, chosen (arm_plane)")
        ("ridge regression on the chain's trigonometric basis", "ANFIS in the arm's plane")
        >>> reader_label("RBF interpolation (contest)"), reader_label("generic: multilayer perceptron")
        ('RBF interpolation', 'generic: multilayer perceptron')
    """
    match = re.fullmatch(r"(.*?) \(([^()]*)\)", name)
    if match is None:
        return name
    parts = [part.strip() for part in match[2].split(",")]
    if not all("=" in part or part in _CONFIG_WORDS or part in _INTERNAL for part in parts):
        return name                      # a parenthesis a reader needs ("assumed", "needs the geometry")
    return " ".join([_LEARNER_WORDS.get(match[1], match[1]), *(_CONFIG_WORDS[p] for p in parts if p in _CONFIG_WORDS)])


#: The verdict as a reader sees it (:func:`verdict_display`): the index, the PDF and chapter 8 show these columns.
VERDICT_HEAD = ("task", "arm", "best on held-out data", "ANFIS's best (rank)", "best other",
                "ANFIS − best other (paired interval)", "verdict", "targets met: ANFIS / best other", "interval")


def verdict_display(rows: Sequence[Mapping[str, str]]) -> list[list[str]]:
    """The verdict rows (:func:`read_verdicts`) as the cells of :data:`VERDICT_HEAD`: each method's
    value with its interval and unit, the ANFIS's rank among the methods compared, the paired gap,
    the targets met and what the intervals resampled."""
    def with_interval(r, who):
        value, low, high = r[f"{who}_value"], r[f"{who}_low"], r[f"{who}_high"]
        # an interval where there is one: not around a value at rounding level ("< 1e-6"), nor a missing one
        spread = low and low != "nan" and low != high and not value.startswith("<")
        return f"{reader_label(r[who])}, {value}" + (f" ({low}–{high})" if spread else "") + f" {r['unit']}"
    return [[r["task"], r["arm"], f"{reader_label(r['best'])}, {r['best_value']} {r['unit']}",
             f"{with_interval(r, 'anfis')} ({r['rank']} of {r['compared']})", with_interval(r, "rival"),
             f"{r['gap']} ({r['gap_low']} to {r['gap_high']}) {r['unit']}",
             r["verdict"] + (f" (Holm p {r['holm_p']}, {r['comparisons']} comparisons)"
                             if r.get("holm_p") and not r["verdict"].endswith("(Holm)") else ""),
             f"{r['anfis_targets'] or '—'} / {r['rival_targets'] or '—'}", r["interval"]] for r in rows]


def read_verdicts(path) -> list[dict[str, str]]:
    """The rows of a verdict table written by :func:`verdict_table` (``07_verdict.csv``), as dicts
    of its columns' text; a file without the table's columns is refused with a one-line error."""
    import csv
    from pathlib import Path

    path = Path(path)
    with path.open(encoding="utf-8", newline="") as f:
        rows = list(csv.DictReader(f))
    missing = [c for c in VERDICT_COLUMNS if rows and c not in rows[0]]
    if missing:
        raise ValueError(f"{path}: not a verdict table: columns {', '.join(missing)} missing")
    return rows


#: The columns of chapter 7's table of Levenberg–Marquardt from each start (``07_ik_warm_start.csv``).
WARM_START_COLUMNS = ("start", "targets", "mean iterations")
#: Its rows' names of the starts the conclusion compares (the rival's is "<rival> prediction").
WARM_HOME, WARM_ANFIS, WARM_CLOSED = "home (the dissertation's)", "ANFIS prediction", "closed form (the region's solution)"


def read_warm_starts(path) -> list[dict[str, str]]:
    """The rows of chapter 7's table of LM from each start (``07_ik_warm_start.csv``), as dicts of
    its columns' text; a file without its columns is refused with a one-line error."""
    import csv
    from pathlib import Path

    path = Path(path)
    with path.open(encoding="utf-8", newline="") as f:
        rows = list(csv.DictReader(f))
    missing = [c for c in WARM_START_COLUMNS if not rows or c not in rows[0]]
    if missing:
        raise ValueError(f"{path}: not a table of LM's starts: columns {', '.join(missing)} missing")
    return rows


def contribution(warm_starts: Mapping[str, Sequence[Mapping[str, str]]]) -> str | None:
    """One sentence on what the ANFIS gives the exact solver, as measured: Levenberg–Marquardt's
    mean (and largest) iterations from the ANFIS's prediction, from the home pose and from the
    best rival's prediction, per arm (``warm_starts``: arm -> the rows of
    :func:`read_warm_starts`), the numbers side by side and no comparison the table's means
    cannot carry; ``None`` without an arm that measured both the ANFIS's start and the home pose's."""
    said, closed = [], False
    for arm, rows in warm_starts.items():
        by = {r["start"]: r for r in rows}
        rivals = [s for s in by if s.endswith(" prediction") and s != WARM_ANFIS]
        if WARM_ANFIS not in by or WARM_HOME not in by:
            continue
        closed = closed or WARM_CLOSED in by

        def iterations(start: str) -> str:
            most = by[start].get("max iterations", "")
            return by[start]["mean iterations"] + (f" (at most {most})" if most else "")
        rival = "".join(f" and {iterations(s)} from the prediction of "
                        f"{reader_label(s[:-len(' prediction')].replace(' (contest)', ''))}" for s in rivals[:1])
        said.append(f"{iterations(WARM_ANFIS)}{' iterations' if not said else ''} against {iterations(WARM_HOME)} "
                    f"from the home pose{rival} ({arm})")
    if not said:
        return None
    return ("What the ANFIS gives the exact solver, as measured: started from its prediction, Levenberg–Marquardt "
            "needs on average " + "; ".join(said)
            + ("; from the closed form's solution, none" if closed else "")
            + "; whether such a start saves seconds depends on what the prediction costs, which chapter 7 times on "
              "the reader's machine.")


def conclusion(verdicts: Sequence[Mapping[str, str]],
               warm_starts: Mapping[str, Sequence[Mapping[str, str]]] | None = None) -> list[str]:
    """At most five plain sentences from the verdict rows of every arm (:data:`VERDICT_COLUMNS`,
    as read back from the published tables): where the ANFIS wins beyond the paired interval,
    where another method wins and which (each by its paired gap, in the metric's unit) and where
    no difference is shown, what the ANFIS gives beside the winners (:func:`contribution`, from
    ``warm_starts``, arm -> chapter 7's table of LM's starts), the study's targets the ANFIS
    meets, and what to use for each task. A task ending in "every tier" sums up the tasks of its
    tiers: it gives the targets and what to use, the tiers the wins and losses."""
    def plain(task: str, name: str) -> str:          # "generic: multilayer perceptron" in "…, generic": the learner
        tier, name = task.rsplit(", ", 1)[-1], reader_label(name)
        return name.split(": ", 1)[1] if name.startswith(tier + ": ") else name

    summed = [r for r in verdicts if r["task"].endswith("every tier")]
    judged = [r for r in verdicts if r not in summed]
    tasks = list(dict.fromkeys(r["task"] for r in judged))

    def grouped(kind: str, say) -> list[str]:
        out = []
        for task in tasks:
            rows = [r for r in judged if r["task"] == task and r["verdict"] == kind]
            if rows:
                out.append(f"{task} ({'; '.join(say(r) for r in rows)})")
        return out

    def gap_unit(r: Mapping[str, str]) -> str:       # a gap of two shares: not "% of" one
        return "percentage points" if r["unit"] == "%" else r["unit"]

    def by(r: Mapping[str, str]) -> str:             # the paired gap's size, in the metric's unit
        gap = r.get("gap", "")
        if not gap or gap.startswith("<"):
            return ""
        return f", by {gap.lstrip('-')} {gap_unit(r)} of {r['metric']}"

    sentences = []
    won = grouped("ANFIS better", lambda r: r["arm"] + by(r))
    lost = grouped("rival better", lambda r: f"{r['arm']}: {plain(r['task'], r['rival'])}{by(r)}")
    tied = [t for kind in (NO_DIFFERENCE, f"{NO_DIFFERENCE} (Holm)")
            for t in grouped(kind, lambda r: f"{r['arm']}: {plain(r['task'], r['rival'])}, "
                                             f"{r['gap']} ({r['gap_low']} to {r['gap_high']}) {gap_unit(r)}")]
    if won:
        sentences.append("ANFIS is better than every other method it was compared with, beyond the paired interval, on "
                         + "; ".join(won) + ".")
    if lost or tied:                                 # one sentence: five at most
        sentences.append("; and ".join(
            ([f"Another method is better than ANFIS, beyond the paired interval, on {'; '.join(lost)}"] if lost else [])
            + ([f"no difference between ANFIS and its best rival is shown (the paired interval, or Holm's "
                f"correction for the arm's comparisons) on {'; '.join(tied)}"] if tied else [])) + ".")
    gives = contribution(warm_starts or {})
    if gives:
        sentences.append(gives)
    headline = [r for r in verdicts if r["anfis_targets"] and (r in summed or not r["task"].startswith("measured arm"))]
    if headline:
        sentences.append("The study's targets the ANFIS meets on the whole interval: " + "; ".join(
            f"{r['task'].replace(', every tier', '')} ({r['arm']}) {r['anfis_targets']}" for r in headline) + ".")
    use = []
    for task in [t for t in tasks if not t.startswith("measured arm")] + list(dict.fromkeys(r["task"] for r in summed)):
        rows = [r for r in verdicts if r["task"] == task]
        # on a tie, no method is recommended over the other: both are named
        best = " or ".join(dict.fromkeys(name for r in rows for name in (
            [reader_label(r["best"])] if not r["verdict"].startswith(NO_DIFFERENCE) else
            [reader_label(r["anfis"]), reader_label(r["rival"])])))
        if any(r["verdict"].startswith(NO_DIFFERENCE) for r in rows):
            best += " (no difference shown)"
        exact = " or ".join(dict.fromkeys(r["exact"] for r in rows if r.get("exact")))
        name = task.replace(", every tier", "")
        use.append(f"{name}, {exact} (exact; of the learned methods, {best})" if exact else f"{name}, {best}")
    sentences.append("What to use, by the held-out data: " + "; ".join(use) + ".")
    return sentences
