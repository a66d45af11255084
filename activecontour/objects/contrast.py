"""Stage 3 of the split (:mod:`activecontour.objects.split`): contrast.

A bright object touching a dim one, or two separated by a dark seam, without any waist: cores of
one intensity, far enough from the outline and from each other, and every pixel to its nearest
core (:func:`_contrast_parts`); a block-averaged look at an object's intensities first
(:func:`_block_spread`), so an object of one intensity pays almost nothing.  Objects of one
brightness pressed together, each brightest in its middle, are told apart by the seams between
them (:func:`_seam_parts`): valleys of the smoothed intensity that end in waists of the outline.
"""

from __future__ import annotations

import numpy as np

from activecontour import _kernels
from activecontour.objects.necks import _h_maxima_count
from activecontour.objects.shapes import MIN_WAIST_DEPTH, _concavity, _is_blob, _reaches

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
#: :func:`_seam_parts` smooths the intensity with a Gaussian of this sigma (pixels): a seam a pixel
#: or two wide between two nuclei survives it, and the noise of the smoothed values is the pixel
#: noise over ``2 sqrt(pi) SEAM_SCALE`` (a mean over the Gaussian's 4 pi SEAM_SCALE^2 pixels).
SEAM_SCALE = 2.0
#: A part with more maxima than this is a texture, not a clump of objects each brightest in its
#: middle (8 objects, the most of :data:`activecontour.synthetic.FAMILY_CLUMP`, two maxima each;
#: the textured class of retina with three regions has about a thousand): it is not cut at seams.
SEAM_MAX = 16


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
                and np.count_nonzero(_reaches(region, min_radius)) >= 2)


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

    result, count = np.zeros_like(parts), 0
    smallest = np.pi * min_radius ** 2
    # the seams are valleys where the objects are brighter than the window around them, ridges
    # where they are darker (:func:`_seam_parts` looks for the maxima of the objects' contrast)
    contrast = 1.0 if values[parts > 0].mean() >= values[parts == 0].mean() else -1.0
    # each part on its box, grown by the reach of the smoothing: the same numbers as on the
    # window (outside the part everything is zero), at a cost of the part's size, not the window's
    margin = int(4.0 * CONTRAST_SCALE + 0.5) + 1
    for j, box in enumerate(scipy.ndimage.find_objects(parts), start=1):
        if box is None:
            continue
        box = tuple(slice(max(b.start - margin, 0), b.stop + margin) for b in box)
        mask = parts[box] == j
        pieces = _contrast_split(mask, values[box], least, smallest)
        if pieces is not None and not _acceptable(pieces, min_radius):
            pieces = None
        if pieces is None:
            pieces = mask.astype(np.int32)
        # each piece of one brightness may still hold objects pressed together, seams between them
        for k in range(1, int(pieces.max()) + 1):
            piece = pieces == k
            seams = _seam_parts(piece, contrast * values[box], least, min_radius)
            if seams is None:
                count += 1
                result[box][piece] = count
            else:
                result[box][piece] = seams[piece] + count
                count += int(seams.max())
    return result


def _seam_parts(mask, values, least, min_radius):
    """The pieces of a part (a bool mask, the image under its box, negated for objects darker
    than their surroundings) separated by seams, or None.

    Nuclei of one brightness pressed together (DSB 2018: three nuclei in a clump, each brightest in
    its middle, the clump's outline dented only a pixel or a few where two meet) are neither split
    by Otsu's two classes (the seams are as bright as the rims) nor by their outline (no neck, no
    corner sharp enough).  What tells them apart is both together: a seam is a valley of the
    intensity between two maxima, and it ends in waists of the outline.  The intensity smoothed by
    ``SEAM_SCALE`` (normalised to the part) has its maxima of dynamic ``least / (2 sqrt(pi)
    SEAM_SCALE)`` at least -- the least contrast of a split for the smoothed field, whose noise
    is the pixel noise over ``2 sqrt(pi) SEAM_SCALE`` -- as cores (two to ``SEAM_MAX``), and the
    watershed of the smoothed intensity from them makes the pieces.  Pieces whose border reaches the outline
    nowhere, or at a place less than ``MIN_WAIST_DEPTH`` inside the convex hull of the part's
    pixels, merge (:func:`_merge_off_waists`), so the texture of one convex nucleus (its valleys
    end on convex stretches) and a bright spot inside it (its border is closed) are not cut.  The
    split stands when two pieces or more are left and each passes the tests of a split by
    contrast (:func:`_acceptable`).
    """
    import scipy.ndimage
    import skimage.morphology
    import skimage.segmentation

    smallest = np.pi * min_radius ** 2
    if np.count_nonzero(mask) <= 2 * smallest:
        return None
    weight = scipy.ndimage.gaussian_filter(mask.astype(float), SEAM_SCALE)
    smooth = (scipy.ndimage.gaussian_filter(np.where(mask, values, 0.0), SEAM_SCALE)
              / np.maximum(weight, 1e-12))
    smooth = np.where(mask, smooth, smooth[mask].min())
    depth = least / (2 * np.sqrt(np.pi) * SEAM_SCALE)
    # (the count of the cores first, one compiled pass: most parts have one, a texture hundreds)
    if not 2 <= _h_maxima_count(smooth, depth) <= SEAM_MAX:
        return None
    cores = scipy.ndimage.label(skimage.morphology.h_maxima(smooth, depth) & mask)[0]
    pieces = skimage.segmentation.watershed(-smooth, cores, mask=mask)
    pieces = _merge_off_waists(pieces, _concavity(mask, np.argwhere(mask).astype(np.float64)))
    if pieces.max() < 2 or not _acceptable(pieces, min_radius):
        return None
    return pieces


def _merge_off_waists(pieces, concavity):
    """The pieces (a label image, 1..n) merged until every border between two of them reaches the
    part's edge, and every place where a border does (8-connected pixels of the edge next to
    another piece) lies ``MIN_WAIST_DEPTH`` inside the convex hull (``concavity``:
    :func:`activecontour.objects.shapes._concavity`, -1 off the edge).  Each round merges at
    once the pieces that meet at a shallow place and those whose border is closed."""
    import scipy.ndimage
    import scipy.sparse
    import scipy.sparse.csgraph

    index = np.arange(pieces.size).reshape(pieces.shape)
    on_edge = concavity.ravel() >= 0
    while (count := int(pieces.max())) > 1:
        flat = pieces.ravel()
        a = np.concatenate([index[1:, :].ravel(), index[:, 1:].ravel()])
        b = np.concatenate([index[:-1, :].ravel(), index[:, :-1].ravel()])
        keep = (flat[a] != flat[b]) & (flat[a] > 0) & (flat[b] > 0)
        a, b = a[keep], b[keep]
        pair = np.minimum(flat[a], flat[b]) * (count + 1) + np.maximum(flat[a], flat[b])
        reaching = on_edge[a] | on_edge[b]
        closed = np.setdiff1d(pair, pair[reaching])
        ends = np.zeros(pieces.size, dtype=bool)
        ends[a[on_edge[a]]] = True
        ends[b[on_edge[b]]] = True
        places, n_places = scipy.ndimage.label(ends.reshape(pieces.shape), structure=np.ones((3, 3)))
        at = np.flatnonzero(ends)
        deepest = np.full(n_places + 1, -1.0)
        np.maximum.at(deepest, places.ravel()[at], concavity.ravel()[at])
        # each contact that reaches the edge, at its place: shallow ones join their two pieces
        place = places.ravel()[np.where(on_edge[a], a, b)][reaching]
        shallow = deepest[place] < MIN_WAIST_DEPTH
        if closed.size == 0 and not shallow.any():
            break
        # the merge graph: pieces 1..count, then the places, each joined to the pieces that meet
        # at it shallowly, and the pairs whose border is closed (each round joins two pieces)
        node = count + place[shallow]
        rows = np.concatenate([closed // (count + 1), flat[a[reaching][shallow]], flat[b[reaching][shallow]]])
        cols = np.concatenate([closed % (count + 1), node, node])
        graph = scipy.sparse.coo_matrix((np.ones(rows.size), (rows, cols)),
                                        shape=(count + n_places + 1,) * 2)
        component = scipy.sparse.csgraph.connected_components(graph, directed=False)[1][:count + 1]
        lookup = np.zeros(count + 1, dtype=pieces.dtype)
        lookup[1:] = np.unique(component[1:], return_inverse=True)[1] + 1
        pieces = lookup[pieces]
    return pieces


def _acceptable(pieces, min_radius):
    """The tests every split by contrast passes: every piece at least ``CONTRAST_SIZE_RATIO`` of
    the largest, with an inscribed radius of ``min_radius`` or more, and a blob (:func:`_is_blob`).
    (Every piece's size first, then every piece's inscribed radius, one compiled pass each: a
    blob's solidity and moments cost a convex hull image and skimage's moments; the tests are
    and-ed, so their order changes no answer.)"""
    import skimage.measure

    props = skimage.measure.regionprops(pieces)
    largest = max(p.area for p in props)
    return (all(p.area >= CONTRAST_SIZE_RATIO * largest for p in props)
            and all(_inscribed_radius_reaches(pieces, p.label, p.slice, min_radius) for p in props)
            and all(_is_blob(p) for p in props))


def _inscribed_radius_reaches(labels, label, box, radius):
    """Whether the largest distance from a pixel of ``labels == label`` (within ``box``) to one
    outside is at least ``radius``."""
    grown = tuple(slice(max(b.start - 1, 0), b.stop + 1) for b in box)
    return bool(_reaches(labels[grown] == label, radius).any())


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
    # (holes filled as scipy.ndimage.binary_fill_holes fills them, on the class framed by one pixel:
    # one compiled flood fill, :func:`activecontour._kernels.fill_holes`)
    framed = np.pad((smooth > threshold) & mask, 1)
    _kernels.fill_holes(framed.view(np.uint8))
    bright = _without_small(framed[1:-1, 1:-1], smallest) & mask
    # (no bright core: every pixel is far from one)
    away = _reaches(mask, CONTRAST_RIM, strict=True) & (
        _reaches(~bright, CONTRAST_RIM, strict=True) if bright.any() else True)
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
