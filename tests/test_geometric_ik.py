"""The closed-form IK (nfarm.solvers.ik.closed_form) against forward kinematics, Pinocchio, multi-start
LM and the geometry of the class: every solution found, every solution exact, every branch
named, nothing non-finite at the singular poses, and every other robot refused in one line."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import load_quietly, random_chains
from nfarm.solvers.geometric_ik import check_class
from nfarm.solvers.ik import BRANCHES, branch_of, closed_form, in_class, solve
from nfarm.model.kinematics import fk, fk_all
from nfarm.infra.paths import ROOT
from nfarm.model.pinocchio_ref import pinocchio_model
from nfarm.model.robot import Robot, robot_from_dict, sample_configurations
from nfarm.model.rotations import exp_so3, pose_error, quat_to_matrix

ARMS = ["intelbot5", "so101"]


def arm(name: str) -> Robot:
    return load_quietly(ROOT / "params" / "robots" / f"{name}.yaml")


def wrapped(x):
    return np.abs(np.remainder(x + np.pi, 2 * np.pi) - np.pi)


def errors(robot, T, q):
    """Position and orientation errors of fk(q) ``(..., k, n)`` against ``T (..., 4, 4)``."""
    e = pose_error(np.broadcast_to(T[..., None, :, :], q.shape[:-1] + (4, 4)), fk(robot, q))
    return np.linalg.norm(e[..., :3], axis=-1), np.linalg.norm(e[..., 3:], axis=-1)


def _tx_rx(a, alpha):
    T = np.eye(4)
    c, s = np.cos(alpha), np.sin(alpha)
    T[:3, :3] = [[1, 0, 0], [0, c, -s], [0, s, c]]
    T[0, 3] = a
    return T


@st.composite
def class_arms(draw) -> Robot:
    """A random yaw-pitch-pitch-pitch-roll arm: random lengths, lateral offsets, joint offsets,
    tilted base and roll axes, tool point off the roll axis, base and tool, in either DH
    convention (a modified table built as the standard chain it equals)."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    tilt = lambda: float(rng.choice([np.pi / 2, -np.pi / 2, rng.uniform(0.3, np.pi - 0.3)]))  # noqa: E731
    alpha = [tilt(), float(rng.choice([0.0, np.pi])), float(rng.choice([0.0, np.pi])), 0.0,
             float(rng.uniform(-np.pi, np.pi))]
    beta = tilt()                                     # β = α2 + α3 + α4 away from 0 and π
    alpha[3] = float(np.remainder(beta - alpha[1] - alpha[2] + np.pi, 2 * np.pi) - np.pi)
    a = [rng.uniform(-0.1, 0.1), rng.choice([-1, 1]) * rng.uniform(0.1, 0.4),
         rng.choice([-1, 1]) * rng.uniform(0.1, 0.4), rng.uniform(-0.05, 0.05),
         rng.uniform(-0.05, 0.05)]
    d = rng.uniform(-0.1, 0.1, 5)
    d[0], d[4] = rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2)
    offset = rng.uniform(-np.pi, np.pi, 5)
    lo = -rng.uniform(1.0, np.pi, 5)
    hi = rng.uniform(1.0, np.pi, 5)
    tool, base = np.eye(4), np.eye(4)
    tool[:3, :3], tool[:3, 3] = quat_to_matrix(rng.normal(size=4)), rng.uniform(-0.1, 0.1, 3)
    if draw(st.booleans()):
        base[:3, :3], base[:3, 3] = quat_to_matrix(rng.normal(size=4)), rng.uniform(-0.3, 0.3, 3)
    convention = draw(st.sampled_from(["standard", "modified"]))
    if convention == "modified":   # Tx(a_i) Rx(α_i) move to the next joint; the last to the tool
        tool = _tx_rx(a[4], alpha[4]) @ tool
        a, alpha = [0.0] + a[:4], [0.0] + alpha[:4]
    joints = [{"a": float(a[i]), "alpha": float(alpha[i]), "d": float(d[i]),
               "offset": float(offset[i]), "qlim": [float(lo[i]), float(hi[i])], "mass": 1.0,
               "com": [0.0, 0.0, 0.0], "inertia": [0.01, 0.01, 0.01, 0.0, 0.0, 0.0]}
              for i in range(5)]
    return robot_from_dict({"name": f"class-{convention}", "convention": convention,
                            "gravity": [0.0, 0.0, -9.81], "tool": tool.tolist(),
                            "base": base.tolist(), "joints": joints}, source="<class arm>")


def check_round_trip(robot: Robot, seed: int, count: int) -> None:
    q = sample_configurations(robot, count, seed)
    T = fk(robot, q)
    result = closed_form(robot, T)
    assert result.q.shape == (count, 4, 5) and np.isfinite(result.q).all()
    # The original angles are among the valid solutions.
    distance = wrapped(result.q - q[:, None]).max(-1)
    found = ((distance < 1e-7) & result.valid).any(-1)
    assert found.all(), f"{(~found).sum()} configurations not found, e.g. {q[~found][0]}"
    # Every valid solution reaches its pose; the reported errors are fk's.
    pos, rot = errors(robot, T, result.q)
    assert pos[result.valid].max() <= 1e-9 and rot[result.valid].max() <= 1e-9
    np.testing.assert_allclose(result.pos_error, pos, rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(result.rot_error, rot, rtol=1e-6, atol=1e-12)
    assert not result.refined.any()
    # Each branch's solution lies on that branch.
    k = np.argmin(np.where(result.valid, distance, np.inf), axis=-1)
    np.testing.assert_array_equal(branch_of(robot, q), k)


@pytest.mark.parametrize("name", ARMS)
@given(seed=st.integers(0, 2**32 - 1))
@settings(max_examples=10)
def test_shipped_arms_every_configuration_is_among_the_exact_solutions(name, seed):
    check_round_trip(arm(name), seed, 2000)


@given(robot=class_arms(), seed=st.integers(0, 2**32 - 1))
@settings(max_examples=40)
def test_random_arms_of_the_class_every_configuration_is_among_the_exact_solutions(robot, seed):
    check_round_trip(robot, seed, 300)


@pytest.mark.parametrize("name", ARMS)
def test_valid_solutions_reach_their_pose_by_pinocchio(name):
    """An independent forward kinematics (Pinocchio, built joint by joint)."""
    robot = arm(name)
    ref = pinocchio_model(robot)
    q = sample_configurations(robot, 100, 7)
    T = fk(robot, q)
    result = closed_form(robot, T)
    for target, solutions, valid in zip(T, result.q, result.valid):
        assert valid.any()
        for q_k in solutions[valid]:
            e = pose_error(target, ref.fk(q_k))
            assert np.linalg.norm(e[:3]) <= 1e-9 and np.linalg.norm(e[3:]) <= 1e-9


def multistart_count(robot, T, starts=256, seed=0, distinct=1e-4):
    """Distinct solutions within the limits that LM finds from ``starts`` random configurations."""
    q0 = sample_configurations(robot, (len(T), starts), seed)
    result = solve(robot, np.repeat(T[:, None], starts, axis=1), q0, restarts=0)
    counts = []
    for q, ok in zip(result.q, result.success):
        found = []
        for x in q[ok]:
            if all(wrapped(x - y).max() > distinct for y in found):
                found.append(x)
        counts.append(len(found))
    return np.array(counts)


@pytest.mark.parametrize("name", ARMS)
def test_the_count_of_solutions_agrees_with_exhaustive_multistart_lm(name):
    robot = arm(name)
    rng = np.random.default_rng(11)
    # Targets from the whole joint ranges: one, two, three and four solutions within limits.
    T = fk(robot, sample_configurations(robot, 40, rng))
    counts = closed_form(robot, T).count(distinct=1e-4)
    assert set(counts) >= ({1, 2, 3, 4} if name == "intelbot5" else {1, 2})
    np.testing.assert_array_equal(counts, multistart_count(robot, T))


@pytest.mark.parametrize("name", ARMS)
def test_a_target_outside_the_pose_set_gets_the_nearest_pose_as_lm_finds_it(name):
    """Poses turned and moved off the arm's 5-D pose set: the best branch's residual equals
    the least residual of LM with 25 starts (joint limits aside), and no branch is valid."""
    robot = arm(name)
    rng = np.random.default_rng(3)
    T = fk(robot, sample_configurations(robot, 60, rng))
    turn = rng.standard_normal((60, 3))
    turn *= np.radians(rng.uniform(0.5, 20, (60, 1))) / np.linalg.norm(turn, axis=1, keepdims=True)
    T[:, :3, :3] = exp_so3(turn) @ T[:, :3, :3]
    T[:, :3, 3] += rng.normal(0.0, 0.01, (60, 3))
    result = closed_form(robot, T)
    assert result.refined.all() and not result.valid.any() and not result.in_pose_set.any()
    pos, rot = errors(robot, T, result.q)
    np.testing.assert_allclose(result.pos_error, pos, atol=1e-15)
    cost = (0.5 * (pos ** 2 + rot ** 2)).min(-1)
    q_near, pos_near, rot_near = result.nearest()
    np.testing.assert_allclose(0.5 * (pos_near ** 2 + rot_near ** 2), cost)
    np.testing.assert_allclose(errors(robot, T, q_near[:, None])[0][:, 0], pos_near, atol=1e-15)
    lm = solve(robot, T, respect_limits=False, restarts=24)
    e = pose_error(T, fk(robot, lm.q))
    cost_lm = 0.5 * (e ** 2).sum(-1)
    assert (cost <= cost_lm * (1 + 1e-6) + 1e-15).all(), np.max(cost / cost_lm)
    assert (cost_lm.min() > 1e-10)
    # Without refinement: the closed form's projections, larger residuals, nothing refined.
    plain = closed_form(robot, T, refine=False)
    assert not plain.refined.any() and not plain.valid.any()
    assert ((0.5 * (plain.pos_error ** 2 + plain.rot_error ** 2)).min(-1) >= cost * (1 - 1e-9)).all()


def test_weights_choose_what_nearest_means(intelbot5):
    """Position-only weights: the nearest pose keeps the position exactly."""
    T = fk(intelbot5, sample_configurations(intelbot5, 20, 5))
    T[:, :3, :3] = exp_so3(np.tile([0.0, 0.3, 0.2], (20, 1))) @ T[:, :3, :3]
    result = closed_form(intelbot5, T, weights=[1, 1, 1, 0, 0, 0])
    best = result.best(weights=[1, 1, 1, 0, 0, 0])
    assert result.refined.all()
    assert np.take_along_axis(result.pos_error, best[:, None], 1).max() < 1e-9


def wrist_on_axis(robot: Robot, q: np.ndarray) -> np.ndarray:
    """``q`` with its shoulder moved so that the wrist point lies on the base axis."""
    from scipy.optimize import brentq
    g = check_class(robot)

    def ahead(q2):
        x = q.copy()
        x[1] = q2
        t = x + g.offset
        gamma = g.sigma2 * t[2]
        phi = t[1] + gamma + g.sigma * t[3]
        return g.a1 + g.a2 * np.cos(t[1]) + g.a3 * np.cos(t[1] + gamma) + g.a4 * np.cos(phi)

    grid = np.linspace(-np.pi, np.pi, 721)
    values = np.array([ahead(v) for v in grid])
    k = np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))[0]
    q = q.copy()
    q[1] = brentq(ahead, grid[k], grid[k + 1], xtol=1e-15)
    return q


def singular_configurations(robot: Robot) -> dict[str, np.ndarray]:
    g = check_class(robot)
    base = np.array([0.3, 0.2, 0.5, -0.4, 0.7])
    stretched = base.copy()
    stretched[2] = -g.offset[2]                                  # γ = 0
    folded = base.copy()
    folded[2] = np.pi - g.offset[2]                              # γ = π
    on_axis = wrist_on_axis(robot, base)
    both = on_axis.copy()                                        # the roll axis along the base axis too
    roll_axis = lambda x: fk_all(robot, x)[4][:3, 2]            # noqa: E731
    base_axis = robot.base[:3, 2]
    from scipy.optimize import minimize_scalar
    both[3] = minimize_scalar(lambda v: -abs(roll_axis(np.r_[both[:3], v, both[4]]) @ base_axis),
                              bounds=(-np.pi, np.pi), method="bounded",
                              options={"xatol": 1e-12}).x
    return {"stretched": stretched, "folded": folded, "wrist on base axis": on_axis,
            "near the axis": wrist_on_axis(robot, base) + [0, 1e-7, 0, 0, 0],
            "wrist on base axis, roll axis along it": both}


@pytest.mark.parametrize("name", ARMS)
@pytest.mark.parametrize("case", ["stretched", "folded", "wrist on base axis", "near the axis",
                                  "wrist on base axis, roll axis along it"])
def test_singular_poses_give_finite_exact_answers(name, case):
    robot = arm(name)
    q = singular_configurations(robot)[case]
    T = fk(robot, q)
    result = closed_form(robot, T, tol_pos=1e-9, tol_rot=1e-9)
    assert np.isfinite(result.q).all() and np.isfinite(result.pos_error).all()
    pos, rot = errors(robot, T, result.q)
    assert result.reaches.any()
    assert pos[result.reaches].max() <= 1e-9 and rot[result.reaches].max() <= 1e-9
    if case != "wrist on base axis, roll axis along it":     # there, a family: one member shown
        assert (wrapped(result.q[result.reaches] - q).max(-1) < 1e-6).any()


def test_the_home_pose_is_front_elbow_up(intelbot5):
    result = closed_form(intelbot5, fk(intelbot5, np.zeros(5)))
    assert BRANCHES[int(np.argmin(wrapped(result.q).max(-1)))] == "front, elbow up"
    assert result.q.shape == (4, 5) and result.valid.shape == (4,)


@pytest.mark.parametrize("name", ARMS)
def test_elbow_up_is_above_the_shoulder_wrist_line(name):
    """For front solutions (wrist ahead of the shoulder), the "up" branch's elbow lies above
    the line from shoulder to wrist, up being against gravity."""
    robot = arm(name)
    q = sample_configurations(robot, 400, 9)
    frames = fk_all(robot, q)                    # base, frame 1, …, frame 5
    shoulder, elbow, wrist = frames[:, 1, :3, 3], frames[:, 2, :3, 3], frames[:, 3, :3, 3]
    up = -robot.gravity / np.linalg.norm(robot.gravity)
    line = wrist - shoulder
    normal = np.cross(frames[:, 1, :3, 2], line)                 # in the arm's plane, ⊥ line
    normal *= np.sign(normal @ up)[:, None]
    above = np.einsum("mi,mi->m", elbow - shoulder, normal) > 0
    radial = np.einsum("mi,mi->m", line, frames[:, 1, :3, 0])   # ahead along x1
    steep = np.abs(line @ up) < 0.9 * np.linalg.norm(line, axis=1)
    branch = branch_of(robot, q)
    front = (branch < 2) & (radial > 0) & steep
    assert front.sum() > 50
    np.testing.assert_array_equal(branch[front] % 2 == 0, above[front])


@given(robot=class_arms(), seed=st.integers(0, 2**32 - 1), weightless=st.booleans())
@settings(max_examples=40)
def test_elbow_up_holds_for_links_of_either_sign_and_without_gravity(robot, seed, weightless):
    """Random arms of the class with a vertical base axis (up along it, or against gravity):
    for front solutions the "up" branch's elbow lies above the line from the shoulder's axis to
    the wrist-pitch axis (standard-DH frames 1 and 3; a modified-DH frame k is standard frame k
    less its last ``Tx(a) Rx(α)``, the next joint's ``a`` and ``α`` in the modified table)."""
    from dataclasses import replace
    base = robot.base.copy()
    base[:3, :3] = np.eye(3)
    robot = replace(robot, base=base, gravity=np.zeros(3) if weightless else robot.gravity)
    q = sample_configurations(robot, 300, seed)
    result = closed_form(robot, fk(robot, q))
    checked = 0
    front = (0, 1) if check_class(robot).forward > 0 else (2, 3)   # the columns ahead along x1
    for k in front:                                  # the front branches' own geometry
        qk = result.q[:, k]
        F = fk_all(robot, qk)
        if robot.convention == "modified":           # the standard frames 1–3
            F = F.copy()
            for j in (1, 2, 3):
                F[:, j] = F[:, j] @ _tx_rx(robot.a[j], robot.alpha[j])
        z1, x1 = F[:, 1, :3, 2], F[:, 1, :3, 0]
        shoulder, elbow, wrist = F[:, 1, :3, 3], F[:, 2, :3, 3], F[:, 3, :3, 3]  # the pitch axes
        line = wrist - shoulder
        normal = np.cross(z1, line)
        normal *= np.sign(normal[:, 2])[:, None]     # up: the base axis, +z
        side = np.einsum("mi,mi->m", elbow - shoulder, normal)
        ahead = np.einsum("mi,mi->m", line, x1)
        clear = (np.abs(side) > 1e-6) & (ahead > 1e-3) & (np.abs(line[:, 2]) < 0.9 * np.linalg.norm(line, axis=1))
        assert ((side > 0) == (k == front[0]))[clear].all()
        checked += clear.sum()
    # Most front solutions are clear of the edges (at least 162 of 600 in every example drawn):
    # a mask that kept a handful would check nothing.
    assert checked >= 100, f"only {checked} of 600 solutions clear of the elbow's and the base axis's edges"


@pytest.mark.parametrize("name", ARMS)
def test_lm_reports_the_branch_it_converged_to(name):
    robot = arm(name)
    T = fk(robot, sample_configurations(robot, 50, 4))
    lm = solve(robot, T)
    cf = closed_form(robot, T)
    assert lm.branch.shape == (50,) and lm.branch_name[0] in BRANCHES
    distance = wrapped(cf.q - lm.q[:, None]).max(-1)
    same = distance.min(-1) < 1e-4     # LM's 1e-9 m near a stretched elbow: 4e-6 rad measured
    assert same[lm.success].all()
    np.testing.assert_array_equal(lm.branch[same], np.argmin(distance, -1)[same])


@pytest.mark.parametrize("batch", [(), (3,), (2, 3)])
def test_batch_shapes(intelbot5, batch):
    T = fk(intelbot5, sample_configurations(intelbot5, batch, 1))
    result = closed_form(intelbot5, T)
    assert result.q.shape == (*batch, 4, 5)
    for field in ("valid", "reaches", "within_limits", "pos_error", "rot_error"):
        assert getattr(result, field).shape == (*batch, 4)
    assert result.refined.shape == batch and result.count().shape == batch
    assert result.best().shape == batch


def test_threads_do_not_change_the_result(intelbot5):
    from nfarm.solvers.geometric_ik import _CHUNK
    T = fk(intelbot5, sample_configurations(intelbot5, 3 * _CHUNK + 5, 2))    # four chunks
    one, two = closed_form(intelbot5, T, threads=1), closed_form(intelbot5, T, threads=2)
    for field in ("q", "valid", "pos_error", "rot_error"):
        np.testing.assert_array_equal(getattr(one, field), getattr(two, field))


def test_joint_limits_mark_solutions_invalid_but_keep_them(intelbot5):
    T = fk(intelbot5, sample_configurations(intelbot5, 500, 3))
    result = closed_form(intelbot5, T)
    outside = result.reaches & ~result.within_limits
    assert outside.any()
    lo, hi = intelbot5.qlim[:, 0], intelbot5.qlim[:, 1]
    q = result.q[outside]
    assert (((q < lo) | (q > hi)).any(-1)).all() and not result.valid[outside].any()
    inside = result.q[result.valid]
    assert ((inside >= lo) & (inside <= hi)).all()


# -- refusals ---------------------------------------------------------------------------------


def test_the_shipped_arms_are_in_the_class_and_the_puma_is_not(puma560):
    assert in_class(arm("intelbot5")) and in_class(arm("so101")) and not in_class(puma560)
    with pytest.raises(ValueError, match=r"^puma560 has no closed-form IK here: it has 6 joints"):
        closed_form(puma560, np.eye(4))


def chain(**changes) -> Robot:
    joints = [{"a": 0.0, "alpha": np.pi / 2, "d": 0.1}, {"a": 0.2, "alpha": 0.0, "d": 0.0},
              {"a": 0.2, "alpha": 0.0, "d": 0.0}, {"a": 0.0, "alpha": np.pi / 2, "d": 0.0},
              {"a": 0.0, "alpha": 0.0, "d": 0.1}]
    for key, value in changes.items():
        name, i = key.rsplit("_", 1)
        joints[int(i)][name] = value
    for j in joints:
        j.update(offset=0.0, qlim=[-3.0, 3.0], mass=1.0, com=[0, 0, 0],
                 inertia=[0.01, 0.01, 0.01, 0, 0, 0])
    return robot_from_dict({"name": "chain", "convention": "standard",
                            "gravity": [0, 0, -9.81], "joints": joints})


@pytest.mark.parametrize("changes, message", [
    ({"alpha_1": 0.3}, r"joints 2 and 3 are not parallel \(standard-DH alpha2 = 17\.1887°"),
    ({"alpha_2": -1.0}, r"joints 3 and 4 are not parallel"),
    ({"alpha_0": 0.0}, r"joint 1 is parallel to joints 2-4"),
    ({"alpha_3": np.pi}, r"joint 5 is parallel to joints 2-4"),
    ({"a_1": 0.0}, r"standard-DH a2 = 0 m: joints 2-4 need two links"),
    ({"a_2": 0.0}, r"standard-DH a3 = 0 m"),
])
def test_chains_outside_the_class_are_refused_in_one_line(changes, message):
    robot = chain(**changes)
    assert not in_class(robot)
    with pytest.raises(ValueError, match=rf"^chain has no closed-form IK here: {message}") as info:
        closed_form(robot, np.eye(4))
    assert "\n" not in str(info.value)
    with pytest.raises(ValueError, match=message):
        branch_of(robot, np.zeros(5))


@given(robot=random_chains(1, 7))
@settings(max_examples=60)
def test_random_chains_outside_the_class_are_refused_in_one_line(robot):
    """(A random chain is almost never of the class; one that is gets solved exactly.)"""
    if not in_class(robot):
        with pytest.raises(ValueError, match=r"has no closed-form IK here: .*; the closed form") as info:
            closed_form(robot, fk(robot, np.zeros(robot.n)))
        assert "\n" not in str(info.value)
        return
    check_round_trip(robot, 0, 50)


BAD = {
    "shape": (np.eye(3), r"T_target must have shape \(\.\.\., 4, 4\)"),
    "nan": (np.full((4, 4), np.nan), r"T_target: contains NaN or inf"),
    "not rigid": (np.diag([2.0, 1.0, 1.0, 1.0]), r"T_target: rotation is not orthonormal"),
    "reflection": (np.diag([-1.0, 1.0, 1.0, 1.0]), r"T_target: rotation is a reflection"),
    "text": ("pose", r"T_target must be an array of numbers"),
    "complex": (np.eye(4) * (1 + 0j), r"T_target must be an array of numbers .* got complex numbers"),
    "booleans": (np.eye(4, dtype=bool), r"got booleans"),
    "ragged": ([[1.0, 0.0], [0.0]], r"T_target must be an array of numbers"),
    "None": (None, r"T_target must be an array of numbers"),
}


@pytest.mark.parametrize("case", BAD)
def test_bad_targets_are_one_line_errors(intelbot5, case):
    T, message = BAD[case]
    for solver in (closed_form, solve):
        with pytest.raises(ValueError, match=message) as info:
            solver(intelbot5, T)
        assert "\n" not in str(info.value)


@pytest.mark.parametrize("kwargs, message", [
    ({"tol_pos": -1.0}, r"tol_pos must be a finite number > 0"),
    ({"tol_rot": float("nan")}, r"tol_rot must be a finite number"),
    ({"refine": "yes"}, r"refine must be True or False"),
    ({"refine_iter": 0}, r"refine_iter must be an integer >= 1"),
    ({"threads": 0}, r"threads must be an integer >= 1"),
    ({"limit_tol": -1e-3}, r"limit_tol must be a finite number >= 0"),
    ({"weights": [1, 1]}, r"weights must be 6 numbers"),
])
def test_bad_options_are_one_line_errors(intelbot5, kwargs, message):
    with pytest.raises(ValueError, match=message):
        closed_form(intelbot5, np.eye(4), **kwargs)


def test_not_a_robot_is_refused():
    with pytest.raises(ValueError, match="closed_form needs a Robot, got str"):
        closed_form("intelbot5", np.eye(4))


# -- the geometry the chapters show -----------------------------------------------------------


@pytest.mark.parametrize("name", ARMS)
def test_planar_points_are_the_arm_in_frame_1(name):
    """Standard-DH arms: frame k's origin, seen from frame 1, is the planar chain's point (its
    lateral part is the offset w)."""
    from nfarm.solvers.geometric_ik import planar_points
    robot = arm(name)
    q = sample_configurations(robot, 50, 8)
    frames = fk_all(robot, q)                                   # (N, 6, 4, 4): base, frames 1-5
    R1, o1 = frames[:, 1, :3, :3], frames[:, 1, :3, 3]
    local = lambda k: np.einsum("nji,nj->ni", R1, frames[:, k, :3, 3] - o1)  # noqa: E731
    p = planar_points(robot, q)
    for k, key in ((2, "elbow"), (3, "wrist pitch"), (4, "wrist point")):
        np.testing.assert_allclose(local(k)[:, :2], p[key], atol=1e-12)


@pytest.mark.parametrize("name", ARMS)
def test_branch_margins_vanish_where_solutions_meet(name):
    from nfarm.solvers.geometric_ik import branch_margins, elbow_meeting_angles
    robot = arm(name)
    q = singular_configurations(robot)
    stretched, folded = elbow_meeting_angles(robot)
    at_stretch, at_fold = q["stretched"].copy(), q["folded"].copy()
    at_stretch[2], at_fold[2] = stretched, folded
    m = branch_margins(robot, np.stack([at_stretch, at_fold, q["wrist on base axis"]]))
    assert m["elbow"][0] < 1e-12 and m["elbow"][1] < 1e-12 and m["wrist"][2] < 1e-12
    # Elsewhere: the nearest other solution is the closed form's, by the same distance.
    q = sample_configurations(robot, 200, 12)
    m = branch_margins(robot, q)
    result = closed_form(robot, fk(robot, q))
    distance = wrapped(result.q - q[:, None]).max(-1)
    expected = np.where(result.valid & (distance > 1e-6), distance, np.inf).min(-1)
    np.testing.assert_allclose(m["other"], expected)
    assert np.isfinite(m["other"]).any() and (m["elbow"] > 0).all() and (m["wrist"] > 0).all()


def test_empty_batches_and_nested_lists(intelbot5):
    assert closed_form(intelbot5, np.zeros((0, 4, 4))).q.shape == (0, 4, 5)
    assert closed_form(intelbot5, np.zeros((2, 0, 4, 4))).count().shape == (2, 0)
    T = fk(intelbot5, np.zeros(5))
    from_list = closed_form(intelbot5, T.tolist())
    np.testing.assert_array_equal(from_list.q, closed_form(intelbot5, T).q)


# -- near the class: pitch axes a rounded π apart ---------------------------------------------


NEAR = """<robot name="rounded">
  <link name="base"/>
  <joint name="yaw" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="2" velocity="3"/></joint>
  <link name="l1"/>
  <joint name="shoulder" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0 0 0.05" rpy="1.5707963267948966 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="2" velocity="3"/></joint>
  <link name="l2"/>
  <joint name="elbow" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.2 0 0" rpy="0 0 0.3"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="2" velocity="3"/></joint>
  <link name="l3"/>
  <joint name="pitch" type="revolute"><parent link="l3"/><child link="l4"/>
    <origin xyz="0.18 0 0" rpy="{rpy}"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="2" velocity="3"/></joint>
  <link name="l4"/>
  <joint name="roll" type="revolute"><parent link="l4"/><child link="hand"/>
    <origin xyz="0.05 0 0" rpy="0 1.5707963267948966 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="2" velocity="3"/></joint>
  <link name="hand"/>
</robot>"""


def near_arm(tmp_path, rpy: str) -> Robot:
    """The arm with its pitch joint's origin turned by ``rpy`` (nearly parallel axes are named
    in a warning, checked by tests/test_urdf_hardening.py)."""
    import warnings

    from nfarm.infra.reading import ParamsWarning
    from nfarm.model.urdf_import import from_urdf
    path = tmp_path / f"near_{rpy.replace(' ', '_')}.urdf"
    path.write_text(NEAR.format(rpy=rpy))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ParamsWarning)
        return from_urdf(path)


@pytest.mark.parametrize("rpy, how", [
    (f"0 {3.1416 - np.pi!r} 0", "fixed"),     # the axes meet 25 km away: DH rows and a fixed tilt
    (f"{3.1416 - np.pi!r} 0 0", "alpha"),     # their normal is the link: alpha3 = 7.3e-6 rad
])
def test_an_arm_near_the_class_is_solved_on_the_arm_itself(tmp_path, rpy, how):
    """The parallel arm's branches seed LM on the arm itself: the branch a target came from is
    found to rounding; the other branches reach the nearest pose, micrometres off (on a 5-joint
    arm, tilted pitch axes move the other branches' poses), as many of them as the exact arm has."""
    robot, exact = near_arm(tmp_path, rpy), near_arm(tmp_path, "0 0 0")
    assert (robot.fixed is not None) == (how == "fixed") and exact.fixed is None
    assert in_class(robot)
    rng = np.random.default_rng(3)
    q = rng.uniform(-2.5, 2.5, (200, 5))
    result = closed_form(robot, fk(robot, q), tol_pos=1e-10, tol_rot=1e-10)
    assert result.refined.all()
    assert result.valid.any(axis=1).all()
    nearest = np.argmin(np.abs(np.remainder(result.q - q[:, None] + np.pi, 2 * np.pi) - np.pi).max(-1), axis=1)
    found = result.q[np.arange(200), nearest]
    assert np.abs(np.remainder(found - q + np.pi, 2 * np.pi) - np.pi).max() < 1e-8
    assert result.pos_error.max() < 2e-5 and result.rot_error.max() < 5e-5     # [m], [rad] (7e-6, 1.4e-5)
    counted = closed_form(exact, fk(exact, q), tol_pos=1e-10, tol_rot=1e-10)
    near = (result.pos_error < 2e-5) & result.within_limits
    np.testing.assert_array_equal(near.sum(1), counted.valid.sum(1))     # every target, every branch


def test_identity_fixed_transforms_leave_an_arm_exact(tmp_path):
    """A robot file may write the identity after every row: a pure DH chain, solved by the closed
    form itself (``exact``), not seeded into LM as an arm near the class."""
    import dataclasses

    exact = near_arm(tmp_path, "0 0 0")
    written = dataclasses.replace(exact, fixed=np.tile(np.eye(4), (5, 1, 1)))
    assert check_class(exact).exact and check_class(written).exact
    q = np.random.default_rng(4).uniform(-2.5, 2.5, (50, 5))
    result = closed_form(written, fk(written, q))
    assert not result.refined.any()


def test_an_arm_beyond_the_near_class_is_refused_naming_the_joint_and_the_angle(tmp_path):
    robot = near_arm(tmp_path, "0 0.001 0")          # 0.057°: beyond NEAR_TOL
    with pytest.raises(ValueError, match=r"joint 3's fixed transform after its DH row turns 0\.0573° "
                                         r"and shifts .* m \(the closed form seeds LM through at most"):
        closed_form(robot, np.eye(4))
    tilted = chain(alpha_2=1e-3)
    with pytest.raises(ValueError, match=r"joints 3 and 4 are not parallel \(standard-DH alpha3 = "
                                         r"0\.0572958°; the class needs 0° or 180°, within 0\.00573°\)"):
        closed_form(tilted, np.eye(4))


def test_front_is_where_the_arm_reaches_at_home_whatever_frame_0_faces(tmp_path):
    """An arm reaching along the world's x at home, its pitch axes written as +y or −y: for one
    sense the converter's frame 0 faces backwards (x1 points behind the arm); "front" still
    names the side the arm reaches to at home, in the labels and in the columns."""
    import warnings

    from nfarm.model.urdf_import import from_urdf
    from test_add_arm import write_arm
    arms = {}
    for axis in ("0 1 0", "0 -1 0"):
        text = (write_arm(tmp_path / "arm.urdf").read_text().replace('<axis xyz="0 1 0"/>', f'<axis xyz="{axis}"/>')
                .replace('xyz="0 0 0.2"', 'xyz="0.2 0 0"').replace('xyz="0 0 0.18"', 'xyz="0.18 0 0"'))
        (tmp_path / f"arm{axis[2]}.urdf").write_text(text)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            arms[axis] = from_urdf(tmp_path / f"arm{axis[2]}.urdf", tip="tool_link")
    assert sorted(check_class(arm).forward for arm in arms.values()) == [-1.0, 1.0]
    backward = next(arm for arm in arms.values() if check_class(arm).forward < 0)
    for arm in arms.values():
        assert fk(arm, np.zeros(5))[0, 3] > 0.3                        # home: reaching along +x [m]
        assert BRANCHES[branch_of(arm, np.zeros(5))].startswith("front")
    q = np.array([[0.3, 0.4, 0.6, -0.5, 0.2], [0.3, 0.4, -0.6, 0.5, 0.2]])
    result = closed_form(backward, fk(backward, q))
    assert result.reaches.all()                        # (the back branches lie beyond ±2 rad)
    np.testing.assert_array_equal(branch_of(backward, result.q), np.broadcast_to(np.arange(4), (2, 4)))
    # In the arm's own frames: at home the wrist-pitch axis lies behind the base axis along x1
    # (frame 0 faces backwards); the front columns' wrists lie on that side, the back ones' not.
    def side(q_k):
        F = fk_all(backward, q_k)
        return np.sign(np.einsum("...i,...i->...", F[..., 3, :3, 3] - F[..., 1, :3, 3], F[..., 1, :3, 0]))
    assert side(np.zeros(5)) < 0
    np.testing.assert_array_equal(side(result.q), np.broadcast_to([-1, -1, 1, 1], (2, 4)))
