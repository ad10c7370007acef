"""ANFIS: gradients, hybrid learning on Jang's examples, persistence, conventions, bad input."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest

from nfarm.learning import jang
from nfarm.learning.anfis import ANFIS, ANFISMulti, ANFISWarning, load
from nfarm.infra.reading import ParamsError, with_content_digest
from nfarm.learning import hybrid
from nfarm.learning.fuzzy import mf_gradients, mf_rows, mf_values


@pytest.mark.parametrize("kind, params", [
    ("gbell", np.array([[1.5, 2.0, -1.0], [0.7, 1.3, 0.5], [2.0, 0.8, 3.0]])),
    ("gauss", np.array([[1.2, -1.0], [0.4, 0.5], [2.5, 3.0]])),
])
def test_membership_derivatives_match_central_differences(kind, params):
    x = np.linspace(-4, 6, 101)
    analytic = mf_gradients(kind, x, params, mf_values(kind, x, params))
    h = 1e-6
    for k in range(params.shape[0]):
        for p in range(params.shape[1]):
            up, down = params.copy(), params.copy()
            up[k, p] += h
            down[k, p] -= h
            numeric = (mf_values(kind, x, up)[:, k] - mf_values(kind, x, down)[:, k]) / (2 * h)
            np.testing.assert_allclose(analytic[:, k, p], numeric, atol=1e-7)


@pytest.mark.parametrize("mf", ["gbell", "gauss"])
@pytest.mark.parametrize("partition", ["grid", "fcm", "subtractive"])
def test_premise_gradient_matches_finite_differences_of_the_error(mf, partition):
    """Every premise parameter: ∂E/∂θ of the network (consequents fixed) by central differences."""
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, (80, 2))
    y = np.sin(2 * X[:, 0]) + X[:, 1] ** 2
    model = ANFIS(n_mfs=[2, 3], mf=mf, partition=partition, n_rules=3, radius=0.6, epochs=1,
                  random_state=0)
    mfs, rules = model._initial_structure(X, y, [2, 3])
    w = hybrid.firing(mf, X, mfs, rules)
    total, w_bar = hybrid.normalised(w)
    Xa = np.column_stack([X, np.ones(len(X))])
    theta = hybrid.least_squares(w_bar, Xa, y[:, None]).reshape(len(rules), 3)
    f = hybrid.rule_outputs(Xa, theta)
    y_hat = (w_bar * f).sum(1)
    D = (-2.0 * (y - y_hat) / total)[:, None] * (f - y_hat[:, None]) * w      # (∂E/∂w) ⊙ w
    analytic = hybrid.premise_gradient(mf, X, mfs, rules, D)
    error = lambda m: ((y - hybrid.network_outputs(mf, X, X, m, rules, theta)) ** 2).sum()  # noqa: E731
    h = 1e-6
    for i, params in enumerate(mfs):
        for k, p in np.ndindex(params.shape):
            up = [q.copy() for q in mfs]
            down = [q.copy() for q in mfs]
            up[i][k, p] += h
            down[i][k, p] -= h
            numeric = (error(up) - error(down)) / (2 * h)
            assert analytic[i][k, p] == pytest.approx(numeric, rel=1e-5, abs=1e-7), (i, k, p)


def test_hybrid_learning_lowers_the_training_error_on_sinc():
    X, z = jang.sinc_data()
    model = ANFIS(n_mfs=4, epochs=100).fit(X, z)
    assert len(model.rules_) == 16
    # Jang's 16-rule set-up: the least-squares start at 0.105 RMSE; after 100 epochs 0.036–0.049 over the last
    # ten (Jang's step oscillating; 0.034 after his 250, chapter 4): their mean below 0.045, the last below half
    # the start and below the 50th epoch's
    curve = np.asarray(model.loss_curve_)
    assert curve[0] == pytest.approx(0.105, abs=0.005)
    assert curve[-10:].mean() < 0.045 and curve[-1] < 0.5 * curve[0] and curve[-1] < curve[49]


def jang_step(step, errors, increase, decrease):
    """Jang's (1993) heuristic, written from the paper: the step after the training errors
    ``errors`` so far — × ``increase`` after four consecutive decreases, × ``decrease`` after
    two consecutive up–down alternations (the last five errors), else unchanged."""
    if len(errors) < 5:
        return step
    e = errors[-5:]
    moves = ["down" if b < a else "up" if b > a else "same" for a, b in zip(e, e[1:])]
    if moves == ["down"] * 4:
        return step * increase
    if moves in (["down", "up", "down", "up"], ["up", "down", "up", "down"]):
        return step * decrease
    return step


# Training errors of ten epochs, and the step each epoch uses, traced by hand from 0.01 (the
# rule reads the errors up to epoch k and sets the step of epoch k + 1): epochs 0–4 fall four
# times (epoch 5: ×1.1 → 0.011); 1–5 end in a rise and 2–6 break the alternation (epochs 6, 7:
# unchanged); 3–7 go down-up-down-up (epoch 8: ×0.9 → 0.0099); 4–8 up-down-up-down (epoch 9:
# ×0.9 → 0.00891).
TRACED_ERRORS = [5.0, 4.0, 3.0, 2.0, 1.0, 2.0, 1.0, 2.0, 1.0, 1.5]
TRACED_STEPS = [0.01, 0.01, 0.01, 0.01, 0.01, 0.011, 0.011, 0.011, 0.0099, 0.00891]


@pytest.mark.parametrize("errors, factor", [
    ([1.0, 0.9, 0.8, 0.7], 1.0),                    # fewer than five errors: no rule yet
    ([1.0, 0.9, 0.8, 0.7, 0.6], "increase"),        # four decreases
    ([0.1, 1.0, 0.9, 0.8, 0.7, 0.6], "increase"),   # only the last five count
    ([0.5, 1.0, 0.9, 0.8, 0.7], 1.0),               # a rise, then three decreases
    ([1.0, 0.9, 0.8, 0.7, 0.7], 1.0),               # an equal error is no decrease
    ([1.0, 0.8, 0.9, 0.7, 0.8], "decrease"),        # down, up, down, up
    ([0.8, 1.0, 0.9, 1.1, 0.7], "decrease"),        # up, down, up, down
    ([1.0, 0.8, 0.9, 0.7, 0.6], 1.0),               # down, up, down, down
    ([1.0, 0.8, 0.8, 0.7, 0.8], 1.0),               # an equal pair breaks the alternation
])
@pytest.mark.parametrize("increase, decrease", [(1.1, 0.9), (1.5, 0.25)])
def test_jang_step_size_rule_on_crafted_error_curves(errors, factor, increase, decrease):
    """The rule the module docstring states, driven by crafted training errors: × step_increase
    after four consecutive decreases, × step_decrease after two up–down alternations."""
    model = ANFIS(step_increase=increase, step_decrease=decrease)
    model.loss_curve_ = list(errors)
    factor = {"increase": increase, "decrease": decrease}.get(factor, factor)
    assert model._adapt_step(0.02) == 0.02 * factor


def test_jang_step_size_rule_follows_the_hand_traced_sequence():
    model, step, steps = ANFIS(), 0.01, []
    for k in range(len(TRACED_ERRORS)):
        steps.append(step)                          # the step used in epoch k
        model.loss_curve_ = TRACED_ERRORS[:k + 1]
        step = model._adapt_step(step)
    assert steps == pytest.approx(TRACED_STEPS, rel=1e-14)
    assert steps == pytest.approx([s for s in _replayed(TRACED_ERRORS, 0.01, 1.1, 0.9)], rel=1e-14)


def _replayed(errors, step, increase, decrease):
    """The step of each epoch by :func:`jang_step`, given the errors of the epochs before."""
    for k in range(len(errors)):
        yield step
        step = jang_step(step, errors[:k + 1], increase, decrease)


@pytest.mark.parametrize("step_size, increase, decrease", [(0.1, 1.1, 0.9), (0.3, 1.25, 0.5)])
def test_training_follows_jang_s_step_size_rule(step_size, increase, decrease):
    """On sinc, a step large enough to overshoot: the step of every epoch is the rule's on the
    training errors before it, and both the growth and the shrinking happen."""
    X, z = jang.sinc_data()
    model = ANFIS(n_mfs=4, epochs=60, step_size=step_size, step_increase=increase,
                  step_decrease=decrease).fit(X, z)
    expected = list(_replayed(model.loss_curve_, step_size, increase, decrease))
    assert model.step_size_curve_ == pytest.approx(expected, rel=1e-12)
    ratios = np.array(model.step_size_curve_[1:]) / np.array(model.step_size_curve_[:-1])
    assert (np.isclose(ratios, increase).sum() >= 3 and np.isclose(ratios, decrease).sum() >= 3), ratios


def test_jang_three_input_example_reaches_below_0_1_percent():
    X, y, Xc, yc = jang.three_input_data()
    model = ANFIS(n_mfs=2, epochs=200).fit(X, y)
    assert len(model.rules_) == 8
    assert jang.ape(y, model.predict(X)) < 0.1
    assert jang.ape(yc, model.predict(Xc)) < 1.5


def test_validation_keeps_the_best_epoch():
    X, y, Xc, yc = jang.three_input_data()
    model = ANFIS(n_mfs=2, epochs=30).fit(X, y, Xc, yc)
    assert len(model.val_loss_curve_) == model.n_epochs_ == 30
    assert model.best_epoch_ == int(np.argmin(model.val_loss_curve_))
    assert jang.rmse(yc, model.predict(Xc)) == pytest.approx(min(model.val_loss_curve_), rel=1e-9)


def test_error_goal_stops_early():
    X, y, *_ = jang.three_input_data()
    model = ANFIS(epochs=100, error_goal=1.0).fit(X, y)
    assert model.n_epochs_ < 100 and model.loss_curve_[-1] <= 1.0


def first_order_sugeno(X, bells, rules, theta):
    """Jang's five layers written out from the paper, sample by sample and rule by rule:
    bells ``μ = 1 / (1 + |(x − c)/a|^{2b})``, product firing, normalisation, ``f_r = p_r·x + r_r``."""
    out = []
    for x in X:
        w = [math.prod(1 / (1 + abs((x[i] - bells[i][k][2]) / bells[i][k][0]) ** (2 * bells[i][k][1]))
                       for i, k in enumerate(rule)) for rule in rules]
        f = [sum(p * v for p, v in zip(t[:-1], x)) + t[-1] for t in theta]
        out.append(sum(wr * fr for wr, fr in zip(w, f)) / sum(w))
    return np.array(out)


@pytest.mark.parametrize("solver", ["normal", "lstsq"])
def test_one_epoch_is_genfis1_s_grid_and_the_least_squares_consequents(solver):
    """After one epoch (no premise step yet) the model is MATLAB genfis1's grid on the data's
    range (bells of half width (hi − lo)/2(m − 1), slope 2, centres evenly spread: neighbours
    cross at 0.5) with the consequents that minimise the squared error, found here by an
    orthogonal least-squares solve of the layers written out (numpy's lstsq). Tolerance: the
    normal equations square the design's condition number (below 10³ here, so 10⁶) and add a
    ridge of 1e-12 of their mean diagonal, a relative error of at most ~10⁶ · (ε + 1e-12) ≈ 1e-6
    in the consequents' worst direction, far less in the predictions (measured 3.6e-10 with
    the normal equations, 5e-15 with lstsq)."""
    X, y, Xc, yc = jang.three_input_data()
    model = ANFIS(n_mfs=2, epochs=1, solver=solver).fit(X, y)
    bells = [[[2.5, 2.0, 1.0], [2.5, 2.0, 6.0]]] * 3           # inputs on [1, 6], two bells each
    for params in model.mfs_:
        np.testing.assert_array_equal(params, bells[0])
    rules = list(itertools.product(range(2), repeat=3))
    np.testing.assert_array_equal(model.rules_, rules)
    # The output is linear in the consequents: column j of the design is the output of the
    # network whose only non-zero consequent parameter is the j-th, set to 1.
    P = len(rules) * 4
    design = np.column_stack([first_order_sugeno(X, bells, rules, np.eye(P)[j].reshape(-1, 4))
                              for j in range(P)])
    assert np.linalg.cond(design) < 1e3
    theta = np.linalg.lstsq(design, y, rcond=None)[0].reshape(-1, 4)
    reference = first_order_sugeno(Xc, bells, rules, theta)
    np.testing.assert_allclose(model.predict(Xc), reference, rtol=1e-6)
    np.testing.assert_allclose(model.loss_curve_[0], np.sqrt(np.mean((design @ theta.ravel() - y) ** 2)),
                               rtol=1e-7)


@pytest.mark.parametrize("partition, extra", [("fcm", dict(n_rules=4)), ("subtractive", dict(radius=0.5))])
def test_clustering_partitions_learn(partition, extra):
    X, y, Xc, yc = jang.three_input_data()
    model = ANFIS(partition=partition, mf="gauss", epochs=30, random_state=1, **extra).fit(X, y)
    assert model.rules_.shape[1] == 3 and (model.rules_ == model.rules_[:, :1]).all()
    assert model.score(Xc, yc) > 0.95


def test_save_load_round_trip_is_bit_for_bit(tmp_path):
    X, y, Xc, yc = jang.three_input_data()
    model = ANFIS(n_mfs=[2, 3, 2], epochs=8, feature_names=["x", "y", "z"]).fit(X, y, Xc, yc)
    path = model.save(tmp_path / "m")
    assert path == tmp_path / "m" / "anfis.json" and not list((tmp_path / "m").glob("*.tmp*"))
    again = load(tmp_path / "m")
    np.testing.assert_array_equal(load(path).predict(Xc), model.predict(Xc))      # or the file itself
    np.testing.assert_array_equal(again.predict(Xc), model.predict(Xc))
    assert again.get_params() == model.get_params() | {"n_mfs": [2, 3, 2], "feature_names": ["x", "y", "z"]}
    assert again.loss_curve_ == model.loss_curve_


def test_determinism_with_random_state():
    X, y, *_ = jang.three_input_data()
    a = ANFIS(partition="fcm", n_rules=4, epochs=5, random_state=3).fit(X, y).predict(X)
    b = ANFIS(partition="fcm", n_rules=4, epochs=5, random_state=3).fit(X, y).predict(X)
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("seed", [0, 1])
def test_fcm_memberships_match_scikit_fuzzy_with_the_centres_held(seed):
    from skfuzzy.cluster import cmeans_predict
    from nfarm.learning.fuzzy import fcm_memberships
    rng = np.random.default_rng(seed)
    data, centres = rng.normal(size=(300, 4)), rng.normal(size=(6, 4))
    data[7] = centres[2]                                   # a sample on a centre belongs to it alone
    u = fcm_memberships(data, centres)
    assert u.shape == (6, 300) and np.allclose(u.sum(axis=0), 1.0)
    np.testing.assert_array_equal(u[:, 7], np.eye(6)[2])
    ref = cmeans_predict(np.delete(data, 7, axis=0).T, centres, 2.0, error=1e-12, maxiter=3, seed=seed)[0]
    np.testing.assert_allclose(np.delete(u, 7, axis=1), ref, rtol=1e-10, atol=1e-14)


def test_fcm_on_a_subsample_is_the_full_clustering_when_the_data_are_fewer():
    X, y, Xc, yc = jang.three_input_data()
    full = ANFIS(partition="fcm", n_rules=4, epochs=3, random_state=1, fcm_samples=None).fit(X, y)
    same = ANFIS(partition="fcm", n_rules=4, epochs=3, random_state=1, fcm_samples=len(X)).fit(X, y)
    np.testing.assert_array_equal(same.predict(Xc), full.predict(Xc))


def test_fcm_on_a_subsample_learns_as_well_as_on_all_samples():
    rng = np.random.default_rng(4)
    X = rng.uniform(-1, 1, size=(4000, 2))
    y = np.sin(2 * X[:, 0]) * np.cos(X[:, 1]) + 0.3 * X[:, 1] ** 2
    Xv = rng.uniform(-1, 1, size=(1000, 2))
    yv = np.sin(2 * Xv[:, 0]) * np.cos(Xv[:, 1]) + 0.3 * Xv[:, 1] ** 2
    errors = {}
    for samples in (None, 600):
        model = ANFIS(partition="fcm", n_rules=6, mf="gauss", epochs=5, random_state=0,
                      fcm_samples=samples).fit(X, y)
        errors[samples] = float(np.sqrt(np.mean((model.predict(Xv) - yv) ** 2)))
    assert errors[None] < 0.1 * yv.std() and errors[600] < 1.2 * errors[None]


@pytest.mark.parametrize("budget", [2e5, 3e4, 1.0])
def test_prediction_in_blocks_bounded_by_the_memory_budget_is_the_same(budget):
    X, y, Xc, yc = jang.three_input_data()
    model = ANFIS(n_mfs=[3, 3, 2], epochs=2).fit(X, y)
    whole = model.predict(Xc)
    model.set_params(memory_budget=budget)          # 18 rules: 2e5 → 28 rows a block, 1.0 → one row
    np.testing.assert_allclose(model.predict(Xc), whole, rtol=1e-13, atol=1e-15)


def test_estimator_conventions():
    model = ANFIS(n_mfs=3, epochs=7)
    params = model.get_params()
    assert params["n_mfs"] == 3 and params["epochs"] == 7
    clone = ANFIS(**params)
    assert clone.get_params() == params
    assert model.set_params(epochs=9) is model and model.epochs == 9
    assert not hasattr(model, "consequents_"), "__init__ only stores arguments"
    with pytest.raises(ValueError, match="unknown parameter 'epoch'"):
        model.set_params(epoch=3)
    from sklearn.base import clone as sk_clone         # scikit-learn is a dependency (the baselines)
    assert sk_clone(model).get_params() == model.get_params()


def test_describe_and_plot():
    X, y, *_ = jang.three_input_data()
    model = ANFIS(epochs=2, feature_names=["x", "y", "z"]).fit(X, y)
    text = model.describe()
    assert text.count("\n") == 7 and text.startswith("Rule 1: IF x is MF1 AND y is MF1 AND z is MF1 THEN y = ")
    fig = model.plot_mfs()
    assert len(fig.axes) == 3


def test_joint_curves_take_a_scale_per_joint_and_draw_the_noise():
    from nfarm.presentation.plotting import plot_joint_curves
    X, y, Xc, yc = jang.three_input_data()
    models = [ANFIS(epochs=3).fit(X, k * y, Xc, k * yc) for k in (1.0, 10.0)]
    fig = plot_joint_curves(models, ["a", "b"], scale=[2.0, 0.1], unit="%", quantity="NRMSE", symbol="τ",
                            noise=[0.5, 0.25])
    ax = fig.axes[0]
    lines = {line.get_label(): line for line in ax.get_lines()}
    np.testing.assert_allclose(lines["τ1 a"].get_ydata(), 2.0 * np.asarray(models[0].loss_curve_))
    np.testing.assert_allclose(lines["τ2 b"].get_ydata(), 0.1 * np.asarray(models[1].loss_curve_))
    assert [line.get_ydata()[0] for line in ax.get_lines() if line.get_linestyle() == ":" and len(line.get_ydata())] == [0.5, 0.25]
    assert ax.get_ylabel() == "NRMSE [%]"
    assert "sensor noise σ" in [t.get_text() for t in ax.get_legend().get_texts()]


def test_predicted_vs_true_shows_the_errors_at_their_own_scale():
    from nfarm.presentation.plotting import plot_predicted_vs_true
    rng = np.random.default_rng(0)
    q = rng.uniform(-1, 1, (500, 3))
    error = np.column_stack([np.zeros(500), 0.004 * rng.normal(size=500), np.zeros(500)])
    fig = plot_predicted_vs_true(q, q + error, ["a", "b", "c"])
    bottom = fig.axes[3:]
    np.testing.assert_allclose(bottom[1].get_lines()[0].get_ydata(), np.degrees(error[:, 1]), atol=1e-12)
    assert [t.get_text().startswith("exact to rounding") for ax in bottom for t in ax.texts] == [True, True]


def test_multi_output_fits_one_model_per_column(tmp_path):
    X, y, Xc, yc = jang.three_input_data()
    Y = np.column_stack([y, np.sqrt(y)])
    multi = ANFISMulti(n_mfs=2, epochs=5).fit(X, Y)
    assert len(multi.models_) == 2
    np.testing.assert_allclose(multi.predict(X)[:, 1], ANFIS(n_mfs=2, epochs=5).fit(X, np.sqrt(y)).predict(X))
    multi.save(tmp_path / "multi")
    np.testing.assert_array_equal(load(tmp_path / "multi").predict(Xc), multi.predict(Xc))
    with pytest.raises(ValueError, match=r"save takes a directory \(the model is written into it as "
                                         r"anfis.json\), got the file name '.*multi.json'"):
        multi.save(tmp_path / "multi.json")


X3, Y3, *_ = jang.three_input_data()


@pytest.mark.parametrize("args, kwargs, message", [
    ((np.r_[X3[:-1], [[np.nan, 1, 1]]], Y3), {}, r"X contains NaN or inf \(first in row 215\)"),
    ((X3, np.r_[Y3[:-1], np.inf]), {}, r"y contains NaN or inf"),
    ((X3, Y3[:-1]), {}, r"y must have shape \(216,\) to match X"),
    ((X3[:, 0], Y3), {}, r"X must be a 2-D array"),
    ((X3[::11], Y3[::11]), {}, r"20 samples are fewer than the 32 consequent parameters"),
    ((np.c_[X3, np.ones(216)], Y3), {}, r"input 3 \(x4\) is constant"),
    ((X3, Y3), dict(mf="triangle"), r"mf must be one of gbell, gauss"),
    ((X3, Y3), dict(partition="kmeans"), r"partition must be one of grid, fcm, subtractive"),
    ((X3, Y3), dict(n_mfs=[2, 2]), r"n_mfs must be an integer >= 1 or one per premise input \(3\)"),
    ((X3, Y3), dict(epochs=0), r"epochs must be an integer >= 1"),
    ((X3, Y3), dict(n_mfs=2.5), r"n_mfs must be an integer >= 1 or one per premise input \(3\), got 2.5"),
    ((X3, Y3), dict(premise_inputs=[0, 3]), r"premise_inputs must be None or distinct column indices in 0..2"),
    ((X3, Y3), dict(premise_inputs=[1, 1]), r"premise_inputs must be None or distinct column indices"),
    ((X3, Y3), dict(premise_inputs=[]), r"premise_inputs must be None or distinct column indices"),
    ((X3, Y3), dict(premise_inputs="01"), r"premise_inputs must be None or distinct column indices"),
    ((X3, Y3), dict(premise_inputs=[0, 2], n_mfs=[2, 2, 2]), r"one per premise input \(2\)"),
    ((X3, Y3), dict(partition="fcm"), r"partition 'fcm' needs n_rules \(an integer\) >= 2"),
    ((X3, Y3), dict(memory_budget=1e4), r"would need about .* GB, over memory_budget"),
    ((X3, Y3), dict(solver="qr"), r"solver must be one of normal, lstsq"),
    ((X3, Y3), dict(partition="fcm", n_rules=3, fcm_tolerance=0.0), r"fcm_tolerance must be a finite number > 0, got 0.0"),
    ((X3, Y3), dict(step_size=True), r"step_size must be a finite number > 0, got True"),
    ((X3, Y3), dict(ridge="0"), r"ridge must be a finite number >= 0, got '0'"),
    ((X3, Y3), dict(error_goal=float("nan")), r"error_goal must be a finite number >= 0, got nan"),
    ((X3, Y3), dict(epochs=True), r"epochs must be an integer >= 1, got True"),
    ((X3, Y3), dict(partition="fcm", n_rules=3, fcm_max_iter=0), r"fcm_max_iter must be an integer >= 1"),
    ((X3, Y3), dict(partition="fcm", n_rules=3, fcm_samples=1), r"fcm_samples must be an integer >= 2 or None, got 1"),
    ((X3, Y3), dict(partition="fcm", n_rules=3, fcm_samples=True), r"fcm_samples must be an integer >= 2 or None"),
    ((X3, Y3), dict(partition="fcm", n_rules=3, fcm_samples=500.0), r"fcm_samples must be an integer >= 2 or None"),
])
def test_bad_input_is_refused_before_any_work(args, kwargs, message):
    with pytest.raises(ValueError, match=message):
        ANFIS(**({"epochs": 1} | kwargs)).fit(*args)


def test_predict_checks():
    with pytest.raises(ValueError, match="not fitted yet"):
        ANFIS().predict(X3)
    model = ANFIS(epochs=1).fit(X3, Y3)
    with pytest.raises(ValueError, match="X has 2 inputs, the model was fitted with 3"):
        model.predict(X3[:, :2])


def _saved(tmp_path):
    model = ANFIS(epochs=2).fit(X3, Y3)
    return model, json.loads(json.dumps(model.to_dict()))


def _edit(data, path, value):
    *head, last = path
    for key in head:
        data = data[key]
    if value is _DELETE:
        del data[last]
    else:
        data[last] = value


_DELETE = object()


@pytest.mark.parametrize("path, value, message", [
    (("state",), _DELETE, r"x.json: state: required field is missing"),
    (("params", "learning_rate"), 0.1, r"x.json: params.learning_rate: unknown field"),
    (("params", "mf"), "gauss", r"x.json: state.mfs\[0\]: must be a N × 2 array of numbers"),
    (("state", "rules", 0, 1), -1, r"x.json: state.rules\[0\]\[1\]: must index one of input 1's "
                                   r"2 functions \(0..1\), got -1"),
    (("state", "rules", 3, 0), 2, r"state.rules\[3\]\[0\]: must index one of input 0's"),
    (("state", "consequents", 2, 0), None, r"state.consequents: must be a 8 × 4 array of numbers"),
    (("state", "consequents", 0), [1.0, 2.0], r"state.consequents: must be a 8 × 4 array"),
    (("state", "mfs", 1, 0, 0), -1.0, r"state.mfs\[1\]: must hold at least one gbell function "
                                      r"with positive widths"),
    (("state", "feature_names"), [], r"state.feature_names: must be a list of 1 to 10000 items"),
    (("state", "best_epoch"), 7, r"state.best_epoch: must be <= 1, got 7"),
    (("format",), "other", r"x.json: format: must be 'nfarm-anfis-1'"),
    (("params", "n_mfs"), 2.5, r"x.json: params: n_mfs must be an integer >= 1"),
])
def test_load_validates_an_edited_model(tmp_path, path, value, message):
    """A saved model is checked like a parameter file: every edit is one error naming the
    file and the field, never a silently different model."""
    _, data = _saved(tmp_path)
    _edit(data, path, value)
    (tmp_path / "x.json").write_text(json.dumps(with_content_digest(data)))     # an edit that re-hashes
    with pytest.raises(ParamsError, match=message):
        load(tmp_path / "x.json")


def test_load_refuses_nan_consequents(tmp_path):
    _, data = _saved(tmp_path)
    text = json.dumps(data).replace(str(data["state"]["consequents"][0][0]), "NaN", 1)
    (tmp_path / "x.json").write_text(text)
    with pytest.raises(ParamsError, match=r"x.json: NaN is not a number JSON allows"):
        load(tmp_path / "x.json")


@pytest.mark.parametrize("content, message", [
    ('{"format": "other"}', r"x.json: class: must be 'ANFIS' or 'ANFISMulti'"),
    ("[1, 2]", r"x.json: must be 'ANFIS' or 'ANFISMulti' \(an nfarm ANFIS model\), got \[1, 2\]"),
    ('{"format": "nfarm-anfis-1", "class": "ANFIS", "params": {}}', r"x.json: content_sha256: missing"),
    ('{"format": "nfarm-anfis-1", "class": "ANFISMulti", "params": {}, "models": [], "content_sha256": "x"}',
     r"x.json: content_sha256: does not match the file's content"),
    ("[" * 5000 + "]" * 5000, r"x.json: nested deeper than 32 levels"),
    ("{", r"x.json:1:2: not valid JSON"),
    (b"\x89PNG\r\n\x1a\n\x00\xff", r"x.json: not UTF-8 text \(byte 0"),
])
def test_load_refuses_other_files(tmp_path, content, message):
    path = tmp_path / "x.json"
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    with pytest.raises(ParamsError, match=message):
        load(path)


def test_load_refuses_special_files():
    with pytest.raises(ParamsError, match=r"/dev/zero: must be a regular file"):
        load("/dev/zero")


def test_predict_far_outside_the_data_warns():
    model = ANFIS(epochs=1, mf="gauss").fit(X3, Y3)     # Gaussians underflow to exactly 0
    with pytest.warns(ANFISWarning, match=r"1 of 2 inputs \(first: row 1\) fire no rule"):
        y = model.predict(np.array([X3[0], [1e3, 1e3, 1e3]]))
    assert y[1] == 0.0


def test_clustering_is_bounded_before_the_work():
    rng = np.random.default_rng(0)
    X = rng.random((5000, 2))
    with pytest.raises(ValueError, match=r"5000 samples are fewer than the 6000 consequent"):
        ANFIS(partition="fcm", n_rules=2000).fit(X, X.sum(1))
    with pytest.raises(ValueError, match=r"radius 0.001 finds more than \d+ clusters"):
        ANFIS(partition="subtractive", radius=1e-3).fit(X[:1500], X[:1500].sum(1))


def test_prediction_rows_of_bells_are_scikit_fuzzy_s_bit_for_bit():
    from skfuzzy import gbellmf
    rng = np.random.default_rng(5)
    x = rng.normal(size=500) * 3
    P = np.column_stack([rng.random(4) + 0.01, rng.random(4) * 4, rng.normal(size=4)])
    expected = gbellmf(x[None], P[:, 0, None], P[:, 1, None], P[:, 2, None])
    assert np.array_equal(mf_rows("gbell", x, P), expected)


@pytest.mark.parametrize("n_mfs", [[1, 3, 1, 2], [2, 2, 2, 1], [1, 1, 1, 1], [3, 1, 1, 1], [2, 3, 2, 2]])
def test_fast_grid_prediction_equals_the_training_path(n_mfs):
    rng = np.random.default_rng(6)
    X = rng.random((400, 4))
    y = np.sin(3 * X[:, 0]) + X[:, 1] * X[:, 3] - X[:, 2] ** 2
    model = ANFIS(n_mfs=n_mfs, epochs=3, random_state=0).fit(X, y)
    assert model._grid_sizes() == n_mfs
    slow = hybrid.network_outputs(model.mf, X, X, model.mfs_, model.rules_, model.consequents_)
    np.testing.assert_allclose(model.predict(X), slow, rtol=0, atol=1e-13)


@pytest.mark.parametrize("mf, partition", [("gbell", "grid"), ("gauss", "grid"), ("gauss", "fcm")])
def test_premise_inputs_equal_inputs_with_one_function(mf, partition):
    """Inputs outside the premises enter the consequents only: the same model as giving them
    one membership function (a common factor of every rule, cancelled by the normalisation)."""
    rng = np.random.default_rng(3)
    X = rng.random((300, 4))
    y = np.sin(3 * X[:, 0]) * X[:, 2] + X[:, 1] * X[:, 3]
    options = dict(mf=mf, partition=partition, epochs=4, random_state=0)
    if partition == "grid":
        full = ANFIS(n_mfs=[3, 1, 2, 1], **options).fit(X, y, X[:60], y[:60])
        part = ANFIS(n_mfs=[3, 2], premise_inputs=[0, 2], **options).fit(X, y, X[:60], y[:60])
        np.testing.assert_allclose(part.loss_curve_, full.loss_curve_, rtol=1e-9)
        np.testing.assert_allclose(part.predict(X), full.predict(X), atol=1e-9)
    part = ANFIS(n_mfs=2, premise_inputs=[2, 0], n_rules=3, **options).fit(X, y)
    assert part.rules_.shape[1] == 2 and part.consequents_.shape == (len(part.rules_), 5)
    assert [len(m) for m in part.mfs_] == ([2, 2] if partition == "grid" else [3, 3])
    # premises read their own columns: permuting the others changes only the consequents' inputs
    assert "IF x3 is MF1 AND x1 is MF1" in part.describe()
    again = ANFIS.from_dict(json.loads(json.dumps(part.to_dict())))
    np.testing.assert_array_equal(again.predict(X), part.predict(X))


def test_normal_equations_in_blocks_equal_the_whole(monkeypatch):
    """A design too large to form is summed over blocks of samples: the same consequents."""
    rng = np.random.default_rng(4)
    X = rng.random((500, 6))
    y = X[:, 0] * X[:, 1] + np.cos(2 * X[:, 2]) + 0.1 * X[:, 5]
    whole = ANFIS(n_mfs=2, premise_inputs=[0, 1, 2], epochs=3).fit(X, y)
    monkeypatch.setattr(hybrid, "DESIGN_BYTES", 8 * 56 * 37)     # 37 rows per block
    blocks = ANFIS(n_mfs=2, premise_inputs=[0, 1, 2], epochs=3).fit(X, y)
    np.testing.assert_allclose(blocks.consequents_, whole.consequents_, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(blocks.loss_curve_, whole.loss_curve_, rtol=1e-9)


def test_ill_conditioned_normal_equations_fall_back_to_an_orthogonal_solve():
    """A consequent input that repeats another makes AᵀA singular (no ridge here): the fit takes
    the orthogonal factorisation (no LinAlgWarning or error reaches the user) and equals
    solver="lstsq"."""
    import warnings
    rng = np.random.default_rng(5)
    X = rng.random((200, 2))
    X = np.column_stack([X, X[:, 1]])                       # the third input repeats the second
    y = np.sin(3 * X[:, 0]) + X[:, 1]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        normal = ANFIS(n_mfs=3, premise_inputs=[0], epochs=2, ridge=0.0).fit(X, y)
    lstsq = ANFIS(n_mfs=3, premise_inputs=[0], epochs=2, ridge=0.0, solver="lstsq").fit(X, y)
    np.testing.assert_allclose(normal.predict(X), lstsq.predict(X), atol=1e-9)


@pytest.mark.parametrize("seed", [0, 3])
def test_jang_data_draws_are_seeded_uniform_and_keep_the_checking_grid(seed):
    X, z = jang.sinc_data(seed=seed)
    assert X.shape == (121, 2) and np.all(np.abs(X) <= 10) and len(np.unique(X[:, 0])) == 121
    np.testing.assert_array_equal(X, jang.sinc_data(seed=seed)[0])
    np.testing.assert_allclose(z, np.sin(X[:, 0]) / X[:, 0] * np.sin(X[:, 1]) / X[:, 1])
    X3, y3, X3c, y3c = jang.three_input_data(seed=seed)
    grid = jang.three_input_data()
    assert X3.shape == (216, 3) and np.all((X3 >= 1) & (X3 <= 6))
    x, y, z = X3.T
    np.testing.assert_allclose(y3, (1 + np.sqrt(x) + 1 / y + z ** -1.5) ** 2, rtol=1e-14)   # Jang's formula
    np.testing.assert_array_equal(X3c, grid[2])
    np.testing.assert_array_equal(y3c, grid[3])
    assert not np.array_equal(X3, jang.three_input_data(seed=seed + 1)[0])


def test_jang_grids_are_his_training_and_checking_points():
    """Jang (1993), example 2: 216 training points on the integer grid 1…6 and 125 checking
    points on 1.5…5.5, of ``(1 + x^0.5 + y^−1 + z^−1.5)²``."""
    X, y, Xc, yc = jang.three_input_data()
    for points, target, values in ((X, y, [1, 2, 3, 4, 5, 6]), (Xc, yc, [1.5, 2.5, 3.5, 4.5, 5.5])):
        assert sorted(map(tuple, points)) == [(a, b, c) for a in values for b in values for c in values]
        a, b, c = points.T
        np.testing.assert_allclose(target, (1 + np.sqrt(a) + 1 / b + c ** -1.5) ** 2, rtol=1e-14)
    assert jang.three_input_data()[1][0] == 16.0                    # x = y = z = 1: (1 + 1 + 1 + 1)²


def test_fuzzy_c_means_stops_at_its_tolerance():
    """A looser tolerance stops the clustering sooner; the partition it starts from hardly moves."""
    X = np.random.default_rng(0).random((400, 3))
    y = np.sin(3 * X).sum(axis=1)
    tight = ANFIS(partition="fcm", n_rules=4, mf="gauss", epochs=1, fcm_tolerance=1e-9, random_state=0).fit(X, y)
    loose = ANFIS(partition="fcm", n_rules=4, mf="gauss", epochs=1, fcm_tolerance=1e-3, random_state=0).fit(X, y)
    one = ANFIS(partition="fcm", n_rules=4, mf="gauss", epochs=1, fcm_max_iter=1, random_state=0).fit(X, y)
    centres = lambda m: np.column_stack([p[:, 1] for p in m.mfs_initial_])   # noqa: E731 (gauss: sigma, centre)
    assert np.abs(centres(tight) - centres(loose)).max() < 1e-2 < np.abs(centres(tight) - centres(one)).max()


def test_options_after_partition_are_keyword_only():
    """Only ``n_mfs``, ``mf`` and ``partition`` are positional: a fourth value is refused rather
    than read as whichever of the other eighteen options comes next."""
    assert ANFIS(3, "gauss", "fcm", n_rules=4).get_params()["n_rules"] == 4
    with pytest.raises(TypeError, match="positional"):
        ANFIS(3, "gauss", "fcm", 4)
