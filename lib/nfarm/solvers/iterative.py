"""Iterative inverse kinematics: joint angles for target tool poses from a starting guess, for
any chain, as the dissertation does; batched over targets. Use it as
:func:`nfarm.solvers.ik.solve` (:mod:`nfarm.solvers.ik` gathers this solver and the closed form);
its result says which closed-form branch it converged to where the robot has one
(:func:`nfarm.solvers.arm_class.branch_of`).

All targets are solved together: every iteration evaluates the pose and the Jacobian of the
still-unsolved targets as one batch (component layout, samples last), and a target leaves
the batch as soon as it converges. The update rule is an object of
:mod:`nfarm.solvers.ik_methods` (``LM``, the default, ``DLS``, ``Pinv``, ``JT``) that carries and
checks its own options and supplies the step; ``solve(robot, T, method=LM(damping="marquardt"))``
picks one with its options, a name (``"dls"``) one with its defaults.

A 5-DOF arm cannot reach most 6-D poses. A target is ``success`` when the weighted position
and orientation errors are within ``tol_pos`` and ``tol_rot`` at a configuration within the
joint limits (each angle moved by a multiple of 2π into its range). The iterates themselves are
not clamped — clamping stalls the search against a limit far more often than it helps (on
intelbot5, 35 % of searches from the home pose instead of none) — but a search that ends outside
the limits, or stops improving, restarts from a seeded random configuration within them. When
the restarts are used up, the result holds the best (weighted least-squares closest)
configuration within the limits seen on the way, and the reason: ``joint_limits`` (the pose was
reached, but only outside the limits), ``unreachable`` (a residual no step reduces) or
``max_iter`` (still improving when the steps ran out).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..infra.arguments import check_integer, check_number
from ..model.kinematics import fk, pose_jacobian_T
from ..model.robot import Robot, sample_configurations
from ..model.rotations import relative_log_T
from .arguments import check_targets, check_weights
from .arm_class import BRANCHES, branch_of, in_class
from .ik_methods import Method, method_of

__all__ = ["IKResult", "solve", "solve_path", "REASONS"]

REASONS = ("converged", "max_iter", "unreachable", "joint_limits")
_CONVERGED, _MAX_ITER, _UNREACHABLE, _LIMITS = range(4)
_TABLE_STREAM = 0x1C7AB1E
_FIELDS = ("q", "success", "iterations", "restarts", "pos_error", "rot_error", "reason")


@dataclass(frozen=True)
class IKResult:
    """Result of :func:`solve` for a batch of targets of shape ``(...)``.

    Attributes:
        q: ``(..., n)`` joint angles [rad]: the solution, or the best configuration found.
        success: ``(...)`` whether the weighted errors are within the tolerances.
        iterations: ``(...)`` steps taken, over all attempts (attempts that ran side by side
            each count).
        restarts: ``(...)`` restarts used.
        pos_error: ``(...)`` ``‖p_target − p(q)‖`` [m].
        rot_error: ``(...)`` angle between the target and the reached orientation [rad].
        reason: ``(...)`` one of :data:`REASONS`.
        history: ``(..., K, 2)`` position and orientation error before each step (NaN after
            the target stopped), or ``None`` unless ``record_history=True``.
        branch: ``(...)`` the index in :data:`BRANCHES` of the branch ``q`` lies on, for a
            robot of the closed form's class (:func:`nfarm.solvers.ik.closed_form`); ``None`` for others.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> result = solve(robot, fk(robot, np.zeros((2, 5))))     # two targets: the home pose
        >>> result.success.tolist(), result.reason.tolist(), result.q.shape
        ([True, True], ['converged', 'converged'], (2, 5))
        >>> result.branch_name.tolist(), result.summary()["success"]
        (['front, elbow up', 'front, elbow up'], 1.0)
    """

    q: np.ndarray
    success: np.ndarray
    iterations: np.ndarray
    restarts: np.ndarray
    pos_error: np.ndarray
    rot_error: np.ndarray
    reason: np.ndarray
    history: np.ndarray | None = None
    branch: np.ndarray | None = None

    @property
    def success_rate(self) -> float:
        return float(np.mean(self.success))

    @property
    def branch_name(self) -> np.ndarray | None:
        """``(...)`` the names of :attr:`branch` (:data:`BRANCHES`), or ``None``."""
        return None if self.branch is None else np.array(BRANCHES)[self.branch]

    def summary(self) -> dict:
        """Success rate, iterations (median, 95th percentile), restarts per target, and the
        median and largest errors of the solved targets, as plain numbers."""
        ok = np.ravel(self.success)
        solved = lambda x: np.ravel(x)[ok] if ok.any() else np.full(1, np.nan)  # noqa: E731
        return {
            "success": self.success_rate,
            "median iterations": float(np.median(self.iterations)),
            "p95 iterations": float(np.percentile(self.iterations, 95)),
            "restarts per target": float(np.mean(self.restarts)),
            "median position error [m]": float(np.median(solved(self.pos_error))),
            "max position error [m]": float(np.max(solved(self.pos_error))),
            "median orientation error [rad]": float(np.median(solved(self.rot_error))),
            "max orientation error [rad]": float(np.max(solved(self.rot_error))),
        }



#: The largest table of seeded starting configurations ``solve`` draws (``guess_table``): the
#: default is 256; a million configurations of a 5-joint arm take 40 MB, 10⁹ would take 37 GiB.
MAX_GUESS_TABLE = 1_000_000

def _check_q0(robot: Robot, q0, batch: tuple, respect_limits: bool) -> np.ndarray | None:
    lo, hi = robot.qlim[:, 0], robot.qlim[:, 1]
    if q0 is None:
        return None
    if isinstance(q0, str):
        if q0 != "home":
            raise ValueError(f"q0 must be None, 'home' or joint angles, got {q0!r}")
        # The home configuration, as in the dissertation (0 moved into the limits).
        return np.broadcast_to(np.clip(0.0, lo, hi), (*batch, robot.n)).reshape(-1, robot.n)
    q0 = np.asarray(q0, dtype=float)
    if q0.shape not in ((robot.n,), (*batch, robot.n)):
        raise ValueError(f"q0 must have shape ({robot.n},) or {(*batch, robot.n)}, got {q0.shape}")
    single = q0.shape == (robot.n,)
    flat = q0.reshape(-1, robot.n)
    bad = ~np.isfinite(flat).all(axis=1)
    if respect_limits:
        bad |= ((flat < lo - 1e-12) | (flat > hi + 1e-12)).any(axis=1)
    if bad.any():
        k = int(np.argmax(bad))
        where = "q0" if single else f"q0[{', '.join(map(str, np.unravel_index(k, batch)))}]"
        raise ValueError(f"{where}: must be finite and within the joint limits, got {flat[k].tolist()}")
    return np.broadcast_to(q0, (*batch, robot.n)).reshape(-1, robot.n)


class _Seeds:
    """Starting configurations: a seeded table of ``size`` random configurations within the
    limits, ranked for each target by how near their tool poses are to it.

    Distance: ``Σ w_p Δp² + ℓ² w̄_r ‖ΔR‖²_F`` (ℓ the mean link length, so that a radian of
    orientation weighs like ℓ metres), for many targets at once through one matrix product
    ``‖a − b‖² = ‖a‖² − 2 a·b + ‖b‖²``. The nearest entry is the default initial guess; the
    next ones are the restarts: on intelbot5, an attempt from the k-th nearest entry succeeds
    more often than one from a uniformly drawn configuration (57 % against 44 % for targets
    whose first attempt failed) and in fewer steps (6.5 against 8.5).
    """

    def __init__(self, robot: Robot, T: np.ndarray, w: np.ndarray, size: int, seed: int,
                 ranks: int):
        # A stream of its own: targets drawn by a user with the same seed must not be the
        # table's entries (that would make every such target trivially solved).
        self.table = sample_configurations(robot, size, np.random.default_rng([_TABLE_STREAM, seed]))
        ell = max(float(np.abs(robot.a).sum() + np.abs(robot.d).sum()) / robot.n, 1e-3)
        self.scale = np.concatenate([np.sqrt(w[:3]), np.full(9, ell * np.sqrt(w[3:].mean()))])
        self.targets = self._features(T)
        self.entries = self._features(fk(robot, self.table))
        self.norms = (self.entries * self.entries).sum(1)
        # The `ranks` nearest entries of each target that restarts, nearest first (-1: not yet).
        self.ranks = min(ranks, size)
        self.order = np.full((T.shape[0], self.ranks), -1)

    def _features(self, poses: np.ndarray) -> np.ndarray:
        # float32: a near-nearest entry is as good a start, and the product is twice as fast.
        features = np.concatenate([poses[:, :3, 3], poses[:, :3, :3].reshape(-1, 9)], axis=1)
        return (features * self.scale).astype(np.float32)

    def _distances(self, target: np.ndarray) -> np.ndarray:
        return self.norms - 2.0 * self.targets[target] @ self.entries.T

    def nearest(self, target: np.ndarray) -> np.ndarray:
        """The nearest entry for each target: ``(len, n)``."""
        return self.table[np.argmin(self._distances(target), axis=1)]

    def ranked(self, target: np.ndarray, rank: np.ndarray) -> np.ndarray:
        """The entry of the given rank (0 = nearest, < ``ranks``) for each target: ``(len, n)``."""
        new = np.unique(target[self.order[target, 0] < 0])
        if new.size:
            d = self._distances(new)
            k = self.ranks
            part = np.argpartition(d, k - 1, axis=1)[:, :k] if k < d.shape[1] else \
                np.broadcast_to(np.arange(d.shape[1]), d.shape)
            rows = np.arange(new.size)[:, None]
            self.order[new] = part[rows, np.argsort(d[rows, part], axis=1, kind="stable")]
        return self.table[self.order[target, rank]]


def _wrap_into_limits(q: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each angle outside its limits moved by a multiple of 2π into ``[mid − π, mid + π)`` of
    its range (``q (n, A)``); returns the angles and, per target, whether all lie within."""
    lo, hi = lo[:, None], hi[:, None]
    inside = ((q >= lo) & (q <= hi)).all(axis=0)
    out = np.flatnonzero(~inside)
    if out.size == 0:
        return q, inside
    mid = 0.5 * (lo + hi)
    wrapped = mid + np.remainder(q[:, out] - mid + np.pi, 2 * np.pi) - np.pi
    q = q.copy()
    q[:, out] = wrapped
    inside[out] = ((wrapped >= lo) & (wrapped <= hi)).all(axis=0)
    return q, inside


# --------------------------------------------------------------------------------------------
# The solver


def solve(robot: Robot, T_target, q0=None, *, method: str | Method = "lm", weights=None,
          tol_pos: float = 1e-9, tol_rot: float = 1e-9, max_iter: int | None = None,
          restarts: int = 24, restart_batch: int = 16, respect_limits: bool = True,
          seed: int = 0, guess_table: int = 256, stall_rtol: float = 1e-2, stall_iters: int = 4,
          ortho_tol: float = 1e-9, record_history: bool = False, chunk: int = 8192) -> IKResult:
    """Solve ``fk(robot, q) = T_target`` for a batch of targets.

    Args:
        T_target: ``(..., 4, 4)`` target tool poses.
        q0: initial guess ``(n,)`` or ``(..., n)`` [rad]; ``"home"`` for the home
            configuration (as the dissertation); by default, per target, the nearest pose in a
            seeded table of ``guess_table`` random configurations within the limits.
        method: the update rule, :class:`LM` (default), :class:`DLS`, :class:`Pinv` or
            :class:`JT` with its options, or its name (``"lm"``, ``"dls"``, ``"pinv"``,
            ``"jt"``) for its defaults (module docstring).
        weights: 6 weights on the squared errors, position x, y, z [1/m²] then rotation x, y, z
            [1/rad²] (base axes); a zero drops that component. Default all ones.
        tol_pos, tol_rot: success thresholds on the weighted components' position [m] and
            orientation [rad] errors.
        max_iter: steps per attempt (default: the method's, 25 for LM, 50 for Pinv, 100 for
            DLS, 2000 for JT).
        restarts: attempts from random configurations after the first one fails.
        restart_batch: how many of those a target runs side by side.
        respect_limits: accept only solutions within the joint limits, and return a
            configuration within them.
        seed: seed of the restart configurations.
        stall_rtol, stall_iters: an attempt has stalled when E has not dropped by a factor
            ``1 − stall_rtol`` below its best for ``stall_iters`` steps.
        ortho_tol: largest accepted ``|RᵀR − I|`` of a target rotation.
        record_history: keep the errors of every iteration (for small batches).
        chunk: targets solved together. Memory is about 2.6 KB per target of a chunk (lanes,
            Jacobians, the seed table's distances), so the default bounds a solve to ~25 MB
            whatever the batch; each target's result does not depend on the chunk size.

    Raises:
        ValueError: a bad target, initial guess, weight vector or option; the message names
            the first bad target's index.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> q = np.array([[0.3, 0.2, -0.4, 0.5, 0.1], [0.0, 0.5, 0.5, -0.5, 0.0]])     # (2, 5) [rad]
        >>> result = solve(robot, fk(robot, q))                                       # targets (2, 4, 4)
        >>> result.success.tolist(), np.allclose(fk(robot, result.q), fk(robot, q))
        ([True, True], True)
        >>> from nfarm.solvers.ik_methods import LM
        >>> solve(robot, fk(robot, q), method=LM(damping="marquardt")).success.tolist()
        [True, True]
    """
    method = method_of(method)
    for name, value, lo, hi in (("tol_pos", tol_pos, 0, None), ("tol_rot", tol_rot, 0, None),
                                ("ortho_tol", ortho_tol, 0, 1), ("stall_rtol", stall_rtol, 0, 1)):
        check_number(name, value, lo, hi, open_lo=True)
    max_iter = method.max_iter if max_iter is None else max_iter
    for name, value, lo in (("max_iter", max_iter, 1), ("restarts", restarts, 0),
                            ("restart_batch", restart_batch, 1), ("seed", seed, 0),
                            ("guess_table", guess_table, 1), ("stall_iters", stall_iters, 1),
                            ("chunk", chunk, 1)):
        check_integer(name, value, lo)
    if guess_table > MAX_GUESS_TABLE:
        raise ValueError(f"guess_table must be at most {MAX_GUESS_TABLE:,} (a table of {guess_table:,} "
                         f"configurations would take {guess_table * robot.n * 8 / 2**30:.3g} GiB), got {guess_table}")
    T = check_targets(T_target, ortho_tol)
    batch = T.shape[:-2]
    q_start = _check_q0(robot, q0, batch, respect_limits)
    w = check_weights(weights)
    first_rank = 1 if q_start is None else 0  # the table rank of the first restart
    if restarts + first_rank > guess_table:
        raise ValueError(f"restarts ({restarts}) must be below guess_table ({guess_table})")
    T = T.reshape(-1, 4, 4)
    if T.shape[0] == 0:
        return _with_branch(robot, _empty(robot, batch, record_history))
    rules = _Rules(method, max_iter, restarts, restart_batch, respect_limits, stall_rtol, stall_iters,
                   np.array([tol_pos, tol_rot]), record_history)
    # Targets are independent: solving them in chunks bounds the memory and gives the same
    # result for each target whatever the chunk size.
    results = []
    for start in range(0, T.shape[0], chunk):
        part = slice(start, start + chunk)
        seeds = _Seeds(robot, T[part], w, guess_table, seed, restarts + first_rank)
        q_part = seeds.nearest(np.arange(seeds.targets.shape[0])) if q_start is None \
            else q_start[part]
        results.append(_Search(robot, T[part], w, rules, seeds, first_rank).run(q_part))
    return _with_branch(robot, _concatenate(results, batch, robot.n))


def _empty(robot: Robot, batch: tuple, record_history: bool) -> IKResult:
    """The result of no targets, of shape ``batch``."""
    empty = {f: np.zeros((*batch, robot.n) if f == "q" else batch,
                         dtype={"success": bool, "iterations": int, "restarts": int,
                                "reason": np.array(REASONS).dtype}.get(f, float))
             for f in _FIELDS}
    return IKResult(**empty, history=np.zeros((*batch, 0, 2)) if record_history else None)


def _with_branch(robot: Robot, result: IKResult) -> IKResult:
    """The result with the branch of each configuration, for a robot of the closed form's class."""
    if not in_class(robot):
        return result
    return dataclasses.replace(result, branch=branch_of(robot, result.q))


def _concatenate(results: list[IKResult], batch: tuple, n: int) -> IKResult:
    """The chunks' results as one result of shape ``batch``."""
    if len(results) == 1:
        r = results[0]
        history = None if r.history is None else r.history.reshape((*batch, *r.history.shape[-2:]))
        return IKResult(**{f: getattr(r, f).reshape((*batch, *getattr(r, f).shape[1:]))
                           for f in _FIELDS}, history=history)
    out = {f: np.concatenate([getattr(r, f) for r in results]) for f in _FIELDS}
    history = None
    if results[0].history is not None:
        K = max(r.history.shape[1] for r in results)
        history = np.concatenate([np.pad(r.history, ((0, 0), (0, K - r.history.shape[1]), (0, 0)),
                                         constant_values=np.nan) for r in results])
        history = history.reshape((*batch, K, 2))
    return IKResult(**{f: v.reshape((*batch, *v.shape[1:])) for f, v in out.items()},
                    history=history)


@dataclass(frozen=True)
class _Rules:
    """What a search needs besides its targets: the update rule, its budget, the stopping rules
    (tolerances ``tol = [tol_pos, tol_rot]``, stalls) and whether to keep the history."""

    method: Method
    max_iter: int
    restarts: int
    restart_batch: int
    respect_limits: bool
    stall_rtol: float
    stall_iters: int
    tol: np.ndarray
    record_history: bool


class _Search:
    """The batched search of one chunk of targets. Work is organised in *lanes*: a lane is one
    attempt at one target, and all live lanes step together. Every target starts with one lane
    from its initial guess; when a target's last lane ends without a solution, new lanes start
    from its next random configurations, 1, 2, 4, … (at most ``restart_batch``) at once, so that
    the few hard targets at the end of a batch do not need many rounds one after another.

    Each iteration: evaluate the lanes' errors and Jacobians, record the history, keep each
    target's best point, finish the solved targets, (LM) accept or reject the step, end the
    lanes that stalled or ran out of steps, step the others, and restart or stop the targets
    left without a lane."""

    def __init__(self, robot: Robot, T: np.ndarray, w: np.ndarray, rules: _Rules, seeds: _Seeds,
                 first_rank: int):
        self.robot, self.rules, self.method = robot, rules, rules.method
        self.seeds, self.first_rank = seeds, first_rank
        self.sw = np.sqrt(w)
        self.mask = w > 0
        self.unit_weights = bool((self.sw == 1).all())    # no scaling needed
        self.lo, self.hi = robot.qlim[:, 0], robot.qlim[:, 1]
        self.R_t = np.ascontiguousarray(np.moveaxis(T[:, :3, :3], 0, -1))
        self.p_t = np.ascontiguousarray(T[:, :3, 3].T)

    def run(self, q_start: np.ndarray) -> IKResult:
        """Solve from ``q_start (M, n)``; the result has shape ``(M,)``."""
        M = q_start.shape[0]
        # Per target: the best configuration so far (within the limits when they are
        # respected), how its attempts ended, and the outcome.
        self.best_q, self.best_E = np.array(q_start.T, order="C"), np.full(M, np.inf)
        self.best_err = np.full((2, M), np.inf)
        self.attempts = np.zeros(M, int)          # attempts started beyond the first
        self.live = np.ones(M, int)                # live lanes
        self.iterations = np.zeros(M, int)
        self.hit_max_iter = np.zeros(M, bool)
        self.solved_outside = np.zeros(M, bool)
        self.done = np.zeros(M, bool)
        self.reason = np.full(M, _UNREACHABLE)
        self.history = [] if self.rules.record_history else None
        self.lanes = self._new_lanes(np.arange(M), q_start.T)
        while self.lanes["target"].size:
            self._iteration()
        return self._result((M,))

    def _new_lanes(self, target, q):
        L = target.size
        lanes = dict(target=target, q=np.array(q, dtype=float).reshape(-1, L),
                     best=np.full(L, np.inf), since=np.zeros(L, int), steps=np.zeros(L, int),
                     lam=np.full(L, self.method.initial_damping()))
        if self.method.guarded:  # the last accepted point: q, E, scaled error and Jacobian
            n = lanes["q"].shape[0]
            lanes.update(acc_q=lanes["q"].copy(), acc_E=np.full(L, np.inf),
                         acc_e=np.zeros((6, L)), acc_J=np.zeros((6, n, L)))
        return lanes

    def _iteration(self):
        """One step of every live lane, each job in its method (class docstring)."""
        t = self.lanes["target"]
        es, Js, weighted, full = self._errors(self.lanes["q"], t)
        E = 0.5 * (es * es).sum(0)
        self._record(t, full)
        q, inside = self._within_limits(self.lanes["q"])
        self._keep_best(t, q, inside, E, full)
        solved = self._finish_solved(t, q, inside, weighted, full)
        if self.method.guarded:
            es, Js, E = self._accept_or_reject(es, Js, E)
        keep = self._still_going(t, E, solved)
        if not keep.all():
            es, Js, E = self._cull(t, keep, es, Js, E)
        self._step(es, Js, E)
        self._restart_or_stop()

    def _errors(self, q, target):
        """Pose error ``e (6, L)`` and Jacobian ``(6, n, L)``, both scaled by ``sqrt(weights)``,
        and per lane the position and orientation errors, of the weighted components ``(2, L)``
        and in full ``(2, L)``."""
        T, J = pose_jacobian_T(self.robot, q)
        e = np.empty((6, target.size))
        e[:3] = self.p_t[:, target] - T[:3, 3]
        e[3:] = relative_log_T(self.R_t[:, :, target], T[:3, :3])       # log(R_t Rᵀ)
        square = e * e
        full = np.sqrt(np.stack([square[:3].sum(0), square[3:].sum(0)]))
        weighted = full
        if not self.mask.all():
            square *= self.mask[:, None]
            weighted = np.sqrt(np.stack([square[:3].sum(0), square[3:].sum(0)]))
        if self.unit_weights:
            return e, J, weighted, full
        return e * self.sw[:, None], J * self.sw[:, None, None], weighted, full

    def _within_limits(self, q):
        """The lanes' angles moved by multiples of 2π into the limits, and which lanes then lie
        within them (all of them when the limits are not respected)."""
        if self.rules.respect_limits:
            return _wrap_into_limits(q, self.lo, self.hi)
        return q, np.ones(q.shape[1], bool)

    def _record(self, t, full):
        """The history: each target's smallest errors over its lanes before this step."""
        if self.history is not None:
            row = np.full((2, self.best_E.size), np.inf)
            np.minimum.at(row, (slice(None), t), full)
            self.history.append(np.where(np.isinf(row), np.nan, row))

    def _keep_best(self, t, q, inside, E, full):
        """The best point of each target (of several lanes of a target, the lowest E)."""
        eligible = np.flatnonzero(inside & (E < self.best_E[t]))
        np.minimum.at(self.best_E, t[eligible], E[eligible])
        eligible = eligible[E[eligible] == self.best_E[t[eligible]]]
        self.best_q[:, t[eligible]] = q[:, eligible]
        self.best_err[:, t[eligible]] = full[:, eligible]

    def _finish_solved(self, t, q, inside, weighted, full):
        """Targets with a lane within the tolerances (and the limits) are done; returns which
        lanes are within the tolerances."""
        solved = (weighted <= self.rules.tol[:, None]).all(axis=0)
        winners = np.flatnonzero(solved & inside)
        winners = winners[np.unique(t[winners], return_index=True)[1]]
        self.best_q[:, t[winners]], self.best_err[:, t[winners]] = q[:, winners], full[:, winners]
        self.done[t[winners]], self.reason[t[winners]] = True, _CONVERGED
        self.solved_outside[t[solved & ~inside]] = True
        return solved

    def _accept_or_reject(self, es, Js, E):
        """Accept the new point if it lowered E (damping ÷ ν), else go back to the last
        accepted point (damping × ν). Returns the error, Jacobian and E to step from."""
        lanes = self.lanes
        accept = E < lanes["acc_E"]
        lanes["lam"] = self.method.adapt(lanes["lam"], accept)
        # The fresh arrays become the accepted ones, with the old values put back where the
        # step was rejected (usually few lanes).
        r = np.flatnonzero(~accept)
        if r.size:
            lanes["q"][:, r] = lanes["acc_q"][:, r]
            es[:, r], Js[:, :, r], E[r] = lanes["acc_e"][:, r], lanes["acc_J"][:, :, r], lanes["acc_E"][r]
        lanes["acc_q"], lanes["acc_E"], lanes["acc_e"], lanes["acc_J"] = lanes["q"].copy(), E, es, Js
        return es, Js, E

    def _still_going(self, t, E, solved):
        """Which lanes step again: not solved, not stalled (E not below its best by the factor
        ``1 − stall_rtol`` for ``stall_iters`` steps), not out of steps, target not done."""
        lanes, rules = self.lanes, self.rules
        improved = E < lanes["best"] * (1.0 - rules.stall_rtol)
        lanes["best"] = np.where(improved, E, lanes["best"])
        lanes["since"] = np.where(improved, 0, lanes["since"] + 1)
        stalled = (lanes["since"] >= rules.stall_iters) & ~solved
        out_of_steps = (lanes["steps"] >= rules.max_iter) & ~solved & ~stalled
        self.hit_max_iter[t[out_of_steps]] = True
        return ~solved & ~stalled & ~out_of_steps & ~self.done[t]

    def _step(self, es, Js, E):
        """Move every live lane by its method's step, and count the step for its target (lanes
        side by side each count)."""
        lanes = self.lanes
        lanes["q"] += self.method.step(Js, es, E, lanes["lam"])
        lanes["steps"] += 1
        np.add.at(self.iterations, lanes["target"], 1)

    def _cull(self, t, keep, es, Js, E):
        """Drop the lanes that ended; returns the kept lanes' error, Jacobian and E."""
        np.subtract.at(self.live, t[~keep], 1)
        g = np.flatnonzero(keep)
        for key, value in self.lanes.items():
            self.lanes[key] = value[..., g]
        return es[:, g], Js[:, :, g], E[g]

    def _restart_or_stop(self):
        """Targets with no live lane: start their next batch of attempts, or stop them."""
        idle = np.flatnonzero((self.live == 0) & ~self.done)
        left = self.rules.restarts - self.attempts[idle]
        stop = idle[left == 0]
        self.done[stop] = True
        self.reason[stop] = np.where(self.solved_outside[stop], _LIMITS,
                                     np.where(self.hit_max_iter[stop], _MAX_ITER, _UNREACHABLE))
        # Rounds of 1, 2, 4, … lanes (at most restart_batch): cheap for the many targets that
        # need one more try, parallel for the few that need many.
        again = idle[left > 0]
        count = np.minimum(left[left > 0], np.minimum(self.rules.restart_batch, self.attempts[again] + 1))
        if again.size == 0:
            return
        target = np.repeat(again, count)
        attempt = self.attempts[target] + np.arange(target.size) - np.repeat(np.cumsum(count) - count, count)
        self.attempts[again] += count
        self.live[again] += count
        q = self.seeds.ranked(target, attempt + self.first_rank)
        new = self._new_lanes(target, q.T)
        self.lanes = {key: np.concatenate([value, new[key]], axis=-1)
                      for key, value in self.lanes.items()}

    def _result(self, batch: tuple) -> IKResult:
        n = self.best_q.shape[0]
        history = None
        if self.history is not None:
            history = np.stack(self.history, axis=-1).transpose(1, 2, 0).reshape(*batch, -1, 2)
        return IKResult(
            q=self.best_q.T.reshape(*batch, n).copy(),
            success=(self.reason == _CONVERGED).reshape(batch),
            iterations=self.iterations.reshape(batch),
            restarts=self.attempts.reshape(batch),
            pos_error=self.best_err[0].reshape(batch),
            rot_error=self.best_err[1].reshape(batch),
            reason=np.array(REASONS)[self.reason].reshape(batch),
            history=history,
        )


def solve_path(robot: Robot, T_path, q0, **options) -> IKResult:
    """Solve a sequence of poses ``T_path (K, 4, 4)`` one after another, each from the previous
    solution (the first from ``q0 (n,)``), so that the joint path stays on one branch.

    ``options`` are those of :func:`solve` (restarts default to 0 here: a restart would jump
    to another branch). Returns the results stacked along the path, shapes ``(K, ...)``.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> q_path = np.linspace(np.zeros(5), [0.3, 0.2, -0.4, 0.5, 0.1], 5)     # (K, n) [rad]
        >>> result = solve_path(robot, fk(robot, q_path), np.zeros(5))
        >>> result.q.shape, bool(result.success.all()), np.allclose(result.q, q_path)
        ((5, 5), True, True)
    """
    options = {"restarts": 0, **options}
    T_path = check_targets(T_path, options.get("ortho_tol", 1e-9))
    if T_path.ndim != 3:
        raise ValueError(f"T_path must have shape (K, 4, 4), got {T_path.shape}")
    results, q = [], np.asarray(q0, dtype=float)
    for T in T_path:
        result = solve(robot, T, q, **options)
        results.append(result)
        q = result.q
    return _with_branch(robot, IKResult(**{f: np.stack([getattr(r, f) for r in results])
                                           for f in _FIELDS}))

