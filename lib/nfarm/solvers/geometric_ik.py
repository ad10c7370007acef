"""Geometric inverse kinematics: every solution of every pose in closed form, batched.

Use it as :func:`nfarm.solvers.ik.closed_form`. It is the exact reference of the study: where LM finds
one solution from one start, the closed form gives all of them, with nothing to converge.
Which robots it solves and which branch a configuration lies on are in :mod:`.arm_class`
(re-exported here); the refinement uses the iterative solver of :mod:`.iterative`.

**The class.** Five revolute joints: a base joint ("yaw"), three joints about parallel axes
("pitch": joints 2, 3, 4) and a last joint ("roll") not parallel to them. In standard DH terms
(a modified-DH table is first rewritten as the standard chain it equals)::

    sin α2 = sin α3 = 0 (within axis_tol),   sin α1 ≠ 0,   sin β ≠ 0 with β = α2 + α3 + α4,
    a2 ≠ 0, a3 ≠ 0 (two links between the three pitch axes).

Every other number is free and enters the formulas as it is: a1 and d1 (the SO-101's shoulder
offset), the lateral offsets d2, d3, d4, a4, a roll axis not exactly perpendicular to the
pitch axes (the SO-101's α4 is −1.5708, 3.7e-6 rad off −π/2), a5 and d5 (a tool point off the
roll axis: the SO-101's 7.9 mm), the joint offsets, the base and the tool. Any other robot is
refused in one line saying which condition it breaks (:func:`check_class`).

**Near the class.** A robot whose pitch axes are a little off parallel (α2 or α3 within
:data:`~nfarm.solvers.arm_class.NEAR_TOL` of 0 or π, or small fixed transforms after its rows,
:class:`~nfarm.model.robot.Robot`'s ``fixed``: a URDF written with a rounded π puts them 7e-6
rad apart) is solved through the parallel arm: every branch of it seeds Levenberg–Marquardt on
the arm itself (the refinement below, for every target), so each branch is found on the arm
as it is (``refined`` set). Further off, the robot is refused as outside the class.

**Derivation** (θ̄ = q + offset; u(φ) = (cos φ, sin φ); σ2 = cos α2, σ = cos α2 cos α3, both
±1; ``Rx(π) Rz(θ) = Rz(−θ) Rx(π)``). The three pitch joints act in the plane of frame 1::

    R_14 = Rz(Φ) Rx(β),   Φ = θ̄2 + γ + σ θ̄4,   γ = σ2 θ̄3,
    o_4 in frame 1 = (a2 u(θ̄2) + a3 u(θ̄2 + γ) + a4 u(Φ),  w),   w = d2 + σ2 d3 + σ d4.

1. *Wrist point and roll axis*, from the target alone: with ``T_05 = base⁻¹ T tool⁻¹ = (R, p)``
   and ``M = R Rx(−α5)``, the wrist point is ``p4 = p − M (a5, 0, d5)`` and the roll axis
   ``z4 = M e_z`` (joint 5 turns about z4 and moves neither).
2. *Base*: the pitch axis ``z1(θ̄1)`` must lie at the lateral offset w from the wrist point and at
   the angle β from the roll axis::

       z1 · (p4 − o1) = w,     z1 · z4 = cos β,

   each of the form ``A sin θ̄1 − B cos θ̄1 = C``, solved by
   ``θ̄1 = atan2(B, A) + atan2(C, ±√(A² + B² − C²))``. The two roots of the first are the base
   branches, *front* and *back* (the wrist point on the side of the base axis it is on at the
   arm's home, q = 0 within the limits, or on the other: ahead along x1 on both arms of the
   study; a URDF's converted frame 0 may face backwards). A target in the arm's pose set satisfies both. Where the first is ill-conditioned (its
   square root small: the wrist point near the base axis, its error growing as 1/√) the roots
   of the second are taken instead, the one nearest to a root of the first for that root's
   branch and the other for the other branch. With w ≠ 0 the back branch reaches a target
   only when the roll axis is parallel to the base axis: the SO-101 (w = −0.18 mm) has two
   solutions per pose elsewhere. Four need w = 0 and both conditions symmetric under a half
   turn of the base (cos α1 = cos β = 0), as on intelbot5 (joint limits aside).
3. *Wrist angles*: ``G = R_1ᵀ M = Rz(Φ) Rx(β) Rz(θ̄5)``, a ZXZ decomposition whose middle angle
   is fixed: ``Φ = atan2(s G02, −s G12)``, ``θ̄5 = atan2(s G20, s G21)``, s = sign(sin β).
4. *Planar two-link*: ``(X, Y, Z) = R_1ᵀ (p4 − o1)``, ``Q = (X, Y) − a4 u(Φ)``; with
   k = sign(a2 a3), the elbow ``γ = ±2 atan2(√(k((a2 + a3)² − |Q|²)), √(k(|Q|² − (a2 − a3)²)))``
   (the half-angle form: accurate where acos of the cosine law loses half the digits, at the
   stretched and folded arm), ``θ̄2 = atan2(Qy, Qx) − atan2(a3 sin γ, a2 + a3 cos γ)`` and
   ``θ̄4 = σ (Φ − θ̄2 − γ)``.

The branches: front and back, each with the elbow up and down (:data:`BRANCHES`). "Up" is the
elbow above the line from the shoulder's axis to the wrist-pitch axis, up meaning against gravity (the base's z axis
when gravity is zero), for a wrist ahead of the shoulder; the back branch mirrors it. The label
takes the up-component of the arm's plane from the base axis, so it is exact for a base axis
along gravity (both arms of the study) and a convention for a tilted one; it holds for links
of either sign (the elbow's side is that of −a2 a3 sin γ).

**Errors in closed form.** Nothing here calls forward kinematics: the reached pose differs from
the target only where a sub-problem had no exact solution, and each difference is computed
from the sub-problems: the orientation error is the angle of ``G'ᵀ G`` (G' the decomposition's
rotation), ``|β' − β|`` with ``cos β' = G22``; the position error is
``|(Q − Q', Z − w) + (G − G') v|`` (Q' the point the two links reach, v the tool point from the
wrist point, ``(a5, 0, d5) + Rx(α5) p_tool``). The tests check both against
:func:`nfarm.model.kinematics.fk` and Pinocchio. Why not call fk: its four branches would cost about
twice the whole closed form (0.5 µs per configuration against 0.8 µs per pose on one core,
measured on this project's machines; ``benchmarks/bench_ik_closed_form.py``).

**Speed.** Everything is NumPy on component arrays (one array per matrix entry, targets last),
in chunks of 32 768 targets solved side by side in threads (NumPy releases the GIL in its
loops); half of the time is ``arctan2``, ten per pose, the least the four branches need.

**Numerics.** The arguments of the square roots are clipped at 0. A clip by rounding (a target
on the boundary of the workspace, a stretched or folded arm) leaves an error at rounding level;
a larger one means the sub-problem had no solution, and the branch holds the nearest point of
that sub-problem, its error in ``pos_error`` and the branch invalid. Where an angle is
undetermined (the wrist point on the base axis with the roll axis along it; the wrist point on
the shoulder axis of a two-link with a2 = ±a3) the family of solutions is represented by one
member. No NaN is produced for targets within 1e150 m of the base (squares of positions
overflow beyond). Angles are wrapped to within π of the middle of their range: a range wider
than 2π holds further copies of a solution, which are not listed.

**Targets outside the pose set.** A 5-DOF arm reaches a 5-dimensional set of poses. For a target
that no branch reaches (to ``tol_pos`` and ``tol_rot``), each branch is refined by
Levenberg–Marquardt (:func:`nfarm.solvers.ik.solve`, joint limits ignored) from its closed-form point
to the nearest pose in the weighted least-squares sense LM minimises, ``½ Σ w_i e_i²`` over the
pose error ``e`` of :func:`nfarm.model.rotations.pose_error`; ``pos_error`` and ``rot_error`` are then
the residual of each branch, by :func:`nfarm.model.kinematics.fk`, and ``refined`` is set.
:meth:`ClosedFormResult.nearest` gives each target's nearest pose and its residual. A refinement
may converge to another branch's solution, so for such targets the columns are the four
refinements' results, named by the branch each started from. Measured on targets turned and
moved off the pose set (up to 20° and 1 cm), the best branch's residual is never above that of
LM with 25 starts (equal to 1e-8 relative, or lower where LM's starts missed the nearest
pose; ``tests/test_geometric_ik.py``).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from ..infra.arguments import check_integer, check_number
from ..model.kinematics import fk
from ..model.robot import Robot, joint_array
from ..model.rotations import pose_error
from .arguments import check_targets, check_weights
from .arm_class import BRANCHES, ArmConstants, branch_of, check_class, class_refusal, in_class
from .iterative import solve

__all__ = ["BRANCHES", "ArmConstants", "ClosedFormResult", "closed_form", "check_class", "in_class", "class_refusal",
           "branch_of", "branch_margins", "planar_points", "elbow_meeting_angles", "count_distinct",
           "wrapped_gap"]

_CHUNK = 32768


@dataclass(frozen=True)
class ClosedFormResult:
    """Result of :func:`closed_form` for targets of batch shape ``(...)``; ``k = 4`` branches
    in the order of :data:`BRANCHES`.

    Attributes:
        q: ``(..., k, n)`` joint angles [rad] of every branch, each angle moved by a multiple
            of 2π to within π of the middle of its range (for a ``refined`` target: the
            refinement started from that branch, which may end on another).
        valid: ``(..., k)`` the branch reaches the target (``reaches``) within the joint
            limits (``within_limits``).
        reaches: ``(..., k)`` position and orientation errors within ``tol_pos``, ``tol_rot``.
        within_limits: ``(..., k)`` every angle within its limits.
        pos_error: ``(..., k)`` ``‖p_target − p(q)‖`` [m].
        rot_error: ``(..., k)`` the angle between the target's and the reached orientation
            [rad].
        refined: ``(...)`` the target is outside the pose set, and every branch was refined to
            its nearest pose (module docstring).
        branches: the names of the branches.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> result = closed_form(robot, fk(robot, [0.3, 0.2, -0.4, 0.5, 0.1]))
        >>> result.reaches.tolist(), result.valid.tolist()     # four solutions, one within the limits
        ([True, True, True, True], [True, False, False, False])
        >>> int(result.count()), result.branches[result.best()], result.nearest()[0].round(6).tolist()
        (1, 'front, elbow up', [0.3, 0.2, -0.4, 0.5, 0.1])
    """

    q: np.ndarray
    valid: np.ndarray
    reaches: np.ndarray
    within_limits: np.ndarray
    pos_error: np.ndarray
    rot_error: np.ndarray
    refined: np.ndarray
    branches: tuple[str, ...] = BRANCHES

    @property
    def in_pose_set(self) -> np.ndarray:
        """``(...)`` some branch reaches the target (joint limits aside)."""
        return self.reaches.any(axis=-1)

    def count(self, distinct: float = 1e-6) -> np.ndarray:
        """``(...)`` the number of distinct valid solutions (:func:`count_distinct`): branches
        coincide at singular poses (a stretched elbow)."""
        return count_distinct(self.q, self.valid, distinct)

    def best(self, weights=None) -> np.ndarray:
        """``(...)`` the index of the branch to take: a valid one if any (the first in
        :data:`BRANCHES` order), else the one with the least ``w_p e_p² + w_r e_r²`` (``e_p``,
        ``e_r`` the position and orientation error norms, ``w_p``, ``w_r`` the means of the
        position and rotation ``weights`` of :func:`nfarm.solvers.ik.solve`)."""
        w = check_weights(weights)
        cost = w[:3].mean() * self.pos_error ** 2 + w[3:].mean() * self.rot_error ** 2
        cost = np.where(self.valid, -1.0, cost)
        return np.argmin(cost, axis=-1)

    def nearest(self, weights=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The configuration ``(..., n)`` [rad] of the branch :meth:`best` picks, and its
        position and orientation residual ``(...)`` [m], [rad]: for a target outside the pose
        set, the nearest pose the arm reaches (of the four refinements, the one :meth:`best`
        picks) and how far it is."""
        k = self.best(weights)[..., None]
        return (np.take_along_axis(self.q, k[..., None], axis=-2)[..., 0, :],
                np.take_along_axis(self.pos_error, k, axis=-1)[..., 0],
                np.take_along_axis(self.rot_error, k, axis=-1)[..., 0])


def wrapped_gap(x: np.ndarray) -> np.ndarray:
    """``|x|`` of angle differences [rad] with multiples of 2π taken out: in ``[0, π]``.

    Example:
        >>> wrapped_gap(np.array([0.1, 2 * np.pi - 0.1, -4.0])).round(6).tolist()     # [rad]
        [0.1, 0.1, 2.283185]
        >>> a, b = np.array([0.1, 3.1]), np.array([2 * np.pi, -3.1])     # angles [rad]
        >>> wrapped_gap(a - b).round(6).tolist()                           # 3.1 and -3.1 are 0.08 apart
        [0.1, 0.083185]
    """
    return np.abs(np.remainder(x + np.pi, 2 * np.pi) - np.pi)


def count_distinct(q: np.ndarray, ok: np.ndarray, distinct: float = 1e-6) -> np.ndarray:
    """``(...)`` how many of the configurations ``q (..., k, n)`` marked ``ok (..., k)`` are
    distinct: each counts unless an earlier one marked ``ok`` lies within ``distinct`` [rad]
    in every joint, angles 2π apart being the same (rounding to a grid instead would split
    one solution across a cell boundary and count it twice).

    Example:
        >>> q = np.array([[0.0, 0.0], [2 * np.pi, 1e-9], [0.0, 1.0]])     # (k, n): the first two are one
        >>> int(count_distinct(q, np.array([True, True, True])))
        2
        >>> int(count_distinct(q, np.array([True, True, False])))
        1
    """
    apart = (wrapped_gap(q[..., :, None, :] - q[..., None, :, :]) > distinct).any(-1)
    k = q.shape[-2]
    earlier = np.tril(np.ones((k, k), bool), -1)                          # j < i
    repeat = (~apart & earlier & ok[..., None, :]).any(-1)
    return (ok & ~repeat).sum(-1)


# --------------------------------------------------------------------------------------------
# The closed form on a chunk of targets (component layout, samples last)


def _solve_chunk(g: ArmConstants, T: np.ndarray):
    """``T (m, 4, 4)`` → the joint angles ``q1, q5 (2, m)`` (base branch, target) and
    ``q2, q3, q4 (2, 2, m)`` (base branch, elbow column, target), and per base branch the
    errors ``(2, m)`` [m], [rad]: the steps of the module docstring, one function each."""
    target = _target_in_base(g, T)
    t1, c1, s1 = _base_angles(g, target)
    wrist = _wrist_angles(g, target, c1, s1)
    link = _two_link(g, target, c1, s1, wrist)
    pos_error, rot_error = _errors(g, wrist, link)
    return _joint_angles(g, t1, wrist, link), pos_error, rot_error


@dataclass(frozen=True)
class _Target:
    """Step 1 on m targets, in the frame of the base joint (the base taken out): the roll
    frame's rotation ``M = R Rx(−α5)`` (3 × 3 entries, each ``(m,)``; its column 2 the roll
    axis z4) and the wrist point ``(px, py)`` and ``pz1`` (its height above d1) [m]."""

    M: list
    px: np.ndarray
    py: np.ndarray
    pz1: np.ndarray


def _target_in_base(g: ArmConstants, T: np.ndarray) -> _Target:
    """Step 1: the wrist point and the roll frame of targets ``T (m, 4, 4)``. Component layout:
    one transposed copy, then 3 × 3 products entry by entry (a batched ``(m, 3, 3) @ (3, 3)``
    matmul costs five times as much)."""
    flat = T.reshape(-1, 16).T.copy()                                      # (16, m)
    R = [[flat[4 * i + j] for j in range(3)] for i in range(3)]
    p = [flat[4 * i + 3] - g.pb[i] for i in range(3)]
    if g.RbT is None:
        M = R
    else:
        RC = _product(R, g.C)
        M = _product(g.RbT, RC)
    Rc0 = [_dot(R[i], g.c0) for i in range(3)]
    p = [p[i] - Rc0[i] for i in range(3)]
    px, py, pz = p if g.RbT is None else [_dot(p, g.RbT[i]) for i in range(3)]
    return _Target(M, px, py, pz - g.d1)


def _base_angles(g: ArmConstants, target: _Target) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Step 2: θ̄1 ``(2, m)`` [rad] of the front and back branches and its cos and sin: both
    roots of the position condition, the orientation condition's where the position's is weak
    (its square root small) or undetermined (the wrist point on the base axis)."""
    sa, ca = g.sa1, g.ca1
    px, py, pz1 = target.px, target.py, target.pz1
    Ap, Bp, Cp = sa * px, sa * py, g.w - ca * pz1
    hp = np.sqrt(np.maximum(Ap * Ap + Bp * Bp - Cp * Cp, 0.0))
    front = math.copysign(1.0, sa) * g.forward        # the root whose wrist is in front first
    root = np.stack([front * hp, -front * hp])                             # ±√ of each root
    # cos, sin of θ̄1 = φ + ψ by the angle sum (cos φ = A/ρ, cos ψ = ±h/ρ, sin ψ = C/ρ).
    with np.errstate(invalid="ignore", divide="ignore"):
        inv = 1.0 / (np.sqrt(Ap * Ap + Bp * Bp) * np.sqrt(hp * hp + Cp * Cp))  # 1/ρ² unclipped
        c1, s1 = (Ap * root - Bp * Cp) * inv, (Bp * root + Ap * Cp) * inv   # NaN where ρ = 0
    t1 = np.arctan2(s1, c1)
    bad = np.flatnonzero(~np.isfinite(inv))                 # ρ = 0: the wrist point on the axis
    if bad.size:
        t1[:, bad] = np.arctan2(Bp[bad], Ap[bad]) + np.arctan2(Cp[bad], root[:, bad])
    z4x, z4y, z4z = target.M[0][2], target.M[1][2], target.M[2][2]
    Ao, Bo, Co = sa * z4x, sa * z4y, g.cb - ca * z4z
    ho = np.sqrt(np.maximum(Ao * Ao + Bo * Bo - Co * Co, 0.0))
    # The position root's error grows as reach/hp, the orientation root's as 1/ho: switch only
    # where the position root is a hundred times the worse (its θ̄1 error is then ~1e-14 rad).
    weak = np.flatnonzero(hp < 1e-2 * g.reach * ho)
    if weak.size:
        phio = np.arctan2(Bo[weak], Ao[weak])
        roots = np.stack([phio + np.arctan2(Co[weak], ho[weak]),
                          phio + np.arctan2(Co[weak], -ho[weak])])           # (2, k)
        # The closest pair of an orientation root and a position root is matched (for a target
        # in the pose set they coincide), the other orientation root goes to the other branch.
        gap = lambda x, y: np.abs(np.remainder(x - y + np.pi, 2 * np.pi) - np.pi)  # noqa: E731
        keep = (np.minimum(gap(roots[0], t1[0, weak]), gap(roots[1], t1[1, weak]))
                <= np.minimum(gap(roots[1], t1[0, weak]), gap(roots[0], t1[1, weak])))
        t1[0, weak], t1[1, weak] = np.where(keep, roots[0], roots[1]), np.where(keep, roots[1], roots[0])
    if weak.size or bad.size:
        redo = np.union1d(weak, bad)
        c1[:, redo], s1[:, redo] = np.cos(t1[:, redo]), np.sin(t1[:, redo])
    return t1, c1, s1


class _WristRotation:
    """``G = R_1ᵀ M`` of both base branches (rows x1ᵀM, y1ᵀM, z1ᵀM), entry ``(i, j)`` as
    asked, ``(2, m)``, each computed once."""

    def __init__(self, g: ArmConstants, M: list, c1: np.ndarray, s1: np.ndarray):
        self.g, self.M, self.c1, self.s1 = g, M, c1, s1
        self.entries: dict[tuple[int, int], np.ndarray] = {}

    def __call__(self, i: int, j: int) -> np.ndarray:
        if (i, j) not in self.entries:
            self.entries[i, j] = self._entry(i, j)
        return self.entries[i, j]

    def _entry(self, i: int, j: int) -> np.ndarray:
        c1, s1, sa, ca = self.c1, self.s1, self.g.sa1, self.g.ca1
        mx, my, mz = self.M[0][j], self.M[1][j], self.M[2][j]
        if i == 0:
            return c1 * mx + s1 * my
        if i == 1:
            return ca * (c1 * my - s1 * mx) + sa * mz if ca else sa * mz
        return sa * (s1 * mx - c1 * my) + ca * mz if ca else sa * (s1 * mx - c1 * my)


@dataclass(frozen=True)
class _Wrist:
    """Step 3 per base branch ``(2, m)``: ``G = Rz(Φ) Rx(β) Rz(θ̄5)`` decomposed: ``Phi`` (Φ)
    and ``t5`` (θ̄5) [rad] with their cos and sin, ``n = |(G02, G12)|`` (sin β' up to sign)."""

    G: _WristRotation
    Phi: np.ndarray
    t5: np.ndarray
    cP: np.ndarray
    sP: np.ndarray
    c5: np.ndarray
    s5: np.ndarray
    n: np.ndarray


def _wrist_angles(g: ArmConstants, target: _Target, c1: np.ndarray, s1: np.ndarray) -> _Wrist:
    """Step 3: the ZXZ decomposition of ``G = R_1ᵀ M`` whose middle angle is β."""
    G = _WristRotation(g, target.M, c1, s1)
    G02, G12, G20, G21 = G(0, 2), G(1, 2), G(2, 0), G(2, 1)
    s = g.s
    Phi = np.arctan2(s * G02, -s * G12)
    t5 = np.arctan2(s * G20, s * G21)
    cP, sP, n = _cos_sin(Phi, -s * G12, s * G02)
    c5, s5, _ = _cos_sin(t5, s * G21, s * G20)
    return _Wrist(G, Phi, t5, cP, sP, c5, s5, n)


@dataclass(frozen=True)
class _TwoLink:
    """Step 4 per base branch ``(2, m)``: the wrist-pitch point ``Q = (Qx, Qy)`` [m] in the
    arm's plane (``r2 = |Q|²``) and ``Z`` across it, the elbow angle ``gamma`` (γ ≥ 0) [rad]
    with its cos ``cg`` and sin ``sg``, the direction ``psi`` of Q and the shoulder's angle
    ``delta`` from it [rad]."""

    Qx: np.ndarray
    Qy: np.ndarray
    r2: np.ndarray
    Z: np.ndarray
    gamma: np.ndarray
    cg: np.ndarray
    sg: np.ndarray
    psi: np.ndarray
    delta: np.ndarray


def _two_link(g: ArmConstants, target: _Target, c1: np.ndarray, s1: np.ndarray, wrist: _Wrist) -> _TwoLink:
    """Step 4: the planar two-link, by the half-angle form of the elbow."""
    sa, ca = g.sa1, g.ca1
    px, py, pz1 = target.px, target.py, target.pz1
    X = c1 * px + s1 * py - g.a1
    Y = ca * (c1 * py - s1 * px) + sa * pz1
    Z = sa * (s1 * px - c1 * py) + ca * pz1
    Qx, Qy = X - g.a4 * wrist.cP, Y - g.a4 * wrist.sP
    r2 = Qx * Qx + Qy * Qy
    a2, a3 = g.a2, g.a3
    k = math.copysign(1.0, a2 * a3)
    far = np.sqrt(np.maximum(k * ((a2 + a3) ** 2 - r2), 0.0))
    near = np.sqrt(np.maximum(k * (r2 - (a2 - a3) ** 2), 0.0))
    with np.errstate(divide="ignore"):
        gamma = 2.0 * np.arctan(far / near)     # = 2 atan2(far, near) ≥ 0, far/near = inf → π
    inv = 1.0 / (far * far + near * near)      # > 0: far and near are not both clipped
    cg, sg = (near * near - far * far) * inv, 2.0 * far * near * inv
    psi = np.arctan2(Qy, Qx)
    delta = np.arctan2(a3 * sg, a2 + a3 * cg)
    return _TwoLink(Qx, Qy, r2, Z, gamma, cg, sg, psi, delta)


def _errors(g: ArmConstants, wrist: _Wrist, link: _TwoLink) -> tuple[np.ndarray, np.ndarray]:
    """The position [m] and orientation [rad] errors ``(2, m)`` of each base branch (module
    docstring): from the point the links reach and ``G' = Rz(Φ) Rx(β) Rz(θ̄5)``."""
    G, cP, sP, c5, s5, n = wrist.G, wrist.cP, wrist.sP, wrist.c5, wrist.s5, wrist.n
    a2, a3 = g.a2, g.a3
    rQ = np.sqrt(link.r2)
    reached = np.sqrt(np.maximum(a2 * a2 + a3 * a3 + 2 * a2 * a3 * link.cg, 0.0))
    short = rQ - reached
    ux, uy, _ = _cos_sin(link.psi, link.Qx, link.Qy)        # the direction of Q (u(ψ) at Q = 0)
    sb, cb = g.sb, g.cb
    ex, ey, ez = short * ux, short * uy, link.Z - g.w
    if g.v[0]:                                  # (G − G')[:, j] v_j, G' column by column
        ex = ex + g.v[0] * (G(0, 0) - (cP * c5 - sP * cb * s5))
        ey = ey + g.v[0] * (G(1, 0) - (sP * c5 + cP * cb * s5))
        ez = ez + g.v[0] * (G(2, 0) - sb * s5)
    if g.v[1]:
        ex = ex + g.v[1] * (G(0, 1) + cP * s5 + sP * cb * c5)
        ey = ey + g.v[1] * (G(1, 1) + sP * s5 - cP * cb * c5)
        ez = ez + g.v[1] * (G(2, 1) - sb * c5)
    if g.v[2]:
        ex = ex + g.v[2] * (G(0, 2) - sb * sP)
        ey = ey + g.v[2] * (G(1, 2) + sb * cP)
        ez = ez + g.v[2] * (G(2, 2) - cb)
    pos_error = np.sqrt(ex * ex + ey * ey + ez * ez)
    # G = Rz(Φ) Rx(β') Rz(θ̄5) with cos β' = G22, sin β' = s·n: G'ᵀG = Rz(−θ̄5) Rx(β' − β) Rz(θ̄5),
    # an angle of |β' − β|.
    G22 = G(2, 2)
    rot_error = np.abs(np.arcsin(np.clip(n * cb - G22 * abs(sb), -1.0, 1.0)))
    behind = G22 * cb + n * abs(sb) < 0                     # |β' − β| > π/2 (rare)
    if behind.any():
        rot_error[behind] = np.pi - rot_error[behind]
    return pos_error, rot_error


def _joint_angles(g: ArmConstants, t1: np.ndarray, wrist: _Wrist, link: _TwoLink) -> tuple:
    """The joint angles [rad], offsets taken out: ``q1, q5 (2, m)`` and ``q2, q3, q4 (2, 2, m)``
    with elbow column 0 "up" (module docstring), 1 "down"."""
    e_up = np.array([-g.elbow_up, g.elbow_up])[:, None, None] * np.array([g.forward, -g.forward])[:, None]
    gam = e_up * link.gamma[:, None, :]
    q2 = link.psi[:, None, :] - e_up * link.delta[:, None, :]
    q4 = g.sigma * (wrist.Phi[:, None, :] - q2 - gam)
    o = g.offset
    return (t1 - o[0], q2 - o[1], g.sigma2 * gam - o[2], q4 - o[3], wrist.t5 - o[4])


def _dot(row: list, coefficients: np.ndarray):
    """``Σ_k row[k] · c_k`` over component arrays, zero coefficients skipped."""
    terms = [x * c for x, c in zip(row, coefficients) if c]
    return sum(terms[1:], terms[0]) if terms else np.zeros_like(row[0])


def _product(A, B):
    """The 3 × 3 product of ``A`` and ``B``, one of them constant (an array) and the other
    given entry by entry (lists of component arrays)."""
    if isinstance(A, np.ndarray):
        return [[_dot([B[j][k] for j in range(3)], A[i]) for k in range(3)] for i in range(3)]
    return [[_dot(A[i], B[:, k]) for k in range(3)] for i in range(3)]


def _cos_sin(angle: np.ndarray, x: np.ndarray, y: np.ndarray):
    """cos and sin of ``angle = atan2(y, x)`` as ``x/r, y/r`` (no trigonometry), and by
    ``np.cos``/``np.sin`` where ``r = 0``; and ``r``."""
    r = np.sqrt(x * x + y * y)
    zero = r == 0
    with np.errstate(invalid="ignore", divide="ignore"):
        c, s = x / r, y / r
    if zero.any():
        c[zero], s[zero] = np.cos(angle[zero]), np.sin(angle[zero])
    return c, s, r


def _wrap_joint(x: np.ndarray, lo: float, hi: float, limit_tol: float) -> np.ndarray:
    """Angles ``x`` of one joint moved by multiples of 2π into ``[mid − π, mid + π]`` of its
    range, those within ``limit_tol`` outside a limit onto it (in place); returns whether each
    lies within."""
    mid = 0.5 * (lo + hi)
    x -= (2 * np.pi) * np.rint((x - mid) * (0.5 / np.pi))
    inside = (x >= lo - limit_tol) & (x <= hi + limit_tol)
    np.copyto(x, lo, where=inside & (x < lo))
    np.copyto(x, hi, where=inside & (x > hi))
    return inside


#: The farthest target the closed form takes [m from the base, per coordinate]: within it no NaN
#: is produced (the squares of positions stay finite, module docstring); beyond it no arm reaches.
MAX_TARGET_DISTANCE = 1e150


def closed_form(robot: Robot, T_target, *, tol_pos: float = 1e-9, tol_rot: float = 1e-9,
                weights=None, refine: bool = True, refine_iter: int = 200,
                axis_tol: float = 1e-10, limit_tol: float = 1e-12, ortho_tol: float = 1e-9,
                threads: int | None = None) -> ClosedFormResult:
    """Every inverse-kinematics solution of every target, in closed form (module docstring).

    Args:
        T_target: ``(..., 4, 4)`` target tool poses (world frame).
        tol_pos, tol_rot: a branch reaches its target when its position error [m] and
            orientation error [rad] are within these.
        weights: 6 weights on the squared errors (as :func:`nfarm.solvers.ik.solve`): the sense of
            "nearest pose" for targets outside the pose set.
        refine: refine every branch of a target outside the pose set to its nearest pose
            (LM: four solves of some tens of µs each per such target); without it such a
            target keeps the closed form's projection.
        refine_iter: LM steps for that refinement.
        axis_tol: see :func:`check_class`.
        limit_tol: an angle this close [rad] outside its limit counts as within and is moved
            onto it (rounding of an angle sampled at its limit).
        ortho_tol: largest accepted ``|RᵀR − I|`` of a target rotation.
        threads: chunks of 32 768 targets solved side by side (default: the CPUs this process
            may use, at most 8); NumPy releases the GIL in its loops. The result does not
            depend on it.

    Returns:
        :class:`ClosedFormResult`, ``q`` of shape ``(..., 4, 5)``.

    Raises:
        ValueError: the robot is not of the class, a bad target (shape, NaN, last row,
            rotation) or a bad option; one line naming it.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> result = closed_form(robot, fk(robot, np.zeros((3, 5))))     # targets (3, 4, 4)
        >>> result.q.shape, result.valid.shape                             # (..., 4 branches, n)
        ((3, 4, 5), (3, 4))
        >>> np.allclose(fk(robot, result.q[result.valid]), fk(robot, np.zeros(5)))
        True
    """
    for name, value in (("tol_pos", tol_pos), ("tol_rot", tol_rot), ("axis_tol", axis_tol),
                        ("ortho_tol", ortho_tol)):
        check_number(name, value, 0, None, open_lo=True)
    arm = check_class(robot, axis_tol)
    check_number("limit_tol", limit_tol, 0, None, open_lo=False)
    check_integer("refine_iter", refine_iter, 1)
    if not isinstance(refine, (bool, np.bool_)):
        raise ValueError(f"refine must be True or False, got {refine!r}")
    w = check_weights(weights)
    if threads is None:
        threads = min(len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                      else os.cpu_count() or 1, 8)
    check_integer("threads", threads, 1)
    size = np.size(T_target) // 16 if isinstance(T_target, np.ndarray) else 0
    pool = None
    if threads > 1 and size > _CHUNK:
        from concurrent.futures import ThreadPoolExecutor
        pool = ThreadPoolExecutor(min(threads, -(-size // _CHUNK)))
    try:
        return _closed_form(robot, arm, T_target, pool, tol_pos, tol_rot, w, refine,
                            refine_iter, limit_tol, ortho_tol)
    finally:
        if pool is not None:
            pool.shutdown()


def _closed_form(robot, arm, T_target, pool, tol_pos, tol_rot, w, refine, refine_iter,
                 limit_tol, ortho_tol) -> ClosedFormResult:
    map_chunks = map if pool is None else pool.map
    T = check_targets(T_target, ortho_tol, map_chunks=map_chunks)   # every pose first
    batch, flat = T.shape[:-2], T.reshape(-1, 4, 4)
    N = flat.shape[0]
    if N:
        distance = np.abs(flat[:, :3, 3] - robot.base[:3, 3]).max(axis=1)
        if distance.max() > MAX_TARGET_DISTANCE:
            k = int(np.argmax(distance))
            raise ValueError(f"T_target: pose {k}'s position lies {distance[k]:.3g} m from the base, beyond the "
                             f"{MAX_TARGET_DISTANCE:g} m within which the closed form computes (no arm reaches it)")
    # Written in component layout (joint, branch, target) and handed out as its transposed
    # view: the chunks write contiguous rows instead of every fifth number.
    q_c, inside_c = np.empty((5, 4, N)), np.empty((4, N), bool)
    pos_c, rot_c = np.empty((4, N)), np.empty((4, N))

    def chunk(start: int) -> None:
        part = slice(start, start + _CHUNK)
        angles, pe, re = _solve_chunk(arm, flat[part])
        within = np.ones((2, 2, pe.shape[1]), bool)
        for j, x in enumerate(angles):                    # (2, m) or (2, 2, m)
            ok = _wrap_joint(x, arm.lo[j], arm.hi[j], limit_tol)
            if x.ndim == 2:                               # q1, q5: the elbow branches share them
                within &= ok[:, None]
                q_c[j, 0:2, part], q_c[j, 2:4, part] = x[0], x[1]
            else:
                within &= ok
                q_c[j, :, part] = x.reshape(4, -1)
        pos_c[0:2, part], pos_c[2:4, part] = pe[0], pe[1]
        rot_c[0:2, part], rot_c[2:4, part] = re[0], re[1]
        inside_c[:, part] = within.reshape(4, -1)

    for _ in map_chunks(chunk, range(0, N, _CHUNK)):
        pass
    q, inside, pos_error, rot_error = q_c.transpose(2, 1, 0), inside_c.T, pos_c.T, rot_c.T
    reaches = (pos_error <= tol_pos) & (rot_error <= tol_rot)
    refined = ~reaches.any(axis=1)
    if not arm.exact:          # the DH rows' solutions seed LM on the arm with its fixed transforms
        refined[:], refine = True, True
    if refine and refined.any():
        out = np.flatnonzero(refined)
        result = solve(robot, np.repeat(flat[out], 4, axis=0), q[out].reshape(-1, 5),
                           weights=w, tol_pos=tol_pos, tol_rot=tol_rot, max_iter=refine_iter,
                           restarts=0, respect_limits=False,
                           stall_rtol=1e-12, stall_iters=4, ortho_tol=ortho_tol)
        q_near = result.q.reshape(-1, 4, 5).copy()
        within = np.ones(q_near.shape[:2], bool)
        for j in range(5):
            within &= _wrap_joint(q_near[..., j], arm.lo[j], arm.hi[j], limit_tol)
        q[out], inside[out] = q_near, within
        e = pose_error(np.repeat(flat[out], 4, axis=0), fk(robot, result.q))
        pos_error[out] = np.linalg.norm(e[:, :3], axis=1).reshape(-1, 4)
        rot_error[out] = np.linalg.norm(e[:, 3:], axis=1).reshape(-1, 4)
        reaches[out] = (pos_error[out] <= tol_pos) & (rot_error[out] <= tol_rot)
    elif not refine:
        refined[:] = False
    shape = lambda x: x.reshape(batch + x.shape[1:])  # noqa: E731
    return ClosedFormResult(q=shape(q), valid=shape(reaches & inside), reaches=shape(reaches),
                            within_limits=shape(inside), pos_error=shape(pos_error),
                            rot_error=shape(rot_error), refined=shape(refined))


def _principal(angle: np.ndarray) -> np.ndarray:
    """Angles [rad] moved by multiples of 2π into ``(−π, π]``."""
    return np.pi - np.remainder(np.pi - angle, 2 * np.pi)


def _planar(g: ArmConstants, q: np.ndarray):
    """θ̄ (offsets in), the elbow angle γ and Φ of configurations ``q (..., 5)``."""
    t = q + g.offset
    gamma = g.sigma2 * t[..., 2]
    return t, gamma, t[..., 1] + gamma + g.sigma * t[..., 3]


def planar_points(robot: Robot, q) -> dict[str, np.ndarray]:
    """The planar sub-problem of configurations ``q (..., 5)`` [rad], in the arm's plane (frame
    1's x–y plane, coordinates [m] from the shoulder axis): the shoulder, elbow and wrist-pitch
    axes, the wrist point, each ``(..., 2)``; the roll axis's direction in the plane; and the
    angles θ̄2, γ, Φ [rad] in ``(−π, π]``; where the base axis crosses the x axis; whether y1 points up
    (against gravity) or down.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> p = planar_points(robot, np.zeros(5))     # the home pose
        >>> (p["elbow"].round(6) + 0.0).tolist(), (p["wrist pitch"].round(6) + 0.0).tolist()     # [m]
        ([0.0, 0.2], [0.18, 0.2])
        >>> float(p["gamma"]).__round__(6), p["y1 up"]     # the elbow angle [rad]
        (-1.570796, True)
    """
    g = check_class(robot)
    t, gamma, phi = _planar(g, joint_array(robot, q))
    u = lambda a: np.stack([np.cos(a), np.sin(a)], axis=-1)  # noqa: E731
    elbow = g.a2 * u(t[..., 1])
    wrist_pitch = elbow + g.a3 * u(t[..., 1] + gamma)
    return {"shoulder": np.zeros_like(elbow), "elbow": elbow, "wrist pitch": wrist_pitch,
            "wrist point": wrist_pitch + g.a4 * u(phi),
            "roll axis": g.s * np.stack([np.sin(phi), -np.cos(phi)], axis=-1),
            "theta2": _principal(t[..., 1]), "gamma": _principal(gamma), "Phi": _principal(phi),
            "base axis x": -g.a1,
            "y1 up": g.up > 0}


def branch_margins(robot: Robot, q) -> dict[str, np.ndarray]:
    """How far configurations ``q (..., 5)`` [rad] lie from where their branch meets another,
    each ``(...)``:

    - ``"elbow"`` [rad]: the elbow angle γ's distance from the stretched (γ = 0) or folded
      (γ = π) arm, where the elbow-up and elbow-down solutions meet;
    - ``"wrist"`` [m]: the wrist point's distance ahead of (or behind) the base axis along
      x1, where the front and back solutions meet (the base angle is undetermined at 0);
    - ``"other"`` [rad]: the largest joint-angle difference to the nearest other solution of
      the same pose within the joint limits (:func:`closed_form`), ``inf`` where there is none.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> margins = branch_margins(robot, [0.3, 0.2, -0.4, 0.5, 0.1])
        >>> {key: float(value).__round__(6) for key, value in margins.items()}     # [rad], [m], [rad]
        {'elbow': 1.170796, 'wrist': 0.136678, 'other': inf}
        >>> branch_margins(robot, np.zeros((3, 5)))["elbow"].shape                # q (3, 5) → (3,)
        (3,)
    """
    g = check_class(robot)
    q = joint_array(robot, q)
    t, gamma, phi = _planar(g, q)
    ahead = g.a1 + g.a2 * np.cos(t[..., 1]) + g.a3 * np.cos(t[..., 1] + gamma) + g.a4 * np.cos(phi)
    result = closed_form(robot, fk(robot, q))
    gap = wrapped_gap(result.q - q[..., None, :]).max(-1)                 # (..., 4)
    own = np.argmin(gap, axis=-1)
    others = result.valid & (np.arange(4) != own[..., None]) & (gap > 1e-6)
    return {"elbow": np.minimum(wrapped_gap(gamma), wrapped_gap(gamma - np.pi)),
            "wrist": np.abs(ahead), "other": np.where(others, gap, np.inf).min(-1)}


def elbow_meeting_angles(robot: Robot) -> tuple[float, float]:
    """The elbow joint's angles q3 [rad] at which the arm is stretched (γ = 0) and folded
    (γ = π), where its elbow-up and elbow-down solutions meet; each moved by a multiple of 2π
    into ``[mid − π, mid + π)`` of the joint's range. An elbow range between them keeps one
    elbow side.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> [round(angle, 6) for angle in elbow_meeting_angles(robot)]     # stretched, folded [rad]
        [1.570796, -1.570796]
    """
    g = check_class(robot)
    lo, hi = robot.qlim[2]
    mid = 0.5 * (lo + hi)
    wrap = lambda x: float(mid + np.remainder(x - mid + np.pi, 2 * np.pi) - np.pi)  # noqa: E731
    return wrap(-g.offset[2]), wrap(np.pi - g.offset[2])
