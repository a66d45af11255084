"""Touching objects kept apart: an object split where two or more overlapping objects meet.

:func:`split_touching` cuts each object of the inside region into the objects it is made of.  The
cut lines are shared by both parts, so the parts tile the object exactly and the label image stays
the mask with ids.

Three stages, each a model of how touching objects look, each cheap to skip, after a model of the
whole clump:

0. **Arcs grouped into ellipses** (:func:`_arc_parts`, the sub-pixel polygon, holes allowed):
   the concave corners cut the outline into arcs, the arcs are grouped into ellipses (a group
   joins while one ellipse fits it about as well as two, by the Bayesian information criterion)
   and every pixel goes to the ellipse it lies deepest in, the rule by which overlapping
   objects are drawn.  It decides alone where the ellipses explain the object -- its outline,
   its pixels (or most of the outline, the pieces they leave uncovered being objects of their
   own: pressed inside the clump, or without an arc long enough for its ellipse), overlaps two by
   two, borders that end at corners, parts of comparable size, few places where three meet --
   which a trefoil of three disks around one point (three corners,
   no pair of them a cut that leaves ellipses) satisfies and a star, a flower, a bent rod or a
   horse do not; elsewhere the three stages below decide as they did, and each piece they cut
   off goes through this stage on its own (:func:`_clump_parts`): a smaller clump, cut off at
   a neck, has its own outline explained by its arcs where the whole object's was not (an
   object pressed inside it, or a contact rounded away, left part of it unexplained).
1. **Necks** (:func:`_neck_parts`, pixels): the watershed of the distance to the outline (an
   inscribed-circle centre per part) whose parts are merged back while the neck between two is
   nearly as wide as the thinner part; a neck must be a waist (a concavity of the outline at both
   ends).  Disks and blobs that overlap by up to a third of their diameter meet at a neck of
   ``sqrt(5)/3 = 0.745`` of their radius.  A shallow neck (above ``TUBE_NECK``) between two
   parts that hold more than ``TUBE_AREA`` times the area of their inscribed disks is a dent of
   a rod or stroke, and is kept whole.  A part that is no blob (a body with limbs) takes its
   neighbours back, unless every part is an ellipse of the object's outline or is cut at its
   corners into such ellipses (:func:`_as_ellipses`): two elongated objects side by side have no
   neck between them and make such a part in a chain of necks.
2. **Concave corners** (:func:`_corner_parts`, the sub-pixel polygon): two convex objects that
   overlap meet at two corners of the outline, concave stretches where the curvature kappa of the
   book's 1-D geometry (section 6.5: ``kappa nu = -Laplace_Sigma id``, (3.45), (4.30);
   :func:`activecontour.geometry.curve.curvature`) turns by tens of degrees within a pixel or two.
   Elongated objects side by side have no neck narrower than themselves (the neck stage keeps
   them as one), but they have these corners.  Corners are paired into straight cut lines (or cut
   across along a corner's inward normal when the opposite corner is too shallow to be found);
   the cut chosen is the one whose two parts are best explained by one ellipse each (the
   direct least-squares conic fit of Fitzgibbon, Pilu and Fisher in the stable form of Halir and
   Flusser; residuals as Sampson distances in pixels).  It is kept when the parts explain the
   object: at least half of the area that one ellipse did not explain is then explained by
   ellipses (:data:`EXPLAINED_GAIN`), every kept part a good ellipse -- residual within
   :data:`ELLIPSE_RMS`, its ellipse within the object (:data:`ELLIPSE_OUTSIDE`), solid, of aspect
   at most :data:`MAX_PART_ASPECT` -- so a star's arm, a horse's head or a bent rod's arm, which
   leave a part no ellipse explains, are not cut off.
3. **Contrast** (:func:`_contrast_parts`, pixels and the image): a bright object touching a dim
   one, or two separated by a dark seam, without any waist.

Cost: an object whose outline lies within :data:`MIN_WAIST_DEPTH` of its convex hull has no
waist, no neck and no concave corner: it skips stages 0 to 2 after one convex hull of its polygon
(O(K log K) for K vertices), and stage 3 after a block-averaged look at its intensities
(:func:`_block_spread`), so an image of convex objects pays almost nothing for the split.
Past that gate, each stage stops as soon as a consequence of its own criterion shows that it
will not cut, so the shortcuts change no decision (``benchmarks/split_same.py`` compares the
objects before and after a change; ``tests/objects/test_split_gates.py`` the shortcuts): no
neck is looked for where the pixel distance transform has one piece of peaks (one compiled pass,
:func:`_may_have_necks`) or the pixel raster bounds the boundary distance below ``min_radius``
(:func:`_thinner_than`), nor past a watershed with one part thick enough to be an object; no
corner cut in a part that is an ellipse or under twice the smallest part (:func:`_uncuttable`),
nor on the second side of a cut whose first side already leaves too much unexplained; no
contrast split in an object whose box holds fewer pixels than two smallest parts, nor pixels
assigned to cores when the cores' areas already make a piece too small
(:func:`_a_piece_too_small`).  The boundary distance computes the fine raster's distance
transform at the pixel centres only (:func:`activecontour._kernels.sampled_distance`); a
distance compared with a radius of a few pixels is the squared transform up to that radius
(:func:`_near_distance`); the ellipse fits' sums and residuals and the chord-inside test of the
cut search are compiled, and a search's fits share one stacked pass of the sums, one of the
residuals and one eigenproblem (:func:`_stacked_ellipse_fits`); how much of an ellipse lies
outside the object is one compiled clip of the outline by the ellipse's polygon
(:func:`_outside`), and the arc grouping judges all its new fits' shapes at once in closed form
(:func:`_clearly_not_arc_ellipses`), making an ellipse only of a fit that may pass.

Measured on the families of :mod:`activecontour.synthetic` (20 seeds each, F1 at IoU 0.5 of
``res.labels``, ``benchmarks/bench_objects.py``; worst seed / mean):

==========================================  =================  ===============  ============
split                                       touching ellipses  touching disks   singles cut
==========================================  =================  ===============  ============
necks alone (stage 1, the split until now)  0.14 / 0.78        0.48 / 0.91      4 of 120
necks, then concave corners                 0.28 / 0.82        0.48 / 0.91      10 of 120
arcs into ellipses first                    0.28 / 0.85        0.53 / 0.93      10 of 120
  on seeds 20-59                            0.50 / 0.92        0.49 / 0.92      12 of 240
the same, and arcs again on each piece cut  0.28 / 0.87        0.65 / 0.94      10 of 120
off by the necks or corners
  on seeds 20-59                            0.50 / 0.92        0.49 / 0.93      12 of 240
  (necks and corners: 0.50 / 0.90, 0.39 / 0.90, 12 of 240)
the same, and the pieces the arc ellipses   0.41 / 0.89        0.77 / 0.94      10 of 120
leave uncovered objects of their own,
borders ending 10 px from a corner (not 3;
this module)
  on seeds 20-59                            0.65 / 0.94        0.68 / 0.94      12 of 240
the same, and the necks' parts kept where    0.50 / 0.92        0.77 / 0.94      6 of 120
they are ellipses of the outline, or cut
into them (``_as_ellipses``)
  on seeds 20-59                            0.65 / 0.95        0.68 / 0.94      6 of 240
distance-transform-marker watershed of the  0.55 / 0.75        0.69 / 0.96      nearly all
segmented mask (``min_distance=5``)
corner cuts with ellipse fits alone (no     0.45-0.50 /        0.55-0.61 /      13-95
neck stage; several settings)               0.83-0.87          0.85-0.87
Otsu + distance watershed (the scikit-      0.42 / 0.78        0.72 / 0.96      nearly all
image gallery pipeline, for reference)
==========================================  =================  ===============  ============

(The first three rows on the segmentation of ``main`` at the merge 0e85b9a, the fourth on that of
5d1d5b5, the fifth on that of 1ac25e4, the sixth on that of 5fa11a5, the same scenes' objects for
every split.) The corner stage is what wins on elongated objects side by side; the necks keep the
singles whole. Until the fifth row, most errors were objects left merged in clumps that the arc
stage declined (on seeds 0-59: 50 pieces holding 135 disks, 48 holding 160 ellipses): of the
pieces of two objects or more, 106 were declined by the border test alone, nearly all with as many
arc ellipses as objects, explaining the outline and the pixels: a border ended 3-23 px from a
corner (the fitted ellipses of a rounded contact cross away from the corner found,
``ARC_END_REACH``); 116 had their ellipses cover less than ``ARC_COVER`` of them, an object
pressed inside the clump owning no arc, or an arc too short for its ellipse (``ARC_OUTSIDE``,
``ARC_RMS``) leaving its object without one (:func:`_uncovered_parts`). The fifth row takes the
worst seeds from 0.28, 0.65 (seeds 0-19) and 0.50, 0.49 (20-59) to 0.41, 0.77 and 0.65, 0.68; the
ellipses' mean is now 0.11 and 0.18 above the pipeline's. What is left: the worst seeds (ellipses
13, 14, 17: 0.41, 0.50, 0.64; disks 8, 6: 0.76, 0.79; seeds 20-59: ellipses 48, 25: 0.65, 0.69;
disks 38, 41: 0.68, 0.73; the pipeline 0.68, 0.78, 0.81, 0.97, 0.83, 0.92, 0.85, 0.98, 0.92) hold
pieces of 6-8 objects still left to the necks and corners: the border test (``ARC_END_REACH``: 14
px cuts two bent rods of the singles) or the size test declines them, or an uncovered piece holds
two objects and is kept as one (a distance watershed of such pieces, or declining them, cost as
much as it gained: ellipses 0.893 -> 0.897-0.902, disks worst 0.765 -> 0.667). Tried and not kept
before: ellipses added for the uncovered area (the moment ellipse of each large piece of it, split
at its own distance peaks), with the border test at 3 px, gained nothing; the distance-transform
watershed put in an object's place when all its parts are ellipse-like changed F1 by 0.005 at
most. On a 3-disk piece of disks seed 48 the pixel distance has a single maximum (a small disk
pressed a third of its diameter into a larger one): no neck to find. The singles the split cuts
(10 of 120, 12 of 240) are cut by the necks (7 of them) and the corners (7, one after a neck):
bent rods but one star (seed 39). The rods' necks are noise of the outline (a rod 24 px wide
narrowed by 1-2 px at two dents); a ``NECK_RATIO`` of 0.8 keeps them whole (3 of 120, 6 of 240
cut, all by the corners) but costs the clumps more (disks worst 0.765 -> 0.50). Measured against
the area instead (``TUBE_AREA``: two parts of a rod hold 2-4 times the area of their inscribed
disks, two deeply overlapping blobs less than it), the necks keep all rods but one whole (6 of
120, 6 of 240 singles cut, the objects of the touching families and of the DSB image unchanged);
the rest are the corner stage's, at the bend of a rod (a one-sided cut from the inner corner
across to the convex outer side: the same geometry as two rods overlapping end to end, which the
rays across a rounded contact must cut) and a star's arms.
"""

from __future__ import annotations

import heapq
from itertools import pairwise

import numpy as np

from activecontour import _kernels
from activecontour.geometry.curve import curvature, edge_lengths, signed_area, vertex_normals
from activecontour.geometry.hull import hull_area, hull_vertices
from activecontour.geometry.raster import rasterize, sorted_crossings
from activecontour.geometry.regions import _from_shapely, _to_shapely

__all__ = ["split_touching"]

#: Two parts of an object are split apart when the half-width of the neck between them is below
#: this fraction of the smaller part's largest inscribed radius.  Two disks overlapping by a third
#: of their diameter have a neck of sqrt(5)/3 = 0.745 of their radius; a protrusion (a leg, a
#: stroke's arm, a ring's arc) has no neck narrower than itself, ratio ~1.
NECK_RATIO = 0.9
#: Parts whose largest inscribed radius is below this (pixels) are never split off: at that size a
#: neck is a pixel or two of the boundary's noise.
MIN_SPLIT_RADIUS = 3.0
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


def split_touching(objects, labels, image=None, *, neck_ratio=NECK_RATIO, min_radius=MIN_SPLIT_RADIUS):
    """Split objects where touching objects meet (the three stages of the module docstring).

    For each object, the pixels inside its outer boundary (holes filled: the rim around a hole is
    not a neck) are over-segmented by the watershed of their exact distance to that boundary from
    every local maximum (an inscribed-circle centre).
    Neighbouring parts are then merged, the pair with the widest neck first, while the half-width
    of the neck between them (the largest distance value on their common border) is at least
    ``neck_ratio`` times the smaller of their largest inscribed radii, or within
    ``MIN_NECK_DEPTH`` pixels of it, or the smaller radius is below ``min_radius``.  The parts
    left have a narrow neck between every two of them.  A neck must also be a waist: the split
    line ends in a concavity of the outline (``MIN_WAIST_DEPTH`` inside the convex hull) at both
    ends; a notch on one side of one object (a coin's dark slit) is not a contact of two.  Last,
    a part that is not blob-like (solidity below ``MIN_PART_SOLIDITY`` or aspect above
    ``MAX_PART_ASPECT``: a body with legs, a bent stroke) takes its neighbours back, until every
    part is a blob or one is left -- unless the parts before that are each an ellipse of the
    object's outline or cut at their corners into such ellipses (:func:`_as_ellipses`: a clump
    with two elongated objects side by side in it).
    A shape of one piece (a ring, a stroke, a limb on a body) has no neck much narrower than its
    thinner side, or has parts that are no blobs, so it is not split.

    Given the image, each part is then split by intensity where the outline has no waist at all
    (:func:`_contrast_parts`): a bright object touching a dim one, or two separated by a dark
    seam, when the two classes of the smoothed intensity differ by ``CONTRAST_DEPTH`` noise
    sigmas (and ``CONTRAST_FLOOR`` of the image's range) and every piece is a blob of a size
    comparable to the others.  On the DSB 2018 nuclei image this took F1 from 0.68 to 0.74
    (before the corner stage; with it, 0.78, ``benchmarks/bench_objects.py``); the families, of
    one brightness, are unchanged, and so are skimage's coins (25 objects).

    The split is applied to the sub-pixel polygon: the parts' pixels, grown over the object's
    bounding box, become cells whose shared borders are straightened (``shapely.coverage_simplify``
    keeps them shared), and each part is the polygon intersected with its cell.  Each part without
    holes is then cut at its concave corners (:func:`_corner_parts`) by straight segments between
    two of its vertices.  Parts therefore share their split lines exactly, never overlap, and
    their union is the object.

    The cost is about linear in the object's pixels however many parts the watershed makes (a
    speckled outline makes one every few pixels): merges are queued by priority and move the
    smaller side (:class:`_PartGraph`), merged parts' shapes are added up rather than measured
    again (:class:`_PartShapes`), and the split by contrast and the cut work on each part's box.
    An object without a concavity ``MIN_WAIST_DEPTH`` deep and without a contrast
    (:func:`_block_spread`) costs one convex hull of its outline and one look at its pixels.

    Parameters
    ----------
    objects : list of list of ndarray
        Object k: outer boundary, then holes; id k + 1 in ``labels``.
    labels : int ndarray (M, N)
    image : ndarray (M, N) or (M, N, C), optional
        The input image (any units; colour channels are averaged): enables the split by contrast.
    neck_ratio, min_radius : float

    Returns
    -------
    list of list of ndarray
        The objects, split ones replaced by their parts (each an outer boundary then its holes).
    """
    if image is not None:
        # (a grey image in its own type: each object's box is read as float64, the whole image
        # only for the noise)
        image = np.asarray(image)
        image = image.astype(np.float64).mean(axis=2) if image.ndim == 3 else image
        # the least contrast of a split by intensity: a number of noise sigmas, and on a noise-free
        # image a fraction of its range (shading is not two objects); the noise is estimated
        # only for an object whose blocks differ by more than that fraction
        floor = CONTRAST_FLOOR * (float(image.max()) - float(image.min()))
        least = None
    result = []
    for k, curves in enumerate(objects):
        box = _box(curves[0], labels.shape)
        inside = labels[box] == k + 1 if box is not None else None
        if inside is None or not inside.any():
            result.append(curves)
            continue
        depth = _hull_depth(curves[0])
        concave = depth.max() >= MIN_WAIST_DEPTH
        contrast = False
        if image is not None:
            spread = _block_spread(inside, np.asarray(image[box], dtype=np.float64), min_radius)
            if spread > floor and least is None:
                from activecontour.imaging.noise import estimate_noise

                noise = estimate_noise(np.asarray(image, dtype=np.float64)[:, :, None])[0]
                least = max(CONTRAST_DEPTH * float(noise), floor)
            # (a part of fewer than twice pi min_radius^2 pixels is never split by contrast,
            # :func:`_contrast_split`, and the parts lie in the object's box)
            contrast = spread > floor and spread > least and inside.size > 2 * np.pi * min_radius ** 2
        if not concave and not contrast:
            result.append(curves)
            continue
        bent = _bent(curves[0]) if concave else None
        if concave and (clump := _arc_parts(curves, depth, labels.shape, bent)) is not None:
            result.extend(clump)
            continue
        low = np.array([box[0].start - 1, box[1].start - 1])
        # the outline's shape decides (holes filled, as scipy.ndimage.binary_fill_holes): the rim
        # around a hole is no neck
        window = np.pad(inside, 1)
        _kernels.fill_holes(window.view(np.uint8))
        contrast = contrast and _may_split_by_contrast(window, min_radius)
        parts = necks = None  # the window as one part; the necks' parts a non-blob took back
        if concave and (concavity := _may_have_necks(window, curves[0] - low, min_radius)) is not None:
            parts, necks = _neck_stage(window, concavity, _boundary_distance(curves[:1], window, low),
                                       neck_ratio, min_radius)
        if contrast:
            parts = _contrast_parts(window.astype(np.int32) if parts is None else parts,
                                    np.asarray(_window(image, box), dtype=np.float64), least, min_radius)
        pieces = _cut(curves, parts, low) if parts is not None and parts.max() > 1 else [curves]
        if (necks is not None and not contrast and len(pieces) == 1 and not _around_a_hole(curves, necks, low)
                and (ellipses := _as_ellipses(_cut(curves, necks, low), curves[0])) is not None):
            result.extend(ellipses)
            continue
        if concave:
            # (an object its necks did not cut: its hull depth and curvature are known)
            pieces = [cut for piece in pieces for cut in
                      ([piece] if len(piece) > 1 else [[part] for part in _corner_parts(
                          piece[0], *((depth, bent) if piece[0] is curves[0] else ()))])]
        if len(pieces) > 1:
            # a piece cut off may be a smaller clump, which its own arcs explain (a convex piece
            # has no concave corner: one convex hull)
            pieces = [part for piece in pieces for part in _clump_parts(piece, labels.shape)]
        result.extend(pieces)
    return result


def _clump_parts(curves, extent):
    """A piece that the necks, the contrast or the corners cut off an object, as the arc stage
    splits it (:func:`_arc_parts`; the piece alone when it does not, or when its outline lies
    within ``MIN_WAIST_DEPTH`` of its hull: a convex piece has no concave corner)."""
    depth = _hull_depth(curves[0])
    return (depth.max() >= MIN_WAIST_DEPTH and _arc_parts(curves, depth, extent)) or [curves]


def _hull_depth(outline):
    """How far (pixels) each vertex of a closed polygon lies inside its convex hull: its distance
    to the hull edge that bridges the stretch it is on (0 on the hull)."""
    hull = np.sort(hull_vertices(outline))
    if len(hull) < 3:  # all vertices on a line
        return np.zeros(len(outline))
    # vertex i lies on the stretch from hull vertex hull[m] to hull[m + 1] (cyclically)
    m = np.searchsorted(hull, np.arange(len(outline)), side="right") - 1
    start, end = outline[hull[m % len(hull)]], outline[hull[(m + 1) % len(hull)]]
    edge = end - start
    cross = edge[:, 0] * (outline[:, 1] - start[:, 1]) - edge[:, 1] * (outline[:, 0] - start[:, 0])
    return np.abs(cross) / np.maximum(np.hypot(edge[:, 0], edge[:, 1]), 1e-12)


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
    import skimage.morphology  # here: most objects are decided before (0.3 s of a cold import)

    # (the square roots of the squared transform: scipy.ndimage.distance_transform_edt's values)
    if scipy.ndimage.label(skimage.morphology.h_maxima(np.sqrt(squared), MIN_NECK_DEPTH / 2))[1] <= 1:
        return None
    concavity = _concavity(region, outline)
    if whole and np.count_nonzero(concavity >= MIN_WAIST_DEPTH) < 2:
        return None
    return concavity


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
    return _near_distance(inside, min_radius)[region].max() < min_radius


def _near_distance(mask, radius):
    """The distance transform of a bool mask with a False pixel (``scipy.ndimage.
    distance_transform_edt``'s values: from each pixel to the nearest False one) where it is at
    most ``radius``, and a value above ``radius`` elsewhere: every comparison with ``radius``
    comes out as on the transform, at a cost of the pixels times ``radius``
    (:func:`activecontour._kernels.near_distance`, the squared distances as integers up to a cap
    whose square root exceeds ``radius``, then the transform's own square root)."""
    cap = int(radius * radius) + 1
    while np.sqrt(cap) <= radius:  # (a radius whose square rounds down)
        cap += 1
    squared = np.empty(mask.shape, dtype=np.int64)
    _kernels.near_distance(np.ascontiguousarray(mask, dtype=np.uint8), cap, squared)
    return np.sqrt(squared)


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
    peak = np.asarray(scipy.ndimage.maximum(distance, parts, np.arange(count + 1)))
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


#: :func:`_contrast_parts` smooths the intensity inside the object with a Gaussian of this sigma
#: (pixels; normalised to the object, so the background does not darken its rim) ...
CONTRAST_SCALE = 1.0
#: ... and splits it in two classes (Otsu) only where their means differ by at least this many
#: times the pixel noise (:func:`activecontour.imaging.noise.estimate_noise`).  On a uniform object the
#: two classes of the smoothed noise differ by ~0.45 noise sigmas, a fifth of this; on the DSB
#: 2018 nuclei image a bright nucleus touching a dim one differs by 6-25 sigmas.
CONTRAST_DEPTH = 2.0
#: ... and by at least this fraction of the image's range (a noise-free image).
CONTRAST_FLOOR = 0.05
#: The dim class counts only this far (pixels) from the bright one and from the outline: the
#: blurred rim of a bright object is dim too, and would wrap around it.
CONTRAST_RIM = 4.0
#: Every piece must be at least this fraction of the largest one's area: a highlight or the
#: relief on a coin (skimage's coins: pieces of 0.07-0.19 of their coin) is no object; touching
#: nuclei are of comparable size (DSB 2018: 0.26-0.48 in the splits made).
CONTRAST_SIZE_RATIO = 0.25


def _window(image, box):
    """The image under a label window (the box grown by one pixel, edge values repeated)."""
    rows = np.clip(np.arange(box[0].start - 1, box[0].stop + 1), 0, image.shape[0] - 1)
    cols = np.clip(np.arange(box[1].start - 1, box[1].stop + 1), 0, image.shape[1] - 1)
    return image[np.ix_(rows, cols)]


def _without_small(mask, area):
    """The connected pieces (4-neighbours) of a bool mask of at least ``area`` pixels."""
    import scipy.ndimage

    pieces, count = scipy.ndimage.label(mask)
    return (np.bincount(pieces.ravel(), minlength=count + 1) >= area)[pieces] & mask


def _box(outline, shape):
    """The pixels whose centres the outer boundary may enclose: a pair of slices, or None."""
    low = np.maximum(np.ceil(outline.min(axis=0)).astype(int), 0)
    high = np.minimum(np.floor(outline.max(axis=0)).astype(int) + 1, shape)
    return None if np.any(high <= low) else (slice(low[0], high[0]), slice(low[1], high[1]))


def _block_spread(mask, values, min_radius):
    """How much the means of the square blocks wholly inside an object (a bool mask and the image
    under its box) differ: a split by contrast needs more than its least contrast.

    A split needs two pieces whose smoothed intensities differ by that much, each at least
    ``CONTRAST_SIZE_RATIO`` of the largest (:func:`_contrast_parts`); blocks of side
    ``max(2 min_radius, sqrt(area) / 32)`` fit inside such pieces, and their means carry the
    noise divided by the side, far below the least contrast on an object of one intensity.  An
    object too small for a block gives infinity (it is always tried)."""
    side = int(max(2 * min_radius, np.sqrt(np.count_nonzero(mask)) / 32))
    m, n = (mask.shape[0] // side) * side, (mask.shape[1] // side) * side
    if m == 0 or n == 0:
        return np.inf
    full = mask[:m, :n].reshape(m // side, side, n // side, side).all(axis=(1, 3))
    if not full.any():
        return np.inf
    return float(np.ptp(values[:m, :n].reshape(m // side, side, n // side, side).mean(axis=(1, 3))[full]))


def _may_split_by_contrast(region, min_radius):
    """Whether :func:`_contrast_parts` may split a part of a region (a bool window, holes filled,
    whose border is outside), shown false without the image: a split makes two pieces or more,
    each within its part, which lies within the region, and each with a pixel ``min_radius``
    from every pixel outside it (:func:`_inscribed_radius_reaches`), so at least as far from every
    pixel outside the region: the region needs two such pixels, and more than twice pi
    ``min_radius``^2 pixels (:func:`_contrast_split`'s least part).  On grass, 172 of the 395
    objects tried by contrast have no two."""
    return bool(np.count_nonzero(region) > 2 * np.pi * min_radius ** 2
                and np.count_nonzero(_near_distance(region, min_radius) >= min_radius) >= 2)


def _contrast_parts(parts, values, least, min_radius):
    """Split each part where it holds a bright and a dim object (or two bright ones and a dark
    seam), given the image under the window and the least contrast of a split.

    Inside the part, the intensity smoothed by ``CONTRAST_SCALE`` is split at Otsu's threshold
    when the two classes' means differ by ``least``.  The bright class
    (holes filled, pieces below pi min_radius^2 dropped) and the dim class at ``CONTRAST_RIM``
    from it and from the outline (pieces below half that dropped) are the cores; every pixel goes
    to the nearest core.  The split stands only if there are two cores or more and every piece
    is a blob (:func:`_is_blob`) with an inscribed radius of ``min_radius`` or more and an area
    of ``CONTRAST_SIZE_RATIO`` of the largest piece's or more: texture, shading and highlights
    inside one object make specks, rims or arcs, not blobs of a size side by side.
    """
    import scipy.ndimage
    import skimage.measure

    result, count = np.zeros_like(parts), 0
    smallest = np.pi * min_radius ** 2
    # each part on its box, grown by the reach of the smoothing: the same numbers as on the
    # window (outside the part everything is zero), at a cost of the part's size, not the window's
    margin = int(4.0 * CONTRAST_SCALE + 0.5) + 1
    for j, box in enumerate(scipy.ndimage.find_objects(parts), start=1):
        if box is None:
            continue
        box = tuple(slice(max(b.start - margin, 0), b.stop + margin) for b in box)
        mask = parts[box] == j
        pieces = _contrast_split(mask, values[box], least, smallest)
        if pieces is not None:
            props = skimage.measure.regionprops(pieces)
            largest = max(p.area for p in props)
            # a piece's inscribed radius on its box and a pixel more (the nearest pixel outside
            # a piece touches it)
            # (the size first: a blob's solidity and moments cost a convex hull image)
            if not all(p.area >= CONTRAST_SIZE_RATIO * largest and _is_blob(p)
                       and _inscribed_radius_reaches(pieces, p.label, p.slice, min_radius) for p in props):
                pieces = None
        if pieces is None:
            count += 1
            result[box][mask] = count
        else:
            result[box][mask] = pieces[mask] + count
            count += int(pieces.max())
    return result


def _inscribed_radius_reaches(labels, label, box, radius):
    """Whether the largest distance from a pixel of ``labels == label`` (within ``box``) to one
    outside is at least ``radius``."""
    grown = tuple(slice(max(b.start - 1, 0), b.stop + 1) for b in box)
    return bool(_near_distance(labels[grown] == label, radius).max() >= radius)


def _contrast_split(mask, values, least, smallest):
    """The pieces of :func:`_contrast_parts` for one part, or None when there is no split (or a
    piece is sure to fail its size test)."""
    import scipy.ndimage
    import skimage.filters

    # the smoothed values inside are weighted means of the values inside: their range is no wider
    raw = values[mask]
    # (a least contrast of 0, on a constant image, splits nothing either)
    if raw.size <= 2 * smallest or np.ptp(raw) <= least:
        return None
    weight = scipy.ndimage.gaussian_filter(mask.astype(float), CONTRAST_SCALE)
    smooth = (scipy.ndimage.gaussian_filter(np.where(mask, values, 0.0), CONTRAST_SCALE)
              / np.maximum(weight, 1e-12))
    inside = smooth[mask]
    # differences at the rounding of the values' magnitude (an image far from zero) are no contrast
    least = max(least, 1e-9 * float(np.max(np.abs(inside), initial=0.0)))
    # the two classes' means differ by less than the range: a narrower range has no split
    if inside.size <= 2 * smallest or np.ptp(inside) <= least:
        return None
    threshold = skimage.filters.threshold_otsu(inside)
    above = inside > threshold
    if above.all() or not above.any() or inside[above].mean() - inside[~above].mean() < least:
        return None  # (Otsu of values that hardly differ can put them all on one side)
    bright = _without_small(scipy.ndimage.binary_fill_holes((smooth > threshold) & mask), smallest) & mask
    # (no bright core: every pixel is far from one)
    away = (_near_distance(mask, CONTRAST_RIM) > CONTRAST_RIM) & (
        (_near_distance(~bright, CONTRAST_RIM) > CONTRAST_RIM) if bright.any() else True)
    dim = _without_small(mask & ~bright & away, smallest / 2)
    bright_cores, n_bright = scipy.ndimage.label(bright)
    dim_cores, n_dim = scipy.ndimage.label(dim)
    if n_bright + n_dim < 2:
        return None
    cores = np.where(bright, bright_cores, np.where(dim, dim_cores + n_bright, 0))
    if _a_piece_too_small(mask, cores):
        return None
    return _nearest_core(mask, cores)


def _nearest_core(mask, cores):
    """The pieces of a part: each pixel of ``mask`` takes the id of its nearest core."""
    import scipy.ndimage

    nearest = scipy.ndimage.distance_transform_edt(cores == 0, return_distances=False, return_indices=True)
    return np.where(mask, cores[tuple(nearest)], 0)


def _a_piece_too_small(mask, cores):
    """Whether one of the pieces of :func:`_nearest_core` is sure to be under
    ``CONTRAST_SIZE_RATIO`` of the largest (so :func:`_contrast_parts` makes no split), told from
    the cores' areas: every piece holds its core and the pieces tile the part, so a piece is at
    most the part less the other cores, and the largest at least the largest core."""
    core_area = np.bincount(cores.ravel())[1:]
    return bool(np.count_nonzero(mask) - core_area.sum() + core_area.min()
                < CONTRAST_SIZE_RATIO * core_area.max())


#: A part of a split object must be blob-like: at least this solid (area / convex hull area) ...
MIN_PART_SOLIDITY = 0.8
#: ... and at most this elongated (major / minor axis of its moments).
MAX_PART_ASPECT = 4.0


def _is_blob(props):
    """Whether a ``skimage.measure.regionprops`` region is blob-like (:func:`_blob_shape`)."""
    return _blob_shape(props.solidity, props.axis_major_length, props.axis_minor_length)


def _blob_shape(solidity, axis_major_length, axis_minor_length):
    return (solidity >= MIN_PART_SOLIDITY
            and axis_major_length <= MAX_PART_ASPECT * max(axis_minor_length, 1e-9))


#: A split line must end in a concavity of the outline at both ends, at least this deep (pixels
#: inside the convex hull): two objects that touch make a waist, a notch on one side of one
#: object (a coin's dark slit) does not.
MIN_WAIST_DEPTH = 1.0


def _concavity(region, outline):
    """For the pixels on the region's edge (a 4-neighbour outside): their distance to the convex
    hull of the outline (a polygon in window coordinates), the hull's boundary being where the
    outline is convex; -1 elsewhere.  A pixel centre on a convex stretch lies about half a pixel
    inside, one in a waist as deep as the waist."""
    import scipy.ndimage
    import shapely

    edge = region & ~scipy.ndimage.binary_erosion(region, border_value=0)
    rows, cols = np.nonzero(edge)
    hull = shapely.convex_hull(shapely.MultiPoint(outline)).exterior
    depth = np.full(region.shape, -1.0)
    depth[rows, cols] = shapely.distance(shapely.points(rows.astype(float), cols.astype(float)), hull)
    return depth


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
    geometries = [_to_shapely([c + low + (box[0].start, box[1].start)
                               for c in mask_to_curves(cells[box] == j)])
                  for j, box in enumerate(boxes, start=1)]
    # cells traced one by one cut the corners of their staircases each their own way, so they
    # overlap there: the overlap goes to the earlier cell, and the cells become a coverage, which
    # the simplification keeps (simplifying overlapping cells opened gaps between them)
    tree = shapely.STRtree(geometries)
    for j, cell in enumerate(geometries):
        earlier = [k for k in tree.query(cell) if k < j]
        if earlier:
            geometries[j] = shapely.difference(cell, shapely.union_all([geometries[k] for k in earlier]))
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
#: A part is an ellipse when the rms Sampson distance of its vertices to the fitted ellipse is
#: within ``ELLIPSE_RMS[0]`` px plus ``ELLIPSE_RMS[1]`` times its equal-area radius (the contour's
#: noise, and the rounding of the corners the part was cut at) ...
ELLIPSE_RMS = (0.4, 0.03)
#: ... at most this fraction of the fitted ellipse lies outside the object (an overlap lies inside
#: the other part) ...
ELLIPSE_OUTSIDE = 0.05
#: ... and the part is at least this solid (area / convex hull area).
ELLIPSE_SOLIDITY = 0.9
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
    ``turn`` degrees (``CORNER_TURN``; ``ARC_CORNER_TURN`` for :func:`_arc_parts`) and it dips
    ``MIN_WAIST_DEPTH`` inside the convex hull (``depth``: :func:`_hull_depth`, measured here
    unless given, and only once a stretch turns enough); the corner is its vertex of most negative
    curvature.  ``bent``: the outline's :func:`_bent`, when it is known (the arc stage and the
    corner stage look at the same outline).
    """
    kappa, normals, ds = _bent(outline) if bent is None else bent
    concave = kappa < 0
    if concave.all() or not concave.any():
        return np.zeros(0, dtype=int), kappa, normals
    # the stretches of negative curvature, starting the count at a vertex that is not in one
    order = np.roll(np.arange(len(outline)), -int(np.argmin(concave)))
    steps = np.diff(np.r_[0, concave[order].astype(int), 0])
    corners = []
    for start, stop in zip(np.flatnonzero(steps == 1), np.flatnonzero(steps == -1), strict=True):
        stretch = order[start:stop]
        if np.degrees(-np.sum(kappa[stretch] * ds[stretch])) < turn:
            continue
        depth = _hull_depth(outline) if depth is None else depth
        if depth[stretch].max() >= MIN_WAIST_DEPTH:
            corners.append(stretch[np.argmin(kappa[stretch])])
    return np.sort(np.array(corners, dtype=int)), kappa, normals


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
    index, count = np.arange(len(values)), len(values)
    smooth = values * weights[radius]
    for j in range(radius, 0, -1):
        smooth += (values[(index - j) % count] + values[(index + j) % count]) * weights[radius + j]
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
    turns = [np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
             for angle in np.radians(CUT_RAYS)]
    # ray (corner, angle), as (2,) vectors stacked: (corners, angles, 2)
    rays = np.array([[-turn @ normals[cycle[a]] for turn in turns] for a in positions])
    offset = start[None, :, :] - start[positions][:, None, :]  # (corners, edges, 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        denominator = (rays[:, :, 0, None] * edge[None, None, :, 1]
                       - rays[:, :, 1, None] * edge[None, None, :, 0])
        along_ray = ((offset[:, :, 0] * edge[:, 1] - offset[:, :, 1] * edge[:, 0])[:, None, :]
                     / denominator)
        along_edge = (offset[:, None, :, 0] * rays[:, :, 1, None]
                      - offset[:, None, :, 1] * rays[:, :, 0, None]) / denominator
    index = np.arange(count)
    away = (index[None, :] != positions[:, None]) & ((index[None, :] + 1) % count != positions[:, None])
    hit = ((np.abs(denominator) > 1e-12) & (along_ray > 1e-9) & (along_edge >= 0) & (along_edge <= 1)
           & away[:, None, :])
    nearest = np.argmin(np.where(hit, along_ray, np.inf), axis=2)  # (corners, angles)
    corner, angle = np.indices(nearest.shape)
    b = np.where(along_edge[corner, angle, nearest] < 0.5, nearest, (nearest + 1) % count)
    a = positions[corner]
    chosen = hit[corner, angle, nearest] & original[nearest] & (b != a)
    return list(zip(a[chosen].tolist(), b[chosen].tolist(), strict=True))


def _segment_inside(edges, a, b):
    """Whether the segment between vertices a and b of a simple polygon (its ``edges``: starts and
    ends) lies inside it: it crosses no edge (those at a and b aside) and its midpoint is inside
    (:func:`activecontour._kernels.segment_inside`)."""
    return _kernels.segment_inside(np.ascontiguousarray(edges[0], dtype=np.float64),
                                   np.ascontiguousarray(edges[1], dtype=np.float64), int(a), int(b))


def _ellipse_fit(points):
    """The direct least-squares ellipse of points (P, 2) (Halir and Flusser's stable form of
    Fitzgibbon, Pilu and Fisher) and the sum of squared Sampson distances (pixels^2) of the
    points to it: (conic or None, residual).  The conic is its coefficients in the points'
    normalised frame; :func:`_ellipse_axes` gives its centre and axes (only the chosen cut's
    parts need them)."""
    return _ellipse_fits([points])[0]


def _ellipse_fits(sides):
    """:func:`_ellipse_fit` of each of several point sets (:func:`_stacked_ellipse_fits`)."""
    return _as_fits(*_stacked_ellipse_fits(sides))


def _as_fits(conics, found, residuals):
    """The fits of :func:`_stacked_ellipse_fits`' arrays, as :func:`_ellipse_fit` gives them."""
    return [((*conic[3:], conic[:2].copy(), conic[2]), residual) if ok else (None, np.inf)
            for ok, conic, residual in zip(found.tolist(), conics, residuals, strict=True)]


def _stacked_ellipse_fits(sides):
    """:func:`_ellipse_fit` of each of several point sets, stacked: (conics, found, residuals),
    row s of ``conics`` set s's (mean0, mean1, scale, a, b, c, d, e, f) where ``found[s]`` (an
    elliptic conic exists), with its residual.  The sums over the points and the residuals of all
    the sets are compiled in one call each (:func:`activecontour._kernels.ellipse_moments`,
    :func:`activecontour._kernels.conic_residuals`), their 3 x 3 solves and eigenproblems one
    call each (the arc grouping fits thousands of small sets on a textured image: per set,
    Python's overhead outweighed the sums)."""
    sides = [np.asarray(points, dtype=np.float64).reshape(-1, 2) for points in sides]
    starts = np.zeros(len(sides) + 1, dtype=np.intp)
    np.cumsum([len(points) for points in sides], out=starts[1:])
    stacked = np.ascontiguousarray(np.concatenate(sides)) if sides else np.zeros((0, 2))
    moments = np.empty((len(sides), 30))
    _kernels.ellipse_moments(stacked, starts, moments)
    s1, s2, s3 = (moments[:, k:k + 9].reshape(-1, 3, 3) for k in (3, 12, 21))
    try:
        t = -np.linalg.solve(s3, np.swapaxes(s2, 1, 2))
    except np.linalg.LinAlgError:  # one of them is singular: each on its own
        if len(sides) == 1:
            return np.full((1, 9), np.nan), np.zeros(1, dtype=bool), np.full(1, np.inf)
        each = [_stacked_ellipse_fits([points]) for points in sides]
        return tuple(np.concatenate(arrays) for arrays in zip(*each, strict=True))
    m = s1 + s2 @ t
    _, vectors = np.linalg.eig(np.stack([m[:, 2] / 2, -m[:, 1], m[:, 0] / 2], axis=1))
    vectors = np.real(vectors)
    # of each set's three eigenvectors (columns), the first elliptic one: 4 a c - b^2 > 0
    elliptic = 4 * vectors[:, 0] * vectors[:, 2] - vectors[:, 1] ** 2 > 0
    found = elliptic.any(axis=1)
    abc = vectors[np.arange(len(sides)), :, np.argmax(elliptic, axis=1)]
    conics = np.column_stack([moments[:, :3], abc, (t @ abc[:, :, None])[:, :, 0]])
    residuals = np.empty(len(sides))
    _kernels.conic_residuals(stacked, starts, conics, residuals)
    residuals[~found] = np.inf
    return conics, found, residuals


def _ellipse_axes(conic):
    """The ellipse of a conic of :func:`_ellipse_fit`: (centre, semi-axes, axes as columns), or
    None when it is no real ellipse."""
    a, b, c, d, e, f, mean, scale = conic
    # centre and axes: value = (z - z0)^T Q (z - z0) - k
    q = np.array([[a, b / 2], [b / 2, c]])
    try:
        centre = np.linalg.solve(2 * q, [-d, -e])
    except np.linalg.LinAlgError:
        return None
    k = centre @ q @ centre - f
    values, axes = np.linalg.eigh(q)
    if np.any(k / values <= 0):
        return None
    return mean + scale * centre, scale * np.sqrt(k / values), axes


def _explained(part, fit, outline):
    """(area, whether the part is explained by its ellipse): ``ELLIPSE_RMS``, ``ELLIPSE_OUTSIDE``
    (of the object, ``outline``), ``ELLIPSE_SOLIDITY``, an aspect of at most ``MAX_PART_ASPECT``
    and an equal-area radius of at least ``MIN_SPLIT_RADIUS``."""
    area = signed_area(part)
    conic, residual = fit
    radius = np.sqrt(max(area, 0.0) / np.pi)
    if (conic is None or radius < MIN_SPLIT_RADIUS
            or np.sqrt(residual / len(part)) > ELLIPSE_RMS[0] + ELLIPSE_RMS[1] * radius):
        return area, False
    ellipse = _ellipse_axes(conic)
    if ellipse is None:
        return area, False
    centre, semi_axes, axes = ellipse
    if semi_axes.max() > MAX_PART_ASPECT * semi_axes.min():
        return area, False
    if _outside(_ellipse_polygon(ellipse), outline) > ELLIPSE_OUTSIDE:
        return area, False
    return area, area >= ELLIPSE_SOLIDITY * hull_area(part)


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


# ---- stage 2, first: the outline's arcs grouped into ellipses -----------------------------------

#: :func:`_arc_parts` cuts the outline into arcs at concave stretches that turn by this many
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
#: An arc group's ellipse is an object's when its rms Sampson distance is within
#: ``ARC_RMS[0] + ARC_RMS[1]`` times its radius (pixels), its aspect at most ``MAX_PART_ASPECT``,
#: its radius at least ``MIN_SPLIT_RADIUS`` and at most this fraction of it lies outside the
#: object (the rounded contacts bulge it a little).
ARC_RMS, ARC_OUTSIDE = (0.5, 0.04), 0.10
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


def _arc_parts(curves, depth=None, extent=None, bent=None):
    """The parts of an object (outer boundary, then holes: a ring of objects around a gap) as a
    clump of overlapping ellipses (lists of curves), or None when no such clump explains it.
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
    the necks and the corner cuts decide, as for an object without this stage.  Unlike a cut
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
    corners, _, _ = _concave_corners(outline, depth, ARC_CORNER_TURN, bent)
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
    low = np.floor(outline.min(axis=0)).astype(int) - 1
    window = tuple(np.ceil(outline.max(axis=0)).astype(int) - low + 2)
    inside = rasterize([curve - low for curve in curves], window)
    points = np.argwhere(inside)
    depth_in = np.array([_normalised_radius(ellipse, points + low) for ellipse in ellipses])
    covered = np.count_nonzero(depth_in <= 1, axis=0)
    # the outline is the ellipses' visible boundary: each vertex near one (an ellipse dropped for
    # its overlap, or never found, leaves its arc unexplained)
    gap = np.min([np.abs(_normalised_radius(ellipse, outline) - 1) * np.sqrt(np.prod(ellipse[1]))
                  for ellipse in ellipses], axis=0)
    explained = np.count_nonzero(gap <= ARC_GAP)
    if (np.count_nonzero(covered >= 3) > ARC_TRIPLE * len(points)
            or explained < ARC_HIDDEN_OUTLINE * len(outline)):
        return None
    parts = np.zeros(inside.shape, dtype=np.int32)
    parts[tuple(points.T)] = np.argmin(depth_in, axis=0) + 1
    if explained < ARC_COVER * len(outline) or np.count_nonzero(covered) < ARC_COVER * len(points):
        uncovered = np.zeros(inside.shape, dtype=bool)
        uncovered[tuple(points[covered == 0].T)] = True
        if not _uncovered_parts(parts, uncovered):
            return None
    count = int(parts.max())
    outer = rasterize([outline - low], window)
    sizes = np.bincount(parts.ravel(), minlength=count + 1)[1:]
    ends = _concave_corners(outline, depth, ARC_END_TURN, bent)[0]  # (of the corners, those that turn more)
    if (sizes.min() < max(np.pi * MIN_SPLIT_RADIUS**2, ARC_SIZE_RATIO * sizes.max())
            or not _meet_at_corners(parts, outer, outline[ends] - low, count)):
        return None
    pieces = _cut(curves, parts, low)
    if len(pieces) != count or any(len(piece) != 1 for piece in pieces):
        return None  # a cell in pieces, or with a hole: no clump of ellipses
    return pieces


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
    """The arcs joined into groups (:func:`_arc_parts`): a list of (arcs, fit, ellipse or None).
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
        pairs = list(zip(*np.triu_indices(len(groups), 1), strict=True))
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


def _arc_ellipse(points, fit, outline):
    """The ellipse (centre, semi-axes, axes) of an arc group's fit when it is an object's
    (``ARC_RMS``, ``MAX_PART_ASPECT``, ``MIN_SPLIT_RADIUS`` and ``ARC_OUTSIDE`` of the object,
    ``outline``), else None."""
    conic, residual = fit
    ellipse = None if conic is None else _ellipse_axes(conic)
    if ellipse is None:
        return None
    semi_axes = ellipse[1]
    radius = np.sqrt(semi_axes.prod())
    if (radius < MIN_SPLIT_RADIUS or semi_axes.max() > MAX_PART_ASPECT * semi_axes.min()
            or np.sqrt(residual / len(points)) > ARC_RMS[0] + ARC_RMS[1] * radius):
        return None
    if _outside(_ellipse_polygon(ellipse), outline) > ARC_OUTSIDE:
        return None
    return ellipse


#: :func:`_clearly_not_arc_ellipses` rejects a conic only when it fails a test of
#: :func:`_arc_ellipse` by this relative margin: far beyond the rounding by which its closed forms
#: differ from :func:`_ellipse_axes`' solve and eigenproblem.
CLEAR_MARGIN = 1e-6


def _clearly_not_arc_ellipses(conics, found, residuals, counts):
    """Which fits of :func:`_stacked_ellipse_fits` (of ``counts`` points each) :func:`_arc_ellipse`
    rejects for their shape alone, all at once: an aspect above ``MAX_PART_ASPECT``, a radius
    below ``MIN_SPLIT_RADIUS`` or an rms Sampson distance above ``ARC_RMS``, each by
    ``CLEAR_MARGIN``.

    The conic ``a x^2 + b xy + c y^2 + d x + e y + f`` with ``q = [[a, b/2], [b/2, c]]``
    (``det q > 0``: the fit is elliptic) has its centre at ``z = -(2q)^-1 (d, e)``, ``k = z^T q z
    - f`` and, with the eigenvalues ``l`` of q, semi-axes ``scale sqrt(k / l)``: the aspect is
    ``sqrt(l_max / l_min)`` and the radius ``sqrt(semi-axes product) = scale sqrt(k) / det(q)^(1/4)``
    in closed form.  Only a conic whose k is no rounding residue and of the eigenvalues' sign
    (a real ellipse) is judged by its radius; anything near a threshold is left to
    :func:`_arc_ellipse`, so no decision changes (False: ask it)."""
    scale, a, b, c, d, e, f = conics[:, 2:].T
    det = a * c - b * b / 4
    half_sum, half_gap = (a + c) / 2, np.hypot((a - c) / 2, b / 2)
    small, large = np.abs(half_sum) - half_gap, np.abs(half_sum) + half_gap  # |eigenvalues|
    with np.errstate(divide="ignore", invalid="ignore"):
        too_long = (det > 0) & (large > MAX_PART_ASPECT**2 * (1 + CLEAR_MARGIN) * small)
        z0 = -(2 * c * d - b * e) / (4 * det)
        z1 = -(2 * a * e - b * d) / (4 * det)
        quadratic = a * z0 * z0 + b * z0 * z1 + c * z1 * z1
        k = quadratic - f
        real = (det > 0) & (k * half_sum > 0) & (np.abs(k) > CLEAR_MARGIN * (np.abs(quadratic) + np.abs(f)))
        radius = scale * np.sqrt(np.abs(k)) / det ** 0.25
        rms = np.sqrt(residuals / np.asarray(counts, dtype=np.float64))
        too_small = real & (radius < MIN_SPLIT_RADIUS * (1 - CLEAR_MARGIN))
        bound = (ARC_RMS[0] + ARC_RMS[1] * radius * (1 + CLEAR_MARGIN)) * (1 + CLEAR_MARGIN)
        too_rough = real & (rms > bound)
    return found & (too_long | too_small | too_rough)


def _ellipse_polygon(ellipse, count=48):
    """An ellipse (centre, semi-axes, axes as columns) as a polygon of ``count`` vertices (count, 2)."""
    centre, semi_axes, axes = ellipse
    angle = np.linspace(0, 2 * np.pi, count, endpoint=False)
    return np.ascontiguousarray(centre + np.column_stack([semi_axes[0] * np.cos(angle),
                                                          semi_axes[1] * np.sin(angle)]) @ axes.T)


def _outside(shape, outline):
    """The fraction of a convex polygon ``shape`` (an :func:`_ellipse_polygon`) that lies outside
    the simple polygon ``outline`` (:func:`activecontour._kernels.convex_clip_area`: the outline
    clipped by the shape's edges, compiled; GEOS's general intersection cost ten times more)."""
    return 1 - _kernels.convex_clip_area(np.ascontiguousarray(outline, dtype=np.float64), shape) / abs(
        signed_area(shape))


def _normalised_radius(ellipse, points):
    """Each point's radius in the ellipse's normalised frame (1 on the ellipse)."""
    centre, semi_axes, axes = ellipse
    local = (points - centre) @ axes
    return np.hypot(local[:, 0] / semi_axes[0], local[:, 1] / semi_axes[1])


def _meet_at_corners(parts, inside, corners, count):
    """Whether the borders between the pixel parts reach the object's edge (``inside``: the
    pixels within its outer boundary) within ``ARC_END_REACH`` of a corner (window coordinates) only,
    no pixel has four parts within ``ARC_REACH`` and at most ``ARC_TRIPLE_POINTS`` places have
    three."""
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
            return False
        apart = np.hypot(*(ends[:, None, :] - corners[None]).transpose(2, 0, 1))
        if apart.min(axis=1).max() > ARC_END_REACH:
            return False
    if count < 3:
        return True
    reach = int(ARC_REACH)
    rows, cols = np.mgrid[-reach:reach + 1, -reach:reach + 1]
    disk = rows**2 + cols**2 <= ARC_REACH**2
    near = sum(scipy.ndimage.binary_dilation(parts == k, disk).astype(np.int8) for k in range(1, count + 1))
    return bool(near.max() < 4 and scipy.ndimage.label(near >= 3)[1] <= ARC_TRIPLE_POINTS)
