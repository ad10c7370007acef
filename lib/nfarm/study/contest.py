"""The learned-IK contest's rules (chapter 6, ``params/sweeps/ik_contest.yaml``): who competes,
how each contestant's configuration is chosen, with what budget, and how they are ranked.

* A **contestant** is a learner family (:func:`family`): the ANFIS in the arm's plane (fuzzy
  c-means rules shared by the pitch joints, the pitch closure), the ANFIS of the dissertation's
  recipe (seven inputs, a grid of two functions per input), and each rival kind of
  :class:`nfarm.learning.ik_rivals.RivalIK`.
* **Budget**: every contestant has the same number of configurations in the sweep file, each
  trained once on all the training poses with seed 0; :func:`budgets` reports what each spent
  (configurations and seconds of training), so a reader sees that no one got more.
* **Choice**, on validation only (:func:`choose`): the configuration of least 95th-percentile
  tool position error, ties broken by the 95th-percentile orientation error (:data:`RANKED_BY`).
* **Spread**: each chosen configuration that is still in contention trained again on other
  draws of the data (:func:`spread_params`, seeds 1-4: each draws the training and validation
  poses anew and seeds the learner). In contention: the two best on seed 0 and every contestant
  within ``keep_within`` (2×) of the best's 95th percentile; the others are **pruned** after seed
  0 (successive halving's rule: their seed-0 error is further from the leader's than the seeds
  move any contestant — measured in chapter 6 — so more draws cannot change the ranking).
  :func:`standings` ranks the contestants in contention by the mean over the seeds, then the
  pruned ones by seed 0; :func:`paired_gap` compares two of them seed by seed (the same draw of
  data for both): a gap whose range over the seeds contains 0 is no difference.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..learning.ik_rivals import KINDS as RIVAL_KINDS
from ..learning.ik_rivals import RivalIK
from ..learning.learned import ik_errors
from ..model.robot import Robot
from .sweep import CellResult, Replicates, by_configuration

__all__ = ["RANKED_BY", "SPREAD_SEEDS", "KEEP_WITHIN", "LABELS", "contending", "saved_rivals", "rival_ranking", "family", "label", "choose", "budgets", "spread_params",
           "standings", "paired_gap"]

#: The tool metrics a contestant is ranked by, in order (validation, lower is better).
RANKED_BY = ("position_p95_mm", "orientation_p95_deg")
#: The draws each chosen configuration is trained on besides seed 0.
SPREAD_SEEDS = (1, 2, 3, 4)
#: A contestant stays in contention within this factor of the best seed-0 95th percentile.
KEEP_WITHIN = 2.0
#: Each contestant in words a reader knows.
LABELS = {"anfis:arm_plane": "ANFIS in the arm's plane", "anfis:quat_xyz": "ANFIS, the dissertation's 7 inputs",
          "anfis:axes_xyz": "ANFIS on position and two tool axes", "rbf": "RBF interpolation",
          "knn": "k nearest neighbours", "mlp": "multilayer perceptron", "kernel_ridge": "kernel ridge (Nyström)"}


def family(params: Mapping[str, Any]) -> str:
    """The contestant a cell's parameters belong to: ``"anfis:<encoding>"`` for an ANFIS, else
    the rival's kind."""
    return f"anfis:{params['encoding']}" if params["learner"] == "anfis" else params["learner"]


def label(name: str) -> str:
    """A contestant's name in words (:data:`LABELS`), or its key."""
    return LABELS.get(name, name)


def _key(r: CellResult | Replicates) -> tuple[float, ...]:
    return tuple(float(r.metrics[m]) for m in RANKED_BY)


def choose(results: Iterable[CellResult]) -> dict[str, CellResult]:
    """Each contestant's chosen configuration among its seed-0 cells (:data:`RANKED_BY`, on
    validation), in the order the contestants first appear."""
    chosen: dict[str, CellResult] = {}
    for r in results:
        if r.cell.params.get("seed", 0) != 0 or r.cell.params.get("split", "val") != "val":
            continue
        name = family(r.cell.params)
        if name not in chosen or _key(r) < _key(chosen[name]):
            chosen[name] = r
    return chosen


def budgets(results: Iterable[CellResult]) -> dict[str, tuple[int, float, float]]:
    """Each contestant's tuning budget spent: seed-0 configurations tried, the seconds their
    training took (the models' own ``fit_seconds``) and the seconds their cells took (training,
    the validation's predictions and the data's loading, when they ran)."""
    spent: dict[str, list[tuple[float, float]]] = {}
    for r in results:
        if r.cell.params.get("seed", 0) == 0 and r.cell.params.get("split", "val") == "val":
            spent.setdefault(family(r.cell.params), []).append((float(r.metrics["fit_seconds"]), float(r.seconds)))
    return {name: (len(s), float(sum(a for a, _ in s)), float(sum(b for _, b in s))) for name, s in spent.items()}


def contending(chosen: Mapping[str, CellResult], keep_within: float = KEEP_WITHIN) -> list[str]:
    """The contestants still in contention after seed 0 (module docstring): the two best and every
    one whose 95th percentile is within ``keep_within`` of the best's."""
    order = sorted(chosen, key=lambda name: _key(chosen[name]))
    if not order:
        return []
    best = chosen[order[0]].metrics[RANKED_BY[0]]
    return [name for k, name in enumerate(order) if k < 2 or chosen[name].metrics[RANKED_BY[0]] <= keep_within * best]


def spread_params(chosen: Mapping[str, CellResult], seeds: Sequence[int] = SPREAD_SEEDS, *,
                  keep_within: float = KEEP_WITHIN) -> list[dict]:
    """The cells that train each chosen configuration in contention on the other draws."""
    return [{**chosen[name].cell.params, "seed": int(s)} for name in contending(chosen, keep_within) for s in seeds]


def standings(chosen: Mapping[str, CellResult], spread: Iterable[CellResult]) -> list[Replicates]:
    """The chosen configurations over their seeds (seed 0 and ``spread``): those trained on
    several draws best first by the mean of :data:`RANKED_BY` over the seeds, then the pruned ones
    (one seed) by their seed-0 values."""
    groups = by_configuration([*chosen.values(), *spread])
    wanted = {family(r.cell.params) for r in chosen.values()}
    kept = [g for g in groups if family(g.cell.params) in wanted]
    return sorted(kept, key=lambda g: (g.n == 1 and len(kept) > 1 and any(h.n > 1 for h in kept), _key(g)))


def paired_gap(a: Replicates, b: Replicates, metric: str = RANKED_BY[0]) -> tuple[float, float, float]:
    """The mean, least and largest of ``a``'s ``metric`` minus ``b``'s, seed by seed (each seed the
    same draw of data for both).

    Raises:
        ValueError: the two were not trained on the same seeds.
    """
    if a.seeds != b.seeds:
        raise ValueError(f"paired_gap needs the same seeds, got {a.seeds} and {b.seeds}")
    gap = a.values(metric) - b.values(metric)
    return float(np.mean(gap)), float(np.min(gap)), float(np.max(gap))


def saved_rivals(robot: Robot, models_dir: str | os.PathLike) -> dict[str, RivalIK]:
    """The contest's chosen rivals chapter 6 saved for ``robot`` under
    ``models_dir/ik_contest/<kind>/``, by kind (those present)."""
    where = Path(models_dir) / "ik_contest"
    return {kind: RivalIK.load(where / kind, robot) for kind in RIVAL_KINDS if (where / kind).is_dir()}


def rival_ranking(robot: Robot, rivals: Mapping[str, RivalIK], val: Mapping) -> list[str]:
    """The rivals' kinds, best first, as the contest ranks (:data:`RANKED_BY`: the 95th
    percentile of the tool position error, then of the orientation error) on the validation
    poses ``val`` (``T (N, 4, 4)``, ``q (N, n)``): how chapters 7 and 8 pick the best rival of a
    frozen set."""
    def key(kind: str) -> tuple[float, float]:
        e = ik_errors(robot, rivals[kind].predict(val["T"]), val["q"], val["T"])
        return float(np.percentile(e["position"], 95)), float(np.percentile(e["orientation"], 95))
    keys = {kind: key(kind) for kind in rivals}
    return sorted(rivals, key=keys.get)
