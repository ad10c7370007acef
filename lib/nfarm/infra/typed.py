"""Parameter files read into dataclasses by their type annotations: one generic loader for
every section of a file, as Drake's ``yaml_load_typed`` reads the ``Scenario`` of Tedrake's
*manipulation* course. A section is a frozen dataclass whose fields are the file's keys; a field
with a default may be left out, one without is required, and a key that is no field is refused
(with the closest field's name as a hint). Every broken rule is one
:class:`~nfarm.infra.reading.ParamsError` line naming the file, the field and the rule, from
:class:`~nfarm.infra.reading.Validator`.

Annotations read:

================================  ============================================================
``str``, ``int``, ``float``,      one value of that kind (a truth value is no number; an
``bool``                          ``int`` may be given for a ``float``, read as a float)
``Literal["a", "b"]``             one of the texts
``X | None``                      ``null`` is allowed, read as ``None``
``X | list[X]``                   one value, or a list of them (chosen by the value)
``tuple[X, Y]``                   a list of exactly those items, read as a tuple
``list[X]``                       a list of any length (see :class:`Length`, :data:`JOINTS`)
``dict[Literal["a", "b"], X]``    a mapping with exactly those keys, each an ``X``
a dataclass                       a nested section
================================  ============================================================

Rules ride on ``typing.Annotated``: :class:`Range` bounds every number under it (an annotation
on a list or a mapping bounds its items), :class:`Length` and :data:`JOINTS` (one item per
joint of the robot the reader is given) the length of the list it annotates, :data:`ORDERED`
a pair ``[lo, hi]`` (``lo < hi`` where both are given), :data:`TEXT` a string that may be empty.
:class:`ReadBy` hands a field to a reader of its own (a pose, an inertia: a value whose rule no
annotation says), in its place in the file's order. Rules that involve two fields or the robot's
model are the caller's, after the read.

Example:
    >>> from dataclasses import dataclass
    >>> from typing import Annotated, Literal
    >>> @dataclass(frozen=True, kw_only=True)
    ... class Sizes:
    ...     split: dict[Literal["train", "test"], Annotated[int, Range(lo=1)]]
    ...     sampler: Literal["sobol", "uniform"] = "sobol"
    ...     speed_deg_s: Annotated[float | list[float], Range(lo=0, lo_open=True), JOINTS]
    >>> read_typed(Sizes, {"split": {"train": 8, "test": 2}, "speed_deg_s": 90}, "s.yaml", joints=5)
    Sizes(split={'train': 8, 'test': 2}, sampler='sobol', speed_deg_s=90.0)
    >>> read_typed(Sizes, {"split": {"train": 8, "test": 2}, "speed_deg_s": [90, -1, 0, 1, 1]},
    ...            "s.yaml", joints=5)
    Traceback (most recent call last):
    ...
    nfarm.infra.reading.ParamsError: s.yaml: speed_deg_s[1]: must be > 0, got -1.0
    >>> read_typed(Sizes, {"split": {"train": 8}, "speed_deg_s": 90, "samplr": "x"}, "s.yaml", joints=5)
    Traceback (most recent call last):
    ...
    nfarm.infra.reading.ParamsError: s.yaml: samplr: unknown field (did you mean 'sampler'?)
"""

from __future__ import annotations

import dataclasses
import functools
import math
import re
import types
import typing
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Annotated, Any, Literal, Union

from .reading import ParamsError, Validator, show

__all__ = ["read_typed", "Range", "Length", "JOINTS", "ORDERED", "TEXT", "ReadBy", "section_keys",
           "MASS", "INERTIA", "GRAVITY", "LENGTH", "ANGLE", "VELOCITY", "EFFORT", "DRIVE", "SPEED_DEG_S",
           "ACCELERATION_DEG_S2", "TIME_S", "CURRENT_PER_COUNT", "TORQUE_CONSTANT", "EPOCHS", "N_MFS", "N_RULES",
           "ITERATIONS", "COUNT", "CELL_TIMEOUT_S", "PORT", "parse_number"]


@dataclass(frozen=True)
class Range:
    """Every number under the annotation lies in ``[lo, hi]`` (``lo < x`` with ``lo_open``,
    ``x < hi`` with ``hi_open``); ``None``: no bound. ``unit`` follows a bound in the message
    and ``why`` (the reason for the bound) ends it: the plausibility bounds below carry both.

    Example:
        >>> v = Validator("r.yaml")
        >>> MASS.check(v, 2.5, "joints[0].mass")
        2.5
        >>> MASS.check(v, 1e308, "joints[0].mass")
        Traceback (most recent call last):
        ...
        nfarm.infra.reading.ParamsError: r.yaml: joints[0].mass: must be <= 10000 kg, got 1e+308 (heavier than any arm's link: grams by mistake?)
    """

    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    unit: str = ""
    why: str = ""
    floor: float | None = None
    why_floor: str = ""

    def check(self, v: Validator, value: Any, at: str, *, integer: bool = False) -> Any:
        """``value`` as a finite number (a whole number with ``integer``) within the range, or
        one line through ``v`` naming ``at`` and the rule: below ``lo`` (the physical bound,
        such as a mass's 0) as any range says it; below ``floor`` (the least plausible value of
        a quantity that is positive, such as a speed) or beyond ``hi``, with the unit and the
        reason (``why_floor``, ``why``)."""
        if integer:
            x = v.integer(value, at)
        else:
            x = v.number(value, at)
        unit = f" {self.unit}" if self.unit else ""
        got = x if integer else repr(x)
        if self.lo is not None and (x <= self.lo if self.lo_open else x < self.lo):
            v.fail(at, f"must be {'>' if self.lo_open else '>='} {self.lo:g}, got {got}")
        if self.floor is not None and x < self.floor:
            v.fail(at, f"must be >= {self.floor:g}{unit}, got {got}"
                       + (f" ({self.why_floor})" if self.why_floor else ""))
        why = f" ({self.why})" if self.why else ""
        if self.hi is not None and (x >= self.hi if self.hi_open else x > self.hi):
            shown_x = got if not integer or abs(x) < 10 ** 15 else f"{float(x):.3g}"
            v.fail(at, f"must be {'<' if self.hi_open else '<='} {self.hi:g}{unit}, got {shown_x}{why}")
        return x


# --------------------------------------------------------------------------------------------
# Plausibility bounds: one per quantity, each with its unit and its reason. A value beyond one is
# a unit slip, a typo or a hostile file, never an arm; the bounds keep every later computation
# finite (no overflow, no division by a subnormal). Every reader of that quantity uses the same
# constant: robot files, URDFs, study files, sweep files.

#: A link's mass [kg]: 10 t is heavier than the links of any arm (an industrial arm's are < 1 t).
MASS = Range(lo=0.0, hi=1e4, unit="kg", why="heavier than any arm's link: grams by mistake?")
#: A moment or product of inertia [kg·m²]: a 10 t body 1 m from its centre is 1e4 kg·m².
INERTIA = Range(floor=-1e4, hi=1e4, unit="kg·m²", why="beyond a 10 t link 1 m long: g·mm² by mistake?",
                why_floor="beyond a 10 t link 1 m long: g·mm² by mistake?")
#: A component of gravity [m/s²]: ten times the Earth's.
GRAVITY = Range(floor=-100.0, hi=100.0, unit="m/s²", why="ten times the Earth's 9.81: not gravity",
                why_floor="ten times the Earth's 9.81: not gravity")
#: A length or a coordinate [m] (DH a and d, centres of mass, base, tool, URDF origins): a
#: thousand kilometres is no arm, nor the common normal of a CAD export's nearly parallel axes
#: (tens of kilometres away, kept exactly); lengths beyond 10 m already warn (millimetres?).
LENGTH = Range(floor=-1e6, hi=1e6, unit="m", why="a thousand kilometres: no arm's length",
               why_floor="a thousand kilometres: no arm's length")
#: An angle that is no joint limit [rad] (DH alpha and offset, URDF rpy): within a hundred turns
#: (beyond 2π already warns: degrees by mistake?).
ANGLE = Range(floor=-200 * 3.141592653589793, hi=200 * 3.141592653589793, unit="rad",
              why="a hundred turns: not an angle in radians", why_floor="a hundred turns: not an angle in radians")
#: A joint's speed limit [rad/s] (a URDF's ``<limit velocity>``, a robot file's ``velocity``):
#: 1e4 rad/s is 95 000 rpm, beyond any motor's shaft.
VELOCITY = Range(lo=0.0, lo_open=True, floor=1e-4, hi=1e4, unit="rad/s", why="95 000 rpm, beyond any joint drive",
                 why_floor="a turn in 17 hours: no joint drive's limit")
#: A joint's torque limit [N·m] (a URDF's ``<limit effort>``, a robot file's ``effort``).
EFFORT = Range(lo=0.0, lo_open=True, hi=1e6, unit="N·m", why="beyond any arm's drive")
#: A joint-drive term (viscous N·m·s/rad, Coulomb N·m, armature kg·m², noise N·m, offsets N·m).
DRIVE = Range(lo=0.0, hi=1e6, why="beyond any arm's drive: a unit slip?")
#: A speed of a trajectory or a friction model [deg/s]: above 1e6 deg/s no joint turns; below
#: 1e-12 deg/s (a turn in 10^7 years) the time a trajectory takes overflows what is computed
#: from it (5e-324 deg/s divided by zero); a slow speed above that is refused by the study's work
#: bound (its trajectories' samples) instead.
SPEED_DEG_S = Range(lo=0.0, lo_open=True, floor=1e-12, hi=1e6, unit="deg/s", why="no arm's joint turns faster",
                    why_floor="a turn in ten million years: the trajectories' times overflow")
#: An acceleration of a trajectory [deg/s²] (bounds as :data:`SPEED_DEG_S`'s).
ACCELERATION_DEG_S2 = Range(lo=0.0, lo_open=True, floor=1e-12, hi=1e8, unit="deg/s²",
                            why="no arm's joint accelerates faster",
                            why_floor="the trajectories' times overflow")
#: A time of a trajectory [s] (a segment's duration, a sampling step): below a picosecond, or
#: beyond 30 years, the samples' count overflows what is computed from it (5e-324 s divided into
#: nothing); a merely absurd one within (a nanosecond's step) is refused by the study's work bound.
TIME_S = Range(lo=0.0, lo_open=True, floor=1e-12, hi=1e9, unit="s", why="no segment of a trajectory lasts longer",
               why_floor="the trajectories' samples overflow")
#: A sensor's current per count [A]: a nanoampere per count is below any servo's ADC, a kiloampere
#: above any arm's current.
CURRENT_PER_COUNT = Range(lo=0.0, lo_open=True, floor=1e-9, hi=1e3, unit="A",
                          why="above any arm's current", why_floor="below any servo's resolution")
#: A motor's torque constant at the joint [N·m/A].
TORQUE_CONSTANT = Range(lo=0.0, lo_open=True, floor=1e-6, hi=1e4, unit="N·m/A",
                        why="above any geared motor's", why_floor="below any motor's")
#: A notebook cell's or a sweep cell's time limit [s]: a week; no limit is "none" (``null``).
CELL_TIMEOUT_S = Range(lo=0.0, lo_open=True, hi=7 * 24 * 3600.0, unit="s",
                       why="a week; 'none' for no limit")
#: A port of this machine.
PORT = Range(lo=1, hi=65535, why="a TCP port")
#: Training epochs (and an early stop's patience, in epochs): a hundred million epochs of the
#: smallest fit take years, so more are a typo (10^12); a long run within the bound is stopped by a
#: cell's time limit (a study file's learned_ik.epochs keeps its own tighter budget, 10 000).
EPOCHS = Range(lo=1, hi=100_000_000, why="more epochs than any cell could train: a typo?")
#: Membership functions per input of a grid partition: the rules are their product over the
#: inputs (16 on one input of three, the measured arm's finest q̇ grid, is a handful of rules; 8 on
#: 7 inputs is 2 million, which the learner's memory budget refuses before it trains).
N_MFS = Range(lo=1, hi=16, why="the grid's rules are their product over the inputs")
#: Rules of a clustered rule base (at most; fewer than 1 is the learner's to refuse, in its cell).
N_RULES = Range(hi=4096, why="the contest's largest is 512; more do not fit the memory of one cell")
#: Iterations of an iterative learner (an MLP's, boosting's).
ITERATIONS = Range(lo=1, hi=100_000, why="beyond that a cell runs for days")
#: A stride through the training states, or a count of kernel components.
COUNT = Range(lo=1, hi=10_000_000, why="beyond any data set here")


@dataclass(frozen=True)
class Length:
    """The annotated list holds ``lo`` to ``hi`` items; ``joints=True``: one per joint."""

    lo: int = 0
    hi: int | None = None
    joints: bool = False


@dataclass(frozen=True)
class ReadBy:
    """The annotated field is read by ``read(validator, value, at)`` instead of by its type:
    ``value`` as parsed, ``at`` the field's path, ``validator`` the read's
    :class:`~nfarm.infra.reading.Validator` (whatever was given to :func:`read_typed`, so a
    subclass's own checks are at hand); it returns the field's value or fails one line through
    the validator. ``null`` of an ``X | None`` field is ``None`` without the call. Give a named
    function of the section's module (``typing.get_type_hints`` evaluates a class's annotations
    with the class's namespace as their globals: a lambda there sees none of the module's names).

    Example:
        >>> from dataclasses import dataclass
        >>> from typing import Annotated
        >>> @dataclass(frozen=True)
        ... class Pair:
        ...     size: Annotated[int, ReadBy(lambda v, x, at: x if v.integer(x, at) % 2 == 0
        ...                                 else v.fail(at, f"must be even, got {x}"))]
        >>> read_typed(Pair, {"size": 4}, "p.yaml")
        Pair(size=4)
        >>> read_typed(Pair, {"size": 3}, "p.yaml")
        Traceback (most recent call last):
        ...
        nfarm.infra.reading.ParamsError: p.yaml: size: must be even, got 3
    """

    read: Callable[[Validator, Any, str], Any]


@dataclass(frozen=True)
class _Flag:
    name: str

    def __repr__(self) -> str:
        return self.name


#: One item per joint of the robot (the ``joints`` given to :func:`read_typed`).
JOINTS = Length(joints=True)
#: A pair ``[lo, hi]`` with ``lo < hi`` where both are given.
ORDERED = _Flag("ORDERED")
#: A string that may be empty.
TEXT = _Flag("TEXT")


def read_typed(cls: type, data: Any, source: str | Validator, at: str = "", *,
               joints: int | None = None) -> Any:
    """Read ``data`` (as parsed from YAML) into the dataclass ``cls`` by its annotations
    (module docstring); ``source`` names the file in errors; ``at`` is the section's path in
    it; ``joints`` is the robot's joint count for :data:`JOINTS` lists.

    Raises:
        ParamsError: the first broken rule, one line naming the file and the field.
        TypeError: ``cls`` holds an annotation this reader does not know (a programming error).
    """
    v = source if isinstance(source, Validator) else Validator(source)
    return _Reader(v, joints).section(cls, data, at)


def section_keys(cls: type) -> dict[str, bool]:
    """``{key: required}`` of a section's dataclass, in its fields' order."""
    return {f.name: f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
            for f in dataclasses.fields(cls)}


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls, include_extras=True)


def _split(hint: Any) -> tuple[Any, tuple]:
    """``Annotated[T, *rules]`` → ``(T, rules)``, nested annotations flattened."""
    rules: tuple = ()
    while typing.get_origin(hint) is Annotated:
        hint, *more = typing.get_args(hint)
        rules = (*rules, *more)
    return hint, rules


def _is_union(hint: Any) -> bool:
    return typing.get_origin(hint) in (Union, types.UnionType)


def _is_list(value: Any) -> bool:
    return isinstance(value, Sequence) and not isinstance(value, str)


class _Reader:
    """One read: the validator that names the file, the robot's joint count; ``value`` reads one
    field by its annotation, ``bound`` the nearest :class:`Range` above it."""

    def __init__(self, v: Validator, joints: int | None):
        self.v = v
        self.joints = joints

    def section(self, cls: type, data: Any, at: str) -> Any:
        self.v.mapping(data, at, section_keys(cls))
        hints = _hints(cls)
        values = {f.name: self.value(hints[f.name], data[f.name], _join(at, f.name), None)
                  for f in dataclasses.fields(cls) if f.name in data}
        return cls(**values)

    def value(self, hint: Any, value: Any, at: str, bound: Range | None) -> Any:
        hint, rules = _split(hint)
        by = next((r for r in rules if isinstance(r, ReadBy)), None)
        if by is not None:
            if value is None and _is_union(hint) and type(None) in typing.get_args(hint):
                return None
            return by.read(self.v, value, at)
        bound = next((r for r in rules if isinstance(r, Range)), bound)
        length = next((r for r in rules if isinstance(r, Length)), None)
        if _is_union(hint):
            arms = [a for a in typing.get_args(hint) if a is not type(None)]
            if value is None and len(arms) < len(typing.get_args(hint)):
                return None
            if len(arms) == 1:
                return self.value(Annotated[(arms[0], *rules)] if rules else arms[0], value, at, bound)
            listed = [a for a in arms if typing.get_origin(_split(a)[0]) is list]
            if len(arms) != 2 or len(listed) != 1:
                raise TypeError(f"{at}: unsupported union {hint!r}")
            arm = listed[0] if _is_list(value) else next(a for a in arms if a is not listed[0])
            return self.value(Annotated[(arm, *rules)] if rules else arm, value, at, bound)
        if dataclasses.is_dataclass(hint):
            return self.section(hint, value, at)
        origin, args = typing.get_origin(hint), typing.get_args(hint)
        if origin is Literal:
            return self.v.choice(value, at, args)
        if origin is tuple:
            items = self.v.sequence(value, at, min_len=len(args), max_len=len(args))
            out = tuple(self.value(a, x, f"{at}[{k}]", bound) for k, (a, x) in enumerate(zip(args, items)))
            if ORDERED in rules:
                self.ordered(out, at)
            return out
        if origin is list:
            lo, hi = (length.lo, length.hi) if length else (0, None)
            if length and length.joints:
                if self.joints is None:
                    raise TypeError(f"{at}: a per-joint list needs the robot's joint count")
                lo = hi = self.joints
            items = self.v.sequence(value, at, min_len=lo, max_len=hi)
            return [self.value(args[0], x, f"{at}[{k}]", bound) for k, x in enumerate(items)]
        if origin is dict:
            keys, item = args
            if typing.get_origin(keys) is not Literal:
                raise TypeError(f"{at}: a mapping's keys must be a Literal, got {keys!r}")
            self.v.mapping(value, at, dict.fromkeys(typing.get_args(keys), True))
            return {k: self.value(item, value[k], f"{at}.{k}", bound) for k in typing.get_args(keys)}
        if hint is bool:
            return self.v.boolean(value, at)
        if hint is str:
            return self.v.string(value, at, allow_empty=TEXT in rules)
        if hint is int or hint is float:
            return self.number(value, at, bound or Range(), integer=hint is int)
        raise TypeError(f"{at}: unsupported annotation {hint!r}")

    def number(self, value: Any, at: str, b: Range, *, integer: bool) -> float:
        if b.unit or b.why or b.floor is not None:          # a plausibility bound: its message says the unit and why
            return b.check(self.v, value, at, integer=integer)
        if integer:
            x = self.v.integer(value, at, lo=None if b.lo_open else b.lo, hi=None if b.hi_open else b.hi)
        else:
            x = self.v.number(value, at, lo=b.lo, hi=None if b.hi_open else b.hi, lo_open=b.lo_open)
        if integer and b.lo_open and b.lo is not None and x <= b.lo:
            self.v.fail(at, f"must be > {b.lo:g}, got {x}")
        if b.hi_open and b.hi is not None and x >= b.hi:
            self.v.fail(at, f"must be < {b.hi:g}, got {x!r}")
        return x

    def ordered(self, pair: tuple, at: str) -> None:
        if None not in pair and not pair[0] < pair[1]:
            self.v.fail(at, f"must satisfy lo < hi, got {list(pair)}")


def _join(at: str, key: str) -> str:
    return f"{at}.{key}" if at else key


#: A number as a user types it on the command line: plain decimal, as a parameter file's (no
#: ``1_0``, ``0x10``, ``inf``, ``nan``, non-ASCII digits, all of which Python's ``int`` or
#: ``float`` accept).
_TYPED_INT = re.compile(r"[-+]?[0-9]{1,100}")
_TYPED_FLOAT = re.compile(r"[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][-+]?[0-9]{1,4})?")


def parse_number(text: str, what: str, bound: Range = Range(), *, integer: bool = False,
                 none: str | None = None) -> float | int | None:
    """A number typed on the command line (``--cell-timeout 2.5``, ``--lock j=0.1``,
    ``--workers 2``): the one parser of every number a user types, by a parameter file's grammar
    (plain decimal; a whole number for ``integer``), finite and within ``bound``; the word
    ``none`` (any case) is ``None`` when given. Else a :class:`ParamsError` of one line,
    ``"<what>: <rule>, got '<text>'"``.

    Example:
        >>> parse_number("2.5", "--cell-timeout", CELL_TIMEOUT_S, none="none")
        2.5
        >>> parse_number("None", "--cell-timeout", CELL_TIMEOUT_S, none="none") is None
        True
        >>> parse_number("1_0", "--workers", integer=True)
        Traceback (most recent call last):
        ...
        nfarm.infra.reading.ParamsError: --workers: must be a whole number in plain decimal digits, got '1_0'
        >>> parse_number("1e308", "--cell-timeout", CELL_TIMEOUT_S, none="none")
        Traceback (most recent call last):
        ...
        nfarm.infra.reading.ParamsError: --cell-timeout: must be <= 604800 s, got 1e+308 (a week; 'none' for no limit)
    """
    v = _Bare(what)
    raw = text if isinstance(text, str) else str(text)
    word = raw.strip()
    if none is not None and word.lower() == none:
        return None
    or_none = f" (or '{none}')" if none is not None else ""
    kind = "a whole number in plain decimal digits" if integer else \
        "a number in plain decimal (such as 2, 0.5 or 1e-3)"
    if not (_TYPED_INT if integer else _TYPED_FLOAT).fullmatch(word):
        v.fail("", f"must be {kind}{or_none}, got {show(raw)}")
    value = int(word) if integer else float(word)
    if not integer and not math.isfinite(value):
        v.fail("", f"must be a finite number{or_none}, got {show(raw)}")
    return bound.check(v, value, "", integer=integer)


class _Bare(Validator):
    """Failures as ``"<what>: <rule>"`` (a command-line option, no file)."""

    def fail(self, field: str, rule: str):
        raise ParamsError(f"{self.source}: {rule}")
