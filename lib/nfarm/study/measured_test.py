"""Chapter 7.6: the measured arm's learned-ID contest (chapter 6.8) judged once on the held-out
trajectories — what learning adds to Newton–Euler on an arm that is built, not modelled.

The test split of a measured arm holds, beside the rigid-body torques, the torques read from the
motor currents of the built arm (``tau_measured``), the states its encoders read (``q_measured``
…) and, where the study declares one, the same trajectories carrying a payload no model was
trained with (``tau_payload``). :func:`measured_test` runs (or reuses) each finalist's test cell,
the two least-squares references beside them, and Newton–Euler alone on the nominal model; the
tables of :func:`rmse_table`, :func:`nrmse_table` and :func:`payload_table` are chapter 7.6's
(:func:`measured_tables` makes the three), and :func:`against` says one method against another on
the paired interval of their worst joints. :func:`measured_figure` shows a held-out trajectory's
measured torques and predictions (:func:`shown_predictions`), and :func:`deploy_table` what each
tier's choice would cost to deploy.

Every error is kept as **trajectory sums** ``(T, 1 + 3n)`` (:func:`nfarm.study.statistics.trajectory_sums`):
the intervals resample the held-out trajectories, as everywhere in the study.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib.figure import Figure

from ..infra.paths import shown_path
from ..learning.baselines import load_id_model
from ..learning.bases import tier_of
from ..model.dynamics import rnea, stribeck_drive_torques
from ..presentation.plotting import plot_per_joint
from ..presentation.tables import Table
from ..presentation.wording import times, worst_of
from . import contest
from .datasets import built_arm
from .id_test_report import per_sample
from .statistics import (Interval, bootstrap_nrmse, resolved_joints, trajectory_maxima, trajectory_sums,
                         worst_difference)
from .rows import (ROLE_CHOSEN, ROLE_FRICTION_ID, ROLE_LEARNED_ALONE, ROLE_NUMERICAL, ROLE_PHYSICS,
                   ROLE_RESIDUAL_BASELINE, ROLE_SPAN, ROLE_TIER_ANFIS, ROLE_TIER_RIVAL, Row, bootstrap_resolved)
from .verdict_rows import ID_TARGET_PCT, target_verdict
from .sweep import sweep_results
from .sweep_files import Sweep

__all__ = ["JOINT_GROUPS", "joint_groups", "joint_groups_on_validation", "NE", "MeasuredTest", "measured_test", "rmse_table", "nrmse_table", "payload_table", "against",
           "MeasuredTables", "measured_tables", "shown_predictions", "measured_figure", "deploy_times", "deploy_table",
           "deploy_prose"]

#: The nominal model alone, the reference every learned model is compared with.
NE = "Newton–Euler alone"


@dataclass(frozen=True)
class MeasuredTest:
    """The measured arm's held-out trajectories and every tested method's errors on them.

    ``contest`` is chapter 6.8's outcome (:func:`nfarm.study.contest.id_contest`, validation) and
    ``sweep`` its sweep; ``sums``, ``maxima`` and ``payload_sums`` map each method's label —
    :data:`NE` first, then each tested contestant in the order its cells ran — to its trajectory
    sums against the measured torques (``(T, 1 + 3n)``), its largest errors per trajectory
    (``(T, n)``) and its sums against the payload case's torques (empty without one);
    ``predict_us`` each contestant's prediction time per state as its cell measured it [µs].
    ``states`` are the encoders' ``(q, qd, qdd)`` [rad, rad/s, rad/s²], ``measured`` and
    ``payload`` the torques read [N·m]."""

    contest: contest.IDContest
    sweep: Sweep
    states: tuple[np.ndarray, np.ndarray, np.ndarray]
    measured: np.ndarray
    payload: np.ndarray | None
    sums: Mapping[str, np.ndarray]
    maxima: Mapping[str, np.ndarray]
    payload_sums: Mapping[str, np.ndarray]
    predict_us: Mapping[str, float]

    @property
    def order(self) -> list[str]:
        """Every tested method, :data:`NE` first."""
        return list(self.sums)

    @property
    def tier(self) -> dict[str, str]:
        """Each method's tier of prior knowledge (Newton–Euler alone: the nominal model)."""
        return {NE: "nominal model", **{name: name.split(":")[0] for name in self.order[1:]}}

    @property
    def friction_id(self) -> str:
        """The least-squares friction identification on the nominal model (a reference)."""
        return contest.id_label(f"{tier_of({'residual': True})}:friction")

    @property
    def built_identification(self) -> str:
        """The identification of the built arm's masses and drives on the known geometry."""
        return contest.id_label(f"{tier_of({'learner': 'identification'})}:identification")

    @property
    def residual(self) -> str:
        """Newton–Euler with an ANFIS residual: the nominal tier's ANFIS (the chosen model)."""
        return contest.id_label(f"{tier_of({'residual': True})}:anfis")

    @property
    def residual_rival(self) -> str | None:
        """The nominal tier's best other learner as a residual, where the tier has one."""
        rival = self.contest.pair(tier_of({"residual": True}))[1]
        return contest.id_label(contest.id_family(rival.cell.params)) if rival is not None else None

    @property
    def learned_alone(self) -> str | None:
        """The best ANFIS without the rigid-body model (generic or structure-informed), by validation."""
        alone = [g for g in (self.contest.pair(t)[0] for t in (tier_of({"inputs": "own"}), tier_of({"inputs": "affine"})))
                 if g is not None]
        if not alone:
            return None
        return contest.id_label(contest.id_family(min(alone, key=lambda g: g.metrics["worst_nrmse"]).cell.params))

    @property
    def roles(self) -> dict[str, str]:
        """The roles the study's summary and abstract read, for the methods tested."""
        roles = {name: ROLE_TIER_ANFIS if name.endswith(": ANFIS") else ROLE_SPAN if contest.in_span(name) else
                 ROLE_TIER_RIVAL for name in self.order}
        roles |= {NE: ROLE_NUMERICAL, self.friction_id: ROLE_FRICTION_ID, self.built_identification: ROLE_PHYSICS,
                  self.residual: ROLE_CHOSEN}
        if self.residual_rival not in (None, self.friction_id):
            roles[self.residual_rival] = ROLE_RESIDUAL_BASELINE
        if self.learned_alone is not None:
            roles[self.learned_alone] = ROLE_LEARNED_ALONE
        return {name: role for name, role in roles.items() if name in self.sums}

    @property
    def pairs(self) -> dict[str, tuple[str, str]]:
        """Each tier's ANFIS and its best rival (labels), for the tiers that have both."""
        return {tier: tuple(contest.id_label(contest.id_family(g.cell.params)) for g in self.contest.pair(tier))
                for tier in self.contest.tiers if None not in self.contest.pair(tier)}


def measured_test(robot, id_test: Mapping[str, np.ndarray], sweep, *, other_seeds: Sequence[int], seed: int = 0,
                  sweeps_dir=None, workers: int | None = None, run=sweep_results) -> MeasuredTest:
    """The measured arm's test: chapter 6.8's contest read back from its cells (``sweep``: the
    ``id_contest`` sweep restricted to this arm; its seed-0 cells and the finalists' cells on
    ``other_seeds``), then each finalist and the two least-squares references judged once on the
    test split ``id_test`` (the chapter's ``seed``), and Newton–Euler alone on the encoders'
    states. Cells are run or reused through ``run`` (:func:`nfarm.study.sweep.sweep_results`)."""
    states = tuple(id_test.get(f"{k}_measured", id_test[k]) for k in ("q", "qd", "qdd"))
    measured, payload, trajectory = id_test["tau_measured"], id_test.get("tau_payload"), id_test["trajectory"]
    seed0 = run(sweep, sweeps_dir, workers=workers)
    idc = contest.id_contest(seed0, contest.id_spread_runs(sweep, seed0, other_seeds,
                                                           lambda s: run(s, sweeps_dir, workers=workers)))
    nominal, identification = tier_of({"residual": True}), tier_of({"learner": "identification"})
    references = [name for name in idc.chosen if name in (f"{nominal}:friction", f"{identification}:identification")]
    tested = list(dict.fromkeys([*idc.finalists, *references]))
    cells = sweep.with_cells([{**idc.chosen[name].cell.params, "seed": seed, "split": "test"} for name in tested])
    tau_ne = rnea(robot, *states)
    sums = {NE: trajectory_sums(tau_ne, measured, trajectory)}
    maxima = {NE: trajectory_maxima(tau_ne, measured, trajectory)}
    payload_sums = {} if payload is None else {NE: trajectory_sums(tau_ne, payload, trajectory)}
    predict_us = {}
    for r in run(cells, sweeps_dir, workers=workers):
        name = contest.id_label(contest.id_family(r.cell.params))
        sums[name] = np.array(r.metrics["trajectory_sums"]).reshape(-1, 1 + 3 * robot.n)
        maxima[name] = np.array(r.metrics["trajectory_maxima"]).reshape(-1, robot.n)
        predict_us[name] = r.metrics["predict_us"]
        if payload is not None:
            payload_sums[name] = np.array(r.metrics["payload_trajectory_sums"]).reshape(-1, 1 + 3 * robot.n)
    return MeasuredTest(idc, sweep, states, measured, payload, sums, maxima, payload_sums, predict_us)


def rmse_table(t: MeasuredTest, noise: np.ndarray, *, draws: int = 2000, level: float = 0.95,
               seed: int = 0) -> tuple[Table, dict[str, Interval]]:
    """Every method's RMSE per joint against the measured torques [N·m] with the worst joint's
    interval over the test trajectories, beside the sensor noise σ (``noise (n,)`` [N·m]); and
    the intervals by method."""
    ci = {name: bootstrap_nrmse(t.sums[name], draws=draws, level=level, seed=seed, normalised=False) for name in t.order}
    n = len(noise)
    rows = [[name, t.tier[name], *c.value, c.worst, f"{c.worst_low:.3g}–{c.worst_high:.3g}"] for name, c in ci.items()]
    rows += [["sensor noise σ", "", *noise, noise.max(), ""]]
    return Table(["model", "tier", *(f"τ{j + 1} [N·m]" for j in range(n)), "worst [N·m]", f"{level:.0%} interval [N·m]"],
                 rows, floatfmt=".3g",
                 caption=f"RMSE of every joint against the measured torques of the {ci[NE].trajectories} held-out "
                         f"trajectories (states from the encoder), beside the sensor noise σ; the interval of the worst "
                         f"joint's from {draws:,} bootstrap resamples"), ci


def nrmse_table(t: MeasuredTest, noise: np.ndarray, *, draws: int = 2000, level: float = 0.95, seed: int = 0
                ) -> tuple[Table, np.ndarray, dict[str, Row], dict[str, Row]]:
    """The study's ≤ 5 % target judged on the arm as it is measured: every joint's NRMSE against
    the measured torques' spread, the worst over the joints a sensor resolves (their spread above
    ``noise``) and over every joint, each with its interval over the test trajectories. Returns the
    table, the resolved joints ``(n,)`` and the summary rows of both worst values by method."""
    n = len(noise)
    resolved = resolved_joints(t.measured.std(axis=0), noise)
    nrmse = {name: bootstrap_resolved(t.sums[name], resolved, draws=draws, level=level, seed=seed) for name in t.order}
    every = {name: bootstrap_resolved(t.sums[name], np.ones(n, bool), draws=draws, level=level, seed=seed)
             for name in t.order}
    over = f"bootstrap over {nrmse[NE].trajectories} test trajectories"
    roles = t.roles
    rows_of = lambda estimates, metric: {      # noqa: E731
        name: Row("ID, measured arm", name, roles[name], metric, "%", 100 * c.worst, 100 * c.worst_low,
                  100 * c.worst_high, draws, level, over) for name, c in estimates.items()}
    target, target_all = rows_of(nrmse, "worst NRMSE"), rows_of(every, "worst NRMSE, every joint")
    table = Table(["model", "tier", *(f"τ{j + 1} [%]" + ("" if resolved[j] else " (below noise)") for j in range(n)),
                   f"{worst_of(resolved)} [%]", f"{level:.0%} interval [%]", "≤ 5 %", "every joint [%]", "≤ 5 %, every joint"],
                  [[name, t.tier[name], *(100 * c.value), 100 * c.worst, f"{100 * c.worst_low:.3g}–{100 * c.worst_high:.3g}",
                    target_verdict(target[name], ID_TARGET_PCT), 100 * every[name].worst,
                    target_verdict(target_all[name], ID_TARGET_PCT)] for name, c in nrmse.items()], floatfmt=".3g",
                  caption="NRMSE of every joint against the measured torques' spread on the held-out trajectories — the "
                          "study's ≤ 5 % target judged on the arm as it is measured, on the worst joint a sensor resolves "
                          "and on the worst of every joint; ✓ where the whole interval is below it")
    return table, resolved, target, target_all


def payload_table(t: MeasuredTest, rmse: Mapping[str, Interval], payload_kg: float, *, draws: int = 2000,
                  level: float = 0.95, seed: int = 0) -> tuple[Table, dict[str, Interval]]:
    """The payload case: every method's RMSE against the torques of the same held-out trajectories
    with ``payload_kg`` at the tool, which no model was trained with, beside its worst joint's
    without it (``rmse``: :func:`rmse_table`'s intervals)."""
    ci = {name: bootstrap_nrmse(t.payload_sums[name], draws=draws, level=level, seed=seed, normalised=False)
          for name in t.order}
    n = t.measured.shape[1]
    return Table(["model", "tier", *(f"τ{j + 1} [N·m]" for j in range(n)), "worst [N·m]", f"{level:.0%} interval [N·m]",
                  "worst without the payload [N·m]"],
                 [[name, t.tier[name], *c.value, c.worst, f"{c.worst_low:.3g}–{c.worst_high:.3g}", rmse[name].worst]
                  for name, c in ci.items()], floatfmt=".3g",
                 caption=f"The payload case: the same held-out trajectories with {payload_kg:g} kg at the tool, which no "
                         f"model was trained with — RMSE against the measured torques"), ci


def against(t: MeasuredTest, name: str, reference: str, *, draws: int = 2000, level: float = 0.95,
            seed: int = 0) -> tuple[str, str]:
    """``name`` against ``reference`` on the worst joint's RMSE [N·m] of the measured torques,
    paired over the test trajectories: ``("better" | "worse" | "same", words)``."""
    diff, low, high = worst_difference(t.sums[name], t.sums[reference], draws=draws, level=level, seed=seed,
                                       normalised=False)
    if high < 0:
        return "better", f"{-diff:.2g} N·m better (paired interval {-high:.2g} to {-low:.2g})"
    if low > 0:
        return "worse", f"{diff:.2g} N·m worse (paired interval {low:.2g} to {high:.2g})"
    return "same", f"no difference shown (paired interval of the difference {low:.2g} to {high:.2g} N·m)"


@dataclass(frozen=True)
class MeasuredTables:
    """Chapter 7.6's tables (:func:`measured_tables`): ``rmse_table`` and the intervals ``rmse``
    of :func:`rmse_table`; ``nrmse_table``, the resolved joints ``resolved (n,)`` and the summary
    rows ``target`` and ``target_all`` of :func:`nrmse_table`; and, where the test split holds the
    payload case, ``payload_table`` and ``payload`` of :func:`payload_table` with ``payload_kg``
    at the tool (else ``None``, ``None`` and 0)."""

    rmse_table: Table
    rmse: Mapping[str, Interval]
    nrmse_table: Table
    resolved: np.ndarray
    target: Mapping[str, Row]
    target_all: Mapping[str, Row]
    payload_table: Table | None
    payload: Mapping[str, Interval] | None
    payload_kg: float


def measured_tables(t: MeasuredTest, noise: np.ndarray, true_arm=None, *, draws: int = 2000, level: float = 0.95,
                    seed: int = 0) -> MeasuredTables:
    """The tables of :func:`rmse_table` and :func:`nrmse_table` (sensor noise ``noise (n,)``
    [N·m]) and, where ``t`` holds the payload case, of :func:`payload_table` with the payload of
    ``true_arm`` (the study's ``id.true_arm``: its ``payload`` [kg])."""
    boot = {"draws": draws, "level": level, "seed": seed}
    rmse_t, rmse = rmse_table(t, noise, **boot)
    nrmse_t, resolved, target, target_all = nrmse_table(t, noise, **boot)
    if t.payload is None:
        return MeasuredTables(rmse_t, rmse, nrmse_t, resolved, target, target_all, None, None, 0.0)
    if true_arm is None:
        raise ValueError("the test split holds a payload case, and no true_arm says its payload")
    payload_t, payload = payload_table(t, rmse, true_arm.payload, **boot)
    return MeasuredTables(rmse_t, rmse, nrmse_t, resolved, target, target_all, payload_t, payload, true_arm.payload)


def shown_predictions(t: MeasuredTest, robot, models_dir: str | os.PathLike, mask: np.ndarray) -> dict[str, np.ndarray]:
    """The torques [N·m] predicted on the test samples ``mask (M,)`` marks (one trajectory's
    encoder states, ``(K, n)`` each): Newton–Euler alone, then the best ANFIS without the
    rigid-body model and the residual ANFIS, as chapter 6.8 saved them under ``models_dir``
    (where the contest has them). The models' warnings are the caller's to show."""
    names = [name for name in (t.learned_alone, t.residual) if name is not None]
    models = {name: load_id_model(contest.id_model_dir(models_dir, name.split(":")[0], "anfis"), robot) for name in names}
    states = tuple(x[mask] for x in t.states)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        shown = {NE: rnea(robot, *states), **{name: m.predict(*states) for name, m in models.items()}}
    for w in caught:
        warnings.warn(w.message, w.category, stacklevel=2)
    return shown


def measured_figure(t: MeasuredTest, shown: Mapping[str, np.ndarray], time_s: np.ndarray, mask: np.ndarray,
                   trajectory: int, joint_names: Sequence[str]) -> tuple[Figure, str]:
    """The measured torques [N·m] of held-out trajectory ``trajectory`` (its samples ``mask (M,)``
    marks, at ``time_s (M,)`` [s]) and the predictions ``shown`` on it (:func:`shown_predictions`);
    the figure and its caption."""
    fig = plot_per_joint(time_s[mask], {"measured": t.measured[mask], **shown}, joint_names, ylabel="τ [N·m]", focus=3.0)
    return fig, f"Held-out trajectory {trajectory}: measured torques and {len(shown)} predictions"


def deploy_times(robot, t: MeasuredTest, *, repeats: int = 3) -> dict[str, float]:
    """[µs per state] what each tested method costs to predict, batched on one core: this run's
    time for Newton–Euler alone (:data:`NE`) on the encoders' states, the test cell's for the
    others (measured where the cell ran). Depends on the machine: shown, not saved."""
    return {NE: 1e6 * per_sample(lambda q, qd, qdd: rnea(robot, q, qd, qdd), *t.states, repeats=repeats)} | dict(t.predict_us)


def deploy_table(t: MeasuredTest, rmse: Mapping[str, Interval], deploy_us: Mapping[str, float], *,
                 level: float = 0.95) -> Table:
    """Tier by tier, each tested method's worst joint RMSE [N·m] on the held-out trajectories
    with its interval (``rmse``: :func:`rmse_table`'s, at coverage ``level``) and its prediction
    time (``deploy_us``: :func:`deploy_times`) absolute and relative to Newton–Euler's."""
    by_tier = sorted(t.order, key=lambda name: (t.tier[name], rmse[name].worst))
    return Table(["tier", "model", "worst joint RMSE [N·m]", f"{level:.0%} interval [N·m]", "prediction [µs/state]",
                  "relative to rnea"],
                 [[t.tier[name], name, rmse[name].worst, f"{rmse[name].worst_low:.3g}–{rmse[name].worst_high:.3g}",
                   deploy_us[name], deploy_us[name] / deploy_us[NE]] for name in by_tier],
                 floatfmt=["", "", ".3g", "", ".3g", ".2g"],
                 caption="What each tier would deploy on the measured arm: the error on the held-out trajectories and the "
                         "prediction time per state, batched, on one core (not saved: it depends on the machine)")


def deploy_prose(t: MeasuredTest, rmse: Mapping[str, Interval], deploy_us: Mapping[str, float],
                 models_dir: str | os.PathLike) -> str:
    """Tier by tier, what chapter 6.8 chose on validation, its worst joint RMSE on the held-out
    trajectories and its time per state against Newton–Euler's (Markdown); the models are saved
    under ``models_dir/id_measured``."""
    chosen = [contest.id_label(contest.id_family(t.contest.winner(tier).cell.params)) for tier in t.contest.tiers]
    return ("Tier by tier, what chapter 6.8 chose on validation, its error on the held-out trajectories and what it costs "
            f"per state against Newton–Euler's {deploy_us[NE]:.2g} µs (saved under "
            f"`{shown_path(os.path.join(models_dir, 'id_measured'))}`, loadable with "
            "`nfarm.learning.baselines.load_id_model`): "
            + "; ".join(f"{tier}: {name.split(': ', 1)[1]}, {rmse[name].worst:.3g} N·m, "
                        f"{times(deploy_us[name] / deploy_us[NE])} rnea's time"
                        for tier, name in zip(t.contest.tiers, chosen) if name in rmse) + ".")


#: The joint groups of :func:`joint_groups`, in the verdict's order.
JOINT_GROUPS = ("rigid-dominated", "friction-dominated")


def joint_groups(study, data: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The measured arm's joints by what moves them on the exact states of ``data`` (``q, qd, qdd
    (N, n)``, e.g. the test split's): **rigid-dominated** where the built arm's rigid-body torque's
    RMS exceeds its drives' (armature, viscous, Coulomb, Stribeck and load-dependent friction:
    :func:`nfarm.model.dynamics.stribeck_drive_torques` with the study's terms), **friction-dominated**
    elsewhere — so that "learns the dynamics" and "fits the friction law" are judged apart. Returns
    ``{group: (n,) bool}`` in :data:`JOINT_GROUPS`' order; no model's output enters it.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.study.study_files import load_study
        >>> study = load_study(PARAMS / "studies" / "intelbot5.yaml")
        >>> q = np.zeros((4, 5)); qd = np.tile([1.0, 0.0, 0.0, 0.0, 1.0], (4, 1))
        >>> {k: v.astype(int).tolist() for k, v in joint_groups(study, {"q": q, "qd": qd, "qdd": 0 * q}).items()}
        {'rigid-dominated': [0, 1, 1, 1, 0], 'friction-dominated': [1, 0, 0, 0, 1]}
    """
    arm, _ = built_arm(study)
    q, qd, qdd = (np.asarray(data[k], float) for k in ("q", "qd", "qdd"))
    rigid = rnea(arm, q, qd, qdd)
    drive = stribeck_drive_torques(arm, qd, qdd, rigid, **study.id.friction)
    dominated = np.sqrt((rigid ** 2).mean(axis=0)) > np.sqrt((drive ** 2).mean(axis=0))
    return {JOINT_GROUPS[0]: dominated, JOINT_GROUPS[1]: ~dominated}


def joint_groups_on_validation(study, directory) -> dict[str, np.ndarray]:
    """:func:`joint_groups` on the exact states of the study's ID validation trajectories (``id_val.npz``
    in ``directory``): the groups fixed on validation data, as every choice is and as the resolved joints
    are (:func:`nfarm.study.rows.resolved_on_validation`), so that the verdict's rows by group do not
    come and go with the test split's draw (the SO-101's second joint: rigid-dominated on the test
    split 2026120706's states by 0.001 N·m of RMS, friction-dominated on validation by 0.024)."""
    from .datasets import load

    return joint_groups(study, load(os.path.join(directory, "id_val.npz"), study.robot, study))
