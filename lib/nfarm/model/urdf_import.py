"""A URDF's serial chain as an nfarm :class:`~nfarm.model.robot.Robot` (:func:`from_urdf`): the
chain from the root link to the tip, the joints off it locked (or following the joint they
mimic), every link's pose at ``q = 0``, the DH table read off the joint axes
(:mod:`.dh_extraction`) and each moving link's inertia, with everything fixed or locked to it,
lumped into one rigid body in its DH frame. The file is read and checked by :mod:`.urdf_parser`,
its tree by :mod:`.urdf_tree`; writing a URDF is :mod:`.urdf_export`'s.

Importing this module registers :func:`from_urdf` as
:func:`~nfarm.model.robot.load_robot`'s reader of ``.urdf`` files (``nfarm.model`` imports it).
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import warnings
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ..infra.arguments import is_number
from ..infra.reading import MAX_BYTES, ParamsError, ParamsWarning, listed, read_bytes
from .dh_extraction import NearParallel, dh_frames, dh_rows, fixed_transforms
from .robot import Robot, register_reader, robot_from_dict, robot_name, with_provenance
from .urdf_parser import MOVING_TYPES, URDFElements, parse_urdf
from .urdf_tree import URDFTree, urdf_tree

__all__ = ["from_urdf", "CONVERTER_VERSION"]


#: Joint types a chain may hold (``fixed`` ones are folded into the geometry).
_CHAIN_TYPES = ("revolute", "fixed")
#: Joint types a side branch may hold: locked at the position ``lock`` gives (default 0).
_LOCKABLE = ("revolute", "continuous", "prismatic", "fixed")
#: The conversion's version, part of a converted robot's hash (:func:`~nfarm.model.robot.robot_hash`
#: hashes a URDF robot by its sources): a conversion that changes makes another robot, whose data
#: sets and models are made anew. 2: nearly parallel axes with fixed transforms, the common
#: normal without cancellation.
CONVERTER_VERSION = 2


def _axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues: rotation by ``angle`` about the unit ``axis``."""
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def from_urdf(path: str | os.PathLike, tip: str | None = None,
              lock: Mapping[str, float] | None = None, *, name: str | None = None,
              max_bytes: int = MAX_BYTES, near_parallel_deg: float = 5.0) -> Robot:
    """The serial chain of a URDF from its root link to ``tip`` as an nfarm :class:`Robot`
    (standard DH, a base and a tool transform).

    Args:
        path: the URDF file.
        tip: the chain's last link (default: the single leaf; several leaves are an error that
            lists them). The tool frame is this link's frame.
        lock: positions [rad or m] of joints off the chain (e.g. a gripper's jaw), default 0.
            A joint off the chain with a ``<mimic>`` follows its driving joint instead: it is
            locked at ``multiplier · q_driver + offset`` (the driver's lock, or its mimic's).
        name: the robot's name (default the URDF's).
        max_bytes: the largest file read [bytes] (checked before reading it).
        near_parallel_deg: consecutive joint axes closer than this [deg] (but not parallel)
            whose common normal lies beyond 10 m are written as parallel DH axes with the tilt
            in a fixed transform after the row (``Robot.fixed``), with one warning naming them.

    The chain holds revolute and fixed joints. At ``q = 0`` each joint axis is a line in the
    world; DH frame i sits on axis i+1 (standard DH, ``z_i`` along it), at the foot of the
    common normal from axis i, ``x_i`` along that normal: for intersecting axes at the
    intersection with ``x_i = z_{i−1} × z_i``, for parallel axes where the normal through the
    previous origin meets it (``d_i = 0``), for one line continuing the previous frame. Nearly
    parallel axes (``near_parallel_deg``) whose normal lies far away are placed as parallel
    ones, the DH row parallel (``alpha_i`` 0 or π) and the tilt in ``fixed[i]``, so the robot
    is the URDF's chain exactly (to rounding) and its DH table stays at the arm's size. Frame 0
    sits on axis 1 where it passes nearest the root's origin, with ``x_0`` along ``x_1`` (so
    ``offset_1 = 0``); frame n at the tip's origin with ``z_n`` along axis n. Every DH row is
    then read off consecutive frames; ``base`` is frame 0 in the root's frame, ``tool`` the tip
    in frame n. Each moving link's inertia, with everything fixed or locked to it (side
    branches, massless frames), becomes one rigid body in its DH frame (parallel axes);
    bodies before joint 1 never move and are left out. Limits, effort and velocity carry over
    (an effort or velocity of 0 means none, as :func:`~nfarm.model.urdf_export.to_urdf` writes it); gravity is
    ``[0, 0, −9.81]`` in the root's frame.

    The file is decoded first (UTF-8, or UTF-16/32 by their marks, or the 8-bit encoding its
    declaration names), then refused if its text holds a DTD or an entity declaration; numbers
    are plain ASCII decimals (``1``, ``-0.25``, ``1.5e-3``: not ``inf``, ``nan``, ``1_0`` or
    other digits).

    Raises:
        ParamsError: one line naming the file, the element and the rule (a prismatic or
            continuous joint on the chain, a mimic joint on the chain — nfarm's arms are serial
            chains of independent joints — a closed loop, a missing link, a malformed number,
            a negative effort…).

    Warns:
        ParamsWarning: nearly parallel consecutive axes (``near_parallel_deg``) written with a
            fixed transform, once per pair, naming the joints, the angle and the transform.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> so101 = from_urdf(PARAMS / "robots" / "so101" / "so101.urdf", tip="gripper_frame_link",
        ...                   lock={"gripper": 0.0})     # the jaw, off the chain, closed
        >>> so101
        Robot('so101_new_calib', standard DH, n=5, source='params/robots/so101/so101.urdf')
        >>> so101.a.round(4).tolist()     # [m]
        [0.0304, 0.116, 0.135, 0.0, 0.0079]
    """
    path = Path(path)
    raw = read_bytes(path, max_bytes=max_bytes, what="URDF")
    r = URDFElements(str(path), parse_urdf(path, raw))
    # The robot's name names directories and files (data sets, models, recordings): the URDF's
    # own, when no other is given, obeys a robot file's rule.
    if name is not None:
        robot_name(name, str(path), "name")
    else:
        robot_name(r.name, str(path), "<robot name>", ": name the robot in a robot file that names "
                   "this URDF (params/README.md), or add it with add-arm --name")
    tree = urdf_tree(r)
    tip, chain, moving = _chain(r, tree, tip)
    lock = _locks(r, chain, lock)
    pose = _world_poses(r, tree, chain, _mimic_positions(r, chain, lock))
    axes = _joint_axes(r, pose, moving)
    frames, near = dh_frames(axes, pose[tip][:3, 3], near_parallel_deg)
    rows = dh_rows(frames, [pair.k for pair in near])
    bodies = _link_bodies(r, tree, pose, frames, moving)
    _near_parallel(r.v.source, moving, near)
    robot = _build_robot(str(path), name or r.name, f"from {path.name}, chain {tree.root} → {tip}",
                         frames, pose[tip], rows, bodies, fixed_transforms(frames, rows))
    how = json.dumps({"tip": tip, "lock": lock, "name": name, "converter": CONVERTER_VERSION},
                     sort_keys=True).encode("utf-8")
    return with_provenance(robot, raw, how)


def _chain(r: URDFElements, tree: URDFTree, tip: str | None) -> tuple[str, list[str], list[str]]:
    """The tip (the single leaf when not named), the joints from the root to it and the
    revolute ones among them; only revolute and fixed joints may lie on the chain."""
    v = r.v
    leaves = sorted(l for l in r.links if not tree.children[l])
    if tip is None:
        if len(leaves) != 1:
            v.fail("tip", f"the URDF has {len(leaves)} leaf links ({listed(leaves)}): name the "
                          f"chain's last link")
        tip = leaves[0]
    elif tip not in r.links:
        v.fail("tip", f"no link {tip!r} in the URDF (leaves: {listed(leaves)})")
    chain, link = [], tip                       # joint names from the root to the tip
    while link != tree.root:
        chain.append(tree.parent_joint[link])
        link = r.joints[chain[-1]]["parent"]
    chain.reverse()
    for jname in chain:
        kind = r.joints[jname]["type"]
        if kind not in _CHAIN_TYPES:
            v.fail(f"joint {jname!r}", f"type {kind!r} on the chain to {tip!r}: only revolute and "
                                       f"fixed joints are supported there")
    moving = [j for j in chain if r.joints[j]["type"] == "revolute"]
    if not moving:
        v.fail("tip", f"the chain from {tree.root!r} to {tip!r} has no revolute joint")
    return tip, chain, moving


def _locks(r: URDFElements, chain: list[str], lock: Mapping[str, float] | None) -> dict[str, float]:
    """The positions of joints off the chain: finite numbers of joints that exist, not on it."""
    v = r.v
    lock = dict(lock or {})
    for jname, value in lock.items():
        if not is_number(value, numpy=False) or not np.isfinite(value):
            v.fail(f"lock.{jname}", f"must be a finite number, got {value!r}")
        if jname not in r.joints:
            v.fail(f"lock.{jname}", "names no joint of the URDF")
        if jname in chain:
            v.fail(f"lock.{jname}", "is on the chain: only joints off it are locked")
        if r.joints[jname]["mimic"] is not None:
            v.fail(f"lock.{jname}", f"joint {jname!r} mimics joint {r.joints[jname]['mimic'][0]!r}: "
                                    f"it follows that joint; lock that one instead")
    return lock


def _mimic_positions(r: URDFElements, chain: list[str], lock: Mapping[str, float]) -> dict[str, float]:
    """``lock`` and the position of every mimic joint off the chain, ``multiplier · q + offset``
    of its driving joint's ``q`` (the driver's lock, 0 by default, or its own mimic position).
    A mimic joint on the chain (one joint driving two), or a side joint driven by one on the
    chain, is refused: nfarm's arms are serial chains of independent joints."""
    v = r.v
    mimics = {jname: j["mimic"] for jname, j in r.joints.items() if j["mimic"] is not None}
    for jname, (driver, _, _) in mimics.items():
        at = f"joint {jname!r} <mimic joint>"
        if driver not in r.joints:
            v.fail(at, f"names a joint that does not exist: {driver!r}")
        if r.joints[driver]["type"] not in MOVING_TYPES:
            v.fail(at, f"names joint {driver!r} of type {r.joints[driver]['type']!r}, which does "
                       f"not move")
        if jname in chain:
            v.fail(f"joint {jname!r}", f"mimics joint {driver!r} but lies on the chain: mimic "
                                       f"joints on the chain (one joint driving two) are not "
                                       f"supported; nfarm's arms are chains of independent joints")
        if driver in chain:
            v.fail(f"joint {jname!r}", f"mimics joint {driver!r}, which lies on the chain: a side "
                                       f"joint moved by the chain is not supported (it can only "
                                       f"be locked)")
    positions = dict(lock)
    for jname in mimics:
        trail = [jname]                 # the joint, its driver, the driver's driver…
        while trail[-1] in mimics and trail[-1] not in positions:
            driver = mimics[trail[-1]][0]
            if driver in trail:
                v.fail(f"joint {jname!r} <mimic joint>",
                       f"mimic joints drive each other in a loop: {_trail(trail + [driver])}")
            trail.append(driver)
        value = float(positions.get(trail[-1], 0.0))
        for follower in reversed(trail[:-1]):
            _, multiplier, offset = mimics[follower]
            driven = multiplier * value + offset
            if not math.isfinite(driven):
                v.fail(f"joint {follower!r} <mimic>", f"its position {multiplier!r} · "
                                                      f"{value!r} + {offset!r} is not finite")
            positions[follower] = value = driven
    return positions


def _trail(names: list[str]) -> str:
    """A path of joints for a message: all of a short one, the ends of a long one."""
    shown = names if len(names) <= 8 else [*names[:4], f"… {len(names) - 7} more …", *names[-3:]]
    return " → ".join(shown)


def _world_poses(r: URDFElements, tree: URDFTree, chain: list[str], lock: Mapping[str, float]
                 ) -> dict[str, np.ndarray]:
    """Every link's pose ``(4, 4)`` in the root's frame at ``q = 0``, the joints off the chain
    at their lock positions (a revolute joint turned about its axis, a prismatic one slid
    along it): ``T_child = T_parent · origin · motion``."""
    pose = {tree.root: np.eye(4)}
    for link in tree.order:
        for jname in tree.children[link]:
            j = r.joints[jname]
            T = pose[link] @ j["origin"]
            value = float(lock.get(jname, 0.0)) if jname not in chain else 0.0
            if j["type"] in ("revolute", "continuous") and value:
                T[:3, :3] = T[:3, :3] @ _axis_rotation(j["axis"], value)
            elif j["type"] == "prismatic" and value:
                T[:3, 3] += T[:3, :3] @ j["axis"] * value
            elif j["type"] not in _LOCKABLE:
                r.v.fail(f"joint {jname!r}", f"type {j['type']!r} cannot be locked off the chain")
            pose[j["child"]] = T
    return pose


def _joint_axes(r: URDFElements, pose: Mapping[str, np.ndarray], moving: list[str]
                ) -> list[tuple[np.ndarray, np.ndarray]]:
    """Each revolute joint's axis as a line in the root's frame: a point ``(3,)`` [m] (the
    joint frame's origin) and the unit direction ``(3,)``."""
    axes = []
    for jname in moving:
        T = pose[r.joints[jname]["parent"]] @ r.joints[jname]["origin"]
        axes.append((T[:3, 3], T[:3, :3] @ r.joints[jname]["axis"]))
    return axes


def _link_bodies(r: URDFElements, tree: URDFTree, pose: Mapping[str, np.ndarray], frames: list[np.ndarray],
                 moving: list[str]) -> list[dict]:
    """Each revolute joint's moving body: its child link with everything fixed or locked to it
    (side branches, massless frames) lumped into one rigid body in its DH frame (mass [kg],
    centre of mass [m], inertia about it [kg m²] by the parallel-axis theorem), with the
    joint's name, limits, effort and velocity. Links before joint 1 never move: left out."""
    owner, index = {}, {jname: k for k, jname in enumerate(moving)}
    for link in tree.order:
        if link == tree.root:
            continue
        jname = tree.parent_joint[link]
        owner[link] = index[jname] if jname in index else owner.get(r.joints[jname]["parent"])
    bodies = [[] for _ in moving]
    for link, k in owner.items():
        if k is None or r.links[link] is None:
            continue
        mass, T_in, I = r.links[link]
        G = np.linalg.solve(frames[k + 1], pose[link] @ T_in)    # inertial frame in DH frame k
        bodies[k].append((mass, G[:3, 3], G[:3, :3] @ I @ G[:3, :3].T))
    joints = []
    for k, jname in enumerate(moving):
        m, com, I = _lump(bodies[k])
        j = r.joints[jname]
        joints.append({"name": jname, "qlim": list(j["limits"]), "mass": m, "com": com.tolist(),
                       "inertia": [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[1, 2], I[0, 2]],
                       **{key: j[key] for key in ("effort", "velocity") if j[key] > 0}})
    return joints


def _lump(bodies: list[tuple[float, np.ndarray, np.ndarray]]) -> tuple[float, np.ndarray, np.ndarray]:
    """One rigid body from bodies ``(mass [kg], centre of mass (3,) [m], inertia about it
    (3, 3) [kg m²])`` given in one frame: ``m = Σ m_k``, ``c = Σ m_k c_k / m`` and, by the
    parallel-axis theorem, ``I = Σ I_k + m_k (|r_k|² 1 − r_k r_kᵀ)`` with ``r_k = c_k − c``.
    No bodies: zero mass, centre and inertia; all massless: ``c`` the first body's."""
    m = sum(b[0] for b in bodies)
    if not bodies:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    # Massless bodies keep their rotational inertia (the Puma's first link is one).
    com = sum(b[0] * b[1] for b in bodies) / m if m > 0 else bodies[0][1]
    I = np.zeros((3, 3))
    for mass, c, Ic in bodies:
        r = c - com
        I += Ic + mass * (r @ r * np.eye(3) - np.outer(r, r))
    return m, com, I


def _near_parallel(source: str, moving: list[str], near: list[NearParallel]) -> None:
    """Warn once, in one line, for each pair of nearly parallel consecutive axes
    (:func:`dh_frames`) written as parallel DH axes with the tilt in a fixed transform."""
    for pair in near:
        k = pair.k
        warnings.warn(ParamsWarning(
            f"{source}: joints {moving[k]!r} and {moving[k + 1]!r}: axes nearly parallel, "
            f"{pair.angle:.3g}° apart: written as parallel DH axes with the tilt in "
            f"joints[{k}].fixed (their common normal lies {pair.distance:.4g} m away); make the "
            f"axes exactly parallel if they are meant to be"), stacklevel=3)


def _build_robot(source: str, name: str, description: str, frames: list[np.ndarray],
                 T_tip: np.ndarray, rows: list[dict], bodies: list[dict],
                 fixed: list[np.ndarray] | None = None) -> Robot:
    """The standard-DH :class:`Robot` from link frames ``F_0..F_n`` (each ``(4, 4)``, in the
    root's frame), the tip's pose ``T_tip`` ``(4, 4)``, each joint's DH row and body and the
    fixed transforms after the rows (``None``: none): ``base = F_0``, ``tool = F_n⁻¹ · T_tip``
    (by a linear solve), gravity ``[0, 0, −9.81]`` m/s² in the root's frame. A robot file's
    checks apply; their errors say the robot was converted."""
    tool = np.linalg.solve(frames[-1], T_tip)
    joints = [{**row, **body} for row, body in zip(rows, bodies)]
    if fixed is not None:
        for joint, E in zip(joints, fixed):
            if not np.array_equal(E, np.eye(4)):
                joint["fixed"] = E.tolist()
    try:
        # A URDF's name is any text; a robot file's must name directories (ROBOT_NAME): the
        # file's checks run under a plain name, and the robot keeps its URDF's.
        robot = robot_from_dict({"name": "urdf", "convention": "standard",
                                 "gravity": [0.0, 0.0, -9.81], "base": frames[0].tolist(),
                                 "tool": tool.tolist(), "joints": joints,
                                 "description": description}, source=source)
        return dataclasses.replace(robot, name=name)
    except ParamsError as exc:
        raise ParamsError(f"{exc} (converted from the URDF)") from None


register_reader(".urdf", from_urdf)
