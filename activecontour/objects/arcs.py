"""Stage 0 of the split (:mod:`activecontour.objects.split`): arcs grouped into ellipses.

The concave corners cut the outline into arcs, the arcs are grouped into ellipses (a group joins
while one ellipse fits it about as well as two, by the Bayesian information criterion), and every
pixel goes to the ellipse it lies deepest in, the rule by which overlapping objects are drawn
(:func:`_arc_clump`; what it must explain before it decides alone: the module docstring of
:mod:`activecontour.objects.split`).
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

from activecontour import _kernels
from activecontour.geometry.curve import edge_lengths, signed_area
from activecontour.geometry.raster import rasterize
from activecontour.objects.corners import _bent, _corner_turns, _cut
from activecontour.objects.shapes import (
    MIN_SPLIT_RADIUS,
    _arc_ellipse,
    _as_fits,
    _clearly_not_arc_ellipses,
    _ellipse_polygon,
    _normalised_radius,
    _stacked_ellipse_fits,
)

# ---- stage 2, first: the outline's arcs grouped into ellipses -----------------------------------

#: :func:`_arc_clump` cuts the outline into arcs at concave stretches that turn by this many
#: degrees (and dip ``MIN_WAIST_DEPTH`` inside the hull): lower than ``CORNER_TURN``, since a
#: stretch of noise only cuts an arc in two that the grouping joins again, while a contact whose
#: corner the converged contour rounded below ``CORNER_TURN`` is still found.
ARC_CORNER_TURN = 15.0
#: Each arc loses this much (pixels of arc length) at both ends (the rounding of the corner is
#: neither object's outline) and is fitted only when this much of it is left.
ARC_TRIM, ARC_MIN_LENGTH = 1.5, 4.0
#: An outline of more arcs than this is no clump of ellipses (a clump of ``FAMILY_CLUMP`` = 8
#: objects has at most 14 contacts, 28 corners) but a ragged region of a texture: not grouped (the
#: grouping costs the square of the arcs in ellipse fits).
ARC_MAX = 32
#: Two groups of arcs join when one ellipse fits their union as well as two fit them apart, up to
#: the Bayesian information criterion of the five parameters saved: the squared Sampson distances
#: grow by at most ``5 ln n`` noise variances for n points, the noise variance being the two fits'
#: own, at least this (pixels) squared.
ARC_NOISE = 0.2
#: The ellipses explain the object when they cover this fraction of its pixels ...
ARC_COVER = 0.9
#: ... and this fraction of the outline's vertices lies within ``ARC_GAP`` pixels of one
#: (normalised radius off 1 by ``ARC_GAP`` over the ellipse's radius) ...
ARC_GAP = 2.0
#: ... at most this fraction of its pixels lies in three ellipses (objects pressed together overlap
#: two by two; the arms of a star, fitted each by an ellipse, all reach into its centre) ...
ARC_TRIPLE = 0.02
#: Two ellipses may overlap by this fraction of the smaller one (two disks overlapping by a third
#: of their diameter, the families' most, share 0.22 of a disk; a small disk pressed as deep into
#: a large object, 0.29); of two that overlap more, the one that fits its arcs worse is dropped
#: (an ellipse across a star's centre, through two opposite arms).
ARC_OVERLAP = 0.3
#: ... every point where the border between two parts meets the outline lies within
#: ``ARC_END_REACH`` pixels of a corner that turns by ``ARC_END_TURN`` (a waist at both ends: a
#: bent rod or a banana cut across is not two objects), no point has four parts within
#: ``ARC_REACH`` (a star's arms all meet at its centre; objects pressed together meet two or
#: three at a point) ...
ARC_REACH = 3.0
#: The border ends' reach: the ellipses fitted to the arcs of a contact that the converged
#: contour rounded (blur, noise, the length term) cross up to several pixels from the corner
#: found.  On the touching families (seeds 0-59) the clumps whose ellipses explain them had ends
#: 3-23 px from a corner (3 px declined 101 of them); the bent rods of the singles family are cut
#: across by a border that ends 11-14 px from their one corner (singles seeds 38 and 45), so 10.
ARC_END_REACH = 10.0
#: The corners a border between two parts may end at turn by this many degrees: more than
#: ``ARC_CORNER_TURN``, which only cuts the outline into arcs (a wiggle of the noise cuts one arc
#: in two that the grouping joins again), since a border is drawn where two objects cross.  A
#: bent rod has one concave corner, inside its bend; a wiggle of 15-20 degrees on the outside of
#: the bend was the other end of a border cutting it into two ellipses (the singles family,
#: seed 7: 17 degrees), while the contacts of the touching families, the rounded ones too, turn
#: by more (seeds 0-59 split the same with 15 and with 20 degrees).
ARC_END_TURN = 20.0
#: ... and at most this many places have three parts within it (a chain or a tree of objects
#: has none, a trefoil one; the petals of a flower fitted around the part that takes its centre
#: make one with each two neighbours) ...
ARC_TRIPLE_POINTS = 2
#: ... and every part is at least this fraction of the largest: objects pressed into a clump are of
#: comparable size (the families' radii differ by 1.5 at most, areas by 2.25), while the petals of
#: a flower or the arms of a star are small beside the part that takes its centre.
ARC_SIZE_RATIO = 0.25
#: Where the ellipses leave part of the object uncovered (an object pressed inside the clump owns
#: no arc; an arc too short for its ellipse leaves its object without one), each piece of it as
#: large as a part (``ARC_SIZE_RATIO``) is an object of its own when the ellipses still explain
#: this fraction of the outline: the uncovered pieces then lie mostly inside the clump.  The arms
#: of a star, each fitted by an ellipse that overlaps its neighbours too much to be kept, leave
#: more of the outline unexplained (singles seeds 0-59: 0.39-0.55 explained; the clumps so
#: split, 0.62-0.96: a narrow margin, at 0.65 the worst ellipse seed, 13, falls back to 0.28).
ARC_HIDDEN_OUTLINE = 0.6
#: A crowded clump -- more than ``ARC_TRIPLE_POINTS`` places where three parts meet: six to eight
#: objects pressed together, or an object hidden among them (it owns no arc: an uncovered piece,
#: :func:`_uncovered_parts`) -- is a clump of ellipses only where the ellipses overlap two by two
#: (no pixel lies in three: ``ARC_TRIPLE`` is a star's arms, all reaching into its centre) and at
#: most this many parts meet at one point.  Four parts at one point with few places of three is a
#: star's centre where its arms' ellipses meet, and stays declined (singles seeds 100-159, 149
#: and 153: four parts at one place, one or two places of three; the touching families' crowded
#: clumps, seeds 0-79: three to seven places) ...
ARC_CROWD_MEET = 4
#: ... and each uncovered piece made an object is at most this many times the largest ellipse's
#: cell: an object hidden in a clump shows less than its whole, and the clump's objects are of
#: comparable size, while the body of a star whose arms were fitted by ellipses is two to three
#: times each arm (singles seeds 60-99, 79 and 97: 2.1-2.9; the families' hidden objects, seeds
#: 0-59: at most 1.1).  Such a clump is not decided by the arcs alone:
#: :func:`activecontour.objects.split.split_touching` keeps it only where more of its area is an
#: object's ellipse than of the stages' parts.  What this does not tell apart: a five-armed star
#: whose fitted ellipses leave its centre and one arm uncovered, three places of three and the
#: uncovered piece no larger than an arm (singles seed 144, cut into five; the one single of 960,
#: seeds 0-159, that crowded clumps cut).
ARC_HIDDEN_SIZE = 1.5


def _arc_clump(curves, depth=None, extent=None, bent=None):
    """The parts of an object (outer boundary, then holes: a ring of objects around a gap) as a
    clump of overlapping ellipses (lists of curves) and whether the clump is crowded, or None
    when no such clump explains it.
    ``extent``: the label image's shape, whose edge cuts an object that leaves it; ``depth`` and
    ``bent``: the outline's :func:`_hull_depth` and :func:`_bent`, when they are known.

    The model-based split of overlapping convex objects (nuclei): where two convex objects
    overlap, their outlines cross at a concave corner (negative curvature kappa of (3.45), turning
    by ``ARC_CORNER_TURN``, :func:`_concave_corners`), so the corners cut the outline into arcs
    each of which belongs to one object, and an object of a clump owns one arc (at the clump's
    end) or several (one on each side, in a chain).  Each arc is fitted with an ellipse
    (:func:`_ellipse_fits`); arcs are joined, the pair that costs least first, while one ellipse
    explains their union as well as two do (``ARC_NOISE``) or one of them alone is no object's
    ellipse (``ARC_RMS``, ``ARC_OUTSIDE``).  Each pixel goes to the ellipse it lies deepest in
    (its normalised radius least: the truth's rule of :func:`activecontour.synthetic.
    render_instances` for overlaps), and the cells are cut out of the polygon (:func:`_cut`).

    Of two ellipses that overlap by more than ``ARC_OVERLAP``, the worse fit is dropped.  The clump
    stands when the ellipses' boundaries explain the outline (``ARC_COVER`` of its vertices within
    ``ARC_GAP``), the ellipses cover ``ARC_COVER`` of the object and three of them at most
    ``ARC_TRIPLE`` of it -- or, where they cover less or explain less of the outline but
    ``ARC_HIDDEN_OUTLINE`` of it, the uncovered pieces are objects of their own
    (:func:`_uncovered_parts`) --, every part holds pi ``MIN_SPLIT_RADIUS``^2 pixels and
    ``ARC_SIZE_RATIO`` of the largest part, every border between two parts reaches the outline at
    corners only (of ``ARC_END_TURN``, within ``ARC_END_REACH``), no four parts meet and at most
    ``ARC_TRIPLE_POINTS`` places have three (``ARC_REACH``, :func:`_meet_at_corners`).  Otherwise
    the necks and the corner cuts decide, as for an object without this stage -- but for a
    crowded clump (more than ``ARC_TRIPLE_POINTS`` places of three, at most ``ARC_CROWD_MEET``
    parts at one point) whose ellipses overlap two by two and whose uncovered pieces are no
    larger than ``ARC_HIDDEN_SIZE`` ellipses: it is returned as crowded, for the caller to weigh
    against the stages below.  Unlike a cut
    between two corners, the grouping splits three objects pressed around one point (a trefoil
    has three corners, one per contact, and three arcs) and takes a corner whose partner was
    rounded away as the end of two arcs.

    An object that reaches the edge of the image (of the crop of a pointed run,
    ``roi="init"``, where a touching neighbour is cut off by the neighbourhood) is left to the
    stages below: part of its outline is that edge, no object's boundary, so the ellipse of its
    cut-off arcs is not the object's (``tests/imaging/test_pointed.py``: a disk of radius 13 cut
    in half got an ellipse of 13.5 by 8.4 px, and the touching disk's part took three pixels of
    it at the ends of the contact, outside the lens the two share).
    """
    outline = curves[0]
    area = signed_area(outline)
    if area < 2 * np.pi * MIN_SPLIT_RADIUS**2:
        return None
    if extent is not None and (outline.min() <= -0.5
                               or (outline.max(axis=0) >= np.subtract(extent, 0.5)).any()):
        return None
    bent = _bent(outline) if bent is None else bent
    # (the corners, and of them those that turn more for the borders' ends, in one pass)
    found, turning = _corner_turns(outline, depth, min(ARC_CORNER_TURN, ARC_END_TURN), bent)
    corners = found[~(turning < ARC_CORNER_TURN)]
    if len(corners) < 2:
        return None
    arcs = _arcs(outline, corners)
    if not 2 <= len(arcs) <= ARC_MAX:
        return None
    groups = _grouped_arcs(outline, arcs)
    # of two ellipses that overlap too much, the one that fits its arcs worse is no object's
    fitted = sorted(((fit[1] / sum(arcs[k].size for k in group), ellipse) for group, fit, ellipse in groups
                     if ellipse is not None), key=lambda entry: entry[0])
    ellipses, shapes = [], []
    for _, ellipse in fitted:
        shape = _ellipse_polygon(ellipse)
        shape_area = abs(signed_area(shape))
        if all(_kernels.convex_clip_area(shape, other) <= ARC_OVERLAP * min(shape_area, other_area)
               for other, other_area in shapes):
            ellipses.append(ellipse)
            shapes.append((shape, shape_area))
    if len(ellipses) < 2:
        return None
    # the outline is the ellipses' visible boundary: each vertex near one (an ellipse dropped for
    # its overlap, or never found, leaves its arc unexplained); told from the outline alone, so
    # before the pixels are rasterised and placed in the ellipses (either test declines the
    # clump, their order changes no answer; on grass all 39 objects declined after the grouping
    # with two ellipses or more are declined by this one)
    gap = np.min([np.abs(_normalised_radius(ellipse, outline) - 1) * np.sqrt(np.prod(ellipse[1]))
                  for ellipse in ellipses], axis=0)
    explained = np.count_nonzero(gap <= ARC_GAP)
    if explained < ARC_HIDDEN_OUTLINE * len(outline):
        return None
    low = np.floor(outline.min(axis=0)).astype(int) - 1
    window = tuple(np.ceil(outline.max(axis=0)).astype(int) - low + 2)
    inside = rasterize([curve - low for curve in curves], window)
    points = np.argwhere(inside)
    depth_in = np.array([_normalised_radius(ellipse, points + low) for ellipse in ellipses])
    covered = np.count_nonzero(depth_in <= 1, axis=0)
    if np.count_nonzero(covered >= 3) > ARC_TRIPLE * len(points):
        return None
    parts = np.zeros(inside.shape, dtype=np.int32)
    parts[tuple(points.T)] = np.argmin(depth_in, axis=0) + 1
    cells = int(parts.max())  # (the ellipses' cells; the uncovered pieces' ids follow)
    if explained < ARC_COVER * len(outline) or np.count_nonzero(covered) < ARC_COVER * len(points):
        uncovered = np.zeros(inside.shape, dtype=bool)
        uncovered[tuple(points[covered == 0].T)] = True
        if not _uncovered_parts(parts, uncovered):
            return None
    count = int(parts.max())
    outer = inside if len(curves) == 1 else rasterize([outline - low], window)  # (without holes)
    sizes = np.bincount(parts.ravel(), minlength=count + 1)[1:]
    ends = found[~(turning < ARC_END_TURN)]
    if sizes.min() < max(np.pi * MIN_SPLIT_RADIUS**2, ARC_SIZE_RATIO * sizes.max()):
        return None
    if (meeting := _meeting(parts, outer, outline[ends] - low, count)) is None:
        return None
    most, triples = meeting
    crowded = most >= 4 or triples > ARC_TRIPLE_POINTS
    if crowded and (most > ARC_CROWD_MEET or triples <= ARC_TRIPLE_POINTS or np.any(covered >= 3)
                    or sizes[cells:].max(initial=0) > ARC_HIDDEN_SIZE * sizes[:cells].max()):
        return None
    pieces = _cut(curves, parts, low)
    if len(pieces) != count or any(len(piece) != 1 for piece in pieces):
        return None  # a cell in pieces, or with a hole: no clump of ellipses
    return pieces, crowded


def _uncovered_parts(parts, uncovered):
    """Give each 4-connected piece of the ``uncovered`` pixels (those in no ellipse) at least as
    large as a part may be -- pi ``MIN_SPLIT_RADIUS``^2 and ``ARC_SIZE_RATIO`` of the largest
    ellipse's cell -- an id of its own in ``parts`` (the cells of the ellipses, each pixel in
    the one it lies deepest in); smaller pieces, the slivers between ellipses that meet, stay in
    their nearest ellipse's cell.  Whether any piece was large enough."""
    import scipy.ndimage

    pieces, count = scipy.ndimage.label(uncovered)
    if count == 0:
        return False
    smallest = max(np.pi * MIN_SPLIT_RADIUS**2, ARC_SIZE_RATIO * np.bincount(parts[~uncovered])[1:].max())
    large = np.flatnonzero(np.bincount(pieces.ravel())[1:] >= smallest) + 1
    if large.size == 0:
        return False
    lookup = np.zeros(count + 1, dtype=parts.dtype)
    lookup[large] = parts.max() + np.arange(1, large.size + 1)
    new = lookup[pieces[uncovered]]
    parts[uncovered] = np.where(new > 0, new, parts[uncovered])
    return True


def _arcs(outline, corners):
    """The vertices (indices) of the outline between each two consecutive corners, less
    ``ARC_TRIM`` of arc length at both ends; arcs shorter than ``ARC_MIN_LENGTH`` left out."""
    h = edge_lengths(outline)
    along = np.concatenate([[0.0], np.cumsum(h)])
    total, count = along[-1], len(outline)
    arcs = []
    for a, b in zip(corners, np.roll(corners, -1), strict=True):
        index = np.arange(a, b if b > a else b + count) % count
        length = (along[b] - along[a]) % total
        position = (along[index] - along[a]) % total
        keep = index[(position >= ARC_TRIM) & (position <= length - ARC_TRIM)]
        if length - 2 * ARC_TRIM >= ARC_MIN_LENGTH and keep.size >= 6:  # (5 parameters)
            arcs.append(keep)
    return arcs


def _grouped_arcs(outline, arcs):
    """The arcs joined into groups (:func:`_arc_clump`): a list of (arcs, fit, ellipse or None).
    The fits of all new pairs are solved together; a pair's ellipse is made and tested (a polygon
    intersection, the dearest test) only when its cost makes it the pair to join, and a single
    arc's only when it is left alone (the joining reads the fits).  A fit whose conic fails
    :func:`_arc_ellipse`'s shape tests by a clear margin (:func:`_clearly_not_arc_ellipses`, all
    the new fits at once) has no ellipse from the start: an option the joining would have tried
    and passed over, or a single arc's None."""
    def points(group):
        return outline[np.concatenate([arcs[i] for i in group])]

    def fitted(groups):
        """The fits of groups of arcs, each with None for its ellipse, or False where it has none."""
        sets = [points(group) for group in groups]
        conics, found, residuals = _stacked_ellipse_fits(sets)
        rejected = _clearly_not_arc_ellipses(conics, found, residuals, [len(points) for points in sets])
        return [[fit, False if no else None]
                for fit, no in zip(_as_fits(conics, found, residuals), rejected.tolist(), strict=True)]

    singles = [(i,) for i in range(len(arcs))]
    groups = [(group, *entry) for group, entry in zip(singles, fitted(singles), strict=True)]
    joined = {}  # pair of groups: the union's fit, then its ellipse once asked (False: none)
    while len(groups) > 1:
        pairs = list(combinations(range(len(groups)), 2))  # (np.triu_indices' order, as ints)
        new = [(groups[i][0], groups[j][0]) for i, j in pairs if (groups[i][0], groups[j][0]) not in joined]
        joined.update(zip(new, fitted([a + b for a, b in new]), strict=True))
        options = []
        for i, j in pairs:
            fit, ellipse = joined[(groups[i][0], groups[j][0])]
            if ellipse is False or fit[0] is None:
                continue
            # the excess of the union's squared distances over the two fits', in noise variances
            # (a group whose fit failed joins whatever it costs, the cheapest first)
            apart = groups[i][1][1] + groups[j][1][1]
            count = sum(arcs[k].size for k in groups[i][0] + groups[j][0])
            if np.isfinite(apart):
                noise = max(apart / max(count - 10, 1), ARC_NOISE**2)
                cost = (fit[1] - apart) / noise
                if cost > 5 * np.log(count):
                    continue
            else:
                cost = fit[1] / count - 1e12
            options.append((cost, len(options), i, j))
        best = None
        for _, _, i, j in sorted(options):
            key = (groups[i][0], groups[j][0])
            entry = joined[key]
            if entry[1] is None:
                entry[1] = _arc_ellipse(points(key[0] + key[1]), entry[0], outline)
                entry[1] = False if entry[1] is None else entry[1]
            if entry[1] is not False:
                best = (i, j, (key[0] + key[1], entry[0], entry[1]))
                break
        if best is None:
            break
        i, j, union = best
        groups = [group for k, group in enumerate(groups) if k not in (i, j)] + [union]
    return [(group, fit, (None if ellipse is False else _arc_ellipse(points(group), fit, outline))
             if len(group) == 1 else ellipse) for group, fit, ellipse in groups]


def _meet_at_corners(parts, inside, corners, count):
    """Whether the borders between the pixel parts reach the object's edge (``inside``: the
    pixels within its outer boundary) within ``ARC_END_REACH`` of a corner (window coordinates) only,
    no pixel has four parts within ``ARC_REACH`` and at most ``ARC_TRIPLE_POINTS`` places have
    three (:func:`_meeting`)."""
    meeting = _meeting(parts, inside, corners, count)
    return meeting is not None and meeting[0] < 4 and meeting[1] <= ARC_TRIPLE_POINTS


def _meeting(parts, inside, corners, count):
    """None when a border between the pixel parts reaches the object's edge (``inside``) farther
    than ``ARC_END_REACH`` from every corner (window coordinates); else the most parts within
    ``ARC_REACH`` of one pixel (``count`` when under three parts) and the number of places (pieces
    of pixels) where three parts or more are within it."""
    import scipy.ndimage

    edge = inside & ~scipy.ndimage.binary_erosion(inside)
    border = np.zeros_like(inside)
    for axis in (0, 1):
        for shift in (1, -1):
            other = np.roll(parts, shift, axis=axis)
            border |= (other != parts) & (other > 0) & (parts > 0)
    ends = np.argwhere(edge & border)
    if ends.size:
        if not len(corners):  # a border reaches the edge, and there is no corner for it to end at
            return None
        apart = np.hypot(*(ends[:, None, :] - corners[None]).transpose(2, 0, 1))
        if apart.min(axis=1).max() > ARC_END_REACH:
            return None
    if count < 3:
        return count, 0
    reach = int(ARC_REACH)
    rows, cols = np.mgrid[-reach:reach + 1, -reach:reach + 1]
    disk = rows**2 + cols**2 <= ARC_REACH**2
    # each part dilated on its box grown by the reach: nothing of it lies outside, so the window's
    # dilation is that box's and zero beyond it (the work grows with the parts' boxes, not with
    # the window times the parts)
    near = np.zeros(parts.shape, dtype=np.int8)
    for k, box in enumerate(scipy.ndimage.find_objects(parts, count), start=1):
        if box is not None:
            grown = tuple(slice(max(b.start - reach, 0), b.stop + reach) for b in box)
            near[grown] += scipy.ndimage.binary_dilation(parts[grown] == k, disk)
    return int(near.max()), scipy.ndimage.label(near >= 3)[1]
