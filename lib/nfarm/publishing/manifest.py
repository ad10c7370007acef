"""Publishing a chapter's files into ``figures/`` atomically, and the manifest that says what
was published (``MANIFEST.sha256``, checked by ``python -m nfarm verify``).

A chapter that succeeds is published as one step: a copy of ``figures/`` with that chapter's
files replaced and the manifest rewritten is built beside it (``.figures.new/``) and exchanged
with ``figures/`` by one ``renameat2(..., RENAME_EXCHANGE)`` system call, under an ``flock`` on
the figures directory's parent. At every instant ``figures/`` is a complete published state
whose manifest matches it, whenever the run is killed.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import fcntl
import hashlib
import os
import re
import shutil
from pathlib import Path

from ..infra.notebook_runs import ReportError
from ..infra.paths import FIGURES, atomic_path

__all__ = ["write_manifest", "verify_manifest", "chapter_files", "publish_chapter", "publishing_lock",
           "recover_figures"]


def chapter_files(directory: Path, prefix: str) -> list[Path]:
    """The figures and tables of chapter ``prefix`` (``"06"``) in a figures directory."""
    return sorted([*directory.glob(f"{prefix}_*.png"), *(directory / "tables").glob(f"{prefix}_*.csv"),
                   *(directory / "tables").glob(f"{prefix}_*.md")])


def _published_files(figures_dir: Path) -> list[Path]:
    return sorted(p for p in figures_dir.rglob("*")
                  if p.is_file() and p.suffix in (".png", ".csv", ".md"))


def _file_sha256(path: Path, chunk: int = 1 << 20) -> str:
    """SHA-256 of a file read in chunks of ``chunk`` bytes (memory bounded whatever its size)."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while block := f.read(chunk):
            h.update(block)
    return h.hexdigest()


def write_manifest(figures_dir: Path = FIGURES) -> Path:
    """Write ``MANIFEST.sha256`` (``sha256sum -c`` format, paths relative to ``figures_dir``)."""
    lines = []
    for path in _published_files(figures_dir):
        lines.append(f"{_file_sha256(path)}  {path.relative_to(figures_dir).as_posix()}\n")
    manifest = figures_dir / "MANIFEST.sha256"
    with atomic_path(manifest) as tmp:
        tmp.write_text("".join(lines), encoding="utf-8")
    return manifest


def verify_manifest(figures_dir: Path = FIGURES) -> list[str]:
    """What differs between ``figures_dir`` and its manifest (empty when they agree): files
    whose hash differs, listed files that are missing, files the manifest does not list."""
    manifest = figures_dir / "MANIFEST.sha256"
    if not manifest.is_file():
        return [f"{manifest}: missing"]
    problems, listed = [], set()
    root = figures_dir.resolve()
    for number, line in enumerate(manifest.read_text(encoding="utf-8").splitlines(), 1):
        digest, sep, name = line.partition("  ")
        if not sep or not re.fullmatch(r"[0-9a-f]{64}", digest):
            problems.append(f"{manifest}:{number}: not a 'sha256  path' line")
            continue
        path = figures_dir / name
        if Path(name).is_absolute() or not path.resolve().is_relative_to(root):
            problems.append(f"{manifest}:{number}: {name!r} lies outside the figures directory: not checked")
            continue
        listed.add(name)
        if not path.is_file():
            problems.append(f"{name}: listed but missing")
        elif _file_sha256(path) != digest:
            problems.append(f"{name}: differs from the manifest")
    for path in _published_files(figures_dir):
        if path.relative_to(figures_dir).as_posix() not in listed:
            problems.append(f"{path.relative_to(figures_dir).as_posix()}: not in the manifest")
    return problems


_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


def _exchange(a: Path, b: Path) -> bool:
    """Swap two directories atomically (Linux ``renameat2(RENAME_EXCHANGE)``); False where
    the system does not offer it."""
    libc = ctypes.CDLL(ctypes.util.find_library("c") or None, use_errno=True)
    renameat2 = getattr(libc, "renameat2", None)
    if renameat2 is None:
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                          ctypes.c_uint]
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    errno = ctypes.get_errno()
    if errno in (22, 38, 95):   # EINVAL, ENOSYS, EOPNOTSUPP: this file system cannot
        return False
    raise OSError(errno, f"cannot exchange {a} and {b}: {os.strerror(errno)}")


def recover_figures(figures_dir: Path) -> None:
    """Undo what a run killed in the middle of publishing left beside ``figures_dir``."""
    new, old = _sibling(figures_dir, "new"), _sibling(figures_dir, "old")
    if not figures_dir.exists() and old.exists():     # killed between the two fallback renames
        os.rename(old, figures_dir)
    shutil.rmtree(new, ignore_errors=True)
    shutil.rmtree(old, ignore_errors=True)


def _sibling(figures_dir: Path, kind: str) -> Path:
    return figures_dir.with_name(f".{figures_dir.name}.{kind}")


@contextlib.contextmanager
def publishing_lock(figures_dir: Path):
    """Hold the lock of ``figures_dir``'s publishing: editions run side by side (module
    docstring) publish one at a time. An exclusive ``flock`` on the parent directory, which
    the kernel releases when its holder dies: no lock file, nothing stale."""
    parent = figures_dir.parent
    parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(parent, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)            # releases the lock


def publish_chapter(stage: Path, figures_dir: Path, prefix: str, subdir: str = "") -> list[Path]:
    """Replace chapter ``prefix``'s files in ``figures_dir/subdir`` (an edition's directory,
    ``""`` for the primary arm's) with those in ``stage`` and rewrite the manifest, as one
    atomic step (module docstring)."""
    made = chapter_files(stage, prefix)
    strays = sorted(set(p for p in stage.rglob("*") if p.is_file()) - set(made))
    if strays:
        raise ReportError(f"chapter {prefix} wrote files not named {prefix}_*.png or "
                          f"tables/{prefix}_*.{{csv,md}}: {', '.join(map(str, strays))}")
    with publishing_lock(figures_dir):
        return _publish_locked(stage, made, figures_dir, prefix, subdir)


def _publish_locked(stage: Path, made: list[Path], figures_dir: Path, prefix: str, subdir: str) -> list[Path]:
    recover_figures(figures_dir)
    new = _sibling(figures_dir, "new")
    if figures_dir.exists():
        shutil.copytree(figures_dir, new)
    else:
        new.mkdir(parents=True)
    for old in chapter_files(new / subdir, prefix):
        old.unlink()
    published = []
    for path in made:
        target = new / subdir / path.relative_to(stage)
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(path, target)
        published.append(figures_dir / subdir / path.relative_to(stage))
    write_manifest(new)
    if not figures_dir.exists():
        os.rename(new, figures_dir)
    elif _exchange(new, figures_dir):
        shutil.rmtree(new)                      # now the previous state
    else:                                       # two renames; recover_figures repairs a kill between
        old = _sibling(figures_dir, "old")
        os.rename(figures_dir, old)
        os.rename(new, figures_dir)
        shutil.rmtree(old)
    return published
