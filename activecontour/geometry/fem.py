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

import numpy as np

from activecontour import _kernels

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
    import scipy.sparse  # for checks and users; the flow never builds a matrix

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
    if not (len(off) == len(b) == len(diagonal) == offsets[-1] and offsets[0] == 0):
        raise ValueError(f"diagonal, off and rhs must all have offsets[-1] = {offsets[-1]} rows, got "
                         f"{len(diagonal)}, {len(off)} and {len(b)}")
    if np.any(np.diff(offsets) < 3):
        raise ValueError(f"a closed polygon needs at least 3 vertices, got {np.diff(offsets).min()}")
    x = np.empty_like(b)
    _kernels.cyclic_thomas(diagonal, off, b, offsets, x)
    return x[:, 0] if squeeze else x
