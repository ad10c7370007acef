"""Random smooth joint trajectories for the inverse-dynamics data (the dissertation's §3.2.3;
chapter 05), and what a real arm's sensors would record on them.

Random smooth joint trajectories (:func:`random_trajectories`): for each
trajectory, via points drawn within the joint limits (less a margin), joined by quintic
segments whose via velocities follow the neighbouring slopes (zero at a turning point, as
PCHIP does) and whose via accelerations are zero. Each segment gets a random duration, at least
the time its largest move needs from rest to rest within the bounds; the trajectory is then
slowed down uniformly until its velocities and accelerations are within the study's bounds
(time scaling by ``s`` divides velocities by ``s`` and accelerations by ``s²``). Torques are
``rnea(q, qd, qdd)`` of the rigid-body model. With a ``measured`` arm in the study, the files
also hold ``tau_measured``: what a real arm's joint sensors would record on the same
trajectories — the rigid-body torques plus the joint drives' armature and friction
(:func:`nfarm.model.dynamics.stribeck_drive_torques`: viscous, Coulomb, and where the study says so a
Stribeck breakaway and friction that grows with the load) plus Gaussian sensor noise. With an
``encoder_counts`` in the measured arm, the files also hold the states such an arm knows:
``q_measured`` (each angle quantised to the encoder's counts per turn), ``qd_measured`` and
``qdd_measured`` (its first and second derivatives by a Savitzky–Golay filter of
``filter_window`` samples along each trajectory, as a drive controller estimates them). Splits
are by whole trajectories.

**The measured arm is not the model.** With a ``true_arm`` in the measured arm, its links differ
from the nominal model as a built arm's do (:func:`true_arm`: each link's mass, centre of mass
and rotational inertia drawn from the study's seed, another arm for each draw of the data), and ``tau_measured`` is that arm's
torque; the test split also holds ``tau_payload``, the same trajectories with a payload at the
tool (:func:`with_payload`). With a ``sensor``, the torque is read as a servo reads it, from its
motor current (:func:`current_sensed`: a zero offset per joint, noise, and the current's counts).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from ..model.robot import Robot
from ..solvers.trajectory import cubic, quintic_segments

__all__ = ["IDSettings", "TrueArm", "current_sensed", "measured_states", "random_trajectories",
           "seed_like_trajectories", "true_arm", "with_payload"]


@dataclass(frozen=True)
class IDSettings:
    """The random trajectory generator (study file, section ``id``; SI units, radians).

    Attributes:
        trajectories: trajectories per split.
        measured: the "real" arm of ``tau_measured`` — the robot with the study's joint
            drives (viscous and Coulomb friction, armature) — or ``None``.
        noise: ``(n,)`` standard deviation of the torque sensors' noise [N·m].
        friction: the measured arm's Stribeck and load terms (keyword arguments of
            :func:`nfarm.model.dynamics.stribeck_drive_torques`; empty: its tanh Coulomb law only).
        encoder_counts: counts per turn of the measured arm's joint encoders, or ``None``
            (the learners see the exact states).
        filter_window: samples of the Savitzky–Golay filter that estimates ``q̇, q̈`` from the
            encoder angles.
        true_arm: how the measured arm's links differ from the model (:class:`TrueArm`), or
            ``None`` (they are the model's).
        torque_per_count: ``(n,)`` torque of one count of the joints' current reading [N·m], or
            ``None`` (a torque sensor, no quantisation).
        offset_sd: ``(n,)`` standard deviation of each joint's zero offset [N·m], drawn once.
        via_points: via points per trajectory (the first is the start).
        segment_time: ``(lo, hi)`` nominal duration of each segment [s], drawn uniformly.
        dt: sampling step [s].
        margin: via points stay this far inside the joint limits [rad].
        max_velocity, max_acceleration: ``(n,)`` bounds [rad/s, rad/s²].
    """

    trajectories: dict[str, int]
    via_points: int
    segment_time: tuple[float, float]
    dt: float
    margin: float
    max_velocity: np.ndarray
    max_acceleration: np.ndarray
    measured: Robot | None = None
    noise: np.ndarray | None = None
    friction: dict = field(default_factory=dict)
    encoder_counts: int | None = None
    filter_window: int = 7
    true_arm: "TrueArm | None" = None
    torque_per_count: np.ndarray | None = None
    offset_sd: np.ndarray | None = None


@dataclass(frozen=True)
class TrueArm:
    """How a built arm's links differ from its model: relative standard deviations of each
    link's mass (``mass_sd``) and of its rotational inertia about its centre of mass
    (``inertia_sd``), the standard deviation of each coordinate of its centre of mass
    (``com_sd`` [m]), and the payload of the payload case (``payload`` [kg], a point mass at the
    tool point; 0: none). Every draw is clipped to ±3 standard deviations, so a factor
    ``1 + sd·z`` stays positive for ``sd < 1/3``."""

    mass_sd: float = 0.0
    com_sd: float = 0.0
    inertia_sd: float = 0.0
    payload: float = 0.0


def true_arm(robot: Robot, spec: TrueArm, rng: np.random.Generator) -> Robot:
    """The built arm: ``robot`` with each link's mass scaled by ``1 + mass_sd·z``, its centre of
    mass moved by ``com_sd·z`` along each link axis [m] and its inertia tensor about the centre
    of mass scaled by ``1 + inertia_sd·z`` (z standard normal, clipped to ±3; a positive scale
    keeps every tensor physically valid: positive definite, its triangle inequalities kept).
    Geometry and drives are the model's. Draws, in this order: ``n`` masses, ``(n, 3)``
    centres, ``n`` inertias.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> built = true_arm(robot, TrueArm(mass_sd=0.05, com_sd=0.002, inertia_sd=0.1),
        ...                  np.random.default_rng(0))
        >>> bool(np.all(np.abs(built.mass / robot.mass - 1) <= 0.15)), built.a.tolist() == robot.a.tolist()
        (True, True)
    """
    draw = lambda shape: np.clip(rng.standard_normal(shape), -3.0, 3.0)   # noqa: E731
    n = robot.n
    mass = robot.mass * (1 + spec.mass_sd * draw(n))
    com = robot.com + spec.com_sd * draw((n, 3))
    inertia = robot.inertia * (1 + spec.inertia_sd * draw(n))[:, None, None]
    return dataclasses.replace(robot, mass=mass, com=com, inertia=inertia)


def with_payload(robot: Robot, mass: float) -> Robot:
    """``robot`` carrying a point mass ``mass`` [kg] at its tool point: the last link's mass,
    centre of mass and inertia about it combined with the point's (parallel-axis theorem,
    ``I = I_c + m (|d|² 1 − d dᵀ)`` for each part's offset ``d`` from the joint centre).
    Statically it adds ``Jᵀ f`` with ``f = −mass·g`` at the tool point (``tests/test_measured_arm.py``).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> round(float(with_payload(robot, 0.1).mass[-1] - robot.mass[-1]), 12)
        0.1
    """
    if mass == 0:
        return robot
    m1, c1, p = robot.mass[-1], robot.com[-1], robot.tool[:3, 3]
    total = m1 + mass
    c = (m1 * c1 + mass * p) / total
    shift = lambda m, d: m * (d @ d * np.eye(3) - np.outer(d, d))   # noqa: E731
    inertia_n = robot.inertia[-1] + shift(m1, c1 - c) + shift(mass, p - c)
    return dataclasses.replace(robot, mass=np.append(robot.mass[:-1], total), com=np.vstack([robot.com[:-1], c]),
                               inertia=np.concatenate([robot.inertia[:-1], inertia_n[None]]))


def current_sensed(tau: np.ndarray, rng: np.random.Generator, *, noise: np.ndarray,
                   torque_per_count: np.ndarray | None = None, offset: np.ndarray | None = None) -> np.ndarray:
    """The torque ``tau (N, n)`` [N·m] a joint reports: plus its zero ``offset (n,)`` [N·m] and
    Gaussian noise of ``noise (n,)`` [N·m], then, for a servo that senses its motor current,
    rounded to the torque of one count of the current reading, ``torque_per_count (n,)``
    [N·m] (``None``: a torque sensor, not quantised). Draws ``(N, n)`` normals."""
    sensed = tau + (0.0 if offset is None else offset) + noise * rng.standard_normal(tau.shape)
    if torque_per_count is not None:
        sensed = np.round(sensed / torque_per_count) * torque_per_count
    return sensed


def measured_states(q: np.ndarray, trajectory: np.ndarray, dt: float, counts: int, window: int
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What a real arm knows of its motion: each joint angle read by an encoder of ``counts``
    per turn (rounded to its nearest count), and the velocity and acceleration a drive
    estimates from those readings — Savitzky–Golay derivatives (cubic fits over ``window``
    samples, scipy's ``savgol_filter``) along each trajectory. ``q (N, n)`` [rad], ``trajectory
    (N,)`` labels, ``dt`` [s]; returns ``q, q̇, q̈ (N, n)``."""
    from scipy.signal import savgol_filter

    step = 2 * math.pi / counts
    q_read = np.round(q / step) * step
    qd, qdd = np.empty_like(q), np.empty_like(q)
    order = min(3, window - 1)
    for label in np.unique(trajectory):
        rows = np.flatnonzero(trajectory == label)
        part = q_read[rows]
        w = min(window, len(rows) - (1 - len(rows) % 2))
        qd[rows] = savgol_filter(part, w, min(order, w - 1), deriv=1, delta=dt, axis=0, mode="interp")
        qdd[rows] = savgol_filter(part, w, min(order, w - 1), deriv=2, delta=dt, axis=0, mode="interp")
    return q_read, qd, qdd


def _via_velocities(points: np.ndarray, durations: np.ndarray) -> np.ndarray:
    """Velocities at via points ``(J, K, n)`` from the neighbouring slopes: the harmonic mean
    where both slopes have one sign, 0 at turning points and at both ends (as PCHIP)."""
    slopes = np.diff(points, axis=1) / durations[..., None]            # (J, K-1, n)
    a, b = slopes[:, :-1], slopes[:, 1:]
    with np.errstate(divide="ignore", invalid="ignore"):
        inner = np.where(a * b > 0, 2 * a * b / (a + b), 0.0)
    v = np.zeros_like(points)
    v[:, 1:-1] = inner
    return v


def seed_like_trajectories(robot: Robot, settings: IDSettings, count: int, seed, *, duration: float = 6.0,
                           dt: float = 0.2) -> dict[str, np.ndarray]:
    """``count`` trajectories made the way the dissertation's program makes them (its defaults,
    ``docs/STUDY.md``): one cubic per trajectory (:func:`nfarm.solvers.trajectory.cubic`) from rest at a
    random configuration to rest at another, drawn uniformly within the joint limits less the
    study's margin, over ``duration`` [s] sampled every ``dt`` [s] (31 states each by default).
    The arrays of :func:`random_trajectories` (``scale`` all ones); chapter 06's ablation trains
    on them and chapter 07 tests on the study's own held-out trajectories."""
    rng = np.random.default_rng(seed)
    lo, hi = robot.qlim[:, 0] + settings.margin, robot.qlim[:, 1] - settings.margin
    ends = lo + (hi - lo) * rng.random((count, 2, robot.n))
    parts = [cubic(start, end, 0.0, 0.0, 0.0, duration, dt) for start, end in ends]
    return {"t": np.concatenate([p.t for p in parts]), "q": np.concatenate([p.q for p in parts]),
            "qd": np.concatenate([p.qd for p in parts]), "qdd": np.concatenate([p.qdd for p in parts]),
            "trajectory": np.repeat(np.arange(count), [len(p.t) for p in parts]), "scale": np.ones(count)}


def random_trajectories(robot: Robot, settings: IDSettings, count: int, seed) -> dict[str, np.ndarray]:
    """``count`` random trajectories sampled at ``settings.dt`` (module docstring).

    Returns ``t (N,)`` [s] (from 0 in each trajectory), ``q, qd, qdd (N, n)``, ``trajectory
    (N,)`` (index of each sample's trajectory) and ``scale (count,)`` (the time scaling used).
    Every sample lies within the joint limits and the velocity and acceleration bounds.
    """
    rng = np.random.default_rng(seed)
    n, K = robot.n, settings.via_points
    lo = robot.qlim[:, 0] + settings.margin
    hi = robot.qlim[:, 1] - settings.margin
    points = lo + (hi - lo) * rng.random((count, K, n))
    # Each segment lasts a random nominal time, or longer if its largest joint move could not
    # be made in it from rest to rest within the bounds (peak speed 1.875 Δ/T, peak acceleration
    # 5.7735 Δ/T² for a rest-to-rest quintic): segments then move at similar speeds, instead of
    # one fast segment slowing the whole trajectory down.
    move = np.abs(np.diff(points, axis=1))                               # (J, K-1, n)
    needed = np.maximum(1.875 * move / settings.max_velocity,
                        np.sqrt(5.7735 * move / settings.max_acceleration)).max(axis=-1)
    durations = np.maximum(rng.uniform(*settings.segment_time, size=(count, K - 1)), needed)
    v = _via_velocities(points, durations)
    # A segment that overshoots the joint limits gets zero velocity at both ends (a rest-to-rest
    # quintic is monotone, so it stays between its via points); repeat until none does.
    s = np.linspace(0.0, 1.0, 129)[:, None, None, None]
    for _ in range(K):
        q, qd, qdd = quintic_segments(points[:, :-1], v[:, :-1], points[:, 1:], v[:, 1:],
                              durations[..., None], s)                   # (129, J, K-1, n)
        over = ((q < robot.qlim[:, 0]) | (q > robot.qlim[:, 1])).any(axis=(0, 3))  # (J, K-1)
        if not over.any():
            break
        v[:, :-1][over] = 0.0
        v[:, 1:][over] = 0.0
    # Slow each trajectory down uniformly until it keeps the velocity and acceleration bounds
    # (a 0.5 % margin covers the maxima between the 129 points per segment checked).
    ratio_v = (np.abs(qd) / settings.max_velocity).max(axis=(0, 2, 3))
    ratio_a = (np.abs(qdd) / settings.max_acceleration).max(axis=(0, 2, 3))
    scale = np.maximum(1.0, np.maximum(ratio_v, np.sqrt(ratio_a)) * 1.005)
    durations = durations * scale[:, None]
    v = v / scale[:, None, None]
    # Sample every trajectory at dt from 0 to its end; find each sample's segment with one
    # search over all trajectories' segment ends, shifted apart so that they stay sorted.
    ends = np.cumsum(durations, axis=1)                                  # (J, K-1)
    counts = np.floor(ends[:, -1] / settings.dt + 1e-9).astype(int) + 1
    trajectory = np.repeat(np.arange(count), counts)
    t = (np.arange(trajectory.size) - np.repeat(np.cumsum(counts) - counts, counts)) * settings.dt
    offset = np.arange(count) * (ends[:, -1].max() + 1.0)
    found = np.searchsorted((ends + offset[:, None]).ravel(), t + offset[trajectory], side="right")
    segment = np.minimum(found - trajectory * (K - 1), K - 2)
    starts = np.concatenate([np.zeros((count, 1)), ends[:, :-1]], axis=1)
    T = durations[trajectory, segment]
    sn = np.clip((t - starts[trajectory, segment]) / T, 0.0, 1.0)[:, None]
    q, qd, qdd = quintic_segments(points[trajectory, segment], v[trajectory, segment],
                          points[trajectory, segment + 1], v[trajectory, segment + 1],
                          T[:, None], sn)
    return {"t": t, "q": q, "qd": qd, "qdd": qdd, "trajectory": trajectory, "scale": scale}
