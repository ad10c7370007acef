"""The chosen learned IK as chapter 6.2–6.3 reports it: the models chapter 7 tests, how the
contest's search over the ANFIS's rule count went, and how its training ended.

The chosen models are published by :func:`nfarm.study.chosen_models.publish_chosen_ik`; this
module writes down what they are. Joint errors are in degrees; a joint learned to rounding
(below :data:`ROUNDING_DEG`: the linear maps of the arm's plane, q1 and q5) is shown as such.

Example:
    >>> from nfarm.study.sweep import Cell, CellResult
    >>> cells = [CellResult(Cell({"learner": "anfis", "encoding": "arm_plane", "options": {"n_rules": n}}, str(n)), "ok",
    ...                     {"position_p95_mm": p95, "position_p50_mm": p95 / 3, "train_samples": 500}, 1.0, "w")
    ...          for n, p95 in ((64, 3.6), (128, 2.9), (256, 2.8))]
    >>> search = rule_count_search(cells, cells[2:], full_poses=2000)
    >>> search.rules, sorted(search.full)
    ([64, 128, 256], [256])
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from ..infra.paths import shown_path
from ..learning.per_joint import n_parameters
from ..model.robot import Robot
from ..presentation.plotting import plot_against, plot_joint_curves
from ..presentation.tables import Table, shown
from . import contest
from .chosen_models import PLANE, RECIPE, ChosenIK, ChosenModels
from .configurations import kept_validation_loss
from .ik_contest_report import configuration_text, mm_text
from .sweep import CellResult, Replicates

__all__ = ["ROUNDING_DEG", "models_table", "models_note", "RuleCountSearch", "rule_count_search", "rule_count_figure",
           "rule_count_prose", "learned_joints", "curves_figure", "epochs_prose"]

#: [deg] a joint's validation RMSE below this is rounding: a joint the model computes exactly.
ROUNDING_DEG = 1e-3


def models_table(chosen_ik: ChosenIK, contest_chosen: Mapping[str, CellResult], robot: Robot, seed: int = 0, *,
                 floor: float = ROUNDING_DEG) -> Table:
    """The validation RMSE per joint [deg] of the ANFIS models chapter 7 tests: the chosen learned
    IK and the recipe as the contest trained them (from their cells' predictions; ``"—"`` unless
    ``seed`` is 0, the contest's) and the recipe as it is on its full-range data (from its kept
    epoch), each with its epochs per joint and its parameters."""
    rows = []
    for name_, name in (("chosen: " + contest.label(chosen_ik.name), chosen_ik.name),
                        ("the dissertation's 7 inputs (contest)", RECIPE)):
        if name in contest_chosen:
            r = contest_chosen[name] if seed == 0 else None
            model = chosen_ik.saved[name]
            rows.append([name_, "/".join(str(len(m.loss_curve_)) for m in model.models_), n_parameters(model),
                         *((shown(v, ".3g", floor=floor) for v in r.metrics["joint_rmse_deg"]) if r is not None
                           else ["—"] * robot.n)])
    if "ik_full" in chosen_ik.recipe:
        full = chosen_ik.recipe["ik_full"]
        rows.append(["the dissertation's recipe as it is, full joint ranges", "/".join(str(len(m.loss_curve_)) for m in full.models_),
                     n_parameters(full), *(shown(v, ".3g", floor=floor) for v in np.degrees(kept_validation_loss(full)))])
    return Table(["model", "epochs per joint", "parameters", *(f"q{j + 1} [deg]" for j in range(robot.n))], rows,
                 caption=f"Validation RMSE per joint of the ANFIS models chapter 7 tests (seed {seed}: the study's own data; the "
                         f"contest's models from their predictions, the full-range recipe's from its kept epoch)")


def models_note(store: ChosenModels, chosen_ik: ChosenIK) -> str:
    """Where the IK models are (and how to load them), and how long the chosen ANFIS (and the
    full-range recipe) took to train when they were made."""
    recipe = chosen_ik.recipe
    return (f"Models in `{shown_path(store.ik_contest)}` (one directory per contestant; `LearnedIK.load(directory, robot)` "
            f"or `RivalIK.load(directory, robot)`) and the chosen learned IK in `{shown_path(store.ik)}`. Training the chosen "
            f"ANFIS took {sum(chosen_ik.model.fit_seconds_):.0f} s when it was made"
            + (", the full-range recipe " + f"{sum(recipe['ik_full'].fit_seconds_):.0f} s" if "ik_full" in recipe else "") + ".")


@dataclass(frozen=True)
class RuleCountSearch:
    """The contest's search over the rule count of the ANFIS in the arm's plane (seed 0):
    every count at the first rung (``rung``, ascending), the promoted ones on all the training
    poses (``full``: count → cell), and the two sizes [poses]."""

    rung: tuple[CellResult, ...]
    full: Mapping[int, CellResult]
    full_poses: int

    @property
    def rules(self) -> list[int]:
        """The rule counts tried, ascending."""
        return [r.cell.params["options"]["n_rules"] for r in self.rung]

    @property
    def rung_poses(self) -> int:
        """The first rung's training poses."""
        return self.rung[0].metrics["train_samples"]

    def at_rung(self, metric: str) -> list[float]:
        """Each count's ``metric`` at the first rung."""
        return [r.metrics[metric] for r in self.rung]

    def at_full(self, metric: str) -> list[float]:
        """Each count's ``metric`` on all the poses (NaN where it was not promoted)."""
        return [self.full[n].metrics[metric] if n in self.full else np.nan for n in self.rules]


def rule_count_search(rung_runs: Sequence[CellResult], tuning_runs: Sequence[CellResult], *,
                      full_poses: int) -> RuleCountSearch:
    """The ANFIS in the arm's plane's cells of both rungs (``rung_runs``, ``tuning_runs``);
    ``full_poses``: the number of training poses."""
    rung = sorted((r for r in rung_runs if contest.family(r.cell.params) == PLANE),
                  key=lambda r: r.cell.params["options"]["n_rules"])
    full = {r.cell.params["options"]["n_rules"]: r for r in tuning_runs if contest.family(r.cell.params) == PLANE}
    return RuleCountSearch(tuple(rung), full, int(full_poses))


def rule_count_figure(search: RuleCountSearch, ranked: Sequence[Replicates], chosen: Mapping[str, CellResult],
                      robot_name: str) -> tuple[Figure, str]:
    """The tool position error [mm] of the ANFIS in the arm's plane against its rule count on the
    validation poses (seed 0), at both rungs, beside the best rival's on all the poses (dashed:
    the best of ``ranked`` that is not an ANFIS, its configuration ``chosen``); the figure and its
    caption."""
    rivals = [g for g in ranked if not contest.family(g.cell.params).startswith("anfis")]
    best_rival = chosen[contest.family(rivals[0].cell.params)] if rivals else None
    rung, full = f"{search.rung_poses:,} poses", f"{search.full_poses:,} poses"
    fig = plot_against(search.rules, {f"ANFIS, 95th percentile, {rung}": search.at_rung("position_p95_mm"),
                                      f"ANFIS, median, {rung}": search.at_rung("position_p50_mm"),
                                      f"ANFIS, 95th percentile, {full}": search.at_full("position_p95_mm"),
                                      f"ANFIS, median, {full}": search.at_full("position_p50_mm")},
                       xlabel="rules (fuzzy c-means, shared by the pitch joints)",
                       ylabel="tool position error on validation [mm]",
                       references={} if best_rival is None else {
                           f"{contest.label(contest.family(best_rival.cell.params))}, 95th percentile":
                               best_rival.metrics["position_p95_mm"],
                           f"{contest.label(contest.family(best_rival.cell.params))}, median":
                               best_rival.metrics["position_p50_mm"]})
    fig.axes[0].set_title(f"{robot_name}: the contest's rule counts (seed 0)", fontsize=10)
    return fig, ("Tool position error of the ANFIS in the arm's plane against its rule count on the validation poses "
                 "(seed 0): every count trained on the first rung's share of the training poses, the promoted ones on all "
                 "of them, and the best rival's on all of them (dashed)")


def rule_count_prose(search: RuleCountSearch, *, tolerance: float = contest.RUNG_TOLERANCE) -> str:
    """Where the rule count's first-rung 95th percentile is least and whether the search reached
    past it — more counts doing no better, the curve flattened (the last doubling gaining at most
    ``tolerance``, :data:`nfarm.study.contest.RUNG_TOLERANCE`) or still falling (the budget ended
    the search) — the count promoted, and the promoted counts' errors on all the poses. Needs two
    counts or more."""
    rules, p95 = search.rules, search.at_rung("position_p95_mm")
    best_k = int(np.argmin(p95))
    last_gain = 1 - p95[-1] / p95[-2]
    return (f"Trained on {search.rung_poses:,} poses, from {rules[0]} to {rules[-1]} rules the 95th percentile goes from "
            f"{mm_text(p95[0])} to {mm_text(p95[-1])} mm; the best is {rules[best_k]} rules ({mm_text(p95[best_k])} mm)"
            + (f", and more rules do no better ("
               f"{', '.join(f'{n} rules {mm_text(v)} mm' for n, v in zip(rules[best_k + 1:], p95[best_k + 1:]))})"
               if best_k < len(rules) - 1 else
               f", the largest count tried, but its doubling gained {last_gain:.1%} only: the curve has flattened"
               if last_gain <= tolerance else
               f", the largest count tried, its doubling still gaining {last_gain:.0%}: the contest's budget, not the model, "
               f"ended the search, and more rules would likely do better still")
            + (f". The smallest count within {tolerance:.0%} of the best is promoted to all the poses." if tolerance else
               ". The best count is promoted to all the poses.")
            + " On all " + f"{search.full_poses:,} poses: "
            + "; ".join(f"{n} rules {mm_text(r.metrics['position_p95_mm'])} mm" for n, r in sorted(search.full.items()))
            + ".")


def learned_joints(model, *, floor: float = ROUNDING_DEG) -> list[int]:
    """The joints a learned IK ``model`` learns (indices): those whose kept validation RMSE is
    above ``floor`` [deg] and that the pitch closure does not compute."""
    closure = getattr(model, "closure_", None)
    return [j for j, loss in enumerate(kept_validation_loss(model))
            if np.degrees(loss) > floor and (closure is None or j != closure["joint"])]


def curves_figure(chosen_ik: ChosenIK, params: Mapping[str, Any], robot: Robot, *,
                  floor: float = ROUNDING_DEG) -> tuple[Figure, str]:
    """The training and validation RMSE [deg] per epoch of the chosen learned IK's learned joints
    (:func:`learned_joints`), titled with its configuration (``params``: its cell's); the figure
    and its caption."""
    model = chosen_ik.model
    closure = getattr(model, "closure_", None)
    joints = learned_joints(model, floor=floor)
    fig = plot_joint_curves(model.models_, robot.joint_names, joints=joints)
    fig.suptitle(f"{robot.name}: {contest.label(chosen_ik.name)} ({configuration_text(params)})", fontsize=10)
    return fig, ("Training and validation RMSE per epoch of the chosen learned IK's models"
                 + (" (joints learned to rounding left out"
                    + (f"; q{closure['joint'] + 1} comes from the pitch closure" if closure else "")
                    + ")" if len(joints) < robot.n else ""))


def epochs_prose(model, options: Mapping[str, Any], *, floor: float = ROUNDING_DEG) -> str:
    """How the chosen learned IK's training ended (``options``: its cell's, with its ``epochs``
    limit, ``patience`` and ``min_improvement``): the epochs each learned joint ran and kept, and
    whether the limit or early stopping ended it (and how much its last ``patience`` epochs still
    lowered the least validation error)."""
    joints = learned_joints(model, floor=floor)
    ran = [len(model.models_[j].loss_curve_) for j in joints]
    kept = [int(model.models_[j].best_epoch_) + 1 for j in joints]      # 1-based, as the figure counts
    limit = options.get("epochs")
    patience, min_fall = options.get("patience"), options.get("min_improvement", 0.0)
    if limit is not None and max(ran) >= limit:
        how = f"— the limit of {limit}: early stopping did not end the training, so longer training would likely help."
    elif patience is not None and min(ran) > patience:
        # The share by which each joint's last `patience` epochs lowered its least validation error
        last = [1 - min(model.models_[j].val_loss_curve_[-patience:]) / min(model.models_[j].val_loss_curve_[:-patience])
                for j in joints]
        how = (f"— early stopping ended the training before the limit of {limit} epochs: its last {patience} epochs "
               f"lowered the joints' least validation errors by "
               f"{'–'.join(dict.fromkeys(f'{max(0.0, 100 * x):.2g}' for x in (min(last), max(last))))} % "
               + (f"(a fall counts when it takes the joints' combined error {min_fall:.1%} below the last level that "
                  f"counted)." if min_fall else "(none counts: the error had stopped falling)."))
    else:
        how = f"— early stopping ended the training before the limit of {limit} epochs."
    return (f"The chosen model's learned joints ran {', '.join(str(e) for e in ran)} epochs and kept epochs "
            f"{', '.join(str(e) for e in kept)}, where their validation error was least {how}")
