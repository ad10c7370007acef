"""The chosen inverse-dynamics models as chapter 6.7 and 6.9 report them: how their training
went, the models chapter 7 tests, and the chosen ANFIS trained the dissertation's way.

The models are published by :func:`nfarm.study.chosen_models.publish_chosen_id` and
:func:`~nfarm.study.chosen_models.publish_seed_like`; errors are validation NRMSEs read as
section 6.4 reads them (:class:`nfarm.study.id_comparison_report.TorqueReading`).

Example (the largest speed of each joint over a trajectory's states, in degrees):
    >>> import numpy as np
    >>> largest_deg({"qd": np.array([[0.1, -0.2], [-0.3, 0.0]])}, "qd").round(2).tolist()
    [17.19, 11.46]
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from ..infra.paths import BUILD, project_path, shown_path
from ..learning.bases import tier_of
from ..learning.per_joint import n_parameters
from ..presentation.plotting import plot_joint_curves
from ..presentation.tables import Table
from ..presentation.wording import listed
from .chosen_models import ChosenID, ChosenModels, configuration_of
from .configurations import kept_validation_loss
from .id_comparison_report import TorqueReading, same
from .jobs import id_training_data
from .sweep import CellResult, Replicates

__all__ = ["curves_figure", "curves_prose", "models_table", "largest_deg", "SeedLikeData", "seed_like_data",
           "seed_like_table", "seed_like_prose", "distinct_cells", "models_note"]


def curves_figure(chosen: ChosenID, reading: TorqueReading, robot_name: str) -> tuple[Figure, str]:
    """The training and validation NRMSE [% of each joint's torque spread] per epoch of the
    chosen ANFIS's models, one per resolved joint; the figure and its caption."""
    resolved, tier = reading.resolved, tier_of(chosen.best.cell.params)
    fig = plot_joint_curves(chosen.model_free.models_, list(reading.joint_names), scale=100 / reading.spread,
                            unit="% of the joint's torque spread", quantity="NRMSE", symbol="τ",
                            joints=np.flatnonzero(resolved))
    fig.suptitle(f"{robot_name}: {reading.label(chosen.options)} ({tier})", fontsize=10)
    below = [f"τ{j + 1}" for j in range(len(resolved)) if not resolved[j]]
    return fig, (f"Training and validation NRMSE per epoch of the chosen ID models ({tier}), one per joint"
                 + (f" ({listed(below)}, below the sensor noise, left out)" if below else ""))


def curves_prose(chosen: ChosenID, reading: TorqueReading, *, flat: float = 0.05) -> str:
    """What the epochs after the first did: by how much Jang's gradient steps on the premises
    lowered a resolved joint's validation error below the first epoch's (under ``flat`` of it:
    the first epoch's least squares of the consequents do nearly all the learning)."""
    models = chosen.model_free.models_
    curves = [np.asarray(m.val_loss_curve_) for m in models]
    epochs = len(models[0].loss_curve_)
    fall = np.array([1 - c[m.best_epoch_] / c[0] for c, m in zip(curves, models)])   # share the later epochs removed
    fall = np.where(reading.resolved, fall, -np.inf)      # of the joints the figure shows (a sensor resolves)
    if epochs == 1:
        return "The model trains one epoch: the least squares of its consequents are the whole fit."
    if fall.max() <= 0:
        return (f"None of the {epochs - 1} epochs after the first lowers a joint's validation error: the kept epoch "
                f"is the first for every joint, and the first epoch's least squares of the consequents are the whole fit.")
    j = int(np.argmax(fall))
    return (f"After the first of its {epochs} epochs, Jang's gradient steps on the premises lower a joint's validation "
            f"error by at most {100 * fall.max():.2g} % of the first epoch's ({reading.joint_names[j]})"
            + (": the first epoch's least squares of the consequents do nearly all the learning, and the curves are flat."
               if fall.max() < flat else "."))


def _designs(chosen: ChosenID, id_dissertation: Mapping, id_identified: Mapping, reading: TorqueReading):
    tier = tier_of(chosen.best.cell.params)
    return ((f"chosen, {tier}: " + reading.label(chosen.options), chosen.model_free, chosen.options),
            ("dissertation's design (assumed): " + reading.label(id_dissertation), chosen.dissertation, id_dissertation),
            ("identification (reference): " + reading.label(id_identified), chosen.identified, id_identified))


def models_table(reading: TorqueReading, chosen: ChosenID, results: Sequence[Replicates], id_train: Mapping,
                 id_dissertation: Mapping[str, Any], id_identified: Mapping[str, Any], seed: int = 0) -> Table:
    """The ID models chapter 7 tests (each its configuration's cell on the study's own data,
    ``seed``): epochs, parameters, training states (of ``id_train``, at the chosen stride), each
    joint's validation NRMSE from its kept epoch, the worst joint, and the configuration's range
    over the sweep's seeds (``results``: section 6.4's configurations; "one run" if it holds none)."""
    r_ = reading
    rows = []
    for name, model, options in _designs(chosen, id_dissertation, id_identified, reading):
        nrmse = kept_validation_loss(model) / r_.spread
        group = configuration_of(results, options, stride=chosen.stride)
        rows.append([name, len(model.models_[0].loss_curve_), n_parameters(model), f"{len(id_train['q'][::chosen.stride]):,}",
                     *(r_.fmt(v) for v in nrmse), r_.fmt(nrmse[r_.resolved].max()),
                     r_.seeds_range(group) if group is not None else "one run"])
    return Table(["model", "epochs", "parameters", "training states", *r_.columns, f"{r_.worst} [%]",
                  f"{r_.worst}, the configuration over seeds [%]"], rows,
                 caption=f"Validation NRMSE per joint of the ID models chapter 7 tests (each its configuration's cell on the "
                         f"study's own data, seed {seed}), and the configuration's range over the sweep's seeds{r_.noise_note}")


def largest_deg(states: Mapping[str, np.ndarray], key: str) -> np.ndarray:
    """``(n,)`` each joint's largest ``|states[key]|`` over the states, in degrees (of a speed
    ``"qd"`` [rad/s] or an acceleration ``"qdd"`` [rad/s²]: deg/s, deg/s²)."""
    return np.degrees(np.abs(states[key])).max(axis=0)


@dataclass(frozen=True)
class SeedLikeData:
    """Section 6.9's two trainings (:func:`seed_like_data`): the configurations trained on the
    dissertation's cubic trajectories (``groups``: ``"model_free"``, ``"dissertation"``, over the
    ablation seeds) and the training states of the chapter's seed, made the dissertation's way
    (``cubic``) and this study's own at the same stride (``own``), each ``q, qd, qdd, tau``."""

    groups: Mapping[str, Replicates]
    cubic: Mapping[str, np.ndarray]
    own: Mapping[str, np.ndarray]


def seed_like_data(groups: Mapping[str, Replicates], chosen: ChosenID, cell_of, seed: int = 0) -> SeedLikeData:
    """The training states behind section 6.9's comparison (``cell_of(options, stride)``: the
    chapter's cell of these options, :meth:`nfarm.study.training_setup.TrainingSweeps.chosen_cell`)."""
    return SeedLikeData(groups, id_training_data({**groups["model_free"].cell.params, "seed": seed}),
                        id_training_data(cell_of(chosen.options, chosen.stride)))


def seed_like_table(reading: TorqueReading, data: SeedLikeData, chosen: ChosenID, results: Sequence[Replicates],
                    id_dissertation: Mapping[str, Any], seed_like: Mapping[str, Any], study, id_stride: int,
                    seed: int = 0) -> Table:
    """The training trajectories made the dissertation's way (``seed_like``: cubics of
    ``duration_s`` sampled every ``dt_s``) against this study's (the ``study``'s quintics, every
    ``id_stride``-th state), as many states of each: their largest speed and acceleration, and the
    chosen ANFIS's and the dissertation design's worst-joint validation NRMSE trained on each."""
    r_ = reading

    def with_range(g, model):
        """A configuration's mean worst NRMSE and its range over the seeds, or the one model's."""
        if g is None:
            return f"{r_.fmt((kept_validation_loss(model) / r_.spread)[r_.resolved].max())} (one run)"
        return f"{r_.fmt(g.metrics['worst_nrmse'])} ({r_.seeds_range(g) if g.n > 1 else 'one run'})"

    cubic, own = data.cubic, data.own
    rows = [["training states", f"{len(cubic['q']):,}", f"{len(own['q']):,}"],
            ["largest |q̇| [deg/s], over the joints", f"{largest_deg(cubic, 'qd').max():.3g}", f"{largest_deg(own, 'qd').max():.3g}"],
            ["largest |q̈| [deg/s²], over the joints", f"{largest_deg(cubic, 'qdd').max():.3g}",
             f"{largest_deg(own, 'qdd').max():.3g}"]]
    for name, options, own_model, words in (
            ("model_free", chosen.options, chosen.model_free, f"chosen ANFIS ({tier_of(chosen.best.cell.params)})"),
            ("dissertation", id_dissertation, chosen.dissertation, "dissertation's design (assumed)")):
        rows.append([f"{words}: validation NRMSE, {r_.worst} [%], mean (range over the seeds)",
                     with_range(data.groups[name], None),
                     with_range(configuration_of(results, options, stride=chosen.stride), own_model)])
    return Table(["", f"the dissertation's way (cubic, {seed_like['duration_s']:g} s, dt {seed_like['dt_s']:g} s)",
                  f"this study's (quintic through {study.id.via_points} via points, dt {study.id.dt:g} s, one state in "
                  f"{id_stride})"], rows,
                 caption=f"Training trajectories made the dissertation's way against this study's, as many states of each, and "
                         f"the models trained on them (mean and range over the seeds where more than one ran, `ablation_seeds`), "
                         f"validated on the study's validation trajectories; the speeds and accelerations of seed {seed}'s draw")


def seed_like_prose(reading: TorqueReading, data: SeedLikeData, best: Replicates, seed_like: Mapping[str, Any]) -> str:
    """Section 6.9's finding in words: how slowly the dissertation's cubics move, and whether the
    chosen ANFIS trained on them misses the validation trajectories by more than when trained on
    this study's data (``best``, over its seeds)."""
    fmt, seeds_range = reading.fmt, reading.seeds_range
    cubic = data.groups["model_free"]
    return (f"Cubics from rest to rest over {seed_like['duration_s']:g} s move slowly: their largest acceleration is "
            f"{largest_deg(data.cubic, 'qdd').max():.3g} °/s² against {largest_deg(data.own, 'qdd').max():.3g} °/s² in this "
            f"study's trajectories, so the inertial and centrifugal terms are barely excited. The chosen ANFIS trained on as "
            f"many states of them misses the validation trajectories by {fmt(cubic.metrics['worst_nrmse'])} % on its worst "
            f"joint ({seeds_range(cubic) + ' over the seeds' if cubic.n > 1 else 'one run'}), against "
            f"{fmt(best.metrics['worst_nrmse'])} % ({seeds_range(best)} %) when trained on this study's data"
            + (": no difference shown by the seeds' ranges." if cubic.n > 1 and same(cubic, best) else
               ": within the range of the study-trained seeds." if cubic.n == 1
               and best.low("worst_nrmse") <= cubic.metrics["worst_nrmse"] <= best.high("worst_nrmse") else
               ": the dissertation's data do not teach the dynamics the arm meets in faster motion."
               if cubic.low("worst_nrmse") > best.high("worst_nrmse") else "."))


def distinct_cells(*runs: Iterable[CellResult]) -> list[CellResult]:
    """The sweep cells of several lists, each once (a cell two lists hold counts once)."""
    return list({r.cell.key: r for rs in runs for r in rs}.values())


def models_note(store: ChosenModels, chosen: ChosenID, residual, cells: Sequence[CellResult],
                sweeps_dir: str | os.PathLike | None = None) -> str:
    """Where the ID models are, how long the chosen ANFIS (and the measured arm's residual
    ANFIS, ``residual``; ``None``: none) took to train, and where the chapter's sweep ``cells``
    are (``sweeps_dir``, default ``build/sweeps/``)."""
    return (f"ID models in `{shown_path(store.id_model_free)}` and `{shown_path(store.id)}`. Training the chosen "
            f"ID models (a cell of section 6.4) took {sum(chosen.model_free.fit_seconds_):.0f} s when they were made"
            + (f", the residual ANFIS of section 6.8 {sum(residual.fit_seconds_):.0f} s. " if residual is not None else ". ")
            + f"The {len(cells):,} sweep cells this chapter shows are in "
              f"`{shown_path(project_path(sweeps_dir) if sweeps_dir else BUILD / 'sweeps')}`.")
