"""The plumbing every learner of this package shares, written once (as scikit-learn's
``BaseEstimator``): the parameters are those of ``__init__``'s signature, which stores them
unchanged; ``get_params`` and ``set_params`` read and change them (an unknown name is refused in
one line naming the valid ones); ``repr`` shows those that differ from their defaults; and a
learner used before it was fitted says so in one line.

**Saving.** A learner that can be saved (:class:`nfarm.learning.anfis.ANFIS`, ``ANFISMulti``,
and the robot's learners, :class:`SavedModel`: ``LearnedIK``, ``LearnedID``, ``RivalIK``,
``BaselineID``) takes a *directory* and writes one JSON file of a fixed name in it
(:func:`write_model`), so that a model's directory can hold what belongs with it
(``fit_cached``'s ``inputs.sha256``); loading takes that directory or the file itself
(:func:`model_file`), refuses an edited file before reading any field (:func:`checked_file`) and a
model of another robot (:func:`check_robot`).

A learner whose ``__init__`` takes ``**options`` passes them on to the learners it builds (an
:class:`nfarm.learning.anfis.ANFIS` per joint): they are parameters too, kept in the attribute
named like that argument and checked against the learner they go to (:attr:`Estimator._passed_to`).

**One class per learner.** A task whose learners share their plumbing (the learned-IK rivals,
:mod:`nfarm.learning.ik_rivals`; the ID baselines, :mod:`nfarm.learning.baselines`) has a base
class and a :class:`Registry`: each learner is one class, registered where it is defined under the
name sweep files give it (``learner: knn``), with its words for tables and figures (``label``).
"""

from __future__ import annotations

import inspect
import json
import os
from pathlib import Path
from typing import Any, ClassVar

from ..infra.paths import atomic_path
from ..infra.reading import Validator, checked_content, load_json, show, with_content_digest
from ..model.robot import Robot, robot_hash

__all__ = ["Estimator", "Registry", "SavedModel", "write_model", "model_file", "checked_file", "check_robot"]


class Estimator:
    """Base of the package's learners (module docstring).

    Class attributes a learner sets:
        _fitted: the learned attribute that exists once it is fitted (or loaded).
        _passed_to: the estimator class that checks the ``**options`` passed on, or ``None``.

    Example:
        >>> class Scaled(Estimator):
        ...     _fitted = "scale_"
        ...     def __init__(self, factor: float = 1.0, clip: bool = False):
        ...         self.factor = factor
        ...         self.clip = clip
        >>> model = Scaled(factor=2.0)
        >>> model, model.get_params()
        (Scaled(factor=2.0), {'factor': 2.0, 'clip': False})
        >>> model.set_params(clip=True)
        Scaled(factor=2.0, clip=True)
        >>> model.set_params(scale=3)
        Traceback (most recent call last):
        ...
        ValueError: unknown parameter 'scale' for Scaled; valid: factor, clip
        >>> model._check_fitted()
        Traceback (most recent call last):
        ...
        ValueError: this Scaled is not fitted yet: call fit
    """

    _fitted: ClassVar[str] = "models_"
    _passed_to: ClassVar[type | None] = None

    @classmethod
    def _signature(cls) -> tuple[dict[str, Any], str | None]:
        """The named parameters of ``__init__`` with their defaults, and the name of its
        ``**options`` argument (or ``None``)."""
        named, passed_on = {}, None
        for p in list(inspect.signature(cls.__init__).parameters.values())[1:]:
            if p.kind is inspect.Parameter.VAR_KEYWORD:
                passed_on = p.name
            else:
                named[p.name] = p.default
        return named, passed_on

    @classmethod
    def _param_names(cls) -> list[str]:
        """The parameter names a learner accepts: its own, then those it passes on."""
        named, passed_on = cls._signature()
        return list(named) + (cls._passed_to._param_names() if passed_on and cls._passed_to else [])

    def get_params(self, deep: bool = True) -> dict:
        """The parameters, as ``__init__`` stored them (the options passed on last)."""
        named, passed_on = self._signature()
        return {**{name: getattr(self, name) for name in named},
                **(getattr(self, passed_on) if passed_on else {})}

    def set_params(self, **params) -> "Estimator":
        """Change parameters; an unknown name is refused before any is changed."""
        named, passed_on = self._signature()
        valid = self._param_names()
        for name in params:
            if name not in valid:
                raise ValueError(f"unknown parameter {name!r} for {type(self).__name__}; "
                                 f"valid: {', '.join(valid)}")
        for name, value in params.items():
            if name in named:
                setattr(self, name, value)
            else:
                getattr(self, passed_on)[name] = value
        return self

    def __repr__(self) -> str:
        named, passed_on = self._signature()
        changed = [f"{k}={getattr(self, k)!r}" for k, default in named.items()
                   if not _same(getattr(self, k), default)]
        changed += [f"{k}={v!r}" for k, v in (getattr(self, passed_on) if passed_on else {}).items()]
        return f"{type(self).__name__}({', '.join(changed)})"

    def _check_fitted(self) -> None:
        """A one-line error when the learner is used before it was fitted (or loaded)."""
        if not hasattr(self, self._fitted):
            how = "fit or load" if hasattr(type(self), "load") else "fit"
            raise ValueError(f"this {type(self).__name__} is not fitted yet: call {how}")


class Registry(dict):
    """A task's learners by the name sweep files and saved models give them: ``name → class``,
    filled by :meth:`register`, the decorator of each learner's class (``name`` its class
    attribute ``field``, e.g. ``kind``); ``task`` names the task in messages.

    Example:
        >>> SCALERS = Registry("scaler", "kind")
        >>> @SCALERS.register
        ... class Doubling(Estimator):
        ...     kind, label = "double", "doubling"
        ...     def __init__(self, factor: float = 2.0):
        ...         self.factor = factor
        >>> SCALERS.make("double", factor=3.0), SCALERS.label("double"), SCALERS.label("halve")
        (Doubling(factor=3.0), 'doubling', 'halve')
        >>> SCALERS.make("halve")
        Traceback (most recent call last):
        ...
        ValueError: kind must be one of double, got 'halve'
    """

    def __init__(self, task: str, field: str):
        super().__init__()
        self.task, self.field = task, field

    def register(self, cls: type) -> type:
        """Register ``cls`` under its ``field`` (a class decorator; a class defined again under
        the same qualified name, as a notebook cell run twice defines it, replaces the first)."""
        name = getattr(cls, self.field, None)
        if not isinstance(name, str) or not name:
            raise ValueError(f"{cls.__name__}: a {self.task} learner needs its {self.field} (a class attribute)")
        old = self.get(name)
        if old is not None and (old.__module__, old.__qualname__) != (cls.__module__, cls.__qualname__):
            raise ValueError(f"{self.task}: {self.field} {name!r} is {old.__name__}'s, not {cls.__name__}'s")
        self[name] = cls
        return cls

    def of(self, name: Any) -> type:
        """The class registered as ``name``; a one-line ``ValueError`` naming the valid ones."""
        if not isinstance(name, str) or name not in self:
            raise ValueError(f"{self.field} must be one of {', '.join(self)}, got {show(name)}")
        return self[name]

    def make(self, name: Any, **params) -> Estimator:
        """A learner of class ``name`` with ``params`` (an unknown one refused in one line)."""
        return self.of(name)().set_params(**params)

    def label(self, name: str) -> str:
        """``name``'s words for tables and figures (its class's ``label``), or ``name`` itself."""
        return getattr(self.get(name), "label", None) or name


def _same(value: Any, default: Any) -> bool:
    """Whether a parameter still has its default (arrays and other values that do not compare
    to one bool count as changed)."""
    try:
        return bool(value == default) and type(value) is type(default)
    except (TypeError, ValueError):
        return False


def write_model(directory: str | os.PathLike, file_name: str, data: dict) -> Path:
    """Write a model's :meth:`to_dict` ``data`` as ``directory/file_name`` (JSON with its content
    hash, :func:`nfarm.infra.reading.with_content_digest`; atomically, the directory made if
    missing) and return the file's path. Floats are written with full precision, so the model
    read back predicts bit for bit what it did.

    Raises:
        ValueError: ``directory`` names a JSON file (``….json``): a model is saved into a
            directory, as ``file_name``.
    """
    directory = Path(directory)
    if directory.suffix.lower() == ".json":
        raise ValueError(f"save takes a directory (the model is written into it as {file_name}), "
                         f"got the file name {str(directory)!r}")
    path = directory / file_name
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(with_content_digest(data)), encoding="utf-8")
    return path


def model_file(path: str | os.PathLike, file_name: str) -> Path:
    """The saved model at ``path``: ``path/file_name`` when ``path`` is a directory (what
    :func:`write_model` was given), else ``path`` itself (the file)."""
    path = Path(path)
    return path / file_name if path.is_dir() else path


def checked_file(data: Any, source: str, form: str, what: str) -> dict:
    """A saved model's content once it is an nfarm ``what`` model of format ``form`` whose
    content hash matches (:func:`nfarm.infra.reading.checked_content`): an edited file is refused
    whatever the edit, before any field is read."""
    v = Validator(source)
    if not isinstance(data, dict):
        v.fail("", f"must be a JSON object (an nfarm {what} model), got {show(data)}")
    if data.get("format") != form:
        v.fail("format", f"must be {form!r} (an nfarm {what} model), got {show(data.get('format'))}")
    return checked_content(data, source)


def check_robot(v: Validator, data: Any, robot: Robot) -> None:
    """Refuse (through ``v``, naming ``robot_params_sha256``) a saved model's ``data`` trained for
    a robot with other parameters than ``robot``."""
    if data["robot_params_sha256"] != robot_hash(robot):
        v.fail("robot_params_sha256", f"trained for robot {show(data['robot'])} with other parameters than "
                                      f"{robot.name!r} ({robot.source}): retrain it for this robot")


class SavedModel(Estimator):
    """A learner of a robot saved as one JSON file of a fixed name: ``file_name``, of format
    ``file_format``, a ``what`` model (in messages). Subclasses supply ``to_dict`` and
    ``from_dict(data, robot, source)``."""

    file_name: ClassVar[str]
    file_format: ClassVar[str]
    what: ClassVar[str]

    def save(self, directory: str | os.PathLike) -> Path:
        """Write the model as ``directory/<file_name>`` (JSON, atomically) and return the file's
        path; :meth:`load` of the directory reproduces the predictions bit for bit."""
        return write_model(directory, self.file_name, self.to_dict())

    @classmethod
    def load(cls, directory: str | os.PathLike, robot: Robot):
        """Read a model saved by :meth:`save` for ``robot`` from the directory it was saved
        into (or from the file itself).

        Raises:
            ParamsError: a missing, damaged or edited file (named, with the field), or a model
                trained for another robot.
        """
        path = model_file(directory, cls.file_name)
        data = checked_file(load_json(path, what=f"{cls.what} model"), str(path), cls.file_format, cls.what)
        return cls.from_dict(data, robot, str(path))
