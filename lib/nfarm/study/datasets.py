"""The study's data sets: training, validation and test data for learned inverse kinematics and
inverse dynamics, generated from the numerical models (the dissertation's §3.2.3; chapter 05),
written once and reused while their inputs are unchanged.

What the data are: IK samples ``q`` in the study's region and ``T = fk(q)``
(:mod:`nfarm.study.regions`); ID trajectories with ``rnea`` torques and, for a measured arm,
what its sensors record (:mod:`nfarm.study.id_trajectories`); the study file that declares them
(:mod:`nfarm.study.study_files`).

**Files** (:func:`build_datasets`, ``python -m nfarm datasets STUDY``):
``build/datasets/<robot>/{ik,ik_full,id}_{train,val,test}.npz`` of plain arrays (``np.load(...,
allow_pickle=False)``; written with fixed zip timestamps, so the same inputs give the same
bytes), each with a ``.json`` beside it: the robot's parameter hash, the study parameters, the
seed, the nfarm and data-code versions, the array shapes, the npz's SHA-256 and the command.
A file whose inputs' hash is unchanged is reused. :func:`load` refuses a file made for another
robot or other study parameters, saying what differs and how to regenerate.

Every random draw comes from the study's ``seed``, through one named stream per use and split
(``numpy.random.SeedSequence([seed, stream, split])``, :data:`nfarm.study.regions.STREAMS`), so
adding a use never shifts another's draws. The test split's draws come from the study's own
``test_seed`` instead (:func:`split_seed`): a fresh held-out set is drawn by changing it alone,
every model and choice unchanged.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import sys
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..infra.paths import BUILD, atomic_path, project_path
from ..infra.provenance import code_digest
from ..infra.reading import ParamsError, Validator, load_json, show
from ..model.dynamics import rnea, stribeck_drive_torques
from ..model.robot import Robot, robot_hash, robot_name
from .id_trajectories import current_sensed, measured_states, random_trajectories, true_arm, with_payload
from .regions import STREAMS, IKRegion, ik_samples
from .study_files import SPLITS, Study, redrawn

__all__ = ["Dataset", "build_datasets", "built_arm", "measured_readings", "held_out_readings", "load", "dataset_dir", "inputs_hash", "split_seed", "DATA_VERSION",
           "SPLITS"]

#: Version of the generating code: bump when the same inputs would give different data.
DATA_VERSION = 4
_SPLIT_STREAM = {"train": 0, "val": 1, "test": 2}


def split_seed(study: Study, split: str) -> int:
    """The seed a split's draws come from: the study's ``test_seed`` for the test split, its
    ``seed`` for the others.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.study.study_files import load_study
        >>> study = load_study(PARAMS / "studies" / "intelbot5.yaml")
        >>> split_seed(study, "train") == study.seed, split_seed(study, "test") == study.test_seed
        (True, True)
    """
    return study.test_seed if split == "test" else study.seed


def inputs_hash(study: Study) -> str:
    """SHA-256 of what a study's data depend on: the robot's parameters, the study's
    parameters, the data code's version and the content of the code that makes them
    (:func:`nfarm.infra.provenance.code_digest` of this module and what it imports)."""
    blob = json.dumps({"robot": robot_hash(study.robot), "study": study.data_params,
                       "data_version": DATA_VERSION, "code": code_digest("study.datasets")}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()


def dataset_dir(study: Study, out: str | os.PathLike | None = None) -> Path:
    """Where a study's data sets go: ``out`` or ``build/datasets/<robot name>/`` (a smoke
    study's: ``build/datasets/<robot name>-smoke/``); a redrawn study's (:func:`redrawn`) in
    its subdirectory ``draw<k>/``."""
    if out is not None:
        base = project_path(out)
    else:
        smoke = "-smoke" if study.name.endswith("(smoke)") else ""
        # the robot's name names the directory: a name that could leave build/ is refused
        name = robot_name(study.robot.name, study.robot.source)
        base = BUILD / "datasets" / f"{name}{smoke}"
    return base / f"draw{study.draw}" if study.draw else base


def _npz_bytes(arrays: Mapping[str, np.ndarray]) -> bytes:
    """An ``.npz`` (uncompressed zip of ``.npy``) with fixed timestamps: same arrays, same bytes."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_STORED) as archive:
        for name, array in arrays.items():
            info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.external_attr = 0o644 << 16
            npy = io.BytesIO()
            np.lib.format.write_array(npy, np.ascontiguousarray(array), allow_pickle=False)
            archive.writestr(info, npy.getvalue())
    return buffer.getvalue()


def _write(path: Path, arrays: Mapping[str, np.ndarray], meta: dict) -> None:
    """The npz, then its JSON (atomically each): a JSON is only there for a complete npz."""
    data = _npz_bytes(arrays)
    meta = {**meta, "npz_sha256": hashlib.sha256(data).hexdigest(),
            "arrays": {k: {"shape": list(a.shape), "dtype": a.dtype.str} for k, a in arrays.items()}}
    json_path = path.with_suffix(".json")
    json_path.unlink(missing_ok=True)
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    with atomic_path(json_path) as tmp:
        tmp.write_text(json.dumps(meta, indent=1, sort_keys=True) + "\n", encoding="utf-8")


@dataclass(frozen=True)
class Dataset(Mapping):
    """A loaded data set: its arrays by name (``data["q"]``) and its description ``meta``."""

    path: Path
    arrays: dict[str, np.ndarray]
    meta: dict

    def __getitem__(self, key: str) -> np.ndarray:
        return self.arrays[key]

    def __iter__(self):
        return iter(self.arrays)

    def __len__(self) -> int:
        return len(self.arrays)


def _differences(made: Any, now: Any, at: str = "") -> list[str]:
    if isinstance(made, dict) and isinstance(now, dict):
        out = []
        for key in sorted(set(made) | set(now)):
            out += _differences(made.get(key), now.get(key), f"{at}.{key}" if at else str(key))
        return out
    return [] if made == now else [f"{at} ({show(made)} → {show(now)})"]


def load(path: str | os.PathLike, robot: Robot, study: Study | None = None) -> Dataset:
    """Read a data set written by :func:`build_datasets`, refusing one made for another robot
    (or, with ``study``, from other study parameters or data code).

    Raises:
        ParamsError: a missing, damaged or mismatched file; the message says what differs and
            how to regenerate.
    """
    path = Path(path)
    meta = load_json(path.with_suffix(".json"), what="data set description")
    v = Validator(str(path.with_suffix(".json")))
    v.mapping(meta, "", dict.fromkeys(_META_KEYS, True))
    again = f"regenerate with `python -m nfarm datasets {meta.get('study_file', 'STUDY')}`"
    if meta["robot_params_sha256"] != robot_hash(robot):
        v.fail("robot_params_sha256", f"made for robot {show(meta.get('robot'))} with other "
                                      f"parameters than {robot.name!r} ({robot.source}): {again}")
    if study is not None and meta["inputs_hash"] != inputs_hash(study):
        diff = _differences(meta["study"], study.data_params)
        if meta["data_version"] != DATA_VERSION:
            diff.append(f"data code version ({meta['data_version']} → {DATA_VERSION})")
        if diff:
            v.fail("study", f"made from other study parameters: {'; '.join(diff[:4])}; {again}")
        v.fail("study", f"made by other code than this checkout's (nfarm.study.datasets or a module it "
                        f"imports changed since): {again}")
    raw = _read_limited(path)
    if hashlib.sha256(raw).hexdigest() != meta["npz_sha256"]:
        v.fail("npz_sha256", f"{path.name} is not the file this description was written for "
                             f"(changed or damaged): {again}")
    with np.load(io.BytesIO(raw), allow_pickle=False) as npz:
        arrays = {k: npz[k] for k in npz.files}
    declared = meta["arrays"]
    if set(arrays) != set(declared) or any(list(arrays[k].shape) != declared[k]["shape"]
                                           for k in arrays):
        v.fail("arrays", f"the arrays of {path.name} do not match their description: {again}")
    return Dataset(path, arrays, meta)


_META_KEYS = ("kind", "split", "robot", "robot_file", "robot_params_sha256", "study_file",
              "study", "seed", "inputs_hash", "nfarm_version", "data_version", "command",
              "npz_sha256", "arrays")


def _read_limited(path: Path) -> bytes:
    from ..infra.reading import read_bytes
    return read_bytes(path, max_bytes=8 << 30, what="data set")


def _up_to_date(path: Path, digest: str) -> bool:
    json_path = path.with_suffix(".json")
    if not (path.is_file() and json_path.is_file()):
        return False
    try:
        meta = load_json(json_path)
        return isinstance(meta, dict) and meta.get("inputs_hash") == digest and \
            hashlib.sha256(path.read_bytes()).hexdigest() == meta.get("npz_sha256")
    except (ParamsError, OSError):
        return False


def built_arm(study: Study) -> tuple[Robot, np.ndarray]:
    """The arm a study's ``id.measured`` section describes, as built: the robot with its
    drives and, with a ``true_arm``, its links drawn (:func:`nfarm.study.id_trajectories.true_arm`)
    from the study's seed — each redrawn study (``draw`` k, seed + k:
    :func:`nfarm.study.study_files.redrawn`) **another arm built** to the same declared
    tolerances, so that a spread over draws covers the built arm as well as the data (issue 65);
    draw 0, the study's own, is chapter 5's — and the ``(n,)`` zero offsets of its torque
    readings [N·m] (zero without a ``sensor``), drawn after the links from the same stream.

    Raises:
        ValueError: the study has no measured arm.
    """
    settings = study.id
    if settings.measured is None:
        raise ValueError(f"{study.source}: id.measured: the study declares no measured arm")
    rng = np.random.default_rng(np.random.SeedSequence([study.seed, STREAMS["true_arm"]]))
    arm = settings.measured if settings.true_arm is None else true_arm(settings.measured, settings.true_arm, rng)
    offset = np.zeros(arm.n) if settings.offset_sd is None else \
        settings.offset_sd * np.clip(rng.standard_normal(arm.n), -3.0, 3.0)
    return arm, offset


def _measured_torques(study: Study, data: dict, split: str) -> dict[str, np.ndarray]:
    """``tau_measured``: the torques the built arm (:func:`built_arm`) reports on the states of
    ``data`` — its rigid body, its drives (Stribeck and load terms from the study) and its
    sensors (:func:`nfarm.study.id_trajectories.current_sensed`); on the test split with a
    payload, also ``tau_payload``, the same arm carrying it (its own noise draws)."""
    return measured_readings(study, data, [split_seed(study, split), STREAMS["id_noise"], _SPLIT_STREAM[split]],
                             payload=split == "test")


def measured_readings(study: Study, data: Mapping[str, np.ndarray], stream: list[int], *,
                      payload: bool = False) -> dict[str, np.ndarray]:
    """The built arm's torque readings on the exact states ``data`` (``q, qd, qdd (N, n)``, ``tau``
    the model's rigid-body torques): ``tau_measured (N, n)`` [N·m] — its rigid body, its drives and
    its sensors, their noise drawn from ``numpy.random.SeedSequence(stream)`` — and with ``payload``
    (and a study whose built arm declares one) ``tau_payload``, the same arm carrying it (the noise
    from ``stream + [1]``). The data sets' splits use it with their own streams; a shifted
    population (:mod:`nfarm.study.shifted`) with its own."""
    settings = study.id
    arm, offset = built_arm(study)
    cases = {"tau_measured": arm}
    if payload and settings.true_arm is not None and settings.true_arm.payload > 0:
        cases["tau_payload"] = with_payload(arm, settings.true_arm.payload)
    out = {}
    for k, (key, built) in enumerate(cases.items()):
        draws = [*stream] + ([k] if k else [])
        rigid = data["tau"] if built is settings.measured else rnea(built, data["q"], data["qd"], data["qdd"])
        drive = stribeck_drive_torques(built, data["qd"], data["qdd"], rigid, **settings.friction)
        out[key] = current_sensed(rigid + drive, np.random.default_rng(np.random.SeedSequence(draws)),
                                  noise=settings.noise, torque_per_count=settings.torque_per_count, offset=offset)
    return out


def held_out_readings(study: Study, draw: int, test: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """What the arm built for ``draw`` (:func:`built_arm` of the redrawn study) reads on the
    test split's exact states ``test`` (the study's own ``id_test``, never redrawn:
    ``q, qd, qdd, tau``): ``tau_measured`` and, where the built arm declares a payload,
    ``tau_payload`` — so that a draw's models are judged against the arm they were trained on.
    Draw 0's are the split's own readings; another draw's noise comes from the split's stream
    extended by the draw.

    Raises:
        ValueError: the study has no measured arm, or ``draw`` is not a whole number >= 0.
    """
    if study.id.measured is None:
        raise ValueError(f"{study.source}: id.measured: the study declares no measured arm")
    if draw == 0:
        return {k: test[k] for k in ("tau_measured", "tau_payload") if k in test}
    return measured_readings(redrawn(study, draw), test, [split_seed(study, "test"), STREAMS["id_noise"],
                                                          _SPLIT_STREAM["test"], int(draw)], payload=True)


def build_datasets(study: Study, out: str | os.PathLike | None = None, *, force: bool = False,
                   progress: bool = False, command: str | None = None) -> list[tuple[Path, str]]:
    """Write every data set of ``study`` (module docstring); returns ``(path, "made" |
    "reused")`` per file. Files whose inputs' hash is unchanged are reused unless ``force``."""
    directory = dataset_dir(study, out)
    directory.mkdir(parents=True, exist_ok=True)
    digest = inputs_hash(study)
    base = {"robot": study.robot.name, "robot_file": study.robot_file,
            "robot_params_sha256": robot_hash(study.robot), "study_file": study.source,
            "study": study.data_params, "seed": study.seed, "inputs_hash": digest,
            "nfarm_version": __version__, "data_version": DATA_VERSION,
            "command": command or f"python -m nfarm datasets {study.source}"}
    splits = [s for s in SPLITS if s != "test"] if study.draw else SPLITS    # never redrawn
    jobs = [("ik", s) for s in splits] + [("id", s) for s in splits]
    if study.ik_full_range:
        jobs += [("ik_full", s) for s in splits]
    bar = None
    if progress:
        from tqdm.auto import tqdm
        bar = tqdm(total=len(jobs), desc="data sets", unit="file", file=sys.stderr)
    done = []
    for kind, split in jobs:
        path = directory / f"{kind}_{split}.npz"
        if not force and _up_to_date(path, digest):
            done.append((path, "reused"))
        else:
            seed = [split_seed(study, split), STREAMS[kind], _SPLIT_STREAM[split]]
            if kind == "id":
                data = random_trajectories(study.robot, study.id, study.id.trajectories[split],
                                           np.random.SeedSequence(seed))
                data["tau"] = rnea(study.robot, data["q"], data["qd"], data["qdd"])
                if study.id.measured is not None:
                    data.update(_measured_torques(study, data, split))
                    if study.id.encoder_counts is not None:
                        data["q_measured"], data["qd_measured"], data["qdd_measured"] = measured_states(
                            data["q"], data["trajectory"], study.id.dt, study.id.encoder_counts,
                            study.id.filter_window)
            else:
                region = study.ik_region if kind == "ik" else IKRegion.full(study.robot)
                data = ik_samples(region, study.ik_sizes[split], np.random.SeedSequence(seed),
                                  method=study.ik_sampler)
            _write(path, data, {**base, "kind": kind, "split": split})
            done.append((path, "made"))
        if bar is not None:
            bar.update(1)
    if bar is not None:
        bar.close()
    return done
