"""What the learned-IK contest's rivals of ANFIS share (chapter 6), written once: the encoded,
scaled pose inputs of :class:`nfarm.learning.learned.LearnedIK`, the robot, the structure and the
pitch closure, the checks of these common arguments, and saving and loading as JSON (no pickle).
Each rival is one subclass of :class:`RivalIK` in :mod:`nfarm.learning.ik_rivals`, registered in
:data:`RIVALS` under the name sweep files give it (``learner: knn``); import the rivals from there.

**Structures** (:data:`STRUCTURES`): by default (``"whole"``) one model learns all the joints. With
``"arm"`` a rival gets the structure the contest's ANFIS in the arm's plane has
(:class:`nfarm.learning.learned.LearnedIK` with ``shared_joints`` the pitch joints, one linear rule
for the first and last joints, ``pitch_closure``): for an arm of ``n`` joints on the
``"arm_plane"`` encoding, the first and the last joint are affine maps of the inputs (least
squares, what a one-rule first-order Sugeno model is), the pitch joints ``q[1:n-1]`` are learned by
the one model, and the last pitch joint is predicted from the target's pitch
(:func:`nfarm.learning.learned.fit_pitch_closure`) — the same outputs learned, the same joints
computed, so that a contest of the two judges the learners (chapter 6). :meth:`RivalIK.without_closure`
keeps the learned last pitch joint instead (the closure's ablation, chapter 7).

**A rival's part** (the hooks a subclass writes): ``kind`` and ``label`` (class attributes: the
registry's name, the words of tables and figures), ``__init__`` with its hyper-parameters (then
the common ones, keyword-only, passed on to :meth:`RivalIK.__init__`), ``_checked()`` (its
hyper-parameters checked, as the dict saved as ``options``), ``_learn`` and ``_predict`` (on the
scaled inputs ``X (N, d)`` and the learned joints' angles, standardised when ``standardised``),
``_state`` and ``_read_state`` (its arrays in the saved ``state``) and, optionally, ``_check_inputs``
(checks that need the encoding's ``d``) and ``_build`` (structures rebuilt on load).
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from .. import __version__
from ..infra.arguments import is_integer, is_number
from ..infra.reading import Validator, json_ready, show
from ..model.robot import Robot, robot_hash
from ..solvers.ik import check_targets
from .encoding import ENCODINGS, PoseEncoder
from .estimator import Registry, SavedModel, check_robot
from .hybrid import least_squares
from .learned import close_pitch, fit_pitch_closure, ik_pairs, read_closure

__all__ = ["RivalIK", "RIVALS", "STRUCTURES", "FILE_NAME", "FORMAT", "rival_ik", "whole_number", "finite_number"]

FILE_NAME = "rival_ik.json"
FORMAT = "nfarm-rival-ik-1"

#: The rivals by the name sweep files and saved models give them (``kind``): ``knn``, ``rbf``, …
RIVALS = Registry("learned-IK rival", "kind")
#: How the joints are computed: one model for all (``"whole"``) or the ANFIS's structure (``"arm"``, module docstring).
STRUCTURES = ("whole", "arm")
_ARM_FIELDS = ("closure_tolerance", "affine_ridge", "pitch_closure", "affine", "closure")


def whole_number(kind: str, name: str, x: Any, lo: int, hi: int) -> None:
    """Refuse, in one line naming the rival ``kind`` and the option ``name``, ``x`` that is not a
    whole number in ``[lo, hi]``."""
    if not is_integer(x) or not lo <= x <= hi:
        raise ValueError(f"{kind}: {name} must be a whole number in [{lo}, {hi}], got {show(x)}")


def finite_number(kind: str, name: str, x: Any, zero: bool = False) -> None:
    """Refuse ``x`` that is not a finite number ``> 0`` (``>= 0`` with ``zero``), in one line."""
    if not is_number(x, numpy=False) or not math.isfinite(x) or not (x >= 0 if zero else x > 0):
        raise ValueError(f"{kind}: {name} must be a finite number {'>= 0' if zero else '> 0'}, got {show(x)}")


def rival_ik(kind: str, encoding: str = "arm_plane", options: Mapping | None = None, **common) -> "RivalIK":
    """The rival registered as ``kind`` (:data:`RIVALS`) with its hyper-parameters ``options``
    (a sweep file's ``options``) and the ``common`` arguments of :class:`RivalIK`.

    Raises:
        ValueError: an unknown kind or parameter, in one line naming the valid ones.
    """
    cls = RIVALS.of(kind)
    options = {} if options is None else options
    if not isinstance(options, Mapping):
        raise ValueError(f"options must be a mapping of {kind} options, got {show(options)}")
    unknown = sorted(set(options) - set(cls.hyper_params()))
    if unknown:
        raise ValueError(f"{kind}: unknown option {unknown[0]!r}; valid: {', '.join(cls.hyper_params())}")
    return cls().set_params(**options, encoding=encoding, **common)


class RivalIK(SavedModel):
    """The base of the learned-IK rivals (module docstring; scikit-learn conventions: a rival's
    ``__init__`` stores its arguments unchanged, ``fit`` checks them and returns the rival).

    Args (common to every rival, keyword-only in the subclasses):
        encoding: how a pose becomes inputs (:data:`nfarm.learning.encoding.ENCODINGS`), as the
            learned IK's.
        max_out_of_plane: the ``"arm_plane"`` encoder's check [rad] (by default none, π).
        random_state: the seed of every random draw.
        structure: ``"whole"`` (one model learns every joint) or ``"arm"`` (the ANFIS's
            structure: module docstring; ``"arm_plane"`` only).
        closure_tolerance: for ``"arm"``, the pitch closure's largest residual [rad] on the
            training poses (:func:`nfarm.learning.learned.fit_pitch_closure`).
        affine_ridge: for ``"arm"``, the ridge on the first and last joints' least squares,
            relative to the normal matrix's mean diagonal — the one-rule ANFIS's least squares
            (:func:`nfarm.learning.hybrid.least_squares`, one rule), so that with the contest
            ANFIS's ridge (1e-8) those joints are the ANFIS's to the last bits.
        pitch_closure: for ``"arm"``, close the last pitch joint from the target's pitch (the
            structure's; ``False``: keep the model's own prediction of it, as
            :meth:`without_closure` does).

    Learned attributes: ``encoder_``, ``n_joints_``, ``robot_hash_``, ``robot_name_``,
    ``fit_seconds_``, ``epochs_`` and ``best_epoch_`` (an iterative rival's epochs run and kept;
    else 0), ``options_`` (the hyper-parameters checked, as saved), ``learned_`` (the joints the
    model learns, 0-based), ``affine_`` (``None``, or ``(d + 1, 2)``: the first and last joints'
    affine maps of the scaled inputs and 1), ``closure_`` (``None`` or the pitch closure),
    ``y_mean_`` and ``y_scale_`` (a ``standardised`` rival's), and the rival's own state.
    """

    _fitted = "encoder_"
    file_name, file_format, what = FILE_NAME, FORMAT, "rival IK"

    #: The rival's name in :data:`RIVALS` (a sweep file's ``learner``) and in words.
    kind: ClassVar[str]
    label: ClassVar[str]
    #: Whether the rival learns standardised joint angles (``y_mean_``, ``y_scale_``).
    standardised: ClassVar[bool] = False
    #: Whether ``fit`` needs validation poses (an iterative rival keeping its best epoch).
    needs_val: ClassVar[bool] = False
    #: The rival's arrays in the saved ``state`` (besides ``y_mean`` and ``y_scale``).
    _state_keys: ClassVar[tuple[str, ...]] = ()
    _optional_state_keys: ClassVar[tuple[str, ...]] = ()     # state a subclass saves in some configurations only

    def __init__(self, *, encoding: str = "arm_plane", max_out_of_plane: float = math.pi,
                 random_state: int | None = None, structure: str = "whole", closure_tolerance: float = 1e-4,
                 affine_ridge: float = 1e-8, pitch_closure: bool = True):
        self.encoding = encoding
        self.max_out_of_plane = max_out_of_plane
        self.random_state = random_state
        self.structure = structure
        self.closure_tolerance = closure_tolerance
        self.affine_ridge = affine_ridge
        self.pitch_closure = pitch_closure

    @classmethod
    def hyper_params(cls) -> list[str]:
        """The rival's own parameters (its saved ``options``), in its ``__init__``'s order."""
        common = RivalIK._signature()[0]
        return [name for name in cls._signature()[0] if name not in common]

    # -- a rival's part (module docstring) ----------------------------------------------------

    def _checked(self) -> dict:
        raise TypeError(f"{type(self).__name__} is not a rival of its own: fit one of {', '.join(RIVALS)} "
                        f"(nfarm.learning.ik_rivals.RIVALS)")

    def _check_inputs(self, o: dict, d: int) -> None:
        """Checks of the options that need the number ``d`` of inputs of the encoding."""

    def _learn(self, o: dict, X: np.ndarray, y: np.ndarray, X_val, y_val) -> None:
        raise NotImplementedError

    def _build(self, o: dict) -> None:
        """Structures rebuilt (deterministically) from the state, after fitting and on load."""

    def _predict(self, X: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _state(self) -> dict:
        raise NotImplementedError

    def _read_state(self, v: Validator, state: Mapping, d: int, n_out: int, o: dict) -> None:
        raise NotImplementedError

    # -- fitting ------------------------------------------------------------------------------

    def fit(self, robot: Robot, train: Mapping, val: Mapping | None = None) -> "RivalIK":
        """Fit on ``train`` (``T (N, 4, 4)``, ``q (N, n)``); ``val`` (the same) is used by a rival
        that ``needs_val`` only, to keep its best epoch and stop early.

        Raises:
            ValueError: bad options or data, before any training; such a rival without ``val``.
        """
        o = self._checked()
        if self.encoding not in ENCODINGS:
            raise ValueError(f"encoding must be one of {', '.join(ENCODINGS)}, got {show(self.encoding)}")
        if self.structure not in STRUCTURES:
            raise ValueError(f"structure must be one of {', '.join(STRUCTURES)}, got {show(self.structure)}")
        if self.structure == "arm" and (self.encoding != "arm_plane" or robot.n < 3):
            raise ValueError(f"structure 'arm' needs the 'arm_plane' encoding and at least 3 joints, got "
                             f"{show(self.encoding)} and {robot.n}")
        T, q = ik_pairs(train, robot, "train")
        if self.needs_val and val is None:
            raise ValueError(f"an {self.kind} rival keeps its best epoch on validation poses: give val")
        self._check_inputs(o, ENCODINGS[self.encoding])
        self.encoder_ = PoseEncoder(self.encoding, self.max_out_of_plane)
        X = self.encoder_.fit_transform(robot, T)
        start = time.perf_counter()
        self.epochs_ = self.best_epoch_ = 0
        self.learned_, self.affine_, self.closure_ = list(range(robot.n)), None, None
        if self.structure == "arm":
            if not isinstance(self.pitch_closure, bool):
                raise ValueError(f"pitch_closure must be true or false, got {show(self.pitch_closure)}")
            closure = fit_pitch_closure(self.encoder_, X, q, self.closure_tolerance)   # checks the arm either way
            self.closure_ = closure if self.pitch_closure else None
            self.learned_ = list(range(1, robot.n - 1))
            if isinstance(self.affine_ridge, bool) or not isinstance(self.affine_ridge, (int, float)) \
                    or not 0 <= self.affine_ridge < 1:
                raise ValueError(f"affine_ridge must be a number in [0, 1), got {show(self.affine_ridge)}")
            self.affine_ = least_squares(np.ones((len(X), 1)), np.column_stack([X, np.ones(len(X))]),
                                         q[:, [0, robot.n - 1]], ridge=float(self.affine_ridge))
        y = q[:, self.learned_]
        if self.standardised:
            self.y_mean_, self.y_scale_ = y.mean(axis=0), np.where(y.std(axis=0) > 0, y.std(axis=0), 1.0)
            y = (y - self.y_mean_) / self.y_scale_
        X_val = y_val = None
        if self.needs_val:
            T_val, q_val = ik_pairs(val, robot, "val")
            X_val, y_val = self.encoder_.transform(T_val), q_val[:, self.learned_]
            if self.standardised:
                y_val = (y_val - self.y_mean_) / self.y_scale_
        self._learn(o, X, y, X_val, y_val)
        self.options_ = o
        self._build(o)
        self.fit_seconds_ = time.perf_counter() - start
        self.n_joints_, self.robot_hash_, self.robot_name_ = robot.n, robot_hash(robot), robot.name
        return self

    # -- prediction ---------------------------------------------------------------------------

    def without_closure(self) -> "RivalIK":
        """A copy of the fitted model that keeps its learned last pitch joint instead of the pitch
        closure (the closure's ablation, chapter 7); a model without a closure comes back as a copy."""
        self._check_fitted()
        model = copy.copy(self)
        model.__dict__.update(copy.deepcopy({k: v for k, v in self.__dict__.items() if not k.endswith("_")}))
        model.pitch_closure, model.closure_ = False, None
        return model

    def predict(self, T_0e) -> np.ndarray:
        """Joint angles ``(..., n)`` [rad] for tool poses ``T_0e (..., 4, 4)``."""
        self._check_fitted()
        T = check_targets(T_0e, 1e-6)
        X = self.encoder_.transform(T.reshape(-1, 4, 4))
        y = self._predict(X)
        if self.standardised:
            y = y * self.y_scale_ + self.y_mean_
        if self.affine_ is None:
            return y.reshape(*T.shape[:-2], self.n_joints_)
        n = self.n_joints_
        q = np.empty((len(X), n))
        q[:, self.learned_] = y
        q[:, [0, n - 1]] = np.column_stack([X, np.ones(len(X))]) @ self.affine_
        if self.closure_ is not None:
            close_pitch(self.closure_, self.encoder_, X, q)
        return q.reshape(*T.shape[:-2], n)

    # -- persistence --------------------------------------------------------------------------

    def to_dict(self) -> dict:
        """The model as JSON-ready fields (its kind and options, the robot's name and hash, the
        encoder and the rival's ``state``)."""
        self._check_fitted()
        scaling = {"y_mean": json_ready(self.y_mean_), "y_scale": json_ready(self.y_scale_)} if self.standardised else {}
        structure = {} if self.structure == "whole" else {
            "structure": self.structure, "closure_tolerance": self.closure_tolerance, "affine_ridge": self.affine_ridge,
            "pitch_closure": self.pitch_closure,
            "affine": json_ready(self.affine_), "closure": json_ready(self.closure_)}
        return {"format": FORMAT, "nfarm_version": __version__, "kind": self.kind, **structure,
                "options": json_ready(self.options_), "random_state": self.random_state,
                "robot": self.robot_name_, "robot_params_sha256": self.robot_hash_, "n_joints": self.n_joints_,
                "fit_seconds": self.fit_seconds_, "epochs": self.epochs_, "best_epoch": self.best_epoch_,
                "state": {**scaling, **self._state()}, **self.encoder_.to_dict()}

    @classmethod
    def from_dict(cls, data: Any, robot: Robot, source: str = "<dict>") -> "RivalIK":
        """The rival saved as ``data`` (:meth:`to_dict`), of the class its ``kind`` names in
        :data:`RIVALS` whatever class this is called on.

        Raises:
            ParamsError: a field missing, unknown or out of its range (named, with ``source``), a
                kind no class is registered as, or a model trained for another robot.
        """
        v = Validator(source)
        keys = ("format", "nfarm_version", "kind", "options", "random_state", "robot", "robot_params_sha256",
                "n_joints", "fit_seconds", "epochs", "best_epoch", "state", "encoding", "max_out_of_plane",
                "angle_centre", "input_lo", "input_span")
        v.mapping(data, "", {**dict.fromkeys(keys, True), "chart": False, **dict.fromkeys(("structure", *_ARM_FIELDS), False)})
        rival = RIVALS[v.choice(data["kind"], "kind", tuple(RIVALS))]
        if not issubclass(rival, cls):
            v.fail("kind", f"must be {cls.kind!r} (a {cls.__name__}), got {show(data['kind'])}")
        structure = v.choice(data.get("structure", "whole"), "structure", STRUCTURES)
        if not isinstance(data["options"], Mapping):
            v.fail("options", f"must be a mapping of {data['kind']} options, got {show(data['options'])}")
        unknown = sorted(set(data["options"]) - set(rival.hyper_params()))
        if unknown:
            v.fail("options", f"{rival.kind}: unknown option {unknown[0]!r}; valid: {', '.join(rival.hyper_params())}")
        check_robot(v, data, robot)
        n = v.integer(data["n_joints"], "n_joints", lo=robot.n, hi=robot.n)
        encoder = PoseEncoder.from_dict(data, source)
        d = len(encoder.input_lo_)
        seed = None if data["random_state"] is None else v.integer(data["random_state"], "random_state", lo=0)
        model = rival(**data["options"], encoding=encoder.encoding, max_out_of_plane=encoder.max_out_of_plane,
                      random_state=seed, structure=structure)
        try:
            options = model._checked()
        except ValueError as exc:
            v.fail("options", str(exc))
        model.encoder_, model.n_joints_, model.robot_hash_ = encoder, n, data["robot_params_sha256"]
        model.learned_, model.affine_, model.closure_ = list(range(n)), None, None
        if structure == "arm":
            model._read_structure(v, data, n, d)
        elif any(key in data for key in _ARM_FIELDS):
            v.fail("structure", "closure_tolerance, affine_ridge, pitch_closure, affine and closure belong to structure 'arm'")
        n_out = len(model.learned_)
        model.robot_name_ = data["robot"]
        model.fit_seconds_ = v.number(data["fit_seconds"], "fit_seconds", lo=0)
        model.epochs_ = v.integer(data["epochs"], "epochs", lo=0)
        model.best_epoch_ = v.integer(data["best_epoch"], "best_epoch", lo=0)
        state = data["state"]
        v.mapping(state, "state", {**dict.fromkeys((*(("y_mean", "y_scale") if rival.standardised else ()),
                                                    *rival._state_keys), True),
                                   **dict.fromkeys(rival._optional_state_keys, False)})
        if rival.standardised:
            model.y_mean_ = v.array(state["y_mean"], "state.y_mean", (n_out,))
            model.y_scale_ = v.array(state["y_scale"], "state.y_scale", (n_out,))
        model._read_state(v, state, d, n_out, options)
        model.options_ = options
        model._build(options)
        return model

    def _read_structure(self, v: Validator, data: Mapping, n: int, d: int) -> None:
        """The saved structure ``"arm"``'s fields, in the ranges ``fit`` accepts."""
        if self.encoding != "arm_plane" or n < 3:
            v.fail("structure", f"'arm' needs the 'arm_plane' encoding and at least 3 joints, got "
                                f"{show(self.encoding)} and {n}")
        for key in ("closure_tolerance", "affine_ridge", "affine", "closure"):
            if key not in data:
                v.fail(key, "is required with structure 'arm'")
        # the ranges fit accepts: (0, π) and [0, 1)
        self.closure_tolerance = v.number(data["closure_tolerance"], "closure_tolerance", lo=0, hi=math.pi, lo_open=True)
        if self.closure_tolerance >= math.pi:
            v.fail("closure_tolerance", f"must be below pi, got {show(data['closure_tolerance'])}")
        self.affine_ridge = v.number(data["affine_ridge"], "affine_ridge", lo=0, hi=1)
        if self.affine_ridge >= 1:
            v.fail("affine_ridge", f"must be below 1, got {show(data['affine_ridge'])}")
        self.pitch_closure = v.boolean(data.get("pitch_closure", True), "pitch_closure")
        self.learned_ = list(range(1, n - 1))
        self.affine_ = v.array(data["affine"], "affine", (d + 1, 2))
        self.closure_ = read_closure(v, data["closure"], n) if self.pitch_closure else None
        if not self.pitch_closure and data["closure"] is not None:
            v.fail("closure", "must be null when pitch_closure is false")
