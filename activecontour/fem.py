"""P1 finite elements on a closed polygon: mass M, stiffness K, and the O(K) cyclic solve.

The mesh is the polygon itself: vertex i carries the hat function phi_i, element i is the edge
from vertex i to vertex (i + 1) mod K with length ``h[i]``.  Both matrices are symmetric and
cyclic tridiagonal, stored as a pair ``(diagonal, off)`` with ``off[i] = A[i, (i + 1) % K]``:

    M[i, i] = (h[i - 1] + h[i]) / 3,   M[i, i + 1] = h[i] / 6      (exact P1 mass)
    K[i, i] = 1 / h[i - 1] + 1 / h[i], K[i, i + 1] = -1 / h[i]      (P1 stiffness, -Laplace_Sigma)

``b(V, Y) = int V.Y + int grad_Sigma V : grad_Sigma Y`` of (6.39) is ``M + K``; the L^2 form (6.25) is
``M``.  :func:`cyclic_solve` solves either in O(K) by Sherman-Morrison on a banded Cholesky
factorisation: no dense inverse, no general sparse LU.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
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


def mass_diagonals(h):
    """Diagonal and cyclic off-diagonal of the P1 mass matrix for edge lengths ``h``."""
    h = np.asarray(h, dtype=np.float64)
    return (np.roll(h, 1) + h) / 3.0, h / 6.0


def stiffness_diagonals(h):
    """Diagonal and cyclic off-diagonal of the P1 stiffness matrix for edge lengths ``h``."""
    inv = 1.0 / np.asarray(h, dtype=np.float64)
    return np.roll(inv, 1) + inv, -inv


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


def cyclic_solve(diagonal, off, rhs):
    """Solve ``A x = rhs`` for a symmetric positive definite cyclic tridiagonal A in O(K).

    A is split as ``T + u v^T`` with T tridiagonal SPD (Sherman-Morrison), and T is factorised once
    by a banded Cholesky for all right-hand sides.

    Parameters
    ----------
    diagonal, off : ndarray of shape (K,)
        ``A[i, i]`` and ``A[i, (i + 1) % K]``, K >= 3.
    rhs : ndarray of shape (K,) or (K, d)
    """
    diagonal = np.asarray(diagonal, dtype=np.float64)
    off = np.asarray(off, dtype=np.float64)
    rhs = np.asarray(rhs, dtype=np.float64)
    k = diagonal.shape[0]
    if k < 3:
        raise ValueError(f"a closed polygon needs at least 3 vertices, got {k}")
    squeeze = rhs.ndim == 1
    b = rhs[:, None] if squeeze else rhs
    gamma = -diagonal[0]
    corner = off[-1]
    banded = np.empty((2, k))
    banded[0, 0] = 0.0
    banded[0, 1:] = off[:-1]
    banded[1] = diagonal
    banded[1, 0] -= gamma
    banded[1, -1] -= corner * corner / gamma
    u = np.zeros(k)
    u[0], u[-1] = gamma, corner
    solution = scipy.linalg.solveh_banded(banded, np.column_stack([b, u]), check_finite=False)
    y, z = solution[:, :-1], solution[:, -1]
    v_y = y[0] + (corner / gamma) * y[-1]
    v_z = z[0] + (corner / gamma) * z[-1]
    x = y - np.outer(z, v_y / (1.0 + v_z))
    return x[:, 0] if squeeze else x
