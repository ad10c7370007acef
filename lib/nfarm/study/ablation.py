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

__all__ = ["LinearOnEncoding", "linear_on_encoding"]


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
