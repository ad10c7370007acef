"""The plumbing every learner of this package shares, written once (as scikit-learn's
``BaseEstimator``): the parameters are those of ``__init__``'s signature, which stores them
unchanged; ``get_params`` and ``set_params`` read and change them (an unknown name is refused in
one line naming the valid ones); ``repr`` shows those that differ from their defaults; and a
learner used before it was fitted says so in one line.

**Saving.** A learner that can be saved (:class:`nfarm.learning.anfis.ANFIS`, ``ANFISMulti``,
:class:`nfarm.learning.learned.LearnedIK`, ``LearnedID``) takes a *directory* and writes one JSON
file of a fixed name in it (:func:`write_model`), so that a model's directory can hold what
belongs with it (``fit_cached``'s ``inputs.sha256``); loading takes that directory or the file
itself (:func:`model_file`).

A learner whose ``__init__`` takes ``**options`` passes them on to the learners it builds (an
:class:`nfarm.learning.anfis.ANFIS` per joint): they are parameters too, kept in the attribute
named like that argument and checked against the learner they go to (:attr:`Estimator._passed_to`).
"""

from __future__ import annotations

import inspect
import json
import os
from pathlib import Path
from typing import Any, ClassVar

from ..infra.paths import atomic_path
from ..infra.reading import with_content_digest

__all__ = ["Estimator", "write_model", "model_file"]


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
