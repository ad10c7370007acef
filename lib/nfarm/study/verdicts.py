"""The study's verdict (chapter 7.7): per task, the ANFIS's best against the best other method,
both chosen on validation, judged on held-out data over every seed chapter 6 trained each on.

A **seed** is a draw of the training data and of the learner's initialisation; chapter 6 trains a
contest's finalists on seed 0 and on :data:`nfarm.study.contest.SPREAD_SEEDS`, and keeps the
models of a published configuration beside it (``seeds.json``, :mod:`nfarm.study.replicates`).
Here each method's errors on the test units (poses for IK, trajectories for ID) are stacked over
its seeds — ``(S, N, k)``, the chapter's seed first — and judged by
:func:`nfarm.study.paired.seed_comparison`: a two-level bootstrap (the seeds resampled, then the
test units), the gap paired by seed and unit. :func:`judge_task` turns that into a
:class:`nfarm.study.verdict_rows.Verdict` with the study's targets met on the same intervals;
:func:`measured_verdicts` judges the measured arm tier by tier.

Example (two methods on two seeds of 30 test poses; the rival's position errors three times the
ANFIS's):

    >>> rng = np.random.default_rng(0)
    >>> def errors(scale):
    ...     return {"joint": rng.normal(0, 1e-3, (30, 5)), "position": scale * rng.random(30) * 1e-3,
    ...             "orientation": rng.random(30) * 1e-3}
    >>> values = {m: ik_seed_values([errors(s), errors(s)]) for m, s in (("ANFIS", 1.0), ("RBF", 3.0))}
    >>> v = judge_task("arm", "inverse kinematics", "position p95", "mm", values, "ANFIS", "RBF", ik=True, draws=200)
    >>> v.rival, v.verdict, v.anfis_value < v.rival_value
    ('RBF', 'ANFIS better', True)
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ..learning.baselines import load_id_model
from ..learning.learned import ik_errors
from .statistics import distinct_resamples, trajectory_sums
from . import contest, replicates
from .shifted import describe as describe_shifted, describe_id as describe_shifted_id, shifted_id, shifted_ik, shifted_readings
from .paired import seed_comparison
from .rows import WORST_ID, Row, ik_seed_values, seed_estimates
from .verdict_rows import ID_TARGET_PCT, IK_TARGETS, Verdict, targets_met, task_verdict, with_holm
from .sweep import sweep_results

__all__ = ["seed_models", "seed_sums", "summary_row", "judge_task", "ik_values_over_seeds", "id_values_over_seeds",
           "measured_verdicts", "measured_verdict", "ik_verdict", "rigid_id_verdict", "shifted_id_verdicts", "baseline_models", "finalist_models", "seed_values_by_task", "shifted_verdict", "shifted_caption",
           "verdict_caption", "summary_caption", "paired_caption", "wide_caption"]


def seed_models(where: str | os.PathLike, published: Any, probe: Sequence[np.ndarray], *, seed: int = 0) -> list:
    """The models of a published model's configuration on each of its seeds (the ``seeds.json``
    chapter 6 wrote beside it in ``where``), the chapter's ``seed`` first and checked to give the
    published model's predictions on ``probe`` (the arguments of its ``predict``), then the
    others in seed order; ``[published]`` where no seeds are listed (a method trained once).

    Raises:
        RuntimeError: the seed-``seed`` model is missing or is not the published one (chapter 6
            must be run again).
    """
    where = Path(where)
    if not (where / replicates.SEEDS_FILE).is_file():
        return [published]
    models = replicates.seed_models(where)
    if seed not in models or not np.array_equal(models[seed].predict(*probe), published.predict(*probe)):
        raise RuntimeError(f"{where}: its seed-{seed} model is not the published one: rerun chapter 6")
    return [models[seed]] + [models[s] for s in sorted(models) if s != seed]


def seed_sums(runs: Sequence, n_joints: int, *, seed: int = 0) -> np.ndarray:
    """``(S, T, 1 + 3n)``: the test cells' trajectory sums (their metric ``trajectory_sums``,
    :func:`nfarm.study.statistics.trajectory_sums`) of one configuration over its seeds, the
    chapter's ``seed`` first, then the others in order."""
    runs = sorted(runs, key=lambda r: (r.cell.params["seed"] != seed, r.cell.params["seed"]))
    return np.stack([np.array(r.metrics["trajectory_sums"]).reshape(-1, 1 + 3 * n_joints) for r in runs])


def summary_row(task: str, method: str, metric: str, unit: str, estimate, scale: float = 1.0) -> Row:
    """A two-level estimate (of :func:`nfarm.study.paired.seed_comparison`) as a summary
    :class:`~nfarm.study.rows.Row`, its value and interval times ``scale`` (what the targets
    are judged on)."""
    return Row(task, method, "", metric, unit, scale * estimate.value, scale * estimate.low, scale * estimate.high,
               estimate.draws, estimate.level, "")


def judge_task(arm: str, task: str, metric: str, unit: str, values: Mapping[str, np.ndarray], anfis: str, rival: str, *,
               targets: Sequence[tuple[str, float, str]] = (), exact: str = "", units: str = "test poses",
               scale: float = 1.0, draws: int = 2000, level: float = 0.95, seed: int = 0, **given) -> Verdict:
    """One task's :class:`~nfarm.study.verdict_rows.Verdict` on two-level intervals: the ``anfis``
    against ``rival`` on ``metric`` (in ``unit`` after multiplying by ``scale``), from each
    method's values over its seeds (``values``: method → ``(S, N, k)``, as
    :func:`~nfarm.study.paired.seed_comparison` takes them, with its options ``given``:
    ``ik=True``, ``resolved=…``); ``targets`` the study's targets ``(metric, limit, unit)`` judged
    for each compared method on the same intervals; ``units`` names the test units in the
    interval's description."""
    boot = {"draws": draws, "level": level, "seed": seed}
    est, gap = seed_comparison(values, anfis, rival, metric, **given, **boot)
    met: dict[str, list[tuple[Row, float]]] = {}
    for target_metric, limit, target_unit in targets:
        on = est if target_metric == metric else seed_estimates(values, target_metric, **given, **boot)
        for name in values:
            met.setdefault(name, []).append((summary_row(task, name, target_metric, target_unit, on[name], scale), limit))
    kind = (f"{level:.0%} two-level bootstrap, seeds × {est[anfis].rows:,} {units}; seeds: ANFIS {est[anfis].seeds}, "
            f"best other {est[rival].seeds}, paired {gap.seeds}"
            + (f" (coarse: {gap.seeds} seeds allow {distinct_resamples(gap.seeds)} distinct resamples)" if gap.seeds > 1 else ""))
    return task_verdict(arm, task, metric, unit, {n: scale * e.value for n, e in est.items()}, anfis,
                        (scale * gap.value, scale * gap.low, scale * gap.high),
                        {n: targets_met([r for r, _ in rows], [lim for _, lim in rows]) for n, rows in met.items()},
                        exact, intervals={n: (scale * e.low, scale * e.high) for n, e in est.items()}, interval=kind,
                        p=gap.p_zero, draws=gap.draws)


def ik_values_over_seeds(robot, published: Mapping[str, tuple[Any, str | os.PathLike]], T: np.ndarray, q: np.ndarray, *,
                         probe: np.ndarray, first: Mapping[str, Mapping[str, np.ndarray]] | None = None,
                         seed: int = 0) -> dict[str, np.ndarray]:
    """Each published IK method's errors on the targets ``T (N, 4, 4)`` (true joints ``q (N, n)``)
    over its seeds, as :func:`~nfarm.study.rows.ik_seed_values` stacks them: ``published``
    maps a method to its published model and the directory it was published in
    (:func:`seed_models`, checked on the targets ``probe``); ``first`` the chapter seed's errors
    where already computed (:func:`nfarm.learning.learned.ik_errors`), reused."""
    values = {}
    for name, (model, where) in published.items():
        models = seed_models(where, model, (probe,), seed=seed)
        errors = [first[name]] if first is not None else [ik_errors(robot, models[0].predict(T), q, T)]
        values[name] = ik_seed_values(errors + [ik_errors(robot, m.predict(T), q, T) for m in models[1:]])
    return values


def id_values_over_seeds(published: Mapping[str, tuple[Any, str | os.PathLike]], X: Sequence[np.ndarray],
                         tau: np.ndarray, trajectory: np.ndarray, *, first: Mapping[str, np.ndarray],
                         probe: Sequence[np.ndarray], seed: int = 0) -> dict[str, np.ndarray]:
    """Each published ID model's trajectory sums on the held-out states ``X = (q, qd, qdd)``
    (each ``(M, n)``; true torques ``tau (M, n)`` [N·m], ``trajectory (M,)`` the samples'
    trajectories) over its seeds, ``(S, T, 1 + 3n)``: the chapter seed's from ``first``, the
    others predicted here (:func:`seed_models`, checked on the states ``probe``)."""
    with warnings.catch_warnings(record=True) as caught:       # a model's warnings are the caller's to show
        warnings.simplefilter("always")
        values = {name: np.stack([first[name]] + [trajectory_sums(m.predict(*X), tau, trajectory)
                                                  for m in seed_models(where, model, probe, seed=seed)[1:]])
                  for name, (model, where) in published.items()}
    for w in caught:
        warnings.warn(w.message, w.category, stacklevel=2)
    return values


def measured_verdicts(arm: str, idc, idc_sweep, names: Sequence[str], pairs: Mapping[str, Sequence[str]], *,
                      resolved: np.ndarray, n_joints: int, reference: str, groups: Mapping[str, np.ndarray] | None = None,
                      sweeps_dir=None, workers: int | None = None, draws: int = 2000, level: float = 0.95, seed: int = 0,
                      run: Callable = sweep_results) -> tuple[list[Verdict], dict[str, np.ndarray]]:
    """The measured arm's verdicts: for each tier of ``pairs`` (tier → its ANFIS and its best
    rival, by label), and over every tier (the best ANFIS and the best other method by
    validation), the two judged on the test trajectories over their seeds by the worst resolved
    joint's NRMSE [%] against the measured torques' spread (the best other method never of the
    rigid-body span tier, :data:`nfarm.learning.bases.TIERS`) — with the study's ≤ 5 % target met on
    the ``resolved`` joints and on every joint; then the every-tier pair again on each group of
    ``groups`` (name → ``(n,)`` bool, :func:`nfarm.study.measured_test.joint_groups`) that holds a
    resolved joint and not every joint, by the worst of those (task ``"measured arm, every tier, <name> joints"``), so
    that the joints the rigid body moves and those the drives' friction moves are judged apart. ``idc`` is chapter 6.8's contest
    (:func:`nfarm.study.contest.id_contest`) and ``idc_sweep`` its sweep; ``names`` every tested
    method's label, ``reference`` (Newton–Euler alone) among them but never a contestant. Each
    contestant's test cells are run or reused through ``run`` (:func:`nfarm.study.sweep.sweep_results`).
    Returns the verdicts (unranked for Holm's correction) and every contestant's trajectory sums
    over its seeds."""
    boot = {"draws": draws, "level": level, "seed": seed}
    family_of = {contest.id_label(f): f for f in idc.chosen}
    tested = [n for n in names if n != reference]
    runs = run(idc_sweep.with_cells([{**r.cell.params, "split": "test"} for name in tested
                                     for r in idc.group(family_of[name]).runs]), sweeps_dir, workers=workers)
    values = {name: seed_sums([r for r in runs if contest.id_label(contest.id_family(r.cell.params)) == name], n_joints,
                              seed=seed) for name in tested}
    on_val = {contest.id_label(contest.id_family(g.cell.params)): g.metrics["worst_nrmse"] for g in idc.standings}
    best_anfis = min((n for n in names if n.endswith(": ANFIS") and n in on_val), key=on_val.get)
    best_other = min((n for n in names if n != reference and not n.endswith(": ANFIS") and not contest.in_span(n)
                      and n in on_val), key=on_val.get)
    # Ranked by what chapter 6.8's contest ranked by and the ≤ 5 % target judges: the worst resolved joint's NRMSE
    # [%] against the measured torques' spread (the summary's "worst NRMSE"); the target also over every joint
    verdicts = [measured_verdict(arm, values, a, b, resolved=resolved, tier=tier, **boot)
                for tier, (a, b) in [*pairs.items(), ("every tier", (best_anfis, best_other))]]
    for group, mask in (groups or {}).items():
        mask = np.asarray(mask, bool)
        if (mask & resolved).any() and not mask.all():          # a group of every joint is the every-tier row
            verdicts.append(measured_verdict(arm, values, best_anfis, best_other, resolved=mask & resolved, every=mask,
                                             tier=f"every tier, {group} joints", **boot))
    return verdicts, values


def ik_verdict(arm: str, values: Mapping[str, np.ndarray], anfis: str, rival: str, *, exact: str = "",
               task: str = "inverse kinematics", units: str = "test poses", draws: int = 2000, level: float = 0.95,
               seed: int = 0) -> Verdict:
    """The learned-IK task's verdict: ``anfis`` against ``rival`` by the 95th-percentile tool position
    error [mm] over their seeds (``values`` as :func:`ik_values_over_seeds` gives them), with the
    study's IK targets (:data:`nfarm.study.verdict_rows.IK_TARGETS`); ``exact`` names the exact method,
    ``task`` and ``units`` the population judged (the test split's poses, or another's)."""
    return judge_task(arm, task, "position p95", "mm", values, anfis, rival, ik=True,
                      targets=[(metric, limit, unit) for _, metric, limit, unit in IK_TARGETS], exact=exact,
                      units=units, draws=draws, level=level, seed=seed)


def rigid_id_verdict(arm: str, values: Mapping[str, np.ndarray], anfis: str, rival: str, *, resolved,
                     task: str = "rigid-body inverse dynamics", units: str = "test trajectories",
                     draws: int = 2000, level: float = 0.95, seed: int = 0) -> Verdict:
    """The rigid-body ID task's verdict: ``anfis`` against ``rival`` by the worst ``resolved`` joint's
    NRMSE [%] over their seeds and the test trajectories (``values`` as :func:`id_values_over_seeds`
    gives them), with the study's ≤ 5 % target; Newton–Euler, which made the torques, is exact.
    ``task`` and ``units`` name the population judged (the test split's trajectories, or another's)."""
    return judge_task(arm, task, WORST_ID, "%", values, anfis, rival,
                      targets=[(WORST_ID, ID_TARGET_PCT, "%")], exact="Newton–Euler (the rigid-body model that made the torques)",
                      units=units, scale=100.0, resolved=resolved, draws=draws, level=level, seed=seed)


def measured_verdict(arm: str, values: Mapping[str, np.ndarray], anfis: str, rival: str, *, resolved, tier: str,
                     units: str = "test trajectories", every=None, draws: int = 2000, level: float = 0.95,
                     seed: int = 0) -> Verdict:
    """One measured-arm verdict: ``anfis`` against ``rival`` by the worst ``resolved`` joint's NRMSE [%]
    against the measured torques' spread, over their seeds and the trajectories (``values``:
    method → ``(S, T, 1 + 3n)`` trajectory sums), with the study's ≤ 5 % target on the resolved joints
    and on ``every`` joint (``(n,)`` bool, default all; ``anfis_targets`` and ``rival_targets`` count
    both); ``tier`` names the comparison (``"every tier"``, a tier, or a group of joints), ``units``
    the trajectories judged."""
    boot = {"draws": draws, "level": level, "seed": seed}
    pair = {n: values[n] for n in (anfis, rival)}
    n_joints = (next(iter(pair.values())).shape[-1] - 1) // 3
    # each seed a draw of the data on an arm built for it (nfarm.study.datasets.built_arm): the seeds' level covers both
    verdict = judge_task(arm, f"measured arm, {tier}", "worst NRMSE", "%", pair, anfis, rival,
                         units=f"{units} (each seed an arm built and its data drawn)", scale=100.0, resolved=resolved,
                         **boot)
    rows: dict[str, list[Row]] = {n: [] for n in (anfis, rival)}
    for mask in (resolved, np.ones(n_joints, bool) if every is None else np.asarray(every, bool)):
        est, _ = seed_comparison(pair, anfis, rival, WORST_ID, resolved=mask, **boot)
        for n in (anfis, rival):
            rows[n].append(summary_row("measured", n, WORST_ID, "%", est[n], 100.0))
    met = {n: targets_met(r, [ID_TARGET_PCT, ID_TARGET_PCT]) for n, r in rows.items()}
    return replace(verdict, anfis_targets=met[anfis], rival_targets=met[rival])


def seed_values_by_task(ik_values: Mapping[str, np.ndarray], id_values: Mapping[str, np.ndarray], resolved, *,
                        measured: Mapping[str, np.ndarray] | None = None, reference: tuple[str, np.ndarray] | None = None,
                        measured_resolved=None) -> tuple[dict[tuple[str, str], np.ndarray], dict[str, Any]]:
    """Every method's values over its seeds by ``(task, method)`` as
    :func:`nfarm.study.rows.pooled_rows` takes them, and the resolved joints by task: the IK's,
    the rigid-body ID's and, for a measured arm, each contestant's (``measured``) with the reference
    ``(name, sums (T, 1 + 3n))`` (Newton–Euler alone, one model) beside them."""
    values = {("inverse kinematics", n): v for n, v in ik_values.items()} | \
             {("inverse dynamics", n): v for n, v in id_values.items()}
    resolved_by = {"inverse dynamics": resolved}
    if measured is not None:
        values |= {("ID, measured arm", n): v for n, v in measured.items()}
        if reference is not None:
            values["ID, measured arm", reference[0]] = np.asarray(reference[1])[None]
        resolved_by["ID, measured arm"] = measured_resolved
    return values, resolved_by


def shifted_verdict(study, published: Mapping[str, tuple[Any, str | os.PathLike]], anfis: str, rival: str, *,
                    probe: np.ndarray, draws: int = 2000, level: float = 0.95, seed: int = 0) -> Verdict | None:
    """The learned-IK verdict on the shifted population ``study`` declares (``study.shifted``,
    :func:`nfarm.study.shifted.shifted_ik`; ``None`` where it declares none), read once by the
    frozen models of the main verdict: ``anfis`` against ``rival``, each over its seeds
    (``published`` as :func:`ik_values_over_seeds` takes it, checked on the poses ``probe``), by
    the 95th-percentile tool position error with the study's IK targets; one comparison of the
    shifted family (:func:`shifted_id_verdicts` gives the others; Holm's correction over them is the
    caller's, :func:`nfarm.study.verdict_rows.with_holm`)."""
    if study.shifted is None:
        return None
    targets = shifted_ik(study)
    values = ik_values_over_seeds(study.robot, {name: published[name] for name in (anfis, rival)}, targets["T"],
                                  targets["q"], probe=probe, seed=seed)
    return ik_verdict(study.robot.name, values, anfis, rival, task="inverse kinematics, shifted population",
                      units="shifted targets", draws=draws, level=level, seed=seed)


def baseline_models(group, *, seed: int = 0) -> list:
    """The models of an ``id_baseline`` configuration's cells over its seeds (``group``: its
    :class:`~nfarm.study.sweep.Replicates`), the chapter's ``seed`` first, each reused where its
    cell keeps it (:data:`nfarm.study.replicates.MODEL_OF`)."""
    runs = sorted(group.runs, key=lambda r: (r.cell.params["seed"] != seed, r.cell.params["seed"]))
    return [replicates.MODEL_OF["id_baseline"](r.cell.params) for r in runs]


def finalist_models(idc, label: str, where_of: Callable[[str, str], Path], robot, probe: Sequence[np.ndarray], *,
                    seed: int = 0) -> list:
    """The models of the measured arm's finalist ``label`` (a label of chapter 6.8's contest ``idc``)
    over its seeds, the chapter's ``seed`` first, from where chapter 6 published it (``where_of(tier,
    slot)``, e.g. :meth:`nfarm.study.chosen_models.ChosenModels.id_finalist`), checked on the states
    ``probe``.

    Raises:
        ValueError: ``label`` is not one of the tiers' published finalists.
    """
    family = {contest.id_label(f): f for f in idc.chosen}.get(label)
    tier = family.rsplit(":", 1)[0] if family else None
    pair = idc.pair(tier) if tier else (None, None)
    slot = next((k for k, g in zip(("anfis", "rival"), pair) if g is not None and contest.id_family(g.cell.params) == family),
                None)
    if slot is None:
        raise ValueError(f"{label!r} is not a published finalist of the measured arm's contest")
    where = where_of(tier, slot)
    return seed_models(where, load_id_model(where, robot), probe, seed=seed)


def shifted_id_verdicts(study, rigid: Mapping[str, Sequence[Any]], rigid_pair: tuple[str, str], *, resolved,
                        measured: Mapping[str, Sequence[Any]] | None = None, measured_pair: tuple[str, str] | None = None,
                        measured_resolved=None, measured_seeds: Sequence[int] | None = None, draws: int = 2000,
                        level: float = 0.95, seed: int = 0) -> list[Verdict]:
    """The ID verdicts on the shifted trajectories ``study`` declares (:func:`nfarm.study.shifted.shifted_id`;
    ``[]`` where it declares none), read once by the frozen models of the main verdict, each over its
    seeds (``rigid``, ``measured``: method → its models, the chapter's seed first): the rigid-body
    task's ``rigid_pair`` (ANFIS, best other) by the worst ``resolved`` joint's NRMSE on the model's
    torques, and, for a measured arm, the measured arm's headline pair ``measured_pair`` over every
    tier on the readings of the arm built for each model's draw (``measured_seeds``: the seed of the
    cell that trained each of a method's models, in their order; ``None``: all the study's own, draw 0;
    :func:`nfarm.study.shifted.shifted_readings`) and the states its
    encoders give (``measured_resolved``: the joints its sensors resolve, fixed on validation). The
    NRMSE divides by the shifted torques' own spread. Holm's correction over the shifted family is
    the caller's."""
    if study.shifted is None or study.shifted.id_trajectories is None:
        return []
    data = shifted_id(study)
    boot = {"draws": draws, "level": level, "seed": seed}

    def sums(models, states, tau):
        return np.stack([trajectory_sums(m.predict(*states), tau, data["trajectory"]) for m in models])

    with warnings.catch_warnings(record=True) as caught:       # a model's warnings are the caller's to show
        warnings.simplefilter("always")
        exact = tuple(data[k] for k in ("q", "qd", "qdd"))
        values = {name: sums(rigid[name], exact, data["tau"]) for name in rigid_pair}
        out = [rigid_id_verdict(study.robot.name, values, *rigid_pair, resolved=resolved, units="shifted trajectories",
                                task="rigid-body inverse dynamics, shifted population", **boot)]
        if measured is not None and measured_pair is not None and "tau_measured" in data:
            known = tuple(data.get(f"{k}_measured", data[k]) for k in ("q", "qd", "qdd"))
            # each model against the arm built for its draw, as on the test split
            seeds = [0] * max(len(measured[name]) for name in measured_pair) if measured_seeds is None else \
                [int(s) for s in measured_seeds]
            if any(len(measured[name]) > len(seeds) for name in measured_pair):     # fewer: trained once, the first
                raise ValueError(f"measured_seeds names {len(seeds)} draws, fewer than the pair's models "
                                 f"({[len(measured[name]) for name in measured_pair]})")
            readings = {s: shifted_readings(study, data, s)["tau_measured"] for s in dict.fromkeys(seeds)}
            values = {name: np.stack([trajectory_sums(m.predict(*known), readings[s], data["trajectory"])
                                      for m, s in zip(measured[name], seeds)]) for name in measured_pair}
            out.append(measured_verdict(study.robot.name, values, *measured_pair, resolved=measured_resolved,
                                        tier="every tier, shifted population", units="shifted trajectories", **boot))
    for w in caught:
        warnings.warn(w.message, w.category, stacklevel=2)
    return out


def shifted_caption(study, level: float = 0.95, comparisons: int = 1, alpha: float = 0.05) -> str:
    """The shifted verdict table's caption: what the populations are and how they were judged
    (``comparisons`` of them, Holm's correction at family-wise error ``alpha`` over more than one)."""
    ids = study.shifted is not None and study.shifted.id_trajectories is not None
    return (f"The verdict on shifted populations read once: for inverse kinematics {describe_shifted(study)}"
            + (f"; for inverse dynamics {describe_shifted_id(study)}" if ids else "")
            + f" — the ANFIS and the best other method of each main verdict, frozen, over the same seeds, with the same "
            f"two-level {level:.0%} bootstrap"
            + (f"; Holm's correction over these {comparisons} comparisons at a family-wise error of {alpha:.0%}"
               if comparisons > 1 else " (one comparison: no family-wise correction)"))


# --------------------------------------------------------------------------------------------
# The captions of chapter 7.7's published tables


def verdict_caption(level: float, comparisons: int, alpha: float) -> str:
    """The verdict table's caption: ``comparisons`` distinct comparisons under Holm's correction at
    family-wise error ``alpha``."""
    return (f"The verdict on held-out data: per task, the methods compared (each chosen on validation), each pooled "
            f"over its seeds and the test units with a two-level {level:.0%} bootstrap interval (kind in the 'interval' "
            f"column), the ANFIS's rank, its difference from the best other method paired by seed and unit, and the "
            f"study's targets met on those intervals (docs/STUDY.md). A difference is shown where its interval excludes "
            f"0 and its bootstrap p-value (p), corrected by Holm's method over the arm's {comparisons} distinct "
            f"comparisons (holm_p), is below {alpha:g}: the family-wise error of the whole verdict at most {alpha:.0%}")


def summary_caption(level: float, draws: int) -> str:
    """The long summary table's caption (``07_summary``)."""
    return (f"The study's result: every method's errors on held-out data, a method chapter 6 trained over several seeds "
            f"pooled over them (a two-level {level:.0%} bootstrap interval over the seeds and the test units), one "
            f"trained once or exact over the test units ({draws:,} resamples; the kind of each interval in the 'spread' "
            f"column)")


def paired_caption(level: float) -> str:
    """The paired comparisons' caption (``07_paired``)."""
    return (f"The comparisons the abstract states: each method less the one it is compared with, seed by seed on the "
            f"same test poses or trajectories, with the paired two-level {level:.0%} interval where either was trained "
            f"over several seeds (one with a single model beside each seed's model), else over the test units ('spread' "
            f"names the kind; an interval that holds 0: no difference)")


def wide_caption(task: str, level: float) -> str:
    """A task's wide table's caption (``07_summary_ik`` and the like)."""
    return (f"{task[0].upper() + task[1:]} on held-out data: value ({level:.0%} interval over the seeds and the test "
            f"units for a method trained over several seeds, over the test units for the others)")
