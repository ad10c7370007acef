"""Helpers shared by the benchmarks: robust timing and a printed table."""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable

sys.path.insert(0, os.path.dirname(__file__))

# No environment of its own: nfarm tunes glibc's allocator when imported (nfarm.infra._allocator),
# so a benchmark measures what a user's plain script gets.


def seconds_per_call(fn: Callable[[], object], *, min_time: float = 0.2, repeat: int = 5) -> float:
    """Best-of-``repeat`` wall time of one call of ``fn``; each repeat runs at least ``min_time``."""
    fn()  # warm up
    best = float("inf")
    for _ in range(repeat):
        calls, start = 0, time.perf_counter()
        while True:
            fn()
            calls += 1
            elapsed = time.perf_counter() - start
            if elapsed >= min_time:
                break
        best = min(best, elapsed / calls)
    return best


def best_of(fn: Callable[[], object], repeat: int = 3) -> float:
    """Best-of-``repeat`` wall time of one call of ``fn`` (for calls of a second or more)."""
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best
