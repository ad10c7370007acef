"""The shared reading path (nfarm.infra.reading): hostile and careless parameter files, each one a
one-line error naming the file, the field (or line) and the rule, found in bounded time and
memory."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

from nfarm.infra.paths import PARAMS
from nfarm.infra.reading import ParamsError, ParamsWarning, load_json, load_yaml, read_bytes
from nfarm.model.robot import load_robot

INTELBOT5 = PARAMS / "robots" / "intelbot5.yaml"
TEXT = INTELBOT5.read_text()


def variant(tmp_path, old, new, name="x.yaml"):
    assert old in TEXT
    path = tmp_path / name
    path.write_text(TEXT.replace(old, new, 1))
    return path


def alias_bomb() -> str:
    levels = ["&a0 [" + ", ".join(["x"] * 10) + "]"]
    levels += [f"&a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]" for i in range(1, 9)]
    return "[" + ", ".join(levels) + "]"


@pytest.mark.parametrize("old, new, message", [
    # 1: a number too large for a float (was an OverflowError traceback)
    ("    mass: 0.50", "    mass: 1" + "0" * 400, r"x.yaml:16:11: an integer of 401 digits \(at most 100\)"),
    ("    mass: 0.50", "    mass: 1" + "0" * 400 + ".0", r"x.yaml: joints\[0\].mass: must be finite, got inf"),
    # 2: deep nesting (was a RecursionError traceback)
    ("name: intelbot5", "name: " + "[" * 5000 + "]" * 5000, r"x.yaml:5:\d+: nested deeper than 32 levels"),
    # 3: an alias bomb, in three places (was 95 s and 3 GB, then MemoryError)
    ("name: intelbot5", "name: " + alias_bomb(), r"x.yaml:5:\d+: more than 200000 values once aliases"),
    ("description: \"5-DOF", "description: " + alias_bomb() + "\nx: \"", r"more than 200000 values"),
    ("  - name: base_yaw ", "  - name: " + alias_bomb() + " ", r"more than 200000 values"),
    # 4: duplicate keys (the last value silently won)
    ("    mass: 0.50", "    mass: 0.50\n    mass: 5.0", r"x.yaml:17:5: duplicate key 'mass' \(first at line 16\)"),
    ("convention: standard", "convention: standard\nconvention: modified",
     r"x.yaml:8:1: duplicate key 'convention' \(first at line 7\)"),
    # 6: YAML 1.1 readings that are not what the author meant
    ("    mass: 0.50", "    mass: 1:30", r"x.yaml: joints\[0\].mass: must be a number, got '1:30'"),
    ("    mass: 0.50", "    mass: 0x10", r"x.yaml: joints\[0\].mass: must be a number, got '0x10'"),
    ("    mass: 0.50", "    mass: 010_0", r"joints\[0\].mass: must be a number, got '010_0'"),
    ("    mass: 0.50", "    mass: 010", r"joints\[0\].mass: must be a number, got '010'"),
    ("    mass: 0.50", "    mass: -007", r"joints\[0\].mass: must be a number, got '-007'"),
    # 7: integers Python will not convert (a traceback)
    ("    mass: 0.50", "    mass: " + "9" * 5000, r"x.yaml:16:11: an integer of 5,000 digits \(at most 100\)"),
    ("gravity: [0.0, 0.0, -9.81]", "gravity: [0.0, 0.0, -" + "1" * 400 + "]", r"an integer of 400 digits"),
    ("    qlim: [-1.5707963267948966, 1.5707963267948966]", "    qlim: [-90, 90]",
     r"x.yaml: joints\[1\].qlim: must lie within \[-2π, 2π\] rad, got \[-90.0, 90.0\] \(degrees by mistake\?\)"),
    ("inertia: [5.1e-4, 1.0e-4, 5.1e-4, 0.0, 0.0, 0.0]", "inertia: [1e-20, 1e-20, 1e-20, 5e-20, 0, 0]",
     r"joints\[0\].inertia: must be positive semi-definite, got principal moments \[-4e-20"),
    ("name: intelbot5", "name: true", r"x.yaml: name: must be 1-64 letters, digits, .*, got True"),
])
def test_bad_files_are_one_line_errors(tmp_path, old, new, message):
    path = variant(tmp_path, old, new)
    with pytest.raises(ParamsError, match=message) as caught:
        load_robot(path)
    assert "\n" not in str(caught.value)
    assert len(str(caught.value)) < 300


def test_yaml_booleans_and_numbers_follow_yaml_1_2(tmp_path):
    path = tmp_path / "x.yaml"
    path.write_text("a: yes\nb: true\nc: 1e-4\nd: 12\ne: .inf\nf: 2001-12-14\ng: ~\nh: 0o17\ni: -.5\n")
    assert load_yaml(path) == {"a": "yes", "b": True, "c": 1e-4, "d": 12, "e": float("inf"),
                               "f": "2001-12-14", "g": None, "h": "0o17", "i": -0.5}


def test_merge_keys_are_refused(tmp_path):
    path = tmp_path / "x.yaml"
    path.write_text("base: &b {a: 1}\nother:\n  <<: *b\n")
    with pytest.raises(ParamsError, match=r"x.yaml:3:3: merge keys '<<' are not supported"):
        load_yaml(path)


def test_small_aliases_are_fine(tmp_path):
    path = tmp_path / "x.yaml"
    path.write_text("i: &i [1, 2, 3]\nj: *i\n")
    assert load_yaml(path) == {"i": [1, 2, 3], "j": [1, 2, 3]}


def test_special_and_large_files_are_refused_unread(tmp_path):
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    with pytest.raises(ParamsError, match=r"fifo.yaml: must be a regular file, got a FIFO"):
        load_robot(fifo)  # would block forever if opened for reading
    for device in ("/dev/zero", "/dev/urandom"):
        with pytest.raises(ParamsError, match=f"{device}: must be a regular file, got a device"):
            load_robot(device)
    with pytest.raises(ParamsError, match=r"must be a regular file, got a directory"):
        load_robot(tmp_path)
    big = tmp_path / "big.yaml"
    big.write_bytes(b" " * (2 << 20))
    with pytest.raises(ParamsError, match=r"big.yaml: file is 2097152 bytes, over the limit of "
                                          r"1048576 for a robot file"):
        load_robot(big)
    binary = tmp_path / "bin.yaml"
    binary.write_bytes(b"name: \xff\xfe")
    with pytest.raises(ParamsError, match=r"bin.yaml: not UTF-8 text \(byte 6"):
        load_robot(binary)
    assert read_bytes(INTELBOT5) == INTELBOT5.read_bytes()


@pytest.mark.parametrize("old, new, field", [
    ("    alpha: 1.5707963267948966", "    alpha: 90", r"joints\[0\].alpha: 90.0 rad is more than a full turn"),
    ("    offset: 1.5707963267948966", "    offset: -90", r"joints\[1\].offset: -90.0 rad is more"),
    ("    a: 0.200", "    a: 200", r"joints\[1\].a: 200.0 m is over 10 m: a length in millimetres\?"),
    ("    com: [-0.100, 0.0, 0.0]", "    com: [-100, 0.0, 0.0]", r"joints\[1\].com\[0\]: -100.0 m is over"),
])
def test_implausible_values_warn(tmp_path, old, new, field):
    with pytest.warns(ParamsWarning, match=field):
        load_robot(variant(tmp_path, old, new))


def test_shipped_robot_loads_without_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_robot(INTELBOT5)


def test_check_params_goes_on_after_every_kind_of_bad_file(tmp_path):
    """Every file is checked and reported on one line, whatever went wrong before it."""
    files = [variant(tmp_path, "    mass: 0.50", "    mass: 1" + "0" * 400, "big.yaml"),
             variant(tmp_path, "name: intelbot5", "name: " + "[" * 5000 + "]" * 5000, "deep.yaml"),
             "/dev/zero", INTELBOT5]
    run = subprocess.run([sys.executable, "-m", "nfarm", "check-params", *map(str, files)],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 2
    assert run.stdout.splitlines() == [f"{INTELBOT5}: ok (intelbot5, 5 joints, standard DH)"]
    errors = run.stderr.splitlines()
    assert [line.split(":")[0] for line in errors] == [str(files[0]), str(files[1]), "/dev/zero"]
    assert "Traceback" not in run.stderr


def test_json_reader_limits(tmp_path):
    path = tmp_path / "x.json"
    path.write_text('{"a": [1, 2.5, "x"]}')
    assert load_json(path) == {"a": [1, 2.5, "x"]}
    path.write_text('{"a": Infinity}')
    with pytest.raises(ParamsError, match=r"x.json: Infinity is not a number JSON allows"):
        load_json(path)
    path.write_text("[" * 40 + "]" * 40)
    with pytest.raises(ParamsError, match=r"x.json: nested deeper than 32 levels"):
        load_json(path)
    with pytest.raises(ParamsError, match=r"x.json: file is 80 bytes, over the limit of 10 for a JSON file"):
        load_json(path, max_bytes=10)


@pytest.mark.parametrize("text, message", [
    ('{"a": 1, "b": 2, "a": 3}', r"x.json: duplicate key 'a' in one object"),
    ('{"m": [{"lo": 1}, {"lo": [1, 2], "x": 0, "lo": 5}]}', r"x.json: duplicate key 'lo' in one object"),
    ('{"a": ' + "7" * 5000 + "}", r"x.json: an integer of 5,000 digits \(at most 100\)"),
    ('{"a": [-' + "1" * 101 + "]}", r"x.json: an integer of 101 digits"),
    ('{"a": 1.5e400}', r"x.json: 1.5e400 overflows a floating-point number"),
    ('{"a": -2e308}', r"x.json: -2e308 overflows"),
])
def test_json_reader_refuses_what_json_would_read_silently(tmp_path, text, message):
    path = tmp_path / "x.json"
    path.write_text(text)
    with pytest.raises(ParamsError, match=message) as caught:
        load_json(path)
    assert "\n" not in str(caught.value) and len(str(caught.value)) < 200


def test_json_ready_converts_numpy_and_refuses_non_finite():
    from nfarm.infra.reading import json_ready
    value = {"a": (1, np.float64(2.5)), "b": np.arange(3), "c": [np.int64(4), None, "x"]}
    assert json_ready(value) == {"a": [1, 2.5], "b": [0, 1, 2], "c": [4, None, "x"]}
    for bad in (float("nan"), [1.0, float("inf")], {"k": np.float32("nan")}, np.array([[1.0, np.nan]])):
        with pytest.raises(ValueError, match="cannot be saved as JSON"):
            json_ready(bad)


@pytest.mark.parametrize("array", [np.linspace(-1, 1, 12).reshape(3, 4), np.linspace(0, 1, 6, dtype=np.float32),
                                   np.arange(6, dtype=np.uint8).reshape(2, 3), np.array([True, False]), np.zeros((2, 0))])
def test_json_ready_writes_a_numeric_array_as_its_numbers_one_by_one_would(array):
    """The whole-array path (tolist) gives the lists, Python types and values the element-by-element
    conversion gives."""
    from nfarm.infra.reading import json_ready

    def one_by_one(value):
        return [one_by_one(v) for v in value] if isinstance(value, np.ndarray) else value.item()
    out = json_ready(array)
    assert out == one_by_one(array) and json.dumps(out) == json.dumps(one_by_one(array))
    flat = np.asarray(out, dtype=object).ravel().tolist() if array.size else []
    assert all(type(x) in (int, float, bool) for x in flat)
