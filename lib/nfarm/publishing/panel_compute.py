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
from ..model.robot import Robot
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
    q = np.asarray(q, dtype=float)
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
    for name, value in (("position [mm]", position_mm), ("roll, pitch, yaw [deg]", rpy_deg)):
        v = np.asarray(value, dtype=float)
        if v.shape != (3,) or not np.isfinite(v).all():
            raise PanelInputError(f"target {name}: three finite numbers needed, got {list(np.ravel(v))}")
    T = np.eye(4)
    T[:3, :3] = rpy_to_matrix(np.radians(rpy_deg))
    T[:3, 3] = np.asarray(position_mm, dtype=float) / 1e3
    return T


def parse_pose_matrix(text: str, *, ortho_tol: float = 1e-6) -> np.ndarray:
    """A typed tool pose: three or four rows separated by ``;`` or new lines, four numbers each
    (rotation row and position [mm]); a fourth row must be ``0 0 0 1``. Returns ``(4, 4)`` [m].

    Raises:
        PanelInputError: not numbers, wrong shape, or a rotation part that is not a rotation
            (``|RᵀR − I| > ortho_tol`` or ``det R < 0``).
    """
    rows = [r for r in (line.replace(",", " ").split() for line in text.replace(";", "\n").splitlines()) if r]
    try:
        values = np.array([[float(x) for x in row] for row in rows])
    except ValueError as error:
        raise PanelInputError(f"typed pose: {_one_line(error)} (rows of four numbers expected)") from None
    if values.ndim != 2 or values.shape[1:] != (4,) or len(values) not in (3, 4):
        raise PanelInputError(f"typed pose: 3 or 4 rows of 4 numbers expected, got rows of "
                              f"{[len(r) for r in rows]} numbers")
    if len(values) == 4 and not np.allclose(values[3], [0, 0, 0, 1]):
        raise PanelInputError(f"typed pose: the fourth row must be 0 0 0 1, got {values[3].tolist()}")
    T = np.eye(4)
    T[:3] = values[:3]
    T[:3, 3] /= 1e3
    try:
        return check_targets(T, ortho_tol)
    except ValueError as error:
        raise PanelInputError(f"typed pose: {_one_line(error).removeprefix('T_target: ')}") from None


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
               progress: Callable[[int, int], None] | None = None) -> list[Answer]:
    """Every method's answer to one target pose ``T_target (4, 4)`` [m]: the closed form's
    every branch (for an arm of its class), Levenberg–Marquardt (chapter 2's defaults, seeded
    by ``seed``) and the learned ANFIS (``learned``; when ``None``, one row saying
    ``learned_note``).

    An answer "reaches" when its tool is within ``tol_mm`` and ``tol_deg`` of the target and its
    angles within the joint limits. For a target outside the arm's pose set (a 5-DOF arm holds
    only some orientations at a position) the closed form's branches are its nearest poses, and
    say so. ``progress(done, total)`` is called after each method.

    Raises:
        PanelInputError: the target is not a rigid transform.
    """
    try:
        T = check_targets(T_target, 1e-6)
    except ValueError as error:
        raise PanelInputError(f"target pose: {_one_line(error).removeprefix('T_target: ')}") from None
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
                     max_samples: int = 100_000) -> tuple[Trajectory, list[str]]:
    """The joint trajectory from ``q0_deg`` to ``qf_deg`` (``(n,)`` [deg]) with end velocities
    ``v0_deg_s, vf_deg_s`` [deg/s], sampled every ``dt`` from ``t0`` to ``tf`` [s] (defaults:
    the dissertation's 0, 0.2, 6 s), by ``profile`` (:data:`PROFILES`); and one sentence per
    joint that leaves its limits on the way.

    Raises:
        PanelInputError: a value that is not a finite number, the end before the start, a step
            larger than the duration, or more than ``max_samples`` samples.
    """
    if profile not in PROFILES:
        raise PanelInputError(f"profile: one of {', '.join(PROFILES)}, got {profile!r}")
    arrays = []
    for name, value in (("initial position [deg]", q0_deg), ("final position [deg]", qf_deg),
                        ("initial velocity [deg/s]", v0_deg_s), ("final velocity [deg/s]", vf_deg_s)):
        v = np.asarray(value, dtype=float)
        if v.shape != (robot.n,) or not np.isfinite(v).all():
            raise PanelInputError(f"{name}: {robot.n} finite numbers needed, got {list(np.ravel(v))}")
        arrays.append(np.radians(v))
    for name, value in (("start time", t0), ("time step", dt), ("end time", tf)):
        if not np.isfinite(value):
            raise PanelInputError(f"{name}: a finite number of seconds needed, got {value!r}")
    if not tf > t0:
        raise PanelInputError(f"end time {tf:g} s must be after the start time {t0:g} s")
    if not 0 < dt <= tf - t0:
        raise PanelInputError(f"time step {dt:g} s must be > 0 and at most the duration {tf - t0:g} s")
    samples = int(np.floor((tf - t0) / dt + 1e-9)) + 2
    if samples > max_samples:
        raise PanelInputError(f"time step {dt:g} s over {tf - t0:g} s gives {samples - 1:,} samples; "
                              f"the panel draws at most {max_samples:,}: take a larger step")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TrajectoryLimitWarning)
        trajectory = PROFILES[profile](*arrays, t0, tf, dt, qlim=robot.qlim)
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
    each."""
    q, qd, qdd = trajectory.q, trajectory.qd, trajectory.qdd
    parts = {key: np.empty_like(q) for key in ("total", "inertial", "coriolis", "gravity")}
    predicted = None if learned is None else np.empty_like(q)
    notes: list[str] = []
    for start in range(0, len(q), chunk):
        s = slice(start, start + chunk)
        parts["total"][s] = rnea(robot, q[s], qd[s], qdd[s])
        parts["inertial"][s] = np.einsum("kij,kj->ki", mass_matrix(robot, q[s]), qdd[s])
        parts["coriolis"][s] = coriolis(robot, q[s], qd[s])
        parts["gravity"][s] = gravity_torques(robot, q[s])
        if learned is not None:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                try:
                    predicted[s] = learned.predict(q[s], qd[s], qdd[s])
                except ValueError as error:
                    predicted[s] = np.nan
                    caught.append(warnings.WarningMessage(error, UserWarning, "", 0))
            notes.extend(_one_line(w.message) for w in caught)
        if progress:
            progress(min(start + chunk, len(q)), len(q))
    note = notes[0] + (f" (and {len(notes) - 1} more)" if len(notes) > 1 else "") if notes else ""
    return TorqueParts(**parts, learned=predicted, note=note)
