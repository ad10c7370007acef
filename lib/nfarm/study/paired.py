"""Paired comparisons of two methods on the study's held-out data (chapters 07 and 08, the
abstract): each metric of method a less method b's on the **same** resamples of the same test
units, so a chapter says where a baseline wins only when the interval of the difference excludes 0.

* over the test units of one model each: :func:`ik_difference` (the IK metrics over the test
  poses), :func:`largest_difference` (the largest torque error over the test trajectories) and
  :func:`paired_rows`, the :class:`Paired` rows of every comparison the abstract makes, written as
  the paired table (:func:`paired_table`, ``07_paired.csv``);
* over the seeds: :func:`seed_comparison` (every method's metric with its two-level interval and
  the ANFIS's paired difference from a rival) and :func:`pooled_pairs` (the paired rows judged
  over the seeds where either method has several);
* read back from the paired table's text rows: :func:`paired_difference` and :func:`paired_judge`
  (-1, 0 or +1, as the abstract and the findings judge), and :func:`orientation_by_structure`,
  where no orientation comparison is claimed.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Mapping, Sequence

import numpy as np

from ..presentation.tables import Table, shown
from .result_tables import DIGITS, SUMMARY_FLOORS, table_number
from .rows import IK_METRICS, WORST_ID, _ik_columns, _ik_statistic, _pooled_metric, _seed_metric, resolved_sums
from .statistics import Estimate, bootstrap_counts, bootstrap_rows, bootstrap_seeds

__all__ = ["Paired", "ik_difference", "largest_difference", "seed_comparison", "pooled_pairs", "paired_rows",
           "paired_table", "paired_judge", "ORIENTATION_BY_STRUCTURE_DEG", "orientation_by_structure",
           "paired_difference"]


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


def ik_difference(errors_a: Mapping, errors_b: Mapping, *, draws: int = 2000, level: float = 0.95,
                  seed: int = 0) -> Estimate:
    """Each IK metric of method a less method b's on the **same** test poses, with the paired
    interval (both recomputed on each resample of the poses): ``(7,)`` arrays in the order of
    :data:`nfarm.study.rows.IK_METRICS`. An interval that holds 0 is no difference."""
    a, b = _ik_columns(errors_a), _ik_columns(errors_b)
    if a.shape != b.shape:
        raise ValueError(f"the two methods must be judged on the same poses, got {a.shape} and {b.shape}")
    stat_a, stat_b = _ik_statistic(a), _ik_statistic(b)
    return bootstrap_counts(len(a), lambda counts: stat_a(counts) - stat_b(counts),
                            draws=draws, level=level, seed=seed)


def _largest(X):
    return X.max(axis=(-2, -1))


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


def seed_comparison(values: Mapping[str, np.ndarray], anfis: str, rival: str, metric: str, *, ik: bool = False,
                    resolved=None, normalised: bool = True, draws: int = 2000, level: float = 0.95,
                    seed: int = 0) -> tuple[dict[str, Estimate], Estimate]:
    """Every method's ``metric`` over its seeds' models and the test units, with the two-level
    interval (:func:`nfarm.study.statistics.bootstrap_seeds`), and the ANFIS's paired difference
    from ``rival`` on the seeds both have (seed ``s`` of each trained on the same draw of data).

    ``values``: method → ``(S, N, k)`` — with ``ik=True`` its seeds' IK errors
    (:func:`nfarm.study.rows.ik_seed_values`; ``metric`` one of :data:`nfarm.study.rows.IK_METRICS`,
    e.g. ``"position p95"``), else its seeds' trajectory sums
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


def pooled_pairs(pairs: Sequence[Paired], values: Mapping[tuple[str, str], np.ndarray], *,
                 resolved: Mapping[str, np.ndarray] | None = None, draws: int = 2000, level: float = 0.95,
                 seed: int = 0) -> list[Paired]:
    """``pairs`` (:func:`paired_rows`, the chapter's seed's) each judged over the seeds (``values``
    as :func:`nfarm.study.rows.pooled_rows` takes them) where at least one of the two methods has several: model
    ``s`` of each trained on the same draw of data, on the same test units, the difference with its
    paired two-level interval. A method with one model (trained once, or needing no training, as
    Newton–Euler alone) stands as it is beside each of the other's seeds' models: the comparison
    of the two values :func:`nfarm.study.rows.pooled_rows` gives. A pair neither of whose methods has several seeds,
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


def paired_rows(pairs, *, ik_errors: Mapping[str, Mapping] | None = None,
                id_sums: Mapping[str, np.ndarray] | None = None, resolved=None,
                measured_sums: Mapping[str, np.ndarray] | None = None, measured_resolved=None,
                draws: int = 2000, level: float = 0.95, seed: int = 0) -> list[Paired]:
    """The paired difference of each ``(task, method, against, metric)`` of ``pairs``
    (:func:`nfarm.publishing.abstract.abstract_pairs`), each pair judged on the same resamples of the same test units:
    the IK metrics over the test poses (:func:`ik_difference`, from ``ik_errors[name]``); the
    worst (resolved) joint's NRMSE over the test trajectories from ``id_sums[name]``
    (:func:`nfarm.study.statistics.worst_difference`; ``resolved`` as :func:`nfarm.study.rows.id_rows` takes it);
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


def paired_judge(paired: Sequence[Mapping[str, str]], floors: Mapping[str, float] = SUMMARY_FLOORS):
    """The comparison :func:`nfarm.publishing.abstract.abstract_lines` makes of two rows of one task and metric: -1 when
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
    return table_number(top) < ORIENTATION_BY_STRUCTURE_DEG


def paired_difference(paired: Sequence[Mapping[str, str]], task: str, method: str, against: str,
                      metric: str) -> tuple[float, float, float]:
    """``method`` less ``against`` on ``metric`` of ``task``, and its paired interval, read from a
    paired table's text rows (:func:`nfarm.study.result_tables.read_paired`; the pair written either way round, its sign
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
            return table_number(p["difference"]), table_number(p["ci_low"]), table_number(p["ci_high"])
        if (p["method"], p["against"]) == (against, method):
            return -table_number(p["difference"]), -table_number(p["ci_high"]), -table_number(p["ci_low"])
    raise ValueError(f"no paired difference of {method!r} against {against!r} on {metric} ({task}) in the paired "
                     f"table (07_paired.csv)")
