"""Warnings a chapter meets while reading its inputs, said once in its prose.

A robot file's plausibility checks and a URDF's conversion warn
(:class:`~nfarm.infra.reading.ParamsWarning`: nearly parallel axes written with a fixed
transform, an inertia that breaks the triangle inequality, …) each time the file is read. In a
chapter, Python prints each as a stderr block naming the library's source line and the
checkout's path, again for every later read. :func:`noted` records them instead, the checkout's
path left out, and silences the same messages for the rest of the process, so that a chapter
says each once (:func:`notes_text`) where it reads its robot. Warnings of other kinds pass on.

Example:
    >>> import warnings
    >>> with noted() as notes:
    ...     warnings.warn(ParamsWarning("arm.urdf: joints 'elbow' and 'wrist': axes nearly parallel"))
    >>> notes
    ["arm.urdf: joints 'elbow' and 'wrist': axes nearly parallel"]
    >>> print(notes_text(notes))
    Reading the robot noted: arm.urdf: joints 'elbow' and 'wrist': axes nearly parallel.
    >>> with noted() as again:          # said already: silenced
    ...     warnings.warn(ParamsWarning("arm.urdf: joints 'elbow' and 'wrist': axes nearly parallel"))
    >>> again, notes_text(again)
    ([], '')
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager

from ..infra.paths import ROOT
from ..infra.reading import ParamsWarning

__all__ = ["noted", "notes_text"]

_SAID: set[str] = set()         # the messages noted in this process


@contextmanager
def noted(category: type[Warning] = ParamsWarning) -> Iterator[list[str]]:
    """Record the warnings of ``category`` raised inside (each message once, in order, with the
    checkout's path ``<root>/`` removed) into the list yielded; afterwards the same messages are
    ignored for the rest of the process. Warnings of other categories are issued again as they
    came."""
    notes: list[str] = []
    with warnings.catch_warnings(record=True) as records:
        warnings.simplefilter("always", category)
        yield notes
    others = [r for r in records if not issubclass(r.category, category)]
    said = [str(r.message) for r in records if issubclass(r.category, category)]
    for message in dict.fromkeys(m for m in said if m not in _SAID):
        _SAID.add(message)
        warnings.filterwarnings("ignore", message=re.escape(message) + r"\Z", category=category)
        notes.append(message.replace(f"{ROOT}/", ""))
    for r in others:
        warnings.warn_explicit(r.message, r.category, r.filename, r.lineno, source=r.source)


def notes_text(notes: Sequence[str], what: str = "the robot") -> str:
    """One sentence of Markdown stating ``notes`` (from :func:`noted`); ``""`` for none."""
    if not notes:
        return ""
    return f"Reading {what} noted: " + "; ".join(n.rstrip(".") for n in notes) + "."
