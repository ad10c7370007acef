"""Publishing a chapter's files into ``figures/`` atomically, and the manifest that says what
was published (``MANIFEST.sha256``, checked by ``python -m nfarm verify``).

A chapter that succeeds is published as one step: a copy of ``figures/`` with that chapter's
files replaced and the manifest rewritten is built beside it (``.figures.new/``) and exchanged
with ``figures/`` by one ``renameat2(..., RENAME_EXCHANGE)`` system call, under an ``flock`` on
the figures directory's parent. At every instant ``figures/`` is a complete published state
whose manifest matches it, whenever the run is killed. A table with measured columns (seconds)
keeps the published measurements while every other cell comes out the same
(:func:`nfarm.presentation.tables.keep_measurements`): a build that reproduces the results leaves
the published files as they are.
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
from ..presentation.tables import MEASURED, keep_measurements

__all__ = ["write_manifest", "verify_manifest", "manifest_entries", "chapter_files", "publish_chapter", "publishing_lock",
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


#: The largest manifest read [bytes]: ``figures/``'s lists 271 files in 27 KB; a manifest of 64 MiB
#: would list half a million, none of which this project publishes.
MAX_MANIFEST_BYTES = 64 << 20
#: The longest line read [bytes]: a digest, two spaces and a path of at most :data:`MAX_NAME_BYTES`.
MAX_NAME_BYTES = 4096
#: Problems listed before the rest are counted in one line (a manifest of a million bad lines is
#: not a million lines of output).
MAX_PROBLEMS = 100


def _entries(manifest: Path, problems: list[str]):
    """The manifest's lines ``(number, digest, name)``, read one at a time (memory bounded by
    the longest line, :data:`MAX_NAME_BYTES`), each checked; a line that is no entry (not UTF-8,
    a NUL byte, too long, no ``sha256  path``) adds one problem and is not checked further."""
    with open(manifest, "rb") as f:
        number = 0
        while True:
            raw = f.readline(MAX_NAME_BYTES + 70)
            if not raw:
                return
            number += 1
            if len(raw) > MAX_NAME_BYTES + 68 and not raw.endswith(b"\n"):
                problems.append(f"{manifest}:{number}: longer than {MAX_NAME_BYTES + 67:,} bytes: not a "
                                f"'sha256  path' line")
                while raw and not raw.endswith(b"\n"):          # skip the rest of the line
                    raw = f.readline(1 << 16)
                continue
            raw = raw.rstrip(b"\n").rstrip(b"\r")
            try:
                line = raw.decode("utf-8")
            except UnicodeDecodeError as exc:
                problems.append(f"{manifest}:{number}: not UTF-8 text (byte {exc.start}): not a 'sha256  path' line")
                continue
            digest, sep, name = line.partition("  ")
            if not sep or not re.fullmatch(r"[0-9a-f]{64}", digest) or not name:
                problems.append(f"{manifest}:{number}: not a 'sha256  path' line")
                continue
            if "\x00" in name or not name.isprintable():
                problems.append(f"{manifest}:{number}: the path holds a NUL or control character: not checked")
                continue
            if any(len(part.encode("utf-8")) > 255 for part in name.split("/")):
                problems.append(f"{manifest}:{number}: a name in the path is longer than 255 bytes: not checked")
                continue
            yield number, digest, name


def verify_manifest(figures_dir: Path = FIGURES) -> list[str]:
    """What differs between ``figures_dir`` and its manifest (empty when they agree): files
    whose hash differs, listed files that are missing, files the manifest does not list, and
    lines that are no entry (one line each: not UTF-8, a NUL byte, an over-long name, a path
    outside the directory or through a symbolic-link loop, a file listed twice — refused, not
    counted once). The manifest is streamed (at most :data:`MAX_MANIFEST_BYTES`); at most
    :data:`MAX_PROBLEMS` problems are listed, then how many more."""
    manifest = figures_dir / "MANIFEST.sha256"
    if not manifest.is_file():
        return [f"{manifest}: missing"]
    size = manifest.stat().st_size
    if size > MAX_MANIFEST_BYTES:
        return [f"{manifest}: {size:,} bytes, over the {MAX_MANIFEST_BYTES:,}-byte limit of a manifest: not read"]
    problems: list[str] = []
    listed: dict[str, int] = {}
    root = figures_dir.resolve()
    for number, digest, name in _entries(manifest, problems):
        path = figures_dir / name
        try:
            outside = Path(name).is_absolute() or not path.resolve().is_relative_to(root)
        except (OSError, RuntimeError):       # a symbolic-link loop (3.11's resolve), a name too long
            problems.append(f"{manifest}:{number}: {name!r} cannot be resolved (a symbolic-link loop?): not checked")
            continue
        if outside:
            problems.append(f"{manifest}:{number}: {name!r} lies outside the figures directory: not checked")
            continue
        if name in listed:
            problems.append(f"{manifest}:{number}: {name!r} is listed twice (first at line {listed[name]})")
            continue
        listed[name] = number
        try:
            is_file = path.is_file()
        except OSError:
            is_file = False
        if not is_file:
            problems.append(f"{name}: listed but missing")
        elif _file_sha256(path) != digest:
            problems.append(f"{name}: differs from the manifest")
    for path in _published_files(figures_dir):
        if path.relative_to(figures_dir).as_posix() not in listed:
            problems.append(f"{path.relative_to(figures_dir).as_posix()}: not in the manifest")
    if len(problems) > MAX_PROBLEMS:
        problems = problems[:MAX_PROBLEMS] + [f"… and {len(problems) - MAX_PROBLEMS:,} more problems"]
    return problems


def manifest_entries(figures_dir: Path = FIGURES) -> int:
    """How many entries ``figures_dir``'s manifest holds (its lines, streamed)."""
    with open(figures_dir / "MANIFEST.sha256", "rb") as f:
        return sum(1 for _ in iter(lambda: f.readline(1 << 16), b"") )


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


def _kept_measurements(stage: Path, made: list[Path], published: Path) -> dict[Path, str]:
    """The texts to publish for ``made`` tables whose measured columns keep the published ones
    (:func:`nfarm.presentation.tables.keep_measurements`: every other cell the same), by staged path."""
    kept: dict[Path, str] = {}
    for path in made:
        twin, old = path.with_suffix(".md"), published / path.relative_to(stage)
        if path.suffix != ".csv" or twin not in made or not old.is_file():
            continue
        text = path.read_text(encoding="utf-8")
        if MEASURED not in text.partition("\n")[0]:
            continue
        merged = keep_measurements(text, twin.read_text(encoding="utf-8"), old.read_text(encoding="utf-8"))
        if merged is not None:
            kept[path], kept[twin] = merged
    return kept


def publish_chapter(stage: Path, figures_dir: Path, prefix: str, subdir: str = "") -> list[Path]:
    """Replace chapter ``prefix``'s files in ``figures_dir/subdir`` (an edition's directory,
    ``""`` for the primary arm's) with those in ``stage`` (a table's measurements kept while the
    rest agrees, module docstring) and rewrite the manifest, as one atomic step."""
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
    kept = _kept_measurements(stage, made, new / subdir)
    for old in chapter_files(new / subdir, prefix):
        old.unlink()
    published = []
    for path in made:
        target = new / subdir / path.relative_to(stage)
        target.parent.mkdir(parents=True, exist_ok=True)
        if path in kept:
            target.write_text(kept[path], encoding="utf-8")
        else:
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
