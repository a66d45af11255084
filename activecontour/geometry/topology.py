"""Topology of a set of closed polygons: crossings, and their repair into the boundary of {w > 0}.

The curves carry orientation (outer boundaries positive, holes negative), so every point x of the
plane has a winding number w(x).  Where the flow has pushed two pieces of curve through each other
(a pinching neck, two fronts meeting, a curve running into another) the winding number takes values
other than 0 and 1: an overlap of two objects has w = 2; a neck whose sides crossed leaves a pocket
with w = -1.  The segmentation is the region {w > 0}.  :func:`repair` rebuilds the curves as exactly
its boundary, which splits curves, merges them, and opens or closes holes in one rule:

* every edge is cut at its crossings with other edges; a piece between two crossings is a *chain*;
* a chain is kept when the winding number just to its right (the side its normal points to, out of
  Omega_i) is 0, so its left side has w = 1: it separates {w > 0} from {w <= 0};
* kept chains are linked at the crossings into closed curves, which keep their orientation.

The geometry is exact (crossing points are computed, nothing is resampled), so the region changes
only where the winding number was not 0 or 1.  The curves stay stacked (one vertex array, the
offsets of the curves) throughout: crossings are found in compiled code through a uniform grid of
cells about one edge long, winding numbers through bands of rows, and only the curves that cross
are cut into chains, so an iteration costs O(K) on average, however many curves there are.
"""

from __future__ import annotations

import numpy as np

from activecontour import _kernels
from activecontour.geometry.curve import (
    curve_areas,
    signed_area,
    split_curves,
    stack_curves,
    stacked_next,
    take_curves,
)
from activecontour.geometry.regions import nesting
from activecontour.geometry.regions import polygons as valid_polygons

__all__ = ["border_overlap", "crossings", "curve_areas", "nucleation_sites", "region_problem",
           "region_union", "repair", "repair_stacked", "winding_number"]

#: pixels per band of rows in :func:`nucleation_sites` (a few float32 arrays of 16 MB)
_BAND_PIXELS = 1 << 22
#: probe-vertex pairs below which :func:`winding_number` makes one pass over every edge
_DIRECT_WORK = 1 << 12
#: pixels: a chain's first segment shorter than this does not place its probe (:func:`_right_probes`)
_SHORT_SEGMENT = 1e-3
#: crossings the output arrays of :func:`crossings` hold at first
_CROSSINGS = 64


def crossings(points, next_index):
    """Pairs of non-adjacent edges that cross, with the crossing's parameter on each edge.

    Found in compiled code (:func:`activecontour._kernels.segments_meet`, the network's test too:
    a uniform grid, O(K)).

    Returns
    -------
    first, second : ndarray of int
        Edge indices (edge e joins ``e`` and ``next_index[e]``), ``first < second``, sorted.
    s, t : ndarray of float
        The crossing is ``X[first] + s (X[next[first]] - X[first])``, likewise t on ``second``;
        both strictly inside (0, 1).
    """
    points = np.ascontiguousarray(points, dtype=np.float64)
    start, end = np.arange(len(points)), np.ascontiguousarray(next_index, dtype=np.intp)
    capacity = _CROSSINGS
    while True:
        pairs, where = np.empty((capacity, 2), dtype=np.intp), np.empty((capacity, 2))
        found = _kernels.segments_meet(points, start, end, False, len(points) ** 2, pairs, where)
        if found <= capacity:
            break
        capacity = found
    pairs, where = pairs[:found], where[:found]
    order = np.lexsort((pairs[:, 1], pairs[:, 0]))
    return pairs[order, 0], pairs[order, 1], where[order, 0], where[order, 1]


def winding_number(points, next_index, probes):
    """Winding number of each probe point (P, 2) with respect to the oriented curves.

    Many probes go through bands of rows (:func:`activecontour._kernels.winding_banded`): a probe
    meets the edges of its band only, so many curves cost O(P + K), not O(P K).
    """
    probes = np.ascontiguousarray(probes, dtype=np.float64).reshape(-1, 2)
    points = np.ascontiguousarray(points, dtype=np.float64)
    next_index = np.ascontiguousarray(next_index, dtype=np.intp)
    out = np.empty(len(probes), dtype=np.int64)
    if len(probes) * len(points) <= _DIRECT_WORK:
        _kernels.winding(points, next_index, probes, out)
    else:
        _kernels.winding_banded(points, np.arange(len(points)), next_index, probes, out)
    return out


def repair(points, next_index, offsets, *, min_area=0.0, before=None):
    """Rebuild the curves as the boundary of {w > 0}; None when they already are.

    :func:`repair_stacked`, as a list of (K, 2) curves.
    """
    repaired = repair_stacked(points, next_index, offsets, min_area=min_area, before=before)
    return None if repaired is None else split_curves(repaired[0], repaired[2])


def repair_stacked(points, next_index, offsets, *, min_area=0.0, before=None):
    """Rebuild the curves as the boundary of {w > 0}; None when they already are.

    They are when no edges cross and every curve has w = 0 on its right.  A step can turn a
    whole curve over without any crossing left at its end (a sliver whose sides pass each other,
    a small curve jumped across itself): alone it bounds a region of w = -1, inside an object
    (positive, within another positive curve) one of w = 2; such a curve is no boundary of
    {w > 0} and is dropped, like any chain between crossings.

    Only the curves that cross are cut into chains (a Python loop over those); every other curve
    is one closed chain, kept or dropped whole in the stacked arrays.

    Parameters
    ----------
    points, next_index, offsets : as from :func:`activecontour.energy.stack_curves`
    min_area : float
        Curves enclosing less than this (absolute) area are dropped.
    before : ndarray or None
        The signed areas of the same curves in a state that bounded a region (the iterate a
        step starts from, the curves a resampling starts from).  Without crossings, only the
        curves whose orientation changed are then probed.  (A curve that jumps whole into or out
        of another in one step, keeping its orientation, is not looked for then.)

    Returns
    -------
    (points, next_index, offsets) or None
        The repaired curves stacked: the curves that were kept whole, in their order, then the
        curves linked from chains.
    """
    first, second, s, t = crossings(points, next_index)
    n_points, n_cross, n_curves = len(points), first.size, len(offsets) - 1
    if n_cross == 0:  # every curve is one closed chain: the common case
        turned = _right_windings(points, next_index, offsets, before) != 0
        if not turned.any():
            return None
        areas = curve_areas(points, next_index, offsets)
        return take_curves(points, offsets, ~turned & (np.diff(offsets) >= 3) & (np.abs(areas) > min_area))
    owner = np.repeat(np.arange(n_curves), np.diff(offsets))
    cut = np.zeros(n_curves, dtype=bool)
    cut[owner[first]] = cut[owner[second]] = True
    cross_points = points[first] + s[:, None] * (points[next_index[first]] - points[first])
    nodes = np.vstack([points, cross_points])
    # Every cut curve's node sequence with its crossings inserted in order along each edge: vertex
    # e sorts at key e, a crossing at parameter s of edge e at e + s (curves are stacked in order).
    vertices = np.flatnonzero(cut[owner])
    cut_edge = np.concatenate([first, second])
    keys = np.concatenate([vertices.astype(np.float64), cut_edge + np.concatenate([s, t])])
    node_ids = np.concatenate([vertices, np.tile(np.arange(n_cross), 2) + n_points])
    order = np.argsort(keys, kind="stable")
    sequence = node_ids[order]
    bounds = np.append(np.searchsorted(keys[order], offsets[:-1][cut].astype(np.float64)), len(sequence))
    chains = []
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        chains.extend(_chains(sequence[a:b], n_points))
    whole = np.flatnonzero(~cut)  # closed chains, probed by the same rule as the chains
    probes = np.vstack([_right_probes(chains, nodes), _closed_probes(points, next_index, offsets, whole)])
    windings = winding_number(points, next_index, probes)
    kept = np.zeros(n_curves, dtype=bool)
    kept[whole] = windings[len(chains):] == 0
    linked = _link([chain for chain, w in zip(chains, windings[:len(chains)], strict=True) if w == 0], nodes,
                   n_points)
    kept_points, _, kept_offsets = take_curves(points, offsets, kept)
    # the linked curves stacked after the kept ones (no list of the kept curves: there are many)
    linked_offsets = kept_offsets[-1] + np.cumsum([len(curve) for curve in linked], dtype=np.intp)
    repaired_offsets = np.concatenate([kept_offsets, linked_offsets])
    repaired = (np.concatenate([kept_points] + linked), stacked_next(repaired_offsets), repaired_offsets)
    areas = curve_areas(*repaired)
    return take_curves(repaired[0], repaired[2], (np.diff(repaired[2]) >= 3) & (np.abs(areas) > min_area))


def border_overlap(points, next_index, bounds):
    """Whether two edges lying on the same side of the image domain overlap (positive length).

    Vertices clipped to the domain's border can run along it twice, forwards and back, or in the
    same direction: collinear overlaps, which :func:`crossings` (proper crossings only) does not
    see, and which make a winding number of 2 (a double-counted strip) or a zero-width slit.  A
    region's boundary covers every point of the border at most once, and each corner at most once.
    """
    # one pass over the edges in compiled code; per side, the edges on it sorted by their low end
    # (ties in edge order), an edge that starts before the farthest reach of the earlier ones
    return bool(_kernels.border_overlap(np.ascontiguousarray(points, dtype=np.float64),
                                        np.ascontiguousarray(next_index, dtype=np.intp),
                                        np.ascontiguousarray(bounds, dtype=np.float64)))


def region_problem(curves, nested=None):
    """Why oriented closed curves do not bound a region, or None when they do.

    They bound one when every curve is a simple polygon (no self-crossing, no self-touching), no
    two curves cross or overlap (touching at isolated points is allowed), and the orientation
    follows the nesting: a curve inside an even number of the others is an outer boundary
    (positive signed area), inside an odd number a hole (negative).  Then the winding number is
    0 or 1 everywhere and (6.38) is defined: shapely's ``is_valid`` holds for the polygons with
    their holes.  Crossing or overlapping input (winding numbers 2 or -1) gives an energy of no
    region, such as -1e12 for a curve run twice along the image border.

    Parameters
    ----------
    curves : list of ndarray (K, 2)
    nested : tuple, optional
        :func:`activecontour.geometry.regions.nesting` of the curves' polygons when the caller has
        it (as :func:`activecontour.geometry.regions.orient_by_nesting`'s caller does): it is not
        computed again.  Nesting does not depend on orientation, so the curves before orienting
        give the same.

    Returns
    -------
    str or None
        One short line naming the first curve at fault.
    """
    import shapely

    if not curves:
        return None
    points, next_index, offsets = stack_curves([np.asarray(c, dtype=np.float64) for c in curves])
    counts = np.diff(offsets)
    # every curve a polygon, all at once (a ring needs 3 vertices: shorter curves are made alone,
    # which raises as a Polygon of them would)
    if counts.min() < 3:
        polygons = np.array([shapely.Polygon(c) for c in curves], dtype=object)
    else:
        closing = np.insert(np.arange(len(points)), offsets[1:], offsets[:-1])
        rings = shapely.linearrings(points[closing], indices=np.repeat(np.arange(len(curves)), counts + 1))
        polygons = shapely.polygons(rings)
    invalid = np.flatnonzero(~shapely.is_valid(polygons))
    if invalid.size:
        i = int(invalid[0])
        return f"contours[{i}] crosses or touches itself ({shapely.is_valid_reason(polygons[i])})"
    depth, parent, same = nesting(polygons) if nested is None else nested
    if same:
        return f"contours[{same[0][0]}] and contours[{same[0][1]}] are the same curve"
    areas = curve_areas(points, next_index, offsets)
    wrong = np.flatnonzero((areas > 0) != (depth % 2 == 0))
    if wrong.size:
        i = int(wrong[0])
        return (f"contours[{i}] is {'positively' if areas[i] > 0 else 'negatively'} oriented inside "
                f"{depth[i]} other contours: outer boundaries must be positive and holes negative, "
                "and no contour may cross another")
    holes = {i: [] for i in np.flatnonzero(depth % 2 == 0).tolist()}
    for i in np.flatnonzero(depth % 2 == 1).tolist():
        if parent[i] in holes:
            holes[parent[i]].append(shapely.get_exterior_ring(polygons[i]))
    shells = [shapely.Polygon(shapely.get_exterior_ring(polygons[i]), holes[i]) for i in holes]
    region = shapely.MultiPolygon(shells)
    if not shapely.is_valid(region):
        return f"the contours cross or overlap each other ({shapely.is_valid_reason(region)})"
    return None


def region_union(curves, *, signed=False):
    """The boundary of the region that nested, overlapping or duplicated curves outline.

    Each curve's polygon (made valid: a self-crossing curve is the union of its loops) is added
    to the region when it lies inside an even number of the others and cut out of it when inside
    an odd number, in order of nesting depth: overlapping outlines merge, a curve given twice
    counts once, nested curves alternate between object and hole.  With ``signed`` the curves'
    own orientation says which is which instead (positive added, negative cut out, the larger
    first): the region {w > 0} of curves whose winding number is 0 or 1 but which touch
    themselves or each other, as a backend's may.  The result obeys :func:`region_problem`:
    outer boundaries positive, holes negative, each vertex once.

    Returns
    -------
    list of ndarray (K, 2)
    """
    import shapely
    from shapely.geometry.polygon import orient

    polygons = valid_polygons(curves)
    if signed:
        areas = np.array([signed_area(np.asarray(c, dtype=np.float64)) for c in curves])
        order, adds = np.argsort(-np.abs(areas), kind="stable"), areas > 0
    else:
        depth = nesting(polygons)[0]
        order, adds = np.argsort(depth, kind="stable"), depth % 2 == 0
    region = shapely.Polygon()
    for i in order:
        region = region.union(polygons[i]) if adds[i] else region.difference(polygons[i])
    out = []
    for polygon in shapely.get_parts(region):
        if isinstance(polygon, shapely.Polygon) and polygon.area > 0:
            polygon = orient(polygon, sign=1.0)  # x = row, y = col: counterclockwise is positive
            out.append(np.asarray(polygon.exterior.coords)[:-1])
            out.extend(np.asarray(ring.coords)[:-1] for ring in polygon.interiors)
    return out


def _chains(sequence, n_points):
    """Split one curve's cyclic node sequence at its crossing nodes (ids >= n_points) into chains
    from crossing to crossing; a curve without crossings is one closed chain."""
    marks = np.nonzero(sequence >= n_points)[0]
    if marks.size == 0:
        return [np.append(sequence, sequence[0])]
    rotated = np.roll(sequence, -marks[0])
    cuts = np.append(marks - marks[0], len(rotated))
    closed = np.append(rotated, rotated[0])
    return [closed[a: b + 1] for a, b in zip(cuts[:-1], cuts[1:], strict=True)]


def _right_windings(points, next_index, offsets, before=None):
    """The winding number just right of every stacked curve, beside its longest edge (for the
    closed chains of curves without crossings).

    Without ``before`` every curve is probed (a positive curve in no other has 0 there); with the
    areas ``before`` of :func:`repair_stacked`, only the curves whose orientation changed.
    """
    n_curves = len(offsets) - 1
    out = np.zeros(n_curves, dtype=np.int64)
    if before is None:
        suspect = np.ones(n_curves, dtype=bool)
    else:
        suspect = (curve_areas(points, next_index, offsets) > 0) != (np.asarray(before) > 0)
    if suspect.any():
        edges = np.flatnonzero(np.repeat(suspect, np.diff(offsets)))
        owner = np.repeat(np.arange(n_curves), np.diff(offsets))[edges]
        probes = _beside_longest(points[edges], points[next_index[edges]], owner)
        out[suspect] = winding_number(points, next_index, probes)
    return out


def _closed_probes(points, next_index, offsets, which):
    """A point just right of each stacked curve ``which`` (indices), by the rule of
    :func:`_right_probes` for the closed chain of the curve: beside its first edge, or where that
    is shorter than ``_SHORT_SEGMENT``, its longest."""
    if len(which) == 0:
        return np.zeros((0, 2))
    starts = offsets[:-1][which]
    ends = next_index[starts]
    probes = _beside_longest(points[starts], points[ends], np.arange(len(which)))
    direction = points[ends] - points[starts]
    short = np.flatnonzero(np.hypot(direction[:, 0], direction[:, 1]) < _SHORT_SEGMENT)
    if short.size:
        counts = np.diff(offsets)[which[short]]
        owner = np.repeat(np.arange(short.size), counts)
        edges = np.arange(counts.sum()) + np.repeat(starts[short] - np.cumsum(counts) + counts, counts)
        probes[short] = _beside_longest(points[edges], points[next_index[edges]], owner)
    return probes


def _right_probes(chains, nodes):
    """A point just right of each chain: beside its first segment, or where that is shorter
    than ``_SHORT_SEGMENT`` (clipping to the border makes such), its longest
    (:func:`_beside_longest`)."""
    owner = np.arange(len(chains))
    starts, ends = nodes[[c[0] for c in chains]], nodes[[c[1] for c in chains]]
    probes = _beside_longest(starts, ends, owner)
    direction = ends - starts
    short = np.flatnonzero(np.hypot(direction[:, 0], direction[:, 1]) < _SHORT_SEGMENT)
    if short.size:
        segments = [chains[k] for k in short]
        first = np.concatenate([c[:-1] for c in segments])
        second = np.concatenate([c[1:] for c in segments])
        owner = np.repeat(np.arange(short.size), [len(c) - 1 for c in segments])
        probes[short] = _beside_longest(nodes[first], nodes[second], owner)
    return probes


def _beside_longest(starts, ends, owner):
    """For each owner (sorted ids) of segments ``starts -> ends``: a point just right of the
    middle of its longest segment, so that a segment of (nearly) zero length, as clipping to the
    border makes, never places it on the curves themselves."""
    direction = ends - starts
    length = np.hypot(direction[:, 0], direction[:, 1])
    order = np.lexsort((-length, owner))
    longest = order[np.r_[True, owner[order][1:] != owner[order][:-1]]]  # the first of each owner
    direction, length = direction[longest], np.maximum(length[longest], 1e-300)
    normal = np.column_stack([direction[:, 1], -direction[:, 0]]) / length[:, None]
    middle = starts[longest] + 0.5 * direction
    return middle + normal * np.minimum(1e-6, 1e-3 * length)[:, None]


def _link(kept, nodes, n_points):
    """Join chains end to start at the crossings into closed curves (most-left turn on ties)."""
    curves = []
    open_chains = []
    for chain in kept:
        if chain[0] == chain[-1] and chain[0] < n_points:
            curves.append(nodes[chain[:-1]])
        else:
            open_chains.append(chain)
    starting = {}
    for index, chain in enumerate(open_chains):
        starting.setdefault(chain[0], []).append(index)
    used = np.zeros(len(open_chains), dtype=bool)
    for index in range(len(open_chains)):
        if used[index]:
            continue
        loop, current = [], index
        while current is not None and not used[current]:
            used[current] = True
            chain = open_chains[current]
            loop.extend(chain[:-1])
            candidates = [c for c in starting.get(chain[-1], []) if not used[c]]
            if not candidates:
                current = None
            elif len(candidates) == 1:
                current = candidates[0]
            else:
                incoming = nodes[chain[-1]] - nodes[chain[-2]]
                turns = []
                for c in candidates:
                    outgoing = nodes[open_chains[c][1]] - nodes[open_chains[c][0]]
                    cross = incoming[0] * outgoing[1] - incoming[1] * outgoing[0]
                    turns.append(np.arctan2(cross, incoming @ outgoing))
                current = candidates[int(np.argmax(turns))]
        if len(loop) >= 3:
            curves.append(nodes[loop])
    return curves


#: the float32 filters' error on a disk's mean of g, relative to the size of its terms (k taps
#: in float32 err by ~k 6e-8 of it: 3e-6 for the 49 of radius 4): :func:`_band_range` widens its
#: range by this much
_FILTER_SLACK = 1e-3


def _band_range(channels, form):
    """A range that holds ``g`` (the quadratic form) at every pixel of a band (its float32
    channels) and every float32 filter's mean of it there: the least and the largest g over
    each channel's [min, max] (at the ends, or where the parabola turns), summed, widened by
    ``_FILTER_SLACK`` of the terms' size."""
    import cv2

    least = largest = form.constant
    size = abs(form.constant)
    for channel, linear, square in zip(channels, form.linear, form.square, strict=True):
        low, high = cv2.minMaxLoc(channel)[:2]
        points = [low, high]
        if square != 0 and low < -linear / (2.0 * square) < high:
            points.append(-linear / (2.0 * square))
        g = [linear * x + square * x * x for x in points]
        least, largest = least + min(g), largest + max(g)
        reach = max(abs(low), abs(high))
        size += abs(linear) * reach + abs(square) * reach * reach
    return least - _FILTER_SLACK * size, largest + _FILTER_SLACK * size


def nucleation_sites(values, inside, form, mu, radius):
    """Where a small disk should change sides: the topological derivative of (6.38).

    Moving a disk B of radius ``radius`` from Omega_i to Omega_o changes J by about
    ``int_B g - 2 pi radius mu``, with ``g = g_i - g_o`` the integrand of (6.41), the difference of
    the two regions' quadratic forms (:meth:`ChanVeseParameters.load_form`); from Omega_o to Omega_i
    by ``-int_B g + 2 pi radius mu``.  So a hole pays where the mean of g over the disk exceeds
    ``2 mu / radius`` inside, and a new component where it is below ``-2 mu / radius`` outside.
    Returns one centre (row, col) per connected candidate region, with a flag telling whether it
    is a hole, best candidates first.

    Parameters
    ----------
    values : ndarray (M, N, C)
        The model's feature channels.
    inside : ndarray (M, N) bool
        The current Omega_i.
    form : QuadraticForm
        ``g = g_i - g_o``.
    mu : float
        The length weight.
    radius : float
    """
    import cv2

    # mean_B g = constant + sum_ch [linear mean_B I + square mean_B I^2]: local means of I (and
    # I^2), in float32 (a mean of a few tens of values in [0, 1]: float32 is exact to ~1e-7, far
    # below any threshold)
    square, linear, constant = form.square, form.linear, form.constant
    size = int(np.ceil(radius))
    yy, xx = np.mgrid[-size: size + 1, -size: size + 1]
    disk = (yy**2 + xx**2) <= radius**2
    kernel = (disk / disk.sum()).astype(np.float32)
    footprint = disk.astype(np.uint8)
    threshold = 2.0 * mu / radius
    m, n = inside.shape
    inside_u8 = np.ascontiguousarray(inside, dtype=bool).view(np.uint8)
    found = {True: ([], []), False: ([], [])}  # flat index and gain of every candidate pixel
    band = max(1, _BAND_PIXELS // n)
    for start in range(0, m, band):
        stop = min(m, start + band)
        low, high = max(0, start - size), min(m, stop + size)  # margins: the filters see real data
        keep = slice(start - low, stop - low)
        channels = [np.ascontiguousarray(values[low:high, :, ch], dtype=np.float32)
                    for ch in range(values.shape[2])]
        # a disk's mean of g lies between the least and the largest g of the band's pixels (the
        # filters read no other): a band where no pixel passes a threshold holds no candidate of
        # it, and needs neither the filters nor that region's morphology
        least, largest = _band_range(channels, form)
        wanted = {True: largest > threshold, False: least < -threshold}
        if not (wanted[True] or wanted[False]):
            continue
        mean = None
        for ch, channel in enumerate(channels):
            terms = [(channel, linear[ch])] + ([(channel * channel, square[ch])] if square[ch] != 0 else [])
            for data, factor in terms:
                part = cv2.filter2D(data, -1, kernel * np.float32(factor), delta=0.0 if mean is not None
                                    else constant, borderType=cv2.BORDER_REPLICATE)
                mean = part if mean is None else cv2.add(mean, part)
        mean = mean[keep]
        region = inside_u8[low:high]
        for hole, sign in ((True, 1.0), (False, -1.0)):
            if not wanted[hole]:
                continue
            passed = (mean > threshold) if hole else (mean < -threshold)
            # on its own side (a disk inside holds its centre, one outside too): the morphology
            # only where such a pixel is (noise passes on the other side, never a candidate)
            own = region[keep].view(bool)
            passed &= own if hole else ~own
            if not passed.any():
                continue
            # pixels whose whole disk lies inside (erosion) or outside (no dilation reaches them);
            # the image's outside counts as either region, as for a disk cut by the border
            if hole:
                room = cv2.erode(region, footprint, borderType=cv2.BORDER_CONSTANT, borderValue=1)[keep]
            else:
                room = cv2.dilate(region, footprint, borderType=cv2.BORDER_CONSTANT, borderValue=0)[keep]
            room_ok = room.view(bool)  # 0/1 bytes
            where = np.flatnonzero(passed & room_ok if hole else passed & ~room_ok)
            found[hole][0].append(where + start * n)
            found[hole][1].append(sign * mean.ravel()[where].astype(np.float64) - threshold)
    sites = []
    for hole in (True, False):
        if not found[hole][0]:
            continue
        index, gain = np.concatenate(found[hole][0]), np.concatenate(found[hole][1])
        if index.size == 0:
            continue
        rows, cols = np.divmod(index, n)
        box = np.zeros((rows.max() - rows.min() + 1, cols.max() - cols.min() + 1), np.uint8)
        box[rows - rows.min(), cols - cols.min()] = 1
        _, labels = cv2.connectedComponents(box, connectivity=4, ltype=cv2.CV_32S)
        label = labels[rows - rows.min(), cols - cols.min()]
        # the best pixel of each component, the first in raster order on ties
        order = np.lexsort((index, -gain, label))
        best = order[np.r_[True, label[order][1:] != label[order][:-1]]]
        sites.extend((float(gain[b]), np.array(divmod(int(index[b]), n), dtype=np.float64), hole)
                     for b in best)
    sites.sort(key=lambda site: -site[0])
    return [(center, hole) for _, center, hole in sites]
