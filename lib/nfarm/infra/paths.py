"""Project paths and atomic file output.

``ROOT`` is the repository root (``lib/nfarm/`` is installed in editable mode, so the package
knows where it lives). Relative paths given to notebooks and commands are resolved against it,
so a notebook finds ``params/robots/intelbot5.yaml`` whatever its working directory.
"""

from __future__ import annotations

import contextlib
import glob
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

__all__ = ["ROOT", "FIGURES", "BUILD", "NOTEBOOKS", "PARAMS", "project_path", "shown_path",
           "atomic_path"]

ROOT = Path(__file__).resolve().parents[3]
FIGURES = ROOT / "figures"
BUILD = ROOT / "build"
NOTEBOOKS = ROOT / "notebooks"
PARAMS = ROOT / "params"


def project_path(path: str | os.PathLike) -> Path:
    """``path`` itself if absolute, else resolved against the repository root."""
    path = Path(path)
    return path if path.is_absolute() else ROOT / path


def shown_path(path: str | os.PathLike) -> str:
    """``path`` for people and for notebooks: relative to the repository root when inside it
    (so that no executed notebook holds the checkout's absolute path), else as given."""
    try:
        return Path(path).resolve().relative_to(ROOT).as_posix()
    except ValueError:
        return str(path)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it onto ``path``.

    A reader never sees a half-written file: on an exception the temporary file is removed
    and ``path`` is left as it was. Parent directories are created. The temporary file's name
    holds the writer's process id (``.<name>.<pid>.<random>.tmp``): one a killed writer left
    (SIGKILL runs no clean-up) is removed by the next write of the same path, once no process
    of that id is alive on this machine.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    _remove_leftovers(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    tmp = Path(tmp)
    try:
        yield tmp
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def _remove_leftovers(path: Path) -> None:
    """Remove the temporary files of writes of ``path`` whose process is gone (:func:`atomic_path`)."""
    for old in path.parent.glob(f".{glob.escape(path.name)}.*.tmp"):
        pid = old.name[len(path.name) + 2:].split(".", 1)[0]
        if not pid.isdigit() or int(pid) == os.getpid():
            continue
        try:
            os.kill(int(pid), 0)            # alive (or another user's): leave its file alone
        except ProcessLookupError:
            old.unlink(missing_ok=True)
        except (PermissionError, OverflowError):
            continue
