"""Chapter 7.2–7.4: where in the region the chosen learned IK's errors are large and how that
follows from where the arm's solutions meet; the learned IK as Levenberg–Marquardt's starting
guess; and both following a Cartesian path.

Every function reads the chosen model's test-pose errors ``e`` as
:func:`nfarm.learning.learned.ik_errors` gives them (``joint (N, n)`` [rad], ``position (N,)``
[m], ``orientation (N,)`` [rad]) and shows millimetres and degrees. A cause's effect is the ratio
of the median error of the tenth of the test poses nearest to it over that of the tenth farthest,
with its bootstrap interval over the poses (:func:`nfarm.study.statistics.tail_ratios`).

Example:
    >>> from types import SimpleNamespace
    >>> ratios = SimpleNamespace(names=["edge"], value=np.array([1.7]), low=np.array([1.6]), high=np.array([1.8]))
    >>> ratio_said(ratios, "edge")
    '1.7 times that of the tenth farthest (ratio 1.6–1.8)'
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from ..infra.paths import shown_path
from ..learning.learned import ik_errors
from ..model.kinematics import fk, min_singular_value
from ..model.robot import Robot
from ..presentation.plotting import plot_error_against, plot_error_map, plot_predicted_vs_true
from ..presentation.tables import Table, shown
from ..presentation.wording import times
from ..solvers import ik
from ..solvers.geometric_ik import branch_margins, in_class
from ..solvers.tool_paths import plane_held_poses
from .ik_test_report import CLOSED_NAME, FLOOR
from .statistics import Estimate, TailRatios, tail_ratios
from .warm_start import iterations_words

__all__ = ["EDGE", "SING", "DEFAULT_START", "ANFIS_START", "CLOSED_START", "ratio_said", "predicted_vs_true_figure",
           "error_map_figure", "Places", "error_places", "causes_figure", "near_ratios", "causes_prose",
           "branches_figure", "worst_poses", "worst_table", "branches_prose", "lm_starts", "warm_start_prose", "IKPath",
           "follow_path", "path_table", "path_prose"]

#: The two candidate causes of section 7.2 (:func:`near_ratios`).
EDGE, SING = "the box's edge", "a singularity"
#: The starts of section 7.3 that :func:`warm_start_prose` names.
DEFAULT_START, ANFIS_START, CLOSED_START = ("default (nearest of a random table)", "ANFIS prediction",
                                            "closed form (the region's solution)")
#: The panels of the branch figure: label → (the place in words, its unit in the sentences).
_EDGE_X = "distance to the box edge [deg]"
_PLACES = {"elbow from stretched or folded [deg]": ("the stretched or folded elbow", "°"),
           "wrist point from the base axis [mm]": ("the base axis (wrist point)", " mm"),
           "nearest other solution [deg] (poses that have one)": ("another solution (of the poses that have one)", "°"),
           _EDGE_X: ("the box's edge", "°")}
_ERROR_LABEL = "tool position error [mm]"
_COUNTS = dict(enumerate(("no", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten")))


def ratio_said(ratios: TailRatios, name: str, farthest: str = "the tenth farthest") -> str:
    """One cause's ratio in words, ``"1.7 times that of the tenth farthest (ratio 1.6–1.8)"``:
    the words from the value, then its interval."""
    k = ratios.names.index(name)
    return f"{times(ratios.value[k])} that of {farthest} (ratio {ratios.low[k]:.2g}–{ratios.high[k]:.2g})"


def predicted_vs_true_figure(q_true: np.ndarray, q_pred: np.ndarray, joint_names, *,
                             exact: float = 1e-6) -> tuple[Figure, str]:
    """The chosen ANFIS's predicted against true joint angles ``(N, n)`` [rad] on the test set,
    and the error against the true angle (a joint within ``exact`` [deg]: the linear maps'
    floating-point rounding, shown as exact); the figure and its caption."""
    return (plot_predicted_vs_true(q_true, q_pred, joint_names, exact=exact),
            "Chosen ANFIS on the test set: predicted against true joint angle (top) and the error against the true "
            "angle (bottom)")


def error_map_figure(robot_name: str, T: np.ndarray, e: Mapping[str, np.ndarray]) -> tuple[Figure, str]:
    """The tool position error [mm] of the test poses ``T (N, 4, 4)`` over the region, side view
    (the median of the poses in each cell); the figure and its caption."""
    p = T[:, :3, 3]
    fig = plot_error_map(p, e["position"] * 1e3, label=_ERROR_LABEL,
                         title=f"{robot_name}: chosen ANFIS on {len(p):,} test poses")
    return fig, ("Tool position error of the chosen ANFIS over the region, side view: the median of the test poses in "
                 "each cell (cells of fewer than three poses blank)")


@dataclass(frozen=True)
class Places:
    """How near each test pose lies to the places where a learned IK may err
    (:func:`error_places`): ``edge (N,)`` [deg], the least distance of a joint to its bound in the
    region's box; ``sigma (N,)`` [m], the least singular value of the position Jacobian; and, for an
    arm in the closed form's class, ``near``: panel label → ``(N,)`` distances to where two of
    its solutions meet (the elbow [deg], the wrist point from the base axis [mm], the nearest other
    solution within the joint limits [deg], NaN for a pose that has none), ``None`` otherwise."""

    edge: np.ndarray
    sigma: np.ndarray
    near: dict[str, np.ndarray] | None

    @property
    def other_share(self) -> float:
        """The share of the test poses with another solution within the joint limits."""
        return float(np.isfinite(self.near["nearest other solution [deg] (poses that have one)"]).mean())


def error_places(robot: Robot, region, q: np.ndarray) -> Places:
    """:class:`Places` of the test configurations ``q (N, n)`` [rad] in ``region``."""
    edge = np.degrees(np.minimum(q - region.box[:, 0], region.box[:, 1] - q).min(axis=1))
    sigma = min_singular_value(robot, q, "position")
    near = None
    if in_class(robot):
        margins = branch_margins(robot, q)
        near = {"elbow from stretched or folded [deg]": np.degrees(margins["elbow"]),
                "wrist point from the base axis [mm]": margins["wrist"] * 1e3,
                "nearest other solution [deg] (poses that have one)":
                    np.degrees(np.where(np.isfinite(margins["other"]), margins["other"], np.nan))}
    return Places(edge, sigma, near)


def causes_figure(places: Places, e: Mapping[str, np.ndarray]) -> tuple[Figure, str]:
    """The tool position error [mm] against the distance to the region's edge and to
    singularities; the figure and its caption."""
    fig = plot_error_against({"distance to the region's box edge [deg]": places.edge,
                              "σmin of the position Jacobian [m]": places.sigma}, e["position"] * 1e3,
                             label=_ERROR_LABEL)
    return fig, ("Tool position error against the distance to the region's edge and to singularities (medians and "
                 "95th percentiles in equal-count bins)")


def near_ratios(places: Places, e: Mapping[str, np.ndarray], *, draws: int = 2000, level: float = 0.95,
                seed: int = 0) -> TailRatios:
    """The tail ratios of :data:`EDGE` and :data:`SING` (the same resamples for both)."""
    return tail_ratios({EDGE: places.edge, SING: places.sigma}, e["position"], draws=draws, level=level, seed=seed)


def causes_prose(ratios: TailRatios, *, level: float = 0.95, strong: float = 1.5) -> str:
    """The two causes' ratios (:func:`near_ratios`) in words, and which matters more: neither
    (both intervals below ``strong``), the one whose ratio over the other's lies above 1, or both
    about as much."""
    return (f"The tenth of test poses closest to the box's edge has a median error "
            f"{ratio_said(ratios, EDGE, 'the tenth farthest from it')}; the tenth closest to a singularity, "
            f"{ratio_said(ratios, SING)} ({level:.0%} intervals over the test poses). "
            + (f"Neither is a strong cause (both intervals below {strong:g}): the errors are spread over the region, "
               f"as the map shows." if ratios.high.max() < strong else
               "The edge matters more (the interval of the ratio of the two ratios lies above 1): there a rule's "
               "linear consequent is extrapolated from one side." if ratios.larger(EDGE, SING) else
               "Closeness to a singularity matters more (the interval of the ratio of the two ratios lies above 1): "
               "there small pose changes need large joint changes, which the smooth rule base flattens."
               if ratios.larger(SING, EDGE) else
               "Both matter about as much: the interval of the ratio of the two ratios holds 1."))


def _near(places: Places) -> dict[str, np.ndarray]:
    if places.near is None:
        raise ValueError("no branch margins: the arm is outside the closed form's class (places.near is None)")
    return places.near


def branches_figure(places: Places, e: Mapping[str, np.ndarray]) -> tuple[Figure, str]:
    """The tool position error [mm] against the distance to where two of the arm's solutions
    meet (``places.near``: an arm in the closed form's class, else ValueError); the figure and
    its caption."""
    fig = plot_error_against(_near(places), e["position"] * 1e3, label=_ERROR_LABEL)
    return fig, ("Chosen ANFIS: tool position error against the distance to where two of the arm's solutions meet "
                 "(medians and 95th percentiles in equal-count bins)")


def worst_poses(e: Mapping[str, np.ndarray], count: int = 8) -> np.ndarray:
    """The indices ``(count,)`` of the test poses with the largest tool position error, largest first."""
    return np.argsort(e["position"])[::-1][:count]


def worst_table(places: Places, e: Mapping[str, np.ndarray], *, count: int = 8) -> Table:
    """The ``count`` worst test poses: their tool [mm] and largest joint error [deg], and how near
    each lies to where solutions meet and to the region's edge (``"none"``: no other solution);
    ValueError for an arm outside the closed form's class, or ``count`` below 1."""
    near = _near(places)
    if count < 1:
        raise ValueError(f"count is {count}: a table of the worst poses needs one or more")
    rows = [[f"{e['position'][i] * 1e3:.3g}", f"{np.degrees(np.abs(e['joint'][i])).max():.3g}",
             *("none" if np.isnan(v[i]) else f"{v[i]:.3g}" for v in near.values()), f"{places.edge[i]:.3g}"]
            for i in worst_poses(e, count)]
    return Table(["tool position error [mm]", "largest joint error [deg]", *near, _EDGE_X], rows,
                 caption=f"The chosen ANFIS's {_COUNTS.get(count, count)} worst test poses, and how near each lies "
                         f"to where solutions meet and to the region's edge")


def branches_prose(places: Places, e: Mapping[str, np.ndarray], *, count: int = 8, draws: int = 2000,
                   level: float = 0.95, seed: int = 0, strong: float = 1.5) -> str:
    """Where the arm's solutions meet, in words: how many of the ``count`` worst test poses lie
    closer to each place than 95 % of the test poses, and over the whole test set each place's
    tail ratio (a resample may hold no pose with another solution: its ratio is NaN, left out of
    the interval) and which raises the error most — none by half or more (every interval below
    ``strong``), one above each other's, or several about as much. ValueError for an arm outside
    the closed form's class."""
    near_x = {**_near(places), _EDGE_X: places.edge}
    worst = worst_poses(e, count)
    nearest_5 = {name: np.nanquantile(v, 0.05) for name, v in near_x.items()}
    is_near = {name: v[worst] <= nearest_5[name] for name, v in near_x.items()}
    near_none = ~np.any(list(is_near.values()), axis=0)
    place_ratios = tail_ratios(near_x, e["position"], draws=draws, level=level, seed=seed)
    ratios = dict(zip(place_ratios.names, place_ratios.value))
    strongest = max(ratios, key=ratios.get)
    return (f"Of the {len(worst)} test poses with the largest tool error (up to "
            f"{e['position'][worst[0]] * 1e3:.3g} mm), this many lie closer than 95 % of the test poses "
            f"to each place: "
            + "; ".join(f"{_PLACES[name][0]} ({nearest_5[name]:.2g}{_PLACES[name][1]} or less): {int(c.sum())}"
                        for name, c in is_near.items())
            + f"; none of them: {int(near_none.sum())}. Over the whole test set ({places.other_share:.0%} "
            f"of its poses have another solution within the joint limits), the tenth of poses nearest to "
            + "; ".join(f"{_PLACES[name][0]} has a median error {ratio_said(place_ratios, name)}" for name in near_x)
            + f" ({level:.0%} intervals)"
            + (f". None of them raises the median error by half or more (every interval below {strong:g})."
               if place_ratios.high.max() < strong
               else f". The error rises most with closeness to {_PLACES[strongest][0]} (the interval of its ratio over "
                    f"each other's lies above 1)."
               if all(place_ratios.larger(strongest, name) for name in ratios if name != strongest)
               else ". Closeness to " + " and to ".join(_PLACES[name][0] for name in ratios
                                                        if name == strongest or not place_ratios.larger(strongest, name))
               + " raise it about as much (the intervals of the ratios of their ratios hold 1)."))


# --------------------------------------------------------------------------------------------
# 7.3: the learned IK as LM's starting guess (nfarm.study.warm_start)

def lm_starts(robot: Robot, T: np.ndarray, learned, rival, rival_name: str, chosen: str,
              q_closed: np.ndarray | None = None) -> tuple[dict[str, Any], dict[str, str]]:
    """LM's starts on the targets ``T (K, 4, 4)`` (as :func:`nfarm.study.warm_start.warm_starts`
    takes them): LM's default, the dissertation's home pose, the chosen ANFIS's (``learned``)
    and the best rival's (``rival``, named ``rival_name``) predictions — clipped to the joint
    limits, which a prediction may leave near the region's edge — and the closed form's solution
    in the region (``q_closed (K, n)`` [rad], for an arm in its class); and whose prediction
    time each start adds (start → method name: ``chosen``, ``rival_name``, the closed form's)."""
    lo, hi = robot.qlim[:, 0], robot.qlim[:, 1]
    starts = {DEFAULT_START: None, "home (the dissertation's)": "home",
              ANFIS_START: np.clip(learned.predict(T), lo, hi),
              f"{rival_name} prediction": np.clip(rival.predict(T), lo, hi)}
    predicted_by = {ANFIS_START: chosen, f"{rival_name} prediction": rival_name}
    if q_closed is not None:
        starts[CLOSED_START] = q_closed
        predicted_by[CLOSED_START] = CLOSED_NAME
    return starts, predicted_by


def warm_start_prose(warm: Mapping[str, tuple], region, other: str, ratio: Estimate,
                     prediction_s: Mapping[str, float], *, level: float = 0.95) -> str:
    """Section 7.3 in words: the ANFIS start's iterations against the best other start LM must
    iterate from (``other`` and the ratio of their means, :func:`nfarm.study.warm_start.fewer_iterations`)
    and the default's, its success and share of solutions in ``region`` against the default's,
    and this run's times — LM's per target and the ANFIS's prediction (``prediction_s``: start →
    its prediction's seconds per target) — and the fastest start by total time."""
    d, a, o = warm[DEFAULT_START], warm[ANFIS_START], warm[other]
    compared, _ = iterations_words(ratio, level)
    total = {name: w[1] + prediction_s.get(name, 0.0) for name, w in warm.items()}
    return (f"Started from the ANFIS prediction, LM needs {compared} from "
            f"the best of the other starts it must iterate from in this region, {other.split(' (')[0]} "
            f"({a[0].iterations.mean():.2f} against {o[0].iterations.mean():.2f}; the library's default start: "
            f"{d[0].iterations.mean():.2f}"
            + ("; from the closed form's solution, none: it is exact" if CLOSED_START in warm else "") + "), succeeds on "
            f"{a[0].success.mean():.2%} of the targets (default {d[0].success.mean():.2%}), and its solution lies "
            f"in the region — on the branch the data describe — for {region.contains(a[0].q).mean():.2%} of them "
            f"(default {region.contains(d[0].q).mean():.2%}). In this run the solve took "
            f"{a[1] * 1e6:.0f} µs per target from the ANFIS start (plus {prediction_s[ANFIS_START] * 1e6:.0f} µs for "
            f"the prediction) against {d[1] * 1e6:.0f} µs from the default start."
            f" By total time in this run the fastest start is **{min(total, key=total.get)}**.")


# --------------------------------------------------------------------------------------------
# 7.4: a Cartesian path

@dataclass(frozen=True)
class IKPath:
    """A line then a circle followed by the ANFIS and by LM (:func:`follow_path`): the targets
    ``T_0e (P, 4, 4)`` at times ``t (P,)`` [s]; ``moved (P,)``: the targets this arm cannot
    hold, replaced by the nearest pose it reaches, ``near_pos``/``near_rot (P,)`` [m]/[rad] how far
    that is; the ANFIS's joint angles ``q_anfis (P, n)`` [rad], LM's result ``lm``
    (:func:`nfarm.solvers.ik.solve_path`) and each one's ``errors`` (the ANFIS's against LM's
    joint angles)."""

    T_0e: np.ndarray
    t: np.ndarray
    moved: np.ndarray
    near_pos: np.ndarray
    near_rot: np.ndarray
    q_anfis: np.ndarray
    lm: Any
    errors: dict[str, dict[str, np.ndarray]]


def follow_path(robot: Robot, region, learned, *, line_start, radius: float, steps: int, seconds: float,
                seed: int = 0, reached: float = 1e-9) -> IKPath:
    """About the tool pose of ``region``'s centre configuration: a straight line from
    ``line_start (3,)`` [m, relative to it] to the circle's start, then a horizontal circle of
    ``radius`` [m], ``steps`` poses in all over ``seconds``, the tool's orientation relative to the
    arm's plane held (:func:`nfarm.solvers.tool_paths.plane_held_poses`). A pose the arm cannot
    reach (residual above ``reached`` [m], [rad]) is replaced by the nearest it reaches (the closed
    form's refinement; LM's least-squares pose for an arm outside its class). The ANFIS predicts
    each pose on its own; LM follows the path from its previous solution, starting from the
    ANFIS's first prediction (clipped to the joint limits). ValueError for fewer than 2 ``steps``."""
    if steps < 2:
        raise ValueError(f"steps is {steps}: a line and a circle need 2 poses or more")
    q_centre = region.box.mean(axis=1)
    centre = fk(robot, q_centre)[:3, 3]
    half = steps // 2
    start, corner = centre + np.array(line_start), centre + np.array([radius, 0.0, 0.0])
    line = start + np.linspace(0, 1, half, endpoint=False)[:, None] * (corner - start)
    angle = np.linspace(0, 2 * np.pi, steps - half)
    circle = centre + radius * np.column_stack([np.cos(angle), np.sin(angle), np.zeros_like(angle)])
    T_path = plane_held_poses(robot, q_centre, np.vstack([line, circle]))
    if in_class(robot):
        q_near, near_pos, near_rot = ik.closed_form(robot, T_path).nearest()
    else:
        result = ik.solve(robot, T_path, seed=seed)
        q_near, near_pos, near_rot = result.q, result.pos_error, result.rot_error
    moved = (near_pos > reached) | (near_rot > reached)
    T_path = np.where(moved[:, None, None], fk(robot, q_near), T_path)
    q_anfis = learned.predict(T_path)
    q_lm = ik.solve_path(robot, T_path, np.clip(q_anfis[0], robot.qlim[:, 0], robot.qlim[:, 1]), seed=seed)
    errors = {"ANFIS": ik_errors(robot, q_anfis, q_lm.q, T_path), "LM": ik_errors(robot, q_lm.q, q_lm.q, T_path)}
    return IKPath(T_path, np.linspace(0, seconds, len(T_path)), moved, near_pos, near_rot, q_anfis, q_lm, errors)


def path_table(path: IKPath, region, *, floor: float = FLOOR) -> Table:
    """Per IK along the path: the poses, the share of its solutions in ``region``, the largest and
    median tool position error [mm] and the largest orientation error [deg]."""
    return Table(["IK", "poses", "in the region", "position max [mm]", "position median [mm]", "orientation max [deg]"],
                 [[name, len(path.T_0e), f"{region.contains(q).mean():.0%}", *(shown(v, ".3g", floor=floor) for v in (
                     e["position"].max() * 1e3, np.median(e["position"]) * 1e3, np.degrees(e["orientation"].max())))]
                  for (name, e), q in zip(path.errors.items(), (path.q_anfis, path.lm.q))],
                 caption="Tool errors along the line and circle")


def path_prose(path: IKPath, region, recording) -> str:
    """The path in words: the poses moved to the nearest the arm reaches, how many LM solves and
    how many of its solutions lie in ``region``, how far the ANFIS stays from the targets [mm],
    [deg] and from LM's joint angles [deg], and where the rerun ``recording`` is."""
    anfis_e, gap = path.errors["ANFIS"], np.degrees(np.abs(path.q_anfis - path.lm.q)).max()
    moved, n = path.moved, len(path.T_0e)
    return ((f"{int(moved.sum())} of the {n} poses cannot be held exactly by this arm and were moved to the "
             f"nearest pose it reaches, at most {path.near_pos[moved].max() * 1e3:.2g} mm and "
             f"{np.degrees(path.near_rot[moved].max()):.2g}° away. " if moved.any() else "")
            + f"LM solves {int(path.lm.success.sum())} of the {n} poses of the path within its tolerances, "
            f"{region.contains(path.lm.q).mean():.0%} of its solutions in the region. ANFIS, pose by pose and without "
            f"any memory of the path, stays within {anfis_e['position'].max() * 1e3:.2g} mm and "
            f"{shown(np.degrees(anfis_e['orientation'].max()), '.2g', floor=1e-5)}° of the targets and within "
            f"{gap:.2g}° of LM's joint angles. Recording: `{shown_path(recording)}`.")
