"""Progress of long work, told to whoever runs it: the work posts where it is, the runner reads it.

A chapter that runs sweep cells spends most of its time inside one notebook cell. Whoever
runs the notebook (:func:`nfarm.infra.notebook_runs.run_notebook`, for ``make report``) names
a file in the environment variable :data:`ENV` of the kernel it starts; long work in that
kernel (:func:`nfarm.study.sweep.run_sweeps`) calls :func:`post` with its step, how many of its
units are done, and an estimate of the time left, and the runner reads the file
(:func:`read`) to show it and to tell work that is slow from work that is stuck: a post is
progress, and only a cell that posts nothing for the runner's limit is stopped.

Nothing is posted where :data:`ENV` is not set (a notebook run by hand, a test): the work runs
the same. A post never fails the work: a file that cannot be written is skipped.

>>> import os, tempfile
>>> where = os.path.join(tempfile.mkdtemp(), "progress.json")
>>> os.environ[ENV] = where
>>> post("sweep ik_contest", 3, 10, reused=2, eta_s=70.0)
>>> state = read(where)
>>> state["step"], state["done"], state["total"], state["reused"], state["eta_s"]
('sweep ik_contest', 3, 10, 2, 70.0)
>>> del os.environ[ENV]
"""

from __future__ import annotations

import json
import math
import os
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["ENV", "post", "read", "heartbeat", "eta"]

#: The environment variable naming the file that long work posts its progress to.
ENV = "NFARM_PROGRESS"


def post(step: str, done: int, total: int, *, reused: int = 0, eta_s: float | None = None) -> None:
    """Post that ``done`` of ``total`` units of ``step`` are finished (``reused`` of them found
    finished before this run began), with ``eta_s`` seconds estimated to be left (``None``:
    no estimate yet). Written atomically to the file :data:`ENV` names; nothing where it names
    none, or where the file cannot be written."""
    path = os.environ.get(ENV)
    if not path:
        return
    state = {"step": str(step), "done": int(done), "total": int(total), "reused": int(reused),
             "eta_s": None if eta_s is None or not math.isfinite(eta_s) else round(float(eta_s), 1),
             "posted": time.time(), "pid": os.getpid()}
    tmp = f"{path}.{os.getpid()}.{threading.get_ident()}.tmp"
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            json.dump(state, f)
        os.replace(tmp, path)
    except OSError:
        try:
            os.unlink(tmp)
        except OSError:
            pass


def read(path: str | os.PathLike) -> dict | None:
    """The last state posted to ``path``, or ``None`` (nothing posted yet, or not a post)."""
    try:
        state = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    kinds = {"step": str, "done": int, "total": int, "reused": int, "posted": (int, float)}
    if not isinstance(state, dict) or any(not isinstance(state.get(k), t) for k, t in kinds.items()):
        return None
    return state


def eta(done_here: int, left: int, elapsed_s: float, *, at_least: int = 3, share: float = 0.1) -> float | None:
    """Seconds left for ``left`` units at the rate of the ``done_here`` finished in
    ``elapsed_s`` seconds of this run: ``left · elapsed / done``; ``None`` (not known yet) until
    ``at_least`` units and ``share`` of this run's units have finished. A sweep starts its
    longest cells first, and its first finishes, read as a rate, overstated the time left of a
    chapter-6 batch by hours (seen: "6 h 52 min" after 1 of 62 cells).

    >>> eta(4, 6, 120.0)
    180.0
    >>> eta(2, 6, 120.0) is None, eta(5, 60, 120.0) is None     # too few finished to tell
    (True, True)
    """
    if done_here < max(at_least, share * (done_here + left)):
        return None
    return left * elapsed_s / done_here


@contextmanager
def heartbeat(state: Callable[[], tuple], every_s: float = 20.0,
              alive_for_s: float | None = None) -> Iterator[None]:
    """Post ``state()`` (the arguments of :func:`post`, as a tuple ``(step, done, total,
    reused, eta_s)``) every ``every_s`` seconds while the block runs: the work is waiting on
    others (a cluster's workers) and is not stuck. ``alive_for_s``: the beats stop once that
    many seconds pass without a change of the counts (the tuple's first four) — when every unit under way should have ended by its own time limit, the
    waiting proves nothing more, and the runner's limit takes over (``None``: beat while the
    block runs)."""
    if not os.environ.get(ENV):
        yield
        return
    stop = threading.Event()

    def beat() -> None:
        last, changed = None, time.monotonic()
        while not stop.wait(every_s):
            now, current = time.monotonic(), state()
            if current[:4] != last:
                last, changed = current[:4], now
            if alive_for_s is None or now - changed <= alive_for_s:
                step, done, total, reused, eta_s = current
                post(step, done, total, reused=reused, eta_s=eta_s)

    thread = threading.Thread(target=beat, name="nfarm-progress-heartbeat", daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
