"""What the arm panel (:mod:`nfarm.publishing.panel`) shows, computed without widgets.

The panel is the dissertation's interactive program ("Intelbot", its chapter 4) made
desktop-free: forward kinematics from joint sliders, inverse kinematics by every method of the
study side by side, a trajectory between two configurations, and its torques. Each page's
numbers come from one function here, so that the tests check them against the library's own
functions without a browser, and the widgets only lay them out.

Units follow the panel, not the library: the reader types and reads millimetres and degrees;
these functions take and return them where their names say so (``_mm``, ``_deg``) and radians
and metres otherwise. Every bad input raises :class:`PanelInputError`, one line naming the field
and the rule broken, which the panel shows in place of a result.
"""

from __future__ import annotations

import numbers
import re
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..infra.paths import BUILD, PARAMS, shown_path
from ..infra.reading import ParamsError
from ..learning.learned import LearnedIK
from ..learning.learned_id import LearnedID
from ..model.dynamics import coriolis, gravity_torques, mass_matrix, rnea
from ..model.kinematics import fk, manipulability, min_singular_value
from ..model.robot import Robot, is_robot_name, robot_hash
from ..model.rotations import matrix_to_quat, matrix_to_rpy, pose_error, rpy_to_matrix
from ..solvers.geometric_ik import class_refusal, closed_form
from ..solvers.ik import check_targets, solve
from ..solvers.trajectory import Trajectory, TrajectoryLimitWarning, cubic, quintic

__all__ = ["PanelInputError", "shipped_robots", "PoseReadout", "pose_readout", "target_pose",
           "parse_pose_matrix", "Answer", "ik_answers", "Models", "trained_models",
           "joint_trajectory", "TorqueParts", "torque_parts", "PROFILES"]

#: The trajectory profiles the panel offers: the dissertation's cubic, and the quintic the
#: study's data sets use (zero acceleration at both ends).
PROFILES = {"cubic": cubic, "quintic": quintic}


class PanelInputError(ValueError):
    """A value typed into the panel breaks a rule; the message is one line naming the field."""


def _one_line(error: BaseException) -> str:
    text = str(error).strip().splitlines()
    return text[0] if text else type(error).__name__


def shown(value, digits: int = 6) -> str:
    """``value`` as a message shows it: numbers plainly (``1``, ``0.2``, ``nan``, ``1e+300``, never
    ``np.float64(1.0)``), sequences and arrays as ``[…]`` (the first 8 values), text quoted,
    anything else by its type's name.

    Example:
        >>> shown(np.float64(1.0)), shown([np.float64(0.5), np.nan]), shown("0.2"), shown(None)
        ('1', '[0.5, nan]', "'0.2'", 'None')
    """
    if value is None or isinstance(value, (bool, np.bool_)):
        return str(bool(value)) if value is not None else "None"
    if isinstance(value, numbers.Real):
        return f"{float(value):.{digits}g}"
    if isinstance(value, numbers.Complex):
        return f"{complex(value)}"
    if isinstance(value, (str, bytes)):
        return repr(value[:40])
    if isinstance(value, np.ndarray) or isinstance(value, (list, tuple)):
        flat = np.ravel(np.asarray(value, dtype=object)) if not isinstance(value, np.ndarray) else value.ravel()
        items = [shown(v, digits) for v in flat[:8]]
        return "[" + ", ".join(items) + (", …" if len(flat) > 8 else "") + "]"
    return type(value).__name__


def _reals(name: str, value, shape: tuple[int, ...] | None = None) -> np.ndarray:
    """``value`` as a float array of real, finite numbers (of ``shape`` when given), or a
    :class:`PanelInputError` naming ``name``: ``None``, text, bytes, booleans, complex numbers
    and ragged lists are refused, not converted."""
    if value is None or isinstance(value, (str, bytes)):
        raise PanelInputError(f"{name}: numbers needed, got {shown(value)}")
    try:
        array = value if isinstance(value, np.ndarray) else np.asarray(value)
    except (TypeError, ValueError):
        raise PanelInputError(f"{name}: numbers needed, got a ragged or mixed {type(value).__name__}") from None
    kind = array.dtype.kind
    if kind not in "iuf":
        what = {"b": "booleans", "c": "complex numbers", "U": "text", "S": "bytes",
                "O": "objects or ragged lists"}.get(kind, f"values of dtype {array.dtype}")
        raise PanelInputError(f"{name}: real numbers needed, got {what} ({shown(value)})")
    array = array.astype(float)
    if shape is not None and array.shape != shape:
        raise PanelInputError(f"{name}: shape {shape} needed, got {array.shape}")
    if not np.isfinite(array).all():
        raise PanelInputError(f"{name}: finite numbers needed, got {shown(array)}")
    return array


def _real(name: str, value, unit: str = "", *, low: float | None = None, high: float | None = None,
          positive: bool = False) -> float:
    """``value`` as one finite real number within its bounds, or a one-line
    :class:`PanelInputError` naming ``name``, the value and the bound."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise PanelInputError(f"{name}: a real number needed, got {type(value).__name__} {shown(value)}")
    x = float(value)
    unit = f" {unit}" if unit else ""
    if not np.isfinite(x):
        raise PanelInputError(f"{name}: a finite number needed, got {shown(x)}")
    if positive and not x > 0:
        raise PanelInputError(f"{name}: must be > 0, got {shown(x)}{unit}")
    if low is not None and x < low:
        raise PanelInputError(f"{name}: {shown(x)}{unit} is below the bound of {shown(low)}{unit}")
    if high is not None and x > high:
        raise PanelInputError(f"{name}: {shown(x)}{unit} is over the bound of {shown(high)}{unit}")
    return x


def _whole(name: str, value, *, low: int = 1) -> int:
    """``value`` as a whole number >= ``low``, or a one-line :class:`PanelInputError`."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral) or value < low:
        kind = "" if isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_)) else \
            f"{type(value).__name__} "
        raise PanelInputError(f"{name}: a whole number >= {low} needed, got {kind}{shown(value)}")
    return int(value)


def _robot(robot) -> Robot:
    if not isinstance(robot, Robot):
        raise PanelInputError(f"robot: a Robot (nfarm.model.robot.load_robot) needed, got {type(robot).__name__}")
    return robot


def _model_of(name: str, model, cls: type, robot: Robot):
    """``model``, a fitted ``cls`` of ``robot`` (or ``None``); a model of another robot, not
    fitted, or of another kind is refused in one line."""
    if model is None:
        return None
    if not isinstance(model, cls):
        raise PanelInputError(f"{name}: a {cls.__name__} or None needed, got {type(model).__name__}")
    own = getattr(model, "robot_hash_", None)
    if own is None:
        raise PanelInputError(f"{name}: the {cls.__name__} is not fitted")
    if own != robot_hash(robot):
        raise PanelInputError(f"{name}: the model was trained for the robot {model.robot_name_!r} "
                              f"({model.n_joints_} joints, parameters {own[:12]}…), not for "
                              f"{robot.name!r} as this robot file gives it: train it for this robot")
    return model


def shipped_robots(directory: Path | None = None) -> dict[str, Path]:
    """The robot files shipped in ``params/robots/`` (``*.yaml``), by file stem."""
    directory = directory or PARAMS / "robots"
    return {p.stem: p for p in sorted(directory.glob("*.yaml"))}


def arm_scale(robot: Robot) -> float:
    """The arm's size [m]: the sum of its DH lengths ``|a| + |d|`` (and the tool's offset), the
    scale against which the panel judges nearness to a singularity."""
    return float(np.abs(robot.a).sum() + np.abs(robot.d).sum() + np.linalg.norm(robot.tool[:3, 3]))


# --------------------------------------------------------------------------------------------
# Forward kinematics


@dataclass(frozen=True)
class PoseReadout:
    """The tool pose of one configuration as the panel shows it.

    Attributes:
        T_0e: ``(4, 4)`` tool pose (world frame) [m].
        position_mm: ``(3,)`` tool position [mm].
        rpy_deg: ``(3,)`` ZYX roll, pitch, yaw [deg] (:func:`nfarm.model.rotations.matrix_to_rpy`).
        quat: ``(4,)`` unit quaternion ``[w, x, y, z]``, ``w >= 0``.
        manipulability: Yoshikawa's ``w`` of the position Jacobian [m³].
        sigma_position_m: smallest singular value of the position Jacobian [m].
        sigma_orientation: smallest singular value of the orientation Jacobian [rad/rad].
        warning: a sentence when the arm is near a singularity, else ``""``.
    """

    T_0e: np.ndarray
    position_mm: np.ndarray
    rpy_deg: np.ndarray
    quat: np.ndarray
    manipulability: float
    sigma_position_m: float
    sigma_orientation: float
    warning: str


def pose_readout(robot: Robot, q, *, near_singular: float = 0.02) -> PoseReadout:
    """The tool pose, its rotation in three forms and the distance to a singularity at ``q (n,)``
    [rad].

    Near a singularity means: the position Jacobian's smallest singular value below
    ``near_singular`` × :func:`arm_scale` (the tool can hardly move in some direction: over the
    base axis, where the base joint cannot move it sideways, or with the elbow and wrist
    stretched in a line), or the orientation Jacobian's below ``near_singular`` (two joints turn
    the tool about nearly the same axis: the tool axis along the base axis). The threshold is
    assumed: at 0.02, 6.9 % of 20 000 intelbot5 configurations drawn within its limits get a
    warning (5.3 % for the position, 1.7 % for the orientation; at 0.05, 16 % for the position
    alone), and 5.1 % of the SO-101's.
    """
    robot = _robot(robot)
    q = _reals("configuration q [rad]", q, (robot.n,))
    near_singular = _real("near_singular", near_singular, positive=True)
    T = fk(robot, q)
    sigma_p = float(min_singular_value(robot, q, "position"))
    sigma_r = float(min_singular_value(robot, q, "orientation"))
    warning = []
    if sigma_p < near_singular * arm_scale(robot):
        warning.append(f"the tool can hardly move in one direction (σ_min of the position Jacobian "
                       f"{sigma_p * 1e3:.3g} mm per rad)")
    if sigma_r < near_singular:
        warning.append(f"two joints turn the tool about nearly the same axis (σ_min of the "
                       f"orientation Jacobian {sigma_r:.3g})")
    return PoseReadout(T, T[:3, 3] * 1e3, np.degrees(matrix_to_rpy(T[:3, :3])), matrix_to_quat(T[:3, :3]),
                       float(manipulability(robot, q)), sigma_p, sigma_r,
                       ("Near a singularity: " + "; ".join(warning) + ".") if warning else "")


# --------------------------------------------------------------------------------------------
# Inverse kinematics


def target_pose(position_mm: Sequence[float], rpy_deg: Sequence[float]) -> np.ndarray:
    """The pose ``(4, 4)`` [m] with tool position ``position_mm (3,)`` and ZYX roll-pitch-yaw
    ``rpy_deg (3,)``."""
    position = _reals("target position [mm]", position_mm, (3,))
    rpy = _reals("target roll, pitch, yaw [deg]", rpy_deg, (3,))
    T = np.eye(4)
    T[:3, :3] = rpy_to_matrix(np.radians(rpy))
    T[:3, 3] = position / 1e3
    return T


def parse_pose_matrix(text: str, *, ortho_tol: float = 1e-6) -> np.ndarray:
    """A typed tool pose: three or four rows separated by ``;`` or new lines, four numbers each
    (rotation row and position [mm]); a fourth row must be ``0 0 0 1``. Returns ``(4, 4)`` [m].

    Raises:
        PanelInputError: not numbers, wrong shape, or a rotation part that is not a rotation
            (``|RᵀR − I| > ortho_tol`` or ``det R < 0``).
    """
    if not isinstance(text, str):
        raise PanelInputError(f"typed pose: text needed, got {type(text).__name__}")
    ortho_tol = _real("ortho_tol", ortho_tol, positive=True)
    rows = [r for r in (line.replace(",", " ").split() for line in text.replace(";", "\n").splitlines()) if r]
    bad = next((x for row in rows for x in row if not _NUMBER.fullmatch(x)), None)
    if bad is not None:
        raise PanelInputError(f"typed pose: {bad[:20]!r} is not a number (rows of four numbers expected, "
                              f"such as 1, -0.5, 2.5e-3)")
    values = [[float(x) for x in row] for row in rows]
    if len(rows) not in (3, 4) or any(len(row) != 4 for row in rows):
        raise PanelInputError(f"typed pose: 3 or 4 rows of 4 numbers expected, got rows of "
                              f"{[len(r) for r in rows]} numbers")
    values = np.array(values)
    if not np.isfinite(values).all():
        raise PanelInputError(f"typed pose: finite numbers needed, got {shown(values[~np.isfinite(values)])}")
    if len(values) == 4 and values[3].tolist() != [0.0, 0.0, 0.0, 1.0]:
        raise PanelInputError(f"typed pose: the fourth row must be exactly 0 0 0 1, got "
                              f"{' '.join(shown(v) for v in values[3])}")
    T = np.eye(4)
    T[:3] = values[:3]
    T[:3, 3] /= 1e3
    try:
        return check_targets(T, ortho_tol)
    except ValueError as error:
        raise PanelInputError(f"typed pose: {_one_line(error).removeprefix('T_target: ')}") from None


#: A typed number: decimal digits with an optional sign, point and exponent (no ``_``, ``nan``,
#: ``inf`` or digits of other scripts, which ``float`` would take).
_NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?", re.ASCII)


@dataclass(frozen=True)
class Answer:
    """One method's answer to a target pose.

    Attributes:
        method: the method's name as the panel shows it.
        q: ``(n,)`` joint angles [rad], or ``None`` when the method gives none (``note`` says
            why).
        pos_error_m, rot_error_rad: the tool's distance from the target at ``q`` [m], [rad].
        seconds: the method's wall-clock time for this target [s].
        reaches: the tool is on the target within ``tol_mm`` and ``tol_deg`` and ``q`` is within
            the joint limits.
        note: what the reader should know about this answer ("" when nothing).
    """

    method: str
    q: np.ndarray | None
    pos_error_m: float = np.nan
    rot_error_rad: float = np.nan
    seconds: float = np.nan
    reaches: bool = False
    note: str = ""


def _answer(robot: Robot, T: np.ndarray, method: str, q: np.ndarray, seconds: float, note: str,
            tol_mm: float, tol_deg: float) -> Answer:
    e = pose_error(fk(robot, q), T)
    pos, rot = float(np.linalg.norm(e[:3])), float(np.linalg.norm(e[3:]))
    within = bool(np.all((q >= robot.qlim[:, 0] - 1e-12) & (q <= robot.qlim[:, 1] + 1e-12)))
    if not within:
        note = "; ".join(filter(None, [note, "outside the joint limits"]))
    return Answer(method, q, pos, rot, seconds, pos <= tol_mm / 1e3 and rot <= np.radians(tol_deg) and within,
                  note)


def ik_answers(robot: Robot, T_target, *, learned: LearnedIK | None = None, learned_note: str = "",
               seed: int = 0, tol_mm: float = 0.1, tol_deg: float = 0.1,
               progress: Callable[[int, int], None] | None = None,
               max_distance: float = 100.0) -> list[Answer]:
    """Every method's answer to one target pose ``T_target (4, 4)`` [m]: the closed form's
    every branch (for an arm of its class), Levenberg–Marquardt (chapter 2's defaults, seeded
    by ``seed``) and the learned ANFIS (``learned``; when ``None``, one row saying
    ``learned_note``).

    An answer "reaches" when its tool is within ``tol_mm`` and ``tol_deg`` of the target and its
    angles within the joint limits. For a target outside the arm's pose set (a 5-DOF arm holds
    only some orientations at a position) the closed form's branches are its nearest poses, and
    say so. ``progress(done, total)`` is called after each method. A target farther from the
    arm's base than ``max_distance`` × :func:`arm_scale` is refused (no method answers it
    meaningfully, and squares of its distance overflow).

    Raises:
        PanelInputError: the target is not one rigid transform ``(4, 4)`` of real numbers, or
            lies beyond the bound; ``learned`` is not a LearnedIK of this robot; a tolerance,
            the seed or ``progress`` is not of its kind.
    """
    robot = _robot(robot)
    T = _target(robot, T_target, max_distance)
    learned = _model_of("learned", learned, LearnedIK, robot)
    if not isinstance(learned_note, str):
        raise PanelInputError(f"learned_note: text needed, got {type(learned_note).__name__}")
    seed = _whole("seed", seed, low=0)
    tol_mm = _real("tol_mm", tol_mm, "mm", positive=True)
    tol_deg = _real("tol_deg", tol_deg, "deg", positive=True)
    if progress is not None and not callable(progress):
        raise PanelInputError(f"progress: a function or None needed, got {type(progress).__name__}")
    answers: list[Answer] = []
    steps = 3
    refusal = class_refusal(robot)
    if refusal is None:
        start = time.perf_counter()
        exact = closed_form(robot, T)
        seconds = time.perf_counter() - start
        outside = bool(exact.refined)
        for k, branch in enumerate(exact.branches):
            note = "nearest pose the arm reaches (target outside its pose set)" if outside else ""
            answers.append(_answer(robot, T, f"closed form, {branch}", exact.q[k], seconds, note, tol_mm, tol_deg))
    else:
        answers.append(Answer("closed form", None, note=f"not for this arm: {refusal}"))
    if progress:
        progress(1, steps)
    start = time.perf_counter()
    lm = solve(robot, T, seed=seed)
    seconds = time.perf_counter() - start
    answers.append(_answer(robot, T, "Levenberg–Marquardt", lm.q, seconds,
                           "" if lm.success else f"did not converge ({lm.reason}): best configuration found",
                           tol_mm, tol_deg))
    if progress:
        progress(2, steps)
    if learned is None:
        answers.append(Answer("ANFIS (chapter 6)", None, note=learned_note or "no trained model"))
    else:
        start = time.perf_counter()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            q = learned.predict(T, threads=1)
        seconds = time.perf_counter() - start
        note = "; ".join(_one_line(w.message) for w in caught)
        answers.append(_answer(robot, T, f"ANFIS (chapter 6, {learned.encoding})", q, seconds, note,
                               tol_mm, tol_deg))
    if progress:
        progress(3, steps)
    return answers


def _target(robot: Robot, T_target, max_distance: float) -> np.ndarray:
    """One target pose ``(4, 4)`` [m] of real, finite numbers, a rigid transform, within
    ``max_distance`` × :func:`arm_scale` of the base; else a one-line :class:`PanelInputError`."""
    max_distance = _real("max_distance", max_distance, positive=True)
    T = _reals("target pose", T_target)
    if T.shape != (4, 4):
        raise PanelInputError(f"target pose: one pose of shape (4, 4) needed, got shape {T.shape}")
    try:
        T = check_targets(T, 1e-6)
    except ValueError as error:
        raise PanelInputError(f"target pose: {_one_line(error).removeprefix('T_target: ')}") from None
    bound = max_distance * arm_scale(robot)
    offset = T[:3, 3] - robot.base[:3, 3]
    scale = float(np.abs(offset).max())       # the norm of 1e158 m squared would overflow
    distance = scale * float(np.linalg.norm(offset / scale)) if scale > 0 else 0.0
    if not distance <= bound:
        raise PanelInputError(f"target pose: its position lies {shown(distance, 3)} m from the arm's base, over "
                              f"the bound of {shown(bound, 3)} m ({shown(max_distance)} × the arm's size)")
    return T


# --------------------------------------------------------------------------------------------
# Learned models


@dataclass(frozen=True)
class Models:
    """The learned models ``make report`` trained for a robot, and why one is missing."""

    ik: LearnedIK | None
    id: LearnedID | None
    ik_note: str = ""
    id_note: str = ""


def trained_models(robot: Robot, models_dir: Path | None = None) -> Models:
    """Chapter 06's chosen learned IK and model-free learned ID for ``robot``, from
    ``models_dir`` (default ``build/models/<robot name>/``), each ``None`` with a one-line note
    when it is missing or was trained for another robot file."""
    if models_dir is None and not is_robot_name(robot.name):     # it would name a directory elsewhere
        note = f"no trained model: the robot's name {robot.name!r} cannot name a directory under build/models/"
        return Models(None, None, note, note)
    directory = Path(models_dir) if models_dir else BUILD / "models" / robot.name
    found, notes = {}, {}
    for key, cls, sub in (("ik", LearnedIK, "ik"), ("id", LearnedID, "id_model_free")):
        path = directory / sub
        if not path.is_dir():
            found[key] = None
            notes[key] = (f"no trained model in {shown_path(path)}: `make report` trains it for the robots "
                          f"with a study (params/studies/)")
            continue
        try:
            found[key] = cls.load(path, robot)
            notes[key] = ""
        except (OSError, ValueError, ParamsError) as error:
            found[key] = None
            notes[key] = f"the model in {shown_path(path)} cannot be used: {_one_line(error)}"
    return Models(found["ik"], found["id"], notes["ik"], notes["id"])


# --------------------------------------------------------------------------------------------
# Trajectory and inverse dynamics


def joint_trajectory(robot: Robot, q0_deg, qf_deg, v0_deg_s, vf_deg_s, *, t0: float = 0.0,
                     dt: float = 0.2, tf: float = 6.0, profile: str = "cubic",
                     max_samples: int = 100_000, max_position_deg: float = 3600.0,
                     max_speed_deg_s: float = 1e5, max_time_s: float = 1e6,
                     min_duration_s: float = 1e-3) -> tuple[Trajectory, list[str]]:
    """The joint trajectory from ``q0_deg`` to ``qf_deg`` (``(n,)`` [deg]) with end velocities
    ``v0_deg_s, vf_deg_s`` [deg/s], sampled every ``dt`` from ``t0`` to ``tf`` [s] (defaults:
    the dissertation's 0, 0.2, 6 s), by ``profile`` (:data:`PROFILES`); and one sentence per
    joint that leaves its limits on the way.

    The values are bounded where the arithmetic of the trajectory and its torques stays finite
    and far from rounding: positions within ±``max_position_deg`` (ten turns), speeds within
    ±``max_speed_deg_s``, times within ±``max_time_s`` and a duration of at least
    ``min_duration_s`` (with these, accelerations stay below 1e10 rad/s² and the torques of
    the shipped arms finite). ``max_samples`` bounds the samples: at 100 000 every page action
    (compute, draw, save) takes 1-2.5 s on the shipped arms (measured, issue 46).

    Raises:
        PanelInputError: a value that is not a finite real number or lies beyond its bound, the
            end before the start, a step larger than the duration, or more than ``max_samples``
            samples.
    """
    robot = _robot(robot)
    if not isinstance(profile, str) or profile not in PROFILES:
        raise PanelInputError(f"profile: one of {', '.join(PROFILES)}, got {shown(profile)}")
    max_samples = _whole("max_samples", max_samples, low=2)
    arrays = []
    for name, value, bound in (("initial position [deg]", q0_deg, max_position_deg),
                               ("final position [deg]", qf_deg, max_position_deg),
                               ("initial velocity [deg/s]", v0_deg_s, max_speed_deg_s),
                               ("final velocity [deg/s]", vf_deg_s, max_speed_deg_s)):
        v = _reals(name, value, (robot.n,))
        worst = int(np.argmax(np.abs(v)))
        if abs(v[worst]) > bound:
            # as many digits as tell the value from the bound (3600.0000001 is not "3600")
            digits = next((d for d in range(6, 18) if float(shown(v[worst], d)) != bound * np.sign(v[worst])), 17)
            raise PanelInputError(f"{name}: {shown(v[worst], digits)} for {robot.joint_names[worst]} is beyond the "
                                  f"bound of ±{shown(bound)}")
        arrays.append(np.radians(v))
    t0 = _real("start time", t0, "s", low=-max_time_s, high=max_time_s)
    tf = _real("end time", tf, "s", low=-max_time_s, high=max_time_s)
    dt = _real("time step", dt, "s")
    if not tf > t0:
        raise PanelInputError(f"end time {shown(tf)} s must be after the start time {shown(t0)} s")
    if tf - t0 < min_duration_s:
        raise PanelInputError(f"duration {shown(tf - t0)} s (end time − start time) is below the bound of "
                              f"{shown(min_duration_s)} s")
    if not 0 < dt <= tf - t0:
        raise PanelInputError(f"time step {shown(dt)} s must be > 0 and at most the duration {shown(tf - t0)} s")
    steps = (tf - t0) / dt
    # The samples the trajectory has (nfarm.solvers.trajectory's times): every step from the
    # start, and the end time when it falls between two.
    whole = np.floor(steps + 1e-9)
    count = whole + 1 + (1 if np.isfinite(whole) and (tf - (t0 + dt * whole)) > 1e-9 * dt else 0)
    if not count <= max_samples:
        count = f"{int(count):,}" if count < 1e15 else f"about {shown(count, 3)}" if np.isfinite(count) else \
            "more than 1e308"
        raise PanelInputError(f"time step {shown(dt)} s over {shown(tf - t0)} s gives {count} samples; the "
                              f"panel draws at most {max_samples:,}: take a larger step")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TrajectoryLimitWarning)
        with np.errstate(all="ignore"):
            trajectory = PROFILES[profile](*arrays, t0, tf, dt, qlim=robot.qlim)
    for name, values in (("positions", trajectory.q), ("velocities", trajectory.qd),
                         ("accelerations", trajectory.qdd), ("times", trajectory.t)):
        if not np.isfinite(values).all():       # not with the bounds above; never shown if so
            raise PanelInputError(f"trajectory: its {name} are not finite numbers with these values: "
                                  f"take a longer duration or smaller positions and speeds")
    notes = [f"{robot.joint_names[v.joint]} leaves its limits "
             f"[{np.degrees(v.lo):.4g}, {np.degrees(v.hi):.4g}]° from t = {v.t_start:.3g} s to "
             f"{v.t_end:.3g} s (reaching {np.degrees(v.worst):.4g}°)" for v in trajectory.violations]
    return trajectory, notes


@dataclass(frozen=True)
class TorqueParts:
    """Joint torques along a trajectory, ``(K, n)`` [N·m] each: ``total = inertial + coriolis +
    gravity`` (Newton–Euler), with ``inertial = M(q) q̈``, ``coriolis = C(q, q̇) q̇`` and
    ``gravity = g(q)``; ``learned``, the learned ID model's prediction, or ``None``."""

    total: np.ndarray
    inertial: np.ndarray
    coriolis: np.ndarray
    gravity: np.ndarray
    learned: np.ndarray | None = None
    note: str = ""


def torque_parts(robot: Robot, trajectory: Trajectory, *, learned: LearnedID | None = None,
                 chunk: int = 4096, progress: Callable[[int, int], None] | None = None) -> TorqueParts:
    """The Newton–Euler torques along ``trajectory`` split into their parts, and the learned
    model's (when given), in chunks of ``chunk`` samples with ``progress(done, total)`` after
    each. A learned model that cannot predict these states gives no torques (``learned`` is
    ``None``) and says why in ``note``: no NaN is shown.

    Raises:
        PanelInputError: ``trajectory`` is not a Trajectory of this robot's joints with finite
            values, ``learned`` not a LearnedID of this robot, ``chunk`` not a whole number
            >= 1, ``progress`` not a function; torques that are not finite numbers.
    """
    robot = _robot(robot)
    if not isinstance(trajectory, Trajectory):
        raise PanelInputError(f"trajectory: a Trajectory (joint_trajectory) needed, got {type(trajectory).__name__}")
    K = len(trajectory.t)
    q, qd, qdd = (_reals(f"trajectory.{name}", getattr(trajectory, name), (K, robot.n)) for name in ("q", "qd", "qdd"))
    learned = _model_of("learned", learned, LearnedID, robot)
    chunk = _whole("chunk", chunk)
    if progress is not None and not callable(progress):
        raise PanelInputError(f"progress: a function or None needed, got {type(progress).__name__}")
    parts = {key: np.empty_like(q) for key in ("total", "inertial", "coriolis", "gravity")}
    predicted = None if learned is None else np.empty_like(q)
    notes: list[str] = []
    for start in range(0, len(q), chunk):
        s = slice(start, start + chunk)
        with np.errstate(all="ignore"):
            parts["total"][s] = rnea(robot, q[s], qd[s], qdd[s])
            parts["inertial"][s] = np.einsum("kij,kj->ki", mass_matrix(robot, q[s]), qdd[s])
            parts["coriolis"][s] = coriolis(robot, q[s], qd[s])
            parts["gravity"][s] = gravity_torques(robot, q[s])
        if predicted is not None:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                try:
                    predicted[s] = learned.predict(q[s], qd[s], qdd[s])
                except ValueError as error:
                    caught.append(warnings.WarningMessage(error, UserWarning, "", 0))
                    predicted = None
            said = [_one_line(w.message) for w in caught]
            if predicted is not None and not np.isfinite(predicted[s]).all():
                said.append("its torques are not finite numbers for these states")
                predicted = None
            if predicted is None:
                notes.insert(0, f"learned ID not shown: {said.pop()}")
            notes.extend(said)
        if progress:
            progress(min(start + chunk, len(q)), len(q))
    for key, values in parts.items():
        if not np.isfinite(values).all():
            k = int(np.argmax(~np.isfinite(values).all(axis=1)))
            raise PanelInputError(f"torques: the {key} torques at t = {shown(trajectory.t[k])} s are not finite "
                                  f"numbers: take a longer duration or smaller positions and speeds")
    note = notes[0] + (f" (and {len(notes) - 1} more)" if len(notes) > 1 else "") if notes else ""
    return TorqueParts(**parts, learned=predicted, note=note)
