"""A cache of fitted learned models (:class:`~nfarm.learning.learned.LearnedIK`,
:class:`~nfarm.learning.learned_id.LearnedID`, their rivals :class:`~nfarm.learning.ik_rivals.RivalIK`
and :class:`~nfarm.learning.baselines.BaselineID`): a model is fitted once for its options, data,
robot, code and numerical environment, and loaded while they are unchanged.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..infra.paths import atomic_path
from ..infra.provenance import code_digest
from ..infra.reading import json_ready
from ..model.robot import Robot, robot_hash
from .baselines import FILE_NAME as BASELINE_FILE_NAME, FORMAT as BASELINE_FORMAT, BaselineID
from .ik_rivals import FILE_NAME as RIVAL_FILE_NAME, FORMAT as RIVAL_FORMAT, RivalIK
from .learned import FILE_NAME, FORMAT, LearnedIK, ik_pairs
from .learned_id import ID_FILE_NAME, ID_FORMAT, LearnedID, id_states
from .per_joint import n_parameters

__all__ = ["fit_cached", "fingerprint", "n_parameters", "NUMERICS_ENV"]


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
    """Fit ``model`` (a :class:`LearnedIK`, :class:`LearnedID`,
    :class:`~nfarm.learning.ik_rivals.RivalIK` or :class:`~nfarm.learning.baselines.BaselineID`), or load the one saved in
    ``directory`` if it was fitted with the same options on the same data for the same robot
    by the same code.

    The inputs' hash (the model's class and options, the data's :func:`fingerprint`, the
    robot's hash, the model format, the content of this module and of every package module it
    imports (the learned IK's and ID's among them) (:func:`nfarm.infra.provenance.code_digest`) and the numerical environment of
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
        cls, name, form = LearnedIK, FILE_NAME, FORMAT
        arrays = lambda data, what: ik_pairs(data, robot, what)          # noqa: E731
    elif isinstance(model, RivalIK):            # any rival (nfarm.learning.ik_rivals): loaded by its kind
        cls, name, form = RivalIK, RIVAL_FILE_NAME, RIVAL_FORMAT
        arrays = lambda data, what: ik_pairs(data, robot, what)          # noqa: E731
    elif isinstance(model, (LearnedID, BaselineID)):
        cls, name, form = (LearnedID, ID_FILE_NAME, ID_FORMAT) if isinstance(model, LearnedID) else \
            (BaselineID, BASELINE_FILE_NAME, BASELINE_FORMAT)
        arrays = lambda data, what: id_states(data, robot, what)         # noqa: E731
    else:
        raise TypeError(f"model must be a LearnedIK, a LearnedID, a RivalIK or a BaselineID, got {type(model).__name__}")
    parts = [type(model).__name__, json.dumps(json_ready(model.get_params()), sort_keys=True),
             fingerprint(*arrays(train, "train")), robot_hash(robot), form, code_digest("learning.model_cache"),
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
