"""Paths and trajectories.

Cartesian paths (for inverse kinematics along a line) are built here; joint-space polynomial
trajectories join them in chapter 3.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

__all__ = ["line_path"]


def line_path(T_start, T_end, steps: int) -> np.ndarray:
    """Poses ``(steps, 4, 4)`` along the straight line from ``T_start`` to ``T_end``.

    Positions are interpolated linearly, orientations by spherical linear interpolation
    (SciPy's :class:`~scipy.spatial.transform.Slerp`, constant angular speed), both at
    ``s = 0, 1/(steps − 1), …, 1``.
    """
    T_start, T_end = np.asarray(T_start, dtype=float), np.asarray(T_end, dtype=float)
    if T_start.shape != (4, 4) or T_end.shape != (4, 4):
        raise ValueError(f"T_start and T_end must be 4x4 poses, got {T_start.shape}, {T_end.shape}")
    if not isinstance(steps, (int, np.integer)) or steps < 2:
        raise ValueError(f"steps must be an integer >= 2, got {steps!r}")
    s = np.linspace(0.0, 1.0, steps)
    slerp = Slerp([0.0, 1.0], Rotation.from_matrix(np.stack([T_start[:3, :3], T_end[:3, :3]])))
    T = np.tile(np.eye(4), (steps, 1, 1))
    T[:, :3, :3] = slerp(s).as_matrix()
    T[:, :3, 3] = (1 - s)[:, None] * T_start[:3, 3] + s[:, None] * T_end[:3, 3]
    return T
