"""Curves to masks and masks to curves, in the pixel-centre convention.

A pixel belongs to the mask when its centre (integer row, col) has a nonzero winding number with
respect to the set of closed curves: outer boundaries count +1, holes -1.  The test is exact and
costs one pass over the rows each curve spans.
"""

from __future__ import annotations

import numpy as np

from activecontour import _kernels
from activecontour.geometry.curve import curve_areas, split_curves, stack_curves, take_curves, take_vertices

__all__ = ["level_curves", "mask_to_curves", "rasterize", "sorted_crossings"]

#: pixels per band of rows in :func:`rasterize` (16 MB of int32 winding numbers)
_BAND_CELLS = 1 << 22


def rasterize(curves, shape):
    """Boolean mask of the pixel centres inside the curves (nonzero winding rule).

    Parameters
    ----------
    curves : list of ndarray (K, 2)
        Closed curves in (row, col).
    shape : tuple (M, N)

    Only the rows the curves span are visited, in bands of about ``_BAND_CELLS`` pixels, so the
    memory beyond the mask itself stays small however large the image.
    """
    m, n = shape
    mask = np.zeros((m, n), dtype=bool)
    row, first, direction = _row_crossings(curves, m, n)
    if row.size == 0:
        return mask
    order = np.argsort(row, kind="stable")
    row, first, direction = row[order], first[order], direction[order]
    band = max(1, _BAND_CELLS // (n + 1))
    for start in range(int(row[0]), int(row[-1]) + 1, band):
        low, high = np.searchsorted(row, [start, start + band])
        # winding[i, j] accumulates, at the first pixel centre right of each upward/downward
        # crossing of the row line r = start + i, the crossing's direction; a cumulative sum along
        # the row then gives the winding number of every pixel centre.
        winding = np.zeros((min(band, m - start), n + 1), dtype=np.int32)
        np.add.at(winding, (row[low:high] - start, first[low:high]), direction[low:high])
        np.cumsum(winding, axis=1, dtype=np.int32, out=winding)
        mask[start: start + len(winding)] = winding[:, :n] != 0
    return mask


def sorted_crossings(curves, shape):
    """The crossings :func:`rasterize` adds up, sorted by row, then by column: ``(row, first,
    direction)``, the pixel at ``(row, c)`` inside when the directions of its row's crossings with
    ``first <= c`` do not add up to 0.  For a compiled reader of the mask that never draws it
    (:func:`activecontour._kernels.sampled_distance`)."""
    row, first, direction = _row_crossings(curves, *shape)
    order = np.lexsort((first, row))
    return row[order], first[order], direction[order]


def _row_crossings(curves, m, n):
    """Where the edges cross the row lines r = 0..M-1: row, first pixel column to the right, +-1
    (all curves stacked, in the order of the curves and their edges)."""
    start, next_index, _ = stack_curves([np.asarray(c, dtype=np.float64) for c in curves])
    end = np.take(start, next_index, axis=0)
    r0, r1 = start[:, 0], end[:, 0]
    # half-open rule [min, max) on rows avoids counting a vertex twice
    low = np.ceil(np.minimum(r0, r1))
    high = np.ceil(np.maximum(r0, r1))
    count = np.maximum(np.clip(high, 0, m) - np.clip(low, 0, m), 0).astype(np.intp)
    edge = np.repeat(np.arange(len(start)), count)
    if edge.size == 0:
        return np.zeros(0, np.intp), np.zeros(0, np.intp), np.zeros(0, np.int32)
    rank = np.arange(edge.size) - np.repeat(np.cumsum(count) - count, count)
    row = np.clip(low, 0, m)[edge] + rank
    t = (row - r0[edge]) / (r1 - r0)[edge]
    col = start[edge, 1] + t * (end[edge, 1] - start[edge, 1])
    return (row.astype(np.intp), np.clip(np.ceil(col), 0, n).astype(np.intp),
            np.where(r1[edge] > r0[edge], 1, -1).astype(np.int32))


def mask_to_curves(mask, *, min_area=0.0, place=None):
    """Closed curves around the components (positive) and holes (negative) of a boolean mask.

    The curves are the 0.5 iso-lines of the mask padded by one pixel of False (marching squares:
    exactly ``skimage.measure.find_contours(padded, 0.5, positive_orientation="high")``, in its
    order, traced in compiled code by :func:`activecontour._kernels.mask_contours`), so they pass
    half-way between inside and outside pixel centres and :func:`rasterize` of the result gives
    the mask back.  With ``positive_orientation="high"`` the mask lies on the same side of every
    curve, which makes outer boundaries positive and holes negative in our convention.  Curves
    with ``|area| <= min_area`` are dropped.  Only the mask's bounding box is traced (the same
    curves: a small object in a large image costs its box, not the image).

    ``place``: a function of the vertices (K, 2), each the midpoint of a grid edge between a pixel
    centre in the mask and one outside it (in the mask's coordinates), returning them moved along
    their edges, before repeated vertices and small curves are dropped: the crossings of a field
    whose sign the mask is (:func:`activecontour.backends.levelset.zeroset.level_set_contours`).
    """
    mask = np.asarray(mask, dtype=bool)
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if rows.size == 0:
        return []
    box = np.ascontiguousarray(mask[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1])
    points, offsets = _kernels.mask_contours(box.view(np.uint8))
    points = np.frombuffer(points, dtype=np.float64).reshape(-1, 2) + (rows[0], cols[0])
    if place is not None:
        points = place(points)
    return _closed_curves(points, np.frombuffer(offsets, dtype=np.intp), min_area)


def level_curves(padded, level, *, min_area=0.0):
    """Closed curves where a field, padded by one pixel that lies below ``level``, crosses it.

    Marching squares (``skimage.measure.find_contours``) with ``positive_orientation="high"``:
    the side above ``level`` is inside, so outer boundaries are positive and holes negative.  The
    closing vertex and repeated vertices are dropped and the padding is shifted away; curves with
    ``|area| <= min_area`` are dropped.
    """
    import skimage.measure

    contours = skimage.measure.find_contours(padded, level, positive_orientation="high")
    if not contours:
        return []
    points, _, offsets = stack_curves([contour[:-1] for contour in contours])
    return _closed_curves(points - 1.0, offsets, min_area)


def _closed_curves(points, offsets, min_area):
    """The stacked curves without every vertex equal to the one before it (cyclically), then
    without those with fewer than 3 vertices or ``|area| <= min_area``, as a list."""
    previous = np.arange(-1, len(points) - 1)
    filled = np.diff(offsets) > 0
    previous[offsets[:-1][filled]] = offsets[1:][filled] - 1
    distinct = np.any(points != np.take(points, previous, axis=0), axis=1)
    points, next_index, offsets = take_vertices(points, offsets, distinct)
    areas = curve_areas(points, next_index, offsets)
    keep = (np.diff(offsets) >= 3) & (np.abs(areas) > min_area)
    points, _, offsets = take_curves(points, offsets, keep)
    return split_curves(points, offsets)
