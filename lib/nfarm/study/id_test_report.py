"""Chapter 7.5: the learned inverse dynamics judged once on the held-out trajectories of the
test split — the chosen model-free ANFIS, the dissertation's design, the identification on the
regressor, the two trained the dissertation's way (section 6.9) and each scikit-learn learner's
best configuration by validation (chapter 6.5, read back) — and the rerun recording of one of
them.

Every error is kept as **trajectory sums** ``(T, 1 + 3n)`` (:func:`nfarm.study.statistics.trajectory_sums`)
and every interval resamples the held-out trajectories; the worst joint is taken over the joints
a sensor resolves, fixed on validation (:func:`nfarm.study.rows.resolved_on_validation`).
NRMSEs are shares of each joint's torque spread (shown in %), torques are in N·m.

Example (the worst joint's interval in %, one value when both ends lie below the floor):
    >>> import numpy as np
    >>> from nfarm.study.statistics import Interval
    >>> ci = lambda low, high: Interval(np.zeros(2), np.zeros(2), np.zeros(2), high, low, high, 0.95, 200, 12)
    >>> interval(ci(0.018, 0.0235)), interval(ci(1e-12, 2e-12))
    ('1.8–2.35', '< 1e-6')
"""

from __future__ import annotations

import os
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from ..infra.paths import shown_path
from ..learning.bases import TIERS, tier_of
from ..learning.baselines import label as base_label
from ..learning.learned import OutsideTrainingWarning
from ..model.dynamics import rnea
from ..presentation.plotting import plot_error_against, plot_per_joint
from ..presentation.recording import record_id_trajectory
from ..presentation.tables import Table
from ..presentation.wording import listed, times, torque_columns, worst_of
from . import contest
from .id_comparison_report import ID_FLOOR, by_tier_and_learner
from .id_contest_report import pct
from .statistics import Interval, tail_ratio, trajectory_maxima, trajectory_sums, worst_difference
from .rows import ROLE_CHOSEN, ROLE_DESIGN, ROLE_PHYSICS, ROLE_SPAN, bootstrap_resolved, resolved_sums, with_resolved_worst
from .sweep import CellResult, Replicates, by_configuration, sweep_results
from .sweep_files import Sweep
from .verdict_rows import ID_TARGET_PCT

__all__ = ["IDENT", "SEED_FREE", "SEED_RECIPE", "ROLE_SEED_LIKE", "ROLE_FLOOR", "ROLE_BASELINE", "RNEA", "ERR_FLOOR",
           "BaselineTest", "baseline_errors", "baseline_test", "HeldOutID", "held_out", "interval",
           "extrapolation_prose", "errors_table", "errors_prose", "torques_figure", "relative_error", "peak_rates",
           "causes_figure", "causes_prose", "per_sample", "prediction_times", "timing_table", "timing_prose",
           "record_trajectory"]

#: The identification on the regressor's inputs: exact by construction, a physics-informed reference.
IDENT = "identification on the regressor (needs the geometry)"
#: The chosen ANFIS and the dissertation's design, trained on trajectories made the dissertation's way (section 6.9).
SEED_FREE = "ANFIS, model-free, trained the dissertation's way"
SEED_RECIPE = "ANFIS, dissertation's design (assumed), trained the dissertation's way"
#: The roles of the two trained the dissertation's way, of the linear least squares and of the other baselines.
ROLE_SEED_LIKE = "ablation: the dissertation's data"
ROLE_FLOOR = "floor (least squares on q, q̇, q̈)"
ROLE_BASELINE = "baseline"
#: The Newton–Euler recursion in the timing table.
RNEA = "Newton–Euler (rnea)"
#: [N·m] an error at the level of rounding: :data:`~nfarm.study.id_comparison_report.ID_FLOOR` (an NRMSE) on a
#: torque spread of about 1 N·m; shown as "< 1e-8".
ERR_FLOOR = 1e-8


def _unseeded(params: Mapping[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in params.items() if k != "seed"}


# -- the baselines of chapter 6.5, read back ---------------------------------------------------------------------


@dataclass(frozen=True)
class BaselineTest:
    """Chapter 6.5's baselines judged on the test split: ``chosen`` is each learner's
    configuration chosen on validation (seed 0) in each tier of prior knowledge (keyed ``(tier,
    learner)``), and ``sums``,
    ``maxima``, ``val_worst`` and ``roles`` map each tested baseline's label, in the order its
    cell ran, to its trajectory sums ``(T, 1 + 3n)``, its largest errors per trajectory ``(T, n)``
    [N·m], its worst resolved joint's validation NRMSE (a share) and its role."""

    chosen: Mapping[Any, Replicates]
    sums: Mapping[str, np.ndarray]
    maxima: Mapping[str, np.ndarray]
    val_worst: Mapping[str, float]
    roles: Mapping[str, str]


def baseline_errors(chosen: Mapping[Any, Replicates], test_runs: Sequence[CellResult], n: int) -> BaselineTest:
    """The baselines' test cells (``test_runs``, each a configuration of ``chosen``) as
    :class:`BaselineTest` of an ``n``-joint arm: the linear least squares is the floor, a learner
    of the rigid-body span tier :data:`ROLE_SPAN`, every other learner a baseline."""
    val_of = {base_label(_unseeded(g.cell.params)): g.values("worst_nrmse")[0] for g in chosen.values()}
    span = TIERS["span"]
    sums, maxima, val_worst, roles = {}, {}, {}, {}
    for r in test_runs:
        name, learner = base_label(r.cell.params), r.cell.params["learner"]
        if name not in val_of:
            raise ValueError(f"the test cell of {name} is none of the chosen configurations' ({sorted(val_of)})")
        sums[name] = np.array(r.metrics["trajectory_sums"]).reshape(-1, 1 + 3 * n)
        maxima[name] = np.array(r.metrics["trajectory_maxima"]).reshape(-1, n)
        val_worst[name] = val_of[name]
        roles[name] = ROLE_FLOOR if learner == "linear" else ROLE_SPAN if tier_of(r.cell.params) == span else ROLE_BASELINE
    return BaselineTest(chosen, sums, maxima, val_worst, roles)


def baseline_test(sweep: Sweep, resolved, n: int, *, other_seeds: Sequence[int], seed: int = 0,
                  sweeps_dir: str | os.PathLike | None = None, workers: int | None = None) -> BaselineTest:
    """Chapter 6.5's choice read back — each learner's best configuration on seed 0 by the worst
    ``resolved (n,)`` joint's validation NRMSE, where every configuration ran (each tier's best
    also ran on ``other_seeds``) — and the chosen configurations' cells on the test split run or
    reused on the chapter's ``seed`` (the study's own data), as the ANFIS models are tested."""
    val = with_resolved_worst(by_configuration(contest.with_tier_finalists(
        sweep, resolved, "nrmse", sweeps_dir, workers=workers, seeds=other_seeds)), resolved, "nrmse")
    chosen = by_tier_and_learner(val)
    configs = [_unseeded(g.cell.params) for g in chosen.values()]
    test_runs = sweep_results(sweep.select(lambda p: _unseeded(p) in configs).restrict(split="test", seed=seed),
                              sweeps_dir, workers=workers)
    return baseline_errors(chosen, test_runs, n)


# -- every model on the test split -------------------------------------------------------------------------------


@dataclass(frozen=True)
class HeldOutID:
    """The learned inverse dynamics on the held-out trajectories (:func:`held_out`).

    ``data`` is the test split (``q, qd, qdd`` [rad, rad/s, rad/s²], ``tau`` [N·m], ``t`` [s],
    ``trajectory``), ``resolved (n,)`` the joints a sensor resolves; ``free`` and ``recipe`` the
    labels of the chosen ANFIS and the dissertation's design, ``models`` the chapter's three models
    by label (those two and :data:`IDENT`), ``predictions`` their torques and those of the two
    trained the dissertation's way, each ``(M, n)`` [N·m]; ``extrapolated`` the warning each of
    those two gave about test states beyond its training range. ``sums``, ``maxima``, ``roles``
    and ``intervals`` map every tested method (baselines last) to its trajectory sums, its largest
    errors per trajectory, its role and its NRMSE with the worst joint's interval
    (:func:`nfarm.study.rows.bootstrap_resolved`, ``draws`` resamples at coverage ``level``)."""

    data: Mapping[str, np.ndarray]
    resolved: np.ndarray
    free: str
    recipe: str
    models: Mapping[str, Any]
    predictions: Mapping[str, np.ndarray]
    extrapolated: Mapping[str, OutsideTrainingWarning]
    baselines: BaselineTest
    sums: Mapping[str, np.ndarray]
    maxima: Mapping[str, np.ndarray]
    roles: Mapping[str, str]
    intervals: Mapping[str, Interval]
    draws: int
    level: float
    seed: int

    @property
    def X(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The test states ``(q, qd, qdd)``, each ``(M, n)``."""
        return self.data["q"], self.data["qd"], self.data["qdd"]

    @property
    def spread(self) -> np.ndarray:
        """``(n,)`` [N·m] each joint's torque spread on the test split (its standard deviation)."""
        return self.data["tau"].std(axis=0)

    @property
    def worst(self) -> str:
        """The words for the worst joint over the resolved ones ("worst of τ1–τ4")."""
        return worst_of(self.resolved)

    @property
    def best_base(self) -> str | None:
        """The baseline of least worst-joint NRMSE on validation (the floor and the rigid-body span
        aside), or ``None``."""
        tested = [name for name in self.intervals if self.roles[name] == ROLE_BASELINE]
        return min(tested, key=self.baselines.val_worst.get) if tested else None

    def on_trajectory(self, trajectory: int) -> np.ndarray:
        """``(M,)`` bool: the test samples of held-out trajectory ``trajectory``."""
        mask = self.data["trajectory"] == trajectory
        if not mask.any():
            raise ValueError(f"the test split has no trajectory {trajectory} "
                             f"(it holds {len(np.unique(self.data['trajectory']))})")
        return mask


def held_out(id_test: Mapping[str, np.ndarray], resolved, model_free, dissertation, identified,
             seed_like: Mapping[str, Any], baselines: BaselineTest, *, draws: int = 2000, level: float = 0.95,
             seed: int = 0) -> HeldOutID:
    """Every ID model's predictions and errors on the test split ``id_test``: the chosen ANFIS
    (``model_free``), the dissertation's design, the identification on the regressor, the two of
    ``seed_like`` (``"model_free"``, ``"dissertation"``: trained the dissertation's way) and the
    ``baselines``; each worst joint's interval over the held-out trajectories. The first three
    models' warnings are the caller's to show; the two trained the dissertation's way meet faster
    states than they were trained on, which is said (:func:`extrapolation_prose`), not warned."""
    resolved = np.asarray(resolved, bool)
    X, tau, trajectory = (id_test["q"], id_test["qd"], id_test["qdd"]), id_test["tau"], id_test["trajectory"]
    if resolved.shape != (tau.shape[1],) or not resolved.any():
        raise ValueError(f"resolved must mark at least one of the {tau.shape[1]} joints, got {resolved.tolist()}")
    free = f"ANFIS, {tier_of({'inputs': model_free.inputs})} ({model_free.inputs})"   # its tier of prior knowledge
    recipe = f"ANFIS, dissertation's design ({dissertation.inputs}, assumed)"
    models = {free: model_free, recipe: dissertation, IDENT: identified}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        predictions = {name: model.predict(*X) for name, model in models.items()}
    for w in caught:
        warnings.warn(w.message, w.category, stacklevel=2)
    extrapolated = {}
    for name, model in ((SEED_FREE, seed_like["model_free"]), (SEED_RECIPE, seed_like["dissertation"])):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            predictions[name] = model.predict(*X)
        for w in caught:
            if issubclass(w.category, OutsideTrainingWarning) and w.message.what == "states":
                extrapolated[name] = w.message
    sums = {name: trajectory_sums(p, tau, trajectory) for name, p in predictions.items()} | dict(baselines.sums)
    maxima = {name: trajectory_maxima(p, tau, trajectory) for name, p in predictions.items()} | dict(baselines.maxima)
    roles = {free: ROLE_CHOSEN, recipe: ROLE_DESIGN, IDENT: ROLE_PHYSICS, SEED_FREE: ROLE_SEED_LIKE,
             SEED_RECIPE: ROLE_SEED_LIKE} | dict(baselines.roles)
    intervals = {name: bootstrap_resolved(s, resolved, draws=draws, level=level, seed=seed) for name, s in sums.items()}
    return HeldOutID(id_test, resolved, free, recipe, models, predictions, extrapolated, baselines, sums, maxima, roles,
                     intervals, draws, level, seed)


# -- section 7.5's table and words -------------------------------------------------------------------------------


def interval(ci: Interval, *, floor: float = ID_FLOOR) -> str:
    """The worst joint's interval in % ("180–235"); one "< 1e-6" when both ends are below ``floor``."""
    low, high = pct(ci.worst_low, floor=floor), pct(ci.worst_high, floor=floor)
    return high if low == high else f"{low}–{high}"


def extrapolation_prose(t: HeldOutID) -> str:
    """How many test states the models trained the dissertation's way meet beyond their training
    range, and how far (Markdown; ``""`` when none does)."""
    if not t.extrapolated:
        return ""
    return ("Trained the dissertation's way, the models meet faster test states than any they were trained on, and "
            "predict them by extrapolation — "
            + "; ".join(f"{name}: {w.count:,} of the {w.total:,} test states ({w.count / w.total:.0%}) lie outside the "
                        f"range of its training inputs by more than {w.far:g} of that range's width "
                        f"(up to {w.how_far:.2g} widths)" for name, w in t.extrapolated.items()) + ".")


def errors_table(t: HeldOutID, noise, joint_names: Sequence[str], *, floor: float = ID_FLOOR) -> Table:
    """Every method's NRMSE per joint [%] on the held-out trajectories, its role, its worst
    resolved joint's and that one's interval; a joint whose spread is below the sensor noise
    (``noise (n,)`` [N·m], or ``None``) is marked in its header and named in the caption."""
    fmt = lambda v: pct(v, floor=floor)       # noqa: E731
    cols, noise_note = torque_columns(t.spread, noise, joint_names)
    rows = [[name, t.roles[name], *(fmt(v) for v in ci.value), fmt(ci.worst), interval(ci, floor=floor)]
            for name, ci in t.intervals.items()]
    return Table(["model", "role", *cols, f"{t.worst} [%]", f"{t.level:.0%} interval [%]"], rows,
                 caption=f"Torque NRMSE per joint on {t.intervals[t.free].trajectories} held-out trajectories "
                         f"({len(t.data['t']):,} samples); the interval of the worst joint's from {t.draws:,} "
                         f"bootstrap resamples of the trajectories{noise_note}")


def errors_prose(t: HeldOutID, joint_names: Sequence[str], *, target: float = ID_TARGET_PCT / 100,
                 floor: float = ID_FLOOR) -> str:
    """Section 7.5's finding in words (Markdown): the chosen ANFIS's worst NRMSE against the
    study's ``target`` (a share), against the best baseline on the paired interval of their worst
    joints, the dissertation's design joint by joint, the identification and the chosen ANFIS
    trained the dissertation's way."""
    ci, fmt = t.intervals, (lambda v: pct(v, floor=floor))      # noqa: E731
    free, best = ci[t.free], t.best_base
    text = (f"The model-free ANFIS reaches a worst per-joint NRMSE of **{fmt(free.worst)} %** "
            f"({interval(free, floor=floor)} %) on the held-out trajectories (the study's target, ≤ {100 * target:g} %: "
            f"{chr(10003) if free.worst_high <= target else chr(10007)}). ")
    if best is not None:
        diff, low, high = worst_difference(resolved_sums(t.sums[t.free], t.resolved), resolved_sums(t.sums[best], t.resolved),
                                           draws=t.draws, level=t.level, seed=t.seed)
        text += (f"The best baseline on the validation trajectories, {best}, reaches {fmt(ci[best].worst)} % "
                 f"({interval(ci[best], floor=floor)} %): ")
        if low > 0:
            text += f"it beats the ANFIS by {100 * diff:.3g} points (paired interval {100 * low:.3g} to {100 * high:.3g}). "
        elif high < 0:
            text += f"the ANFIS beats it by {-100 * diff:.3g} points (paired interval {-100 * high:.3g} to {-100 * low:.3g}). "
        else:
            text += (f"no difference shown (the paired interval of the difference, {100 * low:.3g} to {100 * high:.3g} "
                     f"points, holds 0). ")
    recipe = ci[t.recipe].value
    worst_joint = joint_names[int(np.argmax(np.where(t.resolved, recipe, -np.inf)))]
    on = recipe[t.resolved]
    text += (f"The dissertation's design misses by {100 * on.min():.3g}–{100 * on.max():.3g} % of each "
             f"{'resolved ' if not t.resolved.all() else ''}joint's spread (100 % is what predicting each joint's mean "
             f"torque would give; worst: {worst_joint})"
             + (", worse than that mean on its worst joint. " if on.max() > 1 else ". "))
    text += (f"The identification on the regressor, which is given the geometry, is at {fmt(ci[IDENT].worst)} %: "
             f"a reference for what exact physics gives, not a learned result.")
    seed_free = ci[SEED_FREE]
    return text + (f" Trained on trajectories made the dissertation's way (chapter 6.9), the same model-free ANFIS misses "
                   f"by {fmt(seed_free.worst)} % ({interval(seed_free, floor=floor)} %)"
                   + (": slow rest-to-rest cubics do not teach the dynamics of faster motion."
                      if seed_free.worst_low > free.worst_high
                      else ", not different from training on this study's data within the intervals."))


# -- the figures -------------------------------------------------------------------------------------------------


def torques_figure(t: HeldOutID, trajectory: int, joint_names: Sequence[str]) -> tuple[Figure, str]:
    """The true torques [N·m] of held-out trajectory ``trajectory`` against time and the
    chapter's three models' predictions (those trained the dissertation's way are in the table:
    their torques would swamp the panels); the figure and its caption."""
    mask = t.on_trajectory(trajectory)
    fig = plot_per_joint(t.data["t"][mask], {"Newton–Euler (truth)": t.data["tau"][mask],
                                             **{name: t.predictions[name][mask] for name in t.models}},
                         joint_names, ylabel="τ [N·m]", focus=3.0)
    return fig, (f"Held-out trajectory {trajectory}: true torques and the predictions of the three models of chapter "
                 f"6.7 (each panel's range three times the truth's; a prediction that leaves it is marked in the legend; "
                 f"the models trained the dissertation's way are in the table of section 7.5's errors above)")


def relative_error(t: HeldOutID, name: str) -> np.ndarray:
    """``(M,)`` each test sample's relative torque error of method ``name``: the RMS over the
    resolved joints of its error over the joint's torque spread (a fraction)."""
    e = (t.predictions[name] - t.data["tau"]) / t.spread
    return np.sqrt((e[:, t.resolved] ** 2).mean(axis=1))


def peak_rates(t: HeldOutID) -> tuple[np.ndarray, np.ndarray]:
    """``(M,)`` each test sample's largest joint speed |q̇| [deg/s] and ``(M,)`` largest joint
    acceleration |q̈| [deg/s²]."""
    return np.degrees(np.abs(t.data["qd"])).max(axis=1), np.degrees(np.abs(t.data["qdd"])).max(axis=1)


def _over(resolved) -> str:
    return "joints" if np.all(resolved) else listed(f"τ{j + 1}" for j in range(len(resolved)) if resolved[j])


def causes_figure(t: HeldOutID) -> tuple[Figure, str]:
    """The dissertation design's relative torque error per test sample (:func:`relative_error`)
    against its largest joint speed and acceleration (:func:`peak_rates`); the figure and its
    caption."""
    speed, accel = peak_rates(t)
    fig = plot_error_against({"largest joint speed |q̇| [deg/s]": speed, "largest joint acceleration |q̈| [deg/s²]": accel},
                             relative_error(t, t.recipe), label="relative torque error e/σ [-]")
    return fig, (f"Dissertation design: the relative torque error of each test sample (the RMS over {_over(t.resolved)} "
                 f"of the error over the joint's torque spread σ, a fraction) against speed and acceleration (medians "
                 f"and 95th percentiles in equal-count bins)")


def causes_prose(t: HeldOutID, *, share: float = 0.1) -> str:
    """What the figure of :func:`causes_figure` shows, in words (Markdown): the median error of
    the ``share`` of slowest samples against the fastest's, by speed and by acceleration (point
    values: the samples of a trajectory are not independent, so no interval over samples), and the
    chosen ANFIS's median and largest relative error."""
    speed, accel = peak_rates(t)
    relative, chosen = relative_error(t, t.recipe), relative_error(t, t.free)
    r_speed, r_accel = tail_ratio(speed, relative, share), tail_ratio(accel, relative, share)
    part = "tenth" if share == 0.1 else f"{share:.0%}"
    return (f"For the dissertation's design, the {part} of samples with the lowest speeds has a median error "
            f"{times(r_speed)} that of the {part} with the highest, and the {part} with the lowest "
            f"accelerations {times(r_accel)} that of the highest. The model-free ANFIS's relative error (per sample, the "
            f"RMS over {_over(t.resolved)} of its error over the joint's torque spread) has median "
            f"{100 * np.median(chosen):.2g} % and largest {100 * chosen.max():.2g} % over the test samples.")


# -- what each costs -----------------------------------------------------------------------------------------------


def per_sample(f: Callable, *args: np.ndarray, repeats: int = 3) -> float:
    """[s] the best of ``repeats`` timings of ``f(*args)``, per row of its first argument (one
    batched call; the best is the least disturbed by the machine's other work)."""
    if repeats < 1 or not len(args) or not len(args[0]):
        raise ValueError(f"per_sample needs at least one repeat and one row, got repeats={repeats!r}")
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        f(*args)
        best = min(best, time.perf_counter() - start)
    return best / len(args[0])


def prediction_times(robot, t: HeldOutID, *, repeats: int = 3) -> dict[str, float]:
    """[s per sample] this run's prediction time of the Newton–Euler recursion (:data:`RNEA`)
    and of the chapter's three models, batched over the test states (:func:`per_sample`). The
    models' warnings are the caller's to show. Depends on the machine: shown, not saved."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        timing = {RNEA: per_sample(lambda q, qd, qdd: rnea(robot, q, qd, qdd), *t.X, repeats=repeats),
                  **{name: per_sample(model.predict, *t.X, repeats=repeats) for name, model in t.models.items()}}
    for w in caught:
        warnings.warn(w.message, w.category, stacklevel=2)
    return timing


def timing_table(timing: Mapping[str, float]) -> Table:
    """The prediction times of :func:`prediction_times` in µs per sample and relative to rnea's
    (not saved: they depend on the machine)."""
    return Table(["method", "time per sample [µs]", "relative to rnea"],
                 [[name, s * 1e6, s / timing[RNEA]] for name, s in timing.items()], floatfmt=["", ".3g", ".2g"],
                 caption="Prediction time of this run, batched over the test set (not saved: it depends on the machine; "
                         "`make bench` measures it)")


def timing_prose(timing: Mapping[str, float], chosen: str) -> str:
    """How many times rnea's time the ``chosen`` ANFIS takes per sample, and what that shows (Markdown)."""
    slower = timing[chosen] / timing[RNEA]
    return (f"In this run the model-free ANFIS takes {times(slower)} the time per sample of the Newton–Euler "
            f"recursion whose torques it learned: "
            + ("it shows that the map can be learned from data without the arm's parameters, not a faster way to "
               "compute it where the parameters are known." if slower > 1 else "the learned model is the faster of the two."))


# -- the recording -------------------------------------------------------------------------------------------------


def record_trajectory(robot, t: HeldOutID, trajectory: int, path: str | os.PathLike, *,
                      measured: np.ndarray | None = None, residual: np.ndarray | None = None,
                      seed: int = 0) -> tuple[Path, str]:
    """Write the rerun recording of held-out trajectory ``trajectory`` to ``path``: the arm
    moving and per joint the true torques, the chosen ANFIS's and the dissertation design's, and
    on a measured arm the ``measured`` torques and Newton–Euler with the residual ANFIS
    (``residual``), each ``(K, n)`` [N·m] on that trajectory (``None``: not recorded). Returns the
    file and the sentence saying what it holds (Markdown)."""
    mask = t.on_trajectory(trajectory)
    torques = {"newton_euler": t.data["tau"][mask], "anfis_model_free": t.predictions[t.free][mask],
               "anfis_dissertation": t.predictions[t.recipe][mask]}
    torques |= {k: v for k, v in (("measured", measured), ("newton_euler_plus_residual", residual)) if v is not None}
    t_k = t.data["t"][mask]
    where = record_id_trajectory(robot, t_k, t.data["q"][mask], torques, path, name=Path(path).stem, seed=seed)
    return where, (f"The rerun recording `{shown_path(where)}` replays held-out trajectory {trajectory} "
                   f"({t_k[-1]:.1f} s): the arm moving, and per joint the torques {', '.join(f'`{k}`' for k in torques)} "
                   f"on one plot (open it with `.venv/bin/rerun {shown_path(where)}`).")
