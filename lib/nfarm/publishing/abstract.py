"""What the index (:mod:`.index`) and the PDF (:mod:`.paper`) both open with: the dissertation
reproduced, what this report can compare with it, the study's question and limits, and each
arm's answers and verdict, read from the tables chapter 7 published (``07_summary.csv``,
``07_paired.csv``, ``07_verdict.csv``, ``07_ik_warm_start.csv``; :mod:`nfarm.study.result_tables`
reads them). Each arm's answers are sentences (:func:`abstract_lines`) whose every number is read
from its summary rows and every comparison from its paired rows; :func:`abstract_pairs` lists the
comparisons they make, which chapter 7 computes (:func:`nfarm.study.paired.paired_rows`). The
verdict's words and the conclusion are :mod:`.conclusion`'s.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

from ..presentation.wording import times
from ..study.result_tables import read_long_table, read_paired, read_verdicts, read_warm_starts, table_number
from .conclusion import reader_label
from .editions import Edition

__all__ = ["DISSERTATION_TITLE", "DISSERTATION_TITLE_EN", "ABSTRACT_FRAMING", "ABSTRACT_QUESTION", "ABSTRACT_LIMITS",
           "ANSWERS_KIND", "abstract_answers", "verdict_rows", "warm_start_rows", "abstract_lines", "abstract_pairs"]


#: The dissertation this study reproduces (``docs/STUDY.md``), its title in Russian and in English.
DISSERTATION_TITLE = ("Модели, алгоритмы и комплекс программ для моделирования манипуляторов на основе "
                      "архитектуры адаптивной нейро-нечеткой системы вывода и обучающих алгоритмов")
DISSERTATION_TITLE_EN = ("Models, algorithms and a software package for modelling manipulators based on "
                         "the architecture of an adaptive neuro-fuzzy inference system and learning "
                         "algorithms")
ABSTRACT_QUESTION = (
    "Can adaptive neuro-fuzzy inference systems (ANFIS), trained with Jang's hybrid rule on data generated "
    "from a 5-DOF arm's models — tool poses from the DH forward kinematics of sampled joint configurations, "
    "torques from recursive Newton–Euler and from a simulated measured arm — compute the arm's inverse "
    "kinematics and inverse dynamics, and how do they compare with the exact solutions (Levenberg–Marquardt, "
    "the closed form, Newton–Euler) and with strong baselines given the same inputs and tuning budget?")
ABSTRACT_LIMITS = (
    "The learned inverse kinematics covers one declared region of each arm, where the inverse map is "
    "single-valued (chapter 5); over the full joint ranges it is many-valued and not learnable as one "
    "function. The data are simulated: the rigid-body torques are exact, and the measured arm is a model — "
    "links off their nominal parameters, friction whose law no learner assumes, torques read from a "
    "simulated motor current — not a real arm. The dissertation's text does not give its robot's numbers, data "
    "settings, rule bases or budgets: those designs are assumed and labelled so (the deviations table of "
    "chapter 5). Comparisons made on validation data are spread over the seeds (draws of the data and of the "
    "initialisation) of every finalist; results on held-out data carry bootstrap intervals over the held-out poses "
    "or trajectories, and the verdict's pool every seed's model, resampled with the held-out units (a two-level "
    "bootstrap).")


#: What this report can and cannot compare with the dissertation: the index and the PDF say it first.
ABSTRACT_FRAMING = (
    "This is a re-implementation of the dissertation's study under stated assumptions, not a replication of its "
    "numbers. The source we have (docs/STUDY.md) is an OCR text of its introduction, its table of contents, the "
    "first part of its chapter 1, its bibliography and fragments of its program's MATLAB code: it names the methods — "
    "a DH model of a 5-DOF arm, Levenberg–Marquardt IK, recursive Newton–Euler ID, ANFIS trained by Jang's hybrid "
    "rule — but holds none of chapters 2–4: no robot parameters, no data settings or training budgets, and no "
    "tables of results. So what can be compared with a published number is the "
    "ANFIS engine itself, on Jang's three benchmarks beside his results (chapter 4); every result for the arms — "
    "the errors, the comparisons with other learners and the verdict below — is this study's own, on assumed arms "
    "and designs labelled \"(assumed)\" where they are ours, and cannot say whether the dissertation's own figures "
    "would be met.")


#: What the abstract's intervals and comparisons are (:func:`abstract_answers`), as the index and the PDF say it.
ANSWERS_KIND = ("on held-out data; a method chapter 6 trained over several seeds pooled over them, with a two-level 95 % "
                "bootstrap interval over the seeds and the test poses or trajectories; a method trained once, or exact, "
                "with its interval over the test units alone, marked so; every comparison on the paired interval of the two methods' "
                "difference on the same poses or trajectories, seed by seed where either has several (a method with one model "
                "beside each of the other's seeds)")


def abstract_answers(figures_dir: Path, arms: list[Edition]) -> list[str]:
    """Each arm's answers, read from its published ``07_summary.csv`` and its comparisons from
    ``07_paired.csv`` (chapter 07's section 7.7: every method pooled over the seeds chapter 06
    trained it on; every number computed by chapter 07; :func:`abstract_lines`):
    what the HTML index and the PDF both print. A table an older chapter 07 wrote (or none of
    its paired differences) gives one line saying so, not a failure."""
    answers = []
    for edition in arms:
        tables = figures_dir / edition.subdir / "tables"
        path, paired = tables / "07_summary.csv", tables / "07_paired.csv"
        if path.is_file():
            try:
                answers += abstract_lines(edition.name, read_long_table(path),
                                          read_paired(paired) if paired.is_file() else [])
            except (ValueError, KeyError) as exc:
                answers.append(f"{edition.name}: no answers ({exc}); rerun chapter 7.")
    return answers


def verdict_rows(figures_dir: Path, arms: list[Edition]) -> list[dict[str, str]]:
    """Every arm's verdict rows, read from its published ``07_verdict.csv`` (chapter 07;
    :func:`nfarm.study.verdict_rows.verdict_table`), in the arms' order; an arm without one, or with
    one :func:`nfarm.study.result_tables.read_table` refuses (empty, or an older chapter 07's), adds
    none."""
    rows = []
    for edition in arms:
        path = figures_dir / edition.subdir / "tables" / "07_verdict.csv"
        if path.is_file():
            try:
                rows += read_verdicts(path)
            except ValueError:
                continue
    return rows


def warm_start_rows(figures_dir: Path, arms: list[Edition]) -> dict[str, list[dict[str, str]]]:
    """Every arm's table of LM from each start (chapter 07's ``07_ik_warm_start.csv``), by the
    arm's name, for :func:`nfarm.publishing.conclusion.conclusion`; an arm without one, or with one
    :func:`nfarm.study.result_tables.read_table` refuses, adds none."""
    out = {}
    for edition in arms:
        path = figures_dir / edition.subdir / "tables" / "07_ik_warm_start.csv"
        if path.is_file():
            try:
                out[edition.name] = read_warm_starts(path)
            except ValueError:
                continue
    return out


# --------------------------------------------------------------------------------------------
# Each arm's answers in sentences, from the published long and paired tables. The study's rows and
# comparisons (nfarm.study.rows, .paired: numpy and the sweeps) are imported where they are used, so
# that the index and the PDF import this module without them.


def _three(text: str) -> str:
    """A table's number (written to four significant digits) to three, as the chapters write
    them; ``< 1e-06`` and empty cells as they are."""
    from ..presentation.tables import shown

    return text if not text or text.startswith("<") else shown(float(text), ".3g")


def _with_interval(row: Mapping[str, str]) -> str:
    """``value unit (low–high)``; an interval over the test units alone (not pooled over seeds:
    :func:`nfarm.study.rows.pooled_rows`) says so."""
    value, low, high = (_three(row[k]) for k in ("value", "ci_low", "ci_high"))
    unit = {"deg": "°", "%": " %", "mm": " mm", "N·m": " N·m"}.get(row["unit"], f" {row['unit']}")
    spread = row.get("spread", "")
    kind = "" if not spread or spread.startswith("two-level") else \
        f", test {'poses' if 'poses' in spread else 'trajectories'} only"
    return f"{value}{unit}" if low == high == value or not (low or high) else f"{value}{unit} ({low}–{high}{kind})"


def _row_text(row) -> Mapping[str, str]:
    """A :class:`~nfarm.study.rows.Row` as the text fields :func:`abstract_lines` reads (a row read
    back from a long table already is)."""
    from ..study.rows import Row

    if isinstance(row, Row):
        return {"task": row.task, "method": row.method, "role": row.role, "metric": row.metric,
                "unit": row.unit, "value": repr(row.value), "ci_low": repr(row.low) if row.n else "",
                "ci_high": repr(row.high) if row.n else "", "n": str(row.n), "spread": row.spread}
    return row


def abstract_pairs(rows) -> list[tuple[str, str, str, str]]:
    """``(task, method, against, metric)`` of every comparison :func:`abstract_lines` makes of
    ``rows`` (:class:`~nfarm.study.rows.Row` objects or a long table's text rows): the paired
    differences a chapter computes for it (:func:`nfarm.study.paired.paired_rows`)."""
    pairs = []

    def record(ours, theirs):
        if "0" not in (ours.get("n"), theirs.get("n")):
            pairs.append((ours["task"], ours["method"], theirs["method"], ours["metric"]))
        return 0
    _abstract("", [_row_text(r) for r in rows], record)
    return list(dict.fromkeys(pairs))


def _times_of(ours: Mapping[str, str], theirs: Mapping[str, str]) -> str:
    """"2.2 times" or "85 % of": ours's value over theirs's, in words
    (:func:`nfarm.presentation.wording.times`)."""
    return times(table_number(ours["value"]) / table_number(theirs["value"]))


_VERDICT = {-1: "better than", 1: "worse than", 0: "not shown to differ from"}


def abstract_lines(arm: str, rows: Sequence[Mapping[str, str]],
                   paired: Sequence[Mapping[str, str]]) -> list[str]:
    """Plain-text sentences (one per task) of one arm's answers, every number read from its
    summary rows: the chosen ANFIS, the dissertation's design (assumed), the best baseline and
    the references; every comparison ("better", "worse", "not shown to differ") on the paired
    interval of the two methods' difference over the same test units (``paired``: the rows of
    :func:`nfarm.study.paired.paired_table`, as text; :func:`abstract_pairs` lists the ones
    needed). Rows are found by their whole role (:data:`nfarm.study.rows.ROLES`)."""
    from ..study.paired import paired_judge

    return _abstract(arm, rows, paired_judge(paired))


def _abstract(arm: str, rows: Sequence[Mapping[str, str]], _compare) -> list[str]:
    """:func:`abstract_lines` with its comparison ``_compare(ours, theirs) -> -1, 0, 1``."""
    from ..study.paired import orientation_by_structure
    from ..study.rows import (ROLE_BEST_BASELINE, ROLE_CHOSEN, ROLE_DESIGN, ROLE_EXACT, ROLE_FRICTION_ID,
                              ROLE_LEARNED_ALONE, ROLE_NUMERICAL, ROLE_PHYSICS, ROLE_RECIPE, ROLE_RESIDUAL_BASELINE,
                              ROLE_SPAN, WORST_ID)

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
                met = [reader_label(r["method"]) for r in judged if r.get("n") != "0" and table_number(r["ci_high"]) <= 5.0]
                best = min((r for r in judged if r["role"] != ROLE_SPAN), key=lambda r: table_number(r["value"]))
                text += (f" The study's ≤ 5 % target on the measured spread, {over}: "
                         + (f"met by {', '.join(met)}." if met else
                            f"met by none (best {reader_label(best['method'])}, {_with_interval(best)})."))
        lines.append(text)
    return lines
