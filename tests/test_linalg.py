"""Batched small linear algebra against numpy.linalg."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm.model.linalg import cholesky_solve_T, gram_T


@pytest.mark.parametrize("n", [1, 2, 5, 7])
def test_gram_and_cholesky_solve_match_numpy(n):
    rng = np.random.default_rng(n)
    M = 50
    J = rng.normal(size=(6, n, M))
    w = rng.uniform(0.1, 2.0, 6)
    A = gram_T(J, w)
    reference = np.einsum("kim,k,kjm->mij", J, w, J)
    lower = np.tril_indices(n)
    np.testing.assert_allclose(A[lower], np.moveaxis(reference, 0, -1)[lower], rtol=1e-13)
    for k in range(n):
        A[k, k] += 0.1
    b = rng.normal(size=(n, M))
    x = cholesky_solve_T(A, b)
    expected = np.linalg.solve(reference + 0.1 * np.eye(n), b.T[..., None])[..., 0]
    np.testing.assert_allclose(x.T, expected, rtol=1e-10, atol=1e-12)


def test_not_positive_definite_gives_nan_in_that_column_only():
    A = np.zeros((2, 2, 2))
    A[:, :, 0] = [[4.0, 0.0], [2.0, 3.0]]
    A[:, :, 1] = [[-1.0, 0.0], [0.0, 1.0]]
    x = cholesky_solve_T(A, np.ones((2, 2)))
    assert np.isfinite(x[:, 0]).all() and np.isnan(x[:, 1]).all()
