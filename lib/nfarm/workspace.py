"""Workspace and singularity analysis: where the tool can go and how well it can move there."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import binned_statistic_2d

from .kinematics import fk, manipulability
from .robot import Robot, sample_configurations

__all__ = ["Map2D", "workspace_points", "reach", "plane_map", "joint_map"]


@dataclass(frozen=True)
class Map2D:
    """Values on a rectangular grid: ``values[i, j]`` belongs to the cell
    ``[x_edges[i], x_edges[i+1]) × [y_edges[j], y_edges[j+1])``; NaN where there is no data."""

    x_edges: np.ndarray
    y_edges: np.ndarray
    values: np.ndarray


def workspace_points(robot: Robot, n_samples: int, seed: int) -> np.ndarray:
    """Tool positions ``(n_samples, 3)`` [m] of configurations drawn uniformly within the limits."""
    return fk(robot, sample_configurations(robot, n_samples, seed))[:, :3, 3]


def reach(points: np.ndarray, robot: Robot) -> float:
    """Largest distance [m] of tool positions ``points (N, 3)`` from the first joint's origin
    (the base transform's position)."""
    return float(np.linalg.norm(points - robot.base[:3, 3], axis=1).max())


def plane_map(robot: Robot, n_samples: int, bins: int, seed: int, *,
              part: str = "position") -> Map2D:
    """The best manipulability reachable in each cell of the vertical plane ``y = 0``.

    Configurations are drawn within the limits with ``q_1 = 0`` (for an arm whose first joint
    turns about the base z axis, any other ``q_1`` turns the same picture about that axis), the
    tool positions ``(x, z)`` binned, and each cell keeps the largest ``w`` among its samples:
    a cell with a small value can only be reached close to a singularity.
    """
    q = sample_configurations(robot, n_samples, seed)
    q[:, 0] = 0.0
    p = fk(robot, q)[:, :3, 3]
    w = manipulability(robot, q, part=part)
    values, x_edges, z_edges, _ = binned_statistic_2d(p[:, 0], p[:, 2], w, "max", bins=bins)
    return Map2D(x_edges, z_edges, values)


def joint_map(robot: Robot, i: int, j: int, points: int, *, part: str = "position",
              q_rest: np.ndarray | None = None) -> Map2D:
    """Manipulability over joints ``i`` and ``j`` (0-based) across their limits, the other
    joints held at ``q_rest`` (zero by default); ``points`` samples per joint."""
    q_rest = np.zeros(robot.n) if q_rest is None else np.asarray(q_rest, dtype=float)
    edges_i = np.linspace(*robot.qlim[i], points + 1)
    edges_j = np.linspace(*robot.qlim[j], points + 1)
    qi, qj = np.meshgrid((edges_i[:-1] + edges_i[1:]) / 2, (edges_j[:-1] + edges_j[1:]) / 2,
                         indexing="ij")
    q = np.broadcast_to(q_rest, (*qi.shape, robot.n)).copy()
    q[..., i], q[..., j] = qi, qj
    return Map2D(edges_i, edges_j, manipulability(robot, q, part=part))
