"""nfarm.study.measured_test: chapter 7.6's tables and comparisons from the methods' trajectory sums."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import matplotlib
import numpy as np
import pytest

from nfarm.study.measured_test import (NE, MeasuredTest, against, deploy_prose, deploy_table, deploy_times,
                                       measured_figure, measured_tables, payload_table, rmse_table)

matplotlib.use("Agg")
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


# -- the tables as one record, the figure, and what each tier costs to deploy ---------------------------------


class _Contest:
    """A contest of two tiers whose winners are the ANFIS of the generic tier and ridge regression of the nominal one."""
    tiers = ["generic", "nominal model + learned"]

    def winner(self, tier):
        params = {"generic": {"learner": "anfis", "options": {"inputs": "own"}},
                  "nominal model + learned": {"learner": "ridge", "options": {"residual": True}}}[tier]
        return SimpleNamespace(cell=SimpleNamespace(params=params))

    def pair(self, tier):
        return None, None


def test_the_tables_come_as_one_record_the_payload_case_only_where_the_split_holds_it():
    t = replace(_test({NE: 0.5, "generic: ANFIS": 0.2}), contest=_Contest())
    noise = np.array([0.01, 0.02, 0.03])
    tables = measured_tables(t, noise, None, **BOOT)
    assert tables.payload_table is None and tables.payload is None and tables.payload_kg == 0.0
    assert tables.rmse[NE].worst == pytest.approx(rmse_table(t, noise, **BOOT)[1][NE].worst)
    assert tables.resolved.tolist() == [True] * 3 and set(tables.target) == {NE, "generic: ANFIS"}
    with_payload = replace(t, payload=t.measured)
    with pytest.raises(ValueError, match="no true_arm says its payload"):
        measured_tables(with_payload, noise, None, **BOOT)
    tables = measured_tables(with_payload, noise, SimpleNamespace(payload=0.25), **BOOT)
    assert tables.payload_kg == 0.25 and "0.25 kg" in tables.payload_table.caption
    assert tables.payload[NE].worst == pytest.approx(np.sqrt(1.5) * tables.rmse[NE].worst)


def test_the_deploy_table_goes_tier_by_tier_and_the_words_name_each_tiers_choice(intelbot5):
    names = [NE, "generic: ANFIS", "generic: ridge regression", "nominal model + learned: ridge regression"]
    t = _test(dict(zip(names, [0.5, 0.3, 0.2, 0.1])), n=intelbot5.n)
    t = replace(t, contest=_Contest(), predict_us={names[1]: 4.0, names[2]: 1.0, names[3]: 2.0})
    _, ci = rmse_table(t, np.full(intelbot5.n, 0.01), **BOOT)
    deploy_us = deploy_times(intelbot5, t, repeats=1)
    assert list(deploy_us)[0] == NE and deploy_us[NE] > 0 and deploy_us[names[1]] == 4.0
    deploy_us = {**deploy_us, NE: 2.0}                   # this run's time for Newton–Euler, fixed for the words
    table = deploy_table(t, ci, deploy_us, level=0.9)
    assert [row[1] for row in table.rows] == [names[2], names[1], NE, names[3]]     # by tier, then by error
    assert [row[-1] for row in table.rows] == [0.5, 2.0, 1.0, 1.0] and "90% interval [N·m]" in table.columns
    words = deploy_prose(t, ci, deploy_us, "/tmp/models")
    assert "against Newton–Euler's 2 µs (saved under `/tmp/models/id_measured`" in words
    assert f"generic: ANFIS, {ci[names[1]].worst:.3g} N·m, 2.0 times rnea's time" in words
    assert "nominal model + learned: ridge regression, " in words and "about the same as rnea's time" in words


def test_the_measured_figure_counts_its_predictions():
    t = _test({NE: 0.5})
    mask = np.arange(len(t.measured)) < 50
    shown = {NE: t.measured[mask] + 0.1, "nominal model + learned: ANFIS": t.measured[mask]}
    fig, caption = measured_figure(t, shown, np.arange(len(t.measured)) * 0.01, mask, 0, ["a", "b", "c"])
    assert caption == "Held-out trajectory 0: measured torques and 2 predictions" and len(fig.axes) >= 3


def test_joint_groups_split_the_joints_by_what_moves_them():
    """A joint is rigid-dominated where the built arm's rigid-body torque's RMS exceeds its drives';
    the two groups partition the joints; on the SO-101's hobby servos friction moves every joint."""
    import numpy as np

    from nfarm.infra.paths import PARAMS
    from nfarm.model.dynamics import rnea, stribeck_drive_torques
    from nfarm.study.datasets import built_arm
    from nfarm.study.id_trajectories import random_trajectories
    from nfarm.study.measured_test import JOINT_GROUPS, joint_groups
    from nfarm.study.study_files import load_study

    for arm, expected in (("intelbot5", [0, 1, 1, 1, 0]), ("so101", [0, 0, 0, 0, 0])):
        study = load_study(PARAMS / "studies" / f"{arm}.yaml")
        data = random_trajectories(study.robot, study.id, 20, np.random.SeedSequence([7, 1]))
        groups = joint_groups(study, data)
        assert tuple(groups) == JOINT_GROUPS
        assert (groups["rigid-dominated"] ^ groups["friction-dominated"]).all()
        assert groups["rigid-dominated"].astype(int).tolist() == expected
        built, _ = built_arm(study)
        rigid = rnea(built, data["q"], data["qd"], data["qdd"])
        drive = stribeck_drive_torques(built, data["qd"], data["qdd"], rigid, **study.id.friction)
        np.testing.assert_array_equal(groups["rigid-dominated"], np.sqrt((rigid ** 2).mean(0)) > np.sqrt((drive ** 2).mean(0)))


def test_the_joint_groups_are_fixed_on_the_validation_trajectories(monkeypatch, tmp_path):
    """The verdict's rows by joint group come from the validation trajectories' exact states (``id_val.npz`` in the data
    directory), as the resolved joints do, never from the test split's: the same groups as ``joint_groups`` of them."""
    import numpy as np

    from nfarm.infra.paths import PARAMS
    from nfarm.study import datasets
    from nfarm.study.id_trajectories import random_trajectories
    from nfarm.study.measured_test import joint_groups, joint_groups_on_validation
    from nfarm.study.study_files import load_study

    study = load_study(PARAMS / "studies" / "intelbot5.yaml")
    val = random_trajectories(study.robot, study.id, 6, np.random.SeedSequence([7, 2]))
    read = []
    monkeypatch.setattr(datasets, "load", lambda path, robot, study=None: read.append(str(path)) or val)
    groups = joint_groups_on_validation(study, tmp_path)
    assert read == [str(tmp_path / "id_val.npz")]
    assert {k: v.tolist() for k, v in groups.items()} == {k: v.tolist() for k, v in joint_groups(study, val).items()}
