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

import codecs
import dataclasses
import json
import math
import os
import re
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import escape

import numpy as np

from ..infra.reading import MAX_BYTES, ParamsError, ParamsWarning, Validator, listed, read_bytes, show
from ..infra.typed import ANGLE, DRIVE, EFFORT, INERTIA, LENGTH, MASS, VELOCITY, Range
from .kinematics import dh_transform, joint_placements
from .robot import MAX_PLAUSIBLE_LENGTH, Robot, register_reader, robot_from_dict, robot_name, with_provenance
from .rotations import matrix_to_rpy

__all__ = ["to_urdf", "from_urdf", "urdf_outline"]


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


# --------------------------------------------------------------------------------------------
# Reading: a URDF's serial chain as a DH robot

#: Joint types a chain may hold (``fixed`` ones are folded into the geometry).
_CHAIN_TYPES = ("revolute", "fixed")
#: Joint types a side branch may hold: locked at the position ``lock`` gives (default 0).
_LOCKABLE = ("revolute", "continuous", "prismatic", "fixed")
#: Joint types that move (about or along their axis), and so may mimic or be mimicked.
_MOVING = ("revolute", "continuous", "prismatic")
#: A URDF number: plain ASCII decimal, optionally with an exponent (no ``inf``, ``nan``, ``_``,
#: hexadecimal or non-ASCII digits, all of which Python's ``float`` accepts).
_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?\Z")
#: XML's white space, which separates the numbers of a list.
_SPACE = re.compile(r"[ \t\n\r]+")
#: Axes closer than this (the sine of their angle) are parallel; lines closer than
#: ``_NEAR`` metres intersect.
_PARALLEL = 1e-9
_NEAR = 1e-12
#: The conversion's version, part of a converted robot's hash (:func:`~nfarm.model.robot.robot_hash`
#: hashes a URDF robot by its sources): a conversion that changes makes another robot, whose data
#: sets and models are made anew. 2: nearly parallel axes with fixed transforms, the common
#: normal without cancellation.
CONVERTER_VERSION = 2


def _rpy_matrix(r: float, p: float, y: float) -> np.ndarray:
    """URDF's fixed-axis roll, pitch, yaw: ``Rz(y) · Ry(p) · Rx(r)``."""
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues: rotation by ``angle`` about the unit ``axis``."""
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


class _Reader:
    """The URDF's elements, validated, with one-line errors naming the file and element."""

    def __init__(self, source: str, root):
        self.v = Validator(source)
        if root.tag != "robot":
            self.v.fail("<robot>", f"the root element must be <robot>, got <{root.tag}>")
        self.name = root.get("name") or "urdf_robot"
        self.links, self.joints = {}, {}
        for link in root.findall("link"):
            name = self._name(link, "link")
            if name in self.links:
                self.v.fail(f"link {name!r}", "is defined twice")
            self.links[name] = self._inertial(link, f"link {name!r}")
        for joint in root.findall("joint"):
            name = self._name(joint, "joint")
            if name in self.joints:
                self.v.fail(f"joint {name!r}", "is defined twice")
            self.joints[name] = self._joint(joint, f"joint {name!r}")
        if not self.links:
            self.v.fail("<robot>", "has no <link>")

    def _name(self, element, kind: str) -> str:
        name = element.get("name")
        if not name:
            self.v.fail(f"<{kind}>", "needs a non-empty name attribute")
        return name

    def _numbers(self, text, at: str, count: int, default=None, bound: Range | None = None) -> np.ndarray:
        """``count`` numbers of URDF's grammar (:data:`_NUMBER`, separated by XML white
        space), each finite and within the plausibility ``bound`` (:mod:`nfarm.infra.typed`; a
        0 of a drive limit is "none", outside its bound)."""
        if text is None:
            if default is None:
                self.v.fail(at, "is required")
            return np.array(default, dtype=float)
        what = "a finite number" if count == 1 else f"{count} finite numbers"
        words = _SPACE.split(text.strip(" \t\n\r")) if text.strip(" \t\n\r") else []
        for word in words[:count + 1]:
            if not _NUMBER.match(word):
                self.v.fail(at, f"must be {what}, got {show(text)}: {show(word)} is not a plain "
                                f"decimal number (ASCII digits, a point, an exponent)")
        if len(words) != count:
            self.v.fail(at, f"must be {what}, got {show(text)}")
        values = np.array([float(x) for x in words])
        if not np.isfinite(values).all():
            self.v.fail(at, f"must be {what}, got {show(text)}")
        if bound is not None:
            for x in values:
                if not (x == 0 and bound in (VELOCITY, EFFORT)):
                    bound.check(self.v, float(x), at)
        return values

    def _origin(self, element, at: str) -> np.ndarray:
        T = np.eye(4)
        origin = element.find("origin")
        if origin is not None:
            xyz = self._numbers(origin.get("xyz"), f"{at} <origin xyz>", 3, (0, 0, 0), LENGTH)
            rpy = self._numbers(origin.get("rpy"), f"{at} <origin rpy>", 3, (0, 0, 0), ANGLE)
            T[:3, :3], T[:3, 3] = _rpy_matrix(*rpy), xyz
        return T

    def _inertial(self, link, at: str):
        inertial = link.find("inertial")
        if inertial is None:
            return None
        mass_el = inertial.find("mass")
        mass = self._numbers(None if mass_el is None else mass_el.get("value"),
                             f"{at} <inertial><mass value>", 1)[0]
        if mass >= 0:
            MASS.check(self.v, float(mass), f"{at} <inertial><mass value>")
        if mass < 0:
            self.v.fail(f"{at} <inertial><mass value>", f"must be >= 0, got {float(mass)!r}")
        el = inertial.find("inertia")
        keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
        values = {k: self._numbers(None if el is None else el.get(k, "0"),
                                   f"{at} <inertial><inertia {k}>", 1, bound=INERTIA)[0] for k in keys}
        I = np.array([[values["ixx"], values["ixy"], values["ixz"]],
                      [values["ixy"], values["iyy"], values["iyz"]],
                      [values["ixz"], values["iyz"], values["izz"]]])
        if np.linalg.eigvalsh(I).min() < -1e-9 * max(np.abs(I).max(), 1e-300):
            self.v.fail(f"{at} <inertial><inertia>", "must be positive semi-definite")
        T = self._origin(inertial, f"{at} <inertial>")
        return mass, T, I          # inertia about the centre of mass, axes of T

    def _joint(self, joint, at: str) -> dict:
        kind = joint.get("type")
        parent, child = joint.find("parent"), joint.find("child")
        out = {"type": kind, "origin": self._origin(joint, at),
               "parent": None if parent is None else parent.get("link"),
               "child": None if child is None else child.get("link")}
        for key in ("parent", "child"):
            if not out[key]:
                self.v.fail(f"{at} <{key} link>", "is required")
        text = None if joint.find("axis") is None else joint.find("axis").get("xyz")
        axis = self._numbers(text, f"{at} <axis xyz>", 3, (1, 0, 0))       # URDF's default axis
        if kind in _MOVING:
            with np.errstate(over="ignore"):
                norm = float(np.linalg.norm(axis))
            if not np.isfinite(norm):
                self.v.fail(f"{at} <axis xyz>", f"its length overflows, got {show(text)}: give a "
                                                f"direction of moderate size, such as a unit vector")
            if norm < 1e-12:
                self.v.fail(f"{at} <axis xyz>", f"must not be the zero vector (length below 1e-12), "
                                                f"got {show(text)}")
            axis = axis / norm
        out["axis"] = axis
        out["mimic"] = self._mimic(joint, at, kind)
        limit = joint.find("limit")
        if kind == "revolute":
            if limit is None:
                self.v.fail(f"{at} <limit>", "is required for a revolute joint")
            lo = self._numbers(limit.get("lower", "0"), f"{at} <limit lower>", 1)[0]
            hi = self._numbers(limit.get("upper", "0"), f"{at} <limit upper>", 1)[0]
            if not lo < hi:
                self.v.fail(f"{at} <limit>", f"must satisfy lower < upper, got "
                                             f"[{float(lo)!r}, {float(hi)!r}]")
            out["limits"] = (lo, hi)
            for key in ("effort", "velocity"):      # 0: none given (what to_urdf writes for none)
                out[key] = self._numbers(limit.get(key), f"{at} <limit {key}>", 1)[0]
                if out[key] < 0:
                    self.v.fail(f"{at} <limit {key}>", f"must be > 0 (or 0 for no limit), got "
                                                       f"{show(limit.get(key))}")
                if out[key] > 0:
                    (EFFORT if key == "effort" else VELOCITY).check(self.v, float(out[key]), f"{at} <limit {key}>")
        return out

    def _mimic(self, joint, at: str, kind: str) -> tuple[str, float, float] | None:
        """A joint's ``<mimic joint= multiplier= offset=>`` (defaults 1 and 0): its position is
        ``multiplier · q_joint + offset``; only a moving joint may mimic."""
        mimic = joint.find("mimic")
        if mimic is None:
            return None
        if kind not in _MOVING:
            self.v.fail(f"{at} <mimic>", f"a {kind!r} joint cannot mimic another: only revolute, "
                                         f"continuous and prismatic joints move")
        driver = mimic.get("joint")
        if not driver:
            self.v.fail(f"{at} <mimic joint>", "is required")
        multiplier = self._numbers(mimic.get("multiplier"), f"{at} <mimic multiplier>", 1, (1.0,))[0]
        offset = self._numbers(mimic.get("offset"), f"{at} <mimic offset>", 1, (0.0,))[0]
        return driver, float(multiplier), float(offset)


#: Byte-order marks and, without one, the first bytes of ``<`` or ``<?`` (XML 1.0, appendix F):
#: the encodings not compatible with ASCII, told apart before anything is read.
_BOMS = ((b"\xef\xbb\xbf", "utf-8"), (b"\xff\xfe\x00\x00", "utf-32-le"),
         (b"\x00\x00\xfe\xff", "utf-32-be"), (b"\xff\xfe", "utf-16-le"), (b"\xfe\xff", "utf-16-be"))
_WIDE = ((b"\x00\x00\x00<", "utf-32-be"), (b"<\x00\x00\x00", "utf-32-le"),
         (b"\x00<", "utf-16-be"), (b"<\x00", "utf-16-le"))
#: The encoding an ASCII-compatible document declares in ``<?xml … encoding="…"?>``.
_DECLARED = re.compile(rb"""<\?xml[ \t\r\n]+version[ \t\r\n]*=[ \t\r\n]*["'][^"']*["']"""
                       rb"""[ \t\r\n]+encoding[ \t\r\n]*=[ \t\r\n]*["']([^"']*)["']""")
#: Encodings read (Python's codec names): Unicode, ASCII and the ISO and Windows 8-bit pages.
_ENCODINGS = re.compile(r"utf[-_]8|utf[-_](?:16|32)(?:[-_][bl]e)?|ascii|latin[-_]1|iso8859[-_]\d+"
                        r"|cp125\d")
#: A document type or entity declaration (only ever in a DTD).
_DECLARATION = re.compile(r"<!(?:DOCTYPE|ENTITY)", re.IGNORECASE)


def _decode(path: Path, raw: bytes) -> str:
    """The URDF's text: UTF-16 or UTF-32 by their byte-order mark or first bytes, UTF-8 by its
    mark, else the encoding the XML declaration names (default UTF-8)."""
    for mark, encoding in _BOMS:
        if raw.startswith(mark):
            raw = raw[len(mark):]
            break
    else:
        for start, encoding in _WIDE:
            if raw.startswith(start):
                break
        else:
            declared = _DECLARED.match(raw)
            encoding = declared[1].decode("ascii", "replace") if declared else "utf-8"
            try:
                known = codecs.lookup(encoding).name
            except (LookupError, ValueError):
                known = ""
            if not _ENCODINGS.fullmatch(known):
                raise ParamsError(f"{path}: encoding {show(encoding)} (its XML declaration) is "
                                  f"not read: save the URDF as UTF-8")
    try:
        return raw.decode(encoding)
    except UnicodeDecodeError as exc:
        raise ParamsError(f"{path}: not {encoding} text at byte {exc.start}: is it a binary "
                          f"file, or in another encoding than it declares?") from None


def _parse(path: Path, raw: bytes):
    """The URDF's root element: decoded (:func:`_decode`), then no DTD in the text (so no
    entity expansion, whatever the encoding), well-formed. The parser reads exactly the text
    checked: its UTF-8, whatever the document declares."""
    import xml.etree.ElementTree as ET

    text = _decode(path, raw)
    if _DECLARATION.search(text):
        raise ParamsError(f"{path}: <!DOCTYPE>/<!ENTITY> declarations are not accepted in a URDF")
    parser = ET.XMLParser(encoding="utf-8")
    try:
        parser.feed(text.encode("utf-8", "surrogatepass"))
        return parser.close()
    except ET.ParseError as exc:
        line, column = exc.position
        raise ParamsError(f"{path}: not well-formed XML at line {line}, column {column + 1}") from None


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
    (an effort or velocity of 0 means none, as :func:`to_urdf` writes it); gravity is
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
    r = _Reader(str(path), _parse(path, raw))
    # The robot's name names directories and files (data sets, models, recordings): the URDF's
    # own, when no other is given, obeys a robot file's rule.
    if name is not None:
        robot_name(name, str(path), "name")
    else:
        robot_name(r.name, str(path), "<robot name>", ": name the robot in a robot file that names "
                   "this URDF (params/README.md), or add it with add-arm --name")
    tree = _tree(r)
    tip, chain, moving = _chain(r, tree, tip)
    lock = _locks(r, chain, lock)
    pose = _world_poses(r, tree, chain, _mimic_positions(r, chain, lock))
    axes = _joint_axes(r, pose, moving)
    frames, near = _dh_frames(axes, pose[tip][:3, 3], near_parallel_deg)
    rows = _dh_rows(frames, [pair.k for pair in near])
    bodies = _link_bodies(r, tree, pose, frames, moving)
    _near_parallel(r.v.source, moving, near)
    robot = _build_robot(str(path), name or r.name, f"from {path.name}, chain {tree.root} → {tip}",
                         frames, pose[tip], rows, bodies, _fixed_transforms(frames, rows))
    how = json.dumps({"tip": tip, "lock": lock, "name": name, "converter": CONVERTER_VERSION},
                     sort_keys=True).encode("utf-8")
    return with_provenance(robot, raw, how)


@dataclass(frozen=True)
class _Tree:
    """The URDF's kinematic tree: its root link, every link with parents before children,
    each link's child joints and each child link's parent joint."""

    root: str
    order: list[str]
    children: dict[str, list[str]]
    parent_joint: dict[str, str]


def _tree(r: _Reader) -> _Tree:
    """Check that the links and joints form one tree (every named link exists, no link has two
    parents, one root, every link connected to it) and return it."""
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
    return _Tree(root, order, children, parent_joint)


def _chain(r: _Reader, tree: _Tree, tip: str | None) -> tuple[str, list[str], list[str]]:
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


def _locks(r: _Reader, chain: list[str], lock: Mapping[str, float] | None) -> dict[str, float]:
    """The positions of joints off the chain: finite numbers of joints that exist, not on it."""
    v = r.v
    lock = dict(lock or {})
    for jname, value in lock.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
            v.fail(f"lock.{jname}", f"must be a finite number, got {value!r}")
        if jname not in r.joints:
            v.fail(f"lock.{jname}", "names no joint of the URDF")
        if jname in chain:
            v.fail(f"lock.{jname}", "is on the chain: only joints off it are locked")
        if r.joints[jname]["mimic"] is not None:
            v.fail(f"lock.{jname}", f"joint {jname!r} mimics joint {r.joints[jname]['mimic'][0]!r}: "
                                    f"it follows that joint; lock that one instead")
    return lock


def _mimic_positions(r: _Reader, chain: list[str], lock: Mapping[str, float]) -> dict[str, float]:
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
        if r.joints[driver]["type"] not in _MOVING:
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


def _world_poses(r: _Reader, tree: _Tree, chain: list[str], lock: Mapping[str, float]
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


def _joint_axes(r: _Reader, pose: Mapping[str, np.ndarray], moving: list[str]
                ) -> list[tuple[np.ndarray, np.ndarray]]:
    """Each revolute joint's axis as a line in the root's frame: a point ``(3,)`` [m] (the
    joint frame's origin) and the unit direction ``(3,)``."""
    axes = []
    for jname in moving:
        T = pose[r.joints[jname]["parent"]] @ r.joints[jname]["origin"]
        axes.append((T[:3, 3], T[:3, :3] @ r.joints[jname]["axis"]))
    return axes


@dataclass(frozen=True)
class _NearParallel:
    """Consecutive axes ``k`` and ``k + 1`` (0-based) nearly parallel: ``angle`` [deg] apart,
    their common normal ``distance`` [m] from the previous frame's origin."""

    k: int
    angle: float
    distance: float


def _dh_frames(axes: list[tuple[np.ndarray, np.ndarray]], p_tip: np.ndarray,
               near_parallel_deg: float = 5.0) -> tuple[list[np.ndarray], list[_NearParallel]]:
    """The link frames ``F_0..F_n`` (each ``(4, 4)``, in the root's frame) from the ``n`` joint
    axes at ``q = 0`` (a point ``(3,)`` [m] and a unit direction ``(3,)`` each) and the tip's
    origin ``(3,)`` [m], by :func:`from_urdf`'s rule: ``z_i`` along axis i+1; frame i
    (0 < i < n) at the foot of the common normal from axis i (:func:`_common_normal`), ``x_i``
    along it, any perpendicular when axes 1 and 2 are one line; frame n at the tip with ``x_n``
    along the tip's offset from axis n (else ``x_{n−1}``); frame 0 on axis 1 nearest the root's
    origin with ``x_0`` the component of ``x_1`` across ``z_0``, made exactly orthonormal.

    Axes less than ``near_parallel_deg`` apart whose common normal lies beyond
    :data:`MAX_PLAUSIBLE_LENGTH` from the previous origin are placed as parallel ones are:
    frame i where the normal through the previous origin meets axis i+1 (:func:`_beside`);
    those pairs are returned too (their DH rows are parallel, the tilt in a fixed transform)."""
    n = len(axes)
    z_0 = axes[0][1]
    o_0 = axes[0][0] - np.dot(axes[0][0], z_0) * z_0          # on axis 1, nearest the origin
    frames = [None] * (n + 1)
    near = []
    o, x = o_0, np.zeros(3)
    limit = math.sin(math.radians(min(near_parallel_deg, 90.0)))
    for i in range(1, n):
        z0, (p1, z1) = axes[i - 1][1], axes[i]
        sine = float(np.linalg.norm(np.cross(z0, z1)))
        o_next, x_next = _common_normal(o, z0, p1, z1, x)
        far = float(np.linalg.norm(o_next - o))
        if _PARALLEL <= sine < limit and far > MAX_PLAUSIBLE_LENGTH:
            near.append(_NearParallel(i - 1, math.degrees(math.atan2(sine, abs(float(z0 @ z1)))), far))
            o_next, x_next = _beside(o, p1, z1, x)
        o, x = o_next, x_next
        if not x.any():                                        # axes 1 and 2 the same line
            x = _perpendicular(axes[0][1])
        frames[i] = _frame(x, axes[i][1], o)
    # Frame n at the tip's origin, z along axis n; x along the tip's offset from the axis.
    z_n = axes[-1][1]
    gap = p_tip - o
    scale = max(1.0, float(np.linalg.norm(o)), float(np.linalg.norm(p_tip)))   # of the rounding
    gap -= np.dot(gap, z_n) * z_n
    if np.linalg.norm(gap) > _NEAR * scale:
        x = gap / np.linalg.norm(gap)
    elif not x.any():
        x = _perpendicular(z_n)
    frames[n] = _frame(x, z_n, p_tip)
    # Frame 0 on axis 1, x_0 = x_1 (offset_1 = 0).
    x_1 = frames[1][:3, 0]
    frames[0] = _frame(x_1 - np.dot(x_1, z_0) * z_0, z_0, o_0)
    frames[0][:3, :3] = _orthonormal(frames[0][:3, :3])
    return frames, near


def _beside(o0: np.ndarray, p1: np.ndarray, z1: np.ndarray, x_prev: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
    """The frame origin on the line ``(p1, z1)`` nearest ``o0`` and its x axis, along the
    normal from ``o0`` (``x_prev`` made across ``z1`` when ``o0`` is on the line): for parallel
    axes, and for nearly parallel ones placed as parallel ones are, so that the DH frames stay
    near the arm (the origin is on the line itself, the tilt left to a fixed transform)."""
    foot = p1 + np.dot(o0 - p1, z1) * z1
    gap = foot - o0
    gap -= np.dot(gap, z1) * z1
    distance = float(np.linalg.norm(gap))
    if distance < _NEAR * max(1.0, float(np.linalg.norm(o0)), float(np.linalg.norm(foot))):
        x = x_prev - np.dot(x_prev, z1) * z1
        return foot, x / np.linalg.norm(x) if x.any() else x
    return foot, gap / distance


def _common_normal(o0: np.ndarray, z0: np.ndarray, p1: np.ndarray, z1: np.ndarray,
                   x_prev: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """DH frame origin on the line ``(p1, z1)`` and its x axis, from the line ``(o0, z0)``:
    the foot of their common normal and its direction ``±n``, ``n = z0 × z1 / |z0 × z1|``
    (skew lines); the intersection and ``n`` (intersecting); the foot of the normal through
    ``o0`` (parallel, so that ``d = 0``; :func:`_beside`); ``o0`` and ``x_prev`` (the same line).

    The normal's signed length is ``δ = (p1 − o0)·n`` and its foot on the second line
    ``p1 + t1 z1`` with ``t1 = ((p1 − o0) × z0)·n / |z0 × z1|``: no ``1 − (z0·z1)²``, whose
    cancellation for nearly parallel axes would put the foot metres off and tilt ``x`` off
    the axes."""
    cross = np.cross(z0, z1)
    sine = float(np.linalg.norm(cross))
    if sine < _PARALLEL:                                         # parallel or the same line
        return _beside(o0, p1, z1, x_prev)
    n = cross / sine
    w = p1 - o0
    delta = float(np.dot(w, n))
    foot = p1 + (float(np.dot(np.cross(w, z0), n)) / sine) * z1
    # Rounding grows with the points' distance from the origin: below it, the lines meet.
    if abs(delta) < _NEAR * max(1.0, float(np.linalg.norm(o0)), float(np.linalg.norm(foot))):
        return foot, n
    return foot, n if delta > 0 else -n


def _frame(x: np.ndarray, z: np.ndarray, o: np.ndarray) -> np.ndarray:
    """The pose ``(4, 4)`` with origin ``o`` [m] and axes ``x``, ``z × x``, ``z`` (unit,
    orthogonal, each ``(3,)``)."""
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    T[:3, 3] = o
    return T


def _perpendicular(z: np.ndarray) -> np.ndarray:
    """A unit vector ``(3,)`` across the unit ``z``: the world x axis (y when ``z`` is within
    about 26° of x) less its component along ``z``, normalised."""
    helper = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = helper - np.dot(helper, z) * z
    return x / np.linalg.norm(x)


def _orthonormal(R: np.ndarray) -> np.ndarray:
    """The orthogonal matrix nearest ``R`` ``(3, 3)`` (Frobenius norm): ``U Vᵀ`` from the SVD
    ``R = U Σ Vᵀ``, which removes rounding from a nearly orthonormal ``R``."""
    U, _, Vt = np.linalg.svd(R)
    return U @ Vt


def _dh_rows(frames: list[np.ndarray], near: Sequence[int] = ()) -> list[dict[str, float]]:
    """Standard DH rows read off consecutive frames ``F_{i−1}, F_i`` (``n + 1`` frames):
    ``a = (o_i − o_{i−1})·x_i``, ``d = (o_i − o_{i−1})·z_{i−1}``, ``offset`` the angle from
    ``x_{i−1}`` to ``x_i`` about ``z_{i−1}``, ``alpha`` from ``z_{i−1}`` to ``z_i`` about ``x_i``;
    values within 1e-12 of a round number snapped to it. The rows ``near`` (0-based: nearly
    parallel axes, :func:`_dh_frames`) get ``alpha`` 0 or π, the parallel axes nearest them
    (:func:`_fixed_transforms` keeps the rest)."""
    rows = []
    for i in range(1, len(frames)):
        F0, F1 = frames[i - 1], frames[i]
        z0, x0, x1, z1 = F0[:3, 2], F0[:3, 0], F1[:3, 0], F1[:3, 2]
        step = F1[:3, 3] - F0[:3, 3]
        alpha = (0.0 if np.dot(z0, z1) > 0 else math.pi) if i - 1 in near else \
            _snap(np.arctan2(np.dot(np.cross(z0, z1), x1), np.dot(z0, z1)))
        rows.append({"a": _snap(np.dot(step, x1)), "d": _snap(np.dot(step, z0)),
                     "offset": _snap(np.arctan2(np.dot(np.cross(x0, x1), z0), np.dot(x0, x1))),
                     "alpha": alpha})
    return rows


def _fixed_transforms(frames: list[np.ndarray], rows: list[dict[str, float]],
                      tol: float = 1e-12) -> list[np.ndarray] | None:
    """The transform ``E_i = (F_{i−1} · A_i(0))⁻¹ · F_i`` ``(4, 4)`` each joint's DH row
    leaves between its frame and the next (:class:`~nfarm.model.robot.Robot`'s ``fixed``):
    a small rotation for nearly parallel axes written as parallel, rounding elsewhere. ``None``
    when every one is the identity within ``tol`` (rotation) and ``tol`` times the arm's size
    (translation [m]): a pure DH chain."""
    scale = max([1.0] + [float(np.linalg.norm(F[:3, 3])) for F in frames])
    out, exact = [], True
    for i, row in enumerate(rows):
        A = dh_transform(row["a"], row["alpha"], row["d"], row["offset"])
        E = np.linalg.solve(frames[i] @ A, frames[i + 1])
        if (np.abs(E[:3, :3] - np.eye(3)).max() <= tol and np.abs(E[:3, 3]).max() <= tol * scale):
            E = np.eye(4)
        else:
            E[:3, :3] = _orthonormal(E[:3, :3])
            E[3] = [0.0, 0.0, 0.0, 1.0]
            exact = False
        out.append(E)
    return None if exact else out


def _snap(x: float, tol: float = 1e-12) -> float:
    """A DH parameter, 0 when it is rounding (below 1e-12 m or rad): the frames are built
    from products of rounded numbers, and a table of 1e-20 values reads as data."""
    return 0.0 if abs(x) < tol else float(x)


def _link_bodies(r: _Reader, tree: _Tree, pose: Mapping[str, np.ndarray], frames: list[np.ndarray],
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


def _near_parallel(source: str, moving: list[str], near: list[_NearParallel]) -> None:
    """Warn once, in one line, for each pair of nearly parallel consecutive axes
    (:func:`_dh_frames`) written as parallel DH axes with the tilt in a fixed transform."""
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




@dataclass(frozen=True)
class URDFJoint:
    """One joint of a URDF as :func:`urdf_outline` reads it (which has an example): its
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
    """A URDF's tree, validated as :func:`from_urdf` validates it, before any chain is chosen
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
    """The tree of a URDF, read and checked as :func:`from_urdf` reads it (one-line
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
    root_element = _parse(path, raw)
    r = _Reader(str(path), root_element)
    tree = _tree(r)
    elements = {el.get("name"): el for el in root_element.findall("joint")}
    joints = {}
    for jname, j in r.joints.items():
        el, at = elements[jname], f"joint {jname!r}"
        limits = j.get("limits")
        limit = el.find("limit")
        values = {}
        if j["type"] == "prismatic" and limit is not None:
            lo = r._numbers(limit.get("lower", "0"), f"{at} <limit lower>", 1, bound=LENGTH)[0]
            hi = r._numbers(limit.get("upper", "0"), f"{at} <limit upper>", 1, bound=LENGTH)[0]
            limits = (lo, hi) if lo < hi else None
        if j["type"] in _MOVING and limit is not None:
            for key in ("effort", "velocity"):
                values[key] = float(r._numbers(limit.get(key, "0"), f"{at} <limit {key}>", 1)[0])
        dynamics = el.find("dynamics")
        if j["type"] in _MOVING and dynamics is not None:
            for key in ("damping", "friction"):
                values[key] = float(r._numbers(dynamics.get(key, "0"), f"{at} <dynamics {key}>", 1)[0])
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



register_reader(".urdf", from_urdf)
