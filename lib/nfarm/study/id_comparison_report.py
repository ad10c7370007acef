"""The rigid-body inverse dynamics as chapter 6.4–6.6 reports it: which inputs let one ANFIS per
joint learn the Newton–Euler torques without the arm's parameters, how strong scikit-learn
learners fare on the same states, and how the error falls with data and rules.

Every number is a validation **NRMSE**: a joint's RMSE divided by the standard deviation of its
torque on the validation trajectories, in % (one whole spread: predicting the mean torque). The
**worst joint** is taken over the joints a sensor of the measured arm resolves (their spread at
least the sensor noise, :func:`nfarm.study.statistics.resolved_joints`); a configuration's value
is its mean over the seeds it ran, with the least and largest; two whose ranges overlap are not
shown to differ (:func:`nfarm.study.configurations.no_difference`). :class:`TorqueReading` holds
what every table and sentence of these sections shares.

Example:
    >>> import numpy as np
    >>> reading = torque_reading(np.array([[0.0, 0.0], [2.0, 0.02]]), np.array([0.1, 0.1]), ["shoulder", "wrist"])
    >>> reading.worst, reading.fmt(0.0123), reading.fmt(1e-12)
    ('worst of τ1', '1.23', '< 1e-6')
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from ..learning.bases import TIERS, tier_of
from ..learning.baselines import BASELINES, label as base_name
from ..presentation.plotting import plot_size_curve
from ..presentation.tables import Table, shown
from ..presentation.wording import listed, torque_columns, worst_of
from .configurations import RULE_BASE, configuration_label, counts, no_difference, span, value_range
from .statistics import resolved_joints, separation_level
from .rows import with_resolved_worst
from .verdict_rows import ID_TARGET_PCT
from .sweep import CellResult, Replicates, best_by, by_configuration

__all__ = ["ID_FLOOR", "MODEL_FREE", "baseline_words", "TorqueReading", "torque_reading", "same", "comparison_table",
           "wall_time_table", "best_model_free", "comparison_prose", "baselines_table", "by_tier_and_learner", "baselines_timing_table",
           "baseline_winner", "baselines_prose", "size_configurations", "size_figure", "affine_by_rules", "rules_table", "sizes_prose"]

#: An NRMSE at the level of rounding (shown as such, in %: ``"< 1e-6"``).
ID_FLOOR = 1e-8
#: The input sets that need none of the arm's lengths, masses or inertias (section 6.4).
MODEL_FREE = ("own", "all", "trig", "affine_generic", "affine")


def baseline_words(params: Mapping[str, Any]) -> str:
    """A baseline's name for prose: its learner in words and the options its cell gives it (the
    tables keep the learner's key, :func:`nfarm.learning.baselines.label`).

    Example:
        >>> baseline_words({"learner": "mlp", "hidden": [64, 64], "angles": "chain"})
        'multilayer perceptron (angles=chain, hidden=[64, 64])'
    """
    name, learner = base_name(params), params["learner"]
    return (BASELINES[learner].label if learner in BASELINES else learner) + name[len(learner):]


@dataclass(frozen=True)
class TorqueReading:
    """What chapter 6's ID tables and sentences share (:func:`torque_reading`).

    Attributes:
        joint_names: the arm's joints.
        spread: ``(n,)`` [N·m] each joint's torque standard deviation on the validation trajectories.
        resolved: ``(n,)`` bool, the joints the worst joint is taken over.
        columns: the torque columns' headers (``"τ5 [%] (below noise)"``), and ``noise_note`` the
            sentence a caption adds for the joints below the noise.
        worst: the worst joint's words (``"worst of τ1–τ4"``), a table header's.
        keys: the options that name a configuration (the rule base and the options the sweep varies).
        floor: an NRMSE below this is rounding.
    """

    joint_names: tuple[str, ...]
    spread: np.ndarray
    resolved: np.ndarray
    columns: tuple[str, ...]
    noise_note: str
    worst: str
    keys: tuple[str, ...] = RULE_BASE
    floor: float = ID_FLOOR

    def fmt(self, value: float) -> str:
        """An NRMSE (a share) in %, to three digits (``"< 1e-6"`` at rounding level)."""
        return shown(100 * value, ".3g", floor=100 * self.floor)

    def seeds_range(self, g: Replicates, metric: str = "worst_nrmse") -> str:
        """A configuration's least–largest ``metric`` over its seeds, in %."""
        return value_range(g, metric, fmt=self.fmt)

    def label(self, options: Mapping[str, Any], keys: Sequence[str] = RULE_BASE) -> str:
        """A configuration in one line, ``"affine: partition=grid, n_mfs=[1, 2, 2, 2, 1]"`` (shared
        premises named where the joints share them; per joint is every other design)."""
        return configuration_label({**options, "shared_premises": options.get("shared_premises") or None}, "inputs", keys)

    def configurations(self, runs: Iterable[CellResult], source: str) -> list[Replicates]:
        """A sweep's configurations over their seeds, the worst joint taken over the resolved joints
        of the per-joint metric ``source`` (:func:`nfarm.study.rows.with_resolved_worst`)."""
        return with_resolved_worst(by_configuration(runs), self.resolved, source)


def torque_reading(val_tau: np.ndarray, noise, joint_names: Sequence[str], varying: Sequence[str] = ()) -> TorqueReading:
    """How chapter 6 reads learned-ID errors on validation torques ``val_tau (N, n)`` [N·m], with
    sensor noise ``noise (n,)`` [N·m] (``None``: no sensor), for a sweep that varies ``varying``."""
    spread = np.asarray(val_tau).std(axis=0)
    columns, noise_note = torque_columns(spread, noise, joint_names)
    resolved = resolved_joints(spread, noise)
    keys = RULE_BASE + tuple(k for k in varying if k not in RULE_BASE + ("inputs", "seed"))
    return TorqueReading(tuple(joint_names), spread, resolved, tuple(columns), noise_note, worst_of(resolved), keys)


def same(a: Replicates, b: Replicates, metric: str = "worst_nrmse") -> bool:
    """Whether two configurations are not shown to differ (their ranges over the seeds overlap)."""
    return no_difference(a, b, metric)


def _nrmse(r) -> np.ndarray:
    return np.array(r.metrics["val_nrmse"])


def comparison_table(reading: TorqueReading, results: Sequence[Replicates]) -> Table:
    """Section 6.4's input sets (``results``: the sweep's configurations, :meth:`TorqueReading.configurations`):
    each one's tier, rules and parameters, its validation NRMSE per joint, its worst joint and that
    worst's range over the seeds."""
    r_ = reading
    rows = [[r_.label(r.cell.params, r_.keys), tier_of(r.cell.params), counts(r, "rules"), counts(r, "parameters"),
             f"{r.metrics['train_samples']:,.0f}", *(r_.fmt(v) for v in _nrmse(r)), r_.fmt(r.metrics["worst_nrmse"]),
             r_.seeds_range(r)] for r in results]
    return Table(["configuration", "tier", "rules per joint", "parameters", "training states",
                  *r_.columns, f"{r_.worst} [%]", f"{r_.worst}, range over seeds [%]"], rows,
                 caption=f"Validation NRMSE per joint after {span(r.cell.params['epochs'] for r in results)} epochs "
                         f"(rigid-body torques): each tier's best on seed 0 over {max(r.n for r in results)} seeds (each a draw "
                         f"of the training and validation trajectories and of the initialisation), their mean and the worst "
                         f"joint's least and largest value; the others on seed 0, where they were pruned{r_.noise_note}")


def wall_time_table(reading: TorqueReading, results: Sequence[Replicates]) -> Table:
    """Each configuration's wall time, summed over its seeds [s]: shown, not saved (it depends on
    the machine, and a cell whose models were already trained takes less)."""
    return Table(["configuration", f"{len(reading.joint_names)} models per seed, summed over the seeds [s]"],
                 [[reading.label(r.cell.params, reading.keys), sum(x.seconds for x in r.runs)] for r in results],
                 floatfmt=["", ".0f"],
                 caption="Wall time of each configuration's cell when it ran (not saved: it depends on the "
                         "machine, and a cell whose models were already trained takes less)")


def _model_free(results: Sequence[Replicates]) -> list[Replicates]:
    return [r for r in results if r.cell.params["inputs"] in MODEL_FREE]


def best_model_free(results: Sequence[Replicates]) -> Replicates:
    """The chosen ANFIS: of the configurations that need none of the arm's lengths or masses
    (:data:`MODEL_FREE`), the one of least worst-joint NRMSE on validation with seed 0 (where all ran)."""
    return min(_model_free(results), key=lambda r: r.values("worst_nrmse")[0])


def comparison_prose(reading: TorqueReading, results: Sequence[Replicates], best: Replicates) -> str:
    """Section 6.4's findings in words: which joints the worst is taken over, the best
    configuration without the arm's parameters (``best``) and the study's target
    (:data:`nfarm.study.verdict_rows.ID_TARGET_PCT`), the generic tier's best, the configurations
    not shown to differ from it, the dissertation's own-state design, a single rule, and the
    identification on the regressor (a reference)."""
    r_, names, n = reading, reading.joint_names, len(reading.joint_names)
    resolved, fmt, seeds_range = reading.resolved, reading.fmt, reading.seeds_range
    free = _model_free(results)
    own = [r for r in free if r.cell.params["inputs"] == "own"]
    affine = [r for r in free if r.cell.params["inputs"].startswith("affine")]
    below = [names[j] for j in range(n) if not resolved[j]]
    text = (f"The worst joint is taken over {listed(names[j] for j in range(n) if resolved[j])}, whose torques a "
            f"sensor resolves; {listed(below)}'s torque is below the sensor noise. " if below else "")
    text += (f"The best configuration that needs none of the arm's lengths or masses, {r_.label(best.cell.params, r_.keys)} "
             f"({tier_of(best.cell.params)} tier; {best.metrics['rules'][0]} rules per joint), reaches a worst joint NRMSE of "
             f"**{fmt(best.metrics['worst_nrmse'])} %** on the validation trajectories (mean over {best.n} seeds; "
             f"{seeds_range(best)} % over them), on {names[int(np.argmax(np.where(resolved, _nrmse(best), -np.inf)))]}")
    chance = separation_level(best.n, best.n) if best.n >= 2 else float("nan")
    target = f"the study's target for an ANFIS without the arm's parameters, ≤ {ID_TARGET_PCT:g} %"
    text += (f" ({target}: met). " if best.high("worst_nrmse") <= ID_TARGET_PCT / 100
             else f" ({target}: met on average, not in every seed). "
             if best.metrics["worst_nrmse"] <= ID_TARGET_PCT / 100 else f" ({target}: not met). ")
    generic = [r for r in free if tier_of(r.cell.params) == tier_of({"inputs": "own"})]
    if generic and tier_of(best.cell.params) != tier_of(generic[0].cell.params):
        g = min(generic, key=lambda r: r.metrics["worst_nrmse"])
        text += (f"Knowing nothing of the arm — the {tier_of(g.cell.params)} tier, without which axes are parallel — the best "
                 f"is {r_.label(g.cell.params, r_.keys)} at {fmt(g.metrics['worst_nrmse'])} % ({seeds_range(g)} %)"
                 + (": no difference shown, by the seeds' ranges. " if same(g, best) else
                    f": the structure the {tier_of(best.cell.params)} inputs are told is worth the difference. "))
    tied = [r for r in free if r is not best and same(r, best)]
    if tied:
        text += ("Within its spread over the seeds, and so not shown to differ from it: " + ", ".join(
            f"{r_.label(r.cell.params, r_.keys)} ({fmt(r.metrics['worst_nrmse'])} %)" for r in tied) + ". ")
    text += (f"(Two configurations whose {best.n} seeds each came from one distribution would have separate "
             f"ranges by chance with probability {chance:.1%}.) ")
    if own:
        text += (f"With each joint's own state (the dissertation's design, assumed) no grid does better than "
                 f"{fmt(min(r.metrics['worst_nrmse'] for r in own))} % on its worst joint: a joint's torque depends on "
                 f"every joint's angle, speed and acceleration, which its own three inputs do not see. ")
    one_rule = [r for r in affine if r.metrics["rules"][0] == 1 and r.cell.params["inputs"] == best.cell.params["inputs"]]
    if one_rule and best.metrics["rules"][0] > 1:
        one = one_rule[0]
        text += (f"With the same consequents and a single rule — a linear map of the trigonometric terms — "
                 f"the worst joint is at {fmt(one.metrics['worst_nrmse'])} % ({seeds_range(one)} %): "
                 + (f"the rules over the configuration are what turns it into {fmt(best.metrics['worst_nrmse'])} %. "
                    if not same(one, best) else "not shown to differ from the rule base's, by the seeds' ranges. "))
    regressor = [r for r in results if r.cell.params["inputs"] == "regressor"]
    if regressor:
        one = min(regressor, key=lambda r: r.metrics["rules"][0])
        text += (f"The identification on the regressor's inputs ({one.metrics['rules'][0]} rule, least squares on "
                 f"the known geometry) is at {fmt(one.metrics['worst_nrmse'])} %: exact by construction on "
                 f"noise-free torques, a reference, not a learning result.")
    return text


def by_tier_and_learner(groups, metric: str = "worst_nrmse", *, seed: int = 0) -> dict[tuple[str, str], Replicates]:
    """Each learner's configuration of least ``metric`` on ``seed`` within each tier of prior
    knowledge (:func:`nfarm.learning.bases.tier_of`), keyed ``(tier, learner)``: ridge on the chain basis
    (the rigid-body span) and on the structure-informed ANFIS's columns are chosen apart."""
    by_tier: dict[str, list[Replicates]] = {}
    for g in groups:
        by_tier.setdefault(tier_of(g.cell.params), []).append(g)
    return {(tier, learner): g for tier, members in by_tier.items()
            for learner, g in best_by(members, "learner", metric, seed=seed).items()}


def baselines_table(reading: TorqueReading, results: Sequence[Replicates],
                    best: Mapping[tuple[str, str], Replicates]) -> Table:
    """Section 6.5's scikit-learn baselines (``results``, their configurations; ``best``: each
    learner's best on seed 0 in each tier, :func:`by_tier_and_learner`, marked ◀): each one's tier,
    features, validation NRMSE per joint, worst joint and its range over the seeds."""
    r_ = reading
    chosen = {id(g) for g in best.values()}
    rows = [[base_name(r.cell.params) + (" ◀" if id(r) in chosen else ""), tier_of(r.cell.params),
             r.metrics["features"], f"{r.metrics['train_samples']:,.0f}", *(r_.fmt(v) for v in r.metrics["nrmse"]),
             r_.fmt(r.metrics["worst_nrmse"]), r_.seeds_range(r)] for r in results]
    return Table(["learner", "tier", "features", "training states", *r_.columns, f"{r_.worst} [%]",
                  f"{r_.worst}, range over seeds [%]"], rows,
                 caption=f"Validation NRMSE of the scikit-learn baselines: each tier's best on seed 0 over "
                         f"{max(r.n for r in results)} seeds, their mean and the worst joint's range; the others on seed 0, "
                         f"where they were pruned (◀ each learner's best on seed 0 in its tier, tested in chapter 7){r_.noise_note}")


def baselines_timing_table(results: Sequence[Replicates]) -> Table:
    """The baselines' fit [s] and prediction [µs per state] times, mean over the seeds: shown,
    not saved (they depend on the machine)."""
    return Table(["learner", "fit [s]", "predict [µs/state]"],
                 [[base_name(r.cell.params), r.metrics["fit_seconds"], r.metrics["predict_us"]] for r in results],
                 floatfmt=["", ".3g", ".3g"],
                 caption="Fit and prediction times of the runs that made the cells, on one core, mean over the seeds "
                         "(not saved: they depend on the machine)")


def _ranked(best: Mapping[tuple[str, str], Replicates]) -> list[Replicates]:
    """The learners' choices but the rigid-body span's (an identification in disguise, not a rival:
    :data:`nfarm.learning.bases.TIERS`), by the worst joint's NRMSE on seed 0, as chosen."""
    return sorted((g for (tier, _), g in best.items() if tier != TIERS["span"]),
                  key=lambda r: r.values("worst_nrmse")[0])


def baseline_winner(best: Mapping[tuple[str, str], Replicates]) -> Replicates:
    """The best baseline: of each learner's best in each tier (the rigid-body span aside), the least
    worst-joint NRMSE on seed 0.

    Raises:
        ValueError: every baseline is of the rigid-body span (or there is none).
    """
    ranked = _ranked(best)
    if not ranked:
        raise ValueError(f"the baselines' sweep holds no learner outside the {TIERS['span']} tier "
                         f"(an identification in disguise is no rival): add one to params/sweeps/id_baselines.yaml")
    return ranked[0]


def baselines_prose(reading: TorqueReading, results: Sequence[Replicates], best: Mapping[str, Replicates],
                    anfis: Replicates, *, exact: float = 1e-4) -> str:
    """Section 6.5's findings in words: the best baseline and the least-squares floor, the
    learners better than the chosen ANFIS (``anfis``) on every seed and those not shown to
    differ from it, and what ridge regression on the chain and generic bases reaches (exact to
    rounding when every seed's worst NRMSE is below ``exact``)."""
    fmt, seeds_range = reading.fmt, reading.seeds_range
    winner = baseline_winner(best)
    ranked = _ranked(best)
    anfis_worst = anfis.metrics["worst_nrmse"]
    floor = next((g for (_, learner), g in best.items() if learner == "linear"), None)
    text = (f"Of the baselines (the rigid-body span aside), {baseline_words(winner.cell.params)} is best on the validation "
            f"trajectories, at **{fmt(winner.metrics['worst_nrmse'])} %** on its worst joint ({seeds_range(winner)} % over "
            f"the seeds); the least-squares floor on `[q, q̇, q̈]` is at {fmt(floor.metrics['worst_nrmse'])} %. "
            if floor is not None else
            f"Of the baselines, {baseline_words(winner.cell.params)} is best, at {fmt(winner.metrics['worst_nrmse'])} %. ")
    beaten = [r for r in ranked if r.metrics["worst_nrmse"] < anfis_worst and not same(r, anfis)]
    tied = [r for r in ranked if same(r, anfis)]
    tier = tier_of(anfis.cell.params)
    if beaten:
        text += (f"{len(beaten)} of the {len(ranked)} learners {'does' if len(beaten) == 1 else 'do'} better than the best "
                 f"{tier} ANFIS ({fmt(anfis_worst)} %, {seeds_range(anfis)} %), every seed of "
                 f"{'it' if len(beaten) == 1 else 'each'} below every seed of the ANFIS: "
                 + ", ".join(f"{baseline_words(r.cell.params)} ({fmt(r.metrics['worst_nrmse'])} %)" for r in beaten) + ". ")
    if tied:
        text += ("No different from the ANFIS by the seeds' ranges: " + ", ".join(
            f"{baseline_words(r.cell.params)} ({fmt(r.metrics['worst_nrmse'])} %, {seeds_range(r)} %)" for r in tied) + ". ")
    if not beaten and not tied:
        text += f"None does better than the best ANFIS, {tier} ({fmt(anfis_worst)} %). "
    chain = [r for r in results if r.cell.params.get("basis") == "chain"]
    if chain and min(r.high("worst_nrmse") for r in chain) < exact:
        text += ("Ridge regression on the chain basis is exact to rounding in every seed: for this arm the span of "
                 "those products holds the rigid-body model (`tests/test_bases.py` checks it), so the fit is an "
                 "identification that needs no masses — it needs the right basis, which the fuzzy rules of "
                 "the `affine` set approximate instead of being told; it stands in a tier of its own, the rigid-body "
                 "span, shown beside the verdict as Newton–Euler is, not as the learners' rival. ")
    elif chain:
        text += (f"Ridge regression on the chain basis reaches {fmt(min(r.metrics['worst_nrmse'] for r in chain))} % "
                 f"on this arm, whose roll link couples more angles than products of two functions express. ")
    generic = [r for r in results if r.cell.params.get("basis") == "generic"]
    if generic:
        text += (f"On the generic basis (no knowledge of parallel axes) ridge regression reaches "
                 f"{fmt(min(r.metrics['worst_nrmse'] for r in generic))} %.")
    return text


def size_configurations(reading: TorqueReading, runs: Iterable[CellResult]) -> list[Replicates]:
    """Section 6.6's configurations (the ``id_sizes`` sweep's cells, ``runs``) over their seeds,
    by ascending share of the training trajectories."""
    return sorted(reading.configurations(runs, "val_nrmse"), key=lambda r: r.cell.params["fraction"])


def size_figure(reading: TorqueReading, sizes: Sequence[Replicates]) -> tuple[Figure, str]:
    """Section 6.6's curve: the validation NRMSE [%] of each resolved joint against the training
    states (``sizes``: the ``id_sizes`` sweep's configurations by ascending share), mean over the
    seeds and their range (a joint below the noise would stretch the log axis by decades: left
    out); the figure and its caption."""
    names, resolved = reading.joint_names, reading.resolved
    shown_j = np.flatnonzero(resolved)
    shares = listed(f"{r.cell.params['fraction']:.0%}" for r in sizes)
    fig = plot_size_curve([r.metrics["train_samples"] for r in sizes],
                          100 * np.array([r.metrics["val_nrmse"] for r in sizes])[:, shown_j],
                          [names[j] for j in shown_j], numbers=shown_j + 1, unit="%", quantity="validation NRMSE",
                          symbol="τ", xlabel=f"training states, mean over the seeds\n(one in {sizes[0].cell.params['stride']} "
                                             f"of the first {shares} of the trajectories)",
                          low=100 * np.array([r.low("val_nrmse") for r in sizes])[:, shown_j],
                          high=100 * np.array([r.high("val_nrmse") for r in sizes])[:, shown_j],
                          spread_label=f"range over {span(r.n for r in sizes)} seeds")
    left = [f"τ{j + 1}" for j in range(len(names)) if not resolved[j]]
    return fig, (f"Validation NRMSE per joint of the {tier_of({'inputs': 'affine'})} ANFIS (affine inputs, rules over "
                 "q2–q4) against the training data: mean over the seeds, and their range"
                 + (f" ({listed(left)}, below the sensor noise, left out: the table of rule counts below gives "
                    f"{'its' if len(left) == 1 else 'their'} values)" if left else ""))


def affine_by_rules(results: Sequence[Replicates]) -> list[Replicates]:
    """Section 6.4's ``affine`` configurations by ascending rule count."""
    return sorted((r for r in results if r.cell.params["inputs"] == "affine"), key=lambda r: r.metrics["rules"][0])


def rules_table(reading: TorqueReading, results: Sequence[Replicates]) -> Table:
    """The ``affine`` input set against its rule base (section 6.4's cells): rules, functions per
    joint angle, parameters, validation NRMSE per joint, the worst joint and its range over the seeds."""
    r_ = reading
    rows = [[r.metrics["rules"][0], str(r.cell.params["n_mfs"]), r.metrics["parameters"], *(r_.fmt(v) for v in _nrmse(r)),
             r_.fmt(r.metrics["worst_nrmse"]), r_.seeds_range(r)] for r in affine_by_rules(results)]
    return Table(["rules per joint", "functions per joint angle", "parameters", *r_.columns,
                  f"{r_.worst} [%]", f"{r_.worst}, range over seeds [%]"], rows,
                 caption="Validation NRMSE of the affine input set against its rule base (section 6.4's cells, mean over the "
                         f"seeds){r_.noise_note}")


def sizes_prose(reading: TorqueReading, sizes: Sequence[Replicates], results: Sequence[Replicates]) -> str:
    """Section 6.6's findings in words: whether more training states lowered the worst joint's
    NRMSE beyond the seeds' ranges, and which rule base of the ``affine`` set is best and by how
    much the others differ."""
    fmt, seeds_range = reading.fmt, reading.seeds_range
    by_rules = affine_by_rules(results)
    text = ""
    if len(sizes) >= 2:
        first, last = sizes[0], sizes[-1]
        text += (f"From {first.metrics['train_samples']:,.0f} to {last.metrics['train_samples']:,.0f} training states the "
                 f"worst joint's validation NRMSE goes from {fmt(first.metrics['worst_nrmse'])} % ({seeds_range(first)} %) to "
                 f"{fmt(last.metrics['worst_nrmse'])} % ({seeds_range(last)} %)"
                 + (": no difference shown by the seeds' ranges. " if same(first, last) else
                    ": the seeds' ranges are separate, so more data still helps. "
                    if last.metrics["worst_nrmse"] < first.metrics["worst_nrmse"] else
                    ": the seeds' ranges are separate, and more data did worse. "))
    if len(by_rules) >= 2:
        best = min(by_rules, key=lambda r: r.metrics["worst_nrmse"])
        text += (f"Over the rule bases tried, the worst joint is least with {best.metrics['rules'][0]} rules "
                 f"({fmt(best.metrics['worst_nrmse'])} %, {best.metrics['parameters']:,} parameters)")
        fewer = [r for r in by_rules if r.metrics["rules"][0] < best.metrics["rules"][0]]
        more = [r for r in by_rules if r.metrics["rules"][0] > best.metrics["rules"][0]]
        parts = [f"{r.metrics['rules'][0]} rule{'s' if r.metrics['rules'][0] != 1 else ''}: {fmt(r.metrics['worst_nrmse'])} %"
                 + (" (no difference shown by the seeds' ranges)" if same(r, best) else "") for r in fewer + more]
        text += ("; " + ", ".join(parts) + ". ") if parts else ". "
        if more and all(not same(r, best) for r in more):
            text += ("More rules do worse on the validation trajectories: each rule's hundreds of consequents see "
                     "fewer states, and the trajectories do not fill the configuration space. ")
        text += "Larger rule bases are in `params/sweeps/id_comparison_large.yaml`, for a cluster."
    return text
