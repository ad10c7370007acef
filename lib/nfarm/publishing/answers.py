"""Reference answers of the chapters' exercises (:mod:`nfarm.publishing.course`), computed for any robot.

The check cells call these, so a student reads the question and the check, not the answer
beside it; each is computed by a route other than the worked solution where one exists (a
one-joint robot's forward kinematics for the DH transform, a two-link arm's Newton–Euler torques
for the torques by hand). Angles in radians unless a name says otherwise.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..learning.anfis import ANFIS
from ..learning.jang import rmse, sinc_data
from ..learning.learned import LearnedIK, arm_chart, out_of_plane
from ..learning.learned_id import LearnedID
from ..model.dynamics import gravity_torques, rnea
from ..model.kinematics import fk, jacobian, min_singular_value
from ..model.robot import Robot, robot_from_dict, robot_hash, robot_to_dict, sample_configurations
from ..solvers.ik import solve
from ..solvers.workspace import reach, workspace_points
from ..study import datasets, study_files
from ..study.regions import check_single_valued, IKRegion
from ..study.study_files import Study
from ..solvers.workspace import workspace_volume

__all__ = ["scan", "tool_shift", "dh_transform", "dh_cases", "singular_elbows_deg", "one_more_joint",
           "one_more_joint_answers", "tolerance_iterations", "jt_step", "jt_cases", "jt_success",
           "two_link_torques", "payload_torque_change", "peak_gravity_shoulder_deg",
           "sinc_fit", "best_sinc_mf", "second_share_full_elbow", "other_branch_verdict",
           "mean_solutions_full", "TrainingExercises", "training_exercises", "IKExercises", "ik_exercises", "learned_ik_worst", "learned_id_worst", "beats",
           "median_tool_error_mm", "warm_start_iterations", "nearest_by_position", "reaches",
           "volume_error_ratio", "annulus_area", "area_verdict"]


# -- chapter 1 ---------------------------------------------------------------------------------


def tool_shift(robot: Robot, joint: int = 1, extra_m: float = 0.05) -> float:
    """How far the tool centre moves at q = 0 when joint ``joint``'s ``a`` grows by ``extra_m``."""
    longer = robot_to_dict(robot)
    longer["joints"][joint]["a"] += extra_m
    q = np.zeros(robot.n)
    return float(np.linalg.norm(fk(robot_from_dict(longer), q)[:3, 3] - fk(robot, q)[:3, 3]))


def _one_joint(d: float, a: float, alpha: float) -> Robot:
    return robot_from_dict({"name": "one", "convention": "standard", "gravity": [0, 0, -9.81],
                            "joints": [{"a": a, "alpha": alpha, "d": d, "offset": 0.0,
                                        "qlim": [-6.0, 6.0], "mass": 1.0, "com": [0, 0, 0],
                                        "inertia": [1e-3, 1e-3, 1e-3, 0, 0, 0]}]})


def dh_transform(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """The standard DH transform, as the forward kinematics of a one-joint robot."""
    return fk(_one_joint(d, a, alpha), [theta])


def dh_cases(seed: int, count: int = 6) -> list[tuple[float, float, float, float]]:
    rng = np.random.default_rng(seed)
    return [(float(rng.uniform(-3, 3)), float(rng.uniform(-0.3, 0.3)), float(rng.uniform(-0.3, 0.3)),
             float(rng.uniform(-3, 3))) for _ in range(count)]


def scan(lo: float, hi: float, step_deg: float) -> np.ndarray:
    """Angles from ``lo`` to ``hi`` [rad] in steps of at most ``step_deg``."""
    return np.linspace(lo, hi, int(math.ceil(math.degrees(hi - lo) / step_deg)) + 1)


def singular_elbows_deg(robot: Robot, step_deg: float, round_deg: float, rel: float) -> list[float]:
    """The elbow angles (joint 3, the others at 0), scanned over its limits in steps of at
    most ``step_deg``, where the position Jacobian's smallest singular value has a local
    minimum below ``rel`` of its largest [deg, rounded to ``round_deg``]."""
    q3 = scan(*robot.qlim[2], step_deg)
    q = np.zeros((q3.size, robot.n))
    q[:, 2] = q3
    s = min_singular_value(robot, q, "position")
    inner = s[1:-1]
    found = np.flatnonzero((inner <= s[:-2]) & (inner <= s[2:]) & (inner < rel * s.max())) + 1
    return [round(round(math.degrees(q3[i]) / round_deg) * round_deg, 6) for i in found]


def one_more_joint(robot: Robot, alpha: float, d: float) -> Robot:
    """``robot`` with one more joint: its last joint's ``alpha`` set to ``alpha`` [rad] (the
    new axis turned away from it) and a copy of that joint appended with ``a = alpha = 0`` and
    ``d`` [m]."""
    data = robot_to_dict(robot)
    data["joints"][-1]["alpha"] = alpha
    data["joints"].append(dict(data["joints"][-1], name="extra_wrist", a=0.0, alpha=0.0, d=d))
    return robot_from_dict(data)


def one_more_joint_answers(robot: Robot, seed: int, alpha: float, d: float) -> tuple[int, float]:
    """The arm with one more joint (:func:`one_more_joint`): its Jacobian's rank at a seeded
    random configuration, and the smallest singular value of its Jacobian at q = 0."""
    six = one_more_joint(robot, alpha, d)
    q = sample_configurations(six, 1, seed)[0]
    rank = int(np.linalg.matrix_rank(jacobian(six, q), tol=1e-9))
    return rank, float(np.linalg.svd(jacobian(six, np.zeros(six.n)), compute_uv=False)[-1])


# -- chapter 2 ---------------------------------------------------------------------------------


def _target(robot: Robot, seed: int) -> np.ndarray:
    return fk(robot, sample_configurations(robot, 1, seed)[0])


def tolerance_iterations(robot: Robot, seed: int, loose: float, tight: float) -> int:
    """LM iterations from q = 0 to a seeded random reachable target at tolerance ``tight``,
    less those at ``loose``."""
    T = _target(robot, seed)
    steps = [int(solve(robot, T, np.zeros(robot.n), tol_pos=tol, tol_rot=tol, restarts=0).iterations)
             for tol in (tight, loose)]
    return steps[0] - steps[1]


def jt_step(J: np.ndarray, e: np.ndarray) -> np.ndarray:
    """Buss's Jacobian-transpose step: ``α Jᵀe`` with ``α = ⟨e, J Jᵀe⟩ / ‖J Jᵀe‖²``."""
    g = J.T @ e
    Jg = J @ g
    return float(e @ Jg) / float(Jg @ Jg) * g


def jt_cases(seed: int, n: int, count: int = 5) -> list[tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(seed)
    return [(rng.normal(size=(6, n)), rng.normal(size=6)) for _ in range(count)]


_JT_SUCCESS: dict[tuple[str, int, int], float] = {}


def jt_success(robot: Robot, targets: int, seed: int) -> float:
    """Share of ``targets`` seeded random reachable targets the Jacobian transpose solves
    (computed once per robot, count and seed in a process: the course stages a check three
    times, and the method needs thousands of steps a target)."""
    key = (robot_hash(robot), int(targets), int(seed))
    if key not in _JT_SUCCESS:
        T = fk(robot, sample_configurations(robot, targets, seed))
        _JT_SUCCESS[key] = solve(robot, T, method="jt", seed=seed).success_rate
    return _JT_SUCCESS[key]


# -- chapter 3 ---------------------------------------------------------------------------------


def two_link_torques(l1_m: float, l2_m: float, m1_kg: float, m2_kg: float, q_deg, g: float
                     ) -> np.ndarray:
    """Static torques of a planar two-link arm with point masses at the links' ends, in a
    vertical plane (gravity ``g`` [m/s²] along −y), by Newton–Euler."""
    point = {"offset": 0.0, "alpha": 0.0, "d": 0.0, "qlim": [-4.0, 4.0], "com": [0, 0, 0],
             "inertia": [0, 0, 0, 0, 0, 0]}
    arm = robot_from_dict({"name": "two_link", "convention": "standard", "gravity": [0, -g, 0],
                           "joints": [{**point, "a": l1_m, "mass": m1_kg}, {**point, "a": l2_m, "mass": m2_kg}]})
    q = np.radians(q_deg)
    return rnea(arm, q, np.zeros(2), np.zeros(2))


def payload_torque_change(robot: Robot, extra_kg: float, joint: int = 1) -> float:
    """Change of the static torque at ``joint`` at q = 0 when the last link gains ``extra_kg``."""
    heavier = robot_to_dict(robot)
    heavier["joints"][-1]["mass"] += extra_kg
    q = np.zeros(robot.n)
    return float(gravity_torques(robot_from_dict(heavier), q)[joint] - gravity_torques(robot, q)[joint])


def peak_gravity_shoulder_deg(robot: Robot, step_deg: float) -> float:
    """The shoulder angle (joint 2, the others at 0), scanned over its limits in steps of at
    most ``step_deg``, where the gravity torque at the shoulder is largest in magnitude [deg]."""
    q2 = scan(*robot.qlim[1], step_deg)
    q = np.zeros((q2.size, robot.n))
    q[:, 1] = q2
    return math.degrees(q2[int(np.argmax(np.abs(gravity_torques(robot, q)[:, 1])))])


# -- chapter 4 ---------------------------------------------------------------------------------


def sinc_fit(n_mfs: int, mf: str, epochs: int) -> tuple[float, float]:
    """Jang's sinc with ``n_mfs`` functions ``mf`` per input: training RMSE (last epoch) and
    RMSE on a 41 × 41 check grid of the same square."""
    X, y = sinc_data()
    model = ANFIS(n_mfs=n_mfs, mf=mf, epochs=epochs).fit(X, y)
    Xc, yc = sinc_data(points=41)
    return float(model.loss_curve_[-1]), rmse(yc, model.predict(Xc))


def best_sinc_mf(epochs: int) -> str:
    """The function type (4 per input) with the lower check RMSE on sinc."""
    return min(("gbell", "gauss"), key=lambda mf: sinc_fit(4, mf, epochs)[1])


# -- chapter 5 ---------------------------------------------------------------------------------


def second_share_full_elbow(study: Study, targets: int, seed: int) -> float:
    """Share of targets with a second solution when the study's region lets the elbow (joint
    3) use its whole range."""
    region = study.ik_region
    box = region.box.copy()
    box[2] = study.robot.qlim[2]
    wide = IKRegion(region.robot, box, region.radial, region.height, region.approach_axis,
                    region.approach_angle, region.reach)
    return check_single_valued(wide, targets, seed=seed).fraction


def other_branch_verdict(study: Study, region, targets: int, seed: int) -> tuple[bool | None, str]:
    """Whether ``region`` (an :class:`IKRegion`) holds the other elbow branch — its elbow
    range does not meet the study's — and is single-valued on ``targets`` targets; and what is
    wrong if not."""
    if region is None:
        return None, ""
    if not isinstance(region, IKRegion):
        return False, f"expected an IKRegion, got {type(region).__name__}"
    lo, hi = region.box[2]
    s_lo, s_hi = study.ik_region.box[2]
    if hi >= s_lo and lo <= s_hi:
        return False, (f"its elbow range [{math.degrees(lo):.0f}°, {math.degrees(hi):.0f}°] meets "
                       f"the study's [{math.degrees(s_lo):.0f}°, {math.degrees(s_hi):.0f}°]")
    try:
        result = check_single_valued(region, targets, seed=seed)
    except ValueError as exc:
        return False, f"no targets can be drawn in it ({exc})"
    if result.fraction > 0:
        return False, f"{result.fraction:.0%} of its targets have a second solution inside it"
    return True, ""


def mean_solutions_full(robot: Robot, targets: int, seed: int) -> float:
    """Mean number of distinct solutions within the joint limits that 24 starts find for
    targets drawn over the full joint ranges."""
    return float(check_single_valued(IKRegion.full(robot), targets, seed=seed).solutions.mean())


# -- chapters 6 and 7 --------------------------------------------------------------------------


def _exercise_data(study_file, smoke: bool, data_dir) -> tuple[Robot, dict[str, Mapping]]:
    """The study's robot and the splits the exercises read, the data sets built (or reused) as
    chapter 5 builds them (the smoke study's in smoke mode)."""
    study = study_files.load_study(study_file)
    study = study_files.smoke_study(study) if smoke else study
    datasets.build_datasets(study, data_dir)
    directory = datasets.dataset_dir(study, data_dir)
    return study.robot, {name: datasets.load(directory / f"{name}.npz", study.robot, study)
                         for name in ("ik_train", "ik_val", "ik_test", "id_train", "id_val")}


def _in_plane(robot: Robot, data: Mapping[str, Mapping], plane: float) -> bool:
    """Whether the arm's plane describes the training poses (to within ``plane`` [rad])."""
    return bool(out_of_plane(data["ik_train"]["T"], arm_chart(robot)).max() <= plane)


@dataclass(frozen=True)
class TrainingExercises:
    """Chapter 6's exercises' set-up (:func:`training_exercises`): the study's ``robot`` and its
    splits ``data`` (as :class:`IKExercises`'), the budgets — ``samples`` training poses,
    ``epochs``, every ``stride``-th ID training state —, ``plane`` [rad], the out-of-plane angle
    the arm's plane accepts, ``planar``: whether it describes this arm (exercises 6.1 and 6.2 train
    in it), and ``notice``: a sentence for the student where it does not ("" otherwise)."""

    robot: Robot
    data: Mapping[str, Mapping]
    samples: int
    epochs: int
    stride: int
    plane: float
    planar: bool
    notice: str


def training_exercises(study_file, *, smoke: bool = False, data_dir=None,
                       max_out_of_plane_deg: float = 0.5) -> TrainingExercises:
    """The study's data and small budgets for chapter 6's exercises: 2 000 training poses, 5 epochs
    and every 32nd ID training state (smoke: 300, 2 and every 4th)."""
    robot, data = _exercise_data(study_file, smoke, data_dir)
    plane = np.radians(max_out_of_plane_deg)
    planar = _in_plane(robot, data, plane)
    notice = "" if planar else (f"{robot.name}'s tool leaves the arm's vertical plane: exercises 6.1 and 6.2, which "
                                f"train in that plane, do not apply to this arm (their cells say so); exercise 6.3 does.")
    return TrainingExercises(robot, data, 300 if smoke else 2000, 2 if smoke else 5, 4 if smoke else 32, plane, planar,
                             notice)


@dataclass(frozen=True)
class IKExercises:
    """Chapter 7's exercises' set-up (:func:`ik_exercises`): the study's ``robot``, its splits
    ``data`` (``"ik_train"``, ``"ik_val"``, ``"ik_test"``, ``"id_train"``, ``"id_val"``), the small
    model's LearnedIK ``options`` and the ``model`` trained with them on the first ``samples``
    training poses, the first ``test`` test poses ``T (test, 4, 4)``, and ``notice``: a sentence
    for the student when the arm's plane cannot describe the arm ("" otherwise)."""

    robot: Robot
    data: Mapping[str, Mapping]
    options: dict
    model: LearnedIK
    T: np.ndarray
    samples: int
    test: int
    notice: str


def ik_exercises(study_file, *, smoke: bool = False, data_dir=None, seed: int = 0, samples: int | None = None,
                 epochs: int | None = None, test: int | None = None, max_out_of_plane_deg: float = 0.5) -> IKExercises:
    """The study's data (built or reused, as chapter 5 builds it) and one small learned IK for
    chapter 7's three exercises: chapter 6's options with fewer functions and epochs, in the arm's
    plane — or on the dissertation's seven inputs for an arm whose tool leaves that plane by more
    than ``max_out_of_plane_deg`` [deg] (the plane cannot describe its poses). ``samples``,
    ``epochs`` and ``test`` default to 2 000, 5 and 500 (smoke: 300, 2 and 100)."""
    robot, data = _exercise_data(study_file, smoke, data_dir)
    samples = (300 if smoke else 2000) if samples is None else samples
    epochs = (2 if smoke else 5) if epochs is None else epochs
    test = (100 if smoke else 500) if test is None else test
    plane = np.radians(max_out_of_plane_deg)
    notice = ""
    if _in_plane(robot, data, plane):
        options = dict(encoding="arm_plane", partition="grid", n_mfs=[1, 2, 2, 2, 2, 1], epochs=epochs,
                       max_out_of_plane=plane)
    else:
        options = dict(encoding="quat_xyz", partition="grid", n_mfs=[2, 2, 2, 1, 1, 1, 1], epochs=epochs)
        notice = (f"{robot.name}'s tool leaves the arm's vertical plane: the exercises' model takes the dissertation's "
                  f"seven inputs")
    model = LearnedIK(**options, random_state=seed).fit(
        robot, {k: data["ik_train"][k][:samples] for k in ("T", "q")}, data["ik_val"])
    return IKExercises(robot, data, options, model, data["ik_test"]["T"][:test], samples, test, notice)


def _fit_ik(robot: Robot, train, val, options: dict, samples: int, seed: int) -> LearnedIK:
    subset = {k: train[k][:samples] for k in ("T", "q")}
    return LearnedIK(**options, random_state=seed).fit(robot, subset, val)


def learned_ik_worst(robot: Robot, train, val, options: dict, samples: int, seed: int) -> float:
    """Worst joint validation RMSE [deg] of a LearnedIK with ``options`` trained on the first
    ``samples`` training poses."""
    model = _fit_ik(robot, train, val, options, samples, seed)
    return float(np.degrees(max(m.val_loss_curve_[m.best_epoch_] for m in model.models_)))


def beats(robot: Robot, train, val, options, to_beat: float, samples: int, epochs: int,
          seed: int) -> tuple[bool | None, str]:
    """Whether LearnedIK ``options`` (a mapping; ``epochs`` is the budget's) beat ``to_beat``
    [deg] on the budget, and why not."""
    if options is None:
        return None, ""
    if not isinstance(options, dict):
        return False, f"expected a dict of LearnedIK options, got {type(options).__name__}"
    if "epochs" in options:
        return False, "the budget fixes the epochs: leave them out of your options"
    try:
        worst = learned_ik_worst(robot, train, val, {**options, "epochs": epochs}, samples, seed)
    except (TypeError, ValueError) as exc:
        return False, f"LearnedIK refused the options: {exc}"
    if worst >= to_beat:
        return False, f"worst joint {worst:.3g}° is not below {to_beat:.3g}°"
    return True, ""


def learned_id_worst(robot: Robot, train, val, options: dict, stride: int, seed: int) -> float:
    """Worst joint validation NRMSE [%] of a LearnedID trained on every ``stride``-th state."""
    keys = ("q", "qd", "qdd", "tau")
    model = LearnedID(**options, random_state=seed).fit(
        robot, {k: train[k][::stride] for k in keys}, {k: val[k] for k in keys})
    rmse = np.array([m.val_loss_curve_[m.best_epoch_] for m in model.models_])
    return float(100 * np.max(rmse / np.asarray(val["tau"]).std(axis=0)))


def median_tool_error_mm(robot: Robot, train, val, test, options: dict, samples: int, seed: int,
                         count: int) -> float:
    """Median tool position error [mm] of the model's predictions on the first ``count``
    test poses."""
    model = _fit_ik(robot, train, val, options, samples, seed)
    T = test["T"][:count]
    return float(1000 * np.median(np.linalg.norm(fk(robot, model.predict(T))[:, :3, 3] - T[:, :3, 3], axis=-1)))


def warm_start_iterations(robot: Robot, train, val, test, options: dict, samples: int, seed: int,
                          count: int) -> float:
    """Mean LM iterations (no restarts) on the first ``count`` test poses from the model's
    predictions, clipped into the joint limits."""
    model = _fit_ik(robot, train, val, options, samples, seed)
    T = test["T"][:count]
    q0 = np.clip(model.predict(T), robot.qlim[:, 0], robot.qlim[:, 1])
    return float(np.mean(solve(robot, T, q0, restarts=0).iterations))


def nearest_by_position(train_T: np.ndarray, train_q: np.ndarray, T: np.ndarray) -> np.ndarray:
    """For each pose of ``T``, the joint angles of the training sample whose tool position is
    nearest (brute force over all pairs)."""
    d = np.linalg.norm(T[:, None, :3, 3] - train_T[None, :, :3, 3], axis=-1)
    return train_q[np.argmin(d, axis=1)]


# -- chapter 8 ---------------------------------------------------------------------------------


def reaches(robots, samples: int, seed: int) -> list[float]:
    """Each arm's reach [m] from ``samples`` random configurations (chapter 8's estimate)."""
    return [reach(workspace_points(robot, samples, seed), robot) for robot in robots]


def volume_error_ratio(robot: Robot, reach_m: float, points: int, seed: int, factor: int) -> float:
    """Standard error of the Monte Carlo workspace volume with ``points`` points over that with
    ``factor`` times as many."""
    small = workspace_volume(robot, reach_m, points, seed)
    large = workspace_volume(robot, reach_m, factor * points, seed)
    return small.std_error / large.std_error


def annulus_area(l1: float, l2: float) -> float:
    """Area [m²] a planar two-link arm's tool point reaches (joints turning freely)."""
    return math.pi * ((l1 + l2) ** 2 - (l1 - l2) ** 2)


def area_verdict(my_area, seed: int, points: int, sigmas: float,
                 arms=((0.3, 0.2), (0.25, 0.25), (0.4, 0.1))) -> tuple[bool | None, str]:
    """Whether a student's ``my_area(l1, l2, n, seed)`` with ``points`` points lands within
    ``sigmas`` standard errors of the exact annulus for each arm ``(l1, l2)`` [m], and where
    it does not (an exception is reported)."""
    if my_area is None:
        return None, ""
    problems = []
    for l1, l2 in arms:
        exact = annulus_area(l1, l2)
        square = (2 * (l1 + l2)) ** 2
        se = square * math.sqrt(exact / square * (1 - exact / square) / points)
        try:
            got = float(my_area(l1, l2, points, seed))
        except Exception as exc:  # noqa: BLE001 — the student's code: report, never raise
            return False, f"my_area({l1}, {l2}, ...) raised {type(exc).__name__}: {exc}"
        if not abs(got - exact) <= sigmas * se:
            problems.append(f"l1 = {l1}, l2 = {l2}: {got:.4g} m² against {exact:.4g} m² (± {se:.1g})")
    return not problems, "; ".join(problems)
