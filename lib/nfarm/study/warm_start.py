"""Chapter 7.3: a learned IK as the starting guess of Levenberg–Marquardt.

The learned IK is not exact, but it is close: LM started from its prediction only has to polish.
:func:`warm_starts` solves the same targets from each start (LM's default — the nearest of a random
table — the home pose, the ANFIS's prediction, the best rival's, the closed form's solution);
:func:`warm_start_table` says how often each succeeds, lands in the region and how many
iterations it needs; :func:`fewer_iterations` compares the ANFIS start with the best other start
LM must still iterate from, on the ratio of their mean iterations paired over the targets.

Example (intelbot5, 20 targets of its region, started from LM's default and from the truth):

    >>> from nfarm.infra.paths import PARAMS
    >>> from nfarm.study.study_files import load_study
    >>> study = load_study(PARAMS / "studies" / "intelbot5.yaml")
    >>> q = study.ik_region.sample(20, np.random.default_rng(0))
    >>> from nfarm.model.kinematics import fk
    >>> warm = warm_starts(study.robot, fk(study.robot, q), {"default": None, "truth": q})
    >>> float(warm["truth"][0].iterations.mean()) <= float(warm["default"][0].iterations.mean())
    True
"""

from __future__ import annotations

import time
from collections.abc import Mapping

import numpy as np

from ..presentation.tables import Table
from ..solvers import ik
from .statistics import Estimate, bootstrap_rows

__all__ = ["warm_starts", "warm_start_table", "warm_start_timing", "fewer_iterations", "iterations_words"]


def warm_starts(robot, T: np.ndarray, starts: Mapping[str, object], *, seed: int = 0) -> dict[str, tuple[object, float]]:
    """LM (:func:`nfarm.solvers.ik.solve`) on the targets ``T (N, 4, 4)`` from each start
    (``starts``: name → ``q0``, as :func:`~nfarm.solvers.ik.solve` takes it: ``None`` for its
    default, ``"home"``, or ``(N, n)`` joint angles [rad]); name → ``(result, seconds per
    target)``."""
    warm = {}
    for name, q0 in starts.items():
        start = time.perf_counter()
        result = ik.solve(robot, T, q0=q0, seed=seed)
        warm[name] = (result, (time.perf_counter() - start) / len(T))
    return warm


def warm_start_table(warm: Mapping[str, tuple], region) -> Table:
    """Per start: the targets, LM's success rate, the share of solutions in ``region`` (on the
    branch the data describe), the mean and largest iterations and the share restarted."""
    rows = []
    for name, (result, _) in warm.items():
        rows.append([name, len(result.q), f"{result.success.mean():.2%}", f"{region.contains(result.q).mean():.2%}",
                     float(result.iterations.mean()), int(result.iterations.max()), float((result.restarts > 0).mean())])
    return Table(["start", "targets", "success", "solution in the region", "mean iterations", "max iterations",
                  "share restarted"], rows, floatfmt=["", "", "", "", ".2f", "", ".3f"],
                 caption="LM from each start on the test targets")


def warm_start_timing(warm: Mapping[str, tuple], prediction_s: Mapping[str, float]) -> Table:
    """Per start, the seconds to a converged solution in this run: LM's, the start's prediction
    (``prediction_s``: start → seconds per target of the model that made it; none for the others)
    and their total, in µs per target — not saved (it depends on the machine)."""
    rows = []
    for name, (_, seconds) in warm.items():
        predicted = prediction_s.get(name, 0.0)
        rows.append([name, seconds * 1e6, predicted * 1e6, (seconds + predicted) * 1e6])
    return Table(["start", "LM per target [µs]", "the start's prediction per target [µs]", "total per target [µs]"],
                 rows, floatfmt=["", ".0f", ".1f", ".0f"],
                 caption="Time to a converged solution from each start in this run (not saved: it depends on the machine)")


def fewer_iterations(warm: Mapping[str, tuple], start: str, exclude=(), *, draws: int = 2000, level: float = 0.95,
                     seed: int = 0) -> tuple[str, Estimate]:
    """The best other start LM iterates from (the least mean iterations, ``start`` and ``exclude``
    left out: a closed form's exact solution leaves LM nothing to do) and the ratio of ``start``'s
    mean iterations to its, with its bootstrap interval paired over the same targets."""
    other = min((name for name in warm if name != start and name not in exclude),
                key=lambda name: warm[name][0].iterations.mean())
    ratio = bootstrap_rows(np.column_stack([warm[start][0].iterations, warm[other][0].iterations]).astype(float),
                           lambda X: X[..., 0].mean(axis=-1) / X[..., 1].mean(axis=-1), draws=draws, level=level, seed=seed)
    return other, ratio


def iterations_words(ratio: Estimate, level: float = 0.95) -> tuple[str, str]:
    """The ratio of :func:`fewer_iterations` in words: how many iterations the start needs against
    the other (``"**21% fewer iterations** on average (…) than"``) and what it does to them
    (``"saves 21% (15%–26%) of"``) — as many, within the interval, where it holds 1."""
    spread = f"{level:.0%} interval of the ratio {ratio.low:.2f}–{ratio.high:.2f}, paired over the targets"
    compared = (f"**{1 - ratio.value:.0%} fewer iterations** on average ({spread}) than" if ratio.high < 1 else
                f"**{ratio.value - 1:.0%} more iterations** on average ({spread}) than" if ratio.low > 1 else
                f"**as many iterations** on average (within the {spread}) as")
    saves = (f"saves {1 - ratio.value:.0%} ({1 - ratio.high:.0%}–{1 - ratio.low:.0%}) of" if ratio.high < 1 else
             f"adds {ratio.value - 1:.0%} ({ratio.low - 1:.0%}–{ratio.high - 1:.0%}) to" if ratio.low > 1 else
             "changes nothing, within its interval, in")
    return compared, saves
