"""Stage 2 of the split (:mod:`activecontour.objects.split`): cuts between concave corners.

Two convex objects that overlap meet at two corners of the outline, concave stretches where the
curvature kappa of the book's 1-D geometry (section 6.5: ``kappa nu = -Laplace_Sigma id``, (3.45),
(4.30)) turns by tens of degrees within a pixel or two (:func:`_concave_corners`, :func:`_bent`).
Corners are paired into straight cut lines, or cut across along a corner's inward normal
(:func:`_cuts`), and the cut kept is the one whose parts one ellipse each explains best
(:func:`_corner_parts`).  Also here: the polygon cut along lines that every stage's parts are made
by (:func:`_cut`), and the cut of a neck's part into ellipses of the object's outline
(:func:`_as_ellipses`).
"""

from __future__ import annotations

import numpy as np

from activecontour import _kernels
from activecontour.geometry.curve import curvature, edge_lengths, signed_area, vertex_normals
from activecontour.geometry.hull import hull_area
from activecontour.geometry.raster import rasterize
from activecontour.geometry.regions import _from_shapely, _to_shapely
from activecontour.objects.shapes import (
    MIN_SPLIT_RADIUS,
    MIN_WAIST_DEPTH,
    _arc_ellipse,
    _ellipse_fit,
    _ellipse_fits,
    _explained,
    _hull_depth,
)

#: Tolerance (pixels) of the straightening of split lines (``shapely.coverage_simplify``).
SPLIT_LINE_TOLERANCE = 1.0


#: A piece of a cut smaller than this (px^2) is a sliver of the outline beside a cell's staircase ...
_SLIVER_AREA = 1.0
#: ... and joins the piece within this distance (px) of it that it overlaps most once grown by it
_SLIVER_REACH = 1e-6


def _cut(curves, parts, low):
    """The object's polygon cut along the borders of its pixel parts, as lists of curves."""
    import scipy.ndimage
    import shapely

    from activecontour.geometry.raster import mask_to_curves

    # grow the parts over the whole window so that their cells tile it; each cell is traced
    # and cut on its own box (the work grows with the object, not with its parts times it)
    nearest = scipy.ndimage.distance_transform_edt(parts == 0, return_distances=False,
                                                   return_indices=True)
    cells = parts[tuple(nearest)]
    boxes = scipy.ndimage.find_objects(cells)
    geometries = np.array([_to_shapely([c + low + (box[0].start, box[1].start)
                                    for c in mask_to_curves(cells[box] == j)])
                           for j, box in enumerate(boxes, start=1)], dtype=object)
    # the traced cells are a coverage, which the simplification keeps: marching squares at 0.5
    # (mask_to_curves) gives a grid square's pixels of one cell the square's corner, half or all
    # but a corner, and two diagonal pixels two corners, so the cells of a tiling never overlap
    # (their vertices are exact half-pixels).  A cell whose box meets an earlier cell's box is
    # made clockwise: the orientation GEOS's difference with the earlier cells (an empty
    # overlap) gave it, which the simplification and the intersection below read (the first
    # vertex they do not: the same pieces to the bit on the 282 cuts of the families, DSB and
    # the sample images as with the 1-2 overlays per cell)
    pairs = shapely.STRtree(geometries).query(geometries)
    later = np.unique(pairs[0][pairs[1] < pairs[0]])
    geometries[later] = shapely.orient_polygons(geometries[later], exterior_cw=True)
    geometries = shapely.coverage_simplify(geometries, SPLIT_LINE_TOLERANCE, simplify_boundary=False)
    region = _to_shapely(curves)
    polygons = [polygon for piece in shapely.intersection(region, geometries)
                for polygon in getattr(piece, "geoms", [piece])
                if isinstance(polygon, shapely.Polygon) and polygon.area > 0]
    # where the sub-pixel outline crosses a cell's staircase, a sliver of the region can fall in
    # the other cell, apart from its body: it joins the piece it touches, the region stays whole
    slivers = [k for k, polygon in enumerate(polygons) if polygon.area < _SLIVER_AREA]
    for k in slivers:
        touching = np.nan_to_num(shapely.area(shapely.intersection(polygons[k].buffer(_SLIVER_REACH),
                                                                   polygons)))
        touching[slivers] = 0.0
        j = int(np.argmax(touching))
        joined = shapely.union(polygons[j], polygons[k]) if touching[j] > 0 else None
        if isinstance(joined, shapely.Polygon):
            polygons[j], polygons[k] = joined, None
    return [part for polygon in polygons if polygon is not None and (part := _from_shapely(polygon))]


# ---- stage 2: concave corners paired into cut lines ---------------------------------------------

#: The curvature is smoothed along the outline by a Gaussian of this width (pixels at the
#: outline's mean vertex spacing: :func:`_bent`) ...
CORNER_SMOOTHING = 1.5
#: ... and a concave stretch (smoothed kappa < 0) is a corner when it turns by at least this many
#: degrees in all and lies at least ``MIN_WAIST_DEPTH`` inside the convex hull.  Two disks that
#: overlap by a third of their diameter meet at corners of 84 degrees, objects that barely touch
#: at corners of nearly 180; the noise of the converged contour makes stretches of a few degrees.
CORNER_TURN = 30.0
#: A cut must be a neck: its length at most this fraction of each part's extent along it.  Two
#: ellipses overlapping by a third of the minor axis meet along a chord of at most 0.75 of the
#: part's width parallel to it; a protrusion (an arm, a leg) is cut at its widest, ratio ~1.
CUT_NECK = 0.9
#: A cut between two corners runs within this angle (degrees) of the inward normal at both ends:
#: the corners of a contact face each other.
CUT_ALIGN = 35.0
#: A corner whose partner is too shallow to be found is cut across along its inward normal turned
#: by these angles (degrees), to the first point of the outline that is not convex.
CUT_RAYS = (-25.0, 0.0, 25.0)
#: Of the admissible cuts, the narrowest this many are fitted; the best fit of two ellipses wins.
CUT_OPTIONS = 4
#: A cut stands when its parts explain, as ellipses, at least this fraction of the area that was
#: not explained before (a part that is an ellipse is never cut).  Half, so that cutting one arm
#: off a star or the head off a horse, which leaves most of the shape unexplained, is no split,
#: while a clump with one contact missed still has its other contacts cut.
EXPLAINED_GAIN = 0.5


def _corner_parts(outline, depth=None, bent=None):
    """The parts of a polygon (an outer boundary without holes) cut at its concave corners, as
    polygons that share their cut lines (each cut joins two vertices of the outline).

    The polygon is cut recursively: at each part, the admissible cuts (two corners facing each
    other, or one corner and the outline across, :func:`_cuts`) that are necks (``CUT_NECK``) and
    lie inside the part are ordered by their neck ratio; of the first ``CUT_OPTIONS``, the one
    whose two sides are fitted best by an ellipse each is made and its sides cut in turn.  A cut
    is undone when its parts do not explain the part (``EXPLAINED_GAIN``).  ``depth`` and
    ``bent``: the outline's :func:`_hull_depth` and :func:`_bent`, when they are known.
    """
    if _uncuttable(signed_area(outline), False):
        return [outline]
    corners, kappa, normals = _concave_corners(outline, depth, bent=bent)
    if len(corners) == 0:
        return [outline]
    spacing = edge_lengths(outline).mean()
    reach = max(int(2 * CORNER_SMOOTHING / spacing), 1)
    # a cut may end across from a corner where the outline is concave or straight within reach
    flat = _within(kappa <= 0, reach)
    is_corner = np.zeros(len(outline), dtype=bool)
    is_corner[corners] = True

    def admissible(cycle):
        """The first ``CUT_OPTIONS`` admissible cuts of the part whose sides are large enough."""
        cuts = []
        for _, a, b in _cuts(outline, cycle, is_corner, flat, normals):
            first, second = cycle[a:b + 1], np.concatenate([cycle[b:], cycle[:a + 1]])
            areas = signed_area(outline[first]), signed_area(outline[second])
            if min(areas) < np.pi * MIN_SPLIT_RADIUS**2:
                continue
            cuts.append((first, second))
            if len(cuts) == CUT_OPTIONS:
                break
        return cuts

    def split(cycle, fit, cuts=None):
        area, good = fit
        if _uncuttable(area, good):
            return [(cycle, fit)]
        cuts = admissible(cycle) if cuts is None else cuts
        if not cuts:
            return [(cycle, fit)]
        fits = _ellipse_fits([outline[side] for cut in cuts for side in cut])
        options = [(fits[2 * k][1] + fits[2 * k + 1][1], first, second, (fits[2 * k], fits[2 * k + 1]))
                   for k, (first, second) in enumerate(cuts)]
        _, first, second, fits = min(options, key=lambda option: option[0])
        sides = [(first, _explained(outline[first], fits[0], outline)),
                 (second, _explained(outline[second], fits[1], outline))]
        allowed = (0.0 if good else area) - EXPLAINED_GAIN * area
        # the area a side leaves unexplained only adds up: once one side (the larger first) leaves
        # more than the cut may, the cut is undone whatever the other side's parts
        found = [None, None]
        for i in sorted((0, 1), key=lambda i: -sides[i][1][0]):
            found[i] = split(*sides[i])
            if sum(size for _, (size, kept) in found[i] if not kept) > allowed + 1e-9 * abs(area):
                return [(cycle, fit)]
        parts = found[0] + found[1]
        unexplained = sum(size for _, (size, kept) in parts if not kept)
        if unexplained <= allowed:
            return parts
        return [(cycle, fit)]

    # the whole outline's cuts before its fit: an outline without one is kept unfitted
    whole = np.arange(len(outline))
    cuts = admissible(whole)
    if not cuts:
        return [outline]
    parts = split(whole, _explained(outline, _ellipse_fit(outline), outline), cuts)
    return [outline[cycle] for cycle, _ in parts]


def _within(marked, reach):
    """Which entries of a cyclic bool array lie within ``reach`` places of a True one: the
    count of True entries in each cyclic window of ``2 reach + 1``, from one cumulative sum."""
    count = len(marked)
    if 2 * reach + 1 >= count:
        return np.full(count, marked.any())
    wrapped = np.concatenate([marked[count - reach:], marked, marked[:reach]])
    total = np.concatenate([[0], np.cumsum(wrapped)])
    return total[2 * reach + 1:] > total[:count]


def _uncuttable(area, good):
    """Whether :func:`_corner_parts` keeps a part of this area, explained by an ellipse or not,
    whatever its cuts: one that is an ellipse (its parts would have to leave less than nothing
    unexplained, ``EXPLAINED_GAIN``), or one under twice the smallest part (the two sides of a
    cut inside it add up to its area, so one is under ``pi MIN_SPLIT_RADIUS^2``)."""
    return (good and area > 0) or area < (1 - 1e-9) * 2 * np.pi * MIN_SPLIT_RADIUS**2


def _bent(outline):
    """A polygon's smoothed curvature, its smoothed outward unit normals and the arc length each
    vertex stands for (:func:`_concave_corners`).

    The smoothing is a Gaussian over the vertices' numbers (cyclic) of ``CORNER_SMOOTHING``
    pixels at the mean vertex spacing, ``CORNER_SMOOTHING / mean(h)`` vertices: each vertex's
    turning ``kappa ds`` and its ``ds`` are smoothed, and their ratio is the curvature, an
    average weighted by arc length (a vertex on short edges turns little).  Where the spacing is
    uneven (the polygon flow's vertices: 0.4-1.7 px on the families' outlines) the window is
    narrower in pixels where vertices crowd.  It is not a Gaussian of arc length: one on an even
    0.5 px grid along the outline (tried, with the thresholds of this module as they are) found
    more concave corners, cutting 21 of 240 singles (seeds 20-59) instead of 6, and took the
    worst disk scene from 0.68 to 0.49 and the DSB image from 0.79 to 0.77."""
    h = edge_lengths(outline)
    ds = 0.5 * (h + np.roll(h, 1))  # the arc length each vertex stands for
    width = CORNER_SMOOTHING / h.mean()
    # (the three smoothings in one: each column is smoothed on its own)
    smooth = _cyclic_gaussian(np.column_stack([curvature(outline) * ds, ds, vertex_normals(outline)]), width)
    kappa = smooth[:, 0] / smooth[:, 1]
    normals = np.ascontiguousarray(smooth[:, 2:])
    normals /= np.maximum(np.hypot(normals[:, 0], normals[:, 1]), 1e-12)[:, None]
    return kappa, normals, ds


def _concave_corners(outline, depth=None, turn=CORNER_TURN, bent=None):
    """The vertices at the concave corners of a polygon, its smoothed curvature and its smoothed
    outward unit normals.

    The curvature is the book's (3.45) in P1 weak form (:func:`activecontour.geometry.curve.
    curvature`), smoothed along the outline (:func:`_bent`, ``CORNER_SMOOTHING``).  A
    maximal stretch where it is negative is a corner when its turning ``-int kappa ds`` reaches
    ``turn`` degrees (``CORNER_TURN``; ``ARC_CORNER_TURN`` for :func:`_arc_clump`) and it dips
    ``MIN_WAIST_DEPTH`` inside the convex hull (``depth``: :func:`_hull_depth`, measured here
    unless given, and only once a stretch turns enough); the corner is its vertex of most negative
    curvature.  ``bent``: the outline's :func:`_bent`, when it is known (the arc stage and the
    corner stage look at the same outline).
    """
    kappa, normals, _ = bent = _bent(outline) if bent is None else bent
    corners, turning = _corner_turns(outline, depth, turn, bent)
    return corners[~(turning < turn)], kappa, normals


def _corner_turns(outline, depth, least, bent):
    """The corners of :func:`_concave_corners` for every turn of ``least`` degrees or more at once
    (the arc stage asks for two): the sorted vertices of the stretches that turn by ``least`` or
    more and dip ``MIN_WAIST_DEPTH`` inside the hull, and each one's turning in degrees.  Those
    of ``turn`` degrees are the ones whose turning is not below it (the two tests are and-ed)."""
    kappa, normals, ds = bent
    concave = kappa < 0
    if concave.all() or not concave.any():
        return np.zeros(0, dtype=int), np.zeros(0)
    # the stretches of negative curvature, starting the count at a vertex that is not in one
    order = np.roll(np.arange(len(outline)), -int(np.argmin(concave)))
    steps = np.diff(np.r_[0, concave[order].astype(int), 0])
    corners, turns = [], []
    for start, stop in zip(np.flatnonzero(steps == 1), np.flatnonzero(steps == -1), strict=True):
        stretch = order[start:stop]
        turning = np.degrees(-np.sum(kappa[stretch] * ds[stretch]))
        if turning < least:
            continue
        depth = _hull_depth(outline) if depth is None else depth
        if depth[stretch].max() >= MIN_WAIST_DEPTH:
            corners.append(stretch[np.argmin(kappa[stretch])])
            turns.append(turning)
    order = np.argsort(np.array(corners, dtype=int), kind="stable")
    return np.array(corners, dtype=int)[order], np.array(turns, dtype=np.float64)[order]


def _cyclic_gaussian(values, sigma):
    """``scipy.ndimage.gaussian_filter1d(values, sigma, axis=0, mode="wrap")`` to the last bit,
    without loading scipy.ndimage (0.2-0.4 s of a cold start, for an object that is then not
    cut): its weights (truncated at 4 sigma, normalised) and its order of summation for a
    symmetric kernel (the centre, then the pairs of taps from the outermost in)."""
    values = np.asarray(values, dtype=np.float64)
    radius = int(4.0 * float(sigma) + 0.5)
    offsets = np.arange(-radius, radius + 1)
    weights = np.exp(-0.5 / (sigma * sigma) * offsets ** 2)
    weights = weights / weights.sum()
    count = len(values)
    # the values wrapped ``radius`` places beyond both ends (one gather): the taps are slices
    wrapped = values[np.arange(-radius, count + radius) % count]
    smooth = values * weights[radius]
    for j in range(radius, 0, -1):
        before, after = wrapped[radius - j:radius - j + count], wrapped[radius + j:radius + j + count]
        smooth += (before + after) * weights[radius + j]
    return smooth


def _cuts(outline, cycle, is_corner, flat, normals):
    """The admissible cuts of the part ``outline[cycle]``: (neck ratio, a, b) with a < b positions
    in ``cycle``, narrowest first, one by one (a cut is tested for lying inside the part only when
    it is asked for).

    Candidates join two corners of the part, or a corner and the first vertex of the part's
    outline hit by a ray along the corner's inward normal (turned by ``CUT_RAYS``) where the
    outline is not convex.  Admissible: the cut faces the inward normal at both ends within
    ``CUT_ALIGN``, is a neck (``CUT_NECK``) and lies inside the part.
    """
    part = outline[cycle]
    edges = part, np.roll(part, -1, axis=0)  # edge i of the part: from edges[0][i] to edges[1][i]
    positions = np.flatnonzero(is_corner[cycle])
    candidates = {(int(a), int(b)) for i, a in enumerate(positions) for b in positions[i + 1:]}
    for a, b in _ray_hits(outline, cycle, edges, positions, normals):
        if flat[cycle[b]]:
            candidates.add((min(a, b), max(a, b)))
    if not candidates:
        return
    # each cut's neck ratio, compiled: with ``direction`` its unit vector and ``along`` the
    # part's offsets from their mean projected on it, ``length / min(ptp(along[a:b + 1]),
    # ptp(along[b:] and along[:a + 1]))``, infinite where a normal does not face it
    first, second = np.array(sorted(candidates), dtype=np.intp).T.copy()
    ratios = np.empty(len(first))
    _kernels.cut_ratios(part, part - part.mean(axis=0), normals[cycle], first, second,
                        float(np.cos(np.radians(CUT_ALIGN))), ratios)
    keep = ratios <= CUT_NECK
    for ratio, a, b in sorted(zip(ratios[keep].tolist(), first[keep].tolist(), second[keep].tolist(),
                                  strict=True)):
        if _segment_inside(edges, a, b):
            yield ratio, a, b


#: The rotations of :data:`CUT_RAYS` (angles, 2, 2).
_RAY_TURNS = np.array([[[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]]
                       for angle in np.radians(CUT_RAYS)])


def _ray_hits(outline, cycle, edges, positions, normals):
    """The pairs (a, b) of positions in ``cycle``: rays from each corner ``cycle[a]`` (``a`` in
    ``positions``) along its inward normal (turned by ``CUT_RAYS``) first meet the part's outline
    ``edges`` on an edge of the object's outline (not a cut), at its nearer end ``b``.  All rays
    of all corners at once: one pass over the edges."""
    count = len(cycle)
    if count == 0 or len(positions) == 0:
        return []
    start, edge = edges[0], edges[1] - edges[0]
    original = np.roll(cycle, -1) == (cycle + 1) % len(outline)
    # ray (corner, angle) ``-turn @ normal`` and the first edge it crosses, compiled (the numpy
    # definition: ``tests/objects/test_split_gates.py``)
    shape = (len(positions), len(_RAY_TURNS))
    nearest, along, hit = np.empty(shape, dtype=np.intp), np.empty(shape), np.empty(shape, dtype=np.uint8)
    _kernels.ray_hits(np.ascontiguousarray(start, dtype=np.float64), np.ascontiguousarray(edge), _RAY_TURNS,
                      np.ascontiguousarray(normals[cycle[positions]], dtype=np.float64),
                      np.ascontiguousarray(positions, dtype=np.intp), nearest, along, hit)
    b = np.where(along < 0.5, nearest, (nearest + 1) % count)
    corner = np.indices(shape)[0]
    a = positions[corner]
    chosen = hit.astype(bool) & original[nearest] & (b != a)
    return list(zip(a[chosen].tolist(), b[chosen].tolist(), strict=True))


def _segment_inside(edges, a, b):
    """Whether the segment between vertices a and b of a simple polygon (its ``edges``: starts and
    ends) lies inside it: it crosses no edge (those at a and b aside) and its midpoint is inside
    (:func:`activecontour._kernels.segment_inside`)."""
    return _kernels.segment_inside(np.ascontiguousarray(edges[0], dtype=np.float64),
                                   np.ascontiguousarray(edges[1], dtype=np.float64), int(a), int(b))


# ---- stage 1, then 2: the necks' parts kept when they are ellipses ---------------------------------

#: A piece cut off at a neck or a corner is an object's ellipse when the stretches of the object's
#: outline it holds are fitted by one ellipse (``ARC_RMS``, ``ARC_OUTSIDE``, ``MAX_PART_ASPECT``),
#: leaving out the vertices within this distance (pixels) of the cut: the rounded contact, which
#: is neither object's outline (twice ``ARC_TRIM``, which trims an arc at each of its corners) ...
CUT_TRIM = 3.0
#: ... and the piece is this solid (area / convex hull area): an ellipse less its overlap with
#: the other, cut along a chord, is less solid than an ellipse (``ELLIPSE_SOLIDITY``) ...
CUT_SOLIDITY = 0.85
#: ... or it is cut at its corners (:func:`_cuts`) into pieces that are such ellipses, recursively
#: this deep (a piece of two objects, or of three).
CUT_DEPTH = 2


def _as_ellipses(pieces, outline):
    """The pieces (lists of curves) of an object cut at its necks as objects: each piece an
    ellipse of the object's outline (:func:`_cut_ellipse`) or cut at its corners into such
    ellipses (:func:`_ellipse_cuts`); None when one is neither.

    The neck stage keeps an object whole when one of its parts is no blob (a body with limbs,
    :meth:`_PartGraph.merge_non_blobs`); two elongated objects side by side have no neck between
    them and make such a part, and their neighbours in the clump were merged back with them
    (touching ellipses seed 13: a chain of six, one object).  A clump is told from a body with
    limbs by its outline: every stretch of it is an ellipse's, which a star's arms, a horse's
    legs and head or a bent rod's halves are not (the singles family, seeds 0-59: none kept)."""
    # (the cheaper tests first, each over all pieces: most objects that are no clump fail one)
    if any(len(piece) > 1 for piece in pieces):  # a piece with a hole is no ellipse
        return None
    ellipses = [_cut_ellipse(piece[0], outline) for piece in pieces]
    found = []
    for piece, ellipse in zip(pieces, ellipses, strict=True):
        if ellipse:
            found.append(piece)
        elif (cuts := _ellipse_cuts(piece[0], outline, CUT_DEPTH)) is not None:
            found.extend([cut] for cut in cuts)
        else:
            return None
    return found


#: :func:`_around_a_hole`: a part whose pixels reach this far (pixels) around a hole on every side
#: holds it once cut out, whatever the straightening of its borders (``SPLIT_LINE_TOLERANCE``).
_HOLE_MARGIN = 2


def _around_a_hole(curves, parts, low):
    """Whether one of the pixel parts (window coordinates, ``low`` its corner) surrounds a hole of
    the object: every pixel within ``_HOLE_MARGIN`` of the hole's pixels is in that part, so its
    piece of :func:`_cut` has the hole, and :func:`_as_ellipses` declines it.  Shown on the
    pixels, without cutting the polygon (on the singles family, half of the objects that reach
    :func:`_as_ellipses` have such a piece: rings, horses)."""
    import scipy.ndimage

    for hole in curves[1:]:
        pixels = rasterize([hole - low], parts.shape)
        if not pixels.any():
            continue
        near = scipy.ndimage.binary_dilation(pixels, iterations=_HOLE_MARGIN)
        if len(np.unique(parts[near])) == 1 and parts[near][0] > 0:
            return True
    return False


def _as_rows(points):
    """Each point of an (P, 2) float array as one opaque value (its 16 bytes), for exact lookups."""
    points = np.ascontiguousarray(points, dtype=np.float64)
    return points.view(np.dtype((np.void, 16))).ravel()


def _cut_ellipse(part, outline):
    """Whether a piece cut off an object (a polygon whose vertices are the object's ``outline``'s
    vertices and those of straight cuts) is an object's ellipse: its vertices on the outline, but
    those within ``CUT_TRIM`` of a vertex that is not the outline's (the ends and bends of a
    neck's cut; a corner cut of :func:`_ellipse_cuts` joins two of the outline's vertices and
    trims none), fitted by one ellipse within ``ARC_RMS``, of aspect
    at most ``MAX_PART_ASPECT``, at most ``ARC_OUTSIDE`` of it outside the object, and the piece
    ``CUT_SOLIDITY`` solid.  An ellipse of the arc stage (:func:`_arc_ellipse`), fitted to the
    piece's arcs."""
    # (the cut keeps the outline's vertices to the bit, :func:`_cut`: one lookup of each vertex)
    on_outline = np.isin(_as_rows(part), _as_rows(outline))
    if not on_outline.all():
        cut = part[~on_outline]
        apart = np.hypot(*(part[:, None, :] - cut[None]).transpose(2, 0, 1)).min(axis=1)
        on_outline &= apart > CUT_TRIM
    area = signed_area(part)
    if np.count_nonzero(on_outline) < 6 or area < np.pi * MIN_SPLIT_RADIUS**2:  # (5 parameters)
        return False
    points = part[on_outline]
    return bool(_arc_ellipse(points, _ellipse_fit(points), outline) is not None
                and area >= CUT_SOLIDITY * hull_area(part))


def _ellipse_area(pieces, outline):
    """The area of the pieces (lists of curves) cut off an object (its ``outline``) that are an
    object's ellipse (:func:`_cut_ellipse`; a piece with a hole is none): how much of the object
    a split explains, by which two splits of it are weighed."""
    return sum(signed_area(piece[0]) for piece in pieces
               if len(piece) == 1 and _cut_ellipse(piece[0], outline))


def _ellipse_cuts(part, outline, depth):
    """A piece cut off an object cut at its concave corners into pieces that are each an object's
    ellipse (:func:`_cut_ellipse`; a side that is not cut again, down to ``depth`` cuts deep):
    the polygons, or None.  The cuts tried are :func:`_corner_parts`' (the first ``CUT_OPTIONS``
    admissible ones of :func:`_cuts`, narrowest first), and the first whose sides are ellipses
    stands."""
    if _uncuttable(signed_area(part), False):
        return None
    corners, kappa, normals = _concave_corners(part)
    if len(corners) == 0:
        return None
    flat = _within(kappa <= 0, max(int(2 * CORNER_SMOOTHING / edge_lengths(part).mean()), 1))
    is_corner = np.zeros(len(part), dtype=bool)
    is_corner[corners] = True
    tried = 0
    for _, a, b in _cuts(part, np.arange(len(part)), is_corner, flat, normals):
        sides = part[a:b + 1], np.concatenate([part[b:], part[:a + 1]])
        if min(signed_area(side) for side in sides) < np.pi * MIN_SPLIT_RADIUS**2:
            continue
        found = []
        for side in sides:
            if _cut_ellipse(side, outline):
                found.append(side)
            elif depth > 1 and (cuts := _ellipse_cuts(side, outline, depth - 1)) is not None:
                found.extend(cuts)
            else:
                break
        else:
            return found
        tried += 1
        if tried == CUT_OPTIONS:
            break
    return None
