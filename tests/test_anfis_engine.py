"""The hybrid-learning engine (nfarm.learning.hybrid): fuzzy c-means against scikit-fuzzy, the
multiple-output training with shared premises, early stopping, and LearnedID's shared premises."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm.learning import hybrid
from nfarm.learning.anfis import ANFIS, fit_shared, load
from nfarm.learning.fuzzy import fuzzy_cmeans, grid_params


@pytest.mark.parametrize("c, seed", [(3, 0), (8, 1), (20, 2)])
def test_fuzzy_cmeans_is_scikit_fuzzys_iteration(c, seed):
    """The same start, update and stop as skfuzzy.cluster.cmeans: the same iterations, and
    centres and memberships equal to rounding (a fixed point reached from the same start)."""
    from skfuzzy.cluster import cmeans
    rng = np.random.default_rng(seed)
    data = np.concatenate([rng.normal(k, 0.3, (60, 3)) for k in range(4)])
    ref_centres, ref_u, _, _, _, ref_iterations, _ = cmeans(data.T, c, 2.0, error=1e-6, maxiter=500, seed=seed)
    centres, u, iterations = fuzzy_cmeans(data, c, tolerance=1e-6, max_iter=500, seed=seed)
    assert iterations == ref_iterations
    np.testing.assert_allclose(centres, ref_centres, rtol=0, atol=1e-12)
    np.testing.assert_allclose(u, ref_u, rtol=0, atol=1e-12)


def test_fuzzy_cmeans_leaves_numpys_global_random_state_alone():
    np.random.seed(123)
    expected = np.random.rand(3)
    np.random.seed(123)
    fuzzy_cmeans(np.random.default_rng(0).random((50, 2)), 3, seed=7)
    np.testing.assert_array_equal(np.random.rand(3), expected)


def _data(seed=0, N=300):
    rng = np.random.default_rng(seed)
    X = rng.uniform(-1, 1, (N, 3))
    Y = np.column_stack([np.sin(2 * X[:, 0]) + X[:, 1] ** 2, X[:, 0] * X[:, 2], np.cos(X[:, 1]) * X[:, 2]])
    return X, Y


@pytest.mark.parametrize("options", [dict(n_mfs=2), dict(partition="fcm", n_rules=5, mf="gauss"),
                                     dict(partition="subtractive", radius=0.6)])
def test_one_shared_output_is_the_ordinary_fit_bit_for_bit(options):
    X, Y = _data()
    alone = ANFIS(**options, epochs=4, random_state=0).fit(X, Y[:, 0], X[:100], Y[:100, 0])
    (shared,) = fit_shared(ANFIS(**options, epochs=4, random_state=0), X, Y[:, :1], X[:100], Y[:100, :1])
    np.testing.assert_array_equal(shared.consequents_, alone.consequents_)
    for a, b in zip(shared.mfs_, alone.mfs_):
        np.testing.assert_array_equal(a, b)
    assert shared.loss_curve_ == alone.loss_curve_ and shared.val_loss_curve_ == alone.val_loss_curve_


def test_shared_outputs_start_from_one_premise_part_and_least_squares_each():
    """Epoch 1 is least squares on the shared initial premises: each output's consequents are
    those of its own fit (a grid's premises do not depend on the output)."""
    X, Y = _data(1)
    models = fit_shared(ANFIS(n_mfs=2, epochs=1), X, Y)
    assert len(models) == 3
    for k, model in enumerate(models):
        alone = ANFIS(n_mfs=2, epochs=1).fit(X, Y[:, k])
        np.testing.assert_allclose(model.consequents_, alone.consequents_, rtol=1e-9, atol=1e-12)
        for a, b in zip(model.mfs_initial_, models[0].mfs_initial_):
            np.testing.assert_array_equal(a, b)


def test_each_output_is_weighed_by_its_spread():
    """The shared error weighs output k by 1/var(y_k): scaling one output by 1000 changes no
    premise and scales its consequents (to rounding)."""
    X, Y = _data(2)
    base = fit_shared(ANFIS(n_mfs=2, epochs=6, step_size=0.1), X, Y)
    scaled = fit_shared(ANFIS(n_mfs=2, epochs=6, step_size=0.1), X, Y * [1.0, 1000.0, 1.0])
    for a, b in zip(base, scaled):
        assert a.best_epoch_ == b.best_epoch_
        for p, q in zip(a.mfs_, b.mfs_):
            np.testing.assert_allclose(p, q, rtol=1e-9)
    np.testing.assert_allclose(scaled[1].consequents_, 1000 * base[1].consequents_, rtol=1e-6, atol=1e-9)


def test_the_shared_premise_gradient_is_that_of_the_weighed_error():
    """Every premise parameter: ∂(Σ_k c_k E_k)/∂θ by central differences, consequents fixed."""
    X, Y = _data(3, 120)
    mfs, rules = ANFIS(n_mfs=2, mf="gauss")._initial_structure(X, None, [2, 2, 2])
    w = hybrid.firing("gauss", X, mfs, rules)
    total, w_bar = hybrid.normalised(w)
    Xa = np.column_stack([X, np.ones(len(X))])
    theta = hybrid.least_squares(w_bar, Xa, Y).reshape(len(rules), 4, 3)
    c = hybrid.output_weights(Y)
    D = np.zeros_like(w)
    for k in range(3):
        f = hybrid.rule_outputs(Xa, theta[:, :, k])
        y_hat = (w_bar * f).sum(1)
        D += (-2.0 * c[k] * (Y[:, k] - y_hat) / total)[:, None] * (f - y_hat[:, None])
    analytic = hybrid.premise_gradient("gauss", X, mfs, rules, D * w)

    def error(m):
        return sum(c[k] * ((Y[:, k] - hybrid.network_outputs("gauss", X, X, m, rules, theta[:, :, k])) ** 2).sum()
                   for k in range(3))
    h = 1e-6
    for i, params in enumerate(mfs):
        for j, p in np.ndindex(params.shape):
            up, down = [q.copy() for q in mfs], [q.copy() for q in mfs]
            up[i][j, p] += h
            down[i][j, p] -= h
            assert analytic[i][j, p] == pytest.approx((error(up) - error(down)) / (2 * h), rel=1e-5, abs=1e-6)


def test_shared_models_are_ordinary_models_that_save_and_load(tmp_path):
    X, Y = _data(4)
    models = fit_shared(ANFIS(partition="fcm", n_rules=4, mf="gauss", epochs=3, random_state=0), X, Y, X[:50], Y[:50])
    for k, model in enumerate(models):
        assert model.best_epoch_ == int(np.argmin(model.val_loss_curve_))
        path = model.save(tmp_path / str(k))
        np.testing.assert_array_equal(load(path).predict(X), model.predict(X))


@pytest.mark.parametrize("Y, message", [(np.zeros(300), r"Y must have shape \(300, outputs\)"),
                                        (np.zeros((299, 2)), r"Y must have shape \(300, outputs\)"),
                                        (np.zeros((300, 0)), r"Y must have shape"),
                                        (np.full((300, 2), np.nan), "Y contains NaN")])
def test_fit_shared_refuses_bad_outputs_in_one_line(Y, message):
    X, _ = _data()
    with pytest.raises(ValueError, match=message):
        fit_shared(ANFIS(n_mfs=2), X, Y)


def test_fit_shared_refuses_validation_outputs_of_another_width():
    X, Y = _data()
    with pytest.raises(ValueError, match=r"Y_val must have shape \(50, 3\)"):
        fit_shared(ANFIS(n_mfs=2), X, Y, X[:50], Y[:50, :2])


@pytest.mark.parametrize("patience", [1, 2, 3])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_early_stopping_stops_patience_epochs_after_the_best_and_keeps_it(patience, seed):
    """A large step makes the validation error wander: training stops exactly ``patience`` epochs
    after the best one (or at the last epoch), and the model kept is that best epoch's."""
    rng = np.random.default_rng(seed)
    X = rng.uniform(-1, 1, (200, 2))
    y = np.sin(3 * X[:, 0]) * X[:, 1] + 0.05 * rng.normal(size=200)
    Xv = rng.uniform(-1, 1, (100, 2))
    yv = np.sin(3 * Xv[:, 0]) * Xv[:, 1]
    options = dict(n_mfs=3, epochs=40, step_size=0.5, step_increase=1.5)
    model = ANFIS(**options, patience=patience).fit(X, y, Xv, yv)
    full = ANFIS(**options).fit(X, y, Xv, yv)
    assert model.n_epochs_ == min(40, model.best_epoch_ + patience + 1)
    assert model.val_loss_curve_ == full.val_loss_curve_[:model.n_epochs_]         # the same training, cut
    assert model.best_epoch_ == int(np.argmin(model.val_loss_curve_))
    best = full.val_loss_curve_[:model.best_epoch_ + patience + 1]
    assert model.val_loss_curve_[model.best_epoch_] == min(best)


@pytest.mark.parametrize("patience, min_improvement", [(5, 0.02), (5, 0.05), (3, 0.1)])
def test_early_stopping_counts_only_falls_of_min_improvement(patience, min_improvement):
    """With ``min_improvement`` a fall of the validation error counts only if it takes it at
    least that share below its reference (Keras's min_delta, relative): training stops where the
    rule, replayed on the uncut run's curve, says — and never later than without it — and the
    epoch kept is still that of the least error."""
    rng = np.random.default_rng(7)
    X = rng.uniform(-1, 1, (300, 2))
    y = np.sin(3 * X[:, 0]) * X[:, 1]
    Xv = rng.uniform(-1, 1, (100, 2))
    yv = np.sin(3 * Xv[:, 0]) * Xv[:, 1]
    options = dict(n_mfs=3, mf="gauss", epochs=60, step_size=0.05)
    full = ANFIS(**options).fit(X, y, Xv, yv)

    def replayed(share):
        reference, since = np.inf, 0
        for epoch, error in enumerate(full.val_loss_curve_):
            if error < reference * (1 - share):
                reference, since = error, 0
            else:
                since += 1
                if since >= patience:
                    return epoch + 1
        return options["epochs"]
    expected = replayed(min_improvement)
    assert expected < replayed(0.0)                      # the threshold, not patience alone, stops this run
    model = ANFIS(**options, patience=patience, min_improvement=min_improvement).fit(X, y, Xv, yv)
    plain = ANFIS(**options, patience=patience).fit(X, y, Xv, yv)
    assert model.n_epochs_ == expected < plain.n_epochs_
    assert model.val_loss_curve_ == full.val_loss_curve_[:expected]
    assert model.best_epoch_ == int(np.argmin(model.val_loss_curve_))


@pytest.mark.parametrize("value", [-0.1, 1.0, float("nan"), "0.01"])
def test_min_improvement_must_be_a_share_below_one(value):
    X, Y = _data()
    with pytest.raises(ValueError, match="min_improvement"):
        ANFIS(n_mfs=2, patience=2, min_improvement=value).fit(X, Y[:, 0])


@pytest.mark.parametrize("patience", [0, -1, 1.5, True, "3"])
def test_patience_must_be_a_positive_integer(patience):
    X, Y = _data()
    with pytest.raises(ValueError, match="patience must be an integer >= 1 or None"):
        ANFIS(n_mfs=2, patience=patience).fit(X, Y[:, 0])


def test_memory_refusal_counts_every_output():
    X, Y = _data()
    one = ANFIS(n_mfs=2)._bytes_needed(300, 8, 3, 3, 1)
    three = ANFIS(n_mfs=2)._bytes_needed(300, 8, 3, 3, 3)
    assert three > one
    with pytest.raises(ValueError, match="over memory_budget"):
        fit_shared(ANFIS(n_mfs=2, memory_budget=(one + three) / 2), X, Y)


def test_the_firing_strengths_are_the_product_of_the_grades():
    """w_r = Π_i μ_i as an exp of summed log-grades, in blocks of samples: equal to the product
    of scikit-fuzzy's grades to rounding, for bell and Gaussian functions and any block size."""
    from nfarm.learning.fuzzy import mf_values
    rng = np.random.default_rng(5)
    X = rng.uniform(-1, 1, (257, 3))
    rules = np.array(np.meshgrid(range(2), range(3), range(2), indexing="ij")).reshape(3, -1).T
    for kind in ("gbell", "gauss"):
        mfs = [grid_params(kind, -1, 1, m) for m in (2, 3, 2)]
        expected = np.prod([mf_values(kind, X[:, i], mfs[i])[:, rules[:, i]] for i in range(3)], axis=0)
        for block in (1, 7, 2**16):
            hybrid.BLOCK_VALUES, saved = block, hybrid.BLOCK_VALUES
            try:
                np.testing.assert_allclose(hybrid.firing(kind, X, mfs, rules), expected, rtol=1e-13, atol=1e-300)
            finally:
                hybrid.BLOCK_VALUES = saved


# -- LearnedID with shared premises ---------------------------------------------------------------

@pytest.fixture(scope="module")
def id_split():
    from nfarm.infra.paths import PARAMS
    from nfarm.model.dynamics import rnea
    from nfarm.study.id_trajectories import random_trajectories
    from nfarm.study.study_files import load_study
    study = load_study(PARAMS / "studies" / "intelbot5.yaml")

    def split(count, seed):
        d = random_trajectories(study.robot, study.id, count, seed)
        d["tau"] = rnea(study.robot, d["q"], d["qd"], d["qdd"])
        return d
    return study.robot, split(6, 1), split(2, 2)


def test_learned_id_with_shared_premises_trains_one_premise_part(id_split, tmp_path):
    from nfarm.learning.learned_id import LearnedID
    robot, train, val = id_split
    options = dict(inputs="trig", partition="grid", n_mfs=[2] + [1] * 24, mf="gauss", epochs=3, random_state=0)
    shared = LearnedID(shared_premises=True, **options).fit(robot, train, val)
    alone = LearnedID(**options).fit(robot, train, val)
    for a in shared.models_[1:]:
        for p, q in zip(a.mfs_initial_, shared.models_[0].mfs_initial_):
            np.testing.assert_array_equal(p, q)
    # the first epoch (least squares on the shared initial premises) is each joint's own
    for a, b in zip(shared.models_, alone.models_):
        assert a.loss_curve_[0] == pytest.approx(b.loss_curve_[0], rel=1e-9)
    loaded = LearnedID.load(shared.save(tmp_path), robot)
    assert loaded.shared_premises is True
    np.testing.assert_array_equal(loaded.predict(val["q"], val["qd"], val["qdd"]),
                                  shared.predict(val["q"], val["qd"], val["qdd"]))


@pytest.mark.parametrize("kwargs, message", [
    (dict(inputs="own"), "shared_premises needs inputs every joint sees alike"),
    (dict(inputs="regressor"), "shared_premises needs inputs every joint sees alike"),
    (dict(inputs="trig", joint_options=[{"epochs": 2}, {}, {}, {}, {}]), "same ANFIS options for every joint"),
    (dict(inputs="trig", shared_premises="yes"), "shared_premises must be True or False"),
])
def test_learned_id_refuses_shared_premises_it_cannot_share(id_split, kwargs, message):
    from nfarm.learning.learned_id import LearnedID
    robot, train, _ = id_split
    kwargs = {"shared_premises": True, "n_mfs": 1, **kwargs}
    with pytest.raises(ValueError, match=message):
        LearnedID(**kwargs).fit(robot, train)


@pytest.mark.parametrize("shape", [(3000, 50), (120, 80)])
@pytest.mark.parametrize("outputs", [None, 3])
def test_the_orthogonal_fall_back_is_the_minimum_norm_solution(shape, outputs):
    """Rank-deficient designs (a repeated column, a sum of two): the fall-back's solution is the
    pseudo-inverse's (an independent SVD), tall designs through their QR alike. scipy's gelsy
    with its default cutoff (machine epsilon) keeps a direction of rounding here and returns
    coefficients of 1e13 with a larger residual."""
    rng = np.random.default_rng(sum(shape))
    A = rng.normal(size=shape)
    A[:, 5] = A[:, 6]
    A[:, 7] = A[:, 1] + A[:, 2]
    y = rng.normal(size=(shape[0],) if outputs is None else (shape[0], outputs))
    np.testing.assert_allclose(hybrid._orthogonal(A, y), np.linalg.pinv(A) @ y, rtol=0, atol=1e-10)


@pytest.mark.parametrize("N, R, d, k, block_rows", [(400, 40, 3, 1, None), (257, 64, 7, 2, 50), (90, 33, 5, 3, 1)])
def test_the_normal_equations_from_their_blocks_are_the_designs(N, R, d, k, block_rows):
    """kronecker_normal's AᵀA and AᵀY (d(d + 1)/2 symmetric R × R blocks, the off-diagonal ones
    by polarisation) against the formed design's, summed over blocks of samples or not, with
    inputs of either sign; and least_squares on a clustered rule base (which takes that path)
    solves the same equations as the formed design."""
    rng = np.random.default_rng(N + R)
    w = rng.random((N, R)) ** 4
    w_bar = w / w.sum(axis=1, keepdims=True)
    Xa = np.column_stack([rng.uniform(-1, 2, (N, d - 1)), np.ones(N)])
    Y = rng.normal(size=(N, k))
    A = hybrid._design(w_bar, Xa)
    G, b = hybrid.kronecker_normal(w_bar, Xa, Y, design_bytes=None if block_rows is None else 8 * R * block_rows)
    scale = np.abs(A.T @ A).max()
    np.testing.assert_allclose(G, A.T @ A, rtol=0, atol=1e-13 * scale)
    np.testing.assert_allclose(b, A.T @ Y, rtol=0, atol=1e-13 * np.abs(A.T @ Y).max())
    assert hybrid._kronecker(R, d) == (R >= 32)
    if hybrid._kronecker(R, d):
        theta = hybrid.least_squares(w_bar, Xa, Y, ridge=1e-10)
        direct = A.T @ A
        direct[np.diag_indices_from(direct)] += 1e-10 * np.trace(direct) / len(direct) + 1e-300
        expected = np.linalg.solve(direct, A.T @ Y)
        np.testing.assert_allclose(A @ theta, A @ expected, rtol=0, atol=1e-8)


def test_a_clustered_rule_base_forms_no_design():
    """The design buffer of a clustered rule base is empty (kronecker_normal needs none); a few
    rules over many inputs (the ID designs) keep theirs."""
    assert hybrid.design_buffer(20_000, 256, 7).size == 0
    assert hybrid.design_buffer(1000, 8, 358).shape == (1000, 8, 358)
