"""How a tool pose becomes a learner's inputs: the encodings of a pose ``T_0e`` (:func:`encode`),
the chart an arm's poses are read in (:func:`arm_chart`), and :class:`PoseEncoder`, which learns
the unwrapping and scaling from training poses — shared by the learned IK
(:class:`nfarm.learning.learned.LearnedIK`) and its baselines, so that both see the same inputs.

The dissertation's IK page feeds its five ANFIS models, one per joint, with the target's
orientation quaternion and position (7 inputs): ``"quat_xyz"``. The **encodings** of a target
pose ``T_0e`` (:func:`encode`):

* ``"quat_xyz"`` — the dissertation's ``[w, x, y, z]`` quaternion (kept on one hemisphere,
  ``w ≥ 0``, so that ``q`` and ``−q`` are one input) and the position ``[x, y, z]``: 7 inputs.
  The hemisphere is a cut: a rotation by about 180° (the gripper pointing down is one) has
  ``w ≈ 0``, and across it ``x, y, z`` change sign — a jump the model must learn;
* ``"axes_xyz"`` — the position, the tool's approach axis (the z column of ``R``) and its
  x axis: 9 inputs, continuous everywhere (two columns of ``R`` determine it);
* ``"arm_plane"`` — six numbers for an arm whose tool's approach axis stays in the vertical
  plane through the tool point (a base yaw, then joints pitching in that plane, then a roll:
  intelbot5, the SO-101): the tool point's azimuth ``atan2(y, x)``, its distance ``r`` from the
  base axis and its height ``z``; with ``R' = Rz(−azimuth) · R`` (the orientation seen in the
  arm's plane), the pitch ``φ = atan2(R'₀₂, −R'₂₂)`` of the approach axis from pointing straight
  down, as ``cos φ, sin φ``, and the roll ``ψ = atan2(R'₁₀, R'₁₁)`` about it. The pose set of such
  an arm is 5-dimensional and this is a minimal chart of it but for the pitch, which is kept as a
  point on the circle because the arm's pitch ``q2 + q3 + q4`` spans more than a turn: a single
  pitch angle would jump by 2π inside the region. For intelbot5 in a region that keeps the tool
  in front of the base axis, ``q1`` *is* the azimuth and ``q5`` the roll less a constant, so two of
  the five models are linear maps, which a first-order Sugeno rule represents exactly.
  The pose is read in the robot's :func:`arm_chart`: in DH frame 0 (whose z is the base axis),
  at the point of the roll axis nearest the tool point — the identity for intelbot5; for the
  SO-101, whose tool point is 7.9 mm off its roll axis, the difference between its approach axis
  leaving the arm's plane by up to 27° (in the world) and by 0.13° (in the chart).

Angular inputs (the azimuth and the roll of ``"arm_plane"``) are unwrapped about the circular
mean of the training data (stored with the model), so a region that straddles ±180° is not cut.
Chapter 06's contest (``figures/tables/06_ik_contest``) puts the dissertation's encoding against
the arm's plane: a first-order rule's consequent is linear in its inputs, and the joint angles
are far from linear in a quaternion's components.

Inputs are scaled to ``[0, 1]`` by the training set's range (stored with the model,
:func:`input_scaling`, which :class:`nfarm.learning.learned_id.LearnedID` uses for its state inputs
too), so grid partitions and clustering see every input alike.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..infra.arguments import check_choice
from ..infra.reading import Validator, show
from ..model.kinematics import fk_all
from ..model.robot import Robot
from ..model.rotations import matrix_to_quat
from .estimator import Estimator

__all__ = ["ENCODINGS", "ANGULAR", "FEATURE_NAMES", "SPAN_MIN", "PLAUSIBLE_INPUT", "encode", "arm_chart",
           "out_of_plane", "input_scaling", "check_scaling", "PoseEncoder"]

#: The encodings and their number of inputs.
ENCODINGS = {"quat_xyz": 7, "axes_xyz": 9, "arm_plane": 6}
#: Columns of each encoding that are angles [rad] (unwrapped about a centre).
ANGULAR = {"quat_xyz": (), "axes_xyz": (), "arm_plane": (0, 5)}
#: The inputs' names, per encoding.
FEATURE_NAMES = {"quat_xyz": ["qw", "qx", "qy", "qz", "x", "y", "z"],
                 "axes_xyz": ["x", "y", "z", "ax", "ay", "az", "nx", "ny", "nz"],
                 "arm_plane": ["azimuth", "r", "z", "cos_pitch", "sin_pitch", "roll"]}
#: An input whose training range is narrower than this is constant: scaled by 1, not by its range.
SPAN_MIN = 1e-12
#: A saved input's lowest value and span must lie within ±PLAUSIBLE_INPUT: every input of the
#: study (angles, metres, rad/s, rad/s² and their products) is far inside, and an edited 1e308
#: or 1e-300 would otherwise turn predictions into inf or 1e287.
PLAUSIBLE_INPUT = 1e6


def arm_chart(robot: Robot) -> np.ndarray | None:
    """``(2, 4, 4)``: the poses ``[B, W]`` that put a tool pose into the frame ``"arm_plane"``
    reads, ``B · T_0e · W``, or ``None`` when both are the identity (intelbot5).

    ``B = base⁻¹`` moves the world into DH frame 0, whose z axis is the base axis. ``W`` is, in
    the tool frame, the frame on the last joint's axis nearest the tool point, its z along that
    axis (on the side of the tool axis nearest it: z for a tool frame whose z is the approach,
    x for one in ROS's convention, x along the approach) and its x the tool's x made
    perpendicular to it (the tool's y when its x lies within 26° of the axis). For an arm whose
    tool point lies off its roll axis (the SO-101's, by 7.9 mm) the tool point leaves the arm's
    vertical plane as the wrist rolls, the point on the roll axis does not.
    """
    F = fk_all(robot, np.zeros(robot.n))
    axis_frame = F[-2] if robot.convention == "standard" else F[-1]
    tool = F[-1] @ robot.tool
    Rt = tool[:3, :3].T                                          # world → tool frame
    c = Rt @ (axis_frame[:3, 3] - tool[:3, 3])                   # a point on the axis
    u = Rt @ axis_frame[:3, 2]
    nearest = int(np.argmax(np.abs(u)))                          # the tool axis along the roll axis
    u = u if u[nearest] >= 0 else -u
    w = c - np.dot(c, u) * u
    k = 0 if abs(u[0]) < 0.9 else 1                              # the tool's x, or its y
    x = np.eye(3)[k] - u[k] * u
    x /= np.linalg.norm(x)
    W = np.eye(4)
    W[:3, :3], W[:3, 3] = np.column_stack([x, np.cross(u, x), u]), w
    W[np.abs(W) < 1e-12] = 0.0
    W[np.abs(W - 1) < 1e-12] = 1.0
    B = np.eye(4)                                                # base⁻¹ of a rigid transform
    B[:3, :3] = robot.base[:3, :3].T
    B[:3, 3] = -B[:3, :3] @ robot.base[:3, 3]
    if np.array_equal(W, np.eye(4)) and np.array_equal(robot.base, np.eye(4)):
        return None
    return np.stack([B, W])


def _in_chart(T: np.ndarray, chart: np.ndarray | None) -> np.ndarray:
    return T if chart is None else chart[0] @ T @ chart[1]


def encode(T_0e: np.ndarray, encoding: str, chart: np.ndarray | None = None) -> np.ndarray:
    """Input features ``(..., d)`` of tool poses ``T_0e (..., 4, 4)`` (module docstring);
    ``"arm_plane"`` reads the poses in the robot's :func:`arm_chart` when given."""
    check_choice("encoding", encoding, ENCODINGS)
    T = np.asarray(T_0e, dtype=float)
    if encoding == "arm_plane":
        T = _in_chart(T, chart)
    p, R = T[..., :3, 3], T[..., :3, :3]
    if encoding == "quat_xyz":
        quat = matrix_to_quat(R)                         # [w, x, y, z]
        quat = np.where(quat[..., :1] < 0, -quat, quat)  # one hemisphere: w >= 0
        return np.concatenate([quat, p], axis=-1)
    if encoding == "axes_xyz":
        return np.concatenate([p, R[..., :, 2], R[..., :, 0]], axis=-1)
    azimuth = np.arctan2(p[..., 1], p[..., 0])
    c, s = np.cos(azimuth), np.sin(azimuth)
    # R' = Rz(−azimuth) R: rows 0 and 1 rotated, row 2 unchanged; only R'_02, R'_10, R'_11
    # are needed, computed alone (fewer operations, the same bits as the full product).
    r0z = c * R[..., 0, 2] + s * R[..., 1, 2]
    r1x = -s * R[..., 0, 0] + c * R[..., 1, 0]
    r1y = -s * R[..., 0, 1] + c * R[..., 1, 1]
    pitch = np.arctan2(r0z, -R[..., 2, 2])
    roll = np.arctan2(r1x, r1y)
    return np.stack([azimuth, np.hypot(p[..., 0], p[..., 1]), p[..., 2], np.cos(pitch),
                     np.sin(pitch), roll], axis=-1)


def out_of_plane(T_0e: np.ndarray, chart: np.ndarray | None = None) -> np.ndarray:
    """Angle [rad] ``(...)`` by which the tool's approach axis leaves the vertical plane through
    the tool point and the base axis: 0 for every pose of an arm ``"arm_plane"`` describes
    (with ``chart``, :func:`arm_chart`: the roll axis and its point nearest the tool)."""
    T = _in_chart(np.asarray(T_0e, dtype=float), chart)
    azimuth = np.arctan2(T[..., 1, 3], T[..., 0, 3])
    normal = -np.sin(azimuth) * T[..., 0, 2] + np.cos(azimuth) * T[..., 1, 2]
    return np.arcsin(np.clip(np.abs(normal), 0.0, 1.0))


def _unwrap(X: np.ndarray, columns: tuple, centre: np.ndarray, *, inplace: bool = False
            ) -> np.ndarray:
    """Angular columns mapped into ``[centre − π, centre + π)`` (a copy unless ``inplace``)."""
    if columns:
        X = X if inplace else X.copy()
        for column, c in zip(columns, centre):
            X[..., column] = c + np.mod(X[..., column] - c + np.pi, 2 * np.pi) - np.pi
    return X


def input_scaling(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The lowest value ``lo (d,)`` and span ``(d,)`` of training inputs ``X (N, d)``, so that
    ``(X − lo) / span`` lies in ``[0, 1]``; an input spanning :data:`SPAN_MIN` or less is
    constant and is scaled by 1, not divided by its span (an ANFIS refuses it by name if it is
    a premise input)."""
    span = np.ptp(X, axis=0)
    return X.min(axis=0), np.where(span > SPAN_MIN, span, 1.0)


def check_scaling(v: Validator, lo: np.ndarray, span: np.ndarray, at_lo: str, at_span: str) -> None:
    """A saved scaling (:func:`input_scaling`) is plausible: ``lo`` within ±:data:`PLAUSIBLE_INPUT`,
    spans in ``(SPAN_MIN, PLAUSIBLE_INPUT]`` (else ``v.fail`` naming the field)."""
    if (np.abs(lo) > PLAUSIBLE_INPUT).any():
        v.fail(at_lo, f"must hold numbers within ±{PLAUSIBLE_INPUT:g}, got {show(lo.tolist())}")
    if ((span <= SPAN_MIN) | (span > PLAUSIBLE_INPUT)).any():
        v.fail(at_span, f"must hold spans in ({SPAN_MIN:g}, {PLAUSIBLE_INPUT:g}], got {show(span.tolist())}")


class PoseEncoder(Estimator):
    """Tool poses to scaled inputs: :func:`encode` (read in the robot's :func:`arm_chart` for
    ``"arm_plane"``), angular inputs unwrapped about the training poses' circular mean, every
    input scaled to ``[0, 1]`` by the training poses' range (:func:`input_scaling`).

    Args:
        encoding: one of :data:`ENCODINGS`.
        max_out_of_plane: for ``"arm_plane"``, the largest angle [rad] by which a training
            pose's approach axis may leave the arm's vertical plane (:func:`out_of_plane`);
            beyond it the encoding loses information and ``fit`` refuses the robot.

    Learned attributes: ``chart_`` (:func:`arm_chart` ``(2, 4, 4)`` or ``None``),
    ``angle_centre_`` (``(a,)`` [rad], one per angular input of :data:`ANGULAR`), ``input_lo_``
    and ``input_span_`` (``(d,)``, in the inputs' units: rad, m or none), ``feature_names_``
    (the ``d`` inputs' names, :data:`FEATURE_NAMES`).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.kinematics import fk
        >>> from nfarm.model.robot import load_robot, sample_configurations
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> T = fk(robot, sample_configurations(robot, 100, 0))                 # (100, 4, 4)
        >>> encoder = PoseEncoder("arm_plane").fit(robot, T)
        >>> X = encoder.transform(T)
        >>> X.shape, float(X.min()), float(X.max()), encoder.feature_names_[:3]
        ((100, 6), 0.0, 1.0, ['azimuth', 'r', 'z'])
    """

    _fitted = "input_span_"

    def __init__(self, encoding: str = "quat_xyz", max_out_of_plane: float = 1e-6):
        self.encoding = encoding
        self.max_out_of_plane = max_out_of_plane

    def fit(self, robot: Robot, T: np.ndarray) -> "PoseEncoder":
        """Learn the chart, the unwrapping centres and the scaling from training poses
        ``T (N, 4, 4)`` (rigid transforms, checked by the caller)."""
        self.fit_transform(robot, T)
        return self

    def fit_transform(self, robot: Robot, T: np.ndarray) -> np.ndarray:
        """:meth:`fit`, returning the training poses' scaled inputs ``(N, d)``.

        Raises:
            ValueError: an unknown encoding, or ``"arm_plane"`` for poses that leave the arm's
                plane by more than ``max_out_of_plane`` (naming the robot and the angle).
        """
        check_choice("encoding", self.encoding, ENCODINGS)
        self.chart_ = arm_chart(robot) if self.encoding == "arm_plane" else None
        if self.encoding == "arm_plane":
            worst = float(out_of_plane(T, self.chart_).max())
            if not worst <= self.max_out_of_plane:
                raise ValueError(f"encoding 'arm_plane' needs the tool's approach axis in the "
                                 f"vertical plane through the tool point; {robot.name}'s training "
                                 f"poses leave it by up to {math.degrees(worst):.3g} deg: use "
                                 f"'axes_xyz'")
        X = encode(T, self.encoding, self.chart_)
        columns = ANGULAR[self.encoding]
        self.angle_centre_ = np.angle(np.exp(1j * X[:, columns]).mean(axis=0)) if columns \
            else np.zeros(0)
        X = _unwrap(X, columns, self.angle_centre_)
        self.input_lo_, self.input_span_ = input_scaling(X)
        self.feature_names_ = list(FEATURE_NAMES[self.encoding])
        return (X - self.input_lo_) / self.input_span_

    def transform(self, T: np.ndarray) -> np.ndarray:
        """Scaled inputs ``(..., d)`` of poses ``T (..., 4, 4)``: in ``[0, 1]`` inside the
        training poses' range, beyond it outside."""
        self._check_fitted()
        X = _unwrap(encode(T, self.encoding, self.chart_), ANGULAR[self.encoding],
                    self.angle_centre_, inplace=True)
        X -= self.input_lo_
        X /= self.input_span_
        return X

    # -- persistence --------------------------------------------------------------------------

    def to_dict(self) -> dict:
        """The parameters and learned state as JSON-ready fields: ``encoding``,
        ``max_out_of_plane``, ``angle_centre``, ``input_lo``, ``input_span`` and, when there is
        one, ``chart``. A :class:`nfarm.learning.learned.LearnedIK` file holds them among its own."""
        self._check_fitted()
        return {"encoding": self.encoding, "max_out_of_plane": self.max_out_of_plane,
                "angle_centre": self.angle_centre_.tolist(), "input_lo": self.input_lo_.tolist(),
                "input_span": self.input_span_.tolist()} | \
            ({} if self.chart_ is None else {"chart": self.chart_.tolist()})

    @classmethod
    def from_dict(cls, data: Any, source: str = "<dict>") -> "PoseEncoder":
        """The encoder :meth:`to_dict` described, each field checked (a ``ParamsError`` naming
        ``source`` and the field); other fields of ``data`` are left to its caller."""
        v = Validator(source)
        if not isinstance(data, Mapping):
            v.fail("", f"must be a mapping of fields, got {show(data)}")
        for key in ("encoding", "max_out_of_plane", "angle_centre", "input_lo", "input_span"):
            if key not in data:
                v.fail(key, "required field is missing")
        encoding = v.choice(data["encoding"], "encoding", tuple(ENCODINGS))
        d = ENCODINGS[encoding]
        lo = v.array(data["input_lo"], "input_lo", (d,))
        span = v.array(data["input_span"], "input_span", (d,))
        check_scaling(v, lo, span, "input_lo", "input_span")
        max_out = v.number(data["max_out_of_plane"], "max_out_of_plane", lo=0.0, hi=math.pi)
        centre = v.array(data["angle_centre"], "angle_centre", (len(ANGULAR[encoding]),))
        if (np.abs(centre) > 2 * math.pi).any():
            v.fail("angle_centre", f"must hold angles within [-2π, 2π] rad, got {show(centre.tolist())}")
        chart = v.array(data["chart"], "chart", (2, 4, 4)) if data.get("chart") is not None else None
        for k, T in enumerate([] if chart is None else chart):
            R = T[:3, :3]
            if not (np.allclose(T[3], [0.0, 0.0, 0.0, 1.0], rtol=0.0, atol=1e-12)
                    and np.allclose(R @ R.T, np.eye(3), rtol=0.0, atol=1e-9)
                    and np.linalg.det(R) > 0 and (np.abs(T[:3, 3]) <= PLAUSIBLE_INPUT).all()):
                v.fail(f"chart[{k}]", "must be a rigid transform (a rotation, a plausible position, last "
                                      "row 0 0 0 1)")
        encoder = cls(encoding, max_out)
        encoder.chart_, encoder.angle_centre_, encoder.input_lo_, encoder.input_span_ = chart, centre, lo, span
        encoder.feature_names_ = list(FEATURE_NAMES[encoding])
        return encoder
