"""ANFIS training time per epoch on Jang's examples and on a model of the dissertation's IK
shape (7 inputs, 2 functions each, 128 rules, 10 000 samples), next to ``anfis-toolbox``
(hybrid optimiser, bell functions, the same rule bases and epochs) when the optional `bench`
extra is installed, with the error each reaches.

Target (issue 5): ≥ 10× faster per epoch than anfis-toolbox (about 7.7 ms per epoch on the
three-input example and 37 ms on Mackey–Glass on this kind of machine).
"""

from __future__ import annotations

import time

import numpy as np

from common import seconds_per_call  # noqa: F401  (sets the allocator like `make bench`)
from nfarm.learning import jang
from nfarm.learning.anfis import ANFIS
from nfarm.presentation.tables import Table


def problems():
    X, z = jang.sinc_data()
    yield "sinc, 16 rules", X, z, None, None, 4, 100, "rmse"
    X, y, Xc, yc = jang.three_input_data()
    yield "three-input, 8 rules", X, y, Xc, yc, 2, 200, "ape"
    X, y, Xc, yc = jang.mackey_glass_data()
    yield "Mackey–Glass, 16 rules", X, y, Xc, yc, 2, 100, "ndei"
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, (12_000, 7))
    y = np.sin(X @ rng.normal(size=7)) + 0.1 * (X**2).sum(1)
    yield "7 inputs, 128 rules, 10 000 samples", X[:10_000], y[:10_000], X[10_000:], y[10_000:], 2, 3, "rmse"


def measure(fit_predict, X, y, Xc, yc, epochs, metric):
    start = time.perf_counter()
    predict = fit_predict()
    ms = (time.perf_counter() - start) / epochs * 1e3
    Xe, ye = (X, y) if Xc is None else (Xc, yc)
    error = {"rmse": jang.rmse, "ape": jang.ape, "ndei": jang.ndei}[metric](ye, predict(Xe))
    return ms, f"{metric.upper()} {'train' if Xc is None else 'check'} {error:.4g}"


def main() -> None:
    try:
        from anfis_toolbox import ANFISRegressor
    except ImportError:
        ANFISRegressor = None
    rows = []
    for name, X, y, Xc, yc, n_mfs, epochs, metric in problems():
        ours = lambda: ANFIS(n_mfs=n_mfs, epochs=epochs).fit(X, y).predict  # noqa: E731
        ms, error = measure(ours, X, y, Xc, yc, epochs, metric)
        other_ms, other_error, ratio = "", "not installed: .venv/bin/pip install -e '.[bench]'", ""
        if ANFISRegressor is not None:
            theirs = lambda: ANFISRegressor(n_mfs=n_mfs, mf_type="bell", optimizer="hybrid",  # noqa: E731
                                            epochs=epochs, random_state=0).fit(X, y).predict
            other_ms, other_error = measure(theirs, X, y, Xc, yc, epochs, metric)
            ratio = other_ms / ms
        rows.append([name, epochs, ms, error, other_ms, other_error, ratio])
    print(Table(["problem", "epochs", "nfarm ms/epoch", "nfarm error", "anfis-toolbox ms/epoch",
                 "anfis-toolbox error", "speed-up"], rows,
                floatfmt=["", "", ".3f", "", ".3f", "", ".1f"]).to_markdown())


if __name__ == "__main__":
    main()
