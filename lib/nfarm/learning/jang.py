"""Jang's (1993) benchmark problems for ANFIS, and his error measures.

* :func:`sinc_data` — two-input sinc, 121 training pairs on an 11 × 11 grid over [−10, 10]²;
* :func:`three_input_data` — ``(1 + x^0.5 + y^−1 + z^−1.5)²``, 216 training points on the
  integer grid 1…6, 125 checking points on 1.5…5.5;
* :func:`mackey_glass` and :func:`mackey_glass_data` — the chaotic Mackey–Glass series and
  Jang's 4-input, 6-step-ahead prediction pairs (t = 118…1117, 500 to train, 500 to check).
"""

from __future__ import annotations

import numpy as np

__all__ = ["sinc_data", "three_input_data", "mackey_glass", "mackey_glass_data", "ape", "ndei",
           "rmse"]


def sinc_data(points: int = 11, span: float = 10.0, *, seed: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``z = sinc(x) · sinc(y)`` (sinc(x) = sin(x)/x) on a ``points × points`` grid over
    ``[−span, span]²`` (Jang's): ``X (points², 2)``, ``z``. With ``seed``, as many points
    drawn uniformly over the square instead (a data draw, for the spread of a result)."""
    if seed is None:
        g = np.linspace(-span, span, points)
        x, y = (a.ravel() for a in np.meshgrid(g, g, indexing="ij"))
    else:
        x, y = np.random.default_rng(seed).uniform(-span, span, size=(2, points * points))
    return np.column_stack([x, y]), np.sinc(x / np.pi) * np.sinc(y / np.pi)


def _three_input(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    X = np.array(np.meshgrid(values, values, values, indexing="ij")).reshape(3, -1).T
    x, y, z = X.T
    return X, (1 + x**0.5 + y**-1 + z**-1.5) ** 2


def three_input_data(*, seed: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``X_train (216, 3)``, ``y_train``, ``X_check (125, 3)``, ``y_check`` (Jang's grids). With
    ``seed``, the 216 training points are drawn uniformly over ``[1, 6]³`` instead (a data
    draw); the checking grid stays Jang's."""
    X_check, y_check = _three_input(np.arange(1.5, 6.0))
    if seed is None:
        return (*_three_input(np.arange(1.0, 7.0)), X_check, y_check)
    X = np.random.default_rng(seed).uniform(1.0, 6.0, size=(216, 3))
    x, y, z = X.T
    return X, (1 + x**0.5 + y**-1 + z**-1.5) ** 2, X_check, y_check


def mackey_glass(t_end: float = 1200.0, *, tau: float = 17.0, x0: float = 1.2, h: float = 0.1,
                 a: float = 0.2, b: float = 0.1, hold_delay: bool = False) -> np.ndarray:
    """``x(t)`` at t = 0, 1, …, t_end of ``ẋ = a x(t − τ) / (1 + x(t − τ)¹⁰) − b x(t)``,
    ``x(0) = x0``, ``x(t) = 0`` for t < 0, by fourth-order Runge–Kutta with step ``h``.

    The delayed value at each Runge–Kutta stage is interpolated linearly from the solution so
    far (τ is a whole number of steps, so only the half-step stages interpolate; before t = 0
    the history is 0, so the step that crosses t = τ sees 0 up to its end); with
    ``hold_delay`` it is held at its value at the start of the step instead, as some generators
    of Jang's data do — a cruder solution whose series drifts apart from the accurate one.
    """
    steps, delay = int(round(t_end / h)), int(round(tau / h))
    per_unit = int(round(1 / h))
    x = np.zeros(steps + 1)
    x[0] = x0
    f = lambda value, delayed: a * delayed / (1 + delayed**10) - b * value  # noqa: E731
    past = lambda k: x[k] if k >= 0 else 0.0  # noqa: E731  x at step k (0 before the start)
    for k in range(steps):
        # The history jumps from 0 to x0 at t = 0: the step that ends at t = τ sees 0 up to its
        # end (its last stage takes the left limit), the next one starts from x0.
        start, end = past(k - delay), (past(k + 1 - delay) if k + 1 > delay else 0.0)
        # Before t = 0 the history is exactly 0: the half step before the jump at t = τ is too.
        middle = 0.5 * (start + end) if k >= delay else 0.0
        if hold_delay:
            middle, end = start, start
        k1 = f(x[k], start)
        k2 = f(x[k] + 0.5 * h * k1, middle)
        k3 = f(x[k] + 0.5 * h * k2, middle)
        k4 = f(x[k] + h * k3, end)
        x[k + 1] = x[k] + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x[::per_unit]


def mackey_glass_data(series: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Jang's pairs ``[x(t−18), x(t−12), x(t−6), x(t)] → x(t+6)`` for t = 118…1117: the first
    500 to train, the next 500 to check."""
    x = mackey_glass() if series is None else series
    t = np.arange(118, 1118)
    X = np.column_stack([x[t - 18], x[t - 12], x[t - 6], x[t]])
    y = x[t + 6]
    return X[:500], y[:500], X[500:], y[500:]


def ape(target, output) -> float:
    """Average percentage error ``100/P · Σ |T − O| / |T|`` [%]."""
    target, output = np.asarray(target), np.asarray(output)
    return float(100 * np.mean(np.abs(target - output) / np.abs(target)))


def rmse(target, output) -> float:
    return float(np.sqrt(np.mean((np.asarray(target) - np.asarray(output)) ** 2)))


def ndei(target, output) -> float:
    """Non-dimensional error index: RMSE divided by the standard deviation of the target."""
    return rmse(target, output) / float(np.std(target))
