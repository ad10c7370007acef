"""nfarm.study.warm_start: LM from several starts, and the ratio of their iterations."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from nfarm.infra.paths import PARAMS
from nfarm.model.kinematics import fk
from nfarm.study.study_files import load_study
from nfarm.study.warm_start import fewer_iterations, iterations_words, warm_start_table, warm_start_timing, warm_starts


@pytest.fixture(scope="module")
def solved():
    study = load_study(PARAMS / "studies" / "intelbot5.yaml")
    q = study.ik_region.sample(30, np.random.default_rng(3))
    near = q + np.random.default_rng(4).normal(0, 0.02, q.shape)
    return study, warm_starts(study.robot, fk(study.robot, q), {"default": None, "near": near, "truth": q}, seed=0)


def test_a_start_at_the_truth_needs_fewest_iterations_and_lands_in_the_region(solved):
    study, warm = solved
    iterations = {name: float(result.iterations.mean()) for name, (result, _) in warm.items()}
    assert iterations["truth"] <= iterations["near"] <= iterations["default"]
    table = warm_start_table(warm, study.ik_region)
    truth = next(r for r in table.rows if r[0] == "truth")
    assert truth[1:4] == [30, "100.00%", "100.00%"]


def test_fewer_iterations_leaves_out_the_excluded_start_and_pairs_the_targets(solved):
    _, warm = solved
    other, ratio = fewer_iterations(warm, "near", exclude=("truth",), draws=300)
    assert other == "default"
    expected = warm["near"][0].iterations.mean() / warm["default"][0].iterations.mean()
    assert ratio.value == pytest.approx(expected)
    assert ratio.low <= ratio.value <= ratio.high


@pytest.mark.parametrize("low, high, compared, saves", [
    (0.7, 0.9, "**20% fewer iterations**", "saves 20% (10%–30%) of"),
    (1.1, 1.3, "**20% more iterations**", "adds 20% (10%–30%) to"),
    (0.9, 1.1, "**as many iterations**", "changes nothing, within its interval, in")])
def test_iterations_words_follow_the_interval_of_the_ratio(low, high, compared, saves):
    value = 0.8 if high < 1 else 1.2 if low > 1 else 1.0
    words, effect = iterations_words(SimpleNamespace(value=value, low=low, high=high))
    assert words.startswith(compared) and effect == saves


def test_the_timing_table_adds_each_starts_prediction(solved):
    _, warm = solved
    table = warm_start_timing(warm, {"near": 1e-6})
    near = next(r for r in table.rows if r[0] == "near")
    assert near[2] == pytest.approx(1.0) and near[3] == pytest.approx(near[1] + 1.0)
    assert next(r for r in table.rows if r[0] == "default")[2] == 0.0
