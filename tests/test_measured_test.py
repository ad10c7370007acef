"""nfarm.study.measured_test: chapter 7.6's tables and comparisons from the methods' trajectory sums."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm.study.measured_test import NE, MeasuredTest, against, payload_table, rmse_table
from nfarm.study.statistics import bootstrap_nrmse, trajectory_sums

BOOT = {"draws": 300, "level": 0.95, "seed": 0}


def _test(errors: dict[str, float], n=3, trajectories=10, samples=50, seed=0) -> MeasuredTest:
    """A measured test whose methods' errors are Gaussian of the given standard deviations [N·m]."""
    rng = np.random.default_rng(seed)
    tau = rng.normal(0, 2.0, (trajectories * samples, n))
    trajectory = np.repeat(np.arange(trajectories), samples)
    sums = {name: trajectory_sums(tau + rng.normal(0, sd, tau.shape), tau, trajectory) for name, sd in errors.items()}
    states = (np.zeros_like(tau),) * 3
    return MeasuredTest(None, None, states, tau, None, sums, {k: np.zeros((trajectories, n)) for k in sums},
                        {k: v * np.r_[1.0, [1.5] * n, [1.0] * 2 * n] for k, v in sums.items()}, {})


def test_the_rmse_table_holds_every_method_with_its_tier_and_the_noise_row():
    t = _test({NE: 0.5, "generic: ANFIS": 0.2, "nominal model + learned: ridge regression": 0.1})
    table, ci = rmse_table(t, np.array([0.01, 0.02, 0.03]), **BOOT)
    assert [r[0] for r in table.rows] == [NE, "generic: ANFIS", "nominal model + learned: ridge regression", "sensor noise σ"]
    assert [r[1] for r in table.rows[:3]] == ["nominal model", "generic", "nominal model + learned"]
    assert ci[NE].worst == pytest.approx(bootstrap_nrmse(t.sums[NE], normalised=False, **BOOT).worst)
    assert 0.4 < ci[NE].worst < 0.6 and 0.08 < ci["nominal model + learned: ridge regression"].worst < 0.12
    assert table.rows[-1][-2] == 0.03           # the noise row's worst: the largest σ


@pytest.mark.parametrize("sd, word", [(0.1, "better"), (0.9, "worse"), (0.5, "same")])
def test_against_reads_the_paired_interval_of_the_worst_joints(sd, word):
    t = _test({NE: 0.5, "x": sd} if word != "same" else {NE: 0.5, "x": 0.5}, seed=1)
    if word == "same":
        t = MeasuredTest(None, None, t.states, t.measured, None, {NE: t.sums[NE], "x": t.sums[NE]}, t.maxima, {}, {})
    verdict, words = against(t, "x", NE, **BOOT)
    assert verdict == word
    assert ("no difference shown" in words) == (word == "same")


def test_the_payload_table_sets_each_method_beside_its_error_without_the_payload():
    t = _test({NE: 0.5, "generic: ANFIS": 0.2})
    _, ci = rmse_table(t, np.array([0.01] * 3), **BOOT)
    table, payload = payload_table(t, ci, 0.5, **BOOT)
    assert [r[-1] for r in table.rows] == [ci[NE].worst, ci["generic: ANFIS"].worst]
    assert payload[NE].worst == pytest.approx(np.sqrt(1.5) * ci[NE].worst)     # squared errors 1.5 times larger
    assert "0.5 kg" in table.caption
