"""nfarm.study.verdicts: the verdict of chapter 7.7 from each method's values over its seeds."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm.study import replicates, verdicts
from nfarm.study.rows import ik_seed_values
from nfarm.study.sweep import CellResult
from nfarm.study.sweep_files import Cell

BOOT = {"draws": 300, "level": 0.95, "seed": 0}


def _ik_errors(rng, scale, n=40):
    return {"joint": rng.normal(0, 1e-3, (n, 5)), "position": scale * (0.5 + rng.random(n)) * 1e-3,
            "orientation": rng.random(n) * 1e-4}


def _sums(rng, scale, trajectories=12, n=3):
    """Trajectory sums ``(T, 1 + 3n)``: counts, squared errors, torques, squared torques."""
    counts = np.full((trajectories, 1), 100.0)
    tau = rng.normal(0, 1, (trajectories, n)) * 10
    tau2 = 100 * (1 + rng.random((trajectories, n))) * 100
    err2 = scale * 100 * (1 + 0.1 * rng.random((trajectories, n)))
    return np.hstack([counts, err2, tau, tau2])


@pytest.mark.parametrize("anfis_scale, rival_scale, expected", [(1.0, 3.0, "ANFIS better"), (3.0, 1.0, "rival better"),
                                                                (1.0, 1.0, "no difference shown")])
def test_judge_task_reads_the_paired_interval(anfis_scale, rival_scale, expected):
    rng = np.random.default_rng(1)
    same = [_ik_errors(rng, 1.0) for _ in range(2)]
    values = {"ANFIS": ik_seed_values(same if anfis_scale == rival_scale else
                                      [_ik_errors(rng, anfis_scale) for _ in range(2)]),
              "RBF": ik_seed_values(same if anfis_scale == rival_scale else
                                    [_ik_errors(rng, rival_scale) for _ in range(2)])}
    v = verdicts.judge_task("arm", "inverse kinematics", "position p95", "mm", values, "ANFIS", "RBF", ik=True, **BOOT)
    assert v.verdict == expected
    assert v.rival == "RBF" and v.compared == 2
    assert v.gap_low <= v.gap <= v.gap_high
    assert "seeds: ANFIS 2, best other 2, paired 2" in v.interval and "distinct resamples" in v.interval


def test_judge_task_counts_the_targets_each_method_meets_on_its_interval():
    rng = np.random.default_rng(2)
    values = {"ANFIS": ik_seed_values([_ik_errors(rng, 1.0)]), "RBF": ik_seed_values([_ik_errors(rng, 20.0)])}
    # position p95 of the ANFIS is about 1.5 mm, of the RBF about 30 mm: a 10 mm limit the first meets, a 0.1 mm neither
    v = verdicts.judge_task("arm", "inverse kinematics", "position p95", "mm", values, "ANFIS", "RBF", ik=True,
                            targets=[("position p95", 10.0, "mm"), ("position median", 0.1, "mm")], **BOOT)
    assert (v.anfis_targets, v.rival_targets) == ("1 of 2", "0 of 2")
    assert "coarse" not in v.interval          # one seed each: no outer resampling to call coarse


def test_seed_sums_put_the_chapters_seed_first_then_the_others_in_order():
    def run(seed):
        return CellResult(Cell({"seed": seed}, f"k{seed}"), "ok", {"trajectory_sums": [float(seed)] * 7}, 0.0, "")
    stacked = verdicts.seed_sums([run(3), run(0), run(2), run(1)], 2, seed=2)
    assert stacked.shape == (4, 1, 7)
    assert stacked[:, 0, 0].tolist() == [2.0, 0.0, 1.0, 3.0]


class _Constant:
    def __init__(self, value):
        self.value = value

    def predict(self, X):
        return np.full(len(X), self.value)


def test_seed_models_without_a_seeds_file_is_the_published_model_alone(tmp_path):
    model = _Constant(1.0)
    assert verdicts.seed_models(tmp_path, model, (np.zeros(3),)) == [model]


def test_seed_models_refuses_a_seed_model_that_is_not_the_published_one(tmp_path, monkeypatch):
    (tmp_path / replicates.SEEDS_FILE).write_text("{}")
    monkeypatch.setattr(replicates, "seed_models", lambda where: {0: _Constant(2.0), 1: _Constant(3.0)})
    with pytest.raises(RuntimeError, match="is not the published one"):
        verdicts.seed_models(tmp_path, _Constant(1.0), (np.zeros(3),))
    got = verdicts.seed_models(tmp_path, _Constant(2.0), (np.zeros(3),))
    assert [m.value for m in got] == [2.0, 3.0]


def test_id_values_over_seeds_reuse_the_chapters_seed_and_predict_the_others(tmp_path, monkeypatch):
    class Torques:
        def __init__(self, offset):
            self.offset = offset

        def predict(self, q, qd, qdd):
            return q + self.offset

    (tmp_path / replicates.SEEDS_FILE).write_text("{}")
    monkeypatch.setattr(replicates, "seed_models", lambda where: {0: Torques(0.0), 1: Torques(1.0)})
    q = np.zeros((6, 2))
    X, tau, trajectory = (q, q, q), np.zeros((6, 2)), np.repeat([0, 1, 2], 2)
    first = np.full((3, 7), -1.0)
    got = verdicts.id_values_over_seeds({"ANFIS": (Torques(0.0), tmp_path)}, X, tau, trajectory, first={"ANFIS": first},
                                        probe=(q[:2], q[:2], q[:2]))
    assert got["ANFIS"].shape == (2, 3, 7)
    assert np.array_equal(got["ANFIS"][0], first)                  # reused, not recomputed
    assert got["ANFIS"][1, :, 1:3].tolist() == [[2.0, 2.0]] * 3     # seed 1: an error of 1 N·m on 2 samples a trajectory


def test_the_task_verdicts_judge_each_task_on_its_metric_and_targets():
    rng = np.random.default_rng(3)
    ik = {m: ik_seed_values([_ik_errors(rng, s) for _ in range(2)]) for m, s in (("ANFIS", 1.0), ("RBF", 3.0))}
    v = verdicts.ik_verdict("arm", ik, "ANFIS", "RBF", exact="closed form", **BOOT)
    assert (v.task, v.metric, v.unit, v.verdict, v.exact) == ("inverse kinematics", "position p95", "mm", "ANFIS better",
                                                               "closed form")
    ids = {m: np.stack([_sums(rng, s) for _ in range(2)]) for m, s in (("ANFIS", 4.0), ("ridge", 1.0))}
    w = verdicts.rigid_id_verdict("arm", ids, "ANFIS", "ridge", resolved=np.ones(3, bool), **BOOT)
    assert (w.task, w.unit, w.verdict) == ("rigid-body inverse dynamics", "%", "rival better")
    assert w.rival_value < w.anfis_value


def test_seed_values_by_task_keys_every_method_by_its_task():
    values, resolved_by = verdicts.seed_values_by_task({"A": np.zeros((2, 5, 7))}, {"B": np.ones((2, 4, 10))}, "r",
                                                       measured={"C": np.ones((3, 4, 10))},
                                                       reference=("NE", np.ones((4, 10))), measured_resolved="m")
    assert sorted(values) == [("ID, measured arm", "C"), ("ID, measured arm", "NE"), ("inverse dynamics", "B"),
                              ("inverse kinematics", "A")]
    assert values["ID, measured arm", "NE"].shape == (1, 4, 10)
    assert resolved_by == {"inverse dynamics": "r", "ID, measured arm": "m"}


class _Scaled:
    """A model predicting ``factor`` times the true torques it was made for (a function of the states)."""

    def __init__(self, truth, factor):
        self.truth, self.factor = truth, factor

    def predict(self, q, qd, qdd):
        return self.factor * self.truth(q, qd, qdd)


def test_the_shifted_id_verdicts_judge_the_main_pairs_on_the_faster_trajectories():
    """The rigid-body pair on the model's torques and the measured pair on the built arm's readings
    (the states its encoders give), each over its seeds: a model that is the truth beats one 20 % off;
    one of NRMSE 1 % meets the 5 % target; no verdict where the study declares no ID population."""
    import json

    from nfarm.infra.paths import PARAMS
    from nfarm.model.dynamics import rnea
    from nfarm.study.shifted import shifted_id
    from nfarm.study.study_files import load_study, study_from_dict

    study = load_study(PARAMS / "studies" / "intelbot5.yaml")
    data = shifted_id(study)
    robot = study.robot
    exact = lambda q, qd, qdd: rnea(robot, q, qd, qdd)            # noqa: E731

    def measured(q, qd, qdd):          # what the built arm read on the states its encoders give, by lookup
        return data["tau_measured"] if np.array_equal(q, data["q_measured"]) else np.full_like(q, np.nan)

    rigid = {"ANFIS": [_Scaled(exact, 1.0), _Scaled(exact, 1.0)], "ridge": [_Scaled(exact, 1.2), _Scaled(exact, 1.2)]}
    known = {"ANFIS: m": [_Scaled(measured, 1.2)] * 2, "MLP: m": [_Scaled(measured, 1.0)] * 2}
    resolved = np.ones(robot.n, bool)
    out = verdicts.shifted_id_verdicts(study, rigid, ("ANFIS", "ridge"), resolved=resolved, measured=known,
                                       measured_pair=("ANFIS: m", "MLP: m"), measured_resolved=resolved, draws=200)
    assert [v.task for v in out] == ["rigid-body inverse dynamics, shifted population",
                                     "measured arm, every tier, shifted population"]
    assert out[0].verdict == "ANFIS better" and out[0].anfis_value == 0 and out[0].rival_value > 0
    assert out[1].verdict == "rival better" and out[1].rival_value == 0
    assert "shifted trajectories" in out[0].interval and out[0].anfis_targets.startswith("1 of 1")
    params = json.loads(json.dumps(study.params))
    params["shifted"].pop("id_trajectories")
    assert verdicts.shifted_id_verdicts(study_from_dict(params, source="ik-only.yaml"), rigid, ("ANFIS", "ridge"),
                                        resolved=resolved) == []


def test_each_measured_model_meets_the_shifted_trajectories_as_the_arm_built_for_its_draw_reads_them():
    """Issue 65: the second seed's model was trained on another built arm; a model that predicts exactly
    what its draw's arm reads scores 0 when judged on its own draw (measured_seeds) and not when every
    model is judged on chapter 5's arm; more models than draws named is refused."""
    from nfarm.infra.paths import PARAMS
    from nfarm.study.shifted import shifted_id, shifted_readings
    from nfarm.study.study_files import load_study

    study = load_study(PARAMS / "studies" / "intelbot5.yaml")
    data = shifted_id(study)
    reads = {draw: shifted_readings(study, data, draw)["tau_measured"] for draw in (0, 1)}
    models = {name: [_Scaled(lambda q, qd, qdd, d=draw: reads[d], factor) for draw in (0, 1)]
              for name, factor in (("ANFIS: m", 1.2), ("MLP: m", 1.0))}
    rigid = {"ANFIS": models["MLP: m"], "ridge": models["MLP: m"]}
    resolved = np.ones(study.robot.n, bool)
    kwargs = dict(resolved=resolved, measured=models, measured_pair=("ANFIS: m", "MLP: m"), measured_resolved=resolved,
                  draws=200)
    own = verdicts.shifted_id_verdicts(study, rigid, ("ANFIS", "ridge"), measured_seeds=[0, 1], **kwargs)[1]
    first = verdicts.shifted_id_verdicts(study, rigid, ("ANFIS", "ridge"), **kwargs)[1]
    assert own.rival_value == 0 and first.rival_value > 0
    with pytest.raises(ValueError, match=r"measured_seeds names 1 draws, fewer than the pair's models \(\[2, 2\]\)"):
        verdicts.shifted_id_verdicts(study, rigid, ("ANFIS", "ridge"), measured_seeds=[0], **kwargs)


def _joint_sums(rng, nrmse, trajectories=12):
    """Trajectory sums ``(T, 1 + 3n)`` whose joints' NRMSE are about ``nrmse (n,)``."""
    nrmse = np.asarray(nrmse, float)
    counts = np.full((trajectories, 1), 100.0)
    tau = np.zeros((trajectories, nrmse.size))
    tau2 = np.full((trajectories, nrmse.size), 100.0 * 4.0)          # spread 2 N·m on every joint
    err2 = 100.0 * (2.0 * nrmse) ** 2 * (1 + 0.05 * rng.random((trajectories, nrmse.size)))
    return np.hstack([counts, err2, tau, tau2])[None]


def test_a_measured_verdict_on_a_group_judges_only_its_joints():
    """The ANFIS worse on the friction joint, better on the rigid ones: the group's verdicts differ, and the
    target over every joint is judged over the group's joints only."""
    rng = np.random.default_rng(4)
    values = {"ANFIS": _joint_sums(rng, [0.30, 0.02, 0.03]), "MLP": _joint_sums(rng, [0.10, 0.08, 0.09])}
    rigid, friction = np.array([False, True, True]), np.array([True, False, False])
    on_rigid = verdicts.measured_verdict("arm", values, "ANFIS", "MLP", resolved=rigid, every=rigid,
                                         tier="every tier, rigid-dominated joints", **BOOT)
    on_friction = verdicts.measured_verdict("arm", values, "ANFIS", "MLP", resolved=friction, every=friction,
                                            tier="every tier, friction-dominated joints", **BOOT)
    whole = verdicts.measured_verdict("arm", values, "ANFIS", "MLP", resolved=np.ones(3, bool), tier="every tier", **BOOT)
    assert on_rigid.task == "measured arm, every tier, rigid-dominated joints"
    assert (on_rigid.verdict, on_friction.verdict, whole.verdict) == ("ANFIS better", "rival better", "rival better")
    assert on_rigid.anfis_value == pytest.approx(3.0, rel=0.05) and on_rigid.anfis_targets == "2 of 2"
    assert whole.anfis_targets == "0 of 2" and on_friction.rival_targets == "0 of 2"


def test_the_every_tier_verdict_never_takes_the_rigid_body_span_for_the_anfiss_rival():
    """Issue 65: ridge on the chain basis (the rigid-body span, an identification in disguise) is best on
    validation, yet the verdict over every tier sets the ANFIS against the best of the other learners; the
    tiers with an ANFIS and a rival get their own verdict, the span (no ANFIS) none."""
    from nfarm.infra.paths import PARAMS
    from nfarm.study import contest
    from nfarm.study.sweep_files import load_sweep

    def cell(learner, seed, worst, split="val", **options):
        return CellResult(Cell({"learner": learner, "options": options, "seed": seed, "split": split,
                                "study_file": "params/studies/intelbot5.yaml"}, f"{learner}{seed}{split}{options}"),
                          "ok", {"worst_nrmse": worst, "worst_rmse": worst, "fit_seconds": 1.0}, 1.0, "w")

    seed0 = [cell("anfis", 0, 0.20, inputs="affine_drives"), cell("mlp", 0, 0.10, angles="chain"),
             cell("ridge", 0, 0.01, basis="chain_drives")]
    spread = [cell(c.cell.params["learner"], s, c.metrics["worst_nrmse"], **c.cell.params["options"])
              for c in seed0 for s in (1, 2)]
    idc = contest.id_contest(seed0, spread)
    rng = np.random.default_rng(3)
    error = {"anfis": 1.0, "mlp": 2.0, "ridge": 0.01}          # on the test trajectories, relative

    def run(sweep, *args, **kwargs):
        return [CellResult(c, "ok", {"trajectory_sums": _sums(rng, error[c.params["learner"]]).ravel().tolist()}, 1.0, "w")
                for c in sweep.cells]

    sweep = load_sweep(PARAMS / "sweeps" / "id_contest.yaml", smoke=True)
    names = [contest.id_label(f) for f in idc.chosen] + ["Newton–Euler"]
    pairs = {"structure-informed": ("structure-informed: ANFIS", "structure-informed: multilayer perceptron")}
    found, values = verdicts.measured_verdicts("arm", idc, sweep, names, pairs, resolved=np.ones(3, bool), n_joints=3,
                                               reference="Newton–Euler", run=run, **BOOT)
    every = next(v for v in found if v.task == "measured arm, every tier")
    assert every.rival == "structure-informed: multilayer perceptron" and every.verdict == "ANFIS better"
    assert "rigid-body span: ridge regression" in values          # tested, shown beside the verdict
    assert not any("span" in v.task for v in found)                # no verdict of its own
