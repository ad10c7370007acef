"""Study files: what a study of one arm declares (the IK region and data sizes, the ID trajectory
generator and its measured arm, the seed), read and validated into a :class:`Study` (schema in
``params/README.md``), and the studies derived from one (smoke-sized, redrawn).

A study file is refused before any work when a data set it asks for would not fit the memory
budget (:func:`work_estimates`, :func:`memory_budget`).
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..infra.paths import project_path
from ..infra.reading import ParamsError, Validator, load_yaml, show
from ..model.kinematics import fk
from ..model.robot import Robot, load_robot
from ..solvers.ik import in_class
from .id_trajectories import IDSettings
from .regions import IKRegion

__all__ = ["Study", "SPLITS", "load_study", "study_from_dict", "smoke_study", "redrawn",
           "memory_budget", "work_estimates", "PER_JOINT_MAX"]

SPLITS = ("train", "val", "test")


@dataclass(frozen=True, eq=False)
class Study:
    """A validated study file (schema in ``params/README.md``)."""

    source: str
    name: str
    robot_file: str
    robot: Robot
    seed: int
    ik_region: IKRegion
    ik_sampler: str
    ik_sizes: dict[str, int]
    ik_full_range: bool
    check_targets: int
    check_starts: int
    id: IDSettings
    learned_ik: dict = field(default_factory=dict)   # the chosen learned IK's size for this arm
    params: dict = field(repr=False, default_factory=dict)
    #: 0 for the study's own data; k for its training and validation data drawn again
    #: (:func:`redrawn`).
    draw: int = 0

    @property
    def data_params(self) -> dict:
        """The study parameters the data sets depend on (all but ``learned_ik``)."""
        return {k: v for k, v in self.params.items() if k != "learned_ik"}


_TOP = {"name": True, "description": False, "robot_file": True, "seed": True, "ik": True,
        "id": True, "learned_ik": False}
_LEARNED_IK = {"n_mfs": False, "epochs": False}
_IK = {"region": True, "sampler": False, "sizes": True, "check": True, "full_range": False}
_REGION = {"joints_deg": True, "radial_m": False, "reach_m": False, "height_m": False,
           "approach": False}
_APPROACH = {"axis": True, "max_angle_deg": True}
_SIZES = dict.fromkeys(SPLITS, True)
_CHECK = {"targets": True, "starts": True}
_ID = {"trajectories": True, "via_points": True, "segment_time_s": True, "dt_s": True,
       "margin_deg": False, "max_velocity_deg_s": True, "max_acceleration_deg_s2": True,
       "measured": False}
_MEASURED = {"viscous": True, "coulomb": True, "coulomb_velocity_deg_s": True, "armature": True,
             "noise_nm": True, "stribeck": False, "stribeck_velocity_deg_s": False,
             "load_coefficient": False, "encoder_counts": False, "filter_window": False}


def memory_budget() -> float:
    """Bytes the making of one data set may take: ``NFARM_MEMORY_GB`` (GiB, for a bigger or
    shared machine) if set, else half of this machine's physical memory."""
    given = os.environ.get("NFARM_MEMORY_GB")
    if given:
        try:
            value = float(given)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and value > 0):
            raise ParamsError(f"NFARM_MEMORY_GB: must be a positive number of GiB, got {given!r}")
        return value * 2 ** 30
    return 0.5 * os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")


#: Peak bytes per IK pose while a data set is made (drawn, filtered by the region, checked,
#: written): 365 traced by ``tracemalloc`` for 200 000 of intelbot5's poses, 580 by the
#: process's peak memory for 5 million; the larger, rounded up.
IK_BYTES_PER_SAMPLE = 600.0


def _id_samples(segment, via: int, dt: float, vmax: np.ndarray, amax: np.ndarray, widest: float) -> float:
    """An estimate of one trajectory's samples (:func:`random_trajectories`): each segment
    lasts its mean nominal time or what its largest joint move needs within the bounds (the
    largest of a segment's moves is about 0.6 of the widest range), and the whole is slowed
    down by about 1.2. Measured on intelbot5's study: 1 340 estimated against 962 drawn per
    trajectory (200 trajectories)."""
    move = 0.6 * widest
    needed = max(1.875 * move / float(vmax.min()), math.sqrt(5.7735 * move / float(amax.min())))
    return 1.2 * (via - 1) * max(0.5 * (segment[0] + segment[1]), needed) / dt


def work_estimates(study_fields: Mapping[str, Any], robot: Robot) -> list[tuple[str, float, str]]:
    """``(field, bytes, what)`` of the largest pieces of work a study file asks for (the
    making of its largest data set of each kind, chapter 05's solution check), from its
    validated fields: ``ik_sizes``, ``trajectories``, ``via``, ``segment``, ``dt``, ``vmax``,
    ``amax``, ``check_targets``, ``check_starts``."""
    f = study_fields
    n = robot.n
    out = []
    split = max(SPLITS, key=lambda k: f["ik_sizes"][k])
    out.append((f"ik.sizes.{split}", IK_BYTES_PER_SAMPLE * f["ik_sizes"][split],
                f"{f['ik_sizes'][split]:,} IK poses"))
    widest = float(np.max(robot.qlim[:, 1] - robot.qlim[:, 0]))
    per_trajectory = _id_samples(f["segment"], f["via"], f["dt"], f["vmax"], f["amax"], widest)
    # 739 bytes a sample at the peak, measured without a measured arm's arrays: 3 × 8 × (2 + 8n)
    # (1 008 for five joints) covers them.
    split = max(SPLITS, key=lambda k: f["trajectories"][k])
    count = f["trajectories"][split]
    samples = count * per_trajectory
    # the states and torques (and their measured copies), three times over; the 129-point
    # check of every segment of every trajectory at once (q, q̇, q̈)
    peak = max(3 * 8.0 * (2 + 8 * n) * samples, 3 * 8.0 * 129 * count * (f["via"] - 1) * n)
    out.append((f"id.trajectories.{split}", peak,
                f"{count:,} trajectories of about {per_trajectory:,.0f} samples each"))
    if not in_class(robot):       # LM from every start at once; the closed form goes in batches
        out.append(("ik.check.targets", 3 * 8.0 * n * f["check_targets"] * f["check_starts"],
                    f"{f['check_targets']:,} targets × {f['check_starts']} starts"))
    return out


def _gib(size: float) -> str:
    gib = size / 2 ** 30
    return f"{gib:,.0f}" if gib >= 100 else f"{gib:.3g}"


def _check_work(v: Validator, fields: Mapping[str, Any], robot: Robot) -> None:
    budget = memory_budget()
    source = "NFARM_MEMORY_GB" if os.environ.get("NFARM_MEMORY_GB") else \
        "half this machine's memory; NFARM_MEMORY_GB sets another"
    for field_, need, what in work_estimates(fields, robot):
        if need > budget:
            v.fail(field_, f"{what} would take about {_gib(need)} GiB while made, over the memory budget of "
                           f"{_gib(budget)} GiB ({source})")


def load_study(path: str | os.PathLike) -> Study:
    """Load and validate a study file; every broken rule is one :class:`ParamsError` line
    naming the file and the field."""
    path = Path(path)
    data = load_yaml(project_path(path), what="study file")
    return study_from_dict(data, source=str(path))


def _bounds(v: Validator, value: Any, at: str, *, positive: bool = False) -> tuple:
    pair = v.sequence(value, at, min_len=2, max_len=2)
    out = tuple(None if x is None else v.number(x, f"{at}[{k}]", lo=0.0 if positive else None)
                for k, x in enumerate(pair))
    if None not in out and not out[0] < out[1]:
        v.fail(at, f"must satisfy lo < hi, got {list(out)}")
    return out


#: The largest per-joint drive, noise, speed or acceleration value a study may give: every
#: plausible one is far below, and 1.7e308 would turn the data sets' torques into inf.
PER_JOINT_MAX = 1e6


def _per_joint(v: Validator, value: Any, at: str, n: int, *, zero: bool = False) -> np.ndarray:
    """One number for every joint, or one per joint; > 0 (``>= 0`` with ``zero``), at most
    :data:`PER_JOINT_MAX`."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        values = [v.number(value, at, lo=0.0, lo_open=not zero, hi=PER_JOINT_MAX)] * n
    else:
        values = [v.number(x, f"{at}[{k}]", lo=0.0, lo_open=not zero, hi=PER_JOINT_MAX)
                  for k, x in enumerate(v.sequence(value, at, min_len=n, max_len=n))]
    return np.array(values, dtype=float)


def study_from_dict(data: Any, source: str = "<dict>") -> Study:
    """Validate a study mapping (as read from YAML) and build a :class:`Study`: the sections
    in file order, each by its reader, the first broken rule one :class:`ParamsError` line
    naming the file and the field.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.infra.reading import load_yaml
        >>> data = load_yaml(PARAMS / "studies" / "intelbot5.yaml")
        >>> study = study_from_dict(data, "intelbot5.yaml")
        >>> study.robot.name, study.ik_sizes["train"] > 0, study.id.dt > 0
        ('intelbot5', True, True)
        >>> study_from_dict({**data, "seed": -1}, "intelbot5.yaml")
        Traceback (most recent call last):
        ...
        nfarm.infra.reading.ParamsError: intelbot5.yaml: seed: must be >= 0, got -1
    """
    v = Validator(source)
    v.mapping(data, "", _TOP)
    name = v.string(data["name"], "name")
    if "description" in data:
        v.string(data["description"], "description", allow_empty=True)
    robot_file = v.string(data["robot_file"], "robot_file")
    try:
        robot = load_robot(project_path(robot_file))
    except ParamsError as exc:
        v.fail("robot_file", f"cannot load the robot: {exc}")
    seed = v.integer(data["seed"], "seed", lo=0, hi=2**63 - 1)
    ik = _read_ik(v, data["ik"], robot, seed)
    id_settings = _read_id(v, data["id"], robot)
    _check_work(v, {"ik_sizes": ik["ik_sizes"], "trajectories": id_settings.trajectories,
                    "via": id_settings.via_points, "segment": id_settings.segment_time,
                    "dt": id_settings.dt, "vmax": id_settings.max_velocity,
                    "amax": id_settings.max_acceleration, "check_targets": ik["check_targets"],
                    "check_starts": ik["check_starts"]}, robot)
    if data["id"].get("measured") is not None:
        id_settings = dataclasses.replace(id_settings, **_read_measured(v, data["id"]["measured"], robot))
    learned_ik = _read_learned_ik(v, data["learned_ik"], robot.n) \
        if data.get("learned_ik") is not None else {}
    return Study(source=source, name=name, robot_file=robot_file, robot=robot, seed=seed, **ik,
                 id=id_settings, learned_ik=learned_ik, params=json.loads(json.dumps(data)))


def _read_region(v: Validator, data: Any, robot: Robot, seed: int) -> IKRegion:
    """Section ``ik.region``: the joint box [deg] within the limits, the task-space filters, and
    a check that some pose of the box passes them."""
    n = robot.n
    region = v.mapping(data, "ik.region", _REGION)
    joints = v.sequence(region["joints_deg"], "ik.region.joints_deg", min_len=n, max_len=n)
    box = robot.qlim.copy()
    for i, pair in enumerate(joints):
        at = f"ik.region.joints_deg[{i}]"
        if pair is None:
            continue
        lo, hi = (math.radians(x) for x in v.vector(pair, at, 2))
        if not lo < hi:
            v.fail(at, f"must satisfy lo < hi, got {show(pair)}")
        limits = robot.qlim[i]
        if lo < limits[0] - 1e-12 or hi > limits[1] + 1e-12:
            v.fail(at, f"must lie within joint {i + 1}'s limits "
                       f"[{math.degrees(limits[0]):.6g}, {math.degrees(limits[1]):.6g}] deg, "
                       f"got {show(pair)}")
        box[i] = (max(lo, limits[0]), min(hi, limits[1]))
    radial = _bounds(v, region["radial_m"], "ik.region.radial_m", positive=True) \
        if region.get("radial_m") is not None else (None, None)
    height = _bounds(v, region["height_m"], "ik.region.height_m") \
        if region.get("height_m") is not None else (None, None)
    reach = _bounds(v, region["reach_m"], "ik.region.reach_m") \
        if region.get("reach_m") is not None else (None, None)
    if reach != (None, None) and robot.convention == "modified" and \
            (abs(robot.a[0]) > 1e-12 or abs(math.remainder(robot.alpha[0], 2 * math.pi)) > 1e-12):
        v.fail("ik.region.reach_m", f"needs joint 1 to turn about the base z axis; {robot.name}'s "
                                    f"first joint has a = {robot.a[0]:g} m, alpha = "
                                    f"{math.degrees(robot.alpha[0]):g} deg")
    axis, angle = None, math.pi
    if region.get("approach") is not None:
        approach = v.mapping(region["approach"], "ik.region.approach", _APPROACH)
        axis = np.array(v.vector(approach["axis"], "ik.region.approach.axis", 3))
        norm = float(np.linalg.norm(axis))
        if norm == 0:
            v.fail("ik.region.approach.axis", "must not be the zero vector")
        axis = axis / norm
        angle = math.radians(v.number(approach["max_angle_deg"], "ik.region.approach.max_angle_deg",
                                      lo=0.0, hi=180.0, lo_open=True))
    region_ = IKRegion(robot, box, radial, height, axis, angle, reach)
    if region_.has_filters:        # 8 192 draws (a few ms): a region no pose of the box reaches
        q_try = region_.box[:, 0] + (region_.box[:, 1] - region_.box[:, 0]) * \
            np.random.default_rng(seed).random((8192, n))
        if not region_.contains_pose(fk(robot, q_try), q_try).any():
            v.fail("ik.region", "no pose of 8,192 drawn in the joint box passes its task-space filters "
                                "(radial_m, height_m, reach_m, approach): the arm cannot reach it")
    return region_


def _read_ik(v: Validator, data: Any, robot: Robot, seed: int) -> dict[str, Any]:
    """Section ``ik``: the region, the sampler, the sizes and the solution check (the
    :class:`Study` fields they fill)."""
    ik = v.mapping(data, "ik", _IK)
    region = _read_region(v, ik["region"], robot, seed)
    sampler = v.choice(ik.get("sampler", "sobol"), "ik.sampler", ("sobol", "uniform"))
    sizes = v.mapping(ik["sizes"], "ik.sizes", _SIZES)
    ik_sizes = {k: v.integer(sizes[k], f"ik.sizes.{k}", lo=1, hi=50_000_000) for k in SPLITS}
    check = v.mapping(ik["check"], "ik.check", _CHECK)
    return {"ik_region": region, "ik_sampler": sampler, "ik_sizes": ik_sizes,
            "check_targets": v.integer(check["targets"], "ik.check.targets", lo=1, hi=1_000_000),
            "check_starts": v.integer(check["starts"], "ik.check.starts", lo=1, hi=1024),
            "ik_full_range": v.boolean(ik.get("full_range", False), "ik.full_range")}


def _read_id(v: Validator, data: Any, robot: Robot) -> IDSettings:
    """Section ``id`` but its ``measured`` arm: the trajectory generator, SI units inside."""
    n = robot.n
    idd = v.mapping(data, "id", _ID)
    counts = v.mapping(idd["trajectories"], "id.trajectories", _SIZES)
    trajectories = {k: v.integer(counts[k], f"id.trajectories.{k}", lo=1, hi=1_000_000)
                    for k in SPLITS}
    via = v.integer(idd["via_points"], "id.via_points", lo=2, hi=10_000)
    segment = _bounds(v, idd["segment_time_s"], "id.segment_time_s", positive=True)
    if None in segment or segment[0] <= 0:
        v.fail("id.segment_time_s", f"must be two durations 0 < lo < hi [s], got "
                                    f"{show(idd['segment_time_s'])}")
    dt = v.number(idd["dt_s"], "id.dt_s", lo=0.0, lo_open=True, hi=segment[0])
    margin = math.radians(v.number(idd.get("margin_deg", 0.0), "id.margin_deg", lo=0.0))
    narrowest = float(np.min(robot.qlim[:, 1] - robot.qlim[:, 0]))
    if 2 * margin >= narrowest:
        v.fail("id.margin_deg", f"must leave room inside the narrowest joint range "
                                f"({math.degrees(narrowest):.6g} deg), got {math.degrees(margin):.6g}")
    vmax = np.radians(_per_joint(v, idd["max_velocity_deg_s"], "id.max_velocity_deg_s", n))
    amax = np.radians(_per_joint(v, idd["max_acceleration_deg_s2"], "id.max_acceleration_deg_s2", n))
    return IDSettings(trajectories, via, segment, dt, margin, vmax, amax)


def _read_measured(v: Validator, data: Any, robot: Robot) -> dict[str, Any]:
    """Section ``id.measured``: the "real" arm's drives, friction, sensor noise and encoders
    (the :class:`IDSettings` fields they fill)."""
    n = robot.n
    m = v.mapping(data, "id.measured", _MEASURED)
    drives = {key: _per_joint(v, m[key], f"id.measured.{key}", n, zero=True)
              for key in ("viscous", "coulomb", "armature")}
    drives["coulomb_velocity"] = np.radians(_per_joint(
        v, m["coulomb_velocity_deg_s"], "id.measured.coulomb_velocity_deg_s", n))
    out: dict[str, Any] = {"measured": dataclasses.replace(robot, **drives),
                           "noise": _per_joint(v, m["noise_nm"], "id.measured.noise_nm", n, zero=True)}
    friction: dict[str, np.ndarray] = {}
    if "stribeck" in m:
        friction["stribeck"] = _per_joint(v, m["stribeck"], "id.measured.stribeck", n, zero=True)
        low = np.flatnonzero(friction["stribeck"] < drives["coulomb"])
        if low.size:
            v.fail("id.measured.stribeck", f"the breakaway friction must be at least the Coulomb "
                                           f"friction (joint {low[0] + 1}: {friction['stribeck'][low[0]]:g} "
                                           f"< {drives['coulomb'][low[0]]:g} N·m)")
        if "stribeck_velocity_deg_s" not in m:
            v.fail("id.measured", "stribeck needs stribeck_velocity_deg_s (> 0)")
    if "stribeck_velocity_deg_s" in m:
        friction["stribeck_velocity"] = np.radians(_per_joint(
            v, m["stribeck_velocity_deg_s"], "id.measured.stribeck_velocity_deg_s", n))
    if "load_coefficient" in m:
        friction["load_coefficient"] = _per_joint(v, m["load_coefficient"], "id.measured.load_coefficient",
                                                  n, zero=True)
        if (friction["load_coefficient"] >= 1).any():
            v.fail("id.measured.load_coefficient", "must be < 1 (a fraction of the joint's load torque)")
    out["friction"] = friction
    if m.get("encoder_counts") is not None:
        out["encoder_counts"] = v.integer(m["encoder_counts"], "id.measured.encoder_counts", lo=16, hi=2**31)
    out["filter_window"] = v.integer(m.get("filter_window", 7), "id.measured.filter_window", lo=5, hi=101)
    if out["filter_window"] % 2 == 0:
        v.fail("id.measured.filter_window", f"must be an odd number of samples, got {out['filter_window']}")
    return out


def _read_learned_ik(v: Validator, data: Any, n: int) -> dict[str, Any]:
    """Section ``learned_ik``: the chosen learned IK's functions per input and epochs."""
    chosen = v.mapping(data, "learned_ik", _LEARNED_IK)
    learned_ik: dict[str, Any] = {}
    if "n_mfs" in chosen:
        mfs = chosen["n_mfs"]
        learned_ik["n_mfs"] = v.integer(mfs, "learned_ik.n_mfs", lo=1, hi=8) \
            if not isinstance(mfs, list) else \
            [v.integer(m, f"learned_ik.n_mfs[{i}]", lo=1, hi=8)
             for i, m in enumerate(v.sequence(mfs, "learned_ik.n_mfs", min_len=1, max_len=16))]
    if "epochs" in chosen:
        epochs = chosen["epochs"]
        learned_ik["epochs"] = v.integer(epochs, "learned_ik.epochs", lo=1, hi=10_000) \
            if not isinstance(epochs, list) else \
            [v.integer(e, f"learned_ik.epochs[{j}]", lo=1, hi=10_000)
             for j, e in enumerate(v.sequence(epochs, "learned_ik.epochs", min_len=n, max_len=n))]
    return learned_ik


def smoke_study(study: Study, factor: int = 50) -> Study:
    """The same study with every size divided by ``factor`` (at least a few samples each),
    for quick runs; its data sets go to a directory of their own (``<robot>-smoke``)."""
    params = json.loads(json.dumps(study.params))
    params["ik"]["sizes"] = {k: max(v // factor, 64) for k, v in params["ik"]["sizes"].items()}
    params["ik"]["check"]["targets"] = max(params["ik"]["check"]["targets"] // factor, 50)
    params["id"]["trajectories"] = {k: max(v // factor, 2)
                                    for k, v in params["id"]["trajectories"].items()}
    params["name"] = f"{params['name']} (smoke)"
    return study_from_dict(params, source=study.source)


def redrawn(study: Study, draw: int) -> Study:
    """The study with its training and validation data drawn again: draw ``k`` is the study
    with ``seed + k`` (a reader reproduces it by editing the seed), its data sets in a
    directory of their own (``draw<k>/`` in the study's, :func:`dataset_dir`) and without a
    test split — the test set is never redrawn, so every draw's models are tested on the same
    held-out data. Draw 0 is the study itself. A sweep's ``seeds`` are draws (:mod:`nfarm.study.jobs`): the spread over
    seeds is over data and initialisation together.

    Raises:
        ValueError: ``draw`` is not a non-negative integer.
    """
    if isinstance(draw, bool) or not isinstance(draw, (int, np.integer)) or draw < 0:
        raise ValueError(f"draw must be a non-negative integer, got {draw!r}")
    if draw == 0:
        return study
    params = json.loads(json.dumps(study.params))
    params["seed"] = study.seed + int(draw)
    return dataclasses.replace(study_from_dict(params, source=study.source), draw=int(draw))
