"""Learned inverse kinematics and inverse dynamics: one ANFIS per joint behind one object
(chapters 06 and 07). :class:`LearnedIK` maps tool poses to joint angles; :class:`LearnedID`
maps joint states to torques (section "Learned inverse dynamics" below).

The dissertation's IK page feeds five trained ANFIS models, one per joint, with the target's
orientation quaternion and position (7 inputs). :class:`LearnedIK` does that, and offers other
**encodings** of a target pose (:mod:`nfarm.learning.encoding`, where they are defined and
measured against each other); its baselines (:class:`Baseline`) see the same inputs through the
same :class:`~nfarm.learning.encoding.PoseEncoder`. Outputs are the joint angles [rad].

:class:`LearnedID` feeds each joint's model one of six **input sets** (:func:`id_features`):
the joint's own ``q, q̇, q̈`` (the likely dissertation design), every joint's, trigonometric
features, the two ``affine`` sets — rules over the configuration, consequents over the terms
every rigid arm's torque is a sum of (:mod:`nfarm.learning.bases`) — or the joint's row of the
rigid-body regressor (:func:`nfarm.model.dynamics.regressor`), which needs the arm's geometry.
Chapter 06 compares them on validation trajectories (``figures/tables/06_id_comparison``):
the rules of the ``affine`` sets supply the products of angle functions the inertia needs,
which the dissertation's own-state design lacks. The regressor's row with one rule fits the
torques exactly (they are linear in it, ``τ = Y π``): one rule is least squares on the inertial
parameters, an identification, not a learning result. With ``residual=True`` a model learns
``τ − rnea`` instead: what the rigid-body model misses on chapter 05's measured arm (friction,
encoder states, sensor noise), compared with a least-squares friction identification in
chapter 07 (``figures/tables/07_id_measured``).

A model is saved into a directory as one JSON file (``learned_ik.json``, ``learned_id.json``; no
pickle; the convention of every saved learner, :func:`nfarm.learning.estimator.write_model`)
holding the robot's parameter hash (:func:`nfarm.model.robot.robot_hash`); loading against
another robot is an error, and the file is validated like a parameter file
(:mod:`nfarm.infra.reading`).
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
import time
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..infra.paths import atomic_path
from ..infra.provenance import code_digest
from ..infra.reading import Validator, checked_content, json_ready, load_json, show
from ..model.dynamics import regressor, rnea
from ..model.kinematics import fk
from ..model.robot import Robot, joint_array, robot_hash
from ..model.rotations import pose_error
from ..solvers.ik import check_targets
from .anfis import ANFIS
from .bases import basis, basis_width
from .encoding import (ANGULAR, ENCODINGS, PoseEncoder, arm_chart, check_scaling, encode, input_scaling,
                       out_of_plane)
from .estimator import Estimator, model_file, write_model

__all__ = ["LearnedIK", "LearnedID", "Baseline", "id_features", "regressor_columns", "INPUT_SETS",
           "encode", "arm_chart", "out_of_plane", "ik_errors", "fit_cached", "fingerprint", "n_parameters",
           "ENCODINGS",
           "ANGULAR", "FILE_NAME", "ID_FILE_NAME", "BASELINES", "OutsideTrainingWarning", "FAR"]

FILE_NAME = "learned_ik.json"
_FORMAT = "nfarm-learned-ik-1"


class OutsideTrainingWarning(UserWarning):
    """A learned model was asked about inputs far outside the range it was trained on."""


#: How far beyond its training range (in spans of that range) an input may lie before a
#: prediction warns: an ANFIS extrapolates its consequents linearly, and its membership
#: functions, fitted inside the range, say nothing about what lies beyond.
FAR = 0.5


def _check_far(far: Any) -> None:
    if isinstance(far, bool) or not isinstance(far, (int, float)) or not far >= 0 or math.isnan(far):
        raise ValueError(f"far must be a number >= 0 (spans of the training range; inf: never warn), got {far!r}")


def _beyond(X: np.ndarray) -> np.ndarray:
    """How far each row of scaled inputs ``X (N, d)`` (the training range is [0, 1]) lies
    beyond that range, in spans: ``(N,)``, 0 inside."""
    return np.maximum(np.maximum(-X, X - 1.0).max(axis=1), 0.0)


def _warn_far(beyond: np.ndarray, far: float, what: str) -> None:
    out = beyond > far
    if out.any():
        i = int(np.argmax(out))
        warnings.warn(OutsideTrainingWarning(
            f"{int(out.sum())} of {len(beyond)} {what} lie beyond the training data's input range by more "
            f"than {far:g} of it (up to {beyond.max():.3g}; first: {what[:-1]} {i}): predicted by "
            f"extrapolation"), stacklevel=3)
_CHUNK = 16384


def _check_q(q, robot: Robot, what: str, name: str = "q") -> np.ndarray:
    q = np.asarray(q)
    if q.dtype.kind not in "iuf" or q.ndim != 2 or q.shape[1] != robot.n:
        raise ValueError(f"{what}: {name} must be a (N, {robot.n}) array of real numbers, got "
                         f"shape {q.shape} of {q.dtype}")
    q = q.astype(float)
    if not np.isfinite(q).all():
        raise ValueError(f"{what}: {name} contains NaN or inf (first in row "
                         f"{int(np.argmax(~np.isfinite(q).all(axis=1)))})")
    return q


def _pairs(data: Mapping, robot: Robot, what: str) -> tuple[np.ndarray, np.ndarray]:
    """``T (N, 4, 4)`` (rigid transforms) and ``q (N, n)`` of a data set."""
    if not isinstance(data, Mapping) or "T" not in data or "q" not in data:
        raise ValueError(f"{what} must be a mapping with arrays 'T' (N, 4, 4) and 'q' (N, "
                         f"{robot.n}), e.g. a data set of nfarm.study.datasets.load")
    try:
        T = check_targets(data["T"], 1e-9)
    except ValueError as exc:
        raise ValueError(f"{what}: {str(exc).replace('T_target', 'T')}") from None
    q = _check_q(data["q"], robot, what)
    if T.ndim != 3 or len(T) != len(q):
        raise ValueError(f"{what}: T must be (N, 4, 4) with one pose per row of q ({len(q)}), "
                         f"got {T.shape}")
    return T, q


class LearnedIK(Estimator):
    """Inverse kinematics learned by one ANFIS per joint (scikit-learn conventions).

    Args:
        encoding: how a pose becomes inputs (:data:`ENCODINGS`, module docstring).
        joint_options: ``None`` or one mapping per joint of ANFIS options that override the
            shared ones for that joint (e.g. a single rule for a joint that is a linear map of
            the inputs).
        max_out_of_plane: for ``"arm_plane"``, the largest angle [rad] by which a training pose's
            approach axis may leave the arm's vertical plane (:func:`out_of_plane`); beyond it
            the encoding loses information and ``fit`` refuses the robot.
        **anfis_options: passed to every joint's :class:`nfarm.learning.anfis.ANFIS` (``n_mfs``,
            ``partition``, ``n_rules``, ``radius``, ``epochs``, …).

    Learned attributes: ``models_`` (one fitted ANFIS per joint), ``robot_hash_``,
    ``robot_name_``, ``n_joints_``, ``encoder_`` (the fitted :class:`nfarm.learning.encoding.PoseEncoder`:
    the chart, the unwrapping centres of the angular inputs and the scaling), ``fit_seconds_``
    (per joint).
    """

    _passed_to = ANFIS

    def __init__(self, encoding: str = "quat_xyz", joint_options: Sequence[Mapping] | None = None,
                 max_out_of_plane: float = 1e-6, **anfis_options):
        self.encoding = encoding
        self.joint_options = joint_options
        self.max_out_of_plane = max_out_of_plane
        self.anfis_options = anfis_options

    # -- fitting ------------------------------------------------------------------------------

    def _options(self, n: int) -> list[dict]:
        """The ANFIS options of each joint, validated before any training."""
        if self.encoding not in ENCODINGS:
            raise ValueError(f"encoding must be one of {', '.join(ENCODINGS)}, got {self.encoding!r}")
        return _joint_anfis_options(self.anfis_options, self.joint_options, n,
                                    [ENCODINGS[self.encoding]] * n)

    def fit(self, robot: Robot, train: Mapping, val: Mapping | None = None) -> "LearnedIK":
        """Train one ANFIS per joint on ``train`` (arrays ``T (N, 4, 4)`` and ``q (N, n)``),
        keeping each model's epoch of least error on ``val`` when given (MATLAB's chkFIS).

        Raises:
            ValueError: bad options or data (not rigid transforms, wrong shapes, NaN), or an
                encoding that cannot describe the robot's poses, before any training.
        """
        options = self._options(robot.n)
        T, q = _pairs(train, robot, "train")
        T_val, q_val = _pairs(val, robot, "val") if val is not None else (None, None)
        self.encoder_ = PoseEncoder(self.encoding, self.max_out_of_plane)
        Xs = self.encoder_.fit_transform(robot, T)
        Xv = self.encoder_.transform(T_val) if T_val is not None else None
        names = self.encoder_.feature_names_
        self.models_, self.fit_seconds_ = [], []
        for j in range(robot.n):
            start = time.perf_counter()
            model = ANFIS(**{**options[j], "feature_names": names})
            model.fit(Xs, q[:, j], Xv, None if q_val is None else q_val[:, j])
            self.models_.append(model)
            self.fit_seconds_.append(time.perf_counter() - start)
        self.robot_hash_, self.robot_name_, self.n_joints_ = robot_hash(robot), robot.name, robot.n
        return self

    # -- prediction ---------------------------------------------------------------------------

    def predict(self, T_0e, *, threads: int | None = None, far: float = FAR) -> np.ndarray:
        """Joint angles ``(..., n)`` [rad] for tool poses ``T_0e (..., 4, 4)`` (a single pose
        is the ``()`` batch), in chunks of 16 384 poses.

        Poses whose inputs lie more than ``far`` of their training range beyond it are
        predicted (an ANFIS extrapolates its linear consequents) with an
        :class:`OutsideTrainingWarning` naming how many, how far and the first.

        ``threads``: chunks predicted side by side (default: the CPUs this process may use, at
        most 8). NumPy releases the GIL in its loops, so threads share the work; each chunk's
        result does not depend on the number of threads. While they run, BLAS is limited to
        one thread (``threadpoolctl``), process-wide.

        Raises:
            ValueError: not a batch of rigid transforms (shape, NaN, last row, rotation), or a
                bad ``threads``, before any work.
        """
        self._check_fitted()
        if threads is None:
            threads = min(len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                          else os.cpu_count() or 1, 8)
        if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) or threads < 1:
            raise ValueError(f"threads must be a whole number >= 1, got {threads!r}")
        size = np.size(T_0e) // 16 if isinstance(T_0e, np.ndarray) else 0

        _check_far(far)

        def predict_all(map_chunks) -> np.ndarray:
            T = check_targets(T_0e, 1e-6, map_chunks=map_chunks)   # every pose, before any work
            flat = T.reshape(-1, 4, 4)
            out = np.empty((len(flat), self.n_joints_))
            beyond = np.empty(len(flat))

            def chunk(start: int) -> None:
                X = self.encoder_.transform(flat[start:start + _CHUNK])
                beyond[start:start + _CHUNK] = _beyond(X)
                for j, model in enumerate(self.models_):
                    out[start:start + _CHUNK, j] = model._predict_fast(X)[0]

            with np.errstate(over="ignore", invalid="ignore"):
                for _ in map_chunks(chunk, range(0, len(flat), _CHUNK)):
                    pass
            _warn_far(beyond, far, "poses")
            return out.reshape(*T.shape[:-2], self.n_joints_)

        if threads == 1 or size < 2 * _CHUNK:
            return predict_all(map)
        from concurrent.futures import ThreadPoolExecutor

        from threadpoolctl import threadpool_limits
        # One BLAS thread per chunk: OpenBLAS's own threads would compete with these (measured
        # on 2 cores: 5.0e5 poses/s with both, 8.4e5 with BLAS limited to one). The limit is
        # process-wide while the prediction runs.
        with threadpool_limits(limits=1, user_api="blas"), ThreadPoolExecutor(threads) as pool:
            return predict_all(pool.map)

    def describe(self) -> str:
        """What the model is: encoding, rule bases, sizes, training errors, per joint."""
        self._check_fitted()
        names = self.encoder_.feature_names_
        lines = [f"LearnedIK for {self.robot_name_} ({self.n_joints_} joints), encoding "
                 f"{self.encoding!r} ({len(names)} inputs: {', '.join(names)})"]
        return "\n".join(lines + _model_lines(self.models_, "rad"))

    # -- persistence --------------------------------------------------------------------------

    def to_dict(self) -> dict:
        """The model as JSON-ready fields: its options, the robot's name and parameter hash,
        the encoder's fields (:meth:`PoseEncoder.to_dict`) and one ANFIS per joint."""
        self._check_fitted()
        return {"format": _FORMAT, "nfarm_version": __version__,
                "anfis_options": json_ready(self.anfis_options),
                "joint_options": json_ready(self.joint_options), "robot": self.robot_name_,
                "robot_params_sha256": self.robot_hash_, "n_joints": self.n_joints_,
                "fit_seconds": list(self.fit_seconds_),
                "models": [m.to_dict() for m in self.models_], **self.encoder_.to_dict()}

    def save(self, directory: str | os.PathLike) -> Path:
        """Write the model as ``directory/learned_ik.json`` (:data:`FILE_NAME`; JSON,
        atomically) and return the file's path; :meth:`load` of the directory reproduces the
        predictions bit for bit."""
        return write_model(directory, FILE_NAME, self.to_dict())

    @classmethod
    def load(cls, directory: str | os.PathLike, robot: Robot) -> "LearnedIK":
        """Read a model saved by :meth:`save` for ``robot`` from the directory it was saved
        into (or from the file itself).

        Raises:
            ParamsError: a missing, damaged or edited file (named, with the field), or a model
                trained for another robot.
        """
        path = model_file(directory, FILE_NAME)
        data = _checked_file(load_json(path, what="learned IK model"), str(path), _FORMAT, "learned IK")
        return cls.from_dict(data, robot, str(path))

    @classmethod
    def from_dict(cls, data: Any, robot: Robot, source: str = "<dict>") -> "LearnedIK":
        v = Validator(source)
        v.mapping(data, "", {**dict.fromkeys(_KEYS, True), "chart": False})
        if data["format"] != _FORMAT:
            v.fail("format", f"must be {_FORMAT!r} (an nfarm learned IK model), got {show(data['format'])}")
        encoding = v.choice(data["encoding"], "encoding", tuple(ENCODINGS))
        d = ENCODINGS[encoding]
        n, options, joint_options, fitted, seconds = _read_joint_models(
            v, data, robot, source, [d] * robot.n, f"encoding {encoding!r}")
        encoder = PoseEncoder.from_dict(data, source)
        model = cls(encoding=encoding, joint_options=joint_options,
                    max_out_of_plane=encoder.max_out_of_plane, **options)
        model.models_, model.fit_seconds_, model.encoder_ = fitted, seconds, encoder
        model.robot_hash_, model.robot_name_, model.n_joints_ = data["robot_params_sha256"], \
            data["robot"], n
        return model


_KEYS = ("format", "nfarm_version", "encoding", "anfis_options", "joint_options",
         "max_out_of_plane", "robot", "robot_params_sha256", "n_joints", "angle_centre",
         "input_lo", "input_span", "fit_seconds", "models")


def _checked_file(data: Any, source: str, form: str, what: str) -> dict:
    """A saved model's content once it is an nfarm ``what`` model of format ``form`` whose
    content hash matches (:func:`nfarm.infra.reading.checked_content`): an edited file is refused
    whatever the edit, before any field is read."""
    v = Validator(source)
    if not isinstance(data, dict):
        v.fail("", f"must be a JSON object (an nfarm {what} model), got {show(data)}")
    if data.get("format") != form:
        v.fail("format", f"must be {form!r} (an nfarm {what} model), got {show(data.get('format'))}")
    return checked_content(data, source)


def _read_joint_models(v: Validator, data: Mapping, robot: Robot, source: str, widths: list[int],
                       what: str) -> tuple[int, dict, list | None, list, list]:
    """The fields every per-joint model file holds, validated for ``robot``: the joint count,
    the shared and per-joint ANFIS options, the fitted models (joint j taking ``widths[j]``
    inputs, those of ``what``) and the training times."""
    if data["robot_params_sha256"] != robot_hash(robot):
        v.fail("robot_params_sha256", f"trained for robot {show(data['robot'])} with other "
                                      f"parameters than {robot.name!r} ({robot.source}): "
                                      f"retrain it for this robot")
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


def _joint_anfis_options(shared: Mapping, joint_options, n: int, n_inputs: list[int]) -> list[dict]:
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


def _model_lines(models: list, unit: str) -> list[str]:
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


# --------------------------------------------------------------------------------------------
# Learned inverse dynamics

#: Input sets of :class:`LearnedID`: what each joint's model sees of a state ``(q, q̇, q̈)``.
INPUT_SETS = ("own", "all", "trig", "affine_generic", "affine", "regressor")
#: Input sets whose rules are built over the configuration ``q`` only (the first n columns).
_CONFIGURATION_PREMISES = ("affine_generic", "affine")
ID_FILE_NAME = "learned_id.json"
_ID_FORMAT = "nfarm-learned-id-1"


def id_features(robot: Robot, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, inputs: str
                ) -> list[np.ndarray]:
    """The inputs each joint's model sees of states ``q, qd, qdd (N, n)``: one ``(N, d_j)``
    array per joint j.

    * ``"own"`` — the joint's own ``q_j, q̇_j, q̈_j`` (3 inputs; the likely dissertation design);
    * ``"all"`` — every joint's ``q, q̇, q̈`` (3n);
    * ``"trig"`` — ``sin q, cos q`` (what gravity and the Coriolis terms see of the angles:
      trigonometric, not linear), ``q̇``, ``q̈`` and ``q̇ ⊙ |q̇|`` (the sign-keeping square of the
      centrifugal terms): 5n;
    * ``"affine_generic"``, ``"affine"`` — the configuration ``q`` (the rules' premises: the
      models are built with ``premise_inputs`` the first n columns), then the terms every rigid
      arm's torque is a sum of — ``q̈_k``, ``q̇_k q̇_l`` and ``1``, each times ``1, sin, cos`` of
      the joint angles (``"affine_generic"``: 230 columns for five joints) or of the angles and
      the sums of every stretch of parallel joints (``"affine"``: 356 for intelbot5), in the
      consequents only (:mod:`nfarm.learning.bases`, ``"generic_linear"`` and ``"chain_linear"`` less
      their constant). No mass, length or inertia enters; within one rule the torque is linear
      in trigonometric functions of the angles, and the rules over ``q`` supply their products
      (chapter 06: from 37 % worst-joint NRMSE with one rule to 2.6 % with eight on intelbot5);
    * ``"regressor"`` — row j of the rigid-body regressor ``Y(q, q̇, q̈)``
      (:func:`nfarm.model.dynamics.regressor`): the columns of links j..n that are not zero for
      every state (:func:`regressor_columns`; for intelbot5 34, 38, 28, 17 and 8). The
      geometry (DH parameters) is known, the masses are not: ``τ_j`` is linear in these
      inputs, so one rule (least squares) can already be exact.
    """
    if inputs == "own":
        return [np.column_stack([q[:, j], qd[:, j], qdd[:, j]]) for j in range(robot.n)]
    if inputs == "all":
        X = np.concatenate([q, qd, qdd], axis=1)
        return [X] * robot.n
    if inputs == "trig":
        X = np.concatenate([np.sin(q), np.cos(q), qd, qdd, qd * np.abs(qd)], axis=1)
        return [X] * robot.n
    if inputs in _CONFIGURATION_PREMISES:
        kind = "chain_linear" if inputs == "affine" else "generic_linear"
        X = np.concatenate([q, basis(robot, q, qd, qdd, kind)[:, 1:]], axis=1)
        return [X] * robot.n
    Y = regressor(robot, q, qd, qdd)
    return [np.ascontiguousarray(Y[:, j, cols]) for j, cols in enumerate(regressor_columns(robot))]


@functools.lru_cache(maxsize=16)
def _regressor_columns(robot: Robot) -> tuple[tuple[int, ...], ...]:
    rng = np.random.default_rng(0)
    lo, hi = robot.qlim[:, 0], robot.qlim[:, 1]
    q = lo + (hi - lo) * rng.random((256, robot.n))
    Y = regressor(robot, q, rng.normal(size=q.shape), rng.normal(size=q.shape))
    size = np.abs(Y).max(axis=0)                                           # (n, 10 n)
    return tuple(tuple(int(k) for k in np.flatnonzero(row > 1e-9 * max(row.max(), 1e-300)))
                 for row in size)


def regressor_columns(robot: Robot) -> list[np.ndarray]:
    """Per joint j, the columns of the regressor (:func:`nfarm.model.dynamics.regressor`) that
    joint j's torque depends on: those not zero at any of 256 seeded random states (the
    others are zero for every state — the parameters of links before j, and e.g. a link's
    moments about axes its torque never sees)."""
    return [np.array(cols, dtype=int) for cols in _regressor_columns(robot)]


def _id_widths(inputs: str, robot: Robot) -> list[int]:
    if inputs == "regressor":
        return [len(cols) for cols in _regressor_columns(robot)]
    n = robot.n
    if inputs in _CONFIGURATION_PREMISES:
        kind = "chain_linear" if inputs == "affine" else "generic_linear"
        return [n + basis_width(robot, kind) - 1] * n
    return [{"own": 3, "all": 3 * n, "trig": 5 * n}[inputs]] * n


def _states(data: Mapping, robot: Robot, what: str, *, tau: bool = True) -> list[np.ndarray]:
    """``q, qd, qdd`` (and ``tau``) ``(N, n)`` of an ID data set, checked."""
    keys = ("q", "qd", "qdd", "tau") if tau else ("q", "qd", "qdd")
    if not isinstance(data, Mapping) or any(k not in data for k in keys):
        raise ValueError(f"{what} must be a mapping with arrays {', '.join(map(repr, keys))} "
                         f"(N, {robot.n}), e.g. an ID data set of nfarm.study.datasets.load")
    arrays = [_check_q(data[k], robot, what, k) for k in keys]
    if len({len(a) for a in arrays}) != 1:
        raise ValueError(f"{what}: {', '.join(keys)} must have one row per sample, got "
                         f"{', '.join(str(len(a)) for a in arrays)} rows")
    return arrays


class LearnedID(Estimator):
    """Inverse dynamics learned by one ANFIS per joint (scikit-learn conventions).

    Args:
        inputs: what each joint's model sees (:data:`INPUT_SETS`, :func:`id_features`).
        residual: learn ``τ − rnea(q, q̇, q̈)`` (what the rigid-body model misses: friction,
            armature) and predict ``rnea + ANFIS`` (semi-parametric, Nguyen-Tuong & Peters
            2010); ``False`` learns the torques themselves.
        joint_options: ``None`` or one mapping per joint of ANFIS options overriding the shared.
        **anfis_options: passed to every joint's :class:`nfarm.learning.anfis.ANFIS`.

    Learned attributes: ``models_``, ``robot_`` (the robot it was fitted or loaded with),
    ``robot_hash_``, ``robot_name_``, ``n_joints_``, ``input_lo_``, ``input_span_`` (per joint, the inputs' scaling to ``[0, 1]``),
    ``fit_seconds_``.
    """

    _passed_to = ANFIS

    def __init__(self, inputs: str = "own", residual: bool = False,
                 joint_options: Sequence[Mapping] | None = None, **anfis_options):
        self.inputs = inputs
        self.residual = residual
        self.joint_options = joint_options
        self.anfis_options = anfis_options

    def _inputs(self, q, qd, qdd) -> list[np.ndarray]:
        """Each joint's inputs, scaled to [0, 1] over the training data."""
        return [(X - lo) / span for X, lo, span in
                zip(id_features(self.robot_, q, qd, qdd, self.inputs), self.input_lo_,
                    self.input_span_)]

    def fit(self, robot: Robot, train: Mapping, val: Mapping | None = None) -> "LearnedID":
        """Train one ANFIS per joint on ``train`` (arrays ``q, qd, qdd, tau (N, n)``), keeping
        each model's epoch of least error on ``val`` when given.

        Raises:
            ValueError: bad options or data (shapes, NaN, lengths), before any training.
        """
        if self.inputs not in INPUT_SETS:
            raise ValueError(f"inputs must be one of {', '.join(INPUT_SETS)}, got {self.inputs!r}")
        if not isinstance(self.residual, bool):
            raise ValueError(f"residual must be True or False, got {self.residual!r}")
        n = robot.n
        shared = dict(self.anfis_options)
        if self.inputs in _CONFIGURATION_PREMISES:
            shared.setdefault("premise_inputs", list(range(n)))
        options = _joint_anfis_options(shared, self.joint_options, n, _id_widths(self.inputs, robot))
        q, qd, qdd, tau = _states(train, robot, "train")
        val_states = _states(val, robot, "val") if val is not None else None
        target = tau - rnea(robot, q, qd, qdd) if self.residual else tau
        if val_states is not None:
            vq, vqd, vqdd, vtau = val_states
            val_target = vtau - rnea(robot, vq, vqd, vqdd) if self.residual else vtau
        self.__dict__.pop("models_", None)       # a failed refit leaves no half-fitted model
        self.robot_ = robot
        scalings = [input_scaling(X) for X in id_features(robot, q, qd, qdd, self.inputs)]
        self.input_lo_, self.input_span_ = [lo for lo, _ in scalings], [span for _, span in scalings]
        X = self._inputs(q, qd, qdd)
        Xv = self._inputs(vq, vqd, vqdd) if val_states is not None else [None] * n
        models, seconds = [], []
        for j in range(n):
            start = time.perf_counter()
            models.append(ANFIS(**options[j]).fit(X[j], target[:, j], Xv[j],
                                                  None if val_states is None else val_target[:, j]))
            seconds.append(time.perf_counter() - start)
        self.robot_hash_, self.robot_name_, self.n_joints_ = robot_hash(robot), robot.name, n
        self.models_, self.fit_seconds_ = models, seconds
        return self

    def predict(self, q, qd, qdd, *, far: float = FAR) -> np.ndarray:
        """Joint torques ``(..., n)`` [N·m] for states ``q, qd, qdd (..., n)`` (batch shapes
        broadcast; one state is the ``()`` batch). A residual model adds ``rnea`` of the robot
        it was fitted or loaded with. States whose inputs lie more than ``far`` of their
        training range beyond it are predicted with an :class:`OutsideTrainingWarning`.

        Raises:
            ValueError: states that are not real ``(..., n)`` arrays, or NaN, before any work;
                states so far outside the training data that a torque overflows (named).
        """
        _check_far(far)
        self._check_fitted()
        robot = self.robot_
        arrays = [joint_array(robot, x, name) for x, name in ((q, "q"), (qd, "qd"), (qdd, "qdd"))]
        try:
            arrays = np.broadcast_arrays(*arrays)
        except ValueError:
            raise ValueError(f"q, qd, qdd batch shapes do not broadcast: "
                             f"{', '.join(str(np.shape(a)) for a in arrays)}") from None
        batch = arrays[0].shape[:-1]
        flat = [np.ascontiguousarray(a.reshape(-1, robot.n)) for a in arrays]
        if not all(np.isfinite(a).all() for a in flat):
            raise ValueError("q, qd, qdd must be finite (NaN or inf found)")
        tau = np.empty((len(flat[0]), robot.n))
        beyond = np.empty(len(tau))
        with np.errstate(over="ignore", invalid="ignore"):
            for start in range(0, len(tau), _CHUNK):
                part = [a[start:start + _CHUNK] for a in flat]
                X = self._inputs(*part)
                beyond[start:start + _CHUNK] = np.max([_beyond(x) for x in X], axis=0)
                for j, model in enumerate(self.models_):
                    tau[start:start + _CHUNK, j] = model._predict_fast(X[j])[0]
            if self.residual:
                tau += rnea(robot, *flat)
        bad = ~np.isfinite(tau).all(axis=1)
        if bad.any():
            i = int(np.argmax(bad))
            raise ValueError(f"the torques of {int(bad.sum())} of {len(tau)} states overflow (first: state {i}, "
                             f"its inputs {beyond[i]:.3g} training ranges beyond the training states'): "
                             f"q, qd, qdd far outside the data the model learned from")
        _warn_far(beyond, far, "states")
        return tau.reshape(*batch, robot.n)

    def describe(self) -> str:
        self._check_fitted()
        what = "τ − rnea (residual)" if self.residual else "τ"
        head = (f"LearnedID for {self.robot_name_} ({self.n_joints_} joints), inputs "
                f"{self.inputs!r} ({', '.join(str(len(lo)) for lo in self.input_lo_)} per joint), "
                f"learning {what}")
        return "\n".join([head] + _model_lines(self.models_, "N·m"))

    def to_dict(self) -> dict:
        self._check_fitted()
        return {"format": _ID_FORMAT, "nfarm_version": __version__, "inputs": self.inputs,
                "residual": self.residual, "anfis_options": json_ready(self.anfis_options),
                "joint_options": json_ready(self.joint_options), "robot": self.robot_name_,
                "robot_params_sha256": self.robot_hash_, "n_joints": self.n_joints_,
                "input_lo": json_ready(self.input_lo_), "input_span": json_ready(self.input_span_),
                "fit_seconds": list(self.fit_seconds_),
                "models": [m.to_dict() for m in self.models_]}

    def save(self, directory: str | os.PathLike) -> Path:
        """Write the model as ``directory/learned_id.json`` (:data:`ID_FILE_NAME`; JSON,
        atomically) and return the file's path; :meth:`load` of the directory reproduces the
        predictions bit for bit."""
        return write_model(directory, ID_FILE_NAME, self.to_dict())

    @classmethod
    def load(cls, directory: str | os.PathLike, robot: Robot) -> "LearnedID":
        """Read a model saved by :meth:`save` for ``robot`` from the directory it was saved
        into (or from the file itself); a :class:`ParamsError` naming the file and the field
        for a missing, damaged, edited or other robot's file."""
        path = model_file(directory, ID_FILE_NAME)
        data = _checked_file(load_json(path, what="learned ID model"), str(path), _ID_FORMAT, "learned ID")
        return cls.from_dict(data, robot, str(path))

    @classmethod
    def from_dict(cls, data: Any, robot: Robot, source: str = "<dict>") -> "LearnedID":
        v = Validator(source)
        v.mapping(data, "", dict.fromkeys(_ID_KEYS, True))
        if data["format"] != _ID_FORMAT:
            v.fail("format", f"must be {_ID_FORMAT!r} (an nfarm learned ID model), got {show(data['format'])}")
        inputs = v.choice(data["inputs"], "inputs", INPUT_SETS)
        residual = v.boolean(data["residual"], "residual")
        widths = _id_widths(inputs, robot)
        n, options, joint_options, fitted, seconds = _read_joint_models(
            v, data, robot, source, widths, f"input set {inputs!r}")
        lo = [v.array(x, f"input_lo[{j}]", (d,)) for j, (x, d) in
              enumerate(zip(v.sequence(data["input_lo"], "input_lo", min_len=n, max_len=n), widths))]
        span = [v.array(x, f"input_span[{j}]", (d,)) for j, (x, d) in
                enumerate(zip(v.sequence(data["input_span"], "input_span", min_len=n, max_len=n),
                              widths))]
        for j, (lo_j, span_j) in enumerate(zip(lo, span)):
            check_scaling(v, lo_j, span_j, f"input_lo[{j}]", f"input_span[{j}]")
        model = cls(inputs=inputs, residual=residual, joint_options=joint_options, **options)
        model.models_, model.fit_seconds_ = fitted, seconds
        model.input_lo_, model.input_span_ = list(lo), list(span)
        model.robot_hash_, model.robot_name_, model.n_joints_ = data["robot_params_sha256"], \
            data["robot"], n
        model.robot_ = robot
        return model


_ID_KEYS = ("format", "nfarm_version", "inputs", "residual", "anfis_options", "joint_options",
            "robot", "robot_params_sha256", "n_joints", "input_lo", "input_span", "fit_seconds",
            "models")


# --------------------------------------------------------------------------------------------
# Errors, baselines and a cache of fitted models


def ik_errors(robot: Robot, q_pred, q_true, T_true) -> dict[str, np.ndarray]:
    """How far predicted joint angles are from the truth, in joint space and at the tool.

    Args:
        q_pred, q_true: ``(N, n)`` [rad]; ``T_true (N, 4, 4)`` the target poses.

    Returns:
        ``joint (N, n)`` signed joint errors [rad]; ``position (N,)`` distance between the
        tool point of ``fk(q_pred)`` and the target's [m]; ``orientation (N,)`` angle of the
        rotation between the two tool orientations [rad].
    """
    q_pred, q_true = np.asarray(q_pred, float), np.asarray(q_true, float)
    twist = pose_error(T_true, fk(robot, q_pred))
    return {"joint": q_pred - q_true, "position": np.linalg.norm(twist[..., :3], axis=-1),
            "orientation": np.linalg.norm(twist[..., 3:], axis=-1)}


BASELINES = ("nearest", "rbf", "linear")


class Baseline(Estimator):
    """Learned-IK baselines that need no new dependency, on the same encoded, scaled inputs as
    :class:`LearnedIK`: ``"nearest"`` — the training sample nearest to the pose
    (``scipy.spatial.cKDTree``); ``"rbf"`` — thin-plate-spline interpolation over the
    ``neighbors`` nearest samples (``scipy.interpolate.RBFInterpolator``); ``"linear"`` —
    one affine map fitted by least squares (``scipy.linalg.lstsq``).

    ``max_out_of_plane`` [rad] is the :class:`~nfarm.learning.encoding.PoseEncoder`'s check of
    ``"arm_plane"`` poses; by default none (π): a baseline is fitted on the inputs it is given,
    and the learned IK it is compared with has already refused poses its encoding cannot describe.
    """

    _fitted = "encoder_"

    def __init__(self, kind: str = "nearest", encoding: str = "arm_plane", neighbors: int = 32,
                 max_out_of_plane: float = math.pi):
        self.kind = kind
        self.encoding = encoding
        self.neighbors = neighbors
        self.max_out_of_plane = max_out_of_plane

    def fit(self, robot: Robot, train: Mapping) -> "Baseline":
        import scipy.linalg
        from scipy.interpolate import RBFInterpolator
        from scipy.spatial import cKDTree

        if self.kind not in BASELINES:
            raise ValueError(f"kind must be one of {', '.join(BASELINES)}, got {self.kind!r}")
        if self.encoding not in ENCODINGS:
            raise ValueError(f"encoding must be one of {', '.join(ENCODINGS)}, got {self.encoding!r}")
        T, q = _pairs(train, robot, "train")
        self.encoder_ = PoseEncoder(self.encoding, self.max_out_of_plane)   # the learned IK's inputs
        X = self.encoder_.fit_transform(robot, T)
        start = time.perf_counter()
        if self.kind == "nearest":
            self.tree_, self.q_ = cKDTree(X), q
        elif self.kind == "rbf":
            self.rbf_ = RBFInterpolator(X, q, neighbors=min(self.neighbors, len(X)),
                                        kernel="thin_plate_spline", degree=1)
        else:
            A = np.column_stack([X, np.ones(len(X))])
            self.coef_ = scipy.linalg.lstsq(A, q, lapack_driver="gelsy")[0]
        self.fit_seconds_ = time.perf_counter() - start
        self.n_joints_ = robot.n
        return self

    def predict(self, T_0e) -> np.ndarray:
        """Joint angles ``(..., n)`` [rad] for poses ``T_0e (..., 4, 4)``."""
        self._check_fitted()
        T = check_targets(T_0e, 1e-6)
        batch = T.shape[:-2]
        X = self.encoder_.transform(T.reshape(-1, 4, 4))
        if self.kind == "nearest":
            q = self.q_[self.tree_.query(X)[1]]
        elif self.kind == "rbf":
            q = self.rbf_(X)
        else:
            q = np.column_stack([X, np.ones(len(X))]) @ self.coef_
        return q.reshape(*batch, self.n_joints_)


def n_parameters(model) -> int:
    """Adjustable parameters of a fitted :class:`LearnedIK` or :class:`LearnedID`, summed over
    its joint models: premise (membership functions) and consequent."""
    return int(sum(sum(mf.size for mf in m.mfs_) + m.consequents_.size for m in model.models_))


def fingerprint(*arrays: np.ndarray) -> str:
    """SHA-256 of arrays' shapes, dtypes and bytes: the identity of a data set."""
    digest = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        digest.update(f"{a.shape}{a.dtype.str}".encode())
        digest.update(a.tobytes())
    return digest.hexdigest()


#: Environment variables that change floating-point results (SIMD paths, BLAS kernels and
#: threads): part of :func:`fit_cached`'s key. ``make report`` pins them (Makefile).
NUMERICS_ENV = ("NPY_DISABLE_CPU_FEATURES", "OPENBLAS_CORETYPE", "OPENBLAS_NUM_THREADS",
                "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def fit_cached(model, robot: Robot, train: Mapping, val: Mapping | None,
               directory: str | os.PathLike) -> tuple[Any, str]:
    """Fit ``model`` (a :class:`LearnedIK` or :class:`LearnedID`), or load the one saved in
    ``directory`` if it was fitted with the same options on the same data for the same robot
    by the same code.

    The inputs' hash (the model's class and options, the data's :func:`fingerprint`, the
    robot's hash, the model format, the content of this module and of every package module it
    imports (:func:`nfarm.infra.provenance.code_digest`) and the numerical environment of
    :data:`NUMERICS_ENV`) is stored beside the model as ``inputs.sha256``; a model whose
    stored hash differs is retrained and replaced (atomically). Returns the model and
    ``"made"`` or ``"reused"``.

    The environment is in the hash because training is not bit-reproducible across CPU
    features and thread counts (fuzzy c-means moved validation errors by up to 6 % between
    this machine's default and ``make report``'s pinned set-up): a model trained while
    exploring is not reused by the published report.
    """
    directory = Path(directory)
    if isinstance(model, LearnedIK):
        cls, name, form = LearnedIK, FILE_NAME, _FORMAT
        arrays = lambda data, what: _pairs(data, robot, what)          # noqa: E731
    elif isinstance(model, LearnedID):
        cls, name, form = LearnedID, ID_FILE_NAME, _ID_FORMAT
        arrays = lambda data, what: _states(data, robot, what)         # noqa: E731
    else:
        raise TypeError(f"model must be a LearnedIK or a LearnedID, got {type(model).__name__}")
    parts = [cls.__name__, json.dumps(json_ready(model.get_params()), sort_keys=True),
             fingerprint(*arrays(train, "train")), robot_hash(robot), form, code_digest("learning.learned"),
             json.dumps({k: os.environ.get(k) for k in NUMERICS_ENV})]
    if val is not None:
        parts.append(fingerprint(*arrays(val, "val")))
    key = hashlib.sha256("\n".join(parts).encode()).hexdigest()
    stamp = directory / "inputs.sha256"
    if stamp.is_file() and (directory / name).is_file() and \
            stamp.read_text(encoding="utf-8").strip() == key:
        return cls.load(directory, robot), "reused"
    model.fit(robot, train, val)
    stamp.unlink(missing_ok=True)          # a model without its stamp is never reused
    model.save(directory)
    with atomic_path(stamp) as tmp:
        tmp.write_text(key + "\n", encoding="utf-8")
    return model, "made"
