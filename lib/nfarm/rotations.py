"""Rotation representations and the pose error, batched over leading axes.

Conversions delegate to :class:`scipy.spatial.transform.Rotation` (Shepperd-style quaternion
extraction, log map robust near π) and only fix the conventions used throughout nfarm:

* quaternions are ``[w, x, y, z]`` with the canonical sign ``w >= 0`` (and, when ``w == 0``,
  the first non-zero of ``x, y, z`` positive);
* roll-pitch-yaw is ZYX: ``R = Rz(yaw) · Ry(pitch) · Rx(roll)``, returned as
  ``[roll, pitch, yaw]`` [rad];
* rotation vectors are ``θ·u`` with ``θ ∈ [0, π]``.
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = [
    "matrix_to_quat", "quat_to_matrix", "matrix_to_rpy", "rpy_to_matrix", "quat_to_rpy",
    "rpy_to_quat", "log_so3", "exp_so3", "pose_error",
]


def _rotation(R: np.ndarray) -> Rotation:
    R = np.asarray(R, dtype=float)
    if R.shape[-2:] != (3, 3):
        raise ValueError(f"expected rotation matrices of shape (..., 3, 3), got {R.shape}")
    return Rotation.from_matrix(R)


def matrix_to_quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(..., 4)`` ``[w, x, y, z]``, ``w >= 0``, of rotation matrices ``(..., 3, 3)``."""
    return _rotation(R).as_quat(canonical=True, scalar_first=True)


def quat_to_matrix(quat: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` of quaternions ``(..., 4)`` ``[w, x, y, z]`` (normalised first)."""
    quat = np.asarray(quat, dtype=float)
    if quat.shape[-1:] != (4,):
        raise ValueError(f"expected quaternions of shape (..., 4), got {quat.shape}")
    return Rotation.from_quat(quat, scalar_first=True).as_matrix()


def matrix_to_rpy(R: np.ndarray) -> np.ndarray:
    """ZYX roll-pitch-yaw ``(..., 3)`` ``[roll, pitch, yaw]`` of ``R = Rz(yaw) Ry(pitch) Rx(roll)``.

    At gimbal lock (pitch = ±π/2) only ``yaw ∓ roll`` is defined; roll is then set to 0.
    """
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Gimbal lock detected")
        yaw_pitch_roll = _rotation(R).as_euler("ZYX")
    return yaw_pitch_roll[..., ::-1]


def rpy_to_matrix(rpy: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` ``Rz(yaw) Ry(pitch) Rx(roll)`` from ``(..., 3)`` ``[roll, pitch, yaw]``."""
    rpy = np.asarray(rpy, dtype=float)
    if rpy.shape[-1:] != (3,):
        raise ValueError(f"expected roll-pitch-yaw of shape (..., 3), got {rpy.shape}")
    return Rotation.from_euler("ZYX", rpy[..., ::-1]).as_matrix()


def quat_to_rpy(quat: np.ndarray) -> np.ndarray:
    """ZYX ``[roll, pitch, yaw]`` ``(..., 3)`` of quaternions ``(..., 4)`` ``[w, x, y, z]``."""
    return matrix_to_rpy(quat_to_matrix(quat))


def rpy_to_quat(rpy: np.ndarray) -> np.ndarray:
    """Canonical quaternions ``(..., 4)`` ``[w, x, y, z]`` of ZYX ``[roll, pitch, yaw]`` ``(..., 3)``."""
    return matrix_to_quat(rpy_to_matrix(rpy))


def log_so3(R: np.ndarray) -> np.ndarray:
    """Rotation vectors ``(..., 3)`` ``θ u`` (θ ∈ [0, π]) with ``exp([θu]×) = R``."""
    return _rotation(R).as_rotvec()


def exp_so3(rotvec: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` ``exp([ω]×)`` of rotation vectors ``ω (..., 3)``."""
    rotvec = np.asarray(rotvec, dtype=float)
    if rotvec.shape[-1:] != (3,):
        raise ValueError(f"expected rotation vectors of shape (..., 3), got {rotvec.shape}")
    return Rotation.from_rotvec(rotvec).as_matrix()


def pose_error(T_a: np.ndarray, T_b: np.ndarray) -> np.ndarray:
    """The twist ``(..., 6)`` from pose ``T_b`` to pose ``T_a``, in base coordinates.

    ``e = [p_a − p_b,  log(R_a R_bᵀ)]`` (position difference [m], then the rotation vector of
    the relative rotation [rad]). With ``T_a`` a target and ``T_b = fk(q)``, ``J(q) Δq ≈ e``
    for the geometric Jacobian of :func:`nfarm.kinematics.jacobian`; ``‖e[..., 3:]‖`` is the
    angle between the two orientations. Shapes broadcast.
    """
    T_a = np.asarray(T_a, dtype=float)
    T_b = np.asarray(T_b, dtype=float)
    for name, T in (("T_a", T_a), ("T_b", T_b)):
        if T.shape[-2:] != (4, 4):
            raise ValueError(f"{name}: expected poses of shape (..., 4, 4), got {T.shape}")
    dp = T_a[..., :3, 3] - T_b[..., :3, 3]
    R_rel = T_a[..., :3, :3] @ np.swapaxes(T_b[..., :3, :3], -1, -2)
    return np.concatenate([dp, log_so3(R_rel)], axis=-1)
