"""Tables of the study: saved as CSV (for machines) and Markdown (for people), shown in
notebooks, byte-reproducible; numbers at the level of floating-point noise shown as such
(:func:`shown`); a part of a project document shown from its one source
(:func:`markdown_section`).

**Measurements** (seconds): a column whose name ends in :data:`MEASURED` (:func:`measured`) holds
values that depend on the machine and its load. A published table keeps the measurements of the
build that first published it for as long as every other cell comes out the same
(:func:`keep_measurements`, applied when a chapter is published), so that a build which reproduces
the results reproduces the published files byte for byte, and the seconds published are those
measured when the results were computed (delete the published table to publish a new build's).
"""

from __future__ import annotations

import csv
import io
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..infra.paths import atomic_path, shown_path
from .numbering import anchor, number

__all__ = ["Table", "shown", "markdown_section", "DOCUMENTS", "MEASURED", "measured", "keep_measurements"]

#: How the name of a column of measurements ends (module docstring).
MEASURED = "(measured)"


_NEGATIVE_ZERO = re.compile(r"^-(0(\.0*)?(e[+-]?0+)?)$")


def _cell(value, floatfmt: str) -> str:
    if isinstance(value, (float, np.floating)):
        text = format(float(value), floatfmt)
        return _NEGATIVE_ZERO.sub(r"\1", text)  # -1e-17 shown as 0.0000, not -0.0000
    if isinstance(value, (np.integer, np.bool_)):
        return str(value.item())
    return str(value)


def shown(value: float, fmt: str = ".3g", *, floor: float = 1e-15) -> str:
    """A number for people: ``format(value, fmt)``, or ``"< 1e-15"`` when it is at the level of
    floating-point noise (|value| below ``floor``), which is not data. A general format (``g``)
    writes thousands up to a million as plain digits, rounded to its precision ("14100", not
    "1.41e+04"), which a machine still reads as a number.

    >>> shown(14_123.4), shown(0.000123), shown(2.5e7), shown(1e-17)
    ('14100', '0.000123', '2.5e+07', '< 1e-15')
    """
    value = float(value)
    if not np.isfinite(value) or value == 0:
        return str(value) if value else "0"
    if abs(value) < floor:
        return f"< {floor:.0e}".replace("e-0", "e-")
    text = format(value, fmt)
    if fmt.endswith("g") and "e+" in text and 1e3 <= abs(float(text)) < 1e6:
        text = f"{float(text):.0f}"
    return _NEGATIVE_ZERO.sub(r"\1", text)


@dataclass
class Table:
    """A small table saved as CSV (for machines) and Markdown (for people), shown in notebooks.

    Floats are written with ``floatfmt`` (one format, or one per column) so the files are
    byte-reproducible.
    """

    columns: Sequence[str]
    rows: Sequence[Sequence]
    floatfmt: str | Sequence[str] = ".6g"
    caption: str = ""
    _text: list[list[str]] = field(init=False, repr=False)
    _name: str = field(init=False, repr=False, compare=False, default="")     # the name it is saved under

    def __post_init__(self):
        for k, row in enumerate(self.rows):
            if len(row) != len(self.columns):
                raise ValueError(f"table row {k} has {len(row)} cells, expected "
                                 f"{len(self.columns)} ({', '.join(self.columns)})")
        formats = [self.floatfmt] * len(self.columns) if isinstance(self.floatfmt, str) \
            else list(self.floatfmt)
        if len(formats) != len(self.columns):
            raise ValueError(f"floatfmt has {len(formats)} formats for {len(self.columns)} columns")
        self._text = [[_cell(v, f) for v, f in zip(row, formats)] for row in self.rows]

    def to_csv(self) -> str:
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(self.columns)
        writer.writerows(self._text)
        return buffer.getvalue()

    def _lines(self) -> list[str]:
        escape = lambda s: s.replace("|", "\\|")  # noqa: E731
        lines = ["| " + " | ".join(map(escape, self.columns)) + " |",
                 "|" + "|".join("---" for _ in self.columns) + "|"]
        return lines + ["| " + " | ".join(map(escape, row)) + " |" for row in self._text]

    def to_markdown(self) -> str:
        lines = self._lines()
        if self.caption:
            lines = [f"*{self.caption}*", ""] + lines
        return "\n".join(lines) + "\n"

    def _repr_markdown_(self) -> str:
        """The table as a chapter shows it: a saved table with a caption is numbered in its chapter
        (**Table 6.2.**, :mod:`nfarm.presentation.numbering`) under an anchor of its name, which
        citations link to; any other as :meth:`to_markdown` writes it."""
        found = number("Table", self._name) if self._name and self.caption else None
        if not found:
            return self.to_markdown()
        return "\n".join([f'<a id="{anchor("Table", self._name)}"></a>', "", f"**Table {found}.** *{self.caption}*", "",
                          *self._lines()]) + "\n"

    def save(self, out_dir: str | os.PathLike, name: str) -> "Table":
        """Write ``out_dir/tables/name.csv`` and ``.md`` atomically; return ``self`` (for display,
        numbered under ``name``)."""
        for suffix, text in ((".csv", self.to_csv()), (".md", self.to_markdown())):
            with atomic_path(Path(out_dir) / "tables" / f"{name}{suffix}") as tmp:
                tmp.write_text(text, encoding="utf-8")
        self._name = name
        return self


def measured(name: str) -> str:
    """The name of a column of measurements (module docstring): ``measured("training [s]")`` is
    ``"training [s] (measured)"``."""
    return f"{name} {MEASURED}"


def _csv_rows(text: str) -> list[list[str]]:
    return list(csv.reader(io.StringIO(text)))


def keep_measurements(csv_text: str, markdown: str, published_csv: str) -> tuple[str, str] | None:
    """A table's CSV and Markdown (``csv_text``, ``markdown``, as :meth:`Table.save` writes them) with
    the cells of its measured columns (:data:`MEASURED`) taken from the ``published_csv`` of the same
    table, row by row — each row matched to the published row whose every other cell is the same,
    in this build's order —, or ``None`` when the two tables differ in anything else (their columns,
    a row without its published twin) or the table has no measured column. The Markdown keeps this
    build's caption.

    Example:
        >>> old = Table(["learner", measured("training [s]")], [["MLP", 12.0], ["RBF", 0.5]], floatfmt=".3g", caption="Old")
        >>> new = Table(["learner", measured("training [s]")], [["RBF", 0.6], ["MLP", 13.5]], floatfmt=".3g", caption="New")
        >>> kept = keep_measurements(new.to_csv(), new.to_markdown(), old.to_csv())
        >>> kept[0].splitlines()[1:], kept[1].splitlines()[0], kept[1].splitlines()[-1]
        (['RBF,0.5', 'MLP,12'], '*New*', '| MLP | 12 |')
        >>> other = Table(["learner", measured("training [s]")], [["RBF", 0.6], ["kNN", 13.5]], floatfmt=".3g")
        >>> keep_measurements(other.to_csv(), other.to_markdown(), old.to_csv()) is None
        True
    """
    new, old = _csv_rows(csv_text), _csv_rows(published_csv)
    if not new or not old or new[0] != old[0] or len(new) != len(old):
        return None
    columns = new[0]
    kept = [k for k, name in enumerate(columns) if name.endswith(MEASURED)]
    if not kept or any(len(row) != len(columns) for row in (*new, *old)):
        return None

    def rest(row):
        return tuple(cell for k, cell in enumerate(row) if k not in kept)

    published: dict[tuple, list[list[str]]] = {}
    for row in old[1:]:
        published.setdefault(rest(row), []).append(row)
    rows = []
    for row in new[1:]:
        twins = published.get(rest(row))
        if not twins:
            return None
        rows.append(twins.pop(0))
    table_lines = Table(columns, new[1:])._lines()
    lines = markdown.splitlines()
    if table_lines[0] not in lines or lines[lines.index(table_lines[0]):] != table_lines:
        return None            # not the Markdown this table's own rows make
    merged = Table(columns, rows)
    return merged.to_csv(), "\n".join([*lines[:lines.index(table_lines[0])], *merged._lines()]) + "\n"


DOCUMENTS = ("docs/STUDY.md",)   # project documents a chapter shows a part of (in every chapter's key)


def markdown_section(path: str | os.PathLike, heading: str) -> str:
    """The text of the section ``## heading`` of a Markdown file (up to the next heading of
    the same or a higher level, without the heading line): a chapter shows a document's table
    from its one source instead of a copy."""
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise ValueError(f"{shown_path(path)}: cannot read it ({exc.strerror})") from None
    starts = [k for k, line in enumerate(lines) if line.strip() == f"## {heading}"]
    if len(starts) != 1:
        raise ValueError(f"{shown_path(path)}: heading '## {heading}': expected once, found {len(starts)} times")
    body = []
    for line in lines[starts[0] + 1:]:
        if re.match(r"#{1,2} ", line):
            break
        body.append(line)
    return "\n".join(body).strip() + "\n"
