"""Hardening 4 (issue #69): a robot's name cannot write outside build/, add-arm copies only what it
should and refuses whole, every number a user types is checked. Each family is parametrised over
the issue's cases and variants it does not list; every refusal is one line naming the file (or
the option), the field and the rule."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nfarm.__main__ import main
from nfarm.infra.paths import PARAMS, ROOT
from nfarm.infra.reading import ParamsError, load_yaml
from nfarm.infra.typed import CELL_TIMEOUT_S, MASS, Range, parse_number
from nfarm.model.robot import is_robot_name, load_robot, robot_from_dict, robot_to_dict
from nfarm.model.urdf_import import from_urdf
from nfarm.study.add_arm import MAX_LICENCE_BYTES, add_arm
from test_add_arm import write_arm

INTELBOT5 = PARAMS / "robots" / "intelbot5.yaml"


def one_line(text: str) -> str:
    assert "\n" not in text.strip() and "Traceback" not in text and "please report" not in text, text
    return text


def files_under(directory) -> list[str]:
    return sorted(str(p.relative_to(directory)) for p in directory.rglob("*")) if directory.exists() else []


# -- robot names from every source ---------------------------------------------------------------


BAD_NAMES = ["../../../../elsewhere/pwned", "/tmp/abs", "a/b", "..", ".hidden", "a..b", "with space",
             "x" * 65, "tab\tname", "-dash", "ünï"]


@pytest.mark.parametrize("name", BAD_NAMES)
def test_a_urdf_robot_name_that_could_leave_build_is_refused(tmp_path, name):
    from xml.sax.saxutils import quoteattr
    urdf = write_arm(tmp_path / "arm.urdf")
    urdf.write_text(urdf.read_text().replace('<robot name="test_arm">', f"<robot name={quoteattr(name)}>"))
    with pytest.raises(ParamsError, match=r"<robot name>: must be 1-64 letters") as caught:
        load_robot(urdf)
    assert one_line(str(caught.value)).startswith(f"{urdf}: ")
    # a name given (a robot file's, add-arm's) is the robot's instead, checked by the same rule
    assert from_urdf(urdf, name="fine").name == "fine"
    with pytest.raises(ParamsError, match=r"name: must be 1-64"):
        from_urdf(urdf, name=name)


@pytest.mark.parametrize("name", ["../x", "/abs", "a/b"])
def test_check_params_and_datasets_refuse_such_a_urdf_and_write_nothing(tmp_path, name):
    urdf = write_arm(tmp_path / "arm.urdf")
    urdf.write_text(urdf.read_text().replace('<robot name="test_arm">', f'<robot name="{name}">'))
    out = subprocess.run([sys.executable, "-m", "nfarm", "check-params", str(urdf)], capture_output=True,
                         text=True, cwd=ROOT)
    assert out.returncode == 2 and "ok" not in out.stdout
    one_line(out.stderr)
    study = tmp_path / "s.yaml"
    study.write_text((PARAMS / "studies" / "intelbot5.yaml").read_text()
                     .replace("params/robots/intelbot5.yaml", str(urdf)))
    before = files_under(tmp_path.parent)
    assert main(["datasets", str(study)]) == 2
    assert files_under(tmp_path.parent) == before


@given(st.text(min_size=0, max_size=70))
@settings(max_examples=200, deadline=None)
def test_a_robot_name_is_one_harmless_path_component(name):
    if is_robot_name(name):
        assert os.path.basename(name) == name and ".." not in name and not name.startswith(".")
        assert all(c.isascii() and (c.isalnum() or c in "_.-") for c in name)


def test_the_dataset_directory_refuses_a_robot_renamed_in_python(tmp_path):
    import dataclasses

    from nfarm.study.datasets import dataset_dir
    from nfarm.study.study_files import load_study
    study = load_study(PARAMS / "studies" / "intelbot5.yaml")
    bad = dataclasses.replace(study, robot=dataclasses.replace(study.robot, name="../../x"))
    with pytest.raises(ParamsError, match=r"name: must be 1-64"):
        dataset_dir(bad)


# -- add-arm: licences, and nothing written on refusal --------------------------------------------


def test_only_regular_licence_files_under_the_limit_are_copied(tmp_path):
    source = tmp_path / "src"
    source.mkdir()
    urdf = write_arm(source / "arm.urdf")
    secret = tmp_path / "secret.txt"
    secret.write_text("not a licence")
    (source / "LICENSE").symlink_to(secret)                          # a symlink: not followed
    (source / "COPYING").write_text("GPL")                           # regular: copied
    with open(source / "NOTICE.bin", "wb") as f:                     # sparse, over the limit
        f.truncate(MAX_LICENCE_BYTES + 1)
    os.mkfifo(source / "LICENCE")                                    # a FIFO: never opened blocking
    lines = []
    add_arm(urdf, params=tmp_path / "params", say=lines.append, targets=200)
    copied = files_under(tmp_path / "params" / "robots" / "arm")
    assert copied == ["COPYING", "arm.urdf"]
    skipped = [line for line in lines if line.startswith("  not copied")]
    assert len(skipped) == 3 and any("symbolic link" in line for line in skipped)
    assert any(f"{MAX_LICENCE_BYTES:,}-byte limit" in line for line in skipped)


@pytest.mark.parametrize("layout", ["studies_file_is_dir", "studies_dir_is_file", "robots_dir_is_file",
                                    "urdf_dir_is_file", "params_is_file"])
def test_a_refused_destination_leaves_nothing(tmp_path, layout):
    urdf = write_arm(tmp_path / "arm.urdf")
    params = tmp_path / "params"
    params.mkdir()
    if layout == "studies_file_is_dir":
        (params / "studies" / "arm.yaml").mkdir(parents=True)
    elif layout == "studies_dir_is_file":
        (params / "studies").write_text("")
    elif layout == "robots_dir_is_file":
        (params / "robots").write_text("")
    elif layout == "urdf_dir_is_file":
        (params / "robots").mkdir()
        (params / "robots" / "arm").write_text("")
    else:
        params.rmdir()
        params.write_text("")
    before = files_under(params) if params.is_dir() else None
    with pytest.raises(ParamsError) as caught:
        add_arm(urdf, params=params, force=True, targets=200)
    one_line(str(caught.value))
    assert (files_under(params) if params.is_dir() else None) == before


def test_the_command_line_refusal_is_one_line_and_leaves_nothing(tmp_path, capsys):
    urdf = write_arm(tmp_path / "arm.urdf")
    params = tmp_path / "params"
    (params / "studies").mkdir(parents=True)
    (params / "studies" / "arm.yaml").mkdir()
    assert main(["add-arm", str(urdf), "--params", str(params), "--force"]) == 2
    one_line(capsys.readouterr().err)
    assert files_under(params) == ["studies", "studies/arm.yaml"]


def _side_mimics(base: str, count: int, multiplier: str = "1", offset: str = "0") -> str:
    links = "".join(f'<link name="m{k}"/>' for k in range(count))
    joints = ('<joint name="mj0" type="revolute"><parent link="link5"/><child link="m0"/>'
              '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>')
    # the followers before their drivers, the last first: a reader that recursed from each joint
    # to its driver would go thousands deep
    joints += "".join(f'<joint name="mj{k}" type="revolute"><parent link="link5"/><child link="m{k}"/>'
                      f'<mimic joint="mj{k - 1}" multiplier="{multiplier}" offset="{offset}"/>'
                      f'<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>' for k in range(count - 1, 0, -1))
    return base.replace("</robot>", links + joints + "</robot>")


@pytest.mark.parametrize("case, message", [
    ("velocity", r"<limit velocity>: must be <= 10000 rad/s, got 1e\+308"),
    ("effort", r"<limit effort>: must be <= 1e\+06 N·m"),
    ("origin", r"<origin xyz>: must be <= 1e\+06 m, got 1e\+308"),
    ("negative_origin", r"<origin xyz>: must be >= -1e\+06 m"),
    ("rpy", r"<origin rpy>: must be <= 628"),
    ("mass", r"<mass value>: must be <= 10000 kg"),
    ("inertia", r"<inertia ixx>: must be <= 10000 kg·m²"),
    ("tiny_velocity", r"<limit velocity>: must be >= 0.0001 rad/s"),
    ("narrow", r"joint 'yaw': its limits span .* under the 3°"),
    ("mimic_overflow", r"is not finite|outside its limits|would sit at"),
    ("roots", r"must have one root link, got 40001: base_link, r0, .* and 39,993 more$"),
])
def test_add_arm_refuses_absurd_geometry_in_one_short_line(tmp_path, case, message):
    urdf = write_arm(tmp_path / "arm.urdf")
    text = urdf.read_text()
    text = {
        "velocity": lambda: text.replace('velocity="3"', 'velocity="1e308"', 1),
        "effort": lambda: text.replace('effort="5"', 'effort="1e300"', 1),
        "origin": lambda: text.replace('<origin xyz="0 0 0.1"', '<origin xyz="1e308 0 0"', 1),
        "negative_origin": lambda: text.replace('<origin xyz="0 0 0.1"', '<origin xyz="0 -1e7 0"', 1),
        "rpy": lambda: text.replace('rpy="0 0 0"', 'rpy="1e9 0 0"', 1),
        "mass": lambda: text.replace('<mass value="0.3"/>', '<mass value="1e308"/>', 1),
        "inertia": lambda: text.replace('ixx="1e-3"', 'ixx="1e300"', 1),
        "tiny_velocity": lambda: text.replace('velocity="3"', 'velocity="1e-300"', 1),
        "narrow": lambda: text.replace('lower="-2.0" upper="2.0"', 'lower="0" upper="1e-9"', 1),
        "mimic_overflow": lambda: _side_mimics(text, 400, "10", "1"),
        "roots": lambda: text.replace("</robot>", "".join(f'<link name="r{k}"/>' for k in range(40_000))
                                      + "</robot>"),
    }[case]()
    urdf.write_text(text)
    params = tmp_path / "params"
    with pytest.raises(ParamsError, match=message) as caught:
        add_arm(urdf, params=params, tip="tool_link", targets=200)
    assert len(one_line(str(caught.value))) < 400
    assert not params.exists()


def test_thousands_of_chained_mimic_joints_are_no_recursion(tmp_path):
    urdf = write_arm(tmp_path / "arm.urdf")
    urdf.write_text(_side_mimics(urdf.read_text(), 3000))
    added = add_arm(urdf, params=tmp_path / "params", tip="tool_link", targets=200)
    assert added.robot.n == 5


def test_a_region_the_check_did_not_solve_is_refused(tmp_path, monkeypatch):
    from nfarm.study import add_arm as module
    real = module.check_single_valued

    def unsolved(*args, **kwargs):
        import dataclasses
        check = real(*args, **kwargs)
        return dataclasses.replace(check, solved=np.zeros_like(check.solved))
    monkeypatch.setattr(module, "check_single_valued", unsolved)
    urdf = write_arm(tmp_path / "arm.urdf")
    with pytest.raises(ParamsError, match=r"solved 0 of 200 targets .* not declared single-valued"):
        add_arm(urdf, params=tmp_path / "params", targets=200)
    assert not (tmp_path / "params").exists()


@pytest.mark.parametrize("tip", ["tool&#9;link", "tool&#133;link", "tool&#x2028;link", "tool#link", "tool: link"])
def test_names_yaml_cannot_hold_raw_are_written_so_they_read_back(tmp_path, tip):
    urdf = write_arm(tmp_path / "arm.urdf")
    urdf.write_text(urdf.read_text().replace('"tool_link"', f'"{tip}"'))
    added = add_arm(urdf, params=tmp_path / "params", targets=200)
    assert load_robot(tmp_path / "params" / "robots" / "arm.yaml").n == added.robot.n


# -- YAML the loader cannot build --------------------------------------------------------------------


TAGS = ["!!int 0x10", "!!float abc", "!!bool maybe", "!!timestamp x", "!!timestamp 2001-12-14",
        "!!int 1_0", "!!int ''", "!!null x", "!!binary aGk=", "!!set {a: null}", "!!omap [a: 1]",
        "!<tag:yaml.org,2002:int> 0o17", "!!float 1:30"]


@pytest.mark.parametrize("tag", TAGS)
def test_a_tag_the_loader_cannot_build_is_one_line(tmp_path, tag):
    path = tmp_path / "r.yaml"
    path.write_text(INTELBOT5.read_text().replace("mass: ", f"mass: {tag} #", 1))
    with pytest.raises(ParamsError) as caught:
        load_robot(path)
    assert one_line(str(caught.value)).startswith(f"{path}:")


@pytest.mark.parametrize("command", ["check-params", "datasets", "sweep"])
@pytest.mark.parametrize("tag", ["!!int 0x10", "!!bool maybe", "!!timestamp x"])
def test_every_command_says_a_bad_tag_in_one_line(tmp_path, command, tag):
    if command == "sweep":
        path = tmp_path / "sw.yaml"
        path.write_text(f"name: t\njob: idle\nfixed: {{value: {tag}}}\nseeds: [0]\nmetrics: [value]\n")
        argv = [command, str(path), "--workers", "0", "--out", str(tmp_path / "out")]
    else:
        path = tmp_path / "s.yaml"
        path.write_text((PARAMS / "studies" / "intelbot5.yaml").read_text().replace("seed: 0", f"seed: {tag}", 1))
        argv = [command, str(path)] + (["--out", str(tmp_path / "out")] if command == "datasets" else [])
    out = subprocess.run([sys.executable, "-m", "nfarm", *argv], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 2, out.stderr
    assert "a value tagged !!" in one_line(out.stderr)


@pytest.mark.parametrize("text", ["a: &x [1, *x]\n", "a: &x {b: *x}\n", "a: &x [[[*x]]]\n"])
def test_a_recursive_alias_is_one_line(tmp_path, text):
    path = tmp_path / "sw.yaml"
    path.write_text(text)
    with pytest.raises(ParamsError, match=r"a recursive alias \*x"):
        load_yaml(path)
    assert main(["check-params", str(path)]) == 2


def test_shared_aliases_still_read(tmp_path):
    path = tmp_path / "ok.yaml"
    path.write_text("a: &x [1]\nb: *x\nc: &y {k: &z [2]}\nd: [*y, *z]\n")
    assert load_yaml(path) == {"a": [1], "b": [1], "c": {"k": [2]}, "d": [{"k": [2]}, [2]]}


# -- plausibility bounds ----------------------------------------------------------------------------


def _joint(data, key, value):
    data["joints"][1][key] = value
    return data


@pytest.mark.parametrize("edit, message", [
    (lambda d: _joint(d, "mass", 1e308), r"joints\[1\]\.mass: must be <= 10000 kg, got 1e\+308"),
    (lambda d: _joint(d, "a", 1e308), r"joints\[1\]\.a: must be <= 1e\+06 m"),
    (lambda d: _joint(d, "d", -1e12), r"joints\[1\]\.d: must be >= -1e\+06 m"),
    (lambda d: _joint(d, "alpha", 1e300), r"joints\[1\]\.alpha: must be <= 628"),
    (lambda d: _joint(d, "com", [0, 0, 1e300]), r"joints\[1\]\.com\[2\]: must be <= 1e\+06 m"),
    (lambda d: _joint(d, "inertia", [1e308, 1, 1, 0, 0, 0]), r"joints\[1\]\.inertia\[0\]: must be <= 10000 kg·m²"),
    (lambda d: _joint(d, "velocity", 1e300), r"joints\[1\]\.velocity: must be <= 10000 rad/s"),
    (lambda d: _joint(d, "viscous", 1e300), r"joints\[1\]\.viscous: must be <= 1e\+06"),
    (lambda d: {**d, "gravity": [0, 0, -1e308]}, r"gravity\[2\]: must be >= -100 m/s²"),
    (lambda d: {**d, "tool": [[1, 0, 0, 1e308], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]},
     r"tool\[0\]\[3\]: must be <= 1e\+06 m"),
])
def test_implausible_robot_values_are_refused_with_unit_and_reason(edit, message):
    data = edit(robot_to_dict(load_robot(INTELBOT5)))
    with pytest.raises(ParamsError, match=message) as caught:
        robot_from_dict(data, "r.yaml")
    assert one_line(str(caught.value)).endswith(")")       # the bound's reason


@pytest.mark.parametrize("path, value, message", [
    (("id", "max_velocity_deg_s"), 5.0e-324, r"id.max_velocity_deg_s: must be >= 1e-12 deg/s, got 5e-324"),
    (("id", "max_acceleration_deg_s2"), 1e-300, r"max_acceleration_deg_s2: must be >= 1e-12"),
    (("id", "max_velocity_deg_s"), 1e308, r"max_velocity_deg_s: must be <= 1e\+06 deg/s"),
    (("id", "dt_s"), 5e-324, r"id.dt_s: must be >= 1e-12 s"),
    (("id", "segment_time_s"), [0.5, 1e308], r"segment_time_s\[1\]: must be <= 1e\+09 s"),
    (("id", "measured", "sensor", "current_per_count_a"), 1e-300, r"current_per_count_a: must be >= 1e-09 A"),
    (("id", "measured", "sensor", "torque_constant_nm_a"), 1e-300, r"torque_constant_nm_a: must be >= 1e-06 N·m/A"),
    (("id", "measured", "sensor", "torque_constant_nm_a"), 1e300, r"torque_constant_nm_a: must be <= 10000 N·m/A"),
])
def test_implausible_study_values_are_refused(tmp_path, path, value, message):
    from nfarm.study.study_files import study_from_dict
    data = load_yaml(PARAMS / "studies" / "intelbot5.yaml")
    node = data
    for key in path[:-1]:
        node = node[key]
    if path[-1] not in node:
        pytest.skip(f"the shipped study has no {'.'.join(path)}")
    node[path[-1]] = value
    with pytest.raises(ParamsError, match=message) as caught:
        study_from_dict(data, "s.yaml")
    one_line(str(caught.value))


@pytest.mark.parametrize("fixed, grid, message", [
    ("{problem: sinc, epochs: -1}", "{}", r"fixed.epochs: must be >= 1, got -1"),
    ("{problem: sinc, epochs: 1000000000000}", "{}", r"fixed.epochs: must be <= 1e\+08"),
    ("{problem: sinc}", "{n_mfs: [2, 1000000]}", r"grid.n_mfs: must be <= 16, got 1000000"),
    ("{problem: sinc}", "{epochs: [2, 10000000000]}", r"grid.epochs: must be <= 1e\+08"),
    ("{problem: sinc, n_rules: 100000, partition: fcm}", "{}", r"fixed.n_rules: must be <= 4096"),
])
def test_a_sweep_files_counts_are_bounded(tmp_path, fixed, grid, message):
    path = tmp_path / "sw.yaml"
    path.write_text(f"name: t\njob: anfis_benchmark\nfixed: {fixed}\ngrid: {grid}\nseeds: [0]\n"
                    f"metrics: [train_rmse]\n")
    from nfarm.study.sweep import load_sweep
    with pytest.raises(ParamsError, match=message) as caught:
        load_sweep(path)
    one_line(str(caught.value))


def test_a_learners_options_in_a_cell_are_bounded_too():
    from nfarm.study.jobs import _bounded
    with pytest.raises(ParamsError, match=r"joint_options\[1\]\.epochs: must be <= 1e\+08"):
        _bounded({"joint_options": [{}, {"epochs": 10 ** 12}]})
    with pytest.raises(ParamsError, match=r"options\.max_iter: must be <= 100000"):
        _bounded({"options": {"max_iter": 10 ** 9}})
    _bounded({"joint_options": None, "options": {"max_iter": 300}, "epochs": 10})


@given(st.floats(allow_nan=True, allow_infinity=True))
@settings(max_examples=300, deadline=None)
def test_a_bound_accepts_exactly_its_range(x):
    v = __import__("nfarm.infra.reading", fromlist=["Validator"]).Validator("f")
    inside = np.isfinite(x) and MASS.lo <= x <= MASS.hi
    try:
        assert MASS.check(v, x, "m") == x and inside
    except ParamsError as error:
        assert not inside and "\n" not in str(error)


# -- numbers typed on the command line ----------------------------------------------------------------


@pytest.mark.parametrize("text, value", [("2.5", 2.5), ("1800", 1800.0), ("none", None), ("NONE", None),
                                         (" 90 ", 90.0), ("1e3", 1000.0), ("604800", 604800.0)])
def test_cell_timeout_takes_any_positive_number_of_seconds(text, value):
    from nfarm.__main__ import _seconds
    assert _seconds(text) == value


@pytest.mark.parametrize("text", ["1e308", "0", "-1", "nan", "inf", "1_0", "0x10", "٣", "1e99999", "", "soon",
                                  "604801"])
def test_cell_timeout_refuses_other_text_as_a_usage_error(text, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["report", "--cell-timeout", text])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and "Traceback" not in err and "--cell-timeout" in err


@pytest.mark.parametrize("text, integer", [("1_0", True), ("1_0", False), ("0x10", True), ("٣", True), ("inf", False),
                                           ("nan", False), ("1e400", False), ("+-1", False), ("1.5", True)])
def test_the_one_parser_refuses_what_python_would_read(text, integer):
    with pytest.raises(ParamsError) as caught:
        parse_number(text, "--x", Range(), integer=integer)
    assert one_line(str(caught.value)).startswith("--x: must be ")


def test_the_parser_keeps_its_bound():
    with pytest.raises(ParamsError, match=r"--cell-timeout: must be <= 604800 s, got 1e\+308 \(a week"):
        parse_number("1e308", "--cell-timeout", CELL_TIMEOUT_S, none="none")


@pytest.mark.parametrize("locks, message", [
    (["finger=1_0"], r"--lock finger: must be a number in plain decimal"),
    (["finger=inf"], r"--lock finger: must be a number in plain decimal"),
    (["finger=0x1"], r"--lock finger: must be a number"),
    (["finger=0.01", "finger=0.02"], r"--lock finger: given twice \(0.01 and 0.02\)"),
    (["finger=0.01", "finger=0.01"], r"--lock finger: given twice"),
])
def test_a_lock_is_parsed_by_the_one_parser_and_given_once(tmp_path, capsys, locks, message):
    urdf = write_arm(tmp_path / "arm.urdf", gripper="mimic")
    argv = ["add-arm", str(urdf), "--params", str(tmp_path / "params"), "--tip", "tool_link"]
    for lock in locks:
        argv += ["--lock", lock]
    assert main(argv) == 2
    err = one_line(capsys.readouterr().err)
    assert __import__("re").search(message, err), err
    assert not (tmp_path / "params").exists()


@pytest.mark.parametrize("argv", [["sweep", "x.yaml", "--workers", "1_0"], ["panel", "--port", "1_0"],
                                  ["panel", "--port", "99999"], ["panel", "--port", "٣"]])
def test_other_numeric_options_take_plain_digits(argv, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2 and "Traceback" not in capsys.readouterr().err


# -- verify ----------------------------------------------------------------------------------------------


def _figures(tmp_path):
    from nfarm.publishing.manifest import write_manifest
    figures = tmp_path / "figures"
    (figures / "tables").mkdir(parents=True)
    (figures / "01_a.png").write_bytes(b"png")
    (figures / "tables" / "01_t.csv").write_text("a\n1\n")
    write_manifest(figures)
    return figures


@pytest.mark.parametrize("line, message", [
    (b"0" * 64 + b"  01_a\x00.png\n", "NUL or control character"),
    (b"0" * 64 + b"  " + b"x" * 300 + b".png\n", "longer than 255 bytes"),
    (b"0" * 64 + b"  " + b"x" * 10_000 + b"\n", "longer than"),
    (b"0" * 64 + b"  \xff\xfe.png\n", "not UTF-8 text"),
    (b"0" * 64 + b"  loop/x.png\n", "symbolic-link loop"),
    (b"0" * 64 + b"  ../outside.png\n", "outside the figures directory"),
    (b"0" * 64 + b"  01_a\x1b.png\n", "NUL or control character"),
])
def test_verify_refuses_a_bad_line_in_one_line(tmp_path, line, message):
    from nfarm.publishing.manifest import verify_manifest
    figures = _figures(tmp_path)
    (figures / "loop").symlink_to(figures / "loop")
    with open(figures / "MANIFEST.sha256", "ab") as f:
        f.write(line)
    problems = verify_manifest(figures)
    assert any(message in p for p in problems), problems
    assert all("\n" not in p and len(p) < 500 for p in problems)
    assert subprocess.run([sys.executable, "-m", "nfarm", "verify", "--figures", str(figures)],
                          capture_output=True, cwd=ROOT).returncode == 1


def test_verify_refuses_a_duplicated_line_and_a_huge_manifest(tmp_path):
    from nfarm.publishing import manifest
    figures = _figures(tmp_path)
    first = (figures / "MANIFEST.sha256").read_bytes().splitlines(keepends=True)[0]
    with open(figures / "MANIFEST.sha256", "ab") as f:
        f.write(first)
    problems = manifest.verify_manifest(figures)
    assert len(problems) == 1 and "listed twice (first at line 1)" in problems[0]
    with open(figures / "MANIFEST.sha256", "ab") as f:
        f.truncate(manifest.MAX_MANIFEST_BYTES + 1)
    (problem,) = manifest.verify_manifest(figures)
    assert "over the" in problem and "not read" in problem


def test_verify_lists_at_most_its_bound_of_problems(tmp_path):
    from nfarm.publishing import manifest
    figures = _figures(tmp_path)
    with open(figures / "MANIFEST.sha256", "ab") as f:
        f.write(b"junk\n" * 5000)
    problems = manifest.verify_manifest(figures)
    assert len(problems) == manifest.MAX_PROBLEMS + 1 and problems[-1].startswith("… and 4,900 more")


# -- the panel, saved models, solvers, dynamics ------------------------------------------------------------


@pytest.mark.parametrize("host", ["[::1%2Ftmp]:8866", "[::1%2ftmp]", "::1%2Ftmp", "[::1%25lo]:8866", "127.0.0.1%2Ftmp",
                                  "localhost%2F..", "127.0.0.1 ", " localhost", "127.0.0.1:99999", "127.0.0.1:8866/x",
                                  "localhost:", "127.0.0.1\t", "[::1]:0"])
def test_the_panel_refuses_encoded_or_padded_hosts(host):
    from nfarm.publishing.panel_app import local_host
    assert local_host(host) is False


def test_the_panels_messages_state_the_rule():
    from nfarm.publishing.panel_compute import PanelInputError, joint_trajectory
    robot = load_robot(INTELBOT5)
    trajectory, _ = joint_trajectory(robot, [0] * 5, [10] * 5, [0] * 5, [0] * 5, dt=6 / 99_999)
    assert len(trajectory.t) == 100_000                               # at the bound: drawn
    with pytest.raises(PanelInputError, match=r"gives 100,001 samples; the panel draws at most 100,000"):
        joint_trajectory(robot, [0] * 5, [10] * 5, [0] * 5, [0] * 5, dt=6 / 100_000)
    for sign in (1, -1):
        with pytest.raises(PanelInputError, match=rf"{'-' if sign < 0 else ''}3600.0000001 for base_yaw is beyond"):
            joint_trajectory(robot, [sign * 3600.0000001, 0, 0, 0, 0], [0] * 5, [0] * 5, [0] * 5)


def _saved_anfis(tmp_path):
    from nfarm.learning.anfis import ANFIS
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, (200, 2))
    model = ANFIS(n_mfs=2, epochs=2).fit(X, np.sin(X[:, 0]) + X[:, 1])
    return model, model.to_dict(), X


@pytest.mark.parametrize("edit, message", [
    (lambda s: s["consequents"][0].__setitem__(0, 1e308), r"state.consequents\[0\]\[0\]: must lie within ±1e\+100"),
    (lambda s: s.__setitem__("rules", s["rules"] + s["rules"][:1]), r"repeats an earlier rule"),
    (lambda s: s.__setitem__("rules", [[0, 0]] * 70_000), r"holds 70,000 rules, over the 65,536"),
])
def test_an_edited_saved_model_is_refused_at_load(tmp_path, edit, message):
    import copy

    from nfarm.learning.anfis import ANFIS
    model, data, X = _saved_anfis(tmp_path)
    data = copy.deepcopy(data)
    edit(data["state"])
    if len(data["state"]["rules"]) != len(data["state"]["consequents"]):
        data["state"]["consequents"] = [data["state"]["consequents"][0]] * len(data["state"]["rules"])
    with pytest.raises(ParamsError, match=message) as caught:
        ANFIS.from_dict(data, "m.json")
    one_line(str(caught.value))
    np.testing.assert_array_equal(ANFIS.from_dict(model.to_dict()).predict(X), model.predict(X))


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("which", ["q", "qd", "qdd"])
def test_rnea_refuses_non_finite_inputs(bad, which):
    from nfarm.model.dynamics import rnea
    robot = load_robot(INTELBOT5)
    args = {"q": np.zeros(5), "qd": np.zeros(5), "qdd": np.zeros(5)}
    args[which] = np.array([0, 0, bad, 0, 0])
    with pytest.raises(ValueError, match=rf"intelbot5: {which} must hold finite numbers") as caught:
        rnea(robot, **args)
    one_line(str(caught.value))


@pytest.mark.parametrize("qd, qdd", [(1e200, 0.0), (0.0, 1e308), (1e155, 1e155)])
def test_rnea_refuses_torques_that_overflow(qd, qdd, recwarn):
    from nfarm.model.dynamics import rnea
    robot = load_robot(INTELBOT5)
    with pytest.raises(ValueError, match=r"the torques of 1 states overflow"):
        rnea(robot, np.zeros(5), np.full(5, qd), np.full(5, qdd))
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


@pytest.mark.parametrize("distance", [1e151, 1e200, -1e300])
def test_the_closed_form_refuses_a_pose_no_arm_reaches_without_blaming_q0(distance):
    import nfarm.ik as ik
    T = np.eye(4)
    T[1, 3] = distance
    with pytest.raises(ValueError, match=r"T_target: pose 0's position lies .* beyond the 1e\+150 m") as caught:
        ik.closed_form(load_robot(INTELBOT5), T)
    assert "q0" not in str(caught.value)


def test_solve_bounds_its_table_of_starts():
    import nfarm.ik as ik
    from nfarm.solvers.iterative import MAX_GUESS_TABLE
    with pytest.raises(ValueError, match=r"guess_table must be at most 1,000,000 .* 37.3 GiB"):
        ik.solve(load_robot(INTELBOT5), np.eye(4), guess_table=10 ** 9)
    assert MAX_GUESS_TABLE >= 256
