"""The zero level set of phi: marching-squares segments, chained contours and the oriented edge soup."""

from __future__ import annotations

import numpy as np

from activecontour.geometry.raster import level_curves


def _cell_segments(a, b, c, d, cell_r, cell_c, width):
    """Marching-squares segments of the zero set in grid cells, shape (K, 2 slots, 2 ends, 2).

    Cell (i, j) has the corners (i, j), (i, j+1), (i+1, j+1), (i+1, j) with the values ``a, b,
    c, d`` (K,) (float64; a corner is inside where its value is > 0).  Slot 1 is used by saddle
    cells only; unused slots are NaN.  A saddle isolates its two inside corners, the rule of
    ``skimage.measure.find_contours`` (``fully_connected="low"``), so the segments are those of
    :func:`level_set_contours`.  Also returns the key of the grid edge of every segment end
    (K, 2, 2), -1 for unused slots: two segments with a common key meet there (``width``: the
    grid's row length).
    """
    sa, sb, sc, sd = a > 0, b > 0, c > 0, d > 0
    r, q = cell_r.astype(np.float64), cell_c.astype(np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        # crossings on the edges top (a-b), right (b-c), bottom (d-c), left (a-d)
        points = np.stack([
            np.column_stack([r, q + a / (a - b)]),
            np.column_stack([r + b / (b - c), q + 1.0]),
            np.column_stack([r + 1.0, q + d / (d - c)]),
            np.column_stack([r + a / (a - d), q]),
        ], axis=1)
    exists = np.column_stack([sa != sb, sb != sc, sd != sc, sa != sd])
    # every crossing is named by its grid edge: 2 (row n + col) for the edge from (row, col) to
    # (row, col + 1), plus 1 for the edge from (row, col) to (row + 1, col)
    cell = cell_r * width + cell_c
    keys = np.column_stack([2 * cell, 2 * (cell + 1) + 1, 2 * (cell + width), 2 * cell + 1])
    count = exists.sum(axis=1)
    segments = np.full((len(a), 2, 2, 2), np.nan)
    segment_keys = np.full((len(a), 2, 2), -1, dtype=np.intp)
    simple = count == 2
    # the two crossings of a simple cell, in edge order (the first two True of ``exists``)
    first = np.argmax(exists[simple], axis=1)
    second = 3 - np.argmax(exists[simple][:, ::-1], axis=1)
    order = np.column_stack([first, second])
    segments[simple, 0] = np.take_along_axis(points[simple], order[:, :, None], axis=1)
    segment_keys[simple, 0] = np.take_along_axis(keys[simple], order, axis=1)
    saddle = count == 4
    if saddle.any():
        p, k = points[saddle], keys[saddle]
        a_inside = sa[saddle][:, None]
        # inside corners a and c: cut off a (top, left) and c (right, bottom); else b and d
        segments[saddle, 0] = np.where(a_inside[:, :, None], p[:, [0, 3]], p[:, [0, 1]])
        segments[saddle, 1] = np.where(a_inside[:, :, None], p[:, [1, 2]], p[:, [3, 2]])
        segment_keys[saddle, 0] = np.where(a_inside, k[:, [0, 3]], k[:, [0, 1]])
        segment_keys[saddle, 1] = np.where(a_inside, k[:, [1, 2]], k[:, [3, 2]])
    return segments, segment_keys


def _change_cells(positive):
    """Flat indices (row * (N - 1) + col) of the grid cells whose corners are not all on one side."""
    corner = positive[:-1, :-1]
    change = corner != positive[:-1, 1:]
    change |= corner != positive[1:, 1:]
    change |= corner != positive[1:, :-1]
    return np.flatnonzero(change)


def _corners(phi, cell_r, cell_c):
    """The values (float64) at the corners a, b, c, d of the cells (cell_r, cell_c)."""
    return (phi[cell_r, cell_c].astype(np.float64), phi[cell_r, cell_c + 1].astype(np.float64),
            phi[cell_r + 1, cell_c + 1].astype(np.float64), phi[cell_r + 1, cell_c].astype(np.float64))


def level_set_contours(phi):
    """The zero level set of phi as closed sub-pixel curves, oriented as in :mod:`~activecontour.geometry`.

    Marching squares (``skimage.measure.find_contours``) on phi padded by one pixel of
    ``-|phi|`` (:func:`_closed_padding`): a region that touches the image border closes along the
    domain edge, half a pixel outside the outermost pixel centres, so every curve is closed.
    With ``positive_orientation="high"`` outer boundaries have positive signed area and holes
    negative.  Each vertex is stored once.  Only the box around the inside (and one pixel more)
    is traced: beyond it phi is negative and has no zero crossing, and the float64 copies that
    marching squares makes stay the size of that box.
    """
    phi = np.asarray(phi)
    positive = phi > 0
    rows, cols = np.flatnonzero(positive.any(axis=1)), np.flatnonzero(positive.any(axis=0))
    if rows.size == 0:
        return []
    top, left = max(rows[0] - 1, 0), max(cols[0] - 1, 0)
    box = phi[top: rows[-1] + 2, left: cols[-1] + 2]
    # the padding of a side of the box inside the image is -|phi| of negative pixels: phi itself
    return [curve + (top, left) for curve in level_curves(_closed_padding(box), 0.0)]


def _closed_padding(phi):
    """phi padded by one pixel of ``-|phi|``: the zero set closes on the domain edge (inside only)."""
    padded = np.pad(np.asarray(phi, dtype=np.float64), 1, mode="edge")
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
    positive = phi > 0
    return _edge_soup(phi, positive, _change_cells(positive))


def _edge_soup(phi, positive, cells):
    """:func:`zero_set_edges` from the cells of phi with a sign change (:func:`_change_cells`).

    Works on the cells of the padded grid of :func:`_closed_padding` without building it: the
    image's own cells with a sign change, shifted by the frame, and the frame's cells next to an
    inside pixel (the frame lies outside), with the padding's values read off phi.  O(|Gamma| +
    M + N) after the sign test.
    """
    m, n = phi.shape
    inner_r, inner_c = np.divmod(cells, n - 1)
    # frame cells of the padded (M + 2, N + 2) grid, (M + 1) x (N + 1) cells: a frame cell has a
    # sign change when one of its image corners is inside
    top = np.flatnonzero(positive[0, np.clip(np.arange(n + 1) - 1, 0, n - 1)]
                         | positive[0, np.clip(np.arange(n + 1), 0, n - 1)])
    bottom = np.flatnonzero(positive[-1, np.clip(np.arange(n + 1) - 1, 0, n - 1)]
                            | positive[-1, np.clip(np.arange(n + 1), 0, n - 1)])
    left = np.flatnonzero(positive[np.clip(np.arange(1, m) - 1, 0, m - 1), 0]
                          | positive[np.clip(np.arange(1, m), 0, m - 1), 0]) + 1
    right = np.flatnonzero(positive[np.clip(np.arange(1, m) - 1, 0, m - 1), -1]
                           | positive[np.clip(np.arange(1, m), 0, m - 1), -1]) + 1
    cell_r = np.concatenate([inner_r + 1, np.zeros(top.size, np.intp), np.full(bottom.size, m, np.intp),
                             left, right])
    cell_c = np.concatenate([inner_c + 1, top, bottom, np.zeros(left.size, np.intp),
                             np.full(right.size, n, np.intp)])
    corners = [_padded_value(phi, m, n, cell_r + dr, cell_c + dc)
               for dr, dc in ((0, 0), (0, 1), (1, 1), (1, 0))]
    segments, _ = _cell_segments(*corners, cell_r, cell_c, n + 2)
    inside = np.stack([corner > 0 for corner in corners], axis=1)
    offsets = np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]])
    base = np.column_stack([cell_r, cell_c]).astype(np.float64)
    # a point on the inside of each segment: the mean of the inside corners of a simple cell;
    # in a saddle each segment cuts off one inside corner (a and c, or b and d)
    mean_corner = np.einsum("ki,ij->kj", inside.astype(np.float64), offsets) / inside.sum(axis=1)[:, None]
    reference = np.repeat((base + mean_corner)[:, None], 2, axis=1)
    saddle = inside.sum(axis=1) == 2
    saddle &= inside[:, 0] == inside[:, 2]
    a_in = inside[saddle, 0][:, None]
    reference[saddle, 0] = base[saddle] + np.where(a_in, offsets[0], offsets[1])
    reference[saddle, 1] = base[saddle] + np.where(a_in, offsets[2], offsets[3])
    segments, reference = segments.reshape(-1, 2, 2), reference.reshape(-1, 2)
    valid = ~np.isnan(segments[:, 0, 0])
    segments, reference = segments[valid], reference[valid]
    tangent = segments[:, 1] - segments[:, 0]
    offset = reference - segments[:, 0]
    # inside on the left: (x - p) . nu < 0 for the inside point x
    flip = offset[:, 0] * tangent[:, 1] - offset[:, 1] * tangent[:, 0] > 0
    segments[flip] = segments[flip, ::-1]
    return segments - 1.0


def _padded_value(phi, m, n, row, col):
    """The values of :func:`_closed_padding` at (row, col) of the padded grid, read off phi."""
    value = phi[np.clip(row - 1, 0, m - 1), np.clip(col - 1, 0, n - 1)].astype(np.float64)
    frame = (row == 0) | (row == m + 1) | (col == 0) | (col == n + 1)
    value[frame] = -np.abs(value[frame])
    value[value == 0] = -1e-300  # phi = 0 is outside, as in the mask phi > 0
    return value
