"""Learned inverse kinematics: one ANFIS per joint behind one object (chapters 06 and 07), and
its baselines.

The dissertation's IK page feeds five trained ANFIS models, one per joint, with the target's
orientation quaternion and position (7 inputs). :class:`LearnedIK` does that, and offers other
**encodings** of a target pose (:mod:`nfarm.learning.encoding`, where they are defined and
measured against each other); its baselines (:class:`Baseline`) see the same inputs through the
same :class:`~nfarm.learning.encoding.PoseEncoder`. Outputs are the joint angles [rad].
The learned inverse dynamics is :mod:`nfarm.learning.learned_id`; what both share,
:mod:`nfarm.learning.per_joint`; the cache of fitted models, :mod:`nfarm.learning.model_cache`.

A model is saved into a directory as one JSON file (``learned_ik.json``; no pickle; the
convention of every saved learner, :func:`nfarm.learning.estimator.write_model`) holding the
robot's parameter hash (:func:`nfarm.model.robot.robot_hash`); loading against another robot
is an error, and the file is validated like a parameter file (:mod:`nfarm.infra.reading`).
"""

from __future__ import annotations

import copy
import math
import os
import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .. import __version__
from ..infra.arguments import check_choice, check_integer, check_number, is_integer
from ..infra.reading import Validator, json_ready, show
from ..model.kinematics import fk
from ..model.robot import Robot, robot_hash
from ..model.rotations import pose_error
from ..solvers.ik import check_targets
from .anfis import ANFIS, fit_shared
from .encoding import ANGULAR, ENCODINGS, FEATURE_NAMES, PoseEncoder, arm_chart, encode, out_of_plane
from .estimator import Estimator
from .per_joint import (PerJointModel, CHUNK, FAR, OutsideTrainingWarning, beyond_range, check_far, check_joint_array,
                        joint_anfis_options, model_lines, read_joint_models, warn_far)

__all__ = ["LearnedIK", "Baseline", "ik_errors", "ik_pairs", "fit_pitch_closure", "close_pitch", "read_closure", "encode", "arm_chart", "out_of_plane", "ENCODINGS",
           "ANGULAR", "FILE_NAME", "FORMAT", "BASELINES", "OutsideTrainingWarning", "FAR"]


FILE_NAME = "learned_ik.json"
FORMAT = "nfarm-learned-ik-1"


def ik_pairs(data: Mapping, robot: Robot, what: str) -> tuple[np.ndarray, np.ndarray]:
    """``T (N, 4, 4)`` (rigid transforms) and ``q (N, n)`` of a data set."""
    if not isinstance(data, Mapping) or "T" not in data or "q" not in data:
        raise ValueError(f"{what} must be a mapping with arrays 'T' (N, 4, 4) and 'q' (N, "
                         f"{robot.n}), e.g. a data set of nfarm.study.datasets.load")
    try:
        T = check_targets(data["T"], 1e-9)
    except ValueError as exc:
        raise ValueError(f"{what}: {str(exc).replace('T_target', 'T')}") from None
    q = check_joint_array(data["q"], robot, what)
    if T.ndim != 3 or len(T) != len(q):
        raise ValueError(f"{what}: T must be (N, 4, 4) with one pose per row of q ({len(q)}), "
                         f"got {T.shape}")
    return T, q


class LearnedIK(PerJointModel):
    """Inverse kinematics learned by one ANFIS per joint (scikit-learn conventions).

    Args:
        encoding: how a pose becomes inputs (:data:`ENCODINGS`, module docstring).
        joint_options: ``None`` or one mapping per joint of ANFIS options that override the
            shared ones for that joint (e.g. a single rule for a joint that is a linear map of
            the inputs).
        max_out_of_plane: for ``"arm_plane"``, the largest angle [rad] by which a training pose's
            approach axis may leave the arm's vertical plane (:func:`out_of_plane`); beyond it
            the encoding loses information and ``fit`` refuses the robot.
        shared_joints: ``None`` or the indices (0-based, at least two) of joints trained as one
            multiple-output ANFIS whose rules share their membership functions
            (:func:`nfarm.learning.anfis.fit_shared`): e.g. ``[1, 2, 3]``, the pitch joints of an arm
            whose planar sub-problem they solve together. Their options must be equal.
        pitch_closure: for ``"arm_plane"``, predict the last pitch joint (``q[n-2]``) from the
            target's pitch instead of its model: the pitch joints' angles sum to ``s·φ + c``
            (``s = ±1``, a constant ``c``, fitted on the training poses; ``φ`` the approach
            axis's pitch), so ``q[n-2] = s·φ + c − Σ`` of the other pitch joints' predictions,
            wrapped to within half a turn of the joint's training mean. Its ANFIS is still
            trained (it shapes shared premises and is shown by :meth:`describe`), but predictions
            take the closure. ``fit`` refuses a robot whose training poses break the identity by
            more than ``closure_tolerance`` [rad].
        **anfis_options: passed to every joint's :class:`nfarm.learning.anfis.ANFIS` (``n_mfs``,
            ``partition``, ``n_rules``, ``radius``, ``epochs``, …).

    Learned attributes: ``models_`` (one fitted ANFIS per joint), ``robot_hash_``,
    ``robot_name_``, ``n_joints_``, ``encoder_`` (the fitted :class:`nfarm.learning.encoding.PoseEncoder`:
    the chart, the unwrapping centres of the angular inputs and the scaling), ``fit_seconds_``
    (per joint; a shared group's time split evenly), ``closure_`` (``None``, or the pitch
    closure's ``joint``, ``sign``, ``offset`` [rad] and ``centre`` [rad]).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> from nfarm.model.kinematics import fk
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> rng = np.random.default_rng(0)
        >>> q = rng.uniform([-1.2, -0.4, -1.2, -1.4, -1.4], [1.2, 0.9, 1.2, 1.4, 1.4], (3000, 5))
        >>> model = LearnedIK("arm_plane", joint_options=[{"n_mfs": 1}, {}, {}, {}, {"n_mfs": 1}],
        ...                   shared_joints=[1, 2, 3], pitch_closure=True, partition="fcm",
        ...                   n_rules=8, mf="gauss", epochs=3, random_state=0)
        >>> T = fk(robot, q)
        >>> ahead = T[:, 0, 3] * np.cos(q[:, 0]) + T[:, 1, 3] * np.sin(q[:, 0]) > 0.08   # in front
        >>> model = model.fit(robot, {"T": T[ahead], "q": q[ahead]})
        >>> model.closure_["sign"], model.predict(T[ahead][:2]).shape
        (1, (2, 5))
    """

    _passed_to = ANFIS
    file_name, file_format, what = FILE_NAME, FORMAT, "learned IK"

    def __init__(self, encoding: str = "quat_xyz", joint_options: Sequence[Mapping] | None = None,
                 max_out_of_plane: float = 1e-6, shared_joints: Sequence[int] | None = None,
                 pitch_closure: bool = False, closure_tolerance: float = 1e-4, **anfis_options):
        self.encoding = encoding
        self.joint_options = joint_options
        self.max_out_of_plane = max_out_of_plane
        self.shared_joints = shared_joints
        self.pitch_closure = pitch_closure
        self.closure_tolerance = closure_tolerance
        self.anfis_options = anfis_options

    # -- fitting ------------------------------------------------------------------------------

    def _options(self, n: int) -> list[dict]:
        """The ANFIS options of each joint, validated before any training."""
        check_choice("encoding", self.encoding, ENCODINGS)
        return joint_anfis_options(self.anfis_options, self.joint_options, n,
                                    [ENCODINGS[self.encoding]] * n)

    def fit(self, robot: Robot, train: Mapping, val: Mapping | None = None) -> "LearnedIK":
        """Train one ANFIS per joint on ``train`` (arrays ``T (N, 4, 4)`` and ``q (N, n)``),
        keeping each model's epoch of least error on ``val`` when given (MATLAB's chkFIS).

        Raises:
            ValueError: bad options or data (not rigid transforms, wrong shapes, NaN), or an
                encoding that cannot describe the robot's poses, before any training.
        """
        options = self._options(robot.n)
        shared = self._shared(options, robot.n)
        T, q = ik_pairs(train, robot, "train")
        T_val, q_val = ik_pairs(val, robot, "val") if val is not None else (None, None)
        self.encoder_ = PoseEncoder(self.encoding, self.max_out_of_plane)
        Xs = self.encoder_.fit_transform(robot, T)
        Xv = self.encoder_.transform(T_val) if T_val is not None else None
        names = self.encoder_.feature_names_
        self.closure_ = self._closure(Xs, q) if self.pitch_closure else None
        self.models_, self.fit_seconds_ = [None] * robot.n, [0.0] * robot.n
        groups = ([shared] if shared else []) + [[j] for j in range(robot.n) if j not in shared]
        for group in groups:
            start = time.perf_counter()
            model = ANFIS(**{**options[group[0]], "feature_names": names})
            y_val = None if q_val is None else q_val[:, group]
            fitted = fit_shared(model, Xs, q[:, group], Xv, y_val) if len(group) > 1 else \
                [model.fit(Xs, q[:, group[0]], Xv, None if y_val is None else y_val[:, 0])]
            for j, m in zip(group, fitted):
                self.models_[j] = m
                self.fit_seconds_[j] = (time.perf_counter() - start) / len(group)
        self.robot_hash_, self.robot_name_, self.n_joints_ = robot_hash(robot), robot.name, robot.n
        return self

    def _shared(self, options: list[dict], n: int) -> list[int]:
        """The checked ``shared_joints`` (``[]`` for none)."""
        if self.shared_joints is None:
            return []
        given = self.shared_joints
        if isinstance(given, (str, bytes, Mapping)) or not isinstance(given, Sequence) or len(given) < 2 \
                or not all(is_integer(j) and 0 <= j < n for j in given) or len(set(given)) != len(given):
            raise ValueError(f"shared_joints must be None or at least two distinct joint indices in "
                             f"[0, {n}), got {show(given)}")
        different = [j for j in given if options[j] != options[given[0]]]
        if different:
            raise ValueError(f"shared_joints: joint {different[0] + 1}'s options differ from joint "
                             f"{given[0] + 1}'s; joints that share their premises share their options")
        return [int(j) for j in given]

    def _closure(self, X: np.ndarray, q: np.ndarray) -> dict:
        """The pitch closure's sign, offset and centre, fitted on the training poses (class
        docstring, ``pitch_closure``; :func:`fit_pitch_closure`)."""
        if self.encoding != "arm_plane":
            raise ValueError(f"pitch_closure needs the 'arm_plane' encoding and at least 3 joints, got "
                             f"{self.encoding!r} and {q.shape[1]}")
        return fit_pitch_closure(self.encoder_, X, q, self.closure_tolerance)

    def _close(self, X: np.ndarray, q: np.ndarray) -> None:
        """Replace ``q``'s closure joint (in place) by the pitch closure of inputs ``X``."""
        close_pitch(self.closure_, self.encoder_, X, q)

    def without_closure(self) -> "LearnedIK":
        """A copy of the fitted model that predicts the last pitch joint by its own ANFIS instead
        of the pitch closure — the closure's ablation (chapter 7): the same trained rules, so a
        difference is the closure's alone. The copy says so in its parameters (``pitch_closure``
        false: saved, loaded and refitted as such) and shares no parameter with the original; a
        model without a closure comes back as such a copy."""
        self._check_fitted()
        model = copy.copy(self)
        model.__dict__.update(copy.deepcopy({k: v for k, v in self.__dict__.items() if not k.endswith("_")}))
        model.pitch_closure, model.closure_ = False, None
        return model

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
        check_integer("threads", threads, 1, message=f"threads must be a whole number >= 1, got {threads!r}")
        size = np.size(T_0e) // 16 if isinstance(T_0e, np.ndarray) else 0

        check_far(far)

        def predict_all(map_chunks) -> np.ndarray:
            T = check_targets(T_0e, 1e-6, map_chunks=map_chunks)   # every pose, before any work
            flat = T.reshape(-1, 4, 4)
            out = np.empty((len(flat), self.n_joints_))
            beyond = np.empty(len(flat))

            def chunk(start: int) -> None:
                X = self.encoder_.transform(flat[start:start + CHUNK])
                beyond[start:start + CHUNK] = beyond_range(X)
                for j, model in enumerate(self.models_):
                    out[start:start + CHUNK, j] = model._predict_fast(X)[0]
                if self.closure_ is not None:
                    self._close(X, out[start:start + CHUNK])

            with np.errstate(over="ignore", invalid="ignore"):
                for _ in map_chunks(chunk, range(0, len(flat), CHUNK)):
                    pass
            bad = ~np.isfinite(out).all(axis=1)
            if bad.any():        # as LearnedID's torques: no inf or NaN angles handed on
                i = int(np.argmax(bad))
                raise ValueError(f"the joint angles of {int(bad.sum())} of {len(out)} poses overflow (first: pose "
                                 f"{i}, its inputs {beyond[i]:.3g} training ranges beyond the training poses'): "
                                 f"poses far outside the data the model learned from, or a damaged model")
            warn_far(beyond, far, "poses")
            return out.reshape(*T.shape[:-2], self.n_joints_)

        if threads == 1 or size < 2 * CHUNK:
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
        return "\n".join(lines + model_lines(self.models_, "rad"))

    # -- persistence --------------------------------------------------------------------------

    def to_dict(self) -> dict:
        """The model as JSON-ready fields: its options, the robot's name and parameter hash,
        the encoder's fields (:meth:`PoseEncoder.to_dict`) and one ANFIS per joint."""
        self._check_fitted()
        return {"format": FORMAT, "nfarm_version": __version__,
                "anfis_options": json_ready(self.anfis_options),
                "joint_options": json_ready(self.joint_options), "shared_joints": json_ready(self.shared_joints),
                "pitch_closure": self.pitch_closure, "closure_tolerance": self.closure_tolerance,
                "closure": json_ready(self.closure_), "robot": self.robot_name_,
                "robot_params_sha256": self.robot_hash_, "n_joints": self.n_joints_,
                "fit_seconds": list(self.fit_seconds_),
                "models": [m.to_dict() for m in self.models_], **self.encoder_.to_dict()}

    @classmethod
    def from_dict(cls, data: Any, robot: Robot, source: str = "<dict>") -> "LearnedIK":
        v = Validator(source)
        v.mapping(data, "", {**dict.fromkeys(_KEYS, True), "chart": False,
                             **dict.fromkeys(_CLOSURE_KEYS, False)})
        if data["format"] != FORMAT:
            v.fail("format", f"must be {FORMAT!r} (an nfarm learned IK model), got {show(data['format'])}")
        encoding = v.choice(data["encoding"], "encoding", tuple(ENCODINGS))
        d = ENCODINGS[encoding]
        n, options, joint_options, fitted, seconds = read_joint_models(
            v, data, robot, source, [d] * robot.n, f"encoding {encoding!r}")
        encoder = PoseEncoder.from_dict(data, source)
        shared = data.get("shared_joints")
        if shared is not None:
            shared = [v.integer(j, f"shared_joints[{k}]", lo=0, hi=n - 1) for k, j in
                      enumerate(v.sequence(shared, "shared_joints", min_len=2, max_len=n))]
        closing = v.boolean(data.get("pitch_closure", False), "pitch_closure")
        tolerance = v.number(data.get("closure_tolerance", 1e-4), "closure_tolerance", lo=0, hi=math.pi)
        model = cls(encoding=encoding, joint_options=joint_options,
                    max_out_of_plane=encoder.max_out_of_plane, shared_joints=shared,
                    pitch_closure=closing, closure_tolerance=tolerance, **options)
        model.models_, model.fit_seconds_, model.encoder_ = fitted, seconds, encoder
        model.closure_ = read_closure(v, data.get("closure"), n) if closing else None
        model.robot_hash_, model.robot_name_, model.n_joints_ = data["robot_params_sha256"], \
            data["robot"], n
        return model


def _pitch(encoder: PoseEncoder, X: np.ndarray) -> np.ndarray:
    """The approach axis's pitch ``φ`` [rad] of scaled ``"arm_plane"`` inputs ``X (N, 6)``."""
    lo, span = encoder.input_lo_, encoder.input_span_
    c, s = (FEATURE_NAMES["arm_plane"].index(name) for name in ("cos_pitch", "sin_pitch"))
    return np.arctan2(X[:, s] * span[s] + lo[s], X[:, c] * span[c] + lo[c])


def fit_pitch_closure(encoder: PoseEncoder, X: np.ndarray, q: np.ndarray, tolerance: float = 1e-4) -> dict:
    """The pitch closure of an arm whose pitch joints solve a planar sub-problem, fitted on its
    training poses: the pitch joints' angles ``q[:, 1:n-1]`` sum to ``s·φ + c`` (``φ`` the
    approach axis's pitch; ``s = ±1`` and the constant ``c`` fitted), so the last pitch joint is
    ``q[n-2] = s·φ + c − Σ`` of the others (:func:`close_pitch`).

    Args:
        encoder: the fitted ``"arm_plane"`` :class:`PoseEncoder` of ``X``.
        X: ``(N, 6)`` its scaled inputs of the training poses; ``q (N, n)`` their joint angles [rad].
        tolerance: the largest residual [rad] of the identity allowed on the training poses.

    Returns:
        ``{"joint": n - 2, "sign": s, "offset": c, "centre": ...}`` [rad] (``centre``: the circular
        mean of ``q[n-2]``, about which a closed angle is wrapped).

    Raises:
        ValueError: another encoding, fewer than 3 joints, a bad ``tolerance``, or training poses
            that break the identity by more than ``tolerance``.
    """
    n = q.shape[1]
    if encoder.encoding != "arm_plane" or n < 3:
        raise ValueError("pitch_closure needs the 'arm_plane' encoding and at least 3 joints, got "
                         f"{encoder.encoding!r} and {n}")
    check_number("closure_tolerance", tolerance, 0, math.pi, open_lo=True, finite=False, numpy=False,
                 message=f"closure_tolerance must be in (0, pi) rad, got {show(tolerance)}")
    phi, total = _pitch(encoder, X), q[:, 1:n - 1].sum(axis=1)
    fits = []
    for sign in (1, -1):
        offset = float(np.angle(np.exp(1j * (total - sign * phi)).mean()))
        fits.append((float(np.abs(_wrap(total - sign * phi - offset)).max()), sign, offset))
    residual, sign, offset = min(fits)
    if residual > tolerance:
        raise ValueError(f"pitch_closure: joints 2-{n - 1}'s angles do not sum to the tool's pitch "
                         f"plus a constant on the training poses (largest residual "
                         f"{math.degrees(residual):.3g} deg, tolerance "
                         f"{math.degrees(tolerance):.3g} deg); use pitch_closure=False")
    centre = float(np.angle(np.exp(1j * q[:, n - 2]).mean()))
    return {"joint": n - 2, "sign": sign, "offset": offset, "centre": centre}


def close_pitch(closure: Mapping, encoder: PoseEncoder, X: np.ndarray, q: np.ndarray) -> None:
    """Replace the closure joint of predictions ``q (N, n)`` [rad], in place, by the pitch
    closure (:func:`fit_pitch_closure`) of scaled inputs ``X (N, 6)``, wrapped to within half a
    turn of the joint's training mean."""
    j = closure["joint"]
    others = q[:, 1:j].sum(axis=1)
    q[:, j] = closure["centre"] + _wrap(closure["sign"] * _pitch(encoder, X) + closure["offset"] - others
                                        - closure["centre"])


def read_closure(v: Validator, data: Any, n: int) -> dict:
    """A saved pitch closure (``closure``), checked."""
    v.mapping(data, "closure", dict.fromkeys(("joint", "sign", "offset", "centre"), True))
    if data["joint"] != n - 2 or data["sign"] not in (1, -1):
        v.fail("closure", f"joint must be {n - 2} and sign 1 or -1, got {show(data['joint'])} and "
                          f"{show(data['sign'])}")
    return {"joint": n - 2, "sign": int(data["sign"]),
            **{k: v.number(data[k], f"closure.{k}", lo=-math.pi, hi=math.pi) for k in ("offset", "centre")}}


_CLOSURE_KEYS = ("shared_joints", "pitch_closure", "closure_tolerance", "closure")
_KEYS = ("format", "nfarm_version", "encoding", "anfis_options", "joint_options",
         "max_out_of_plane", "robot", "robot_params_sha256", "n_joints", "angle_centre",
         "input_lo", "input_span", "fit_seconds", "models")


def _wrap(angle: np.ndarray) -> np.ndarray:
    """``angle`` [rad] wrapped into ``[-π, π)``."""
    return (angle + math.pi) % (2 * math.pi) - math.pi


# --------------------------------------------------------------------------------------------
# Errors and baselines


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

        check_choice("kind", self.kind, BASELINES)
        check_choice("encoding", self.encoding, ENCODINGS)
        T, q = ik_pairs(train, robot, "train")
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
