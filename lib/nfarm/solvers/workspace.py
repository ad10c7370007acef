"""Workspace and singularity analysis: where the tool can go and how well it can move there."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import binned_statistic_2d

from ..model.kinematics import fk, fk_all, manipulability, min_singular_value
from ..model.robot import Robot, sample_configurations
from .geometric_ik import class_refusal, elbow_meeting_angles
from .ik import solve

__all__ = ["Map2D", "workspace_points", "reach", "REACH_SAMPLES", "sampled_reach", "plane_map", "joint_map", "singular_configurations",
           "near_stretched", "Volume", "workspace_volume"]


@dataclass(frozen=True)
class Map2D:
    """Values on a rectangular grid: ``values[i, j]`` belongs to the cell
    ``[x_edges[i], x_edges[i+1]) × [y_edges[j], y_edges[j+1])``; NaN where there is no data.

    Example:
        >>> grid = Map2D(np.array([0.0, 1.0, 2.0]), np.array([0.0, 0.5]), np.array([[1.0], [np.nan]]))
        >>> grid.values.shape, grid.x_edges.size - 1, grid.y_edges.size - 1     # one value per cell
        ((2, 1), 2, 1)
    """

    x_edges: np.ndarray
    y_edges: np.ndarray
    values: np.ndarray


def workspace_points(robot: Robot, n_samples: int, seed: int) -> np.ndarray:
    """Tool positions ``(n_samples, 3)`` [m] of configurations drawn uniformly within the limits.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> points = workspace_points(robot, 1000, seed=0)
        >>> points.shape     # (n_samples, 3) [m]
        (1000, 3)
    """
    return fk(robot, sample_configurations(robot, n_samples, seed))[:, :3, 3]


def reach(points: np.ndarray, robot: Robot) -> float:
    """Largest distance [m] of tool positions ``points (N, 3)`` from the first joint's origin
    (the base transform's position).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> reach(np.array([[0.18, 0.0, 0.195]]), robot).__round__(6)     # the tool point at q = 0 [m]
        0.265377
        >>> reach(workspace_points(robot, 1000, seed=0), robot) < 0.105 + 0.2 + 0.18 + 0.11     # links [m]
        True
    """
    return float(np.linalg.norm(points - robot.base[:3, 3], axis=1).max())


#: Configurations :func:`sampled_reach` draws: the arm's reach is a maximum over samples, a little
#: short of the true one, so every chapter that quotes it draws the same ones.
REACH_SAMPLES = 200_000


def sampled_reach(robot: Robot, seed: int, samples: int = REACH_SAMPLES) -> float:
    """The arm's reach [m] (:func:`reach`) over ``samples`` configurations drawn with ``seed``
    (:func:`workspace_points`): the one computation of the number chapters 1 and 8 both quote.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> sampled_reach(robot, seed=0, samples=1000) == reach(workspace_points(robot, 1000, 0), robot)
        True
    """
    return reach(workspace_points(robot, samples, seed), robot)


def plane_map(robot: Robot, n_samples: int, bins: int, seed: int, *,
              part: str = "position") -> Map2D:
    """The best manipulability reachable in each cell of the vertical plane ``y = 0``.

    Configurations are drawn within the limits with ``q_1 = 0`` (for an arm whose first joint
    turns about the base z axis, any other ``q_1`` turns the same picture about that axis), the
    tool positions ``(x, z)`` binned, and each cell keeps the largest ``w`` among its samples:
    a cell with a small value can only be reached close to a singularity.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> grid = plane_map(robot, 2000, bins=8, seed=0)
        >>> grid.values.shape, grid.x_edges.shape, grid.y_edges.shape     # (x, z) cells [m]
        ((8, 8), (9,), (9,))
    """
    q = sample_configurations(robot, n_samples, seed)
    q[:, 0] = 0.0
    p = fk(robot, q)[:, :3, 3]
    w = manipulability(robot, q, part=part)
    values, x_edges, z_edges, _ = binned_statistic_2d(p[:, 0], p[:, 2], w, "max", bins=bins)
    return Map2D(x_edges, z_edges, values)


def joint_map(robot: Robot, i: int, j: int, points: int, *, part: str = "position",
              q_rest: np.ndarray | None = None) -> Map2D:
    """Manipulability over joints ``i`` and ``j`` (0-based) across their limits, the other
    joints held at ``q_rest`` (zero by default); ``points`` samples per joint.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> grid = joint_map(robot, 1, 2, points=4)     # shoulder and elbow
        >>> (grid.x_edges.round(4) + 0.0).tolist()     # the shoulder's cell edges [rad]
        [-1.5708, -0.7854, 0.0, 0.7854, 1.5708]
        >>> grid.values.shape
        (4, 4)
    """
    q_rest = np.zeros(robot.n) if q_rest is None else np.asarray(q_rest, dtype=float)
    edges_i = np.linspace(*robot.qlim[i], points + 1)
    edges_j = np.linspace(*robot.qlim[j], points + 1)
    qi, qj = np.meshgrid((edges_i[:-1] + edges_i[1:]) / 2, (edges_j[:-1] + edges_j[1:]) / 2,
                         indexing="ij")
    q = np.broadcast_to(q_rest, (*qi.shape, robot.n)).copy()
    q[..., i], q[..., j] = qi, qj
    return Map2D(edges_i, edges_j, manipulability(robot, q, part=part))


def singular_configurations(robot: Robot, *, steps: int = 721) -> tuple[dict[str, np.ndarray], str]:
    """Named configurations [rad] at the arm's elbow singularities, computed from its geometry,
    and a note for the reader ("" when there is nothing to say).

    The ready pose (0 moved into the limits), and the elbow at each angle where its two links
    are in line (``"arm stretched"``, ``"arm folded"``: the closed form's meeting angles,
    :func:`nfarm.solvers.geometric_ik.elbow_meeting_angles`, where they lie within the elbow's limits)
    with the wrist turned to put the tool point on that line too — a root of the tool's signed
    distance from the line through the shoulder and wrist axes, bracketed on ``steps`` wrist
    angles and refined by Brent's method (``scipy.optimize.brentq``); every other joint at 0.
    Where no root exists, the wrist angle of least position σ_min. An arm outside the closed
    form's class (:func:`nfarm.solvers.geometric_ik.class_refusal`) gets its ready pose and a note.

    Why computed, not written down: the angles at which an arm is stretched depend on its DH
    offsets (intelbot5: elbow 90°; the SO-101: −73.8°), so poses written for one arm are
    ordinary configurations of another.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> named, note = singular_configurations(robot)
        >>> list(named), note
        (['ready (q = 0)', 'arm stretched', 'arm folded'], '')
        >>> (named["arm stretched"].round(6) + 0.0).tolist()     # elbow and wrist at 90° [rad]
        [0.0, 0.0, 1.570796, 1.570796, 0.0]
    """
    from scipy.optimize import brentq

    ready = np.clip(0.0, robot.qlim[:, 0], robot.qlim[:, 1])
    refusal = class_refusal(robot)
    if refusal:
        return {"ready (q = 0)": ready}, f"No stretched or folded configuration is computed for {robot.name}: {refusal}."
    axis = (lambda k: k - 1) if robot.convention == "standard" else (lambda k: k)   # frame of joint k's axis

    def with_wrist(elbow, wrist):
        q = np.tile(ready, np.shape(wrist) + (1,))
        q[..., 2], q[..., 3] = elbow, wrist
        return q

    def off_line(q):
        """The tool point's signed distance from the line through the shoulder and wrist axes [m]."""
        frames, tool = fk_all(robot, q), fk(robot, q)[..., :3, 3]
        p2, p4, n = frames[..., axis(2), :3, 3], frames[..., axis(4), :3, 3], frames[..., axis(2), :3, 2]
        u = p4 - p2
        return np.einsum("...i,...i", n, np.cross(u, tool - p2)) / np.linalg.norm(u, axis=-1)

    def in_line(elbow):
        wrist = np.linspace(robot.qlim[3, 0], robot.qlim[3, 1], steps)
        f = off_line(with_wrist(elbow, wrist))
        roots = [brentq(lambda x: float(off_line(with_wrist(elbow, x))), wrist[k], wrist[k + 1], xtol=1e-15)
                 for k in np.flatnonzero(np.sign(f[:-1]) * np.sign(f[1:]) <= 0)]
        q = with_wrist(elbow, np.array(roots if roots else wrist))
        return q[np.argmin(min_singular_value(robot, q))]

    named = {"ready (q = 0)": ready}
    for name, elbow in zip(("arm stretched", "arm folded"), elbow_meeting_angles(robot)):
        if robot.qlim[2, 0] <= elbow <= robot.qlim[2, 1]:
            named[name] = in_line(elbow)
    return named, ""


def near_stretched(robot: Robot, stretched: np.ndarray, degrees: float) -> np.ndarray:
    """``stretched (n,)`` [rad] (:func:`singular_configurations`) with the elbow moved
    ``degrees`` towards the middle of its range: a configuration next to the singularity,
    inside the limits.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> stretched = singular_configurations(robot)[0]["arm stretched"]
        >>> (near_stretched(robot, stretched, 5.0).round(6) + 0.0).tolist()     # elbow at 85° [rad]
        [0.0, 0.0, 1.48353, 1.570796, 0.0]
    """
    if not 0 < degrees < 90:
        raise ValueError(f"degrees from stretched must be in (0, 90), got {degrees!r}")
    near = np.array(stretched, dtype=float)
    inward = np.sign(robot.qlim[2].mean() - near[2]) or 1.0
    near[2] += inward * np.radians(degrees)
    return near


@dataclass(frozen=True)
class Volume:
    """A Monte Carlo estimate of the workspace's volume: made by
    :func:`workspace_volume`, which has an example."""

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

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> v = workspace_volume(robot, reach_m=0.5, n_points=400)
        >>> 0.0 < v.share < 1.0, round(v.volume / (4 / 3 * np.pi * 0.5**3), 12) == round(v.share, 12)
        (True, True)
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
