"""Inverse kinematics: round trips, unreachable targets, limits, determinism, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import load_quietly
from nfarm.solvers.ik import DLS, JT, LM, METHODS, REASONS, Pinv, solve
from nfarm.model.kinematics import fk
from nfarm.infra.paths import PARAMS
from nfarm.model.robot import robot_from_dict, sample_configurations
from nfarm.model.rotations import exp_so3, pose_error

ROBOTS = {name: load_quietly(PARAMS / "robots" / f"{name}.yaml") for name in ("intelbot5", "puma560")}


def assert_within_limits(robot, q):
    assert np.all(q >= robot.qlim[:, 0]) and np.all(q <= robot.qlim[:, 1])


@pytest.mark.parametrize("name", ROBOTS)
@given(seed=st.integers(0, 2**32 - 1))
@settings(max_examples=15)
def test_round_trip_reaches_every_target_to_full_accuracy(name, seed):
    """fk(solve(fk(q)).q) = fk(q) to 1e-9 m and 1e-9 rad, within the joint limits."""
    robot = ROBOTS[name]
    q = sample_configurations(robot, 40, seed)
    T = fk(robot, q)
    result = solve(robot, T, seed=seed)
    assert result.success.all(), result.reason[~result.success]
    assert (result.reason == "converged").all()
    error = pose_error(T, fk(robot, result.q))
    assert np.linalg.norm(error[:, :3], axis=1).max() <= 1e-9
    assert np.linalg.norm(error[:, 3:], axis=1).max() <= 1e-9
    np.testing.assert_allclose(result.pos_error, np.linalg.norm(error[:, :3], axis=1), atol=1e-15)
    assert_within_limits(robot, result.q)


def random_poses(count, seed, reach=0.3):
    rng = np.random.default_rng(seed)
    T = np.tile(np.eye(4), (count, 1, 1))
    T[:, :3, :3] = exp_so3(rng.normal(size=(count, 3)))
    T[:, :3, 3] = rng.uniform(-reach, reach, (count, 3))
    return T


def test_unreachable_targets_end_with_the_closest_configuration(intelbot5):
    """A 5-DOF arm reaches almost no random 6-D pose: no exception, no NaN, reason given,
    and the returned q is at least as close as any configuration the search started from."""
    T = random_poses(60, seed=1)
    result = solve(intelbot5, T, restarts=4)
    assert not result.success.any()
    assert set(result.reason) <= {"unreachable", "max_iter"} and (result.reason == "unreachable").mean() > 0.9
    assert np.isfinite(result.q).all()
    assert_within_limits(intelbot5, result.q)
    E = lambda q: 0.5 * (pose_error(T, fk(intelbot5, q)) ** 2).sum(-1)  # noqa: E731
    assert np.all(E(result.q) <= E(np.zeros(5)) + 1e-12)
    np.testing.assert_allclose(result.pos_error, np.linalg.norm(pose_error(T, fk(intelbot5, result.q))[:, :3], axis=1))


@pytest.mark.parametrize("options, tolerance", [({}, 1e-2), ({"stall_rtol": 1e-9, "max_iter": 2000}, 1e-5)])
def test_out_of_reach_position_ends_stretched_towards_it(intelbot5, options, tolerance):
    """The least-squares closest point to a position 2 m away (36° above the shoulder, so the
    stretched arm pointing at it is within the limits) is the stretched arm's tip. The
    stretched arm is singular, so LM creeps towards it; the stall test decides how far."""
    T = np.eye(4)
    T[:3, 3] = [0.0, 0.0, 0.105] + 2.0 * np.array([np.cos(0.63), 0.0, np.sin(0.63)])
    result = solve(intelbot5, T, weights=[1, 1, 1, 0, 0, 0], **options)
    assert not result.success and result.reason == "unreachable"
    tip = fk(intelbot5, result.q)[:3, 3]
    assert result.pos_error == pytest.approx(np.linalg.norm(T[:3, 3] - tip), rel=1e-12)
    stretched = 0.2 + 0.18 + 0.11
    assert stretched * (1 - tolerance) <= np.linalg.norm(tip - [0, 0, 0.105]) <= stretched
    optimum = 2.0 - stretched
    assert optimum - 1e-12 <= result.pos_error <= optimum * (1 + tolerance)


def test_position_only_weights_reach_positions_of_unreachable_poses(intelbot5):
    T = fk(intelbot5, sample_configurations(intelbot5, 30, 5))
    T[:, :3, :3] = exp_so3(np.random.default_rng(0).normal(size=(30, 3))) @ T[:, :3, :3]
    result = solve(intelbot5, T, weights=[1, 1, 1, 0, 0, 0])
    assert result.success.all()
    assert result.pos_error.max() <= 1e-9
    assert result.rot_error.min() > 1e-3, "the orientation is not asked for and not reached"


def planar_2r(lo=0.0, hi=0.5):
    joint = {"a": 1.0, "alpha": 0.0, "d": 0.0, "offset": 0.0, "qlim": [lo, hi], "mass": 1.0,
             "com": [-0.5, 0, 0], "inertia": [0.01, 0.1, 0.1, 0, 0, 0]}
    return robot_from_dict({"name": "planar2r", "convention": "standard",
                            "gravity": [0, -9.81, 0], "joints": [joint, dict(joint)]})


def test_a_pose_reachable_only_outside_the_limits_is_reported_as_such():
    """A planar 2R arm reaches (x, y) with elbow up or down; both lie outside tight limits."""
    robot = planar_2r()
    T = fk(robot, np.array([1.0, 1.0]))
    result = solve(robot, T, weights=[1, 1, 0, 0, 0, 0], restarts=5)
    assert not result.success and result.reason == "joint_limits"
    assert_within_limits(robot, result.q)
    free = solve(robot, T, weights=[1, 1, 0, 0, 0, 0], respect_limits=False)
    assert free.success and free.pos_error <= 1e-9


def test_same_seed_same_result_and_the_seed_matters(intelbot5):
    T = np.concatenate([fk(intelbot5, sample_configurations(intelbot5, 50, 3)), random_poses(10, 2)])
    a, b = solve(intelbot5, T, seed=7), solve(intelbot5, T, seed=7)
    for field in ("q", "success", "iterations", "restarts", "pos_error", "rot_error", "reason"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    c = solve(intelbot5, T, seed=8)
    assert not np.array_equal(a.q[-10:], c.q[-10:])


@pytest.mark.parametrize("method", METHODS)
def test_each_method_converges_on_an_easy_target(intelbot5, method):
    q_ready = np.zeros(5)
    T = fk(intelbot5, q_ready + np.radians([5, -4, 3, 6, -5]))
    result = solve(intelbot5, T, q_ready, method=method, restarts=0)
    assert result.success and result.reason == "converged", (method, result.reason)
    assert result.pos_error <= 1e-9 and result.rot_error <= 1e-9


def test_marquardt_damping_also_solves(intelbot5):
    T = fk(intelbot5, sample_configurations(intelbot5, 30, 11))
    assert solve(intelbot5, T, method=LM(damping="marquardt")).success.all()


# What the documentation promises a name picks (nfarm.solvers.ik_methods: its table and the
# constants its docstring argues for — Sugihara's rule with s = 0.1, w̄ = 1e-12, ν ×10; DLS's
# μ = 0.05 m; the pseudo-inverse's cut-off 1e-6), written out rather than read from METHODS.
DOCUMENTED = {"lm": LM(damping="sugihara", scale=0.1, bias=1e-12, factor=10.0), "dls": DLS(damping=0.05),
              "pinv": Pinv(rcond=1e-6), "jt": JT()}
# The same rules with another option: a name that picked one of these would be caught.
OTHERS = {"lm": LM(damping="marquardt"), "dls": DLS(damping=0.5), "pinv": Pinv(rcond=0.5), "jt": DLS()}


def test_the_documented_names_are_the_methods():
    assert set(METHODS) == set(DOCUMENTED)


@pytest.mark.parametrize("name", list(DOCUMENTED))
def test_a_method_s_name_is_that_method_with_its_documented_defaults(intelbot5, name):
    T = good_targets(intelbot5, 2 if name == "jt" else 20)      # the transpose takes thousands of steps a target
    fields = ("q", "success", "iterations", "restarts", "pos_error", "rot_error", "reason")
    by_name, documented = solve(intelbot5, T, method=name), solve(intelbot5, T, method=DOCUMENTED[name])
    for field in fields:
        np.testing.assert_array_equal(getattr(by_name, field), getattr(documented, field))
    other = solve(intelbot5, T, method=OTHERS[name])
    assert any(not np.array_equal(getattr(by_name, f), getattr(other, f)) for f in fields), \
        "the comparison can tell rules apart"


def test_the_methods_are_importable_from_the_top():
    import nfarm

    assert (nfarm.LM, nfarm.DLS, nfarm.Pinv, nfarm.JT) == (LM, DLS, Pinv, JT)
    assert {"LM", "DLS", "Pinv", "JT"} <= set(dir(nfarm))


@pytest.mark.parametrize("batch", [(), (1,), (2, 3)])
def test_batch_shapes_and_history(intelbot5, batch):
    T = fk(intelbot5, sample_configurations(intelbot5, batch, 4))
    result = solve(intelbot5, T, record_history=True)
    assert result.q.shape == (*batch, 5)
    for field in ("success", "iterations", "restarts", "pos_error", "rot_error", "reason"):
        assert np.shape(getattr(result, field)) == batch
    assert result.history.shape[:-2] == batch and result.history.shape[-1] == 2
    first = result.history.reshape(-1, *result.history.shape[-2:])[:, 0]
    assert np.isfinite(first).all()
    assert set(np.ravel(result.reason)) <= set(REASONS)


def good_targets(robot, count=4):
    return fk(robot, sample_configurations(robot, count, 0))


def bad(change):
    def make(robot):
        T = good_targets(robot).copy()
        change(T)
        return T
    return make


BAD_TARGETS = {
    "shape": (lambda robot: np.eye(3), r"T_target must have shape \(\.\.\., 4, 4\), got \(3, 3\)"),
    "nan": (bad(lambda T: T.__setitem__((2, 0, 3), np.nan)), r"T_target\[2\]: contains NaN or inf"),
    "inf": (bad(lambda T: T.__setitem__((1, 1, 1), np.inf)), r"T_target\[1\]: contains NaN or inf"),
    "last row": (bad(lambda T: T.__setitem__((3, 3, 0), 0.5)), r"T_target\[3\]: last row must be \[0, 0, 0, 1\]"),
    "not orthonormal": (bad(lambda T: T.__setitem__((1, 0, 0), T[1, 0, 0] + 1e-3)), r"T_target\[1\]: rotation is not orthonormal"),
    "reflection": (bad(lambda T: T.__setitem__((2, slice(0, 3), 0), -T[2, :3, 0])), r"T_target\[2\]: rotation is a reflection"),
}


@pytest.mark.parametrize("rule", BAD_TARGETS)
def test_bad_targets_name_the_first_bad_index(intelbot5, rule):
    make, message = BAD_TARGETS[rule]
    with pytest.raises(ValueError, match=message):
        solve(intelbot5, make(intelbot5))


def test_bad_target_index_in_a_2d_batch(intelbot5):
    T = fk(intelbot5, sample_configurations(intelbot5, (2, 3), 0))
    T[1, 2, 0, 0] = np.nan
    with pytest.raises(ValueError, match=r"T_target\[1, 2\]: contains NaN"):
        solve(intelbot5, T)



@pytest.mark.parametrize("rule", ["nan", "last row", "not orthonormal", "reflection"])
def test_bad_targets_beyond_the_first_check_chunk_are_named(intelbot5, rule, monkeypatch):
    import nfarm.solvers.arguments
    import nfarm.solvers.ik
    monkeypatch.setattr(nfarm.solvers.arguments, "_CHECK_CHUNK", 3)       # the pose sits in the second chunk
    make, message = BAD_TARGETS[rule]
    T = make(intelbot5)
    bad_row = {"nan": 2, "last row": 3, "not orthonormal": 1, "reflection": 2}[rule]
    shifted = np.concatenate([good_targets(intelbot5)[:4], T[bad_row:bad_row + 1]])
    with pytest.raises(ValueError, match=message.replace(rf"\[{bad_row}\]", r"\[4\]")):
        nfarm.solvers.ik.check_targets(shifted)

@pytest.mark.parametrize("kwargs, message", [
    (dict(q0=np.zeros(4)), r"q0 must have shape \(5,\) or \(4, 5\)"),
    (dict(q0=np.full(5, 3.0)), r"q0: must be finite and within the joint limits"),
    (dict(q0=np.r_[np.zeros((3, 5)), [[0, 0, 0, 0, np.nan]]]), r"q0\[3\]: must be finite"),
    (dict(q0="ready"), r"q0 must be None, 'home' or joint angles"),
    (dict(weights=[1, 1, 1]), r"weights must be 6 numbers"),
    (dict(weights=[1, 1, 1, 1, 1, -1]), r"weights must be finite, >= 0 and not all zero"),
    (dict(weights=np.zeros(6)), r"weights must be finite, >= 0 and not all zero"),
    (dict(method="newton"), r"method must be one of lm, dls, pinv, jt or an update rule"),
    (dict(method=LM), r"method must be one of lm, dls, pinv, jt or an update rule \(LM\(\), DLS\(\)"),
    (dict(lm_damping="marquardt"), r"unexpected keyword argument 'lm_damping'"),   # LM(damping=…)
    (dict(tol_pos=0.0), r"tol_pos must be a finite number > 0, got 0.0"),
    (dict(ortho_tol=np.nan), r"ortho_tol must be a finite number > 0 and < 1, got nan"),
    (dict(restarts=2.5), r"restarts must be an integer >= 0, got 2.5"),
    (dict(seed=-1), r"seed must be an integer >= 0, got -1"),
    (dict(chunk=0), r"chunk must be an integer >= 1, got 0"),
    (dict(restarts=300), r"restarts \(300\) must be below guess_table \(256\)"),
])
def test_bad_options_are_clear_errors(intelbot5, kwargs, message):
    with pytest.raises((ValueError, TypeError), match=message):
        solve(intelbot5, good_targets(intelbot5), **kwargs)


# A method's options are checked when it is made, in one line naming the option and the rule:
# unchecked, a NaN or out-of-range option turns reachable targets into "unreachable" silently.
@pytest.mark.parametrize("make, message", [
    (lambda: LM(damping="fixed"), r"LM: damping must be 'sugihara' or 'marquardt', got 'fixed'"),
    (lambda: LM(scale=-1), r"LM: scale must be a finite number >= 0, got -1"),
    (lambda: LM(bias=np.nan), r"LM: bias must be a finite number >= 0, got nan"),
    (lambda: LM(factor=0), r"LM: factor must be a finite number > 1, got 0"),
    (lambda: LM(lambda0=np.nan), r"LM: lambda0 must be a finite number > 0, got nan"),
    (lambda: LM(scale=0, bias=0), r"LM: scale and bias must not both be 0"),
    (lambda: DLS(damping=np.inf), r"DLS: damping must be a finite number > 0, got inf"),
    (lambda: Pinv(rcond=np.nan), r"Pinv: rcond must be a finite number > 0 and < 1, got nan"),
    (lambda: Pinv(rcond=True), r"Pinv: rcond must be a finite number > 0 and < 1, got True"),
])
def test_bad_method_options_are_clear_errors(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_q0_outside_the_limits_is_fine_when_limits_are_not_respected(intelbot5):
    T = good_targets(intelbot5, 1)[0]
    assert solve(intelbot5, T, np.full(5, 3.0), respect_limits=False).success


def test_the_seed_table_is_not_the_users_sample(intelbot5):
    """Targets drawn with the solver's own seed are not trivially in its table of starts."""
    T = fk(intelbot5, sample_configurations(intelbot5, 50, 0))
    assert np.median(solve(intelbot5, T, seed=0).iterations) >= 2


def test_empty_batch_gives_an_empty_result(intelbot5):
    result = solve(intelbot5, np.zeros((0, 4, 4)))
    assert result.q.shape == (0, 5) and result.success.shape == (0,) and result.reason.shape == (0,)
    result = solve(intelbot5, np.zeros((3, 0, 4, 4)), record_history=True)
    assert result.q.shape == (3, 0, 5) and result.history.shape == (3, 0, 0, 2)


def test_chunks_do_not_change_any_target_s_result(intelbot5):
    """Targets are solved in bounded chunks; each result is the same whatever the chunk size."""
    q = sample_configurations(intelbot5, 37, seed=5)
    T = fk(intelbot5, q).reshape(37, 4, 4)
    T[::7, :3, 3] += 0.3                          # some unreachable targets, with restarts
    whole = solve(intelbot5, T)
    parts = solve(intelbot5, T, chunk=8)
    for field in ("q", "success", "iterations", "restarts", "pos_error", "rot_error", "reason"):
        np.testing.assert_array_equal(getattr(parts, field), getattr(whole, field), err_msg=field)


def test_solve_path_stays_on_the_branch_it_starts_on(intelbot5):
    """solve_path follows a tool path from the previous solution: on a path whose every pose has
    other solutions (the elbow flipped, the arm turned over), it keeps the start's branch at every
    point, recovers the path's own configurations, and takes no step larger than the path's."""
    from nfarm.solvers.arm_class import BRANCHES, branch_of
    from nfarm.solvers.geometric_ik import closed_form
    from nfarm.solvers.iterative import solve_path

    # [rad]: front, elbow down at every point, where LM from the home configuration finds the elbow up
    q_path = np.linspace([0.3, -0.9, 1.9, -0.8, 0.1], [1.2, -0.7, 1.6, -0.5, -0.4], 60)
    T = fk(intelbot5, q_path)
    branch = branch_of(intelbot5, q_path)
    assert len(set(branch.tolist())) == 1
    other = np.delete(closed_form(intelbot5, T).reaches, branch[0], axis=-1)
    assert other.any(axis=-1).all(), "every pose has another branch's solution (joint limits aside)"
    assert (solve(intelbot5, T, np.zeros(5), restarts=0).branch != branch[0]).all()
    result = solve_path(intelbot5, T, q_path[0])
    assert result.success.all()
    assert set(result.branch.tolist()) == {int(branch[0])}, BRANCHES[branch[0]]
    np.testing.assert_allclose(result.q, q_path, rtol=0, atol=1e-6)
    steps = np.abs(np.diff(result.q, axis=0)).max()
    assert steps <= np.abs(np.diff(q_path, axis=0)).max() + 1e-6
