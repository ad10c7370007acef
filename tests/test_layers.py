"""The package's layers are its subpackages, bottom to top; a module imports only from its own
layer and the layers below it (``nfarm/__init__``'s docstring says what each holds)."""

from __future__ import annotations

import ast

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
