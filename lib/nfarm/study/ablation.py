"""What an encoding gives before any learning (issue 41's credit ablation, chapter 7.1): the
simplest learner that uses an encoding of the tool pose — one least-squares **linear** map from
the encoding's features (and a constant) to the joint angles — so that a reader sees how much of
a learned IK's accuracy is the encoding's and how much the learner adds beyond it.

The arm's plane (``arm_plane``) gives the base joint and the roll as linear functions of its
features (the tool point's azimuth, the roll about the approach axis), and the pitch joints as
non-linear ones of the rest; the dissertation's seven inputs (``quat_xyz``) give no joint
linearly. A frozen model: fitted on the training poses only, then judged, like every other
model, once on the test poses.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..learning.encoding import PoseEncoder
from ..model.robot import Robot
from .contest import label, learner_of, structure_of

__all__ = ["LinearOnEncoding", "linear_on_encoding", "STRUCTURE_LABELS", "structure_ablation"]


@dataclass(frozen=True)
class LinearOnEncoding:
    """A fitted linear map ``q = [x, 1] W`` from an encoding's inputs ``x (..., d)`` of a tool
    pose (:class:`nfarm.learning.encoding.PoseEncoder`: unwrapped and scaled as a learned IK's)
    to the joint angles ``q (..., n)`` [rad] (:func:`linear_on_encoding`)."""

    encoder: PoseEncoder
    weights: np.ndarray               # (d + 1, n)

    def predict(self, T_0e: np.ndarray) -> np.ndarray:
        """Joint angles ``(..., n)`` [rad] for tool poses ``T_0e (..., 4, 4)``."""
        x = self.encoder.transform(np.asarray(T_0e, dtype=float))
        return np.concatenate([x, np.ones(x.shape[:-1] + (1,))], axis=-1) @ self.weights


def linear_on_encoding(robot: Robot, encoding: str, train: Mapping, *,
                       max_out_of_plane: float = 1e-6) -> LinearOnEncoding:
    """The least-squares linear map from ``encoding``'s inputs of the training poses
    ``train["T"] (N, 4, 4)`` (unwrapped and scaled as a learned IK's; ``max_out_of_plane`` [rad]
    as :class:`nfarm.learning.encoding.PoseEncoder`'s) to their joint angles ``train["q"] (N, n)``
    [rad]: what the encoding gives with nothing learned beyond a linear map (module docstring).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.kinematics import fk
        >>> from nfarm.model.robot import load_robot, sample_configurations
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> q = sample_configurations(robot, 2000, 0) * 0.2          # near home, one branch
        >>> floor = linear_on_encoding(robot, "arm_plane", {"T": fk(robot, q), "q": q})
        >>> bool(np.abs(floor.predict(fk(robot, q))[:, 0] - q[:, 0]).max() < 1e-9)   # the base joint: exact
        True

    Raises:
        ValueError: an unknown encoding, poses that leave the arm's plane (``"arm_plane"``), or
            training poses and angles of different counts.
    """
    T, q = np.asarray(train["T"], dtype=float), np.asarray(train["q"], dtype=float)
    if T.ndim != 3 or T.shape[1:] != (4, 4) or q.shape != (len(T), robot.n):
        raise ValueError(f"train: T {T.shape} and q {q.shape} must be (N, 4, 4) and (N, {robot.n})")
    encoder = PoseEncoder(encoding, max_out_of_plane=max_out_of_plane)
    x = encoder.fit_transform(robot, T)
    A = np.concatenate([x, np.ones((len(x), 1))], axis=1)
    weights = np.linalg.lstsq(A, q, rcond=None)[0]
    return LinearOnEncoding(encoder, weights)


# --------------------------------------------------------------------------------------------
# The structure's ablation (issue 64, chapter 7.1): structure × learner on the test poses

#: The structures of the ablation, in the order shown: one model of all the joints (the rivals'
#: own), the ANFIS's structure with the last pitch joint learned, and with it closed from the
#: target's pitch (:mod:`nfarm.learning.ik_rivals`).
STRUCTURE_LABELS = {"whole": "one model of all the joints",
                    "arm_open": "the ANFIS's structure, the last pitch joint learned",
                    "arm": "the ANFIS's structure, the last pitch joint closed"}


def structure_ablation(anfis, rivals: Mapping[str, object]) -> dict[tuple[str, str], object]:
    """Each learner's frozen chosen model in every structure the learned-IK contest trained it
    in, with and without the pitch closure: ``(learner, structure) → model``, ``learner`` a
    contestant's words (:func:`nfarm.study.contest.label` of its learner), ``structure`` a key
    of :data:`STRUCTURE_LABELS`.

    Args:
        anfis: the chosen :class:`nfarm.learning.learned.LearnedIK` (its closure dropped by
            :meth:`~nfarm.learning.learned.LearnedIK.without_closure` for ``"arm_open"``); one
            without a closure (an arm the arm's plane cannot describe) is left out.
        rivals: the contest's chosen rivals by contestant (:func:`nfarm.study.contest.saved_rivals`:
            ``"rbf"``, ``"rbf:arm"``, …).

    The models are the contest's, not retrained: ``"arm_open"`` predicts the last pitch joint by
    the model's own learned output, so a difference from ``"arm"`` is the closure's alone; the
    difference of ``"whole"`` and ``"arm_open"`` is that of learning the first and last joints
    and of learning the pitch joints alone or with them.
    """
    models: dict[tuple[str, str], object] = {}
    if anfis is not None and getattr(anfis, "closure_", None) is not None:
        models["ANFIS", "arm_open"] = anfis.without_closure()
        models["ANFIS", "arm"] = anfis
    for name, model in rivals.items():
        learner = label(learner_of(name))
        if structure_of(name) == "arm":
            models[learner, "arm_open"] = model.without_closure()
            models[learner, "arm"] = model
        else:
            models[learner, "whole"] = model
    order = list(dict.fromkeys(learner for learner, _ in models))
    return {(learner, s): models[learner, s] for learner in order for s in STRUCTURE_LABELS if (learner, s) in models}
