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
The chain hangs from the world frame at ``base`` (DH frame 0 in the world; default identity) and
carries the ``tool``: ``T_0e = base · A_1 ··· A_n · tool``.

A standard-DH joint may carry a ``fixed`` transform ``E_i`` after its row, ``A_i = Rz(q_i +
offset_i) · Tz(d_i) · Tx(a_i) · Rx(alpha_i) · E_i`` (default identity): the joint placements DH
cannot hold exactly, such as nearly parallel axes of a URDF written with a rounded π (DH would
put their common normal kilometres away; :func:`nfarm.model.urdf_import.from_urdf` writes the pair as
parallel with the small tilt in ``E_i``). Link i's frame is then the DH frame followed by
``E_i``: its z axis is joint i+1's axis, and ``com`` and ``inertia`` are in it.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import re
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal, Optional, get_args

import numpy as np

from ..infra.paths import project_path, shown_path
from ..infra.reading import ParamsError, ParamsWarning, Validator, load_yaml, show
from ..infra.reading import read_bytes as _read_bytes
from ..infra.typed import ANGLE, DRIVE, EFFORT, GRAVITY, INERTIA, LENGTH, MASS, TEXT, VELOCITY, Range, ReadBy, read_typed
from .rotations import log_so3

__all__ = [
    "ParamsError",
    "ParamsWarning",
    "Robot",
    "load_robot",
    "robot_from_dict",
    "robot_to_dict",
    "sample_configurations",
    "robot_hash",
    "joint_array",
    "poses_for",
    "dh_rows",
    "DRIVE_DEFAULTS",
    "register_reader",
    "with_provenance",
    "robot_name",
    "is_robot_name",
]

Convention = Literal["standard", "modified"]
CONVENTIONS: tuple[str, ...] = get_args(Convention)
#: Joint-drive terms (optional per joint; see :func:`nfarm.model.dynamics.joint_drive_torques`) and
#: their defaults: viscous [N·m·s/rad], Coulomb [N·m], Coulomb smoothing speed [rad/s],
#: armature (reflected rotor inertia) [kg·m²].
DRIVE_DEFAULTS = {"viscous": 0.0, "coulomb": 0.0, "coulomb_velocity": 0.01, "armature": 0.0}
ORTHONORMAL_TOL = 1e-9
INERTIA_RTOL = 1e-12
MAX_PLAUSIBLE_LENGTH = 10.0   # [m]


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
        gravity: ``(3,)`` gravity acceleration in the world frame [m/s²].
        tool: ``(4, 4)`` pose of the tool frame in the last link frame.
        base: ``(4, 4)`` pose of DH frame 0 in the world frame (identity unless the file or
            the URDF gives one); poses, Jacobians, gravity and tip wrenches are in the world
            frame.
        joint_names: ``n`` names (``"q1"``… when the file gives none).
        viscous, coulomb, coulomb_velocity, armature: ``(n,)`` joint-drive terms (viscous
            [N·m·s/rad] and Coulomb [N·m] friction, the Coulomb smoothing speed [rad/s], the
            reflected rotor inertia [kg·m²]); zero friction and armature unless the file gives
            them. Used only where asked (``rnea(..., drive=True)``).
        fixed: ``(n, 4, 4)`` the fixed transform ``E_i`` after each standard-DH row (module
            docstring), or ``None``: identity for every joint, a pure DH chain.
        effort, velocity: ``(n,)`` the joints' torque [N·m] and speed [rad/s] limits (a URDF's
            ``<limit effort velocity>``; ``inf`` unless given). Informative: no solver
            enforces them.
        source: the file the robot was loaded from, or a description.
        poses: named configurations ``{name: (n,)}`` [rad] within the limits, for a reader
            (the file's ``poses_deg``; :func:`poses_for`): each arm's own, named for what it
            does there. Not a model parameter: :func:`robot_hash` leaves them out, so naming a
            pose keeps the robot's data sets and models valid.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> robot.name, robot.convention, robot.source
        ('intelbot5', 'standard', 'params/robots/intelbot5.yaml')
        >>> robot.n, robot.a.tolist(), robot.qlim.shape     # a [m], qlim [rad]
        (5, [0.0, 0.2, 0.18, 0.0, 0.0], (5, 2))
        >>> robot.a.flags.writeable
        False
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
    viscous: np.ndarray | None = None
    coulomb: np.ndarray | None = None
    coulomb_velocity: np.ndarray | None = None
    armature: np.ndarray | None = None
    base: np.ndarray | None = None
    effort: np.ndarray | None = None
    velocity: np.ndarray | None = None
    fixed: np.ndarray | None = None
    poses: dict[str, np.ndarray] = dataclasses.field(default_factory=dict, repr=False)
    provenance: tuple[str, str] | None = dataclasses.field(default=None, repr=False)

    def __post_init__(self) -> None:
        for key in ("effort", "velocity"):
            if getattr(self, key) is None:
                object.__setattr__(self, key, np.full(self.a.shape[0], np.inf))
        if self.base is None:
            object.__setattr__(self, "base", np.eye(4))
        for key, default in DRIVE_DEFAULTS.items():
            if getattr(self, key) is None:
                object.__setattr__(self, key, np.full(self.a.shape[0], default))
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            if isinstance(value, np.ndarray):
                value.setflags(write=False)
        for value in self.poses.values():
            value.setflags(write=False)
        if self.fixed is not None:
            if self.convention != "standard" or self.fixed.shape != (self.a.shape[0], 4, 4):
                raise ValueError(f"{self.name}: fixed must be (n, 4, 4) on a standard-DH chain, "
                                 f"got shape {self.fixed.shape} on a {self.convention} one")

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.a.shape[0]

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, {self.convention} DH, n={self.n}, source={shown_path(project_path(self.source))!r})"


# --------------------------------------------------------------------------------------------
# Loading


#: Readers of robot descriptions in other formats, by file suffix. The URDF reader registers
#: itself (:mod:`nfarm.model.urdf_import`, imported by the package), so that this model layer does not
#: import the file-format layer.
_READERS: dict[str, Any] = {}
URDF_FILE_KEYS = {"name": True, "urdf": True, "tip": False, "lock": False, "gravity": False,
                  "drive": False, "description": False, "poses_deg": False}
_DRIVE_KEYS = dict.fromkeys(DRIVE_DEFAULTS, False)


def register_reader(suffix: str, reader) -> None:
    """Let :func:`load_robot` read files ending in ``suffix`` with ``reader(path, tip=None,
    lock=None, name=None) -> Robot``.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.urdf_import import from_urdf
        >>> register_reader(".urdf", from_urdf)     # what importing nfarm.model.urdf_import does
        >>> load_robot(PARAMS / "robots" / "so101.yaml").n     # a robot file naming a .urdf
        5
    """
    _READERS[suffix.lower()] = reader


def load_robot(path: str | Path) -> Robot:
    """Load and validate a robot file: a DH parameter file (YAML; schema in
    ``params/README.md``), a URDF (``.urdf``: :func:`nfarm.model.urdf_import.from_urdf`, its single leaf the
    tip), or a YAML file naming a URDF with its ``tip``, the ``lock`` positions of joints off the
    chain, and optional ``gravity``, joint ``drive`` terms and ``description``.

    The file goes through :func:`nfarm.infra.reading.load_yaml` (regular file, size limit, no
    duplicate keys, bounded aliases and nesting, YAML 1.2 decimal numbers).

    Raises:
        ParamsError: the file is missing, is not valid YAML, or breaks a schema rule; the
            message names the file, the field and the rule (and the line for YAML errors).
    Warns:
        ParamsWarning: an inertia that violates the triangle inequality; an implausible
            value (an angle beyond 2π, a length beyond 10 m: degrees or millimetres by mistake?).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> robot.joint_names
        ('base_yaw', 'shoulder_pitch', 'elbow_pitch', 'wrist_pitch', 'wrist_roll')
        >>> so101 = load_robot(PARAMS / "robots" / "so101.yaml")     # a YAML file naming a URDF
        >>> so101.name, so101.n, so101.source
        ('so101', 5, 'params/robots/so101.yaml')
    """
    path = Path(path)
    if path.suffix.lower() in _READERS:
        return _READERS[path.suffix.lower()](path)
    data = load_yaml(path, what="robot file")
    if isinstance(data, dict) and "urdf" in data and "joints" not in data:
        return _from_described_urdf(data, path)
    return robot_from_dict(data, source=shown_path(path))     # messages name it relative to the checkout


#: A robot's name: it names directories and files (``build/datasets/<name>/``, models,
#: recordings), so letters, digits, ``_``, ``-`` and ``.``, starting with a letter or digit.
ROBOT_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}")


#: The rule :data:`ROBOT_NAME` states, as messages say it.
ROBOT_NAME_RULE = ("must be 1-64 letters, digits, '_', '-' or '.', starting with a letter or digit "
                   "and without '..' (it names directories and files)")


def _robot_name(v, value, at: str = "name", hint: str = "") -> str:
    """``value`` as a robot's name (:data:`ROBOT_NAME`), or a one-line error naming the field."""
    if not is_robot_name(value):
        v.fail(at, f"{ROBOT_NAME_RULE}, got {show(value)}{hint}")
    return value


def is_robot_name(value: Any) -> bool:
    """Whether ``value`` can be a robot's name (:data:`ROBOT_NAME`, no ``..``): one path
    component that names nothing but itself.

    Example:
        >>> [is_robot_name(x) for x in ("so101", "so-101.v2", "../x", "/tmp/x", "a..b", ".hidden", 3)]
        [True, True, False, False, False, False, False]
    """
    return isinstance(value, str) and ROBOT_NAME.fullmatch(value) is not None and ".." not in value


def robot_name(value: Any, source: str, at: str = "name", hint: str = "") -> str:
    """``value`` as a robot's name, whatever gave it (a robot file, a URDF's ``<robot name>``,
    ``add-arm --name``, a robot built in Python before its name names a path), or a one-line
    :class:`ParamsError` naming ``source``, ``at`` and the rule (then ``hint``).

    Example:
        >>> robot_name("so101", "x.urdf")
        'so101'
        >>> robot_name("../../elsewhere/pwned", "x.urdf", "<robot name>")
        Traceback (most recent call last):
        ...
        nfarm.infra.reading.ParamsError: x.urdf: <robot name>: must be 1-64 letters, digits, '_', '-' or '.', starting with a letter or digit and without '..' (it names directories and files), got '../../elsewhere/pwned'
    """
    return _robot_name(Validator(source), value, at, hint)


def _from_described_urdf(data: dict, path: Path) -> Robot:
    """A robot file naming a URDF (``urdf`` relative to the file) and what to take from it."""
    v = _Validator(str(path))
    v.mapping(data, "", URDF_FILE_KEYS)
    name = _robot_name(v, data["name"])
    urdf = path.parent / v.string(data["urdf"], "urdf")
    if urdf.suffix.lower() not in _READERS:
        v.fail("urdf", f"must name a .urdf file, got {show(data['urdf'])}")
    tip = v.string(data["tip"], "tip") if data.get("tip") is not None else None
    lock = {}
    if data.get("lock") is not None:
        if not isinstance(data["lock"], dict):
            v.fail("lock", f"must map joint names to positions, got {show(data['lock'])}")
        lock = {str(k): v.number(x, f"lock.{k}") for k, x in data["lock"].items()}
    robot = _READERS[urdf.suffix.lower()](urdf, tip=tip, lock=lock, name=name)
    changes: dict[str, Any] = {"source": shown_path(path)}
    if data.get("gravity") is not None:
        changes["gravity"] = np.array(_vector(3, GRAVITY)(v, data["gravity"], "gravity"))
    if "description" in data:
        changes["description"] = v.string(data["description"], "description", allow_empty=True)
    if data.get("poses_deg") is not None:
        changes["poses"] = v.poses(data["poses_deg"], "poses_deg", robot)
    if data.get("drive") is not None:
        drive = v.mapping(data["drive"], "drive", _DRIVE_KEYS)
        for key, value in drive.items():
            values = value if isinstance(value, list) else [value] * robot.n
            if len(values) != robot.n:
                v.fail(f"drive.{key}", f"must be one number or {robot.n}, got {len(values)}")
            numbers = [(VELOCITY if key == "coulomb_velocity" else DRIVE).check(v, x, f"drive.{key}")
                       for x in values]
            changes[key] = np.array(numbers)
    robot = dataclasses.replace(robot, **changes)
    model = {k: x for k, x in data.items() if k != "poses_deg"}      # the poses are no parameter
    fields = json.dumps(model, sort_keys=True, default=str).encode("utf-8")
    return with_provenance(robot, fields, _read_bytes(urdf))


# --------------------------------------------------------------------------------------------
# A DH robot file as written: the schema :func:`robot_from_dict` reads through the generic reader
# (:func:`nfarm.infra.typed.read_typed`). A field whose rule no annotation says (a pose, an
# inertia, a name that names directories) is read by the validator's own check (``ReadBy``; named
# functions: an annotation's lambda would not see this module's names).


def _name(v: Validator, value: Any, at: str) -> str:
    return _robot_name(v, value)


def _pose(v: _Validator, value: Any, at: str) -> np.ndarray:
    return v.pose(value, at)


def _inertia(v: _Validator, value: Any, at: str) -> np.ndarray:
    return v.inertia(value, at)


def _as_given(v: Validator, value: Any, at: str) -> Any:
    """A field checked once the robot is built (the named poses: within its joint limits)."""
    return value


def _vector(length: int, bound: Range):
    """A reader of a list of ``length`` finite numbers (one error: "must be a list of 3 numbers"),
    each within the plausibility ``bound`` (:mod:`nfarm.infra.typed`)."""
    def read(v, value, at):
        return [bound.check(v, x, f"{at}[{k}]") for k, x in enumerate(v.vector(value, at, length))]
    return read


def _limits(v: Validator, value: Any, at: str) -> tuple[float, float]:
    """A joint's ``qlim`` [rad]: two numbers, ``lo < hi``, both within [-2π, 2π]."""
    lo, hi = v.vector(value, at, 2)
    if not lo < hi:
        v.fail(at, f"must satisfy lo < hi, got [{lo!r}, {hi!r}]")
    if max(abs(lo), abs(hi)) > 2 * math.pi:
        v.fail(at, f"must lie within [-2π, 2π] rad, got [{lo!r}, {hi!r}] (degrees by mistake?)")
    return lo, hi


def _joints(v: Validator, value: Any, at: str) -> list[JointSection]:
    """``joints``: a non-empty list, each item a :class:`JointSection`."""
    if not isinstance(value, list) or not value:
        v.fail(at, f"must be a non-empty list of joints, got {show(value)}")
    return [read_typed(JointSection, joint, v, f"{at}[{i}]") for i, joint in enumerate(value)]


@dataclass(frozen=True, kw_only=True)
class JointSection:
    """``joints[i]``: one revolute joint as written: DH parameters [m, rad], limits [rad], the
    link's mass [kg], centre of mass [m] and inertia [kg·m², the 3×3 matrix read from ``[Ixx,
    Iyy, Izz, Ixy, Iyz, Ixz]``] about it in link frame i, the drive terms (:data:`DRIVE_DEFAULTS`),
    the effort [N·m] and speed [rad/s] limits (``inf``: none) and the ``fixed`` 4×4 transform
    after the DH row (``None``: identity; standard DH only)."""

    a: Annotated[float, LENGTH]
    alpha: Annotated[float, ANGLE]
    d: Annotated[float, LENGTH]
    offset: Annotated[float, ANGLE]
    qlim: Annotated[tuple[float, float], ReadBy(_limits)]
    mass: Annotated[float, MASS]
    com: Annotated[list[float], ReadBy(_vector(3, LENGTH))]
    inertia: Annotated[np.ndarray, ReadBy(_inertia)]
    name: str = ""                  # left out: q1, q2, … by position
    viscous: Annotated[float, DRIVE] = DRIVE_DEFAULTS["viscous"]
    coulomb: Annotated[float, DRIVE] = DRIVE_DEFAULTS["coulomb"]
    coulomb_velocity: Annotated[float, VELOCITY] = DRIVE_DEFAULTS["coulomb_velocity"]
    armature: Annotated[float, DRIVE] = DRIVE_DEFAULTS["armature"]
    effort: Annotated[float, EFFORT] = math.inf
    velocity: Annotated[float, VELOCITY] = math.inf
    fixed: Annotated[Optional[np.ndarray], ReadBy(_pose)] = None


@dataclass(frozen=True, kw_only=True)
class RobotFile:
    """A DH robot file as written (``params/README.md``, "Robots"): typed and checked field by
    field; ``tool`` and ``base`` 4×4 poses (``None``: identity), ``gravity`` [m/s²], and the
    named poses ``poses_deg`` as given (checked against the joint limits once the robot is built)."""

    name: Annotated[str, ReadBy(_name)]
    convention: Convention
    gravity: Annotated[list[float], ReadBy(_vector(3, GRAVITY))]
    joints: Annotated[list[JointSection], ReadBy(_joints)]
    tool: Annotated[Optional[np.ndarray], ReadBy(_pose)] = None
    base: Annotated[Optional[np.ndarray], ReadBy(_pose)] = None
    description: Annotated[str, TEXT] = ""
    poses_deg: Annotated[Optional[dict], ReadBy(_as_given)] = None


def robot_from_dict(data: Any, source: str = "<dict>") -> Robot:
    """Validate a parameter mapping (as read from YAML) and build a :class:`Robot`: the mapping
    into a :class:`RobotFile` by the generic reader (every field's type and rule, unknown keys
    refused), then the warnings about implausible values and the named poses, which need the
    robot; the first broken rule is one :class:`ParamsError` line naming the file and the field.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> data = robot_to_dict(robot)
        >>> robot_from_dict(data).a.tolist()     # [m]
        [0.0, 0.2, 0.18, 0.0, 0.0]
        >>> robot_from_dict({**data, "convention": "craig"})
        Traceback (most recent call last):
        ...
        nfarm.infra.reading.ParamsError: <dict>: convention: must be one of standard, modified, got 'craig'
    """
    v = _Validator(source)
    file = read_typed(RobotFile, data, v)
    tool = np.eye(4) if file.tool is None else file.tool
    base = np.eye(4) if file.base is None else file.base
    for what, pose in (("tool", tool), ("base", base)):
        for k in range(3):
            v.plausible(float(pose[k, 3]), f"{what}[{k}][3]", "length")
    joints = file.joints
    for i, joint in enumerate(joints):
        at = f"joints[{i}]"
        for key, kind in (("a", "length"), ("alpha", "angle"), ("d", "length"), ("offset", "angle")):
            v.plausible(getattr(joint, key), f"{at}.{key}", kind)
        for k, c in enumerate(joint.com):
            v.plausible(c, f"{at}.com[{k}]", "length")
        v.triangle(joint.inertia, f"{at}.inertia")
        if joint.fixed is not None:
            if file.convention != "standard":
                v.fail(f"{at}.fixed", "a fixed transform after the DH row needs the standard convention")
            for k in range(3):
                v.plausible(float(joint.fixed[k, 3]), f"{at}.fixed[{k}][3]", "length")
    fixed = None
    if any(joint.fixed is not None for joint in joints):
        fixed = np.array([np.eye(4) if joint.fixed is None else joint.fixed for joint in joints])

    def column(key: str) -> np.ndarray:
        return np.array([getattr(joint, key) for joint in joints], dtype=float)

    robot = Robot(
        name=file.name, convention=file.convention,
        a=column("a"), alpha=column("alpha"), d=column("d"), offset=column("offset"),
        qlim=np.array([joint.qlim for joint in joints], dtype=float), mass=column("mass"),
        com=np.array([joint.com for joint in joints]), inertia=np.array([joint.inertia for joint in joints]),
        gravity=np.array(file.gravity), tool=tool, base=base,
        joint_names=tuple(joint.name or f"q{i + 1}" for i, joint in enumerate(joints)), source=source,
        description=file.description, **{key: column(key) for key in DRIVE_DEFAULTS},
        effort=column("effort"), velocity=column("velocity"), fixed=fixed,
    )
    if file.poses_deg is not None:
        robot = dataclasses.replace(robot, poses=v.poses(file.poses_deg, "poses_deg", robot))
    return robot


def robot_to_dict(robot: Robot) -> dict:
    """The model parameters of ``robot`` (plain Python types), as :func:`robot_from_dict` reads;
    not its named poses (:attr:`Robot.poses`, a reader's, not the model's), so that a mapping edited
    joint by joint (a joint added, say) stays valid.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> data = robot_to_dict(robot)
        >>> list(data)
        ['name', 'convention', 'gravity', 'tool', 'joints', 'description']
        >>> data["joints"][1]["a"], data["joints"][1]["qlim"]     # [m], [rad]
        (0.2, [-1.5707963267948966, 1.5707963267948966])
    """
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
        # Drive terms only where they differ from the defaults: a file without them keeps its
        # hash (and its data sets and models stay valid).
        joints[-1].update({key: float(getattr(robot, key)[i]) for key, default in
                           DRIVE_DEFAULTS.items() if getattr(robot, key)[i] != default})
        joints[-1].update({key: float(getattr(robot, key)[i]) for key in ("effort", "velocity")
                           if np.isfinite(getattr(robot, key)[i])})
        if robot.fixed is not None and not np.array_equal(robot.fixed[i], np.eye(4)):
            joints[-1]["fixed"] = robot.fixed[i].tolist()
    out = {"name": robot.name, "convention": robot.convention,
           "gravity": robot.gravity.tolist(), "tool": robot.tool.tolist(), "joints": joints}
    if not np.array_equal(robot.base, np.eye(4)):     # as the drive terms: old hashes kept
        out["base"] = robot.base.tolist()
    if robot.description:
        out["description"] = robot.description
    return out


def _canonical(robot: Robot) -> str:
    """The robot's model parameters as canonical JSON: what :func:`robot_hash` hashes."""
    return json.dumps(robot_to_dict(robot), sort_keys=True, separators=(",", ":"))


def robot_hash(robot: Robot) -> str:
    """SHA-256 of the robot's parameters as loaded (canonical JSON of :func:`robot_to_dict`,
    floats written exactly): two files that differ only in comments or layout are one robot.
    Data sets and saved models record it, and refuse to be used with another robot.

    A robot converted from a URDF is hashed by its sources instead (the URDF's bytes and what
    the robot file takes from it, :func:`with_provenance`) as long as its parameters are the
    ones converted: the conversion's last bits depend on the machine's floating point (BLAS
    kernels, SIMD paths), and the same files must be the same robot everywhere. A robot
    changed after loading (``dataclasses.replace``) is hashed by its parameters again.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> h = robot_hash(robot)
        >>> len(h), h == robot_hash(robot_from_dict(robot_to_dict(robot)))     # hex digits; same robot
        (64, True)
    """
    canonical = _canonical(robot)
    if robot.provenance is not None and robot.provenance[1] == canonical:
        return robot.provenance[0]
    return hashlib.sha256(canonical.encode("utf-8")).hexdigest()


def with_provenance(robot: Robot, *sources: bytes) -> Robot:
    """``robot`` hashed by ``sources`` (e.g. a URDF's bytes and the robot file's canonical
    fields) while its parameters stay as they are now (:func:`robot_hash`).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> tagged = with_provenance(robot, b"urdf bytes", b"fields")
        >>> robot_hash(tagged) == robot_hash(robot), robot_to_dict(tagged) == robot_to_dict(robot)
        (False, True)
        >>> robot_hash(tagged) == robot_hash(with_provenance(robot, b"urdf bytes", b"fields"))
        True
    """
    digest = hashlib.sha256()
    for part in sources:
        digest.update(hashlib.sha256(part).digest())
    return dataclasses.replace(robot, provenance=(digest.hexdigest(), _canonical(robot)))


def sample_configurations(robot: Robot, size: int | tuple[int, ...], seed: int | np.random.Generator,
                          ) -> np.ndarray:
    """Joint configurations drawn uniformly within the limits: ``(*size, n)`` [rad].

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> q = sample_configurations(robot, (2, 3), seed=0)
        >>> q.shape                                                          # (*size, n) [rad]
        (2, 3, 5)
        >>> bool(((q >= robot.qlim[:, 0]) & (q <= robot.qlim[:, 1])).all())
        True
    """
    rng = np.random.default_rng(seed)
    size = (size,) if isinstance(size, int) else tuple(size)
    lo, hi = robot.qlim[:, 0], robot.qlim[:, 1]
    return lo + (hi - lo) * rng.random(size + (robot.n,))


def joint_array(robot: Robot, value, name: str = "q") -> np.ndarray:
    """``value`` as a float array of shape ``(..., n)``, or a one-line ``ValueError``: real
    numbers only (booleans, complex numbers, strings and ``None`` are refused, not cast).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> joint_array(robot, [0, 0, 0, 0, 0]).dtype, joint_array(robot, np.zeros((3, 5))).shape
        (dtype('float64'), (3, 5))
        >>> joint_array(robot, [0.0, 0.0, 0.0])
        Traceback (most recent call last):
        ...
        ValueError: intelbot5: q must have shape (..., 5), got (3,)
    """
    array = value if isinstance(value, np.ndarray) else np.asarray(value)
    if array.dtype.kind not in "iuf":
        kind = {"b": "booleans", "c": "complex numbers", "U": "text", "S": "bytes",
                "O": "objects"}.get(array.dtype.kind, array.dtype.name)
        raise ValueError(f"{robot.name}: {name} must hold real numbers, got {kind} ({show(value)})")
    if array.ndim == 0 or array.shape[-1] != robot.n:
        raise ValueError(f"{robot.name}: {name} must have shape (..., {robot.n}), got {array.shape}")
    return array.astype(float, copy=False)


def poses_for(robot: Robot, poses_deg: dict[str, Sequence[float]] | None = None, seed: int = 0,
              ) -> tuple[dict[str, np.ndarray], str]:
    """Named configurations [rad] for a chapter, and a note for its reader.

    ``poses_deg`` maps names to angles [deg]; ``None`` takes the robot file's own named poses
    (:attr:`Robot.poses`). When every pose has one angle per joint they are used as given (an
    empty note); when they were written for another arm (another number of joints), or the
    robot file names none, the home configuration (0 moved into the limits) and seeded random
    configurations within the limits take their place, as many as were asked for (four when the
    file names none), and the note says so — a chapter run for another robot shows that robot
    instead of failing.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> poses, note = poses_for(robot, {"ready": [0, 30, 60, -90, 0]})     # [deg]
        >>> (poses["ready"].round(6) + 0.0).tolist(), note                      # [rad]
        ([0.0, 0.523599, 1.047198, -1.570796, 0.0], '')
        >>> list(poses_for(robot, {"a": [0] * 6, "b": [10] * 6})[0])          # poses for 6 joints
        ['home (q = 0)', 'random configuration 1']
        >>> list(poses_for(robot)[0])                                          # the file's own
        ['ready (q = 0)', 'reaching forward and down', 'raised, base turned 60°', 'folded back']
    """
    if poses_deg is None and robot.poses:
        return {name: q.copy() for name, q in robot.poses.items()}, ""
    if poses_deg and all(len(q) == robot.n for q in poses_deg.values()):
        return {name: np.radians(np.asarray(q, dtype=float)) for name, q in poses_deg.items()}, ""
    wanted = 4 if poses_deg is None else len(poses_deg)
    rng = np.random.default_rng(seed)
    home = np.clip(0.0, robot.qlim[:, 0], robot.qlim[:, 1])
    poses = {"home (q = 0)": home}
    for k in range(1, max(wanted, 1)):
        poses[f"random configuration {k}"] = sample_configurations(robot, (), rng)
    shown_instead = (f"so its home configuration and {len(poses) - 1} random "
                     f"configuration{'s' if len(poses) != 2 else ''} within its limits (seed {seed}) "
                     f"are shown instead.")
    if poses_deg is None:
        note = f"{robot.name}'s robot file names no poses (poses_deg), {shown_instead}"
    else:
        lengths = sorted({len(q) for q in poses_deg.values()})
        note = (f"The chapter's named poses have {', '.join(map(str, lengths))} angles; "
                f"{robot.name} has {robot.n} joints, {shown_instead}")
    return poses, note


def dh_rows(robot: Robot) -> tuple[list[str], list[list]]:
    """The DH table for people: column names and one row per joint, angles in degrees (and,
    for a chain with fixed transforms after its rows, each one's rotation angle and shift).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> columns, rows = dh_rows(robot)
        >>> columns[:6]
        ['joint', 'name', 'a [m]', 'alpha [deg]', 'd [m]', 'offset [deg]']
        >>> print(*rows[1])
        2 shoulder_pitch 0.2 0.0 0.0 90.0 -90.0 90.0 0.35
    """
    prime = "" if robot.convention == "standard" else "_{i-1}"
    columns = ["joint", "name", f"a{prime} [m]", f"alpha{prime} [deg]", "d [m]",
               "offset [deg]", "q min [deg]", "q max [deg]", "mass [kg]"]
    deg = np.degrees
    rows = [[i + 1, robot.joint_names[i], robot.a[i], deg(robot.alpha[i]), robot.d[i],
             deg(robot.offset[i]), deg(robot.qlim[i, 0]), deg(robot.qlim[i, 1]), robot.mass[i]]
            for i in range(robot.n)]
    if robot.fixed is not None:         # the transforms after the rows: how far and how much
        columns += ["fixed turn [deg]", "fixed shift [m]"]
        for i, row in enumerate(rows):
            E = robot.fixed[i]
            row += [deg(float(np.linalg.norm(log_so3(E[:3, :3])))), float(np.linalg.norm(E[:3, 3]))]
    return columns, rows


# --------------------------------------------------------------------------------------------
# Validation


class _Validator(Validator):
    """The shared field checks plus a robot's own: poses and inertias."""

    def pose(self, value: Any, at: str) -> np.ndarray:
        if not isinstance(value, Sequence) or isinstance(value, str) or len(value) != 4:
            self.fail(at, f"must be a 4x4 matrix (list of 4 rows), got {show(value)}")
        T = np.array([self.vector(row, f"{at}[{r}]", 4) for r, row in enumerate(value)])
        if not np.array_equal(T[3], [0.0, 0.0, 0.0, 1.0]):
            self.fail(f"{at}[3]", f"last row must be [0, 0, 0, 1], got {T[3].tolist()}")
        for r in range(3):
            LENGTH.check(self, float(T[r, 3]), f"{at}[{r}][3]")
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
                          f"got {show(value)}")
        ixx, iyy, izz, ixy, iyz, ixz = (INERTIA.check(self, x, f"{at}[{k}]") for k, x in enumerate(value))
        inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        principal = np.linalg.eigvalsh(inertia)
        # Relative to the inertia's own scale: a 1e-20 kg m² part is as much a body as a
        # 1 kg m² one (eigvalsh is accurate to ~1e-16 of the largest moment).
        tol = INERTIA_RTOL * float(np.abs(principal).max())
        if principal[0] < -tol:
            self.fail(at, f"must be positive semi-definite, got principal moments "
                          f"{[float(f'{p:.6g}') for p in principal]}")
        return inertia

    def triangle(self, inertia: np.ndarray, at: str) -> None:
        """Warn about a ``(3, 3)`` inertia [kg·m²] whose principal moments break the triangle
        inequality (not a physical rigid body; accepted as given)."""
        principal = np.linalg.eigvalsh(inertia)
        tol = INERTIA_RTOL * float(np.abs(principal).max())
        p1, p2, p3 = principal
        if p1 + p2 < p3 - tol:
            self.warn(at, f"principal moments {[float(f'{p:.6g}') for p in principal]} break "
                          f"the triangle inequality (I1 + I2 >= I3): not a physical rigid body; "
                          f"accepted as given")

    def poses(self, value: Any, at: str, robot: Robot) -> dict[str, np.ndarray]:
        """Named configurations ``{name: [deg, ...]}``: one angle per joint, within its limits."""
        if not isinstance(value, dict) or not value:
            self.fail(at, f"must map pose names to {robot.n} joint angles [deg], got {show(value)}")
        poses = {}
        for name, angles in value.items():
            where = f"{at}.{name}"
            if not isinstance(name, str) or not name.strip():
                self.fail(at, f"pose names must be non-empty text, got {show(name)}")
            q = np.radians(np.asarray(self.vector(angles, where, robot.n), dtype=float))
            for j in range(robot.n):
                lo, hi = robot.qlim[j]
                if not lo - 1e-9 <= q[j] <= hi + 1e-9:
                    self.fail(f"{where}[{j}]", f"must lie within {robot.joint_names[j]}'s limits "
                                               f"[{math.degrees(lo):.6g}, {math.degrees(hi):.6g}] deg, "
                                               f"got {angles[j]!r}")
            poses[name] = q
        return poses

    def warn(self, at: str, message: str) -> None:
        warnings.warn(ParamsWarning(f"{self.source}: {at}: {message}"), stacklevel=5)

    def plausible(self, value: float, at: str, kind: str) -> None:
        """Warn about an angle beyond 2π or a length beyond 10 m (a unit slip?)."""
        if kind == "angle" and abs(value) > 2 * math.pi:
            self.warn(at, f"{value!r} rad is more than a full turn: an angle in degrees?")
        elif kind == "length" and abs(value) > MAX_PLAUSIBLE_LENGTH:
            self.warn(at, f"{value!r} m is over {MAX_PLAUSIBLE_LENGTH:g} m: a length in "
                          f"millimetres?")
