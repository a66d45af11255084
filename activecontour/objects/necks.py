"""Stage 1 of the split (:mod:`activecontour.objects.split`): necks.

The watershed of the distance to the outline, one inscribed-circle centre per part, whose parts are
merged back while the neck between two is nearly as wide as the thinner part (:func:`_neck_parts`,
:class:`_PartGraph`); a neck must be a waist, and a shallow neck between two pieces of a rod is a
dent, not a contact (``TUBE_NECK``, ``TUBE_AREA``).  The gates that skip the stage without changing
a decision (:func:`_may_have_necks`, :func:`_thinner_than`) and the boundary distance at the pixel
centres from a finer raster (:func:`_boundary_distance`).
"""

from __future__ import annotations

import heapq
from itertools import pairwise

import numpy as np

from activecontour import _kernels
from activecontour.geometry.hull import hull_vertices
from activecontour.geometry.raster import rasterize, sorted_crossings
from activecontour.objects.shapes import MIN_WAIST_DEPTH, _blob_shape, _concavity, _reaches

#: Two parts of an object are split apart when the half-width of the neck between them is below
#: this fraction of the smaller part's largest inscribed radius.  Two disks overlapping by a third
#: of their diameter have a neck of sqrt(5)/3 = 0.745 of their radius; a protrusion (a leg, a
#: stroke's arm, a ring's arc) has no neck narrower than itself, ratio ~1.
NECK_RATIO = 0.9
#: A neck must also be this much (pixels) narrower than the thinner part's inscribed radius: the
#: converged contour wiggles by a fraction of a pixel, which on a ring or a stroke of constant
#: width makes necks of a few per cent.
MIN_NECK_DEPTH = 1.0
#: A shallow neck (at least this fraction of the thinner part's inscribed radius) ...
TUBE_NECK = 0.85
#: ... between two parts that together hold at least this many times the area of their two
#: largest inscribed disks is a dent of a stroke or rod (a tube of about constant width), which
#: the neck stage keeps whole: two blobs that overlap so deeply that their neck is this shallow
#: hold less than the area of their two disks (measured: at most 1.74 of it on the touching
#: families, seeds 0-59; the bent rods' pieces cut at noise dents of 1-2 px: 2.0-4.0, but for
#: one rod of short pieces with rounded ends, 1.35-1.9, still cut).  A neck
#: below ``TUBE_NECK`` is a contact whatever the parts' area (objects of aspect 3 meet there).
TUBE_AREA = 2.0


def _may_have_necks(region, outline, min_radius):
    """The region's :func:`_concavity` when it may have necks, None when it has none: necks need
    two maxima of dynamic above half a pixel in the pixel distance transform (without them no
    neck is ``MIN_NECK_DEPTH`` deep even after its half-pixel errors), two edge pixels
    ``MIN_WAIST_DEPTH`` inside the outline's convex hull (every split line ends in two such
    waists, :meth:`_PartGraph.is_waist`; pixels touching only at a corner are parts without one)
    and a part that may reach ``min_radius`` (:func:`_thinner_than`): cheap tests that spare most
    single objects the exact distance.  Each is a consequence of the neck criterion on its own,
    so their order changes no answer; the cheapest proof for a single blob comes first (and the
    h-maxima before the concavity: on a textured image, grass, a third of the objects that
    reach them have one h-maximum, and none fewer than two waist pixels).
    The h-maxima (plateaus of regional maxima) lie in the pixels not below any 8-neighbour, each
    of whose 4-connected pieces holds at most one of them, so one such piece means no two
    h-maxima: the transform and its pieces of peaks cost one compiled pass
    (:func:`activecontour._kernels.distance_peaks`), and only an object with two pieces or more
    is looked at further.  The outline is in window coordinates."""
    squared = np.empty(region.shape, dtype=np.int64)
    if _kernels.distance_peaks(region.view(np.uint8), squared) <= 1:
        return None
    import scipy.ndimage  # here: a single blob need not load it (0.2-0.4 s of a cold import)

    whole = scipy.ndimage.label(region)[1] == 1
    if whole and _thinner_than(region, outline, min_radius):
        return None
    # (the square roots of the squared transform: scipy.ndimage.distance_transform_edt's values)
    if _h_maxima_count(np.sqrt(squared), MIN_NECK_DEPTH / 2) <= 1:
        return None
    concavity = _concavity(region, outline)
    if whole and np.count_nonzero(concavity >= MIN_WAIST_DEPTH) < 2:
        return None
    return concavity


def _h_maxima_count(image, h):
    """The number of 4-connected pieces of ``skimage.morphology.h_maxima(image, h)`` (a float
    image, h > 0), ``scipy.ndimage.label``'s count: the same marker, computed as skimage computes
    it, reconstructed under the image by one compiled pass (:func:`activecontour._kernels.
    h_maxima_pieces`, O(pixels) without skimage's sort: 0.09 of 0.12 s of this gate on brick's
    textured object of 166 000 pixels)."""
    if h > np.ptp(image):  # (skimage: no maxima)
        return 0
    shifted = image - h - 2 * np.finfo(image.dtype).resolution * np.abs(image)
    return _kernels.h_maxima_pieces(np.ascontiguousarray(image), np.ascontiguousarray(shifted), float(h))


#: :func:`_boundary_distance` measures on a raster this many times finer than the pixels ...
DISTANCE_SUPERSAMPLE = 8
#: ... or coarser, so that the finer raster has at most this many pixels (giant objects).
DISTANCE_MAX_SAMPLES = 1 << 20


def _supersample(shape):
    """The factor of :func:`_boundary_distance`'s finer raster for a window of this shape."""
    return int(np.clip(np.sqrt(DISTANCE_MAX_SAMPLES / (shape[0] * shape[1])), 1, DISTANCE_SUPERSAMPLE))


def _thinner_than(region, outline, min_radius):
    """Whether :func:`_boundary_distance` stays below ``min_radius`` on the region, shown without
    computing it: then every part of :func:`_neck_parts` is too small to be an object and they
    all merge (a region of one 4-connected piece stays whole).

    The bound: with a finer raster ``2^k`` times finer, the fine raster read at the pixel centres
    is the raster of the outline itself (every coordinate and every step of
    :func:`activecontour.geometry.raster.rasterize` scales by ``2^k`` exactly), so every pixel
    centre outside it is a fine pixel outside, and the fine distance, in pixels, is at most the
    distance transform of the pixel raster (less half a fine pixel)."""
    fine = _supersample(region.shape)
    if fine & (fine - 1):  # not a power of two: no exact bound
        return False
    inside = rasterize([outline], region.shape)
    return not _reaches(inside, min_radius)[region].any()


def _boundary_distance(curves, region, low):
    """The distance from each pixel centre of ``region`` to the object's sub-pixel boundary (0
    outside): the Euclidean distance transform of the polygon rasterised ``DISTANCE_SUPERSAMPLE``
    times finer, within half a fine pixel.  On the pixel grid itself its half-pixel steps, 8 % of
    the radius of a 12 px object, would make necks out of nothing."""
    m, n = region.shape
    fine = _supersample(region.shape)
    # fine pixel centre (i, j) is window point (i, j) / fine: every pixel centre is a fine one;
    # the fine raster's Euclidean distance transform, at the pixel centres only, from its crossings
    shape = (fine * (m - 1) + 1, fine * (n - 1) + 1)
    distance = np.empty(region.shape)
    _kernels.sampled_distance(*sorted_crossings([(c - low) * fine for c in curves], shape), *shape, fine,
                              distance)
    distance = (distance - 0.5) / fine
    return np.where(region, np.maximum(distance, 0.0), 0.0)


def _neck_parts(region, concavity, distance, neck_ratio, min_radius):
    """Label the pixels of a bool region by parts separated by narrow waists (0 outside), given
    its edge pixels' depth inside the outline's convex hull (:func:`_concavity`) and each pixel's
    distance to the outline (:func:`_neck_stage`'s parts)."""
    return _neck_stage(region, concavity, distance, neck_ratio, min_radius)[0]


def _neck_stage(region, concavity, distance, neck_ratio, min_radius):
    """:func:`_neck_parts`' labels, and the parts as they were before the parts that are no blob
    took their neighbours back (None when that merged none).

    The watershed's parts are merged pair by pair (:meth:`_PartGraph.merge_necks`), then the
    parts that are no blob take their neighbours back (:meth:`_PartGraph.merge_non_blobs`).
    Both work on the graph of parts with priority queues and merge the smaller side into the
    larger, so the cost is about linear in the region's pixels however many parts the watershed
    makes (a speckled outline makes one per few pixels).
    """
    import scipy.ndimage
    import skimage.morphology
    import skimage.segmentation

    markers, count = scipy.ndimage.label(skimage.morphology.local_maxima(distance) & region)
    if count <= 1:
        return region.astype(np.int32), None
    parts = skimage.segmentation.watershed(-distance, markers, mask=region)
    # each part's largest distance (scipy.ndimage.maximum's, without its sort: every part holds
    # its marker, and the window's frame is part 0)
    peak = np.full(count + 1, -np.inf)
    np.maximum.at(peak, parts.ravel(), distance.ravel())
    # at most one part as thick as an object: every neck has a thinner side too small to be one,
    # so every pair merges (:meth:`_PartGraph.merit`) and a region of one 4-connected piece,
    # which the watershed covers, is one part
    if np.count_nonzero(peak >= min_radius) <= 1 and scipy.ndimage.label(region)[1] == 1:
        return region.astype(np.int32), None
    graph = _PartGraph(parts, distance, peak, concavity, min_radius)
    graph.merge_necks(neck_ratio)
    necks = graph.labels() if len(graph.members) > 1 else None
    graph.merge_non_blobs()
    merged = graph.labels()
    return merged, (necks if necks is not None and necks.max() > merged.max() else None)


class _Border:
    """The common border of two parts: its neck (the largest distance value along it), its
    pixels (flat indices, in chunks), its rank in the scan that found the borders (ties between
    equal merits go to the first found) and whether it is a waist (cached)."""

    __slots__ = ("neck", "chunks", "rank", "waist")

    def __init__(self, neck, pixels, rank):
        self.neck, self.chunks, self.rank, self.waist = neck, [pixels], rank, None

    def absorb(self, other):
        """Become the border of a merged part with ``other``'s neighbour too."""
        self.neck = max(self.neck, other.neck)
        self.rank = min(self.rank, other.rank)
        small, large = sorted((self.chunks, other.chunks), key=len)
        large.extend(small)
        self.chunks, self.waist = large, None

    def pixels(self):
        if len(self.chunks) > 1:
            self.chunks = [np.concatenate(self.chunks)]
        return self.chunks[0]


class _PartGraph:
    """Parts of a watershed as a graph: each part's peak distance, each border's neck (saddle),
    its pixels and whether it is a waist.

    A merge moves the smaller side's members and borders to the kept part, and the merges are
    chosen from priority queues whose entries are checked when they come out (a merit only
    falls unless the border itself changed, and a changed border is queued again): the whole
    merging costs O(B log B) for B border pixels, not a scan of every border per merge.
    """

    def __init__(self, parts, distance, peak, concavity, min_radius):
        self.parts, self.concavity, self.min_radius = parts, concavity, min_radius
        self.peak, count = peak, len(peak) - 1
        self.members = {k: [k] for k in range(1, count + 1)}
        self.adjacent = {k: {} for k in range(1, count + 1)}  # part: {neighbour: _Border}
        # every 4-neighbour pair of pixels in two parts: rows first, then columns, in raster order
        index = np.arange(parts.size).reshape(parts.shape)
        first, second, neck, pixels = [], [], [], []
        for a, b, da, db, ia, ib in ((parts[:, :-1], parts[:, 1:], distance[:, :-1], distance[:, 1:],
                                      index[:, :-1], index[:, 1:]),
                                     (parts[:-1], parts[1:], distance[:-1], distance[1:], index[:-1],
                                      index[1:])):
            border = (a != b) & (a > 0) & (b > 0)
            first.append(np.minimum(a[border], b[border]))
            second.append(np.maximum(a[border], b[border]))
            neck.append(np.minimum(da[border], db[border]))
            pixels.append(np.column_stack([ia[border], ib[border]]))
        first, second = np.concatenate(first), np.concatenate(second)
        neck, pixels = np.concatenate(neck), np.concatenate(pixels)
        pair = first.astype(np.int64) * (count + 1) + second
        order = np.argsort(pair, kind="stable")
        starts = np.flatnonzero(np.diff(pair[order], prepend=-1))  # none: parts touch at corners
        for start, stop in pairwise(np.append(starts, order.size)):
            chosen = order[start:stop]
            i, j = int(first[chosen[0]]), int(second[chosen[0]])
            border = _Border(float(neck[chosen].max()), pixels[chosen].ravel(), int(chosen[0]))
            self.adjacent[i][j] = self.adjacent[j][i] = border
        self.queues = None
        self.shapes = None  # per part: moments and convex hull, once the blob test needs them

    def merit(self, i, j, border):
        """The neck over the thinner part's peak; infinite when that part is too small to be an
        object (it merges whatever its neck)."""
        thinner = min(self.peak[i], self.peak[j])
        return np.inf if thinner < self.min_radius else border.neck / thinner

    def _queue(self, i, j, border):
        entry = (-self.merit(i, j, border), border.rank, min(i, j), max(i, j))
        for queue in self.queues:
            heapq.heappush(queue, entry)

    def _best(self, queue, one_sided=False):
        """The pair of highest merit in a queue (first found on ties), and its merit; with
        ``one_sided``, of the pairs whose border is no waist.  None when there is none."""
        while queue:
            negative, rank, i, j = queue[0]
            border = self.adjacent.get(i, {}).get(j)
            if border is None:
                heapq.heappop(queue)
                continue
            merit = self.merit(i, j, border)
            if (-merit, border.rank) != (negative, rank):  # the merit fell since: queue it anew
                heapq.heapreplace(queue, (-merit, border.rank, i, j))
                continue
            if one_sided and self.is_waist(border):
                heapq.heappop(queue)  # a waist stays one until its border changes (queued then)
                continue
            return (i, j), merit
        return None

    def merge_necks(self, neck_ratio):
        """Merge neighbouring parts, the widest neck relative to the thinner side first, while
        the neck is at least ``neck_ratio`` of the thinner part's peak or within
        ``MIN_NECK_DEPTH`` of it (a side too small to be an object merges whatever its neck)
        or, above ``TUBE_NECK`` of it, the two parts are a stretch of a tube (:meth:`is_tube`);
        the narrow necks left that are a notch on one side only (no waist) go too."""
        self.queues = ([], [])  # all pairs; the pairs not yet found to be waists
        for i, neighbours in self.adjacent.items():
            for j, border in neighbours.items():
                if i < j:
                    self._queue(i, j, border)
        while (best := self._best(self.queues[0])) is not None:
            (i, j), merit = best
            thinner = min(self.peak[i], self.peak[j])
            if (merit < neck_ratio and self.adjacent[i][j].neck < thinner - MIN_NECK_DEPTH
                    and not (merit >= TUBE_NECK and self.is_tube(i, j))):
                best = self._best(self.queues[1], one_sided=True)
                if best is None:
                    break
            self.merge(*best[0])
        self.queues = None

    def is_tube(self, i, j):
        """Whether parts i and j together hold at least ``TUBE_AREA`` times the area of their
        two largest inscribed disks: a stretch of a stroke or a rod, not two blobs."""
        if self.shapes is None:
            self.shapes = _PartShapes(self.parts, self.members)
        area = self.shapes.sums[i][0] + self.shapes.sums[j][0]
        return bool(area >= TUBE_AREA * np.pi * (self.peak[i] ** 2 + self.peak[j] ** 2))

    def merge_non_blobs(self):
        """A part that is no blob (a body with limbs, a bent stroke, an arc) means the necks were
        a shape's own: it takes its neighbours back, the least solid first, until every part is a
        blob or has no neighbour (pixels touching only at a corner are no neighbours)."""
        if not any(self.adjacent.values()):  # no part has a neighbour to take back: no shapes needed
            return
        if self.shapes is None:  # (made by :meth:`is_tube` when a shallow neck asked)
            self.shapes = _PartShapes(self.parts, self.members)
        queue = []
        for root in self.members:
            self._queue_shape(queue, root)
        while queue:
            solidity, root, version = heapq.heappop(queue)
            if root not in self.members or version != self.shapes.version[root]:
                continue
            for neighbour in list(self.adjacent[root]):
                self.merge(root, neighbour)
            self._queue_shape(queue, root)

    def _queue_shape(self, queue, root):
        blob, solidity = self.shapes.blob(root)
        if not blob and self.adjacent[root]:  # a part without neighbours never gains one
            heapq.heappush(queue, (solidity, root, self.shapes.version[root]))

    def is_waist(self, border):
        """Whether a border ends in a concavity of the outline at two places: its pixels on the
        outline fall in two pieces (8-neighbours) or more, two of them ``MIN_WAIST_DEPTH`` deep."""
        import scipy.ndimage

        if border.waist is not None:
            return border.waist
        pixels = np.unique(border.pixels())
        depth = self.concavity.ravel()[pixels]
        pixels, depth = pixels[depth >= 0], depth[depth >= 0]
        border.waist = False
        if pixels.size >= 2:
            rows, cols = np.divmod(pixels, self.parts.shape[1])
            # 8-neighbour pieces of a sparse set of pixels, labelled on their bounding box
            rows, cols = rows - rows.min(), cols - cols.min()
            drawn = np.zeros((rows.max() + 1, cols.max() + 1), dtype=bool)
            drawn[rows, cols] = True
            pieces, count = scipy.ndimage.label(drawn, structure=np.ones((3, 3)))
            piece = pieces[rows, cols] - 1
            if count >= 2:
                deepest = np.full(count, -1.0)
                np.maximum.at(deepest, piece, depth)
                border.waist = bool(np.sort(deepest)[-2] >= MIN_WAIST_DEPTH)
        return border.waist

    def merge(self, keep, gone):
        """Part ``gone`` joins part ``keep`` (which keeps its number)."""
        self.peak[keep] = max(self.peak[keep], self.peak[gone])
        small, large = sorted((self.members.pop(gone), self.members[keep]), key=len)
        large.extend(small)
        self.members[keep] = large
        if self.shapes is not None:
            self.shapes.merge(keep, gone)
        kept = self.adjacent[keep]
        for neighbour, border in self.adjacent.pop(gone).items():
            del self.adjacent[neighbour][gone]
            if neighbour == keep:
                continue
            if neighbour in kept:
                kept[neighbour].absorb(border)
                border = kept[neighbour]
            else:
                kept[neighbour] = self.adjacent[neighbour][keep] = border
            if self.queues is not None:
                self._queue(keep, neighbour, border)

    def labels(self):
        """The merged parts numbered 1..k in the order of their numbers (0 outside)."""
        relabel = np.zeros(len(self.peak), dtype=np.int32)
        for number, root in enumerate(sorted(self.members), start=1):
            relabel[self.members[root]] = number
        return relabel[self.parts]


#: The four points of a pixel's edge midpoints, whose hull is the pixel's in the convex hull of
#: ``skimage.morphology.convex_hull_image`` (``offset_coordinates=True``).
_EDGE_MIDPOINTS = np.array([[-0.5, 0.0], [0.5, 0.0], [0.0, -0.5], [0.0, 0.5]])


class _PartShapes:
    """The area, second moments and convex hull of every part, kept through merges: the blob
    test (:func:`_blob_shape`) of a merged part without measuring its pixels again.

    The solidity and axis lengths are those of ``skimage.measure.regionprops`` (its convex hull
    holds the pixel centres in the hull of the pixels' edge midpoints), from sums that add up
    under a merge and hulls that merge by their vertices."""

    def __init__(self, parts, members):
        rows, cols = np.nonzero(parts)
        lookup = np.zeros(int(parts.max()) + 1, dtype=np.intp)
        for root, numbers in members.items():
            lookup[numbers] = root
        owner = lookup[parts[rows, cols]]
        rows, cols = rows.astype(np.float64), cols.astype(np.float64)
        size = len(lookup)
        sums = [np.bincount(owner, weights=w, minlength=size)
                for w in (None, rows, cols, rows * rows, cols * cols, rows * cols)]
        self.sums = {root: np.array([s[root] for s in sums]) for root in members}
        # hull candidates: the first and last pixel of every row and of every column of a part
        ends = []
        for along, across in ((rows, cols), (cols, rows)):
            order = np.lexsort((across, along, owner))
            key = np.column_stack([owner[order], along[order]])
            change = np.any(key[1:] != key[:-1], axis=1)
            ends.append(order[np.r_[True, change] | np.r_[change, True]])
        ends = np.unique(np.concatenate(ends))
        by_owner = np.argsort(owner[ends], kind="stable")
        ends = ends[by_owner]
        splits = np.searchsorted(owner[ends], list(members), side="left")
        stops = np.searchsorted(owner[ends], list(members), side="right")
        self.hull = {}
        for root, a, b in zip(members, splits, stops, strict=True):
            centres = np.column_stack([rows[ends[a:b]], cols[ends[a:b]]])
            self.hull[root] = _hull((centres[:, None, :] + _EDGE_MIDPOINTS).reshape(-1, 2))
        self.version = dict.fromkeys(members, 0)

    def merge(self, keep, gone):
        self.sums[keep] = self.sums[keep] + self.sums.pop(gone)
        self.hull[keep] = _hull(np.vstack([self.hull[keep], self.hull.pop(gone)]))
        self.version[keep] += 1
        del self.version[gone]

    def blob(self, root):
        """(whether the part is a blob, its solidity)."""
        n, sr, sc, srr, scc, src = self.sums[root]
        solidity = n / _lattice_points(self.hull[root])
        # the inertia tensor of regionprops: central moments over the area
        mu20, mu02, mu11 = (srr - sr * sr / n) / n, (scc - sc * sc / n) / n, (src - sr * sc / n) / n
        low, high = np.clip(np.linalg.eigvalsh([[mu02, -mu11], [-mu11, mu20]]), 0, None)
        return _blob_shape(solidity, 4 * np.sqrt(high), 4 * np.sqrt(low)), solidity


def _hull(points):
    """The vertices of the convex hull of points (P, 2), P >= 3 not all on a line."""
    return points[hull_vertices(points)]


def _lattice_points(vertices):
    """How many integer points (pixel centres) a convex polygon holds, its boundary included:
    the span of each integer row between the polygon's two crossings of it."""
    start, end = vertices, np.roll(vertices, -1, axis=0)
    rows = np.arange(np.ceil(vertices[:, 0].min()), np.floor(vertices[:, 0].max()) + 1)[:, None]
    r0, r1, c0, c1 = start[:, 0], end[:, 0], start[:, 1], end[:, 1]
    spans = (np.minimum(r0, r1) <= rows) & (rows <= np.maximum(r0, r1))
    flat = r0 == r1
    with np.errstate(divide="ignore", invalid="ignore"):
        cross = c0 + np.where(flat, 0.0, (rows - r0) / (r1 - r0)) * (c1 - c0)
    low = np.where(spans, np.where(flat, np.minimum(c0, c1), cross), np.inf).min(axis=1)
    high = np.where(spans, np.where(flat, np.maximum(c0, c1), cross), -np.inf).max(axis=1)
    # the vertices are half-integers: a centre on the boundary is exact to far below 1e-9
    return int(np.sum(np.maximum(np.floor(high + 1e-9) - np.ceil(low - 1e-9) + 1, 0)))
