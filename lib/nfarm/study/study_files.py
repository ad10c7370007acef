"""Study files: what a study of one arm declares (the IK region and data sizes, the ID trajectory
generator and its measured arm, the seed), and the studies derived from one (smoke-sized,
redrawn).

A file is read in two steps. The generic reader (:func:`nfarm.infra.typed.read_typed`) reads
it into a :class:`StudyFile`, a tree of dataclasses that is the schema (``params/README.md``,
"Studies", documents the same fields, and a test checks that it does): every field's type,
range and length, unknown keys refused. Then :func:`study_from_dict` checks the rules that
involve two fields or the robot's model (a region within the joint limits that the arm
reaches, a step within the shortest segment, breakaway friction above the Coulomb level) and
builds the :class:`Study` the data sets are made from, in SI units and radians.

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
from typing import Annotated, Any, Literal, Optional, Union, get_args

import numpy as np

from ..infra.arguments import check_integer
from ..infra.paths import project_path
from ..infra.reading import ParamsError, Validator, load_yaml
from ..infra.typed import (ACCELERATION_DEG_S2, CURRENT_PER_COUNT, DRIVE, JOINTS, MASS, N_MFS, ORDERED,
                           SPEED_DEG_S, TEXT, TIME_S, TORQUE_CONSTANT, Length, Range, read_typed, section_keys)
from ..model.kinematics import fk
from ..model.robot import Robot, load_robot
from ..solvers.ik import in_class
from .id_trajectories import IDSettings, TrueArm
from .regions import IKRegion

__all__ = ["Study", "StudyFile", "ShiftedSection", "SPLITS", "load_study", "study_from_dict", "smoke_study", "SMOKE_IK_SIZES", "redrawn",
           "memory_budget", "work_estimates", "PER_JOINT_MAX"]

Split = Literal["train", "val", "test"]
SPLITS: tuple[str, ...] = get_args(Split)


@dataclass(frozen=True, eq=False)
class Study:
    """A validated study file, in SI units and radians, with what the data sets are made from
    (the region, the trajectory generator); ``file`` holds the file as written."""

    source: str
    name: str
    robot_file: str
    robot: Robot
    seed: int
    #: The test split's own seed: the held-out set is drawn apart from the training and
    #: validation data, so a fresh one is drawn by changing this alone (docs/STUDY.md, "Data").
    test_seed: int
    ik_region: IKRegion
    ik_sampler: str
    ik_sizes: dict[str, int]
    ik_full_range: bool
    check_targets: int
    check_starts: int
    id: IDSettings
    learned_ik: dict = field(default_factory=dict)   # the chosen learned IK's size for this arm
    #: The shifted test population chapter 7 reads once (:class:`ShiftedSection`), or ``None``.
    shifted: "ShiftedSection | None" = None
    params: dict = field(repr=False, default_factory=dict)
    #: 0 for the study's own data; k for its training and validation data drawn again
    #: (:func:`redrawn`).
    draw: int = 0
    #: The file as written (degrees, as in the file), typed and checked field by field.
    file: StudyFile | None = field(default=None, repr=False)

    @property
    def data_params(self) -> dict:
        """The study parameters the data sets depend on (all but ``learned_ik`` and ``shifted``,
        whose test population is drawn apart, by chapter 7)."""
        return {k: v for k, v in self.params.items() if k not in ("learned_ik", "shifted")}


#: ``[lo, hi]``, either ``null`` for no bound, ``lo < hi`` where both are given.
Bounds = Annotated[tuple[Optional[float], Optional[float]], ORDERED]
#: One number for every joint, or one per joint.
PerJoint = Union[float, Annotated[list[float], JOINTS]]
#: The largest per-joint drive, noise, speed or acceleration value a study may give: every
#: plausible one is far below, and 1.7e308 would turn the data sets' torques into inf.
PER_JOINT_MAX = DRIVE.hi
#: Drive terms and noise [N·m, N·m·s/rad, kg·m²] (>= 0); speeds and accelerations have their own
#: plausibility bounds (nfarm.infra.typed: SPEED_DEG_S, ACCELERATION_DEG_S2).
_DRIVE = DRIVE


@dataclass(frozen=True, kw_only=True)
class ApproachSection:
    """``ik.region.approach``: the tool's approach (z) axis within ``max_angle_deg`` of
    ``axis`` (base frame)."""

    axis: tuple[float, float, float]
    max_angle_deg: Annotated[float, Range(lo=0.0, lo_open=True, hi=180.0)]


@dataclass(frozen=True, kw_only=True)
class RegionSection:
    """``ik.region``: one ``[lo, hi]`` per joint [deg] (``null``: its limits) and the tool
    point's filters [m]."""

    joints_deg: Annotated[list[Optional[Annotated[tuple[float, float], ORDERED]]], JOINTS]
    radial_m: Annotated[Optional[Bounds], Range(lo=0.0)] = None
    reach_m: Optional[Bounds] = None
    height_m: Optional[Bounds] = None
    approach: Optional[ApproachSection] = None


@dataclass(frozen=True, kw_only=True)
class CheckSection:
    """``ik.check``: chapter 05's single-valuedness check, its targets and LM starts each."""

    targets: Annotated[int, Range(lo=1, hi=1_000_000)]
    starts: Annotated[int, Range(lo=1, hi=1024)]


@dataclass(frozen=True, kw_only=True)
class IKSection:
    """``ik``: the region, the sampler, the sizes of the splits and the check."""

    region: RegionSection
    sampler: Literal["sobol", "uniform"] = "sobol"
    sizes: Annotated[dict[Split, int], Range(lo=1, hi=50_000_000)]
    check: CheckSection
    full_range: bool = False


@dataclass(frozen=True, kw_only=True)
class ShiftedSection:
    """``shifted``: a test population that no choice of a model met (issue 66), declared in the
    study file before it is read and read once, by chapter 7, with the frozen models: IK targets
    just beyond the region — every joint within ``ik_band`` of its range's width beyond the ends of
    the region's box (and within its limits), at least one outside it, the task-space filters kept
    (``nfarm.study.shifted``) — ``ik_samples`` of them, drawn from ``seed``; ``declared`` says when
    it was declared. With ``id_trajectories``, also ID trajectories faster than any the models met:
    the generator's paths run ``id_speed`` times as fast (velocity bounds × ``id_speed``,
    acceleration bounds × ``id_speed``², segment times ÷ ``id_speed``), their torques the model's and,
    for a measured arm, the built arm's as its sensors read them; ``id_declared`` says when."""

    seed: Annotated[int, Range(lo=0, hi=2 ** 63 - 1)]
    declared: Annotated[str, TEXT]
    ik_band: Annotated[float, Range(lo=0.0, lo_open=True, hi=0.5)]
    ik_samples: Annotated[int, Range(lo=1, hi=1_000_000)]
    id_trajectories: Annotated[Optional[int], Range(lo=1, hi=10_000)] = None
    id_speed: Annotated[float, Range(lo=1.0, lo_open=True, hi=10.0)] = 1.5
    id_declared: Annotated[str, TEXT] = ""


@dataclass(frozen=True, kw_only=True)
class TrueArmSection:
    """``id.measured.true_arm``: how the built arm's links differ from the model (standard
    deviations of the draws, made once from the study's seed) and the payload case."""

    mass_sd: Annotated[float, Range(lo=0.0, hi=1 / 3, hi_open=True)] = 0.0      # relative
    com_sd_m: Annotated[float, Range(lo=0.0, hi=0.1)] = 0.0                     # m, per coordinate
    inertia_sd: Annotated[float, Range(lo=0.0, hi=1 / 3, hi_open=True)] = 0.0   # relative
    payload_kg: Annotated[float, MASS] = 0.0


@dataclass(frozen=True, kw_only=True)
class SensorSection:
    """``id.measured.sensor``: the torque read from the motor current — its count, the torque
    per ampere at the joint, each joint's zero offset (drawn from the study's seed, with the links)."""

    current_per_count_a: Annotated[PerJoint, CURRENT_PER_COUNT]             # A per count of the reading
    torque_constant_nm_a: Annotated[PerJoint, TORQUE_CONSTANT]            # N·m at the joint per A
    offset_sd_nm: Annotated[PerJoint, _DRIVE] = 0.0             # N·m


@dataclass(frozen=True, kw_only=True)
class MeasuredSection:
    """``id.measured``: the "real" arm's drives, friction, sensor noise and encoders."""

    viscous: Annotated[PerJoint, _DRIVE]                    # N·m·s/rad
    coulomb: Annotated[PerJoint, _DRIVE]                    # N·m
    coulomb_velocity_deg_s: Annotated[PerJoint, SPEED_DEG_S]
    armature: Annotated[PerJoint, _DRIVE]                   # kg·m²
    noise_nm: Annotated[PerJoint, _DRIVE]
    stribeck: Optional[Annotated[PerJoint, _DRIVE]] = None
    stribeck_velocity_deg_s: Optional[Annotated[PerJoint, SPEED_DEG_S]] = None
    load_coefficient: Optional[Annotated[PerJoint, Range(lo=0.0, hi=1.0, hi_open=True)]] = None
    encoder_counts: Optional[Annotated[int, Range(lo=16, hi=2 ** 31)]] = None
    filter_window: Annotated[int, Range(lo=5, hi=101)] = 7
    true_arm: Optional[TrueArmSection] = None
    sensor: Optional[SensorSection] = None


@dataclass(frozen=True, kw_only=True)
class IDSection:
    """``id``: the random trajectories and the measured arm."""

    trajectories: Annotated[dict[Split, int], Range(lo=1, hi=1_000_000)]
    via_points: Annotated[int, Range(lo=2, hi=10_000)]
    segment_time_s: Annotated[tuple[float, float], TIME_S, ORDERED]
    dt_s: Annotated[float, TIME_S]
    margin_deg: Annotated[float, Range(lo=0.0)] = 0.0
    max_velocity_deg_s: Annotated[PerJoint, SPEED_DEG_S]
    max_acceleration_deg_s2: Annotated[PerJoint, ACCELERATION_DEG_S2]
    measured: Optional[MeasuredSection] = None


@dataclass(frozen=True, kw_only=True)
class LearnedIKSection:
    """``learned_ik``: the chosen learned IK's functions per input and epochs."""

    n_mfs: Optional[Annotated[Union[int, Annotated[list[int], Length(1, 16)]], N_MFS]] = None
    epochs: Optional[Annotated[Union[int, Annotated[list[int], JOINTS]], Range(lo=1, hi=10_000)]] = None


@dataclass(frozen=True, kw_only=True)
class StudyFile:
    """A study file as written (``params/README.md``, "Studies"): typed and checked field by
    field by :func:`~nfarm.infra.typed.read_typed`; angles in degrees, as in the file."""

    name: str
    description: Annotated[str, TEXT] = ""
    robot_file: str
    seed: Annotated[int, Range(lo=0, hi=2 ** 63 - 1)]
    test_seed: Annotated[int, Range(lo=0, hi=2 ** 63 - 1)]
    ik: IKSection
    id: IDSection
    learned_ik: Optional[LearnedIKSection] = None
    shifted: Optional[ShiftedSection] = None


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


def _per_joint(value: float | list[float], n: int) -> np.ndarray:
    """A :data:`PerJoint` value as ``(n,)`` floats."""
    return np.array([value] * n if isinstance(value, float) else value, dtype=float)


def study_from_dict(data: Any, source: str = "<dict>") -> Study:
    """Validate a study mapping (as read from YAML) and build a :class:`Study`: the robot
    first (the per-joint fields are sized by it), the file into a :class:`StudyFile` by the
    generic reader (every field's type and range), then the rules that involve two fields or
    the robot, section by section; the first broken rule is one :class:`ParamsError` line
    naming the file and the field.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.infra.reading import load_yaml
        >>> data = load_yaml(PARAMS / "studies" / "intelbot5.yaml")
        >>> study = study_from_dict(data, "intelbot5.yaml")
        >>> study.robot.name, study.ik_sizes["train"] > 0, study.id.dt > 0
        ('intelbot5', True, True)
        >>> study.file.id.segment_time_s                     # the file as written, typed
        (0.6, 1.8)
        >>> study_from_dict({**data, "seed": -1}, "intelbot5.yaml")
        Traceback (most recent call last):
        ...
        nfarm.infra.reading.ParamsError: intelbot5.yaml: seed: must be >= 0, got -1
    """
    v = Validator(source)
    v.mapping(data, "", section_keys(StudyFile))
    robot_file = v.string(data["robot_file"], "robot_file")
    try:
        robot = load_robot(project_path(robot_file))
    except ParamsError as exc:
        v.fail("robot_file", f"cannot load the robot: {exc}")
    file = read_typed(StudyFile, data, v, joints=robot.n)
    region = _region(v, file.ik.region, robot, file.seed)
    id_settings = _id_settings(v, file.id, robot)
    _check_work(v, {"ik_sizes": file.ik.sizes, "trajectories": id_settings.trajectories,
                    "via": id_settings.via_points, "segment": id_settings.segment_time,
                    "dt": id_settings.dt, "vmax": id_settings.max_velocity,
                    "amax": id_settings.max_acceleration, "check_targets": file.ik.check.targets,
                    "check_starts": file.ik.check.starts}, robot)
    if file.id.measured is not None:
        id_settings = dataclasses.replace(id_settings, **_measured(v, file.id.measured, robot))
    learned_ik = {} if file.learned_ik is None else \
        {k: x for k, x in dataclasses.asdict(file.learned_ik).items() if x is not None}
    return Study(source=source, name=file.name, robot_file=robot_file, robot=robot, seed=file.seed,
                 test_seed=file.test_seed, ik_region=region, ik_sampler=file.ik.sampler, ik_sizes=file.ik.sizes,
                 ik_full_range=file.ik.full_range, check_targets=file.ik.check.targets,
                 check_starts=file.ik.check.starts, id=id_settings, learned_ik=learned_ik, shifted=file.shifted,
                 params=json.loads(json.dumps(data)), file=file)


def _region(v: Validator, section: RegionSection, robot: Robot, seed: int) -> IKRegion:
    """``ik.region`` in radians: each joint's range within its limits, the reach filter only
    for an arm whose first joint turns about the base z axis, and some pose of the box that
    passes the filters."""
    box = robot.qlim.copy()
    for i, pair in enumerate(section.joints_deg):
        if pair is None:
            continue
        lo, hi = (math.radians(x) for x in pair)
        limits = robot.qlim[i]
        if lo < limits[0] - 1e-12 or hi > limits[1] + 1e-12:
            v.fail(f"ik.region.joints_deg[{i}]", f"must lie within joint {i + 1}'s limits "
                   f"[{math.degrees(limits[0]):.6g}, {math.degrees(limits[1]):.6g}] deg, got {list(pair)}")
        box[i] = (max(lo, limits[0]), min(hi, limits[1]))
    if section.reach_m not in (None, (None, None)) and robot.convention == "modified" and \
            (abs(robot.a[0]) > 1e-12 or abs(math.remainder(robot.alpha[0], 2 * math.pi)) > 1e-12):
        v.fail("ik.region.reach_m", f"needs joint 1 to turn about the base z axis; {robot.name}'s "
                                    f"first joint has a = {robot.a[0]:g} m, alpha = "
                                    f"{math.degrees(robot.alpha[0]):g} deg")
    axis, angle = None, math.pi
    if section.approach is not None:
        axis = np.array(section.approach.axis)
        norm = float(np.linalg.norm(axis))
        if norm == 0:
            v.fail("ik.region.approach.axis", "must not be the zero vector")
        axis, angle = axis / norm, math.radians(section.approach.max_angle_deg)
    unbounded = (None, None)
    region = IKRegion(robot, box, section.radial_m or unbounded, section.height_m or unbounded,
                      axis, angle, section.reach_m or unbounded)
    if region.has_filters:        # 8 192 draws (a few ms): a region no pose of the box reaches
        q_try = region.box[:, 0] + (region.box[:, 1] - region.box[:, 0]) * \
            np.random.default_rng(seed).random((8192, robot.n))
        if not region.contains_pose(fk(robot, q_try), q_try).any():
            v.fail("ik.region", "no pose of 8,192 drawn in the joint box passes its task-space filters "
                                "(radial_m, height_m, reach_m, approach): the arm cannot reach it")
    return region


def _id_settings(v: Validator, section: IDSection, robot: Robot) -> IDSettings:
    """``id`` but its ``measured`` arm, in SI units and radians: the step within the shortest
    segment, the margin within the narrowest joint range."""
    segment = section.segment_time_s
    if section.dt_s > segment[0]:
        v.fail("id.dt_s", f"must be <= {segment[0]:g} (the shortest segment, id.segment_time_s), "
                          f"got {section.dt_s!r}")
    margin = math.radians(section.margin_deg)
    narrowest = float(np.min(robot.qlim[:, 1] - robot.qlim[:, 0]))
    if 2 * margin >= narrowest:
        v.fail("id.margin_deg", f"must leave room inside the narrowest joint range "
                                f"({math.degrees(narrowest):.6g} deg), got {math.degrees(margin):.6g}")
    n = robot.n
    return IDSettings(section.trajectories, section.via_points, segment, section.dt_s, margin,
                      np.radians(_per_joint(section.max_velocity_deg_s, n)),
                      np.radians(_per_joint(section.max_acceleration_deg_s2, n)))


def _measured(v: Validator, section: MeasuredSection, robot: Robot) -> dict[str, Any]:
    """``id.measured`` as the :class:`IDSettings` fields it fills: the robot with the drives,
    the noise, the Stribeck and load terms (breakaway friction at least the Coulomb level,
    with its speed), the encoders and an odd filter window."""
    n = robot.n
    drives = {key: _per_joint(getattr(section, key), n) for key in ("viscous", "coulomb", "armature")}
    drives["coulomb_velocity"] = np.radians(_per_joint(section.coulomb_velocity_deg_s, n))
    friction: dict[str, np.ndarray] = {}
    if section.stribeck is not None:
        friction["stribeck"] = _per_joint(section.stribeck, n)
        low = np.flatnonzero(friction["stribeck"] < drives["coulomb"])
        if low.size:
            v.fail("id.measured.stribeck", f"the breakaway friction must be at least the Coulomb "
                                           f"friction (joint {low[0] + 1}: {friction['stribeck'][low[0]]:g} "
                                           f"< {drives['coulomb'][low[0]]:g} N·m)")
        if section.stribeck_velocity_deg_s is None:
            v.fail("id.measured", "stribeck needs stribeck_velocity_deg_s (> 0)")
    if section.stribeck_velocity_deg_s is not None:
        friction["stribeck_velocity"] = np.radians(_per_joint(section.stribeck_velocity_deg_s, n))
    if section.load_coefficient is not None:
        friction["load_coefficient"] = _per_joint(section.load_coefficient, n)
    if section.filter_window % 2 == 0:
        v.fail("id.measured.filter_window", f"must be an odd number of samples, got {section.filter_window}")
    out: dict[str, Any] = {"measured": dataclasses.replace(robot, **drives),
                           "noise": _per_joint(section.noise_nm, n), "friction": friction,
                           "filter_window": section.filter_window}
    if section.encoder_counts is not None:
        out["encoder_counts"] = section.encoder_counts
    if section.true_arm is not None:
        t = section.true_arm
        out["true_arm"] = TrueArm(mass_sd=t.mass_sd, com_sd=t.com_sd_m, inertia_sd=t.inertia_sd, payload=t.payload_kg)
    if section.sensor is not None:
        out["torque_per_count"] = _per_joint(section.sensor.current_per_count_a, n) * \
            _per_joint(section.sensor.torque_constant_nm_a, n)
        out["offset_sd"] = _per_joint(section.sensor.offset_sd_nm, n)
    return out


#: A smoke study's IK splits at most (:func:`smoke_study`): enough training poses for the smoke runs' rule
#: bases (16 rules of 7 consequents on the first rung's quarter), whatever the study's own sizes.
SMOKE_IK_SIZES = {"train": 400, "val": 100, "test": 200}


def smoke_study(study: Study, factor: int = 50) -> Study:
    """The same study, small for quick runs: its IK splits at most :data:`SMOKE_IK_SIZES`, every
    other size divided by ``factor`` (at least a few samples each); its data sets go to a
    directory of their own (``<robot>-smoke``)."""
    params = json.loads(json.dumps(study.params))
    params["ik"]["sizes"] = {k: min(v, SMOKE_IK_SIZES[k]) for k, v in params["ik"]["sizes"].items()}
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
    check_integer("draw", draw, 0, message=f"draw must be a non-negative integer, got {draw!r}")
    if draw == 0:
        return study
    params = json.loads(json.dumps(study.params))
    params["seed"] = study.seed + int(draw)
    return dataclasses.replace(study_from_dict(params, source=study.source), draw=int(draw))
