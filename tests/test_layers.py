"""The package's layers: the model (robot, rotations, kinematics, dynamics) never imports the
solvers and learners, nor the I/O and presentation modules above them."""

from __future__ import annotations

import ast

import pytest

from nfarm.paths import ROOT

LAYERS = {
    "model": ["reading", "paths", "limits", "provenance", "robot", "rotations", "linalg", "kinematics", "dynamics",
              "fuzzy", "trajectory"],
    "solvers": ["ik", "geometric_ik", "tool_paths", "workspace", "anfis", "jang", "datasets", "bases", "learned", "baselines"],
    "io": ["urdf", "recording", "plotting", "wording", "report", "panel_compute", "panel", "panel_server", "statistics", "summary", "pinocchio_ref", "jobs", "sweep", "course",
           "answers", "__main__"],
}
RANK = {module: rank for rank, names in enumerate(LAYERS.values()) for module in names}


def imports(module: str) -> set[str]:
    tree = ast.parse((ROOT / "lib" / "nfarm" / f"{module}.py").read_text())
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            if node.module:
                out.add(node.module.split(".")[0])
            else:
                out.update(alias.name for alias in node.names)
    return out - {"__version__", "_allocator"}


def test_every_module_has_a_layer():
    modules = {p.stem for p in (ROOT / "lib" / "nfarm").glob("*.py")} - {"__init__", "_allocator"}
    assert modules == set(RANK), modules ^ set(RANK)


@pytest.mark.parametrize("module", sorted(RANK))
def test_lower_layers_never_import_upper_ones(module):
    upper = {m for m in imports(module) if m in RANK and RANK[m] > RANK[module]}
    assert not upper, f"{module} (layer {RANK[module]}) imports {sorted(upper)} from a layer above"
