"""Cartesian tool paths an arm with a base yaw can follow: the poses it holds while its tool
moves through given positions.

A five-joint arm of the closed form's class (a base yaw, three parallel pitch joints, a roll;
:mod:`nfarm.solvers.geometric_ik`) cannot keep a fixed orientation while its tool moves sideways, but
it can keep the orientation it has *relative to its own vertical plane*: turning the base by
``Δ`` turns every later axis and the tool's orientation about the base axis by ``Δ``, and the
pitch joints then move the tool within the turned plane without changing the pitch and roll.
:func:`plane_held_poses` builds those poses for any robot from its kinematics alone, without
assuming that the tool point lies in a vertical plane through the world's z axis, which is
false for the SO-101: its base axis is 38.8 mm from the world origin and its tool point 7.9 mm
off the roll axis (turning poses about the world's z axis instead puts 200 of the 201 poses of
chapter 02's 0.53 m line outside the SO-101's pose set, by up to 45 mm and 1°; of the poses
made here it reaches all 201, exactly — ``tests/test_tool_paths.py``).

**Equations.** With the base axis through ``o`` along the unit vector ``e`` and ``n`` the
pitch joints' common axis at ``q_ref`` (both from the geometric Jacobian: angular parts of
columns 1 and 2, ``o = p − v₁ × e`` with ``v₁`` column 1's linear part at the tool point
``p``), every pose the pitch joints reach without turning the base keeps the tool point at
the same offset ``K = n · (p_ref − o)`` along ``n``. A target position ``x`` is held after a
turn ``Δ`` about ``e`` with ``n(Δ) · (x − o) = K``, that is::

    a cos Δ + b sin Δ = c,   a = n⊥ · x',  b = (e × n⊥) · x',  c = K − (n · e)(e · x'),

``x' = x − o`` and ``n⊥ = n − (n · e) e``; ``Δ = atan2(b, a) ± acos(c / √(a² + b²))``, the sign
the one whose root at ``x = p_ref`` is ``Δ = 0`` (the reference's branch, continuous along a
path). The pose is ``(Rot(e, Δ) R_ref, x)``. Whether the pitch joints then reach ``x`` (the
two links' reach, the joint limits) is the closed form's question (:func:`nfarm.solvers.ik.closed_form`).
"""

from __future__ import annotations

import numpy as np

from ..model.kinematics import fk, jacobian
from ..model.robot import Robot

__all__ = ["plane_held_poses"]


def _rotation_about(e: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rodrigues' rotations ``(K, 3, 3)`` by ``angle (K,)`` about the unit axis ``e (3,)``."""
    E = np.array([[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]])
    c, s = np.cos(angle)[:, None, None], np.sin(angle)[:, None, None]
    return np.eye(3) + s * E + (1.0 - c) * (E @ E)


def plane_held_poses(robot: Robot, q_ref, positions, *, parallel_tol: float = 1e-9) -> np.ndarray:
    """Tool poses ``(K, 4, 4)`` at ``positions (K, 3)`` [m, world frame] that keep the tool's
    orientation relative to the arm's plane as it is at ``q_ref (n,)`` [rad] (module docstring).

    Raises:
        ValueError: ``q_ref`` or ``positions`` of the wrong shape or not finite; a robot whose
            second joint's axis is parallel to the first's (within ``parallel_tol``: no plane
            to hold); a position no turn of the base can bring to the plane's offset (closer to
            the base axis than the offset ``K``), named by its index.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> T = plane_held_poses(robot, np.zeros(5), [[0.18, 0.0, 0.195], [0.15, 0.1, 0.195],
        ...                                           [0.0, 0.2, 0.1]])     # positions [m]
        >>> from nfarm.solvers.ik import closed_form
        >>> T.shape, closed_form(robot, T).valid.any(-1).tolist()     # the arm reaches every pose
        ((3, 4, 4), [True, True, True])
    """
    q_ref = np.asarray(q_ref, dtype=float)
    x = np.asarray(positions, dtype=float)
    if q_ref.shape != (robot.n,) or not np.isfinite(q_ref).all():
        raise ValueError(f"q_ref must be {robot.n} finite joint angles [rad], got shape {q_ref.shape}")
    if x.ndim != 2 or x.shape[1] != 3 or not np.isfinite(x).all():
        raise ValueError(f"positions must be finite (K, 3) [m], got shape {x.shape}")
    T_ref, J = fk(robot, q_ref), jacobian(robot, q_ref)
    p_ref = T_ref[:3, 3]
    e = J[3:, 0] / np.linalg.norm(J[3:, 0])
    n = J[3:, 1] / np.linalg.norm(J[3:, 1])
    n_perp = n - (n @ e) * e
    if np.linalg.norm(n_perp) <= parallel_tol:
        raise ValueError(f"{robot.name}: the second joint's axis is parallel to the first's: "
                         f"the arm has no vertical plane to hold")
    o = p_ref - np.cross(J[:3, 0], e)
    K = n @ (p_ref - o)

    def turns(xs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        xp = xs - o
        a, b = xp @ n_perp, xp @ np.cross(e, n_perp)
        c = K - (n @ e) * (xp @ e)
        r = np.hypot(a, b)
        return np.arctan2(b, a), np.arccos(np.clip(c / np.where(r > 0, r, 1.0), -1.0, 1.0)), np.abs(c) - r

    psi_ref, half_ref, _ = turns(p_ref[None])
    sign = 1.0 if abs(np.angle(np.exp(1j * (psi_ref[0] + half_ref[0])))) <= \
        abs(np.angle(np.exp(1j * (psi_ref[0] - half_ref[0])))) else -1.0
    psi, half, short = turns(x)
    far = short > 1e-12 * max(1.0, abs(K))
    if far.any():
        i = int(np.argmax(far))
        raise ValueError(f"positions[{i}] = {x[i].round(4).tolist()} m is nearer the base axis than the "
                         f"arm's plane offset ({abs(K):.4g} m): no turn of the base reaches it")
    delta = psi + sign * half
    out = np.tile(np.eye(4), (len(x), 1, 1))
    out[:, :3, :3] = _rotation_about(e, delta) @ T_ref[:3, :3]
    out[:, :3, 3] = x
    return out
