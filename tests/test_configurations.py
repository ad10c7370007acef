"""Chapter 06's reading of a sweep's configurations (nfarm.study.configurations)."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm.study.configurations import (RULE_BASE, configuration_label, counts, kept_validation_loss,
                                        no_difference, span, value_range)
from nfarm.study.sweep import Cell, CellResult, Replicates


def group(*per_seed, **params):
    return Replicates(tuple(CellResult(Cell({"encoding": "e", "seed": k, **params}, f"c{k}"), "ok", dict(m), 1.0, "w")
                            for k, m in enumerate(per_seed)))


def test_labels_name_the_first_option_and_the_given_rule_base():
    options = {"inputs": "affine", "partition": "grid", "n_mfs": [1, 2, 2, 2, 1], "n_rules": None, "mf": "gauss"}
    assert configuration_label(options, "inputs") == "affine: partition=grid, n_mfs=[1, 2, 2, 2, 1], mf=gauss"
    assert configuration_label({**options, "encoding": "x", "epochs": 3}, keys=RULE_BASE + ("epochs",)) \
        == "x: partition=grid, n_mfs=[1, 2, 2, 2, 1], mf=gauss, epochs=3"


@pytest.mark.parametrize("values, text", [([7], "7"), ([3, 10, 3], "3–10"), ([1_000_000, 2_000], "2,000–1,000,000")])
def test_a_span_is_one_value_or_the_least_and_largest(values, text):
    assert span(values) == text


def test_a_span_of_nothing_is_refused():
    with pytest.raises(ValueError, match="at least one value"):
        span([])


def test_ranges_counts_and_differences_read_the_seeds():
    a = group({"worst": 0.2, "rules": [8, 8], "parameters": 250}, {"worst": 0.3, "rules": [8, 27], "parameters": 675})
    b = group({"worst": 0.5, "rules": [8, 8], "parameters": 250}, {"worst": 0.6, "rules": [8, 8], "parameters": 250})
    c = group({"worst": 0.25, "rules": [8, 8], "parameters": 250}, {"worst": 0.55, "rules": [8, 8], "parameters": 250})
    assert value_range(a, "worst", fmt=lambda v: f"{v:.2g}") == "0.2–0.3"
    assert value_range(group({"worst": 1e-12}, {"worst": 2e-12}), "worst", fmt=lambda v: "< 1e-6") == "< 1e-6"
    assert counts(a, "rules") == "8/8–27" and counts(a, "parameters") == "250–675" and counts(b, "parameters") == "250"
    assert not no_difference(a, b, "worst") and no_difference(a, c, "worst") and no_difference(b, c, "worst")
    # A configuration pruned after seed 0: its one value within the other's range, or not
    inside, outside = group({"worst": 0.25}), group({"worst": 0.4})
    assert no_difference(inside, a, "worst") and no_difference(a, inside, "worst") and not no_difference(outside, a, "worst")
    assert not no_difference(inside, outside, "worst") and no_difference(inside, group({"worst": 0.25}), "worst")


def test_the_kept_validation_loss_is_each_joints_at_its_kept_epoch():
    class Joint:
        def __init__(self, curve, best):
            self.val_loss_curve_, self.best_epoch_ = curve, best

    class Model:
        models_ = [Joint([3.0, 2.0, 2.5], 1), Joint([1.0, 0.5], 1), Joint([4.0], 0)]

    np.testing.assert_array_equal(kept_validation_loss(Model()), [2.0, 0.5, 4.0])
