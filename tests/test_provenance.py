"""Cached artefacts are keyed on the content of the code that makes them (nfarm.infra.provenance):
editing a training module retrains, editing a presentation module reuses."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from nfarm.study import datasets, id_trajectories, study_files, sweep
from nfarm.infra import provenance
from nfarm.model.dynamics import rnea
from nfarm.learning.learned_id import LearnedID
from nfarm.learning.model_cache import fit_cached
from nfarm.infra.paths import ROOT
from nfarm.publishing.report import _chapter_key, notebook_modules

STUDY = study_files.smoke_study(study_files.load_study(ROOT / "params" / "studies" / "intelbot5.yaml"))
ROBOT = STUDY.robot


@pytest.fixture()
def package(tmp_path, monkeypatch) -> Path:
    """A copy of the package's sources that the keys are computed from."""
    copy = tmp_path / "nfarm"
    shutil.copytree(provenance.PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(provenance, "PACKAGE", copy)
    return copy


def edit(package: Path, module: str) -> None:
    path = provenance.module_file(module, package)
    path.write_text(path.read_text(encoding="utf-8") + "\n# an edit\n", encoding="utf-8")


def test_the_closure_follows_imports_and_stops_at_the_layers_above():
    learned = provenance.code_modules("learning.model_cache")      # the key of every fitted model
    assert {"learning.learned", "learning.learned_id", "learning.anfis", "learning.fuzzy", "learning.bases", "model.kinematics",
            "__init__", "learning.__init__", "model.__init__", "model.urdf_import"} <= set(learned)
    assert not {m for m in learned if m.split(".")[0] in ("presentation", "study", "publishing")}
    # A function-level import counts: jobs imports the learners at the top, sweep runs notebooks lazily.
    assert "infra.notebook_runs" in provenance.code_modules("study.sweep")
    with pytest.raises(ValueError, match="no module nosuch"):
        provenance.code_modules("nosuch")


def test_the_public_names_of_the_package_are_not_in_every_key():
    """``nfarm/__init__`` names its public names lazily (and for type checkers under
    TYPE_CHECKING): importing any module runs it, but its closure holds no layer."""
    assert provenance.code_modules("__init__") == ["__init__", "infra.__init__", "infra._allocator"]
    assert "learning.learned" not in provenance.code_modules("model.robot")


@pytest.mark.parametrize("module, changes", [("learning.anfis", True), ("learning.learned", True),
                                             ("learning.learned_id", True), ("model.kinematics", True),
                                             ("presentation.plotting", False), ("publishing.report", False), ("publishing.course", False)])
def test_the_learners_digest_changes_with_their_code_only(package, module, changes):
    before = provenance.code_digest("learning.model_cache")
    edit(package, module)
    assert (provenance.code_digest("learning.model_cache") != before) == changes


def test_a_model_is_retrained_after_a_training_module_changes_and_reused_after_a_presentation_one(
        package, tmp_path):
    def split(count, seed):
        d = id_trajectories.random_trajectories(ROBOT, STUDY.id, count, seed)
        return {**d, "tau": rnea(ROBOT, d["q"], d["qd"], d["qdd"])}
    train, val = split(3, 1), split(1, 2)
    where = tmp_path / "model"
    make = lambda: LearnedID(inputs="own", n_mfs=2, epochs=1)          # noqa: E731
    assert fit_cached(make(), ROBOT, train, val, where)[1] == "made"
    assert fit_cached(make(), ROBOT, train, val, where)[1] == "reused"
    edit(package, "presentation.plotting")
    assert fit_cached(make(), ROBOT, train, val, where)[1] == "reused"
    edit(package, "learning.anfis")
    assert fit_cached(make(), ROBOT, train, val, where)[1] == "made"
    assert fit_cached(make(), ROBOT, train, val, where)[1] == "reused"


def test_data_sets_are_remade_after_the_data_code_changes(package, tmp_path):
    out = tmp_path / "data"
    datasets.build_datasets(STUDY, out)
    edit(package, "presentation.plotting")
    assert {how for _, how in datasets.build_datasets(STUDY, out)} == {"reused"}
    edit(package, "model.dynamics")
    with pytest.raises(datasets.ParamsError, match=r"id_train\.json: study: made by other code than "
                                                    r"this checkout's .*regenerate with"):
        datasets.load(out / "id_train.npz", ROBOT, STUDY)
    assert {how for _, how in datasets.build_datasets(STUDY, out)} == {"made"}


def test_sweep_cells_and_chapters_rerun_only_for_code_they_import(package):
    job = sweep.sweep_from_dict({"name": "t", "job": "idle", "metrics": ["value"]})
    chapter = ROOT / "notebooks" / "04_anfis_method.ipynb"
    assert {"learning.jang", "learning.anfis", "presentation.plotting", "presentation.tables"} <= set(notebook_modules(chapter))
    keys = lambda: (sweep.code_key(job), _chapter_key(chapter, {}, False))          # noqa: E731
    before = keys()
    edit(package, "presentation.recording")           # imported by neither the jobs nor chapter 04
    assert keys() == before
    edit(package, "presentation.plotting")            # chapter 04 draws with it; no job imports it
    after = keys()
    assert after[0] == before[0] and after[1] != before[1]
    edit(package, "learning.anfis")               # both
    assert all(a != b for a, b in zip(keys(), after))
