"""ANFIS training on the study's own shapes: today's engine (:mod:`nfarm.learning.hybrid`) against
the engine before issue 40 (:mod:`engine_before`, read from the repository's history), fitting the
same data in the same run, one BLAS thread each (as a sweep cell trains).

Shapes:

* **learned IK at its deployment size** — intelbot5's 20 000 training poses in the arm's plane
  (the chosen encoding), the elbow joint, fuzzy c-means rules (16, 32, 64, 128), Gaussian
  functions, the learned-IK contest's ridge on the least squares (``IK_RIDGE``, as
  ``params/sweeps/ik_contest.yaml`` trains), validated on the 5 000 validation poses; and the
  128-rule shape once more at the engine's default ridge, whose ill-conditioned epochs take the
  orthogonal fall-back (the column "fall-backs" counts them, per engine);
* **model-free ID** — intelbot5's ``affine`` input set (rules over q, 357 consequent inputs), the
  five joints' models: every 16th training state for 3 epochs (chapter 6's cells), and **all**
  156 413 training states for one epoch; today's engine trains the joints with shared premises
  (:func:`nfarm.learning.anfis.fit_shared`: one factorisation per epoch for all five);
* **Mackey–Glass** — Jang's 500 / 500 series, 16 grid rules, 100 epochs.

Columns: seconds per fit and per epoch (the fit less its initial rule base, over the epochs),
the speed-up, peak memory (tracemalloc: NumPy's
allocations), the error each reaches, how many least-squares steps took the orthogonal fall-back
(IK rows), and the largest difference between the two engines'
predictions. Beside that difference, the same for the *old* engine fitted on inputs moved by one
unit in the last place: the hybrid rule's normal equations are ill-conditioned (a Gaussian
rule base of many rules), so a rounding change anywhere moves the trained model by about that
much — the scale on which the two engines can be compared. Then where one IK fit's time goes,
per phase, in each engine; and the learned-IK contest's least-squares step at its own shapes,
its normal equations from the formed design against their blocks
(:func:`nfarm.learning.hybrid.kronecker_normal`, which the engine takes for clustered rule bases).

Targets (issue 40, on 2 cores): IK ≥ 3× per epoch and per fit; the ID design's models ≥ 3×
for the same epochs at equal or better validation error; peak memory ≤ 2 GB for the ID design on
all training states; ``bench_anfis.py``'s comparison with anfis-toolbox stays ≥ 10×.
About 6 minutes on one core.
"""

from __future__ import annotations

import sys
import time
import tracemalloc
from contextlib import contextmanager

import numpy as np
import scipy.linalg
from threadpoolctl import threadpool_limits

import common  # noqa: F401  (sets sys.path like `make bench`)
import engine_before
from nfarm.infra.paths import PARAMS
from nfarm.learning import hybrid, jang, learned_id
from nfarm.learning.anfis import ANFIS, fit_shared
from nfarm.learning.encoding import PoseEncoder
from nfarm.presentation.tables import Table
from nfarm.study import datasets
from nfarm.study.study_files import load_study

IK_RULES = (16, 32, 64, 128)
IK_JOINT = 2                  # the elbow: q1 and q5 are near-linear maps of the arm-plane inputs
IK_EPOCHS = 5
#: The learned-IK contest's relative ridge on the normal equations (params/sweeps/ik_contest.yaml).
IK_RIDGE = 1e-8


@contextmanager
def measured():
    """Wall seconds and peak bytes of what runs inside: ``with measured() as m: …; m["s"], m["peak"]``."""
    result = {}
    tracemalloc.start()
    tracemalloc.reset_peak()
    start = time.perf_counter()
    try:
        yield result
    finally:
        result["s"] = time.perf_counter() - start
        result["peak"] = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()


def study_data(arm: str = "intelbot5"):
    study = load_study(PARAMS / "studies" / f"{arm}.yaml")
    datasets.build_datasets(study)
    directory = datasets.dataset_dir(study)
    return study, {name: datasets.load(directory / f"{name}.npz", study.robot, study)
                   for name in ("ik_train", "ik_val", "ik_test", "id_train", "id_val")}


def ik_rows(old, study, data):
    encoder = PoseEncoder(encoding="arm_plane", max_out_of_plane=np.radians(0.5))
    X = encoder.fit_transform(study.robot, data["ik_train"]["T"])
    Xv, Xt = encoder.transform(data["ik_val"]["T"]), encoder.transform(data["ik_test"]["T"])
    y, yv = data["ik_train"]["q"][:, IK_JOINT], data["ik_val"]["q"][:, IK_JOINT]
    rows = []
    for rules, ridge in [(r, IK_RIDGE) for r in IK_RULES] + [(128, 1e-12)]:
        options = dict(partition="fcm", n_rules=rules, mf="gauss", ridge=ridge, random_state=0)
        fits = {}
        for name, cls in (("before", old.ANFIS), ("today", ANFIS)):
            phases = Phases()
            undo = phases.wrap(cls, "_initial_structure", "init")
            try:
                with measured() as full, orthogonal_calls() as calls:
                    model = cls(**options, epochs=IK_EPOCHS).fit(X, y, Xv, yv)
            finally:
                undo()
            epoch = (full["s"] - phases.seconds["init"]) / model.n_epochs_     # the epochs alone
            fits[name] = (full["s"], epoch, full["peak"], model, calls["n"])
        sensitivity = ""
        if rules == 64:
            nudged = old.ANFIS(**options, epochs=IK_EPOCHS).fit(np.nextafter(X, np.inf), y, Xv, yv)
            sensitivity = f"{np.abs(nudged.predict(Xt) - fits['before'][3].predict(Xt)).max():.2g}"
        rows.append(_row(f"IK, {rules} rules, ridge {ridge:.0e}, 20 000 poses", IK_EPOCHS, fits,
                         lambda m: f"val {np.degrees(m.val_loss_curve_[m.best_epoch_]):.3f}°",
                         np.abs(fits["today"][3].predict(Xt) - fits["before"][3].predict(Xt)).max(),
                         sensitivity))
    return rows


@contextmanager
def orthogonal_calls():
    """How many least-squares solutions by orthogonal factorisation (``scipy.linalg.lstsq``, the
    fall-back of both engines' normal equations) run inside: ``with orthogonal_calls() as c: …; c["n"]``."""
    count, original = {"n": 0}, scipy.linalg.lstsq

    def counted(*args, **kwargs):
        count["n"] += 1
        return original(*args, **kwargs)
    scipy.linalg.lstsq = counted
    try:
        yield count
    finally:
        scipy.linalg.lstsq = original


def _row(name, epochs, fits, error, difference, sensitivity):
    (t_old, e_old, m_old, old, *f_old), (t_new, e_new, m_new, new, *f_new) = fits["before"], fits["today"]
    fallbacks = f"{f_old[0]} / {f_new[0]}" if f_old else ""
    return [name, epochs, t_old, t_new, t_old / t_new, e_old, e_new, e_old / e_new,
            m_old / 2**20, m_new / 2**20, error(old), error(new), fallbacks, f"{difference:.2g}", sensitivity]


def id_rows(old, study, data):
    robot = study.robot
    val = {k: data["id_val"][k] for k in ("q", "qd", "qdd", "tau")}
    rows = []
    for stride, epochs in ((16, 3), (1, 1)):
        train = {k: data["id_train"][k][::stride] for k in ("q", "qd", "qdd", "tau")}
        fits = {}
        for name, cls, shared in (("before", old.ANFIS, False), ("today", ANFIS, True)):
            learned_id.ANFIS = cls                                  # the engine the joints train with
            model = learned_id.LearnedID(inputs="affine", partition="grid", n_mfs=[1, 2, 2, 2, 1], mf="gauss",
                                         epochs=epochs, shared_premises=shared, random_state=0)
            with measured() as fit:
                model.fit(robot, train, val)
            seconds = sum(model.fit_seconds_)                       # the models, not the features
            fits[name] = (seconds, seconds / epochs, fit["peak"], model)
        learned_id.ANFIS = ANFIS
        spread = val["tau"].std(axis=0)

        def worst(model):
            nrmse = [m.val_loss_curve_[m.best_epoch_] / s for m, s in zip(model.models_, spread)]
            return f"val worst {100 * max(nrmse):.3f} % (" + ", ".join(f"{100 * e:.3f}" for e in nrmse) + ")"
        q = val["q"][:2000]
        difference = np.abs(fits["today"][3].predict(q, val["qd"][:2000], val["qdd"][:2000])
                            - fits["before"][3].predict(q, val["qd"][:2000], val["qdd"][:2000])).max()
        rows.append(_row(f"ID affine, 5 joints, {len(train['q'])} states", epochs, fits, worst,
                         difference, ""))
    return rows


def mackey_glass_row(old):
    X, y, Xc, yc = jang.mackey_glass_data()
    fits = {}
    for name, cls in (("before", old.ANFIS), ("today", ANFIS)):
        start = time.perf_counter()
        for _ in range(5):
            with measured() as fit:
                model = cls(n_mfs=2, epochs=100).fit(X, y)
        seconds = (time.perf_counter() - start) / 5
        fits[name] = (seconds, seconds / 100, fit["peak"], model)
    return _row("Mackey–Glass, 16 rules, 500 samples", 100, fits,
                lambda m: f"NDEI check {jang.ndei(yc, m.predict(Xc)):.4g}",
                np.abs(fits["today"][3].predict(Xc) - fits["before"][3].predict(Xc)).max(), "")


class Phases:
    """Exclusive wall time per phase of functions wrapped with :meth:`wrap` (a phase called
    inside another counts only for itself)."""

    def __init__(self):
        self.seconds, self._stack = {}, []

    def wrap(self, owner, name, phase):
        original = getattr(owner, name)

        def timed(*args, **kwargs):
            start = time.perf_counter()
            self._stack.append(0.0)
            try:
                return original(*args, **kwargs)
            finally:
                inner = self._stack.pop()
                elapsed = time.perf_counter() - start
                self.seconds[phase] = self.seconds.get(phase, 0.0) + elapsed - inner
                if self._stack:
                    self._stack[-1] += elapsed
        setattr(owner, name, timed)
        return lambda: setattr(owner, name, original)


def phase_table(old, study, data):
    encoder = PoseEncoder(encoding="arm_plane", max_out_of_plane=np.radians(0.5))
    X = encoder.fit_transform(study.robot, data["ik_train"]["T"])
    Xv = encoder.transform(data["ik_val"]["T"])
    y, yv = data["ik_train"]["q"][:, IK_JOINT], data["ik_val"]["q"][:, IK_JOINT]
    options = dict(partition="fcm", n_rules=64, mf="gauss", random_state=0, epochs=10)
    plans = {
        "before": (old.ANFIS, [(old.ANFIS, "_initial_structure", "initial rules (fuzzy c-means)"),
                               (old.ANFIS, "_layers", "firing strengths"),
                               (old.ANFIS, "_consequents", "least squares (design, AᵀA, Cholesky)"),
                               (old.ANFIS, "_premise_gradient", "premise gradient"),
                               (old.ANFIS, "_predict_with", "validation error")]),
        "today": (ANFIS, [(ANFIS, "_initial_structure", "initial rules (fuzzy c-means)"),
                          (hybrid, "firing", "firing strengths"),
                          (hybrid, "least_squares", "least squares (normal equations, Cholesky)"),
                          (hybrid, "premise_gradient", "premise gradient"),
                          (hybrid, "_outputs", "validation error")]),
    }
    spent = {}
    for name, (cls, wraps) in plans.items():
        phases = Phases()
        undo = [phases.wrap(*w) for w in wraps]
        start = time.perf_counter()
        try:
            cls(**options).fit(X, y, Xv, yv)
        finally:
            for u in undo:
                u()
        total = time.perf_counter() - start
        phases.seconds["other"] = total - sum(phases.seconds.values())
        spent[name] = (phases.seconds, total)
    names = [w[2] for w in plans["today"][1]] + ["other"]
    rows = [[p, spent["before"][0].get(p, 0.0), 100 * spent["before"][0].get(p, 0.0) / spent["before"][1],
             spent["today"][0].get(p, 0.0), 100 * spent["today"][0].get(p, 0.0) / spent["today"][1]] for p in names]
    rows.append(["whole fit", spent["before"][1], 100.0, spent["today"][1], 100.0])
    return Table(["phase (IK, 64 rules, 10 epochs)", "before s", "before %", "today s", "today %"], rows,
                 floatfmt=["", ".2f", ".0f", ".2f", ".0f"])


def normal_table(study, data):
    """The learned-IK contest's least-squares step at its own shapes (the pitch joints' shared
    model: 6 arm-plane inputs and a constant, 2 outputs; fuzzy c-means rules on a quarter of the
    training poses and on all of them): the normal equations from the formed design
    (``AᵀA`` of ``N × R·7``) against :func:`nfarm.learning.hybrid.kronecker_normal` (28 blocks of
    ``R × R``), the same firing strengths, in the same run (the least time of three; the peak
    memory of one); the largest difference of the
    normal matrices relative to its largest entry, and of the solved consequents' fitted values
    (metres of no unit: radians of the joints)."""
    encoder = PoseEncoder(encoding="arm_plane", max_out_of_plane=np.radians(0.5))
    X_all = encoder.fit_transform(study.robot, data["ik_train"]["T"])
    lo, span = X_all.min(axis=0), np.ptp(X_all, axis=0)
    X_all = (X_all - lo) / np.where(span > 0, span, 1.0)
    Y_all = data["ik_train"]["q"][:, 1:3]
    rows = []
    for N, R in [(len(X_all) // 4, 128), (len(X_all) // 4, 512), (len(X_all), 64), (len(X_all), 128), (len(X_all), 256)]:
        X, Y = X_all[:N], Y_all[:N]
        mfs, rules = ANFIS(partition="fcm", n_rules=R, mf="gauss", random_state=0)._initial_structure(X, Y, None)
        _, w_bar = hybrid.normalised(hybrid.firing("gauss", X, mfs, rules))
        Xa = np.column_stack([X, np.ones(N)])
        def formed_normal():
            A = hybrid._design(w_bar, Xa)
            return A.T @ A, A.T @ Y
        seconds = {}
        for name, run in (("formed", formed_normal), ("blocks", lambda: hybrid.kronecker_normal(w_bar, Xa, Y))):
            with measured() as peak:                     # the peak of one run; the least time of three (no tracing)
                result = run()
            times = []
            for _ in range(3):
                start = time.perf_counter()
                run()
                times.append(time.perf_counter() - start)
            seconds[name] = (min(times), peak["peak"], result)
        (G_formed, b_formed), (G, b) = seconds["formed"][2], seconds["blocks"][2]
        formed, blocks = ({"s": seconds[k][0], "peak": seconds[k][1]} for k in ("formed", "blocks"))
        theta = [scipy.linalg.solve(g + 1e-8 * np.trace(g) / len(g) * np.eye(len(g)), r, assume_a="pos")
                 for g, r in ((G_formed, b_formed), (G, b))]
        fitted = [hybrid._design(w_bar[:2000], Xa[:2000]) @ t for t in theta]
        rows.append([f"{N:,} poses, {R} rules", formed["s"], blocks["s"], formed["s"] / blocks["s"],
                     formed["peak"] / 2**20, blocks["peak"] / 2**20,
                     f"{np.abs(G - G_formed).max() / np.abs(G_formed).max():.1e}",
                     f"{np.abs(fitted[1] - fitted[0]).max():.1e}"])
    return Table(["IK least squares (7 consequent inputs, 2 outputs)", "formed design s", "blocks s", "×",
                  "formed MiB", "blocks MiB", "max |ΔAᵀA| / max AᵀA", "max |Δ fitted| (first 2 000 poses)"], rows,
                 floatfmt=["", ".3f", ".3f", ".2f", ".0f", ".0f", "", ""])


def main() -> None:
    try:
        old = engine_before.load()
    except RuntimeError as exc:
        print(f"bench_anfis_train: {exc}", file=sys.stderr)
        sys.exit(1)
    with threadpool_limits(1):
        study, data = study_data()
        rows = [mackey_glass_row(old), *ik_rows(old, study, data), *id_rows(old, study, data)]
        phases = phase_table(old, study, data)
        normal = normal_table(study, data)
    print(Table(["shape", "epochs", "before s/fit", "today s/fit", "fit ×", "before s/epoch",
                 "today s/epoch", "epoch ×", "before peak MiB", "today peak MiB", "before error",
                 "today error", "fall-backs before / today", "max |Δ prediction|",
                 "before vs before, inputs ±1 ulp"], rows,
                floatfmt=["", "", ".2f", ".2f", ".1f", ".3f", ".3f", ".1f", ".0f", ".0f", "", "", "", "", ""]).to_markdown())
    print()
    print(phases.to_markdown())
    print()
    print(normal.to_markdown())


if __name__ == "__main__":
    main()
