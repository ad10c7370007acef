"""Joint trajectories: boundary conditions, continuity, limits, bad input; rerun recordings."""

from __future__ import annotations

import re
import subprocess
import sys
import warnings
from collections import Counter

import numpy as np
import pytest

from nfarm.model.dynamics import rnea
from nfarm.model.kinematics import fk
from nfarm.presentation.recording import record_id_trajectory, record_ik_paths, record_trajectory
from nfarm.solvers.trajectory import (TrajectoryLimitWarning, cubic, line_path, quintic, quintic_segments,
                              time_grid, via_points)

Q0, QF = np.radians([0, 10, -20, 30, 0]), np.radians([90, 45, -60, 30, 120])
V0, VF = np.radians([0, 5, 0, -5, 0]), np.radians([10, 0, 0, 0, -10])


def test_time_grid_as_the_seed_gui():
    t = time_grid(0.0, 6.0, 0.2)
    assert len(t) == 31 and t[0] == 0.0 and t[-1] == 6.0
    np.testing.assert_allclose(np.diff(t), 0.2)
    np.testing.assert_allclose(time_grid(0, 1, 0.3), [0, 0.3, 0.6, 0.9, 1.0])


def test_cubic_boundary_conditions():
    tr = cubic(Q0, QF, V0, VF, 0.0, 6.0, 0.2)
    np.testing.assert_allclose(tr.q[[0, -1]], [Q0, QF], atol=1e-14)
    np.testing.assert_allclose(tr.qd[[0, -1]], [V0, VF], atol=1e-14)
    assert np.ptp(tr.qddd, axis=0).max() < 1e-12, "a cubic has constant jerk"


def test_quintic_boundary_conditions_and_smooth_start():
    acc0, accf = np.radians([1, 0, 0, 0, 2]), np.radians([0, -1, 0, 0, 0])
    tr = quintic(Q0, QF, V0, VF, 1.0, 4.0, 0.01, acc0=acc0, accf=accf)
    np.testing.assert_allclose(tr.q[[0, -1]], [Q0, QF], atol=1e-13)
    np.testing.assert_allclose(tr.qd[[0, -1]], [V0, VF], atol=1e-13)
    np.testing.assert_allclose(tr.qdd[[0, -1]], [acc0, accf], atol=1e-12)


@pytest.mark.parametrize("make", [cubic, quintic])
def test_derivatives_are_consistent(make):
    tr = make(Q0, QF, V0, VF, 0.0, 2.0, 1e-3)
    np.testing.assert_allclose(np.gradient(tr.q, tr.t, axis=0)[1:-1], tr.qd[1:-1], atol=1e-5)
    np.testing.assert_allclose(np.gradient(tr.qd, tr.t, axis=0)[1:-1], tr.qdd[1:-1], atol=1e-5)


def test_via_points_pass_through_with_continuous_velocity_and_acceleration():
    times = [0.0, 1.0, 2.5, 4.0]
    points = np.radians([[0, 0, 0, 0, 0], [30, 20, -40, 10, 60], [-10, 40, -80, 30, 0], [45, 10, -30, 0, 90]])
    tr = via_points(times, points, 0.05, v0=0, vf=0)
    for t_k, p_k in zip(times, points):
        np.testing.assert_allclose(tr.q[np.argmin(np.abs(tr.t - t_k))], p_k, atol=1e-12)
    np.testing.assert_allclose(tr.qd[[0, -1]], 0, atol=1e-12)
    # A step of q̇ is at most the largest |q̈| times the step (the mean value theorem), at the via points too
    dt = 0.05
    assert np.abs(np.diff(tr.qd, axis=0)).max() <= np.abs(tr.qdd).max() * dt * (1 + 1e-9)
    # Continuous at each interior via point: q̇ (quadratic on each cubic piece) and q̈ (linear) at the via point
    # are what the samples of either side extrapolate to — a kink or a jump there is not
    for t_k in times[1:-1]:
        k = int(np.argmin(np.abs(tr.t - t_k)))
        for side in (-1, 1):
            a, b, c = (k + side * j for j in (1, 2, 3))
            np.testing.assert_allclose(3 * tr.qd[a] - 3 * tr.qd[b] + tr.qd[c], tr.qd[k], rtol=0, atol=1e-9)
            np.testing.assert_allclose(2 * tr.qdd[a] - tr.qdd[b], tr.qdd[k], rtol=0, atol=1e-9)


def test_leaving_the_limits_is_reported_not_clipped(intelbot5):
    with pytest.warns(TrajectoryLimitWarning, match=r"joint 2 leaves its limits .* from t = "):
        tr = cubic([0, 0, 0, 0, 0], [0, 2.0, 0, 0, 0], 0, 0, 0.0, 2.0, 0.1, qlim=intelbot5.qlim)
    (violation,) = tr.violations
    assert violation.joint == 1 and violation.worst == pytest.approx(2.0)
    assert tr.t[np.flatnonzero(tr.q[:, 1] > intelbot5.qlim[1, 1])[0]] == violation.t_start
    assert tr.q[-1, 1] == pytest.approx(2.0), "not clipped"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert cubic(Q0, QF, V0, VF, 0, 6, 0.2, qlim=intelbot5.qlim).violations == ()


@pytest.mark.parametrize("args, message", [
    ((0, 1, 0, 0, 1.0, 1.0, 0.1), r"tf must be > t0"),
    ((0, 1, 0, 0, 0.0, 1.0, 0.0), r"dt must be > 0 and <= tf − t0"),
    ((0, 1, 0, 0, 0.0, 1.0, 2.0), r"dt must be > 0 and <= tf − t0"),
    ((0, np.nan, 0, 0, 0.0, 1.0, 0.1), r"qf must be finite"),
    ((np.zeros(5), np.zeros(4), 0, 0, 0.0, 1.0, 0.1), r"mismatched shapes"),
    ((0, 1, 0, 0, 0.0, np.inf, 0.1), r"tf must be a finite number"),
])
def test_bad_input(args, message):
    for make in (cubic, quintic):
        with pytest.raises(ValueError, match=message):
            make(*args)


def test_via_points_bad_input():
    with pytest.raises(ValueError, match="times must increase strictly"):
        via_points([0, 2, 1], np.zeros((3, 2)), 0.1)
    with pytest.raises(ValueError, match=r"times must be \(m,\)"):
        via_points([0, 1], np.zeros((3, 2)), 0.1)


def test_line_path_endpoints_and_constant_speed():
    T_a, T_b = np.eye(4), np.eye(4)
    T_b[:3, 3] = [1.0, 2.0, 3.0]
    T_b[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    path = line_path(T_a, T_b, 11)
    np.testing.assert_allclose(path[[0, -1]], [T_a, T_b], atol=1e-15)
    np.testing.assert_allclose(np.diff(path[:, :3, 3], axis=0), np.full((10, 3), [0.1, 0.2, 0.3]), atol=1e-15)


def chunk_rows(rrd) -> Counter:
    printed = subprocess.run([sys.executable, "-m", "rerun", "rrd", "print", str(rrd)],
                             capture_output=True, text=True, check=True).stdout
    rows = Counter()
    for count, entity in re.findall(r"with (\d+) rows .* - (/\S+) - data columns", printed):
        rows[entity] += int(count)
    return rows


def test_recording_holds_the_robot_and_every_time_step(intelbot5, tmp_path):
    tr = cubic(Q0, QF, V0, VF, 0.0, 6.0, 0.2)
    tau = rnea(intelbot5, tr.q, tr.qd, tr.qdd)
    path = record_trajectory(intelbot5, tr, tmp_path / "move.rrd", tau=tau, name="move", seed=3)
    subprocess.run([sys.executable, "-m", "rerun", "rrd", "verify", str(path)], check=True,
                   capture_output=True)
    rows = chunk_rows(path)
    K = len(tr.t)
    assert rows["/intelbot5"] >= 1 and any(e.startswith("/intelbot5/visual_geometries/link5") for e in rows)
    for joint in intelbot5.joint_names:
        assert rows[f"/transforms/{joint}"] == K
        for key in ("q_deg", "qd_deg_s", "tau"):
            assert rows[f"/{key}/{joint}"] == K
    assert rows["/tool_path"] == K
    assert list(tmp_path.iterdir()) == [path], "no temporary files left"
    printed = subprocess.run([sys.executable, "-m", "rerun", "rrd", "print", str(path)],
                             capture_output=True, text=True, check=True).stdout
    assert "blueprint" in printed.lower(), "the recording carries its viewer layout"


def test_ik_path_recording_holds_both_arms_and_their_errors(intelbot5, tmp_path):
    """Two copies of the arm (frames named apart), the target path, and each arm's joint
    motion, tool path and errors at every time step; bad shapes are refused, no file left."""
    t = np.linspace(0.0, 2.0, 21)
    q = np.linspace(np.zeros(5), np.radians([30, 20, -20, 10, 40]), len(t))
    off = q + np.array([0.0, 0.01, 0.0, 0.0, 0.0])
    path = record_ik_paths(intelbot5, t, fk(intelbot5, q), {"exact": q, "off": off},
                           tmp_path / "paths.rrd", seed=1)
    subprocess.run([sys.executable, "-m", "rerun", "rrd", "verify", str(path)], check=True,
                   capture_output=True)
    rows = chunk_rows(path)
    K = len(t)
    for label in ("exact", "off"):
        assert rows[f"/{label}_intelbot5"] >= 1
        for joint in intelbot5.joint_names:
            assert rows[f"/{label}_transforms/{joint}"] == K
        assert rows[f"/{label}_tool_path"] == K
        assert rows[f"/position_error_mm/{label}"] == K and rows[f"/orientation_error_deg/{label}"] == K
    assert rows["/target_path"] == 1
    assert list(tmp_path.iterdir()) == [path]
    with pytest.raises(ValueError, match=r"solutions\['off'\] must have shape \(21, 5\)"):
        record_ik_paths(intelbot5, t, fk(intelbot5, q), {"off": off[:3]}, tmp_path / "x.rrd")
    assert not (tmp_path / "x.rrd").exists()


def test_id_recording_holds_the_arm_and_every_torque_series(intelbot5, tmp_path):
    """The arm's motion and, per joint and label, one torque time series at every step; bad
    shapes are refused before a file is made."""
    t = np.linspace(0.0, 2.0, 21)
    q = np.linspace(np.zeros(5), np.radians([30, 20, -20, 10, 40]), len(t))
    tau = np.sin(t)[:, None] * np.arange(1, 6)
    path = record_id_trajectory(intelbot5, t, q, {"true": tau, "anfis": tau + 0.01},
                                tmp_path / "id.rrd", seed=2)
    subprocess.run([sys.executable, "-m", "rerun", "rrd", "verify", str(path)], check=True,
                   capture_output=True)
    rows = chunk_rows(path)
    for joint in intelbot5.joint_names:
        assert rows[f"/transforms/{joint}"] == len(t)
        assert rows[f"/tau/{joint}/true"] == len(t) and rows[f"/tau/{joint}/anfis"] == len(t)
    assert rows["/tool_path"] == len(t)
    assert list(tmp_path.iterdir()) == [path]
    with pytest.raises(ValueError, match=r"torques\['anfis'\] must have shape \(21, 5\)"):
        record_id_trajectory(intelbot5, t, q, {"anfis": tau[:, :4]}, tmp_path / "x.rrd")
    with pytest.raises(ValueError, match=r"at least one"):
        record_id_trajectory(intelbot5, t, q, {}, tmp_path / "x.rrd")
    assert not (tmp_path / "x.rrd").exists()




def test_quintic_segments_are_the_quintic_in_normalised_time():
    """The batched evaluator and the sampled quintic are one polynomial: positions,
    velocities and accelerations agree on random segments with end velocities."""
    rng = np.random.default_rng(5)
    for p0, p1, v0, v1, T in rng.uniform(-2, 2, size=(20, 5)):
        T = abs(T) + 0.1
        reference = quintic(p0, p1, v0, v1, 0.0, T, T / 16)
        q, qd, qdd = quintic_segments(p0, v0, p1, v1, T, reference.t / T)
        np.testing.assert_allclose(q, reference.q[:, 0], atol=1e-12)
        np.testing.assert_allclose(qd, reference.qd[:, 0], atol=1e-10)
        np.testing.assert_allclose(qdd, reference.qdd[:, 0], atol=1e-8 / T**2)
