"""The learned-IK contest's rules (chapter 6, ``params/sweeps/ik_contest.yaml``): who competes,
how each contestant's configuration is chosen, with what budget, and how they are ranked.

* A **contestant** is a learner family (:func:`family`): the ANFIS in the arm's plane (fuzzy
  c-means rules shared by the pitch joints, the pitch closure), the ANFIS of the dissertation's
  recipe (seven inputs, a grid of two functions per input), and each rival kind of
  :class:`nfarm.learning.ik_rivals.RivalIK`.
* **Budget**: every contestant has the same number of configurations in the sweep file, tuned
  by **successive halving** (Jamieson & Talwalkar 2016) with seed 0: every configuration trains
  on a share of the training poses (:data:`RUNG_FRACTION`), and each contestant's
  :data:`PROMOTED` best of them on validation (:func:`promoted_params`) train again on all of
  them — the deployment size, where the contestants are ranked; :func:`budgets` reports what each spent
  (configurations and seconds of training), so a reader sees that no one got more.
* **Choice**, on validation only (:func:`choose`, given the cells trained on all the poses): the
  configuration of least 95th-percentile tool position error, ties broken by the
  95th-percentile orientation error (:data:`RANKED_BY`).
* **Spread**: each chosen configuration that is still in contention trained again on other
  draws of the data (:func:`spread_params`, seeds 1-2: each draws the training and validation
  poses anew and seeds the learner). In contention: the two best on seed 0, every contestant
  within ``keep_within`` (2×) of the best's 95th percentile, and the best ANFIS whatever its gap
  (the verdict's subject: its spread is the verdict's); the others are **pruned** after seed
  0 (successive halving's rule: their seed-0 error is further from the leader's than the seeds
  move any contestant — measured in chapter 6 — so more draws cannot change the ranking).
  :func:`standings` ranks the contestants in contention by the mean over the seeds, then the
  pruned ones by seed 0; :func:`paired_gap` compares two of them seed by seed (the same draw of
  data for both): a gap whose range over the seeds contains 0 is no difference.

**The learned-ID contest on the measured arm** (chapter 6.8, ``params/sweeps/id_contest.yaml``)
follows the same rules with its own contestants and metric: a contestant is a learner within a
**tier of prior knowledge** (:func:`id_family`: ``"<tier>:anfis"`` or ``"<tier>:<learner>"``,
the tier from :func:`nfarm.learning.bases.tier_of`), every learner of a tier has the same number
of configurations, and they are ranked by :data:`ID_RANKED_BY` — the study's target metric, the
worst resolved joint's NRMSE against the measured torques' spread, then the worst joint's RMSE.
In contention after seed 0 (:func:`id_contending`): each tier's best ANFIS and best rival (its
leaders), and every other rival of the tier within reach of its leader — its seed-0 value at most
the largest the leader reached over its seeds — so that every tier's verdict — ANFIS against the
best of the others with the same knowledge, by the mean over the seeds — has its spread over the
seeds and no rival is pruned that another draw could rank first (:func:`id_spread_runs`). Pass ``family_of=id_family, ranked_by=ID_RANKED_BY`` to
:func:`choose`, :func:`budgets` and :func:`standings`.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from ..infra.arguments import is_number
from ..infra.paths import atomic_path
from ..learning.bases import TIERS, tier_of
from ..learning.baselines import BASELINES
from ..learning.ik_rivals import RIVALS, RivalIK
from ..learning.learned import ik_errors
from ..model.robot import Robot
from .sweep import CellResult, Replicates, by_configuration, sweep_results
from .sweep_files import Cell, Sweep

__all__ = ["SEVEN_FCM", "ID_TIER_DIRS", "ID_RANKED_BY", "ID_LABELS", "id_label", "in_span", "id_configuration", "IDContest", "id_contest", "id_model_dir", "id_spread_params", "id_spread_runs", "json_key", "id_family", "id_tier", "id_contending", "RANKED_BY", "SPREAD_SEEDS", "SMOKE_SPREAD_SEEDS", "KEEP_WITHIN", "LABELS", "contending", "saved_rivals", "VALIDATION_FILE", "save_validation", "saved_ranking", "rival_ranking", "family", "label", "STRUCTURE_OF", "structure_of", "learner_of", "choose", "Budget", "passes_of", "budgets", "spread_params",
           "standings", "paired_gap", "RUNG_FRACTION", "PROMOTED", "RUNG_TOLERANCE", "promoted_params", "at_edge", "EDGE_FLAT", "edge_step", "edges_text", "tier_finalists", "tier_spread_params", "with_tier_finalists"]

#: The tool metrics a contestant is ranked by, in order (validation, lower is better).
RANKED_BY = ("position_p95_mm", "orientation_p95_deg")
#: Successive halving's first rung: the share of the training poses every configuration trains on.
RUNG_FRACTION = 0.25
#: Successive halving's second rung: each contestant's configurations trained again on all the poses
#: (one: its best of the first rung).
PROMOTED = 1
#: At the first rung, a configuration within this share of a contestant's best 95th percentile would
#: count as doing as well, and the one the sweep file lists first (the cheaper) be promoted. None: the
#: first rung's quarter of the poses favours the smaller model, which gains the less from the rest. At
#: 5 % (before) intelbot5's 64 rules, 1.405 mm at the first rung against 128 rules' 1.340, were
#: promoted, and on all the poses reached 1.29 mm on average over five seeds (1.145-1.365), where the
#: 128 rules, promoted without it, reach 0.628 (0.559-0.79) mm (2026-11-26, validation; chapter 6.1's
#: table of the contest).
RUNG_TOLERANCE = 0.0
#: The draws each chosen configuration is trained on besides seed 0: three draws in all, the fewest that give a
#: spread its least and largest (four more until the study was cut to the clean build's budget, issue 63).
SPREAD_SEEDS = (1, 2)
#: The other draws of a smoke run (chapters 6-7's ``spread_seeds`` in smoke mode): two draws in all,
#: a spread to exercise the code, not a measure of it.
SMOKE_SPREAD_SEEDS = (1,)
#: A contestant stays in contention within this factor of the best seed-0 95th percentile.
KEEP_WITHIN = 2.0
#: The ANFIS contestants in words a reader knows (a rival's words are its class's ``label``: :func:`label`).
LABELS = {"anfis:arm_plane": "ANFIS in the arm's plane", "anfis:quat_xyz": "ANFIS, the dissertation's 7 inputs",
          "anfis:quat_xyz_fcm": "ANFIS, the dissertation's 7 inputs, fuzzy c-means rules",
          "anfis:axes_xyz": "ANFIS on position and two tool axes"}
#: The ANFIS on the dissertation's seven inputs with fuzzy c-means rules shared by all the joints (issue 64: its best
#: shot on that encoding, a contestant apart from the recipe's grid, so that what the seven inputs give is the learner's).
SEVEN_FCM = "anfis:quat_xyz_fcm"
#: The structure each contestant computes the joints with: ``"arm"`` (the first and last joints affine
#: maps, the pitch joints learned, the last pitch joint closed from the target's pitch), ``"whole"``
#: (one model learns all the joints) or ``"recipe"`` (the dissertation's: one ANFIS per joint on its 7 inputs).
STRUCTURE_OF = {"anfis:arm_plane": "arm", "anfis:quat_xyz": "recipe", "anfis:quat_xyz_fcm": "whole",
                "anfis:axes_xyz": "whole"}


def structure_of(name: str) -> str:
    """The structure of contestant ``name`` (:data:`STRUCTURE_OF`): ``"arm"``, ``"whole"`` or
    ``"recipe"``.

    Example:
        >>> structure_of("rbf:arm"), structure_of("mlp"), structure_of("anfis:arm_plane")
        ('arm', 'whole', 'arm')
    """
    return STRUCTURE_OF.get(name, "arm" if name.endswith(":arm") else "whole")


def learner_of(name: str) -> str:
    """The learner of contestant ``name`` whatever its structure: ``"rbf:arm"`` → ``"rbf"``,
    ``"anfis:arm_plane"`` → ``"anfis"``."""
    return name.split(":", 1)[0]


#: The directory of each learned-ID tier's finalists under ``id_measured/`` (:func:`id_model_dir`).
ID_TIER_DIRS = {TIERS["generic"]: "generic", TIERS["structure"]: "structure_informed", TIERS["span"]: "rigid_body",
                TIERS["identification"]: "identification", TIERS["identified"]: "identified",
                TIERS["nominal"]: "nominal"}
#: The learned-ID contest's metrics, in order (validation, lower is better).
ID_RANKED_BY = ("worst_nrmse", "worst_rmse")


#: The learned-ID ANFIS in words (a baseline's words are its class's ``label``: :func:`id_label`).
ID_LABELS = {"anfis": "ANFIS"}


def id_label(name: str) -> str:
    """A learned-ID contestant (``"<tier>:<learner>"``) in words: ``"generic: ANFIS"``, a
    baseline's from its class (:data:`nfarm.learning.baselines.BASELINES`), else its name.

    Example:
        >>> id_label("generic:anfis"), id_label("generic:boosting"), id_label("generic:new")
        ('generic: ANFIS', 'generic: gradient-boosted trees', 'generic: new')
    """
    tier, learner = name.rsplit(":", 1)
    return f"{tier}: {ID_LABELS.get(learner) or BASELINES.label(learner)}"


def in_span(label: str) -> bool:
    """Whether a learned-ID contestant's label (:func:`id_label`) is of the rigid-body span tier
    (:data:`nfarm.learning.bases.TIERS`): ridge on the chain basis, an identification in disguise,
    shown beside the verdicts and never an ANFIS's rival.

    Example:
        >>> in_span(id_label("rigid-body span:ridge")), in_span(id_label("structure-informed:ridge"))
        (True, False)
    """
    return label.startswith(f"{TIERS['span']}: ")


def id_configuration(params: Mapping[str, Any]) -> str:
    """An ``id_contest`` cell's options in one line (``residual`` left out: the tier says it)."""
    options = {k: v for k, v in (params.get("options") or {}).items() if k != "residual"}
    return ", ".join(f"{k}={v}" for k, v in options.items()) or "nothing to tune"


def id_tier(params: Mapping[str, Any]) -> str:
    """The tier of prior knowledge of an ``id_contest`` cell's learner (``params``: the cell's
    parameters; :func:`nfarm.learning.bases.tier_of`)."""
    options = dict(params.get("options") or {})
    return tier_of(options if params["learner"] == "anfis" else {**options, "learner": params["learner"]})


def id_family(params: Mapping[str, Any]) -> str:
    """The learned-ID contestant an ``id_contest`` cell belongs to: ``"<tier>:<learner>"``.

    Example:
        >>> id_family({"learner": "anfis", "options": {"inputs": "affine"}})
        'structure-informed:anfis'
        >>> id_family({"learner": "boosting", "options": {"residual": True}})
        'nominal model + learned:boosting'
    """
    return f"{id_tier(params)}:{params['learner']}"


def id_contending(chosen: Mapping[str, CellResult], ranked_by: Sequence[str] = ID_RANKED_BY,
                  spread: Iterable[CellResult] = ()) -> list[str]:
    """The learned-ID contestants still in contention after seed 0: in each tier, the best ANFIS
    and the best of the other learners (by ``ranked_by`` on validation) — the tier's **leaders** —
    and, once the leaders' cells on the other draws are given (``spread``), every other learner of
    the tier **within reach**: its seed-0 value of ``ranked_by[0]`` at most the largest its tier's
    best other learner reached over its seeds (seed 0 and ``spread``), since another draw of the
    data could then rank the two the other way round (issue 65: the SO-101's boosted trees, 3.03 %
    on seed 0, had been pruned inside the MLP's range of 2.72–3.36 %).

    Example (a tier whose MLP leads on seed 0, the trees inside its range, the kernel outside):
        >>> def cell(learner, seed, worst):
        ...     return CellResult(Cell({"learner": learner, "options": {"inputs": "own"}, "seed": seed}, "x"), "ok",
        ...                       {"worst_nrmse": worst, "worst_rmse": worst}, 0.0, "local")
        >>> chosen = {f"generic:{k}": cell(k, 0, v) for k, v in (("anfis", 0.05), ("mlp", 0.027), ("boosting", 0.030),
        ...                                                      ("kernel", 0.05))}
        >>> id_contending(chosen)
        ['generic:anfis', 'generic:mlp']
        >>> id_contending(chosen, spread=[cell("mlp", 1, 0.0336), cell("mlp", 2, 0.0272)])
        ['generic:anfis', 'generic:mlp', 'generic:boosting']
    """
    best: dict[tuple[str, bool], str] = {}
    for name, r in chosen.items():
        slot = (name.rsplit(":", 1)[0], name.endswith(":anfis"))
        if slot not in best or _key(r, ranked_by) < _key(chosen[best[slot]], ranked_by):
            best[slot] = name
    reach: dict[str, float] = {}
    spread = list(spread)
    for (tier, anfis), name in best.items():
        if not anfis:
            same = json_key(chosen[name].cell.params)
            values = [chosen[name].metrics[ranked_by[0]]] + [r.metrics[ranked_by[0]] for r in spread
                                                             if json_key(r.cell.params) == same]
            if len(values) > 1:
                reach[tier] = float(max(values))
    return [name for name in chosen if name in best.values() or (
        not name.endswith(":anfis") and name.rsplit(":", 1)[0] in reach
        and chosen[name].metrics[ranked_by[0]] <= reach[name.rsplit(":", 1)[0]])]


def family(params: Mapping[str, Any]) -> str:
    """The contestant a cell's parameters belong to: ``"anfis:<encoding>"`` for an ANFIS (on the
    dissertation's seven inputs with fuzzy c-means rules, :data:`SEVEN_FCM`: the recipe's
    ``"anfis:quat_xyz"`` is a grid), else the rival's kind, ``"<kind>:arm"`` for a rival in the
    ANFIS's structure (its option ``structure: arm``, :data:`nfarm.learning.ik_rivals.STRUCTURES`).

    Example:
        >>> family({"learner": "rbf", "options": {"structure": "arm", "neighbors": 64}})
        'rbf:arm'
        >>> family({"learner": "anfis", "encoding": "arm_plane"})
        'anfis:arm_plane'
        >>> family({"learner": "anfis", "encoding": "quat_xyz", "options": {"partition": "fcm", "n_rules": 8}})
        'anfis:quat_xyz_fcm'
    """
    if params["learner"] == "anfis":
        fcm = dict(params.get("options") or {}).get("partition") == "fcm"
        return SEVEN_FCM if params["encoding"] == "quat_xyz" and fcm else f"anfis:{params['encoding']}"
    structure = dict(params.get("options") or {}).get("structure", "whole")
    return params["learner"] if structure == "whole" else f"{params['learner']}:{structure}"


def label(name: str) -> str:
    """A contestant's name in words: an ANFIS's from :data:`LABELS`, a rival's from its class
    (:data:`nfarm.learning.ik_rivals.RIVALS`, ``"<kind>:arm"`` in the ANFIS's structure), else its key: one
    phrase, so that a list of contestants reads as one item each.

    Example:
        >>> label("anfis:arm_plane"), label("knn"), label("mlp:arm"), label("svm")
        ("ANFIS in the arm's plane", 'k nearest neighbours', "multilayer perceptron in the ANFIS's structure", 'svm')
    """
    if name in LABELS:
        return LABELS[name]
    kind, _, structure = name.partition(":")
    if kind not in RIVALS or structure not in ("", "arm"):
        return name
    return RIVALS.label(kind) + (" in the ANFIS's structure" if structure == "arm" else "")


def _key(r: CellResult | Replicates, ranked_by: Sequence[str] = RANKED_BY) -> tuple[float, ...]:
    return tuple(float(r.metrics[m]) for m in ranked_by)


def choose(results: Iterable[CellResult], *, family_of=family,
           ranked_by: Sequence[str] = RANKED_BY) -> dict[str, CellResult]:
    """Each contestant's chosen configuration among its seed-0 cells (``ranked_by``, on
    validation), in the order the contestants first appear (``family_of``: a cell's contestant)."""
    chosen: dict[str, CellResult] = {}
    for r in results:
        if r.cell.params.get("seed", 0) != 0 or r.cell.params.get("split", "val") != "val":
            continue
        name = family_of(r.cell.params)
        if name not in chosen or _key(r, ranked_by) < _key(chosen[name], ranked_by):
            chosen[name] = r
    return chosen


def promoted_params(results: Iterable[CellResult], *, family_of=family, ranked_by: Sequence[str] = RANKED_BY,
                    keep: int = PROMOTED, tolerance: float = RUNG_TOLERANCE) -> list[dict]:
    """Successive halving's second rung: each contestant's ``keep`` best seed-0 validation cells
    of the first rung (``results``, by ``ranked_by``) again, on all the training poses
    (``fraction`` 1), in the order of the first rung — where a configuration is within
    ``tolerance`` of the contestant's best first metric, the one listed first (the sweep file
    lists each learner's configurations from the cheapest, those that cost alike in the order
    written: with a ``tolerance``, the smaller of two models that do about as well is promoted;
    :data:`RUNG_TOLERANCE` says why the contest has none).

    Example (the best is promoted; with a tolerance of 5 %, a rule count whose doubling gains
    less than that is not promoted over the smaller):
        >>> from nfarm.study.sweep import CellResult
        >>> from nfarm.study.sweep_files import Cell
        >>> rung = [CellResult(Cell({"learner": "anfis", "encoding": "arm_plane", "options": {"n_rules": n}, "seed": 0},
        ...                         str(n)), "ok", {"position_p95_mm": p95, "orientation_p95_deg": 0.0}, 1.0, "w")
        ...         for n, p95 in ((64, 3.61), (128, 2.93), (256, 2.82), (512, 2.81))]
        >>> [p["options"]["n_rules"] for p in promoted_params(rung)]
        [512]
        >>> [p["options"]["n_rules"] for p in promoted_params(rung, tolerance=0.05)]
        [128]
    """
    results = [r for r in results if r.cell.params.get("seed", 0) == 0 and r.cell.params.get("split", "val") == "val"]
    by_family: dict[str, list[CellResult]] = {}
    for r in results:
        by_family.setdefault(family_of(r.cell.params), []).append(r)
    kept = set()
    for rs in by_family.values():
        limit = (1.0 + tolerance) * min(float(r.metrics[ranked_by[0]]) for r in rs)
        order = sorted(range(len(rs)), key=lambda k: (0, k) if float(rs[k].metrics[ranked_by[0]]) <= limit
                       else (1, _key(rs[k], ranked_by)))
        kept |= {id(rs[k]) for k in order[:keep]}
    return [{**r.cell.params, "fraction": 1.0} for r in results if id(r) in kept]


def at_edge(results: Iterable[CellResult], chosen: Mapping[str, CellResult], *,
            family_of=family) -> dict[str, list[tuple[str, Any, str]]]:
    """Where each contestant's chosen configuration lies at the edge of what its search tried:
    for every numerical option (a number, or a list of numbers sized by their sum) that all of the
    contestant's seed-0 configurations *alike the chosen one* set — those with its other options,
    the words and flags (an ANFIS's ``inputs`` and ``partition``, RBF's ``kernel``), equal — with at
    least three distinct values, ``(option, value, "smallest" | "largest")`` when the chosen
    value is the least or the greatest tried — a wider search in that direction might do better.
    ``chosen``: :func:`choose`'s result (contestant → its chosen cell).

    Example:
        >>> from nfarm.study.sweep import CellResult
        >>> from nfarm.study.sweep_files import Cell
        >>> cells = [CellResult(Cell({"learner": "kernel_ridge", "options": {"gamma": g}, "seed": 0}, str(g)), "ok",
        ...                     {}, 1.0, "w") for g in (1.0, 3.0, 10.0)]
        >>> at_edge(cells, {"kernel_ridge": cells[0]})
        {'kernel_ridge': [('gamma', 1.0, 'smallest')]}

    A list of numbers (an MLP's layer widths) is sized by its sum, its hidden units:
        >>> nets = [CellResult(Cell({"learner": "mlp", "options": {"hidden": h}, "seed": 0}, str(h)), "ok", {}, 1.0, "w")
        ...         for h in ([64, 64], [128, 128, 128], [512, 512])]
        >>> at_edge(nets, {"mlp": nets[2]})
        {'mlp': [('hidden', [512, 512], 'largest')]}
    """
    tried: dict[str, list[Mapping[str, Any]]] = {}
    for r in results:
        if r.cell.params.get("seed", 0) == 0 and r.cell.params.get("split", "val") == "val":
            tried.setdefault(family_of(r.cell.params), []).append(dict(r.cell.params.get("options") or {}))
    edges: dict[str, list[tuple[str, Any, str]]] = {}
    for name, r in chosen.items():
        mine = dict(r.cell.params.get("options") or {})
        options = [o for o in tried.get(name, []) if _alike(o, mine)]
        for key, value in mine.items():
            size = _size(value)
            sizes = [_size(o.get(key)) for o in options]
            if size is None or any(v is None for v in sizes):
                continue
            distinct = sorted(set(sizes))
            if len(distinct) >= 3 and size in (distinct[0], distinct[-1]):
                edges.setdefault(name, []).append((key, value, "smallest" if size == distinct[0] else "largest"))
    return edges


#: A search is *flat* toward its edge when its last step there changed the contestant's best seed-0 validation score by
#: less than this share of it (assumed: well inside every contest's spread over the seeds): a wider search that way is
#: unlikely to move the score, as a steeper last step says it might (:func:`edge_step`).
EDGE_FLAT = 0.01


def edge_step(results: Iterable[CellResult], name: str, option: str, value: Any, metric: str, *,
              family_of=family, like: Mapping[str, Any] | None = None) -> tuple[Any, float] | None:
    """The last step of contestant ``name``'s search toward its edge ``option=value`` (one of
    :func:`at_edge`'s): ``(neighbour, gain)`` — the value tried next to the edge and the relative
    change of the best seed-0 validation ``metric`` over the step, ``(m_neighbour − m_edge) / m_neighbour``,
    among ``name``'s configurations with each value — those alike ``like`` (the chosen configuration's
    options: :func:`at_edge`'s same design) where it is given — (positive: the edge scored better; below
    :data:`EDGE_FLAT` in size, the search is flat there). ``None`` where no configuration holds a
    neighbouring value.

    Example (ridge's penalty: from 1e4 to 1e6 the score moved by 0.05 %, flat):
        >>> from nfarm.study.sweep import CellResult
        >>> from nfarm.study.sweep_files import Cell
        >>> cells = [CellResult(Cell({"learner": "ridge", "options": {"alpha": a}, "seed": 0}, str(a)), "ok",
        ...                     {"worst_nrmse": m}, 1.0, "w") for a, m in ((1.0, 0.158), (1e4, 0.14535), (1e6, 0.14528))]
        >>> neighbour, gain = edge_step(cells, "ridge", "alpha", 1e6, "worst_nrmse")
        >>> neighbour, round(gain, 5), abs(gain) < EDGE_FLAT
        (10000.0, 0.00048, True)
    """
    best: dict[float, tuple[float, Any]] = {}
    for r in results:
        params = r.cell.params
        if params.get("seed", 0) != 0 or params.get("split", "val") != "val" or family_of(params) != name:
            continue
        if like is not None and not _alike(params.get("options") or {}, like):
            continue
        size = _size((params.get("options") or {}).get(option))
        if size is not None and metric in r.metrics:
            m = float(r.metrics[metric])
            if size not in best or m < best[size][0]:
                best[size] = (m, (params.get("options") or {})[option])
    edge = _size(value)
    if edge not in best:
        return None
    sizes = sorted(best)
    k = sizes.index(edge)
    inward = k + 1 if k == 0 else k - 1
    if not 0 <= inward < len(sizes) or inward == k:
        return None
    m_in, neighbour = best[sizes[inward]]
    return neighbour, (m_in - best[edge][0]) / m_in if m_in else 0.0


def edges_text(results: Sequence[CellResult], edges: Mapping[str, Sequence[tuple[str, Any, str]]], metric: str, *,
               label_of, family_of=family, chosen: Mapping[str, CellResult] | None = None) -> str:
    """Each of :func:`at_edge`'s ``edges`` in words with its last step (:func:`edge_step` of ``metric``):
    ``"ridge regression, alpha=1e6 (the largest tried; the step from 10000.0 moved the validation score by
    0.048 %: flat)"``, joined by ``"; "`` (``label_of``: a contestant's name in words; ``chosen``: the
    chosen cells, whose designs the steps compare alike, as :func:`at_edge` does)."""
    phrases = []
    for name, found in edges.items():
        for key, value, side in found:
            like = None if chosen is None else dict(chosen[name].cell.params.get("options") or {})
            step = edge_step(results, name, key, value, metric, family_of=family_of, like=like)
            said = f"{label_of(name)}, {key}={_option_text(value)} (the {side} tried"
            if step is not None:
                neighbour, gain = step
                said += (f"; the step from {_option_text(neighbour)} moved the validation score by "
                         + (f"{100 * abs(gain):.2g} %: flat" if abs(gain) < EDGE_FLAT else
                            f"{100 * gain:+.2g} %"))
            phrases.append(said + ")")
    return "; ".join(phrases)


def _option_text(value: Any) -> str:
    """An option's value in prose: a power of ten's mantissa and exponent from 1e5 up or below 1e-3
    (``1e8``, ``2.5e-06`` → ``2.5e-6``), anything else as written.

    Example:
        >>> _option_text(100000000), _option_text(1.0e6), _option_text(2.5e-6), _option_text(0.025), _option_text([4, 4])
        ('1e8', '1e6', '2.5e-6', '0.025', '[4, 4]')
    """
    if is_number(value, numpy=False) and not isinstance(value, bool) and (abs(value) >= 1e5 or 0 < abs(value) < 1e-3):
        mantissa, exponent = f"{float(value):.3e}".split("e")
        return f"{float(mantissa):g}e{int(exponent)}"
    return str(value)


def _alike(options: Mapping[str, Any], like: Mapping[str, Any]) -> bool:
    """Whether two configurations' options agree on every option that is not numerical (:func:`_size`):
    a search along a number compares configurations of one design, not an ANFIS of fuzzy c-means rules
    with one of a grid."""
    words = lambda o: {k: v for k, v in o.items() if _size(v) is None}        # noqa: E731
    return words(options) == words(like)


def _size(value: Any) -> float | None:
    """A numerical option's size for :func:`at_edge`: the number itself, or a list of numbers'
    sum (an MLP's ``hidden`` widths: its hidden units); ``None`` for anything else."""
    if isinstance(value, (list, tuple)) and value and all(is_number(v, numpy=False) for v in value):
        return float(sum(value))
    if not is_number(value, numpy=False):
        return None
    return float(value)


class Budget(NamedTuple):
    """What one contestant's tuning spent over its seed-0 cells (:func:`budgets`)."""

    configurations: int          #: configurations tried (a promoted one counted once)
    fits: int                    #: models trained (each rung's)
    pose_passes: int             #: training poses (or states) times the passes over them, summed over the fits
    fit_seconds: float           #: the models' own training seconds (``fit_seconds``)
    cell_seconds: float          #: the cells' seconds (training, the validation's predictions, the data's loading)


def passes_of(metrics: Mapping, params: Mapping | None = None) -> int:
    """The passes over its training data one fit made: the epochs its models ran, summed over its
    per-joint models (``metrics["epochs"]``, a number or a list); for gradient boosting (``params``'
    learner), one a tree, ``max_iter`` trees for each joint (``metrics["rmse"]``'s length: each
    iteration sweeps every training state for its gradients and histograms); one for a fit in
    closed form (least squares, kernel ridge, RBF, k-NN).

    Example:
        >>> passes_of({"epochs": [20, 18]}), passes_of({}), passes_of({"rmse": [0.1] * 5},
        ...                                                              {"learner": "boosting", "options": {"max_iter": 300}})
        (38, 1, 1500)
    """
    epochs = metrics.get("epochs") or 0
    total = int(sum(epochs)) if isinstance(epochs, (list, tuple)) else int(epochs)
    if not total and params is not None and params.get("learner") == "boosting":
        joints = metrics.get("rmse")
        trees = (params.get("options") or {}).get("max_iter", BASELINES.of("boosting")().max_iter)
        total = int(trees) * (len(joints) if isinstance(joints, (list, tuple)) else 1)
    return max(total, 1)


def budgets(results: Iterable[CellResult], *, family_of=family) -> dict[str, Budget]:
    """Each contestant's tuning budget spent over its seed-0 cells (both rungs of successive
    halving, :class:`Budget`): the configurations it tried, the fits made, the training poses
    times the passes over them (machine-independent: the published budget, issue 64), and the
    seconds their training took (the models' own ``fit_seconds``) and their cells took (training,
    the validation's predictions and the data's loading, when they ran: they depend on the machine)."""
    spent: dict[str, list[tuple[int, float, float]]] = {}
    tried: dict[str, set[str]] = {}
    for r in results:
        if r.cell.params.get("seed", 0) == 0 and r.cell.params.get("split", "val") == "val":
            name = family_of(r.cell.params)
            work = int(r.metrics.get("train_samples", 0)) * passes_of(r.metrics, r.cell.params)
            spent.setdefault(name, []).append((work, float(r.metrics["fit_seconds"]), float(r.seconds)))
            tried.setdefault(name, set()).add(json_key({k: v for k, v in r.cell.params.items() if k != "fraction"}))
    return {name: Budget(len(tried[name]), len(s), sum(w for w, _, _ in s), float(sum(a for _, a, _ in s)),
                         float(sum(b for _, _, b in s))) for name, s in spent.items()}


def contending(chosen: Mapping[str, CellResult], keep_within: float = KEEP_WITHIN) -> list[str]:
    """The contestants still in contention after seed 0 (module docstring): the two best, every
    one whose 95th percentile is within ``keep_within`` of the best's, and the best ANFIS whatever
    its gap — the verdict's subject, whose spread over the seeds the verdict needs.

    Example (the ANFIS more than twice the best's 95th percentile, still kept):
        >>> def cell(learner, p95):
        ...     return CellResult(Cell({"learner": learner, "encoding": "arm_plane", "seed": 0}, learner), "ok",
        ...                       {"position_p95_mm": p95, "orientation_p95_deg": 0.0}, 0.0, "local")
        >>> chosen = {"kernel_ridge:arm": cell("kernel_ridge", 1.6), "kernel_ridge": cell("kernel_ridge", 2.5),
        ...           "mlp": cell("mlp", 4.5), "anfis:arm_plane": cell("anfis", 5.4), "knn": cell("knn", 40.0)}
        >>> contending(chosen)
        ['kernel_ridge:arm', 'kernel_ridge', 'anfis:arm_plane']
    """
    order = sorted(chosen, key=lambda name: _key(chosen[name]))
    if not order:
        return []
    best = chosen[order[0]].metrics[RANKED_BY[0]]
    anfis = next((name for name in order if name.startswith("anfis:")), None)
    return [name for k, name in enumerate(order)
            if k < 2 or chosen[name].metrics[RANKED_BY[0]] <= keep_within * best or name == anfis]


def spread_params(chosen: Mapping[str, CellResult], seeds: Sequence[int] = SPREAD_SEEDS, *,
                  keep_within: float = KEEP_WITHIN, names: Sequence[str] | None = None) -> list[dict]:
    """The cells that train each chosen configuration in contention on the other draws (those of
    ``names``, or by :func:`contending`)."""
    names = contending(chosen, keep_within) if names is None else names
    return [{**chosen[name].cell.params, "seed": int(s)} for name in names for s in seeds]


def standings(chosen: Mapping[str, CellResult], spread: Iterable[CellResult], *, family_of=family,
              ranked_by: Sequence[str] = RANKED_BY) -> list[Replicates]:
    """The chosen configurations over their seeds (seed 0 and ``spread``): those trained on
    several draws best first by the mean of ``ranked_by`` over the seeds, then the pruned ones
    (one seed) by their seed-0 values."""
    groups = by_configuration([*chosen.values(), *spread])
    wanted = {family_of(r.cell.params) for r in chosen.values()}
    kept = [g for g in groups if family_of(g.cell.params) in wanted]
    return sorted(kept, key=lambda g: (g.n == 1 and len(kept) > 1 and any(h.n > 1 for h in kept), _key(g, ranked_by)))


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
    ``models_dir/ik_contest/<kind>/`` (one model of all joints) and ``<kind>_arm/`` (the ANFIS's
    structure), by contestant (``"rbf"``, ``"rbf:arm"``, …; those present)."""
    where = Path(models_dir) / "ik_contest"
    names = [name for kind in RIVALS for name in (kind, f"{kind}:arm")]
    return {name: RivalIK.load(where / name.replace(":", "_"), robot) for name in names
            if (where / name.replace(":", "_")).is_dir()}


#: The file beside a saved contestant (``ik_contest/<contestant>/``) that holds its chosen cell's
#: validation metrics (:data:`RANKED_BY`) as the contest recorded them (:func:`save_validation`).
VALIDATION_FILE = "validation.json"


def save_validation(where: str | os.PathLike, cell: CellResult, ranked_by: Sequence[str] = RANKED_BY) -> Path:
    """Write ``where/validation.json``: the metrics ``ranked_by`` of ``cell`` (the contestant's chosen
    configuration at the chapter's seed, whose model is saved in ``where``; those it recorded),
    atomically, so that a later chapter ranks the frozen contestants as the contest did without
    predicting the validation poses again (:func:`saved_ranking`, which ranks none with a metric
    missing)."""
    path = Path(where) / VALIDATION_FILE
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps({m: float(cell.metrics[m]) for m in ranked_by if m in cell.metrics}, indent=1) + "\n",
                       encoding="utf-8")
    return path


def saved_ranking(models_dir: str | os.PathLike, contestants: Iterable[str],
                  ranked_by: Sequence[str] = RANKED_BY) -> list[str] | None:
    """``contestants`` (``"rbf"``, ``"rbf:arm"``, … saved under ``models_dir/ik_contest/``) best first
    by the validation metrics the contest recorded for them (:func:`save_validation`; ties in the
    order given), or ``None`` if one has no such record or a damaged one (then rank them again:
    :func:`rival_ranking`)."""
    keys = {}
    for name in contestants:
        path = Path(models_dir) / "ik_contest" / name.replace(":", "_") / VALIDATION_FILE
        try:
            record = json.loads(path.read_text(encoding="utf-8"))
            keys[name] = tuple(float(record[m]) for m in ranked_by)
        except (OSError, ValueError, KeyError, TypeError):
            return None
        if not all(np.isfinite(keys[name])):
            return None
    return sorted(keys, key=keys.get)


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


# --------------------------------------------------------------------------------------------
# The learned-ID contest on the measured arm


@dataclass(frozen=True)
class IDContest:
    """The learned-ID contest's outcome (module docstring): each contestant's chosen configuration
    (``chosen``: family → its seed-0 cell), those kept in contention (``finalists``), every chosen
    configuration over its seeds (``standings``, best first) and each contestant's budget spent
    (``budgets``: :func:`budgets`)."""

    chosen: Mapping[str, CellResult]
    finalists: tuple[str, ...]
    standings: tuple[Replicates, ...]
    budgets: Mapping[str, Budget]

    @property
    def tiers(self) -> list[str]:
        """The tiers present, in the order of the sweep's first cells."""
        return list(dict.fromkeys(name.rsplit(":", 1)[0] for name in self.chosen))

    def group(self, name: str) -> Replicates:
        """Contestant ``name``'s chosen configuration over its seeds."""
        return next(g for g in self.standings if id_family(g.cell.params) == name)

    def pair(self, tier: str) -> tuple[Replicates | None, Replicates | None]:
        """The tier's ANFIS finalist and its best rival over their seeds — of the finalists of other
        learners (the leader and those within its reach), the least by the mean of
        :data:`ID_RANKED_BY` over the seeds (``None`` where the tier has no such contestant)."""
        names = [n for n in self.finalists if n.rsplit(":", 1)[0] == tier]
        anfis = next((self.group(n) for n in names if n.endswith(":anfis")), None)
        rivals = [self.group(n) for n in names if not n.endswith(":anfis")]
        return anfis, min(rivals, key=lambda g: _key(g, ID_RANKED_BY)) if rivals else None

    @property
    def leaders(self) -> tuple[str, ...]:
        """The finalists that led their tier's ANFIS or other learners on seed 0 (those within reach
        of a leader aside)."""
        return tuple(id_contending(self.chosen))

    @property
    def paired(self) -> tuple[str, ...]:
        """The families of every tier's :meth:`pair` (the ANFIS and its best rival over the seeds),
        tier by tier. The rival may be one within reach that overtook the seed-0 leader."""
        return tuple(id_family(g.cell.params) for tier in self.tiers for g in self.pair(tier) if g is not None)

    def winner(self, tier: str) -> Replicates:
        """The tier's best finalist by the mean of :data:`ID_RANKED_BY` over the seeds."""
        return min((g for g in self.pair(tier) if g is not None), key=lambda g: _key(g, ID_RANKED_BY))


def id_model_dir(models_dir: str | os.PathLike, tier: str, slot: str) -> Path:
    """Where chapter 6.8 saves a tier's finalist for ``robot``'s models directory: ``slot``
    ``"anfis"`` or ``"rival"`` under ``models_dir/id_measured/<tier>/`` (:data:`ID_TIER_DIRS`:
    ``generic``, ``structure_informed``, ``rigid_body``, ``identification``, ``identified``,
    ``nominal``; another tier's first word); read it with :func:`nfarm.learning.baselines.load_id_model`.

    Example:
        >>> id_model_dir("m", "identification + learned", "rival").as_posix()
        'm/id_measured/identified/rival'
    """
    if slot not in ("anfis", "rival"):
        raise ValueError(f"slot must be 'anfis' or 'rival', got {slot!r}")
    return Path(models_dir) / "id_measured" / ID_TIER_DIRS.get(tier, tier.split()[0].replace("-", "_")) / slot


def id_contest(seed0: Iterable[CellResult], spread: Iterable[CellResult] = ()) -> IDContest:
    """The learned-ID contest's outcome from its seed-0 cells (``seed0``, validation) and the
    finalists' cells on the other draws (``spread``, those of :func:`id_spread_params`)."""
    seed0 = [r for r in seed0 if r.cell.params.get("split", "val") == "val"]
    chosen = choose(seed0, family_of=id_family, ranked_by=ID_RANKED_BY)
    spread = list(spread)
    finalists = tuple(id_contending(chosen, spread=spread))
    wanted = {json_key(chosen[n].cell.params) for n in finalists}
    spread = [r for r in spread if json_key(r.cell.params) in wanted]
    groups = standings({n: chosen[n] for n in chosen}, spread, family_of=id_family, ranked_by=ID_RANKED_BY)
    return IDContest(chosen, finalists, tuple(groups), budgets(seed0, family_of=id_family))


def id_spread_params(seed0: Iterable[CellResult], seeds: Sequence[int] = SPREAD_SEEDS,
                     spread: Iterable[CellResult] = ()) -> list[dict]:
    """The cells that train each learned-ID finalist on the other draws: the leaders' without
    ``spread``, and with the leaders' cells on those draws (``spread``) also those within their reach
    (:func:`id_contending`)."""
    seed0 = [r for r in seed0 if r.cell.params.get("split", "val") == "val"]
    chosen = choose(seed0, family_of=id_family, ranked_by=ID_RANKED_BY)
    return spread_params(chosen, seeds, names=id_contending(chosen, spread=spread))


def id_spread_runs(sweep: Sweep, seed0: Sequence[CellResult], seeds: Sequence[int], run: Callable[[Sweep], list]
                   ) -> list[CellResult]:
    """The learned-ID finalists' cells on the other draws ``seeds``, run (or reused) by ``run`` (a
    sweep → its results): the leaders' first, then those within their reach (:func:`id_contending`)."""
    spread = run(sweep.with_cells(id_spread_params(seed0, seeds)))
    more = id_spread_params(seed0, seeds, spread)
    return run(sweep.with_cells(more)) if len(more) > len(spread) else spread


# --------------------------------------------------------------------------------------------
# Rigid-body ID sweeps pruned after seed 0 (chapter 6.4's input sets, 6.5's baselines)


def _resolved_worst(r: CellResult, resolved, source: str) -> float:
    return float(np.asarray(r.metrics[source], float)[np.asarray(resolved, bool)].max())


def tier_finalists(results: Iterable[CellResult], resolved, source: str) -> list[CellResult]:
    """Each tier's best configuration after seed 0 (:func:`nfarm.learning.bases.tier_of`): of a
    learned-ID sweep's seed-0 validation cells, the one of least worst-joint NRMSE over the
    ``resolved (n,)`` joints of its per-joint metric ``source`` (``"val_nrmse"`` of a
    ``learned_id`` cell, ``"nrmse"`` of an ``id_baseline`` one), in the order the tiers first
    appear. Only these are trained on the other draws (:data:`SPREAD_SEEDS`): the tier's
    comparison — its best against another tier's, or against the ANFIS of its tier — then has
    its spread over the seeds, and the other configurations, chosen against on seed 0, cost one
    training each (the learned-ID contest's rule, :func:`id_contending`)."""
    best: dict[str, CellResult] = {}
    for r in results:
        if r.cell.params.get("seed", 0) != 0 or r.cell.params.get("split", "val") != "val":
            continue
        tier = tier_of(r.cell.params)
        if tier not in best or _resolved_worst(r, resolved, source) < _resolved_worst(best[tier], resolved, source):
            best[tier] = r
    return list(best.values())


def tier_spread_params(results: Iterable[CellResult], resolved, source: str,
                       seeds: Sequence[int] = SPREAD_SEEDS) -> list[dict]:
    """The cells that train each tier's best configuration (:func:`tier_finalists`) on ``seeds``."""
    return [{**r.cell.params, "seed": int(s)} for r in tier_finalists(results, resolved, source) for s in seeds]


def with_tier_finalists(sweep: Sweep, resolved, source: str, sweeps_dir=None, *, workers: int | None = None,
                        seeds: Sequence[int] = SPREAD_SEEDS, seed0: Sequence[CellResult] | None = None) -> list[CellResult]:
    """A learned-ID sweep's cells (seed 0) with its tier finalists' cells on ``seeds``, each run
    where it is missing from ``sweeps_dir``: what chapter 6 ran, read again by chapters 7 and 8
    (``seed0``: the sweep's results when the caller has read them already)."""
    seed0 = sweep_results(sweep, sweeps_dir, workers=workers) if seed0 is None else list(seed0)
    spread = sweep_results(sweep.with_cells(tier_spread_params(seed0, resolved, source, seeds)), sweeps_dir,
                           workers=workers)
    return [*seed0, *spread]


def json_key(params: Mapping[str, Any]) -> str:
    """A cell's parameters without its seed, as one text: the configuration it trains."""
    return json.dumps({k: v for k, v in params.items() if k != "seed"}, sort_keys=True, default=str)
