"""Library jobs a parameter sweep runs (:mod:`nfarm.study.sweep`): each takes one cell's parameters
and returns its metrics, a flat mapping of numbers, strings or lists of numbers.

* ``anfis_benchmark`` — one ANFIS on one of Jang's benchmarks (chapter 4): ``sinc`` (121
  training pairs; checked on a 41 × 41 grid of the same square), ``three_input`` (216 / 125) or
  ``mackey_glass`` (500 / 500). Seconds per fit: what a smoke grid needs.
* ``learned_ik`` — a study's learned inverse kinematics (chapter 6): one ANFIS per joint on the
  first ``fraction`` (at most ``samples``) of the study's training poses (``poses: region``, or
  ``full_range``: its poses over the whole joint ranges), judged by each joint's validation RMSE
  at its best epoch.
* ``learned_id`` — a study's learned inverse dynamics (chapter 6): every ``stride``-th training
  state, each joint's validation NRMSE (RMSE over the standard deviation of its torque). With
  ``seed_like: {duration_s, dt_s, seed}`` it trains instead on as many states on trajectories
  made the dissertation's program's way (:func:`nfarm.study.id_trajectories.seed_like_trajectories`, drawn from that
  seed and the cell's), validated on the study's own validation trajectories.
* ``id_baseline`` — a model-free scikit-learn baseline of a study's inverse dynamics
  (:class:`nfarm.learning.baselines.BaselineID`, chapters 06 and 07): fitted on every ``stride``-th
  training state, judged on the ``split`` (``val`` to choose, ``test`` once for the chosen),
  each joint's NRMSE, the fit's seconds and the prediction's microseconds per state.
* ``ik_contest`` — one contestant of the learned-IK contest (chapter 6): a ``learner``
  (``"anfis"``: :class:`nfarm.learning.learned.LearnedIK` with ``options`` as its keyword
  arguments; or a rival of :data:`nfarm.learning.ik_rivals.RIVALS` with its ``options``)
  trained on all of the study's training poses (or the first ``fraction``), judged **at the
  tool** on the ``split`` (``val`` to choose, ``test`` once for the frozen chosen models): the
  median and 95th percentile of the position error [mm] and of the orientation error [deg],
  each joint's RMSE [deg], the training's seconds and the epochs it ran.
* ``idle`` — sleeps ``seconds`` and returns its parameters: the sweep machinery's own cost
  (``benchmarks/bench_sweep.py``).

A job declares every parameter with its default (:data:`REQUIRED`: none), so a sweep file that
names an unknown parameter is refused before anything runs, and a cell's identity is taken over
its complete parameters: a value left to its default and the same value written out are the
same cell. Path parameters are stored relative to the repository root, so the cells of
``params/studies/x.yaml`` and of its absolute path are one.

A study job's ``seed`` is the **data draw and the initialisation**: seed 0 trains on the
study's own data sets, seed ``k`` on its training and validation data drawn again with the
study's seed plus ``k`` (:func:`nfarm.study.study_files.redrawn`), and seeds the learner; a test split is
always the study's own. A sweep's ``seeds: [0, 1, 2, 3, 4]`` thus gives each configuration's
spread over data and initialisation (:func:`nfarm.study.sweep.by_configuration`). For a measured arm
the draw is also **the arm as built** (:func:`nfarm.study.datasets.built_arm`): seed ``k``'s data are
the readings of the ``k``-th arm built to the study's tolerances, and its test cells judge it on the
same test trajectories as that arm reads them.

The learned jobs reuse data sets and models (:func:`nfarm.study.datasets.build_datasets`,
:func:`nfarm.learning.model_cache.fit_cached`, models under ``<models_dir>/ik/sweep/<options hash>/``): a
cell run again after a change to the code retrains nothing whose inputs are unchanged.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import math
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import datasets, id_trajectories, study_files

from ..infra.arguments import is_integer, is_number
from ..infra.paths import BUILD, project_path, shown_path
from ..infra.reading import ParamsError, Validator, show
from ..infra.typed import COUNT, EPOCHS, ITERATIONS, N_MFS, N_RULES, Range
from ..learning import jang
from ..learning.anfis import ANFIS
from ..learning.baselines import BASELINES, baseline_id, option_names
from ..learning.bases import tier_of
from ..learning.ik_rivals import RIVALS, rival_ik
from ..learning.learned import LearnedIK, ik_errors
from ..learning.learned_id import LearnedID
from ..learning.model_cache import fit_cached, n_parameters
from ..learning.priors import check_residual
from ..model.dynamics import rnea
from .statistics import resolved_joints, trajectory_maxima, trajectory_sums

__all__ = ["Job", "JOBS", "REQUIRED", "id_model", "ik_model", "contest_model", "id_training_data"]

REQUIRED = object()
"""Default of a parameter every cell must give."""

#: Thread counts a cell runs with, whatever the machine's defaults (:mod:`nfarm.study.sweep`).
CELL_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


@contextlib.contextmanager
def cell_threads():
    """One BLAS/OpenMP thread, and the environment saying so (model caches key on it:
    :func:`nfarm.learning.model_cache.fit_cached`), restored afterwards: how a sweep cell runs, and how a
    chapter reads a cell's model (:func:`ik_model`, :func:`id_model`). A chapter's kernel with
    the machine's thread count would otherwise not match the cell's cache key and train the
    model again, serially, in the kernel."""
    from threadpoolctl import threadpool_limits

    saved = {k: os.environ.get(k) for k in CELL_ENV}
    os.environ.update(CELL_ENV)
    try:
        with threadpool_limits(1):
            yield
    finally:
        for k, value in saved.items():
            if value is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = value


@dataclass(frozen=True)
class Job:
    """A named library function of one cell's parameters; ``params`` maps every parameter to
    its default, ``metrics`` names what the function returns, ``paths`` the parameters that are
    file or directory paths (stored relative to the repository root)."""

    function: Callable[[dict], dict]
    params: Mapping[str, Any]
    metrics: tuple[str, ...]
    paths: tuple[str, ...] = ()
    doc: str = field(default="", compare=False)
    #: Work the cells share, done once per distinct value of ``shared`` before they run
    #: (their data sets: workers would otherwise build the same files side by side).
    prepare: Callable[[dict], None] | None = None
    shared: tuple[str, ...] = ()

    def complete(self, given: Mapping[str, Any]) -> dict:
        """``given`` with every default filled in, each value of the kind of its default and
        in one normal form, paths made project-relative: equal parameters make equal cells
        (``2`` and ``2.0``, one file by two paths).

        The kinds: a parameter whose default is a boolean takes ``true`` or ``false`` only (a
        text such as ``"no"`` is refused, not read as true); a whole-number default takes whole
        numbers (``2.0`` becomes 2); a number default takes numbers (as floats); a text default
        and a path take texts. A parameter without a default kind (``None``) takes any value,
        its whole floats, at any depth, made integers.

        Raises:
            KeyError: the names of missing required parameters.
            ParamsError: ``"<name>: <rule>"`` for the first value of the wrong kind.
        """
        params = {k: given.get(k, default) for k, default in self.params.items()}
        missing = [k for k, v in params.items() if v is REQUIRED]
        if missing:
            raise KeyError(", ".join(missing))
        for key, default in self.params.items():
            params[key] = _of_kind(key, params[key], default, key in self.paths)
        for key in self.paths:
            if isinstance(params[key], str):
                params[key] = shown_path(project_path(params[key]))
        _bounded(params)
        return params


#: The plausibility bounds of the counts a cell's parameters give, by parameter name, wherever
#: they stand (a job's own parameter, a joint's options, a learner's ``options``): one
#: declaration per quantity (:mod:`nfarm.infra.typed`), so that ``epochs: -1``, ``10^12`` epochs
#: or ``n_mfs: 10^6`` are refused when the sweep file is read, not hours into a cell.
#: Counts below 1 of a rule base (``n_mfs``, ``n_rules``) are the learner's to refuse, in its cell: a
#: sweep may hold a cell that fails on purpose; the upper bounds are the sweep file's.
PARAMETER_BOUNDS: dict[str, Range] = {"epochs": EPOCHS, "patience": EPOCHS,
                                      "n_mfs": dataclasses.replace(N_MFS, lo=None),
                                      "n_rules": N_RULES, "max_iter": ITERATIONS, "n_estimators": ITERATIONS,
                                      "stride": COUNT, "n_components": COUNT, "samples": COUNT}


class _Named(Validator):
    """Failures as ``"<name>: <rule>"`` (:meth:`Job.complete`'s contract)."""

    def __init__(self):
        super().__init__("")

    def fail(self, field: str, rule: str):
        raise ParamsError(f"{field}: {rule}")


def _bounded(params: Mapping[str, Any]) -> None:
    """Every bounded count (:data:`PARAMETER_BOUNDS`) in ``params``, at any depth, within its
    bound: ``None`` (a default) passes, a number or each number of a list is checked; else a
    ``ParamsError`` ``"<name>: <rule>"`` (``joint_options[1].epochs: ...`` for a nested one)."""
    v = _Named()
    stack: list[tuple[str, Any]] = [(k, x) for k, x in params.items()]
    while stack:
        at, value = stack.pop()
        key = at.rsplit(".", 1)[-1]
        if "[" not in key and key in PARAMETER_BOUNDS and value is not None:
            items = value if isinstance(value, list) else [value]
            for k, x in enumerate(items):
                PARAMETER_BOUNDS[key].check(v, x, at if not isinstance(value, list) else f"{at}[{k}]",
                                            integer=True)
        elif isinstance(value, Mapping):
            stack.extend((f"{at}.{k}", x) for k, x in value.items())
        elif isinstance(value, list):
            stack.extend((f"{at}[{k}]", x) for k, x in enumerate(value))


def _whole(value: Any) -> Any:
    """``value`` with every float that is a whole number (within ±2⁵³) made an int."""
    if isinstance(value, float) and value.is_integer() and abs(value) <= 2 ** 53:
        return int(value)
    if isinstance(value, list):
        return [_whole(x) for x in value]
    if isinstance(value, dict):
        return {k: _whole(x) for k, x in value.items()}
    return value


def _of_kind(name: str, value: Any, default: Any, path: bool) -> Any:
    """A job parameter's value in its default's kind and normal form (:meth:`Job.complete`)."""
    def refuse(kind: str) -> None:
        raise ParamsError(f"{name}: must be {kind}, got {show(value)}")

    if path or default is REQUIRED:
        if value is not None and not isinstance(value, str):
            refuse("a path (text)")
        return value
    if value is None or default is None:
        return _whole(value)
    if isinstance(default, bool):
        if not isinstance(value, bool):
            refuse("true or false")
        return value
    if isinstance(default, int):
        if not is_number(value, numpy=False) \
                or isinstance(value, float) and not (value.is_integer() and abs(value) <= 2 ** 53):
            refuse("a whole number")
        return int(value)
    if isinstance(default, float):
        if not is_number(value, numpy=False):
            refuse("a number")
        return float(value)
    if isinstance(default, str) and not isinstance(value, str):
        refuse("a text")
    return value


# --------------------------------------------------------------------------------------------
# Jang's benchmarks


def _benchmark_data(problem: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    if problem == "sinc":
        X, y = jang.sinc_data()
        X_check, y_check = jang.sinc_data(points=41)
        return X, y, X_check, y_check
    if problem == "three_input":
        return jang.three_input_data()
    if problem == "mackey_glass":
        return jang.mackey_glass_data()
    raise ValueError(f"problem must be one of sinc, three_input, mackey_glass, got {problem!r}")


def anfis_benchmark(p: dict) -> dict:
    X, y, X_check, y_check = _benchmark_data(p["problem"])
    options = {k: p[k] for k in ("n_mfs", "mf", "partition", "n_rules", "radius", "epochs",
                                 "step_size")}
    model = ANFIS(**options, random_state=p["seed"]).fit(X, y)
    return {"train_rmse": float(model.loss_curve_[-1]),
            "check_rmse": jang.rmse(y_check, model.predict(X_check)),
            "rules": int(model.rules_.shape[0])}


# --------------------------------------------------------------------------------------------
# Learned IK and ID on a study's data


def _own_study(p: dict) -> study_files.Study:
    """The cell's study (its smoke version with ``smoke``) as its file draws it."""
    study = study_files.load_study(p["study_file"])
    return study_files.smoke_study(study) if p["smoke"] else study


def _study(p: dict) -> study_files.Study:
    """The study whose training and validation data the cell's ``seed`` draws
    (:func:`nfarm.study.study_files.redrawn`: seed 0 is the study's own)."""
    return study_files.redrawn(_own_study(p), p["seed"])


def _build_data(p: dict) -> None:
    datasets.build_datasets(_study(p), p["data_dir"])
    if p.get("split") == "test" and p["seed"]:
        datasets.build_datasets(_own_study(p), p["data_dir"])


def _study_data(p: dict) -> tuple[study_files.Study, Path, Path]:
    """The cell's study, its data sets (built or reused) and its models directory (the same
    for every draw: a model's directory name holds its seed)."""
    study = _study(p)
    datasets.build_datasets(study, p["data_dir"])
    directory = datasets.dataset_dir(study, p["data_dir"])
    own = datasets.dataset_dir(_own_study(p), p["data_dir"])
    models = project_path(p["models_dir"]) if p["models_dir"] else BUILD / "models" / own.name
    return study, directory, models


def _test_split(p: dict, split_of) -> dict:
    """The study's own held-out split, the same for every draw; with measured torques
    (``p["torques"]``) those that the arm built for the cell's draw (its ``seed``) reads on its
    states (:func:`nfarm.study.datasets.held_out_readings`), so that a draw's models are judged against
    the arm they were trained on."""
    own = _own_study(p)
    datasets.build_datasets(own, p["data_dir"])
    directory = datasets.dataset_dir(own, p["data_dir"])
    judged = split_of(p, own, directory, "test")
    if p.get("torques") == "measured" and p["seed"]:
        readings = datasets.held_out_readings(own, p["seed"], datasets.load(directory / "id_test.npz", own.robot, own))
        judged["tau"] = readings["tau_measured"]
        if "tau_payload" in judged:
            judged["tau_payload"] = readings["tau_payload"]
    return judged


def _options_dir(models: Path, kind: str, options: Mapping) -> Path:
    digest = hashlib.sha256(json.dumps(options, sort_keys=True).encode()).hexdigest()[:16]
    return models / kind / "sweep" / digest


def _first(data: Mapping, keys: tuple[str, ...], fraction: float, samples: int | None,
           stride: int = 1) -> dict:
    n = len(data[keys[0]])
    count = max(1, int(round(fraction * n)))
    if samples is not None:
        count = min(count, samples)
    return {k: data[k][:count][::stride] for k in keys}


_ANFIS_KEYS = ("partition", "n_mfs", "n_rules", "radius", "mf", "epochs", "joint_options", "patience")


_POSES = {"region": "ik", "full_range": "ik_full"}


def study_sized(study: study_files.Study, options: Mapping) -> dict:
    """Chapter 06's chosen learned-IK ``options`` (LearnedIK keyword arguments) with the study
    file's ``learned_ik`` applied: ``n_mfs`` replaces the grid's functions per input;
    ``epochs``, one number or one per joint, the epochs (per joint through ``joint_options``,
    keeping each joint's other options).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.study.study_files import load_study
        >>> study = load_study(PARAMS / "studies" / "intelbot5.yaml")
        >>> import dataclasses
        >>> sized = dataclasses.replace(study, learned_ik={"n_mfs": [1, 4, 4, 4, 4, 1], "epochs": [5, 6, 7, 8, 9]})
        >>> chosen = study_sized(sized, {"n_mfs": 3, "joint_options": [{"n_mfs": 1}, {}, {}, {}, {}]})
        >>> chosen["n_mfs"], chosen["joint_options"][:2]          # the file's sizes win, per joint
        ([1, 4, 4, 4, 4, 1], [{'n_mfs': 1, 'epochs': 5}, {'epochs': 6}])
    """
    chosen = dict(options)
    if "n_mfs" in study.learned_ik:
        chosen["n_mfs"] = study.learned_ik["n_mfs"]
    epochs = study.learned_ik.get("epochs")
    if isinstance(epochs, int):
        chosen["epochs"] = epochs
    elif epochs is not None:
        joint = chosen.get("joint_options") or [{}] * len(epochs)
        chosen["joint_options"] = [{**o, "epochs": e} for o, e in zip(joint, epochs)]
    return chosen


def _fit_ik(p: dict) -> tuple[LearnedIK, int]:
    """A ``learned_ik`` cell's model, trained or reused (:func:`fit_cached`), and the number of
    training samples it saw."""
    if p["poses"] not in _POSES:
        raise ParamsError(f"poses must be one of {', '.join(_POSES)}, got {p['poses']!r}")
    study, directory, models = _study_data(p)
    if p["poses"] == "full_range" and not study.ik_full_range:
        raise ParamsError(f"{p['study_file']}: poses: full_range, but the study declares no poses over "
                          f"the full joint ranges (ik.full_range)")
    robot = study.robot
    kind = _POSES[p["poses"]]
    train = datasets.load(directory / f"{kind}_train.npz", robot, study)
    val = datasets.load(directory / f"{kind}_val.npz", robot, study)
    options = {k: p[k] for k in ("encoding", *_ANFIS_KEYS) if p[k] is not None}
    if p["study_sizes"]:
        options = study_sized(study, options)
    if options["encoding"] == "arm_plane" and p["max_out_of_plane_deg"] is not None:
        options["max_out_of_plane"] = math.radians(p["max_out_of_plane_deg"])
    subset = _first(train, ("T", "q"), p["fraction"], p["samples"])
    model = LearnedIK(**options, random_state=p["seed"])
    where = _options_dir(models, "ik", {**model.get_params(), "fraction": p["fraction"],
                                        "samples": p["samples"], "poses": p["poses"]})
    return fit_cached(model, robot, subset, val, where)[0], len(subset["q"])


def learned_ik(p: dict) -> dict:
    model, n_train = _fit_ik(p)
    rmse = np.degrees([m.val_loss_curve_[m.best_epoch_] for m in model.models_])
    return {"val_rmse_deg": rmse.tolist(), "worst_deg": float(rmse.max()),
            "rules": [int(m.rules_.shape[0]) for m in model.models_],
            "parameters": n_parameters(model), "train_samples": n_train}


def ik_model(params: Mapping[str, Any]) -> LearnedIK:
    """The model a ``learned_ik`` cell trains (``params``: the cell's parameters), reused from
    where the cell keeps it (trained now if it is not there or was made by other code): a
    chapter takes a sweep cell's model as its chosen one instead of training another."""
    with cell_threads():
        return _fit_ik(JOBS["learned_ik"].complete(params))[0]


def _fit_contestant(p: dict):
    """An ``ik_contest`` cell's model, trained or reused (:func:`fit_cached`), its study, its
    validation poses and the number of training poses it saw."""
    study, directory, models = _study_data(p)
    robot = study.robot
    train = _first(datasets.load(directory / "ik_train.npz", robot, study), ("T", "q"), p["fraction"], None)
    val = datasets.load(directory / "ik_val.npz", robot, study)
    options = dict(p["options"] or {})
    plane = {} if p["max_out_of_plane_deg"] is None else {"max_out_of_plane": math.radians(p["max_out_of_plane_deg"])}
    try:
        if p["learner"] == "anfis":
            if {"encoding", "random_state", "max_out_of_plane"} & set(options):
                raise ValueError("options: encoding, max_out_of_plane and random_state are the cell's own "
                                 "parameters (encoding, max_out_of_plane_deg, seed)")
            model = LearnedIK(p["encoding"], **plane, **options, random_state=p["seed"])
            model._options(robot.n)
        elif p["learner"] in RIVALS:
            structure = options.pop("structure", "whole")     # the rival's structure (nfarm.learning.ik_rivals)
            model = rival_ik(p["learner"], p["encoding"], options, **plane, random_state=p["seed"], structure=structure)
        else:
            raise ValueError(f"learner must be anfis or one of {', '.join(RIVALS)}, got {p['learner']!r}")
    except (ValueError, TypeError) as exc:
        raise ParamsError(f"ik_contest: {exc}") from None
    where = _options_dir(models, "ik_contest", {"class": type(model).__name__, **json.loads(
        json.dumps(model.get_params(), default=str)), "fraction": p["fraction"]})
    return fit_cached(model, robot, train, val, where)[0], study, val, len(train["q"])


def ik_contest(p: dict) -> dict:
    if p["split"] not in ("val", "test"):
        raise ParamsError(f"split must be 'val' or 'test', got {p['split']!r}")
    model, study, judged, n_train = _fit_contestant(p)
    robot = study.robot
    if p["split"] == "test":
        judged = _test_split(p, lambda p_, s, d, split: datasets.load(d / f"ik_{split}.npz", s.robot, s))
    start = time.perf_counter()
    q = model.predict(judged["T"])
    seconds = time.perf_counter() - start
    e = ik_errors(robot, q, judged["q"], judged["T"])
    position, orientation = 1e3 * e["position"], np.degrees(e["orientation"])
    if isinstance(model, LearnedIK):
        fit_seconds = float(sum(model.fit_seconds_))
        epochs = [len(m.loss_curve_) for m in model.models_]
        best = [int(m.best_epoch_) for m in model.models_]
    else:
        fit_seconds, epochs, best = float(model.fit_seconds_), [model.epochs_], [model.best_epoch_]
    return {"position_p50_mm": float(np.median(position)), "position_p95_mm": float(np.percentile(position, 95)),
            "orientation_p50_deg": float(np.median(orientation)),
            "orientation_p95_deg": float(np.percentile(orientation, 95)),
            "joint_rmse_deg": np.degrees(np.sqrt((e["joint"] ** 2).mean(axis=0))).tolist(),
            "fit_seconds": fit_seconds, "predict_us": 1e6 * seconds / len(q), "epochs": epochs,
            "best_epoch": best, "train_samples": n_train}


def contest_model(params: Mapping[str, Any]):
    """The model an ``ik_contest`` cell trains (``params``: the cell's parameters), reused from
    where the cell keeps it: a :class:`LearnedIK` or a :class:`RivalIK`, each loadable on its
    own (``LearnedIK.load(directory, robot)``, ``RivalIK.load(directory, robot)``)."""
    with cell_threads():
        return _fit_contestant(JOBS["ik_contest"].complete(params))[0]


def _fit_id(p: dict) -> tuple[LearnedID, dict]:
    """A ``learned_id`` cell's model, trained or reused (:func:`fit_cached`), and its data."""
    study, directory, models = _study_data(p)
    data = _id_data(p, study, directory)
    model, where = _id_model(p, models)
    model, _ = fit_cached(model, study.robot, data["train"], data["val"], where)
    return model, data


def _id_data(p: dict, study, directory: Path) -> dict:
    """A ``learned_id`` cell's training states (its share, every ``stride``-th; or as many made
    the seed's way) and validation states."""
    states = ("q", "qd", "qdd")
    data = {split: _id_split(p, study, directory, split) for split in ("train", "val")}
    data["train"] = _first(data["train"], (*states, "tau"), p["fraction"], None, p["stride"])
    if p["seed_like"] is not None:
        data["train"] = _seed_like_split(p, study, len(data["train"]["q"]))
    return data


def id_training_data(params: Mapping[str, Any]) -> dict:
    """The training states ``q, qd, qdd, tau`` a ``learned_id`` cell trains on (``params``: the
    cell's parameters): a chapter shows what a cell's model saw."""
    p = JOBS["learned_id"].complete(params)
    study, directory, _ = _study_data(p)
    return _id_data(p, study, directory)["train"]


def learned_id(p: dict) -> dict:
    model, data = _fit_id(p)
    rmse = np.array([m.val_loss_curve_[m.best_epoch_] for m in model.models_])
    nrmse = rmse / data["val"]["tau"].std(axis=0)
    return {"val_rmse": rmse.tolist(), "val_nrmse": nrmse.tolist(), "worst_nrmse": float(nrmse.max()),
            "rules": [int(m.rules_.shape[0]) for m in model.models_],
            "parameters": n_parameters(model), "train_samples": int(len(data["train"]["q"]))}


_SEED_LIKE = ("duration_s", "dt_s", "seed")


def _seed_like_split(p: dict, study, states: int) -> dict:
    """``states`` training states on trajectories made the dissertation's program's way (cubics
    from rest to rest, sampled every ``dt_s``), with their rigid-body torques; drawn from
    ``seed_like["seed"]`` and the cell's seed. The states, not the trajectories, are matched to
    the study's (its training set at the cell's fraction and stride): with as many trajectories
    as the study's, 31 coarse states each, the 8-rule affine model had fewer than twice as many
    states as parameters and its least squares fell back to the orthogonal solver (195 s against
    about 50 s), which measured the count of states, not the kind of trajectory."""
    given = p["seed_like"]
    if not isinstance(given, Mapping) or set(given) != set(_SEED_LIKE):
        raise ParamsError(f"seed_like must be null or a mapping of {', '.join(_SEED_LIKE)}, got {given!r}")
    duration, dt, seed = (given[k] for k in _SEED_LIKE)
    if not all(is_number(x, numpy=False) and math.isfinite(x) for x in (duration, dt)) \
            or not 0 < dt <= duration <= 600 or duration / dt > 10_000:
        raise ParamsError(f"seed_like: duration_s and dt_s must be numbers with 0 < dt_s <= duration_s <= 600 "
                          f"and at most 10 000 samples per trajectory, got {duration!r} and {dt!r}")
    if not (is_integer(seed, numpy=False) and 0 <= seed < 2**32):
        raise ParamsError(f"seed_like: seed must be an integer in [0, 2^32), got {seed!r}")
    if p["torques"] != "rigid":
        raise ParamsError("seed_like: trajectories made the seed's way have rigid-body torques only "
                          "(torques: rigid)")
    per = int(round(duration / dt)) + 1
    made = id_trajectories.seed_like_trajectories(study.robot, study.id, -(-states // per), [seed, p["seed"]],
                                           duration=duration, dt=dt)
    made = {k: made[k][:states] for k in ("q", "qd", "qdd", "trajectory")}
    made["tau"] = rnea(study.robot, made["q"], made["qd"], made["qdd"])
    return made


def _id_model(p: dict, models: Path) -> tuple[LearnedID, Path]:
    """A ``learned_id`` cell's unfitted model and the directory its fitted one is kept in."""
    options = {k: p[k] for k in ("inputs", "residual", "shared_premises", *_ANFIS_KEYS) if p[k] is not None}
    model = LearnedID(**options, random_state=p["seed"])
    return model, _options_dir(models, "id", {**model.get_params(), "fraction": p["fraction"],
                                               "stride": p["stride"], "torques": p["torques"],
                                               "seed_like": p["seed_like"]})


def id_model(params: Mapping[str, Any]) -> LearnedID:
    """The model a ``learned_id`` cell trains (``params``: the cell's parameters), reused from
    where the cell keeps it (trained now if it is not there or was made by other code): a
    chapter takes a sweep cell's model as its chosen one instead of training another."""
    with cell_threads():
        return _fit_id(JOBS["learned_id"].complete(params))[0]


def _id_split(p: dict, study, directory: Path, split: str) -> dict:
    """One split of a study's ID data: the rigid-body torques on the exact states, or the
    measured torques on the states the measured arm knows (its encoder's, when it has one)."""
    if p["torques"] not in ("rigid", "measured"):
        raise ParamsError(f"torques must be 'rigid' or 'measured', got {p['torques']!r}")
    loaded = datasets.load(directory / f"id_{split}.npz", study.robot, study)
    if p["torques"] == "rigid":
        return {**{k: loaded[k] for k in ("q", "qd", "qdd", "trajectory")}, "tau": loaded["tau"]}
    if "tau_measured" not in loaded:
        raise ParamsError(f"{p['study_file']}: torques: the study has no measured torques (id.measured)")
    out = {**{k: loaded.get(f"{k}_measured", loaded[k]) for k in ("q", "qd", "qdd")},
           "trajectory": loaded["trajectory"], "tau": loaded["tau_measured"]}
    if "tau_payload" in loaded:             # the test split's payload case (chapter 7)
        out["tau_payload"] = loaded["tau_payload"]
    return out


def _fit_baseline(p: dict):
    """An ``id_baseline`` cell's model, trained or reused (:func:`fit_cached`), with its training
    and validation splits."""
    study, directory, models = _study_data(p)
    robot = study.robot
    train = _first(_id_split(p, study, directory, "train"), ("q", "qd", "qdd", "tau"), p["fraction"],
                   None, p["stride"])
    val = _id_split(p, study, directory, "val")
    learner = p["learner"]
    if learner not in BASELINES:
        raise ParamsError(f"learner must be one of {', '.join(BASELINES)}, got {learner!r}")
    options = {k: p[k] for k in BASELINES[learner].hyper_params() if p[k] is not None}
    # The validation trajectories stop the MLP early, as they stop the ANFIS (the other learners ignore them).
    # Trained once for its options and data (fit_cached): chapter 7's test cell reads the model its validation cell made.
    model = baseline_id(learner, options, residual=p["residual"], random_state=p["seed"])
    where = _options_dir(models, "id_baselines", {"class": type(model).__name__,
                                                  **json.loads(json.dumps(model.get_params(), default=str)),
                                                  "torques": p["torques"], "fraction": p["fraction"], "stride": p["stride"]})
    return fit_cached(model, robot, train, val, where)[0], train, val


def id_baseline_model(params: Mapping[str, Any]):
    """The model an ``id_baseline`` cell trains (``params``: the cell's parameters), reused from
    where the cell keeps it: a :class:`BaselineID`."""
    with cell_threads():
        return _fit_baseline(JOBS["id_baseline"].complete(params))[0]


def id_baseline(p: dict) -> dict:
    if p["split"] not in ("val", "test"):
        raise ParamsError(f"split must be 'val' or 'test', got {p['split']!r}")
    model, train, val = _fit_baseline(p)
    judged = val if p["split"] == "val" else _test_split(p, _id_split)
    start = time.perf_counter()
    predicted = model.predict(judged["q"], judged["qd"], judged["qdd"])
    seconds = time.perf_counter() - start
    rmse = np.sqrt(((predicted - judged["tau"]) ** 2).mean(axis=0))
    nrmse = rmse / judged["tau"].std(axis=0)
    sums = trajectory_sums(predicted, judged["tau"], judged["trajectory"])
    maxima = trajectory_maxima(predicted, judged["tau"], judged["trajectory"])
    # The same predictions against the torques of the arm carrying the payload (the test split of a measured arm)
    loaded = judged.get("tau_payload")
    payload_sums = [] if loaded is None else trajectory_sums(predicted, loaded, judged["trajectory"]).ravel().tolist()
    payload_maxima = [] if loaded is None else trajectory_maxima(predicted, loaded, judged["trajectory"]).ravel().tolist()
    return {"rmse": rmse.tolist(), "nrmse": nrmse.tolist(), "worst_nrmse": float(nrmse.max()),
            "fit_seconds": float(model.fit_seconds_), "predict_us": 1e6 * seconds / len(predicted),
            "features": int(model.n_features_), "train_samples": int(len(train["q"])),
            "epochs": _epochs_run(model.epochs_), "trajectory_sums": sums.ravel().tolist(), "trajectory_maxima": maxima.ravel().tolist(),
            "payload_trajectory_sums": payload_sums, "payload_trajectory_maxima": payload_maxima}


def _epochs_run(epochs) -> int:
    """A baseline's epochs (``epochs_``: ``None``, a count, or one a joint's model), summed: 0 for none."""
    return sum(_per_model(epochs))


def _per_model(counts) -> list[int]:
    """A baseline's ``epochs_`` or ``best_epoch_`` as one count a model (one model, or one a joint); 0 for none."""
    return [int(c) for c in counts] if isinstance(counts, list) else [int(counts or 0)]


def _fit_id_contestant(p: dict):
    """An ``id_contest`` cell's model, trained or reused (:func:`fit_cached`): an ANFIS
    (:class:`LearnedID`) or a rival (:class:`BaselineID`) fitted to the measured torques of the
    training trajectories (every ``stride``-th state), the validation trajectories stopping the
    iterative ones early; with its study, the validation split and the training states' count."""
    study, directory, models = _study_data(p)
    robot = study.robot
    if study.id.measured is None:
        raise ParamsError(f"{p['study_file']}: id_contest: the study declares no measured arm (id.measured)")
    measured = {**p, "torques": "measured"}
    train = _first(_id_split(measured, study, directory, "train"), ("q", "qd", "qdd", "tau"), p["fraction"], None,
                   p["stride"])
    val = _id_split(measured, study, directory, "val")
    options = dict(p["options"] or {})
    try:
        if "random_state" in options:
            raise ValueError("options: random_state is the cell's own parameter (seed)")
        if p["learner"] == "anfis":
            model = LearnedID(**options, random_state=p["seed"])     # its options are checked by fit
        elif p["learner"] in BASELINES:
            residual = options.pop("residual", False)
            check_residual(residual, "options: residual")
            model = baseline_id(p["learner"], options, residual=residual, random_state=p["seed"])
            model._options()
        else:
            raise ValueError(f"learner must be anfis or one of {', '.join(BASELINES)}, got {p['learner']!r}")
    except (ValueError, TypeError) as exc:
        raise ParamsError(f"id_contest: {exc}") from None
    where = _options_dir(models, "id_contest", {"class": type(model).__name__, **json.loads(
        json.dumps(model.get_params(), default=str)), "fraction": p["fraction"], "stride": p["stride"]})
    return fit_cached(model, robot, train, val, where)[0], study, val, len(train["q"])


def id_contest(p: dict) -> dict:
    if p["split"] not in ("val", "test"):
        raise ParamsError(f"split must be 'val' or 'test', got {p['split']!r}")
    model, study, val, n_train = _fit_id_contestant(p)
    judged = val if p["split"] == "val" else _test_split({**p, "torques": "measured"}, _id_split)
    start = time.perf_counter()
    predicted = model.predict(judged["q"], judged["qd"], judged["qdd"])
    seconds = time.perf_counter() - start
    rmse = np.sqrt(((predicted - judged["tau"]) ** 2).mean(axis=0))
    nrmse = rmse / judged["tau"].std(axis=0)
    # The worst joint over those a sensor resolves, fixed on the validation trajectories (as chapter 6 fixes it)
    resolved = resolved_joints(val["tau"].std(axis=0), study.id.noise)
    # The tier from the model as fitted (its defaults included), not from the options the cell wrote
    described = {"inputs": model.inputs, "residual": model.residual} if isinstance(model, LearnedID) else \
        {**model.options_, "learner": model.learner, "residual": model.residual}
    out = {"tier": tier_of(described),
           "rmse": rmse.tolist(), "nrmse": nrmse.tolist(), "worst_nrmse": float(nrmse[resolved].max()),
           "worst_rmse": float(rmse.max()), "resolved": resolved.astype(int).tolist(), "train_samples": int(n_train),
           "predict_us": 1e6 * seconds / len(predicted)}
    if isinstance(model, LearnedID):
        out |= {"fit_seconds": float(sum(model.fit_seconds_)), "epochs": [len(m.loss_curve_) for m in model.models_],
                "best_epoch": [int(m.best_epoch_) for m in model.models_]}
    else:
        out |= {"fit_seconds": float(model.fit_seconds_), "epochs": _per_model(model.epochs_),
                "best_epoch": _per_model(model.best_epoch_)}
    sums = maxima = payload_sums = payload_maxima = []
    if p["split"] == "test":                  # what chapter 7's intervals over the held-out trajectories need
        sums = trajectory_sums(predicted, judged["tau"], judged["trajectory"]).ravel().tolist()
        maxima = trajectory_maxima(predicted, judged["tau"], judged["trajectory"]).ravel().tolist()
        if "tau_payload" in judged:
            payload_sums = trajectory_sums(predicted, judged["tau_payload"], judged["trajectory"]).ravel().tolist()
            payload_maxima = trajectory_maxima(predicted, judged["tau_payload"], judged["trajectory"]).ravel().tolist()
    return {**out, "trajectory_sums": sums, "trajectory_maxima": maxima, "payload_trajectory_sums": payload_sums,
            "payload_trajectory_maxima": payload_maxima}


def id_contest_model(params: Mapping[str, Any]):
    """The model an ``id_contest`` cell trains (``params``: the cell's parameters), reused from
    where the cell keeps it: a :class:`LearnedID` or a :class:`BaselineID`, each loadable on its
    own (:func:`nfarm.learning.baselines.load_id_model`)."""
    with cell_threads():
        return _fit_id_contestant(JOBS["id_contest"].complete(params))[0]


def idle(p: dict) -> dict:
    time.sleep(p["seconds"])
    return {"seconds": p["seconds"], "value": p["value"]}


_STUDY = {"study_file": REQUIRED, "smoke": False, "data_dir": None, "models_dir": None,
          "seed": 0, "fraction": 1.0}
_ANFIS = {"partition": "grid", "n_mfs": None, "n_rules": None, "radius": None, "mf": None,
          "epochs": 10, "joint_options": None, "patience": None}

JOBS: dict[str, Job] = {
    "anfis_benchmark": Job(
        anfis_benchmark,
        {"problem": "sinc", "n_mfs": 2, "mf": "gbell", "partition": "grid", "n_rules": None,
         "radius": 0.5, "epochs": 10, "step_size": 0.01, "seed": 0},
        ("train_rmse", "check_rmse", "rules"),
        doc="one ANFIS on a Jang benchmark"),
    "learned_ik": Job(
        learned_ik,
        {**_STUDY, "samples": None, "poses": "region", "encoding": "quat_xyz", **_ANFIS,
         "study_sizes": False, "max_out_of_plane_deg": None},
        ("val_rmse_deg", "worst_deg", "rules", "parameters", "train_samples"),
        paths=("study_file", "data_dir", "models_dir"),
        doc="a study's learned IK, one ANFIS per joint",
        prepare=_build_data, shared=("study_file", "smoke", "data_dir", "seed")),
    "ik_contest": Job(
        ik_contest,
        {**_STUDY, "learner": "anfis", "encoding": "arm_plane", "options": None, "split": "val",
         "max_out_of_plane_deg": None},
        ("position_p50_mm", "position_p95_mm", "orientation_p50_deg", "orientation_p95_deg", "joint_rmse_deg",
         "fit_seconds", "predict_us", "epochs", "best_epoch", "train_samples"),
        paths=("study_file", "data_dir", "models_dir"),
        doc="one contestant of the learned-IK contest, judged at the tool",
        prepare=_build_data, shared=("study_file", "smoke", "data_dir", "seed")),
    "learned_id": Job(
        learned_id,
        {**_STUDY, "stride": 1, "torques": "rigid", "seed_like": None, "inputs": "own", "residual": False,
         "shared_premises": False, **_ANFIS},
        ("val_rmse", "val_nrmse", "worst_nrmse", "rules", "parameters", "train_samples"),
        paths=("study_file", "data_dir", "models_dir"),
        doc="a study's learned ID, one ANFIS per joint",
        prepare=_build_data, shared=("study_file", "smoke", "data_dir", "seed")),
    "id_baseline": Job(
        id_baseline,
        {**_STUDY, "stride": 1, "torques": "rigid", "residual": False, "split": "val", "learner": "linear",
         **{k: None for k in sorted(option_names())}},
        ("rmse", "nrmse", "worst_nrmse", "fit_seconds", "predict_us", "features", "train_samples", "epochs",
         "trajectory_sums", "trajectory_maxima", "payload_trajectory_sums", "payload_trajectory_maxima"),
        paths=("study_file", "data_dir", "models_dir"),
        doc="a model-free scikit-learn baseline of a study's ID",
        prepare=_build_data, shared=("study_file", "smoke", "data_dir", "seed")),
    "id_contest": Job(
        id_contest,
        {**_STUDY, "stride": 1, "learner": "anfis", "options": None, "split": "val"},
        ("tier", "rmse", "nrmse", "worst_nrmse", "worst_rmse", "resolved", "train_samples", "predict_us",
         "fit_seconds", "epochs", "best_epoch", "trajectory_sums", "trajectory_maxima", "payload_trajectory_sums",
         "payload_trajectory_maxima"),
        paths=("study_file", "data_dir", "models_dir"),
        doc="one contestant of the learned-ID contest on the measured arm",
        prepare=_build_data, shared=("study_file", "smoke", "data_dir", "seed")),
    "idle": Job(idle, {"seconds": 0.0, "value": 0}, ("seconds", "value"),
                doc="sleeps; the sweep machinery's own cost"),
}
