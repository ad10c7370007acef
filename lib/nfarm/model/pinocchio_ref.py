"""Independent reference: the same robot as a Pinocchio model, built joint by joint from DH.

Used by the tests, the benchmarks and the chapters to check nfarm's own algorithms against
Pinocchio (Featherstone's spatial algebra, a different derivation from the DH recursions).
The model is built with ``Model.addJoint`` from :func:`nfarm.model.kinematics.joint_placements`, not from
the URDF, so it also checks :func:`nfarm.model.urdf_export.to_urdf` (see the tests).

For a robot read from a URDF, a model built from nfarm's own DH table would check nothing of the
conversion: :func:`pinocchio_source` gives Pinocchio's own parse of the URDF the robot file
names instead (the chapters' cross-checks use it).

Frames: ``dh_frame1``…``dh_framen`` (the DH link frames) and ``tool``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from .kinematics import joint_placements
from .robot import Robot

__all__ = ["PinocchioRobot", "pinocchio_model", "pinocchio_from_urdf", "pinocchio_source"]


@dataclass
class PinocchioRobot:
    """A Pinocchio model and data with the ids of the DH frames and of the tool frame.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> reference = pinocchio_model(robot)
        >>> q = np.array([0.3, 0.2, -0.4, 0.5, 0.1])     # one configuration (n,) [rad]
        >>> reference.fk(q).shape, reference.fk_all(q).shape, reference.jacobian(q).shape
        ((4, 4), (6, 4, 4), (6, 5))
    """

    model: pin.Model
    data: pin.Data
    frame_ids: list[int]
    tool_id: int
    base: np.ndarray = field(default_factory=lambda: np.eye(4))

    def fk(self, q: np.ndarray) -> np.ndarray:
        """``T_0e`` (4×4) of one configuration ``q (n,)``."""
        pin.framesForwardKinematics(self.model, self.data, q)
        return self.data.oMf[self.tool_id].homogeneous

    def fk_all(self, q: np.ndarray) -> np.ndarray:
        """``(n + 1, 4, 4)``: the base frame then every DH frame, for one ``q (n,)``."""
        pin.framesForwardKinematics(self.model, self.data, q)
        return np.stack([self.base] + [self.data.oMf[f].homogeneous for f in self.frame_ids])

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """``(6, n)`` tool Jacobian in ``LOCAL_WORLD_ALIGNED`` (linear rows first)."""
        pin.computeJointJacobians(self.model, self.data, q)
        pin.updateFramePlacements(self.model, self.data)
        J = pin.getFrameJacobian(self.model, self.data, self.tool_id,
                                 pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        return J.reshape(6, self.model.nv)  # eigenpy gives (6,) for a one-joint chain


def _se3(T: np.ndarray) -> pin.SE3:
    return pin.SE3(np.array(T[:3, :3]), np.array(T[:3, 3]))


def pinocchio_model(robot: Robot, *, armature: bool = False) -> PinocchioRobot:
    """Build the Pinocchio model of ``robot`` (revolute-z joints, inertias, gravity, frames);
    with ``armature``, the robot's armature too (``pin.rnea`` then adds ``I_a q̈``, as
    ``rnea(..., drive=True)`` does without friction).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> from nfarm.model.kinematics import fk
        >>> q = np.array([0.3, 0.2, -0.4, 0.5, 0.1])     # [rad]
        >>> np.allclose(pinocchio_model(robot).fk(q), fk(robot, q))
        True
    """
    model = pin.Model()
    model.name = robot.name
    model.gravity.linear = np.array(robot.gravity)
    J, B = joint_placements(robot)
    frame_ids, parent = [], 0
    for i in range(robot.n):
        lo, hi = robot.qlim[i]
        big = np.array([1e6])
        placement = robot.base @ J[i] if i == 0 else J[i]
        parent = model.addJoint(parent, pin.JointModelRZ(), _se3(placement), robot.joint_names[i],
                                big, big, np.array([lo]), np.array([hi]))
        body = _se3(B[i])
        inertia = pin.Inertia(float(robot.mass[i]), np.array(robot.com[i]),
                              np.array(robot.inertia[i]))
        model.appendBodyToJoint(parent, inertia, body)
        frame_ids.append(model.addFrame(
            pin.Frame(f"dh_frame{i + 1}", parent, body, pin.FrameType.OP_FRAME)))
    tool_id = model.addFrame(
        pin.Frame("tool", parent, _se3(B[-1] @ robot.tool), pin.FrameType.OP_FRAME))
    if armature:
        model.armature = np.asarray(robot.armature, dtype=float).copy()   # pin.rnea adds I_a q̈
    return PinocchioRobot(model, model.createData(), frame_ids, tool_id, np.array(robot.base))


def pinocchio_from_urdf(urdf: str) -> PinocchioRobot:
    """Load a URDF written by :func:`nfarm.model.urdf_export.to_urdf` into Pinocchio.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> from nfarm.model.urdf_export import to_urdf
        >>> q = np.array([0.3, 0.2, -0.4, 0.5, 0.1])     # [rad]
        >>> np.allclose(pinocchio_from_urdf(to_urdf(robot)).fk_all(q), pinocchio_model(robot).fk_all(q))
        True
    """
    model = pin.buildModelFromXML(urdf)
    n = model.nq
    frame_ids = [model.getFrameId(f"dh_frame{i + 1}") for i in range(n)]
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.zeros(n))
    base = data.oMf[model.getFrameId("dh_frame0")].homogeneous.copy()
    return PinocchioRobot(model, data, frame_ids, model.getFrameId("tool"), base)


def pinocchio_source(robot_file: str | os.PathLike, robot: Robot) -> tuple[PinocchioRobot, str]:
    """The independent reference for the robot a robot file describes, and a phrase naming it:
    for a file that names a URDF (``urdf:``, with its ``tip`` and ``lock``), **Pinocchio's own
    parse of that URDF** (``pin.buildModelFromUrdf``), the joints off the chain locked where the
    file locks them (0 otherwise; a ``<mimic>`` joint at ``multiplier · q_driver + offset``, read
    from the URDF here, not by nfarm's reader) and the tool frame at the tip link; for any other
    robot, :func:`pinocchio_model` from its DH table. ``robot`` (the file's, loaded) gives the
    gravity and the joint order, which must be the URDF's. ``fk`` and ``jacobian`` are the tip's in
    the URDF's root frame, nfarm's world; ``fk_all`` has no DH frames to give.

    Raises:
        ValueError: the URDF's chain joints are not the robot's, in order.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> from nfarm.model.kinematics import fk
        >>> robot = load_robot(PARAMS / "robots" / "so101.yaml")
        >>> reference, what = pinocchio_source(PARAMS / "robots" / "so101.yaml", robot)
        >>> what
        "Pinocchio's own parse of the robot's URDF (so101/so101.urdf)"
        >>> q = np.array([0.3, 0.2, -0.4, 0.5, 0.1])     # [rad]
        >>> bool(np.abs(reference.fk(q) - fk(robot, q)).max() < 1e-10)
        True
    """
    import xml.etree.ElementTree as ET

    from ..infra.reading import load_yaml

    path = Path(robot_file)
    fields = load_yaml(path) if path.suffix.lower() in (".yaml", ".yml") else None
    if not isinstance(fields, dict) or "urdf" not in fields or "tip" not in fields:
        return pinocchio_model(robot), "the robot built joint by joint in Pinocchio from nfarm's DH table"
    urdf = path.parent / fields["urdf"]
    lock = dict(fields.get("lock") or {})
    full = pin.buildModelFromUrdf(str(urdf))
    mimics = {j.get("name"): (m.get("joint"), float(m.get("multiplier", 1.0)), float(m.get("offset", 0.0)))
              for j in ET.parse(urdf).getroot().iter("joint") if (m := j.find("mimic")) is not None}
    chain = set(robot.joint_names)

    def position(name: str, depth: int = 0) -> float:
        if name in mimics and depth < 32:
            driver, multiplier, offset = mimics[name]
            return multiplier * position(driver, depth + 1) + offset
        return float(lock.get(name, 0.0))

    q_ref, locked = pin.neutral(full), []
    for jid in range(1, full.njoints):
        name = full.names[jid]
        if name not in chain:
            locked.append(jid)
            q_ref[full.joints[jid].idx_q] = position(name)
    model = pin.buildReducedModel(full, locked, q_ref) if locked else full
    names = [model.names[j] for j in range(1, model.njoints)]
    if names != list(robot.joint_names):
        raise ValueError(f"{urdf}: the chain's joints {names} are not the robot's {list(robot.joint_names)}")
    model.gravity.linear = np.array(robot.gravity)
    return (PinocchioRobot(model, model.createData(), [], model.getFrameId(fields["tip"])),
            f"Pinocchio's own parse of the robot's URDF ({fields['urdf']})")
