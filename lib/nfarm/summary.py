"""The study's result in one long table (chapters 07 and 08): every method's errors on held-out
data, each metric with its percentile-bootstrap interval, machine-readable.

One :class:`Row` per task, method and metric, with ``value``, ``ci_low``, ``ci_high`` and ``n``
(the resamples) and what was resampled (``spread``):

* **inverse kinematics** (:func:`ik_rows`): the worst joint's RMSE [deg] and the median, 95th
  percentile and largest tool position [mm] and orientation [deg] errors of ``fk(predicted q)``,
  resampling the **test poses** (each drawn on its own, so independent);
* **inverse dynamics** (:func:`id_rows`): each joint's NRMSE [%] (or RMSE [N·m] against measured
  torques), the worst joint's and the largest absolute torque error [N·m], resampling the **test
  trajectories** (a trajectory's samples are correlated: :mod:`nfarm.statistics`).

:func:`ik_difference` and :func:`largest_difference` compare two methods on the same resamples
(paired), so a chapter says where a baseline wins only when the interval of the difference
excludes 0. The median and the 95th percentile are the reader's; the maximum is reported because
the worst case is what a controller meets, and its interval is the bootstrap's of an extreme (its
upper end is the sample's own maximum).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Mapping, Sequence

import numpy as np

from .baselines import label as baseline_label
from .learned import Baseline
from .report import Table, shown
from .robot import Robot
from .statistics import Estimate, bootstrap_nrmse, bootstrap_rows
from .sweep import Sweep, best_by, by_configuration, sweep_results

__all__ = ["IK_METRICS", "Row", "ik_rows", "id_rows", "ik_difference", "largest_difference",
           "long_table", "wide_table", "interval_text", "ik_baselines", "best_id_baseline"]

IK_BASELINES = {"nearest": "nearest neighbour", "rbf": "RBF interpolation", "linear": "linear least squares"}

# (metric, unit) of the IK rows, in order; the first is left out for a method whose joint angles
# are another branch's (LM: its "errors" reach the same pose).
IK_METRICS = (("worst joint RMSE", "deg"), ("position median", "mm"), ("position p95", "mm"),
              ("position max", "mm"), ("orientation median", "deg"), ("orientation p95", "deg"),
              ("orientation max", "deg"))


@dataclass(frozen=True)
class Row:
    """One method's value of one metric on held-out data and its interval (``low``, ``high``
    at coverage ``level``, from ``n`` resamples of ``spread``)."""

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
    error (:func:`nfarm.learned.ik_errors`' record)."""
    joint = np.degrees(np.asarray(errors["joint"], float))
    position = 1e3 * np.asarray(errors["position"], float)
    orientation = np.degrees(np.asarray(errors["orientation"], float))
    if joint.ndim != 2 or position.shape != (len(joint),) or orientation.shape != (len(joint),):
        raise ValueError(f"errors must hold joint (N, n), position (N,) and orientation (N,), got shapes "
                         f"{joint.shape}, {position.shape} and {orientation.shape}")
    return np.column_stack([joint, position, orientation])


def _ik_statistic(n: int) -> Callable[[np.ndarray], np.ndarray]:
    """``X (b, N, n + 2) -> (b, 7)``: the metrics of :data:`IK_METRICS`."""
    def statistic(X):
        worst = np.sqrt((X[..., :n] ** 2).mean(axis=-2)).max(axis=-1)
        out = [worst]
        for column in (n, n + 1):
            x = X[..., column]
            out += [np.median(x, axis=-1), np.percentile(x, 95, axis=-1), x.max(axis=-1)]
        return np.stack(out, axis=-1)
    return statistic


def ik_rows(method: str, role: str, errors: Mapping[str, np.ndarray], *, joint: bool = True,
            task: str = "inverse kinematics", draws: int = 2000, level: float = 0.95,
            seed: int = 0, arm: str = "") -> list[Row]:
    """The IK metrics (:data:`IK_METRICS`) of one method's test-pose ``errors`` with their
    intervals over the poses; ``joint=False`` leaves out the joint RMSE (another branch's);
    ``arm`` names the arm when rows of several go in one table."""
    columns = _ik_columns(errors)
    n = columns.shape[1] - 2
    est = bootstrap_rows(columns, _ik_statistic(n), draws=draws, level=level, seed=seed)
    spread = f"bootstrap over {len(columns):,} test poses"
    return [Row(task, method, role, metric, unit, float(est.value[k]), float(est.low[k]), float(est.high[k]),
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
    width = a.shape[1]
    stat = _ik_statistic(width - 2)
    return bootstrap_rows(np.hstack([a, b]), lambda X: stat(X[..., :width]) - stat(X[..., width:]),
                          draws=draws, level=level, seed=seed)


def _largest(X):
    return X.max(axis=(-2, -1))


def id_rows(method: str, role: str, sums: np.ndarray, maxima: np.ndarray, joint_names: Sequence[str], *,
            normalised: bool = True, task: str = "inverse dynamics", draws: int = 2000, level: float = 0.95,
            seed: int = 0, arm: str = "") -> list[Row]:
    """The ID metrics of one method on the test trajectories: each joint's NRMSE [%] (with
    ``normalised=False`` its RMSE [N·m]), the worst joint's, and the largest absolute torque
    error [N·m], with intervals over the trajectories. ``sums (T, 1 + 3n)``:
    :func:`nfarm.statistics.trajectory_sums`; ``maxima (T, n)``:
    :func:`nfarm.statistics.trajectory_maxima` of the same trajectories."""
    sums, maxima = np.asarray(sums, float), np.asarray(maxima, float)
    if maxima.ndim != 2 or len(maxima) != len(sums) or maxima.shape[1] != len(joint_names):
        raise ValueError(f"maxima must be (trajectories={len(sums)}, joints={len(joint_names)}), got {maxima.shape}")
    ci = bootstrap_nrmse(sums, draws=draws, level=level, seed=seed, normalised=normalised)
    scale, name, unit = (100.0, "NRMSE", "%") if normalised else (1.0, "RMSE", "N·m")
    spread = f"bootstrap over {ci.trajectories} test trajectories"
    rows = [Row(task, method, role, f"τ{j + 1} {name}", unit, scale * ci.value[j], scale * ci.low[j],
                scale * ci.high[j], draws, level, spread, arm) for j in range(len(joint_names))]
    rows.append(Row(task, method, role, f"worst joint {name}", unit, scale * ci.worst, scale * ci.worst_low,
                    scale * ci.worst_high, draws, level, spread, arm))
    big = bootstrap_rows(maxima, _largest, draws=draws, level=level, seed=seed)
    rows.append(Row(task, method, role, "largest error", "N·m", big.value, big.low, big.high, draws, level, spread,
                    arm))
    return rows


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


def _floor(row: Row, floors: Mapping[str, float]) -> float:
    return floors.get(row.unit, 0.0)


def long_table(rows: Sequence[Row], *, floors: Mapping[str, float] | None = None, caption: str = "") -> Table:
    """The machine-readable table: one line per task, method and metric (columns ``task,
    method, role, metric, unit, value, ci_low, ci_high, n, level, spread``). Values below a
    unit's floor (``floors``: unit → level of rounding) are written as such (``< 1e-06``)."""
    floors = floors or {}
    fmt = lambda v, r: shown(v, ".4g", floor=_floor(r, floors))   # noqa: E731
    arm = any(r.arm for r in rows)          # a column of arms when the rows are of several
    return Table((["arm"] if arm else []) + ["task", "method", "role", "metric", "unit", "value", "ci_low", "ci_high",
                                             "n", "level", "spread"],
                 [([r.arm] if arm else []) + [r.task, r.method, r.role, r.metric, r.unit, fmt(r.value, r),
                                              fmt(r.low, r), fmt(r.high, r), r.n, f"{r.level:g}", r.spread]
                  for r in rows], caption=caption)


def interval_text(row: Row, floors: Mapping[str, float] | None = None, digits: str = ".3g") -> str:
    """``value (low–high)`` of a row for a reader; one value when the interval is a point."""
    floor = _floor(row, floors or {})
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


def ik_baselines(robot: Robot, train: Mapping, val: Mapping, *, encoding: str = "arm_plane",
                 neighbors: int = 32) -> dict[str, tuple[Baseline, float]]:
    """The learned-IK baselines (:class:`nfarm.learned.Baseline`: nearest neighbour, RBF
    interpolation, linear least squares) fitted on ``train`` and each one's worst joint RMSE
    [deg] on ``val``, by which a chapter chooses the best before it reads the test set. Keys
    name the baseline and its inputs, e.g. ``"RBF interpolation (arm_plane)"``."""
    out = {}
    for kind, name in IK_BASELINES.items():
        model = Baseline(kind, encoding, neighbors).fit(robot, train)
        rmse = np.sqrt(((model.predict(val["T"]) - np.asarray(val["q"], float)) ** 2).mean(axis=0))
        out[f"{name} ({encoding})"] = (model, float(np.degrees(rmse).max()))
    return out


def best_id_baseline(sweep: Sweep, sweeps_dir=None, *, seed: int = 0, workers: int | None = None):
    """The best scikit-learn baseline of a baselines sweep (``params/sweeps/id_baselines.yaml``,
    restricted to one arm): each learner's best configuration by its mean worst-joint NRMSE
    over the seeds on validation, the best of those (least squares on ``q, q̇, q̈``, the floor,
    left out), and that configuration's run on the test split with ``seed`` (run now if it is
    not in ``sweeps_dir``). Returns ``(name, validation Replicates, test CellResult)``, or
    ``None`` if the sweep holds no learner but the floor."""
    unseeded = lambda p: {k: v for k, v in p.items() if k != "seed"}          # noqa: E731
    val = by_configuration(sweep_results(sweep, sweeps_dir, workers=workers))
    learners = [g for learner, g in best_by(val, "learner", "worst_nrmse").items() if learner != "linear"]
    if not learners:
        return None
    best = min(learners, key=lambda g: g.metrics["worst_nrmse"])
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


def _with_interval(row: Mapping[str, str]) -> str:
    value, low, high = row["value"], row["ci_low"], row["ci_high"]
    unit = {"deg": "°", "%": " %", "mm": " mm", "N·m": " N·m"}.get(row["unit"], f" {row['unit']}")
    return f"{value}{unit}" if low == high == value else f"{value}{unit} ({low}–{high})"


def _compare(ours: Mapping[str, str], theirs: Mapping[str, str]) -> int:
    """-1 when ours is lower beyond both intervals, +1 when higher, 0 when they overlap."""
    if _number(ours["ci_high"]) < _number(theirs["ci_low"]):
        return -1
    if _number(ours["ci_low"]) > _number(theirs["ci_high"]):
        return 1
    return 0



def _unchosen(method: str) -> str:
    """A method's name after "the chosen model,": without its own ", chosen" ("ANFIS, chosen
    (arm_plane)" → "ANFIS (arm_plane)")."""
    return method.replace(", chosen", "")

def abstract_lines(arm: str, rows: Sequence[Mapping[str, str]]) -> list[str]:
    """Plain-text sentences (one per task) of one arm's answers, every number read from its
    summary rows: the chosen ANFIS, the dissertation's design (assumed), the best baseline and
    the references, and on which metrics the baseline is better beyond both intervals."""
    def find(task, role_start, metric):
        return next((r for r in rows if r["task"] == task and r["role"].startswith(role_start)
                     and r["metric"] == metric), None)

    lines = []
    task = "inverse kinematics"
    chosen = [r for r in rows if r["task"] == task and r["role"] == "learned (chosen)"]
    if chosen:
        get = {r["metric"]: r for r in chosen}
        text = (f"{arm}, inverse kinematics: the chosen model, {_unchosen(chosen[0]['method'])}, misses by "
                f"{_with_interval(get['worst joint RMSE'])} on its worst joint; the tool lands "
                f"{_with_interval(get['position median'])} from the target at the median, "
                f"{_with_interval(get['position p95'])} at the 95th percentile and "
                f"{_with_interval(get['position max'])} at worst.")
        recipe = find(task, "dissertation's recipe", "worst joint RMSE")
        if recipe:
            text += f" The dissertation's recipe (assumed) on the same data: {_with_interval(recipe)}."
        base = [r for r in rows if r["task"] == task and r["role"].startswith("best baseline")]
        if base:
            wins = [f"{r['metric']} ({_with_interval(r)} against {_with_interval(get[r['metric']])})"
                    for r in base if r["metric"] in get and _compare(r, get[r["metric"]]) < 0]
            losses = [r["metric"] for r in base if r["metric"] in get and _compare(r, get[r["metric"]]) > 0]
            text += (f" The best baseline on validation, {base[0]['method']}, is better beyond both intervals on "
                     + "; ".join(wins) + "." if wins else
                     f" The best baseline on validation, {base[0]['method']}, is better on no metric beyond both "
                     f"intervals.")
            if losses:
                text += f" The ANFIS is better on {', '.join(losses)}."
        exact = find(task, "exact reference", "position max")
        if exact:
            text += f" The closed form is exact (largest tool position error {_with_interval(exact)})."
        lines.append(text)
    task = "inverse dynamics"
    free = find(task, "learned (chosen)", "worst joint NRMSE")
    if free:
        text = (f"{arm}, inverse dynamics without the arm's parameters: the chosen model, {_unchosen(free['method'])}, "
                f"misses by {_with_interval(free)} of the worst joint's torque spread (NRMSE), largest error "
                f"{_with_interval(find(task, 'learned (chosen)', 'largest error'))}.")
        base = find(task, "best baseline", "worst joint NRMSE")
        if base:
            verdict = {-1: "better than the ANFIS", 1: "worse than the ANFIS",
                       0: "no different from the ANFIS within the intervals"}[_compare(base, free)]
            text += f" The best baseline on validation, {base['method']}: {_with_interval(base)}, {verdict}."
        recipe = find(task, "dissertation's design", "worst joint NRMSE")
        if recipe:
            text += f" The dissertation's design (assumed, each joint's own state): {_with_interval(recipe)}."
        ident = find(task, "physics-informed", "worst joint NRMSE")
        if ident:
            text += f" Given the geometry, identifying the inertial parameters: {_with_interval(ident)}."
        lines.append(text)
    task = "ID, measured arm"
    residual = find(task, "learned (chosen)", "worst joint RMSE")
    if residual:
        alone = find(task, "numerical reference", "worst joint RMSE")
        ls = find(task, "baseline (friction", "worst joint RMSE")
        learner = find(task, "baseline (learner", "worst joint RMSE")
        text = (f"{arm}, an arm with friction (measured torques): Newton–Euler alone leaves {_with_interval(alone)} "
                f"on the worst joint, Newton–Euler with an ANFIS residual {_with_interval(residual)}")
        if ls:
            verdict = {-1: "better than", 1: "worse than", 0: "no different from"}[_compare(residual, ls)]
            text += f", {verdict} the least-squares friction identification ({_with_interval(ls)})"
        if learner:
            text += f"; the best learner as a residual, {learner['method']}: {_with_interval(learner)}"
        lines.append(text + ".")
    return lines
