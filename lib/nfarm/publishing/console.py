"""What ``make report`` shows while it runs: a line per chapter as it starts and ends, and where
the long work is — the cell running, of how many, and inside chapter 6's long cells the sweep
cells done of their total (how many a resumed run found finished) and the time left.

On a terminal each chapter under way has a line of its own, redrawn in place (tqdm's bars, one
per edition running side by side). Elsewhere (a log, CI) a line is printed only for long work:
once a cell has run for :attr:`Console.LONG_S` seconds, then every :attr:`Console.EVERY_S`
seconds while it runs, so that a short chapter prints two lines and an hour of sweeps sixty.
Either way a sweep that finds cells finished by an earlier run (a run resumed after a failure or
Ctrl-C) says so once, in a line.

The states come from :func:`nfarm.infra.notebook_runs.run_notebook` (its ``tell``), with the
chapter's ``label`` added by :func:`nfarm.publishing.report.build_report`.
"""

from __future__ import annotations

import sys
import threading
import time
from typing import TextIO

__all__ = ["Console", "status_line", "duration"]


def duration(seconds: float) -> str:
    """A duration for a reader: ``"45 s"``, ``"12 min"``, ``"1 h 05 min"``.

    >>> duration(44.6), duration(719), duration(3900)
    ('45 s', '12 min', '1 h 05 min')
    """
    seconds = max(0.0, float(seconds))
    if seconds < 59.5:
        return f"{seconds:.0f} s"
    minutes = round(seconds / 60)
    return f"{minutes} min" if minutes < 60 else f"{minutes // 60} h {minutes % 60:02d} min"


def status_line(state: dict) -> str:
    """One line of a running chapter's state (:func:`nfarm.infra.notebook_runs.run_notebook`'s
    ``tell``, with ``label``).

    >>> status_line({"label": "06_anfis_training.ipynb (so101)", "cell": 7, "cells": 55,
    ...              "source": "contest_chosen = contest.choose(tuning_runs)", "cell_s": 754.0,
    ...              "work": {"step": "ik_contest", "done": 37, "total": 120, "reused": 20,
    ...                       "eta_s": 700.0}})
    '06_anfis_training.ipynb (so101): cell 7 of 55 for 13 min (contest_chosen = contest.choose(tuning_runs)): sweep cells of ik_contest 37 of 120 done (20 found done), about 12 min left'
    """
    cell = state.get("cell")
    text = f"{state.get('label', state.get('notebook', ''))}: "
    text += "starting its kernel" if cell is None else \
        f"cell {cell} of {state.get('cells', '?')} for {duration(state.get('cell_s', 0.0))}" + \
        (f" ({state['source']})" if state.get("source") else "")
    work = state.get("work")
    if work:
        text += f": sweep cells of {work['step']} {work['done']} of {work['total']} done"
        if work.get("reused"):
            text += f" ({work['reused']} found done)"
        eta = work.get("eta_s")
        text += f", about {duration(eta)} left" if eta is not None else ", time left not known yet"
    return text


class Console:
    """The report's terminal: :meth:`say` prints a line (``report: …``), :meth:`tell` takes a
    running chapter's state (``label`` names the chapter; ``finished`` ends its line)."""

    #: Seconds a cell runs before a log (not a terminal) is told about it.
    LONG_S = 30.0
    #: Seconds between two lines about the same long cell in a log.
    EVERY_S = 60.0

    def __init__(self, stream: TextIO | None = None, *, terminal: bool | None = None, prefix: str = "report: "):
        self.stream = stream if stream is not None else sys.stderr
        self.terminal = terminal if terminal is not None else bool(getattr(self.stream, "isatty", lambda: False)())
        self.prefix = prefix
        self.lock = threading.Lock()
        self.bars: dict[str, object] = {}
        self.positions: dict[str, int] = {}                   # label → its line under the cursor
        self.told: dict[str, tuple[object, float]] = {}      # label → (cell, when last printed)
        self.resumed: set[tuple[str, object]] = set()          # (label, step) said to be resumed

    def say(self, text: str) -> None:
        with self.lock:
            line = f"{self.prefix}{text}"
            if self.bars:
                from tqdm import tqdm

                tqdm.write(line, file=self.stream)
            else:
                print(line, file=self.stream, flush=True)

    def tell(self, state: dict) -> None:
        label = str(state.get("label", state.get("notebook", "")))
        work = state.get("work") or {}
        if work.get("reused") and (label, work.get("step")) not in self.resumed:
            self.resumed.add((label, work.get("step")))
            self.say(f"{label}: {work['reused']} of {work['total']} sweep cells of {work['step']} already finished "
                     f"(by an earlier chapter, or a run that stopped), reused")
        with self.lock:
            if state.get("finished"):
                bar = self.bars.pop(label, None)
                self.positions.pop(label, None)
                if bar is not None:
                    bar.close()
                self.told.pop(label, None)
                return
            if self.terminal:
                self._draw(label, state)
            else:
                self._log(label, state)

    def _draw(self, label: str, state: dict) -> None:
        from tqdm import tqdm

        bar = self.bars.get(label)
        if bar is None:
            taken = set(self.positions.values())
            position = self.positions[label] = next(k for k in range(len(taken) + 1) if k not in taken)
            bar = self.bars[label] = tqdm(total=1, position=position, leave=False, file=self.stream,
                                          dynamic_ncols=True, bar_format="{desc}")
        bar.set_description_str(status_line({**state, "label": label}), refresh=True)

    def _log(self, label: str, state: dict) -> None:
        cell, now = state.get("cell"), time.monotonic()
        if cell is None or state.get("cell_s", 0.0) < self.LONG_S:
            return
        last = self.told.get(label)
        if last is not None and last[0] == cell and now - last[1] < self.EVERY_S:
            return
        self.told[label] = (cell, now)
        print(f"{self.prefix}{status_line({**state, 'label': label})}", file=self.stream, flush=True)

    def close(self) -> None:
        with self.lock:
            for bar in self.bars.values():
                bar.close()
            self.bars.clear()
            self.positions.clear()
