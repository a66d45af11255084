"""The zero level set of phi: marching-squares segments, chained contours and the oriented edge soup."""

from __future__ import annotations

import numpy as np

from activecontour import _kernels
from activecontour.geometry.raster import level_curves, mask_to_curves


def _cell_segments(phi, cells):
    """Marching-squares segments of phi's zero set in the grid cells ``cells``, (K, 2 slots, 2 ends, 2).

    ``cells``: flat indices ``row * (N - 1) + col`` of cells whose corners are not all on one side
    (:func:`_change_cells`); cell (i, j) has the corners (i, j), (i, j+1), (i+1, j+1), (i+1, j)
    (a corner is inside where phi > 0) and a crossing on every edge with a sign change, linear in
    phi (float64).  Slot 1 is used by saddle cells only; unused slots are NaN.  A saddle isolates
    its two inside corners, the rule of ``skimage.measure.find_contours``
    (``fully_connected="low"``), so the segments are those of :func:`level_set_contours`.  Also
    returns the key of the grid edge of every segment end (K, 2, 2), -1 for unused slots: two
    segments with a common key meet there.  Compiled: :func:`activecontour._kernels.cell_segments`.
    """
    segments = np.full((len(cells), 2, 2, 2), np.nan)
    keys = np.full((len(cells), 2, 2), -1, dtype=np.intp)
    cells = np.ascontiguousarray(cells, dtype=np.intp)
    _kernels.cell_segments(np.ascontiguousarray(phi), cells, segments, keys)
    return segments, keys


def _change_cells(positive):
    """Flat indices (row * (N - 1) + col) of the grid cells whose corners are not all on one side."""
    corner = positive[:-1, :-1]
    change = corner != positive[:-1, 1:]
    change |= corner != positive[1:, 1:]
    change |= corner != positive[1:, :-1]
    return np.flatnonzero(change)


def level_set_contours(phi):
    """The zero level set of phi as closed sub-pixel curves, oriented as in :mod:`~activecontour.geometry`.

    Marching squares (``skimage.measure.find_contours``) on phi padded by one pixel of
    ``-|phi|`` (:func:`_closed_padding`): a region that touches the image border closes along the
    domain edge, half a pixel outside the outermost pixel centres, so every curve is closed.
    With ``positive_orientation="high"`` outer boundaries have positive signed area and holes
    negative.  Each vertex is stored once.  Only the box around the inside (and one pixel more)
    is traced: beyond it phi is negative and has no zero crossing.

    The curves of marching squares are fixed by the sides of the pixels alone (which cells a curve
    crosses, and how the crossings join) but for where each crossing lies on its grid edge: they
    are traced from the sides (:func:`activecontour.geometry.raster.mask_to_curves`, compiled, no
    float64 copy of the box) and each crossing then placed as ``find_contours`` places it, by the
    same arithmetic (:func:`_crossings`): the same curves, bit for bit.  Where a crossing would not
    lie strictly inside its edge (a zero or a NaN of phi), ``find_contours`` joins curves at equal
    points, and it runs itself.
    """
    phi = np.asarray(phi)
    positive = phi > 0
    rows, cols = np.flatnonzero(positive.any(axis=1)), np.flatnonzero(positive.any(axis=0))
    if rows.size == 0:
        return []
    top, left = max(rows[0] - 1, 0), max(cols[0] - 1, 0)
    box = phi[top: rows[-1] + 2, left: cols[-1] + 2]
    try:
        curves = mask_to_curves(positive[top: rows[-1] + 2, left: cols[-1] + 2],
                                place=lambda midpoints: _crossings(box, midpoints))
    except _Unplaced:
        # the padding of a side of the box inside the image is -|phi| of negative pixels: phi itself
        curves = level_curves(_closed_padding(box), 0.0)
    return [curve + (top, left) for curve in curves]


class _Unplaced(ValueError):
    """A crossing of phi's zero set that does not lie strictly inside its grid edge (:func:`_crossings`)."""


def _crossings(box, midpoints):
    """The zero crossings of ``box`` padded by :func:`_closed_padding` on the grid edges whose
    midpoints (box coordinates, (K, 2)) are given, in box coordinates: exactly the points of
    ``skimage.measure.find_contours`` on the padded box less the padding's pixel, as
    :func:`activecontour.geometry.raster.level_curves` returns them (``start + (0 - a) / (b - a)``
    from the edge's upper or left end ``a`` to its other end ``b``, in padded coordinates, then
    ``- 1``).  Raises :class:`_Unplaced` when a crossing does not lie strictly inside its edge."""
    row, col = midpoints[:, 0], midpoints[:, 1]
    along = row == np.floor(row)  # a horizontal edge: the crossing moves along the row
    first_r = (np.where(along, row, row - 0.5) + 1.0).astype(np.intp)  # padded coordinates
    first_c = (np.where(along, col - 0.5, col) + 1.0).astype(np.intp)
    a = _padded_values(box, first_r, first_c)
    b = _padded_values(box, first_r + ~along, first_c + along)
    start = np.where(along, first_c, first_r).astype(np.float64)
    placed = start + (0.0 - a) / (b - a)
    if not np.all((placed > start) & (placed < start + 1.0)):
        raise _Unplaced
    out = np.empty_like(midpoints)
    out[:, 0] = np.where(along, first_r - 1.0, placed - 1.0)
    out[:, 1] = np.where(along, placed - 1.0, first_c - 1.0)
    return out


def _padded_values(box, rows, cols):
    """The values of :func:`_closed_padding` of ``box`` at padded (row, col) pixels, float64."""
    m, n = box.shape
    values = box[np.clip(rows - 1, 0, m - 1), np.clip(cols - 1, 0, n - 1)].astype(np.float64)
    frame = (rows < 1) | (rows > m) | (cols < 1) | (cols > n)
    values[frame] = -np.abs(values[frame])
    values[values == 0] = -1e-300
    return values


def _closed_padding(phi):
    """phi padded by one pixel of ``-|phi|``: the zero set closes on the domain edge (inside only)."""
    m, n = np.shape(phi)
    padded = np.empty((m + 2, n + 2))  # np.pad's "edge" mode, in one array rather than a copy and a pad
    padded[1:-1, 1:-1] = phi
    padded[1:-1, 0], padded[1:-1, -1] = padded[1:-1, 1], padded[1:-1, -2]
    padded[0], padded[-1] = padded[1], padded[-2]
    padded[0], padded[-1] = -np.abs(padded[0]), -np.abs(padded[-1])
    padded[:, 0], padded[:, -1] = -np.abs(padded[:, 0]), -np.abs(padded[:, -1])
    padded[padded == 0] = -1e-300  # phi = 0 is outside, as in the mask phi > 0
    return padded


def zero_set_edges(phi):
    """The segments of :func:`level_set_contours`, oriented but not chained: ``(S, 2 ends, 2)``.

    The same marching-squares segments (the saddle rule of :func:`_cell_segments`, the closing
    along the domain edge of :func:`_closed_padding`), each directed so that the inside lies on
    its left, i.e. its normal ``nu = (t_c, -t_r)`` points out of the inside as for the polygons.
    Region and length integrals are sums over edges (Green's theorem), so the common evaluator
    scores this soup exactly as it scores the chained contours, without the O(M N) Python work of
    chaining them.
    """
    phi = np.asarray(phi, dtype=np.float64)
    return _edge_soup(phi, _change_cells(phi > 0))


def _edge_soup(phi, cells):
    """:func:`zero_set_edges` from the cells of phi with a sign change (:func:`_change_cells`).

    Works on the cells of the padded grid of :func:`_closed_padding` without building it: the
    image's own cells with a sign change, shifted by the frame, and the frame's cells next to an
    inside pixel (the frame lies outside), with the padding's values read off phi.  Each segment
    is directed so that a point inside its cell on the inside (the mean of a simple cell's inside
    corners, a saddle segment's cut-off corner) lies on its left.  O(|Gamma| + M + N) after the
    sign test, compiled: :func:`activecontour._kernels.edge_soup`.
    """
    m, n = phi.shape
    out = np.empty((2 * (len(cells) + 2 * (n + 1) + 2 * (m - 1)), 2, 2))
    count = _kernels.edge_soup(np.ascontiguousarray(phi), np.ascontiguousarray(cells, dtype=np.intp), out)
    return out[:count]
