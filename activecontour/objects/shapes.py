"""The shapes the split judges its parts by (:mod:`activecontour.objects.split`).

A blob (solidity and aspect, :func:`_blob_shape`); the depth of an outline below its convex hull
(:func:`_hull_depth`: a waist); ellipses fitted to points, by the direct least-squares conic fit
of Fitzgibbon, Pilu and Fisher in the stable form of Halir and Flusser, with residuals as Sampson
distances in pixels (:func:`_stacked_ellipse_fits`: many point sets in one compiled pass), judged
against an object (:func:`_explained`, :func:`_arc_ellipse`: its residual, aspect and how much of
it lies outside, :func:`_outside`) or all at once in closed form (:func:`_clearly_not_arc_ellipses`);
where the distance transform reaches a radius of a few pixels (:func:`_reaches`).  Every stage uses them.
"""

from __future__ import annotations

import numpy as np

from activecontour import _kernels
from activecontour.geometry.curve import signed_area
from activecontour.geometry.hull import hull_area, hull_vertices

#: Parts whose largest inscribed radius is below this (pixels) are never split off: at that size a
#: neck is a pixel or two of the boundary's noise.
MIN_SPLIT_RADIUS = 3.0


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


def _reaches(mask, radius, strict=False):
    """Where the distance transform of a bool mask with a False pixel (``scipy.ndimage.
    distance_transform_edt``'s values: from each pixel to the nearest False one) is at least
    ``radius`` (above it, ``strict``): a bool array, at a cost of the pixels times ``radius``.

    The transform is the square root of an integer D, correctly rounded, so it grows with D: it
    passes ``radius`` exactly where D is at least the least integer whose square root does
    (:func:`activecontour._kernels.near_reaches`, which looks no farther than that)."""
    least = max(int(radius * radius) - 2, 0)
    while not (np.sqrt(least) > radius if strict else np.sqrt(least) >= radius):
        least += 1
    out = np.empty(mask.shape, dtype=np.uint8)
    _kernels.near_reaches(np.ascontiguousarray(mask, dtype=np.uint8), least, out)
    return out.view(bool)


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
#: A part is an ellipse when the rms Sampson distance of its vertices to the fitted ellipse is
#: within ``ELLIPSE_RMS[0]`` px plus ``ELLIPSE_RMS[1]`` times its equal-area radius (the contour's
#: noise, and the rounding of the corners the part was cut at) ...
ELLIPSE_RMS = (0.4, 0.03)
#: ... at most this fraction of the fitted ellipse lies outside the object (an overlap lies inside
#: the other part) ...
ELLIPSE_OUTSIDE = 0.05
#: ... and the part is at least this solid (area / convex hull area).
ELLIPSE_SOLIDITY = 0.9


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
#: An arc group's ellipse is an object's when its rms Sampson distance is within
#: ``ARC_RMS[0] + ARC_RMS[1]`` times its radius (pixels), its aspect at most ``MAX_PART_ASPECT``,
#: its radius at least ``MIN_SPLIT_RADIUS`` and at most this fraction of it lies outside the
#: object (the rounded contacts bulge it a little).
ARC_RMS, ARC_OUTSIDE = (0.5, 0.04), 0.10


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


#: The unit circle's vertices of :func:`_ellipse_polygon`: its cosines and sines, taken once.
_CIRCLE = (lambda angle: (np.cos(angle), np.sin(angle)))(np.linspace(0, 2 * np.pi, 48, endpoint=False))


def _ellipse_polygon(ellipse):
    """An ellipse (centre, semi-axes, axes as columns) as a polygon of 48 vertices (48, 2)."""
    centre, semi_axes, axes = ellipse
    cos, sin = _CIRCLE
    return np.ascontiguousarray(centre + np.column_stack([semi_axes[0] * cos, semi_axes[1] * sin]) @ axes.T)


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
