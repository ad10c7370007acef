"""The learned-IK contest as chapter 6.1 reports it: its standings, its budget, every
configuration tried, the spread over the seeds and the sentences that read them.

The contest's rules are :mod:`nfarm.study.contest`'s; this module only writes its results down.
Every contestant is judged at the tool on the validation poses: the 95th percentile of the tool
position error [mm] ranks them, the orientation error [deg] breaks ties. A contestant's value
is its mean over the seeds it ran with the least–largest in brackets, or its seed-0 value where
it was pruned after seed 0.

Example:
    >>> mm_text(0.6283), mm_text(3e-8)
    ('0.628', '< 1e-6')
    >>> configuration_text({"options": {"n_rules": 512, "ridge": 1e-9, "joint_options": {"0": {}}}})
    'n_rules=512, ridge=1e-09'
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from ..presentation.plotting import plot_spread
from ..presentation.tables import Table, measured, shown
from ..presentation.wording import listed
from . import contest
from .sweep import CellResult, Replicates

__all__ = ["MM_FLOOR", "DEG_FLOOR", "mm_text", "deg_text", "seeds_text", "configuration_text", "planar_note",
           "contest_table", "budget_table", "configurations_table", "spread_figure", "contest_prose"]

#: [mm] a tool position error below this is rounding (1 nm), shown as such.
MM_FLOOR = 1e-6
#: [deg] an orientation error below this is rounding, shown as such.
DEG_FLOOR = 1e-6


def mm_text(value: float, *, floor: float = MM_FLOOR) -> str:
    """A tool position error [mm] to three digits (``"< 1e-6"`` below ``floor``)."""
    return shown(value, ".3g", floor=floor)


def deg_text(value: float, *, floor: float = DEG_FLOOR) -> str:
    """A tool orientation error [deg] to three digits (``"< 1e-6"`` below ``floor``)."""
    return shown(value, ".3g", floor=floor)


def seeds_text(g: Replicates, metric: str, fmt=mm_text) -> str:
    """A metric's mean over the seeds and its range, ``"0.628 (0.559–0.79)"``, or a pruned
    contestant's ``"1.41 (seed 0)"``; each number written by ``fmt``."""
    return f"{fmt(g.metrics[metric])} ({fmt(g.low(metric))}–{fmt(g.high(metric))})" if g.n > 1 else \
        f"{fmt(g.metrics[metric])} (seed 0)"


def configuration_text(params: Mapping[str, Any]) -> str:
    """A contestant's configuration in one line: its cell's options (``joint_options`` left out)."""
    options = dict(params["options"] or {})
    options.pop("joint_options", None)
    return ", ".join(f"{k}={v}" for k, v in options.items())


def planar_note(robot_name: str, worst_out_of_plane: float, max_out_of_plane_deg: float) -> str:
    """The sentence for an arm whose poses the arm's plane cannot describe: how far its tool's
    roll axis leaves the plane (``worst_out_of_plane`` [rad]) against what the encoding accepts
    [deg], and what the contest does instead."""
    return (f"On {robot_name} the arm's plane cannot describe the poses: the tool's roll axis leaves the arm's vertical "
            f"plane by up to {np.degrees(worst_out_of_plane):.3g}° on the training poses (the "
            f"encoding accepts {max_out_of_plane_deg:g}°). The ANFIS in the arm's plane leaves the contest, and every "
            f"rival takes the dissertation's seven inputs, as its ANFIS does.")


def _name(r) -> str:
    return contest.family(r.cell.params)


def contest_table(ranked: Sequence[Replicates], spent: Mapping[str, tuple]) -> Table:
    """The contest's standings (``ranked``: :func:`nfarm.study.contest.standings`, best first;
    ``spent``: :func:`nfarm.study.contest.budgets`): each contestant's configurations tried, its
    seeds, its chosen configuration, its tool errors over the seeds and its 95th percentile's
    paired difference from the leader's, seed by seed [mm] (a range holding 0: no difference shown)."""
    leader = ranked[0]
    rows = []
    for g in ranked:
        name = _name(g)
        if g is leader:
            gap = "—"
        elif g.n == 1 or leader.n == 1:
            gap = "pruned after seed 0"
        else:
            mean, low, high = contest.paired_gap(g, leader)
            gap = f"{mm_text(mean)} ({mm_text(low)} to {mm_text(high)})" + (" no difference shown" if low <= 0 <= high else "")
        rows.append([contest.label(name), spent[name].configurations, g.n, configuration_text(g.cell.params),
                     seeds_text(g, "position_p50_mm", mm_text), seeds_text(g, "position_p95_mm", mm_text),
                     seeds_text(g, "orientation_p50_deg", deg_text), seeds_text(g, "orientation_p95_deg", deg_text), gap])
    return Table(["contestant", "configurations tried", "seeds", "chosen configuration",
                  "position median [mm]", "position p95 [mm]", "orientation median [deg]", "orientation p95 [deg]",
                  "p95 minus the leader's, paired [mm]"], rows,
                 caption=f"The learned-IK contest on the validation poses, best first: each contestant's configuration chosen on "
                         f"seed 0 by the 95th-percentile tool position error, then, if still in contention, its mean over {leader.n} "
                         f"seeds (each a draw of the training and validation poses and of the initialisation) and the least–largest "
                         f"over them; the last column is the difference from the leader seed by seed (the same draw for both), its mean "
                         f"and range. The budget: the configurations tried (the fits and their seconds in the table below)")


def budget_table(ranked: Sequence[Replicates], spent: Mapping[str, contest.Budget]) -> Table:
    """The contest's budget (saved: ``06_ik_contest_budget``), in the standings' order: each
    contestant's configurations tried, the fits its tuning made (both rungs) and the training poses
    times the passes over them (:class:`nfarm.study.contest.Budget`), the same on any machine; and
    the seconds its tuning's training and its cells took, measurements
    (:func:`nfarm.presentation.tables.measured`: published as the build that first computed these
    results measured them)."""
    return Table(["contestant", "configurations tried", "fits", "training poses × passes",
                  measured("tuning's training [s]"), measured("tuning's cells [s]")],
                 [[contest.label(name), spent[name].configurations, spent[name].fits, f"{spent[name].pose_passes:,}",
                   spent[name].fit_seconds, spent[name].cell_seconds]
                  for name in (_name(g) for g in ranked)],
                 floatfmt=["", "", "", "", ".3g", ".3g"],
                 caption="The contest's budget: each contestant's configurations tried, the models its tuning trained "
                         "(both rungs of successive halving, seed 0) and the training poses they saw times the passes "
                         "over them (the epochs each joint's model ran, summed; a fit in closed form, one pass) — the "
                         "same on any machine —, and the seconds its models' training and its cells (training, "
                         "validation predictions, data loading) took, on one core each, measured (the published "
                         "seconds are those of the build that first computed these results; a build whose other "
                         "columns agree keeps them)")


def configurations_table(rung_runs: Sequence[CellResult], tuning_runs: Sequence[CellResult],
                         chosen: Mapping[str, CellResult]) -> Table:
    """Every configuration of the contest's budget on the validation poses (seed 0): the first
    rung's (``rung_runs``, a share of the training poses) and the second's (``tuning_runs``, all
    of them), each's tool errors and the epochs its models ran; ◀ the configuration ``chosen``
    (:func:`nfarm.study.contest.choose`)."""
    return Table(["contestant", "configuration", "training poses", "position median [mm]", "position p95 [mm]",
                  "orientation p95 [deg]", "epochs run", "choice"],
                 [[contest.label(_name(r)), configuration_text(r.cell.params), f"{r.metrics['train_samples']:,}",
                   mm_text(r.metrics["position_p50_mm"]), mm_text(r.metrics["position_p95_mm"]),
                   deg_text(r.metrics["orientation_p95_deg"]),
                   "/".join(str(e) for e in r.metrics["epochs"]) if max(r.metrics["epochs"]) else "—",
                   "◀ chosen" if chosen[_name(r)] is r else ""]
                  for r in [*rung_runs, *tuning_runs]],
                 caption=f"Every configuration of the contest's budget on the validation poses (seed 0), trained on "
                         f"{contest.RUNG_FRACTION:.0%} of the training poses, then each contestant's promoted "
                         f"{'one' if contest.PROMOTED == 1 else contest.PROMOTED} "
                         + (f"(the first listed within {contest.RUNG_TOLERANCE:.0%} of its best) " if contest.RUNG_TOLERANCE
                            else "(its best) ")
                         + "on all of them (successive halving): the tool errors, the epochs each joint's model ran (early "
                           "stopping; one number for a learner of all joints); their training's seconds are in the budget's "
                           "table above")


def spread_figure(ranked: Sequence[Replicates], robot_name: str) -> tuple[Figure, str]:
    """The contest's spread: each contestant's chosen configuration's 95th percentile [mm] on
    every draw of the data (points, a logarithmic axis) and their mean (bar); the figure and its
    caption."""
    fig = plot_spread({contest.label(_name(g)): g.values("position_p95_mm") for g in ranked},
                      ylabel="95th percentile of the tool position error on validation [mm]",
                      title=f"{robot_name}: each contestant's chosen configuration over its seeds", log=True)
    return fig, ("The contest's spread: each contestant's chosen configuration on every draw of the data (points; their "
                 "number after its name) and their mean (bar), 95th percentile of the tool position error on validation")


def contest_prose(ranked: Sequence[Replicates], spent: Mapping[str, tuple], rung_runs: Sequence[CellResult],
                  chosen: Mapping[str, CellResult]) -> str:
    """What the contest found, in words: the leader and its errors, the runner-up and whether the
    seeds separate them, where the ANFIS in the arm's plane and the dissertation's recipe rank, the
    budget each spent, who was pruned, and which chosen configuration lies at the edge of its search
    (:func:`nfarm.study.contest.at_edge`)."""
    leader = ranked[0]
    runner_up = ranked[1] if len(ranked) > 1 and ranked[1].n == leader.n > 1 else None
    by_name = {_name(g): g for g in ranked}
    text = (f"On the validation poses the leader is **{contest.label(_name(leader))}** "
            f"({configuration_text(leader.cell.params)}): a 95th-percentile tool position error of "
            f"**{seeds_text(leader, 'position_p95_mm', mm_text)} mm** and a median of "
            f"{seeds_text(leader, 'position_p50_mm', mm_text)} mm (mean and range over {leader.n} seeds), orientation "
            f"{seeds_text(leader, 'orientation_p95_deg', deg_text)}° at the 95th percentile. ")
    if runner_up is not None:
        mean, low, high = contest.paired_gap(runner_up, leader)
        text += (f"Second is {contest.label(_name(runner_up))} at {seeds_text(runner_up, 'position_p95_mm', mm_text)} mm: "
                 + (f"seed by seed the two differ by {mm_text(low)} to {mm_text(high)} mm, **no difference shown**. "
                    if low <= 0 <= high else f"worse by {mm_text(low)} to {mm_text(high)} mm on every draw. "))
    plane = by_name.get("anfis:arm_plane")
    if plane is not None and plane not in (leader, runner_up) and plane.n == leader.n > 1:
        mean, low, high = contest.paired_gap(plane, leader)
        text += (f"ANFIS in the arm's plane ranks {ranked.index(plane) + 1} of {len(ranked)}"
                 + (f", not shown to differ from the leader by the seeds (paired, {mm_text(low)} to {mm_text(high)} mm). "
                    if low <= 0 <= high else
                    f": the leader is the better tool, by {mm_text(low)} to {mm_text(high)} mm at the 95th percentile on "
                    f"every draw. "))
    if "anfis:quat_xyz" in by_name:
        g = by_name["anfis:quat_xyz"]
        text += (f"The dissertation's 7-input recipe ranks {ranked.index(g) + 1} of {len(ranked)} at "
                 f"{seeds_text(g, 'position_p95_mm', mm_text)} mm. ")
    if contest.SEVEN_FCM in by_name:
        g = by_name[contest.SEVEN_FCM]
        text += (f"On the same seven inputs with fuzzy c-means rules, the ANFIS ranks {ranked.index(g) + 1} of "
                 f"{len(ranked)} at {seeds_text(g, 'position_p95_mm', mm_text)} mm. ")
    tried = {v[0] for v in spent.values()}
    fewest = min(tried)
    text += (f"Every contestant tried {fewest} configuration{'s' if fewest != 1 else ''} on {contest.RUNG_FRACTION:.0%} "
             f"of the training poses and its promoted "
             f"{'one' if min(contest.PROMOTED, fewest) == 1 else min(contest.PROMOTED, fewest)} again on all of them"
             if len(tried) == 1 else
             "The contestants tried unequal numbers of configurations ("
             + ", ".join(f"{contest.label(k)} {v[0]}" for k, v in spent.items()) + ")")
    text += " (the table gives the seconds each spent)"
    pruned = [contest.label(_name(g)) for g in ranked if g.n == 1 and leader.n > 1]
    text += (f"; pruned after seed 0, more than {contest.KEEP_WITHIN:g} times the best's 95th percentile (the best "
             f"ANFIS is kept whatever its gap, for the verdict's spread): {listed(pruned)}." if pruned else ".")
    edges = contest.at_edge(rung_runs, chosen)
    text += (" At the edge of what its search tried (on the first rung's poses): "
             + contest.edges_text(rung_runs, edges, contest.RANKED_BY[0], label_of=contest.label, chosen=chosen)
             + f". Where the last step moved the score by less than {100 * contest.EDGE_FLAT:g} % the search is flat "
               "there, and a wider one that way is unlikely to move it; where it moved it more, a wider one might "
               "do better." if edges else
             " No contestant's chosen configuration lies at the edge of a value its search tried.")
    if edges:       # what stops the search there: the cost of the chosen fit, and the sweep file's reasons
        costs = [f"{contest.label(name)} {_cost_text(chosen[name].metrics)}" for name in edges]
        text += (" On this machine, one fit of each of those chosen configurations on all the training poses cost: "
                 + "; ".join(costs) + ". The sweep file (`params/sweeps/ik_contest.yaml`) says why each search "
                 "stops where it does (a wider one's cost or a flat search).")
    return text


def _cost_text(metrics: Mapping) -> str:
    """``"12 s of training, 3.6 ms a pose to predict"``: a chosen fit's cost on this machine."""
    us = float(metrics.get("predict_us", 0.0))
    predict = f"{us / 1000:.2g} ms" if us >= 1000 else f"{us:.2g} µs"
    return f"{float(metrics['fit_seconds']):.3g} s of training, {predict} a pose to predict"
