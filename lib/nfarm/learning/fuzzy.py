"""Membership functions and fuzzy partitions for :mod:`nfarm.learning.anfis`.

Membership values come from scikit-fuzzy (``gbellmf``, ``gaussmf``); their parameter
derivatives, MATLAB-style initial grids, fuzzy c-means (scikit-fuzzy's ``cmeans`` iteration,
written for speed and checked against it) and Chiu's subtractive clustering are here.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.distance import cdist
from skfuzzy import gaussmf, gbellmf

__all__ = ["MF_TYPES", "mf_values", "mf_rows", "mf_gradients", "mf_log_gradients", "log_grades",
           "grid_params", "cluster_params", "fuzzy_cmeans", "fcm_memberships", "subtractive_clustering"]

MF_TYPES = ("gbell", "gauss")


def mf_values(kind: str, x: np.ndarray, params: np.ndarray) -> np.ndarray:
    """Membership grades ``(N, m)`` of ``x (N,)`` in ``m`` functions with ``params (m, p)``."""
    x = x[:, None]
    if kind == "gbell":
        return gbellmf(x, params[:, 0], params[:, 1], params[:, 2])
    return gaussmf(x, params[:, 1], params[:, 0])


def mf_rows(kind: str, x: np.ndarray, params: np.ndarray) -> np.ndarray:
    """The grades of :func:`mf_values` laid out as ``(m, N)``: each function's grades over the
    samples contiguous, so that the products built from them run over long rows."""
    if kind == "gbell":
        # scikit-fuzzy's ``1 / (1 + |(x − c)/a|^{2b})`` with the same operations in the same
        # order, in place: bit for bit its values, one temporary instead of five (the time
        # hardly changes: the power is most of it, about 7 ns per value here).
        a, b, c = params[:, 0, None], params[:, 1, None], params[:, 2, None]
        u = np.subtract(x[None, :], c)
        np.divide(u, a, out=u)
        np.abs(u, out=u)
        np.power(u, 2 * b, out=u)
        np.add(1.0, u, out=u)
        return np.divide(1.0, u, out=u)
    return gaussmf(x[None, :], params[:, 1, None], params[:, 0, None])


def mf_gradients(kind: str, x: np.ndarray, params: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """``∂μ/∂θ (N, m, p)`` for the parameters of :func:`mf_values` (``mu`` its values).

    Generalised bell, ``μ = 1 / (1 + |u|^{2b})`` with ``u = (x − c)/a`` and
    ``μ(1 − μ) = |u|^{2b} μ²``::

        ∂μ/∂a = 2b |u|^{2b} μ² / a,   ∂μ/∂b = −2 ln|u| · |u|^{2b} μ²,
        ∂μ/∂c = 2b sign(u) |u|^{2b−1} μ² / a            (all 0 where u = 0)

    Gaussian, ``μ = exp(−(x − c)² / 2σ²)``::

        ∂μ/∂σ = μ (x − c)² / σ³,   ∂μ/∂c = μ (x − c) / σ²
    """
    x = x[:, None]
    if kind == "gbell":
        a, b, c = params[:, 0], params[:, 1], params[:, 2]
        u = (x - c) / a
        au = np.abs(u)
        with np.errstate(divide="ignore", invalid="ignore"):
            powered = au ** (2 * b)
            mu2 = mu * mu
            d_a = 2 * b * powered * mu2 / a
            d_b = np.where(au > 0, -2 * np.log(np.where(au > 0, au, 1.0)) * powered * mu2, 0.0)
            d_c = np.where(au > 0, 2 * b * np.sign(u) * au ** (2 * b - 1) * mu2 / a, 0.0)
        return np.stack([d_a, d_b, d_c], axis=-1)
    sigma, c = params[:, 0], params[:, 1]
    diff = x - c
    return np.stack([mu * diff**2 / sigma**3, mu * diff / sigma**2], axis=-1)


def log_grades(kind: str, x: np.ndarray, params: np.ndarray) -> np.ndarray:
    """``log μ (N, m)`` of :func:`mf_values`: ``−(x − c)²/2σ²`` (Gaussian) or
    ``−log(1 + |(x − c)/a|^{2b})`` (bell), ``-inf`` where a grade underflows to 0. A rule's
    firing strength is then one ``exp`` of a sum instead of a product of ``exp``s (equal to
    rounding, ≈1e-16 relative)."""
    x = x[:, None]
    if kind == "gbell":
        a, b, c = params[:, 0], params[:, 1], params[:, 2]
        with np.errstate(over="ignore"):
            return -np.log1p(np.abs((x - c) / a) ** (2 * b))
    sigma, c = params[:, 0], params[:, 1]
    return -((x - c) ** 2) / (2 * sigma**2)


def mf_log_gradients(kind: str, x: np.ndarray, params: np.ndarray) -> np.ndarray:
    """``(∂μ/∂θ) / μ (N, m, p)``: the derivatives of :func:`mf_gradients` divided by the grade,
    finite where the grade underflows.

    A rule's firing strength ``w_r = Π_i μ_i`` then has ``∂w_r/∂θ_i = w_r · (∂μ_i/∂θ_i)/μ_i``:
    the premise gradient needs no product of the other inputs' grades. Gaussian:
    ``((x − c)²/σ³, (x − c)/σ²)``; bell, with ``u = (x − c)/a`` and ``|u|^{2b} μ = 1 − μ``:
    ``(2b(1 − μ)/a, −2 ln|u| (1 − μ), 2b sign(u) |u|^{2b−1} μ / a)`` (0 where ``u = 0``). The
    bell's grades are scikit-fuzzy's ``gbellmf`` (the same operations, so the same bits), with
    ``|u|^{2b}`` overflowing quietly to a grade of 0 far from the centre."""
    if kind == "gbell":
        a, b, c = params[:, 0], params[:, 1], params[:, 2]
        u = (x[:, None] - c) / a
        au = np.abs(u)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            mu = 1. / (1. + au ** (2 * b))
            rest = 1.0 - mu
            d_a = 2 * b * rest / a
            d_b = np.where(au > 0, -2 * np.log(np.where(au > 0, au, 1.0)) * rest, 0.0)
            d_c = np.where(au > 0, 2 * b * np.sign(u) * au ** (2 * b - 1) * mu / a, 0.0)
        return np.stack([d_a, d_b, d_c], axis=-1)
    sigma, c = params[:, 0], params[:, 1]
    diff = x[:, None] - c
    return np.stack([diff**2 / sigma**3, diff / sigma**2], axis=-1)


def grid_params(kind: str, lo: float, hi: float, m: int) -> np.ndarray:
    """MATLAB ``genfis1``: ``m`` functions evenly over ``[lo, hi]``, neighbours crossing at 0.5."""
    centres = np.linspace(lo, hi, m) if m > 1 else np.array([(lo + hi) / 2])
    half = (hi - lo) / (2 * (m - 1)) if m > 1 else (hi - lo) / 2
    if kind == "gbell":
        return np.column_stack([np.full(m, half), np.full(m, 2.0), centres])
    return np.column_stack([np.full(m, half / math.sqrt(2 * math.log(2))), centres])


def cluster_params(kind: str, centres: np.ndarray, sigmas: np.ndarray) -> np.ndarray:
    """One function per cluster: Gaussian ``(σ, c)``, or the bell with the same half width."""
    if kind == "gauss":
        return np.column_stack([sigmas, centres])
    return np.column_stack([sigmas * math.sqrt(2 * math.log(2)), np.full_like(sigmas, 2.0), centres])


def fuzzy_cmeans(data: np.ndarray, c: int, *, m: float = 2.0, tolerance: float = 1e-3,
                 max_iter: int = 1000, seed: int | None = None) -> tuple[np.ndarray, np.ndarray, int]:
    """Fuzzy c-means (Bezdek 1981) of ``data (N, d)`` into ``c`` clusters: centres ``(c, d)``,
    memberships ``u (c, N)`` and the iterations run.

    scikit-fuzzy's ``cmeans`` (0.5) step for step — the same random start (NumPy's legacy
    generator seeded with ``seed``: ``rand(c, N)``, columns normalised), the same update

        v_i = Σ_j u_ij^m x_j / Σ_j u_ij^m,    u_ij = d_ij^(−2/(m−1)) / Σ_k d_kj^(−2/(m−1)),

    and the same stop (the membership matrix changing by less than ``tolerance`` in Frobenius
    norm, or ``max_iter`` iterations) — computed on squared distances from one matrix product,
    without its rescaling and renormalising of each column (which cancel), and with the
    distances floored at machine epsilon times a bound of the largest instead of each column's
    largest: equal to its results to rounding (``tests/test_anfis_engine.py``), several times
    faster (``benchmarks/bench_anfis_train.py``), and without touching NumPy's global random
    state.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> data = np.concatenate([rng.normal(0, 0.1, (50, 2)), rng.normal(1, 0.1, (50, 2))])
        >>> centres, u, iterations = fuzzy_cmeans(data, 2, seed=0)
        >>> bool(np.abs(np.sort(centres[:, 0]) - [0.0, 1.0]).max() < 0.05), u.shape, iterations < 1000
        (True, (2, 100), True)
    """
    eps = np.finfo(float).eps
    data = np.asarray(data, dtype=float)
    N = len(data)
    u = np.random.RandomState(seed).rand(c, N)
    u = np.fmax(u / u.sum(axis=0, keepdims=True), eps)
    x2 = (data * data).sum(axis=1)
    # ‖x − v‖² = ‖x‖² − 2 v·x + ‖v‖² as one matrix product [−2v, 1, ‖v‖²] · [x; ‖x‖²; 1]
    # (written out, eight passes over the c × N distances per iteration were most of the time).
    right = np.concatenate([data.T, x2[None], np.ones((1, N))])              # (d + 2, N)
    iterations = 0
    while iterations < max_iter:
        u_old = u
        um = np.fmax(u_old, eps)                    # u's columns sum to 1: no renormalising
        um = np.multiply(um, um, out=um) if m == 2.0 else um**m
        centres = (um @ data) / um.sum(axis=1)[:, None]
        v2 = (centres * centres).sum(axis=1)
        left = np.column_stack([-2.0 * centres, np.ones(c), v2])
        d2 = left @ right
        # scikit-fuzzy floors distances at eps and at eps times the column's largest; the
        # largest is bounded by 2 (max ‖x‖² + max ‖v‖²), which saves a pass.
        np.maximum(d2, eps * eps * max(1.0, 2.0 * (x2.max() + v2.max())), out=d2)
        inv = np.reciprocal(d2, out=d2) if m == 2.0 else d2**power
        u = inv / inv.sum(axis=0, keepdims=True)
        iterations += 1
        if np.linalg.norm(u - u_old) < tolerance:
            break
    return centres, u, iterations


def fcm_memberships(data: np.ndarray, centres: np.ndarray, m: float = 2.0) -> np.ndarray:
    """Fuzzy c-means memberships ``u (c, N)`` of ``data (N, d)`` in fixed ``centres (c, d)``:
    ``u_ij = 1 / Σ_k (‖x_j − v_i‖ / ‖x_j − v_k‖)^(2/(m−1))`` (Bezdek 1981, the update of
    scikit-fuzzy's ``cmeans`` and ``cmeans_predict`` with the centres held). A sample on a
    centre belongs to it alone."""
    d2 = ((data[None, :, :] - centres[:, None, :]) ** 2).sum(axis=2)         # (c, N)
    on_centre = d2 <= np.finfo(float).tiny
    inv = np.where(on_centre, 0.0, 1.0 / np.where(on_centre, 1.0, d2)) ** (1.0 / (m - 1.0))
    u = inv / inv.sum(axis=0, keepdims=True).clip(min=np.finfo(float).tiny)
    hit = on_centre.any(axis=0)
    if hit.any():
        u[:, hit] = on_centre[:, hit] / on_centre[:, hit].sum(axis=0)
    return u


def subtractive_clustering(data: np.ndarray, radius: float, *, squash: float = 1.25,
                           accept: float = 0.5, reject: float = 0.15, block: int = 2048,
                           max_centres: int | None = None) -> np.ndarray | None:
    """Cluster centres by Chiu's (1994) subtractive clustering of ``data (N, d)``, scaled to
    the unit hypercube: potentials ``P_i = Σ_j exp(−4‖x_i − x_j‖²/r_a²)``, the highest taken as
    a centre and its influence (radius ``squash · r_a``) subtracted, with Chiu's accept/reject
    thresholds. Returns centres ``(k, d)`` in data units, or ``None`` as soon as more than
    ``max_centres`` are found (a tiny radius would otherwise make every point a centre, at
    O(N) work each). Memory O(N · block)."""
    lo, span = data.min(axis=0), np.ptp(data, axis=0)
    z = (data - lo) / np.where(span > 0, span, 1.0)
    alpha, beta = 4.0 / radius**2, 4.0 / (squash * radius) ** 2
    potential = np.empty(len(z))
    rows = max(1, min(block, (1 << 22) // max(len(z), 1)))       # ≤ 32 MB of distances
    for start in range(0, len(z), rows):
        d2 = cdist(z[start:start + rows], z, "sqeuclidean")
        potential[start:start + rows] = np.exp(-alpha * d2).sum(1)
    limit = len(z) if max_centres is None else min(len(z), max_centres)
    centres = np.empty((limit + 1, z.shape[1]))
    k_found, first = 0, potential.max()
    while True:
        k = int(np.argmax(potential))
        p = potential[k]
        if p > accept * first:
            pass
        elif p < reject * first:
            break
        else:
            d_min = np.sqrt(((centres[:k_found] - z[k]) ** 2).sum(1).min())
            if d_min / radius + p / first < 1.0:
                potential[k] = 0.0
                continue
        centres[k_found] = z[k]
        k_found += 1
        if k_found > limit:                     # only when max_centres < len(z)
            return None
        potential -= p * np.exp(-beta * ((z - z[k]) ** 2).sum(1))
        if k_found >= len(z) or potential.max() <= 0:
            break
    return centres[:k_found] * np.where(span > 0, span, 1.0) + lo
