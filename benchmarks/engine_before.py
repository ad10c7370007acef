"""The ANFIS training engine as it was before issue 40 (commit ``BEFORE``), importable beside
today's so that a benchmark compares the two in one run on one machine.

Its two modules (``learning/anfis.py``, ``learning/fuzzy.py``) are read from the repository's
history with ``git show`` into a package of their own under ``build/bench/``; their imports of
the rest of the package point at today's ``nfarm`` (estimator, readers, limits: no arithmetic).
"""

from __future__ import annotations

import importlib
import re
import subprocess
import sys
from pathlib import Path

#: The last commit with the engine before issue 40.
BEFORE = "a824884"
ROOT = Path(__file__).resolve().parents[1]
_PACKAGE = "nfarm_engine_before"


def load():
    """The old engine's ``anfis`` module (``ANFIS``, ``ANFISMulti``), or a ``RuntimeError``
    naming why it cannot be had (no git, or a clone without that commit)."""
    if f"{_PACKAGE}.anfis" in sys.modules:
        return sys.modules[f"{_PACKAGE}.anfis"]
    where = ROOT / "build" / "bench" / _PACKAGE
    where.mkdir(parents=True, exist_ok=True)
    for name in ("anfis", "fuzzy"):
        try:
            text = subprocess.run(["git", "show", f"{BEFORE}:lib/nfarm/learning/{name}.py"], cwd=ROOT,
                                  capture_output=True, text=True, check=True).stdout
        except (OSError, subprocess.CalledProcessError) as exc:
            raise RuntimeError(f"the engine before issue 40 ({BEFORE}) is not in this clone's history: "
                               f"{getattr(exc, 'stderr', '') or exc}".strip()) from None
        text = re.sub(r"^from \.\.(\w+)", r"from nfarm.\1", text, flags=re.M)
        text = re.sub(r"^from \.(?!fuzzy)(\w+)", r"from nfarm.learning.\1", text, flags=re.M)
        (where / f"{name}.py").write_text(text)
    (where / "__init__.py").write_text("")
    sys.path.insert(0, str(where.parent))
    return importlib.import_module(f"{_PACKAGE}.anfis")
