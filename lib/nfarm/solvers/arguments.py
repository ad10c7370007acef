"""Checks of the solvers' pose arguments: a batch of target poses (:func:`check_targets`) and
a pose error's weights (:func:`check_weights`). Each refuses a bad value with one ``ValueError``
line naming the argument (for a batch of target poses, the first bad one by its index), before
any work; numbers, integers and choices are checked by :mod:`nfarm.infra.arguments`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["check_targets", "check_weights"]


def _where(shape: tuple, flat_index: int) -> str:
    if not shape:
        return "T_target"
    return f"T_target[{', '.join(map(str, np.unravel_index(flat_index, shape)))}]"


_CHECK_CHUNK = 8192


def check_targets(T_target, ortho_tol: float = 1e-9, *, map_chunks=map) -> np.ndarray:
    """``T_target`` as a float array of rigid transforms ``(..., 4, 4)``, or a ``ValueError``
    naming the first bad one (shape, NaN, last row, rotation not orthonormal to ``ortho_tol``,
    reflection).

    The poses are checked in chunks of 8192, so that the temporaries of each check stay in
    the cache: checked whole, a batch of a million poses costs two to three times as much per
    pose (the check is part of :func:`closed_form`'s time on 400 000 poses in
    ``benchmarks/bench_ik_closed_form.py``). ``map_chunks(check, starts)`` applies the check to
    each chunk in order (``map``, or an executor's ``map`` to check chunks side by side); the
    first bad pose is named either way.

    Example:
        >>> check_targets(np.tile(np.eye(4), (2, 3, 1, 1))).shape     # (..., 4, 4)
        (2, 3, 4, 4)
        >>> check_targets(np.zeros((4, 4)))
        Traceback (most recent call last):
        ...
        ValueError: T_target: last row must be [0, 0, 0, 1], got [0.0, 0.0, 0.0, 0.0]
    """
    def refused(what: str = "") -> ValueError:
        return ValueError(f"T_target must be an array of numbers of shape (..., 4, 4), got "
                          f"{what + ' ' if what else ''}({type(T_target).__name__} "
                          f"{str(T_target)[:40]!r})")

    try:
        # Real numbers only: a complex pose would lose its imaginary part to the cast, and
        # booleans or objects are no poses.
        kind = (T_target if isinstance(T_target, np.ndarray) else np.asarray(T_target)).dtype.kind
        T = np.asarray(T_target, dtype=float) if kind in "iuf" else None
    except (TypeError, ValueError):
        raise refused() from None
    if T is None:
        raise refused({"b": "booleans", "c": "complex numbers", "U": "text", "S": "bytes",
                       "O": "objects or ragged lists"}.get(kind, f"dtype kind {kind!r}"))
    if T.ndim < 2 or T.shape[-2:] != (4, 4):
        raise ValueError(f"T_target must have shape (..., 4, 4), got {T.shape}")
    batch, flat = T.shape[:-2], T.reshape(-1, 4, 4)

    def check(start: int) -> None:
        chunk = flat[start:start + _CHECK_CHUNK]
        finite = np.isfinite(chunk)           # whole-chunk tests first, rows only on failure
        if not finite.all():
            bad = ~finite.all(axis=(1, 2))
            raise ValueError(f"{_where(batch, start + np.argmax(bad))}: contains NaN or inf")
        last = chunk[:, 3]
        if not ((last[:, :3] == 0.0).all() and (last[:, 3] == 1.0).all()):
            k = int(np.argmax((last != [0.0, 0.0, 0.0, 1.0]).any(axis=1)))
            raise ValueError(f"{_where(batch, start + k)}: last row must be [0, 0, 0, 1], got "
                             f"{chunk[k, 3].tolist()}")
        # Columns x, y, z of every R as rows of the chunk's length (one copy): the dot products
        # then run over contiguous samples (5× faster than an einsum over the 3 × 3 blocks).
        x, y, z = chunk[:, :3, :3].transpose(2, 1, 0).copy()                  # (3, N) each
        err = np.maximum.reduce([np.abs(np.einsum("kn,kn->n", u, v) - (1.0 if u is v else 0.0))
                                 for u, v in ((x, x), (y, y), (z, z), (x, y), (x, z), (y, z))])
        if (err > ortho_tol).any():                                           # |RᵀR − I|
            k = int(np.argmax(err > ortho_tol))
            raise ValueError(f"{_where(batch, start + k)}: rotation is not orthonormal "
                             f"(max |RᵀR − I| = {err[k]:.3g} > {ortho_tol:g})")
        det = np.einsum("kn,kn->n", np.cross(x, y, axis=0), z)                # (x × y)·z
        if (det < 0).any():
            raise ValueError(f"{_where(batch, start + int(np.argmax(det < 0)))}: rotation is "
                             f"a reflection (determinant −1)")

    for _ in map_chunks(check, range(0, len(flat), _CHECK_CHUNK)):
        pass
    return T


def check_weights(weights) -> np.ndarray:
    """``weights`` of a pose error as ``(6,)`` floats (``None``: all ones): finite, ``>= 0``, not
    all zero; position x, y, z, then rotation x, y, z.

    Example:
        >>> check_weights([1, 1, 1, 0, 0, 0]).tolist()           # position only
        [1.0, 1.0, 1.0, 0.0, 0.0, 0.0]
        >>> check_weights([0] * 6)
        Traceback (most recent call last):
        ...
        ValueError: weights must be finite, >= 0 and not all zero, got [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    """
    if weights is None:
        return np.ones(6)
    w = np.asarray(weights, dtype=float)
    if w.shape != (6,):
        raise ValueError(f"weights must be 6 numbers (position x, y, z, then rotation x, y, z), "
                         f"got shape {w.shape}")
    if not np.isfinite(w).all() or (w < 0).any() or not w.any():
        raise ValueError(f"weights must be finite, >= 0 and not all zero, got {w.tolist()}")
    return w
