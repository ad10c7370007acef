"""Joint trajectories and Cartesian paths.

* :func:`cubic` — the dissertation's point-to-point polynomial (its MATLAB ``trq``): position
  and velocity given at both ends, ``q(τ) = a₀ + a₁τ + a₂τ² + a₃τ³``;
* :func:`quintic` — accelerations given at both ends too (smooth start and stop);
* :func:`via_points` — through several positions, C² (SciPy's clamped cubic spline: position,
  velocity and acceleration continuous at the via points);
* :func:`line_path` — a straight line in Cartesian space (for inverse kinematics).

Times follow the dissertation's GUI: start ``t0``, step ``dt``, final ``tf`` (MATLAB's
``t0:dt:tf``, with ``tf`` appended when ``dt`` does not divide the span). A trajectory that
leaves the joint limits given as ``qlim`` is reported — in ``Trajectory.violations`` and as a
:class:`TrajectoryLimitWarning` naming the joint and the times — never clipped.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation, Slerp

__all__ = ["Trajectory", "LimitViolation", "TrajectoryLimitWarning", "cubic", "quintic",
           "via_points", "time_grid", "line_path", "quintic_segments"]


class TrajectoryLimitWarning(UserWarning):
    """A trajectory leaves the joint limits.

    Example:
        >>> import warnings
        >>> with warnings.catch_warnings(record=True) as caught:
        ...     warnings.simplefilter("always")
        ...     trajectory = cubic(0.0, 2.0, 0.0, 0.0, 0.0, 1.0, 0.25, qlim=[[-1.5, 1.5]])
        >>> caught[0].category.__name__, len(trajectory.violations)
        ('TrajectoryLimitWarning', 1)
        >>> print(caught[0].message)
        joint 1 leaves its limits [-1.5, 1.5] rad from t = 0.75 s to 1 s (reaching 2 rad, 0.5 beyond)
    """


@dataclass(frozen=True)
class LimitViolation:
    """Joint ``joint`` (0-based) is outside ``[lo, hi]`` from ``t_start`` to ``t_end`` [s],
    reaching ``worst`` [rad].

    Example:
        >>> violation = LimitViolation(joint=0, t_start=0.5, t_end=1.0, worst=1.7, lo=-1.5, hi=1.5)
        >>> print(violation)
        joint 1 leaves its limits [-1.5, 1.5] rad from t = 0.5 s to 1 s (reaching 1.7 rad, 0.2 beyond)
    """

    joint: int
    t_start: float
    t_end: float
    worst: float
    lo: float
    hi: float

    def __str__(self) -> str:
        bound = self.lo if self.worst < self.lo else self.hi
        return (f"joint {self.joint + 1} leaves its limits [{self.lo:.4g}, {self.hi:.4g}] rad "
                f"from t = {self.t_start:.4g} s to {self.t_end:.4g} s (reaching {self.worst:.4g} "
                f"rad, {abs(self.worst - bound):.3g} beyond)")


@dataclass(frozen=True)
class Trajectory:
    """Samples of a joint trajectory: ``t (K,)`` [s]; ``q, qd, qdd, qddd (K, n)`` position
    [rad], velocity [rad/s], acceleration [rad/s²] and jerk [rad/s³].

    Example:
        >>> trajectory = cubic(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.25)     # one joint, 0 → 1 rad in 1 s
        >>> trajectory.t.tolist(), trajectory.q.shape, trajectory.qddd.shape     # [s], (K, n)
        ([0.0, 0.25, 0.5, 0.75, 1.0], (5, 1), (5, 1))
        >>> trajectory.violations     # no qlim given: nothing checked
        ()
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    qddd: np.ndarray
    violations: tuple[LimitViolation, ...] = ()


def time_grid(t0: float, tf: float, dt: float) -> np.ndarray:
    """``t0, t0 + dt, …`` up to ``tf`` (``tf`` included; appended if ``dt`` does not divide).

    Example:
        >>> time_grid(0.0, 1.0, 0.25).tolist()               # [s]
        [0.0, 0.25, 0.5, 0.75, 1.0]
        >>> time_grid(0.0, 1.0, 0.4).round(6).tolist()       # 0.4 does not divide 1: tf appended
        [0.0, 0.4, 0.8, 1.0]
    """
    for name, value in (("t0", t0), ("tf", tf), ("dt", dt)):
        if not np.isscalar(value) or not np.isfinite(value):
            raise ValueError(f"{name} must be a finite number, got {value!r}")
    if not tf > t0:
        raise ValueError(f"tf must be > t0, got t0 = {t0!r}, tf = {tf!r}")
    if not 0 < dt <= tf - t0:
        raise ValueError(f"dt must be > 0 and <= tf − t0 = {tf - t0:g}, got {dt!r}")
    steps = int(np.floor((tf - t0) / dt + 1e-9))
    t = t0 + dt * np.arange(steps + 1)
    if tf - t[-1] > 1e-9 * dt:
        t = np.append(t, tf)
    t[-1] = tf
    return t


def _boundary(names: tuple[str, ...], values: tuple) -> list[np.ndarray]:
    arrays = [np.atleast_1d(np.asarray(v, dtype=float)) for v in values]
    for name, a in zip(names, arrays):
        if a.ndim != 1:
            raise ValueError(f"{name} must be a number or a vector of joint values, got shape {a.shape}")
        if not np.isfinite(a).all():
            raise ValueError(f"{name} must be finite, got {a.tolist()}")
    try:
        n = np.broadcast_shapes(*(a.shape for a in arrays))
    except ValueError:
        shapes = ", ".join(f"{k} {a.shape}" for k, a in zip(names, arrays))
        raise ValueError(f"boundary values have mismatched shapes: {shapes}") from None
    return [np.broadcast_to(a, n) for a in arrays]


def _polynomial(coefficients: np.ndarray, t: np.ndarray, t0: float, qlim) -> Trajectory:
    """Evaluate ``Σ_k a_k τ^k`` (``coefficients (deg + 1, n)``, τ = t − t0) and derivatives."""
    tau = (t - t0)[:, None]
    derivatives = []
    c = coefficients
    for _ in range(4):
        derivatives.append(sum(c[k] * tau ** k for k in range(len(c))) if len(c) else 0 * tau)
        c = np.array([k * c[k] for k in range(1, len(c))])
    q, qd, qdd, qddd = (np.broadcast_to(d, (len(t), coefficients.shape[1])).copy() for d in derivatives)
    return _with_limits(Trajectory(t, q, qd, qdd, qddd), qlim)


def cubic(q0, qf, v0, vf, t0: float, tf: float, dt: float, *, qlim=None) -> Trajectory:
    """The dissertation's cubic: ``q(t0) = q0, q(tf) = qf, q̇(t0) = v0, q̇(tf) = vf``.

    With ``T = tf − t0``::

        a₀ = q0,  a₁ = v0,  a₂ = (3(qf − q0) − (2v0 + vf)T) / T²,  a₃ = (−2(qf − q0) + (v0 + vf)T) / T³

    Args: per joint (numbers or ``(n,)``, broadcast) [rad, rad/s]; times [s]; ``qlim (n, 2)``
    to check the joint limits.

    Example:
        >>> trajectory = cubic(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.25)     # 0 → 1 rad in 1 s, at rest at the ends
        >>> trajectory.q[:, 0].round(6).tolist()                        # [rad]
        [0.0, 0.15625, 0.5, 0.84375, 1.0]
        >>> (trajectory.qd[:, 0].round(6) + 0.0).tolist()               # [rad/s]
        [0.0, 1.125, 1.5, 1.125, 0.0]
        >>> cubic([0.0, 0.5], [1.0, -0.5], 0.0, 0.0, 0.0, 2.0, 0.5).q.shape     # two joints: (K, n)
        (5, 2)
    """
    t = time_grid(t0, tf, dt)
    q0, qf, v0, vf = _boundary(("q0", "qf", "v0", "vf"), (q0, qf, v0, vf))
    T = tf - t0
    a2 = (3 * (qf - q0) - (2 * v0 + vf) * T) / T**2
    a3 = (-2 * (qf - q0) + (v0 + vf) * T) / T**3
    return _polynomial(np.stack([q0, v0, a2, a3]), t, t0, qlim)


def quintic(q0, qf, v0, vf, t0: float, tf: float, dt: float, *, acc0=0.0, accf=0.0,
            qlim=None) -> Trajectory:
    """Quintic with positions, velocities and accelerations (default 0) given at both ends::

        a₀ = q0, a₁ = v0, a₂ = α0/2,
        a₃ = (20h − (8vf + 12v0)T − (3α0 − αf)T²) / 2T³
        a₄ = (−30h + (14vf + 16v0)T + (3α0 − 2αf)T²) / 2T⁴
        a₅ = (12h − 6(vf + v0)T − (α0 − αf)T²) / 2T⁵        (h = qf − q0, T = tf − t0)

    Example:
        >>> trajectory = quintic(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.25)     # 0 → 1 rad in 1 s
        >>> trajectory.q[:, 0].round(6).tolist()                          # [rad]
        [0.0, 0.103516, 0.5, 0.896484, 1.0]
        >>> (trajectory.qdd[[0, -1], 0].round(6) + 0.0).tolist()          # a smooth start and stop [rad/s²]
        [0.0, 0.0]
    """
    t = time_grid(t0, tf, dt)
    q0, qf, v0, vf, a0, af = _boundary(("q0", "qf", "v0", "vf", "acc0", "accf"),
                                       (q0, qf, v0, vf, acc0, accf))
    T, h = tf - t0, qf - q0
    a3 = (20 * h - (8 * vf + 12 * v0) * T - (3 * a0 - af) * T**2) / (2 * T**3)
    a4 = (-30 * h + (14 * vf + 16 * v0) * T + (3 * a0 - 2 * af) * T**2) / (2 * T**4)
    a5 = (12 * h - 6 * (vf + v0) * T - (a0 - af) * T**2) / (2 * T**5)
    return _polynomial(np.stack([q0, v0, a0 / 2, a3, a4, a5]), t, t0, qlim)


def quintic_segments(p0, v0, p1, v1, T, s) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Many quintic segments at once, each from ``p0`` at speed ``v0`` to ``p1`` at ``v1`` in ``T``
    [s] with zero end accelerations, at normalised times ``s ∈ [0, 1]`` (``t = s·T``): position,
    velocity and acceleration, arrays broadcast over leading axes.

    The polynomial of :func:`quintic` with ``acc0 = accf = 0``, written in ``s`` (``d = p1 − p0``)::

        q(s) = p0 + c₁ s + c₃ s³ + c₄ s⁴ + c₅ s⁵,   c₁ = v0 T,  c₃ = 10d − (6v0 + 4v1) T,
        c₄ = −15d + (8v0 + 7v1) T,                 c₅ = 6d − 3(v0 + v1) T

    (``q̇ = q'(s)/T``, ``q̈ = q''(s)/T²``). Where :func:`quintic` samples one segment on a time
    grid, this evaluates a whole batch of segments (every segment of every random trajectory,
    :func:`nfarm.study.id_trajectories.random_trajectories`) in one call.

    Example:
        >>> q, qd, qdd = quintic_segments(0.0, 0.0, 1.0, 0.0, 1.0, np.linspace(0.0, 1.0, 5))
        >>> q.round(6).tolist() == quintic(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.25).q[:, 0].round(6).tolist()
        True
        >>> (qdd[[0, -1]].round(9) + 0.0).tolist()     # rest to rest, smoothly [rad/s²]
        [0.0, 0.0]
    """
    d = p1 - p0
    c3 = 10 * d - (6 * v0 + 4 * v1) * T
    c4 = -15 * d + (8 * v0 + 7 * v1) * T
    c5 = 6 * d - 3 * (v0 + v1) * T
    c1 = v0 * T
    q = p0 + s * (c1 + s * s * (c3 + s * (c4 + s * c5)))
    qd = (c1 + s * s * (3 * c3 + s * (4 * c4 + s * 5 * c5))) / T
    qdd = s * (6 * c3 + s * (12 * c4 + s * 20 * c5)) / (T * T)
    return q, qd, qdd


def via_points(times, points, dt: float, *, v0=0.0, vf=0.0, qlim=None) -> Trajectory:
    """Through ``points (m, n)`` [rad] at ``times (m,)`` [s], with velocities ``v0``, ``vf`` at
    the ends: a clamped cubic spline (:class:`scipy.interpolate.CubicSpline`), so position,
    velocity and acceleration are continuous at every via point.

    Example:
        >>> trajectory = via_points([0.0, 1.0, 2.0], [[0.0, 0.0], [1.0, 0.5], [0.0, 1.0]], 0.5)
        >>> trajectory.t.tolist(), trajectory.q.shape     # [s], (K, n): 2 joints through 3 points
        ([0.0, 0.5, 1.0, 1.5, 2.0], (5, 2))
        >>> (trajectory.q[:, 0].round(6) + 0.0).tolist()                 # joint 1 through 0, 1, 0 rad
        [0.0, 0.5, 1.0, 0.5, 0.0]
    """
    times = np.asarray(times, dtype=float)
    points = np.asarray(points, dtype=float)
    if times.ndim != 1 or len(times) < 2 or points.ndim != 2 or points.shape[0] != len(times):
        raise ValueError(f"times must be (m,) with m >= 2 and points (m, n), got {times.shape}, "
                         f"{points.shape}")
    if not (np.isfinite(times).all() and np.isfinite(points).all()):
        raise ValueError("times and points must be finite")
    if not np.all(np.diff(times) > 0):
        raise ValueError(f"times must increase strictly, got {times.tolist()}")
    v0, vf = _boundary(("v0", "vf"), (v0, vf))
    n = points.shape[1]
    v0, vf = np.broadcast_to(v0, n), np.broadcast_to(vf, n)
    t = time_grid(times[0], times[-1], dt)
    spline = CubicSpline(times, points, bc_type=((1, v0), (1, vf)))
    trajectory = Trajectory(t, spline(t), spline(t, 1), spline(t, 2), spline(t, 3))
    return _with_limits(trajectory, qlim)


def _with_limits(trajectory: Trajectory, qlim) -> Trajectory:
    if qlim is None:
        return trajectory
    qlim = np.asarray(qlim, dtype=float)
    n = trajectory.q.shape[1]
    if qlim.shape != (n, 2):
        raise ValueError(f"qlim must have shape ({n}, 2), got {qlim.shape}")
    violations = []
    for j in range(n):
        outside = (trajectory.q[:, j] < qlim[j, 0]) | (trajectory.q[:, j] > qlim[j, 1])
        if outside.any():
            k = np.flatnonzero(outside)
            values = trajectory.q[k, j]
            worst = values[np.argmax(np.maximum(qlim[j, 0] - values, values - qlim[j, 1]))]
            violations.append(LimitViolation(j, float(trajectory.t[k[0]]), float(trajectory.t[k[-1]]),
                                             float(worst), float(qlim[j, 0]), float(qlim[j, 1])))
    if violations:
        warnings.warn(TrajectoryLimitWarning("; ".join(map(str, violations))), stacklevel=3)
    return Trajectory(trajectory.t, trajectory.q, trajectory.qd, trajectory.qdd, trajectory.qddd,
                      tuple(violations))


def line_path(T_start, T_end, steps: int) -> np.ndarray:
    """Poses ``(steps, 4, 4)`` along the straight line from ``T_start`` to ``T_end``.

    Positions are interpolated linearly, orientations by spherical linear interpolation
    (SciPy's :class:`~scipy.spatial.transform.Slerp`, constant angular speed), both at
    ``s = 0, 1/(steps − 1), …, 1``.

    Example:
        >>> T_end = np.eye(4)
        >>> T_end[:3, :3], T_end[:3, 3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]], [1, 0, 0]   # 90° about z, 1 m
        >>> path = line_path(np.eye(4), T_end, 3)
        >>> path.shape, (path[1, :3, 3].round(6) + 0.0).tolist()                        # halfway [m]
        ((3, 4, 4), [0.5, 0.0, 0.0])
        >>> from nfarm.model.rotations import log_so3
        >>> (log_so3(path[:, :3, :3])[:, 2].round(6) + 0.0).tolist()                   # angle about z [rad]
        [0.0, 0.785398, 1.570796]
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
