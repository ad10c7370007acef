"""The package's layers are its subpackages, bottom to top; a module imports only from its own
layer and the layers below it (``nfarm/__init__``'s docstring says what each holds)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from nfarm.infra import provenance

LAYERS = ["infra", "model", "solvers", "learning", "presentation", "study", "publishing"]
RANK = {layer: rank for rank, layer in enumerate(LAYERS)}
PACKAGE = provenance.PACKAGE
MODULES = sorted(p.relative_to(PACKAGE) for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)


def layer_of(relative) -> str:
    return relative.parts[0] if len(relative.parts) > 1 else relative.stem


def imported_layers(relative) -> set[str]:
    """The layers the module's relative imports reach, anywhere in the file, but not under
    ``if TYPE_CHECKING:`` (never run)."""
    tree = ast.parse((PACKAGE / relative).read_bytes())
    own = list(relative.parent.parts)
    out = set()
    for node in provenance._run_time_nodes(tree):
        if isinstance(node, ast.ImportFrom) and node.level >= 1:
            base = own[:len(own) - (node.level - 1)]
            target = base + (node.module.split(".") if node.module else [])
            if target:
                out.add(target[0])
            else:                                   # `from .. import layer` or `__version__`
                out.update(a.name for a in node.names if a.name in RANK)
    return out


def test_every_module_is_in_a_layer():
    loose = [str(m) for m in MODULES if len(m.parts) == 1 and m.stem not in ("__init__", "__main__")]
    assert not loose, f"modules outside the layers: {loose}"
    assert {m.parts[0] for m in MODULES if len(m.parts) > 1} == set(LAYERS)


@pytest.mark.parametrize("relative", [m for m in MODULES if len(m.parts) > 1], ids=str)
def test_lower_layers_never_import_upper_ones(relative):
    rank = RANK[layer_of(relative)]
    upper = {layer for layer in imported_layers(relative) if RANK.get(layer, -1) > rank}
    assert not upper, f"{relative} (layer {layer_of(relative)}) imports from {sorted(upper)} above it"


def test_the_package_itself_imports_no_layer_at_import_time():
    """``import nfarm`` runs only the allocator's tuning; public names load on first use."""
    assert imported_layers(PACKAGE.relative_to(PACKAGE) / "__init__.py") <= {"infra"}


def _public(layer: str):
    """``(name, object)`` of every function and class a module of ``layer`` defines and lists
    in its ``__all__``."""
    import importlib
    import inspect
    for relative in MODULES:
        if relative.parts[0] != layer or relative.name == "__init__.py":
            continue
        module = importlib.import_module("nfarm." + ".".join(relative.with_suffix("").parts))
        for name in getattr(module, "__all__", []):
            obj = getattr(module, name)
            if (inspect.isfunction(obj) or inspect.isclass(obj)) and obj.__module__ == module.__name__:
                yield f"{module.__name__}.{name}", obj


@pytest.mark.parametrize("layer", ["model", "solvers"])
def test_every_public_function_of_the_model_and_solvers_has_an_example(layer):
    """An example (run by --doctest-modules) in the docstring of each public function and class;
    a result record may point to the function that makes it instead."""
    missing = [name for name, obj in _public(layer)
               if ">>>" not in (obj.__doc__ or "") and ", which has an example" not in (obj.__doc__ or "")]
    assert not missing, f"public names without an example: {missing}"


# -- no cycles ----------------------------------------------------------------------------------


def _module_file(root: Path, parts: list[str]) -> Path | None:
    """The package file of the dotted module ``parts`` (from the package), or None."""
    for candidate in (root.joinpath(*parts).with_suffix(".py") if parts else None,
                      root.joinpath(*parts, "__init__.py")):
        if candidate is not None and candidate.is_file():
            return candidate.relative_to(root)
    return None


def module_imports(root: Path, relative: Path) -> set[Path]:
    """The package modules the file ``relative`` names in an import statement anywhere in it
    (at the top, inside a function, under ``if TYPE_CHECKING:``): ``from .x import y`` is
    module ``x``, or ``x.y`` where that is a module; ``import nfarm.x`` and ``from nfarm.x import
    y`` alike. The package's own ``__init__`` is read without its ``TYPE_CHECKING`` block, which
    only declares the public names it loads on first use."""
    tree = ast.parse((root / relative).read_bytes())
    nodes = provenance._run_time_nodes(tree) if relative == Path("__init__.py") else ast.walk(tree)
    own = list(relative.parent.parts)
    found = set()
    for node in nodes:
        if isinstance(node, ast.ImportFrom):
            if node.level:
                target = own[:len(own) - (node.level - 1)] + (node.module.split(".") if node.module else [])
            elif node.module and node.module.split(".")[0] == root.name:
                target = node.module.split(".")[1:]
            else:
                continue
            for alias in node.names:
                found.add(_module_file(root, target + [alias.name]) or _module_file(root, target))
        elif isinstance(node, ast.Import):
            found.update(_module_file(root, alias.name.split(".")[1:]) for alias in node.names
                         if alias.name.split(".")[0] == root.name)
    return found - {None, relative}


def import_cycles(root: Path) -> list[tuple[str, str]]:
    """Every pair of the package's modules each of which imports the other, directly or through
    others (so each pair on a cycle), sorted."""
    files = sorted(p.relative_to(root) for p in root.rglob("*.py") if "__pycache__" not in p.parts)
    graph = {f: module_imports(root, f) for f in files}
    reach = {}
    for start in files:
        seen, todo = set(), [start]
        while todo:
            for nxt in graph.get(todo.pop(), ()):
                if nxt not in seen:
                    seen.add(nxt)
                    todo.append(nxt)
        reach[start] = seen
    return sorted({tuple(sorted((a.as_posix(), b.as_posix()))) for a in files for b in reach[a]
                   if a != b and a in reach.get(b, ())})


def test_no_two_modules_import_each_other():
    """Not even inside a function: a cycle makes two modules one unit to read, to test and to
    change (and an import inside a function only hides it)."""
    assert import_cycles(PACKAGE) == []


@pytest.mark.parametrize("second", [
    "def later():\n    from .a import f\n    return f\n",                           # inside a function
    "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .a import f\n",  # for readers only
    "import nfarm.sub.a\n",                                                         # absolute
])
def test_the_cycle_check_sees_every_kind_of_import(tmp_path, second):
    root = tmp_path / "nfarm"
    (root / "sub").mkdir(parents=True)
    (root / "__init__.py").write_text("")
    (root / "sub" / "__init__.py").write_text("")
    (root / "sub" / "a.py").write_text("from . import b\n\ndef f():\n    return b\n")
    (root / "sub" / "b.py").write_text(second)
    (root / "sub" / "c.py").write_text("from .a import f\n")                       # imports, no cycle
    assert import_cycles(root) == [("sub/a.py", "sub/b.py")]
