"""The learned-ID contest on the measured arm as chapter 6.8 reports it: learners compete within
their tier of prior knowledge on the measured torques, each tier's ANFIS against its best rival.

The contest's rules are :mod:`nfarm.study.contest`'s (:func:`~nfarm.study.contest.id_contest`);
this module writes its results down. The ranking metric is the study's target metric: the worst
resolved joint's validation NRMSE against the **measured** torques' spread, in %; torques and
their RMSE are in N·m. Each tier's two finalists are also trained on fewer and more training
states (seed 0), so that a reader sees whether the tier's verdict depends on the data's size.

Example (a share in %, at rounding level shown as such):
    >>> pct(0.01234), pct(1e-12)
    ('1.23', '< 1e-6')
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

from ..learning.bases import TIERS, tier_of
from ..model.dynamics import rnea
from ..model.robot import Robot
from ..presentation.plotting import plot_error_by_size, plot_joint_curves
from ..presentation.tables import Table, measured, shown
from ..presentation.wording import listed, ordinal
from . import contest
from .id_comparison_report import ID_FLOOR
from .statistics import resolved_joints
from .sweep import CellResult, Replicates

__all__ = ["pct", "worst_ends", "measured_validation", "newton_euler_rmse", "contest_table", "budget_table",
           "joints_table", "size_curves", "sizes_figure", "contest_prose", "nominal_anfis", "residual_figure"]

STATES = ("q", "qd", "qdd")


def pct(value: float, *, floor: float = ID_FLOOR) -> str:
    """An NRMSE (a share) in %, to three digits (``"< 1e-6"`` below ``floor``)."""
    return shown(100 * value, ".3g", floor=100 * floor)


def worst_ends(g: Replicates) -> str:
    """A finalist's least–largest worst-joint NRMSE over its seeds, in %."""
    return f"{pct(g.low('worst_nrmse'))}–{pct(g.high('worst_nrmse'))}"


def measured_validation(id_val: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The validation data as the measured arm's learners see it: the states its sensors give
    (``q_measured``, … where the data hold them) and the measured torques ``tau`` [N·m]."""
    return {**{k: id_val.get(f"{k}_measured", id_val[k]) for k in STATES}, "tau": id_val["tau_measured"]}


def newton_euler_rmse(robot: Robot, id_val: Mapping[str, np.ndarray]) -> np.ndarray:
    """``(n,)`` [N·m] each joint's RMSE of Newton–Euler with the nominal model on the measured
    validation torques (:func:`measured_validation`): what learning has to beat."""
    m = measured_validation(id_val)
    return np.sqrt(np.mean((rnea(robot, m["q"], m["qd"], m["qdd"]) - m["tau"]) ** 2, axis=0))


def contest_table(idc: contest.IDContest) -> Table:
    """The contest by tier: each learner's chosen configuration, its budget, its training states,
    its worst resolved joint's NRMSE (mean over the seeds of a finalist; ◀ the tier's best), the
    range over the seeds, the worst joint's RMSE [N·m] and the seeds it ran."""
    spent, rows = idc.budgets, []
    for tier in idc.tiers:
        winner = idc.winner(tier)
        for name, r in idc.chosen.items():
            if name.rsplit(":", 1)[0] != tier:
                continue
            g = idc.group(name)
            rows.append([tier, contest.id_label(name).split(": ", 1)[1] + (" ◀" if g is winner else ""),
                         contest.id_configuration(r.cell.params), spent[name][0], f"{r.metrics['train_samples']:,}",
                         pct(g.metrics["worst_nrmse"]), worst_ends(g) if g.n > 1 else "pruned after seed 0",
                         f"{g.metrics['worst_rmse']:.3g}", g.n])
    return Table(["tier", "learner", "chosen configuration", "configurations tried", "training states",
                  "worst resolved joint NRMSE [%]", "range over seeds [%]", "worst joint RMSE [N·m]", "seeds"], rows,
                 caption="The learned-ID contest on the measured arm (validation): each learner's configuration chosen on "
                         "seed 0 by the worst resolved joint's NRMSE against the measured torques' spread; each tier's best "
                         f"ANFIS and best rival also over {len(contest.SPREAD_SEEDS)} more draws of the data (mean and range over the seeds); "
                         "◀ the tier's best by the mean")


def budget_table(idc: contest.IDContest) -> Table:
    """The tuning budget each learner spent on seed 0 (saved: ``06_id_contest_budget``):
    configurations, fits and the training states times the passes over them
    (:class:`nfarm.study.contest.Budget`), the same on any machine; and the seconds its models'
    training and its cells took, measurements (:func:`nfarm.presentation.tables.measured`)."""
    return Table(["learner", "configurations", "fits", "training states × passes",
                  measured("training [s]"), measured("cells [s]")],
                 [[contest.id_label(name), idc.budgets[name].configurations, idc.budgets[name].fits,
                   f"{idc.budgets[name].pose_passes:,}", idc.budgets[name].fit_seconds, idc.budgets[name].cell_seconds]
                  for name in idc.chosen],
                 floatfmt=["", "", "", "", ".3g", ".3g"],
                 caption="The tuning budget each learner spent on seed 0: configurations, the models trained and the "
                         "training states they saw times the passes over them (the epochs each joint's model ran, "
                         "summed; boosting, one a tree of each joint; a fit in closed form, one pass) — the same on any "
                         "machine —, and the seconds its models' training and its cells took, on one core each, "
                         "measured (the published seconds are those of the build that first computed these results; "
                         "a build whose other columns agree keeps them)")


def joints_table(idc: contest.IDContest, id_val: Mapping[str, np.ndarray], ne_rmse: np.ndarray, noise) -> Table:
    """Every joint's validation RMSE [N·m] on the measured torques: Newton–Euler alone
    (``ne_rmse``, :func:`newton_euler_rmse`), each tier's finalists (its leaders and the rivals within
    their reach, :func:`nfarm.study.contest.id_contending`; mean over the seeds),
    the sensor noise σ (``noise (n,)`` [N·m]) and the measured torque's spread; a joint whose
    spread is below σ is marked "(below noise)": shown, not judged."""
    spread = measured_validation(id_val)["tau"].std(axis=0)
    resolved = resolved_joints(spread, noise)
    finalists = {contest.id_label(name): idc.group(name) for name in idc.finalists}
    rows = [["Newton–Euler alone", "nominal model", *(f"{x:.3g}" for x in ne_rmse), "study's own data"]]
    rows += [[name, name.split(":")[0], *(f"{x:.3g}" for x in g.metrics["rmse"]), g.n] for name, g in finalists.items()]
    rows += [["sensor noise σ", "", *(f"{x:.3g}" for x in noise), ""],
             ["measured torque's spread (standard deviation)", "", *(f"{x:.3g}" for x in spread), ""]]
    return Table(["model", "tier", *(f"τ{j + 1} [N·m]" + ("" if resolved[j] else " (below noise)") for j in range(len(spread))),
                  "seeds"], rows,
                 caption="Every joint's validation RMSE on the measured torques for each tier's finalists — its best ANFIS and "
                         "best other learner on seed 0, and every other learner within reach of that one (its seed-0 "
                         "value inside the leader's range over the seeds) — (mean over the seeds), beside the sensor noise σ and the measured torque's spread; a joint whose spread is below "
                         "σ is shown but not judged")


def size_curves(idc: contest.IDContest, size_runs: Sequence[CellResult]) -> dict[str, list[tuple[int, float]]]:
    """Each tier leader's and each tier's pair's (:attr:`nfarm.study.contest.IDContest.paired`)
    ``(training states, worst resolved joint NRMSE [%])`` on seed 0, at the contest's size and at
    every other size it ran (``size_runs``), by the contestant's words."""
    curves: dict[str, list[tuple[int, float]]] = {}
    for r in [*size_runs, *(idc.chosen[name] for name in dict.fromkeys([*idc.leaders, *idc.paired]))]:
        curves.setdefault(contest.id_label(contest.id_family(r.cell.params)), []).append(
            (r.metrics["train_samples"], 100 * r.metrics["worst_nrmse"]))
    return curves


def sizes_figure(curves: Mapping[str, Sequence[tuple[int, float]]], robot_name: str, strides: Sequence[int],
                 id_stride: int) -> tuple[Figure, str]:
    """The validation error of each tier's two finalists against their training states
    (``curves``: :func:`size_curves`; every ``strides``-th and, the contest's, every
    ``id_stride``-th training state); the figure and its caption."""
    fig = plot_error_by_size({name: tuple(zip(*sorted(points))) for name, points in curves.items()},
                             quantity="worst resolved joint NRMSE, validation")
    fig.suptitle(f"{robot_name}: the measured arm's contest, each tier's finalists (seed 0)", fontsize=10)
    return fig, ("Validation error of each tier's two finalists against the number of training states "
                 f"(seed 0; every {listed(ordinal(s) for s in sorted({*strides, id_stride}, reverse=True))} state of "
                 f"the training trajectories, the contest's every {ordinal(id_stride)})")


def contest_prose(idc: contest.IDContest, curves: Mapping[str, Sequence[tuple[int, float]]], ne_rmse: np.ndarray,
                  noise, runs: Sequence[CellResult] = ()) -> str:
    """The contest's verdicts in words: in each tier the ANFIS against its best rival, paired
    seed by seed, and whether their order holds on the most training states (``curves``:
    :func:`size_curves`); then Newton–Euler alone (``ne_rmse``), the best of all, and the sensor
    noise (``noise (n,)`` [N·m]) no model can predict; and, given the tuning round's cells
    (``runs``), every learner whose choice lies at the edge of a search of three or more values
    (:func:`nfarm.study.contest.at_edge`; two configurations bracket nothing and are not judged)."""
    sentences = []
    for tier in idc.tiers:
        a, b = idc.pair(tier)
        winner = idc.winner(tier)
        if a is None or b is None:
            only = contest.id_label(contest.id_family(winner.cell.params)).split(": ", 1)[1]
            sentences.append(f"In the {tier} tier only {only} competes, at {pct(winner.metrics['worst_nrmse'])} %.")
            continue
        rival = contest.id_label(contest.id_family(b.cell.params)).split(": ", 1)[1]
        mean, low, high = contest.paired_gap(a, b, "worst_nrmse")
        verdict = ("not shown to differ from" if low <= 0 <= high else "better than" if high < 0 else "worse than")
        sentences.append(
            f"In the **{tier}** tier the ANFIS reaches {pct(a.metrics['worst_nrmse'])} % ({worst_ends(a)} over "
            f"{a.n} seeds) against the tier's best rival, {rival}, at {pct(b.metrics['worst_nrmse'])} % "
            f"({worst_ends(b)}): paired seed by seed, the ANFIS is **{verdict}** it (difference {pct(low)} to "
            f"{pct(high)} percentage points).")
        curve_a, curve_b = (dict(curves[contest.id_label(contest.id_family(g.cell.params))]) for g in (a, b))
        if len(curve_a) > 1 and len(curve_a) == len(curve_b):
            most, contest_size = max(curve_a), int(a.runs[0].metrics["train_samples"])

            def ahead(n: int) -> bool:
                """The ANFIS ahead on seed 0 at ``n`` training states."""
                return curve_a[n] < curve_b[n]

            sentences[-1] += (f" On {most:,} training states (seed 0) the ANFIS reaches "
                              f"{shown(curve_a[most], '.3g', floor=100 * ID_FLOOR)} % and {rival} "
                              f"{shown(curve_b[most], '.3g', floor=100 * ID_FLOOR)} %: "
                              + ("the same order as on the contest's " if ahead(most) == ahead(contest_size)
                                 else "the other order than on the contest's ") + f"{contest_size:,}.")
    best = min((idc.winner(t) for t in idc.tiers if t != TIERS["span"]), key=lambda g: g.metrics["worst_nrmse"])
    return " ".join(sentences) + (
        f" Newton–Euler alone misses the validation torques by up to {ne_rmse.max():.3g} N·m; best of all is "
        f"{contest.id_label(contest.id_family(best.cell.params))} at {pct(best.metrics['worst_nrmse'])} % "
        f"({best.metrics['worst_rmse']:.3g} N·m on the worst joint; the rigid-body span, an identification in disguise, "
        f"aside). The sensor noise, which no model can predict, is {np.max(noise):.3g} N·m. Chapter 7 tests each "
        f"tier's finalists, frozen, on the held-out trajectories.") + _prior_alone_text(idc, runs) + _edges_text(idc, runs)


def _prior_alone_text(idc: contest.IDContest, runs: Sequence[CellResult]) -> str:
    """`` The identification alone reaches …``: the identification + learned tier's learners whose
    chosen configuration scores within :data:`~nfarm.study.contest.EDGE_FLAT` of the identification
    alone (the identification tier's least squares, seed 0, from the tuning round's ``runs``) add
    nothing to it; those below it are named with their scores (``""`` where the tier or that cell is missing)."""
    metric = contest.ID_RANKED_BY[0]
    alone = next((r for r in runs if r.cell.params.get("learner") == "identification" and r.cell.params.get("seed", 0) == 0
                  and r.cell.params.get("split", "val") == "val"), None)
    tier = TIERS["identified"]
    learners = {name: r for name, r in idc.chosen.items() if name.rsplit(":", 1)[0] == tier}
    if alone is None or not learners:
        return ""
    base = float(alone.metrics[metric])
    nothing, gained = [], []
    for name, r in learners.items():
        learner = contest.id_label(name).split(": ", 1)[1]
        if float(r.metrics[metric]) > (1 - contest.EDGE_FLAT) * base:
            nothing.append(learner)
        else:
            gained.append(f"{learner} {pct(r.metrics[metric])} %")
    text = f" On validation (seed 0) the identification alone reaches {pct(base)} %."
    if nothing:
        text += (f" On its residual, {listed(nothing)} {'does' if len(nothing) == 1 else 'do'} no better than it (within "
                 f"{100 * contest.EDGE_FLAT:g} %): on the inputs {'it is' if len(nothing) == 1 else 'they are'} given here, "
                 f"{'it adds' if len(nothing) == 1 else 'they add'} nothing the identification lacks.")
        anfis = idc.chosen.get(f"{tier}:anfis")
        own_rivals = any((r.cell.params.get("options") or {}).get("angles") == "own" for r in runs
                         if contest.id_family(r.cell.params).rsplit(":", 1)[0] == tier)
        if anfis is not None and (anfis.cell.params.get("options") or {}).get("inputs") == "own" and not own_rivals:
            text += (" The ANFIS's chosen configuration sees each joint's own state alone, one model a joint: a "
                     "structure these rivals, on every joint's state, are not given.")
    if gained:
        text += f" Learners that improve on it: {listed(gained)}."
    return text


def _edges_text(idc: contest.IDContest, runs: Sequence[CellResult]) -> str:
    """`` At the edge of …``: the learners whose chosen value lies at an end of a search of three or
    more values (``""`` when none does or no ``runs`` are given)."""
    edges = contest.at_edge(runs, idc.chosen, family_of=contest.id_family) if runs else {}
    if not edges:
        return " No learner's chosen value lies at the edge of a search of three or more values." if runs else ""
    return (" At the edge of what its search tried: "
            + contest.edges_text(runs, edges, contest.ID_RANKED_BY[0], label_of=contest.id_label,
                                 family_of=contest.id_family, chosen=idc.chosen)
            + f". Where the last step moved the score by less than {100 * contest.EDGE_FLAT:g} % the search is flat "
              "there, and a wider one that way is unlikely to move it; where it moved it more, a wider one might "
              "do better.")


def nominal_anfis(idc: contest.IDContest) -> Replicates | None:
    """The residual ANFIS finalist of the *nominal model + learned* tier (Newton–Euler with the
    nominal masses plus a learned residual), or ``None`` where the tier has none."""
    return idc.pair(tier_of({"residual": True}))[0]


def residual_figure(model, group: Replicates, robot: Robot, noise, seed: int = 0) -> tuple[Figure, str]:
    """The training and validation RMSE [N·m] per epoch of the residual ANFIS (``model``, its
    configuration ``group``: the measured torques minus Newton–Euler), with each joint's sensor
    noise (``noise (n,)`` [N·m]); the figure and its caption."""
    fig = plot_joint_curves(model.models_, robot.joint_names, scale=1.0, unit="N·m", symbol="τ", noise=noise)
    fig.suptitle(f"{robot.name}: residual ANFIS, {contest.id_configuration(group.cell.params)}, seed {seed}", fontsize=10)
    return fig, ("Training and validation RMSE per epoch of the residual ANFIS (measured torques minus Newton–Euler), "
                 "with each joint's sensor noise")
