"""Small dense linear algebra over a batch, in component layout (samples last).

``np.linalg.solve`` on a stack of 5 × 5 systems calls LAPACK once per system; for the
thousands of tiny systems an inverse-kinematics iteration solves, writing the Cholesky
factorisation as vector operations over the batch is several times faster.
"""

from __future__ import annotations

import numpy as np

__all__ = ["gram_T", "cholesky_solve_T"]


def gram_T(J: np.ndarray, w: np.ndarray | None = None) -> np.ndarray:
    """The lower triangle of ``A = Jᵀ diag(w) J`` for ``J (m, n, M)``, weights ``w (m,)`` →
    ``A (n, n, M)`` (entries above the diagonal are left uninitialised: pass it to
    :func:`cholesky_solve_T`, which reads only the lower triangle).

    Example:
        >>> J = np.array([[1.0, 2.0], [0.0, 1.0], [3.0, 1.0]])[:, :, None]     # (m, n, M) = (3, 2, 1)
        >>> A = gram_T(J)
        >>> A[0, 0].tolist(), A[1, 0].tolist(), A[1, 1].tolist()              # lower triangle of JᵀJ
        ([10.0], [5.0], [6.0])
    """
    m, n, M = J.shape
    Jw = J if w is None else J * w[:, None, None]
    A = np.empty((n, n, M))
    for i in range(n):
        for j in range(i + 1):
            A[i, j] = np.einsum("km,km->m", Jw[:, i], J[:, j])
    return A


def cholesky_solve_T(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve ``A x = b`` for symmetric positive-definite ``A (n, n, M)``, ``b (n, M)`` → ``x (n, M)``.

    Cholesky ``A = L Lᵀ`` column by column::

        L_jj = sqrt(A_jj − Σ_{k<j} L_jk²),   L_ij = (A_ij − Σ_{k<j} L_ik L_jk) / L_jj   (i > j)

    then forward substitution ``L y = b`` and back substitution ``Lᵀ x = y``. Only the lower
    triangle of ``A`` is read. A matrix that is not positive definite gives NaN in its column.

    Example:
        >>> A = np.zeros((2, 2, 2))                                # two systems, samples last
        >>> A[:, :, 0], A[:, :, 1] = [[4.0, 0.0], [2.0, 3.0]], [[1.0, 0.0], [2.0, 1.0]]   # lower triangles
        >>> cholesky_solve_T(A, np.array([[6.0, 1.0], [5.0, 1.0]])).round(6).tolist()   # the second: not SPD
        [[1.0, nan], [1.0, nan]]
    """
    n = A.shape[0]
    L = [[None] * n for _ in range(n)]
    inv_diag = [None] * n
    for j in range(n):
        s = A[j, j] - sum(L[j][k] * L[j][k] for k in range(j)) if j else A[j, j]
        with np.errstate(invalid="ignore", divide="ignore"):
            inv_diag[j] = 1.0 / np.sqrt(s)
        for i in range(j + 1, n):
            s = A[i, j] - sum(L[i][k] * L[j][k] for k in range(j)) if j else A[i, j]
            L[i][j] = s * inv_diag[j]
    y = [None] * n
    for i in range(n):
        s = b[i] - sum(L[i][k] * y[k] for k in range(i)) if i else b[i]
        y[i] = s * inv_diag[i]
    x = [None] * n
    for i in reversed(range(n)):
        s = y[i] - sum(L[k][i] * x[k] for k in range(i + 1, n)) if i < n - 1 else y[i]
        x[i] = s * inv_diag[i]
    return np.stack(x)
