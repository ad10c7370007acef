"""Learned inverse dynamics: one ANFIS per joint behind one object (chapters 06 and 07).

:class:`LearnedID` maps joint states to torques. It feeds each joint's model one of nine
**input sets** (:func:`id_features`): the joint's own ``q, q̇, q̈`` (the likely dissertation
design), every joint's, trigonometric features, the ``affine`` sets — rules over the
configuration, consequents over the terms every rigid arm's torque is a sum of
(:mod:`nfarm.learning.bases`), with or without every joint's friction terms — or the joint's row of the rigid-body regressor
(:func:`nfarm.model.dynamics.regressor`), which needs the arm's geometry. Chapter 06 compares
them on validation trajectories (``figures/tables/06_id_comparison``): the rules of the
``affine`` sets supply the products of angle functions the inertia needs, which the
dissertation's own-state design lacks. The regressor's row with one rule fits the torques
exactly (they are linear in it, ``τ = Y π``): one rule is least squares on the inertial
parameters, an identification, not a learning result. With ``residual=True`` a model learns
``τ − rnea`` instead: what the rigid-body model misses on chapter 05's measured arm (friction,
encoder states, sensor noise), compared with a least-squares friction identification in
chapter 07 (``figures/tables/07_id_measured``).

A model is saved into a directory as one JSON file (``learned_id.json``; no pickle) holding the
robot's parameter hash; loading against another robot is an error, and the file is validated
like a parameter file (:mod:`nfarm.infra.reading`).
"""

from __future__ import annotations

import functools
import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .. import __version__
from ..infra.arguments import check_bool, check_choice
from ..infra.reading import Validator, json_ready, show
from ..model.dynamics import regressor, rnea
from ..model.robot import Robot, joint_array, robot_hash
from .anfis import ANFIS, fit_shared
from .bases import basis, basis_width
from .encoding import check_scaling, input_scaling
from .priors import DRIVE_LAW, FITTED_LAW, check_residual, drive_law_field, drive_terms, fit_prior, prior_of, prior_torques, read_drive_law, read_prior
from .per_joint import (PerJointModel, CHUNK, FAR, beyond_range, check_far, check_joint_array, joint_anfis_options,
                        model_lines, read_joint_models, warn_far)

__all__ = ["LearnedID", "id_features", "id_states", "regressor_columns", "INPUT_SETS", "SHARED_INPUT_SETS", "ID_FILE_NAME", "ID_FORMAT"]


#: Input sets of :class:`LearnedID`: what each joint's model sees of a state ``(q, q̇, q̈)``.
INPUT_SETS = ("own", "all", "trig", "affine_generic", "affine", "affine_generic_drives", "affine_drives", "regressor",
              "regressor_drives")
#: Input sets every joint's model sees alike: their joints can share premises.
SHARED_INPUT_SETS = ("all", "trig", "affine_generic", "affine", "affine_generic_drives", "affine_drives")
#: Input sets whose rules are built over the configuration ``q`` only (the first n columns), and
#: the basis of :mod:`nfarm.learning.bases` their consequents see (less its constant).
_CONFIGURATION_PREMISES = {"affine_generic": "generic_linear", "affine": "chain_linear",
                           "affine_generic_drives": "generic_linear_drives", "affine_drives": "chain_linear_drives"}
ID_FILE_NAME = "learned_id.json"
ID_FORMAT = "nfarm-learned-id-1"


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
    * ``"affine_generic_drives"``, ``"affine_drives"`` — those and every joint's drive terms
      ``q̇_k, sign q̇_k`` (:func:`nfarm.learning.bases.drive_terms`: viscous and Coulomb
      friction, which every driven joint has and no rigid-body term represents): the same
      tiers of knowledge for a built arm (chapter 06.8's measured arm), 10 more columns for
      five joints;
    * ``"regressor"`` — row j of the rigid-body regressor ``Y(q, q̇, q̈)``
      (:func:`nfarm.model.dynamics.regressor`): the columns of links j..n that are not zero for
      every state (:func:`regressor_columns`; for intelbot5 34, 38, 28, 17 and 8). The
      geometry (DH parameters) is known, the masses are not: ``τ_j`` is linear in these
      inputs, so one rule (least squares) can already be exact;
    * ``"regressor_drives"`` — those columns and the joint's own drive terms ``q̈_j, q̇_j,
      tanh(q̇_j / ε_j)`` (armature, viscous and Coulomb friction, the robot file's drive law:
      :func:`nfarm.learning.priors.drive_terms`): what the identification of a built
      arm (:class:`nfarm.learning.baselines.BaselineID`, learner ``identification``) sees of
      joint j, so that the ANFIS of the identification tier gets the same inputs as its rival.
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
        X = np.concatenate([q, basis(robot, q, qd, qdd, _CONFIGURATION_PREMISES[inputs])[:, 1:]], axis=1)
        return [X] * robot.n
    Y = regressor(robot, q, qd, qdd)
    rows = [np.ascontiguousarray(Y[:, j, cols]) for j, cols in enumerate(regressor_columns(robot))]
    if inputs == "regressor_drives":
        drives = drive_terms(robot, qd, qdd)                                     # (N, n, 3)
        rows = [np.column_stack([Y_j, drives[:, j]]) for j, Y_j in enumerate(rows)]
    return rows


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
    if inputs in ("regressor", "regressor_drives"):
        return [len(cols) + 3 * (inputs == "regressor_drives") for cols in _regressor_columns(robot)]
    n = robot.n
    if inputs in _CONFIGURATION_PREMISES:
        return [n + basis_width(robot, _CONFIGURATION_PREMISES[inputs]) - 1] * n
    return [{"own": 3, "all": 3 * n, "trig": 5 * n}[inputs]] * n


def id_states(data: Mapping, robot: Robot, what: str, *, tau: bool = True) -> list[np.ndarray]:
    """``q, qd, qdd`` (and ``tau``) ``(N, n)`` of an ID data set, checked."""
    keys = ("q", "qd", "qdd", "tau") if tau else ("q", "qd", "qdd")
    if not isinstance(data, Mapping) or any(k not in data for k in keys):
        raise ValueError(f"{what} must be a mapping with arrays {', '.join(map(repr, keys))} "
                         f"(N, {robot.n}), e.g. an ID data set of nfarm.study.datasets.load")
    arrays = [check_joint_array(data[k], robot, what, k) for k in keys]
    if len({len(a) for a in arrays}) != 1:
        raise ValueError(f"{what}: {', '.join(keys)} must have one row per sample, got "
                         f"{', '.join(str(len(a)) for a in arrays)} rows")
    return arrays


class LearnedID(PerJointModel):
    """Inverse dynamics learned by one ANFIS per joint (scikit-learn conventions).

    Args:
        inputs: what each joint's model sees (:data:`INPUT_SETS`, :func:`id_features`).
        residual: learn ``τ − rnea(q, q̇, q̈)`` (what the rigid-body model misses: friction,
            armature) and predict ``rnea + ANFIS`` (semi-parametric, Nguyen-Tuong & Peters
            2010; ``True`` or ``"nominal"``), or learn what the identification of the arm as built,
            fitted first on the same training states, misses (``"identification"``,
            :mod:`nfarm.learning.priors`); ``False`` learns the torques themselves.
        joint_options: ``None`` or one mapping per joint of ANFIS options overriding the shared.
        shared_premises: train the joints' models together, their rules sharing their
            membership functions (:func:`nfarm.learning.anfis.fit_shared`): one least-squares
            factorisation per epoch serves all joints (about ``n`` times less work where the
            consequents have hundreds of inputs). For input sets every joint sees alike
            (:data:`SHARED_INPUT_SETS`) and the same options for every joint. Each joint keeps
            its own consequents and best epoch; the saved models are ordinary per-joint ones.
        **anfis_options: passed to every joint's :class:`nfarm.learning.anfis.ANFIS`.

    Learned attributes: ``models_``, ``prior_`` (the identification's ``θ (14 n,)`` under
    ``residual="identification"``, else ``None``), ``robot_`` (the robot it was fitted or loaded with),
    ``robot_hash_``, ``robot_name_``, ``n_joints_``, ``input_lo_``, ``input_span_`` (per joint, the inputs' scaling to ``[0, 1]``),
    ``fit_seconds_`` (with shared premises, the joint training's time split evenly).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> rng = np.random.default_rng(0)
        >>> def states(N):                        # random states within the joint limits
        ...     q = rng.uniform(robot.qlim[:, 0], robot.qlim[:, 1], (N, robot.n))
        ...     qd, qdd = rng.uniform(-1, 1, (2, N, robot.n))           # [rad/s], [rad/s²]
        ...     return {"q": q, "qd": qd, "qdd": qdd, "tau": rnea(robot, q, qd, qdd)}
        >>> train, test = states(400), states(100)
        >>> model = LearnedID(inputs="regressor", n_mfs=1, epochs=1).fit(robot, train)
        >>> tau = model.predict(test["q"], test["qd"], test["qdd"])
        >>> tau.shape                                                 # (states, joints) [N·m]
        (100, 5)
        >>> model.predict(test["q"][0], test["qd"][0], test["qdd"][0]).shape      # one state
        (5,)
        >>> nrmse = np.sqrt(np.mean((tau - test["tau"]) ** 2, axis=0)) / test["tau"].std(axis=0)
        >>> bool((nrmse < 1e-6).all())        # τ = Y π is linear in the regressor: one rule is exact
        True
    """

    _passed_to = ANFIS
    file_name, file_format, what = ID_FILE_NAME, ID_FORMAT, "learned ID"

    def __init__(self, inputs: str = "own", residual: bool | str = False,
                 joint_options: Sequence[Mapping] | None = None, shared_premises: bool = False,
                 **anfis_options):
        self.inputs = inputs
        self.residual = residual
        self.joint_options = joint_options
        self.shared_premises = shared_premises
        self.anfis_options = anfis_options

    def _inputs(self, q, qd, qdd) -> list[np.ndarray]:
        """Each joint's inputs, scaled to [0, 1] over the training data."""
        return self._scaled(id_features(self.robot_, q, qd, qdd, self.inputs))

    def _scaled(self, features: list[np.ndarray]) -> list[np.ndarray]:
        """Each joint's ``features`` scaled by its ``input_lo_`` and ``input_span_``; joints that
        see one array (the input sets every joint sees alike) with one scaling share one scaled
        copy — five copies of 156 000 states × 361 inputs were 2.3 GB."""
        done, scaled = {}, []
        for X, lo, span in zip(features, self.input_lo_, self.input_span_):
            same = done.get(id(X))
            if same is None or not (np.array_equal(same[0], lo) and np.array_equal(same[1], span)):
                same = done[id(X)] = (lo, span, (X - lo) / span)
            scaled.append(same[2])
        return scaled

    def fit(self, robot: Robot, train: Mapping, val: Mapping | None = None) -> "LearnedID":
        """Train one ANFIS per joint on ``train`` (arrays ``q, qd, qdd, tau (N, n)``), keeping
        each model's epoch of least error on ``val`` when given.

        Raises:
            ValueError: bad options or data (shapes, NaN, lengths), before any training.
        """
        check_choice("inputs", self.inputs, INPUT_SETS)
        check_residual(self.residual)
        check_bool("shared_premises", self.shared_premises)
        if self.shared_premises and self.inputs not in SHARED_INPUT_SETS:
            raise ValueError(f"shared_premises needs inputs every joint sees alike "
                             f"({', '.join(SHARED_INPUT_SETS)}), got inputs {self.inputs!r}")
        n = robot.n
        shared = dict(self.anfis_options)
        if self.inputs in _CONFIGURATION_PREMISES:
            shared.setdefault("premise_inputs", list(range(n)))
        options = joint_anfis_options(shared, self.joint_options, n, _id_widths(self.inputs, robot))
        if self.shared_premises and any(o != options[0] for o in options[1:]):
            raise ValueError("shared_premises needs the same ANFIS options for every joint: "
                             "joint_options must not differ between joints")
        q, qd, qdd, tau = id_states(train, robot, "train")
        val_states = id_states(val, robot, "val") if val is not None else None
        self.__dict__.pop("models_", None)       # a failed refit leaves no half-fitted model
        prior, prior_train, prior_seconds = fit_prior(robot, self.residual, q, qd, qdd, tau)
        target = tau - prior_train
        if val_states is not None:
            vq, vqd, vqdd, vtau = val_states
            val_target = vtau - prior_torques(robot, self.residual, vq, vqd, vqdd, prior)
        self.robot_ = robot
        features = id_features(robot, q, qd, qdd, self.inputs)
        scaling = {id(F): input_scaling(F) for F in features}           # once per distinct array
        self.input_lo_ = [scaling[id(F)][0] for F in features]
        self.input_span_ = [scaling[id(F)][1] for F in features]
        X = self._scaled(features)
        del features
        Xv = self._inputs(vq, vqd, vqdd) if val_states is not None else [None] * n
        if self.shared_premises:
            start = time.perf_counter()
            models = fit_shared(ANFIS(**options[0]), X[0], target, Xv[0],
                                None if val_states is None else val_target)
            seconds = [(time.perf_counter() - start) / n] * n
        else:
            models, seconds = [], []
            for j in range(n):
                start = time.perf_counter()
                models.append(ANFIS(**options[j]).fit(X[j], target[:, j], Xv[j],
                                                      None if val_states is None else val_target[:, j]))
                seconds.append(time.perf_counter() - start)
        self.robot_hash_, self.robot_name_, self.n_joints_ = robot_hash(robot), robot.name, n
        self.prior_ = prior
        self.models_, self.fit_seconds_ = models, [s + prior_seconds / n for s in seconds]
        return self

    def predict(self, q, qd, qdd, *, far: float = FAR) -> np.ndarray:
        """Joint torques ``(..., n)`` [N·m] for states ``q, qd, qdd (..., n)`` (batch shapes
        broadcast; one state is the ``()`` batch). A residual model adds ``rnea`` of the robot
        it was fitted or loaded with, or its identification of the arm as built. States whose inputs lie more than ``far`` of their
        training range beyond it are predicted with an :class:`OutsideTrainingWarning`.

        Raises:
            ValueError: states that are not real ``(..., n)`` arrays, or NaN, before any work;
                states so far outside the training data that a torque overflows (named).
        """
        check_far(far)
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
            for start in range(0, len(tau), CHUNK):
                part = [a[start:start + CHUNK] for a in flat]
                X = self._inputs(*part)
                beyond[start:start + CHUNK] = np.max([beyond_range(x) for x in X], axis=0)
                for j, model in enumerate(self.models_):
                    tau[start:start + CHUNK, j] = model._predict_fast(X[j])[0]
                if self.residual is not False:
                    tau[start:start + CHUNK] += prior_torques(robot, self.residual, *part, self.prior_)
        bad = ~np.isfinite(tau).all(axis=1)
        if bad.any():
            i = int(np.argmax(bad))
            raise ValueError(f"the torques of {int(bad.sum())} of {len(tau)} states overflow (first: state {i}, "
                             f"its inputs {beyond[i]:.3g} training ranges beyond the training states'): "
                             f"q, qd, qdd far outside the data the model learned from")
        warn_far(beyond, far, "states")
        return tau.reshape(*batch, robot.n)

    def describe(self) -> str:
        self._check_fitted()
        what = {None: "τ", "nominal": "τ − rnea (residual)",
                "identification": "τ − the identification (residual)"}[prior_of(self.residual)]
        head = (f"LearnedID for {self.robot_name_} ({self.n_joints_} joints), inputs "
                f"{self.inputs!r} ({', '.join(str(len(lo)) for lo in self.input_lo_)} per joint), "
                f"learning {what}")
        return "\n".join([head] + model_lines(self.models_, "N·m"))

    def to_dict(self) -> dict:
        self._check_fitted()
        return {"format": ID_FORMAT, "nfarm_version": __version__, "inputs": self.inputs,
                "residual": self.residual, "shared_premises": self.shared_premises,
                "anfis_options": json_ready(self.anfis_options),
                "joint_options": json_ready(self.joint_options), "robot": self.robot_name_,
                "robot_params_sha256": self.robot_hash_, "n_joints": self.n_joints_,
                "input_lo": json_ready(self.input_lo_), "input_span": json_ready(self.input_span_),
                "fit_seconds": list(self.fit_seconds_),
                "models": [m.to_dict() for m in self.models_],
                **({} if self.prior_ is None else {"prior": json_ready(self.prior_)}),
                **drive_law_field(_drive_law(self.inputs, self.residual))}

    @classmethod
    def from_dict(cls, data: Any, robot: Robot, source: str = "<dict>") -> "LearnedID":
        v = Validator(source)
        v.mapping(data, "", {**dict.fromkeys(_ID_KEYS, True), "shared_premises": False, "prior": False, "drive_law": False})
        if data["format"] != ID_FORMAT:
            v.fail("format", f"must be {ID_FORMAT!r} (an nfarm learned ID model), got {show(data['format'])}")
        inputs = v.choice(data["inputs"], "inputs", INPUT_SETS)
        residual = data["residual"]
        try:
            check_residual(residual)
        except ValueError as exc:
            v.fail("residual", str(exc).removeprefix("residual "))
        shared_premises = v.boolean(data.get("shared_premises", False), "shared_premises")
        widths = _id_widths(inputs, robot)
        n, options, joint_options, fitted, seconds = read_joint_models(
            v, data, robot, source, widths, f"input set {inputs!r}")
        lo = [v.array(x, f"input_lo[{j}]", (d,)) for j, (x, d) in
              enumerate(zip(v.sequence(data["input_lo"], "input_lo", min_len=n, max_len=n), widths))]
        span = [v.array(x, f"input_span[{j}]", (d,)) for j, (x, d) in
                enumerate(zip(v.sequence(data["input_span"], "input_span", min_len=n, max_len=n),
                              widths))]
        for j, (lo_j, span_j) in enumerate(zip(lo, span)):
            check_scaling(v, lo_j, span_j, f"input_lo[{j}]", f"input_span[{j}]")
        model = cls(inputs=inputs, residual=residual, joint_options=joint_options,
                    shared_premises=shared_premises, **options)
        model.models_, model.fit_seconds_ = fitted, seconds
        read_drive_law(v, data, _drive_law(inputs, residual))     # before the prior: an older law's has other columns
        model.prior_ = read_prior(v, data, residual, robot)
        model.input_lo_, model.input_span_ = list(lo), list(span)
        model.robot_hash_, model.robot_name_, model.n_joints_ = data["robot_params_sha256"], \
            data["robot"], n
        model.robot_ = robot
        return model


def _drive_law(inputs: str, residual) -> str | None:
    """The drive law a learned ID's predictions use (its saved ``drive_law``): the identification's
    (:data:`~nfarm.learning.priors.FITTED_LAW`) on its residual, the drive terms' among the inputs
    (:data:`~nfarm.learning.priors.DRIVE_LAW`) on the regressor's rows with them, else ``None``."""
    if prior_of(residual) == "identification":
        return FITTED_LAW
    return DRIVE_LAW if inputs == "regressor_drives" else None


_ID_KEYS = ("format", "nfarm_version", "inputs", "residual", "anfis_options", "joint_options",
            "robot", "robot_params_sha256", "n_joints", "input_lo", "input_span", "fit_seconds",
            "models")
