"""Where a build was made: the checkout's commit (:func:`current_commit`) and the machine
(:func:`machine`), as the index's "reproduce" box, the PDF's title page and a clean build's
record (:mod:`.report`) state them.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

from ..infra.paths import ROOT

__all__ = ["current_commit", "machine"]


def _git(*args: str) -> str:
    """What ``git *args`` prints in the checkout, stripped; ``""`` where git fails or is missing."""
    try:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True,
                              timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return ""


def current_commit() -> str:
    """The checkout's commit (``"unknown"`` outside a git checkout), and whether it has
    uncommitted changes: ``"ee3816d2cce9"`` or ``"ee3816d2cce9 (with uncommitted changes)"``."""
    return (_git("rev-parse", "--short=12", "HEAD") or "unknown") + \
        (" (with uncommitted changes)" if _git("status", "--porcelain") else "")


def machine() -> str:
    """The machine's CPU model and the cores this process may use."""
    model = ""
    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8", errors="replace").splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import platform

    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    return f"{model or platform.processor() or platform.machine() or 'unknown CPU'}, {cores} core{'s' if cores != 1 else ''}"
