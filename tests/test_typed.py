"""The generic reader of parameter sections (nfarm.infra.typed): every annotation it knows,
read and refused in one line naming the field; the study file's schema is the README's."""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from typing import Annotated, Literal, Optional, Union

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nfarm.infra.paths import PARAMS
from nfarm.infra.reading import ParamsError
from nfarm.infra.typed import JOINTS, ORDERED, TEXT, Length, Range, ReadBy, read_typed, section_keys
from nfarm.study.study_files import StudyFile


@dataclass(frozen=True, kw_only=True)
class Inner:
    axis: tuple[float, float, float]
    angle_deg: Annotated[float, Range(lo=0.0, lo_open=True, hi=180.0)] = 90.0


@dataclass(frozen=True, kw_only=True)
class Section:
    name: str
    note: Annotated[str, TEXT] = ""
    count: Annotated[int, Range(lo=1, hi=10)]
    kind: Literal["a", "b"] = "a"
    flag: bool = False
    sizes: Annotated[dict[Literal["train", "test"], int], Range(lo=0)] = dataclasses.field(
        default_factory=lambda: {"train": 1, "test": 1})
    bounds: Annotated[Optional[tuple[Optional[float], Optional[float]]], ORDERED, Range(lo=0.0)] = None
    per_joint: Annotated[Union[float, Annotated[list[float], JOINTS]], Range(lo=0.0, hi=1.0, hi_open=True)] = 0.5
    few: Annotated[list[int], Length(1, 3)] = dataclasses.field(default_factory=lambda: [1])
    inner: Optional[Inner] = None


GOOD = {"name": "x", "count": 3}


def read(data, joints=3):
    return read_typed(Section, data, "f.yaml", joints=joints)


def test_defaults_fill_what_is_left_out_and_values_keep_their_types():
    s = read({**GOOD, "bounds": [None, 2], "per_joint": [0, 0.25, 0.5], "inner": {"axis": [0, 0, 1]},
              "sizes": {"train": 4, "test": 0}})
    assert s == Section(name="x", count=3, bounds=(None, 2.0), per_joint=[0.0, 0.25, 0.5],
                        inner=Inner(axis=(0.0, 0.0, 1.0)), sizes={"train": 4, "test": 0})
    assert isinstance(s.bounds[1], float) and isinstance(s.count, int)
    assert read({**GOOD, "inner": None, "bounds": None}).inner is None
    assert section_keys(Section) == {"name": True, "note": False, "count": True, "kind": False, "flag": False,
                                     "sizes": False, "bounds": False, "per_joint": False, "few": False,
                                     "inner": False}


@pytest.mark.parametrize("change, message", [
    ({"nmae": "x"}, r"nmae: unknown field \(did you mean 'name'\?\)"),
    ({"zzz": 1}, r"zzz: unknown field \(allowed: name, note, count, kind, flag, sizes, bounds, per_joint, few, inner\)"),
    ({"name": ""}, r"name: must be a non-empty string, got ''"),
    ({"name": None}, r"name: must be a non-empty string, got None"),
    ({"note": 3}, r"note: must be a non-empty string, got 3"),
    ({"count": 0}, r"count: must be >= 1, got 0"),
    ({"count": 11}, r"count: must be <= 10, got 11"),
    ({"count": 2.0}, r"count: must be a whole number, got 2.0"),
    ({"count": True}, r"count: must be a whole number, got True"),
    ({"kind": "c"}, r"kind: must be one of a, b, got 'c'"),
    ({"flag": "yes"}, r"flag: must be true or false, got 'yes'"),
    ({"sizes": {"train": 1}}, r"sizes.test: required field is missing"),
    ({"sizes": {"train": 1, "test": -1}}, r"sizes.test: must be >= 0, got -1"),
    ({"sizes": [1, 2]}, r"sizes: must be a mapping of fields"),
    ({"bounds": [2, 1]}, r"bounds: must satisfy lo < hi, got \[2.0, 1.0\]"),
    ({"bounds": [-1, None]}, r"bounds\[0\]: must be >= 0, got -1.0"),
    ({"bounds": [1]}, r"bounds: must be a list of 2 items, got 1"),
    ({"bounds": "1, 2"}, r"bounds: must be a list, got '1, 2'"),
    ({"per_joint": 1.0}, r"per_joint: must be < 1, got 1.0"),
    ({"per_joint": [0.1, 0.2]}, r"per_joint: must be a list of 3 items, got 2"),
    ({"per_joint": [0.1, float("nan"), 0.2]}, r"per_joint\[1\]: must be finite, got nan"),
    ({"per_joint": None}, r"per_joint: must be a number, got None"),
    ({"few": []}, r"few: must be a list of 1 to 3 items, got 0"),
    ({"few": [1, "2"]}, r"few\[1\]: must be a whole number, got '2'"),
    ({"inner": {}}, r"inner.axis: required field is missing"),
    ({"inner": {"axis": [0, 0, 1], "angle_deg": 0}}, r"inner.angle_deg: must be > 0, got 0.0"),
    ({"inner": {"axis": [0, 0, 1, 0]}}, r"inner.axis: must be a list of 3 items, got 4"),
])
def test_every_rule_is_one_line_naming_the_field(change, message):
    with pytest.raises(ParamsError, match=message) as caught:
        read({**GOOD, **change})
    assert str(caught.value).startswith("f.yaml: ") and "\n" not in str(caught.value)


def test_required_fields_and_sections():
    with pytest.raises(ParamsError, match=r"^f.yaml: count: required field is missing$"):
        read({"name": "x"})
    with pytest.raises(ParamsError, match=r"^f.yaml: must be a mapping of fields, got \[1\]$"):
        read([1])
    with pytest.raises(ParamsError, match=r"^f.yaml: top.count: required field is missing$"):
        read_typed(Section, {"name": "x"}, "f.yaml", "top", joints=3)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(count=st.integers(-5, 15), x=st.floats(allow_nan=False, allow_infinity=False, width=32),
       joints=st.integers(1, 6))
def test_numbers_are_accepted_exactly_within_their_range(count, x, joints):
    data = {**GOOD, "count": count, "per_joint": [x] * joints}
    if 1 <= count <= 10 and 0.0 <= x < 1.0:
        s = read(data, joints)
        assert s.count == count and s.per_joint == [float(x)] * joints
    else:
        with pytest.raises(ParamsError):
            read(data, joints)


def test_annotations_it_does_not_know_are_a_programming_error():
    @dataclass(frozen=True)
    class Odd:
        value: set[int]

    @dataclass(frozen=True)
    class Joints:
        value: Annotated[list[float], JOINTS]

    with pytest.raises(TypeError, match="unsupported annotation"):
        read_typed(Odd, {"value": [1]}, "f.yaml")
    with pytest.raises(TypeError, match="needs the robot's joint count"):
        read_typed(Joints, {"value": [1.0]}, "f.yaml")


def _even(v, value, at):
    if v.integer(value, at) % 2:
        v.fail(at, f"must be even, got {value}")
    return value


@dataclass(frozen=True, kw_only=True)
class OwnReaders:
    size: Annotated[int, ReadBy(_even)]
    sizes: Annotated[list[Annotated[int, ReadBy(_even)]], Length(1, 2)] = dataclasses.field(default_factory=list)
    maybe: Annotated[Optional[int], ReadBy(_even)] = None


def test_a_field_read_by_its_own_reader_keeps_its_place_path_and_null():
    """ReadBy: the reader gets the validator, the value and the field's path (inside a list
    too), in the file's order; null of an optional field never reaches it."""
    assert read_typed(OwnReaders, {"size": 2, "sizes": [4], "maybe": None}, "f.yaml") == \
        OwnReaders(size=2, sizes=[4], maybe=None)
    with pytest.raises(ParamsError, match=r"^f.yaml: size: must be even, got 3$"):
        read_typed(OwnReaders, {"size": 3, "sizes": [1]}, "f.yaml")        # the first field first
    with pytest.raises(ParamsError, match=r"^f.yaml: sizes\[1\]: must be even, got 5$"):
        read_typed(OwnReaders, {"size": 2, "sizes": [4, 5]}, "f.yaml")
    with pytest.raises(ParamsError, match=r"^f.yaml: maybe: must be a whole number, got 'x'$"):
        read_typed(OwnReaders, {"size": 2, "maybe": "x"}, "f.yaml")
    with pytest.raises(ParamsError, match=r"^f.yaml: sizes: must be a list of 1 to 2 items, got 3$"):
        read_typed(OwnReaders, {"size": 2, "sizes": [2, 2, 2]}, "f.yaml")


def _keys(cls, at=""):
    """Every key path of a section's dataclass tree."""
    import typing
    hints = typing.get_type_hints(cls)
    for name in section_keys(cls):
        path = f"{at}.{name}" if at else name
        yield path
        hint = hints[name]
        for arm in typing.get_args(hint) or (hint,):
            if dataclasses.is_dataclass(arm):
                yield from _keys(arm, path)


def test_the_study_file_schema_is_the_one_the_readme_documents():
    table = (PARAMS / "README.md").read_text().split("## Studies", 1)[1].split("\n## ", 1)[0]
    documented = " ".join(re.findall(r"`([^`]+)`", table))
    missing = [path for path in _keys(StudyFile) if path.rsplit(".", 1)[-1] not in documented]
    assert not missing, f"fields of StudyFile the README's study table does not name: {missing}"
