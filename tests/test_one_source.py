"""One source for every number (issue 43): a quantity the published tables label alike has one
value wherever it appears — in each edition's chapter tables and in chapter 8's comparison of the
arms; a method's result on held-out data (task, method, metric) reads the same in chapter 7's
summary, in chapter 8's and in the verdict — and the quantities two chapters compute by two names
agree where they are the same measurement (chapter 2's LM success and chapter 8's, on the same
targets). The smoke run of chapters 07 and 08 is checked the same way (tests/test_notebooks.py)."""

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


def _summary_task(verdict_task: str) -> str | None:
    """A verdict's task (chapter 7's ``07_verdict``) as the summary tables name it; ``None`` for a
    verdict on a group of joints (``"measured arm, every tier, rigid-dominated joints"``), whose worst
    NRMSE is over those joints only: no summary row states it, the verdict table is its one source."""
    if verdict_task.endswith(" joints"):
        return None
    if verdict_task.startswith("measured arm"):
        return "ID, measured arm"
    return "inverse dynamics" if verdict_task == "rigid-body inverse dynamics" else verdict_task


def results_disagreeing(summaries: dict[str, Path], learned: Path | None = None,
                        verdicts: dict[str, Path] | None = None) -> dict[tuple, dict[str, str]]:
    """``(arm, task, method, metric) → {source: value}`` of every method's result on held-out data
    that two sources state differently: each arm's chapter 7 summary (``summaries``, arm → its
    ``07_summary.csv``), chapter 8's long table (``learned``, ``08_learned.csv``, one column of
    arms) and each arm's verdict (``verdicts``, arm → its ``07_verdict.csv``: the ANFIS's and the
    best other method's values, written to three digits, against the summary's read to three); a
    verdict or chapter 8 row that no summary holds is reported too (a number without its table)."""
    from nfarm.presentation.tables import shown
    from nfarm.study.result_tables import read_long_table, read_verdicts

    found: dict[tuple, dict[str, str]] = {}
    summary = {}
    for arm, path in summaries.items():
        for r in read_long_table(path):
            key = (arm, r["task"], r["method"], r["metric"])
            summary[key] = r["value"]
            found.setdefault(key, {})[path.name] = r["value"]
    if learned is not None:
        for r in read_long_table(learned):
            key = (r["arm"], r["task"], r["method"], r["metric"])
            found.setdefault(key, {"summary": "(none)"} if key not in summary else {})[learned.name] = r["value"]
    for arm, path in (verdicts or {}).items():
        for v in read_verdicts(path):
            if _summary_task(v["task"]) is None:
                continue
            for method, value in ((v["anfis"], v["anfis_value"]), (v["rival"], v["rival_value"])):
                key = (arm, _summary_task(v["task"]), method, v["metric"])
                written = summary.get(key)
                three = "(none)" if written is None else written if written.startswith("<") else shown(float(written), ".3g")
                if three != value:
                    found.setdefault(key, {}).update({"summary, to three digits": three, path.name: value})
    return {key: values for key, values in found.items() if len(set(values.values())) > 1}


def test_a_method_s_result_reads_the_same_in_chapter_7_chapter_8_and_the_verdict():
    arms = [e for e in editions() if (FIGURES / e.subdir / "tables" / "07_summary.csv").is_file()]
    assert arms, "no summary published"
    differing = results_disagreeing({e.name: FIGURES / e.subdir / "tables" / "07_summary.csv" for e in arms},
                                    FIGURES / "tables" / "08_learned.csv",
                                    {e.name: FIGURES / e.subdir / "tables" / "07_verdict.csv" for e in arms})
    assert not differing, f"a result stated twice, differently: {differing}"


def test_the_check_finds_a_result_that_two_chapters_state_differently(tmp_path):
    """The check can fail: chapter 8 quoting a seed-0 value (0.90 mm) where chapter 7's pooled one is 0.9355, and a
    verdict rounding the full value (0.936) where the summary's four digits read 0.935."""
    head = "task,method,role,metric,unit,value,ci_low,ci_high,n,level,spread\n"
    row = "inverse kinematics,ANFIS,learned (chosen),position p95,mm,{v},0.9,0.97,2000,0.95,pooled\n"
    (tmp_path / "07_summary.csv").write_text(head + row.format(v="0.9355"), encoding="utf-8")
    (tmp_path / "08_learned.csv").write_text("arm," + head + "a," + row.format(v="0.9001"), encoding="utf-8")
    from nfarm.study.result_tables import VERDICT_COLUMNS
    values = {c: "" for c in VERDICT_COLUMNS} | {"arm": "a", "task": "inverse kinematics", "metric": "position p95",
                                                 "anfis": "ANFIS", "anfis_value": "0.936", "rival": "RBF", "rival_value": "3.97"}
    (tmp_path / "07_verdict.csv").write_text(",".join(VERDICT_COLUMNS) + "\n" + ",".join(values[c] for c in VERDICT_COLUMNS)
                                             + "\n", encoding="utf-8")
    differing = results_disagreeing({"a": tmp_path / "07_summary.csv"}, tmp_path / "08_learned.csv",
                                    {"a": tmp_path / "07_verdict.csv"})
    stated = differing[("a", "inverse kinematics", "ANFIS", "position p95")]
    assert stated["summary, to three digits"] == "0.935" and stated["07_verdict.csv"] == "0.936"
    assert stated["08_learned.csv"] == "0.9001", "every source that disagrees is named"
    assert ("a", "inverse kinematics", "RBF", "position p95") in differing, "a verdict's number no summary holds"
    # A verdict on a group of joints states a worst NRMSE over those joints only, which no summary row holds
    group = values | {"task": "measured arm, every tier, rigid-dominated joints", "metric": "worst NRMSE"}
    with (tmp_path / "07_verdict.csv").open("w", encoding="utf-8", newline="") as f:
        csv.writer(f).writerows([VERDICT_COLUMNS, [group[c] for c in VERDICT_COLUMNS]])
    assert not any(key[1] == "ID, measured arm" for key in results_disagreeing(
        {"a": tmp_path / "07_summary.csv"}, verdicts={"a": tmp_path / "07_verdict.csv"}))
    rows_only = results_disagreeing({"a": tmp_path / "07_summary.csv"}, tmp_path / "08_learned.csv")
    assert rows_only == {("a", "inverse kinematics", "ANFIS", "position p95"): {"07_summary.csv": "0.9355",
                                                                              "08_learned.csv": "0.9001"}}


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
