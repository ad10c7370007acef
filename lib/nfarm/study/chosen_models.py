"""The chosen models' store: where chapter 6 saves the models it chose on validation, and where
chapters 7 and 8 (and anyone with the checkout) load them, frozen, to test them.

One directory per arm, ``build/models/<robot>/`` (a smoke run's ``<robot>-smoke/``, or the
chapter's ``models_dir``)::

    ik/                       the chosen learned IK (LearnedIK.load(directory, robot))
    ik/dissertation/          the dissertation's 7-input recipe, as the contest trained it
    ik/dissertation_full/     the recipe as it is, on its naive data over the full joint ranges
    ik_contest/<contestant>/  each contestant's chosen configuration ("rbf_arm" for "rbf:arm")
    id_model_free/            the chosen ANFIS for the inverse dynamics (no lengths or masses)
    id/dissertation/          the dissertation's ID design (assumed)
    id/identified/            the identification on the regressor's inputs (a reference)
    id_seed_like/<name>/      the chosen ANFIS and the design trained on the dissertation's cubics
    id_measured/<tier>/<slot> each tier's two finalists on the measured arm, with the built arm
                              (built_arm.yaml; built_arm_draw<k>.yaml, the arm built for the
                              finalists' draw k) and its torque readings' offsets beside them
    results/                  chapter 7's verdict and summary tables (chapter 8 reads them)

Each published model is a copy of a sweep cell's (:func:`publish`) and keeps beside it the cells
of its configuration over the seeds (:mod:`nfarm.study.replicates`), for chapter 7's intervals.

Example:
    >>> store = ChosenModels("build/models/intelbot5")
    >>> store.ik_contestant("rbf:arm").as_posix(), store.id_finalist("structure-informed", "anfis").as_posix()
    ('build/models/intelbot5/ik_contest/rbf_arm', 'build/models/intelbot5/id_measured/structure_informed/anfis')
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from ..infra.paths import BUILD, atomic_path, project_path, shown_path
from ..model.robot import robot_to_dict
from . import contest, replicates
from .datasets import built_arm
from .study_files import redrawn
from .jobs import contest_model, id_contest_model, id_model, ik_model
from .sweep import CellResult, Replicates

__all__ = ["ChosenModels", "publish", "save_built_arm", "PLANE", "RECIPE", "ChosenIK", "publish_chosen_ik",
           "ID_OPTION_KEYS", "configuration_of", "ChosenID", "publish_chosen_id", "publish_finalists",
           "publish_seed_like"]


@dataclass(frozen=True)
class ChosenModels:
    """The store of one arm's chosen models (module docstring): each property a directory that
    holds one saved model, ``root`` the arm's models directory."""

    root: Path

    def __post_init__(self):
        object.__setattr__(self, "root", Path(self.root))

    @classmethod
    def of(cls, models_dir: str | os.PathLike | None, dataset_dir: str | os.PathLike) -> "ChosenModels":
        """The store a chapter uses: ``models_dir`` (relative to the checkout), or by default
        ``build/models/<name of the data sets' directory>/`` (``intelbot5``, ``intelbot5-smoke``)."""
        return cls(project_path(models_dir) if models_dir else BUILD / "models" / Path(dataset_dir).name)

    # The learned IK
    @property
    def ik(self) -> Path:
        return self.root / "ik"

    @property
    def ik_dissertation(self) -> Path:
        return self.ik / "dissertation"

    @property
    def ik_dissertation_full(self) -> Path:
        return self.ik / "dissertation_full"

    @property
    def ik_contest(self) -> Path:
        return self.root / "ik_contest"

    def ik_contestant(self, name: str) -> Path:
        """Contestant ``name``'s chosen model (:func:`nfarm.study.contest.family`: ``"rbf:arm"``
        is saved as ``ik_contest/rbf_arm/``)."""
        return self.ik_contest / name.replace(":", "_")

    # The learned ID
    @property
    def id_model_free(self) -> Path:
        return self.root / "id_model_free"

    @property
    def id(self) -> Path:
        return self.root / "id"

    @property
    def id_dissertation(self) -> Path:
        return self.id / "dissertation"

    @property
    def id_identified(self) -> Path:
        return self.id / "identified"

    def id_seed_like(self, name: str) -> Path:
        """A model trained on the dissertation's cubics: ``"model_free"`` or ``"dissertation"``."""
        return self.root / "id_seed_like" / name

    @property
    def id_measured(self) -> Path:
        return self.root / "id_measured"

    def id_finalist(self, tier: str, slot: str) -> Path:
        """A tier's finalist on the measured arm, ``slot`` ``"anfis"`` or ``"rival"``
        (:func:`nfarm.study.contest.id_model_dir`)."""
        return contest.id_model_dir(self.root, tier, slot)

    @property
    def results(self) -> Path:
        """Chapter 7's verdict and summary tables beside the models they judge (chapter 8 reads them)."""
        return self.root / "results"

    @property
    def built_arm(self) -> Path:
        """The measured arm as built, a robot file (:func:`nfarm.model.robot.load_robot` reads it)."""
        return self.id_measured / "built_arm.yaml"

    def built_arm_of(self, draw: int) -> Path:
        """The arm built for data draw ``draw`` (a finalist's seed), a robot file; draw 0's is :attr:`built_arm`."""
        return self.built_arm if draw == 0 else self.id_measured / f"built_arm_draw{int(draw)}.yaml"

    def built_arm_offsets_of(self, draw: int) -> Path:
        """Its torque readings' zero offsets [N·m] (draw 0's: :attr:`built_arm_offsets`)."""
        return self.built_arm_offsets if draw == 0 else self.id_measured / f"built_arm_draw{int(draw)}_offsets.yaml"

    @property
    def built_arm_offsets(self) -> Path:
        """The built arm's torque readings' zero offsets [N·m], by joint."""
        return self.id_measured / "built_arm_offsets.yaml"


def publish(model, where: str | os.PathLike, job: str | None = None, group=None):
    """Save ``model`` where chapters 7 and 8 read it (a copy of its sweep cell's) and return it;
    given ``group`` (its configuration over the seeds, a :class:`nfarm.study.sweep.Replicates`),
    with the cells of ``job`` that train it on every seed the sweep ran beside it
    (:func:`nfarm.study.replicates.write_seeds`). A copy is not a cached fit: the cache's
    ``inputs.sha256`` and an earlier ``seeds.json`` there are removed first."""
    where = Path(where)
    (where / "inputs.sha256").unlink(missing_ok=True)
    (where / replicates.SEEDS_FILE).unlink(missing_ok=True)
    model.save(where)
    if group is not None:
        replicates.write_seeds(where, job, [r.cell.params for r in group.runs])
    return model


def save_built_arm(store: ChosenModels, study, study_file: str | os.PathLike,
                   draws: Sequence[int] = (0,)) -> tuple[Path, ...]:
    """Write the study's measured arm as built for each of ``draws`` (:func:`nfarm.study.datasets.built_arm`
    of the redrawn study: draw k's data and its models' test judge the k-th arm built) beside its
    finalists: a robot file any dynamics engine can take (its DH table and links), its
    ``description`` naming the study file and the seed that drew the links, and its torque readings'
    zero offsets; its friction's breakaway and load terms and its sensor's counts and noise are
    the study file's (``id.measured``). Returns the paths, two a draw (:meth:`ChosenModels.built_arm_of`,
    :meth:`ChosenModels.built_arm_offsets_of`), draw 0's ``built_arm.yaml`` first."""
    written = []
    for draw in dict.fromkeys([0, *(int(d) for d in draws)]):
        drawn = redrawn(study, draw)
        built, zero_offset = built_arm(drawn)
        built_dict = robot_to_dict(built)
        which = "chapter 5's measured arm" if draw == 0 else f"the arm built for draw {draw}"
        built_dict["description"] = (f"{study.robot.name} as built: {which}, its links drawn from "
                                     f"{shown_path(project_path(study_file))}'s seed (+{draw}: {drawn.seed})")
        texts = ((store.built_arm_of(draw), yaml.safe_dump(built_dict, sort_keys=False)),
                 (store.built_arm_offsets_of(draw), yaml.safe_dump(
                     {"joints": list(study.robot.joint_names), "zero_offset_nm": [float(x) for x in zero_offset]},
                     sort_keys=False)))
        for path, text in texts:
            path.parent.mkdir(parents=True, exist_ok=True)
            with atomic_path(path) as tmp:
                tmp.write_text(text, encoding="utf-8")
            written.append(path)
    return tuple(written)


# --------------------------------------------------------------------------------------------
# What chapter 6 publishes

#: The ANFIS in the arm's plane and the dissertation's 7-input recipe, as contestants
#: (:func:`nfarm.study.contest.family`).
PLANE, RECIPE = "anfis:arm_plane", "anfis:quat_xyz"


@dataclass(frozen=True)
class ChosenIK:
    """The learned IK models chapter 6.2 publishes (:func:`publish_chosen_ik`).

    Attributes:
        name: the chosen learned IK's contestant: :data:`PLANE`, or :data:`RECIPE` on an arm the
            arm's plane cannot describe.
        model: the chosen learned IK (the chapter's seed).
        saved: every contestant's chosen configuration's model (the chapter's seed), by contestant.
        recipe: the dissertation's recipe, ``"ik"`` as the contest trained it and ``"ik_full"`` as it
            is on its full-range data (those the study has).
        standing: the chosen configuration over its seeds, as the contest ranked it.
    """

    name: str
    model: Any
    saved: Mapping[str, Any]
    recipe: Mapping[str, Any]
    standing: Replicates


def publish_chosen_ik(store: ChosenModels, chosen: Mapping[str, CellResult], ranked: Sequence[Replicates],
                      recipe_runs: Iterable[CellResult], seed: int = 0) -> ChosenIK:
    """Publish every contestant's chosen configuration (``chosen``: :func:`nfarm.study.contest.choose`)
    as trained on the chapter's ``seed`` with its cells over the seeds (``ranked``:
    :func:`nfarm.study.contest.standings`), the chosen learned IK, the recipe, and the recipe as it
    is (``recipe_runs``: the full-range sweep's cells); the sweeps' models are reused, not retrained."""
    groups = {contest.family(g.cell.params): g for g in ranked}
    saved = {name: publish(contest_model({**r.cell.params, "seed": seed}), store.ik_contestant(name), "ik_contest",
                           groups[name]) for name, r in chosen.items()}
    for name, r in chosen.items():      # its validation metrics, by which chapters 7-8 rank the frozen rivals
        contest.save_validation(store.ik_contestant(name), r)
    name = PLANE if PLANE in saved else RECIPE
    model = publish(saved[name], store.ik, "ik_contest", groups[name])
    recipe = {}
    if RECIPE in saved:
        recipe["ik"] = publish(saved[RECIPE], store.ik_dissertation, "ik_contest", groups[RECIPE])
    for r in recipe_runs:
        recipe["ik_full"] = publish(ik_model(r.cell.params), store.ik_dissertation_full)
    return ChosenIK(name, model, saved, recipe, next(g for g in ranked if contest.family(g.cell.params) == name))


#: The parameters of a ``learned_id`` cell that make its model (the others name its data).
ID_OPTION_KEYS = ("inputs", "residual", "shared_premises", "partition", "n_mfs", "n_rules", "radius", "mf", "epochs",
                  "joint_options")


def configuration_of(results: Iterable[Replicates], options: Mapping[str, Any], **fixed) -> Replicates | None:
    """The configuration of ``results`` whose cells have these ``options`` and ``fixed`` parameters
    (a stride, the torques, the trajectories), or ``None`` if the sweep holds none."""
    wanted = {**fixed, **options}
    return next((r for r in results if all(r.cell.params.get(k) == v for k, v in wanted.items())), None)


@dataclass(frozen=True)
class ChosenID:
    """The learned ID models chapter 6.7 publishes (:func:`publish_chosen_id`), each its
    configuration's cell on the chapter's seed at the chosen configuration's stride.

    Attributes:
        best: the chosen configuration over its seeds (the best without the arm's lengths or masses).
        options: its model's options (:data:`ID_OPTION_KEYS`); ``stride``: its training stride.
        model_free, dissertation, identified: the chosen ANFIS, the dissertation's design
            (assumed) and the identification on the regressor's inputs (the reference).
    """

    best: Replicates
    options: Mapping[str, Any]
    stride: int
    model_free: Any
    dissertation: Any
    identified: Any


def publish_chosen_id(store: ChosenModels, best: Replicates, results: Sequence[Replicates],
                      cell_of: Callable[..., dict], id_dissertation: Mapping[str, Any],
                      id_identified: Mapping[str, Any]) -> ChosenID:
    """Publish the chosen ANFIS (``best``, with its cells over the seeds), the dissertation's
    design (with its configuration's cells in ``results``, if the sweep holds it) and the
    identification; ``cell_of(options, stride)``: a ``learned_id`` cell of these options on the
    chapter's seed (:meth:`nfarm.study.training_setup.TrainingSweeps.chosen_cell`). A configuration
    the sweep does not hold is trained the way its cells are."""
    options = {k: v for k, v in best.cell.params.items() if k in ID_OPTION_KEYS and v is not None}
    stride = best.cell.params["stride"]
    model_free = publish(id_model(cell_of(options, stride)), store.id_model_free, "learned_id", best)
    dissertation = publish(id_model(cell_of(id_dissertation, stride)), store.id_dissertation, "learned_id",
                           configuration_of(results, id_dissertation, stride=stride))
    identified = publish(id_model(cell_of(id_identified, stride)), store.id_identified)
    return ChosenID(best, options, stride, model_free, dissertation, identified)


def publish_finalists(store: ChosenModels, idc: contest.IDContest, seed: int = 0) -> None:
    """Publish each tier's two finalists of the measured arm's contest (``idc``:
    :func:`nfarm.study.contest.id_contest`) on the chapter's ``seed``, with their cells over the
    seeds: ``id_measured/<tier>/<anfis|rival>/``, loadable by :func:`nfarm.learning.baselines.load_id_model`."""
    for tier in idc.tiers:
        for slot, g in zip(("anfis", "rival"), idc.pair(tier)):
            if g is not None:
                publish(id_contest_model({**g.cell.params, "seed": seed}), store.id_finalist(tier, slot), "id_contest", g)


def publish_seed_like(store: ChosenModels, ablation: Sequence[Replicates], designs: Mapping[str, Mapping[str, Any]],
                      seed_like: Mapping[str, Any], seed: int = 0) -> dict[str, Replicates]:
    """Publish each of ``designs`` (name → its options: ``"model_free"``, ``"dissertation"``) as
    trained on the dissertation's cubic trajectories (``seed_like``) on the chapter's seed, and
    return their configurations in ``ablation`` (over the ablation seeds), by name.

    Raises:
        ValueError: ``ablation`` holds no configuration of a design on these trajectories.
    """
    groups = {}
    for name, options in designs.items():
        g = configuration_of(ablation, options, torques="rigid", seed_like=dict(seed_like))
        if g is None:
            raise ValueError(f"no ablation cell of {name} ({dict(options)}) on the trajectories {dict(seed_like)}")
        groups[name] = g
        publish(id_model({**g.cell.params, "seed": seed}), store.id_seed_like(name))
    return groups
