"""Feature bases of joint states for learning inverse dynamics without the arm's parameters
(chapters 06 and 07).

What holds for every rigid arm with revolute joints, whatever its masses and lengths:

* the torque is **affine in the accelerations and quadratic in the velocities**,
  ``τ = M(q) q̈ + C(q, q̇) q̇ + g(q)``, so it is a sum of the terms ``1, q̈_k, q̇_k q̇_l``
  (:func:`dynamic_terms`: ``1 + n + n(n + 1)/2`` of them, 21 for five joints) each times a
  function of the configuration;
* those functions are **trigonometric polynomials** of the joint angles: a link's rotation is a
  product of the joints' ``Rz(q_i) Rx(α_i)``, its inertia enters ``M`` through products of two
  rotation entries, gravity through one;
* consecutive joints whose axes are **parallel** (a pitch chain: intelbot5's and the SO-101's
  joints 2–4) turn the links beyond them by the *sum* of their angles, so the torques depend on
  ``sin, cos`` of those sums (:func:`parallel_runs`, read off the kinematic structure — which
  axes are parallel, not how long or heavy anything is).

Bases (:func:`basis`; each is ``dynamic_terms ⊗ configuration terms``):

* ``"generic"`` — the configuration terms ``1, sin q_i, cos q_i`` and every product of two of
  them: ``1 + 2n + 2n(2n + 1)/2`` terms (66 for five joints; 1 386 features in all). Knows
  nothing of the arm but its number of joints;
* ``"chain"`` — the same over the joint angles *and* the sums of every stretch of parallel
  joints (intelbot5: ``q2+q3``, ``q3+q4``, ``q2+q3+q4``; 153 terms, 3 213 features). For arms
  like intelbot5 (a base yaw, a pitch chain, a roll) this span holds the rigid-body model
  exactly, and the SO-101's nearly (its fit leaves a fraction of a per cent of the torques' spread:
  chapter 6.5's table), so a linear fit of it is an identification in disguise — chapter 06 says so;
* ``"generic_linear"``, ``"chain_linear"`` — dynamic terms times ``1`` and the ``sin, cos`` of
  the angles (and sums), *without* their products (231 and 357 features for intelbot5): what
  one first-order rule of :class:`nfarm.learning.learned_id.LearnedID` with ``inputs="affine_generic"`` or
  ``"affine"`` sees; the products it needs are left to the fuzzy rules over ``q``;
* any of them with ``_drives`` (``"generic_drives"``, ``"chain_linear_drives"``, …) — the same
  columns and every joint's **drive terms** ``q̇_j, sign q̇_j`` (:func:`drive_terms`: viscous and
  Coulomb friction; the armature's ``q̈_j`` is already a dynamic term). A built arm's joints turn
  in bearings and gears, whatever the arm: what holds for every *driven* arm, not for this one.
  A rigid-body basis cannot represent friction, which is odd in ``q̇`` and not smooth at rest:
  on chapter 5's measured arm the bases without these columns miss a friction-dominated joint
  by more than its torque's spread.

All functions are pure and batched over the sample axis: ``q, qd, qdd (N, n)`` [rad, rad/s,
rad/s²] → ``(N, F)``.

**Tiers of prior knowledge** (:data:`TIERS`, :func:`tier_of`): every learned inverse dynamics of
the study is named by what it assumes of the arm — *generic* (what holds for every rigid arm:
functions of ``q``, affine in ``q̈``, quadratic in ``q̇``; with ``_drives``, every driven joint's
friction; nothing about this arm), *structure-informed* (which axes are parallel: the ``chain``
bases without their products, the ``affine`` input sets, the ``sin, cos`` of the parallel joints' angle sums; no length
or mass), *rigid-body span* (a linear fit of the ``chain`` basis with its products, ``"chain"`` and ``"chain_drives"``:
its span holds the rigid-body model of an arm of this kind exactly, or nearly, so the fit is an identification in disguise — a
tier of its own, not a rival of the structure-informed learners, issue 65), *identification* (the geometry known, the
inertial parameters fitted: the rigid-body regressor, its columns as a learner's inputs too), *identification +
learned* (the same knowledge: the identification of the arm as built, fitted first by least squares, and a learner of
what it misses, ``residual="identification"``, :mod:`nfarm.learning.priors` — a tier of its own, so that each learner
there has the same budget as in the others), or *nominal model + learned* (Newton–Euler with the nominal masses, and a
learned or identified correction of what it misses).
"""

from __future__ import annotations

import functools

import numpy as np

from ..infra.arguments import check_choice
from ..model.kinematics import jacobian
from ..model.robot import Robot

__all__ = ["BASES", "DRIVES", "TIERS", "tier_of", "parallel_runs", "angle_sums", "dynamic_terms", "drive_terms",
           "configuration_terms", "basis", "basis_width"]

_RIGID_BASES = ("generic", "chain", "generic_linear", "chain_linear")
BASES = _RIGID_BASES + tuple(f"{kind}_drives" for kind in _RIGID_BASES)
#: The suffix of a basis with the joints' drive terms (:func:`drive_terms`).
DRIVES = "_drives"

#: The tiers of prior knowledge, by key, as tables name them (module docstring).
TIERS = {"generic": "generic", "structure": "structure-informed", "span": "rigid-body span",
         "identification": "identification", "identified": "identification + learned",
         "nominal": "nominal model + learned"}
_STRUCTURE_INPUTS, _IDENTIFICATION_INPUTS = ("affine", "affine_drives"), ("regressor", "regressor_drives")
_STRUCTURE_BASES = ("chain_linear", "chain_linear_drives")
_SPAN_BASES = ("chain", "chain_drives")


def tier_of(params) -> str:
    """The tier (a :data:`TIERS` label) of a learned inverse dynamics described by ``params``, a
    sweep cell's flat parameters: ``residual`` (true or ``"nominal"``: Newton–Euler's nominal model is
    used; ``"identification"``: the identification of the arm as built), the
    ANFIS's ``inputs`` (``learned_id`` cells) or a baseline's ``learner`` and ``basis`` or
    ``angles`` (the ``identification`` learner fits the inertial parameters on the known geometry;
    ``angles="regressor"`` gives a learner the regressor's columns).

    Example:
        >>> tier_of({"inputs": "affine"}), tier_of({"learner": "ridge", "basis": "generic"})
        ('structure-informed', 'generic')
        >>> tier_of({"inputs": "affine_drives"}), tier_of({"learner": "ridge", "basis": "generic_drives"})
        ('structure-informed', 'generic')
        >>> tier_of({"inputs": "regressor"}), tier_of({"learner": "boosting", "residual": True})
        ('identification', 'nominal model + learned')
        >>> tier_of({"learner": "mlp", "angles": "chain"}), tier_of({"learner": "ridge", "basis": "chain_linear"})
        ('structure-informed', 'structure-informed')
        >>> tier_of({"learner": "ridge", "basis": "chain_drives"}), tier_of({"learner": "mlp", "angles": "regressor"})
        ('rigid-body span', 'identification')
        >>> tier_of({"learner": "mlp", "residual": "identification"}), tier_of({"inputs": "own", "residual": "nominal"})
        ('identification + learned', 'nominal model + learned')
    """
    if params.get("residual") == "identification":
        return TIERS["identified"]
    if params.get("residual"):
        return TIERS["nominal"]
    if params.get("inputs") is not None and params.get("learner") is None:
        inputs = params["inputs"]
        return TIERS["structure" if inputs in _STRUCTURE_INPUTS else
                     "identification" if inputs in _IDENTIFICATION_INPUTS else "generic"]
    if params.get("learner") is None:
        raise ValueError(f"a learned inverse dynamics needs inputs or a learner, got {dict(params)!r}")
    if params["learner"] == "identification" or params.get("angles") == "regressor":
        return TIERS["identification"]
    if params.get("basis") in _SPAN_BASES:
        return TIERS["span"]
    return TIERS["structure" if params.get("basis") in _STRUCTURE_BASES or params.get("angles") == "chain" else "generic"]


@functools.lru_cache(maxsize=32)
def _runs(robot: Robot, axis_tol: float) -> tuple[tuple[int, ...], ...]:
    rng = np.random.default_rng(0)
    lo, hi = robot.qlim[:, 0], robot.qlim[:, 1]
    q = lo + (hi - lo) * rng.random((16, robot.n))
    axes = np.moveaxis(jacobian(robot, q)[:, 3:, :], 1, 2)                 # (16, n, 3)
    parallel = np.linalg.norm(np.cross(axes[:, :-1], axes[:, 1:]), axis=-1).max(axis=0) <= axis_tol
    runs, start = [], 0
    for j in range(1, robot.n + 1):
        if j == robot.n or not parallel[j - 1]:
            if j - start >= 2:
                runs.append(tuple(range(start, j)))
            start = j
    return tuple(runs)


def parallel_runs(robot: Robot, *, axis_tol: float = 1e-3) -> list[tuple[int, ...]]:
    """The stretches of two or more consecutive joints (0-based indices) whose axes stay
    parallel: ``|z_j × z_{j+1}| ≤ axis_tol`` at 16 seeded random configurations (the axes are
    the angular rows of :func:`nfarm.model.kinematics.jacobian`). ``axis_tol`` [rad] accepts the
    SO-101's URDF-derived pitch axes (3.7e-6 rad apart). intelbot5 and the SO-101: ``[(1, 2,
    3)]``."""
    return [tuple(r) for r in _runs(robot, float(axis_tol))]


def _sum_columns(robot: Robot) -> list[tuple[int, ...]]:
    """The joint sets whose angle sums the chain bases use: every joint alone, then every
    stretch of two or more consecutive joints within a parallel run."""
    sets = [(j,) for j in range(robot.n)]
    for run in parallel_runs(robot):
        for length in range(2, len(run) + 1):
            sets += [run[i:i + length] for i in range(len(run) - length + 1)]
    return sets


def angle_sums(robot: Robot, q: np.ndarray) -> np.ndarray:
    """``(N, K)``: the joint angles, then the sums of every stretch of parallel joints."""
    return np.column_stack([q[:, list(s)].sum(axis=1) for s in _sum_columns(robot)])


def dynamic_terms(qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """``(N, 1 + n + n(n + 1)/2)``: ``1``, ``q̈_k``, ``q̇_k q̇_l`` (k ≤ l)."""
    k, l = np.triu_indices(qd.shape[1])
    return np.column_stack([np.ones(len(qd)), qdd, qd[:, k] * qd[:, l]])


def configuration_terms(angles: np.ndarray, *, products: bool = True) -> np.ndarray:
    """``(N, 1 + 2K [+ 2K(2K + 1)/2])``: ``1``, ``sin, cos`` of each of ``K`` angles and, with
    ``products``, every product of two of those (squares included)."""
    t = np.column_stack([np.sin(angles), np.cos(angles)])
    columns = [np.ones((len(t), 1)), t]
    if products:
        i, j = np.triu_indices(t.shape[1])
        columns.append(t[:, i] * t[:, j])
    return np.concatenate(columns, axis=1)


def drive_terms(qd: np.ndarray) -> np.ndarray:
    """``(N, 2n)``: every joint's ``q̇_j`` (viscous friction), then its ``sign q̇_j`` (Coulomb
    friction; 0 at rest).

    Example:
        >>> drive_terms(np.array([[0.5, -2.0, 0.0]]))
        array([[ 0.5, -2. ,  0. ,  1. , -1. ,  0. ]])
    """
    return np.column_stack([qd, np.sign(qd)])


def _kind(kind: str) -> tuple[str, bool]:
    """A basis's rigid part and whether it has the drive terms."""
    check_choice("basis", kind, BASES)
    return (kind[:-len(DRIVES)], True) if kind.endswith(DRIVES) else (kind, False)


def basis(robot: Robot, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, kind: str) -> np.ndarray:
    """The basis ``kind`` (:data:`BASES`) of states ``q, qd, qdd (N, n)``: ``(N, F)``, the
    outer product of :func:`dynamic_terms` and the configuration terms, dynamic term major
    (its first column the constant 1); with ``_drives``, :func:`drive_terms` after them.

    Example (intelbot5: 1 386 rigid-body features, and 10 drive terms for its five joints):
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> q = np.zeros((2, 5))
        >>> basis(robot, q, q, q, "generic").shape, basis(robot, q, q, q, "generic_drives").shape
        ((2, 1386), (2, 1396))
    """
    rigid, drives = _kind(kind)
    angles = q if rigid.startswith("generic") else angle_sums(robot, q)
    conf = configuration_terms(angles, products=not rigid.endswith("_linear"))
    dyn = dynamic_terms(qd, qdd)
    out = (dyn[:, :, None] * conf[:, None, :]).reshape(len(q), -1)
    return np.concatenate([out, drive_terms(qd)], axis=1) if drives else out


def basis_width(robot: Robot, kind: str) -> int:
    """Columns of :func:`basis` for ``robot``."""
    n = robot.n
    rigid, drives = _kind(kind)
    K = n if rigid.startswith("generic") else len(_sum_columns(robot))
    conf = 1 + 2 * K + (0 if rigid.endswith("_linear") else 2 * K * (2 * K + 1) // 2)
    return (1 + n + n * (n + 1) // 2) * conf + 2 * n * drives
