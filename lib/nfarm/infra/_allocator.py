"""glibc's allocator, tuned for nfarm's batched kernels when the package is imported.

The batched kernels (``fk``, ``jacobian``, ``rnea``, ANFIS epochs) allocate many 0.1–1 MB numpy
temporaries per call. With glibc's defaults each one above the (dynamic) mmap threshold is
mapped and unmapped, and the heap is trimmed after large frees, so the next temporary
page-faults its memory in again: measured on this project's machines, up to 3.5× slower
``fk`` and 2.3× slower ``rnea`` on 100 000 samples than with the thresholds below.

The library sets them itself (``mallopt``) so that its speed does not depend on the caller's
environment: a script, a notebook and ``make bench`` run alike. It does nothing where the user
chose (``MALLOC_MMAP_THRESHOLD_`` or ``MALLOC_TRIM_THRESHOLD_`` set, or ``NFARM_MALLOPT=0``),
and nothing on other C libraries (musl, macOS, Windows). The cost: freed memory up to 512 MB
stays with the process instead of being returned to the system at once.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import sys

M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
MMAP_THRESHOLD = 256 << 20
TRIM_THRESHOLD = 512 << 20

#: What :func:`tune` did: ``"set"``, or why it did not.
state = "not run"


def tune(*, worker: bool = False) -> str:
    """Set the two thresholds once (see the module docstring); returns :data:`state`.

    ``worker``: the process is a Dask worker running a sweep's cell (``nfarm.study.sweep``). Dask's
    nanny sets ``MALLOC_TRIM_THRESHOLD_`` for every worker it starts (to hand memory back
    between tasks), which is not the user's choice: a cell of ANFIS training ran 1.5× slower
    with it (``benchmarks/bench_sweep.py``), so only ``NFARM_MALLOPT=0`` is respected then."""
    global state
    if state == "set" or (state != "not run" and not worker):
        return state
    if os.environ.get("NFARM_MALLOPT", "1") == "0" or not worker and any(
            k in os.environ for k in ("MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_")):
        state = "left to the environment"
        return state
    if not sys.platform.startswith("linux"):
        state = "not glibc"
        return state
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.gnu_get_libc_version  # glibc only (musl has mallopt but ignores these)
        ok = libc.mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD) and \
            libc.mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD)
    except (OSError, AttributeError):
        state = "not glibc"
        return state
    state = "set" if ok else "refused by glibc"
    return state
