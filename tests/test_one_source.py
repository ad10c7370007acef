"""One source for every number (issue 43): a quantity the published tables label alike has one
value wherever it appears — in each edition's chapter tables and in chapter 8's comparison of the
arms — and the quantities two chapters compute by two names agree where they are the same
measurement (chapter 2's LM success and chapter 8's, on the same targets)."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import pytest

from nfarm.infra.paths import FIGURES
from nfarm.publishing.editions import editions


def _rows(path: Path) -> tuple[list[str], list[list[str]]]:
    with path.open(encoding="utf-8", newline="") as f:
        table = list(csv.reader(f))
    return table[0], table[1:]


def labelled_quantities(figures: Path, arms_present=None) -> dict[tuple[str, str], dict[str, str]]:
    """``(arm, label) → {file: value}`` of every published table whose first column is
    ``quantity``: a two-column table (``quantity, value``) holds its edition's arm; a wider one
    (chapter 8's) one column per arm, named after it."""
    found: dict[tuple[str, str], dict[str, str]] = {}
    arms_present = editions() if arms_present is None else arms_present
    for edition in arms_present:
        where = figures / edition.subdir / "tables"
        for path in sorted(where.glob("*.csv")):
            header, rows = _rows(path)
            if not header or header[0] != "quantity":
                continue
            arms = [edition.name] if header[1:] == ["value"] else header[1:]
            if header[1:] != ["value"] and not set(arms) <= {e.name for e in arms_present}:
                continue                  # a check table (configurations, differences): not a quantity per arm
            for row in rows:
                for arm, value in zip(arms, row[1:]):
                    found.setdefault((arm, row[0]), {})[str(path.relative_to(figures))] = value
    return found


def test_a_labelled_quantity_has_one_value_in_every_published_table():
    found = labelled_quantities(FIGURES)
    assert found, "no quantity tables published"
    differing = {key: values for key, values in found.items() if len(set(values.values())) > 1}
    assert not differing, f"the same quantity with two values: {differing}"


def _number(text: str) -> float:
    match = re.fullmatch(r"\s*([-+]?\d+(?:\.\d+)?)\s*%?\s*", text)
    if match is None:
        raise ValueError(f"not a number: {text!r}")
    return float(match.group(1))


@pytest.mark.parametrize("edition", editions(), ids=lambda e: e.name)
def test_lm_success_is_chapter_2s_wherever_it_is_quoted(edition):
    """Chapter 8 solves chapter 2's targets (the same count and seed): the same success."""
    header, rows = _rows(FIGURES / edition.subdir / "tables" / "02_methods.csv")
    lm = next(r for r in rows if r[0].startswith("LM (Sugihara)"))
    chapter_2 = _number(lm[header.index("success")])
    arms_header, arms_rows = _rows(FIGURES / "tables" / "08_arms.csv")
    if edition.name not in arms_header:
        pytest.skip(f"chapter 8 does not compare {edition.name}")
    quoted = next(r for r in arms_rows if r[0].startswith("LM success on random reachable targets"))
    assert _number(quoted[arms_header.index(edition.name)]) == pytest.approx(chapter_2, abs=0.005)


def test_the_check_finds_a_quantity_with_two_values(tmp_path):
    """The check can fail: a reach of 0.546 m in chapter 1 and 0.531 m in chapter 8."""
    arm = editions()[0]
    tables = tmp_path / arm.subdir / "tables"
    tables.mkdir(parents=True)
    (tables / "01_extent.csv").write_text("quantity,value\nreach [m],0.546\n", encoding="utf-8")
    (tables / "08_arms.csv").write_text(f"quantity,{arm.name}\nreach [m],0.531\n", encoding="utf-8")
    found = {k: v for k, v in labelled_quantities(tmp_path, [arm]).items() if len(set(v.values())) > 1}
    assert list(found) == [(arm.name, "reach [m]")]
