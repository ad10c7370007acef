"""Time limits around work that cannot otherwise be stopped from outside its thread.

A sweep cell runs a job in a Dask worker's thread, where no signal reaches it and a thread
cannot be killed; an ANFIS asked for ``epochs: 1e9`` would train until the machine is taken
away. The caller sets a deadline with :func:`time_limit`; the long loops of the library
(:meth:`nfarm.learning.anfis.ANFIS.fit`, once per epoch) call :func:`check_time`, which raises
:class:`TimeLimitError` once it has passed. The deadline is a :mod:`contextvars` variable: it
holds in the thread (and asyncio task) that set it, and nowhere else.
"""

from __future__ import annotations

import contextlib
import contextvars
import time
from collections.abc import Iterator

from .arguments import check_number

__all__ = ["TimeLimitError", "time_limit", "check_time"]

_DEADLINE: contextvars.ContextVar[tuple[float, float] | None] = contextvars.ContextVar(
    "nfarm_deadline", default=None)


class TimeLimitError(TimeoutError):
    """Work went on past the time limit its caller set (:func:`time_limit`)."""


@contextlib.contextmanager
def time_limit(seconds: float | None) -> Iterator[None]:
    """Within this block, :func:`check_time` raises once ``seconds`` have passed (``None``: no
    limit; an enclosing, earlier deadline still holds)."""
    if seconds is None:
        yield
        return
    check_number("seconds", seconds, 0, open_lo=True, finite=False, numpy=False,
                 message=f"a time limit must be a positive number of seconds, got {seconds!r}")
    deadline = time.monotonic() + seconds
    outer = _DEADLINE.get()
    token = _DEADLINE.set((deadline, seconds) if outer is None or deadline < outer[0] else outer)
    try:
        yield
    finally:
        _DEADLINE.reset(token)


def check_time(what: str) -> None:
    """Raise :class:`TimeLimitError` naming ``what`` was being done if the deadline has passed."""
    limit = _DEADLINE.get()
    if limit is not None and time.monotonic() > limit[0]:
        raise TimeLimitError(f"{what}: over the time limit of {limit[1]:g} s")
