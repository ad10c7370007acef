"""Jang's hybrid learning rule (Jang 1993), the training engine of :class:`nfarm.learning.anfis.ANFIS`:
for one output, or for several outputs that share their premises.

Once per epoch over the whole batch: **forward**, the premise (membership) parameters fixed,
every output is linear in its consequents, found by least squares; **backward**, the
consequents fixed, the premise parameters take one gradient step of length k
(``Δθ = −k ∇E / ‖∇E‖``); the step size k grows by ``increase`` after four consecutive
decreases of the training error and shrinks by ``decrease`` after two consecutive up–down
alternations (:func:`adapted_step`). Each output keeps the epoch of its least validation error
(MATLAB's ``chkFIS``); with ``patience`` training stops once that error has not fallen for so
many epochs — by at least ``min_improvement`` of its least value, when that is given (early
stopping: "epochs to convergence" costs only the epochs needed).

**Several outputs, one premise part** (a multiple-output ANFIS, Jang, Sun & Mizutani 1997,
§12.4): the outputs' rules share their membership functions; each output has its own
consequents. The least-squares step then has one design ``A`` for every output: one normal
matrix ``AᵀA`` and one Cholesky factorisation serve them all (their right-hand sides are the
columns of ``AᵀY``), which is where a model with hundreds of consequent inputs spends its time.
The premise gradient is that of ``E = Σ_k c_k E_k`` with ``c_k = 1 / var(y_k)`` (every output
weighed by its own spread, so a large torque does not drown a small one).

**Where the time goes, and what this module does about it** (measured by
``benchmarks/bench_anfis_train.py`` against the engine before it, in the same run):

* firing strengths ``w (N, R)`` as one ``exp`` of a sum of log-grades (Gaussian and bell
  functions alike, :func:`nfarm.learning.fuzzy.log_grades`) instead of a product of ``n``
  arrays of ``exp``s, and no ``(n, N, R)`` stack of factors;
* the premise gradient from ``∂w_r/∂θ_i = w_r · (∂μ_i/∂θ_i)/μ_i``
  (:func:`nfarm.learning.fuzzy.mf_log_gradients`): no prefix and suffix products over the
  inputs, and for clustered rules (one function per rule and input) no ``R × R`` gather; for
  Gaussian functions the sums over the samples are matrix products;
* the consequents' design built into one reused buffer, its normal matrix by BLAS's
  symmetric rank-k update (what NumPy's ``A.T @ A`` calls), solved by Cholesky with a tiny
  ridge and a rank-revealing fall-back where ill-conditioned (:func:`least_squares`); for a
  clustered rule base (hundreds of rules, a few inputs: learned IK) no design at all, the
  normal matrix from its ``d(d + 1)/2`` distinct ``R × R`` blocks (:func:`kronecker_normal`,
  about half the operations);
* the validation error from the firing strengths and one matrix product, not a second pass
  through the training layers.

Everything is vectorised over samples and rules; memory is ``O(N · R · (k + 7))`` plus one
block of the design (at most :data:`DESIGN_BYTES`) and the ``P × P`` normal matrix.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from ..infra.limits import check_time
from .fuzzy import log_grades, mf_log_gradients

__all__ = ["Options", "Output", "firing", "normalised", "least_squares", "kronecker_normal", "design_buffer", "rule_outputs", "premise_gradient",
           "adapted_step", "keep_valid", "network_outputs", "output_weights", "train", "DESIGN_BYTES", "BLOCK_VALUES"]

#: Firing strengths computed at a time (512 kB): a block's temporaries stay in the cache.
BLOCK_VALUES = 2**16

#: Bytes a block of the consequents' design may take: larger designs have their normal
#: equations summed over blocks of samples (memory bounded whatever the number of samples).
DESIGN_BYTES = 256 * 2**20


@dataclass(frozen=True)
class Options:
    """What the hybrid rule needs of an :class:`nfarm.learning.anfis.ANFIS`'s parameters."""

    mf: str
    epochs: int
    step_size: float
    step_increase: float
    step_decrease: float
    error_goal: float
    solver: str
    ridge: float
    patience: int | None = None
    min_improvement: float = 0.0
    progress: bool = False


@dataclass
class Output:
    """One output's training: its premises and consequents ``(R, n + 1)`` at its best epoch,
    its training and validation RMSE per epoch."""

    mfs: list[np.ndarray]
    consequents: np.ndarray
    best_epoch: int
    loss_curve: list[float] = field(default_factory=list)
    val_loss_curve: list[float] = field(default_factory=list)


def _identity(rules: np.ndarray, i: int, m: int) -> bool:
    """Whether rule r uses function r of input i (clustered rules: one function per rule)."""
    return m == len(rules) and np.array_equal(rules[:, i], np.arange(len(rules)))


def firing(kind: str, Xp: np.ndarray, mfs: Sequence[np.ndarray], rules: np.ndarray) -> np.ndarray:
    """Firing strengths ``w (N, R)`` of premise inputs ``Xp (N, n_p)``:
    ``w_r = Π_i μ_{i, rules[r, i]}(x_i) = exp Σ_i log μ_{i, rules[r, i]}``, summed over blocks
    of samples that stay in the processor's cache (:data:`BLOCK_VALUES` strengths each).

    Example:
        >>> from nfarm.learning.fuzzy import grid_params
        >>> mfs = [grid_params("gauss", 0.0, 1.0, 2)] * 2      # functions at 0 and 1, 1/16 at the other
        >>> rules = np.array([[0, 0], [0, 1], [1, 0], [1, 1]])
        >>> firing("gauss", np.array([[0.0, 1.0]]), mfs, rules).round(3)
        array([[0.062, 1.   , 0.004, 0.062]])
    """
    N, R = len(Xp), len(rules)
    w = np.empty((N, R))
    gathered = [None if _identity(rules, i, len(params)) else rules[:, i] for i, params in enumerate(mfs)]
    rows = max(1, BLOCK_VALUES // R)
    for start in range(0, N, rows):
        log_w = w[start:start + rows]
        for i, (params, take) in enumerate(zip(mfs, gathered)):
            z = log_grades(kind, Xp[start:start + rows, i], params)         # (rows, m_i)
            if take is not None:
                z = z[:, take]
            if i == 0:
                log_w[...] = z
            else:
                log_w += z
        np.exp(log_w, out=log_w)
    return w


def normalised(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Total firing ``(N,)`` and normalised strengths ``w̄ = w / Σ_r w_r`` (0 where none fires)."""
    total = w.sum(axis=1)
    return total, w / np.where(total > 0, total, 1.0)[:, None]


def _design(w_bar: np.ndarray, Xa: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """The consequents' design ``A (N, R·(n + 1))``: ``w̄_r · [x, 1]``, into ``out`` if given."""
    N, R = w_bar.shape
    out = np.empty((N, R, Xa.shape[1])) if out is None else out[:N]
    np.multiply(w_bar[:, :, None], Xa[:, None, :], out=out)
    return out.reshape(N, -1)


def least_squares(w_bar: np.ndarray, Xa: np.ndarray, Y: np.ndarray, *, solver: str = "normal",
                  ridge: float = 1e-12, design_bytes: int | None = None,
                  buffer: np.ndarray | None = None) -> np.ndarray:
    """The consequents ``Θ (R·(n + 1), k)`` minimising ``‖A Θ − Y‖`` for the design ``A`` of
    :func:`_design` and outputs ``Y (N, k)``: the normal equations ``(AᵀA + δI) Θ = AᵀY``
    (``δ = ridge · tr(AᵀA)/P``) by Cholesky, summed over blocks of at most ``design_bytes``
    (default :data:`DESIGN_BYTES`) — for a rule base of at least as many rules as consequent
    inputs, block by block of the rules without forming the design (:func:`kronecker_normal`);
    where they are ill-conditioned (scipy's ``LinAlgWarning``: reciprocal condition below
    machine precision) or not positive definite, the rank-revealing QR solution (``gelsy``)
    instead — the squared condition of the normal equations would lose every digit.
    ``solver="lstsq"`` always takes the orthogonal factorisation of the whole design.
    ``buffer`` (from :func:`design_buffer`) holds the design's block, reused from epoch to
    epoch."""
    N, R = w_bar.shape
    P = R * Xa.shape[1]
    limit = DESIGN_BYTES if design_bytes is None else design_bytes
    rows = max(1, limit // (8 * P))
    vector = Y.shape[1] == 1
    y = Y[:, 0] if vector else Y
    if solver != "lstsq" and _kronecker(R, Xa.shape[1]):
        G, b = kronecker_normal(w_bar, Xa, Y, design_bytes=limit)
        theta = _solve_normal(G, b[:, 0] if vector else b, lambda: _orthogonal(G, b[:, 0] if vector else b, N), ridge)
    elif solver == "lstsq" or N <= rows:
        A = _design(w_bar, Xa, buffer if buffer is not None and len(buffer) >= N else None)
        if solver == "lstsq":
            theta = _orthogonal(A, y)
        else:
            theta = _solve_normal(A.T @ A, A.T @ y, lambda: _orthogonal(A, y), ridge)
    else:
        G, b = np.zeros((P, P)), np.zeros((P,) + y.shape[1:])
        if buffer is None or len(buffer) < rows:
            buffer = np.empty((rows, R, Xa.shape[1]))
        for start in range(0, N, rows):
            A = _design(w_bar[start:start + rows], Xa[start:start + rows], buffer)
            G += A.T @ A
            b += A.T @ y[start:start + rows]
        theta = _solve_normal(G, b, lambda: _orthogonal(G, b, N), ridge)
    return theta[:, None] if vector else theta


def _kronecker(R: int, d: int) -> bool:
    """Whether :func:`least_squares` sums the normal equations by :func:`kronecker_normal`: for
    at least as many rules as consequent inputs (a clustered rule base), where its
    ``d(d + 1)/2`` updates of ``R × R`` matrices are fewer operations than one of ``(R·d)²``
    at BLAS speed (``benchmarks/bench_anfis_train.py``); a few rules over hundreds of inputs
    (the ID designs) form the design."""
    return R >= max(d, 32)


def kronecker_normal(w_bar: np.ndarray, Xa: np.ndarray, Y: np.ndarray, *,
                     design_bytes: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The normal equations ``AᵀA (P, P)`` and ``AᵀY (P, k)`` of the consequents' design
    ``A = w̄ ⊙ [x, 1]`` (:func:`_design`, ``P = R·d``) without forming ``A``.

    Entry ``((r, i), (s, j))`` of ``AᵀA`` is ``M_ij[r, s] = Σ_n w̄_nr w̄_ns x_ni x_nj``: the
    ``d × d`` grid of ``R × R`` blocks ``M_ij = w̄ᵀ diag(x_i x_j) w̄`` has ``M_ij = M_ji`` and
    every block symmetric, so ``d(d + 1)/2`` of them make the whole matrix. Each is a
    symmetric rank-``N`` update (BLAS ``syrk``, what ``B.T @ B`` calls) of ``w̄`` scaled by a
    non-negative column: ``M_ii`` by ``|x_i|``, and by polarisation
    ``M_ij = (S_ij − M_ii − M_jj)/2`` with ``S_ij`` scaled by ``|x_i + x_j|`` —
    ``N R² d(d + 1)/4`` multiply–adds against ``N R² d²/2`` for ``AᵀA``, and no ``N × P``
    design in memory (blocks of at most ``design_bytes`` of ``w̄``'s rows). The polarisation
    rounds each block to within a few units of ``Σ_n w̄_nr w̄_ns (x_ni² + x_nj²)``: of the
    order of the design's own rounding for inputs of comparable scale (they are scaled to
    ``[0, 1]``).

    Example:
        >>> rng = np.random.default_rng(0)
        >>> w_bar, Xa, Y = rng.random((50, 4)), np.column_stack([rng.random((50, 2)), np.ones(50)]), rng.random((50, 1))
        >>> A = _design(w_bar, Xa)
        >>> G, b = kronecker_normal(w_bar, Xa, Y)
        >>> bool(np.allclose(G, A.T @ A, rtol=1e-13, atol=1e-13) and np.allclose(b, A.T @ Y))
        True
    """
    N, R = w_bar.shape
    d, k = Xa.shape[1], Y.shape[1]
    rows = max(1, (DESIGN_BYTES if design_bytes is None else design_bytes) // (8 * R))
    G, b = np.zeros((R, d, R, d)), np.zeros((R, d, k))
    B = np.empty((min(N, rows), R))
    for start in range(0, N, rows):
        w, x, y = w_bar[start:start + rows], Xa[start:start + rows], Y[start:start + rows]
        scaled = B[:len(w)]
        squares = []
        for i in range(d):
            np.multiply(w, np.abs(x[:, i, None]), out=scaled)
            squares.append(scaled.T @ scaled)
            G[:, i, :, i] += squares[i]
        for i in range(d):
            for j in range(i + 1, d):
                np.multiply(w, np.abs(x[:, i] + x[:, j])[:, None], out=scaled)
                M = scaled.T @ scaled
                M -= squares[i]
                M -= squares[j]
                M *= 0.5
                G[:, i, :, j] += M
                G[:, j, :, i] += M
        b += (w.T @ (x[:, :, None] * y[:, None, :]).reshape(len(w), d * k)).reshape(R, d, k)
    return G.reshape(R * d, R * d), b.reshape(R * d, k)


def design_buffer(N: int, R: int, d: int, *, solver: str = "normal",
                  design_bytes: int | None = None) -> np.ndarray:
    """Room for the design block :func:`least_squares` builds for ``N`` samples, ``R`` rules
    and ``d`` consequent inputs (with the constant); none where it forms no design
    (:func:`kronecker_normal`)."""
    if solver != "lstsq" and _kronecker(R, d):
        return np.empty((0, R, d))
    limit = DESIGN_BYTES if design_bytes is None else design_bytes
    rows = N if solver == "lstsq" else min(N, max(1, limit // (8 * R * d)))
    return np.empty((rows, R, d))


def _orthogonal(A: np.ndarray, y: np.ndarray, samples: int = 0) -> np.ndarray:
    """The least-squares solution of ``A θ = y`` by a rank-revealing orthogonal factorisation
    (LAPACK's ``gelsy``: minimum norm where ``A`` is rank-deficient, singular values below
    ``max(N, P)`` machine epsilons of the largest counting as zero — the rounding of a
    factorisation of that size; for a normal matrix ``AᵀA`` summed over ``samples``, that many).
    scipy's default cutoff, one machine epsilon, keeps directions of rounding: on a design with a
    repeated column it returned coefficients of 1e13 and a larger residual
    (``tests/test_anfis_engine.py``). A tall ``A`` is first
    reduced by a Householder QR, ``A = QR`` (blocked, at BLAS-3 speed), and ``gelsy`` solves
    ``R θ = Qᵀy``: the same solution (``A`` and ``R`` have the same singular values), several
    times faster than ``gelsy`` on the tall matrix, whose column pivoting runs at BLAS-2 speed."""
    N, P = A.shape
    cond = np.finfo(float).eps * max(N, P, samples)     # singular values below it: rounding
    if N > 2 * P:
        vector = y.ndim == 1
        qty, R = scipy.linalg.qr_multiply(A, np.atleast_2d(y.T), mode="right")
        R = R[:P]
        y = qty[0] if vector else qty.T
        A = R
    return scipy.linalg.lstsq(A, y, cond=cond, lapack_driver="gelsy", check_finite=False)[0]


def _solve_normal(G: np.ndarray, b: np.ndarray, orthogonal, ridge: float) -> np.ndarray:
    G[np.diag_indices_from(G)] += ridge * max(np.trace(G), 1e-300) / len(G) + 1e-300
    with warnings.catch_warnings():
        warnings.simplefilter("error", scipy.linalg.LinAlgWarning)
        try:
            return scipy.linalg.solve(G, b, assume_a="pos", check_finite=False)
        except (scipy.linalg.LinAlgWarning, np.linalg.LinAlgError):
            pass
    return orthogonal()


def rule_outputs(Xa: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """``f_r = p_r · x + p_r0`` for every sample and rule: ``(N, R)`` of inputs with their
    column of ones ``Xa (N, n + 1)`` and one output's consequents ``theta (R, n + 1)``."""
    return Xa @ theta.T


def premise_gradient(kind: str, Xp: np.ndarray, mfs: Sequence[np.ndarray], rules: np.ndarray,
                     D: np.ndarray) -> list[np.ndarray]:
    """``∇E`` with respect to every premise parameter, per input ``(m_i, p)``, from
    ``D = (∂E/∂w) ⊙ w (N, R)``: ``∂E/∂θ_ik = Σ_n Σ_{r uses k} D_nr (∂μ_ik/∂θ)/μ_ik``.

    For Gaussian functions the sums over the samples are moments of ``D``:
    ``∂E/∂c = (S₁ − c S₀)/σ²``, ``∂E/∂σ = (S₂ − 2c S₁ + c² S₀)/σ³`` with
    ``S_j = Σ_n S_n x_n^j``."""
    gradients = []
    for i, params in enumerate(mfs):
        m = len(params)
        if _identity(rules, i, m):
            S = D
        else:
            one_hot = np.zeros((len(rules), m))
            one_hot[np.arange(len(rules)), rules[:, i]] = 1.0
            S = D @ one_hot                                                  # (N, m)
        x = Xp[:, i]
        if kind == "gauss":
            sigma, c = params[:, 0], params[:, 1]
            moments = np.stack([np.ones_like(x), x, x * x]) @ S              # (3, m)
            s0, s1, s2 = moments
            gradients.append(np.column_stack([(s2 - 2 * c * s1 + c * c * s0) / sigma**3,
                                              (s1 - c * s0) / sigma**2]))
        else:
            g = mf_log_gradients(kind, x, params)                           # (N, m, 3)
            gradients.append(np.einsum("nm,nmp->mp", S, g))
    return gradients


def adapted_step(step: float, errors: Sequence[float], increase: float, decrease: float) -> float:
    """Jang's rule on the last five training errors: ×``increase`` after four consecutive
    decreases, ×``decrease`` after two consecutive up–down alternations, else unchanged."""
    e = list(errors)[-5:]
    if len(e) < 5:
        return step
    changes = np.sign(np.diff(e))
    if np.all(changes < 0):
        return step * increase
    if np.array_equal(changes, [-1, 1, -1, 1]) or np.array_equal(changes, [1, -1, 1, -1]):
        return step * decrease
    return step


def keep_valid(kind: str, new: np.ndarray, old: np.ndarray) -> np.ndarray:
    """Widths stay positive (at least 1e-3 of their value before the step); bell slopes too."""
    new = new.copy()
    new[:, 0] = np.maximum(new[:, 0], 1e-3 * old[:, 0])
    if kind == "gbell":
        new[:, 1] = np.maximum(new[:, 1], 1e-3 * old[:, 1])
    return new


def output_weights(Y: np.ndarray) -> np.ndarray:
    """``c_k`` of the shared error ``Σ_k c_k E_k``: 1 for one output; ``1 / var(y_k)`` for
    several (an output that does not vary weighs nothing; all 1 if none varies)."""
    if Y.shape[1] == 1:
        return np.ones(1)
    var = Y.var(axis=0)
    if not (var > 0).any():
        return np.ones(Y.shape[1])
    return np.where(var > 0, 1.0 / np.where(var > 0, var, 1.0), 0.0)


def network_outputs(kind: str, Xp: np.ndarray, X: np.ndarray, mfs: Sequence[np.ndarray],
                    rules: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """The network's output ``(N,)`` along the training path: ``Σ_r w̄_r f_r`` for premise
    inputs ``Xp (N, n_p)``, consequent inputs ``X (N, n)`` and consequents ``theta (R, n + 1)``
    (a fitted model's :meth:`~nfarm.learning.anfis.ANFIS.predict` lays the same sums out for
    speed; equal to rounding)."""
    Xa = np.column_stack([X, np.ones(len(X))])
    return (normalised(firing(kind, Xp, mfs, rules))[1] * rule_outputs(Xa, theta)).sum(axis=1)


def _outputs(w_bar: np.ndarray, Xa: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Network outputs ``(N, k)``: ``Σ_r w̄_r f_r`` for consequents ``theta (R, n + 1, k)``."""
    R, d, k = theta.shape
    C = (w_bar @ theta.reshape(R, d * k)).reshape(len(Xa), d, k)
    return np.matmul(Xa[:, None, :], C)[:, 0, :]


def train(Xp: np.ndarray, X: np.ndarray, Y: np.ndarray, mfs: list[np.ndarray], rules: np.ndarray,
          options: Options, Xp_val: np.ndarray | None = None, X_val: np.ndarray | None = None,
          Y_val: np.ndarray | None = None) -> tuple[list[Output], list[float]]:
    """Train premises ``mfs`` over ``Xp (N, n_p)`` and each output's consequents over
    ``X (N, n)`` on targets ``Y (N, k)`` (validated on ``Xp_val, X_val, Y_val`` when given).
    Returns each output's :class:`Output` and the step size of every epoch."""
    kind, k = options.mf, Y.shape[1]
    Xa = np.column_stack([X, np.ones(len(X))])
    Xa_val = None if X_val is None else np.column_stack([X_val, np.ones(len(X_val))])
    weights = output_weights(Y)
    buffer = design_buffer(len(X), len(rules), Xa.shape[1], solver=options.solver)
    outputs = [Output(mfs=mfs, consequents=np.zeros((len(rules), Xa.shape[1])), best_epoch=0)
               for _ in range(k)]
    best = [math.inf] * k
    combined_curve, step_curve = [], []
    step, best_combined, since_best = float(options.step_size), math.inf, 0
    epochs = range(options.epochs)
    if options.progress:
        from tqdm.auto import tqdm
        epochs = tqdm(epochs, desc="ANFIS epochs", leave=False)
    for epoch in epochs:
        check_time(f"ANFIS training, epoch {epoch + 1} of {options.epochs}")    # a caller's time limit
        w = firing(kind, Xp, mfs, rules)
        total, w_bar = normalised(w)
        theta = least_squares(w_bar, Xa, Y, solver=options.solver, ridge=options.ridge, buffer=buffer)
        theta = theta.reshape(len(rules), Xa.shape[1], k)
        F = [rule_outputs(Xa, theta[:, :, j]) for j in range(k)]
        Y_hat = np.column_stack([(w_bar * f).sum(axis=1) for f in F])
        rmse = [float(np.sqrt(np.mean((Y_hat[:, j] - Y[:, j]) ** 2))) for j in range(k)]
        combined = rmse[0] if k == 1 else math.sqrt(sum(c * e * e for c, e in zip(weights, rmse)))
        combined_curve.append(combined)
        step_curve.append(step)
        scores = rmse
        if X_val is not None:
            _, w_bar_val = normalised(firing(kind, Xp_val, mfs, rules))
            Y_val_hat = _outputs(w_bar_val, Xa_val, theta)
            scores = [float(np.sqrt(np.mean((Y_val_hat[:, j] - Y_val[:, j]) ** 2))) for j in range(k)]
        for j, out in enumerate(outputs):
            out.loss_curve.append(rmse[j])
            if X_val is not None:
                out.val_loss_curve.append(scores[j])
            if epoch == 0 or scores[j] < best[j]:        # the first epoch even if its score is NaN
                best[j] = scores[j]
                out.mfs, out.consequents, out.best_epoch = mfs, theta[:, :, j].copy(), epoch
        score = scores[0] if k == 1 else math.sqrt(sum(c * e * e for c, e in zip(weights, scores)))
        if score < best_combined * (1.0 - options.min_improvement):   # a fall large enough to count
            best_combined, since_best = score, 0
        else:
            since_best += 1
        if max(rmse) <= options.error_goal or epoch == options.epochs - 1 \
                or (options.patience is not None and since_best >= options.patience):
            break
        inv_total = 1.0 / np.where(total > 0, total, 1.0)
        D = None
        for j in range(k):
            scale = (-2.0 * weights[j]) * (Y[:, j] - Y_hat[:, j]) * inv_total
            term = scale[:, None] * (F[j] - Y_hat[:, j, None])
            D = term if D is None else np.add(D, term, out=D)
        D *= w
        gradient = premise_gradient(kind, Xp, mfs, rules, D)
        norm = math.sqrt(sum(float((g * g).sum()) for g in gradient))
        if norm > 0:
            mfs = [keep_valid(kind, p - step * g / norm, p) for p, g in zip(mfs, gradient)]
        step = adapted_step(step, combined_curve, options.step_increase, options.step_decrease)
    for out in outputs:
        out.mfs = [p.copy() for p in out.mfs]
    return outputs, step_curve
