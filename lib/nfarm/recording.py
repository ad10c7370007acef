"""Rerun recordings (``.rrd``) of joint trajectories, replayable in the rerun viewer.

A recording holds the robot (its URDF from :func:`nfarm.urdf.to_urdf`, loaded by rerun's own
URDF loader), the joint transforms over time (so the robot moves), the tool path as a growing
line strip, and joint positions [deg], velocities [deg/s] and (optionally) torques [N·m] as
scalar time series, in degrees like every figure of the report. It carries its viewer layout
(a blueprint): the moving arm on the left, one plot each for positions, velocities and
torques on the right.
Nothing is displayed: open the file with the pinned viewer, ``.venv/bin/rerun FILE.rrd``.
The recording id comes from the name and the seed, so the same inputs give the same recording
(the file itself also stores when it was written).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
import rerun.urdf as rru

from .kinematics import fk
from .paths import atomic_path
from .robot import Robot
from .trajectory import Trajectory
from .urdf import to_urdf

__all__ = ["record_trajectory", "TIMELINE"]

#: The timeline every recording uses (seconds of trajectory time).
TIMELINE = "time"


def record_trajectory(robot: Robot, trajectory: Trajectory, path: str | os.PathLike, *,
                      tau: np.ndarray | None = None, name: str = "trajectory",
                      seed: int = 0) -> Path:
    """Write ``trajectory`` of ``robot`` to the rerun file ``path`` (atomically); return it.

    Entities: ``/{robot.name}`` (the URDF), ``/transforms/{joint}`` (joint motion),
    ``/tool_path`` (line strip of the tool origin so far), ``/q_deg/{joint}``,
    ``/qd_deg_s/{joint}`` and, with ``tau (K, n)`` [N·m], ``/tau/{joint}``. The growing line strip stores K(K + 1)/2 points: a few
    thousand samples are fine, resample longer trajectories first.
    """
    t, q = trajectory.t, trajectory.q
    if tau is not None and np.shape(tau) != q.shape:
        raise ValueError(f"tau must have the shape of q {q.shape}, got {np.shape(tau)}")
    path = Path(path)
    series = {"q_deg": np.degrees(q), "qd_deg_s": np.degrees(trajectory.qd)} | \
        ({} if tau is None else {"tau": np.asarray(tau)})
    titles = {"q_deg": "joint angle [deg]", "qd_deg_s": "joint velocity [deg/s]",
              "tau": "joint torque [N·m]"}
    blueprint = rrb.Blueprint(rrb.Horizontal(
        rrb.Spatial3DView(origin="/", name=f"{robot.name}: arm and tool path"),
        rrb.Vertical(*(rrb.TimeSeriesView(origin=f"/{key}", name=titles[key]) for key in series)),
        column_shares=[3, 2]), collapse_panels=True)
    rec = rr.RecordingStream(f"nfarm_{name}", recording_id=f"nfarm-{name}-{seed}")
    with tempfile.TemporaryDirectory() as tmp, atomic_path(path) as out:
        urdf = Path(tmp) / f"{robot.name}.urdf"
        urdf.write_text(to_urdf(robot), encoding="utf-8")
        rec.save(out, default_blueprint=blueprint)
        rec.log_file_from_path(urdf, static=True)
        rec.flush()
        times = [rr.TimeColumn(TIMELINE, duration=t)]
        tree = rru.UrdfTree.from_file_path(urdf)
        for j, joint_name in enumerate(robot.joint_names):
            joint = tree.get_joint_by_name(joint_name)
            rec.send_columns(f"transforms/{joint_name}", indexes=times,
                             columns=joint.compute_transform_columns(q[:, j], clamp=False))
        for key, values in series.items():
            for j, joint_name in enumerate(robot.joint_names):
                rec.send_columns(f"{key}/{joint_name}", indexes=times,
                                 columns=rr.Scalars.columns(scalars=values[:, j]))
        tip = fk(robot, q)[:, :3, 3]
        for k in range(len(t)):
            rec.set_time(TIMELINE, duration=float(t[k]))
            rec.log("tool_path", rr.LineStrips3D([tip[: k + 1]], colors=[[230, 120, 30]], radii=0.002))
        rec.flush()
        rec.disconnect()
    return path
