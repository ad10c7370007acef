"""What the index (:mod:`.index`) and the PDF (:mod:`.paper`) both open with: the dissertation
reproduced, what this report can compare with it, the study's question and limits, and each
arm's answers and verdict, read from the tables chapter 7 published (``07_summary.csv``,
``07_paired.csv``, ``07_verdict.csv``, ``07_ik_warm_start.csv``).
"""

from __future__ import annotations

from pathlib import Path

from .editions import Edition

__all__ = ["DISSERTATION_TITLE", "DISSERTATION_TITLE_EN", "ABSTRACT_FRAMING", "ABSTRACT_QUESTION", "ABSTRACT_LIMITS",
           "ANSWERS_KIND", "abstract_answers", "verdict_rows", "warm_start_rows"]


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
    trained it on; every number computed by chapter 07; :func:`nfarm.study.summary.abstract_lines`):
    what the HTML index and the PDF both print. A table an older chapter 07 wrote (or none of
    its paired differences) gives one line saying so, not a failure."""
    from ..study.summary import abstract_lines, read_long_table, read_paired

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
    :func:`nfarm.study.summary.verdict_table`), in the arms' order; an arm without one, or with a
    table an older chapter 07 wrote, adds none."""
    from ..study.summary import read_verdicts

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
    arm's name, for :func:`nfarm.study.summary.conclusion`; an arm without one adds none."""
    from ..study.summary import read_warm_starts

    out = {}
    for edition in arms:
        path = figures_dir / edition.subdir / "tables" / "07_ik_warm_start.csv"
        if path.is_file():
            try:
                out[edition.name] = read_warm_starts(path)
            except ValueError:
                continue
    return out
