"""The chosen models' store (nfarm.study.chosen_models): where chapter 6 publishes each chosen
model, what a published copy keeps beside it, and which model goes where."""

from __future__ import annotations

import json

import numpy as np
import pytest

from nfarm.infra.paths import BUILD
from nfarm.model.dynamics import rnea
from nfarm.model.robot import load_robot
from nfarm.study import chosen_models, replicates, study_files
from nfarm.study.chosen_models import (PLANE, RECIPE, ChosenModels, configuration_of, publish, publish_chosen_ik,
                                       publish_finalists, publish_seed_like, save_built_arm)
from nfarm.study.datasets import built_arm
from nfarm.study.sweep import Cell, CellResult, Replicates, by_configuration


class Saved:
    """A model that records where it was saved (as LearnedIK.save does, one file)."""

    def __init__(self, name):
        self.name, self.places = name, []

    def save(self, where):
        where.mkdir(parents=True, exist_ok=True)
        (where / "model.json").write_text(json.dumps(self.name))
        self.places.append(where)
        return where / "model.json"


def group(params, seeds=(0, 1)):
    return Replicates(tuple(CellResult(Cell({**params, "seed": s}, f"{params}{s}"), "ok", {}, 1.0, "w") for s in seeds))


def test_the_store_lays_out_what_chapters_7_and_8_read(tmp_path):
    store = ChosenModels(tmp_path)
    assert store.ik == tmp_path / "ik" and store.ik_dissertation == tmp_path / "ik" / "dissertation"
    assert store.ik_dissertation_full == tmp_path / "ik" / "dissertation_full"
    assert store.ik_contestant("kernel_ridge:arm") == tmp_path / "ik_contest" / "kernel_ridge_arm"
    assert store.id_model_free == tmp_path / "id_model_free"
    assert (store.id_dissertation, store.id_identified) == (tmp_path / "id" / "dissertation", tmp_path / "id" / "identified")
    assert store.id_seed_like("model_free") == tmp_path / "id_seed_like" / "model_free"
    assert store.id_finalist("nominal model + learned", "rival") == tmp_path / "id_measured" / "nominal" / "rival"
    assert store.built_arm.parent == store.built_arm_offsets.parent == tmp_path / "id_measured"
    with pytest.raises(ValueError, match="slot"):
        store.id_finalist("generic", "best")


def test_the_default_store_is_named_after_the_data_sets_directory(tmp_path):
    assert ChosenModels.of(None, tmp_path / "intelbot5-smoke").root == BUILD / "models" / "intelbot5-smoke"
    assert ChosenModels.of(tmp_path / "mine", tmp_path / "intelbot5").root == tmp_path / "mine"


def test_a_published_copy_keeps_its_seeds_and_drops_a_caches_fingerprint(tmp_path):
    where = tmp_path / "id_model_free"
    where.mkdir()
    (where / "inputs.sha256").write_text("a cache's")
    g = group({"study_file": "params/studies/intelbot5.yaml", "inputs": "affine"}, seeds=(2, 0, 1))
    model = Saved("chosen")
    assert publish(model, where, "learned_id", g) is model and model.places == [where]
    assert not (where / "inputs.sha256").exists()
    job, cells = replicates.read_seeds(where)
    assert job == "learned_id" and [c["seed"] for c in cells] == [0, 1, 2]
    publish(Saved("again"), where)                  # without a group: no seeds file, not a stale one
    assert not (where / replicates.SEEDS_FILE).exists() and json.loads((where / "model.json").read_text()) == "again"


def test_a_configuration_is_found_by_its_options_and_fixed_parameters():
    a = group({"inputs": "own", "n_mfs": 2, "stride": 4})
    b = group({"inputs": "own", "n_mfs": 2, "stride": 8})
    c = group({"inputs": "affine", "n_mfs": 1, "stride": 4})
    assert configuration_of([a, b, c], {"inputs": "own", "n_mfs": 2}, stride=8) is b
    assert configuration_of([a, b, c], {"inputs": "affine"}) is c
    assert configuration_of([a, b, c], {"inputs": "trig"}) is None


def _contestant(learner, seed, encoding=None, **options):
    params = {"learner": learner, "options": options, "seed": seed, **({"encoding": encoding} if encoding else {})}
    return CellResult(Cell(params, f"{learner}{encoding}{seed}"), "ok", {"position_p95_mm": 1.0}, 1.0, "w")


@pytest.mark.parametrize("planar", [True, False])
def test_the_chosen_learned_ik_is_the_anfis_in_the_arms_plane_or_else_the_recipe(tmp_path, monkeypatch, planar):
    made = {}

    def model_of(params):
        made[params["learner"] + str(params.get("encoding"))] = m = Saved(params)
        return m

    monkeypatch.setattr(chosen_models, "contest_model", model_of)
    monkeypatch.setattr(chosen_models, "ik_model", lambda params: Saved("full range"))
    names = ([("anfis", "arm_plane")] if planar else []) + [("anfis", "quat_xyz"), ("rbf", None)]
    chosen = {f"{learner}:{enc}" if enc else learner: _contestant(learner, 0, enc) for learner, enc in names}
    ranked = by_configuration([*chosen.values(), *(_contestant(learner, 1, enc) for learner, enc in names)])
    recipe_runs = [_contestant("anfis", 0, "quat_xyz", poses="full_range")]
    store = ChosenModels(tmp_path)
    out = publish_chosen_ik(store, chosen, ranked, recipe_runs, seed=3)
    assert out.name == (PLANE if planar else RECIPE)
    assert all(m.name["seed"] == 3 for m in made.values())          # the chapter's seed, every contestant
    assert out.model is made["anfis" + ("arm_plane" if planar else "quat_xyz")]
    assert out.model.places == [store.ik_contestant(out.name), store.ik] + ([store.ik_dissertation] if not planar else [])
    assert out.recipe["ik"] is made["anfisquat_xyz"] and out.recipe["ik_full"].places == [store.ik_dissertation_full]
    assert made["rbfNone"].places == [store.ik_contestant("rbf")]
    assert out.standing.n == 2 and out.standing.cell.params["encoding"] == ("arm_plane" if planar else "quat_xyz")
    assert [c["seed"] for c in replicates.read_seeds(store.ik)[1]] == [0, 1]


def test_each_tiers_finalists_and_the_seed_like_designs_go_to_their_places(tmp_path, monkeypatch):
    from nfarm.study import contest
    monkeypatch.setattr(chosen_models, "id_contest_model", lambda params: Saved(params))
    monkeypatch.setattr(chosen_models, "id_model", lambda params: Saved(params))
    seed0 = [CellResult(Cell({"learner": learner, "options": options, "seed": 0, "split": "val"}, learner + str(k)), "ok",
                        {"worst_nrmse": nrmse, "worst_rmse": 0.1, "fit_seconds": 1.0}, 1.0, "w")
             for k, (learner, options, nrmse) in enumerate([("anfis", {"inputs": "affine_generic"}, 0.3),
                                                             ("ridge", {"basis": "generic"}, 0.2),
                                                             ("friction", {"residual": True}, 0.1)])]
    store = ChosenModels(tmp_path)
    publish_finalists(store, contest.id_contest(seed0), seed=0)
    found = sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("model.json"))
    assert found == ["id_measured/generic/anfis/model.json", "id_measured/generic/rival/model.json",
                     "id_measured/nominal/rival/model.json"]
    like = {"duration_s": 6.0, "dt_s": 0.2, "seed": 7}
    ablation = [group({"inputs": "affine", "torques": "rigid", "seed_like": like}),
                group({"inputs": "own", "torques": "rigid", "seed_like": like}),
                group({"inputs": "affine", "torques": "rigid", "seed_like": None})]
    groups = publish_seed_like(store, ablation, {"model_free": {"inputs": "affine"}, "dissertation": {"inputs": "own"}}, like)
    assert groups == {"model_free": ablation[0], "dissertation": ablation[1]}
    assert json.loads((store.id_seed_like("dissertation") / "model.json").read_text())["inputs"] == "own"
    with pytest.raises(ValueError, match="no ablation cell"):
        publish_seed_like(store, ablation[2:], {"model_free": {"inputs": "affine"}}, like)


def test_the_built_arm_is_a_robot_file_with_the_same_dynamics(tmp_path):
    study = study_files.smoke_study(study_files.load_study("params/studies/intelbot5.yaml"))
    store = ChosenModels(tmp_path)
    assert save_built_arm(store, study, "params/studies/intelbot5.yaml") == (store.built_arm, store.built_arm_offsets)
    expected, offsets = built_arm(study)
    q, qd, qdd = np.random.default_rng(0).normal(size=(3, 10, expected.n))
    np.testing.assert_array_equal(rnea(load_robot(store.built_arm), q, qd, qdd, drive=True), rnea(expected, q, qd, qdd, drive=True))
    import yaml
    written = yaml.safe_load(store.built_arm_offsets.read_text())
    assert written["zero_offset_nm"] == offsets.tolist() and written["joints"] == list(study.robot.joint_names)
    assert "params/studies/intelbot5.yaml's seed" in yaml.safe_load(store.built_arm.read_text())["description"]


def test_every_draws_built_arm_is_saved_as_a_robot_file_beside_the_finalists(tmp_path):
    """Issue 65: the finalists of draw k were trained on the k-th arm built; each is saved (draw 0's
    as before), and each file is the arm datasets.built_arm draws for that draw, with its offsets."""
    import yaml
    from nfarm.study.study_files import redrawn

    study = study_files.smoke_study(study_files.load_study("params/studies/intelbot5.yaml"))
    store = ChosenModels(tmp_path)
    written = save_built_arm(store, study, "params/studies/intelbot5.yaml", draws=[0, 1, 2, 1])
    assert written == (store.built_arm, store.built_arm_offsets, store.built_arm_of(1), store.built_arm_offsets_of(1),
                       store.built_arm_of(2), store.built_arm_offsets_of(2))
    assert store.built_arm_of(2).name == "built_arm_draw2.yaml" and store.built_arm_of(0) == store.built_arm
    q, qd, qdd = np.random.default_rng(0).normal(size=(3, 10, study.robot.n))
    torques = {}
    for draw in (0, 1, 2):
        expected, offsets = built_arm(redrawn(study, draw))
        torques[draw] = rnea(load_robot(store.built_arm_of(draw)), q, qd, qdd, drive=True)
        np.testing.assert_array_equal(torques[draw], rnea(expected, q, qd, qdd, drive=True))
        assert yaml.safe_load(store.built_arm_offsets_of(draw).read_text())["zero_offset_nm"] == offsets.tolist()
        assert f"(+{draw}: {study.seed + draw})" in yaml.safe_load(store.built_arm_of(draw).read_text())["description"]
    assert not np.allclose(torques[1], torques[0]) and not np.allclose(torques[2], torques[1])
