"""Where the learned inverse kinematics lives: the declared region of joint space, its samples,
and the check that the inverse kinematics is single-valued there (the dissertation's §3.2.3;
chapter 05).

Over the full joint ranges a 5-DOF arm's inverse kinematics is
many-valued — the base can turn half a turn and the arm lean back over its head, the elbow can
bend up or down — and no regressor learns a map that is not a function. The IK data therefore
live in a declared :class:`IKRegion`: a box of joint sub-ranges that selects one branch, plus
optional task-space filters on the tool point (distance from the base axis, reach in front of
it, height) and on the tool's approach axis (a cone). :func:`check_single_valued` proves the choice:
it counts every solution of each target (the closed form, :func:`nfarm.solvers.ik.closed_form`, for the
arms it covers; else Levenberg–Marquardt from many starts spread over the *full* joint limits)
and looks for a second one inside the region. Samples are ``q`` from the region and
``T = fk(q)``.

Every random draw comes from the study's ``seed``, through one named stream per use
(:data:`STREAMS`, ``numpy.random.SeedSequence([seed, stream])``), so adding a use never shifts
another's draws.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.stats import qmc

from ..infra.arguments import check_integer, check_number
from ..model.kinematics import fk
from ..model.robot import Robot, joint_array
from ..solvers.geometric_ik import wrapped_gap as _wrapped_gap
from ..solvers.arm_class import check_class
from ..solvers.ik import closed_form, count_distinct, in_class, solve

__all__ = ["IKRegion", "SingleValuedness", "check_single_valued", "workspace_fraction", "ik_samples",
           "STREAMS", "stream_rng"]

#: The random streams of a study's draws, one per use (the data sets' and the solution check's).
STREAMS = {"ik": 1, "ik_full": 2, "id": 3, "check": 4, "check_starts": 5, "id_noise": 6, "true_arm": 7}


def stream_rng(seed: int, *stream: int) -> np.random.Generator:
    """The generator of one named use of the study's ``seed``: ``SeedSequence([seed, *stream])``.

    Example:
        >>> first = stream_rng(0, STREAMS["check"]).integers(100, size=3)
        >>> np.array_equal(first, stream_rng(0, STREAMS["check"]).integers(100, size=3))  # the same again
        True
        >>> np.array_equal(first, stream_rng(0, STREAMS["check_starts"]).integers(100, size=3))  # another use
        False
    """
    return np.random.default_rng(np.random.SeedSequence([seed, *stream]))


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
                        method: str = "auto", batch: int = 100_000, near: float = 1e-5,
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

    On an arm near the closed form's class (:data:`nfarm.solvers.arm_class.NEAR_TOL`: pitch axes
    a rounded π apart), the other branches reach the nearest pose micrometres from the target,
    not the target: a branch within ``near`` [m and rad] of it counts as a solution there, as
    it is one to a learner and to any sensor.
    """
    robot = region.robot
    if method == "auto":
        method = "closed form" if in_class(robot) else "lm"
    if method not in ("closed form", "lm"):
        raise ValueError(f"method must be 'auto', 'closed form' or 'lm', got {method!r}")
    check_integer("batch", batch, 1, message=f"batch must be a whole number >= 1, got {batch!r}")
    check_number("near", near, 0, open_lo=True, finite=False, numpy=False,
                 message=f"near must be a number > 0 [m and rad], got {near!r}")
    q = region.sample(n_targets, stream_rng(seed, STREAMS["check"]), method="uniform")
    if method == "closed form":
        if ik_options:
            raise ValueError(f"LM options ({', '.join(sorted(ik_options))}) apply to method='lm' "
                             f"only; the closed form takes none")
        reach = None if check_class(robot).exact else near
        parts = [_closed_form_counts(region, q[k:k + batch], tol, distinct, reach)
                 for k in range(0, n_targets, batch)]
        second, q_second, solutions, inside = (np.concatenate(x) for x in zip(*parts))
        return SingleValuedness(q=q, second=second, q_second=q_second, solutions=solutions,
                                inside=inside, solved=solutions, starts=0, method=method)
    T = fk(robot, q)
    lo, span = robot.qlim[:, 0], robot.qlim[:, 1] - robot.qlim[:, 0]
    sobol = qmc.Sobol(robot.n, scramble=True, seed=stream_rng(seed, STREAMS["check_starts"]))
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


def _closed_form_counts(region: IKRegion, q: np.ndarray, tol: float, distinct: float,
                        reach: float | None):
    """Per target of ``q``: whether it has a second solution in the region, the first such,
    and the distinct solutions in the limits and in the region; ``reach`` [m and rad]: a branch
    that ends this near the target counts (an arm near the class), else the closed form's own
    test."""
    result = closed_form(region.robot, fk(region.robot, q))
    valid = result.valid if reach is None else \
        (result.pos_error <= reach) & (result.rot_error <= reach) & result.within_limits
    in_region = valid & region.contains(result.q)
    second, q_second = _second(q, result.q, in_region, tol)
    return second, q_second, count_distinct(result.q, valid, distinct), \
        count_distinct(result.q, in_region, distinct)


def workspace_fraction(region: IKRegion, n: int = 200_000, seed: int = 0, *,
                       voxel: float = 0.02) -> float:
    """The share of the full workspace the region's tool positions cover: the fraction of the
    ``voxel``-sized cells [m] reached from the full joint ranges that are also reached from the
    region (``n`` samples each, so small cells reached rarely may be missed by both)."""
    full = IKRegion.full(region.robot)
    cells = []
    for k, r in enumerate((full, region)):
        p = fk(region.robot, r.sample(n, stream_rng(seed, 100 + k), method="uniform"))[:, :3, 3]
        cells.append(np.unique(np.floor(p / voxel).astype(np.int64), axis=0))
    both = np.concatenate(cells)
    shared = len(both) - len(np.unique(both, axis=0))
    return shared / len(cells[0])


def ik_samples(region: IKRegion, n: int, seed, *, method: str = "sobol") -> dict[str, np.ndarray]:
    """``q (n, dof)`` in the region and ``T = fk(q) (n, 4, 4)``."""
    q = region.sample(n, seed, method=method)
    return {"q": q, "T": fk(region.robot, q)}
