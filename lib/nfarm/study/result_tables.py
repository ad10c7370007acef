"""The study's published result tables as files (chapters 07 and 08, the abstract, the index and
the PDF read them): their columns, the long tables' precision (:data:`DIGITS`) and each unit's
floor of rounding (:data:`SUMMARY_FLOORS`), and reading them back.

Every table is read by :func:`read_table`, with one rule: a file that is empty, holds only its
header, or lacks any of the table's columns is refused with a one-line ``ValueError`` naming the
file — a table a chapter wrote always has rows, so an empty one is a run that went wrong, not a
result. :func:`read_long_table` (``07_summary.csv``), :func:`read_paired` (``07_paired.csv``),
:func:`read_verdicts` (``07_verdict.csv``) and :func:`read_warm_starts`
(``07_ik_warm_start.csv``) are that reader with each table's columns.

Example:
    >>> import tempfile
    >>> from pathlib import Path
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = Path(tmp) / "07_paired.csv"
    ...     _ = path.write_text("task,method,against,metric,ci_low,ci_high\\n", encoding="utf-8")
    ...     try:
    ...         read_paired(path)
    ...     except ValueError as exc:
    ...         print(str(exc).replace(str(path), "07_paired.csv"))
    07_paired.csv: a paired table without a row
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Sequence

__all__ = ["DIGITS", "SUMMARY_FLOORS", "LONG_COLUMNS", "PAIRED_COLUMNS", "VERDICT_COLUMNS", "WARM_START_COLUMNS",
           "read_table", "read_long_table", "read_paired", "read_verdicts", "read_warm_starts", "table_number"]

#: The long tables' precision (:func:`nfarm.study.rows.long_table`): what every page that quotes a row reads.
DIGITS = ".4g"

#: Each unit's level of rounding in the summary tables (chapters 07 and 08): a value below it is
#: written as such (``< 1e-06``), not as data — LM's tolerances and a float's rounding in degrees
#: and millimetres, an NRMSE [%] at rounding level, a torque error [N·m] on a spread of about 1 N·m.
SUMMARY_FLOORS = {"deg": 1e-6, "mm": 1e-6, "%": 1e-6, "N·m": 1e-8}

#: The columns a long table (:func:`nfarm.study.rows.long_table`, ``07_summary.csv``) is read by.
LONG_COLUMNS = ("task", "method", "role", "metric", "unit", "value", "ci_low", "ci_high")
#: The columns a paired table (:func:`nfarm.study.paired.paired_table`, ``07_paired.csv``) is read by.
PAIRED_COLUMNS = ("task", "method", "against", "metric", "ci_low", "ci_high")
#: The verdict table's columns (:func:`nfarm.study.verdict_rows.verdict_table`), as chapter 07 writes them and the
#: index reads them.
VERDICT_COLUMNS = ("arm", "task", "metric", "unit", "best", "best_value", "anfis", "anfis_value", "anfis_low",
                   "anfis_high", "rank", "compared", "rival", "rival_value", "rival_low", "rival_high", "gap", "gap_low",
                   "gap_high", "interval", "verdict", "anfis_targets", "rival_targets", "exact", "p", "holm_p",
                   "comparisons")
#: The columns of chapter 7's table of Levenberg–Marquardt from each start (``07_ik_warm_start.csv``).
WARM_START_COLUMNS = ("start", "targets", "mean iterations")


def read_table(path, columns: Sequence[str], what: str) -> list[dict[str, str]]:
    """The rows of a published CSV table as dicts of its columns' text. A file that is empty,
    holds only its header, or lacks any of ``columns`` is refused with a one-line ``ValueError``
    naming it and saying it is not ``what`` (``"a summary table"``); the missing columns are
    named in the order of ``columns``."""
    path = Path(path)
    with path.open(encoding="utf-8", newline="") as f:
        reader = csv.DictReader(f)
        header, rows = reader.fieldnames or [], list(reader)
    if not header:
        raise ValueError(f"{path}: empty, not {what}")
    missing = [c for c in columns if c not in header]
    if missing:
        raise ValueError(f"{path}: not {what}: columns {', '.join(missing)} missing")
    if not rows:
        raise ValueError(f"{path}: {what} without a row")
    return rows


def read_long_table(path) -> list[dict[str, str]]:
    """The rows of a long table written by :func:`nfarm.study.rows.long_table` (``07_summary.csv``),
    as dicts of its columns' text (:func:`read_table`'s rule)."""
    return read_table(path, LONG_COLUMNS, "a summary table")


def read_paired(path) -> list[dict[str, str]]:
    """The rows of a paired table (:func:`nfarm.study.paired.paired_table`, ``07_paired.csv``) as
    dicts of their columns' text (:func:`read_table`'s rule)."""
    return read_table(path, PAIRED_COLUMNS, "a paired table")


def read_verdicts(path) -> list[dict[str, str]]:
    """The rows of a verdict table written by :func:`nfarm.study.verdict_rows.verdict_table`
    (``07_verdict.csv``), as dicts of its columns' text (:func:`read_table`'s rule)."""
    return read_table(path, VERDICT_COLUMNS, "a verdict table")


def read_warm_starts(path) -> list[dict[str, str]]:
    """The rows of chapter 7's table of LM from each start (``07_ik_warm_start.csv``), as dicts of
    its columns' text (:func:`read_table`'s rule)."""
    return read_table(path, WARM_START_COLUMNS, "a table of LM's starts")


def table_number(text: str) -> float:
    """A table's value as a number; ``< 1e-06`` (below a floor) as 0."""
    return 0.0 if text.startswith("<") else float(text)
