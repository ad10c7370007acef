"""What chapter 7 tests, loaded once: the study, its held-out data and chapter 6's frozen models.

Chapter 7 reads the models chapter 6 chose on validation from the chosen-model store
(:class:`nfarm.study.chosen_models.ChosenModels`) and the data sets chapter 5 built, and tests
each once on the held-out split. :func:`load_tested` gathers them in one record,
:class:`TestedModels`, so that the chapter's first cell is one call; a store that chapter 6 has not
filled for this arm is a one-line ``RuntimeError`` that says which chapter to run first.

Example (the smoke models of ``make test``'s chapter 6 runs)::

    tested = load_tested("params/studies/intelbot5.yaml", smoke=True)
    tested.robot.name, sorted(tested.rivals)[:2], tested.test["T"].shape
    # ('intelbot5', ['kernel_ridge', 'kernel_ridge:arm'], (N, 4, 4))
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..infra.reading import ParamsError
from ..learning.learned import LearnedIK
from ..learning.learned_id import LearnedID
from ..presentation.notices import noted, notes_text
from . import contest, datasets, study_files
from .chosen_models import ChosenModels

__all__ = ["TestedModels", "load_tested", "SMOKE_LM_TARGETS", "SMOKE_DRAWS"]

#: A smoke run's LM targets and bootstrap resamples (a few hundred poses: enough to run the code).
SMOKE_LM_TARGETS, SMOKE_DRAWS = 100, 200


@dataclass(frozen=True)
class TestedModels:
    """Chapter 7's inputs (:func:`load_tested`).

    Attributes:
        study: the study file as read (a smoke run's thinned copy in smoke mode).
        notes: what reading the robot warned, as Markdown ("" when nothing).
        directory: the data sets' directory (chapter 5's).
        data: the splits by name, ``"ik_train"``, ``"ik_val"``, ``"ik_test"``, ``"id_test"`` (and
            ``"ik_full_train"``, ``"ik_full_test"`` for a study with full-range data).
        store: the chosen-model store chapter 6 wrote.
        learned, recipe: the chosen learned IK; the dissertation's recipe by data kind
            (``"ik"``: the region's, ``"ik_full"``: the full range's, where the study has it), and ``"ik_fcm"``
            the fuzzy c-means ANFIS on the same seven inputs (:data:`nfarm.study.contest.SEVEN_FCM`), where chapter 6 saved it.
        rivals: the learned-IK contest's chosen rivals by contestant (``"rbf"``, ``"rbf:arm"``, …).
        id_learned, id_recipe, id_identified: the chosen model-free ANFIS for the inverse
            dynamics, the dissertation's design (assumed) and the identification on the regressor.
        id_seed_like: the chosen ANFIS and the design trained the dissertation's way, by name
            (``"model_free"``, ``"dissertation"``).
        other_seeds: the draws chapter 6 trained its finalists on besides seed 0.
        lm_targets, bootstrap_draws: the chapter's, or a smoke run's smaller ones.
    """

    __test__ = False                  # a record, not a test class (pytest collects names that start with "Test")

    study: Any
    notes: str
    directory: Path
    data: Mapping[str, Mapping]
    store: ChosenModels
    learned: LearnedIK
    recipe: Mapping[str, LearnedIK]
    rivals: Mapping[str, Any]
    id_learned: LearnedID
    id_recipe: LearnedID
    id_identified: LearnedID
    id_seed_like: Mapping[str, LearnedID]
    other_seeds: tuple[int, ...]
    lm_targets: int
    bootstrap_draws: int

    @property
    def robot(self):
        return self.study.robot

    @property
    def region(self):
        return self.study.ik_region

    @property
    def test(self) -> Mapping:
        """The IK test split: ``T (N, 4, 4)``, ``q (N, n)`` [rad]."""
        return self.data["ik_test"]

    @property
    def train(self) -> Mapping:
        """The IK training split."""
        return self.data["ik_train"]

    @property
    def has_measured(self) -> bool:
        """Whether the study declares a measured arm (``id.measured``: section 7.6 runs)."""
        return self.study.id.measured is not None


def load_tested(study_file: str | os.PathLike, *, smoke: bool = False, data_dir=None, models_dir=None,
                lm_targets: int = 2000, bootstrap_draws: int = 2000,
                spread_seeds: Sequence[int] | None = None) -> TestedModels:
    """The study of ``study_file``, its held-out data (``data_dir``, as chapter 5 built it) and the
    models chapter 6 chose (``models_dir``, else ``build/models/<robot>/``), as a :class:`TestedModels`.
    ``smoke``: the smoke study, :data:`SMOKE_LM_TARGETS` and :data:`SMOKE_DRAWS`, and chapter 6's
    smoke spread seeds unless ``spread_seeds`` names them.

    Raises:
        RuntimeError: chapter 6 has not saved this arm's models (its contest's rivals among them)
            in the store: one line naming the store and the chapter to run.
    """
    with noted() as caught:          # what reading the robot warns, said once
        study = study_files.load_study(study_file)
    notes = notes_text(caught, "the study's robot") if caught else ""
    if smoke:
        study = study_files.smoke_study(study)
        lm_targets, bootstrap_draws = SMOKE_LM_TARGETS, SMOKE_DRAWS
        spread_seeds = list(contest.SMOKE_SPREAD_SEEDS) if spread_seeds is None else spread_seeds
    other_seeds = contest.SPREAD_SEEDS if spread_seeds is None else tuple(spread_seeds)
    robot = study.robot
    directory = datasets.dataset_dir(study, data_dir)
    kinds = ["ik"] + (["ik_full"] if study.ik_full_range else [])
    data = {f"{kind}_{split}": datasets.load(directory / f"{kind}_{split}.npz", robot, study)
            for kind in kinds for split in ("train", "test")}
    data["ik_val"] = datasets.load(directory / "ik_val.npz", robot, study)   # the IK baselines are chosen on it
    data["id_test"] = datasets.load(directory / "id_test.npz", robot, study)
    store = ChosenModels.of(models_dir, directory)
    try:
        learned = LearnedIK.load(store.ik, robot)
        recipe = {"ik": LearnedIK.load(store.ik_dissertation, robot)}
        if study.ik_full_range:
            recipe["ik_full"] = LearnedIK.load(store.ik_dissertation_full, robot)
        if store.ik_contestant(contest.SEVEN_FCM).is_dir():       # the seven inputs' fuzzy c-means ANFIS (issue 64)
            recipe["ik_fcm"] = LearnedIK.load(store.ik_contestant(contest.SEVEN_FCM), robot)
        rivals = contest.saved_rivals(robot, store.root)
        id_models = (LearnedID.load(store.id_model_free, robot), LearnedID.load(store.id_dissertation, robot),
                     LearnedID.load(store.id_identified, robot))
        id_seed_like = {name: LearnedID.load(store.id_seed_like(name), robot) for name in ("model_free", "dissertation")}
    except ParamsError as exc:
        raise RuntimeError(f"chapter 07 tests the models of chapter 06, run it first ({exc})") from None
    if not rivals:
        raise RuntimeError(f"chapter 07 compares chapter 06's contest rivals, and {store.root} holds none for "
                           f"{robot.name}: run chapter 06 for it first")
    return TestedModels(study, notes, directory, data, store, learned, recipe, rivals, *id_models, id_seed_like,
                        tuple(other_seeds), lm_targets, bootstrap_draws)
