"""Robot model: a serial chain of revolute joints described by Denavit–Hartenberg parameters.

A :class:`Robot` is loaded from a YAML file (schema in ``params/README.md``) by
:func:`load_robot`, which validates every field and raises :class:`ParamsError` with a message
of the form ``FILE: joints[2].mass: must be >= 0, got -1.0``.

Conventions (SI units, radians):

* ``standard`` DH (Craig's "distal", Corke's ``RevoluteDH``)::

      A_i = Rz(q_i + offset_i) · Tz(d_i) · Tx(a_i) · Rx(alpha_i)

* ``modified`` DH (Craig's "proximal"); a joint's ``a, alpha`` are the a_{i-1}, alpha_{i-1}
  that precede its rotation::

      A_i = Rx(alpha_i) · Tx(a_i) · Rz(q_i + offset_i) · Tz(d_i)

``com`` and ``inertia`` of link i are about the link's centre of mass, expressed in DH frame i.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import re
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import yaml

__all__ = [
    "ParamsError",
    "ParamsWarning",
    "Robot",
    "load_robot",
    "robot_from_dict",
    "robot_to_dict",
    "sample_configurations",
    "dh_rows",
]

CONVENTIONS = ("standard", "modified")
TOP_KEYS = {"name": True, "convention": True, "gravity": True, "joints": True,
            "tool": False, "description": False}
JOINT_KEYS = {"a": True, "alpha": True, "d": True, "offset": True, "qlim": True, "mass": True,
              "com": True, "inertia": True, "name": False}
ORTHONORMAL_TOL = 1e-9


class ParamsError(ValueError):
    """A parameter file breaks a rule; the message names the file, the field and the rule."""


class ParamsWarning(UserWarning):
    """A parameter file is accepted but something in it is physically suspicious."""


@dataclasses.dataclass(frozen=True, eq=False)
class Robot:
    """A validated serial chain of ``n`` revolute joints. Arrays are read-only.

    Attributes:
        name: robot name.
        convention: ``"standard"`` or ``"modified"`` DH.
        a, alpha, d, offset: ``(n,)`` DH parameters [m, rad, m, rad].
        qlim: ``(n, 2)`` joint limits ``[lo, hi]`` [rad].
        mass: ``(n,)`` link masses [kg].
        com: ``(n, 3)`` centres of mass in link frames [m].
        inertia: ``(n, 3, 3)`` inertia tensors about the centre of mass, link frame [kg m²].
        gravity: ``(3,)`` gravity acceleration in the base frame [m/s²].
        tool: ``(4, 4)`` pose of the tool frame in the last link frame.
        joint_names: ``n`` names (``"q1"``… when the file gives none).
        source: the file the robot was loaded from, or a description.
    """

    name: str
    convention: str
    a: np.ndarray
    alpha: np.ndarray
    d: np.ndarray
    offset: np.ndarray
    qlim: np.ndarray
    mass: np.ndarray
    com: np.ndarray
    inertia: np.ndarray
    gravity: np.ndarray
    tool: np.ndarray
    joint_names: tuple[str, ...]
    source: str = "<dict>"
    description: str = ""

    def __post_init__(self) -> None:
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            if isinstance(value, np.ndarray):
                value.setflags(write=False)

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.a.shape[0]

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, {self.convention} DH, n={self.n}, source={self.source!r})"


# --------------------------------------------------------------------------------------------
# YAML loading


class _Loader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that also reads ``1e-4`` as a float (YAML 1.2), not as a string."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                   |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                   |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
                   |[-+]?\.(?:inf|Inf|INF)
                   |\.(?:nan|NaN|NAN))$""", re.X),
    list("-+0123456789."),
)


def load_robot(path: str | Path) -> Robot:
    """Load and validate a robot parameter file (YAML; schema in ``params/README.md``).

    Raises:
        ParamsError: the file is missing, is not valid YAML, or breaks a schema rule; the
            message names the file, the field and the rule (and the line for YAML errors).
    Warns:
        ParamsWarning: an inertia that violates the triangle inequality.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ParamsError(f"{path}: file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ParamsError(f"{path}: cannot read: {exc}") from None
    try:
        data = yaml.load(text, Loader=_Loader)  # noqa: S506 — a SafeLoader subclass
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark else str(path)
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise ParamsError(f"{where}: YAML syntax error: {problem}") from None
    return robot_from_dict(data, source=str(path))


def robot_from_dict(data: Any, source: str = "<dict>") -> Robot:
    """Validate a parameter mapping (as read from YAML) and build a :class:`Robot`."""
    v = _Validator(source)
    v.mapping(data, "", TOP_KEYS)
    name = v.string(data["name"], "name")
    convention = data["convention"]
    if convention not in CONVENTIONS:
        v.fail("convention", f"must be one of {', '.join(CONVENTIONS)}, got {convention!r}")
    gravity = v.vector(data["gravity"], "gravity", 3)
    tool = v.pose(data["tool"], "tool") if data.get("tool") is not None else np.eye(4)
    description = v.string(data["description"], "description", allow_empty=True) \
        if "description" in data else ""

    joints = data["joints"]
    if not isinstance(joints, list) or not joints:
        v.fail("joints", f"must be a non-empty list of joints, got {_show(joints)}")
    fields: dict[str, list] = {k: [] for k in JOINT_KEYS}
    for i, joint in enumerate(joints):
        at = f"joints[{i}]"
        v.mapping(joint, at, JOINT_KEYS)
        for key in ("a", "alpha", "d", "offset"):
            fields[key].append(v.number(joint[key], f"{at}.{key}"))
        lo, hi = v.vector(joint["qlim"], f"{at}.qlim", 2)
        if not lo < hi:
            v.fail(f"{at}.qlim", f"must satisfy lo < hi, got [{float(lo)!r}, {float(hi)!r}]")
        fields["qlim"].append((lo, hi))
        mass = v.number(joint["mass"], f"{at}.mass")
        if mass < 0:
            v.fail(f"{at}.mass", f"must be >= 0, got {mass!r}")
        fields["mass"].append(mass)
        fields["com"].append(v.vector(joint["com"], f"{at}.com", 3))
        fields["inertia"].append(v.inertia(joint["inertia"], f"{at}.inertia"))
        jname = joint.get("name", f"q{i + 1}")
        fields["name"].append(v.string(jname, f"{at}.name"))

    return Robot(
        name=name, convention=convention,
        a=np.array(fields["a"]), alpha=np.array(fields["alpha"]), d=np.array(fields["d"]),
        offset=np.array(fields["offset"]), qlim=np.array(fields["qlim"], dtype=float),
        mass=np.array(fields["mass"]), com=np.array(fields["com"]),
        inertia=np.array(fields["inertia"]), gravity=gravity, tool=tool,
        joint_names=tuple(fields["name"]), source=source, description=description,
    )


def robot_to_dict(robot: Robot) -> dict:
    """The parameter mapping of ``robot`` (plain Python types), as :func:`robot_from_dict` reads."""
    joints = []
    for i in range(robot.n):
        inertia = robot.inertia[i]
        joints.append({
            "name": robot.joint_names[i],
            "a": float(robot.a[i]), "alpha": float(robot.alpha[i]), "d": float(robot.d[i]),
            "offset": float(robot.offset[i]), "qlim": robot.qlim[i].tolist(),
            "mass": float(robot.mass[i]), "com": robot.com[i].tolist(),
            "inertia": [float(inertia[0, 0]), float(inertia[1, 1]), float(inertia[2, 2]),
                        float(inertia[0, 1]), float(inertia[1, 2]), float(inertia[0, 2])],
        })
    out = {"name": robot.name, "convention": robot.convention,
           "gravity": robot.gravity.tolist(), "tool": robot.tool.tolist(), "joints": joints}
    if robot.description:
        out["description"] = robot.description
    return out


def sample_configurations(robot: Robot, size: int | tuple[int, ...], seed: int | np.random.Generator,
                          ) -> np.ndarray:
    """Joint configurations drawn uniformly within the limits: ``(*size, n)`` [rad]."""
    rng = np.random.default_rng(seed)
    size = (size,) if isinstance(size, int) else tuple(size)
    lo, hi = robot.qlim[:, 0], robot.qlim[:, 1]
    return lo + (hi - lo) * rng.random(size + (robot.n,))


def dh_rows(robot: Robot) -> tuple[list[str], list[list]]:
    """The DH table for people: column names and one row per joint, angles in degrees."""
    prime = "" if robot.convention == "standard" else "_{i-1}"
    columns = ["joint", "name", f"a{prime} [m]", f"alpha{prime} [deg]", "d [m]",
               "offset [deg]", "q min [deg]", "q max [deg]", "mass [kg]"]
    deg = np.degrees
    rows = [[i + 1, robot.joint_names[i], robot.a[i], deg(robot.alpha[i]), robot.d[i],
             deg(robot.offset[i]), deg(robot.qlim[i, 0]), deg(robot.qlim[i, 1]), robot.mass[i]]
            for i in range(robot.n)]
    return columns, rows


# --------------------------------------------------------------------------------------------
# Validation


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


class _Validator:
    """Checks one field at a time; every failure names the source, the field and the rule."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, field: str, rule: str):
        prefix = f"{self.source}: {field}: " if field else f"{self.source}: "
        raise ParamsError(prefix + rule)

    def mapping(self, data: Any, at: str, keys: dict[str, bool]) -> None:
        if not isinstance(data, Mapping):
            self.fail(at, f"must be a mapping of fields, got {_show(data)}")
        for key in data:
            if key not in keys:
                close = difflib.get_close_matches(str(key), list(keys), n=1)
                hint = f" (did you mean {close[0]!r}?)" if close else \
                    f" (allowed: {', '.join(keys)})"
                self.fail(f"{at}.{key}" if at else str(key), f"unknown field{hint}")
        for key, required in keys.items():
            if required and key not in data:
                self.fail(f"{at}.{key}" if at else key, "required field is missing")

    def string(self, value: Any, at: str, allow_empty: bool = False) -> str:
        if not isinstance(value, str) or not (value.strip() or allow_empty):
            self.fail(at, f"must be a non-empty string, got {_show(value)}")
        return value

    def number(self, value: Any, at: str) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(at, f"must be a number, got {_show(value)}")
        if not math.isfinite(value):
            self.fail(at, f"must be finite, got {value!r}")
        return float(value)

    def vector(self, value: Any, at: str, length: int) -> np.ndarray:
        if not isinstance(value, Sequence) or isinstance(value, str) or len(value) != length:
            self.fail(at, f"must be a list of {length} numbers, got {_show(value)}")
        return np.array([self.number(x, f"{at}[{k}]") for k, x in enumerate(value)])

    def pose(self, value: Any, at: str) -> np.ndarray:
        if not isinstance(value, Sequence) or len(value) != 4:
            self.fail(at, f"must be a 4x4 matrix (list of 4 rows), got {_show(value)}")
        T = np.array([self.vector(row, f"{at}[{r}]", 4) for r, row in enumerate(value)])
        if not np.array_equal(T[3], [0.0, 0.0, 0.0, 1.0]):
            self.fail(f"{at}[3]", f"last row must be [0, 0, 0, 1], got {T[3].tolist()}")
        R = T[:3, :3]
        err = float(np.abs(R.T @ R - np.eye(3)).max())
        if err > ORTHONORMAL_TOL:
            self.fail(at, f"rotation part must be orthonormal (max |RᵀR − I| = {err:.3g} "
                          f"> {ORTHONORMAL_TOL:g})")
        if np.linalg.det(R) < 0:
            self.fail(at, "rotation part must have determinant +1 (got a reflection)")
        return T

    def inertia(self, value: Any, at: str) -> np.ndarray:
        if not isinstance(value, Sequence) or isinstance(value, str) or len(value) != 6:
            self.fail(at, f"must be a list of 6 numbers [Ixx, Iyy, Izz, Ixy, Iyz, Ixz], "
                          f"got {_show(value)}")
        ixx, iyy, izz, ixy, iyz, ixz = (self.number(x, f"{at}[{k}]") for k, x in enumerate(value))
        inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        principal = np.linalg.eigvalsh(inertia)
        tol = 1e-12 * max(1.0, float(np.abs(principal).max()))
        if principal[0] < -tol:
            self.fail(at, f"must be positive semi-definite, got principal moments "
                          f"{np.round(principal, 12).tolist()}")
        p1, p2, p3 = principal
        if p1 + p2 < p3 - tol:
            warnings.warn(ParamsWarning(
                f"{self.source}: {at}: principal moments {np.round(principal, 12).tolist()} "
                f"break the triangle inequality (I1 + I2 >= I3): not a physical rigid body; "
                f"accepted as given"), stacklevel=4)
        return inertia
