"""Rotation representations and the pose error, batched over leading axes.

Conversions delegate to :class:`scipy.spatial.transform.Rotation` (Shepperd-style quaternion
extraction) and only fix the conventions used throughout nfarm; the log map, which inverse
kinematics evaluates at every iteration, is hand-written and vectorised (and tested against
SciPy). Conventions:

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
    "rpy_to_quat", "log_so3", "log_so3_T", "relative_log_T", "exp_so3", "pose_error",
]


def _rotation(R: np.ndarray) -> Rotation:
    R = np.asarray(R, dtype=float)
    if R.shape[-2:] != (3, 3):
        raise ValueError(f"expected rotation matrices of shape (..., 3, 3), got {R.shape}")
    return Rotation.from_matrix(R)


def matrix_to_quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(..., 4)`` ``[w, x, y, z]``, ``w >= 0``, of rotation matrices ``(..., 3, 3)``.

    Example:
        >>> Rz = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])     # 90° about z
        >>> (matrix_to_quat(Rz).round(6) + 0.0).tolist()                              # [w, x, y, z]
        [0.707107, 0.0, 0.0, 0.707107]
        >>> matrix_to_quat(np.stack([np.eye(3), Rz])).shape                           # (2, 3, 3) → (2, 4)
        (2, 4)
    """
    return _rotation(R).as_quat(canonical=True, scalar_first=True)


def quat_to_matrix(quat: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` of quaternions ``(..., 4)`` ``[w, x, y, z]`` (normalised first).

    Example:
        >>> (quat_to_matrix([0.0, 0.0, 0.0, 1.0]).round(6) + 0.0).tolist()     # half a turn about z
        [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]
        >>> np.allclose(quat_to_matrix([2.0, 0.0, 0.0, 0.0]), np.eye(3))       # normalised first
        True
        >>> quat_to_matrix(np.tile([1.0, 0.0, 0.0, 0.0], (3, 1))).shape       # (3, 4) → (3, 3, 3)
        (3, 3, 3)
    """
    quat = np.asarray(quat, dtype=float)
    if quat.shape[-1:] != (4,):
        raise ValueError(f"expected quaternions of shape (..., 4), got {quat.shape}")
    return Rotation.from_quat(quat, scalar_first=True).as_matrix()


def matrix_to_rpy(R: np.ndarray) -> np.ndarray:
    """ZYX roll-pitch-yaw ``(..., 3)`` ``[roll, pitch, yaw]`` of ``R = Rz(yaw) Ry(pitch) Rx(roll)``.

    At gimbal lock (pitch = ±π/2) only ``yaw ∓ roll`` is defined; roll is then set to 0.

    Example:
        >>> (matrix_to_rpy(rpy_to_matrix([0.1, -0.2, 0.3])).round(6) + 0.0).tolist()     # [rad]
        [0.1, -0.2, 0.3]
        >>> (matrix_to_rpy(rpy_to_matrix([0.1, np.pi / 2, 0.3])).round(6) + 0.0).tolist()  # gimbal lock
        [0.0, 1.570796, 0.2]
    """
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Gimbal lock detected")
        yaw_pitch_roll = _rotation(R).as_euler("ZYX")
    return yaw_pitch_roll[..., ::-1]


def rpy_to_matrix(rpy: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` ``Rz(yaw) Ry(pitch) Rx(roll)`` from ``(..., 3)``
    ``[roll, pitch, yaw]``.

    Example:
        >>> (rpy_to_matrix([0.0, 0.0, np.pi / 2]).round(6) + 0.0).tolist()     # yaw 90° [rad]
        [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
        >>> rpy_to_matrix(np.zeros((4, 3))).shape                              # (4, 3) → (4, 3, 3)
        (4, 3, 3)
    """
    rpy = np.asarray(rpy, dtype=float)
    if rpy.shape[-1:] != (3,):
        raise ValueError(f"expected roll-pitch-yaw of shape (..., 3), got {rpy.shape}")
    return Rotation.from_euler("ZYX", rpy[..., ::-1]).as_matrix()


def quat_to_rpy(quat: np.ndarray) -> np.ndarray:
    """ZYX ``[roll, pitch, yaw]`` ``(..., 3)`` of quaternions ``(..., 4)`` ``[w, x, y, z]``.

    Example:
        >>> (quat_to_rpy([np.cos(0.25), 0.0, 0.0, np.sin(0.25)]).round(6) + 0.0).tolist()   # 0.5 rad about z
        [0.0, 0.0, 0.5]
        >>> quat_to_rpy(np.tile([1.0, 0.0, 0.0, 0.0], (2, 1))).shape                       # (2, 4) → (2, 3)
        (2, 3)
    """
    return matrix_to_rpy(quat_to_matrix(quat))


def rpy_to_quat(rpy: np.ndarray) -> np.ndarray:
    """Canonical quaternions ``(..., 4)`` ``[w, x, y, z]`` of ZYX ``[roll, pitch, yaw]`` ``(..., 3)``.

    Example:
        >>> (rpy_to_quat([0.0, 0.0, 0.5]).round(6) + 0.0).tolist()     # yaw 0.5 rad → [w, x, y, z]
        [0.968912, 0.0, 0.0, 0.247404]
        >>> rpy_to_quat(np.zeros((2, 3))).shape                        # (2, 3) → (2, 4)
        (2, 4)
    """
    return matrix_to_quat(rpy_to_matrix(rpy))


def log_so3(R: np.ndarray) -> np.ndarray:
    """Rotation vectors ``(..., 3)`` ``θ u`` (θ ∈ [0, π]) with ``exp([θu]×) = R``.

    Hand-written and vectorised (see :func:`log_so3_T`) because inverse kinematics evaluates it
    at every iteration; about 10× faster than SciPy's ``Rotation.as_rotvec``, against which it
    is tested, including next to θ = π.

    Example:
        >>> (log_so3(rpy_to_matrix([0.0, 0.0, np.pi / 2])).round(6) + 0.0).tolist()     # θu [rad]
        [0.0, 0.0, 1.570796]
        >>> (log_so3(exp_so3([0.0, 3.0, 0.0])).round(6) + 0.0).tolist()                 # next to θ = π
        [0.0, 3.0, 0.0]
        >>> log_so3(np.stack([np.eye(3)] * 4)).shape     # (4, 3, 3) → (4, 3)
        (4, 3)
    """
    R = np.asarray(R, dtype=float)
    if R.shape[-2:] != (3, 3):
        raise ValueError(f"expected rotation matrices of shape (..., 3, 3), got {R.shape}")
    batch = R.shape[:-2]
    components = np.moveaxis(R.reshape(-1, 3, 3), 0, -1)
    return np.moveaxis(log_so3_T(components), 0, -1).reshape(*batch, 3)


#: Below this cos θ (θ above about 154°) the axis comes from the symmetric part of R.
_NEAR_PI_COS = -0.9


def log_so3_T(R: np.ndarray) -> np.ndarray:
    """The log map in component layout: ``R (3, 3, M)`` (row, column, sample) → ``ω (3, M)``.

    With ``cos θ = (tr R − 1)/2`` and ``v = vee(R − Rᵀ)/2 = sin θ · u``::

        θ = atan2(‖v‖, cos θ),   ω = (θ / sin θ) · v               (θ / sin θ → 1 + θ²/6)

    Near θ = π, ``v`` carries no accurate direction; there the axis comes from
    ``(R + Rᵀ)/2 − cos θ · I = (1 − cos θ) u uᵀ`` (its largest column), signed to agree with v.

    Example:
        >>> R = np.stack([np.eye(3), rpy_to_matrix([0.0, 0.0, 0.5])], axis=-1)     # (3, 3, M = 2)
        >>> (log_so3_T(R).round(6) + 0.0).tolist()                                 # ω (3, M) [rad]
        [[0.0, 0.0], [0.0, 0.0], [0.0, 0.5]]
    """
    cos = (R[0, 0] + R[1, 1] + R[2, 2] - 1.0) * 0.5
    v = 0.5 * np.stack([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return _log(cos, v, lambda idx: R[:, :, idx])


def relative_log_T(R_a: np.ndarray, R_b: np.ndarray) -> np.ndarray:
    """``log(R_a R_bᵀ)`` in component layout (``(3, 3, M)`` each → ``(3, M)``), without forming
    the product: with columns ``a_k``, ``b_k``, ``tr(R_a R_bᵀ) = Σ_ij (R_a)_ij (R_b)_ij`` and
    ``vee(R_a R_bᵀ − R_b R_aᵀ) = Σ_k b_k × a_k``. Only targets near θ = π form the product.

    Example:
        >>> R_a = np.stack([rpy_to_matrix([0.0, 0.0, 0.5])] * 2, axis=-1)     # (3, 3, 2)
        >>> R_b = np.stack([np.eye(3), R_a[:, :, 0]], axis=-1)
        >>> (relative_log_T(R_a, R_b).round(6) + 0.0).tolist()               # (3, 2) [rad]
        [[0.0, 0.0], [0.0, 0.0], [0.5, 0.0]]
    """
    cos = ((R_a * R_b).sum(axis=(0, 1)) - 1.0) * 0.5
    a, b = R_a, R_b
    v = 0.5 * np.stack([
        (b[1] * a[2] - b[2] * a[1]).sum(0),
        (b[2] * a[0] - b[0] * a[2]).sum(0),
        (b[0] * a[1] - b[1] * a[0]).sum(0),
    ])
    return _log(cos, v, lambda idx: np.einsum("ikm,jkm->ijm", R_a[:, :, idx], R_b[:, :, idx]))


def _log(cos: np.ndarray, v: np.ndarray, rotation) -> np.ndarray:
    """ω from ``cos θ (M,)``, ``v = sin θ · u (3, M)``; ``rotation(idx)`` gives ``R (3, 3, len)``
    for the samples near π."""
    cos = np.clip(cos, -1.0, 1.0)
    sin = np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    theta = np.arctan2(sin, cos)
    small = sin < 1e-6
    scale = np.where(small, 1.0 + theta * theta / 6.0, theta / np.where(small, 1.0, sin))
    omega = scale * v
    near_pi = np.flatnonzero(cos < _NEAR_PI_COS)
    if near_pi.size:
        Rn, c = rotation(near_pi), cos[near_pi]
        B = 0.5 * (Rn + np.swapaxes(Rn, 0, 1)) - c * np.eye(3)[:, :, None]
        k = np.argmax(np.stack([B[0, 0], B[1, 1], B[2, 2]]), axis=0)
        cols = np.arange(near_pi.size)
        column = B[:, k, cols]                                  # (1 − cos) u u_k
        u = column / np.sqrt((1.0 - c) * B[k, k, cols])          # ±u
        sign = np.where(np.einsum("im,im->m", u, v[:, near_pi]) < 0, -1.0, 1.0)
        omega[:, near_pi] = theta[near_pi] * sign * u
    return omega


def exp_so3(rotvec: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` ``exp([ω]×)`` of rotation vectors ``ω (..., 3)``.

    Example:
        >>> (exp_so3([0.0, 0.0, np.pi / 2]).round(6) + 0.0).tolist()     # 90° about z
        [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
        >>> np.allclose(log_so3(exp_so3([0.1, -0.2, 0.3])), [0.1, -0.2, 0.3])
        True
        >>> exp_so3(np.zeros((4, 3))).shape                            # (4, 3) → (4, 3, 3)
        (4, 3, 3)
    """
    rotvec = np.asarray(rotvec, dtype=float)
    if rotvec.shape[-1:] != (3,):
        raise ValueError(f"expected rotation vectors of shape (..., 3), got {rotvec.shape}")
    return Rotation.from_rotvec(rotvec).as_matrix()


def pose_error(T_a: np.ndarray, T_b: np.ndarray) -> np.ndarray:
    """The twist ``(..., 6)`` from pose ``T_b`` to pose ``T_a``, in base coordinates.

    ``e = [p_a − p_b,  log(R_a R_bᵀ)]`` (position difference [m], then the rotation vector of
    the relative rotation [rad]). With ``T_a`` a target and ``T_b = fk(q)``, ``J(q) Δq ≈ e``
    for the geometric Jacobian of :func:`nfarm.model.kinematics.jacobian`; ``‖e[..., 3:]‖`` is the
    angle between the two orientations. Shapes broadcast.

    Example:
        >>> T_a = np.eye(4)
        >>> T_a[:3, :3], T_a[:3, 3] = rpy_to_matrix([0.0, 0.0, 0.1]), [0.01, 0.0, 0.0]
        >>> (pose_error(T_a, np.eye(4)).round(6) + 0.0).tolist()     # [m, m, m, rad, rad, rad]
        [0.01, 0.0, 0.0, 0.0, 0.0, 0.1]
        >>> pose_error(np.stack([T_a] * 3), np.eye(4)).shape         # (3, 4, 4) with (4, 4) → (3, 6)
        (3, 6)
    """
    T_a = np.asarray(T_a, dtype=float)
    T_b = np.asarray(T_b, dtype=float)
    for name, T in (("T_a", T_a), ("T_b", T_b)):
        if T.shape[-2:] != (4, 4):
            raise ValueError(f"{name}: expected poses of shape (..., 4, 4), got {T.shape}")
    dp = T_a[..., :3, 3] - T_b[..., :3, 3]
    R_rel = T_a[..., :3, :3] @ np.swapaxes(T_b[..., :3, :3], -1, -2)
    return np.concatenate([dp, log_so3(R_rel)], axis=-1)
