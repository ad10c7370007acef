"""Model-free inverse dynamics (nfarm.learning.bases, LearnedID's affine input sets): the bases
hold what they claim (the chain basis spans the rigid-body model of arms like intelbot5, the
generic one does not) and the rules over the configuration add what one rule lacks. The
scikit-learn baselines are in test_baselines.py."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.linalg

from nfarm.learning import bases
from nfarm.study.study_files import load_study
from nfarm.study.id_trajectories import random_trajectories
from nfarm.model.dynamics import rnea
from nfarm.learning.learned_id import LearnedID, id_features
from nfarm.infra.paths import PARAMS
from nfarm.model.robot import load_robot

STUDY = load_study(PARAMS / "studies" / "intelbot5.yaml")
ROBOT = STUDY.robot
SO101 = load_robot(PARAMS / "robots" / "so101.yaml")
with warnings.catch_warnings():          # the Puma's published inertias are not physical
    warnings.simplefilter("ignore")
    PUMA = load_robot(PARAMS / "robots" / "puma560.yaml")


def states(robot, count, seed):
    rng = np.random.default_rng(seed)
    lo, hi = robot.qlim[:, 0], robot.qlim[:, 1]
    q = lo + (hi - lo) * rng.random((count, robot.n))
    qd, qdd = rng.normal(size=(2, count, robot.n))
    return {"q": q, "qd": qd, "qdd": qdd, "tau": rnea(robot, q, qd, qdd)}


@pytest.fixture(scope="module")
def trajectories():
    def split(count, seed):
        d = random_trajectories(ROBOT, STUDY.id, count, seed)
        d["tau"] = rnea(ROBOT, d["q"], d["qd"], d["qdd"])
        return {k: d[k] for k in ("q", "qd", "qdd", "tau")}
    return {"train": split(8, 1), "val": split(2, 2)}


def nrmse(tau_hat, tau):
    return np.sqrt(((tau_hat - tau) ** 2).mean(axis=0)) / tau.std(axis=0)


@pytest.mark.parametrize("robot, runs", [(ROBOT, [(1, 2, 3)]), (SO101, [(1, 2, 3)]), (PUMA, [(1, 2)])],
                         ids=["intelbot5", "so101", "puma560"])
def test_parallel_runs_are_read_off_the_axes(robot, runs):
    assert bases.parallel_runs(robot) == runs
    assert bases.parallel_runs(robot, axis_tol=1e-12) == runs       # exactly parallel (α = 0 or π)


@pytest.mark.parametrize("kind", bases.BASES)
@pytest.mark.parametrize("robot", [ROBOT, SO101, PUMA], ids=["intelbot5", "so101", "puma560"])
def test_basis_widths_and_linearity_in_the_accelerations(robot, kind):
    d = states(robot, 7, 0)
    X = bases.basis(robot, d["q"], d["qd"], d["qdd"], kind)
    assert X.shape == (7, bases.basis_width(robot, kind))
    # affine in q̈: the basis of a mix of accelerations is the mix of the bases
    other = np.random.default_rng(1).normal(size=d["qdd"].shape)
    mixed = bases.basis(robot, d["q"], d["qd"], 0.3 * d["qdd"] + 0.7 * other, kind)
    np.testing.assert_allclose(mixed, 0.3 * X + 0.7 * bases.basis(robot, d["q"], d["qd"], other, kind),
                               atol=1e-12)


@pytest.mark.parametrize("robot, chain", [(ROBOT, 1e-6), (SO101, 0.1)], ids=["intelbot5", "so101"])
def test_chain_basis_spans_the_rigid_body_model_the_generic_one_does_not(robot, chain):
    """Least squares on 6 000 random states, checked on 2 000 others: for intelbot5 the chain
    basis (angles and parallel sums, pairwise products) reproduces rnea to rounding; for the
    SO-101, whose roll link's inertia couples the roll with the base and the pitch chain in
    products of three angle functions, it misses by up to 3.2 % (measured); the generic basis
    misses by more than 1 % of some joint's spread on both (measured 51–106 %)."""
    train, test = states(robot, 6000, 1), states(robot, 2000, 2)
    errors = {}
    for kind in ("chain", "generic"):
        A = bases.basis(robot, train["q"], train["qd"], train["qdd"], kind)
        # Normal equations of the unit-norm columns with a ridge of 1e-12 of their mean diagonal (the basis
        # repeats columns: rank-deficient), by Cholesky: 7x faster than pivoted QR on these 3 213 columns, and
        # the same test errors (measured: intelbot5 1.3e-11 against QR's 1.4e-15; SO-101 3.18e-2 both)
        scale = np.sqrt((A ** 2).sum(axis=0))
        scale[scale == 0] = 1.0
        G = (A / scale).T @ (A / scale)
        factor = scipy.linalg.cho_factor(G + 1e-12 * np.trace(G) / len(G) * np.eye(len(G)))
        theta = scipy.linalg.cho_solve(factor, (A / scale).T @ train["tau"]) / scale[:, None]
        errors[kind] = nrmse(bases.basis(robot, test["q"], test["qd"], test["qdd"], kind) @ theta, test["tau"])
    assert errors["chain"].max() < chain, errors
    assert errors["generic"].max() > 0.01, errors


@pytest.mark.parametrize("kind", ["generic", "chain_linear"])
def test_drive_terms_follow_the_rigid_basis(kind):
    d = states(ROBOT, 9, 3)
    d["qd"][0, 2] = 0.0                                     # a joint at rest: no Coulomb friction
    X = bases.basis(ROBOT, d["q"], d["qd"], d["qdd"], f"{kind}_drives")
    rigid = bases.basis(ROBOT, d["q"], d["qd"], d["qdd"], kind)
    np.testing.assert_array_equal(X[:, :rigid.shape[1]], rigid)
    np.testing.assert_array_equal(X[:, rigid.shape[1]:], np.column_stack([d["qd"], np.sign(d["qd"])]))
    assert X[0, rigid.shape[1] + 5 + 2] == 0.0
    assert bases.basis_width(ROBOT, f"{kind}_drives") == bases.basis_width(ROBOT, kind) + 10


def test_only_the_drive_terms_hold_a_driven_arms_friction():
    """Rigid-body torques plus viscous and Coulomb friction (chapter 5's drives, without the
    breakaway): the chain basis with the drive terms reproduces them on other states to
    rounding; without them, a joint whose friction is comparable to its rigid torque is missed
    by a large share of its spread (measured: 2.3e-11 against 35 %)."""
    viscous, coulomb = np.array([0.08, 0.08, 0.06, 0.04, 0.04]), np.array([0.06, 0.06, 0.052, 0.04, 0.04])
    def driven(count, seed):
        d = states(ROBOT, count, seed)
        d["tau"] = d["tau"] + viscous * d["qd"] + coulomb * np.sign(d["qd"])
        return d
    train, test = driven(6000, 1), driven(2000, 2)
    errors = {}
    for kind in ("chain", "chain_drives"):
        A = bases.basis(ROBOT, train["q"], train["qd"], train["qdd"], kind)
        theta = scipy.linalg.lstsq(A, train["tau"], cond=1e-10, lapack_driver="gelsy")[0]
        errors[kind] = nrmse(bases.basis(ROBOT, test["q"], test["qd"], test["qdd"], kind) @ theta, test["tau"]).max()
    assert errors["chain_drives"] < 1e-6 and errors["chain"] > 0.05, errors


def test_bad_basis_is_refused():
    with pytest.raises(ValueError, match="basis must be one of generic, chain"):
        bases.basis(ROBOT, *np.zeros((3, 2, 5)), "fourier")
    with pytest.raises(ValueError, match="basis must be one of"):
        bases.basis_width(ROBOT, "fourier")


# -- LearnedID on the configuration's rules ----------------------------------------------------

def test_affine_input_sets_put_the_rules_over_the_configuration(trajectories):
    d = trajectories["val"]
    for inputs, width in (("affine", 5 + 356), ("affine_generic", 5 + 230), ("affine_drives", 5 + 356 + 10),
                          ("affine_generic_drives", 5 + 230 + 10)):
        X = id_features(ROBOT, d["q"], d["qd"], d["qdd"], inputs)
        assert all(x.shape == (len(d["q"]), width) for x in X)
        np.testing.assert_array_equal(X[0][:, :5], d["q"])


@pytest.fixture(scope="module")
def random_states():
    return {"train": states(ROBOT, 6000, 1), "val": states(ROBOT, 2000, 2)}


def test_rules_over_the_configuration_add_what_one_rule_lacks(random_states, tmp_path):
    """6 000 random states, the affine inputs: one rule (a linear map of the trigonometric
    terms) misses the products of angle functions the inertia needs; eight rules over q2..q4
    supply them. Measured on 2 000 other states, worst joint (the base): 0.52 → 0.055 NRMSE."""
    fits = {}
    v = random_states["val"]
    for name, n_mfs in (("one", 1), ("eight", [1, 2, 2, 2, 1])):
        model = LearnedID(inputs="affine", n_mfs=n_mfs, mf="gauss", epochs=1).fit(ROBOT, random_states["train"])
        fits[name] = nrmse(model.predict(v["q"], v["qd"], v["qdd"]), v["tau"])
    assert fits["eight"].max() < 0.2 * fits["one"].max(), fits
    assert [m.premise_inputs for m in model.models_] == [list(range(5))] * 5
    assert [m.rules_.shape for m in model.models_] == [(8, 5)] * 5
    model.save(tmp_path)
    loaded = LearnedID.load(tmp_path, ROBOT)
    np.testing.assert_array_equal(loaded.predict(v["q"], v["qd"], v["qdd"]), model.predict(v["q"], v["qd"], v["qdd"]))


def test_every_learned_inverse_dynamics_of_the_sweeps_has_its_tier():
    """The tiers of prior knowledge: a cell's tier follows from what it assumes of the arm."""
    from nfarm.learning.bases import TIERS, tier_of
    from nfarm.study.sweep import load_sweep

    seen = {}
    for name in ("id_comparison", "id_baselines"):
        for cell in load_sweep(f"params/sweeps/{name}.yaml").cells:
            seen.setdefault(tier_of(cell.params), set()).add(cell.params.get("inputs") or cell.params["learner"])
    assert seen[TIERS["structure"]] >= {"affine", "ridge"} and "affine_generic" in seen[TIERS["generic"]]
    assert seen[TIERS["identification"]] == {"regressor"}
    assert tier_of({"learner": "friction", "residual": True}) == TIERS["nominal"]
    assert tier_of({"learner": "identification", "residual": False}) == TIERS["identification"]
    assert tier_of({"inputs": "affine", "residual": True}) == TIERS["nominal"]
    assert tier_of({"learner": "kernel", "angles": "chain"}) == TIERS["structure"]
    assert tier_of({"learner": "kernel", "angles": "joints"}) == tier_of({"learner": "kernel"}) == TIERS["generic"]
    from nfarm.study.contest import id_tier
    contest = {}
    for cell in load_sweep("params/sweeps/id_contest.yaml").cells:
        contest.setdefault(id_tier(cell.params), set()).add(cell.params["learner"])
    assert contest[TIERS["structure"]] >= {"anfis", "ridge", "kernel", "boosting", "mlp"}, \
        "every rival of the structure-informed tier, with that tier's knowledge"
    assert contest[TIERS["generic"]] >= {"anfis", "ridge", "kernel", "boosting", "mlp"}
    # the measured arm's linear designs see every joint's friction terms (a rigid-body basis cannot hold friction)
    for cell in load_sweep("params/sweeps/id_contest.yaml").cells:
        design = (cell.params.get("options") or {}).get("inputs") or (cell.params.get("options") or {}).get("basis")
        if design is not None and design not in ("own", "all"):       # rules over q̇ learn friction themselves
            assert design.endswith("_drives"), cell.params
    with pytest.raises(ValueError, match="needs inputs or a learner"):
        tier_of({"basis": "chain"})
