"""A sweep's configurations as a chapter shows them: their labels, their values' least and largest
over the seeds, and whether two of them differ (chapter 06's tables and sentences).

A configuration is one :class:`nfarm.study.sweep.Replicates`: the cells of one set of options
over the sweep's seeds. Two configurations are "no different" when their ranges over the seeds
overlap (:func:`nfarm.study.statistics.ranges_separate`), the rule every compared number of
chapter 06 is read by.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence

import numpy as np

from .statistics import ranges_separate

__all__ = ["RULE_BASE", "configuration_label", "span", "value_range", "counts", "no_difference",
           "kept_validation_loss"]

#: The options that make an ANFIS rule base (the other options of a cell name its data).
RULE_BASE = ("partition", "n_mfs", "n_rules", "radius", "mf")


def configuration_label(options: Mapping, first: str = "encoding", keys: Sequence[str] = RULE_BASE) -> str:
    """``"arm_plane: partition=fcm, n_rules=20, mf=gauss"``: the option ``first`` (the encoding
    of a learned IK, the inputs of a learned ID), then ``keys`` that are given (not None).

    >>> configuration_label({"encoding": "arm_plane", "partition": "grid", "n_mfs": 3, "n_rules": None})
    'arm_plane: partition=grid, n_mfs=3'
    """
    given = {k: options[k] for k in keys if options.get(k) is not None}
    return f"{options[first]}: " + ", ".join(f"{k}={v}" for k, v in given.items())


def span(values: Iterable[float]) -> str:
    """Whole numbers as one value, or the least–largest of several (a widened grid's epochs,
    sample counts, seeds): ``"2,000"``, ``"3–10"``.

    >>> span([5, 5, 5]), span([20000, 2000, 8000])
    ('5', '2,000–20,000')
    """
    values = sorted(set(values))
    if not values:
        raise ValueError("span needs at least one value")
    return f"{values[0]:,}" if len(values) == 1 else f"{values[0]:,}–{values[-1]:,}"


def value_range(group, metric: str, *, fmt: Callable[[float], str] = str) -> str:
    """The least and largest value of ``metric`` over a configuration's seeds, each written by
    ``fmt``; one value when both read alike (two values at rounding level: one ``"< 1e-06"``)."""
    low, high = fmt(group.low(metric)), fmt(group.high(metric))
    return high if low == high else f"{low}–{high}"


def counts(group, metric: str) -> str:
    """A count (rules per joint, parameters) as the seeds gave it: one number, or least–largest
    where they differ; a count per joint as ``"8/8/27"``."""
    low, high = group.low(metric), group.high(metric)
    if isinstance(low, list):
        return "/".join(f"{a:.0f}" if a == b else f"{a:.0f}–{b:.0f}" for a, b in zip(low, high))
    return f"{low:,.0f}" if low == high else f"{low:,.0f}–{high:,.0f}"


def no_difference(a, b, metric: str) -> bool:
    """Whether two configurations' ranges of ``metric`` over their seeds overlap: no difference
    by the study's rule (:func:`nfarm.study.statistics.ranges_separate`). A configuration pruned
    after seed 0 (one seed, no spread of its own) is no different from another when its one value
    lies within the other's range; two of one seed each differ unless their values are equal."""
    if a.n >= 2 and b.n >= 2:
        return not ranges_separate(a.values(metric), b.values(metric))
    return bool(a.low(metric) <= b.high(metric) and b.low(metric) <= a.high(metric))


def kept_validation_loss(model) -> np.ndarray:
    """``(n,)`` each joint's validation loss at the epoch its model kept (a learned IK or ID:
    ``models_[j].val_loss_curve_[best_epoch_]``)."""
    return np.array([m.val_loss_curve_[m.best_epoch_] for m in model.models_])
