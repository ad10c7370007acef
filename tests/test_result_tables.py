"""The published result tables read back (nfarm.study.result_tables): one reader, one rule — a file
that is empty, holds only its header, or lacks a column the table is read by is refused in one
line naming the file; a table its writer wrote reads back whole."""

from __future__ import annotations

import pytest

from nfarm.study.result_tables import (LONG_COLUMNS, PAIRED_COLUMNS, VERDICT_COLUMNS, WARM_START_COLUMNS,
                                       read_long_table, read_paired, read_verdicts, read_warm_starts)

READERS = [(read_long_table, LONG_COLUMNS, "a summary table"), (read_paired, PAIRED_COLUMNS, "a paired table"),
           (read_verdicts, VERDICT_COLUMNS, "a verdict table"), (read_warm_starts, WARM_START_COLUMNS, "a table of LM's starts")]


@pytest.mark.parametrize("read, columns, what", READERS, ids=lambda x: getattr(x, "__name__", None))
def test_every_reader_refuses_an_empty_or_header_only_file_in_one_line_naming_it(tmp_path, read, columns, what):
    empty, head = tmp_path / "empty.csv", tmp_path / "head.csv"
    empty.write_text("", encoding="utf-8")
    head.write_text(",".join(columns) + "\n", encoding="utf-8")
    for path, said in ((empty, f"empty, not {what}"), (head, f"{what} without a row")):
        with pytest.raises(ValueError) as caught:
            read(path)
        assert str(caught.value) == f"{path}: {said}" and "\n" not in str(caught.value)
    row = tmp_path / "row.csv"
    row.write_text(",".join(columns) + "\n" + ",".join("x" for _ in columns) + "\n", encoding="utf-8")
    assert read(row) == [dict.fromkeys(columns, "x")]


def test_a_file_without_the_table_s_columns_is_refused_naming_them(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b\n1,2\n", encoding="utf-8")
    with pytest.raises(ValueError, match="not a summary table"):
        read_long_table(bad)
    (tmp_path / "starts.csv").write_text("start,targets\nhome,10\n")
    with pytest.raises(ValueError, match="starts.csv: not a table of LM's starts: columns mean iterations missing"):
        read_warm_starts(tmp_path / "starts.csv")
    with pytest.raises(ValueError, match="bad.csv: not a verdict table: columns arm, task"):
        read_verdicts(bad)
    head_only = tmp_path / "head_only.csv"                 # the columns are checked before the rows
    head_only.write_text("task,method\n", encoding="utf-8")
    with pytest.raises(ValueError, match="head_only.csv: not a paired table: columns against, metric, ci_low, ci_high missing"):
        read_paired(head_only)
