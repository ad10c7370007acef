"""The model a residual learner of inverse dynamics adds its learned part to (chapter 6.8):
Newton–Euler with the nominal masses, or the identification of the arm as built.

A learned inverse dynamics with ``residual`` set learns ``τ − τ_prior(q, q̇, q̈)`` and predicts
``τ_prior + learned``:

* ``residual=False`` — no prior: the torques themselves are learned;
* ``residual=True`` (or ``"nominal"``) — ``τ_prior = rnea(q, q̇, q̈)``, Newton–Euler with the
  robot file's nominal masses (the *nominal model + learned* tier; Nguyen-Tuong & Peters 2010);
* ``residual="identification"`` — ``τ_prior = Y_d(q, q̇, q̈) θ``, the identification of the arm
  as built (Atkeson, An & Hollerbach 1986), fitted first, by least squares, on the same training
  states the learner then fits the rest of (the *identification + learned* tier: the geometry
  known, nothing of the masses; :func:`identification_columns`, :func:`fit_identification`).

``Y_d (N, n, 14 n)`` is the rigid-body regressor :func:`nfarm.model.dynamics.regressor` (the
inertial parameters shared by all joints' rows) beside every joint's law terms
``[q̈_j, q̇_j, tanh(q̇_j / ε_j), 1]`` in its own columns (:func:`law_terms`): the robot file's own
drive law (:func:`nfarm.model.dynamics.joint_drive_torques`, ``I_a q̈ + b q̇ + τ_c tanh(q̇ / ε)``;
armature, viscous and Coulomb friction, the robot file's smoothing speed ``ε``) and the torque
reading's zero offset (a current sensor's uncalibrated zero, chapter 05), whose four parameters per
joint the identification fits. (With ``sign q̇`` for the Coulomb column, as before 2026-12-07, the
identification's residual held a jump at rest that the arm's friction does not have: on seed 0's
validation data the SO-101's identification scored 5.7 % worst-joint NRMSE with it and 4.7 % with
the file's law, and a smooth learner on its residual 5.1 % and 4.0 %. Without the offset column (added
later on 2026-12-07), the identification missed each reading's constant zero, which every learner's
intercept fits: on the same data its worst joint scored 21.7 % on intelbot5 and 4.7 % on the SO-101,
with it 14.5 % and 3.9 %.) ``θ`` is the least squares of the stacked rows with columns scaled to unit
norm, the minimum-norm solution kept (the regressor's columns are not all identifiable). The same
least squares is the ``identification`` baseline (:class:`nfarm.learning.baselines.IdentificationID`).

Example:
    >>> from nfarm.infra.paths import PARAMS
    >>> from nfarm.model.dynamics import rnea
    >>> from nfarm.model.robot import load_robot
    >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
    >>> rng = np.random.default_rng(0)
    >>> q, qd, qdd = (rng.uniform(-1, 1, (300, robot.n)) for _ in range(3))
    >>> tau = rnea(robot, q, qd, qdd) + 0.05 * qd + 0.01          # the arm, a viscous term, a zero offset
    >>> theta = fit_identification(robot, q, qd, qdd, tau)
    >>> theta.shape, identification_width(robot)                  # 10 n + 4 n columns
    ((70,), 70)
    >>> bool(np.abs(prior_torques(robot, "identification", q, qd, qdd, theta) - tau).max() < 1e-9)
    True
    >>> bool(np.array_equal(prior_torques(robot, True, q, qd, qdd), rnea(robot, q, qd, qdd)))
    True
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..infra.reading import Validator, show
from ..model.dynamics import regressor, rnea
from ..model.robot import Robot
from .baseline_parts import StackedLeastSquares

__all__ = ["RESIDUALS", "check_residual", "prior_of", "drive_terms", "law_terms", "identification_columns",
           "identification_width", "fit_identification", "fit_prior", "prior_torques", "read_prior", "DRIVE_LAW",
           "FITTED_LAW", "drive_law_field", "read_drive_law"]

#: A saved model's ``drive_law`` field where its inputs hold :func:`drive_terms` (a learner on the regressor's columns):
#: a file without it was saved while the Coulomb column was ``sign q̇`` (before 2026-12-07) and would predict other
#: torques, so it is refused.
DRIVE_LAW = "tanh(qd/coulomb_velocity)"

#: The ``drive_law`` field of a model that fits :func:`law_terms` by least squares (the friction identification, the
#: identification, a learner on the identification's residual): a file with another was saved before the law had its
#: zero offset or its ``tanh`` (both added on 2026-12-07) and would predict other torques, so it is refused.
FITTED_LAW = "tanh(qd/coulomb_velocity) + offset"

#: The values ``residual`` takes: no prior, Newton–Euler's nominal model (``True`` is the same), the identification.
RESIDUALS = (False, True, "nominal", "identification")


def check_residual(value: Any, name: str = "residual") -> None:
    """Refuse a ``residual`` outside :data:`RESIDUALS`, in one line.

    Example:
        >>> check_residual("identification"); check_residual(True)
        >>> check_residual("identified")
        Traceback (most recent call last):
        ...
        ValueError: residual must be false (no prior), true or 'nominal' (Newton–Euler's nominal model) or 'identification' (the identification of the arm as built), got 'identified'
    """
    if not any(value is r if isinstance(r, bool) else (isinstance(value, str) and value == r) for r in RESIDUALS):
        raise ValueError(f"{name} must be false (no prior), true or 'nominal' (Newton–Euler's nominal model) or "
                         f"'identification' (the identification of the arm as built), got {value!r}")


def prior_of(residual: Any) -> str | None:
    """``None`` (no prior), ``"nominal"`` or ``"identification"`` for a ``residual`` value."""
    check_residual(residual)
    if residual is False:
        return None
    return "nominal" if residual is True else residual


def drive_terms(robot: Robot, qd, qdd) -> np.ndarray:
    """``(N, n, 3)``: each joint's ``[q̈_j, q̇_j, tanh(q̇_j / ε_j)]``, the columns of the robot
    file's drive law (:func:`nfarm.model.dynamics.joint_drive_torques`: times ``[I_a, b, τ_c]``
    they are its torques; ``ε``, the file's ``coulomb_velocity``).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "so101.yaml")
        >>> drive_terms(robot, np.array([[0.5, -0.5, 0.0, 0.001, 1.0]]), np.zeros((1, 5)))[0, :, 2].round(3).tolist()
        [1.0, -1.0, 0.0, 0.1, 1.0]
    """
    qd, qdd = np.asarray(qd, float), np.asarray(qdd, float)
    return np.stack([qdd, qd, np.tanh(qd / robot.coulomb_velocity)], axis=-1)


def law_terms(robot: Robot, qd, qdd) -> np.ndarray:
    """``(N, n, 4)``: each joint's ``[q̈_j, q̇_j, tanh(q̇_j / ε_j), 1]`` — :func:`drive_terms` and
    the torque reading's zero offset, the columns a least-squares law fits per joint (the friction
    identification's and, beside the rigid-body regressor, the identification's: module docstring).
    A learner needs no offset column: its intercept is one.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "so101.yaml")
        >>> law_terms(robot, np.array([[0.5, -0.5, 0.0, 0.001, 1.0]]), np.ones((1, 5)))[0, 1].round(3).tolist()
        [1.0, -0.5, -1.0, 1.0]
    """
    drives = drive_terms(robot, qd, qdd)
    return np.concatenate([drives, np.ones(drives.shape[:-1] + (1,))], axis=-1)


def identification_columns(robot: Robot, q, qd, qdd) -> np.ndarray:
    """``Y_d (N, n, 14 n)``: every joint's row of the rigid-body regressor and its law terms
    (:func:`law_terms`), joint j's in its own four columns (module docstring)."""
    n = q.shape[1]
    own = law_terms(robot, qd, qdd)                                               # (N, n, 4)
    k = own.shape[-1]
    drives = (np.eye(n)[None, :, :, None] * own[:, :, None, :]).reshape(len(q), n, k * n)
    return np.concatenate([regressor(robot, q, qd, qdd), drives], axis=-1)


def identification_width(robot: Robot) -> int:
    """The columns of :func:`identification_columns` for ``robot`` (``14 n``)."""
    z = np.zeros((1, robot.n))
    return identification_columns(robot, z, z, z).shape[-1]


def fit_identification(robot: Robot, q, qd, qdd, tau) -> np.ndarray:
    """``θ (14 n,)``: the least squares of ``τ (N, n)`` on :func:`identification_columns` of the
    states ``q, q̇, q̈ (N, n)`` (module docstring)."""
    return StackedLeastSquares().fit(identification_columns(robot, q, qd, qdd), tau).coef_


def fit_prior(robot: Robot, residual: Any, q, qd, qdd, tau) -> tuple[np.ndarray | None, np.ndarray | float, float]:
    """The prior of ``residual`` on the training states ``q, q̇, q̈, τ (N, n)``: ``(θ, τ_prior, seconds)``
    — the identification's ``θ`` (:func:`fit_identification`; ``None`` for another prior), its
    torques ``(N, n)`` [N·m] on those states (``0.0`` without a prior) and the seconds its fit and
    torques took. The identification's columns are built once, before the clock starts, as every
    learner's features are (:class:`nfarm.learning.baselines.IdentificationID` times the same least
    squares alone).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> q = np.random.default_rng(0).uniform(-1, 1, (50, robot.n))
        >>> theta, torques, seconds = fit_prior(robot, "identification", q, q, q, np.zeros_like(q))
        >>> theta.shape, torques.shape, fit_prior(robot, False, q, q, q, q)[:2]
        ((70,), (50, 5), (None, 0.0))
    """
    if prior_of(residual) == "identification":
        columns = identification_columns(robot, q, qd, qdd)
        start = time.perf_counter()
        theta = StackedLeastSquares().fit(columns, tau).coef_
        return theta, columns @ theta, time.perf_counter() - start
    start = time.perf_counter()
    torques = prior_torques(robot, residual, q, qd, qdd)
    return None, torques, time.perf_counter() - start


def prior_torques(robot: Robot, residual: Any, q, qd, qdd, theta: np.ndarray | None = None) -> np.ndarray | float:
    """``τ_prior (N, n)`` [N·m] of the states ``(N, n)``: ``rnea`` for the nominal prior, the
    identification ``Y_d θ`` (``theta``: :func:`fit_identification`'s) for ``"identification"``,
    ``0.0`` without a prior."""
    prior = prior_of(residual)
    if prior is None:
        return 0.0
    if prior == "nominal":
        return rnea(robot, q, qd, qdd)
    if theta is None:
        raise ValueError("residual='identification' needs the identification's theta (fit_identification)")
    return identification_columns(robot, q, qd, qdd) @ theta


def read_prior(v: Validator, data: dict, residual: Any, robot: Robot) -> np.ndarray | None:
    """A saved model's ``prior`` field, checked by ``v``: ``θ (14 n,)`` for an identification
    residual (required), absent for any other (``null`` included: refused)."""
    if prior_of(residual) == "identification":
        return v.array(data.get("prior"), "prior", (identification_width(robot),))
    if "prior" in data:
        v.fail("prior", f"must be absent for residual={show(residual)} (only an identification residual has one), "
                        f"got {show(data['prior'])}")
    return None


def drive_law_field(law: str | None) -> dict:
    """``{"drive_law": law}`` for a model whose predictions use a drive law (:data:`DRIVE_LAW` or
    :data:`FITTED_LAW`), ``{}`` for one that uses none (``law`` ``None``)."""
    return {} if law is None else {"drive_law": law}


def read_drive_law(v: Validator, data: dict, law: str | None) -> None:
    """Refuse (through ``v``) a saved model whose predictions use a drive law (``law``:
    :data:`DRIVE_LAW` or :data:`FITTED_LAW`) but whose ``drive_law`` is not it — saved under an older
    law, it would predict other torques — or one that names a law it does not use (``law`` ``None``)."""
    if law is not None and data.get("drive_law") != law:
        got = show(data["drive_law"]) if "drive_law" in data else "nothing (the field is missing)"
        v.fail("drive_law", f"must be {law!r}, got {got}: the file was saved under an older drive law (the Coulomb "
                            f"column sign(qd), or no zero offset, before 2026-12-07) and would predict "
                            f"other torques; refit it")
    if law is None and "drive_law" in data:
        v.fail("drive_law", f"must be absent for a model that uses no drive terms, got {show(data['drive_law'])}")
