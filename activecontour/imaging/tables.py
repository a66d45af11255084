"""The image model: the bilinear interpolant and its row-antiderivative tables.

The image is the continuous bilinear interpolant of the pixel values, pixel centres at integer
(row, col), extended by a constant over the half-pixel margin, on the domain
``D = [-0.5, M - 0.5] x [-0.5, N - 0.5]``.  Region integrals of 1, I and I^2 over Omega_i turn into
boundary integrals by Green's theorem, ``int_Omega g = closed integral of G(r, c) dc``, with
``G(r, c) = int^r g(s, c) ds``.  :class:`ImageModel` precomputes G at the pixel centres of every
row (of every 8th row on a large image) in one pass; G at any other point is a short polynomial
evaluation (after a few increments from the stored row below).  Because the bilinear interpolant
is a polynomial on each grid cell, both G and I are integrated *exactly* along the pieces of a
polygon edge between grid lines, which makes the discrete energy and its shape derivative
consistent to rounding error (:mod:`activecontour.energy`).  The tables live in padded coordinates
``(u, v) = (r + 1, c + 1)``; the evaluation on a cell is :func:`activecontour._kernels.edge_integrals`.
"""

from __future__ import annotations

import numpy as np

from activecontour import _kernels

__all__ = ["ImageModel"]

#: bytes up to which :class:`ImageModel` stores the antiderivatives at every row (3 float64 per
#: pixel and channel: a 1600^2 gray image); above, at every ``_SPARSE_ANCHOR``-th row (3/8 float64)
_FULL_TABLE_BYTES = 1 << 26
_SPARSE_ANCHOR = 8


class ImageModel:
    """The bilinear image on D with its row-antiderivative tables (one pass over the pixels).

    Parameters
    ----------
    values : ndarray of shape (M, N, C)
        Normalised intensities, as returned by :func:`normalize_image`, or the feature channels
        of a model whose integrands are quadratic forms in them (:mod:`activecontour.models`).
    image : ndarray of shape (M, N, C'), optional
        What a start looks at (:func:`activecontour.initial.initial_curves`): the intensities
        when ``values`` are features (the smooth fit's image corrected by its light field);
        by default ``values``.

    Attributes
    ----------
    shape : tuple
        (M, N).
    n_channels : int
        C.
    totals : tuple of (float, ndarray (C,), ndarray (C,))
        ``int_D 1``, ``int_D I`` and ``int_D I^2``, exactly, for the outside region by subtraction.
    """

    def __init__(self, values, image=None):
        values = np.ascontiguousarray(values, dtype=np.float64)
        if values.ndim != 3:
            raise ValueError("ImageModel expects normalised values of shape (M, N, C)")
        self.values = values
        self.image = values if image is None else image
        self.shape = values.shape[:2]
        self.n_channels = values.shape[2]
        m, n = self.shape
        full = 24 * (m + 2) * (n + 2) * self.n_channels <= _FULL_TABLE_BYTES
        #: padded rows between two stored rows of ``table``
        self.anchor = 1 if full else _SPARSE_ANCHOR
        #: ((M + 1) // anchor + 1, N + 2, C, 3): the row-antiderivatives (t1, t2, t3) at every
        #: anchor-th padded row, built in one pass without temporaries
        #: (:func:`activecontour._kernels.build_tables`, which also says why float64)
        self.table = np.empty(((m + 1) // self.anchor + 1, n + 2, self.n_channels, 3))
        total1, total2 = np.empty(self.n_channels), np.empty(self.n_channels)
        _kernels.build_tables(values, self.table, self.anchor, total1, total2)
        self.bounds = np.array([[-0.5, -0.5], [m - 0.5, n - 0.5]])
        self.totals = (float(m * n), total1, total2)
