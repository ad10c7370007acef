"""The study's results as rows (chapters 07 and 08): every method's errors on held-out
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

Pooled over seeds (:func:`pooled_rows`): every method chapter 6 trained over several seeds, each
metric over all its seeds' models and the test units, with the two-level interval. The rows are
written as the long table (:func:`long_table`; read back with
:func:`nfarm.study.result_tables.read_long_table` and :func:`rows_from_table`) and, for a reader,
the wide table (:func:`wide_table`). The median and the 95th percentile are the reader's; the
maximum is reported because the worst case is what a controller meets, **without an interval**:
the percentile bootstrap of a sample's maximum has the maximum itself as its upper end
(measured: "70.4 (27.7–70.4)"), an interval that says nothing of how much larger the next test
set's worst case could be. Such a row has ``low == high == value`` and ``n == 0``; comparisons of
maxima are made on paired differences only (:mod:`nfarm.study.paired`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from typing import Callable, Mapping, Sequence

import numpy as np

from ..presentation.tables import Table, shown
from .result_tables import DIGITS
from .statistics import (Estimate, bootstrap_counts, bootstrap_nrmse, bootstrap_seeds, nrmse_from_sums,
                         resampled_quantile, resolved_joints)
from .sweep import Replicates

__all__ = ["WORST_ID", "ROLES", "ROLE_CHOSEN", "ROLE_RECIPE", "ROLE_BEST_BASELINE", "ROLE_EXACT", "ROLE_DESIGN",
           "ROLE_PHYSICS", "ROLE_NUMERICAL", "ROLE_FRICTION_ID", "ROLE_RESIDUAL_BASELINE", "ROLE_LEARNED_ALONE",
           "ROLE_TIER_ANFIS", "ROLE_TIER_RIVAL", "ROLE_SPAN", "IK_METRICS", "Row", "ik_rows", "ik_seed_values",
           "seed_estimates", "pooled_rows", "resolved_sums", "bootstrap_resolved", "id_rows", "with_resolved_worst",
           "resolved_on_validation", "published", "rows_from_table", "long_table", "interval_text", "wide_table"]

#: The ID rows' worst-joint metric: over the joints a sensor resolves (:func:`id_rows`).
WORST_ID = "worst resolved joint NRMSE"

# The roles of the summary rows :func:`nfarm.publishing.abstract.abstract_lines` reads. The chapters
# write their rows with these labels and the abstract finds its rows by them, matched whole: a label
# reworded on one side only is caught by tests/test_abstract.py rather than silently dropped from the
# abstract.
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
#: A model of the rigid-body span tier (:data:`nfarm.learning.bases.TIERS`): ridge on the chain basis, whose span holds
#: (or nearly holds) the rigid-body model — an identification in disguise, shown beside the verdicts, never a rival.
ROLE_SPAN = "rigid-body span (an identification in disguise)"
#: Every role :func:`nfarm.publishing.abstract.abstract_lines` reads.
ROLES = (ROLE_CHOSEN, ROLE_RECIPE, ROLE_BEST_BASELINE, ROLE_EXACT, ROLE_DESIGN, ROLE_PHYSICS, ROLE_NUMERICAL,
         ROLE_FRICTION_ID, ROLE_RESIDUAL_BASELINE, ROLE_LEARNED_ALONE, ROLE_TIER_ANFIS, ROLE_TIER_RIVAL, ROLE_SPAN)


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


def _pooled_worst(resolved, normalised: bool) -> Callable[[np.ndarray], np.ndarray]:
    """``X (b, M, 1 + 3n) -> (b,)``: the worst ``resolved`` joint's NRMSE (RMSE) of pooled trajectory sums."""
    keep = None if resolved is None else np.asarray(resolved, bool)
    def statistic(X):
        per_joint = nrmse_from_sums(X.sum(axis=-2), normalised=normalised)
        return np.nanmax(per_joint if keep is None else per_joint[..., keep], axis=-1)
    return statistic


def ik_seed_values(errors: Sequence[Mapping[str, np.ndarray]]) -> np.ndarray:
    """``(S, N, n + 2)``: each seed's model's IK errors on the same test poses (a list, one
    :func:`nfarm.learning.learned.ik_errors` record per seed), as :func:`nfarm.study.paired.seed_comparison` takes
    them."""
    return np.stack([_ik_columns(e) for e in errors])


def _seed_metric(values: Mapping[str, np.ndarray], metric: str, ik: bool, resolved, normalised: bool):
    """The columns of each method's seed values that ``metric`` reads, and its statistic of pooled rows."""
    columns, statistic = _pooled_ik(metric) if ik else (slice(None), _pooled_worst(resolved, normalised))
    return {name: np.asarray(v, float)[..., columns] for name, v in values.items()}, statistic


def seed_estimates(values: Mapping[str, np.ndarray], metric: str, *, ik: bool = False, resolved=None,
                   normalised: bool = True, draws: int = 2000, level: float = 0.95, seed: int = 0) -> dict[str, Estimate]:
    """Every method's ``metric`` over its seeds' models and the test units, with the two-level
    interval: :func:`nfarm.study.paired.seed_comparison`'s estimates without the paired difference (the same
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
    errors (:func:`ik_seed_values`) or trajectory sums, as :func:`nfarm.study.paired.seed_comparison` takes them —
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


def _floor(row: Row, floors: Mapping[str, float]) -> float:
    return floors.get(row.unit, 0.0)


def published(rows: Sequence[Row]) -> list[Row]:
    """``rows`` with their values and interval ends rounded to the long table's precision
    (:data:`nfarm.study.result_tables.DIGITS`), as :func:`long_table` writes them: a chapter that shows a row (its wide
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
    """The :class:`Row` objects of a long table's text rows (:func:`nfarm.study.result_tables.read_long_table`), for a
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


