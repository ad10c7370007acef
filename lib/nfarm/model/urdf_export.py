"""URDF export of a DH chain, so that Pinocchio and rerun load the same robot as nfarm
(:func:`to_urdf`; reading a URDF back is :mod:`.urdf_import`'s).

URDF places each joint at a fixed origin in its parent link and turns the child about an axis
through that origin, so a DH link transform is split at the joint rotation:

* standard DH, ``A_i = Rz(θ_i) · F_i`` with ``F_i = Rz(offset_i) Tz(d_i) Tx(a_i) Rx(α_i)``:
  URDF joint i sits at ``F_{i-1}`` in link i−1 (``F_0 = I``); URDF link i is then DH frame i−1
  turned by ``q_i``, and DH frame i is ``F_i`` in it;
* modified DH, ``A_i = G_i · Rz(θ_i)`` with ``G_i = Rx(α_i) Tx(a_i) Tz(d_i) Rz(offset_i)``:
  URDF joint i sits at ``G_i`` and URDF link i *is* DH frame i.

Links: ``base_link``, ``link1``…``linkn`` (the moving bodies, with their inertials), and
massless ``dh_frame1``…``dh_framen`` and ``tool`` on fixed joints, so the DH frames and the tool
frame can be looked up by name. Visuals: a cylinder along each joint axis and cylinders along
the links' common normals and offsets.
"""

from __future__ import annotations

import re
from xml.sax.saxutils import escape

import numpy as np

from ..infra.reading import ParamsError
from .kinematics import joint_placements
from .robot import Robot
from .rotations import matrix_to_rpy

__all__ = ["to_urdf"]


def _f(x: float) -> str:
    """A number as URDF text: its ``repr`` (which reads back exactly), ``0`` for zero."""
    return repr(float(x)) if x != 0 else "0"


#: Characters XML 1.0 cannot hold, even escaped.
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")


def _attr(text: str, source: str, field: str) -> str:
    """``text`` as an XML attribute value between double quotes: ``&``, ``<``, ``>``, ``"`` and
    the whitespace that attribute normalisation would turn into spaces escaped; a character
    XML cannot hold at all is a :class:`ParamsError` naming ``source`` and ``field``."""
    bad = _NOT_XML.search(text)
    if bad:
        raise ParamsError(f"{source}: {field}: {text!r} holds U+{ord(bad[0]):04X}, which XML "
                          f"cannot hold: the robot cannot be written as a URDF")
    return escape(text, {'"': "&quot;", "\t": "&#9;", "\n": "&#10;", "\r": "&#13;"})


def _limit(x: float) -> str:
    """A URDF limit: 0 stands for none."""
    return _f(x) if np.isfinite(x) else "0"


def _origin(T: np.ndarray) -> str:
    """The ``<origin>`` of a pose ``T`` ``(4, 4)``: ``xyz`` its translation [m], ``rpy`` URDF's
    fixed-axis roll, pitch, yaw [rad] of its rotation (``R = Rz(y) · Ry(p) · Rx(r)``)."""
    xyz = " ".join(_f(v) for v in T[:3, 3])
    rpy = " ".join(_f(v) for v in matrix_to_rpy(T[:3, :3]))
    return f'<origin xyz="{xyz}" rpy="{rpy}"/>'


def _cylinder(start: np.ndarray, end: np.ndarray, radius: float) -> str:
    """A visual cylinder from ``start`` to ``end`` (points in the link frame)."""
    axis = end - start
    length = float(np.linalg.norm(axis))
    z = axis / length
    helper = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    T[:3, 3] = (start + end) / 2
    return (f'    <visual>{_origin(T)}<geometry><cylinder radius="{_f(radius)}" '
            f'length="{_f(length)}"/></geometry><material name="link"/></visual>')


def _link_visuals(points: list[np.ndarray], radius: float) -> list[str]:
    """A link's visuals: the joint, a cylinder of radius ``1.25·radius`` [m] along the link
    frame's z axis, and a cylinder along each segment (longer than 1 nm) of the polyline
    ``points`` (each ``(3,)`` [m] in the link frame)."""
    out = [_cylinder(np.array([0, 0, -radius]), np.array([0, 0, radius]), 1.25 * radius)]
    for start, end in zip(points, points[1:]):
        if np.linalg.norm(end - start) > 1e-9:
            out.append(_cylinder(start, end, radius))
    return out


def to_urdf(robot: Robot, *, prefix: str = "", color: tuple[float, float, float] = (0.85, 0.55, 0.15)
            ) -> str:
    """A URDF (XML string) of the chain: revolute joints with limits, inertials, visuals.

    ``prefix`` goes before the robot's, every link's and every joint's name, so that two copies
    of one arm can share a scene (frames are matched by name); ``color`` is the links' RGB.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> text = to_urdf(robot)
        >>> text.splitlines()[1], text.count('type="revolute"')
        ('<robot name="intelbot5">', 5)
        >>> to_urdf(robot, prefix="left_").splitlines()[1]
        '<robot name="left_intelbot5">'
    """
    J, B = joint_placements(robot)
    n = robot.n
    tool = B[-1] @ robot.tool
    radius = _visual_radius(robot)
    lines = _header(_attr(robot.name, robot.source, "name"), color, radius) \
        + _fixed_frame("dh_frame0", "base_link", robot.base)
    for i in range(n):
        parent = "base_link" if i == 0 else f"link{i}"
        lines += _revolute_joint(robot, i, parent, robot.base @ J[i] if i == 0 else J[i])
        end = (J[i + 1] if i + 1 < n else tool)[:3, 3]
        lines += _body_link(robot, i, B[i], end, radius)
        lines += _fixed_frame(f"dh_frame{i + 1}", f"link{i + 1}", B[i])
    lines += _fixed_frame("tool", f"link{n}", tool) + ['</robot>']
    return _prefixed("\n".join(lines) + "\n", _attr(prefix, "to_urdf", "prefix"))


def _visual_radius(robot: Robot) -> float:
    """The visual cylinders' radius [m]: 4 % of the chain's size ``Σ|a_i| + Σ|d_i|``, at least
    0.01 m (so that a tiny chain stays visible)."""
    size = float(np.sum(np.abs(robot.a)) + np.sum(np.abs(robot.d)))
    return 0.04 * max(size, 0.25)


def _header(name: str, color: tuple[float, float, float], radius: float) -> list[str]:
    """The document's opening lines: the ``<robot>`` element (``name`` already escaped), the
    links' material (RGB in [0, 1], opaque) and ``base_link``, drawn as a cylinder of radius
    ``2·radius`` [m] below its origin."""
    return ['<?xml version="1.0"?>', f'<robot name="{name}">',
            f'  <material name="link"><color rgba="{" ".join(_f(c) for c in color)} 1"/></material>',
            '  <link name="base_link">',
            _cylinder(np.array([0, 0, -2 * radius]), np.zeros(3), 2 * radius), '  </link>']


def _fixed_frame(name: str, parent: str, T: np.ndarray) -> list[str]:
    """A massless link ``name`` fixed to ``parent`` at ``T`` ``(4, 4)`` [m] (its pose in the
    parent), by a fixed joint ``<name>_fixed``: a named frame to look up."""
    return [f'  <joint name="{name}_fixed" type="fixed">',
            f'    <parent link="{parent}"/><child link="{name}"/>{_origin(T)}',
            '  </joint>',
            f'  <link name="{name}"/>']


def _revolute_joint(robot: Robot, i: int, parent: str, placement: np.ndarray) -> list[str]:
    """Joint i+1 (0-based ``i``): about the z axis of ``placement`` ``(4, 4)`` (the joint in
    ``parent``'s frame, :func:`~nfarm.model.kinematics.joint_placements`), turning
    ``link{i+1}``, with its limits [rad], effort [N m] and velocity [rad/s] (0: none)."""
    lo, hi = robot.qlim[i]
    name = _attr(robot.joint_names[i], robot.source, f"joints[{i}].name")
    return [f'  <joint name="{name}" type="revolute">',
            f'    <parent link="{parent}"/><child link="link{i + 1}"/>',
            f'    {_origin(placement)}<axis xyz="0 0 1"/>',
            f'    <limit lower="{_f(lo)}" upper="{_f(hi)}" effort="{_limit(robot.effort[i])}" '
            f'velocity="{_limit(robot.velocity[i])}"/>',
            '  </joint>']


def _body_link(robot: Robot, i: int, B_i: np.ndarray, end: np.ndarray, radius: float) -> list[str]:
    """``link{i+1}``, the body joint i+1 moves: its inertial and visuals. ``B_i`` ``(4, 4)`` is
    DH frame i+1 in the body, ``end`` ``(3,)`` [m] the next joint's (or the tool's) origin in it."""
    return [f'  <link name="link{i + 1}">',
            _inertial(robot, i, B_i),
            *_link_visuals(_visual_path(robot, i, B_i, end), radius),
            '  </link>']


def _inertial(robot: Robot, i: int, B_i: np.ndarray) -> str:
    """Link i+1's ``<inertial>``: nfarm gives the centre of mass ``c`` [m] and the inertia about
    it [kg m²] in DH frame i+1 = ``B_i`` in the body, so the inertial frame has ``B_i``'s axes
    and its origin at ``B_i · [c; 1]``; mass [kg]."""
    com = B_i @ np.append(robot.com[i], 1.0)
    inertial = B_i.copy()
    inertial[:3, 3] = com[:3]
    I = robot.inertia[i]
    return (f'    <inertial>{_origin(inertial)}<mass value="{_f(robot.mass[i])}"/>'
            f'<inertia ixx="{_f(I[0, 0])}" ixy="{_f(I[0, 1])}" ixz="{_f(I[0, 2])}" '
            f'iyy="{_f(I[1, 1])}" iyz="{_f(I[1, 2])}" izz="{_f(I[2, 2])}"/></inertial>')


def _visual_path(robot: Robot, i: int, B_i: np.ndarray, end: np.ndarray) -> list[np.ndarray]:
    """The points ``(3,)`` [m], in link i+1's frame, of a polyline from joint i+1 to ``end``
    along the DH parameters: standard DH along z by ``d[i]``, then along the new x by ``a[i]``
    to DH frame i+1's origin; modified DH (the next joint at ``Rx(α) Tx(a) Tz(d) Rz(offset)``
    of row i+1) along x by ``a[i+1]``, then along the new z by ``d[i+1]``."""
    if robot.convention == "standard":
        return [np.zeros(3), np.array([0, 0, robot.d[i]]), B_i[:3, 3], end]
    a_next = robot.a[i + 1] if i + 1 < robot.n else 0.0
    return [np.zeros(3), np.array([a_next, 0, 0]), end]


def _prefixed(text: str, prefix: str) -> str:
    """``text`` with ``prefix`` (escaped) before the robot's, every link's and every joint's
    name."""
    if not prefix:
        return text
    return re.sub(r'(<robot name="|<link name="|<joint name="|link=")', lambda m: m[1] + prefix, text)
