"""A new arm from its URDF: the robot file and the study file, with defaults derived from the arm
(``python -m nfarm add-arm PATH.urdf``, ``make arm URDF=…``).

:func:`add_arm` reads the URDF's tree (:func:`nfarm.model.urdf_tree.urdf_outline`), chooses the tip
(the only leaf, or the one asked for), locks the joints off the chain inside their limits (mimic
joints follow their drivers, and must land inside theirs too), converts the chain
(:func:`nfarm.model.urdf_import.from_urdf`, unchanged), and chooses

* the IK region: a joint box inside the limits with the tool in front of the base axis, shrunk
  until every sampled target has one solution in it, counted by
  :func:`nfarm.study.regions.check_single_valued` (the closed form where the arm is of its
  class, else multi-start Levenberg–Marquardt from starts over the full limits);
* named poses inside the limits, and the drive values the URDF gives (``<dynamics damping
  friction>``, ``<limit velocity>``).

Every file is written first into a scratch directory and loaded there by
:func:`~nfarm.model.robot.load_robot` and :func:`~nfarm.study.study_files.load_study`; only then
are they written into the parameter directory: the destination checked before anything is
written (:func:`_check_destination`), each file beside its place first, then all renamed
(:func:`_install`): a refused arm leaves nothing behind. Licence files are copied only as
regular files (not through a symbolic link) of at most :data:`MAX_LICENCE_BYTES`.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import stat
import tempfile
import time
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..infra.paths import PARAMS, shown_path
from ..infra.reading import ParamsError, ParamsWarning, listed, read_bytes
from ..model.kinematics import fk
from ..model.robot import ROBOT_NAME, Robot, load_robot
from ..model.urdf_import import from_urdf
from ..model.urdf_tree import URDFOutline, urdf_outline
from ..solvers.ik import class_refusal
from .regions import IKRegion, SingleValuedness, check_single_valued, stream_rng
from .study_files import load_study

__all__ = ["add_arm", "AddedArm", "JOINTS"]

#: The joints a study's arm has on its chain.
JOINTS = 5
#: Files beside a URDF that carry its licence, copied with it.
LICENCE_NAMES = ("LICENSE", "LICENCE", "COPYING", "NOTICE")
#: The largest licence file copied [bytes]: the longest licence texts are tens of KB (GPL-3.0
#: 35 KB, Apache-2.0 11 KB) and a NOTICE of many third-party notices a few hundred; a file over
#: 1 MiB beside a URDF is no licence (a 3 GiB sparse NOTICE.bin took 45 s to copy).
MAX_LICENCE_BYTES = 1 << 20
#: The narrowest range of a chain joint [deg]: the IK region is written in whole degrees inside
#: the limits less an inset at each end, which leaves no range below about 2.3°.
MIN_RANGE_DEG = 3.0
#: The least share of the region's sampled targets the check must solve (each is the pose of a
#: configuration in the region, so each has a solution): a check that finds no solution for more
#: than 1 % has not checked the region (an arm of absurd geometry), which is then refused rather
#: than declared single-valued.
MIN_SOLVED_SHARE = 0.99
#: The measured arm's drive values when the URDF gives none: a hobby servo's (the SO-101's
#: STS3215, params/studies/so101.yaml).
SERVO = {"viscous": 0.60, "coulomb": 0.052, "armature": 0.028}


@dataclass
class AddedArm:
    """What :func:`add_arm` wrote and why: the files, the robot, the region's check, and the
    lines it prints (``report``)."""

    name: str
    files: list[Path]
    robot: Robot
    region: IKRegion
    check: SingleValuedness
    seconds: float
    report: list[str] = field(default_factory=list)


def _fail(source: str, reason: str):
    raise ParamsError(f"{source}: {reason}")


def _deg(x: float) -> str:
    return f"{math.degrees(x):.6g}"


def _number(x: float) -> str:
    """A number as YAML text that reads back exactly."""
    x = float(x)
    return str(int(x)) if x.is_integer() and abs(x) < 1e15 else repr(x)


def _text(value: str) -> str:
    """A string as YAML text that reads back as itself: JSON's quoting (which is YAML's
    double-quoted style), every character YAML may not hold raw or reads as a line break (C0
    and C1 controls, DEL, U+2028/2029, a BOM, surrogates) escaped."""
    quoted = json.dumps(value, ensure_ascii=False)
    return "".join(c if c.isprintable() or c == " " else
                   f"\\u{ord(c):04x}" if ord(c) <= 0xFFFF else f"\\U{ord(c):08x}" for c in quoted)


def _choose_name(path: Path, name: str | None) -> str:
    given = name if name is not None else path.stem
    if not ROBOT_NAME.fullmatch(given) or ".." in given:
        what = f"--name {given!r}" if name is not None else f"the file's name {given!r} as the robot's"
        _fail(shown_path(path), f"{what} is not a robot name (1-64 letters, digits, '_', '-' or '.', "
                                f"starting with a letter or digit, without '..'){'' if name else ': give --name'}")
    return given


def _choose_tip(outline: URDFOutline, tip: str | None) -> tuple[str, str]:
    if tip is not None:
        if tip not in outline.parent_joint and tip != outline.root:
            _fail(outline.source, f"--tip {tip!r}: no such link (leaves: {listed(outline.leaves)})")
        return tip, "the tip asked for"
    if len(outline.leaves) != 1:
        _fail(outline.source, f"{len(outline.leaves)} leaf links, which is the tip? "
                              f"{listed(outline.leaves)}: give --tip LINK")
    return outline.leaves[0], "the URDF's only leaf link"


def _check_chain(outline: URDFOutline, tip: str) -> list[str]:
    chain = outline.chain(tip)
    moving = [j for j in chain if outline.joints[j].type != "fixed"]
    revolute = [j for j in moving if outline.joints[j].type == "revolute"]
    if len(revolute) != len(moving):
        other = next(j for j in moving if outline.joints[j].type != "revolute")
        _fail(outline.source, f"joint {other!r} on the chain {outline.root} → {tip} is "
                              f"{outline.joints[other].type}: a study's arm is {JOINTS} revolute joints")
    if len(revolute) != JOINTS:
        _fail(outline.source, f"the chain {outline.root} → {tip} has {len(revolute)} revolute joints "
                              f"({listed(revolute) or 'none'}), not {JOINTS}: a study's arm is a "
                              f"{JOINTS}-joint chain")
    return chain


def _mimic_positions(outline: URDFOutline, lock: Mapping[str, float]) -> dict[str, float]:
    """Every joint off the chain that moves: its lock, or its driver's position through its
    ``<mimic>`` (drivers with no lock at 0), as :func:`nfarm.model.urdf_import.from_urdf` places it."""
    out = dict(lock)
    joints = outline.joints

    def position(jname: str) -> None:
        # The recursion "a mimic's position is its driver's, scaled" unrolled onto a stack: a
        # chain of thousands of mimic joints is no RecursionError. A driver met again (a loop)
        # or missing counts as 0, as from_urdf refuses such files anyway.
        stack, seen = [jname], set()
        while True:
            current = stack[-1]
            if current in out:
                value = out[current]
                stack.pop()
                break
            mimic = joints[current].mimic
            if mimic is None or mimic[0] in seen or mimic[0] not in joints:
                value = 0.0
                stack.pop()
                break
            seen.add(current)
            stack.append(mimic[0])
        for follower in reversed(stack):
            _, multiplier, offset = joints[follower].mimic
            value = multiplier * value + offset
            out[follower] = value

    for jname in joints:
        if joints[jname].mimic is not None:
            position(jname)
    return out


def _outside(outline: URDFOutline, positions: Mapping[str, float]) -> tuple[str, float] | None:
    """The first joint whose position lies outside its limits, or None."""
    for jname, value in positions.items():
        limits = outline.joints[jname].limits
        if limits is not None and not limits[0] - 1e-12 <= value <= limits[1] + 1e-12:
            return jname, value
    return None


def _choose_locks(outline: URDFOutline, chain: list[str], asked: Mapping[str, float]
                  ) -> tuple[dict[str, float], list[str]]:
    """The lock of every moving joint off the chain (not a mimic): the one asked for, checked,
    else 0 within its limits (else the nearest limit), so that every mimic joint lands inside
    its limits too; and why, one line each."""
    src = outline.source
    side = [j for j, joint in outline.joints.items()
            if joint.type != "fixed" and j not in chain and joint.mimic is None]
    for jname, value in asked.items():
        at = f"--lock {jname}={value:g}"
        if jname not in outline.joints:
            _fail(src, f"{at}: no joint {jname!r} (joints off the chain: {listed(side) or 'none'})")
        if jname in chain:
            _fail(src, f"{at}: {jname!r} is on the chain to the tip; only joints off it are locked")
        joint = outline.joints[jname]
        if joint.type == "fixed":
            _fail(src, f"{at}: {jname!r} is a fixed joint: nothing to lock")
        if joint.mimic is not None:
            _fail(src, f"{at}: {jname!r} mimics {joint.mimic[0]!r}: lock that joint instead")
        if not math.isfinite(value):
            _fail(src, f"{at}: not a finite number")
        if joint.limits is not None and not joint.limits[0] <= value <= joint.limits[1]:
            _fail(src, f"{at}: outside the joint's limits [{joint.limits[0]:g}, {joint.limits[1]:g}]")
    lock, why = {}, []
    for jname in side:
        joint = outline.joints[jname]
        unit = "m" if joint.type == "prismatic" else "rad"
        if jname in asked:
            lock[jname] = float(asked[jname])
            why.append(f"{jname} = {lock[jname]:g} {unit} (asked for)")
            continue
        lo, hi = joint.limits if joint.limits is not None else (-math.inf, math.inf)
        followers = [j for j, other in outline.joints.items() if other.mimic and other.mimic[0] == jname]
        for value, reason in ((min(max(0.0, lo), hi), "0, or the limit nearest it"),
                              (lo, "its lower limit"), (hi, "its upper limit"),
                              ((lo + hi) / 2, "the middle of its range")):
            if not math.isfinite(value):
                continue
            if _outside(outline, {k: x for k, x in _mimic_positions(outline, {**lock, jname: value}).items()
                                  if k in followers}) is None:
                break
        else:
            _fail(src, f"joint {jname!r}: no lock within its limits puts the joints that mimic it "
                       f"({listed(followers)}) within theirs: give --lock {jname}=VALUE")
        lock[jname] = float(value)
        mimics = f"; {', '.join(followers)} follow{'s' if len(followers) == 1 else ''} it (mimic)" if followers else ""
        why.append(f"{jname} = {value:g} {unit} ({reason}, limits [{lo:g}, {hi:g}]{mimics})")
    bad = _outside(outline, _mimic_positions(outline, lock))
    if bad is not None:
        limits = outline.joints[bad[0]].limits
        _fail(src, f"--lock: joint {bad[0]!r} (mimic of {outline.joints[bad[0]].mimic[0]!r}) would sit at "
                   f"{bad[1]:g}, outside its limits [{limits[0]:g}, {limits[1]:g}]")
    return lock, why


# -- the IK region ------------------------------------------------------------------------------


def _front(robot: Robot, box: np.ndarray, seed: int) -> tuple[float, float, str]:
    """The sign of "in front" (the side of the base axis the arm reaches to on average over its
    joint box, measured along the direction joint 1 faces; along it when the mean is within 5 %
    of the farthest reach) and the reach bound's size: a fifth of the farthest reach (99th
    percentile), in whole centimetres, at least 1 cm; and why."""
    q = box[:, 0] + (box[:, 1] - box[:, 0]) * stream_rng(seed, 90).random((20_000, robot.n))
    p = fk(robot, q)[:, :3, 3]
    B = robot.base
    p0 = (p - B[:3, 3]) @ B[:3, :3]
    theta1 = q[:, 0] + robot.offset[0]
    reach = p0[:, 0] * np.cos(theta1) + p0[:, 1] * np.sin(theta1)
    far = float(np.percentile(np.hypot(p0[:, 0], p0[:, 1]), 99))
    bound = max(0.01, round(0.2 * far, 2))
    lean = float(np.mean(reach))
    sign = -1.0 if lean < -0.05 * far else 1.0
    if abs(lean) <= 0.05 * far:
        why = ("the arm reaches as far either way over its joint box: in front taken along the "
               "direction joint 1 faces")
    elif sign > 0:
        why = "the arm reaches mostly along the direction joint 1 faces"
    else:
        why = ("the arm reaches mostly against the direction joint 1 faces (the converter's "
               "frame 0 looks backwards): in front is negative reach")
    return sign, bound, why


def _region(robot: Robot, box: np.ndarray, sign: float, bound: float) -> IKRegion:
    reach = (bound, None) if sign > 0 else (None, -bound)
    return IKRegion(robot, box, reach=reach)


def _cut(box: np.ndarray, qlim: np.ndarray, check: SingleValuedness, margin: float
         ) -> tuple[np.ndarray, str] | None:
    """The box cut at one joint between the targets' configurations and their second
    solutions (the median of their midpoints, less a margin), on the side that keeps most
    targets free of a second solution (then the wider side): the cut and why; None when no cut
    leaves a joint range of 10° or more."""
    bad = check.offenders
    q, q2 = check.q[bad], check.q_second[bad]
    best = None
    for k in range(box.shape[0]):
        gap = np.abs(q[:, k] - q2[:, k])
        if np.median(gap) < 1e-3:
            continue
        c = float(np.median((q[:, k] + q2[:, k]) / 2))
        for side in ("low", "high"):
            new = box.copy()
            if side == "low":
                new[k, 1] = c - margin
            else:
                new[k, 0] = c + margin
            if new[k, 1] - new[k, 0] < math.radians(10):
                continue
            inside = lambda x: ((x >= new[:, 0]) & (x <= new[:, 1])).all(axis=1)   # noqa: E731
            left = int(np.sum(inside(q) & inside(q2)))
            score = (left, -(new[k, 1] - new[k, 0]) / (qlim[k, 1] - qlim[k, 0]))
            if best is None or score < best[0]:
                edge = math.degrees(new[k, 1] if side == "low" else new[k, 0])
                why = (f"q{k + 1} {'≤' if side == 'low' else '≥'} {edge:.1f}°: {len(bad)} of "
                       f"{len(check.q)} targets had a second solution in the region across "
                       f"q{k + 1} ≈ {math.degrees(c):.1f}° (cut 5° from it, keeping the side with more "
                       f"targets single-valued)")
                best = (score, new, why)
    return None if best is None else (best[1], best[2])


def choose_region(robot: Robot, *, targets: int, starts: int, seed: int = 0, rounds: int = 8
                  ) -> tuple[IKRegion, SingleValuedness, list[str]]:
    """A single-valued IK region of ``robot``: the joint limits less 5° (or 5 % of the range)
    at each end, the tool in front of the base axis (:func:`_front`), then cut at one joint
    at a time (:func:`_cut`) until :func:`check_single_valued` finds no target with a second
    solution in it; the region, the last check and why, one line each.

    Raises:
        ValueError: no such region within ``rounds`` cuts.
    """
    qlim = robot.qlim
    inset = np.minimum(math.radians(5), 0.05 * (qlim[:, 1] - qlim[:, 0]))
    box = np.column_stack([qlim[:, 0] + inset, qlim[:, 1] - inset])
    box = np.radians(np.column_stack([np.ceil(np.degrees(box[:, 0])), np.floor(np.degrees(box[:, 1]))]))
    sign, bound, why_front = _front(robot, box, seed)
    why = [f"joint box: the limits less {', '.join(f'{math.degrees(x):.3g}' for x in inset)}° at each end",
           f"tool in front of the base axis: reach {'≥' if sign > 0 else '≤'} {sign * bound:g} m "
           f"(a fifth of the farthest reach; {why_front})"]
    for _ in range(rounds + 1):
        region = _region(robot, box, sign, bound)
        check = check_single_valued(region, targets, starts, seed=seed)
        if not check.second.any():
            return region, check, why
        cut = _cut(box, qlim, check, math.radians(5))
        if cut is None:
            break
        box, reason = cut
        box = np.radians(np.column_stack([np.ceil(np.degrees(box[:, 0]) - 1e-9),
                                          np.floor(np.degrees(box[:, 1]) + 1e-9)]))
        why.append(f"cut: {reason}")
    raise ValueError(f"no single-valued region found: {int(check.second.sum())} of {targets} targets "
                     f"still have a second solution in {np.degrees(box).round(0).tolist()} deg")


# -- poses and drives ---------------------------------------------------------------------------


def _inside_deg(robot: Robot, q_deg: np.ndarray) -> list[float]:
    """Whole degrees within the limits (rounded inwards at a limit)."""
    lo = np.ceil(np.degrees(robot.qlim[:, 0]) - 1e-9)
    hi = np.floor(np.degrees(robot.qlim[:, 1]) + 1e-9)
    return [float(x) for x in np.clip(np.round(q_deg), lo, hi)]


def _poses(robot: Robot, region: IKRegion) -> tuple[dict[str, list[float]], str]:
    zero_inside = bool(np.all((robot.qlim[:, 0] <= 0) & (robot.qlim[:, 1] >= 0)))
    home = np.zeros(robot.n) if zero_inside else np.degrees(robot.qlim.mean(axis=1))
    home_name = "home (q = 0)" if zero_inside else "home (the middle of every range)"
    middle = np.degrees(region.box.mean(axis=1))
    turned = home.copy()
    turned[0] -= 45
    turned[-1] += 45
    bent = np.degrees(robot.qlim[:, 0] + 0.3 * (robot.qlim[:, 1] - robot.qlim[:, 0]))
    bent[0], bent[-1] = home[0], home[-1]
    poses = {home_name: _inside_deg(robot, home),
             "the IK region's middle": _inside_deg(robot, middle),
             "base turned −45°, wrist rolled 45°": _inside_deg(robot, turned),
             "joints 2 to 4 at 30 % of their ranges": _inside_deg(robot, bent)}
    return poses, home_name


def _one_or_list(values: list[float]) -> str:
    if all(v == values[0] for v in values):
        return _number(values[0])
    return "[" + ", ".join(_number(v) for v in values) + "]"


# -- the files ----------------------------------------------------------------------------------


def _robot_text(name: str, urdf_name: str, tip: str, lock: Mapping[str, float], robot: Robot,
                drive: dict[str, list[float]], poses: dict[str, list[float]], source: str) -> str:
    shown_source = "".join(c if c.isprintable() else "?" for c in source)     # a comment is one line
    lines = [f"# {name}: made by `python -m nfarm add-arm {shown_source}` from its URDF (in {name}/, unchanged);",
             "# every value below was chosen by add-arm and may be edited (params/README.md, \"Robots from a URDF\").",
             f"name: {name}",
             f"urdf: {_text(f'{name}/{urdf_name}')}",
             f"tip: {_text(tip)}",
             "lock: {" + ", ".join(f"{_text(k)}: {_number(v)}" for k, v in lock.items()) + "}",
             f"description: {_text(f'{name}: five joints from its URDF ({urdf_name}), chain to {tip}')}"]
    if drive:
        lines += ["# The joints' drives, from the URDF's <dynamics damping friction> (used only where asked,",
                  "# rnea(drive=True)).",
                  "drive:"]
        lines += [f"  {key}: {_one_or_list(values)}" for key, values in drive.items()]
    lines += ["# Named configurations a reader is shown (chapter 01) [deg], one angle per joint, within the",
              "# limits; not model parameters. Rename them for what the arm does there.",
              "poses_deg:"]
    lines += [f"  {_text(k)}: [{', '.join(_number(x) for x in q)}]" for k, q in poses.items()]
    return "\n".join(lines) + "\n"


def _study_text(name: str, robot_file: str, robot: Robot, region: IKRegion, check: SingleValuedness,
                measured: dict[str, list[float]], measured_from: str, velocity_deg_s: list[float]) -> str:
    reach = region.reach
    reach_text = f"[{_number(reach[0])}, null]" if reach[0] is not None else f"[null, {_number(reach[1])}]"
    narrowest = float(np.degrees(np.min(robot.qlim[:, 1] - robot.qlim[:, 0])))
    margin = min(5.0, math.floor(narrowest / 4))
    how = ("the closed form (every solution)" if check.method == "closed form"
           else f"LM from {check.starts} starts over the full limits")
    lines = [f"# The study of {name}, made by `python -m nfarm add-arm`; schema: params/README.md (\"Studies\").",
             "# Angles in degrees (_deg), lengths in metres (_m), times in seconds (_s).",
             f"name: {_text(name + ' study')}",
             f"description: {_text(f'Chapter 05-07 data for {name}: one IK branch chosen by add-arm (a joint box inside the limits, tool in front of the base axis)')}",
             f"robot_file: {_text(robot_file)}",
             "seed: 0",
             "# The test split's own seed: once every choice is made on validation data, change it to",
             "# draw a fresh held-out set for the final numbers (docs/STUDY.md, \"Data\").",
             "test_seed: 1",
             "ik:",
             "  region:",
             f"    # Single-valued on {len(check.q)} targets by {how}: add-arm cut the box until no",
             "    # target had a second solution in it. Edit, then check with chapter 05.",
             "    joints_deg:"]
    lines += [f"      - [{_number(round(math.degrees(lo)))}, {_number(round(math.degrees(hi)))}]"
              for lo, hi in region.box]
    lines += [f"    reach_m: {reach_text}       # the tool point in front of the base axis",
              "  sampler: sobol",
              "  sizes: {train: 5000, val: 2000, test: 5000}",      # the shipped arms' (issue 63: the clean build's budget)
              "  check: {targets: 2000, starts: 24}",
              "  full_range: true",
              "id:",
              "  trajectories: {train: 160, val: 20, test: 40}",
              "  via_points: 8",
              "  segment_time_s: [0.6, 1.8]",
              "  dt_s: 0.02",
              f"  margin_deg: {_number(margin)}",
              f"  max_velocity_deg_s: {_one_or_list(velocity_deg_s)}",
              "  max_acceleration_deg_s2: 400",
              f"  # The \"real\" arm whose joint sensors chapter 05 records: {measured_from}.",
              "  measured:"]
    lines += [f"    {key}: {_one_or_list(values)}" for key, values in measured.items()]
    lines += ["    coulomb_velocity_deg_s: 3",
              "    noise_nm: 0.005",
              "    encoder_counts: 4096",
              "    filter_window: 9"]
    return "\n".join(lines) + "\n"


def _licences(urdf: Path) -> tuple[list[tuple[str, bytes]], list[str]]:
    """The licence files beside the URDF (:data:`LICENCE_NAMES`) to copy, ``(name, bytes)``, and
    why the others are not copied, one line each: only a regular file (not a symlink, whose
    target may be any file of the machine; opened with ``O_NOFOLLOW``) of at most
    :data:`MAX_LICENCE_BYTES` is copied."""
    copies, skipped = [], []
    try:
        entries = sorted(os.scandir(urdf.parent), key=lambda e: e.name)
    except OSError:
        return [], []
    for entry in entries:
        if entry.name.upper().split(".")[0] not in LICENCE_NAMES:
            continue
        shown = shown_path(Path(urdf.parent, entry.name))
        try:
            fd = os.open(entry.path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
        except OSError as exc:
            why = "a symbolic link" if entry.is_symlink() else exc.strerror or type(exc).__name__
            skipped.append(f"{shown} ({why}: only a regular file beside the URDF is copied)")
            continue
        with os.fdopen(fd, "rb") as f:
            info = os.fstat(f.fileno())
            if not stat.S_ISREG(info.st_mode):
                skipped.append(f"{shown} (not a regular file: only a regular file beside the URDF is copied)")
                continue
            if info.st_size > MAX_LICENCE_BYTES:
                skipped.append(f"{shown} ({info.st_size:,} bytes, over the {MAX_LICENCE_BYTES:,}-byte limit of "
                               f"a licence file: not a licence text; copy it by hand if it is one)")
                continue
            data = f.read(MAX_LICENCE_BYTES + 1)
        if len(data) > MAX_LICENCE_BYTES:          # grew since fstat
            skipped.append(f"{shown} (over the {MAX_LICENCE_BYTES:,}-byte limit of a licence file)")
            continue
        copies.append((entry.name, data))
    return copies, skipped


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _check_destination(params: Path, name: str, src: str) -> None:
    """Everything :func:`_install` will write can be written, checked before anything is: the
    parameter directory and its ``robots/``, ``studies/`` and ``robots/<name>/`` are
    directories (or do not exist yet, under a writable one), and no file to write is a
    directory; else one line naming the path."""
    wanted_dirs = [params, params / "robots", params / "studies", params / "robots" / name]
    for directory in wanted_dirs:
        if directory.is_symlink() and not directory.is_dir():
            _fail(shown_path(directory), "is a broken symbolic link, not a directory: add-arm writes there")
        if directory.exists() and not directory.is_dir():
            _fail(shown_path(directory), "exists and is not a directory: add-arm writes there")
    for path in (params / "robots" / f"{name}.yaml", params / "studies" / f"{name}.yaml"):
        if path.is_dir():
            _fail(shown_path(path), "is a directory: add-arm would write the file there (remove it first)")
    for directory in wanted_dirs:
        existing = next(p for p in (directory, *directory.parents) if p.exists())
        if not existing.is_dir():
            _fail(shown_path(existing), "is not a directory: add-arm writes under it")
        if not os.access(existing, os.W_OK | os.X_OK):
            _fail(shown_path(existing), "cannot be written (no permission): add-arm writes there")


def _install(params: Path, outputs: list[tuple[Path, bytes]], src: str) -> list[Path]:
    """Write every ``(path, bytes)`` of ``outputs`` as one step: each first to a temporary file
    beside it, then all renamed into place; a failure anywhere (a full disk, a directory that
    changed under us) removes every temporary file and directory made, puts back the files
    replaced, and is one line. The destination was checked before (:func:`_check_destination`)."""
    made_dirs: list[Path] = []
    staged: list[tuple[Path, Path]] = []
    replaced: list[tuple[Path, bytes | None]] = []
    try:
        for path, data in outputs:
            missing = [p for p in (path.parent, *path.parent.parents) if not p.exists()]
            for directory in reversed(missing):
                directory.mkdir()
                made_dirs.append(directory)
            fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp", dir=path.parent)
            staged.append((Path(tmp), path))
            with os.fdopen(fd, "wb") as f:
                f.write(data)
            os.chmod(tmp, 0o644)
        for tmp, path in staged:
            old = path.read_bytes() if path.is_file() and not path.is_symlink() else None
            os.replace(tmp, path)
            replaced.append((path, old))
    except OSError as exc:
        for path, old in reversed(replaced):
            try:
                if old is None:
                    path.unlink(missing_ok=True)
                else:
                    path.write_bytes(old)
            except OSError:
                pass
        for tmp, _ in staged:
            tmp.unlink(missing_ok=True)
        for directory in reversed(made_dirs):
            try:
                directory.rmdir()
            except OSError:
                pass
        where = shown_path(exc.filename) if exc.filename else shown_path(params)
        _fail(where, f"cannot be written ({exc.strerror or type(exc).__name__}): nothing was added")
    return [path for _, path in staged]


def _existing(params: Path, name: str) -> Path | None:
    for path in (params / "robots" / f"{name}.yaml", params / "studies" / f"{name}.yaml",
                 params / "robots" / name):
        if path.exists():
            return path
    return None


def add_arm(urdf: str | Path, *, name: str | None = None, tip: str | None = None,
            lock: Mapping[str, float] | None = None, params: str | Path = PARAMS, force: bool = False,
            targets: int = 2000, starts: int = 24, seed: int = 0,
            say: Callable[[str], None] | None = None) -> AddedArm:
    """Add the arm of ``urdf`` to the parameter directory ``params``: ``robots/<name>/`` (the
    URDF and a licence file beside it), ``robots/<name>.yaml`` and ``studies/<name>.yaml``
    (module docstring). ``targets`` and ``starts`` size the region's check (the closed form
    ignores ``starts``). ``say`` receives the report's lines as they come.

    Raises:
        ParamsError: one line naming the file and the reason: a name that is not a robot name
            or already exists (unless ``force``), a chain that is not five revolute joints from
            the root to the tip, several leaves and no ``tip``, a lock outside its joint's
            limits, a URDF :func:`~nfarm.model.urdf_import.from_urdf` refuses, no single-valued region.
    """
    started = time.perf_counter()
    say = say or (lambda line: None)
    report: list[str] = []

    def tell(line: str) -> None:
        report.append(line)
        say(line)

    urdf = Path(urdf)
    params = Path(params)
    src = shown_path(urdf)
    if urdf.suffix.lower() != ".urdf":
        _fail(src, "not a .urdf file")
    if not urdf.is_file():
        _fail(src, "no such file")
    name = _choose_name(urdf, name)
    if not force and (existing := _existing(params, name)) is not None:
        _fail(shown_path(existing), f"exists: robot {name!r} is already there; choose another --name "
                                    f"or pass --force to replace it")
    _check_destination(params, name, src)
    outline = urdf_outline(urdf)
    outline_digest = _digest(read_bytes(urdf, what="URDF"))
    tip, tip_why = _choose_tip(outline, tip)
    chain = _check_chain(outline, tip)
    lock, lock_why = _choose_locks(outline, chain, dict(lock or {}))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ParamsWarning)
        robot = from_urdf(urdf, tip=tip, lock=lock, name=name)
    notes = [str(w.message) for w in caught if issubclass(w.category, ParamsWarning)]
    revolute = [j for j in chain if outline.joints[j].type == "revolute"]
    tell(f"{name}: {src}, chain {outline.root} → {tip} ({tip_why}): joints {', '.join(revolute)}")
    for note in notes:
        tell(f"  warning: {note}")
    tell("  limits [deg]: " + "; ".join(f"{j} {_deg(lo)}…{_deg(hi)}" for j, (lo, hi) in zip(revolute, robot.qlim)))
    tell("  locks: " + ("; ".join(lock_why) if lock_why else "none (no moving joint off the chain)"))

    for j, (lo, hi) in zip(revolute, robot.qlim):
        if math.degrees(hi - lo) < MIN_RANGE_DEG:
            _fail(src, f"joint {j!r}: its limits span {math.degrees(hi - lo):.3g}°, under the {MIN_RANGE_DEG:g}° "
                       f"a study's IK region needs (written in whole degrees inside them): widen them, or make "
                       f"the joint fixed in the URDF")
    refusal = class_refusal(robot)
    if refusal is None:
        method = f"the closed form (every solution) on {targets} targets"
    else:
        method = f"LM from {starts} starts over the full limits on each of {targets} targets"
    try:
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)     # judged below by what was solved
            region, check, region_why = choose_region(robot, targets=targets, starts=starts, seed=seed)
    except ValueError as exc:
        _fail(src, f"IK region: {exc} (counted by {method}); write ik.region by hand")
    solved = int(np.sum(np.asarray(check.solved) > 0))
    if solved < MIN_SOLVED_SHARE * len(check.q):
        _fail(src, f"IK region: {method} solved {solved} of {len(check.q)} targets (each the pose of a "
                   f"configuration in the region, so each has a solution; at least "
                   f"{MIN_SOLVED_SHARE:.0%} must be solved): the region was not checked, so it is not "
                   f"declared single-valued; check the URDF's geometry, or write ik.region by hand")
    tell(f"  IK region, checked by {method}"
         + ("" if refusal is None else f" (outside the closed form's class: {refusal})") + ":")
    for line in region_why:
        tell(f"    {line}")
    solutions = np.bincount(check.solutions)
    tell(f"    → joints_deg {[[round(math.degrees(lo)), round(math.degrees(hi))] for lo, hi in region.box]}: "
         f"{len(check.q)} sampled targets, none with a second solution in the region "
         f"(solutions within the full limits: "
         + ", ".join(f"{k}: {c}" for k, c in enumerate(solutions) if c) + ")")

    drive = {}
    for urdf_key, key in (("damping", "viscous"), ("friction", "coulomb")):
        values = [getattr(outline.joints[j], urdf_key) for j in revolute]
        if any(values):
            drive[key] = values
    velocity = [outline.joints[j].velocity for j in revolute]
    velocity_deg_s = [(min(120.0, math.floor(math.degrees(v))) if math.degrees(v) >= 1
                       else float(f"{math.degrees(v):.3g}")) if v > 0 else 120.0 for v in velocity]
    if drive:
        measured = {**{k: drive.get(k, [0.0] * JOINTS) for k in ("viscous", "coulomb")}, "armature": [0.0]}
        measured_from = "the URDF's <dynamics> (no armature given: 0)"
    else:
        measured = {k: [v] for k, v in SERVO.items()}
        measured_from = "the URDF gives no <dynamics>: a hobby servo's values (the SO-101's STS3215); edit them"
    tell("  drive: " + ("; ".join(f"{k} {_one_or_list(v)}" for k, v in drive.items()) + " (the URDF's <dynamics>)"
                        if drive else "none in the URDF (no <dynamics>): the robot file has no drive terms")
         + f"; trajectory speed limit {_one_or_list(velocity_deg_s)} deg/s"
         + (" (the URDF's <limit velocity>, at most 120)" if any(v > 0 for v in velocity) else ""))

    poses, home = _poses(robot, region)
    tell(f"  poses_deg: {', '.join(poses)} (whole degrees within the limits)")

    robot_file_final = params / "robots" / f"{name}.yaml"
    study_final = params / "studies" / f"{name}.yaml"
    urdf_bytes = read_bytes(urdf, what="URDF")       # the bytes converted above are the bytes copied
    if _digest(urdf_bytes) != outline_digest:
        _fail(src, "changed while add-arm read it: run add-arm again")
    licences, skipped = _licences(urdf)
    for line in skipped:
        tell(f"  not copied: {line}")
    copies = [(urdf.name, urdf_bytes), *licences]
    with tempfile.TemporaryDirectory(prefix="nfarm-add-arm-") as scratch:
        scratch = Path(scratch)
        (scratch / "robots" / name).mkdir(parents=True)
        (scratch / "studies").mkdir()
        for file_name, data in copies:
            (scratch / "robots" / name / file_name).write_bytes(data)
        robot_text = _robot_text(name, urdf.name, tip, lock, robot, drive, poses, src)
        (scratch / "robots" / f"{name}.yaml").write_text(robot_text, encoding="utf-8")
        study_args = (name, robot, region, check, measured, measured_from, velocity_deg_s)
        scratch_study = _study_text(study_args[0], str(scratch / "robots" / f"{name}.yaml"), *study_args[1:])
        (scratch / "studies" / f"{name}.yaml").write_text(scratch_study, encoding="utf-8")
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ParamsWarning)       # told above
                loaded = load_robot(scratch / "robots" / f"{name}.yaml")
                load_study(scratch / "studies" / f"{name}.yaml")
        except ParamsError as exc:      # a rule of the study's (its work bound, say): nothing is written
            reason = str(exc).splitlines()[0].replace(str(scratch), shown_path(params))
            raise ParamsError(f"{src}: the files add-arm would write are refused: {reason}; edit the URDF "
                              f"(its limits) or write them by hand") from None
    study_text = _study_text(study_args[0], shown_path(robot_file_final), *study_args[1:])
    outputs = [(params / "robots" / name / file_name, data) for file_name, data in copies]
    outputs += [(robot_file_final, robot_text.encode("utf-8")), (study_final, study_text.encode("utf-8"))]
    files = _install(params, outputs, src)
    tell("  wrote " + ", ".join(shown_path(f) for f in files))
    tell(f"  edit: the poses' names; ik.region (then chapter 05 checks it); id.measured (the sensed arm's "
         f"drives{'' if drive else ', a hobby servo here'}); height_m: [z, null] keeps the tool above a table; "
         f"meshes are not copied (nfarm does not read them)")
    return AddedArm(name, files, loaded, region, check,
                    time.perf_counter() - started, report)
