"""What the learned IK and ID share: one ANFIS per joint behind one object.

Each joint's options (the shared ones overridden per joint, checked for that joint's inputs),
the fields every saved per-joint model file holds (read and checked against the robot), a
summary line per joint model, and the warning for inputs far outside the training range.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..infra.arguments import check_number
from ..infra.reading import Validator, show
from ..model.robot import Robot
from .anfis import ANFIS
from .estimator import SavedModel, check_robot, checked_file

__all__ = ["PerJointModel", "OutsideTrainingWarning", "FAR", "CHUNK", "check_far", "beyond_range", "warn_far", "check_joint_array",
           "read_joint_models", "joint_anfis_options", "model_lines", "n_parameters"]


class PerJointModel(SavedModel):
    """A learner of one ANFIS per joint saved as one JSON file of a fixed name
    (:class:`nfarm.learning.estimator.SavedModel`)."""


class OutsideTrainingWarning(UserWarning):
    """A learned model was asked about inputs far outside the range it was trained on.

    Its fields say what its message says: ``count`` of the ``total`` ``what`` (a plural noun:
    ``"poses"``, ``"states"``) lie more than ``far`` spans of the training range beyond it, the
    farthest ``how_far`` spans (unrounded), the first of them at row ``first``.
    """

    def __init__(self, count: int, total: int, what: str, far: float, how_far: float, first: int):
        self.count, self.total, self.what = count, total, what
        self.far, self.how_far, self.first = far, how_far, first
        super().__init__(
            f"{count} of {total} {what} lie beyond the training data's input range by more "
            f"than {far:g} of it (up to {how_far:.3g}; first: {what[:-1]} {first}): predicted by "
            f"extrapolation")

    def __reduce__(self):
        return type(self), (self.count, self.total, self.what, self.far, self.how_far, self.first)


#: How far beyond its training range (in spans of that range) an input may lie before a
#: prediction warns: an ANFIS extrapolates its consequents linearly, and its membership
#: functions, fitted inside the range, say nothing about what lies beyond.
FAR = 0.5


def check_far(far: Any) -> None:
    """A ``ValueError`` unless ``far`` (spans of the training range) is a number ``>= 0``."""
    check_number("far", far, 0, finite=False, numpy=False,
                 message=f"far must be a number >= 0 (spans of the training range; inf: never warn), got {far!r}")


def beyond_range(X: np.ndarray) -> np.ndarray:
    """How far each row of scaled inputs ``X (N, d)`` (the training range is [0, 1]) lies
    beyond that range, in spans: ``(N,)``, 0 inside."""
    return np.maximum(np.maximum(-X, X - 1.0).max(axis=1), 0.0)


def warn_far(beyond: np.ndarray, far: float, what: str) -> None:
    """One :class:`OutsideTrainingWarning` naming how many of the ``what`` (a plural noun) lie
    more than ``far`` spans beyond the training range (``beyond`` from :func:`beyond_range`)."""
    out = beyond > far
    if out.any():
        i = int(np.argmax(out))
        warnings.warn(OutsideTrainingWarning(int(out.sum()), len(beyond), what, far, float(beyond.max()), i),
                      stacklevel=3)


#: Rows predicted at a time: the inputs' temporaries of a chunk stay in the cache.
CHUNK = 16384


def check_joint_array(q, robot: Robot, what: str, name: str = "q") -> np.ndarray:
    """``q`` as a finite ``(N, n)`` float array, or a ``ValueError`` naming ``what`` and ``name``."""
    q = np.asarray(q)
    if q.dtype.kind not in "iuf" or q.ndim != 2 or q.shape[1] != robot.n:
        raise ValueError(f"{what}: {name} must be a (N, {robot.n}) array of real numbers, got "
                         f"shape {q.shape} of {q.dtype}")
    q = q.astype(float)
    if not np.isfinite(q).all():
        raise ValueError(f"{what}: {name} contains NaN or inf (first in row "
                         f"{int(np.argmax(~np.isfinite(q).all(axis=1)))})")
    return q


def read_joint_models(v: Validator, data: Mapping, robot: Robot, source: str, widths: list[int],
                       what: str) -> tuple[int, dict, list | None, list, list]:
    """The fields every per-joint model file holds, validated for ``robot``: the joint count,
    the shared and per-joint ANFIS options, the fitted models (joint j taking ``widths[j]``
    inputs, those of ``what``) and the training times."""
    check_robot(v, data, robot)
    n = v.integer(data["n_joints"], "n_joints", lo=1, hi=64)
    if n != robot.n:
        v.fail("n_joints", f"must be {robot.n} for {robot.name}, got {n}")
    option_names = dict.fromkeys(ANFIS._param_names(), False)
    options = v.mapping(data["anfis_options"], "anfis_options", option_names)
    joint_options = data["joint_options"]
    if joint_options is not None:
        joint_options = [v.mapping(o, f"joint_options[{j}]", option_names) for j, o in
                         enumerate(v.sequence(joint_options, "joint_options", min_len=n,
                                              max_len=n))]
    models = v.sequence(data["models"], "models", min_len=n, max_len=n)
    fitted = [ANFIS.from_dict(m, f"{source}: models[{j}]") for j, m in enumerate(models)]
    for j, m in enumerate(fitted):
        if m.n_features_in_ != widths[j]:
            v.fail(f"models[{j}]", f"must take the {widths[j]} inputs of {what}, takes "
                                   f"{m.n_features_in_}")
    seconds = v.array(data["fit_seconds"], "fit_seconds", (n,))
    return n, dict(options), joint_options, fitted, seconds.tolist()


def joint_anfis_options(shared: Mapping, joint_options, n: int, n_inputs: list[int]) -> list[dict]:
    """Each joint's ANFIS options (``shared`` overridden by ``joint_options[j]``), checked for
    that joint's ``n_inputs[j]`` inputs; one ``ValueError`` naming the joint or the option."""
    joint = [{}] * n if joint_options is None else joint_options
    if isinstance(joint, (str, bytes, Mapping)) or not isinstance(joint, Sequence) or \
            len(joint) != n or not all(isinstance(o, Mapping) for o in joint):
        raise ValueError(f"joint_options must be None or a list of {n} mappings (one per "
                         f"joint), got {show(joint)}")
    names = set(ANFIS._param_names()) - {"feature_names"}
    for j, extra in enumerate([shared, *joint]):
        unknown = sorted(set(extra) - names)
        if unknown:
            where = "" if j == 0 else f"joint_options[{j - 1}]: "
            raise ValueError(f"{where}unknown ANFIS option {unknown[0]!r}; valid: "
                             f"{', '.join(sorted(names))}")
    options = []
    for j in range(n):
        merged = {**shared, **joint[j]}
        try:
            ANFIS(**merged)._check_options(n_inputs[j])
        except ValueError as exc:
            raise ValueError(f"joint {j + 1}: {exc}") from None
        options.append(merged)
    return options


def model_lines(models: list, unit: str) -> list[str]:
    """One line per joint model: rule base, size, kept epoch, errors [``unit``]."""
    lines = []
    for j, m in enumerate(models):
        R, n = m.consequents_.shape[0], m.n_features_in_
        premise = sum(p.size for p in m.mfs_)
        val = f", validation RMSE {m.val_loss_curve_[m.best_epoch_]:.4g} {unit}" \
            if m.val_loss_curve_ else ""
        lines.append(f"  joint {j + 1}: {m.partition} partition, {m.mf} functions, {R} "
                     f"rule{'s' if R != 1 else ''}, {premise + R * (n + 1)} parameters, kept "
                     f"epoch {m.best_epoch_ + 1} of {m.n_epochs_}, training RMSE "
                     f"{m.loss_curve_[m.best_epoch_]:.4g} {unit}{val}")
    return lines


def n_parameters(model) -> int:
    """Adjustable parameters of a fitted :class:`LearnedIK` or :class:`LearnedID`, summed over
    its joint models: premise (membership functions) and consequent."""
    return int(sum(sum(mf.size for mf in m.mfs_) + m.consequents_.size for m in model.models_))
