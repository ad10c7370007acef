"""The URDF writer (Pinocchio and rerun load its output as the same robot nfarm computes
with) and reader (the SO-101 and random URDFs, against Pinocchio's own parse)."""

from __future__ import annotations

import subprocess
import sys
import warnings
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import random_chains
from nfarm.model.dynamics import gravity_torques, mass_matrix, rnea
from nfarm.model.kinematics import fk, fk_all, jacobian
from nfarm.infra.paths import PARAMS
from nfarm.infra.reading import ParamsError, ParamsWarning
from nfarm.model.rotations import quat_to_matrix, matrix_to_rpy
from nfarm.model.robot import load_robot
from nfarm.model.urdf_export import to_urdf
from nfarm.model.urdf_import import from_urdf

TOL = 1e-12


@given(random_chains())
def test_urdf_loads_into_pinocchio_as_the_same_robot(robot):
    """to_urdf → Pinocchio's own parse of the text (``pin.buildModelFromXML``, nothing of nfarm's
    joint placements) gives nfarm's DH kinematics and Newton–Euler dynamics: every DH frame and the
    tool where nfarm's fk puts them, its Jacobian, and rnea, M(q) and g(q) from Pinocchio's algorithms."""
    model = pin.buildModelFromXML(to_urdf(robot))
    data = model.createData()
    model.gravity.linear = robot.gravity
    assert model.nq == model.nv == robot.n
    frames = [model.getFrameId(f"dh_frame{i}") for i in range(robot.n + 1)]
    tool = model.getFrameId("tool")
    assert tool < model.nframes and all(f < model.nframes for f in frames)
    rng = np.random.default_rng(0)
    for q, v, a in rng.uniform(-2, 2, (5, 3, robot.n)):
        pin.framesForwardKinematics(model, data, q)
        np.testing.assert_allclose(np.stack([data.oMf[f].homogeneous for f in frames]), fk_all(robot, q), atol=TOL)
        np.testing.assert_allclose(data.oMf[tool].homogeneous, fk(robot, q), atol=TOL)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        J = pin.getFrameJacobian(model, data, tool, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED).reshape(6, robot.n)
        np.testing.assert_allclose(J, jacobian(robot, q), atol=1e-11)
        np.testing.assert_allclose(pin.rnea(model, data, q, v, a), rnea(robot, q, v, a), rtol=1e-10, atol=1e-10)
        M = pin.crba(model, data, q)
        np.testing.assert_allclose(np.triu(M) + np.triu(M, 1).T, mass_matrix(robot, q), rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(pin.computeGeneralizedGravity(model, data, q), gravity_torques(robot, q),
                                   rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(model.lowerPositionLimit, robot.qlim[:, 0])
    np.testing.assert_allclose(model.upperPositionLimit, robot.qlim[:, 1])


def test_urdf_structure(robot):
    root = ET.fromstring(to_urdf(robot))
    assert root.get("name") == robot.name
    revolute = [j for j in root.iter("joint") if j.get("type") == "revolute"]
    assert [j.get("name") for j in revolute] == list(robot.joint_names)
    masses = [float(link.find("inertial/mass").get("value"))
              for link in root.iter("link") if link.find("inertial") is not None]
    np.testing.assert_array_equal(masses, robot.mass)
    for i in range(robot.n):
        assert root.find(f"link[@name='link{i + 1}']/visual") is not None


def test_a_prefix_renames_every_link_and_joint_and_nothing_else(intelbot5):
    """Two copies of one arm share a scene: every name and every reference to a link carries
    the prefix, the rest of the document (colour apart) is unchanged."""
    plain, left = to_urdf(intelbot5), to_urdf(intelbot5, prefix="left_", color=(0.1, 0.2, 0.3))
    root = ET.fromstring(left)
    links = {link.get("name") for link in root.iter("link")}
    assert root.get("name") == "left_intelbot5"
    assert all(name.startswith("left_") for name in links | {j.get("name") for j in root.iter("joint")})
    assert {e.get("link") for j in root.iter("joint") for e in (j.find("parent"), j.find("child"))} <= links
    assert left.replace("left_", "").replace("0.1 0.2 0.3 1", "0.85 0.55 0.15 1") == plain


def test_rerun_loads_the_urdf(intelbot5, tmp_path):
    """rerun's own URDF loader (inside the SDK, no viewer) turns every link into geometry."""
    urdf = tmp_path / "intelbot5.urdf"
    urdf.write_text(to_urdf(intelbot5))
    rrd = tmp_path / "robot.rrd"
    script = ("import rerun as rr, sys\n"
              "rec = rr.RecordingStream('nfarm-test', recording_id='urdf')\n"
              "rec.save(sys.argv[2])\n"
              "rec.log_file_from_path(sys.argv[1], static=True)\n"
              "rec.flush()\n")
    subprocess.run([sys.executable, "-c", script, str(urdf), str(rrd)], check=True)
    rerun = [sys.executable, "-m", "rerun", "rrd", "print", str(rrd)]
    printed = subprocess.run(rerun, check=True, capture_output=True, text=True).stdout
    for i in range(intelbot5.n):
        assert f"/intelbot5/visual_geometries/link{i + 1}/visual_0" in printed
    assert "Cylinders3D" in printed


# -- reading a URDF ----------------------------------------------------------------------------


SO101 = PARAMS / "robots" / "so101" / "so101.urdf"
AGREE = 1e-10


def pinocchio_locked(path, locked: dict[str, float]):
    """Pinocchio's own parse of the URDF file, the joints off the chain locked."""
    model = pin.buildModelFromUrdf(str(path))
    q_ref = pin.neutral(model)
    ids = []
    for name, value in locked.items():
        jid = model.getJointId(name)
        ids.append(jid)
        q_ref[model.joints[jid].idx_q] = value
    return pin.buildReducedModel(model, ids, q_ref) if ids else model


def check_against_pinocchio(robot, path, tip, locked, seed=0):
    model = pinocchio_locked(path, locked)
    model.gravity.linear = robot.gravity
    data, fid = model.createData(), model.getFrameId(tip)
    names = [model.names[j] for j in range(1, model.njoints)]
    assert names == list(robot.joint_names)
    rng = np.random.default_rng(seed)
    for _ in range(5):
        q = rng.uniform(robot.qlim[:, 0], robot.qlim[:, 1])
        qd, qdd = rng.normal(size=(2, robot.n))
        pin.framesForwardKinematics(model, data, q)
        np.testing.assert_allclose(fk(robot, q), data.oMf[fid].homogeneous, rtol=0, atol=AGREE)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        J = pin.getFrameJacobian(model, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        np.testing.assert_allclose(jacobian(robot, q), J.reshape(6, robot.n), rtol=0, atol=AGREE)
        np.testing.assert_allclose(rnea(robot, q, qd, qdd), pin.rnea(model, data, q, qd, qdd),
                                   rtol=0, atol=AGREE)
        M = pin.crba(model, data, q)
        np.testing.assert_allclose(mass_matrix(robot, q), np.triu(M) + np.triu(M, 1).T, rtol=0, atol=AGREE)
        np.testing.assert_allclose(gravity_torques(robot, q), pin.computeGeneralizedGravity(model, data, q),
                                   rtol=0, atol=AGREE)


def test_so101_agrees_with_pinocchios_own_parse():
    robot = from_urdf(SO101, tip="gripper_frame_link")
    assert robot.n == 5 and robot.joint_names[0] == "shoulder_pan"
    np.testing.assert_allclose(robot.effort, 10.0)
    check_against_pinocchio(robot, SO101, "gripper_frame_link", {"gripper": 0.0})
    opened = from_urdf(SO101, tip="gripper_frame_link", lock={"gripper": 1.0})
    check_against_pinocchio(opened, SO101, "gripper_frame_link", {"gripper": 1.0})
    assert not np.allclose(opened.com[-1], robot.com[-1]), "the jaw's position moves the last link's centre"


def _origin(rng, scale=0.3):
    xyz = rng.uniform(-scale, scale, 3)
    if rng.random() < 0.3:
        xyz[:] = 0.0
    rpy = matrix_to_rpy(quat_to_matrix(rng.normal(size=4))) if rng.random() < 0.8 else np.zeros(3)
    return f'<origin xyz="{" ".join(map(str, xyz.tolist()))}" rpy="{" ".join(map(str, np.asarray(rpy).tolist()))}"/>'


def _inertial(rng):
    R = quat_to_matrix(rng.normal(size=4))
    I = (R @ np.diag(rng.uniform(0.05, 0.1, 3)) @ R.T * 0.1).tolist()   # a physical body
    return (f'<inertial>{_origin(rng, 0.1)}<mass value="{float(rng.uniform(0.1, 2.0))!r}"/>'
            f'<inertia ixx="{I[0][0]!r}" ixy="{I[0][1]!r}" ixz="{I[0][2]!r}" iyy="{I[1][1]!r}" '
            f'iyz="{I[1][2]!r}" izz="{I[2][2]!r}"/></inertial>')


def random_urdf(seed: int, n: int) -> tuple[str, dict[str, float]]:
    """A random tree: a chain of n revolute joints about random axes (some parallel, nearly
    parallel or intersecting the previous one), fixed joints on it, and side branches on revolute joints
    locked at random angles. Returns the URDF and the side joints' lock positions."""
    rng = np.random.default_rng(seed)
    lines = ['<robot name="random">', f'<link name="root">{_inertial(rng)}</link>']
    parent, locks, axis = "root", {}, rng.normal(size=3)
    for i in range(n):
        if rng.random() < 0.3:                                   # a fixed joint on the chain
            lines += [f'<joint name="fixed{i}" type="fixed"><parent link="{parent}"/>'
                      f'<child link="mid{i}"/>{_origin(rng)}</joint>', f'<link name="mid{i}"/>']
            parent = f"mid{i}"
        kind = rng.random()
        origin = _origin(rng)
        if kind < 0.25:     # same axis as the joint frame's z, no rotation: parallel axes
            origin = f'<origin xyz="{float(rng.uniform(-0.3, 0.3))!r} {float(rng.uniform(-0.3, 0.3))!r} 0"/>'
            axis = np.array([0.0, 0.0, 1.0]) if i == 0 else axis
        elif kind < 0.4:    # the same, turned by 1e-12 to 1e-2 rad: nearly parallel axes
            tilt = float(10 ** rng.uniform(-12, -2) * rng.choice([-1, 1]))
            origin = (f'<origin xyz="{float(rng.uniform(-0.3, 0.3))!r} {float(rng.uniform(-0.3, 0.3))!r} '
                      f'{float(rng.uniform(-0.05, 0.05))!r}" rpy="{tilt!r} 0 0"/>')
            axis = np.array([0.0, 0.0, 1.0]) if i == 0 else axis
        else:
            axis = rng.normal(size=3)
        lines += [f'<joint name="j{i}" type="revolute"><parent link="{parent}"/><child link="l{i}"/>'
                  f'{origin}<axis xyz="{" ".join(map(str, axis.tolist()))}"/>'
                  f'<limit lower="-2" upper="2" effort="5" velocity="3"/></joint>',
                  f'<link name="l{i}">{_inertial(rng)}</link>']
        parent = f"l{i}"
        if rng.random() < 0.4:                                   # a side branch, locked
            locks[f"side{i}"] = float(rng.uniform(-1, 1))
            lines += [f'<joint name="side{i}" type="revolute"><parent link="{parent}"/>'
                      f'<child link="s{i}"/>{_origin(rng)}<axis xyz="0 1 0"/>'
                      f'<limit lower="-2" upper="2" effort="1" velocity="1"/></joint>',
                      f'<link name="s{i}">{_inertial(rng)}</link>']
    lines += [f'<joint name="tip_fixed" type="fixed"><parent link="{parent}"/><child link="tip"/>'
              f'{_origin(rng)}</joint>', '<link name="tip"/>', '</robot>']
    return "\n".join(lines), locks


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 7))
def test_random_urdfs_agree_with_pinocchios_own_parse(tmp_path_factory, seed, n):
    text, locks = random_urdf(seed, n)
    path = tmp_path_factory.mktemp("urdf") / "random.urdf"
    path.write_text(text)
    with warnings.catch_warnings():     # nearly parallel axes are named: checked elsewhere
        warnings.simplefilter("ignore", ParamsWarning)
        robot = from_urdf(path, tip="tip", lock=locks)
    assert robot.n == n
    assert np.abs(robot.a).max() < 10 and np.abs(robot.d).max() < 10    # frames near the arm [m]
    check_against_pinocchio(robot, path, "tip", locks, seed)


def test_a_written_urdf_reads_back_as_the_same_robot(robot, tmp_path):
    path = tmp_path / "robot.urdf"
    path.write_text(to_urdf(robot))
    with warnings.catch_warnings():   # the Puma table's published inertias warn, as when loaded
        warnings.simplefilter("ignore", ParamsWarning)
        again = from_urdf(path, tip="tool")
    rng = np.random.default_rng(1)
    q = rng.uniform(robot.qlim[:, 0], robot.qlim[:, 1], (20, robot.n))
    qd, qdd = rng.normal(size=(2, 20, robot.n))
    np.testing.assert_allclose(fk(again, q), fk(robot, q), atol=1e-12)
    np.testing.assert_allclose(rnea(again, q, qd, qdd), rnea(robot, q, qd, qdd), rtol=1e-10, atol=1e-10)
    np.testing.assert_array_equal(again.qlim, robot.qlim)
    assert again.joint_names == robot.joint_names


GOOD = """<robot name="two">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="2" velocity="3"/></joint>
  <link name="l1"><inertial><origin xyz="0 0 0.05"/><mass value="0.5"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.2 0 0" rpy="1.5707963267948966 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="2" velocity="3"/></joint>
  <link name="l2"/>
</robot>
"""


def test_a_small_urdf_reads_as_expected(tmp_path):
    path = tmp_path / "two.urdf"
    path.write_text(GOOD)
    robot = from_urdf(path)                        # its single leaf is the tip
    assert robot.n == 2 and robot.joint_names == ("j1", "j2") and robot.name == "two"
    np.testing.assert_allclose(robot.qlim, [[-1, 1], [-1, 1]])
    np.testing.assert_allclose(robot.effort, 2.0)
    np.testing.assert_allclose(robot.velocity, 3.0)
    np.testing.assert_allclose(abs(robot.a[0]), 0.2, atol=1e-12)       # the common normal
    np.testing.assert_allclose(abs(np.degrees(robot.alpha[0])), 90, atol=1e-9)
    check_against_pinocchio(robot, path, "l2", {})


@pytest.mark.parametrize("change, message", [
    (lambda s: s.replace('type="revolute"><parent link="l1"/>', 'type="prismatic"><parent link="l1"/>'),
     r"joint 'j2': type 'prismatic' on the chain to 'l2': only revolute and fixed joints"),
    (lambda s: s.replace('type="revolute"><parent link="l1"/>', 'type="continuous"><parent link="l1"/>'),
     r"joint 'j2': type 'continuous' on the chain"),
    (lambda s: s.replace('<parent link="l1"/>', '<parent link="l9"/>'),
     r"joint 'j2' <parent link>: names a link that does not exist: 'l9'"),
    (lambda s: s.replace('</robot>', '<joint name="loop" type="fixed"><parent link="l2"/><child link="l1"/></joint></robot>'),
     r"joint 'loop': link 'l1' already has parent joint 'j1': a closed loop"),
    (lambda s: s.replace('xyz="0.2 0 0"', 'xyz="0.2 zero 0"'),
     r"joint 'j2' <origin xyz>: must be 3 finite numbers, got '0.2 zero 0'"),
    (lambda s: s.replace('xyz="0.2 0 0"', 'xyz="0.2 0"'),
     r"joint 'j2' <origin xyz>: must be 3 finite numbers"),
    (lambda s: s.replace('<mass value="0.5"/>', '<mass value="-1"/>'),
     r"link 'l1' <inertial><mass value>: must be >= 0"),
    (lambda s: s.replace('ixx="0.01"', 'ixx="-0.5"'),
     r"link 'l1' <inertial><inertia>: must be positive semi-definite"),
    (lambda s: s.replace('lower="-1" upper="1" effort="2" velocity="3"/></joint>\n  <link name="l2"/>',
                         'lower="1" upper="-1" effort="2" velocity="3"/></joint>\n  <link name="l2"/>'),
     r"joint 'j2' <limit>: must satisfy lower < upper"),
    (lambda s: s.replace('<axis xyz="0 0 1"/>\n    <limit lower="-1" upper="1" effort="2" velocity="3"/></joint>\n  <link name="l2"/>',
                         '<axis xyz="0 0 0"/>\n    <limit lower="-1" upper="1" effort="2" velocity="3"/></joint>\n  <link name="l2"/>'),
     r"joint 'j2' <axis xyz>: must not be the zero vector"),
    (lambda s: s.replace('<link name="l2"/>', '<link name="l2"/><link name="l1"/>'),
     r"link 'l1': is defined twice"),
    (lambda s: s.replace('</robot>', '<link name="stray"/></robot>'),
     r"<robot>: must have one root link, got 2: base, stray"),
    (lambda s: s.replace('<robot name="two">', '<!DOCTYPE r [<!ENTITY a "x">]><robot name="two">'),
     r"<!DOCTYPE>/<!ENTITY> declarations are not accepted"),
    (lambda s: s.replace('</robot>', '</robt>'), r"not well-formed XML at line \d+, column \d+"),
    (lambda s: s.replace('<robot name="two">', '<robots name="two">').replace('</robot>', '</robots>'),
     r"<robot>: the root element must be <robot>, got <robots>"),
    (lambda s: s.replace('</robot>', '<joint name="j3" type="fixed"><parent link="l1"/><child link="l3"/></joint><link name="l3"/></robot>'),
     r"tip: the URDF has 2 leaf links \(l2, l3\): name the chain's last link"),
    (lambda s: s.replace('lower="-1" upper="1"', 'lower="-7" upper="7"', 1),     # the robot's own rules
     r"joints\[0\]\.qlim: must lie within \[-2π, 2π\] rad, .* \(converted from the URDF\)$"),
])
def test_every_urdf_rule_has_a_bad_file(tmp_path, change, message):
    path = tmp_path / "bad.urdf"
    path.write_text(change(GOOD))
    with pytest.raises(ParamsError, match=message) as caught:
        from_urdf(path)
    assert str(caught.value).startswith(f"{path}: ") and "\n" not in str(caught.value)


def test_a_lock_position_must_be_a_finite_number(tmp_path):
    path = tmp_path / "two.urdf"
    path.write_text(GOOD.replace('</robot>', '<joint name="jaw" type="revolute"><parent link="l1"/>'
                                 '<child link="jaw"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" '
                                 'effort="1" velocity="1"/></joint><link name="jaw"/></robot>'))
    with pytest.raises(ParamsError, match=r"lock.jaw: must be a finite number, got nan"):
        from_urdf(path, tip="l2", lock={"jaw": float("nan")})
    assert from_urdf(path, tip="l2", lock={"jaw": 0.5}).n == 2


def test_robot_files_naming_a_urdf(tmp_path):
    """A YAML robot file takes a URDF relative to itself, its tip, locks, gravity and drive
    terms; check-params accepts it and the URDF; their mistakes are one-line errors."""
    from nfarm.model.robot import load_robot
    (tmp_path / "two.urdf").write_text(GOOD)
    good = "name: two\nurdf: two.urdf\ntip: l2\ndrive: {viscous: 0.1, armature: [0.01, 0.02]}\n"
    (tmp_path / "two.yaml").write_text(good)
    robot = load_robot(tmp_path / "two.yaml")
    assert robot.name == "two" and robot.source == str(tmp_path / "two.yaml")
    np.testing.assert_array_equal(robot.viscous, [0.1, 0.1])
    np.testing.assert_array_equal(robot.armature, [0.01, 0.02])
    np.testing.assert_array_equal(load_robot(tmp_path / "two.urdf").a, robot.a)
    for text, message in [
        (good.replace("urdf: two.urdf", "urdf: two.yaml"), r"urdf: must name a .urdf file"),
        (good.replace("tip: l2", "tip: l7"), r"tip: no link 'l7' in the URDF"),
        (good + "lock: {j1: 0.3}\n", r"lock.j1: is on the chain"),
        (good + "lock: {j9: 0.3}\n", r"lock.j9: names no joint"),
        (good.replace("viscous: 0.1", "viscous: -0.1"), r"drive.viscous: must be >= 0"),
        (good.replace("[0.01, 0.02]", "[0.01]"), r"drive.armature: must be one number or 2, got 1"),
        (good + "joints_deg: 3\n", r"joints_deg: unknown field"),
    ]:
        (tmp_path / "bad.yaml").write_text(text)
        with pytest.raises(ParamsError, match=message):
            load_robot(tmp_path / "bad.yaml")
    checked = subprocess.run([sys.executable, "-m", "nfarm", "check-params", str(tmp_path / "two.yaml"),
                              str(tmp_path / "two.urdf")], capture_output=True, text=True)
    assert checked.returncode == 0, checked.stderr
    assert "two, 2 joints" in checked.stdout


def test_a_urdf_robot_is_hashed_by_its_sources(tmp_path):
    """The same files give the same robot hash under another floating-point set-up (the
    converted parameters' last bits may differ); an edited URDF or a robot changed after
    loading gives another."""
    import dataclasses

    from nfarm.model.robot import load_robot, robot_hash
    robot = load_robot(PARAMS / "robots" / "so101.yaml")
    script = ("from nfarm.model.robot import load_robot, robot_hash; import sys; "
              "print(robot_hash(load_robot(sys.argv[1])))")
    env = {**__import__("os").environ, "NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR AVX2 FMA3",
           "OPENBLAS_CORETYPE": "Sandybridge"}
    other = subprocess.run([sys.executable, "-c", script, str(PARAMS / "robots" / "so101.yaml")],
                           capture_output=True, text=True, env=env, check=True).stdout.strip()
    assert other == robot_hash(robot)
    assert robot_hash(dataclasses.replace(robot, viscous=robot.viscous * 2)) != robot_hash(robot)
    (tmp_path / "two.urdf").write_text(GOOD)
    first = robot_hash(from_urdf(tmp_path / "two.urdf"))
    (tmp_path / "two.urdf").write_text(GOOD.replace('<mass value="0.5"/>', '<mass value="0.6"/>'))
    assert robot_hash(from_urdf(tmp_path / "two.urdf")) != first
    assert robot_hash(from_urdf(tmp_path / "two.urdf", name="renamed")) != robot_hash(from_urdf(tmp_path / "two.urdf"))


def test_the_chapters_reference_for_a_urdf_arm_is_pinocchios_own_parse_and_catches_a_wrong_conversion():
    """Chapters 01 and 03 cross-check a URDF arm against Pinocchio's parse of the URDF itself
    (nfarm.model.pinocchio_ref.pinocchio_source): it agrees with the converted robot, and it
    sees a conversion error that a Pinocchio model built from nfarm's own DH table cannot."""
    import dataclasses

    from nfarm.model.pinocchio_ref import pinocchio_model, pinocchio_source

    robot_file = PARAMS / "robots" / "so101.yaml"
    robot = load_robot(robot_file)
    reference, what = pinocchio_source(robot_file, robot)
    assert what.startswith("Pinocchio's own parse of the robot's URDF")
    rng = np.random.default_rng(3)
    q = rng.uniform(robot.qlim[:, 0], robot.qlim[:, 1], size=(20, robot.n))
    qd, qdd = rng.normal(size=(2, 20, robot.n))
    m, d = reference.model, reference.data
    np.testing.assert_allclose(fk(robot, q), [reference.fk(x) for x in q], rtol=0, atol=AGREE)
    np.testing.assert_allclose(jacobian(robot, q), [reference.jacobian(x) for x in q], rtol=0, atol=AGREE)
    np.testing.assert_allclose(rnea(robot, q, qd, qdd), [pin.rnea(m, d, *x) for x in zip(q, qd, qdd)],
                               rtol=0, atol=AGREE)
    wrong = dataclasses.replace(robot, a=robot.a + np.array([0, 1e-3, 0, 0, 0]))     # a 1 mm slip
    own = pinocchio_model(wrong)
    assert np.abs(fk(wrong, q) - np.array([own.fk(x) for x in q])).max() < AGREE, "its own DH: blind"
    assert np.abs(fk(wrong, q) - np.array([reference.fk(x) for x in q])).max() > 1e-4, "the source sees it"
    dh_only, what = pinocchio_source(PARAMS / "robots" / "intelbot5.yaml", load_robot(PARAMS / "robots" / "intelbot5.yaml"))
    assert what == "the robot built joint by joint in Pinocchio from nfarm's DH table"


def test_nfarm_model_urdf_re_exports_the_public_names_from_their_modules():
    from nfarm.model import urdf, urdf_export, urdf_import, urdf_tree
    assert (urdf.to_urdf, urdf.from_urdf, urdf.urdf_outline, urdf.URDFOutline, urdf.URDFJoint) == \
        (urdf_export.to_urdf, urdf_import.from_urdf, urdf_tree.urdf_outline, urdf_tree.URDFOutline,
         urdf_tree.URDFJoint)
