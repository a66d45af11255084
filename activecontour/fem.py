"""P1 finite elements on a closed polygon: mass M, stiffness K, and the O(K) cyclic solve.

The mesh is the polygon itself: vertex i carries the hat function phi_i, element i is the edge
from vertex i to vertex (i + 1) mod K with length ``h[i]``.  Both matrices are symmetric and
cyclic tridiagonal, stored as a pair ``(diagonal, off)`` with ``off[i] = A[i, (i + 1) % K]``:

    M[i, i] = (h[i - 1] + h[i]) / 3,   M[i, i + 1] = h[i] / 6      (exact P1 mass)
    K[i, i] = 1 / h[i - 1] + 1 / h[i], K[i, i + 1] = -1 / h[i]      (P1 stiffness, -Laplace_Sigma)

``b(V, Y) = int V.Y + int grad_Sigma V : grad_Sigma Y`` of (6.39) is ``M + K``; the L^2 form (6.25) is
``M``.  :func:`cyclic_solve` solves either in O(K) by Sherman-Morrison on the Thomas algorithm,
several polygons in one call: no dense inverse, no general sparse LU.
"""

from __future__ import annotations

import numba
import numpy as np
import scipy.sparse

__all__ = [
    "cyclic_apply",
    "cyclic_matrix",
    "cyclic_solve",
    "mass_diagonals",
    "mass_matrix",
    "stiffness_diagonals",
    "stiffness_matrix",
]


def mass_diagonals(h, previous=None):
    """Diagonal and cyclic off-diagonal of the P1 mass matrix for edge lengths ``h``.

    ``previous[i]`` is the edge ending at vertex i (default i - 1, cyclically); pass it for several
    stacked polygons.
    """
    h = np.asarray(h, dtype=np.float64)
    h_before = np.roll(h, 1) if previous is None else h[previous]
    return (h_before + h) / 3.0, h / 6.0


def stiffness_diagonals(h, previous=None):
    """Diagonal and cyclic off-diagonal of the P1 stiffness matrix for edge lengths ``h``."""
    inv = 1.0 / np.asarray(h, dtype=np.float64)
    return (np.roll(inv, 1) if previous is None else inv[previous]) + inv, -inv


def cyclic_matrix(diagonal, off):
    """The sparse (CSR) symmetric cyclic tridiagonal matrix with these diagonals."""
    k = len(diagonal)
    i = np.arange(k)
    j = (i + 1) % k
    rows = np.concatenate([i, i, j])
    cols = np.concatenate([i, j, i])
    data = np.concatenate([diagonal, off, off])
    return scipy.sparse.csr_matrix((data, (rows, cols)), shape=(k, k))


def mass_matrix(h):
    """Sparse P1 mass matrix M of a closed polygon with edge lengths ``h``."""
    return cyclic_matrix(*mass_diagonals(h))


def stiffness_matrix(h):
    """Sparse P1 stiffness matrix K of a closed polygon with edge lengths ``h``."""
    return cyclic_matrix(*stiffness_diagonals(h))


def cyclic_apply(diagonal, off, x):
    """``A @ x`` for the cyclic tridiagonal A, x of shape (K,) or (K, d)."""
    x = np.asarray(x, dtype=np.float64)
    if x.ndim == 2:
        diagonal, off = diagonal[:, None], off[:, None]
    return diagonal * x + off * np.roll(x, -1, axis=0) + np.roll(off * x, 1, axis=0)


def cyclic_solve(diagonal, off, rhs, offsets=None):
    """Solve ``A x = rhs`` for symmetric positive definite cyclic tridiagonal A, in O(K).

    Parameters
    ----------
    diagonal, off : ndarray of shape (K,)
        ``A[i, i]`` and ``A[i, next(i)]``, where next(i) is i + 1 within a block and the block's
        first index for its last one.
    rhs : ndarray of shape (K,) or (K, d)
    offsets : ndarray of int, optional
        Block boundaries ``[0, K_0, K_0 + K_1, ..., K]`` for several independent closed polygons
        solved at once (each block >= 3); by default one block.

    Each block is split as ``T + u v^T`` with T tridiagonal SPD (Sherman-Morrison); T is
    eliminated once (Thomas algorithm, no pivoting needed for SPD) for all right-hand sides.
    """
    diagonal = np.ascontiguousarray(diagonal, dtype=np.float64)
    off = np.ascontiguousarray(off, dtype=np.float64)
    rhs = np.asarray(rhs, dtype=np.float64)
    squeeze = rhs.ndim == 1
    b = np.ascontiguousarray(rhs[:, None] if squeeze else rhs)
    offsets = np.array([0, len(diagonal)] if offsets is None else offsets, dtype=np.intp)
    if np.any(np.diff(offsets) < 3):
        raise ValueError(f"a closed polygon needs at least 3 vertices, got {np.diff(offsets).min()}")
    x = np.empty_like(b)
    _cyclic_thomas(diagonal, off, b, offsets, x)
    return x[:, 0] if squeeze else x


@numba.njit(cache=True, error_model="numpy")
def _cyclic_thomas(diagonal, off, rhs, offsets, out):
    columns = rhs.shape[1]
    for block in range(offsets.shape[0] - 1):
        first, stop = offsets[block], offsets[block + 1]
        k = stop - first
        d = diagonal[first:stop].copy()
        e = off[first:stop]
        gamma = -d[0]
        corner = e[k - 1]
        d[0] -= gamma
        d[k - 1] -= corner * corner / gamma
        # right-hand sides: the block's columns plus u = (gamma, 0, ..., 0, corner)
        y = np.zeros((k, columns + 1))
        y[:, :columns] = rhs[first:stop]
        y[0, columns] = gamma
        y[k - 1, columns] += corner
        # Thomas: forward elimination on the tridiagonal part (super-diagonal e[:k-1])
        c_prime = np.empty(k)
        c_prime[0] = e[0] / d[0]
        for col in range(columns + 1):
            y[0, col] /= d[0]
        for i in range(1, k):
            denominator = d[i] - e[i - 1] * c_prime[i - 1]
            c_prime[i] = e[i] / denominator if i < k - 1 else 0.0
            for col in range(columns + 1):
                y[i, col] = (y[i, col] - e[i - 1] * y[i - 1, col]) / denominator
        for i in range(k - 2, -1, -1):
            for col in range(columns + 1):
                y[i, col] -= c_prime[i] * y[i + 1, col]
        z0, zk = y[0, columns], y[k - 1, columns]
        scale = 1.0 + z0 + (corner / gamma) * zk
        for col in range(columns):
            factor = (y[0, col] + (corner / gamma) * y[k - 1, col]) / scale
            for i in range(k):
                out[first + i, col] = y[i, col] - factor * y[i, columns]
