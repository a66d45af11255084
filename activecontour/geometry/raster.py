"""Curves to masks and masks to curves, in the pixel-centre convention.

A pixel belongs to the mask when its centre (integer row, col) has a nonzero winding number with
respect to the set of closed curves: outer boundaries count +1, holes -1.  The test is exact and
costs one pass over the rows each curve spans.
"""

from __future__ import annotations

import numpy as np

from activecontour.geometry.curve import signed_area

__all__ = ["level_curves", "mask_to_curves", "rasterize"]

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


def _row_crossings(curves, m, n):
    """Where the edges cross the row lines r = 0..M-1: row, first pixel column to the right, +-1."""
    rows, firsts, directions = [np.zeros(0, np.intp)], [np.zeros(0, np.intp)], [np.zeros(0, np.int32)]
    for curve in curves:
        start = np.asarray(curve, dtype=np.float64)
        end = np.roll(start, -1, axis=0)
        r0, r1 = start[:, 0], end[:, 0]
        # half-open rule [min, max) on rows avoids counting a vertex twice
        low = np.ceil(np.minimum(r0, r1))
        high = np.ceil(np.maximum(r0, r1))
        count = np.clip(high, 0, m) - np.clip(low, 0, m)
        count = np.maximum(count, 0).astype(np.intp)
        edge = np.repeat(np.arange(len(start)), count)
        if edge.size == 0:
            continue
        rank = np.arange(edge.size) - np.repeat(np.cumsum(count) - count, count)
        row = np.clip(low, 0, m)[edge] + rank
        t = (row - r0[edge]) / (r1 - r0)[edge]
        col = start[edge, 1] + t * (end[edge, 1] - start[edge, 1])
        rows.append(row.astype(np.intp))
        firsts.append(np.clip(np.ceil(col), 0, n).astype(np.intp))
        directions.append(np.where(r1[edge] > r0[edge], 1, -1).astype(np.int32))
    return np.concatenate(rows), np.concatenate(firsts), np.concatenate(directions)


def mask_to_curves(mask, *, min_area=0.0):
    """Closed curves around the components (positive) and holes (negative) of a boolean mask.

    The curves are the 0.5 iso-lines of the mask (marching squares,
    ``skimage.measure.find_contours``), so they pass half-way between inside and outside pixel
    centres and :func:`rasterize` of the result gives the mask back.  With
    ``positive_orientation="high"`` the mask lies on the same side of every curve, which makes
    outer boundaries positive and holes negative in our convention.  Curves with
    ``|area| <= min_area`` are dropped.  Only the mask's bounding box is traced (the same curves:
    a small object in a large image costs its box, not the image).
    """
    mask = np.asarray(mask, dtype=bool)
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if rows.size == 0:
        return []
    padded = np.pad(mask[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1], 1).astype(np.float64)
    return [curve + (rows[0], cols[0]) for curve in level_curves(padded, 0.5, min_area=min_area)]


def level_curves(padded, level, *, min_area=0.0):
    """Closed curves where a field, padded by one pixel that lies below ``level``, crosses it.

    Marching squares (``skimage.measure.find_contours``) with ``positive_orientation="high"``:
    the side above ``level`` is inside, so outer boundaries are positive and holes negative.  The
    closing vertex and repeated vertices are dropped and the padding is shifted away; curves with
    ``|area| <= min_area`` are dropped.
    """
    import skimage.measure

    curves = []
    for contour in skimage.measure.find_contours(padded, level, positive_orientation="high"):
        curve = contour[:-1] - 1.0
        curve = curve[np.any(curve != np.roll(curve, 1, axis=0), axis=1)]
        if len(curve) >= 3 and abs(signed_area(curve)) > min_area:
            curves.append(curve)
    return curves
