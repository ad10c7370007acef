"""DH parameters extracted from a serial chain's joint axes: standard-DH frames placed on the
axes, each at the foot of the common normal from the axis before (:func:`dh_frames`), the DH rows
read off consecutive frames (:func:`dh_rows`) and the transforms the rows leave between them
(:func:`fixed_transforms`: none for a pure DH chain; nearly parallel axes are written as
parallel ones, the tilt in a fixed transform). Geometry only: the axes are a URDF's at ``q = 0``
(:func:`~nfarm.model.urdf_import.from_urdf`, which builds the robot).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .kinematics import dh_transform
from .robot import MAX_PLAUSIBLE_LENGTH

__all__ = ["dh_frames", "NearParallel", "dh_rows", "fixed_transforms"]


#: Axes closer than this (the sine of their angle) are parallel; lines closer than
#: ``_NEAR`` metres intersect.
_PARALLEL = 1e-9
_NEAR = 1e-12


@dataclass(frozen=True)
class NearParallel:
    """Consecutive axes ``k`` and ``k + 1`` (0-based) nearly parallel: ``angle`` [deg] apart,
    their common normal ``distance`` [m] from the previous frame's origin (found by
    :func:`dh_frames`, which has an example)."""

    k: int
    angle: float
    distance: float


def dh_frames(axes: list[tuple[np.ndarray, np.ndarray]], p_tip: np.ndarray,
               near_parallel_deg: float = 5.0) -> tuple[list[np.ndarray], list[NearParallel]]:
    """The link frames ``F_0..F_n`` (each ``(4, 4)``, in the root's frame) from the ``n`` joint
    axes at ``q = 0`` (a point ``(3,)`` [m] and a unit direction ``(3,)`` each) and the tip's
    origin ``(3,)`` [m], by :func:`~nfarm.model.urdf_import.from_urdf`'s rule: ``z_i`` along axis i+1; frame i
    (0 < i < n) at the foot of the common normal from axis i (:func:`_common_normal`), ``x_i``
    along it, any perpendicular when axes 1 and 2 are one line; frame n at the tip with ``x_n``
    along the tip's offset from axis n (else ``x_{n−1}``); frame 0 on axis 1 nearest the root's
    origin with ``x_0`` the component of ``x_1`` across ``z_0``, made exactly orthonormal.

    Axes less than ``near_parallel_deg`` apart whose common normal lies beyond
    :data:`MAX_PLAUSIBLE_LENGTH` from the previous origin are placed as parallel ones are:
    frame i where the normal through the previous origin meets axis i+1 (:func:`_beside`);
    those pairs are returned too (their DH rows are parallel, the tilt in a fixed transform).

    Example:
        >>> z = np.array([0.0, 0.0, 1.0])
        >>> planar = [(np.zeros(3), z), (np.array([1.0, 0.0, 0.0]), z)]     # parallel axes 1 m apart
        >>> frames, near = dh_frames(planar, np.array([2.0, 0.0, 0.0]))     # the tip 1 m beyond axis 2
        >>> [F[:3, 3].tolist() for F in frames], near
        ([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], [])
        >>> tilted = np.array([np.sin(1e-3), 0.0, np.cos(1e-3)])             # 1 mrad off parallel
        >>> frames, near = dh_frames([(np.zeros(3), z), (np.array([1.0, 0.0, 0.5]), tilted)],
        ...                          np.array([1.0, 0.0, 0.8]))
        >>> near[0].k, round(near[0].angle, 4), round(near[0].distance)    # the normal 1 km away
        (0, 0.0573, 999)
    """
    n = len(axes)
    z_0 = axes[0][1]
    o_0 = axes[0][0] - np.dot(axes[0][0], z_0) * z_0          # on axis 1, nearest the origin
    frames = [None] * (n + 1)
    near = []
    o, x = o_0, np.zeros(3)
    limit = math.sin(math.radians(min(near_parallel_deg, 90.0)))
    for i in range(1, n):
        z0, (p1, z1) = axes[i - 1][1], axes[i]
        sine = float(np.linalg.norm(np.cross(z0, z1)))
        o_next, x_next = _common_normal(o, z0, p1, z1, x)
        far = float(np.linalg.norm(o_next - o))
        if _PARALLEL <= sine < limit and far > MAX_PLAUSIBLE_LENGTH:
            near.append(NearParallel(i - 1, math.degrees(math.atan2(sine, abs(float(z0 @ z1)))), far))
            o_next, x_next = _beside(o, p1, z1, x)
        o, x = o_next, x_next
        if not x.any():                                        # axes 1 and 2 the same line
            x = _perpendicular(axes[0][1])
        frames[i] = _frame(x, axes[i][1], o)
    # Frame n at the tip's origin, z along axis n; x along the tip's offset from the axis.
    z_n = axes[-1][1]
    gap = p_tip - o
    scale = max(1.0, float(np.linalg.norm(o)), float(np.linalg.norm(p_tip)))   # of the rounding
    gap -= np.dot(gap, z_n) * z_n
    if np.linalg.norm(gap) > _NEAR * scale:
        x = gap / np.linalg.norm(gap)
    elif not x.any():
        x = _perpendicular(z_n)
    frames[n] = _frame(x, z_n, p_tip)
    # Frame 0 on axis 1, x_0 = x_1 (offset_1 = 0).
    x_1 = frames[1][:3, 0]
    frames[0] = _frame(x_1 - np.dot(x_1, z_0) * z_0, z_0, o_0)
    frames[0][:3, :3] = _orthonormal(frames[0][:3, :3])
    return frames, near


def _beside(o0: np.ndarray, p1: np.ndarray, z1: np.ndarray, x_prev: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
    """The frame origin on the line ``(p1, z1)`` nearest ``o0`` and its x axis, along the
    normal from ``o0`` (``x_prev`` made across ``z1`` when ``o0`` is on the line): for parallel
    axes, and for nearly parallel ones placed as parallel ones are, so that the DH frames stay
    near the arm (the origin is on the line itself, the tilt left to a fixed transform)."""
    foot = p1 + np.dot(o0 - p1, z1) * z1
    gap = foot - o0
    gap -= np.dot(gap, z1) * z1
    distance = float(np.linalg.norm(gap))
    if distance < _NEAR * max(1.0, float(np.linalg.norm(o0)), float(np.linalg.norm(foot))):
        x = x_prev - np.dot(x_prev, z1) * z1
        return foot, x / np.linalg.norm(x) if x.any() else x
    return foot, gap / distance


def _common_normal(o0: np.ndarray, z0: np.ndarray, p1: np.ndarray, z1: np.ndarray,
                   x_prev: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """DH frame origin on the line ``(p1, z1)`` and its x axis, from the line ``(o0, z0)``:
    the foot of their common normal and its direction ``±n``, ``n = z0 × z1 / |z0 × z1|``
    (skew lines); the intersection and ``n`` (intersecting); the foot of the normal through
    ``o0`` (parallel, so that ``d = 0``; :func:`_beside`); ``o0`` and ``x_prev`` (the same line).

    The normal's signed length is ``δ = (p1 − o0)·n`` and its foot on the second line
    ``p1 + t1 z1`` with ``t1 = ((p1 − o0) × z0)·n / |z0 × z1|``: no ``1 − (z0·z1)²``, whose
    cancellation for nearly parallel axes would put the foot metres off and tilt ``x`` off
    the axes."""
    cross = np.cross(z0, z1)
    sine = float(np.linalg.norm(cross))
    if sine < _PARALLEL:                                         # parallel or the same line
        return _beside(o0, p1, z1, x_prev)
    n = cross / sine
    w = p1 - o0
    delta = float(np.dot(w, n))
    foot = p1 + (float(np.dot(np.cross(w, z0), n)) / sine) * z1
    # Rounding grows with the points' distance from the origin: below it, the lines meet.
    if abs(delta) < _NEAR * max(1.0, float(np.linalg.norm(o0)), float(np.linalg.norm(foot))):
        return foot, n
    return foot, n if delta > 0 else -n


def _frame(x: np.ndarray, z: np.ndarray, o: np.ndarray) -> np.ndarray:
    """The pose ``(4, 4)`` with origin ``o`` [m] and axes ``x``, ``z × x``, ``z`` (unit,
    orthogonal, each ``(3,)``)."""
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    T[:3, 3] = o
    return T


def _perpendicular(z: np.ndarray) -> np.ndarray:
    """A unit vector ``(3,)`` across the unit ``z``: the world x axis (y when ``z`` is within
    about 26° of x) less its component along ``z``, normalised."""
    helper = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = helper - np.dot(helper, z) * z
    return x / np.linalg.norm(x)


def _orthonormal(R: np.ndarray) -> np.ndarray:
    """The orthogonal matrix nearest ``R`` ``(3, 3)`` (Frobenius norm): ``U Vᵀ`` from the SVD
    ``R = U Σ Vᵀ``, which removes rounding from a nearly orthonormal ``R``."""
    U, _, Vt = np.linalg.svd(R)
    return U @ Vt


def dh_rows(frames: list[np.ndarray], near: Sequence[int] = ()) -> list[dict[str, float]]:
    """Standard DH rows read off consecutive frames ``F_{i−1}, F_i`` (``n + 1`` frames):
    ``a = (o_i − o_{i−1})·x_i``, ``d = (o_i − o_{i−1})·z_{i−1}``, ``offset`` the angle from
    ``x_{i−1}`` to ``x_i`` about ``z_{i−1}``, ``alpha`` from ``z_{i−1}`` to ``z_i`` about ``x_i``;
    values within 1e-12 of a round number snapped to it. The rows ``near`` (0-based: nearly
    parallel axes, :func:`dh_frames`) get ``alpha`` 0 or π, the parallel axes nearest them
    (:func:`fixed_transforms` keeps the rest).

    Example:
        >>> z = np.array([0.0, 0.0, 1.0])
        >>> frames, _ = dh_frames([(np.zeros(3), z), (np.array([1.0, 0.0, 0.0]), z)],
        ...                       np.array([2.0, 0.0, 0.0]))                 # a planar arm, 1 m links
        >>> dh_rows(frames)
        [{'a': 1.0, 'd': 0.0, 'offset': 0.0, 'alpha': 0.0}, {'a': 1.0, 'd': 0.0, 'offset': 0.0, 'alpha': 0.0}]
    """
    rows = []
    for i in range(1, len(frames)):
        F0, F1 = frames[i - 1], frames[i]
        z0, x0, x1, z1 = F0[:3, 2], F0[:3, 0], F1[:3, 0], F1[:3, 2]
        step = F1[:3, 3] - F0[:3, 3]
        alpha = (0.0 if np.dot(z0, z1) > 0 else math.pi) if i - 1 in near else \
            _snap(np.arctan2(np.dot(np.cross(z0, z1), x1), np.dot(z0, z1)))
        rows.append({"a": _snap(np.dot(step, x1)), "d": _snap(np.dot(step, z0)),
                     "offset": _snap(np.arctan2(np.dot(np.cross(x0, x1), z0), np.dot(x0, x1))),
                     "alpha": alpha})
    return rows


def fixed_transforms(frames: list[np.ndarray], rows: list[dict[str, float]],
                      tol: float = 1e-12) -> list[np.ndarray] | None:
    """The transform ``E_i = (F_{i−1} · A_i(0))⁻¹ · F_i`` ``(4, 4)`` each joint's DH row
    leaves between its frame and the next (:class:`~nfarm.model.robot.Robot`'s ``fixed``):
    a small rotation for nearly parallel axes written as parallel, rounding elsewhere. ``None``
    when every one is the identity within ``tol`` (rotation) and ``tol`` times the arm's size
    (translation [m]): a pure DH chain.

    Example:
        >>> z = np.array([0.0, 0.0, 1.0])
        >>> frames, _ = dh_frames([(np.zeros(3), z), (np.array([1.0, 0.0, 0.0]), z)],
        ...                       np.array([2.0, 0.0, 0.0]))
        >>> fixed_transforms(frames, dh_rows(frames)) is None                # a pure DH chain
        True
        >>> tilted = np.array([np.sin(1e-3), 0.0, np.cos(1e-3)])
        >>> frames, near = dh_frames([(np.zeros(3), z), (np.array([1.0, 0.0, 0.5]), tilted)],
        ...                          np.array([1.0, 0.0, 0.8]))
        >>> E = fixed_transforms(frames, dh_rows(frames, [pair.k for pair in near]))
        >>> round(float(np.degrees(np.arccos(E[0][2, 2]))), 4)              # the tilt, after row 1 [deg]
        0.0573
    """
    scale = max([1.0] + [float(np.linalg.norm(F[:3, 3])) for F in frames])
    out, exact = [], True
    for i, row in enumerate(rows):
        A = dh_transform(row["a"], row["alpha"], row["d"], row["offset"])
        E = np.linalg.solve(frames[i] @ A, frames[i + 1])
        if (np.abs(E[:3, :3] - np.eye(3)).max() <= tol and np.abs(E[:3, 3]).max() <= tol * scale):
            E = np.eye(4)
        else:
            E[:3, :3] = _orthonormal(E[:3, :3])
            E[3] = [0.0, 0.0, 0.0, 1.0]
            exact = False
        out.append(E)
    return None if exact else out


def _snap(x: float, tol: float = 1e-12) -> float:
    """A DH parameter, 0 when it is rounding (below 1e-12 m or rad): the frames are built
    from products of rounded numbers, and a table of 1e-20 values reads as data."""
    return 0.0 if abs(x) < tol else float(x)
