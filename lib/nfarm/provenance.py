"""What a cached artefact was made by: the content of the code that makes it.

Data sets (:func:`nfarm.datasets.build_datasets`), trained models
(:func:`nfarm.learned.fit_cached`), sweep cells (:func:`nfarm.sweep.code_key`) and chapter runs
(:func:`nfarm.report.build_report`) are reused while the hash of their inputs is unchanged. The
code is part of those inputs, and a version number is not the code: a key holding nfarm's
version let models trained before a change to ANFIS survive it and be published. So each key
holds :func:`code_digest` of the modules that make the artefact — the module named, the
package modules it imports (at the top or inside a function: every ``from .x import`` /
``from . import x`` the syntax tree holds), transitively, and the package's ``__init__`` (which
every import runs) with what it imports.

The layering (``tests/test_layers.py``) keeps these sets small: a model's key holds the
learners and the model layer under them, not the plotting or report modules above, so a change
to a figure's style retrains nothing (``tests/test_provenance.py`` edits a copy of the package
both ways).

Measured: the first digest of :mod:`nfarm.jobs`'s closure (23 files) parses and hashes them in
0.2–0.4 s; it is then cached on the files' sizes and modification times (under 1 ms a call).
"""

from __future__ import annotations

import ast
import hashlib
import os
from collections.abc import Iterable
from pathlib import Path

__all__ = ["PACKAGE", "code_modules", "code_digest", "digest_files"]

PACKAGE = Path(__file__).resolve().parent
"""The directory of the package whose modules are hashed."""

_ROOT_MODULE = "__init__"
_cache: dict[tuple, object] = {}


def _imports(path: Path) -> set[str]:
    """The package modules ``path`` imports (relative imports, anywhere in the file)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_bytes(), filename=str(path))):
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            if node.module:
                out.add(node.module.split(".")[0])
            else:
                out.update(alias.name.split(".")[0] for alias in node.names)
    return out


def _signature(package: Path) -> tuple:
    return tuple((p.name, s.st_size, s.st_mtime_ns) for p in sorted(package.glob("*.py"))
                 for s in (p.stat(),))


def code_modules(*modules: str, package: str | os.PathLike | None = None) -> list[str]:
    """The sorted names of the package modules that ``modules`` (names such as ``"learned"``)
    need: themselves, ``__init__`` and every package module they import, transitively.

    Raises:
        ValueError: a named module is not a file of the package.
    """
    root = Path(package) if package is not None else PACKAGE
    key = ("modules", str(root), tuple(sorted(modules)), _signature(root))
    if key in _cache:
        return list(_cache[key])
    missing = [m for m in modules if not (root / f"{m}.py").is_file()]
    if missing:
        raise ValueError(f"no module {', '.join(missing)} in {root}")
    seen: set[str] = set()
    todo = [*modules, _ROOT_MODULE]
    while todo:
        name = todo.pop()
        path = root / f"{name}.py"
        if name in seen or not path.is_file():      # `from . import __version__` names no file
            continue
        seen.add(name)
        todo.extend(_imports(path) - seen)
    _cache[key] = tuple(sorted(seen))
    return sorted(seen)


def digest_files(h, paths: Iterable[Path], root: Path | None = None) -> None:
    """Feed each file's name (relative to ``root`` when under it) and SHA-256 to the hash
    ``h``, in sorted order."""
    for path in sorted(paths):
        path = Path(path)
        name = path.relative_to(root).as_posix() if root is not None and path.is_relative_to(root) \
            else path.name
        h.update(name.encode() + b"\0")
        h.update(hashlib.sha256(path.read_bytes()).digest())


def code_digest(*modules: str, package: str | os.PathLike | None = None) -> str:
    """SHA-256 over the names and contents of :func:`code_modules` of ``modules``."""
    root = Path(package) if package is not None else PACKAGE
    key = ("digest", str(root), tuple(sorted(modules)), _signature(root))
    if key not in _cache:
        h = hashlib.sha256()
        digest_files(h, [root / f"{m}.py" for m in code_modules(*modules, package=root)], root)
        _cache[key] = h.hexdigest()
    return _cache[key]
