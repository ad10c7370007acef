"""The verdict's history: every test split the study has read, and the verdict of each task on it.

The study drew its test split more than once and changed choices after each read
(``docs/STUDY.md``, "the final test set"). A redraw from the same generator does not undo a
choice tuned to the population, so a reader is shown every split's verdict side by side, not only
the last: whether a task's verdict kept its sign is part of the evidence. The table is kept by the
study, not typed: it is read from the repository's own history — each commit that published a
verdict table (``figures/**/tables/07_verdict.csv``), the test split of the study file at that
commit (``test_seed``; none: the development split, drawn from the study's ``seed``), the last
publication of each split — and from the verdict published now (the working tree's). What was
changed after each split is said in ``docs/STUDY.md``; the table names the commit, where
``git log`` shows the rest.
"""

from __future__ import annotations

import csv
import io
import subprocess
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from ..infra.arguments import is_integer
from ..infra.paths import ROOT
from .editions import Edition

__all__ = ["SplitVerdict", "verdict_history", "DEVELOPMENT"]

#: The split's name where the study file has no ``test_seed``: the test set drawn from its ``seed``.
DEVELOPMENT = "development (the study's seed)"
_TABLE = "tables/07_verdict.csv"


@dataclass(frozen=True)
class SplitVerdict:
    """One task's verdict on one arm's test split: the split (``test_seed``, or
    :data:`DEVELOPMENT`), the last commit that published it (``"now"``: the working tree's
    figures), its date, the task, the verdict's words and the gap (ANFIS minus the best other
    method) with its interval and unit."""

    arm: str
    split: str
    commit: str
    date: str
    task: str
    verdict: str
    gap: str
    unit: str


def _git(root: Path, *args: str) -> str | None:
    try:
        run = subprocess.run(["git", *args], cwd=root, capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return None
    return run.stdout if run.returncode == 0 else None


def _split(study_text: str | None) -> str:
    """The ``test_seed`` a study file's text declares, or :data:`DEVELOPMENT`."""
    import yaml

    try:
        data = yaml.safe_load(study_text or "")
    except yaml.YAMLError:
        return DEVELOPMENT
    seed = data.get("test_seed") if isinstance(data, dict) else None
    return str(seed) if is_integer(seed, numpy=False) else DEVELOPMENT


def _rows(text: str, arm: str, split: str, commit: str, date: str) -> list[SplitVerdict]:
    out = []
    for row in csv.DictReader(io.StringIO(text)):
        if not row.get("task") or not row.get("verdict"):
            continue
        gap = row.get("gap", "")
        if row.get("gap_low") and row.get("gap_high"):
            gap += f" ({row['gap_low']} to {row['gap_high']})"
        out.append(SplitVerdict(row.get("arm") or arm, split, commit, date, row["task"], row["verdict"], gap,
                                row.get("unit", "")))
    return out


def verdict_history(arms: Sequence[Edition], figures_dir: Path | None = None,
                    root: Path = ROOT) -> list[SplitVerdict]:
    """Every test split's verdict rows of each of ``arms`` (in order), oldest split first: the
    last commit that published the arm's verdict on each split, then the verdict published in
    the working tree (``figures_dir``, default ``figures/``) as ``"now"``, which replaces its
    split's last commit where the two are one split. A checkout without git history gives the
    working tree's alone."""
    figures_dir = Path(figures_dir) if figures_dir is not None else root / "figures"
    out: list[SplitVerdict] = []
    for edition in arms:
        table = (Path("figures") / edition.subdir / _TABLE).as_posix()
        study_file = Path(edition.study_file).as_posix()
        last: dict[str, list[SplitVerdict]] = {}
        for line in (_git(root, "log", "--reverse", "--format=%h %cs", "--", table) or "").splitlines():
            commit, _, date = line.partition(" ")
            text = _git(root, "show", f"{commit}:{table}")
            if text is None:
                continue
            split = _split(_git(root, "show", f"{commit}:{study_file}"))
            last.pop(split, None)                      # a later publication of the split replaces it, in order
            last[split] = _rows(text, edition.name, split, commit, date)
        current = figures_dir / edition.subdir / _TABLE
        if current.is_file():
            study = root / study_file
            split = _split(study.read_text(encoding="utf-8") if study.is_file() else None)
            last.pop(split, None)
            last[split] = _rows(current.read_text(encoding="utf-8"), edition.name, split, "now", "")
        for rows in last.values():
            out += rows
    return out
