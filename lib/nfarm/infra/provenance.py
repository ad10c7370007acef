"""What a cached artefact was made by: the content of the code that makes it.

Data sets (:func:`nfarm.study.datasets.build_datasets`), trained models
(:func:`nfarm.learning.model_cache.fit_cached`), sweep cells (:func:`nfarm.study.sweep.code_key`)
and chapter runs (:func:`nfarm.publishing.report.build_report`) are reused while the hash of
their inputs is unchanged. The code is part of those inputs, and a version number is not the
code: a key holding nfarm's version let models trained before a change to ANFIS survive it and
be published. So each key holds :func:`code_digest` of the modules that make the artefact —
the module named (dotted, from the package: ``"learning.learned"``), the package modules it
imports (relative imports at the top or inside a function, every ``from .x import`` /
``from ..layer import x`` the syntax tree holds), transitively, and the ``__init__`` of the
package and of every subpackage on the way (which every import runs), with what they import.

The layering (``tests/test_layers.py``) keeps these sets small: a model's key holds the
learners and the layers under them, not the plotting or report modules above, so a change to a
figure's style retrains nothing (``tests/test_provenance.py`` edits a copy of the package both
ways).

The digests are cached on the files' sizes and modification times (timings in
``benchmarks/bench_sweep.py``).
"""

from __future__ import annotations

import ast
import hashlib
import os
from collections.abc import Iterable
from pathlib import Path

__all__ = ["PACKAGE", "code_modules", "code_digest", "digest_files", "module_file"]

PACKAGE = Path(__file__).resolve().parent.parent
"""The directory of the package whose modules are hashed."""

_ROOT_MODULE = "__init__"
_cache: dict[tuple, object] = {}


def module_file(name: str, package: str | os.PathLike | None = None) -> Path | None:
    """The file of module ``name`` (dotted from the package, ``"model.robot"``; a subpackage
    ``"model"`` or ``"model.__init__"`` is its ``__init__.py``), or None if there is none."""
    root = Path(package) if package is not None else PACKAGE
    parts = [p for p in name.split(".") if p]
    if parts[-1:] == [_ROOT_MODULE]:
        parts = parts[:-1]
    path = root.joinpath(*parts)
    if parts and path.with_suffix(".py").is_file():
        return path.with_suffix(".py")
    return path / "__init__.py" if (path / "__init__.py").is_file() else None


def _dotted(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    return ".".join(parts)           # "__init__", "model.__init__", "model.robot"


def _run_time_nodes(tree: ast.AST):
    """Every node of ``tree`` but those under ``if TYPE_CHECKING:`` (imports for type checkers
    and readers, never run)."""
    todo = [tree]
    while todo:
        node = todo.pop()
        yield node
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and isinstance(child.test, ast.Name) \
                    and child.test.id == "TYPE_CHECKING":
                todo.extend(child.orelse)
                continue
            todo.append(child)


def _imports(path: Path, root: Path) -> set[str]:
    """The package modules the file ``path`` imports (relative imports, anywhere in the file),
    as dotted names of their files."""
    package = list(path.relative_to(root).parent.parts)      # the package the file is in
    out = set()
    for node in _run_time_nodes(ast.parse(path.read_bytes(), filename=str(path))):
        if not (isinstance(node, ast.ImportFrom) and node.level >= 1):
            continue
        base = package[:len(package) - (node.level - 1)] if node.level > 1 else package
        target = base + (node.module.split(".") if node.module else [])
        for k in range(len(target) + 1):                      # the packages on the way run too
            found = module_file(".".join(target[:k]) or _ROOT_MODULE, root)
            if found is not None:
                out.add(_dotted(found, root))
        for alias in node.names:                              # `from .layer import module`
            found = module_file(".".join(target + [alias.name]), root)
            if found is not None:                             # not a name defined in a module
                out.add(_dotted(found, root))
    return out


def _signature(package: Path) -> tuple:
    return tuple((p.relative_to(package).as_posix(), s.st_size, s.st_mtime_ns)
                 for p in sorted(package.rglob("*.py")) for s in (p.stat(),))


def code_modules(*modules: str, package: str | os.PathLike | None = None) -> list[str]:
    """The sorted dotted names of the package modules that ``modules`` (such as
    ``"learning.learned"``) need: themselves, the ``__init__`` of the package and of the
    subpackages they are in, and every package module they import, transitively. A package's
    ``__init__`` is named ``"__init__"`` or ``"<subpackage>.__init__"``.

    Raises:
        ValueError: a named module is not a file of the package.
    """
    root = Path(package) if package is not None else PACKAGE
    key = ("modules", str(root), tuple(sorted(modules)), _signature(root))
    if key in _cache:
        return list(_cache[key])
    missing = [m for m in modules if module_file(m, root) is None]
    if missing:
        raise ValueError(f"no module {', '.join(missing)} in {root}")
    seen: set[str] = set()
    todo = [_dotted(module_file(m, root), root) for m in modules] + [_ROOT_MODULE]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        path = module_file(name, root)
        parts = name.split(".")[:-1]
        todo.extend(_dotted(module_file(".".join(parts[:k]) or _ROOT_MODULE, root), root)
                    for k in range(len(parts) + 1) if module_file(".".join(parts[:k]) or _ROOT_MODULE, root))
        todo.extend(_imports(path, root) - seen)
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
        digest_files(h, [module_file(m, root) for m in code_modules(*modules, package=root)], root)
        _cache[key] = h.hexdigest()
    return _cache[key]
