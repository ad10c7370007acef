"""The verdict in a reader's words (the index, the PDF and chapter 8): each method's name as a
reader knows it (:func:`reader_label`), the verdict table's cells as they show them
(:data:`VERDICT_HEAD`, :func:`verdict_display`), and the conclusion drawn from every arm's verdict
rows (:func:`conclusion`, with what the ANFIS gives the exact solver, :func:`contribution`), read
from the tables chapter 7 published (``07_verdict.csv``, ``07_ik_warm_start.csv``;
:mod:`nfarm.study.result_tables`).
"""

from __future__ import annotations

import re
from typing import Mapping, Sequence

__all__ = ["reader_label", "VERDICT_HEAD", "verdict_display", "WARM_HOME", "WARM_ANFIS", "WARM_CLOSED",
           "contribution", "conclusion"]


#: Configuration words a reader knows, and the learners' names in words (:func:`reader_label`).
_CONFIG_WORDS = {"arm_plane": "in the arm's plane", "quat_xyz": "on quaternion and position",
                 "axes_xyz": "on position and two tool axes", "basis=chain": "on the chain's trigonometric basis",
                 "basis=generic": "on the generic basis",
                 "basis=chain_drives": "on the chain's trigonometric basis and the joints' friction terms",
                 "basis=generic_drives": "on the generic basis and the joints' friction terms"}
_LEARNER_WORDS = {"ridge": "ridge regression", "ANFIS, chosen": "ANFIS"}
#: Internal names of input sets and of where a model came from: in the tables, not in prose.
_INTERNAL = {"contest", "affine", "affine_generic", "affine_drives", "affine_generic_drives", "own", "regressor",
             "regressor_drives"}


def reader_label(name: str) -> str:
    """A method's name in words a reader knows, its internal configuration (kept in the tables)
    left out: a trailing parenthesis of options (``basis=chain, alpha=1e-06``), an encoding's or an
    input set's code name, or ``contest``; the configuration words a reader knows are kept.

    Example:
        >>> reader_label("ridge (basis=chain, alpha=1e-06)"), reader_label("ANFIS, chosen (arm_plane)")
        ("ridge regression on the chain's trigonometric basis", "ANFIS in the arm's plane")
        >>> reader_label("RBF interpolation (contest)"), reader_label("generic: multilayer perceptron")
        ('RBF interpolation', 'generic: multilayer perceptron')
    """
    match = re.fullmatch(r"(.*?) \(([^()]*)\)", name)
    if match is None:
        return name
    parts = [part.strip() for part in match[2].split(",")]
    if not all("=" in part or part in _CONFIG_WORDS or part in _INTERNAL for part in parts):
        return name                      # a parenthesis a reader needs ("assumed", "needs the geometry")
    return " ".join([_LEARNER_WORDS.get(match[1], match[1]), *(_CONFIG_WORDS[p] for p in parts if p in _CONFIG_WORDS)])


#: The verdict as a reader sees it (:func:`verdict_display`): the index, the PDF and chapter 8 show these columns.
VERDICT_HEAD = ("task", "arm", "best on held-out data", "ANFIS's best (rank)", "best other",
                "ANFIS − best other (paired interval)", "verdict", "targets met: ANFIS / best other", "interval")


def verdict_display(rows: Sequence[Mapping[str, str]]) -> list[list[str]]:
    """The verdict rows (:func:`nfarm.study.result_tables.read_verdicts`) as the cells of
    :data:`VERDICT_HEAD`: each method's value with its interval and unit, the ANFIS's rank among
    the methods compared, the paired gap, the targets met and what the intervals resampled."""
    def with_interval(r, who):
        value, low, high = r[f"{who}_value"], r[f"{who}_low"], r[f"{who}_high"]
        # an interval where there is one: not around a value at rounding level ("< 1e-6"), nor a missing one
        spread = low and low != "nan" and low != high and not value.startswith("<")
        return f"{reader_label(r[who])}, {value}" + (f" ({low}–{high})" if spread else "") + f" {r['unit']}"
    return [[r["task"], r["arm"], f"{reader_label(r['best'])}, {r['best_value']} {r['unit']}",
             f"{with_interval(r, 'anfis')} ({r['rank']} of {r['compared']})", with_interval(r, "rival"),
             f"{r['gap']} ({r['gap_low']} to {r['gap_high']}) {r['unit']}",
             r["verdict"] + (f" (Holm p {r['holm_p']}, {r['comparisons']} comparisons)"
                             if r.get("holm_p") and not r["verdict"].endswith("(Holm)") else ""),
             f"{r['anfis_targets'] or '—'} / {r['rival_targets'] or '—'}", r["interval"]] for r in rows]


#: The names of the starts the conclusion compares, as the rows of chapter 7's table of LM from each
#: start (``07_ik_warm_start.csv``) name them (the rival's is "<rival> prediction").
WARM_HOME, WARM_ANFIS, WARM_CLOSED = "home (the dissertation's)", "ANFIS prediction", "closed form (the region's solution)"


def contribution(warm_starts: Mapping[str, Sequence[Mapping[str, str]]]) -> str | None:
    """One sentence on what the ANFIS gives the exact solver, as measured: Levenberg–Marquardt's
    mean (and largest) iterations from the ANFIS's prediction, from the home pose and from the
    best rival's prediction, per arm (``warm_starts``: arm -> the rows of
    :func:`nfarm.study.result_tables.read_warm_starts`), the numbers side by side and no comparison
    the table's means cannot carry; ``None`` without an arm that measured both the ANFIS's start and
    the home pose's."""
    said, closed = [], False
    for arm, rows in warm_starts.items():
        by = {r["start"]: r for r in rows}
        rivals = [s for s in by if s.endswith(" prediction") and s != WARM_ANFIS]
        if WARM_ANFIS not in by or WARM_HOME not in by:
            continue
        closed = closed or WARM_CLOSED in by

        def iterations(start: str) -> str:
            most = by[start].get("max iterations", "")
            return by[start]["mean iterations"] + (f" (at most {most})" if most else "")
        rival = "".join(f" and {iterations(s)} from the prediction of "
                        f"{reader_label(s[:-len(' prediction')].replace(' (contest)', ''))}" for s in rivals[:1])
        said.append(f"{iterations(WARM_ANFIS)}{' iterations' if not said else ''} against {iterations(WARM_HOME)} "
                    f"from the home pose{rival} ({arm})")
    if not said:
        return None
    return ("What the ANFIS gives the exact solver, as measured: started from its prediction, Levenberg–Marquardt "
            "needs on average " + "; ".join(said)
            + ("; from the closed form's solution, none" if closed else "")
            + "; whether such a start saves seconds depends on what the prediction costs, which chapter 7 times on "
              "the reader's machine.")


def conclusion(verdicts: Sequence[Mapping[str, str]],
               warm_starts: Mapping[str, Sequence[Mapping[str, str]]] | None = None) -> list[str]:
    """At most five plain sentences from the verdict rows of every arm
    (:data:`nfarm.study.result_tables.VERDICT_COLUMNS`, as read back from the published tables):
    where the ANFIS wins beyond the paired interval, where another method wins and which (each by
    its paired gap, in the metric's unit) and where no difference is shown, what the ANFIS gives beside the winners (:func:`contribution`, from
    ``warm_starts``, arm -> chapter 7's table of LM's starts), the study's targets the ANFIS
    meets, and what to use for each task. A task ending in "every tier" sums up the tasks of its
    tiers: it gives the targets and what to use, the tiers the wins and losses."""
    from ..study.verdict_rows import NO_DIFFERENCE

    def plain(task: str, name: str) -> str:          # "generic: multilayer perceptron" in "…, generic": the learner
        tier, name = task.rsplit(", ", 1)[-1], reader_label(name)
        return name.split(": ", 1)[1] if name.startswith(tier + ": ") else name

    summed = [r for r in verdicts if r["task"].endswith("every tier")]
    judged = [r for r in verdicts if r not in summed]
    tasks = list(dict.fromkeys(r["task"] for r in judged))

    def grouped(kind: str, say) -> list[str]:
        out = []
        for task in tasks:
            rows = [r for r in judged if r["task"] == task and r["verdict"] == kind]
            if rows:
                out.append(f"{task} ({'; '.join(say(r) for r in rows)})")
        return out

    def gap_unit(r: Mapping[str, str]) -> str:       # a gap of two shares: not "% of" one
        return "percentage points" if r["unit"] == "%" else r["unit"]

    def by(r: Mapping[str, str]) -> str:             # the paired gap's size, in the metric's unit
        gap = r.get("gap", "")
        if not gap or gap.startswith("<"):
            return ""
        return f", by {gap.lstrip('-')} {gap_unit(r)} of {r['metric']}"

    sentences = []
    won = grouped("ANFIS better", lambda r: r["arm"] + by(r))
    lost = grouped("rival better", lambda r: f"{r['arm']}: {plain(r['task'], r['rival'])}{by(r)}")
    tied = [t for kind in (NO_DIFFERENCE, f"{NO_DIFFERENCE} (Holm)")
            for t in grouped(kind, lambda r: f"{r['arm']}: {plain(r['task'], r['rival'])}, "
                                             f"{r['gap']} ({r['gap_low']} to {r['gap_high']}) {gap_unit(r)}")]
    if won:
        sentences.append("ANFIS is better than every other method it was compared with, beyond the paired interval, on "
                         + "; ".join(won) + ".")
    if lost or tied:                                 # one sentence: five at most
        sentences.append("; and ".join(
            ([f"Another method is better than ANFIS, beyond the paired interval, on {'; '.join(lost)}"] if lost else [])
            + ([f"no difference between ANFIS and its best rival is shown (the paired interval, or Holm's "
                f"correction for the arm's comparisons) on {'; '.join(tied)}"] if tied else [])) + ".")
    gives = contribution(warm_starts or {})
    if gives:
        sentences.append(gives)
    headline = [r for r in verdicts if r["anfis_targets"] and (r in summed or not r["task"].startswith("measured arm"))]
    if headline:
        sentences.append("The study's targets the ANFIS meets on the whole interval: " + "; ".join(
            f"{r['task'].replace(', every tier', '')} ({r['arm']}) {r['anfis_targets']}" for r in headline) + ".")
    use = []
    for task in [t for t in tasks if not t.startswith("measured arm")] + list(dict.fromkeys(r["task"] for r in summed)):
        rows = [r for r in verdicts if r["task"] == task]
        # on a tie, no method is recommended over the other: both are named
        best = " or ".join(dict.fromkeys(name for r in rows for name in (
            [reader_label(r["best"])] if not r["verdict"].startswith(NO_DIFFERENCE) else
            [reader_label(r["anfis"]), reader_label(r["rival"])])))
        if any(r["verdict"].startswith(NO_DIFFERENCE) for r in rows):
            best += " (no difference shown)"
        exact = " or ".join(dict.fromkeys(r["exact"] for r in rows if r.get("exact")))
        name = task.replace(", every tier", "")
        use.append(f"{name}, {exact} (exact; of the learned methods, {best})" if exact else f"{name}, {best}")
    sentences.append("What to use, by the held-out data: " + "; ".join(use) + ".")
    return sentences
