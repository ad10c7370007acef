"""A URDF file read and checked element by element, before any chain is chosen: its bytes
decoded (UTF-8, or UTF-16/32 by their marks, or the 8-bit encoding its declaration names),
refused if the text holds a DTD or an entity declaration, and parsed as XML
(:func:`parse_urdf`); every link's inertial and every joint's origin, axis, limits and mimic
then checked by URDF's number grammar and the plausibility bounds of :mod:`nfarm.infra.typed`
(:class:`URDFElements`). Every refusal is one :class:`~nfarm.infra.reading.ParamsError` line
naming the file, the element and the rule.

The tree the elements form is :mod:`.urdf_tree`'s, the chain as a DH robot :mod:`.urdf_import`'s.
"""

from __future__ import annotations

import codecs
import re
from pathlib import Path

import numpy as np

from ..infra.reading import ParamsError, Validator, show
from ..infra.typed import ANGLE, EFFORT, INERTIA, LENGTH, MASS, VELOCITY, Range

__all__ = ["parse_urdf", "URDFElements", "MOVING_TYPES"]


#: Joint types that move (about or along their axis), and so may mimic or be mimicked.
MOVING_TYPES = ("revolute", "continuous", "prismatic")
#: A URDF number: plain ASCII decimal, optionally with an exponent (no ``inf``, ``nan``, ``_``,
#: hexadecimal or non-ASCII digits, all of which Python's ``float`` accepts).
_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?\Z")
#: XML's white space, which separates the numbers of a list.
_SPACE = re.compile(r"[ \t\n\r]+")


def _rpy_matrix(r: float, p: float, y: float) -> np.ndarray:
    """URDF's fixed-axis roll, pitch, yaw: ``Rz(y) · Ry(p) · Rx(r)``."""
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


class URDFElements:
    """The URDF's elements, validated, with one-line errors naming the file and element: the
    robot's ``name``, each link's inertial (``(mass, pose, inertia)`` or ``None``) and each
    joint's fields by name.

    Example:
        >>> import xml.etree.ElementTree as ET
        >>> arm = URDFElements("arm.urdf", ET.fromstring(
        ...     '<robot name="arm"><link name="base"/><link name="l1"/><joint name="j1" type="revolute">'
        ...     '<parent link="base"/><child link="l1"/><limit lower="-1" upper="1" effort="0" velocity="0"/>'
        ...     '</joint></robot>'))
        >>> arm.name, sorted(arm.links), [float(x) for x in arm.joints["j1"]["limits"]]
        ('arm', ['base', 'l1'], [-1.0, 1.0])
        >>> arm.joints["j1"]["axis"].tolist()         # URDF's default axis
        [1.0, 0.0, 0.0]
        >>> URDFElements("arm.urdf", ET.fromstring(
        ...     '<robot name="arm"><link name="l"><inertial><mass value="-1"/></inertial></link></robot>'))
        Traceback (most recent call last):
        ...
        nfarm.infra.reading.ParamsError: arm.urdf: link 'l' <inertial><mass value>: must be >= 0, got -1.0
    """

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

    def numbers(self, text, at: str, count: int, default=None, bound: Range | None = None) -> np.ndarray:
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
            xyz = self.numbers(origin.get("xyz"), f"{at} <origin xyz>", 3, (0, 0, 0), LENGTH)
            rpy = self.numbers(origin.get("rpy"), f"{at} <origin rpy>", 3, (0, 0, 0), ANGLE)
            T[:3, :3], T[:3, 3] = _rpy_matrix(*rpy), xyz
        return T

    def _inertial(self, link, at: str):
        inertial = link.find("inertial")
        if inertial is None:
            return None
        mass_el = inertial.find("mass")
        mass = self.numbers(None if mass_el is None else mass_el.get("value"),
                             f"{at} <inertial><mass value>", 1)[0]
        if mass >= 0:
            MASS.check(self.v, float(mass), f"{at} <inertial><mass value>")
        if mass < 0:
            self.v.fail(f"{at} <inertial><mass value>", f"must be >= 0, got {float(mass)!r}")
        el = inertial.find("inertia")
        keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
        values = {k: self.numbers(None if el is None else el.get(k, "0"),
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
        axis = self.numbers(text, f"{at} <axis xyz>", 3, (1, 0, 0))       # URDF's default axis
        if kind in MOVING_TYPES:
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
            lo = self.numbers(limit.get("lower", "0"), f"{at} <limit lower>", 1)[0]
            hi = self.numbers(limit.get("upper", "0"), f"{at} <limit upper>", 1)[0]
            if not lo < hi:
                self.v.fail(f"{at} <limit>", f"must satisfy lower < upper, got "
                                             f"[{float(lo)!r}, {float(hi)!r}]")
            out["limits"] = (lo, hi)
            for key in ("effort", "velocity"):      # 0: none given (what to_urdf writes for none)
                out[key] = self.numbers(limit.get(key), f"{at} <limit {key}>", 1)[0]
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
        if kind not in MOVING_TYPES:
            self.v.fail(f"{at} <mimic>", f"a {kind!r} joint cannot mimic another: only revolute, "
                                         f"continuous and prismatic joints move")
        driver = mimic.get("joint")
        if not driver:
            self.v.fail(f"{at} <mimic joint>", "is required")
        multiplier = self.numbers(mimic.get("multiplier"), f"{at} <mimic multiplier>", 1, (1.0,))[0]
        offset = self.numbers(mimic.get("offset"), f"{at} <mimic offset>", 1, (0.0,))[0]
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


def parse_urdf(path: Path, raw: bytes):
    """The URDF's root element: decoded (:func:`_decode`), then no DTD in the text (so no
    entity expansion, whatever the encoding), well-formed. The parser reads exactly the text
    checked: its UTF-8, whatever the document declares.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> path = PARAMS / "robots" / "so101" / "so101.urdf"
        >>> parse_urdf(path, path.read_bytes()).get("name")
        'so101_new_calib'
        >>> parse_urdf(Path("x.urdf"), b'<?xml version="1.0"?><!DOCTYPE robot><robot/>')
        Traceback (most recent call last):
        ...
        nfarm.infra.reading.ParamsError: x.urdf: <!DOCTYPE>/<!ENTITY> declarations are not accepted in a URDF
    """
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
