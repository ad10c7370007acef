"""The study's findings in words, every number and comparison read back from the tables chapter 7
publishes (``07_summary.csv``, every method's held-out errors; ``07_paired.csv``, the paired
comparisons), so that what a page says is what a table holds.

:class:`PublishedResults` reads the two tables and answers "what is this method's value, and is it
better than that one's?" on the paired interval of their difference; :func:`study_in_words` is
chapter 7.7's summary of the study in a few bullets.

Example (two IK methods of a summary and their paired difference):

    >>> import tempfile
    >>> from pathlib import Path
    >>> from nfarm.study.paired import Paired, paired_table
    >>> from nfarm.study.rows import Row, long_table
    >>> rows = [Row("inverse kinematics", m, "", "position p95", "mm", v, v - 0.1, v + 0.1, 200, 0.95, "")
    ...         for m, v in (("ANFIS", 0.6), ("RBF", 1.3))]
    >>> pair = Paired("inverse kinematics", "ANFIS", "RBF", "position p95", "mm", -0.7, -0.8, -0.6, 200, 0.95, "")
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     _ = long_table(rows).save(tmp, "07_summary"); _ = paired_table([pair]).save(tmp, "07_paired")
    ...     results = PublishedResults(Path(tmp) / "tables")
    ...     results.order("ANFIS", "RBF", "position p95"), results.said("RBF", "position p95")
    (-1, '1.3 (1.2–1.4) mm')
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from ..presentation.wording import listed, times, times_range
from ..study.measured_test import NE, MeasuredTest, against
from ..study.paired import orientation_by_structure, paired_difference, paired_judge
from ..study.result_tables import SUMMARY_FLOORS, read_long_table, read_paired, table_number
from ..study.rows import ROLE_RESIDUAL_BASELINE, WORST_ID, Row, interval_text, rows_from_table
from ..study.verdict_rows import ID_TARGET_PCT, IK_TARGETS, target_verdict

__all__ = ["PublishedResults", "study_in_words", "residual_baseline", "measured_in_words", "TIER_WORDS",
           "shifted_in_words", "shifted_id_in_words", "joint_groups_in_words"]

IK = "inverse kinematics"
ID = "inverse dynamics"
MEASURED = "ID, measured arm"

#: What an ID tier's inputs tell its learner about the arm, in words.
TIER_WORDS = {"generic": "only what holds for every rigid arm (torque affine in q̈, quadratic in q̇)",
              "structure-informed": "which of the arm's axes are parallel (the sums of their angles), no length or mass"}


class PublishedResults:
    """One arm's published summary and paired comparisons (``tables``: the directory holding
    ``07_summary.csv`` and ``07_paired.csv``), read once; ``floors`` the values shown as below
    their unit's rounding (:data:`nfarm.study.result_tables.SUMMARY_FLOORS`)."""

    def __init__(self, tables: str | os.PathLike, *, floors: Mapping[str, float] = SUMMARY_FLOORS):
        tables = Path(tables)
        self.text = read_long_table(tables / "07_summary.csv")
        self.paired = read_paired(tables / "07_paired.csv")
        self.floors = floors
        self._judge = paired_judge(self.paired)
        self._text_of = {(r["task"], r["method"], r["metric"]): r for r in self.text}
        self.rows: list[Row] = rows_from_table(self.text)
        self._row_of = {(r.task, r.method, r.metric): r for r in self.rows}

    def value(self, method: str, metric: str, task: str = IK) -> Row:
        """The published row of ``method``'s ``metric`` on ``task``."""
        return self._row_of[task, method, metric]

    def said(self, method: str, metric: str, task: str = IK) -> str:
        """The value with its interval and unit, as the prose shows it (``"1.3 (1.2–1.4) mm"``)."""
        r = self.value(method, metric, task)
        return f"{interval_text(r, self.floors)}{'°' if r.unit == 'deg' else ' ' + r.unit}"

    def order(self, a: str, b: str, metric: str, task: str = IK) -> int:
        """-1 where ``a`` is lower than ``b`` on the paired interval of their difference, 1 higher,
        0 no difference shown."""
        return self._judge(self._text_of[task, a, metric], self._text_of[task, b, metric])

    def gap_said(self, a: str, b: str, metric: str, task: str, b_words: str) -> str:
        """``a`` against ``b`` in words, with the paired interval of their difference."""
        d, lo, hi = paired_difference(self.paired, task, a, b, metric)
        unit = self.value(a, metric, task).unit
        unit = "percentage points" if unit == "%" else unit        # the gap of two shares
        if hi < 0:
            return f"better than {b_words} by {-d:.2g} {unit} (paired interval {-hi:.2g} to {-lo:.2g})"
        if lo > 0:
            return f"worse than {b_words} by {d:.2g} {unit} (paired interval {lo:.2g} to {hi:.2g})"
        return f"not shown to differ from {b_words} (paired interval of the difference {lo:.2g} to {hi:.2g} {unit})"

    def ik_metrics(self, method: str) -> list[str]:
        """The IK metrics ``method`` has an interval on (its maxima left out), in the table's order."""
        return [r.metric for r in self.rows if r.task == IK and r.method == method and r.n]

    def sides(self, a: str, b: str, ours: str, theirs: str) -> str:
        """Where ``a`` is better, worse or not shown to differ from ``b`` on every IK metric with an
        interval — with no orientation claim where a structure, not a learner, sets either's
        orientation (:func:`nfarm.study.paired.orientation_by_structure`)."""
        metrics = self.ik_metrics(a)
        side: dict[int, list[str]] = {-1: [], 1: [], 0: []}
        fixed = any(orientation_by_structure({m: self._text_of[IK, x, m] for m in metrics}) for x in (a, b))
        for metric in metrics:
            if fixed and metric.startswith("orientation"):
                continue
            side[self.order(a, b, metric)].append(f"{metric} ({self.said(a, metric)} against {self.said(b, metric)})")
        return "; ".join(([f"{ours} is better on {listed(side[-1])}"] if side[-1] else [])
                         + ([f"**{theirs} is better** on {listed(side[1])}"] if side[1] else [])
                         + ([f"no difference shown on {listed(side[0])}"] if side[0] else [])
                         + (["orientation not compared: a structure, not a learner, sets it"] if fixed else []))


def study_in_words(results: PublishedResults, *, chosen: str, recipe: str, rival: str, lm_saves: str, lm_other: str,
                   closed: str | None = None, closed_time_ratio: float | None = None, closed_start: bool = False,
                   id_chosen: str, id_tier: str, id_recipe: str, identified: str, id_baseline: str | None = None,
                   resolved: np.ndarray | None = None, worst_words: str = "",
                   measured: Mapping | None = None) -> str:
    """Chapter 7.7's summary of the study as Markdown bullets: the learned IK against the recipe
    and the best rival (``chosen``, ``recipe``, ``rival``: their names in the summary), the closed
    form (``closed``, and its time per pose over the ANFIS's), LM's warm start (``lm_saves``: what
    the ANFIS's start does to LM's iterations, in words; ``lm_other``: the best other start;
    ``closed_start``: whether the closed form's solution was a start); the learned ID of tier
    ``id_tier`` against the best baseline, the dissertation's design and the identification
    (``resolved``: the joints a sensor resolves, ``worst_words`` the worst of them in words); and,
    for an arm with a measured twin, ``measured``: ``residual``, ``friction_id`` and
    ``residual_baseline`` (or ``None``) the methods' names, ``tiers`` a sequence of
    ``(tier, chosen method's name)``."""
    said, value = results.said, results.value
    ik_diss, ik_worst = value(recipe, "worst joint RMSE").value, value(chosen, "worst joint RMSE").value
    met = sum(target_verdict(value(chosen, metric), limit) == "✓" for _, metric, limit, _ in IK_TARGETS)
    lines = [
        "* **Inverse kinematics** "
        + ("is learnable where it is a function" if met == len(IK_TARGETS) else
           f"is learned where it is a function, but meets {met} of the study's {len(IK_TARGETS)} targets")
        + f": in the declared region (chapter 5) the chosen ANFIS, over its seeds, misses by at most "
        f"{said(chosen, 'worst joint RMSE')} per joint, {times(ik_worst / ik_diss)} the error of the dissertation's recipe "
        f"(assumed) on the same data ({said(recipe, 'worst joint RMSE')}), each tuned by chapter 6's contest with the same "
        f"budget. Against the recipe (paired intervals): {results.sides(chosen, recipe, 'the chosen ANFIS', 'the recipe')}. "
        f"Against the best baseline on the validation poses, {rival}, on the same test poses (paired intervals): "
        f"{results.sides(chosen, rival, '**the ANFIS**', 'the baseline')}. "
        + (f"The closed form (chapter 2) is exact (position error at most {said(closed, 'position max')}) and "
           f"takes {times(closed_time_ratio)} the ANFIS's time per pose in this run. " if closed is not None else "")
        + f"The ANFIS does not replace LM, which is exact at the tool; as LM's starting guess it {lm_saves} the "
          f"iterations LM needs from the best other start it iterates from in the region, {lm_other.split(' (')[0]} "
          f"(section 7.3)" + ("; the closed form's solution leaves LM nothing to do." if closed_start else ".")]
    free_row = value(id_chosen, WORST_ID, ID)
    all_resolved = resolved is None or bool(np.all(resolved))
    id_text = (f"* **Inverse dynamics**, the ANFIS of the {id_tier} tier (its inputs say "
               f"{TIER_WORDS.get(id_tier, id_tier)}): "
               + ("it meets the study's ≤ 5 % target, " if free_row.high <= ID_TARGET_PCT else
                  "it does not meet the study's ≤ 5 % target on its whole interval, ")
               + f"missing by {said(id_chosen, WORST_ID, ID)} of its worst joint's spread"
               + (f" ({worst_words})" if not all_resolved else "")
               + f", largest error {said(id_chosen, 'largest error', ID)} (the chapter's model). ")
    if id_baseline:
        verdict_word = {-1: "**the baseline is better**", 1: "the ANFIS is better", 0: "no difference shown"}[
            results.order(id_baseline, id_chosen, WORST_ID, ID)]
        id_text += (f"The best baseline on the validation trajectories, {id_baseline}: "
                    f"{said(id_baseline, WORST_ID, ID)} — on the worst joint {verdict_word} (paired interval). ")
    id_text += (f"With each joint's own state, the dissertation's design (assumed), it is not learned "
                f"({said(id_recipe, WORST_ID, ID)} on the worst joint). Given the geometry, the "
                f"identification on the regressor is exact ({said(identified, WORST_ID, ID)}) — physics, "
                f"not learning.")
    lines.append(id_text)
    if measured is not None:
        res, ls, best_res = measured["residual"], measured["friction_id"], measured.get("residual_baseline")
        tiers: Sequence[tuple[str, str]] = measured["tiers"]
        lines.append(
            f"* **What learning adds** to the physical model, on an arm whose friction law no candidate assumes, by "
            f"the study's target metric (the worst resolved joint's NRMSE against the measured torques' spread): "
            f"Newton–Euler + residual ANFIS leaves {said(res, 'worst NRMSE', MEASURED)} "
            f"against {said(ls, 'worst NRMSE', MEASURED)} for the least-squares friction identification — "
            f"{results.gap_said(res, ls, 'worst NRMSE', MEASURED, 'the identification')}"
            + (f"; the best other learner as a residual, {best_res}, is "
               f"{results.gap_said(best_res, res, 'worst NRMSE', MEASURED, 'the ANFIS residual')}"
               if best_res is not None else "") + ". "
            + "Tier by tier on the held-out trajectories, each tier's choice on validation: "
            + "; ".join(f"{tier}, {name.split(': ', 1)[1]} ({said(name, 'worst NRMSE', MEASURED)})" for tier, name in tiers)
            + ".")
    return "\n".join(lines)


def residual_baseline(roles: Mapping[str, str], name: str | None) -> str | None:
    """``name`` where it holds the role of the best other learner as a residual (on validation), else ``None``."""
    return name if name is not None and roles.get(name) == ROLE_RESIDUAL_BASELINE else None


def measured_in_words(t: MeasuredTest, rmse: Mapping, targets: Mapping[str, Row], targets_all: Mapping[str, Row], *,
                      noise: np.ndarray, payload: Mapping | None = None, payload_kg: float = 0.0, draws: int = 2000,
                      level: float = 0.95, seed: int = 0) -> str:
    """Chapter 7.6's findings on the measured arm (:class:`nfarm.study.measured_test.MeasuredTest`):
    what the friction identification gives Newton–Euler, each tier's ANFIS against its best
    rival, what gains on the identification, the best ANFIS without the rigid-body model against
    Newton–Euler alone — each on the paired interval of the worst joints' RMSE
    (:func:`~nfarm.study.measured_test.against`) — the study's ≤ 5 % target (``targets``,
    ``targets_all``: the rows of :func:`~nfarm.study.measured_test.nrmse_table`), the payload case
    (``payload``: its intervals, with ``payload_kg``) and the sensor noise (``noise (n,)`` [N·m]);
    ``rmse`` the intervals of :func:`~nfarm.study.measured_test.rmse_table`."""
    boot = {"draws": draws, "level": level, "seed": seed}
    order, ls = t.order, t.friction_id
    versus_ls = {name: against(t, name, ls, **boot) for name in order if name not in (NE, ls)}
    gains = [name for name, (v, _) in versus_ls.items() if v == "better"]
    ls_ci = rmse[ls]
    text = (f"Newton–Euler alone misses the measured torques by {rmse[NE].worst:.3g} N·m on its worst joint; "
            f"identifying each joint's armature, viscous and Coulomb friction by least squares brings that to "
            f"**{ls_ci.worst:.3g} N·m** ({ls_ci.worst_low:.3g}–{ls_ci.worst_high:.3g}). ")
    text += "Tier by tier, the ANFIS against its best rival on the worst joint: " + "; ".join(
        f"{tier}, the ANFIS is {against(t, a, b, **boot)[1]} against {b.split(': ', 1)[1]}"
        for tier, (a, b) in t.pairs.items()) + ". "
    text += (f"Beyond the spread and beyond the friction identification: {listed(gains)}."
             if gains else "Nothing gains on the friction identification beyond the spread: on this arm, "
                           "the engineer's least-squares friction model is as far as anything gets.")
    alone = t.learned_alone
    if alone is not None:
        verdict, why = against(t, alone, NE, **boot)
        text += (f" The best ANFIS without the rigid-body model, {alone}, is {why} against Newton–Euler alone"
                 + (": learned without the model, the inverse dynamics of the measured arm is worse than the model "
                    "that ignores its friction." if verdict == "worse" else "."))
    met = [name for name in order if target_verdict(targets[name], ID_TARGET_PCT) == "✓"]
    met_all = [name for name in order if target_verdict(targets_all[name], ID_TARGET_PCT) == "✓"]
    text += (f" Against the study's ≤ 5 % target, judged on the measured torques' spread over the joints a sensor "
             f"resolves: met (the whole interval below) by {listed(met)}" if met else
             " No method meets the study's ≤ 5 % target on the measured torques' spread over the joints a sensor resolves")
    text += (f"; over every joint, the noise-level ones included: by {listed(met_all)}." if met_all else
             "; over every joint, the noise-level ones included: by none.")
    if payload is not None:
        grown = [payload[name].worst / rmse[name].worst for name in order if name != NE]
        text += (f" With a payload of {payload_kg:g} kg that no model was trained with, every fitted "
                 f"model's worst-joint error becomes {times_range(min(grown), max(grown))} what it was without it: a load "
                 f"none of them is told is a load none of them predicts.")
    return text + f" The sensor noise, which no model can predict, is {noise.max():.3g} N·m."


def _side(row: Mapping[str, str]) -> int:
    """The side of 0 a verdict row's paired interval lies on (-1: the ANFIS lower, 0: holds 0),
    whatever a family-wise correction says; an end below the table's floor ("< 1e-06") counts as 0."""
    return -1 if table_number(row["gap_high"]) < 0 else 1 if table_number(row["gap_low"]) > 0 else 0


def shifted_in_words(shifted: Mapping[str, str], main: Mapping[str, str], *, rival: str, described: str) -> str:
    """The shifted population's verdict against the main one, in words (chapter 7.7), read back from
    the two published verdict rows (``07_verdict_shifted.csv``'s and ``07_verdict.csv``'s
    inverse-kinematics row, :func:`nfarm.study.result_tables.read_verdicts`); ``rival`` the best other
    method's reader's label, ``described`` the population (:func:`nfarm.study.shifted.describe`)."""
    def span(r, k):
        return f"{r[k + '_value']} mm ({r[k + '_low']}–{r[k + '_high']})"

    def gap(r):
        return f"{r['gap']} mm ({r['gap_low']} to {r['gap_high']})"

    return (f"**A shifted population.** Declared in the study file before it was drawn, {described}: poses "
            f"just past those every model was trained, tuned and chosen on, where each extrapolates. There the ANFIS's "
            f"95th-percentile tool position error is {span(shifted, 'anfis')} and that of the best other method, "
            f"{rival}, {span(shifted, 'rival')}; the ANFIS less the rival {gap(shifted)}: "
            f"**{shifted['verdict']}**, against {gap(main)}, {main['verdict']}, on the test split — "
            + ("the paired interval lies on the same side of 0 on both." if _side(shifted) == _side(main) else
               f"**on the shifted population the paired interval {'holds 0' if _side(shifted) == 0 else 'excludes 0'}, "
               f"on the test split it {'holds 0' if _side(main) == 0 else 'excludes 0'}**.")
            + _holm_note(shifted, main))


def _holm_note(shifted: Mapping[str, str], main: Mapping[str, str]) -> str:
    """What the two verdicts' words carry of Holm's correction (the shifted family's size read from
    its row's ``comparisons``, one where the row has none)."""
    if "Holm" not in main["verdict"]:
        return ""
    n = int(shifted.get("comparisons") or 1)
    return (" (The main verdict's words carry Holm's correction over the arm's comparisons; "
            + ("the shifted one is a single comparison.)" if n == 1 else f"the shifted ones over their own {n}.)"))


def shifted_id_in_words(pairs: Sequence[tuple[Mapping[str, str], Mapping[str, str]]], *, described: str) -> str:
    """The shifted ID trajectories' verdicts against the main ones, in words (chapter 7.7): ``pairs``
    of published verdict rows (``07_verdict_shifted.csv``'s ID rows, each with ``07_verdict.csv``'s
    row of the same task), ``described`` the population (:func:`nfarm.study.shifted.describe_id`);
    ``""`` for no pairs."""
    if not pairs:
        return ""
    said = []
    for shifted, main in pairs:
        task = shifted["task"].replace(", shifted population", "")
        said.append(f"{task}: {shifted['anfis']} {shifted['anfis_value']} % ({shifted['anfis_low']}–"
                    f"{shifted['anfis_high']}), {shifted['rival']} {shifted['rival_value']} % ({shifted['rival_low']}–"
                    f"{shifted['rival_high']}), the gap {shifted['gap']} ({shifted['gap_low']} to {shifted['gap_high']}) "
                    f"points: **{shifted['verdict']}**, against {main['gap']} ({main['gap_low']} to {main['gap_high']}), "
                    f"{main['verdict']}, on the test split — "
                    + ("the paired interval on the same side of 0 on both" if _side(shifted) == _side(main) else
                       f"**the paired interval {'holds 0' if _side(shifted) == 0 else 'excludes 0'} on the shifted "
                       f"trajectories, on the test split it {'holds 0' if _side(main) == 0 else 'excludes 0'}**"))
    return (f"**Faster trajectories.** Declared in the study file before they were drawn, {described}: states "
            f"beyond the speeds and accelerations of every trajectory the models were trained, tuned and chosen on. "
            f"By the worst resolved joint's NRMSE against the shifted torques' own spread — " + "; ".join(said) + "."
            + _holm_note(pairs[0][0], pairs[0][1]))


def joint_groups_in_words(groups: Mapping[str, Sequence[bool]], joint_names: Sequence[str], arm: str) -> str:
    """Which of the measured arm's joints the rigid body moves and which the drives' friction moves
    (``groups``: :func:`nfarm.study.measured_test.joint_groups`), in words, and what the measured
    arm's verdict then judges (chapter 7.7).

    Example:
        >>> print(joint_groups_in_words({"rigid-dominated": [False, True], "friction-dominated": [True, False]},
        ...                             ["yaw", "pitch"], "arm"))
        **What moves the joints.** On arm's built arm the rigid body's torque exceeds the drives' (RMS on the validation trajectories, where the groups are fixed) on pitch (rigid-dominated); the drives' torque (their friction and armature) exceeds it on yaw (friction-dominated). The verdict judges the every-tier pair on each group apart: on the rigid-dominated joints what a method learned of the dynamics, on the friction-dominated ones how well it fits the drives' friction.
    """
    named = {g: [j for j, on in zip(joint_names, mask) if on] for g, mask in groups.items()}
    rigid, friction = named.get("rigid-dominated", []), named.get("friction-dominated", [])
    head = f"**What moves the joints.** On {arm}'s built arm "
    if not rigid:
        return (head + f"the drives' torque (their friction and armature) exceeds the rigid body's (RMS on the validation trajectories, where the groups are fixed) "
                f"on every joint "
                f"({', '.join(friction)}): **its measured-arm verdict judges how well each method fits the drives' friction, "
                f"not what it learned of the rigid body's dynamics**.")
    return (head + f"the rigid body's torque exceeds the drives' (RMS on the validation trajectories, where the groups are fixed) on {', '.join(rigid)} "
            f"(rigid-dominated)" + (f"; the drives' torque (their friction and armature) exceeds it on {', '.join(friction)} (friction-dominated)"
                                    if friction else "")
            + ". The verdict judges the every-tier pair on each group apart: on the rigid-dominated joints what a method "
            "learned of the dynamics" + (", on the friction-dominated ones how well it fits the drives' friction." if friction
                                          else "."))
