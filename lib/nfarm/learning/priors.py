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

``Y_d (N, n, 13 n)`` is the rigid-body regressor :func:`nfarm.model.dynamics.regressor` (the
inertial parameters shared by all joints' rows) beside every joint's drive terms
``[q̈_j, q̇_j, sign q̇_j]`` (armature, viscous and Coulomb friction) in its own columns; ``θ``
is the least squares of the stacked rows with columns scaled to unit norm, the minimum-norm
solution kept (the regressor's columns are not all identifiable). The same least squares is
the ``identification`` baseline (:class:`nfarm.learning.baselines.IdentificationID`).

Example:
    >>> from nfarm.infra.paths import PARAMS
    >>> from nfarm.model.dynamics import rnea
    >>> from nfarm.model.robot import load_robot
    >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
    >>> rng = np.random.default_rng(0)
    >>> q, qd, qdd = (rng.uniform(-1, 1, (300, robot.n)) for _ in range(3))
    >>> tau = rnea(robot, q, qd, qdd) + 0.05 * qd                 # the arm plus a viscous term
    >>> theta = fit_identification(robot, q, qd, qdd, tau)
    >>> theta.shape, identification_width(robot)                  # 10 n + 3 n columns
    ((65,), 65)
    >>> bool(np.abs(prior_torques(robot, "identification", q, qd, qdd, theta) - tau).max() < 1e-9)
    True
    >>> bool(np.array_equal(prior_torques(robot, True, q, qd, qdd), rnea(robot, q, qd, qdd)))
    True
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..model.dynamics import regressor, rnea
from ..model.robot import Robot
from .baseline_parts import StackedLeastSquares

__all__ = ["RESIDUALS", "check_residual", "prior_of", "drive_terms", "identification_columns", "identification_width",
           "fit_identification", "prior_torques"]

#: The values ``residual`` takes: no prior, Newton–Euler's nominal model (``True`` is the same), the identification.
RESIDUALS = (False, True, "nominal", "identification")


def check_residual(value: Any, name: str = "residual") -> None:
    """Refuse a ``residual`` outside :data:`RESIDUALS`, in one line.

    Example:
        >>> check_residual("identification"); check_residual(True)
        >>> check_residual("identified")
        Traceback (most recent call last):
        ...
        ValueError: residual must be false, true (Newton–Euler's nominal model), 'nominal' or 'identification', got 'identified'
    """
    if not any(value is r if isinstance(r, bool) else (isinstance(value, str) and value == r) for r in RESIDUALS):
        raise ValueError(f"{name} must be false, true (Newton–Euler's nominal model), 'nominal' or 'identification', "
                         f"got {value!r}")


def prior_of(residual: Any) -> str | None:
    """``None`` (no prior), ``"nominal"`` or ``"identification"`` for a ``residual`` value."""
    check_residual(residual)
    if residual is False:
        return None
    return "nominal" if residual is True else residual


def drive_terms(qd, qdd) -> np.ndarray:
    """``(N, n, 3)``: each joint's ``[q̈_j, q̇_j, sign q̇_j]``."""
    return np.stack([qdd, qd, np.sign(qd)], axis=-1)


def identification_columns(robot: Robot, q, qd, qdd) -> np.ndarray:
    """``Y_d (N, n, 13 n)``: every joint's row of the rigid-body regressor and the drive terms,
    joint j's in its own three columns (module docstring)."""
    n = q.shape[1]
    own = drive_terms(qd, qdd)                                                    # (N, n, 3)
    drives = (np.eye(n)[None, :, :, None] * own[:, :, None, :]).reshape(len(q), n, 3 * n)
    return np.concatenate([regressor(robot, q, qd, qdd), drives], axis=-1)


def identification_width(robot: Robot) -> int:
    """The columns of :func:`identification_columns` for ``robot`` (``13 n``)."""
    z = np.zeros((1, robot.n))
    return identification_columns(robot, z, z, z).shape[-1]


def fit_identification(robot: Robot, q, qd, qdd, tau) -> np.ndarray:
    """``θ (13 n,)``: the least squares of ``τ (N, n)`` on :func:`identification_columns` of the
    states ``q, q̇, q̈ (N, n)`` (module docstring)."""
    return StackedLeastSquares().fit(identification_columns(robot, q, qd, qdd), tau).coef_


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
