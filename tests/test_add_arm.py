"""``python -m nfarm add-arm``: a new arm's robot and study files from its URDF, with URDFs the
tests write themselves (and the SO-101's shipped one), into temporary parameter directories."""

from __future__ import annotations

import shutil
import subprocess
import sys
import warnings

import numpy as np
import pytest

from nfarm.__main__ import main
from nfarm.infra.paths import PARAMS, ROOT
from nfarm.infra.reading import ParamsError, ParamsWarning, load_yaml
from nfarm.model.dynamics import rnea
from nfarm.model.kinematics import fk
from nfarm.model.robot import load_robot
from nfarm.model.urdf_import import from_urdf
from nfarm.study.add_arm import add_arm
from nfarm.study.study_files import load_study


def _inertial(mass: float = 0.3) -> str:
    return (f'<inertial><origin xyz="0 0 0.02"/><mass value="{mass}"/>'
            f'<inertia ixx="1e-3" iyy="1e-3" izz="5e-4" ixy="0" iyz="0" ixz="0"/></inertial>')


def _joint(name: str, parent: str, child: str, xyz: str, axis: str = "0 0 1", kind: str = "revolute",
           limits: tuple[float, float] = (-2.0, 2.0), extra: str = "") -> str:
    limit = (f'<limit lower="{limits[0]}" upper="{limits[1]}" effort="5" velocity="3"/>'
             if kind in ("revolute", "prismatic") else "")
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}" rpy="0 0 0"/><axis xyz="{axis}"/>{limit}{extra}</joint>')


def write_arm(path, *, joints: int = 5, gripper: str | None = None, extra_leaf: bool = False,
              wrist_axis: str = "0 1 0", dynamics: bool = False):
    """A URDF of a yaw–pitch–pitch–pitch–roll arm (the closed form's class) with ``joints``
    revolute joints on the chain to ``tool_link`` (fewer: the last made fixed; a sixth: another
    roll); ``gripper``: ``"mimic"`` adds two prismatic fingers, the right one mimicking the left
    with limits that exclude the left's 0; ``extra_leaf`` a camera link fixed to the base."""
    spec = [("yaw", "0 0 0.1", "0 0 1"), ("shoulder", "0 0 0.05", "0 1 0"), ("elbow", "0 0 0.2", "0 1 0"),
            ("wrist", "0 0 0.18", wrist_axis), ("roll", "0 0 0.05", "0 0 1"), ("roll2", "0 0 0.03", "0 0 1")]
    links = ['<link name="base_link"/>']
    parts = []
    parent = "base_link"
    for k, (name, xyz, axis) in enumerate(spec[:max(joints, 5)]):
        child = f"link{k + 1}"
        links.append(f'<link name="{child}">{_inertial()}</link>')
        kind = "revolute" if k < joints else "fixed"
        extra = '<dynamics damping="0.1" friction="0.02"/>' if dynamics else ""
        parts.append(_joint(name, parent, child, xyz, axis, kind, extra=extra))
        parent = child
    links.append('<link name="tool_link"/>')
    parts.append(_joint("tool_joint", parent, "tool_link", "0 0 0.08", kind="fixed"))
    if gripper == "mimic":
        links += [f'<link name="finger_left">{_inertial(0.05)}</link>',
                  f'<link name="finger_right">{_inertial(0.05)}</link>']
        parts.append(_joint("finger_left_joint", parent, "finger_left", "0 0.01 0.04", "0 1 0",
                            "prismatic", (0.0, 0.03)))
        parts.append(_joint("finger_right_joint", parent, "finger_right", "0 -0.01 0.04", "0 1 0",
                            "prismatic", (-0.03, -0.005),
                            '<mimic joint="finger_left_joint" multiplier="-1" offset="0"/>'))
    if extra_leaf:
        links.append('<link name="camera_link"/>')
        parts.append(_joint("camera_joint", "base_link", "camera_link", "0.1 0 0.3", kind="fixed"))
    path.write_text('<?xml version="1.0"?>\n<robot name="test_arm">\n' + "\n".join(links + parts)
                    + "\n</robot>\n")
    return path


def _written(directory) -> list[str]:
    return sorted(str(p.relative_to(directory)) for p in directory.rglob("*") if p.is_file())


def test_the_so101_urdf_gives_the_shipped_chain(tmp_path):
    source = tmp_path / "source"
    shutil.copytree(PARAMS / "robots" / "so101", source)
    params = tmp_path / "params"
    lines = []
    added = add_arm(source / "so101.urdf", tip="gripper_frame_link", params=params, say=lines.append)
    assert _written(params) == ["robots/so101.yaml", "robots/so101/LICENSE", "robots/so101/so101.urdf",
                                "studies/so101.yaml"]
    robot = load_robot(params / "robots" / "so101.yaml")
    study = load_study(params / "studies" / "so101.yaml")
    assert robot.name == "so101" and study.robot.n == 5
    # The chain is the URDF's as Pinocchio parses it (buildModelFromUrdf, the gripper locked at 0), not as
    # the converter that made the shipped file reads it: the tool frame's pose, the torques, the limits
    import pinocchio as pin
    full = pin.buildModelFromUrdf(str(source / "so101.urdf"))
    model = pin.buildReducedModel(full, [full.getJointId("gripper")], pin.neutral(full))
    data, tool = model.createData(), model.getFrameId("gripper_frame_link")
    model.gravity.linear = robot.gravity
    assert [model.names[i] for i in range(1, model.njoints)] == list(robot.joint_names)
    np.testing.assert_allclose(np.c_[model.lowerPositionLimit, model.upperPositionLimit], robot.qlim, rtol=0, atol=1e-12)
    for q, qd, qdd in np.random.default_rng(0).uniform(robot.qlim[:, 0], robot.qlim[:, 1], (50, 3, robot.n)):
        pin.framesForwardKinematics(model, data, q)
        np.testing.assert_allclose(fk(robot, q), data.oMf[tool].homogeneous, rtol=0, atol=1e-12)
        np.testing.assert_allclose(rnea(robot, q, qd, qdd), pin.rnea(model, data, q, qd, qdd), rtol=0, atol=1e-12)
    assert load_yaml(params / "robots" / "so101.yaml")["lock"] == {"gripper": 0}
    # The region: inside the limits, in front of the base axis, and single-valued as checked.
    box = study.ik_region.box
    assert np.all(box[:, 0] >= robot.qlim[:, 0]) and np.all(box[:, 1] <= robot.qlim[:, 1])
    assert study.ik_region.reach[0] > 0 and not added.check.second.any()
    assert len(added.check.q) == 2000 and added.check.method == "closed form"
    assert any("2000 sampled targets" in line for line in lines)
    for q in robot.poses.values():
        assert np.all((q >= robot.qlim[:, 0]) & (q <= robot.qlim[:, 1]))


def test_add_arm_gives_the_robot_written_by_hand(tmp_path, capsys):
    """`add-arm` on :func:`write_arm`'s URDF, through the command line, gives the robot of
    tests/data/hand_written_arm.yaml (its DH frames, masses and inertias derived by hand from the URDF,
    not by the converter): the same tool pose, Jacobian, torques and mass matrix everywhere, limits,
    joint names and masses."""
    from nfarm.model.dynamics import mass_matrix
    from nfarm.model.kinematics import jacobian

    urdf = write_arm(tmp_path / "test_arm.urdf")
    params = tmp_path / "params"
    assert main(["add-arm", str(urdf), "--tip", "tool_link", "--params", str(params)]) == 0
    assert "test_arm" in capsys.readouterr().out
    robot = load_robot(params / "robots" / "test_arm.yaml")
    expected = load_robot(ROOT / "tests" / "data" / "hand_written_arm.yaml")
    assert robot.joint_names == expected.joint_names == ("yaw", "shoulder", "elbow", "wrist", "roll")
    np.testing.assert_array_equal(robot.qlim, expected.qlim)
    np.testing.assert_allclose(robot.mass, expected.mass, rtol=0, atol=1e-15)
    np.testing.assert_allclose(fk(robot, np.zeros(5))[:3, 3], [0, 0, 0.66], rtol=0, atol=1e-15)
    q, qd, qdd = np.random.default_rng(1).uniform(-2, 2, (3, 200, 5))
    np.testing.assert_allclose(fk(robot, q), fk(expected, q), rtol=0, atol=1e-12)
    np.testing.assert_allclose(jacobian(robot, q), jacobian(expected, q), rtol=0, atol=1e-12)
    np.testing.assert_allclose(rnea(robot, q, qd, qdd), rnea(expected, q, qd, qdd), rtol=0, atol=1e-12)
    np.testing.assert_allclose(mass_matrix(robot, q), mass_matrix(expected, q), rtol=0, atol=1e-12)


def test_mimic_fingers_are_locked_within_their_limits(tmp_path):
    urdf = write_arm(tmp_path / "gripper_arm.urdf", gripper="mimic", dynamics=True)
    params = tmp_path / "params"
    added = add_arm(urdf, tip="tool_link", params=params)
    robot_file = load_yaml(params / "robots" / "gripper_arm.yaml")
    # finger_left at 0 would put its mirror at 0, outside [-0.03, -0.005]: its upper limit instead.
    assert robot_file["lock"] == {"finger_left_joint": 0.03}
    assert robot_file["drive"] == {"viscous": 0.1, "coulomb": 0.02}
    robot = load_robot(params / "robots" / "gripper_arm.yaml")
    expected = from_urdf(urdf, tip="tool_link", lock={"finger_left_joint": 0.03})
    np.testing.assert_array_equal(robot.com, expected.com)
    np.testing.assert_array_equal(robot.viscous, [0.1] * 5)
    assert not added.check.second.any()
    load_study(params / "studies" / "gripper_arm.yaml")
    # A lock asked for is kept; one outside the limits (or its mirror's) is refused in one line.
    add_arm(urdf, tip="tool_link", lock={"finger_left_joint": 0.02}, params=params, force=True)
    assert load_yaml(params / "robots" / "gripper_arm.yaml")["lock"] == {"finger_left_joint": 0.02}
    for value, reason in ((0.5, "outside the joint's limits"), (0.001, "outside its limits")):
        with pytest.raises(ParamsError, match=reason) as error:
            add_arm(urdf, name="other", tip="tool_link", lock={"finger_left_joint": value}, params=params)
        assert "\n" not in str(error.value) and str(error.value).startswith(str(urdf))
    with pytest.raises(ParamsError, match="mimics 'finger_left_joint': lock that joint"):
        add_arm(urdf, name="other", tip="tool_link", lock={"finger_right_joint": -0.01}, params=params)
    assert not (params / "robots" / "other.yaml").exists()


@pytest.mark.parametrize("joints", [4, 6])
def test_a_chain_of_other_than_five_joints_is_refused(tmp_path, capsys, joints):
    urdf = write_arm(tmp_path / f"arm{joints}.urdf", joints=joints)
    params = tmp_path / "params"
    assert main(["add-arm", str(urdf), "--params", str(params)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(str(urdf))
    assert f"has {joints} revolute joints" in err and "not 5" in err
    assert not params.exists()


def test_two_leaves_without_a_tip_are_refused_listing_them(tmp_path, capsys):
    urdf = write_arm(tmp_path / "two_leaves.urdf", extra_leaf=True)
    params = tmp_path / "params"
    assert main(["add-arm", str(urdf), "--params", str(params)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "camera_link, tool_link" in err and "--tip" in err
    assert not params.exists()
    assert main(["add-arm", str(urdf), "--params", str(params), "--tip", "tool_link",
                 "--name", "leafy"]) == 0
    out = capsys.readouterr().out
    assert "chain base_link → tool_link" in out and "2000 sampled targets" in out
    load_study(params / "studies" / "leafy.yaml")


def test_a_bad_lock_value_is_refused_on_the_command_line(tmp_path, capsys):
    urdf = write_arm(tmp_path / "gripper_arm.urdf", gripper="mimic")
    params = tmp_path / "params"
    assert main(["add-arm", str(urdf), "--params", str(params), "--tip", "tool_link",
                 "--lock", "finger_left_joint=0.5"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--lock finger_left_joint=0.5: outside the joint's limits [0, 0.03]" in err
    assert main(["add-arm", str(urdf), "--params", str(params), "--tip", "tool_link",
                 "--lock", "finger_left_joint"]) == 2
    assert "must be JOINT=VALUE" in capsys.readouterr().err
    assert not params.exists()


def test_names_existing_and_bad_are_refused(tmp_path, capsys):
    urdf = write_arm(tmp_path / "arm.urdf")
    params = tmp_path / "params"
    assert main(["add-arm", str(urdf), "--params", str(params)]) == 0
    before = {p: p.read_bytes() for p in params.rglob("*") if p.is_file()}
    capsys.readouterr()
    assert main(["add-arm", str(urdf), "--params", str(params)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "arm.yaml: exists" in err and "--force" in err
    assert main(["add-arm", str(urdf), "--params", str(params), "--name", "../evil"]) == 2
    assert "is not a robot name" in capsys.readouterr().err
    assert {p: p.read_bytes() for p in params.rglob("*") if p.is_file()} == before
    assert main(["add-arm", str(urdf), "--params", str(params), "--force"]) == 0


def test_an_arm_outside_the_closed_forms_class_is_checked_by_lm(tmp_path):
    """A wrist that turns about an axis across the pitch axes leaves the closed form's class: the region is
    checked by multi-start LM, and the printout says how many targets and starts."""
    urdf = write_arm(tmp_path / "skew.urdf", wrist_axis="1 0 0")
    lines = []
    added = add_arm(urdf, params=tmp_path / "params", targets=200, starts=16, say=lines.append)
    assert added.check.method == "lm" and added.check.starts == 16 and not added.check.second.any()
    assert any("LM from 16 starts" in line and "200 targets" in line for line in lines)
    load_study(tmp_path / "params" / "studies" / "skew.yaml")


def test_import_nfarm_ik_works_as_the_readme_says():
    code = "import nfarm.ik; from nfarm.ik import closed_form; print(nfarm.ik.solve.__name__, nfarm.ik.__spec__.name)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
    assert out.stdout.split() == ["solve", "nfarm.solvers.ik"]


@pytest.mark.parametrize("wrist_axis, how", [
    ("0 1 7.346410206832132e-06", "fixed"),     # a rounded π: the pitch axes meet 25 km away
    ("7.346410206832132e-06 1 0", "alpha"),     # the same tilt about the link: alpha4 = 7.3e-6 rad
])
def test_an_arm_with_a_rounded_pi_is_added_exactly_and_solved_in_closed_form(tmp_path, wrist_axis, how):
    """A CAD export's rounded π between the pitch axes: the robot is the URDF's chain to 1e-10 (the
    tilt in a fixed transform or a small alpha), its DH table at the arm's size, the closed form
    still checks the region (its branches seeding LM), and the region is single-valued."""
    import pinocchio as pin

    from nfarm.model.pinocchio_ref import pinocchio_source
    from nfarm.model.dynamics import rnea
    from nfarm.model.kinematics import fk
    from nfarm.solvers.ik import in_class, solve

    urdf = write_arm(tmp_path / "rounded.urdf", wrist_axis=wrist_axis, dynamics=True)
    params = tmp_path / "params"
    lines = []
    added = add_arm(urdf, tip="tool_link", params=params, targets=300, say=lines.append)
    named = [line for line in lines if "warning:" in line and "nearly parallel" in line]
    assert len(named) == (how == "fixed")           # told, in one line
    robot_file = params / "robots" / "rounded.yaml"
    with warnings.catch_warnings(record=True) as caught:      # loading names the pair again
        warnings.simplefilter("always")
        robot = load_robot(robot_file)
    assert len([w for w in caught if "nearly parallel" in str(w.message)]) == (how == "fixed")
    assert (robot.fixed is not None) == (how == "fixed")
    assert np.abs(robot.a).max() < 1 and np.abs(robot.d).max() < 1 and in_class(robot)
    assert added.check.method == "closed form" and not added.check.second.any()
    reference, what = pinocchio_source(robot_file, robot)
    assert what.startswith("Pinocchio's own parse")
    rng = np.random.default_rng(5)
    for q, qd, qdd in rng.uniform(-1.5, 1.5, (20, 3, 5)):
        np.testing.assert_allclose(fk(robot, q), reference.fk(q), rtol=0, atol=1e-10)
        tau = pin.rnea(reference.model, reference.data, q, qd, qdd)
        np.testing.assert_allclose(rnea(robot, q, qd, qdd), tau, rtol=1e-9, atol=1e-12)
    # LM on the converted arm solves the poses the URDF itself produces (Pinocchio's parse), to
    # 1e-10 (with its restarts: from a start 3° off, 3 of 200 on the tilted arm stop at a
    # micrometre residual, a local minimum the tilt makes between branches).
    q = rng.uniform(-1.5, 1.5, (200, 5))
    targets = np.stack([reference.fk(qk) for qk in q])
    solved = solve(robot, targets, q + rng.normal(scale=0.05, size=q.shape), tol_pos=1e-10, tol_rot=1e-10)
    assert solved.success.all()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ParamsWarning)
        load_study(params / "studies" / "rounded.yaml")
