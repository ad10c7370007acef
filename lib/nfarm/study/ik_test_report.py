"""Chapter 7.1: every IK method on the held-out test poses — the chosen learned IK, the
dissertation's recipe, the contest's rivals, Levenberg–Marquardt and the closed form — their
joint and tool errors, their bootstrap summaries and the sentences that read them; what the
encoding gives before anything is learned (the credit ablation) and what the ANFIS's structure
gives (the structure ablation).

:func:`evaluate_ik` predicts and times every method once (:class:`IKTest`); the tables and sentences
only read it. Errors are kept as :func:`nfarm.learning.learned.ik_errors` gives them (joint [rad],
tool position [m], orientation [rad]); the tables and the words show degrees and millimetres,
a value below :data:`FLOOR` as rounding (``"< 1e-6"``).

Example:
    >>> import numpy as np
    >>> errors = {"exact": {"joint": np.zeros((4, 2)), "position": np.zeros(4), "orientation": np.zeros(4)},
    ...           "off": {"joint": np.radians([[1.0, -2.0]] * 4), "position": np.full(4, 1e-3),
    ...                   "orientation": np.radians(np.full(4, 0.5))}}
    >>> joint_errors_table(errors, 2).rows[1][1:]
    [4, '1', '2', '2', '2']
    >>> tool_errors_table(errors).rows[0][1:4]
    ['0', '0', '0']
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..learning.learned import ik_errors
from ..learning.model_cache import fit_cached
from ..model.robot import Robot
from ..presentation.tables import Table, shown
from ..presentation.wording import listed, sig, times
from ..solvers import ik
from ..solvers.geometric_ik import in_class
from . import contest
from .ablation import STRUCTURE_LABELS, linear_on_encoding, structure_ablation
from .paired import ik_difference
from .rows import (IK_METRICS, ROLE_BEST_BASELINE, ROLE_CHOSEN, ROLE_EXACT, ROLE_NUMERICAL, ROLE_RECIPE, Row, ik_rows,
                   interval_text)
from .verdict_rows import IK_TARGETS, target_verdict

__all__ = ["FLOOR", "DISS", "FULL", "LM_NAME", "CLOSED_NAME", "LINEAR", "ANFIS", "ANFIS_FCM", "EXACT_JOINT_DEG", "IKTest",
           "evaluate_ik", "joint_errors_table", "tool_errors_table", "timing_table", "ik_summaries", "accuracy_prose", "closed_form_prose", "Credit",
           "encoding_credit", "credit_table", "credit_prose", "Structure", "structure_test", "structure_table",
           "structure_prose"]

#: [deg] and [mm]: a value below this is rounding, shown as such (LM's tolerances, 1e-9 m and
#: 1e-9 rad, and the linear maps' rounding lie below it).
FLOOR = 1e-6
#: The methods' names in the tables (the chosen ANFIS's is ``"ANFIS, chosen (<encoding>)"``).
DISS = "ANFIS, dissertation's recipe (assumed), region data"
FULL = "ANFIS, dissertation's recipe (assumed), full-range data (its own test set)"
LM_NAME = "Levenberg–Marquardt (chapter 2)"
CLOSED_NAME = "closed form (chapter 2), the region's solution"
#: The credit ablation's learners (:func:`encoding_credit`): the linear floor, the ANFIS (on the seven inputs, the
#: dissertation's recipe), and on the seven inputs the ANFIS of fuzzy c-means rules (chapter 6's contestant).
LINEAR, ANFIS = "a linear map of the inputs", "ANFIS"
ANFIS_FCM = "ANFIS, fuzzy c-means rules (contest)"
#: [deg] a linear map's joint RMSE below this gives that joint (:func:`credit_prose`).
EXACT_JOINT_DEG = 0.05


@dataclass(frozen=True)
class IKTest:
    """Every IK method on the test poses (:func:`evaluate_ik`).

    ``methods``: name → ``(q_pred (N, n) [rad], T (N, 4, 4), q_true (N, n) [rad], seconds per
    pose)``, in the tables' order (the chosen ANFIS first); ``errors``: name →
    :func:`~nfarm.learning.learned.ik_errors` of it; ``chosen``: the chosen ANFIS's name;
    ``rbf_kind``: the best rival on validation (a contestant, ``"rbf:arm"`` …), ``rbf`` its name;
    ``rival_of``: each rival's name → its model; ``k (K,)``: the test poses LM solved, ``lm`` its
    result; ``closed_share``: the share of the test poses with a closed-form solution in the
    region (``None`` for an arm outside the closed form's class); ``ranking``: every rival
    (contestant), best first on validation (:func:`nfarm.study.contest.rival_ranking`).
    """

    methods: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray, float]]
    errors: dict[str, dict[str, np.ndarray]]
    chosen: str
    rbf: str
    rbf_kind: str
    rival_of: dict[str, Any]
    k: np.ndarray
    lm: Any
    closed_share: float | None
    ranking: tuple[str, ...] = ()

    def seconds(self, name: str) -> float:
        """Method ``name``'s prediction time per pose in this run [s]."""
        return self.methods[name][3]


def _timed(predict: Callable, T: np.ndarray) -> tuple[np.ndarray, float]:
    start = time.perf_counter()
    q = predict(T)
    return q, (time.perf_counter() - start) / len(T)


def evaluate_ik(robot: Robot, region, learned, recipe: Mapping[str, Any], rivals: Mapping[str, Any],
            data: Mapping[str, Mapping], *, lm_targets: int = 2000, seed: int = 0,
            ranking: Sequence[str] | None = None) -> IKTest:
    """Predict (and time, batched) every IK method on the test poses ``data["ik_test"]``:
    the chosen learned IK ``learned``, the recipe on the region's data (``recipe["ik"]``), every
    rival of the contest (``rivals``, :func:`nfarm.study.contest.saved_rivals`), LM (on the first
    ``lm_targets``, seeded by ``seed``), the closed form's solution in ``region`` (the first valid
    branch where none lies in it; an arm in its class only) and the recipe on its own full-range
    test poses (``recipe["ik_full"]``, ``data["ik_full_test"]``, where the study has them). The
    best rival is chosen as the contest ranks, on the validation poses ``data["ik_val"]``: by
    ``ranking`` (the rivals best first as chapter 6 recorded them, :func:`nfarm.study.contest.saved_ranking`),
    or, given none, by predicting those poses here (:func:`nfarm.study.contest.rival_ranking`).

    Raises:
        ValueError: ``lm_targets`` below 1, or no rival to compare.
    """
    if lm_targets < 1:
        raise ValueError(f"lm_targets is {lm_targets}: LM needs one test target or more")
    if not rivals:
        raise ValueError("no rivals: chapter 7 compares the learned IK with chapter 6's contest rivals")
    test = data["ik_test"]
    methods = {}
    for name, model in ((f"ANFIS, chosen ({learned.encoding})", learned), (DISS, recipe["ik"])):
        q, s = _timed(model.predict, test["T"])
        methods[name] = (q, test["T"], test["q"], s)
    # The contest's rivals, frozen (chapter 6.1)
    rival_of = {f"{contest.label(kind)} (contest)": rival for kind, rival in rivals.items()}
    for name, rival in rival_of.items():
        q, s = _timed(rival.predict, test["T"])
        methods[name] = (q, test["T"], test["q"], s)
    k = np.arange(min(lm_targets, len(test["q"])))
    start = time.perf_counter()
    lm = ik.solve(robot, test["T"][k], seed=seed)
    methods[LM_NAME] = (lm.q, test["T"][k], test["q"][k], (time.perf_counter() - start) / len(k))
    closed_share = None
    if in_class(robot):
        start = time.perf_counter()
        exact = ik.closed_form(robot, test["T"])
        in_region = exact.valid & region.contains(exact.q)
        branch = np.where(in_region.any(axis=1), np.argmax(in_region, axis=1), exact.best())
        q_exact = np.take_along_axis(exact.q, branch[:, None, None], axis=1)[:, 0]
        methods[CLOSED_NAME] = (q_exact, test["T"], test["q"], (time.perf_counter() - start) / len(test["T"]))
        closed_share = float(in_region.any(axis=1).mean())
    if "ik_full" in recipe:
        full = data["ik_full_test"]
        q, s = _timed(recipe["ik_full"].predict, full["T"])
        methods[FULL] = (q, full["T"], full["q"], s)
    errors = {name: ik_errors(robot, q, q_true, T) for name, (q, T, q_true, _) in methods.items()}
    # the best rival as the contest ranks: by the 95th-percentile tool position error on the validation poses
    if ranking is not None and sorted(ranking) != sorted(rivals):
        raise ValueError(f"ranking names {sorted(ranking)}, not the rivals {sorted(rivals)}")
    ranking = tuple(contest.rival_ranking(robot, rivals, data["ik_val"]) if ranking is None else ranking)
    rbf_kind = ranking[0]
    return IKTest(methods, errors, next(iter(errors)), f"{contest.label(rbf_kind)} (contest)", rbf_kind, rival_of, k,
                  lm, closed_share, ranking)


def joint_errors_table(errors: Mapping[str, Mapping], n_joints: int, *, floor: float = FLOOR) -> Table:
    """Per method of ``errors`` (name → :func:`~nfarm.learning.learned.ik_errors`): its test
    poses, each joint's RMSE, the worst joint's MAE and the largest joint error [deg]."""
    rows = []
    for name, e in errors.items():
        j = np.degrees(np.abs(e["joint"]))
        values = [*np.sqrt((j ** 2).mean(axis=0)), j.mean(axis=0).max(), j.max()]
        rows.append([name, len(e["position"]), *(shown(v, ".3g", floor=floor) for v in values)])
    return Table(["method", "test poses", *(f"RMSE q{i + 1} [deg]" for i in range(n_joints)), "worst MAE [deg]",
                  "max [deg]"], rows, caption="Joint errors on the held-out test set")


def tool_errors_table(errors: Mapping[str, Mapping], *, floor: float = FLOOR) -> Table:
    """Per method of ``errors``: the median, 95th percentile and largest tool position [mm] and
    orientation [deg] error of ``fk(predicted q)``."""
    def pct(x, p):
        return float(np.percentile(x, p))

    rows = [[name, *(shown(v, ".3g", floor=floor) for v in (
                pct(e["position"] * 1e3, 50), pct(e["position"] * 1e3, 95), e["position"].max() * 1e3,
                pct(np.degrees(e["orientation"]), 50), pct(np.degrees(e["orientation"]), 95),
                np.degrees(e["orientation"].max())))]
            for name, e in errors.items()]
    return Table(["method", "position median [mm]", "p95 [mm]", "max [mm]", "orientation median [deg]", "p95 [deg]",
                  "max [deg]"], rows, caption="Tool error of fk(predicted q) on the held-out test set")


def timing_table(tested: IKTest) -> Table:
    """Each method's prediction time per pose [µs] and poses per second in this run — not saved
    (it depends on the machine)."""
    return Table(["method", "time per pose [µs]", "poses per second"],
                 [[name, s * 1e6, sig(1 / s)] for name, (_, _, _, s) in tested.methods.items()], floatfmt=["", ".3g", ""],
                 caption="Prediction time of this run, batched (not saved: it depends on the machine; `make bench` "
                         "measures it)")


def ik_summaries(tested: IKTest, *, draws: int = 2000, level: float = 0.95,
                 seed: int = 0) -> tuple[list[tuple[str, str]], dict[str, dict[str, Row]]]:
    """The methods section 7.7 tabulates with their roles (``(name, role)``: the chosen ANFIS,
    the recipe on the region's and on its full-range data, the best rival, the closed form, LM)
    and each one's rows (:func:`nfarm.study.rows.ik_rows`: metric → row, with its bootstrap
    interval over the test poses; LM without the joint RMSE, whose "errors" are other branches)."""
    errors = tested.errors
    ik_methods = [(tested.chosen, ROLE_CHOSEN), (DISS, ROLE_RECIPE)] + \
        ([(FULL, ROLE_RECIPE)] if FULL in errors else []) + \
        [(tested.rbf, ROLE_BEST_BASELINE)] + ([(CLOSED_NAME, ROLE_EXACT)] if CLOSED_NAME in errors else []) + \
        [(LM_NAME, ROLE_NUMERICAL)]
    summary = {name: {r.metric: r for r in ik_rows(name, role, errors[name], joint=name != LM_NAME, draws=draws,
                                                   level=level, seed=seed)}
               for name, role in ik_methods}
    return ik_methods, summary


def accuracy_prose(tested: IKTest, ik_summary: Mapping[str, Mapping[str, Row]], region, *, level: float = 0.95,
                   floor: float = FLOOR) -> str:
    """Section 7.1 in words: the chosen ANFIS's worst joint RMSE, median and 95th-percentile tool
    position error with their intervals (``ik_summary``: :func:`ik_summaries`'s) and the study's
    targets judged on them; the recipe's and the best rival's (and its time against the
    ANFIS's in this run); LM exact at the tool, its time, and its share of solutions outside
    ``region`` (other branches); the full-range recipe's where there is one."""
    chosen_rows, diss_rows, rbf_rows = ik_summary[tested.chosen], ik_summary[DISS], ik_summary[tested.rbf]
    targets = {f"{what} ≤ {limit:g} {unit}": target_verdict(chosen_rows[metric], limit)
               for what, metric, limit, unit in IK_TARGETS}
    t_anfis, t_lm, t_rbf = tested.seconds(tested.chosen), tested.seconds(LM_NAME), tested.seconds(tested.rbf)
    text = (f"The chosen ANFIS reaches a per-joint RMSE of at most **{interval_text(chosen_rows['worst joint RMSE'])}°**, "
            f"a median tool position error of **{interval_text(chosen_rows['position median'])} mm** and a 95th "
            f"percentile of **{interval_text(chosen_rows['position p95'])} mm** ({level:.0%} intervals over the test "
            f"poses) — the study's targets, judged on the intervals: {', '.join(f'{k} {v}' for k, v in targets.items())}. "
            f"The dissertation's recipe (assumed), on the region's data, reaches "
            f"{interval_text(diss_rows['worst joint RMSE'])}° and a median of {interval_text(diss_rows['position median'])} mm. "
            f"The strongest baseline on the validation poses, {tested.rbf}, reaches "
            f"{interval_text(rbf_rows['worst joint RMSE'])}° on its worst joint, a median tool position error of "
            f"{interval_text(rbf_rows['position median'])} mm and a 95th percentile of "
            f"{interval_text(rbf_rows['position p95'])} mm, and takes {times(t_rbf / t_anfis)} the ANFIS's time per "
            f"pose in this run (section 7.7 says, with paired intervals, on which metrics either is better). LM is exact "
            f"at the tool (largest position error "
            f"{shown(tested.errors[LM_NAME]['position'].max() * 1e3, '.1g', floor=floor)} mm) "
            f"and takes {times(t_lm / t_anfis)} the ANFIS's time; its large joint “errors” are other branches: "
            f"{1 - region.contains(tested.lm.q).mean():.0%} of its solutions lie outside the region, reaching the "
            f"same pose with other joint angles.")
    if FULL in ik_summary:
        text += (f" Trained and tested over the full joint ranges, where the inverse map is many-valued "
                 f"(chapter 5), the dissertation's recipe misses by "
                 f"{interval_text(ik_summary[FULL]['worst joint RMSE'])}° RMSE on its worst joint and "
                 f"{interval_text(ik_summary[FULL]['position median'])} mm at the median: it learns an average of "
                 f"branches.")
    return text


def closed_form_prose(tested: IKTest, *, floor: float = FLOOR) -> str | None:
    """The closed form in words: on how many test poses a solution lies in the region, its
    largest joint [deg] and tool [mm] error, and its time against the chosen ANFIS's in this run;
    ``None`` for an arm outside its class."""
    if CLOSED_NAME not in tested.errors:
        return None
    e_cf, t_cf = tested.errors[CLOSED_NAME], tested.seconds(CLOSED_NAME)
    share = tested.closed_share
    return (f"The closed form is exact: on {share:.2%} of the test poses one of its solutions lies in the region"
            + ("" if share == 1 else " (on the others the first valid branch is taken)")
            + f", and its largest joint error is {shown(np.degrees(np.abs(e_cf['joint'])).max(), '.1e', floor=floor)}° "
            f"and its largest tool error {shown(e_cf['position'].max() * 1e3, '.1e', floor=floor)} mm. In this run it "
            f"took {t_cf * 1e6:.2g} µs per pose for all four branches, "
            f"{times(t_cf / tested.seconds(tested.chosen))} the chosen ANFIS's time per pose.")


# --------------------------------------------------------------------------------------------
# What the encoding gives (nfarm.study.ablation.linear_on_encoding)

@dataclass(frozen=True)
class Credit:
    """The credit ablation (:func:`encoding_credit`): ``errors``: ``(encoding, learner)`` → the
    test poses' :func:`~nfarm.learning.learned.ik_errors`; ``rows``: the same keys → metric →
    :class:`~nfarm.study.rows.Row` (bootstrap intervals over the poses); ``recipe_encoding``:
    the recipe's encoding; ``rival``: the best rival's name (``"best rival: <rbf>"`` is its learner
    on its own encoding); ``moved``: the learner of its configuration trained on the other one."""

    errors: dict[tuple[str, str], dict[str, np.ndarray]]
    rows: dict[tuple[str, str], dict[str, Row]]
    recipe_encoding: str
    rival: str
    moved: str


def encoding_credit(robot: Robot, tested: IKTest, learned, recipe: Mapping[str, Any], rivals: Mapping[str, Any],
                    data: Mapping[str, Mapping], cache_dir, *, max_out_of_plane: float = np.radians(0.5),
                    draws: int = 2000, level: float = 0.95, seed: int = 0) -> Credit:
    """Each encoding's simplest learner — a least-squares linear map of its inputs
    (:func:`nfarm.study.ablation.linear_on_encoding`, fitted on ``data["ik_train"]``;
    ``max_out_of_plane`` [rad] as chapter 6's contest's) — beside the ANFIS and the best rival
    that use it, on the test poses; on the seven inputs the recipe's ANFIS and, where chapter 6
    saved it (``recipe["ik_fcm"]``), the ANFIS of fuzzy c-means rules (:data:`ANFIS_FCM`). The best rival's chosen configuration is trained once more on
    the encoding it was not chosen on, as one model of all the joints (seed 0; kept under
    ``cache_dir``, :func:`nfarm.learning.model_cache.fit_cached`). An arm the arm's plane cannot
    describe has one encoding: its rows once."""
    train, test = data["ik_train"], data["ik_test"]
    rbf, best = tested.rbf, rivals[tested.rbf_kind]
    moved_name = (f"best rival's configuration: {contest.label(contest.learner_of(tested.rbf_kind))}, "
                  f"one model of all the joints")
    credit = {}
    for encoding, anfis_name in ((learned.encoding, tested.chosen), (recipe["ik"].encoding, DISS)):
        if (encoding, ANFIS) in credit:
            continue
        floor_model = linear_on_encoding(robot, encoding, train, max_out_of_plane=max_out_of_plane)
        credit[encoding, LINEAR] = ik_errors(robot, floor_model.predict(test["T"]), test["q"], test["T"])
        credit[encoding, ANFIS] = tested.errors[anfis_name]
        if encoding == recipe["ik"].encoding and "ik_fcm" in recipe:
            fcm = recipe["ik_fcm"]
            credit[encoding, ANFIS_FCM] = ik_errors(robot, fcm.predict(test["T"]), test["q"], test["T"])
        if encoding == best.encoding:
            credit[encoding, f"best rival: {rbf}"] = tested.errors[rbf]
        else:       # one model of all the joints: the ANFIS's structure needs the arm's plane
            moved = fit_cached(_one_model(best, encoding), robot, train, data["ik_val"],
                               Path(cache_dir) / f"{tested.rbf_kind.replace(':', '_')}_{encoding}")[0]
            credit[encoding, moved_name] = ik_errors(robot, moved.predict(test["T"]), test["q"], test["T"])
    rows = {key: {r.metric: r for r in ik_rows(" ".join(key), "", e, draws=draws, level=level, seed=seed)}
            for key, e in credit.items()}
    return Credit(credit, rows, recipe["ik"].encoding, rbf, moved_name)


def _interval_table(first: list[str], rows: Mapping[tuple[str, str], Mapping[str, Row]], keys, metrics, caption: str,
                    labels: Callable[[tuple[str, str]], list[str]], floor: float) -> Table:
    return Table([*first, *(f"{m} [{dict(IK_METRICS)[m]}]" for m in metrics)],
                 [[*labels(key), *(interval_text(rows[key][m], {"mm": floor, "deg": floor}) for m in metrics)]
                  for key in keys], caption=caption)


def _one_model(rival, encoding: str):
    """An unfitted copy of ``rival``'s configuration (its class and hyper-parameters, its
    ``max_out_of_plane`` and seed) as one model of all the joints on ``encoding``."""
    return type(rival)(**{k: rival.get_params()[k] for k in rival.hyper_params()}, encoding=encoding,
                       max_out_of_plane=rival.max_out_of_plane, random_state=rival.random_state)


def credit_table(credit: Credit, *, level: float = 0.95, floor: float = FLOOR) -> Table:
    """Per encoding and learner: the worst joint RMSE [deg], median and 95th-percentile tool
    position error [mm] and median orientation error [deg], each with its interval."""
    return _interval_table(
        ["encoding", "learner"], credit.rows, credit.errors,
        ("worst joint RMSE", "position median", "position p95", "orientation median"),
        f"What each encoding gives to a linear map of its inputs, and what the ANFIS and the best rival add, on the "
        f"held-out test poses ({level:.0%} bootstrap intervals over the poses; models of the study's own data)",
        list, floor)


def credit_prose(credit: Credit, joint_names, *, floor: float = FLOOR, exact_joint: float = EXACT_JOINT_DEG) -> str | None:
    """The credit ablation in words: in the arm's plane, how close a linear map alone places the
    tool at the median, the joints it already gives (joint RMSE below ``exact_joint`` [deg]),
    how much closer the ANFIS brings it; the same on the recipe's seven inputs (the recipe's and the
    fuzzy c-means ANFIS's, with the 95th percentiles the study's targets read) and for the best
    rival. ``None`` without an ANFIS in the arm's plane."""
    rows, recipe_enc, rbf = credit.rows, credit.recipe_encoding, credit.rival
    plane_floor = rows.get(("arm_plane", LINEAR))
    if plane_floor is None or ("arm_plane", ANFIS) not in rows:
        return None
    names = list(joint_names)
    plane_anfis = rows["arm_plane", ANFIS]
    floor_joint = np.degrees(np.sqrt((credit.errors["arm_plane", LINEAR]["joint"] ** 2).mean(axis=0)))
    exact_joints = [names[j] for j in range(len(names)) if floor_joint[j] < exact_joint]
    ratio = plane_floor["position median"].value / plane_anfis["position median"].value
    return (f"In the arm's plane a linear map alone places the tool {interval_text(plane_floor['position median'])} mm "
            f"from the target at the median"
            + (f" and already gives {listed(exact_joints)} to within "
               f"{shown(floor_joint[[names.index(n) for n in exact_joints]].max(), '.2g', floor=floor)}°"
               if exact_joints else "")
            + f"; the ANFIS brings the median to {interval_text(plane_anfis['position median'])} mm, "
            f"{times(ratio)} closer: the encoding gives "
            + ("those joints" if exact_joints else "little")
            + ", the learner the rest (the pitch joints, whose map is not linear)."
            + (f" On the dissertation's seven inputs a linear map lands "
               f"{interval_text(rows[recipe_enc, LINEAR]['position median'])} mm away at the median, the ANFIS "
               f"{interval_text(rows[recipe_enc, ANFIS]['position median'])} mm."
               if (recipe_enc, ANFIS) in rows and recipe_enc != "arm_plane" else "")
            + (f" Given fuzzy c-means rules on those inputs (chapter 6's contestant), the ANFIS lands "
               f"{interval_text(rows[recipe_enc, ANFIS_FCM]['position median'])} mm away at the median and "
               f"{interval_text(rows[recipe_enc, ANFIS_FCM]['position p95'])} mm at the 95th percentile, against the "
               f"recipe's {interval_text(rows[recipe_enc, ANFIS]['position p95'])} mm"
               + (f" and the best rival's configuration's {interval_text(rows[recipe_enc, credit.moved]['position p95'])} mm"
                  if (recipe_enc, credit.moved) in rows else "") + "."
               if (recipe_enc, ANFIS_FCM) in rows and recipe_enc != "arm_plane" else "")
            + (f" The best rival, {rbf}, lands {interval_text(rows['arm_plane', f'best rival: {rbf}']['position median'])} "
               f"mm away at the median in the arm's plane, and its configuration as one model of all the joints "
               f"{interval_text(rows[recipe_enc, credit.moved]['position median'])} mm on the seven inputs."
               if (recipe_enc, credit.moved) in rows and ("arm_plane", f"best rival: {rbf}") in rows
               and recipe_enc != "arm_plane" else ""))


# --------------------------------------------------------------------------------------------
# What the structure gives (nfarm.study.ablation.structure_ablation)

@dataclass(frozen=True)
class Structure:
    """The structure ablation (:func:`structure_test`): ``errors``: ``(learner, structure)`` →
    the test poses' errors (structure a key of :data:`nfarm.study.ablation.STRUCTURE_LABELS`),
    ``rows`` their metrics with intervals, ``same_pair``: the best rival inside the ANFIS's
    structure on validation, ``(learner, "arm")`` (``None`` without one or without an ANFIS in
    it)."""

    errors: dict[tuple[str, str], dict[str, np.ndarray]]
    rows: dict[tuple[str, str], dict[str, Row]]
    same_pair: tuple[str, str] | None


def structure_test(robot: Robot, learned, rivals: Mapping[str, Any], data: Mapping[str, Mapping], *,
                   tested: IKTest | None = None, draws: int = 2000, level: float = 0.95, seed: int = 0) -> Structure:
    """Every learner's frozen chosen model in each structure the contest trained it in, and
    without the pitch closure (:func:`nfarm.study.ablation.structure_ablation`), on the test
    poses ``data["ik_test"]``; the best rival inside the ANFIS's structure ranked on
    ``data["ik_val"]``. ``tested`` (:func:`evaluate_ik` of the same models and data): its test
    errors and validation ranking are reused, not computed again (a model of 512-neighbour RBF
    interpolation takes about 30 s for 10 000 poses); only the models without their closure are
    predicted here."""
    test = data["ik_test"]
    models = structure_ablation(learned, rivals)
    known = {} if tested is None else {id(model): tested.errors[name] for name, model in
                                       [(tested.chosen, learned), *tested.rival_of.items()]}
    errors = {key: known[id(model)] if id(model) in known else ik_errors(robot, model.predict(test["T"]), test["q"], test["T"])
              for key, model in models.items()}
    rows = {key: {r.metric: r for r in ik_rows(" ".join(key), "", e, draws=draws, level=level, seed=seed)}
            for key, e in errors.items()}
    in_structure = {kind: r for kind, r in rivals.items() if contest.structure_of(kind) == "arm"}
    same_pair = None
    if ("ANFIS", "arm") in errors and in_structure:
        same_kind = next(kind for kind in tested.ranking if kind in in_structure) if tested is not None else \
            contest.rival_ranking(robot, in_structure, data["ik_val"])[0]     # the contest's order, restricted
        same_pair = (contest.label(contest.learner_of(same_kind)), "arm")
    return Structure(errors, rows, same_pair)


def structure_table(structure: Structure, *, level: float = 0.95, floor: float = FLOOR) -> Table | None:
    """Per learner and structure: the worst joint RMSE [deg], median and 95th-percentile tool
    position error [mm] and 95th-percentile orientation error [deg] with their intervals;
    ``None`` when no model has a structure to compare."""
    if not structure.errors:
        return None
    return _interval_table(
        ["learner", "structure"], structure.rows, structure.errors,
        ("worst joint RMSE", "position median", "position p95", "orientation p95"),
        f"Each learner's chosen model in every structure the contest trained it in, and without the pitch closure, on "
        f"the held-out test poses ({level:.0%} bootstrap intervals over the poses; the models of the study's own data, "
        f"frozen)", lambda key: [key[0], STRUCTURE_LABELS[key[1]]], floor)


def structure_prose(structure: Structure, *, floor: float = FLOOR, draws: int = 2000, level: float = 0.95,
                    seed: int = 0) -> str | None:
    """The structure ablation in words: in the ANFIS's structure, its 95th-percentile tool
    position error and the best rival's there, the gap paired on the test poses (its interval
    from ``draws`` resamples), the same learner as one model of all the joints, and the ANFIS
    without its closure. ``None`` when there is no model to speak of."""
    errors, rows, same_pair = structure.errors, structure.rows, structure.same_pair
    if same_pair is None:
        return ("No rival inside the ANFIS's structure is among this arm's models (chapter 6 trains them where the "
                "arm's plane describes the arm): the table holds each learner as it was trained." if errors else None)
    mm3 = lambda v: shown(v, ".3g", floor=floor)   # noqa: E731

    def p95_gap(a, b):
        """a's 95th-percentile tool position error less b's, with its paired interval, in words."""
        d = ik_difference(errors[a], errors[b], draws=draws, level=level, seed=seed)
        k = [m for m, _ in IK_METRICS].index("position p95")
        low, high = float(d.low[k]), float(d.high[k])
        return f"{mm3(d.value[k])} mm ({mm3(low)} to {mm3(high)})" + (", no difference shown" if low <= 0 <= high else "")

    text = (f"**The learner's share.** In the same structure the ANFIS's 95th-percentile tool position error is "
            f"{interval_text(rows['ANFIS', 'arm']['position p95'])} mm, and that of the best rival in it on "
            f"validation, {same_pair[0]}, {interval_text(rows[same_pair]['position p95'])} mm: the ANFIS less the "
            f"rival, paired on the test poses, {p95_gap(('ANFIS', 'arm'), same_pair)}. ")
    if (same_pair[0], "whole") in errors:
        text += (f"The same learner as one model of all the joints reaches "
                 f"{interval_text(rows[same_pair[0], 'whole']['position p95'])} mm (in the structure less as one "
                 f"model: {p95_gap(same_pair, (same_pair[0], 'whole'))}). ")
    text += (f"Without its closure the ANFIS's 95th percentile is "
             f"{interval_text(rows['ANFIS', 'arm_open']['position p95'])} mm and its orientation error's "
             f"{interval_text(rows['ANFIS', 'arm_open']['orientation p95'], {'deg': floor})}° (with the closure "
             f"{interval_text(rows['ANFIS', 'arm']['orientation p95'], {'deg': floor})}°): in the arm's structure the "
             f"orientation is the closure's and the linear rules', the same for every learner, so no orientation "
             f"comparison credits a learner there.")
    return text
