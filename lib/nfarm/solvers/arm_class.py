"""The closed form's class of arms and its branches: which robots :func:`nfarm.solvers.ik.closed_form`
solves (:func:`check_class`, :func:`in_class`, :func:`class_refusal`), the constants it needs
(:class:`ArmConstants`), and which of the four branches (:data:`BRANCHES`) a configuration lies
on (:func:`branch_of`).

The class, its symbols and the branches are defined in :mod:`nfarm.solvers.geometric_ik`'s
docstring. This module is apart from the closed form because the iterative solver
(:mod:`nfarm.solvers.iterative`) names the branch it converged to, and the closed form refines
with it: both import from here, neither from the other.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.kinematics import snap_right_angles
from ..model.robot import Robot, joint_array
from ..model.rotations import log_so3

__all__ = ["BRANCHES", "ArmConstants", "check_class", "in_class", "class_refusal", "branch_of"]

#: The branches, in the order of the result's branch axis.
BRANCHES = ("front, elbow up", "front, elbow down", "back, elbow up", "back, elbow down")
#: The base and roll axes must be this far from parallel to the pitch axes (sin of the angle):
#: the base and roll angles are determined to the rounding of the pose divided by it.
_MIN_SIN = 1e-6
#: Near the class [rad]: pitch axes this close to parallel (sin α2, sin α3), and fixed
#: transforms after the rows (:class:`~nfarm.model.robot.Robot`) turning this little and shifting
#: this times the arm's length, are solved through the parallel arm, whose branches seed LM
#: on the arm itself.
NEAR_TOL = 1e-4


@dataclass(frozen=True)
class ArmConstants:
    """The constants the closed form needs, of a robot of the class in standard DH (the
    symbols of :mod:`nfarm.solvers.geometric_ik`'s docstring); :func:`check_class` makes them.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> arm = check_class(robot)
        >>> arm.a2, arm.a3, arm.w     # the two links between the pitch axes, the lateral offset [m]
        (0.2, 0.18, 0.0)
    """

    RbT: np.ndarray | None       # base rotation transposed (None: identity base and tool part)
    pb: np.ndarray               # base origin
    C: np.ndarray | None         # tool⁻¹ rotation times Rx(−α5)
    c0: np.ndarray               # R c0 = the target point less the wrist point (world axes)
    sa1: float
    ca1: float
    sb: float
    cb: float
    s: float                     # sign(sin β)
    sigma2: float
    sigma: float
    w: float
    a1: float
    d1: float
    a2: float
    a3: float
    a4: float
    v: tuple                     # the tool point from the wrist point, in G's frame
    offset: np.ndarray           # (5,) joint offsets of the standard chain
    up: float                    # +1 / −1: frame 1's y axis points up / down (geometric_ik's docstring)
    elbow_up: float              # +1 / −1: the sign that makes the elbow "up" (geometric_ik's docstring)
    reach: float                 # a length scale [m]: |a| + |d| summed
    lo: np.ndarray
    hi: np.ndarray
    exact: bool = True           # False: the DH rows' arm, the robot's fixed transforms left out
    forward: float = 1.0         # +1 / −1: "front" is ahead of the base axis along x1 / behind it


def _Rx(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _snap(x: float) -> float:
    """cos or sin of a right angle exactly 0 or ±1 (as :func:`nfarm.model.kinematics.fk` takes them)."""
    return float(snap_right_angles(np.array(x)))


def _standard_chain(robot: Robot):
    """``(base, a, alpha, d, offset, tool)`` of the standard-DH chain equal to the robot's:
    a modified-DH chain ``Rx(α1) Tx(a1) [Rz(θ1) Tz(d1) Rx(α2) Tx(a2)] ··· Rz(θn) Tz(dn)`` is the
    base ``Rx(α1) Tx(a1)`` followed by standard links ``(d_i, a_{i+1}, α_{i+1})``."""
    if robot.convention == "standard":
        return robot.base, robot.a, robot.alpha, robot.d, robot.offset, robot.tool
    first = np.eye(4)
    first[:3, :3] = _Rx(robot.alpha[0])
    first[0, 3] = robot.a[0]
    a = np.append(robot.a[1:], 0.0)
    alpha = np.append(robot.alpha[1:], 0.0)
    return robot.base @ first, a, alpha, robot.d, robot.offset, robot.tool


def _reason(robot: Robot, axis_tol: float):
    """``(arm, None)`` for a robot of the class, else ``(None, reason)``. A robot near the
    class (:data:`NEAR_TOL`: pitch axes a little off parallel, or small fixed transforms after
    its rows) gets the constants of the parallel arm and ``arm.exact`` False: the closed form
    then seeds LM on the arm itself."""
    if robot.n != 5:
        return None, f"it has {robot.n} joints (the class has 5)"
    base, a, alpha, d, offset, tool = _standard_chain(robot)
    deg = np.degrees
    scale = float(np.abs(a).sum() + np.abs(d).sum())
    if robot.fixed is not None:
        for i, E in enumerate(robot.fixed):
            turn = float(np.linalg.norm(log_so3(E[:3, :3])))
            shift = float(np.linalg.norm(E[:3, 3]))
            if turn > NEAR_TOL or shift > NEAR_TOL * max(scale, 1e-3):
                return None, (f"joint {i + 1}'s fixed transform after its DH row turns "
                              f"{deg(turn):.3g}° and shifts {shift:.3g} m (the closed form seeds "
                              f"LM through at most {deg(NEAR_TOL):.3g}° and {NEAR_TOL:g} of the "
                              f"arm's length)")
    exact = robot.fixed is None or bool((robot.fixed == np.eye(4)).all())   # identities: a pure DH chain
    alpha = np.array(alpha, dtype=float)
    for i in (1, 2):
        if abs(math.sin(alpha[i])) > NEAR_TOL:
            return None, (f"joints {i + 1} and {i + 2} are not parallel (standard-DH alpha{i + 1} = "
                          f"{deg(alpha[i]):.6g}°; the class needs 0° or 180°, within "
                          f"{deg(NEAR_TOL):.3g}°)")
        if abs(math.sin(alpha[i])) > axis_tol:         # near: the parallel arm's, then LM
            alpha[i], exact = math.pi * round(alpha[i] / math.pi), False
    if abs(math.sin(alpha[0])) < _MIN_SIN:
        return None, (f"joint 1 is parallel to joints 2-4 (standard-DH alpha1 = "
                      f"{deg(alpha[0]):.6g}°): no base joint")
    beta = alpha[1] + alpha[2] + alpha[3]
    if abs(math.sin(beta)) < _MIN_SIN:
        return None, (f"joint 5 is parallel to joints 2-4 (alpha2 + alpha3 + alpha4 = "
                      f"{deg(beta):.6g}°): no roll joint")
    for i in (1, 2):
        if abs(a[i]) <= 1e-9 * max(scale, 1e-300):
            return None, (f"standard-DH a{i + 1} = {a[i]:g} m: joints 2-4 need two links between "
                          f"their axes (a2 and a3 non-zero)")
    sigma2 = math.copysign(1.0, math.cos(alpha[1]))
    sigma = sigma2 * math.copysign(1.0, math.cos(alpha[2]))
    Rb, Re = base[:3, :3], tool[:3, :3]
    C = Re.T @ _Rx(-alpha[4])
    c0 = Re.T @ tool[:3, 3] + C @ np.array([a[4], 0.0, d[4]])
    plain = np.array_equal(Rb, np.eye(3)) and np.array_equal(C, np.eye(3))
    # "Elbow up": frame 1's y axis has the up-component sin α1 · (z0 · up) (z0 the base axis),
    # and the elbow lies on the side of the shoulder-wrist line given by −a2 a3 sin γ.
    # "Front": where the wrist point lies at the arm's home (q = 0 within its limits), ahead of
    # the base axis along x1 or behind it (a URDF's converted frame 0 may face backwards).
    home = np.clip(0.0, robot.qlim[:, 0], robot.qlim[:, 1]) + offset
    gamma = sigma2 * home[2]
    phi = home[1] + gamma + sigma * home[3]
    ahead = a[0] + a[1] * math.cos(home[1]) + a[2] * math.cos(home[1] + gamma) + a[3] * math.cos(phi)
    forward = -1.0 if ahead < 0 else 1.0
    g = robot.gravity
    up_world = -g / np.linalg.norm(g) if np.any(g) else Rb[:, 2]
    vertical = float(Rb[:, 2] @ up_world)
    up = math.copysign(1.0, math.sin(alpha[0]) * (vertical if abs(vertical) > 1e-9 else 1.0))
    return ArmConstants(
        RbT=None if plain else Rb.T.copy(), pb=base[:3, 3].copy(), C=None if plain else C,
        c0=c0, sa1=_snap(math.sin(alpha[0])), ca1=_snap(math.cos(alpha[0])),
        sb=_snap(math.sin(beta)), cb=_snap(math.cos(beta)), s=math.copysign(1.0, math.sin(beta)),
        sigma2=sigma2, sigma=sigma,
        w=float(d[1] + sigma2 * d[2] + sigma * d[3]), a1=float(a[0]), d1=float(d[0]),
        a2=float(a[1]), a3=float(a[2]), a4=float(a[3]),
        v=tuple(float(x) for x in np.array([a[4], 0.0, d[4]]) + _Rx(alpha[4]) @ tool[:3, 3]),
        offset=np.asarray(offset, dtype=float), up=up,
        elbow_up=up * math.copysign(1.0, a[1] * a[2]), reach=max(scale, 1e-3),
        lo=robot.qlim[:, 0], hi=robot.qlim[:, 1], exact=exact, forward=forward), None


def check_class(robot: Robot, axis_tol: float = 1e-10) -> ArmConstants:
    """The robot's constants for :func:`nfarm.solvers.ik.closed_form`, or a one-line ``ValueError`` naming the
    condition of the class (:mod:`nfarm.solvers.geometric_ik`'s docstring) it breaks.

    ``axis_tol`` [rad]: how far α2 and α3 may be from 0 or π and still count as parallel
    axes; the closed form then treats them as exactly parallel, which moves the tool by at
    most ``axis_tol`` times the arm's length (1e-10 rad: < 1e-10 m on the shipped arms).
    Further off, up to :data:`NEAR_TOL`, the arm is near the class: the parallel arm's
    branches seed LM on the arm itself (``ArmConstants.exact`` False).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> import dataclasses
        >>> check_class(robot).sigma     # cos α2 cos α3: the pitch axes point the same way
        1.0
        >>> check_class(dataclasses.replace(robot, alpha=np.zeros(5)))  # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        ValueError: intelbot5 has no closed-form IK here: joint 1 is parallel to joints 2-4 ...
    """
    if not isinstance(robot, Robot):
        raise ValueError(f"closed_form needs a Robot, got {type(robot).__name__}")
    arm, reason = _reason(robot, axis_tol)
    if arm is None:
        raise ValueError(f"{robot.name} has no closed-form IK here: {reason}; the closed form "
                         f"covers yaw-pitch-pitch-pitch-roll arms")
    return arm


def in_class(robot: Robot, axis_tol: float = 1e-10) -> bool:
    """Whether :func:`nfarm.solvers.ik.closed_form` solves this robot.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> import dataclasses
        >>> in_class(robot), in_class(dataclasses.replace(robot, alpha=np.zeros(5)))     # all axes parallel
        (True, False)
    """
    return class_refusal(robot, axis_tol) is None


def class_refusal(robot: Robot, axis_tol: float = 1e-10) -> str | None:
    """The one line :func:`check_class` refuses the robot with, or ``None`` for a robot of
    the class.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> import dataclasses
        >>> class_refusal(robot) is None
        True
        >>> class_refusal(dataclasses.replace(robot, alpha=np.zeros(5)))  # doctest: +ELLIPSIS
        'intelbot5 has no closed-form IK here: joint 1 is parallel to joints 2-4 ...'
    """
    try:
        check_class(robot, axis_tol)
    except ValueError as exc:
        return str(exc)
    return None


def branch_of(robot: Robot, q, axis_tol: float = 1e-10) -> np.ndarray:
    """``(...)`` the index in :data:`BRANCHES` of the branch configurations ``q (..., 5)``
    [rad] lie on: front when the wrist point is on the side of the base axis it is on at the
    arm's home (q = 0 within the limits: ahead along x1 on both arms of the study), and the elbow
    by the sign of its angle (:mod:`nfarm.solvers.geometric_ik`'s docstring). Raises ``ValueError`` for a robot not of the
    class.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> q = np.array([0.3, 0.2, -0.4, 0.5, 0.1])     # [rad]
        >>> BRANCHES[branch_of(robot, q)]
        'front, elbow up'
        >>> from nfarm.model.kinematics import fk
        >>> from nfarm.solvers.geometric_ik import closed_form
        >>> branch_of(robot, closed_form(robot, fk(robot, q)).q).tolist()     # its four solutions (4, 5)
        [0, 1, 2, 3]
    """
    g = check_class(robot, axis_tol)
    t = joint_array(robot, q) + g.offset
    gamma = g.sigma2 * t[..., 2]
    phi = t[..., 1] + gamma + g.sigma * t[..., 3]
    ahead = g.a1 + g.a2 * np.cos(t[..., 1]) + g.a3 * np.cos(t[..., 1] + gamma) + g.a4 * np.cos(phi)
    side = np.where(ahead < 0, -1.0, 1.0)            # of the base axis along x1
    back = g.forward * side < 0
    down = g.elbow_up * side * np.sin(gamma) > 0
    return 2 * back.astype(int) + down.astype(int)
