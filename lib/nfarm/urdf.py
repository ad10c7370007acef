"""URDF export of a DH chain, so that Pinocchio and rerun load the same robot as nfarm.

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

import numpy as np

from .kinematics import joint_placements
from .robot import Robot
from .rotations import matrix_to_rpy

__all__ = ["to_urdf"]


def _f(x: float) -> str:
    return repr(float(x)) if x != 0 else "0"


def _origin(T: np.ndarray) -> str:
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
    out = [_cylinder(np.array([0, 0, -radius]), np.array([0, 0, radius]), 1.25 * radius)]
    for start, end in zip(points, points[1:]):
        if np.linalg.norm(end - start) > 1e-9:
            out.append(_cylinder(start, end, radius))
    return out


def to_urdf(robot: Robot, *, prefix: str = "", color: tuple[float, float, float] = (0.85, 0.55, 0.15)
            ) -> str:
    """A URDF (XML string) of the chain: revolute joints with limits, inertials, visuals.

    ``prefix`` goes before the robot's, every link's and every joint's name, so that two copies
    of one arm can share a scene (frames are matched by name); ``color`` is the links' RGB."""
    J, B = joint_placements(robot)
    n = robot.n
    size = float(np.sum(np.abs(robot.a)) + np.sum(np.abs(robot.d)))
    radius = 0.04 * max(size, 0.25)  # visuals in proportion, and visible on a tiny chain
    tool = B[-1] @ robot.tool
    lines = ['<?xml version="1.0"?>', f'<robot name="{robot.name}">',
             f'  <material name="link"><color rgba="{" ".join(_f(c) for c in color)} 1"/></material>',
             '  <link name="base_link">',
             _cylinder(np.array([0, 0, -2 * radius]), np.zeros(3), 2 * radius), '  </link>',
             '  <joint name="dh_frame0_fixed" type="fixed">',
             f'    <parent link="base_link"/><child link="dh_frame0"/>{_origin(robot.base)}',
             '  </joint>',
             '  <link name="dh_frame0"/>']
    for i in range(n):
        child = f"link{i + 1}"
        parent = "base_link" if i == 0 else f"link{i}"
        lo, hi = robot.qlim[i]
        lines += [
            f'  <joint name="{robot.joint_names[i]}" type="revolute">',
            f'    <parent link="{parent}"/><child link="{child}"/>',
            f'    {_origin(robot.base @ J[i] if i == 0 else J[i])}<axis xyz="0 0 1"/>',
            f'    <limit lower="{_f(lo)}" upper="{_f(hi)}" effort="0" velocity="0"/>',
            '  </joint>',
        ]
        # Inertial: the centre of mass and inertia are given in DH frame i+1 = B[i] in the body.
        com = B[i] @ np.append(robot.com[i], 1.0)
        inertial = B[i].copy()
        inertial[:3, 3] = com[:3]
        I = robot.inertia[i]
        # Visual path: from the joint to the next joint (or the tool) through the DH frame.
        end = (J[i + 1] if i + 1 < n else tool)[:3, 3]
        if robot.convention == "standard":  # along z by d, then along the new x by a
            path = [np.zeros(3), np.array([0, 0, robot.d[i]]), B[i][:3, 3], end]
        else:  # G = Rx(α) Tx(a) Tz(d) Rz(offset): along x by a, then along the new z by d
            a_next = robot.a[i + 1] if i + 1 < n else 0.0
            path = [np.zeros(3), np.array([a_next, 0, 0]), end]
        lines += [
            f'  <link name="{child}">',
            f'    <inertial>{_origin(inertial)}<mass value="{_f(robot.mass[i])}"/>'
            f'<inertia ixx="{_f(I[0, 0])}" ixy="{_f(I[0, 1])}" ixz="{_f(I[0, 2])}" '
            f'iyy="{_f(I[1, 1])}" iyz="{_f(I[1, 2])}" izz="{_f(I[2, 2])}"/></inertial>',
            *_link_visuals(path, radius),
            '  </link>',
            f'  <joint name="dh_frame{i + 1}_fixed" type="fixed">',
            f'    <parent link="{child}"/><child link="dh_frame{i + 1}"/>{_origin(B[i])}',
            '  </joint>',
            f'  <link name="dh_frame{i + 1}"/>',
        ]
    lines += [
        '  <joint name="tool_fixed" type="fixed">',
        f'    <parent link="link{n}"/><child link="tool"/>{_origin(tool)}',
        '  </joint>',
        '  <link name="tool"/>',
        '</robot>',
    ]
    text = "\n".join(lines) + "\n"
    if prefix:
        text = re.sub(r'(<robot name="|<link name="|<joint name="|link=")', lambda m: m[1] + prefix, text)
    return text
