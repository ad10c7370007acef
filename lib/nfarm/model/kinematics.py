"""Forward kinematics, the geometric Jacobian and manipulability of a DH chain, batched.

Every function takes joint angles ``q (..., n)`` [rad] and works on the whole batch at once.
Internally a pose is kept as component arrays — three column vectors ``X, Y, Z`` of the
rotation and the origin ``p``, each ``(3, N)`` — so that one link step is a dozen vector
operations over the batch instead of ``N`` small ``4×4`` products (which are slow in numpy).
The batch is processed in chunks of :data:`CHUNK` configurations so the work stays in cache.

Link transforms (see :mod:`nfarm.model.robot`), θ = q + offset:

* standard: ``T_i = T_{i-1} · Rz(θ_i) · Tz(d_i) · Tx(a_i) · Rx(α_i)``
* modified: ``T_i = T_{i-1} · Rx(α_i) · Tx(a_i) · Rz(θ_i) · Tz(d_i)``

and the tool pose is ``T_0e = base · T_n · tool`` (the robot's ``base`` places DH frame 0 in
the world; every pose and Jacobian is in world coordinates).
"""

from __future__ import annotations

import functools

import numpy as np

from ..infra.arguments import check_choice
from .robot import Robot, joint_array

__all__ = ["dh_transform", "fk", "fk_all", "jacobian", "numerical_jacobian", "pose_jacobian_T",
           "manipulability", "min_singular_value", "joint_placements", "cos_sin", "snap_right_angles",
           "CHUNK"]

#: Configurations per chunk: small enough for every intermediate to stay in the L2 cache.
CHUNK = 16384


def _Rz(t: float) -> np.ndarray:
    T = np.eye(4)
    T[:2, :2] = [[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]]
    return T


def _Rx(t: float) -> np.ndarray:
    T = np.eye(4)
    T[1:3, 1:3] = [[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]]
    return T


def _Tr(x: float, y: float, z: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = x, y, z
    return T


def dh_transform(a, alpha, d, theta) -> np.ndarray:
    """The standard Denavit–Hartenberg link transform (chapter 1, equation 1.1), batched over the
    arguments' broadcast leading shape ``(...)``:

    ``A = R_z(θ) T_z(d) T_x(a) R_x(α) =
    [[cθ, −sθ cα, sθ sα, a cθ], [sθ, cθ cα, −cθ sα, a sθ], [0, sα, cα, d], [0, 0, 0, 1]]``

    Args:
        a: the common normal's length [m]; alpha: the twist about it [rad];
        d: the offset along the previous z [m]; theta: the angle about it [rad] (a revolute
        joint's ``q + offset``).

    Returns:
        ``(..., 4, 4)``: frame i in frame i−1.

    Example:
        >>> A = dh_transform(0.1, np.pi / 2, 0.2, np.pi / 2)
        >>> (A[:3, 3].round(12) + 0.0).tolist()      # a along the turned x, d along z [m]
        [0.0, 0.1, 0.2]
    """
    a, alpha, d, theta = np.broadcast_arrays(*(np.asarray(x, float) for x in (a, alpha, d, theta)))
    c, s, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    A = np.zeros(a.shape + (4, 4))
    A[..., 0, :] = np.stack([c, -s * ca, s * sa, a * c], axis=-1)
    A[..., 1, :] = np.stack([s, c * ca, -c * sa, a * s], axis=-1)
    A[..., 2, 1], A[..., 2, 2], A[..., 2, 3], A[..., 3, 3] = sa, ca, d, 1.0
    return A


def joint_placements(robot: Robot) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Split the DH chain at the joint rotations (the model's geometry, shared by the dynamics,
    the URDF writer and the Pinocchio reference).

    Returns:
        ``(J, B)``: ``J[i]`` is the 4×4 placement of joint i+1 in the frame of the body moved
        by joint i (the base for i = 0); ``B[i]`` is the placement of link frame i+1 (the DH
        frame and its fixed transform, :class:`~nfarm.model.robot.Robot`) in the body moved by
        joint i+1. Then ``T_0k = J_0 Rz(q_1) B_0 · B_0⁻¹ J_1 Rz(q_2) B_1 ···``.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> J, B = joint_placements(robot)
        >>> len(J), len(B)
        (5, 5)
        >>> (B[0][:3, 3].round(6) + 0.0).tolist()     # DH frame 1 in the body of joint 1 [m]
        [0.0, 0.0, 0.105]
    """
    J, B = [], []
    previous = np.eye(4)
    for i, (a, alpha, d, offset) in enumerate(zip(robot.a, robot.alpha, robot.d, robot.offset)):
        if robot.convention == "standard":
            F = _Rz(offset) @ _Tr(0, 0, d) @ _Tr(a, 0, 0) @ _Rx(alpha)
            if robot.fixed is not None:
                F = F @ robot.fixed[i]
            J.append(previous)
            B.append(F)
            previous = F
        else:
            J.append(_Rx(alpha) @ _Tr(a, 0, 0) @ _Tr(0, 0, d) @ _Rz(offset))
            B.append(np.eye(4))
    return J, B


def _check_q(robot: Robot, q) -> np.ndarray:
    return joint_array(robot, q, "q")


def snap_right_angles(x: np.ndarray) -> np.ndarray:
    """Make cos/sin of exact right angles exactly 0 or ±1 (cos(π/2) is 6e-17 in floating point),
    so the link steps can skip those terms.

    Example:
        >>> x = np.cos([0.0, np.pi / 2, np.pi])
        >>> bool(x[1] == 0.0), snap_right_angles(x).tolist()
        (False, [1.0, 0.0, -1.0])
    """
    x = np.where(np.abs(x) < 1e-15, 0.0, x)
    return np.where(np.abs(np.abs(x) - 1.0) < 1e-15, np.sign(x), x)


def cos_sin(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``cos θ, sin θ`` by the half-angle tangent: ``t = tan(θ/2)``,
    ``cos θ = (1 − t²)/(1 + t²)``, ``sin θ = 2t/(1 + t²)`` (within 2 ulp of ``np.cos``/``np.sin``).

    NumPy 2 evaluates float64 ``tan`` with SIMD but ``sin``/``cos`` with scalar libm: this is
    about 5× faster than ``np.cos`` + ``np.sin``, and trigonometry is most of the cost of ``fk``.

    Example:
        >>> theta = np.array([0.0, np.pi / 3, np.pi / 2])     # [rad]
        >>> c, s = cos_sin(theta)
        >>> (c.round(6) + 0.0).tolist(), (s.round(6) + 0.0).tolist()
        ([1.0, 0.5, 0.0], [0.0, 0.866025, 1.0])
        >>> np.allclose(c, np.cos(theta)) and np.allclose(s, np.sin(theta))
        True
    """
    t = np.tan(0.5 * theta)
    t2 = t * t
    r = 1.0 / (1.0 + t2)
    return (1.0 - t2) * r, 2.0 * t * r


def _comb(*terms):
    """``Σ c·V`` over ``(c, V)`` pairs with scalar ``c``: zero terms skipped, ±1 not multiplied."""
    acc = None
    for c, V in terms:
        if c == 0:
            continue
        if acc is None:
            acc = V if c == 1 else c * V
        elif c == 1 or c == -1:
            acc = acc + V if c == 1 else acc - V
        else:
            acc = acc + c * V
    return acc


class _Chain:
    """Constant per-robot factors of the link steps (cosines and sines of α, tool columns)."""

    def __init__(self, robot: Robot):
        self.standard = robot.convention == "standard"
        self.a, self.d, self.offset = robot.a.tolist(), robot.d.tolist(), robot.offset
        self.ca, self.sa = snap_right_angles(np.cos(robot.alpha)).tolist(), snap_right_angles(np.sin(robot.alpha)).tolist()
        self.tool = snap_right_angles(robot.tool).tolist()
        # The fixed transforms after the rows (None where a joint has none): applied as the tool is.
        self.fixed = [None] * robot.n if robot.fixed is None else [
            None if np.array_equal(E, np.eye(4)) else snap_right_angles(E).tolist() for E in robot.fixed]
        self.n = robot.n
        base = snap_right_angles(robot.base)
        self.base = None if np.array_equal(base, np.eye(4)) else (base[:3, :3], base[:3, 3:])

    def frames(self, qT: np.ndarray, every: bool):
        """Yield ``(k, X, Y, Z, p)`` for frames k = 0..n (only k = n unless ``every``).

        ``qT (n, N)``; each of ``X, Y, Z, p`` is ``(3, N)``: the columns of ``base · T_0k`` and
        its origin in world coordinates.
        """
        if self.base is None:
            yield from self._frames(qT, every)
            return
        R, t = self.base
        for k, X, Y, Z, p in self._frames(qT, every):
            yield k, R @ X, R @ Y, R @ Z, R @ p + t

    def _frames(self, qT: np.ndarray, every: bool):
        N = qT.shape[1]
        theta = qT + self.offset[:, None]
        ct, st = cos_sin(theta)
        if every:
            X, Y, Z, p = np.zeros((4, 3, N))
            X[0] = Y[1] = Z[2] = 1.0
            yield 0, X, Y, Z, p
        X, Y, Z, p = self._first_frame(ct[0], st[0])
        if self.fixed[0] is not None:
            X, Y, Z, p = _transformed(self.fixed[0], X, Y, Z, p)
        if every or self.n == 1:
            yield 1, X, Y, Z, p
        for i in range(1, self.n):
            c, s, ca, sa, a, d = ct[i], st[i], self.ca[i], self.sa[i], self.a[i], self.d[i]
            if self.standard:
                # R ← R·Rz(θ)·Rx(α);  p ← p + d·z + a·x   (x after Rz, z before it)
                X, Y = c * X + s * Y, c * Y - s * X
                p = _comb((1, p), (d, Z), (a, X))
                Y, Z = _comb((ca, Y), (sa, Z)), _comb((ca, Z), (-sa, Y))
            else:
                # R ← R·Rx(α)·Rz(θ);  p ← p + a·x + d·z   (x before Rx, z after it)
                p = _comb((1, p), (a, X))
                Y, Z = _comb((ca, Y), (sa, Z)), _comb((ca, Z), (-sa, Y))
                p = _comb((1, p), (d, Z))
                X, Y = c * X + s * Y, c * Y - s * X
            if self.fixed[i] is not None:
                X, Y, Z, p = _transformed(self.fixed[i], X, Y, Z, p)
            if every or i == self.n - 1:
                yield i + 1, X, Y, Z, p

    def _first_frame(self, c, s):
        """``T_01`` in closed form (the general step applied to the identity; a sixth of the
        work of fk for a 5-joint arm)::

            standard:  x = (c, s, 0), y = (−cα s, cα c, sα), z = (sα s, −sα c, cα),  p = (a c, a s, d)
            modified:  x = (c, cα s, sα s), y = (−s, cα c, sα c), z = (0, −sα, cα),  p = (a, −d sα, d cα)
        """
        ca, sa, a, d = self.ca[0], self.sa[0], self.a[0], self.d[0]
        zero, one = np.zeros_like(c), np.ones_like(c)
        if self.standard:
            X = np.stack([c, s, zero])
            Y = np.stack([-ca * s, ca * c, sa * one])
            Z = np.stack([sa * s, -sa * c, ca * one])
            p = np.stack([a * c, a * s, d * one])
        else:
            X = np.stack([c, ca * s, sa * s])
            Y = np.stack([-s, ca * c, sa * c])
            Z = np.stack([zero, -sa * one, ca * one])
            p = np.stack([a * one, -d * sa * one, d * ca * one])
        return X, Y, Z, p

    def tool_frame(self, X, Y, Z, p):
        """Columns and origin of ``T_n · tool``."""
        return _transformed(self.tool, X, Y, Z, p)


def _transformed(t: list, X, Y, Z, p):
    """Columns and origin of ``T · t`` from those of ``T`` (``X, Y, Z, p`` each ``(3, N)``) and
    a constant pose ``t`` (4×4 nested list)."""
    cols = [_comb((t[0][j], X), (t[1][j], Y), (t[2][j], Z)) for j in range(3)]
    return (*cols, _comb((1, p), (t[0][3], X), (t[1][3], Y), (t[2][3], Z)))


@functools.lru_cache(maxsize=64)
def _chain(robot: Robot) -> _Chain:
    """The per-robot constants, computed once (a Robot is immutable and hashed by identity)."""
    return _Chain(robot)


def _chunks(N: int):
    for start in range(0, N, CHUNK):
        yield slice(start, min(start + CHUNK, N))


def _batch(robot: Robot, q):
    q = _check_q(robot, q)
    batch = q.shape[:-1]
    qT = np.ascontiguousarray(q.reshape(-1, robot.n).T)
    return batch, qT


def _store_pose(out: np.ndarray, sl: slice, X, Y, Z, p) -> None:
    """Write a pose into ``out (4, 4, N)`` [row, column, sample]."""
    out[:3, 0, sl], out[:3, 1, sl], out[:3, 2, sl], out[:3, 3, sl] = X, Y, Z, p


def _pose_buffer(*lead: int) -> np.ndarray:
    out = np.zeros((*lead[:-1], 4, 4, lead[-1]))
    out[..., 3, 3, :] = 1.0
    return out


def fk(robot: Robot, q) -> np.ndarray:
    """Tool poses in the world ``T_0e = base · A_1(q_1) ··· A_n(q_n) · tool``.

    Args:
        q: ``(..., n)`` joint angles [rad].
    Returns:
        ``(..., 4, 4)`` homogeneous transforms [m] (a transposed view of a component array).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> (fk(robot, np.zeros(5))[:3, 3].round(6) + 0.0).tolist()     # the tool point at q = 0 [m]
        [0.18, 0.0, 0.195]
        >>> fk(robot, np.zeros((3, 5))).shape                           # q (3, 5) → (3, 4, 4)
        (3, 4, 4)
    """
    batch, qT = _batch(robot, q)
    chain, N = _chain(robot), qT.shape[1]
    out = _pose_buffer(N)
    for sl in _chunks(N):
        for _, X, Y, Z, p in chain.frames(qT[:, sl], every=False):
            _store_pose(out, sl, *chain.tool_frame(X, Y, Z, p))
    return np.moveaxis(out, -1, 0).reshape(*batch, 4, 4)


def fk_all(robot: Robot, q) -> np.ndarray:
    """World poses of every link frame ``base · T_0k``, k = 0..n (the base first, the tool not
    included).

    Args:
        q: ``(..., n)`` joint angles [rad].
    Returns:
        ``(..., n + 1, 4, 4)`` homogeneous transforms; ``[..., 0, :, :]`` is ``base``.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> T = fk_all(robot, np.zeros(5))
        >>> T.shape, (T[2, :3, 3].round(6) + 0.0).tolist()     # frames 0..5; frame 2 at the elbow [m]
        ((6, 4, 4), [0.0, 0.0, 0.305])
        >>> fk_all(robot, np.zeros((3, 5))).shape               # q (3, 5) → (3, n + 1, 4, 4)
        (3, 6, 4, 4)
    """
    batch, qT = _batch(robot, q)
    chain, N = _chain(robot), qT.shape[1]
    out = _pose_buffer(robot.n + 1, N)
    for sl in _chunks(N):
        for k, X, Y, Z, p in chain.frames(qT[:, sl], every=True):
            _store_pose(out[k], sl, X, Y, Z, p)
    return np.moveaxis(out, -1, 0).reshape(*batch, robot.n + 1, 4, 4)


def jacobian(robot: Robot, q) -> np.ndarray:
    """Geometric Jacobian of the tool frame origin, in world coordinates, linear rows first.

    Column k of a revolute joint with unit axis ``z_k`` through the point ``o_k``::

        J[:3, k] = z_k × (p_e − o_k),    J[3:, k] = z_k

    where (standard DH) joint k turns about ``z`` of frame k−1, and (modified DH) about ``z`` of
    frame k; ``p_e`` is the tool origin. So ``[ṗ_e; ω] = J q̇`` (Pinocchio's
    ``LOCAL_WORLD_ALIGNED`` frame Jacobian).

    Args:
        q: ``(..., n)`` joint angles [rad].
    Returns:
        ``(..., 6, n)`` [m/rad for the linear rows, dimensionless for the angular rows].

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> (jacobian(robot, np.zeros(5))[:, 0].round(6) + 0.0).tolist()   # base yaw: [ṗ; ω] per rad/s
        [0.0, 0.18, 0.0, 0.0, 0.0, 1.0]
        >>> jacobian(robot, np.zeros((3, 5))).shape                         # q (3, 5) → (3, 6, 5)
        (3, 6, 5)
    """
    batch, qT = _batch(robot, q)
    _, J = pose_jacobian_T(robot, qT, pose=False)
    return np.moveaxis(J, -1, 0).reshape(*batch, 6, robot.n)


def pose_jacobian_T(robot: Robot, qT: np.ndarray, *, pose: bool = True):
    """Tool pose and Jacobian in component layout, samples last (for solvers that iterate).

    Args:
        qT: ``(n, N)`` joint angles [rad], one column per sample.
        pose: also return the pose.
    Returns:
        ``(T, J)``: ``T (4, 4, N)`` (row, column, sample; ``None`` unless ``pose``) and
        ``J (6, n, N)``, as in :func:`fk` and :func:`jacobian`.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> T, J = pose_jacobian_T(robot, np.zeros((5, 3)))     # qT (n, N): 3 samples as columns
        >>> T.shape, J.shape
        ((4, 4, 3), (6, 5, 3))
        >>> np.allclose(np.moveaxis(J, -1, 0), jacobian(robot, np.zeros((3, 5))))
        True
    """
    chain, n, N = _chain(robot), robot.n, qT.shape[1]
    J = np.empty((6, n, N))
    T = _pose_buffer(N) if pose else None
    shift = 0 if chain.standard else 1  # joint k turns about frame k - 1 + shift
    for sl in _chunks(N):
        frames = list(chain.frames(qT[:, sl], every=True))
        tool = chain.tool_frame(*frames[-1][1:])
        p_e = tool[-1]
        if pose:
            _store_pose(T, sl, *tool)
        for k in range(n):
            *_, z, o = frames[k + shift]
            r = p_e - o
            J[0, k, sl] = z[1] * r[2] - z[2] * r[1]
            J[1, k, sl] = z[2] * r[0] - z[0] * r[2]
            J[2, k, sl] = z[0] * r[1] - z[1] * r[0]
            J[3:, k, sl] = z
    return T, J


def numerical_jacobian(robot: Robot, q, h: float = 1e-6) -> np.ndarray:
    """The Jacobian ``(..., 6, n)`` by central differences of :func:`fk` (an independent check).

    Linear rows ``(p(q + h e_k) − p(q − h e_k)) / 2h``; angular rows from the relative rotation
    ``R_k = R(q + h e_k) R(q − h e_k)ᵀ ≈ exp(2h [ω_k]×)``, so ``ω_k ≈ vee(R_k − R_kᵀ) / 4h``.
    Truncation error O(h²) (about 1e-11 for h = 1e-6 on an arm of metre size).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> q = np.array([0.3, 0.2, -0.4, 0.5, 0.1])     # [rad]
        >>> np.allclose(numerical_jacobian(robot, q), jacobian(robot, q), atol=1e-8)
        True
    """
    q = _check_q(robot, q)
    step = h * np.eye(robot.n)
    T_plus = fk(robot, q[..., None, :] + step)    # (..., n, 4, 4), one row per joint
    T_minus = fk(robot, q[..., None, :] - step)
    linear = (T_plus[..., :3, 3] - T_minus[..., :3, 3]) / (2 * h)
    R = T_plus[..., :3, :3] @ np.swapaxes(T_minus[..., :3, :3], -1, -2)
    angular = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0],
                        R[..., 1, 0] - R[..., 0, 1]], axis=-1) / (4 * h)
    return np.swapaxes(np.concatenate([linear, angular], axis=-1), -1, -2)


_ROWS = {"position": slice(0, 3), "orientation": slice(3, 6), "full": slice(0, 6)}


def _singular_values(robot: Robot, q, part: str) -> np.ndarray:
    check_choice("part", part, _ROWS)
    return np.linalg.svd(jacobian(robot, q)[..., _ROWS[part], :], compute_uv=False)


def manipulability(robot: Robot, q, part: str = "position") -> np.ndarray:
    """Yoshikawa's manipulability ``w`` of a part of the Jacobian: the product of its singular values.

    For the ``m × n`` block ``J_p`` (``part`` = ``"position"``: rows 0–2, the default;
    ``"orientation"``: rows 3–5; ``"full"``: all six) this is ``w = sqrt(det(J_p J_pᵀ))`` when
    ``m <= n`` and ``sqrt(det(J_pᵀ J_p))`` when ``m > n`` (the full 6 × 5 Jacobian of a 5-DOF
    arm), and zero exactly at a singularity of that block. The position part is the default
    because its units are clean (m³ for three rows) and a 5-DOF arm's full Jacobian mixes
    metres and radians.

    Returns:
        ``(...)`` manipulability.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> float(manipulability(robot, np.zeros(5))).__round__(6)     # position part at q = 0 [m³]
        0.008209
        >>> manipulability(robot, np.zeros((3, 5))).shape                # q (3, 5) → (3,)
        (3,)
    """
    return np.prod(_singular_values(robot, q, part), axis=-1)


def min_singular_value(robot: Robot, q, part: str = "position") -> np.ndarray:
    """Smallest singular value ``(...)`` of a part of the Jacobian (see :func:`manipulability`).

    It is the distance of the block to the nearest rank-deficient matrix, and so a better
    scaled measure of nearness to a singularity than ``w``.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> float(min_singular_value(robot, np.zeros(5))).__round__(6)     # [m]
        0.178623
        >>> stretched = [0.0, 0.0, np.pi / 2, np.pi / 2, 0.0]     # links and tool point in one line
        >>> bool(min_singular_value(robot, stretched) < 1e-12)
        True
    """
    return _singular_values(robot, q, part)[..., -1]
