"""The kinematic tree a URDF's links and joints form, checked (every named link exists, no link
has two parents, one root, every link connected to it: :func:`urdf_tree`), and its outline with
each joint's limits, mimic and drive values (:func:`urdf_outline`): what a robot file's ``tip``,
``lock`` and ``drive`` are chosen from (:mod:`nfarm.study.add_arm`). The elements are read and
checked by :mod:`.urdf_parser`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from ..infra.reading import MAX_BYTES, listed, read_bytes
from ..infra.typed import DRIVE, EFFORT, LENGTH, VELOCITY
from .urdf_parser import MOVING_TYPES, URDFElements, parse_urdf

__all__ = ["urdf_tree", "URDFTree", "urdf_outline", "URDFOutline", "URDFJoint"]


@dataclass(frozen=True)
class URDFTree:
    """The URDF's kinematic tree: its root link, every link with parents before children,
    each link's child joints and each child link's parent joint (made by
    :func:`urdf_tree`, which has an example)."""

    root: str
    order: list[str]
    children: dict[str, list[str]]
    parent_joint: dict[str, str]


def urdf_tree(r: URDFElements) -> URDFTree:
    """Check that the links and joints form one tree (every named link exists, no link has two
    parents, one root, every link connected to it) and return it.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> path = PARAMS / "robots" / "so101" / "so101.urdf"
        >>> tree = urdf_tree(URDFElements(str(path), parse_urdf(path, path.read_bytes())))
        >>> tree.root, tree.children["base_link"], tree.parent_joint["gripper_frame_link"]
        ('base_link', ['shoulder_pan'], 'gripper_frame_joint')
    """
    v = r.v
    children: dict[str, list[str]] = {name_: [] for name_ in r.links}
    parent_joint: dict[str, str] = {}
    for jname, j in r.joints.items():
        for key in ("parent", "child"):
            if j[key] not in r.links:
                v.fail(f"joint {jname!r} <{key} link>", f"names a link that does not exist: {j[key]!r}")
        if j["child"] in parent_joint:
            v.fail(f"joint {jname!r}", f"link {j['child']!r} already has parent joint "
                                       f"{parent_joint[j['child']]!r}: a closed loop, not a tree")
        parent_joint[j["child"]] = jname
        children[j["parent"]].append(jname)
    roots = [l for l in r.links if l not in parent_joint]
    if len(roots) != 1:
        v.fail("<robot>", f"must have one root link, got {len(roots)}: {listed(roots) or 'none (a loop)'}")
    root = roots[0]
    order = [root]                              # links, parents before children
    for link in order:
        order += [r.joints[jname]["child"] for jname in children[link]]
    if len(order) != len(r.links):
        v.fail("<robot>", f"links not connected to the root {root!r} (a loop): "
                          f"{listed(sorted(set(r.links) - set(order)))}")
    return URDFTree(root, order, children, parent_joint)


@dataclass(frozen=True)
class URDFJoint:
    """One joint of a URDF as :func:`urdf_outline`, which has an example, reads it: its
    ``type``, ``parent`` and ``child`` links, ``limits`` ``(lo, hi)`` [rad or m] (``None`` when
    the file gives none: a continuous or fixed joint), ``mimic`` ``(driver, multiplier,
    offset)`` or ``None``, and the drive values the file gives (0 where it gives none):
    ``effort`` [N·m or N], ``velocity`` [rad/s or m/s] (``<limit>``), ``damping``
    [N·m·s/rad] and ``friction`` [N·m] (``<dynamics>``)."""

    name: str
    type: str
    parent: str
    child: str
    limits: tuple[float, float] | None
    mimic: tuple[str, float, float] | None
    effort: float = 0.0
    velocity: float = 0.0
    damping: float = 0.0
    friction: float = 0.0


@dataclass(frozen=True)
class URDFOutline:
    """A URDF's tree, validated as :func:`~nfarm.model.urdf_import.from_urdf` validates it, before any chain is chosen
    (made by :func:`urdf_outline`, which has an example): the robot's ``name``, the ``root``
    link, the ``leaves`` (sorted), every joint by name and each child link's parent joint."""

    source: str
    name: str
    root: str
    leaves: tuple[str, ...]
    joints: dict[str, URDFJoint]
    parent_joint: dict[str, str]

    def chain(self, tip: str) -> list[str]:
        """The joints from the root link to link ``tip``, root first."""
        out, link = [], tip
        while link != self.root:
            out.append(self.parent_joint[link])
            link = self.joints[out[-1]].parent
        return out[::-1]


def urdf_outline(path: str | os.PathLike, *, max_bytes: int = MAX_BYTES) -> URDFOutline:
    """The tree of a URDF, read and checked as :func:`~nfarm.model.urdf_import.from_urdf` reads it (one-line
    :class:`ParamsError` naming the file and the element), with each joint's limits, mimic and
    drive values: what a robot file's ``tip``, ``lock`` and ``drive`` are chosen from.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> outline = urdf_outline(PARAMS / "robots" / "so101" / "so101.urdf")
        >>> outline.root, outline.leaves
        ('base_link', ('gripper_frame_link', 'moving_jaw_so101_v1_link'))
        >>> [j for j in outline.chain("gripper_frame_link") if outline.joints[j].type == "revolute"]
        ['shoulder_pan', 'shoulder_lift', 'elbow_flex', 'wrist_flex', 'wrist_roll']
        >>> outline.joints["gripper"].limits, outline.joints["gripper"].effort
        ((-0.174533, 1.74533), 10.0)
    """
    path = Path(path)
    raw = read_bytes(path, max_bytes=max_bytes, what="URDF")
    root_element = parse_urdf(path, raw)
    r = URDFElements(str(path), root_element)
    tree = urdf_tree(r)
    elements = {el.get("name"): el for el in root_element.findall("joint")}
    joints = {}
    for jname, j in r.joints.items():
        el, at = elements[jname], f"joint {jname!r}"
        limits = j.get("limits")
        limit = el.find("limit")
        values = {}
        if j["type"] == "prismatic" and limit is not None:
            lo = r.numbers(limit.get("lower", "0"), f"{at} <limit lower>", 1, bound=LENGTH)[0]
            hi = r.numbers(limit.get("upper", "0"), f"{at} <limit upper>", 1, bound=LENGTH)[0]
            limits = (lo, hi) if lo < hi else None
        if j["type"] in MOVING_TYPES and limit is not None:
            for key in ("effort", "velocity"):
                values[key] = float(r.numbers(limit.get(key, "0"), f"{at} <limit {key}>", 1)[0])
        dynamics = el.find("dynamics")
        if j["type"] in MOVING_TYPES and dynamics is not None:
            for key in ("damping", "friction"):
                values[key] = float(r.numbers(dynamics.get(key, "0"), f"{at} <dynamics {key}>", 1)[0])
        for key, x in values.items():       # beyond its bound, a positive value (others mean none)
            if x > 0:
                bound = {"effort": EFFORT, "velocity": VELOCITY}.get(key, DRIVE)
                where = f"{at} <{'limit' if key in ('effort', 'velocity') else 'dynamics'} {key}>"
                bound.check(r.v, x, where)
        values = {k: x if x > 0 else 0.0 for k, x in values.items()}
        joints[jname] = URDFJoint(jname, j["type"], j["parent"], j["child"],
                                  None if limits is None else (float(limits[0]), float(limits[1])),
                                  j["mimic"], **values)
    leaves = tuple(sorted(link for link in r.links if not tree.children[link]))
    return URDFOutline(str(path), r.name, tree.root, leaves, joints, dict(tree.parent_joint))
