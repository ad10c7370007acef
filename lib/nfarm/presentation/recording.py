"""Rerun recordings (``.rrd``) of joint trajectories, replayable in the rerun viewer.

:func:`record_trajectory` holds the robot (its URDF from :func:`nfarm.model.urdf_export.to_urdf`, loaded by rerun's own
URDF loader), the joint transforms over time (so the robot moves), the tool path growing with
time (one segment a step, which the viewer accumulates up to the time cursor), and joint positions [deg], velocities [deg/s] and (optionally) torques [N·m] as
scalar time series, in degrees like every figure of the report. It carries its viewer layout
(a blueprint): the moving arm on the left, one plot each for positions, velocities and
torques on the right.
:func:`record_ik_paths` shows
several arms (copies of one robot, told apart by colour and name prefix) following one
Cartesian path with different IK solutions, with their tool errors over time.
:func:`record_id_trajectory` shows one arm moving along a joint trajectory and, per joint, the
true torque beside the predictions of several models, as time series.
Nothing is displayed: open the file with the pinned viewer, ``.venv/bin/rerun FILE.rrd``.
The recording id comes from the name and the seed, so the same inputs give the same recording
(the file itself also stores when it was written).
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
import rerun.urdf as rru

from ..infra.arguments import check_integer
from ..infra.paths import atomic_path, shown_path
from ..model.kinematics import fk
from ..model.robot import Robot
from ..model.rotations import pose_error
from ..model.urdf_export import to_urdf
from ..solvers.trajectory import Trajectory

__all__ = ["record_trajectory", "record_ik_paths", "record_id_trajectory", "TIMELINE", "RecordingTooLarge",
           "expected_bytes", "MAX_BYTES"]

#: The timeline every recording uses (seconds of trajectory time).
TIMELINE = "time"
#: The default limit of a recording's size [bytes] (every function's ``max_bytes``).
MAX_BYTES = 256 * 2**20
# What a recording stores, in bytes (upper bounds of the sizes measured with rerun 0.41 on the
# three shipped arms, 1 000 to 20 000 samples: 492-603 bytes a sample for intelbot5, 724 for the
# Puma with torques; 81-109 kB besides): the arm's files and the layout, and per sample each
# joint's transform, each scalar series' value, each tool path's segment.
_FIXED_BYTES = 256 * 1024
_TRANSFORM_BYTES, _SCALAR_BYTES, _SEGMENT_BYTES = 64, 20, 40


class RecordingTooLarge(ValueError):
    """A recording would be larger than its limit; nothing was written."""


def expected_bytes(samples: int, *, transforms: int, scalars: int, paths: int = 1) -> int:
    """About how many bytes a recording of ``samples`` time steps takes, with ``transforms``
    joint transforms, ``scalars`` scalar series and ``paths`` growing tool paths (each one
    value a step): it grows linearly with every count. An upper estimate (measured sizes are
    5-15 % below it).

    Example:
        >>> round(expected_bytes(10_000, transforms=5, scalars=15) / 2**20, 1)    # intelbot5 with torques [MiB]
        6.5
    """
    return _FIXED_BYTES + samples * (transforms * _TRANSFORM_BYTES + scalars * _SCALAR_BYTES + paths * _SEGMENT_BYTES)


def _check_size(path: Path, samples: int, max_bytes: int, **counts) -> None:
    """Raise :class:`RecordingTooLarge` (one line) before a byte is written when the recording of
    ``path`` would exceed ``max_bytes``."""
    check_integer("max_bytes", max_bytes, 1, numpy=False,
                  message=f"max_bytes must be a positive whole number of bytes, got {type(max_bytes).__name__} "
                          f"{max_bytes}")
    size = expected_bytes(samples, **counts)
    if size > max_bytes:
        raise RecordingTooLarge(f"{shown_path(path)}: a recording of {samples:,} samples would take about "
                                f"{size / 2**20:,.1f} MiB, over the limit of {max_bytes / 2**20:,.1f} MiB "
                                f"(max_bytes): nothing written; take a larger time step")


def record_trajectory(robot: Robot, trajectory: Trajectory, path: str | os.PathLike, *,
                      tau: np.ndarray | None = None, name: str = "trajectory",
                      seed: int = 0, max_bytes: int = MAX_BYTES) -> Path:
    """Write ``trajectory`` of ``robot`` to the rerun file ``path`` (atomically); return it.

    Entities: ``/{robot.name}`` (the URDF), ``/transforms/{joint}`` (joint motion),
    ``/tool_path`` (line strip of the tool origin so far), ``/q_deg/{joint}``,
    ``/qd_deg_s/{joint}`` and, with ``tau (K, n)`` [N·m], ``/tau/{joint}``. The size grows
    linearly with K (:func:`expected_bytes`: about 0.6 kB a sample for a 5-joint arm).

    Raises:
        RecordingTooLarge: the recording would take more than ``max_bytes`` (checked first).
    """
    t, q = trajectory.t, trajectory.q
    if tau is not None and np.shape(tau) != q.shape:
        raise ValueError(f"tau must have the shape of q {q.shape}, got {np.shape(tau)}")
    path = Path(path)
    _check_size(path, len(t), max_bytes, transforms=robot.n, scalars=robot.n * (2 if tau is None else 3))
    series = {"q_deg": np.degrees(q), "qd_deg_s": np.degrees(trajectory.qd)} | \
        ({} if tau is None else {"tau": np.asarray(tau)})
    titles = {"q_deg": "joint angle [deg]", "qd_deg_s": "joint velocity [deg/s]",
              "tau": "joint torque [N·m]"}
    blueprint = rrb.Blueprint(rrb.Horizontal(
        rrb.Spatial3DView(origin="/", name=f"{robot.name}: arm and tool path", overrides=_trail("tool_path")),
        rrb.Vertical(*(rrb.TimeSeriesView(origin=f"/{key}", name=titles[key]) for key in series)),
        column_shares=[3, 2]), collapse_panels=True)
    with _recording(path, name, seed, blueprint, t) as (rec, times, tmp):
        _log_arm(rec, robot, q, times, tmp)
        for key, values in series.items():
            for j, joint_name in enumerate(robot.joint_names):
                rec.send_columns(f"{key}/{joint_name}", indexes=times,
                                 columns=rr.Scalars.columns(scalars=values[:, j]))
        _log_growing_path(rec, "tool_path", t, fk(robot, q)[:, :3, 3], (230, 120, 30))
    return path


@contextlib.contextmanager
def _recording(path: Path, name: str, seed: int, blueprint, t: np.ndarray):
    """A recording written to ``path`` atomically, with its blueprint, its id from ``name`` and
    ``seed``: yields the stream, the time column of ``t`` [s] and a temporary directory."""
    rec = rr.RecordingStream(f"nfarm_{name}", recording_id=f"nfarm-{name}-{seed}")
    with tempfile.TemporaryDirectory() as tmp, atomic_path(path) as out:
        rec.save(out, default_blueprint=blueprint)
        yield rec, [rr.TimeColumn(TIMELINE, duration=t)], Path(tmp)
        rec.flush()
        rec.disconnect()


def _log_arm(rec, robot: Robot, q: np.ndarray, times, tmp: Path, *, prefix: str = "",
             color: tuple[float, float, float] = (0.85, 0.55, 0.15)) -> None:
    """The arm's URDF (static; links and joints named with ``prefix``) and its joint motion
    ``q (K, n)`` [rad] at ``times``, under ``/{prefix}transforms/{joint}``."""
    # the robot's name as one plain file name (a URDF's robot name may be any text)
    urdf = tmp / (re.sub(r"[^A-Za-z0-9_.-]", "_", f"{prefix}{robot.name}").lstrip(".") + ".urdf")
    urdf.write_text(to_urdf(robot, prefix=prefix, color=color), encoding="utf-8")
    rec.log_file_from_path(urdf, static=True)
    rec.flush()
    tree = rru.UrdfTree.from_file_path(urdf)
    for j, joint_name in enumerate(robot.joint_names):
        joint = tree.get_joint_by_name(prefix + joint_name)
        rec.send_columns(f"{prefix}transforms/{joint_name}", indexes=times,
                         columns=joint.compute_transform_columns(q[:, j], clamp=False))


def _log_growing_path(rec, entity: str, t: np.ndarray, points: np.ndarray, rgb) -> None:
    """``points (K, 3)`` [m] as a path that grows with time ``t (K,)`` [s]: at each time the one
    segment from the point before, which the viewer accumulates (the entity's visible time
    range, :func:`_trail`, runs from the start to the time cursor). Stored once each: 2 K points,
    where a strip of the whole path so far at every time stored K(K + 1)/2."""
    K = len(t)
    segments = np.stack([points[np.maximum(np.arange(K) - 1, 0)], points], axis=1)
    rec.send_columns(entity, indexes=[rr.TimeColumn(TIMELINE, duration=t)],
                     columns=rr.LineStrips3D.columns(strips=segments, colors=np.tile(np.asarray(rgb, np.uint8), (K, 1)),
                                                     radii=np.full(K, 0.002, dtype=np.float32)))


def _trail(*entities: str) -> dict:
    """A 3-D view's overrides that show each of ``entities`` from the start up to the time
    cursor: the growing paths of :func:`_log_growing_path`."""
    since_start = rrb.VisibleTimeRanges(timeline=TIMELINE, start=rrb.TimeRangeBoundary.infinite(),
                                        end=rrb.TimeRangeBoundary.cursor_relative())
    return {f"/{entity}": since_start for entity in entities}


#: Link colours (RGB) and path colours (0–255) of the arms of :func:`record_ik_paths`.
_ARM_COLOURS = [((0.85, 0.55, 0.15), (230, 120, 30)), ((0.25, 0.45, 0.85), (60, 110, 220)),
                ((0.3, 0.7, 0.35), (70, 170, 80))]


def record_ik_paths(robot: Robot, t: np.ndarray, T_path: np.ndarray,
                    solutions: dict[str, np.ndarray], path: str | os.PathLike, *,
                    name: str = "ik_path", seed: int = 0, max_bytes: int = MAX_BYTES) -> Path:
    """Write arms following one Cartesian path with different IK solutions to the rerun file
    ``path`` (atomically); return it.

    Args:
        t: ``(K,)`` time [s] of each target; ``T_path (K, 4, 4)`` the target tool poses.
        solutions: label → ``q (K, n)`` [rad] (at most three), e.g. ``{"anfis": …, "lm": …}``;
            labels are entity-path names.

    Entities: ``/target_path`` (the targets' positions, grey), per label ``/{label}_{robot}``
    (the arm, its URDF named with the prefix ``{label}_``), ``/{label}_transforms/{joint}``,
    ``/{label}_tool_path`` (the tool point so far), and the errors of ``fk(q)`` against the
    target as time series ``/position_error_mm/{label}`` [mm] and
    ``/orientation_error_deg/{label}`` [deg].

    Raises:
        RecordingTooLarge: the recording would take more than ``max_bytes`` (checked first).
    """
    t = np.asarray(t, dtype=float)
    T_path = np.asarray(T_path, dtype=float)
    if T_path.shape != (len(t), 4, 4):
        raise ValueError(f"T_path must have shape ({len(t)}, 4, 4) (one pose per time), got {T_path.shape}")
    if not 1 <= len(solutions) <= len(_ARM_COLOURS):
        raise ValueError(f"solutions must hold 1 to {len(_ARM_COLOURS)} labelled joint paths, got {len(solutions)}")
    for label, q in solutions.items():
        if np.shape(q) != (len(t), robot.n):
            raise ValueError(f"solutions[{label!r}] must have shape ({len(t)}, {robot.n}), got {np.shape(q)}")
    path = Path(path)
    _check_size(path, len(t), max_bytes, transforms=robot.n * len(solutions), scalars=2 * len(solutions),
                paths=len(solutions) + 1)
    blueprint = rrb.Blueprint(rrb.Horizontal(
        rrb.Spatial3DView(origin="/", name=f"{robot.name}: {' and '.join(solutions)} on one path",
                          overrides=_trail(*(f"{label}_tool_path" for label in solutions))),
        rrb.Vertical(rrb.TimeSeriesView(origin="/position_error_mm", name="tool position error [mm]"),
                     rrb.TimeSeriesView(origin="/orientation_error_deg", name="tool orientation error [deg]")),
        column_shares=[3, 2]), collapse_panels=True)
    with _recording(path, name, seed, blueprint, t) as (rec, times, tmp):
        rec.log("target_path", rr.LineStrips3D([T_path[:, :3, 3]], colors=[[150, 150, 150]],
                                               radii=0.001), static=True)
        for (label, q), (link_rgb, path_rgb) in zip(solutions.items(), _ARM_COLOURS):
            q = np.asarray(q, dtype=float)
            _log_arm(rec, robot, q, times, tmp, prefix=f"{label}_", color=link_rgb)
            T_q = fk(robot, q)
            twist = pose_error(T_path, T_q)
            rec.send_columns(f"position_error_mm/{label}", indexes=times, columns=rr.Scalars.columns(
                scalars=1e3 * np.linalg.norm(twist[:, :3], axis=1)))
            rec.send_columns(f"orientation_error_deg/{label}", indexes=times, columns=rr.Scalars.columns(
                scalars=np.degrees(np.linalg.norm(twist[:, 3:], axis=1))))
            _log_growing_path(rec, f"{label}_tool_path", t, T_q[:, :3, 3], path_rgb)
    return path


def record_id_trajectory(robot: Robot, t: np.ndarray, q: np.ndarray,
                         torques: dict[str, np.ndarray], path: str | os.PathLike, *,
                         name: str = "id_trajectory", seed: int = 0, max_bytes: int = MAX_BYTES) -> Path:
    """Write a joint trajectory of ``robot`` and labelled torques along it to the rerun file
    ``path`` (atomically); return it.

    Args:
        t: ``(K,)`` time [s]; ``q (K, n)`` joint angles [rad].
        torques: label → ``tau (K, n)`` [N·m], e.g. ``{"true": …, "anfis": …}`` (labels are
            entity-path names; at least one).

    Entities: the arm (``/{robot.name}``, ``/transforms/{joint}``), ``/tool_path``, and
    ``/tau/{joint}/{label}`` — one plot per joint in the blueprint, all labels in it, so that
    prediction and truth lie on top of each other.

    Raises:
        RecordingTooLarge: the recording would take more than ``max_bytes`` (checked first).
    """
    t = np.asarray(t, dtype=float)
    q = np.asarray(q, dtype=float)
    if t.ndim != 1 or q.shape != (len(t), robot.n):
        raise ValueError(f"q must have shape ({len(t)}, {robot.n}) (one row per time), got {q.shape}")
    if not torques:
        raise ValueError("torques must hold at least one labelled torque series")
    for label, tau in torques.items():
        if np.shape(tau) != q.shape:
            raise ValueError(f"torques[{label!r}] must have shape {q.shape}, got {np.shape(tau)}")
    path = Path(path)
    _check_size(path, len(t), max_bytes, transforms=robot.n, scalars=robot.n * len(torques))
    blueprint = rrb.Blueprint(rrb.Horizontal(
        rrb.Spatial3DView(origin="/", name=f"{robot.name}: a held-out trajectory", overrides=_trail("tool_path")),
        rrb.Vertical(*(rrb.TimeSeriesView(origin=f"/tau/{joint}", name=f"{joint} torque [N·m]")
                       for joint in robot.joint_names)),
        column_shares=[3, 2]), collapse_panels=True)
    with _recording(path, name, seed, blueprint, t) as (rec, times, tmp):
        _log_arm(rec, robot, q, times, tmp)
        for label, tau in torques.items():
            tau = np.asarray(tau, dtype=float)
            for j, joint in enumerate(robot.joint_names):
                rec.send_columns(f"tau/{joint}/{label}", indexes=times,
                                 columns=rr.Scalars.columns(scalars=tau[:, j]))
        _log_growing_path(rec, "tool_path", t, fk(robot, q)[:, :3, 3], (230, 120, 30))
    return path
