"""Loading and validating robot parameter files; one bad file per rule; the check-params CLI."""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest
import yaml

from conftest import ROBOT_FILES, load_quietly
from nfarm.__main__ import main
from nfarm.infra.paths import PARAMS, ROOT
from nfarm.model.robot import ParamsError, ParamsWarning, load_robot, robot_from_dict, robot_to_dict

INTELBOT5 = ROOT / "params" / "robots" / "intelbot5.yaml"
PUMA560 = ROOT / "params" / "robots" / "puma560.yaml"


def good() -> dict:
    return yaml.safe_load(INTELBOT5.read_text())


def test_intelbot5_has_the_values_of_the_study():
    robot = load_robot(INTELBOT5)
    assert (robot.name, robot.convention, robot.n) == ("intelbot5", "standard", 5)
    np.testing.assert_allclose(robot.a, [0, 0.2, 0.18, 0, 0])
    np.testing.assert_allclose(np.degrees(robot.alpha), [90, 0, 0, 90, 0])
    np.testing.assert_allclose(robot.d, [0.105, 0, 0, 0, 0.11])
    np.testing.assert_allclose(np.degrees(robot.offset), [0, 90, -90, 0, 0])
    np.testing.assert_allclose(np.degrees(robot.qlim[:, 1]), [170, 90, 135, 110, 170])
    np.testing.assert_allclose(robot.qlim[:, 0], -robot.qlim[:, 1])
    np.testing.assert_allclose(robot.mass, [0.5, 0.35, 0.3, 0.15, 0.2])
    np.testing.assert_allclose(robot.inertia[0], np.diag([5.1e-4, 1.0e-4, 5.1e-4]))
    np.testing.assert_array_equal(robot.tool, np.eye(4))
    assert not robot.a.flags.writeable


def test_puma560_loads_with_a_triangle_inequality_warning():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = load_robot(PUMA560)
    messages = [str(w.message) for w in caught if issubclass(w.category, ParamsWarning)]
    # Link 1 (only Iyy) and, in the published numbers, link 3 (0.0125 + 0.066 < 0.086).
    assert [m.split(": ")[1] for m in messages] == ["joints[0].inertia", "joints[2].inertia"]
    assert all("triangle inequality" in m for m in messages)
    assert robot.n == 6 and robot.mass[0] == 0.0


@pytest.mark.parametrize("path", ROBOT_FILES, ids=lambda p: p.stem)
def test_dict_round_trip(path):
    robot = load_quietly(path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ParamsWarning)
        again = robot_from_dict(robot_to_dict(robot))
    for field in ("a", "alpha", "d", "offset", "qlim", "mass", "com", "inertia", "tool"):
        np.testing.assert_array_equal(getattr(again, field), getattr(robot, field))


def test_exponents_without_a_decimal_point_are_numbers(tmp_path):
    """YAML 1.1 reads 5e-4 as a string; our loader reads it as the number users meant."""
    text = INTELBOT5.read_text().replace("5.1e-4", "51e-5")
    path = tmp_path / "exp.yaml"
    path.write_text(text)
    assert load_robot(path).inertia[0, 0, 0] == pytest.approx(5.1e-4)


def edit(change):
    data = good()
    change(data)
    return data


def set_joint(i, key, value):
    return lambda d: d["joints"][i].__setitem__(key, value)


def drop(*path):
    def change(d):
        for key in path[:-1]:
            d = d[key]
        del d[path[-1]]
    return change


def set_top(key, value):
    return lambda d: d.__setitem__(key, value)


BAD = {
    "missing name": (drop("name"), r"name: required field is missing"),
    "missing joint field": (drop("joints", 1, "d"), r"joints\[1\]\.d: required field is missing"),
    "unknown top key": (set_top("gravty", [0, 0, -9.81]), r"gravty: unknown field \(did you mean 'gravity'\?\)"),
    "unknown joint key": (set_joint(2, "mas", 1.0), r"joints\[2\]\.mas: unknown field \(did you mean 'mass'\?\)"),
    "bad convention": (set_top("convention", "craig"), r"convention: must be one of standard, modified, got 'craig'"),
    "gravity length": (set_top("gravity", [0, -9.81]), r"gravity: must be a list of 3 numbers"),
    "not a number": (set_joint(0, "a", "zero"), r"joints\[0\]\.a: must be a number, got 'zero'"),
    "boolean": (set_joint(0, "d", True), r"joints\[0\]\.d: must be a number, got True"),
    "nan": (set_joint(3, "offset", float("nan")), r"joints\[3\]\.offset: must be finite, got nan"),
    "inf": (set_joint(1, "com", [0.0, float("inf"), 0.0]), r"joints\[1\]\.com\[1\]: must be finite, got inf"),
    "limits order": (set_joint(2, "qlim", [1.0, -1.0]), r"joints\[2\]\.qlim: must satisfy lo < hi, got \[1\.0, -1\.0\]"),
    "limits equal": (set_joint(2, "qlim", [0.5, 0.5]), r"joints\[2\]\.qlim: must satisfy lo < hi"),
    "negative mass": (set_joint(2, "mass", -1.0), r"joints\[2\]\.mass: must be >= 0, got -1\.0"),
    "inertia length": (set_joint(0, "inertia", [1, 1, 1]), r"joints\[0\]\.inertia: must be a list of 6 numbers"),
    "inertia not psd": (set_joint(4, "inertia", [1e-4, 1e-4, 1e-4, 5e-4, 0, 0]), r"joints\[4\]\.inertia: must be positive semi-definite"),
    "empty joints": (set_top("joints", []), r"joints: must be a non-empty list of joints"),
    "joint not mapping": (lambda d: d["joints"].__setitem__(1, [0, 1]), r"joints\[1\]: must be a mapping"),
    "tool shape": (set_top("tool", [[1, 0, 0], [0, 1, 0], [0, 0, 1]]), r"tool: must be a 4x4 matrix"),
    "tool last row": (set_top("tool", [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]]), r"tool\[3\]: last row must be \[0, 0, 0, 1\]"),
    "tool not orthonormal": (set_top("tool", [[1, 0.1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]), r"tool: rotation part must be orthonormal"),
    "tool reflection": (set_top("tool", [[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]), r"tool: rotation part must have determinant \+1"),
    "empty name": (set_top("name", " "), r"name: must be 1-64 letters, digits"),
    "fixed not rigid": (set_joint(1, "fixed", [[1, 0.1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]),
                        r"joints\[1\]\.fixed: rotation part must be orthonormal"),
    "fixed on modified DH": (lambda d: (d.__setitem__("convention", "modified"),
                                        d["joints"][2].__setitem__("fixed", np.eye(4).tolist())),
                             r"joints\[2\]\.fixed: a fixed transform after the DH row needs the standard convention"),
    "not a mapping": (lambda d: d.clear(), r"name: required field is missing"),
}


@pytest.mark.parametrize("rule", BAD)
def test_each_rule_names_file_field_and_rule(tmp_path, rule):
    change, message = BAD[rule]
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(edit(change)))
    with pytest.raises(ParamsError, match=rf"^{path}: {message}"):
        load_robot(path)
    assert main(["check-params", str(path)]) == 2


def test_yaml_syntax_error_gives_the_line(tmp_path):
    path = tmp_path / "broken.yaml"
    path.write_text("name: x\nconvention: standard\njoints: [\n  {a: 0,\n")
    with pytest.raises(ParamsError, match=rf"^{path}:5:1: YAML syntax error"):
        load_robot(path)


def test_top_level_not_a_mapping(tmp_path):
    path = tmp_path / "list.yaml"
    path.write_text("- 1\n- 2\n")
    with pytest.raises(ParamsError, match=rf"^{path}: must be a mapping of fields, got \[1, 2\]"):
        load_robot(path)


def test_missing_file(tmp_path):
    with pytest.raises(ParamsError, match="nope.yaml: file not found"):
        load_robot(tmp_path / "nope.yaml")


def test_check_params_cli(tmp_path):
    """One line per file on the real command line: ok, the error, exit 0 only if all are ok."""
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(edit(set_joint(2, "mass", -1.0))))
    run = lambda *files: subprocess.run([sys.executable, "-m", "nfarm", "check-params", *map(str, files)],
                                        capture_output=True, text=True)
    ok = run(INTELBOT5, PUMA560)
    assert ok.returncode == 0, ok.stderr
    assert ok.stdout.splitlines() == [f"{INTELBOT5}: ok (intelbot5, 5 joints, standard DH)",
                                      f"{PUMA560}: ok (puma560, 6 joints, standard DH)"]
    assert "triangle inequality" in ok.stderr
    mixed = run(INTELBOT5, bad, tmp_path / "missing.yaml")
    assert mixed.returncode == 2
    assert mixed.stderr.splitlines() == [f"{bad}: joints[2].mass: must be >= 0, got -1.0",
                                         f"{tmp_path / 'missing.yaml'}: file not found"]


def test_a_robot_names_its_file_from_the_checkout_whatever_the_working_directory(tmp_path, monkeypatch):
    robot = load_robot(ROOT / "params" / "robots" / "intelbot5.yaml")
    monkeypatch.chdir(tmp_path)
    assert "source='params/robots/intelbot5.yaml'" in repr(robot)


def test_named_poses_are_the_files_own_checked_and_outside_the_hash(tmp_path):
    """A robot file's poses_deg: one angle per joint within its limits, in radians inside;
    the hash, data sets and models do not depend on them."""
    from nfarm.model.robot import poses_for, robot_hash
    path = ROOT / "params" / "robots" / "intelbot5.yaml"
    robot = load_robot(path)
    assert list(robot.poses)[0] == "ready (q = 0)" and robot.poses["folded back"][2] == pytest.approx(np.radians(-110))
    assert list(poses_for(robot)[0]) == list(robot.poses) and poses_for(robot)[1] == ""
    text = path.read_text()
    bare = text[:text.index("poses_deg:")]
    plain = tmp_path / "plain.yaml"
    plain.write_text(bare)
    assert robot_hash(load_robot(plain)) == robot_hash(robot)
    assert "poses_deg" not in robot_to_dict(robot)
    poses, note = poses_for(load_robot(plain))
    assert list(poses)[0] == "home (q = 0)" and len(poses) == 4 and "names no poses (poses_deg)" in note
    for bad, message in (("  folded back: [-45, 20, -140, 90, -90]\n", r"poses_deg\.folded back\[2\]: must lie within elbow_pitch's limits \[-135, 135\] deg, got -140"),
                         ("  short: [0, 0, 0]\n", r"poses_deg\.short: must be a list of 5 numbers")):
        broken = tmp_path / "broken.yaml"
        broken.write_text(bare + "poses_deg:\n" + bad)
        with pytest.raises(ParamsError, match=message):
            load_robot(broken)


@pytest.mark.parametrize("name", ["../escape", "a/b", ".hidden", "", "with space", "x" * 65, "tab\tname", "a..b", 3])
def test_a_robot_name_that_could_not_name_a_directory_is_refused_in_one_line(name):
    """A robot's name names directories and files (data sets, models, recordings): no path
    separators, no '..', nothing a file system would read otherwise."""
    data = robot_to_dict(load_robot(PARAMS / "robots" / "intelbot5.yaml"))
    data["name"] = name
    with pytest.raises(ParamsError, match=r"name: must be 1-64 letters, digits, '_', '-' or '\.'"):
        robot_from_dict(data)


def test_a_fixed_transform_after_a_row_is_kept_and_hashed_and_an_identity_one_is_not():
    """``fixed`` moves the chain (fk changes by the transform), survives the file round trip,
    and changes the hash; a file without it, or with identities, is the plain DH robot."""
    from nfarm.model.kinematics import fk
    from nfarm.model.robot import robot_hash
    data = robot_to_dict(load_robot(ROBOT_FILES[0]))
    plain = robot_from_dict(data)
    E = np.eye(4)
    E[:3, 3] = [0.0, 0.0, 0.01]                        # 1 cm along joint 3's axis
    data["joints"][1]["fixed"] = E.tolist()
    moved = robot_from_dict(data)
    np.testing.assert_array_equal(moved.fixed[1], E)
    # fk moves by the transform, inserted after row 2: T = (base A1 A2) E (A3 … An tool), at every q
    from nfarm.model.kinematics import fk_all
    for q in np.random.default_rng(0).uniform(-2, 2, (20, plain.n)):
        T_02 = fk_all(plain, q)[2]
        expected = T_02 @ E @ np.linalg.solve(T_02, fk(plain, q))
        np.testing.assert_allclose(fk(moved, q), expected, rtol=0, atol=1e-14)
        frames = fk_all(moved, q)                     # the frames before it unmoved, frame 2 carried by it
        np.testing.assert_allclose(frames[:2], fk_all(plain, q)[:2], rtol=0, atol=1e-15)
        np.testing.assert_allclose(frames[2], T_02 @ E, rtol=0, atol=1e-15)
    assert not np.allclose(fk(moved, np.zeros(plain.n)), fk(plain, np.zeros(plain.n)))
    assert robot_hash(moved) != robot_hash(plain)
    assert robot_from_dict(robot_to_dict(moved)).fixed.tolist() == moved.fixed.tolist()
    data["joints"][1]["fixed"] = np.eye(4).tolist()
    identity = robot_from_dict(data)
    assert robot_hash(identity) == robot_hash(plain) and "fixed" not in robot_to_dict(identity)["joints"][1]
