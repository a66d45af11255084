"""The sub-pixel partition of the image domain that a label image stands for.

A label image ``classes`` (M, N) says which region each pixel centre belongs to.  The regions it
stands for partition the domain ``D = [-0.5, M - 0.5] x [-0.5, N - 0.5]`` exactly (no gap, no
overlap) along boundaries through the midpoints between pixel centres of different classes, in
each grid cell (the square between four neighbouring pixel centres):

* two classes, not diagonal (a saddle): one straight segment between the midpoints of the two
  cell edges whose ends differ: marching squares of the class indicator at level 1/2, the rule of
  :func:`skimage.measure.find_contours` on a binary image;
* two classes on the diagonals (a saddle): the corners of the larger class are cut off (two
  segments), those of the smaller one stay connected;
* three or four classes: a junction at the cell centre, joined to the midpoint of every cell edge
  whose ends differ.

Along the domain's edge the pixel's class extends to the border (the image is extended by its
edge pixels), so an interface meets the border at right angles, halfway between two pixels.

The boundary is returned as oriented segments with the class on each side: ``inner`` on the side
opposite the normal ``nu = (t_c, -t_r)``, ``outer`` on the normal's side, -1 outside the domain.
That is all Green's theorem needs: the moments of region k are the edge integrals over the
segments with ``inner == k`` plus those with ``outer == k`` reversed
(:func:`activecontour.energy.partition_moments`).  A two-class image gives the marching-squares
contours of its class-1 indicator, so the two-region and the N-region evaluators agree on it.
"""

from __future__ import annotations

import numpy as np

from activecontour import _kernels

__all__ = ["Boundary", "Sides", "chain", "chain_loops", "class_boundary", "class_soup", "lattice_keys",
           "loop_order"]


class Boundary:
    """Oriented segments of a partition with the class on each side.

    Attributes
    ----------
    start, end : ndarray (S, 2)
        Segment ends in (row, col).
    inner, outer : ndarray (S,) int
        The class on the inner side (opposite the normal) and the outer side; ``outer == -1`` on
        the domain's edge.
    sides : Sides
        Which segments bound which class (computed once for segments that keep their classes
        while they move: pass it to the moved boundary).
    """

    def __init__(self, start, end, inner, outer, sides=None):
        self.start, self.end, self.inner, self.outer = start, end, inner, outer
        self.sides = Sides(inner, outer) if sides is None else sides

    @property
    def length(self):
        d = self.end - self.start
        return np.hypot(d[:, 0], d[:, 1])


class Sides:
    """The segments on each class's boundary, found when first asked."""

    def __init__(self, inner, outer):
        self._inner, self._outer = inner, outer
        self._soups = {}

    def of_class(self, k):
        """``(segments with inner == k, segments with outer == k)``."""
        if k not in self._soups:
            self._soups[k] = (np.flatnonzero(self._inner == k), np.flatnonzero(self._outer == k))
        return self._soups[k]


def class_boundary(classes):
    """The oriented boundary segments of the partition a label image stands for (module docstring).

    Parameters
    ----------
    classes : int ndarray (M, N)

    Returns
    -------
    Boundary
    """
    classes = np.asarray(classes)
    m, n = classes.shape
    padded = np.pad(classes.astype(np.int64), 1, mode="edge")
    tl, tr = padded[:-1, :-1], padded[:-1, 1:]
    bl, br = padded[1:, :-1], padded[1:, 1:]
    changes = np.stack([tl != tr, tr != br, bl != br, tl != bl])  # top, right, bottom, left
    count = changes.sum(axis=0)
    rows, cols = np.nonzero(count)
    tl, tr, br, bl = tl[rows, cols], tr[rows, cols], br[rows, cols], bl[rows, cols]
    changes = changes[:, rows, cols]
    count = count[rows, cols]
    # cell (a, j) spans image rows a - 1 .. a and columns j - 1 .. j
    top, left = rows - 1.0, cols - 1.0
    corner = {"tl": (top, left), "tr": (top, left + 1), "br": (top + 1, left + 1), "bl": (top + 1, left)}
    label = {"tl": tl, "tr": tr, "br": br, "bl": bl}
    # each cell edge: its midpoint and its two corners
    edges = [(("tl", "tr"), (top, left + 0.5)), (("tr", "br"), (top + 0.5, left + 1)),
             (("bl", "br"), (top + 1, left + 0.5)), (("tl", "bl"), (top + 0.5, left))]
    centre = (top + 0.5, left + 0.5)
    pieces = []  # per group: start r, start c, end r, end c, corner r, corner c, its class, other

    def add(where, start, end, first, second):
        """Segments in cells ``where`` separating corner ``first`` from corner ``second``."""
        p, q = corner[first]
        pieces.append((start[0][where], start[1][where], end[0][where], end[1][where], p[where],
                       q[where], label[first][where], label[second][where]))

    saddle = (count == 4) & (tl == br) & (tr == bl)
    junction = (count >= 3) & ~saddle
    straight = count == 2
    # two classes: the segment between the two changed edges' midpoints separates the corners of
    # either changed edge
    for i in range(4):
        for k in range(i + 1, 4):
            where = straight & changes[i] & changes[k]
            add(where, edges[i][1], edges[k][1], *edges[i][0])
    # saddles: cut off the corners of the larger class
    cut_tl = saddle & (tl > tr)  # tl, br are cut
    cut_tr = saddle & ~(tl > tr)
    add(cut_tl, edges[0][1], edges[3][1], "tl", "tr")
    add(cut_tl, edges[1][1], edges[2][1], "br", "tr")
    add(cut_tr, edges[0][1], edges[1][1], "tr", "tl")
    add(cut_tr, edges[3][1], edges[2][1], "bl", "tl")
    # junctions: centre to every changed edge's midpoint, between that edge's corners
    for i in range(4):
        add(junction & changes[i], centre, edges[i][1], *edges[i][0])
    start_r, start_c, end_r, end_c, corner_r, corner_c, first_label, other_label = (
        np.concatenate(parts) for parts in zip(*pieces, strict=True))
    start = np.column_stack([start_r, start_c])
    end = np.column_stack([end_r, end_c])
    tangent = end - start
    # nu . (corner - start) > 0: the corner lies on the normal's (outer) side
    corner_outer = tangent[:, 1] * (corner_r - start_r) - tangent[:, 0] * (corner_c - start_c) > 0
    inner = np.where(corner_outer, other_label, first_label)
    outer = np.where(corner_outer, first_label, other_label)
    start, end = _clip(start, m, n), _clip(end, m, n)
    interior = np.any(start != end, axis=1)
    border_start, border_end, border_class = _border(classes)
    return Boundary(np.vstack([start[interior], border_start]), np.vstack([end[interior], border_end]),
                    np.concatenate([inner[interior], border_class]),
                    np.concatenate([outer[interior], np.full(len(border_class), -1)]))


def _clip(points, m, n):
    """Onto the domain: the segments outside it are the perpendicular ends of interfaces at the
    border (module docstring), so clipping their ends is exact."""
    return np.column_stack([np.clip(points[:, 0], -0.5, m - 0.5), np.clip(points[:, 1], -0.5, n - 0.5)])


def _border(classes):
    """The domain's edge, one unit piece per border pixel side, oriented with the normal out of D."""
    m, n = classes.shape
    j, i = np.arange(n, dtype=np.float64), np.arange(m, dtype=np.float64)
    starts, ends, labels = [], [], []
    # top (normal -r): travel towards -c; bottom (+r): towards +c; left (-c): towards +r;
    # right (+c): towards -r
    starts.append(np.column_stack([np.full(n, -0.5), j + 0.5]))
    ends.append(np.column_stack([np.full(n, -0.5), j - 0.5]))
    labels.append(classes[0])
    starts.append(np.column_stack([np.full(n, m - 0.5), j - 0.5]))
    ends.append(np.column_stack([np.full(n, m - 0.5), j + 0.5]))
    labels.append(classes[-1])
    starts.append(np.column_stack([i - 0.5, np.full(m, -0.5)]))
    ends.append(np.column_stack([i + 0.5, np.full(m, -0.5)]))
    labels.append(classes[:, 0])
    starts.append(np.column_stack([i + 0.5, np.full(m, n - 0.5)]))
    ends.append(np.column_stack([i - 0.5, np.full(m, n - 0.5)]))
    labels.append(classes[:, -1])
    return np.vstack(starts), np.vstack(ends), np.concatenate(labels).astype(np.int64)


def class_soup(boundary, k):
    """Region k's boundary as oriented segments (starts, ends): its inner segments as they are,
    its outer ones reversed."""
    inner, outer = boundary.sides.of_class(k)
    return (np.vstack([boundary.start[inner], boundary.end[outer]]),
            np.vstack([boundary.end[inner], boundary.start[outer]]))


def chain(starts, ends):
    """Link oriented segments end to start into closed curves (list of (K, 2) arrays).

    Segment ends lie on the half-pixel lattice (midpoints and cell centres), so they are matched
    exactly.  Where a region pinches (two of its corners meet at a junction) a point has two
    outgoing segments; either pairing gives closed curves of the same region.  Vertices inside
    straight runs are dropped.
    """
    if len(starts) == 0:
        return []
    return [_corners(starts[loop]) for loop in chain_loops(lattice_keys(starts), lattice_keys(ends))]


def chain_loops(start_keys, end_keys, distinct=None):
    """The closed loops of oriented segments given by the keys of their ends (equal keys: the same
    point), each as the indices of its segments in order (:func:`loop_order`)."""
    order, offsets = loop_order(start_keys, end_keys, distinct)
    return np.split(order, offsets[1:-1]) if len(offsets) > 1 else []


def loop_order(start_keys, end_keys, distinct=None):
    """:func:`chain_loops` as one array: ``(order, offsets)``, loop l the segments
    ``order[offsets[l]:offsets[l + 1]]``.  Given ``distinct``, the keys are dense ids
    0..distinct-1 (a node's index): the loops are then found in O(n + distinct)
    (:func:`activecontour._kernels.follow`, :func:`~activecontour._kernels.passes_twice`), the same
    as by sorting.

    The i-th segment ending at a point continues with the i-th starting there.  Where a region
    is pinched at a point (two of its corners meet at a junction), that pairing can make one
    loop that passes the point twice (a figure eight, which bounds no polygon); such a loop is
    cut there into two, each closed: two pieces that touch, or an outer boundary and a hole
    that touches it (:func:`activecontour._kernels.untwist`: at the smallest key passed twice,
    recursively, the piece between its first two passes first).  Loops come in the order of
    their smallest segment index, each cut loop's pieces in its place.
    """
    order, offsets = np.empty(len(start_keys), dtype=np.intp), np.empty(len(start_keys) + 1, dtype=np.intp)
    if len(start_keys) == 0:
        offsets[0] = 0
        return order, offsets
    if distinct is not None:
        ids = np.ascontiguousarray(start_keys, dtype=np.intp)
        following = np.empty(len(ids), dtype=np.intp)
        _kernels.follow(ids, np.ascontiguousarray(end_keys, dtype=np.intp), distinct, following)
        count = _kernels.cycles(following, order, offsets)
        offsets = offsets[:count + 1]
        twice = np.empty(count, dtype=np.uint8)
        _kernels.passes_twice(order, offsets, ids, distinct, twice)
        return _untwisted(order, offsets, twice, ids, distinct)
    sorted_order = np.argsort(start_keys, kind="stable")
    sorted_keys = start_keys[sorted_order]
    end_order = np.argsort(end_keys, kind="stable")
    following = np.empty(len(start_keys), dtype=np.intp)
    position = np.searchsorted(sorted_keys, end_keys[end_order])
    rank = np.arange(len(end_order)) - np.searchsorted(end_keys[end_order], end_keys[end_order])
    following[end_order] = sorted_order[position + rank]
    count = _kernels.cycles(following, order, offsets)
    offsets = offsets[:count + 1]
    # the loops that pass a point twice: equal keys side by side once sorted within each loop
    loop_of = np.repeat(np.arange(count), np.diff(offsets))
    keys = start_keys[order]
    by_key = np.lexsort((keys, loop_of))
    twice = np.zeros(count, dtype=np.uint8)
    same = (keys[by_key[1:]] == keys[by_key[:-1]]) & (loop_of[by_key[1:]] == loop_of[by_key[:-1]])
    twice[loop_of[by_key[1:]][same]] = 1
    if not twice.any():
        return order, offsets
    keys, ids = np.unique(start_keys, return_inverse=True)
    return _untwisted(order, offsets, twice, ids.astype(np.intp).ravel(), len(keys))


def _untwisted(order, offsets, twice, ids, distinct):
    """:func:`loop_order`'s loops cut where they pass a point twice (``twice``), the points' dense
    ids ``ids`` (0..distinct-1, in the order of their keys)."""
    if not twice.any():
        return order, offsets
    out, out_offsets = np.empty_like(order), np.empty(len(order) + 1, dtype=np.intp)
    loops = _kernels.untwist(order, offsets, twice, ids, distinct, out, out_offsets)
    return out, out_offsets[:loops + 1]


def _corners(curve):
    """The curve without its vertices inside straight runs (exactly collinear on the half-pixel
    lattice): the same polygon, a fraction of the vertices."""
    before = curve - np.roll(curve, 1, axis=0)
    after = np.roll(curve, -1, axis=0) - curve
    turn = before[:, 0] * after[:, 1] - before[:, 1] * after[:, 0]
    straight = (turn == 0) & (np.einsum("ij,ij->i", before, after) > 0)
    return curve[~straight] if np.count_nonzero(~straight) >= 3 else curve


def lattice_keys(points):
    """One integer per point of the half-pixel lattice (equal points, equal keys)."""
    twice = np.rint(2.0 * points).astype(np.int64) + 2
    return twice[:, 0] * (1 << 32) + twice[:, 1]
