"""Touching objects kept apart: an object split where two or more overlapping objects meet.

:func:`split_touching` cuts each object of the inside region into the objects it is made of.  The
cut lines are shared by both parts, so the parts tile the object exactly and the label image stays
the mask with ids.

Three stages, each a model of how touching objects look, each cheap to skip, after a model of the
whole clump; each lives in a module of its own (:mod:`activecontour.objects.arcs`,
:mod:`~activecontour.objects.necks`, :mod:`~activecontour.objects.corners`,
:mod:`~activecontour.objects.contrast`), and the shapes they judge parts by in
:mod:`~activecontour.objects.shapes`; this module runs them per object (:func:`split_touching`):

0. **Arcs grouped into ellipses** (:func:`_arc_clump`, the sub-pixel polygon, holes allowed):
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
   object pressed inside it, or a contact rounded away, left part of it unexplained).  A crowded
   clump (six to eight objects pressed together, or one hidden among them: more places where
   three parts meet than a star or a flower may have, its ellipses overlapping two by two,
   ``ARC_CROWD_MEET``, ``ARC_HIDDEN_SIZE``) is weighed against the stages below instead: its
   parts stand where each is an object's ellipse, or where more of the object's area is an
   object's ellipse in them than in the stages' parts (:func:`activecontour.objects.corners.
   _ellipse_area`), the model-based choice between two splits.
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
   one, or two separated by a dark seam, without any waist; and objects of one brightness
   pressed together, each brightest in its middle, at the valleys of the intensity between them
   that end in waists of the outline (:func:`activecontour.objects.contrast._seam_parts`).

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
distance compared with a radius of a few pixels is the squared transform against the least
integer that passes it (:func:`activecontour.objects.shapes._reaches`); the ellipse fits' sums
and residuals and the chord-inside test of the
cut search are compiled, and a search's fits share one stacked pass of the sums, one of the
residuals and one eigenproblem (:func:`_stacked_ellipse_fits`); how much of an ellipse lies
outside the object is one compiled clip of the outline by the ellipse's polygon
(:func:`_outside`), and the arc grouping judges all its new fits' shapes at once in closed form
(:func:`_clearly_not_arc_ellipses`), making an ellipse only of a fit that may pass, and tells
whether the ellipses explain the outline before it places the pixels in them; the necks' count
of h-maxima is one compiled grey reconstruction (:func:`_h_maxima_count`), the corner rays'
first crossings one compiled pass (:func:`_ray_hits`).

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
the same, on the segmentation of b127298     0.50 / 0.92        0.77 / 0.94      6 of 120
  on seeds 20-59                            0.65 / 0.95        0.68 / 0.94      4 of 240
crowded clumps weighed against the stages   0.67 / 0.94        0.78 / 0.95      6 of 120
below (``_arc_clump``, this module)
  on seeds 20-59                            0.68 / 0.96        0.68 / 0.95      4 of 240
  on seeds 60-79 (singles 60-159)           0.74 / 0.97        0.74 / 0.95      15 + 33 of 600
  (the split until now there: 0.74 / 0.96, 0.74 / 0.94, 15 + 29 of 600)
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
rays across a rounded contact must cut) and a star's arms.  With crowded clumps weighed (seeds
0-59), what is left at the worst seeds (ellipses 13, 27: 0.67, 0.68; disks 38, 0: 0.68, 0.78):
contacts that the converged contour rounded below ``ARC_CORNER_TURN`` or ``MIN_WAIST_DEPTH``,
where two deeply overlapping disks own one arc that one ellipse of aspect 1.5-2 fits (disks 38:
four such pairs, the arc stage deciding three objects for four, two for three), a ring of objects
around a gap whose cells hold a hole (ellipses 27), and clumps the border test
(``ARC_END_REACH``) or the size test declines.  More arcs (``ARC_CORNER_TURN`` 10 or 7 instead of
15) took the worst seeds down (ellipses 0.59, disks 0.56, the DSB image 0.790).
"""

from __future__ import annotations

import numpy as np

from activecontour import _kernels
from activecontour.geometry.curve import signed_area
from activecontour.objects.arcs import _arc_clump
from activecontour.objects.contrast import (
    CONTRAST_DEPTH,
    CONTRAST_FLOOR,
    _block_spread,
    _box,
    _contrast_parts,
    _may_split_by_contrast,
    _window,
)
from activecontour.objects.corners import (
    _around_a_hole,
    _as_ellipses,
    _bent,
    _corner_parts,
    _cut,
    _ellipse_area,
    _uncuttable,
)
from activecontour.objects.necks import NECK_RATIO, _boundary_distance, _may_have_necks, _neck_stage
from activecontour.objects.shapes import MIN_SPLIT_RADIUS, MIN_WAIST_DEPTH, _hull_depth

__all__ = ["split_touching"]


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
    one brightness, are unchanged, and so are skimage's coins (25 objects).  Each piece is then
    cut at its seams (:func:`activecontour.objects.contrast._seam_parts`): a clump of three
    nuclei of one brightness took the DSB image from 0.794 to 0.811.

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
    least = None  # the least contrast of a split by intensity, once an object asks for it
    if image is not None:
        # (a grey image in its own type: each object's box is read as float64, the whole image
        # only for the noise)
        image = np.asarray(image)
        image = image.astype(np.float64).mean(axis=2) if image.ndim == 3 else image
        # the least contrast of a split by intensity: a number of noise sigmas, and on a noise-free
        # image a fraction of its range (shading is not two objects); the noise is estimated
        # only for an object whose blocks differ by more than that fraction
        floor = CONTRAST_FLOOR * (float(image.max()) - float(image.min()))
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
        # (the outline's curvature, which the arc and corner stages share: neither reads it for an
        # outline under twice the smallest part, :func:`_uncuttable`; on grass 115 of 423)
        bent = _bent(curves[0]) if concave and not _uncuttable(signed_area(curves[0]), False) else None
        clump = _arc_clump(curves, depth, labels.shape, bent) if concave else None
        if clump is not None and not clump[1]:
            result.extend(clump[0])
            continue
        # a crowded clump of ellipses stands where more of its area is an object's ellipse than of
        # the stages' parts (:func:`activecontour.objects.corners._ellipse_area`), and without
        # them where all of it is (the stages' parts cannot explain more than the whole object)
        explained = None if clump is None else _ellipse_area(clump[0], curves[0])
        if explained is not None and explained == sum(signed_area(piece[0]) for piece in clump[0]):
            result.extend(clump[0])
            continue
        pieces = _staged_parts(curves, box, inside, depth, bent, concave, contrast, image, least, neck_ratio,
                               min_radius, labels.shape)
        if explained is not None and explained > _ellipse_area(pieces, curves[0]):
            pieces = clump[0]
        result.extend(pieces)
    return result


def _staged_parts(curves, box, inside, depth, bent, concave, contrast, image, least, neck_ratio, min_radius,
                  extent):
    """An object's parts by the necks, the contrast and the corners (stages 1 to 3 of the module
    docstring), each piece cut off then split by its own arcs (:func:`_clump_parts`): the object
    ``curves`` in the label image's ``box`` (``inside`` its pixels there), its outline's hull
    ``depth`` and curvature ``bent``, whether it is ``concave`` and may split by ``contrast``
    (with the ``image`` and its ``least`` contrast), as :func:`split_touching` found them."""
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
        return ellipses
    if concave:
        # (an object its necks did not cut: its hull depth and curvature are known)
        pieces = [cut for piece in pieces for cut in
                  ([piece] if len(piece) > 1 else [[part] for part in _corner_parts(
                      piece[0], *((depth, bent) if piece[0] is curves[0] else ()))])]
    if len(pieces) > 1:
        # a piece cut off may be a smaller clump, which its own arcs explain (a convex piece
        # has no concave corner: one convex hull)
        pieces = [part for piece in pieces for part in _clump_parts(piece, extent)]
    return pieces


def _clump_parts(curves, extent):
    """A piece that the necks, the contrast or the corners cut off an object, as the arc stage
    splits it (:func:`_arc_clump`; a crowded clump where more of its area is an object's ellipse
    than of the piece, :func:`activecontour.objects.corners._ellipse_area`); the piece alone
    when it does not, or when its outline lies within ``MIN_WAIST_DEPTH`` of its hull: a convex
    piece has no concave corner."""
    depth = _hull_depth(curves[0])
    clump = _arc_clump(curves, depth, extent) if depth.max() >= MIN_WAIST_DEPTH else None
    if clump is None or (clump[1] and _ellipse_area(clump[0], curves[0])
                         <= _ellipse_area([curves], curves[0])):
        return [curves]
    return clump[0]
