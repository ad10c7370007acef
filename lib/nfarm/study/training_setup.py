"""Chapter 6's set-up: the study's data (chapter 5's, built or reused), whether the arm's plane
describes the arm's poses, and the sweeps whose cells train every model the chapter shows.

Every model of chapter 6 is a cell of a sweep (:mod:`nfarm.study.sweep`), so that a cluster
runs them unchanged: the learned-IK contest (``params/sweeps/ik_contest.yaml``), the ID input
sets (``id_comparison``), the scikit-learn baselines (``id_baselines``), the ID data sizes
(``id_sizes``) and the measured arm's contest (``id_contest``), each restricted to this arm's
cells (:class:`TrainingSweeps`), and two sweeps the chapter writes itself: the dissertation's
recipe on its naive full-range data, and the ID designs trained on the dissertation's cubic
trajectories (section 6.9).

Example (the smoke run's smaller designs):
    >>> smoke_designs({"encoding": "quat_xyz", "n_mfs": 2, "epochs": 10}, {"inputs": "own", "n_mfs": 3},
    ...               [0, 1, 2, 3, 4], None).id_size_strides
    [4, 1]
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from ..learning.learned import arm_chart, out_of_plane
from ..model.robot import Robot
from ..presentation.notices import noted, notes_text
from . import contest, datasets, study_files
from .chosen_models import ChosenModels
from .statistics import resolved_joints
from .sweep import CellResult, Sweep, load_sweep, sweep_from_dict

__all__ = ["SmokeDesigns", "smoke_designs", "read_study", "TrainingSetup", "training_setup", "TrainingSweeps",
           "training_sweeps"]


class SmokeDesigns(NamedTuple):
    """The chapter's designs at a smoke run's size (:func:`smoke_designs`)."""

    dissertation: dict
    id_dissertation: dict
    id_size_strides: list
    ablation_seeds: list
    spread_seeds: list


def smoke_designs(dissertation: Mapping, id_dissertation: Mapping, ablation_seeds: Sequence[int],
                  spread_seeds: Sequence[int] | None) -> SmokeDesigns:
    """The designs of a smoke run (a few hundred samples): rule bases small enough to be
    determined by them (two functions on the quaternion's first three inputs, one on the others;
    two per ID input), two epochs, two training sizes of the measured arm's finalists, the first
    two ablation seeds, and :data:`nfarm.study.contest.SMOKE_SPREAD_SEEDS` unless seeds are given."""
    return SmokeDesigns({**dissertation, "n_mfs": [2, 2, 2, 1, 1, 1, 1], "epochs": 2},
                        {**id_dissertation, "n_mfs": 2, "epochs": 2}, [4, 1], list(ablation_seeds[:2]),
                        list(contest.SMOKE_SPREAD_SEEDS) if spread_seeds is None else spread_seeds)


def read_study(study_file: str | os.PathLike, *, smoke: bool = False) -> tuple[study_files.Study, str]:
    """The study of ``study_file`` (its smoke-sized study with ``smoke``) and the sentence saying
    what reading its robot warned (:func:`nfarm.presentation.notices.notes_text`; ``""`` for
    nothing), for the chapter to say once."""
    with noted() as notes:
        study = study_files.load_study(study_file)
    text = notes_text(notes, "the study's robot")
    return (study_files.smoke_study(study) if smoke else study), text


@dataclass(frozen=True)
class TrainingSetup:
    """What chapter 6 trains on (:func:`training_setup`).

    Attributes:
        study: the study (smoke-sized in a smoke run).
        data: the data sets by name — ``"ik_train"``, ``"ik_val"`` (``T (N, 4, 4)``, ``q (N, n)``
            [rad]), ``"id_train"``, ``"id_val"`` (``q, qd, qdd (N, n)``, ``tau (N, n)`` [N·m], and
            the measured arm's ``tau_measured``), and ``"ik_full_train"``, ``"ik_full_val"`` where
            the study has full-range data. Never a test split: the chapter chooses on validation.
        dataset_dir: the data sets' directory.
        models: the chosen models' store.
        worst_out_of_plane: ``[rad]`` the most the tool's roll axis leaves the arm's vertical
            plane on the training poses.
        planar: whether the arm's plane describes the poses (``worst_out_of_plane`` within the
            chapter's ``max_out_of_plane_deg``).
    """

    study: study_files.Study
    data: Mapping[str, Any]
    dataset_dir: Path
    models: ChosenModels
    worst_out_of_plane: float
    planar: bool

    @property
    def robot(self) -> Robot:
        return self.study.robot

    @property
    def has_measured(self) -> bool:
        """Whether the study declares a measured arm and its data hold the measured torques."""
        return self.study.id.measured is not None and "tau_measured" in self.data["id_train"]

    @property
    def resolved(self) -> np.ndarray:
        """``(n,)`` bool: the joints whose rigid-body torque spread on the validation trajectories
        reaches the sensor noise (:func:`nfarm.study.statistics.resolved_joints`)."""
        return resolved_joints(self.data["id_val"]["tau"].std(axis=0), self.study.id.noise)


def training_setup(study: study_files.Study, data_dir: str | os.PathLike | None = None,
                   models_dir: str | os.PathLike | None = None, *,
                   max_out_of_plane_deg: float = 0.5) -> TrainingSetup:
    """Build (or reuse, when up to date: chapter 5) the study's data sets in ``data_dir``
    (default ``build/datasets/<robot>/``), read their training and validation splits, and find
    whether the arm-plane chart loses at most ``max_out_of_plane_deg`` [deg] on this arm's
    training poses (a CAD model's sub-millimetre offsets). ``models_dir``: the chosen models'
    store (default ``build/models/<robot>/``)."""
    datasets.build_datasets(study, data_dir)
    directory = datasets.dataset_dir(study, data_dir)
    robot = study.robot
    data = {f"{kind}_{split}": datasets.load(directory / f"{kind}_{split}.npz", robot, study)
            for kind in (["ik", "id"] + (["ik_full"] if study.ik_full_range else [])) for split in ("train", "val")}
    worst = float(out_of_plane(data["ik_train"]["T"], arm_chart(robot)).max())
    return TrainingSetup(study, data, directory, ChosenModels.of(models_dir, directory), worst,
                         bool(worst <= np.radians(max_out_of_plane_deg)))


@dataclass(frozen=True)
class TrainingSweeps:
    """The sweeps of chapter 6, restricted to this arm's cells (:func:`training_sweeps`).

    Attributes:
        contest: the learned-IK contest (6.1), every configuration at both rungs.
        id, baselines, id_sizes: sections 6.4, 6.5 and 6.6's rigid-body ID sweeps.
        id_contest: the measured arm's contest (6.8); no cells when the study has no measured arm.
        recipe: the dissertation's recipe on its full-range data (the chapter's seed; no cells
            when the study has no full-range data).
        fixed: the dissertation's ID design on its cubic trajectories over the ablation seeds (6.9).
        draws: this arm's study file, data and models directories (every cell's).
        single: a cell's parameters at full size (``draws``, ``smoke``, ``fraction`` 1).
        seed: the chapter's seed (the chosen models' draw).
        ablation_seeds, other_seeds: the ablation's seeds, the spread's (besides seed 0).
        seed_like: the dissertation program's cubic trajectories (:func:`nfarm.study.id_trajectories.seed_like_trajectories`).
    """

    contest: Sweep
    id: Sweep
    baselines: Sweep
    id_sizes: Sweep
    id_contest: Sweep
    recipe: Sweep
    fixed: Sweep
    draws: Mapping[str, Any]
    single: Mapping[str, Any]
    seed: int
    ablation_seeds: tuple[int, ...]
    other_seeds: tuple[int, ...]
    seed_like: Mapping[str, Any]

    @property
    def id_stride(self) -> int:
        """Section 6.4's stride: every ``id_stride``-th training state."""
        return self.id.cells[0].params["stride"]

    @property
    def contest_rung(self) -> Sweep:
        """The contest's first rung of successive halving: every configuration on a share of
        the training poses (:data:`nfarm.study.contest.RUNG_FRACTION`), seed 0."""
        return self.contest.restrict(fraction=contest.RUNG_FRACTION)

    def over_seeds(self, options: Mapping[str, Any], seeds: Sequence[int] | None = None, **more) -> list[dict]:
        """``learned_id`` cells of these options over ``seeds`` (default the ablation seeds), on
        every :attr:`id_stride`-th training state (as section 6.4's)."""
        seeds = self.ablation_seeds if seeds is None else seeds
        return [{**self.single, "seed": s, "stride": self.id_stride, **options, **more} for s in seeds]

    def chosen_cell(self, options: Mapping[str, Any], stride: int, **more) -> dict:
        """A ``learned_id`` cell of these options on the chapter's seed (the study's own data),
        at ``stride``: how a chosen ID model is trained (section 6.7)."""
        return {**self.draws, "smoke": self.single["smoke"], "seed": self.seed, "stride": stride, **options, **more}

    def ablation(self, options: Mapping[str, Any]) -> Sweep:
        """The chosen ANFIS's options on the dissertation's cubic trajectories, the chapter's
        seed only (section 6.9: 45–50 s a fit at full size)."""
        return self.id.with_cells(self.over_seeds(options, [self.seed], seed_like=self.seed_like), name="id_models")

    def spreads(self, contest_chosen: Mapping[str, CellResult], id_runs: Sequence[CellResult],
                base_runs: Sequence[CellResult], resolved) -> list[Sweep]:
        """The third batch: the contest's chosen configurations in contention on the other
        draws (:func:`nfarm.study.contest.spread_params`), each tier's best of sections 6.4 and
        6.5 on them (seed 0, over the ``resolved`` joints; :func:`nfarm.study.contest.tier_finalists`),
        and the measured arm's tuning round, which depends on no choice."""
        return [self.contest.with_cells(contest.spread_params(contest_chosen, self.other_seeds)),
                self.id.with_cells(contest.tier_spread_params(id_runs, resolved, "val_nrmse", seeds=self.other_seeds)),
                self.baselines.with_cells(contest.tier_spread_params(base_runs, resolved, "nrmse",
                                                                     seeds=self.other_seeds)),
                self.id_contest]

    def measured_finalists(self, idc_runs: Sequence[CellResult], strides: Sequence[int],
                           spread: Sequence[CellResult] = ()) -> list[Sweep]:
        """The measured arm's finalists (of the tuning round ``idc_runs``, seed 0) on the other
        draws — the leaders' without ``spread``, and with their cells on those draws (``spread``)
        also those within their reach (:func:`nfarm.study.contest.id_contending`) — and the leaders
        on every ``strides``-th training state (seed 0)."""
        first = contest.id_contest(idc_runs)
        return [self.id_contest.with_cells(contest.id_spread_params(idc_runs, self.other_seeds, spread)),
                self.id_contest.with_cells([{**first.chosen[name].cell.params, "stride": s}
                                            for name in first.leaders for s in strides])]


    def paired_sizes(self, idc: contest.IDContest, strides: Sequence[int]) -> Sweep:
        """The cells on every ``strides``-th training state (seed 0) of each tier's pair in ``idc``
        (:attr:`nfarm.study.contest.IDContest.paired`) that :meth:`measured_finalists` did not run:
        a rival within reach that overtook its tier's leader over the seeds."""
        return self.id_contest.with_cells([{**idc.chosen[name].cell.params, "stride": s} for name in idc.paired
                                           if name not in idc.leaders for s in strides])


def training_sweeps(setup: TrainingSetup, *, study_file: str, data_dir=None, models_dir=None, smoke: bool = False,
                    seed: int = 0, contest_sweep_file: str, id_sweep_file: str, id_baselines_sweep_file: str,
                    id_sizes_sweep_file: str, id_contest_sweep_file: str, dissertation: Mapping[str, Any],
                    id_dissertation: Mapping[str, Any], seed_like: Mapping[str, Any], ablation_seeds: Sequence[int],
                    spread_seeds: Sequence[int] | None = None, max_out_of_plane_deg: float = 0.5) -> TrainingSweeps:
    """Chapter 6's sweeps (:class:`TrainingSweeps`) for this arm's study file, data and models
    directories, read from their files (their smoke sizes with ``smoke``). On an arm the arm's
    plane cannot describe (``setup.planar`` false) every IK contestant takes the recipe's seven
    inputs, and none the ANFIS's structure in the arm's plane; on one without a measured arm the
    measured arm's contest has no cells. ``spread_seeds``: the draws besides seed 0 (default
    :data:`nfarm.study.contest.SPREAD_SEEDS`)."""
    draws = {"study_file": study_file, "data_dir": data_dir, "models_dir": models_dir}
    contest_sweep = load_sweep(contest_sweep_file, smoke=smoke).restrict(**draws, max_out_of_plane_deg=max_out_of_plane_deg)
    if not setup.planar:
        contest_sweep = contest_sweep.select(lambda p: (p["learner"] != "anfis" or p["encoding"] != "arm_plane")
                                             and contest.structure_of(contest.family(p)) != "arm") \
                                     .restrict(encoding="quat_xyz")
    id_sweep = load_sweep(id_sweep_file, smoke=smoke).restrict(**draws)
    idc_sweep = load_sweep(id_contest_sweep_file, smoke=smoke).restrict(**draws)
    if not setup.has_measured:
        idc_sweep = idc_sweep.select(lambda p: False)
    single = {**draws, "smoke": smoke, "fraction": 1.0}
    recipe = sweep_from_dict({"name": "ik_models", "description": "the dissertation's recipe on full-range data",
                              "job": "learned_ik", "fixed": {"study_file": study_file}, "metrics": ["val_rmse_deg"]},
                             "chapter 6").with_cells(
        [{**single, "seed": seed, **dissertation, "poses": "full_range"}] if setup.study.ik_full_range else [])
    other_seeds = contest.SPREAD_SEEDS if spread_seeds is None else tuple(spread_seeds)
    sweeps = TrainingSweeps(contest_sweep, id_sweep, load_sweep(id_baselines_sweep_file, smoke=smoke).restrict(**draws),
                            load_sweep(id_sizes_sweep_file, smoke=smoke).restrict(**draws), idc_sweep, recipe, id_sweep,
                            draws, single, seed, tuple(ablation_seeds), other_seeds, dict(seed_like))
    fixed = id_sweep.with_cells(sweeps.over_seeds(id_dissertation, seed_like=seed_like), name="id_models")
    return replace(sweeps, fixed=fixed)
