"""Training, validation and test data for learned inverse kinematics and inverse dynamics,
generated from the numerical models (the dissertation's §3.2.3; chapter 05).

**Inverse kinematics.** Over the full joint ranges a 5-DOF arm's inverse kinematics is
many-valued — the base can turn half a turn and the arm lean back over its head, the elbow can
bend up or down — and no regressor learns a map that is not a function. The IK data therefore
live in a declared :class:`IKRegion`: a box of joint sub-ranges that selects one branch, plus
optional task-space filters on the tool point (distance from the base axis, reach in front of
it, height) and on the tool's approach axis (a cone). :func:`check_single_valued` proves the choice:
it counts every solution of each target (the closed form, :func:`nfarm.solvers.ik.closed_form`, for the
arms it covers; else Levenberg–Marquardt from many starts spread over the *full* joint limits)
and looks for a second one inside the region. Samples are ``q`` from the region and
``T = fk(q)``.

**Inverse dynamics.** Random smooth joint trajectories (:func:`random_trajectories`): for each
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

**Files** (:func:`build_datasets`, ``python -m nfarm datasets STUDY``):
``build/datasets/<robot>/{ik,ik_full,id}_{train,val,test}.npz`` of plain arrays (``np.load(...,
allow_pickle=False)``; written with fixed zip timestamps, so the same inputs give the same
bytes), each with a ``.json`` beside it: the robot's parameter hash, the study parameters, the
seed, the nfarm and data-code versions, the array shapes, the npz's SHA-256 and the command.
A file whose inputs' hash is unchanged is reused. :func:`load` refuses a file made for another
robot or other study parameters, saying what differs and how to regenerate.

Every random draw comes from the study's ``seed``, through one named stream per use
(``numpy.random.SeedSequence([seed, stream])``), so adding a use never shifts another's draws.
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import json
import math
import os
import sys
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import qmc

from .. import __version__
from ..infra.paths import BUILD, atomic_path, project_path
from ..infra.provenance import code_digest
from ..infra.reading import ParamsError, Validator, load_json, load_yaml, show
from ..model.dynamics import rnea, stribeck_drive_torques
from ..model.kinematics import fk
from ..model.robot import Robot, joint_array, load_robot, robot_hash
from ..solvers.geometric_ik import wrapped_gap as _wrapped_gap
from ..solvers.ik import closed_form, count_distinct, in_class, solve
from ..solvers.trajectory import cubic

__all__ = ["IKRegion", "Study", "IDSettings", "SingleValuedness", "Dataset", "load_study",
           "study_from_dict", "smoke_study", "check_single_valued", "workspace_fraction",
           "random_trajectories", "seed_like_trajectories", "ik_samples", "redrawn", "build_datasets", "load", "dataset_dir",
           "measured_states", "DATA_VERSION", "SPLITS"]

#: Version of the generating code: bump when the same inputs would give different data.
DATA_VERSION = 3
SPLITS = ("train", "val", "test")
_STREAMS = {"ik": 1, "ik_full": 2, "id": 3, "check": 4, "check_starts": 5, "id_noise": 6}
_SPLIT_STREAM = {"train": 0, "val": 1, "test": 2}


def _rng(seed: int, *stream: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence([seed, *stream]))


# --------------------------------------------------------------------------------------------
# The IK region


@dataclass(frozen=True, eq=False)
class IKRegion:
    """A region of joint space in which the inverse kinematics is to be single-valued.

    Attributes:
        robot: the robot.
        box: ``(n, 2)`` joint sub-ranges ``[lo, hi]`` [rad], within the joint limits.
        radial: ``(lo, hi)`` distance of the tool point from the base z axis [m] (``None``: no
            bound).
        height: ``(lo, hi)`` height ``z`` of the tool point in the base frame [m].
        reach: ``(lo, hi)`` signed horizontal distance of the tool point in front of the base
            axis, along the direction the base joint faces, ``(cos θ1, sin θ1, 0)`` with
            ``θ1 = q1 + offset1`` [m]: negative when the arm reaches back over the base. Needs
            joint 1 to turn about the base z axis.
        approach_axis: unit vector in the base frame, or ``None``; with ``approach_angle``
            [rad], the tool's approach axis (the z column of ``T_0e``) must lie within that
            angle of it.
    """

    robot: Robot
    box: np.ndarray
    radial: tuple[float | None, float | None] = (None, None)
    height: tuple[float | None, float | None] = (None, None)
    approach_axis: np.ndarray | None = None
    approach_angle: float = math.pi
    reach: tuple[float | None, float | None] = (None, None)

    @classmethod
    def full(cls, robot: Robot) -> "IKRegion":
        """The whole joint box: the dissertation's (naive) sampling."""
        return cls(robot, robot.qlim.copy())

    @property
    def has_filters(self) -> bool:
        return self.radial != (None, None) or self.height != (None, None) or \
            self.reach != (None, None) or self.approach_axis is not None

    def contains_pose(self, T_0e: np.ndarray, q: np.ndarray | None = None) -> np.ndarray:
        """Whether tool poses ``(..., 4, 4)`` (world frame) pass the task-space filters:
        ``(...)``. Distance and reach are measured from the base axis, the z axis of DH frame 0
        (the robot's ``base`` places it in the world); the height and the approach axis are
        the world's. The reach filter also needs the configurations ``q (..., n)`` [rad]."""
        p = T_0e[..., :3, 3]
        ok = np.ones(T_0e.shape[:-2], bool)
        B = self.robot.base
        p0 = p if np.array_equal(B, np.eye(4)) else (p - B[:3, 3]) @ B[:3, :3]   # in frame 0
        r = np.hypot(p0[..., 0], p0[..., 1])
        bounds = [(r, self.radial), (p[..., 2], self.height)]
        if self.reach != (None, None):
            if q is None:
                raise ValueError("the region's reach filter needs the poses' configurations q")
            theta1 = q[..., 0] + self.robot.offset[0]
            bounds.append((p0[..., 0] * np.cos(theta1) + p0[..., 1] * np.sin(theta1), self.reach))
        for value, (lo, hi) in bounds:
            if lo is not None:
                ok &= value >= lo
            if hi is not None:
                ok &= value <= hi
        if self.approach_axis is not None:
            ok &= T_0e[..., :3, 2] @ self.approach_axis >= math.cos(self.approach_angle)
        return ok

    def contains(self, q) -> np.ndarray:
        """Whether configurations ``q (..., n)`` [rad] lie in the region: ``(...)``."""
        q = joint_array(self.robot, q)
        ok = np.atleast_1d(((q >= self.box[:, 0]) & (q <= self.box[:, 1])).all(axis=-1))
        if self.has_filters and ok.any():
            flat = q.reshape(-1, self.robot.n)
            inside = ok.reshape(-1)
            inside[inside] = self.contains_pose(fk(self.robot, flat[inside]), flat[inside])
            ok = inside.reshape(ok.shape)
        return ok.reshape(q.shape[:-1])

    def sample(self, n: int, seed: int | np.random.Generator, *, method: str = "sobol",
               max_draws: int = 100_000_000) -> np.ndarray:
        """``n`` configurations ``(n, dof)`` [rad] in the region.

        ``method="sobol"``: a scrambled Sobol sequence (``scipy.stats.qmc``) over the box, which
        covers it more evenly than independent draws (lower discrepancy); ``"uniform"``:
        independent uniform draws. The box is sampled without rejection; the task-space
        filters reject, in batches, until ``n`` are accepted.

        Raises:
            ValueError: the filters accept too few draws to reach ``n`` within ``max_draws``.
        """
        if method not in ("sobol", "uniform"):
            raise ValueError(f"method must be 'sobol' or 'uniform', got {method!r}")
        rng = np.random.default_rng(seed)
        lo, span = self.box[:, 0], self.box[:, 1] - self.box[:, 0]
        sobol = qmc.Sobol(self.robot.n, scramble=True, seed=rng) if method == "sobol" else None
        parts, accepted, drawn = [], 0, 0
        while accepted < n:
            want = min(max(n - accepted, 1024), 1 << 20)     # batches of at most 2²⁰: bounded memory
            if sobol is not None:            # powers of two keep Sobol's balance properties
                u = sobol.random(1 << int(math.ceil(math.log2(want))))
            else:
                u = rng.random((want, self.robot.n))
            q = lo + span * u
            drawn += len(q)
            if self.has_filters:
                q = q[self.contains_pose(fk(self.robot, q), q)]
            parts.append(q)
            accepted += len(q)
            # Stop as soon as the acceptance so far says max_draws will not do (after a million
            # draws: an unreachable region is refused in a second, not after 10⁸ draws).
            if accepted < n and (drawn >= max_draws or drawn >= 1_000_000 and accepted * max_draws < n * drawn):
                raise ValueError(f"the region's task-space filters accepted {accepted:,} of {drawn:,} draws, "
                                 f"too few for the {n:,} asked for within {max_draws:,} draws: widen them")
        return np.concatenate(parts)[:n]

    def describe(self) -> list[tuple[str, str]]:
        """The region for people: (what, bound) rows, angles in degrees."""
        rows = [(f"q{i + 1} ({self.robot.joint_names[i]})",
                 f"{math.degrees(lo):.1f} … {math.degrees(hi):.1f} deg")
                for i, (lo, hi) in enumerate(self.box)]
        for name, (lo, hi), unit in (("distance from the base axis", self.radial, "m"),
                                     ("reach in front of the base axis", self.reach, "m"),
                                     ("height z", self.height, "m")):
            if (lo, hi) != (None, None):
                rows.append((name, f"{'−∞' if lo is None else f'{lo:g}'} … "
                                   f"{'∞' if hi is None else f'{hi:g}'} {unit}"))
        if self.approach_axis is not None:
            rows.append(("tool approach axis", f"within {math.degrees(self.approach_angle):g}° of "
                                               f"{np.round(self.approach_axis, 3).tolist()}"))
        return rows


@dataclass(frozen=True)
class SingleValuedness:
    """Result of :func:`check_single_valued` for ``M`` targets.

    Attributes:
        q: ``(M, n)`` the targets' configurations (in the region).
        second: ``(M,)`` whether a second solution inside the region was found.
        q_second: ``(M, n)`` that solution (NaN where none).
        solutions: ``(M,)`` distinct solutions within the joint limits (anywhere, not only in
            the region): how many-valued the full problem is.
        inside: ``(M,)`` distinct solutions inside the region.
        solved: ``(M,)`` LM starts that converged (``method="lm"``), or ``solutions``.
        starts: LM starts per target (0 for the closed form).
        method: ``"closed form"`` (exact) or ``"lm"``.
    """

    q: np.ndarray
    second: np.ndarray
    q_second: np.ndarray
    solutions: np.ndarray
    inside: np.ndarray
    solved: np.ndarray
    starts: int
    method: str

    @property
    def fraction(self) -> float:
        """Fraction of targets with a second solution in the region."""
        return float(np.mean(self.second))

    @property
    def offenders(self) -> np.ndarray:
        return np.flatnonzero(self.second)


def check_single_valued(region: IKRegion, n_targets: int = 1000, n_starts: int = 24, *,
                        seed: int = 0, tol: float = 1e-6, distinct: float = 1e-4,
                        method: str = "auto", batch: int = 100_000,
                        **ik_options) -> SingleValuedness:
    """Count the IK solutions of ``n_targets`` targets ``T = fk(q)``, ``q`` drawn in ``region``:
    within the full joint limits, and inside the region.

    ``method="closed form"``: every solution of every target (:func:`nfarm.solvers.ik.closed_form`),
    exact; in batches of ``batch`` targets, so that memory does not grow with ``n_targets``.
    ``"lm"``: Levenberg–Marquardt (:func:`nfarm.solvers.ik.solve`, no restarts, ``ik_options``) from
    ``n_starts`` starts spread over the **full** joint limits (a scrambled Sobol sequence),
    which finds only the solutions some start converges to. ``"auto"``: the closed form where the robot
    is of its class, else LM.

    A solution inside the region that differs from ``q`` by more than ``tol`` [rad] in some
    joint is a second solution. Solutions are distinct when they differ by more than
    ``distinct`` [rad] in some joint, angles 2π apart being the same.
    """
    robot = region.robot
    if method == "auto":
        method = "closed form" if in_class(robot) else "lm"
    if method not in ("closed form", "lm"):
        raise ValueError(f"method must be 'auto', 'closed form' or 'lm', got {method!r}")
    if isinstance(batch, bool) or not isinstance(batch, (int, np.integer)) or batch < 1:
        raise ValueError(f"batch must be a whole number >= 1, got {batch!r}")
    q = region.sample(n_targets, _rng(seed, _STREAMS["check"]), method="uniform")
    if method == "closed form":
        if ik_options:
            raise ValueError(f"LM options ({', '.join(sorted(ik_options))}) apply to method='lm' "
                             f"only; the closed form takes none")
        parts = [_closed_form_counts(region, q[k:k + batch], tol, distinct)
                 for k in range(0, n_targets, batch)]
        second, q_second, solutions, inside = (np.concatenate(x) for x in zip(*parts))
        return SingleValuedness(q=q, second=second, q_second=q_second, solutions=solutions,
                                inside=inside, solved=solutions, starts=0, method=method)
    T = fk(robot, q)
    lo, span = robot.qlim[:, 0], robot.qlim[:, 1] - robot.qlim[:, 0]
    sobol = qmc.Sobol(robot.n, scramble=True, seed=_rng(seed, _STREAMS["check_starts"]))
    starts = lo + span * sobol.random(1 << int(math.ceil(math.log2(n_starts))))[:n_starts]
    T_all = np.broadcast_to(T[:, None], (n_targets, n_starts, 4, 4))
    q0 = np.broadcast_to(starts, (n_targets, n_starts, robot.n))
    result = solve(robot, T_all, q0=q0, **{"restarts": 0, **ik_options})
    ok = result.success                                                # (M, S)
    in_region = ok & region.contains(result.q)
    second, q_second = _second(q, result.q, in_region, tol)
    return SingleValuedness(q=q, second=second, q_second=q_second,
                            solutions=count_distinct(result.q, ok, distinct),
                            inside=count_distinct(result.q, in_region, distinct),
                            solved=ok.sum(axis=1), starts=n_starts, method=method)


def _second(q: np.ndarray, candidates: np.ndarray, ok: np.ndarray, tol: float):
    """Per target, whether some ``ok`` candidate ``(M, K, n)`` differs from ``q (M, n)`` by more
    than ``tol`` in some joint (angles 2π apart being the same), and the first such one."""
    other = ok & (_wrapped_gap(candidates - q[:, None]).max(axis=-1) > tol)
    second = other.any(axis=1)
    first = candidates[np.arange(len(q)), np.argmax(other, axis=1)]
    return second, np.where(second[:, None], first, np.nan)


def _closed_form_counts(region: IKRegion, q: np.ndarray, tol: float, distinct: float):
    result = closed_form(region.robot, fk(region.robot, q))
    in_region = result.valid & region.contains(result.q)
    second, q_second = _second(q, result.q, in_region, tol)
    return second, q_second, count_distinct(result.q, result.valid, distinct), \
        count_distinct(result.q, in_region, distinct)


def workspace_fraction(region: IKRegion, n: int = 200_000, seed: int = 0, *,
                       voxel: float = 0.02) -> float:
    """The share of the full workspace the region's tool positions cover: the fraction of the
    ``voxel``-sized cells [m] reached from the full joint ranges that are also reached from the
    region (``n`` samples each, so small cells reached rarely may be missed by both)."""
    full = IKRegion.full(region.robot)
    cells = []
    for k, r in enumerate((full, region)):
        p = fk(region.robot, r.sample(n, _rng(seed, 100 + k), method="uniform"))[:, :3, 3]
        cells.append(np.unique(np.floor(p / voxel).astype(np.int64), axis=0))
    both = np.concatenate(cells)
    shared = len(both) - len(np.unique(both, axis=0))
    return shared / len(cells[0])


@dataclass(frozen=True)
class Volume:
    """A Monte Carlo estimate of the workspace's volume (:func:`workspace_volume`)."""

    volume: float        # [m³]
    std_error: float     # [m³], one standard error of the estimate
    reach: float         # [m], radius of the ball the points were drawn in
    share: float         # share of the drawn points the tool reaches
    points: int


def workspace_volume(robot: Robot, reach_m: float, n_points: int = 4000, seed: int = 0,
                     **solve_options) -> Volume:
    """Volume [m³] of the tool's position workspace: points drawn uniformly in the ball of
    radius ``reach_m`` about the first joint's origin, each tested by position-only IK
    (:func:`nfarm.solvers.ik.solve` with weights ``[1, 1, 1, 0, 0, 0]``, its restarts, within the joint
    limits); ``V = (4/3)π r³ · share reached``, standard error ``(4/3)π r³ √(s(1 − s)/N)``.

    Why not count the cells that sampled configurations reach: with uniform joint samples
    that count was still growing by 10 % from 200 000 to 800 000 samples (cells reached rarely
    hold no sample), whereas 4 000 IK points give ±2 % in 3 s.
    """
    rng = np.random.default_rng(seed)
    direction = rng.normal(size=(n_points, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    radius = reach_m * rng.random(n_points) ** (1 / 3)
    T = np.tile(np.eye(4), (n_points, 1, 1))
    T[:, :3, 3] = robot.base[:3, 3] + direction * radius[:, None]
    reached = solve(robot, T, weights=[1, 1, 1, 0, 0, 0], seed=seed, **solve_options).success
    share = float(reached.mean())
    ball = 4 / 3 * np.pi * reach_m ** 3
    return Volume(ball * share, ball * np.sqrt(share * (1 - share) / n_points), reach_m, share,
                  n_points)


def smoke_study(study: Study, factor: int = 50) -> Study:
    """The same study with every size divided by ``factor`` (at least a few samples each),
    for quick runs; its data sets go to a directory of their own (``<robot>-smoke``)."""
    params = json.loads(json.dumps(study.params))
    params["ik"]["sizes"] = {k: max(v // factor, 64) for k, v in params["ik"]["sizes"].items()}
    params["ik"]["check"]["targets"] = max(params["ik"]["check"]["targets"] // factor, 50)
    params["id"]["trajectories"] = {k: max(v // factor, 2)
                                    for k, v in params["id"]["trajectories"].items()}
    params["name"] = f"{params['name']} (smoke)"
    return study_from_dict(params, source=study.source)


def redrawn(study: Study, draw: int) -> Study:
    """The study with its training and validation data drawn again: draw ``k`` is the study
    with ``seed + k`` (a reader reproduces it by editing the seed), its data sets in a
    directory of their own (``draw<k>/`` in the study's, :func:`dataset_dir`) and without a
    test split — the test set is never redrawn, so every draw's models are tested on the same
    held-out data. Draw 0 is the study itself. A sweep's ``seeds`` are draws (:mod:`nfarm.study.jobs`): the spread over
    seeds is over data and initialisation together.

    Raises:
        ValueError: ``draw`` is not a non-negative integer.
    """
    if isinstance(draw, bool) or not isinstance(draw, (int, np.integer)) or draw < 0:
        raise ValueError(f"draw must be a non-negative integer, got {draw!r}")
    if draw == 0:
        return study
    params = json.loads(json.dumps(study.params))
    params["seed"] = study.seed + int(draw)
    return dataclasses.replace(study_from_dict(params, source=study.source), draw=int(draw))


def ik_samples(region: IKRegion, n: int, seed, *, method: str = "sobol") -> dict[str, np.ndarray]:
    """``q (n, dof)`` in the region and ``T = fk(q) (n, 4, 4)``."""
    q = region.sample(n, seed, method=method)
    return {"q": q, "T": fk(region.robot, q)}


# --------------------------------------------------------------------------------------------
# ID trajectories


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


def _quintic(p0, v0, p1, v1, T, s):
    """Quintic Hermite segment with zero end accelerations, at normalised times ``s``:
    position, velocity, acceleration (arrays broadcast over leading axes)."""
    d = p1 - p0
    c3 = 10 * d - (6 * v0 + 4 * v1) * T
    c4 = -15 * d + (8 * v0 + 7 * v1) * T
    c5 = 6 * d - 3 * (v0 + v1) * T
    c1 = v0 * T
    q = p0 + s * (c1 + s * s * (c3 + s * (c4 + s * c5)))
    qd = (c1 + s * s * (3 * c3 + s * (4 * c4 + s * 5 * c5))) / T
    qdd = s * (6 * c3 + s * (12 * c4 + s * 20 * c5)) / (T * T)
    return q, qd, qdd


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
        q, qd, qdd = _quintic(points[:, :-1], v[:, :-1], points[:, 1:], v[:, 1:],
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
    q, qd, qdd = _quintic(points[trajectory, segment], v[trajectory, segment],
                          points[trajectory, segment + 1], v[trajectory, segment + 1],
                          T[:, None], sn)
    return {"t": t, "q": q, "qd": qd, "qdd": qdd, "trajectory": trajectory, "scale": scale}


# --------------------------------------------------------------------------------------------
# Study files


@dataclass(frozen=True, eq=False)
class Study:
    """A validated study file (schema in ``params/README.md``)."""

    source: str
    name: str
    robot_file: str
    robot: Robot
    seed: int
    ik_region: IKRegion
    ik_sampler: str
    ik_sizes: dict[str, int]
    ik_full_range: bool
    check_targets: int
    check_starts: int
    id: IDSettings
    learned_ik: dict = field(default_factory=dict)   # the chosen learned IK's size for this arm
    params: dict = field(repr=False, default_factory=dict)
    #: 0 for the study's own data; k for its training and validation data drawn again
    #: (:func:`redrawn`).
    draw: int = 0

    @property
    def data_params(self) -> dict:
        """The study parameters the data sets depend on (all but ``learned_ik``)."""
        return {k: v for k, v in self.params.items() if k != "learned_ik"}

    def chosen_ik(self, options: Mapping) -> dict:
        """Chapter 06's chosen learned-IK ``options`` (LearnedIK keyword arguments) with this
        study's ``learned_ik`` applied: ``n_mfs`` replaces the grid's functions per input;
        ``epochs``, one number or one per joint, the epochs (per joint through
        ``joint_options``, keeping each joint's other options)."""
        chosen = dict(options)
        if "n_mfs" in self.learned_ik:
            chosen["n_mfs"] = self.learned_ik["n_mfs"]
        epochs = self.learned_ik.get("epochs")
        if isinstance(epochs, int):
            chosen["epochs"] = epochs
        elif epochs is not None:
            joint = chosen.get("joint_options") or [{}] * len(epochs)
            chosen["joint_options"] = [{**o, "epochs": e} for o, e in zip(joint, epochs)]
        return chosen

    @property
    def inputs_hash(self) -> str:
        """SHA-256 of what the data depend on: the robot's parameters, the study's
        parameters, the data code's version and the content of the code that makes them
        (:func:`nfarm.infra.provenance.code_digest` of this module)."""
        blob = json.dumps({"robot": robot_hash(self.robot), "study": self.data_params,
                           "data_version": DATA_VERSION, "code": code_digest("study.datasets")}, sort_keys=True)
        return hashlib.sha256(blob.encode()).hexdigest()


_TOP = {"name": True, "description": False, "robot_file": True, "seed": True, "ik": True,
        "id": True, "learned_ik": False}
_LEARNED_IK = {"n_mfs": False, "epochs": False}
_IK = {"region": True, "sampler": False, "sizes": True, "check": True, "full_range": False}
_REGION = {"joints_deg": True, "radial_m": False, "reach_m": False, "height_m": False,
           "approach": False}
_APPROACH = {"axis": True, "max_angle_deg": True}
_SIZES = dict.fromkeys(SPLITS, True)
_CHECK = {"targets": True, "starts": True}
_ID = {"trajectories": True, "via_points": True, "segment_time_s": True, "dt_s": True,
       "margin_deg": False, "max_velocity_deg_s": True, "max_acceleration_deg_s2": True,
       "measured": False}
_MEASURED = {"viscous": True, "coulomb": True, "coulomb_velocity_deg_s": True, "armature": True,
             "noise_nm": True, "stribeck": False, "stribeck_velocity_deg_s": False,
             "load_coefficient": False, "encoder_counts": False, "filter_window": False}


# --------------------------------------------------------------------------------------------
# Work estimates


def memory_budget() -> float:
    """Bytes the making of one data set may take: ``NFARM_MEMORY_GB`` (GiB, for a bigger or
    shared machine) if set, else half of this machine's physical memory."""
    given = os.environ.get("NFARM_MEMORY_GB")
    if given:
        try:
            value = float(given)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and value > 0):
            raise ParamsError(f"NFARM_MEMORY_GB: must be a positive number of GiB, got {given!r}")
        return value * 2 ** 30
    return 0.5 * os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")


#: Peak bytes per IK pose while a data set is made (drawn, filtered by the region, checked,
#: written): 365 traced by ``tracemalloc`` for 200 000 of intelbot5's poses, 580 by the
#: process's peak memory for 5 million; the larger, rounded up.
IK_BYTES_PER_SAMPLE = 600.0


def _id_samples(segment, via: int, dt: float, vmax: np.ndarray, amax: np.ndarray, widest: float) -> float:
    """An estimate of one trajectory's samples (:func:`random_trajectories`): each segment
    lasts its mean nominal time or what its largest joint move needs within the bounds (the
    largest of a segment's moves is about 0.6 of the widest range), and the whole is slowed
    down by about 1.2. Measured on intelbot5's study: 1 340 estimated against 962 drawn per
    trajectory (200 trajectories)."""
    move = 0.6 * widest
    needed = max(1.875 * move / float(vmax.min()), math.sqrt(5.7735 * move / float(amax.min())))
    return 1.2 * (via - 1) * max(0.5 * (segment[0] + segment[1]), needed) / dt


def work_estimates(study_fields: Mapping[str, Any], robot: Robot) -> list[tuple[str, float, str]]:
    """``(field, bytes, what)`` of the largest pieces of work a study file asks for (the
    making of its largest data set of each kind, chapter 05's solution check), from its
    validated fields: ``ik_sizes``, ``trajectories``, ``via``, ``segment``, ``dt``, ``vmax``,
    ``amax``, ``check_targets``, ``check_starts``."""
    f = study_fields
    n = robot.n
    out = []
    split = max(SPLITS, key=lambda k: f["ik_sizes"][k])
    out.append((f"ik.sizes.{split}", IK_BYTES_PER_SAMPLE * f["ik_sizes"][split],
                f"{f['ik_sizes'][split]:,} IK poses"))
    widest = float(np.max(robot.qlim[:, 1] - robot.qlim[:, 0]))
    per_trajectory = _id_samples(f["segment"], f["via"], f["dt"], f["vmax"], f["amax"], widest)
    # 739 bytes a sample at the peak, measured without a measured arm's arrays: 3 × 8 × (2 + 8n)
    # (1 008 for five joints) covers them.
    split = max(SPLITS, key=lambda k: f["trajectories"][k])
    count = f["trajectories"][split]
    samples = count * per_trajectory
    # the states and torques (and their measured copies), three times over; the 129-point
    # check of every segment of every trajectory at once (q, q̇, q̈)
    peak = max(3 * 8.0 * (2 + 8 * n) * samples, 3 * 8.0 * 129 * count * (f["via"] - 1) * n)
    out.append((f"id.trajectories.{split}", peak,
                f"{count:,} trajectories of about {per_trajectory:,.0f} samples each"))
    if not in_class(robot):       # LM from every start at once; the closed form goes in batches
        out.append(("ik.check.targets", 3 * 8.0 * n * f["check_targets"] * f["check_starts"],
                    f"{f['check_targets']:,} targets × {f['check_starts']} starts"))
    return out


def _gib(size: float) -> str:
    gib = size / 2 ** 30
    return f"{gib:,.0f}" if gib >= 100 else f"{gib:.3g}"


def _check_work(v: Validator, fields: Mapping[str, Any], robot: Robot) -> None:
    budget = memory_budget()
    source = "NFARM_MEMORY_GB" if os.environ.get("NFARM_MEMORY_GB") else \
        "half this machine's memory; NFARM_MEMORY_GB sets another"
    for field_, need, what in work_estimates(fields, robot):
        if need > budget:
            v.fail(field_, f"{what} would take about {_gib(need)} GiB while made, over the memory budget of "
                           f"{_gib(budget)} GiB ({source})")


def load_study(path: str | os.PathLike) -> Study:
    """Load and validate a study file; every broken rule is one :class:`ParamsError` line
    naming the file and the field."""
    path = Path(path)
    data = load_yaml(project_path(path), what="study file")
    return study_from_dict(data, source=str(path))


def _bounds(v: Validator, value: Any, at: str, *, positive: bool = False) -> tuple:
    pair = v.sequence(value, at, min_len=2, max_len=2)
    out = tuple(None if x is None else v.number(x, f"{at}[{k}]", lo=0.0 if positive else None)
                for k, x in enumerate(pair))
    if None not in out and not out[0] < out[1]:
        v.fail(at, f"must satisfy lo < hi, got {list(out)}")
    return out


#: The largest per-joint drive, noise, speed or acceleration value a study may give: every
#: plausible one is far below, and 1.7e308 would turn the data sets' torques into inf.
PER_JOINT_MAX = 1e6


def _per_joint(v: Validator, value: Any, at: str, n: int, *, zero: bool = False) -> np.ndarray:
    """One number for every joint, or one per joint; > 0 (``>= 0`` with ``zero``), at most
    :data:`PER_JOINT_MAX`."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        values = [v.number(value, at, lo=0.0, lo_open=not zero, hi=PER_JOINT_MAX)] * n
    else:
        values = [v.number(x, f"{at}[{k}]", lo=0.0, lo_open=not zero, hi=PER_JOINT_MAX)
                  for k, x in enumerate(v.sequence(value, at, min_len=n, max_len=n))]
    return np.array(values, dtype=float)


def study_from_dict(data: Any, source: str = "<dict>") -> Study:
    """Validate a study mapping (as read from YAML) and build a :class:`Study`."""
    v = Validator(source)
    v.mapping(data, "", _TOP)
    name = v.string(data["name"], "name")
    if "description" in data:
        v.string(data["description"], "description", allow_empty=True)
    robot_file = v.string(data["robot_file"], "robot_file")
    try:
        robot = load_robot(project_path(robot_file))
    except ParamsError as exc:
        v.fail("robot_file", f"cannot load the robot: {exc}")
    seed = v.integer(data["seed"], "seed", lo=0, hi=2**63 - 1)
    n = robot.n

    ik = v.mapping(data["ik"], "ik", _IK)
    region = v.mapping(ik["region"], "ik.region", _REGION)
    joints = v.sequence(region["joints_deg"], "ik.region.joints_deg", min_len=n, max_len=n)
    box = robot.qlim.copy()
    for i, pair in enumerate(joints):
        at = f"ik.region.joints_deg[{i}]"
        if pair is None:
            continue
        lo, hi = (math.radians(x) for x in v.vector(pair, at, 2))
        if not lo < hi:
            v.fail(at, f"must satisfy lo < hi, got {show(pair)}")
        limits = robot.qlim[i]
        if lo < limits[0] - 1e-12 or hi > limits[1] + 1e-12:
            v.fail(at, f"must lie within joint {i + 1}'s limits "
                       f"[{math.degrees(limits[0]):.6g}, {math.degrees(limits[1]):.6g}] deg, "
                       f"got {show(pair)}")
        box[i] = (max(lo, limits[0]), min(hi, limits[1]))
    radial = _bounds(v, region["radial_m"], "ik.region.radial_m", positive=True) \
        if region.get("radial_m") is not None else (None, None)
    height = _bounds(v, region["height_m"], "ik.region.height_m") \
        if region.get("height_m") is not None else (None, None)
    reach = _bounds(v, region["reach_m"], "ik.region.reach_m") \
        if region.get("reach_m") is not None else (None, None)
    if reach != (None, None) and robot.convention == "modified" and \
            (abs(robot.a[0]) > 1e-12 or abs(math.remainder(robot.alpha[0], 2 * math.pi)) > 1e-12):
        v.fail("ik.region.reach_m", f"needs joint 1 to turn about the base z axis; {robot.name}'s "
                                    f"first joint has a = {robot.a[0]:g} m, alpha = "
                                    f"{math.degrees(robot.alpha[0]):g} deg")
    axis, angle = None, math.pi
    if region.get("approach") is not None:
        approach = v.mapping(region["approach"], "ik.region.approach", _APPROACH)
        axis = np.array(v.vector(approach["axis"], "ik.region.approach.axis", 3))
        norm = float(np.linalg.norm(axis))
        if norm == 0:
            v.fail("ik.region.approach.axis", "must not be the zero vector")
        axis = axis / norm
        angle = math.radians(v.number(approach["max_angle_deg"], "ik.region.approach.max_angle_deg",
                                      lo=0.0, hi=180.0, lo_open=True))
    region_ = IKRegion(robot, box, radial, height, axis, angle, reach)
    if region_.has_filters:        # 8 192 draws (a few ms): a region no pose of the box reaches
        q_try = region_.box[:, 0] + (region_.box[:, 1] - region_.box[:, 0]) * \
            np.random.default_rng(seed).random((8192, n))
        if not region_.contains_pose(fk(robot, q_try), q_try).any():
            v.fail("ik.region", "no pose of 8,192 drawn in the joint box passes its task-space filters "
                                "(radial_m, height_m, reach_m, approach): the arm cannot reach it")
    sampler = v.choice(ik.get("sampler", "sobol"), "ik.sampler", ("sobol", "uniform"))
    sizes = v.mapping(ik["sizes"], "ik.sizes", _SIZES)
    ik_sizes = {k: v.integer(sizes[k], f"ik.sizes.{k}", lo=1, hi=50_000_000) for k in SPLITS}
    check = v.mapping(ik["check"], "ik.check", _CHECK)
    check_targets = v.integer(check["targets"], "ik.check.targets", lo=1, hi=1_000_000)
    check_starts = v.integer(check["starts"], "ik.check.starts", lo=1, hi=1024)
    full_range = v.boolean(ik.get("full_range", False), "ik.full_range")

    idd = v.mapping(data["id"], "id", _ID)
    counts = v.mapping(idd["trajectories"], "id.trajectories", _SIZES)
    trajectories = {k: v.integer(counts[k], f"id.trajectories.{k}", lo=1, hi=1_000_000)
                    for k in SPLITS}
    via = v.integer(idd["via_points"], "id.via_points", lo=2, hi=10_000)
    segment = _bounds(v, idd["segment_time_s"], "id.segment_time_s", positive=True)
    if None in segment or segment[0] <= 0:
        v.fail("id.segment_time_s", f"must be two durations 0 < lo < hi [s], got "
                                    f"{show(idd['segment_time_s'])}")
    dt = v.number(idd["dt_s"], "id.dt_s", lo=0.0, lo_open=True, hi=segment[0])
    margin = math.radians(v.number(idd.get("margin_deg", 0.0), "id.margin_deg", lo=0.0))
    narrowest = float(np.min(robot.qlim[:, 1] - robot.qlim[:, 0]))
    if 2 * margin >= narrowest:
        v.fail("id.margin_deg", f"must leave room inside the narrowest joint range "
                                f"({math.degrees(narrowest):.6g} deg), got {math.degrees(margin):.6g}")
    vmax = np.radians(_per_joint(v, idd["max_velocity_deg_s"], "id.max_velocity_deg_s", n))
    amax = np.radians(_per_joint(v, idd["max_acceleration_deg_s2"], "id.max_acceleration_deg_s2", n))
    _check_work(v, {"ik_sizes": ik_sizes, "trajectories": trajectories, "via": via, "segment": segment,
                    "dt": dt, "vmax": vmax, "amax": amax, "check_targets": check_targets,
                    "check_starts": check_starts}, robot)
    measured = noise = encoder_counts = None
    friction, filter_window = {}, 7
    if idd.get("measured") is not None:
        m = v.mapping(idd["measured"], "id.measured", _MEASURED)
        drives = {key: _per_joint(v, m[key], f"id.measured.{key}", n, zero=True)
                  for key in ("viscous", "coulomb", "armature")}
        drives["coulomb_velocity"] = np.radians(_per_joint(
            v, m["coulomb_velocity_deg_s"], "id.measured.coulomb_velocity_deg_s", n))
        measured = dataclasses.replace(robot, **drives)
        noise = _per_joint(v, m["noise_nm"], "id.measured.noise_nm", n, zero=True)
        if "stribeck" in m:
            friction["stribeck"] = _per_joint(v, m["stribeck"], "id.measured.stribeck", n, zero=True)
            low = np.flatnonzero(friction["stribeck"] < drives["coulomb"])
            if low.size:
                v.fail("id.measured.stribeck", f"the breakaway friction must be at least the Coulomb "
                                               f"friction (joint {low[0] + 1}: {friction['stribeck'][low[0]]:g} "
                                               f"< {drives['coulomb'][low[0]]:g} N·m)")
            if "stribeck_velocity_deg_s" not in m:
                v.fail("id.measured", "stribeck needs stribeck_velocity_deg_s (> 0)")
        if "stribeck_velocity_deg_s" in m:
            friction["stribeck_velocity"] = np.radians(_per_joint(
                v, m["stribeck_velocity_deg_s"], "id.measured.stribeck_velocity_deg_s", n))
        if "load_coefficient" in m:
            friction["load_coefficient"] = _per_joint(v, m["load_coefficient"], "id.measured.load_coefficient",
                                                      n, zero=True)
            if (friction["load_coefficient"] >= 1).any():
                v.fail("id.measured.load_coefficient", "must be < 1 (a fraction of the joint's load torque)")
        if m.get("encoder_counts") is not None:
            encoder_counts = v.integer(m["encoder_counts"], "id.measured.encoder_counts", lo=16, hi=2**31)
        filter_window = v.integer(m.get("filter_window", 7), "id.measured.filter_window", lo=5, hi=101)
        if filter_window % 2 == 0:
            v.fail("id.measured.filter_window", f"must be an odd number of samples, got {filter_window}")

    learned_ik = {}
    if data.get("learned_ik") is not None:
        chosen = v.mapping(data["learned_ik"], "learned_ik", _LEARNED_IK)
        if "n_mfs" in chosen:
            mfs = chosen["n_mfs"]
            learned_ik["n_mfs"] = v.integer(mfs, "learned_ik.n_mfs", lo=1, hi=8) \
                if not isinstance(mfs, list) else \
                [v.integer(m, f"learned_ik.n_mfs[{i}]", lo=1, hi=8)
                 for i, m in enumerate(v.sequence(mfs, "learned_ik.n_mfs", min_len=1, max_len=16))]
        if "epochs" in chosen:
            epochs = chosen["epochs"]
            learned_ik["epochs"] = v.integer(epochs, "learned_ik.epochs", lo=1, hi=10_000) \
                if not isinstance(epochs, list) else \
                [v.integer(e, f"learned_ik.epochs[{j}]", lo=1, hi=10_000)
                 for j, e in enumerate(v.sequence(epochs, "learned_ik.epochs", min_len=n, max_len=n))]

    return Study(
        source=source, name=name, robot_file=robot_file, robot=robot, seed=seed,
        ik_region=region_, ik_sampler=sampler,
        ik_sizes=ik_sizes, ik_full_range=full_range, check_targets=check_targets,
        check_starts=check_starts,
        id=IDSettings(trajectories, via, segment, dt, margin, vmax, amax, measured, noise, friction,
                      encoder_counts, filter_window),
        learned_ik=learned_ik, params=json.loads(json.dumps(data)))


# --------------------------------------------------------------------------------------------
# Files


def dataset_dir(study: Study, out: str | os.PathLike | None = None) -> Path:
    """Where a study's data sets go: ``out`` or ``build/datasets/<robot name>/`` (a smoke
    study's: ``build/datasets/<robot name>-smoke/``); a redrawn study's (:func:`redrawn`) in
    its subdirectory ``draw<k>/``."""
    if out is not None:
        base = project_path(out)
    else:
        smoke = "-smoke" if study.name.endswith("(smoke)") else ""
        base = BUILD / "datasets" / f"{study.robot.name}{smoke}"
    return base / f"draw{study.draw}" if study.draw else base


def _npz_bytes(arrays: Mapping[str, np.ndarray]) -> bytes:
    """An ``.npz`` (uncompressed zip of ``.npy``) with fixed timestamps: same arrays, same bytes."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_STORED) as archive:
        for name, array in arrays.items():
            info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.external_attr = 0o644 << 16
            npy = io.BytesIO()
            np.lib.format.write_array(npy, np.ascontiguousarray(array), allow_pickle=False)
            archive.writestr(info, npy.getvalue())
    return buffer.getvalue()


def _write(path: Path, arrays: Mapping[str, np.ndarray], meta: dict) -> None:
    """The npz, then its JSON (atomically each): a JSON is only there for a complete npz."""
    data = _npz_bytes(arrays)
    meta = {**meta, "npz_sha256": hashlib.sha256(data).hexdigest(),
            "arrays": {k: {"shape": list(a.shape), "dtype": a.dtype.str} for k, a in arrays.items()}}
    json_path = path.with_suffix(".json")
    json_path.unlink(missing_ok=True)
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    with atomic_path(json_path) as tmp:
        tmp.write_text(json.dumps(meta, indent=1, sort_keys=True) + "\n", encoding="utf-8")


@dataclass(frozen=True)
class Dataset(Mapping):
    """A loaded data set: its arrays by name (``data["q"]``) and its description ``meta``."""

    path: Path
    arrays: dict[str, np.ndarray]
    meta: dict

    def __getitem__(self, key: str) -> np.ndarray:
        return self.arrays[key]

    def __iter__(self):
        return iter(self.arrays)

    def __len__(self) -> int:
        return len(self.arrays)


def _differences(made: Any, now: Any, at: str = "") -> list[str]:
    if isinstance(made, dict) and isinstance(now, dict):
        out = []
        for key in sorted(set(made) | set(now)):
            out += _differences(made.get(key), now.get(key), f"{at}.{key}" if at else str(key))
        return out
    return [] if made == now else [f"{at} ({show(made)} → {show(now)})"]


def load(path: str | os.PathLike, robot: Robot, study: Study | None = None) -> Dataset:
    """Read a data set written by :func:`build_datasets`, refusing one made for another robot
    (or, with ``study``, from other study parameters or data code).

    Raises:
        ParamsError: a missing, damaged or mismatched file; the message says what differs and
            how to regenerate.
    """
    path = Path(path)
    meta = load_json(path.with_suffix(".json"), what="data set description")
    v = Validator(str(path.with_suffix(".json")))
    v.mapping(meta, "", dict.fromkeys(_META_KEYS, True))
    again = f"regenerate with `python -m nfarm datasets {meta.get('study_file', 'STUDY')}`"
    if meta["robot_params_sha256"] != robot_hash(robot):
        v.fail("robot_params_sha256", f"made for robot {show(meta.get('robot'))} with other "
                                      f"parameters than {robot.name!r} ({robot.source}): {again}")
    if study is not None and meta["inputs_hash"] != study.inputs_hash:
        diff = _differences(meta["study"], study.data_params)
        if meta["data_version"] != DATA_VERSION:
            diff.append(f"data code version ({meta['data_version']} → {DATA_VERSION})")
        if diff:
            v.fail("study", f"made from other study parameters: {'; '.join(diff[:4])}; {again}")
        v.fail("study", f"made by other code than this checkout's (nfarm.study.datasets or a module it "
                        f"imports changed since): {again}")
    raw = _read_limited(path)
    if hashlib.sha256(raw).hexdigest() != meta["npz_sha256"]:
        v.fail("npz_sha256", f"{path.name} is not the file this description was written for "
                             f"(changed or damaged): {again}")
    with np.load(io.BytesIO(raw), allow_pickle=False) as npz:
        arrays = {k: npz[k] for k in npz.files}
    declared = meta["arrays"]
    if set(arrays) != set(declared) or any(list(arrays[k].shape) != declared[k]["shape"]
                                           for k in arrays):
        v.fail("arrays", f"the arrays of {path.name} do not match their description: {again}")
    return Dataset(path, arrays, meta)


_META_KEYS = ("kind", "split", "robot", "robot_file", "robot_params_sha256", "study_file",
              "study", "seed", "inputs_hash", "nfarm_version", "data_version", "command",
              "npz_sha256", "arrays")


def _read_limited(path: Path) -> bytes:
    from ..infra.reading import read_bytes
    return read_bytes(path, max_bytes=8 << 30, what="data set")


def _up_to_date(path: Path, inputs_hash: str) -> bool:
    json_path = path.with_suffix(".json")
    if not (path.is_file() and json_path.is_file()):
        return False
    try:
        meta = load_json(json_path)
        return isinstance(meta, dict) and meta.get("inputs_hash") == inputs_hash and \
            hashlib.sha256(path.read_bytes()).hexdigest() == meta.get("npz_sha256")
    except (ParamsError, OSError):
        return False


def build_datasets(study: Study, out: str | os.PathLike | None = None, *, force: bool = False,
                   progress: bool = False, command: str | None = None) -> list[tuple[Path, str]]:
    """Write every data set of ``study`` (module docstring); returns ``(path, "made" |
    "reused")`` per file. Files whose inputs' hash is unchanged are reused unless ``force``."""
    directory = dataset_dir(study, out)
    directory.mkdir(parents=True, exist_ok=True)
    inputs_hash = study.inputs_hash
    base = {"robot": study.robot.name, "robot_file": study.robot_file,
            "robot_params_sha256": robot_hash(study.robot), "study_file": study.source,
            "study": study.data_params, "seed": study.seed, "inputs_hash": inputs_hash,
            "nfarm_version": __version__, "data_version": DATA_VERSION,
            "command": command or f"python -m nfarm datasets {study.source}"}
    splits = [s for s in SPLITS if s != "test"] if study.draw else SPLITS    # never redrawn
    jobs = [("ik", s) for s in splits] + [("id", s) for s in splits]
    if study.ik_full_range:
        jobs += [("ik_full", s) for s in splits]
    bar = None
    if progress:
        from tqdm.auto import tqdm
        bar = tqdm(total=len(jobs), desc="data sets", unit="file", file=sys.stderr)
    done = []
    for kind, split in jobs:
        path = directory / f"{kind}_{split}.npz"
        if not force and _up_to_date(path, inputs_hash):
            done.append((path, "reused"))
        else:
            seed = [study.seed, _STREAMS[kind], _SPLIT_STREAM[split]]
            if kind == "id":
                data = random_trajectories(study.robot, study.id, study.id.trajectories[split],
                                           np.random.SeedSequence(seed))
                data["tau"] = rnea(study.robot, data["q"], data["qd"], data["qdd"])
                if study.id.measured is not None:
                    noise = np.random.default_rng(np.random.SeedSequence(
                        [study.seed, _STREAMS["id_noise"], _SPLIT_STREAM[split]]))
                    drive = stribeck_drive_torques(study.id.measured, data["qd"], data["qdd"], data["tau"],
                                                   **study.id.friction)
                    data["tau_measured"] = data["tau"] + drive + \
                        study.id.noise * noise.standard_normal(data["tau"].shape)
                    if study.id.encoder_counts is not None:
                        data["q_measured"], data["qd_measured"], data["qdd_measured"] = measured_states(
                            data["q"], data["trajectory"], study.id.dt, study.id.encoder_counts,
                            study.id.filter_window)
            else:
                region = study.ik_region if kind == "ik" else IKRegion.full(study.robot)
                data = ik_samples(region, study.ik_sizes[split], np.random.SeedSequence(seed),
                                  method=study.ik_sampler)
            _write(path, data, {**base, "kind": kind, "split": split})
            done.append((path, "made"))
        if bar is not None:
            bar.update(1)
    if bar is not None:
        bar.close()
    return done
