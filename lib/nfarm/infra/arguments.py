"""Checks of the arguments a caller passes to the library's functions and options: each refuses a
bad value with one ``ValueError`` line naming the argument, before any work. Files a user hands
to nfarm are checked elsewhere, field by field with one :class:`~nfarm.infra.reading.ParamsError`
line naming the file (:class:`~nfarm.infra.reading.Validator`, :mod:`nfarm.infra.typed`); both
tell a number from a truth value by :func:`is_number` and :func:`is_integer`.

A truth value is no number here (``True`` is an ``int`` to Python, never a count or a tolerance
to nfarm). NumPy's integer and floating scalars count as numbers unless ``numpy=False`` (the
check of a value that must be a plain Python number, such as a port or a seed written to JSON).
``message`` replaces the default text where an argument's message says more (its unit, its
meaning); the default names the argument and the rule::

    tol_pos must be a finite number > 0, got 0.0
    restarts must be an integer >= 0, got 2.0
    residual must be True or False, got 1
    encoding must be one of quat_xyz, axes_xyz, arm_plane, got 'polar'

Example:
    >>> check_number("tol_pos", 1e-6, 0, open_lo=True)       # accepted: nothing returned
    >>> check_integer("restarts", True, 0)
    Traceback (most recent call last):
    ...
    ValueError: restarts must be an integer >= 0, got True
"""

from __future__ import annotations

from collections.abc import Collection
from typing import Any

import numpy as np

__all__ = ["is_number", "is_integer", "check_bool", "check_number", "check_integer", "check_choice"]


def is_number(value: Any, *, numpy: bool = True) -> bool:
    """Whether ``value`` is a real number of Python (``int``, ``float``) or, unless ``numpy`` is
    false, a NumPy integer or floating scalar; never a truth value. Not checked: finiteness.

    Example:
        >>> is_number(2), is_number(0.5), is_number(np.float32(0.5)), is_number(True), is_number("2")
        (True, True, True, False, False)
        >>> is_number(np.float32(0.5), numpy=False)       # a float64 is a Python float
        False
    """
    kinds = (int, float, np.integer, np.floating) if numpy else (int, float)
    return isinstance(value, kinds) and not isinstance(value, bool)


def is_integer(value: Any, *, numpy: bool = True) -> bool:
    """Whether ``value`` is a Python ``int`` or, unless ``numpy`` is false, a NumPy integer
    scalar; never a truth value (nor a whole float such as ``2.0``).

    Example:
        >>> is_integer(3), is_integer(np.int64(3)), is_integer(3.0), is_integer(False)
        (True, True, False, False)
        >>> is_integer(np.int64(3), numpy=False)
        False
    """
    return isinstance(value, (int, np.integer) if numpy else int) and not isinstance(value, bool)


def check_bool(name: str, value: Any, *, message: str | None = None) -> None:
    """A ``ValueError`` naming ``name`` unless ``value`` is ``True`` or ``False`` (not ``1``,
    ``np.True_`` or ``"yes"``).

    Example:
        >>> check_bool("residual", False)                # accepted
        >>> check_bool("residual", 1)
        Traceback (most recent call last):
        ...
        ValueError: residual must be True or False, got 1
    """
    if not isinstance(value, bool):
        raise ValueError(message or f"{name} must be True or False, got {value!r}")


def check_number(name: str, value: Any, lo: float | None = None, hi: float | None = None,
                 open_lo: bool = False, *, open_hi: bool = True, finite: bool = True,
                 numpy: bool = True, or_none: bool = False, message: str | None = None) -> None:
    """A ``ValueError`` naming ``name`` unless ``value`` is a number (:func:`is_number`), finite
    unless ``finite`` is false, ``>= lo`` (``> lo`` with ``open_lo``) and ``< hi`` (``<= hi``
    with ``open_hi=False``); ``None`` for no bound, and with ``or_none`` ``None`` is accepted.
    NaN is never accepted (it lies within no bound; with neither bound nor ``finite``, give one).

    Example:
        >>> check_number("tol_pos", 0.0, 0, None, open_lo=True)
        Traceback (most recent call last):
        ...
        ValueError: tol_pos must be a finite number > 0, got 0.0
        >>> check_number("min_improvement", 1, 0, 1)
        Traceback (most recent call last):
        ...
        ValueError: min_improvement must be a finite number >= 0 and < 1, got 1
        >>> check_number("far", float("inf"), 0, finite=False)      # inf: never warn
        >>> check_number("band", 0.7, 0, 0.5, open_lo=True, open_hi=False, finite=False,
        ...              message="band must be in (0, 0.5], got 0.7")
        Traceback (most recent call last):
        ...
        ValueError: band must be in (0, 0.5], got 0.7
    """
    if or_none and value is None:
        return
    if not (is_number(value, numpy=numpy) and (not finite or np.isfinite(value))
            and (lo is None or (value > lo if open_lo else value >= lo))
            and (hi is None or (value < hi if open_hi else value <= hi))):
        if message is None:
            bounds = " and ".join(([f"{'>' if open_lo else '>='} {lo}"] if lo is not None else [])
                                  + ([f"{'<' if open_hi else '<='} {hi}"] if hi is not None else []))
            message = (f"{name} must be {'a finite number' if finite else 'a number'}"
                       f"{' ' + bounds if bounds else ''}{' or None' if or_none else ''}, got {value!r}")
        raise ValueError(message)


def check_integer(name: str, value: Any, lo: int | None = None, hi: int | None = None, *,
                  or_none: bool = False, numpy: bool = True, message: str | None = None) -> None:
    """A ``ValueError`` naming ``name`` unless ``value`` is an integer (:func:`is_integer`)
    ``>= lo`` and ``<= hi`` (``None``: no bound), or, with ``or_none``, ``None``.

    Example:
        >>> check_integer("restarts", 2.0, 0)
        Traceback (most recent call last):
        ...
        ValueError: restarts must be an integer >= 0, got 2.0
        >>> check_integer("patience", None, 1, or_none=True)    # accepted
        >>> check_integer("patience", 0, 1, or_none=True)
        Traceback (most recent call last):
        ...
        ValueError: patience must be an integer >= 1 or None, got 0
        >>> check_integer("PORT", 70000, 1, 65535, numpy=False,
        ...               message="PORT must be a whole number from 1 to 65535, got 70000")
        Traceback (most recent call last):
        ...
        ValueError: PORT must be a whole number from 1 to 65535, got 70000
    """
    if or_none and value is None:
        return
    if not (is_integer(value, numpy=numpy) and (lo is None or value >= lo)
            and (hi is None or value <= hi)):
        if message is None:
            bounds = " and ".join(([f">= {lo}"] if lo is not None else [])
                                  + ([f"<= {hi}"] if hi is not None else []))
            message = (f"{name} must be an integer{' ' + bounds if bounds else ''}"
                       f"{' or None' if or_none else ''}, got {value!r}")
        raise ValueError(message)


def check_choice(name: str, value: Any, choices: Collection[str]) -> None:
    """A ``ValueError`` naming ``name`` and listing ``choices`` unless ``value`` is one of them
    (``choices`` may be a mapping: its keys).

    Example:
        >>> check_choice("encoding", "arm_plane", ("quat_xyz", "axes_xyz", "arm_plane"))   # accepted
        >>> check_choice("encoding", "polar", ("quat_xyz", "axes_xyz", "arm_plane"))
        Traceback (most recent call last):
        ...
        ValueError: encoding must be one of quat_xyz, axes_xyz, arm_plane, got 'polar'
    """
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(choices)}, got {value!r}")
