"""Inverse dynamics by the recursive Newton–Euler algorithm (Luh, Walker & Paul 1980), batched.

The recursion runs over the joints; every quantity is a component array with the samples
last (``(3, N)`` for a vector), so one recursion step is a few dozen vector operations over
the whole batch. Both DH conventions share one formulation: the chain is split at the joint
rotations (:func:`nfarm.model.kinematics.joint_placements`), so that joint i turns its *joint frame* F_i
about its own z axis, F_i = F_{i−1} · P_i · Rz(q_i) with a constant placement
``P_i = (R_i, p_i)``. The inertial parameters of link i are moved once into F_i.

With ``ᶦR = (R_i Rz(q_i))ᵀ`` (from F_{i−1} to F_i), ``ẑ = (0, 0, 1)``, centre of mass ``c_i``,
mass ``m_i`` and inertia ``I_i`` about the centre of mass (all in F_i), Craig (2005), ch. 6:

Outward, i = 1..n (base: ω₀ = ω̇₀ = 0, a₀ = −g, which adds gravity to every link)::

    ω_i  = ᶦR ω_{i−1} + q̇_i ẑ
    ω̇_i  = ᶦR ω̇_{i−1} + (ᶦR ω_{i−1}) × q̇_i ẑ + q̈_i ẑ
    a_i  = ᶦR (a_{i−1} + ω̇_{i−1} × p_i + ω_{i−1} × (ω_{i−1} × p_i))
    a_ci = a_i + ω̇_i × c_i + ω_i × (ω_i × c_i)
    F_i  = m_i a_ci,    N_i = I_i ω̇_i + ω_i × (I_i ω_i)

Inward, i = n..1 (``f_{n+1}, n_{n+1}``: the wrench the tool exerts on its environment)::

    f_i = F_i + ᶦR_{i+1} f_{i+1}
    n_i = N_i + ᶦR_{i+1} n_{i+1} + c_i × F_i + p_{i+1} × (ᶦR_{i+1} f_{i+1})
    τ_i = n_i · ẑ

where ``ᶦR_{i+1} = R_{i+1} Rz(q_{i+1})`` maps F_{i+1} to F_i.
"""

from __future__ import annotations

import functools

import numpy as np

from .kinematics import cos_sin, joint_placements, snap_right_angles
from .robot import Robot, joint_array

__all__ = ["rnea", "joint_drive_torques", "stribeck_drive_torques", "gravity_torques", "mass_matrix", "coriolis", "regressor",
           "inertial_parameters", "INERTIAL_NAMES", "CHUNK"]

#: Samples per chunk (keeps the working set in cache).
CHUNK = 32768


class _Links:
    """Per-robot constants in joint frames: placements, masses, first and second moments."""

    def __init__(self, robot: Robot):
        J, B = joint_placements(robot)
        n = robot.n
        self.n = n
        self.R = [_matrix(P[:3, :3]) for P in J]             # R_i: F_{i−1} → joint i, before Rz
        self.RT = [_matrix(P[:3, :3].T) for P in J]
        self.p = [_const(P[:3, 3]) for P in J]               # p_i in F_{i−1}
        self.m = robot.mass.tolist()
        self.c, self.I = [], []
        for i in range(n):
            R_B, p_B = B[i][:3, :3], B[i][:3, 3]
            self.c.append(_const(R_B @ robot.com[i] + p_B))           # centre of mass in F_i
            self.I.append(_matrix(R_B @ robot.inertia[i] @ R_B.T))    # about it, axes of F_i
        self.tool = _const((B[-1] @ robot.tool)[:3, 3])      # tool origin in F_n
        self.placements = [P[:3, :3] for P in J]            # for the tip wrench


@functools.lru_cache(maxsize=64)
def _links(robot: Robot) -> _Links:
    return _Links(robot)


# Vectors of the recursion are lists of three components, each an array over the samples or
# ``None`` for an exact zero. Constants (placements, centres of mass, inertias) have many zero
# entries, and the first links many zero velocities: skipping those terms halves the work.


def _add(a, b):
    return b if a is None else a if b is None else a + b


def _sub(a, b):
    return a if b is None else (-b if a is None else a - b)


def _mul(x, a):
    """``x · a`` for a sample array or scalar ``x`` and a component ``a`` (or None)."""
    if a is None or (np.isscalar(x) and x == 0):
        return None
    return a if (np.isscalar(x) and x == 1) else x * a


def _plus(u, v):
    return [_add(a, b) for a, b in zip(u, v)]


def _cross(u, v):
    """``u × v`` of component lists."""
    return [_sub(_mul2(u[1], v[2]), _mul2(u[2], v[1])),
            _sub(_mul2(u[2], v[0]), _mul2(u[0], v[2])),
            _sub(_mul2(u[0], v[1]), _mul2(u[1], v[0]))]


def _mul2(a, b):
    """Product of two components, each a sample array, a scalar constant, or None."""
    if a is None or b is None:
        return None
    if np.isscalar(a):
        return _mul(a, b)
    if np.isscalar(b):
        return _mul(b, a)
    return a * b


def _lin(M: list, v):
    """``M v`` for a constant 3 × 3 ``M`` (nested lists, exact zeros and ones)."""
    out = []
    for row in M:
        acc = None
        for m, x in zip(row, v):
            acc = _add(acc, _mul(m, x))
        out.append(acc)
    return out


def _rz_T(c, s, v):
    """``Rz(q)ᵀ v``."""
    x, y, z = v
    return [_add(_mul(c, x), _mul(s, y)), _sub(_mul(c, y), _mul(s, x)), z]


def _rz(c, s, v):
    """``Rz(q) v``."""
    x, y, z = v
    return [_sub(_mul(c, x), _mul(s, y)), _add(_mul(s, x), _mul(c, y)), z]


def _const(v) -> list:
    """A constant vector as components: scalars, exact zeros as None."""
    return [None if x == 0 else float(x) for x in v]


def _matrix(M) -> list:
    """A constant matrix with cos/sin of right angles made exact."""
    return snap_right_angles(np.asarray(M)).tolist()


def _check(robot: Robot, **arrays) -> tuple[tuple, dict]:
    out = {}
    for name, value in arrays.items():
        out[name] = joint_array(robot, value, name)
        if not np.isfinite(out[name]).all():        # NaN in, plausible torques out: refused
            bad = np.argwhere(~np.isfinite(out[name]))[0]
            raise ValueError(f"{robot.name}: {name} must hold finite numbers, got "
                             f"{float(out[name][tuple(bad)])!r} at index {tuple(int(i) for i in bad)}")
    try:
        batch = np.broadcast_shapes(*(v.shape[:-1] for v in out.values()))
    except ValueError:
        shapes = ", ".join(f"{k} {v.shape}" for k, v in out.items())
        raise ValueError(f"{robot.name}: batch shapes do not broadcast: {shapes}") from None
    return batch, out


def joint_drive_torques(robot: Robot, qd, qdd) -> np.ndarray:
    """Torques ``(..., n)`` [N·m] of the joint drives beyond the rigid links, per joint:

    ``τ_drive = I_a q̈ + b q̇ + τ_c tanh(q̇ / ε)``

    with the armature ``I_a`` (the rotor's inertia reflected through the gearing, seen by the
    joint alone), viscous friction ``b`` and Coulomb friction ``τ_c``, smoothed over speeds
    of about ``ε`` (``coulomb_velocity``) so that it is differentiable at rest (robot-file
    fields, default 0). Friction only dissipates: ``q̇ · τ_friction ≥ 0``.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "so101.yaml")     # its drives: viscous, Coulomb, armature
        >>> qd = [0.5, -0.5, 0.0, 0.0, 1.0]     # [rad/s]
        >>> (joint_drive_torques(robot, qd, np.zeros(5)).round(6) + 0.0).tolist()     # [N·m]
        [0.352, -0.352, 0.0, 0.0, 0.652]
        >>> joint_drive_torques(robot, np.zeros((3, 5)), np.zeros(5)).shape          # batches broadcast
        (3, 5)
    """
    _, a = _check(robot, qd=qd, qdd=qdd)
    qd, qdd = a["qd"], a["qdd"]
    return robot.armature * qdd + robot.viscous * qd + \
        robot.coulomb * np.tanh(qd / robot.coulomb_velocity)


def stribeck_drive_torques(robot: Robot, qd, qdd, tau_load, *, stribeck=None, stribeck_velocity=None,
                           load_coefficient=0.0) -> np.ndarray:
    """Torques ``(..., n)`` [N·m] of joint drives with Stribeck friction that grows with the
    load — a drive law no learner or identification of this project assumes (chapters 05–07):

    ``τ_drive = I_a q̈ + b q̇ + [τ_c + μ |τ_load| + (τ_s − τ_c) exp(−(q̇ / v_s)²)] tanh(q̇ / ε)``

    the armature ``I_a``, viscous ``b``, Coulomb ``τ_c`` and smoothing speed ``ε`` from the
    robot's drive fields (:func:`joint_drive_torques`); the breakaway friction at rest ``τ_s``
    (``stribeck``, ``(n,)`` [N·m], default ``τ_c``: no Stribeck effect) falling to ``τ_c`` over
    speeds of about ``v_s`` (``stribeck_velocity`` [rad/s]; Armstrong-Hélouvry 1994); and
    gear-mesh friction that grows by ``μ`` (``load_coefficient``, ``(n,)``) of the torque the
    joint transmits, ``tau_load (..., n)`` (the rigid-body torque). With ``τ_s = τ_c`` and
    ``μ = 0`` it is :func:`joint_drive_torques`. Friction only dissipates.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "so101.yaml")     # its drives: viscous, Coulomb, armature
        >>> qd, qdd, load = np.full(5, 0.05), np.zeros(5), np.ones(5)     # slow [rad/s]; 1 N·m load
        >>> (stribeck_drive_torques(robot, qd, qdd, load, stribeck=0.1, stribeck_velocity=0.1,
        ...                         load_coefficient=0.01).round(6) + 0.0).tolist()     # [N·m]
        [0.129373, 0.129373, 0.129373, 0.129373, 0.129373]
        >>> np.allclose(stribeck_drive_torques(robot, qd, qdd, load), joint_drive_torques(robot, qd, qdd))
        True
    """
    _, a = _check(robot, qd=qd, qdd=qdd, tau_load=tau_load)
    qd, qdd, load = a["qd"], a["qdd"], a["tau_load"]
    tau_s = robot.coulomb if stribeck is None else np.asarray(stribeck, float)
    v_s = np.ones(robot.n) if stribeck_velocity is None else np.asarray(stribeck_velocity, float)
    level = robot.coulomb + np.asarray(load_coefficient, float) * np.abs(load) + \
        (tau_s - robot.coulomb) * np.exp(-(qd / v_s) ** 2)
    return robot.armature * qdd + robot.viscous * qd + level * np.tanh(qd / robot.coulomb_velocity)


def rnea(robot: Robot, q, qd, qdd, *, gravity=None, f_tip=None, drive: bool = False) -> np.ndarray:
    """Joint torques ``τ = M(q) q̈ + C(q, q̇) q̇ + g(q) + Jᵀ(q) f_tip`` by recursive Newton–Euler,
    plus, with ``drive=True``, the joints' armature and friction (:func:`joint_drive_torques`).

    Args:
        q, qd, qdd: ``(..., n)`` joint positions [rad], velocities [rad/s], accelerations
            [rad/s²]; batch shapes broadcast.
        gravity: ``(3,)`` gravity in the world frame [m/s²]; default the robot's.
        f_tip: ``(..., 6)`` wrench ``[force; moment]`` that the **tool exerts on its
            environment**, in world coordinates, the moment taken about the tool frame origin
            [N, N·m]; it adds ``Jᵀ f_tip`` (J: :func:`nfarm.model.kinematics.jacobian`). Default none.
            Both are in world coordinates; the recursion runs in DH frame 0, the robot's
            ``base`` rotating them into it.
        drive: add the joint drives' armature and friction torques (default: the rigid
            links alone, as chapter 03 and the dissertation).
    Returns:
        ``(..., n)`` joint torques [N·m].

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> z = np.zeros(5)
        >>> tau = rnea(robot, np.zeros((3, 5)), z, z)     # q (3, 5); qd, qdd (5,) broadcast
        >>> tau.shape, (tau[0].round(6) + 0.0).tolist()    # at rest: gravity alone [N·m]
        ((3, 5), [0.0, 0.8829, 0.8829, 0.0, 0.0])
    """
    batch, a = _check(robot, q=q, qd=qd, qdd=qdd)
    g = _gravity_in_frame_0(robot, gravity)
    flat = [np.ascontiguousarray(np.broadcast_to(a[k], (*batch, robot.n)).reshape(-1, robot.n).T)
            for k in ("q", "qd", "qdd")]
    wrench = None
    if f_tip is not None:
        f_tip = np.asarray(f_tip, dtype=float)
        if f_tip.ndim == 0 or f_tip.shape[-1] != 6:
            raise ValueError(f"f_tip must have shape (..., 6), got {f_tip.shape}")
        wrench = np.ascontiguousarray(np.broadcast_to(f_tip, (*batch, 6)).reshape(-1, 6).T)
        R0 = robot.base[:3, :3].T                     # world → DH frame 0
        wrench = np.concatenate([R0 @ wrench[:3], R0 @ wrench[3:]])
    N = flat[0].shape[1]
    tau = np.empty((robot.n, N))
    links = _links(robot)
    for start in range(0, N, CHUNK):
        sl = slice(start, min(start + CHUNK, N))
        with np.errstate(over="ignore", invalid="ignore"):      # an overflow is refused below
            tau[:, sl] = _rnea_T(links, *(x[:, sl] for x in flat), g,
                                 None if wrench is None else wrench[:, sl])
    tau = tau.T.reshape(*batch, robot.n)
    if drive:
        with np.errstate(over="ignore", invalid="ignore"):
            tau = tau + joint_drive_torques(robot, a["qd"], a["qdd"])
    if not np.isfinite(tau).all():       # speeds of 1e200 rad/s: the torques overflow
        raise ValueError(f"{robot.name}: the torques of {int((~np.isfinite(tau)).any(axis=-1).sum())} states "
                         f"overflow: q, qd, qdd far beyond any arm's (|qd| up to "
                         f"{float(np.abs(a['qd']).max()):.3g} rad/s, |qdd| up to {float(np.abs(a['qdd']).max()):.3g} rad/s²)")
    return tau


def _gravity_in_frame_0(robot: Robot, gravity) -> np.ndarray:
    """Gravity [m/s²] (world coordinates; default the robot's) in DH frame 0."""
    g = robot.gravity if gravity is None else np.asarray(gravity, dtype=float)
    if g.shape != (3,) or not np.isfinite(g).all():
        raise ValueError(f"gravity must be 3 finite numbers, got {g!r}")
    return g if np.array_equal(robot.base, np.eye(4)) else robot.base[:3, :3].T @ g


def _rnea_T(L: _Links, q, qd, qdd, g, wrench):
    """The recursion on ``(n, N)`` inputs; returns ``τ (n, N)``."""
    n, N = q.shape
    c, s = cos_sin(q)
    w, dw, acc = [None] * 3, [None] * 3, _const(-g)
    F, Nm = [], []
    for i in range(n):
        # Outward: velocities and accelerations of F_i, then the link's inertial wrench.
        p, RT = L.p[i], L.RT[i]
        acc = _rz_T(c[i], s[i], _lin(RT, _plus(acc, _plus(_cross(dw, p), _cross(w, _cross(w, p))))))
        w = _rz_T(c[i], s[i], _lin(RT, w))
        dw = _rz_T(c[i], s[i], _lin(RT, dw))
        dw = _plus(dw, [_mul2(w[1], qd[i]), _mul2(_mul(-1.0, w[0]), qd[i]), qdd[i]])   # + (ᶦRω) × q̇ẑ + q̈ẑ
        w = [w[0], w[1], _add(w[2], qd[i])]
        cm, I = L.c[i], L.I[i]
        a_c = _plus(acc, _plus(_cross(dw, cm), _cross(w, _cross(w, cm))))
        F.append([_mul(L.m[i], x) for x in a_c])
        Nm.append(_plus(_lin(I, dw), _cross(w, _lin(I, w))))
    # Inward: forces and moments on each link from its parent (zero, or the tip wrench).
    f, m = [None] * 3, [None] * 3
    if wrench is not None:
        f, m = _tip_wrench(L, c, s, wrench)
    tau = np.empty((n, N))
    for i in reversed(range(n)):
        if i + 1 < n:
            f = _lin(L.R[i + 1], _rz(c[i + 1], s[i + 1], f))
            m = _plus(_lin(L.R[i + 1], _rz(c[i + 1], s[i + 1], m)), _cross(L.p[i + 1], f))
        m = _plus(Nm[i], _plus(m, _cross(L.c[i], F[i])))
        f = _plus(F[i], f)
        tau[i] = 0.0 if m[2] is None else m[2]
    return tau


def _tip_wrench(L: _Links, c, s, wrench):
    """The tool's wrench on its environment (base coordinates, moment about the tool origin)
    in F_n, with the moment about the F_n origin."""
    R = np.broadcast_to(np.eye(3)[:, :, None], (3, 3, c.shape[1]))      # R_0,F_i, columns
    for i in range(L.n):
        R = np.einsum("ijm,jk->ikm", R, L.placements[i])
        R = np.stack([c[i] * R[:, 0] + s[i] * R[:, 1], c[i] * R[:, 1] - s[i] * R[:, 0], R[:, 2]], axis=1)
    f = list(np.einsum("jim,jm->im", R, wrench[:3]))                    # R_0nᵀ f
    m = _plus(list(np.einsum("jim,jm->im", R, wrench[3:])), _cross(L.tool, f))
    return f, m


def gravity_torques(robot: Robot, q) -> np.ndarray:
    """``g(q) (..., n)``: the torques that hold the arm still against gravity [N·m].

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> (gravity_torques(robot, np.zeros(5)).round(6) + 0.0).tolist()     # [N·m]
        [0.0, 0.8829, 0.8829, 0.0, 0.0]
        >>> gravity_torques(robot, np.zeros((3, 5))).shape                   # q (3, 5) → (3, 5)
        (3, 5)
    """
    q = np.asarray(q, dtype=float)
    zero = np.zeros_like(q)
    return rnea(robot, q, zero, zero)


def coriolis(robot: Robot, q, qd) -> np.ndarray:
    """``C(q, q̇) q̇ (..., n)``: Coriolis and centrifugal torques [N·m] (RNEA without gravity
    and acceleration).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> q = np.array([0.3, 0.2, -0.4, 0.5, 0.1])     # [rad]
        >>> (coriolis(robot, q, np.ones(5)).round(6) + 0.0).tolist()     # q̇ = 1 rad/s each [N·m]
        [-0.004989, 0.068234, -0.012022, -0.008843, 5.6e-05]
        >>> bool((coriolis(robot, q, np.zeros(5)) == 0).all())           # none at rest
        True
    """
    batch, a = _check(robot, q=q, qd=qd)
    return rnea(robot, a["q"], a["qd"], np.zeros(robot.n), gravity=np.zeros(3))


def mass_matrix(robot: Robot, q) -> np.ndarray:
    """``M(q) (..., n, n)``, symmetric positive definite [kg m²]: column j is the RNEA torque
    for ``q̈ = e_j`` with no velocity and no gravity (Walker & Orin's method 1).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> M = mass_matrix(robot, np.zeros(5))     # [kg m²]
        >>> M.shape, np.allclose(M, M.T), bool((np.linalg.eigvalsh(M) > 0).all())
        ((5, 5), True, True)
        >>> mass_matrix(robot, np.zeros((3, 5))).shape     # q (3, 5) → (3, 5, 5)
        (3, 5, 5)
    """
    batch, a = _check(robot, q=q)
    n = robot.n
    q = np.broadcast_to(a["q"][..., None, :], (*batch, n, n))   # one copy of q per column
    columns = rnea(robot, q, np.zeros(n), np.eye(n), gravity=np.zeros(3))   # (..., j, i)
    return np.swapaxes(columns, -1, -2)


# --------------------------------------------------------------------------------------------
# The dynamic regressor: torques linear in the inertial parameters

#: Names of one link's inertial parameters in :func:`regressor`'s column order (about the
#: origin of the link's joint frame F_k, in its axes).
INERTIAL_NAMES = ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz")

_UNIT_INERTIAS = np.zeros((6, 3, 3))
for _k, (_r, _c) in enumerate([(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]):
    _UNIT_INERTIAS[_k, _r, _c] = _UNIT_INERTIAS[_k, _c, _r] = 1.0


def inertial_parameters(robot: Robot) -> np.ndarray:
    """``π (10 n,)``: per link, in the order of :data:`INERTIAL_NAMES`, its mass [kg], first
    moment ``m c`` [kg m] and inertia about the joint frame's origin
    ``I_o = I_c + m (|c|² 1 − c cᵀ)`` [kg m²] (parallel axes), in the joint frame F_k of
    :func:`rnea`, so that ``rnea(robot, q, q̇, q̈) = regressor(robot, q, q̇, q̈) @ π``.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> pi = inertial_parameters(robot)
        >>> pi.shape     # 10 per link
        (50,)
        >>> dict(zip(INERTIAL_NAMES, (pi[:4].round(6) + 0.0).tolist()))     # link 1: [kg], [kg m]
        {'m': 0.5, 'mcx': 0.0, 'mcy': 0.0, 'mcz': 0.02625}
    """
    L = _links(robot)
    out = []
    for k in range(robot.n):
        m = L.m[k]
        c = np.array([0.0 if x is None else x for x in L.c[k]])
        I = np.array(L.I[k], dtype=float) + m * (c @ c * np.eye(3) - np.outer(c, c))
        out.append([m, *(m * c), I[0, 0], I[0, 1], I[0, 2], I[1, 1], I[1, 2], I[2, 2]])
    return np.array(out).ravel()


def _cross0(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a × b`` over the first axis (length 3) of broadcasting arrays."""
    return np.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _dense(v, N: int) -> np.ndarray:
    return np.stack([np.broadcast_to(0.0 if x is None else x, (N,)) for x in v])


def regressor(robot: Robot, q, qd, qdd, *, gravity=None) -> np.ndarray:
    """The rigid-body dynamic regressor ``Y (..., n, 10 n)``: ``τ = Y(q, q̇, q̈) π`` with the
    inertial parameters ``π`` of :func:`inertial_parameters` (Atkeson, An & Hollerbach 1986).

    Newton–Euler is linear in each link's mass ``m``, first moment ``h = m c`` and inertia
    about its frame origin ``I_o``: link k's wrench about the origin of F_k is
    ``f = m a + ω̇ × h + ω × (ω × h)``, ``n = I_o ω̇ + ω × (I_o ω) + h × a``, with ``a, ω, ω̇``
    of :func:`rnea`'s outward pass (gravity in ``a``). Column (k, p) is that wrench for the
    unit parameter p of link k alone, carried inward to each joint i ≤ k
    (``f ← ᶦR f``, ``n ← ᶦR n + p × ᶦR f``) and projected on its axis; the columns of links
    before joint i are zero in row i. Armature and friction are not in it. Checked against
    Pinocchio's ``computeJointTorqueRegressor`` (tests).

    It tells what the torques can depend on for a known geometry and unknown masses: chapter
    06 feeds each joint's row to ANFIS (``LearnedID(inputs="regressor")``). It carries 10 n
    columns inward where :func:`rnea` carries one wrench, and costs about ten times as much per
    sample (``make bench``); samples are processed in chunks that stay in cache.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> q, qd, qdd = np.array([0.3, 0.2, -0.4, 0.5, 0.1]), np.ones(5), np.zeros(5)
        >>> np.allclose(regressor(robot, q, qd, qdd) @ inertial_parameters(robot), rnea(robot, q, qd, qdd))
        True
        >>> regressor(robot, np.zeros((3, 5)), qd, qdd).shape     # q (3, 5) → (3, n, 10 n)
        (3, 5, 50)
    """
    batch, a = _check(robot, q=q, qd=qd, qdd=qdd)
    g = _gravity_in_frame_0(robot, gravity)
    n = robot.n
    q, qd, qdd = (np.ascontiguousarray(np.broadcast_to(a[k], (*batch, n)).reshape(-1, n).T)
                  for k in ("q", "qd", "qdd"))
    N = q.shape[1]
    L = _links(robot)
    Y = np.empty((N, n, 10 * n))
    for start in range(0, N, _REGRESSOR_CHUNK):
        sl = slice(start, min(start + _REGRESSOR_CHUNK, N))
        Y[sl] = np.moveaxis(_regressor_T(L, q[:, sl], qd[:, sl], qdd[:, sl], g), -1, 0)
    return Y.reshape(*batch, n, 10 * n)


#: Samples per chunk of :func:`regressor` (its (n, 10 n) columns per sample stay in cache).
_REGRESSOR_CHUNK = 2048


def _regressor_T(L: _Links, q, qd, qdd, g) -> np.ndarray:
    """The regressor's recursion on ``(n, N)`` inputs; returns ``Y (n, 10 n, N)``."""
    n, N = q.shape
    c, s = cos_sin(q)
    Y = np.zeros((n, 10 * n, N))
    # Outward: each link's frame motion, then the wrench columns of its parameters.
    w, dw, acc = [None] * 3, [None] * 3, _const(-g)
    own = []
    for i in range(n):
        p, RT = L.p[i], L.RT[i]
        acc = _rz_T(c[i], s[i], _lin(RT, _plus(acc, _plus(_cross(dw, p), _cross(w, _cross(w, p))))))
        w = _rz_T(c[i], s[i], _lin(RT, w))
        dw = _rz_T(c[i], s[i], _lin(RT, dw))
        dw = _plus(dw, [_mul2(w[1], qd[i]), _mul2(_mul(-1.0, w[0]), qd[i]), qdd[i]])
        w = [w[0], w[1], _add(w[2], qd[i])]
        A, W, DW = _dense(acc, N), _dense(w, N), _dense(dw, N)
        f = np.zeros((3, 10, N))
        m = np.zeros((3, 10, N))
        f[:, 0] = A
        for j in range(3):
            e = np.zeros((3, 1))
            e[j] = 1.0
            f[:, 1 + j] = _cross0(DW, e) + _cross0(W, _cross0(W, e))
            m[:, 1 + j] = _cross0(e, A)
        for j, E in enumerate(_UNIT_INERTIAS):
            m[:, 4 + j] = E @ DW + _cross0(W, E @ W)
        own.append((f, m))
    # Inward: the columns of links i..n, about F_i's origin, in its axes.
    f_acc = m_acc = None
    for i in reversed(range(n)):
        if f_acc is not None:
            R = np.asarray(L.R[i + 1], dtype=float)
            ci, si = c[i + 1], s[i + 1]
            f_acc = np.einsum("ij,jkN->ikN", R, np.stack(
                [ci * f_acc[0] - si * f_acc[1], si * f_acc[0] + ci * f_acc[1], f_acc[2]]))
            m_acc = np.einsum("ij,jkN->ikN", R, np.stack(
                [ci * m_acc[0] - si * m_acc[1], si * m_acc[0] + ci * m_acc[1], m_acc[2]]))
            p = np.array([0.0 if x is None else x for x in L.p[i + 1]])[:, None, None]
            m_acc = m_acc + _cross0(p, f_acc)
            f_acc = np.concatenate([own[i][0], f_acc], axis=1)
            m_acc = np.concatenate([own[i][1], m_acc], axis=1)
        else:
            f_acc, m_acc = own[i]
        Y[i, 10 * i:] = m_acc[2]
    return Y
