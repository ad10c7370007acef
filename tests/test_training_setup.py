"""Chapter 6's set-up (nfarm.study.training_setup): the smoke run's designs, the study's data and
chart, and the sweeps restricted to one arm's cells."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from nfarm.study import contest
from nfarm.study.training_setup import read_study, smoke_designs, training_setup, training_sweeps

STUDY = "params/studies/intelbot5.yaml"
DISSERTATION = {"encoding": "quat_xyz", "partition": "grid", "n_mfs": 2, "epochs": 10}
ID_DISSERTATION = {"inputs": "own", "partition": "grid", "n_mfs": 3, "epochs": 10}
SEED_LIKE = {"duration_s": 6.0, "dt_s": 0.2, "seed": 7}


@pytest.fixture(scope="module")
def setup(tmp_path_factory):
    study, notes = read_study(STUDY, smoke=True)
    assert notes == "" and study.name.endswith("(smoke)")
    where = tmp_path_factory.mktemp("setup")
    return training_setup(study, where / "data", where / "models")


def sweeps_of(setup, **more):
    return training_sweeps(setup, study_file=STUDY, smoke=True, seed=0, contest_sweep_file="params/sweeps/ik_contest.yaml",
                           id_sweep_file="params/sweeps/id_comparison.yaml",
                           id_baselines_sweep_file="params/sweeps/id_baselines.yaml",
                           id_sizes_sweep_file="params/sweeps/id_sizes.yaml",
                           id_contest_sweep_file="params/sweeps/id_contest.yaml", dissertation=DISSERTATION,
                           id_dissertation=ID_DISSERTATION, seed_like=SEED_LIKE, ablation_seeds=[0, 1], **more)


def test_a_smoke_run_shrinks_the_designs_and_keeps_given_seeds():
    d = smoke_designs(DISSERTATION, ID_DISSERTATION, [0, 1, 2, 3, 4], None)
    assert d.dissertation == {**DISSERTATION, "n_mfs": [2, 2, 2, 1, 1, 1, 1], "epochs": 2}
    assert len(d.dissertation["n_mfs"]) == 7                        # one per input of the quaternion encoding
    assert d.id_dissertation == {**ID_DISSERTATION, "n_mfs": 2, "epochs": 2}
    assert (d.id_size_strides, d.ablation_seeds, d.spread_seeds) == ([4, 1], [0, 1], list(contest.SMOKE_SPREAD_SEEDS))
    assert smoke_designs(DISSERTATION, ID_DISSERTATION, [3], [5, 6]).spread_seeds == [5, 6]
    assert DISSERTATION["epochs"] == 10                              # the parameters themselves are not changed


def test_the_set_up_reads_training_and_validation_only_and_finds_the_arms_plane(setup):
    assert sorted(setup.data) == ["id_train", "id_val", "ik_full_train", "ik_full_val", "ik_train", "ik_val"]
    assert setup.planar and 0 <= setup.worst_out_of_plane < 1e-9     # intelbot5's tool stays in its vertical plane
    assert setup.has_measured and setup.robot is setup.study.robot
    spread = setup.data["id_val"]["tau"].std(axis=0)
    np.testing.assert_array_equal(setup.resolved, spread >= setup.study.id.noise)
    assert setup.models.root.name == "models"
    tight = training_setup(setup.study, setup.dataset_dir, max_out_of_plane_deg=0.0)
    assert tight.planar == (tight.worst_out_of_plane <= 0.0)


def test_the_sweeps_are_this_arms_cells(setup):
    sweeps = sweeps_of(setup)
    for sweep in (sweeps.contest, sweeps.id, sweeps.baselines, sweeps.id_sizes, sweeps.id_contest):
        assert sweep.cells and {c.params["study_file"] for c in sweep.cells} == {STUDY}
    assert {c.params["fraction"] for c in sweeps.contest_rung.cells} == {contest.RUNG_FRACTION}
    (recipe,) = sweeps.recipe.cells                                 # the study has full-range data
    assert recipe.params["poses"] == "full_range" and recipe.params["epochs"] == 10
    assert [c.params["seed"] for c in sweeps.fixed.cells] == [0, 1]
    assert all(c.params["seed_like"] == SEED_LIKE and c.params["stride"] == sweeps.id_stride for c in sweeps.fixed.cells)
    assert sweeps.other_seeds == contest.SPREAD_SEEDS
    cell = sweeps.chosen_cell({"inputs": "affine"}, 8)
    assert (cell["seed"], cell["stride"], cell["inputs"], cell["smoke"]) == (0, 8, "affine", True) and "fraction" not in cell
    (ablation,) = sweeps.ablation({"inputs": "affine"}).cells
    assert (ablation.params["seed"], ablation.params["seed_like"], ablation.params["inputs"]) == (0, SEED_LIKE, "affine")


def test_an_arm_the_plane_cannot_describe_competes_on_the_recipes_inputs_and_one_without_a_measured_arm_has_no_contest(setup):
    full = sweeps_of(setup)
    off_plane = sweeps_of(replace(setup, planar=False))
    assert {c.params.get("encoding") for c in off_plane.contest.cells} <= {"quat_xyz"}
    assert not [c for c in off_plane.contest.cells if contest.structure_of(contest.family(c.params)) == "arm"]
    assert len(off_plane.contest.cells) < len(full.contest.cells)
    unmeasured = replace(setup, data={**setup.data, "id_train": {k: v for k, v in setup.data["id_train"].items()
                                                                 if k != "tau_measured"}})
    assert not sweeps_of(unmeasured).id_contest.cells and full.id_contest.cells
    no_full_range = replace(setup, study=replace(setup.study, ik_full_range=False))
    assert not sweeps_of(no_full_range).recipe.cells
    assert sweeps_of(setup, spread_seeds=[9]).other_seeds == (9,)
