"""Objects and their measurements: the label image and the per-object table.

An *object* is a connected piece of a non-background region: one outer boundary with the holes
directly inside it (:func:`activecontour.geometry.regions.group_curves`).  :func:`find_objects` groups
the result's curves, keeps touching objects apart (:mod:`activecontour.objects.split`), gives each
an id 1..n in the label image (:func:`label_image`) and a row in the table (:func:`measure`).

Exact and pixel columns of :func:`measure` (names as ``skimage.measure.regionprops_table``):

====================================  ===========================================================
exact, from the sub-pixel polygon     ``area``, ``perimeter`` (outer boundary and holes),
(Green's theorem, holes subtracted)   ``centroid-0/1``, and from the second moments
                                      ``eccentricity``, ``orientation``, ``axis_major_length``,
                                      ``axis_minor_length``; ``area_convex`` and ``solidity``
                                      (convex hull of the polygon); ``equivalent_diameter_area``
from the pixels of the label image    ``label``, ``bbox-0..3``, ``num_pixels``,
                                      ``intensity_mean`` (input units; ``intensity_mean-k`` per
                                      channel of a colour image)
====================================  ===========================================================

The exact moments are those of the continuous region; ``regionprops`` sums point masses at pixel
centres, so its second moments differ by the 1/12 px^2 of a pixel square and by the rasterisation
(a few per cent on objects of a few pixels, below 1 % beyond a radius of ~10 px).
"""

from __future__ import annotations

import operator

import numpy as np

from activecontour import _kernels
from activecontour.geometry.curve import signed_area
from activecontour.geometry.hull import hull_area
from activecontour.geometry.raster import rasterize
from activecontour.geometry.regions import group_curves, top_left
from activecontour.objects.split import split_touching

__all__ = ["SEED_SHARE", "default_min_size", "find_objects", "group_curves", "label_image", "measure",
           "polygon_moments", "split_by_seeds"]


def default_min_size(mu, constants):
    """The least area (px^2) of an object by default: the area below which the length term of
    (6.38) removes a disk of one region's intensity from inside another's.

    A disk of radius r of region k inside region j pays ``2 pi r mu`` of length for
    ``pi r^2 (c_k - c_j)^2`` of fit (the pixels at c_k; the mean over channels), so below
    ``r = 2 mu / (c_k - c_j)^2`` removing it lowers (6.38): the rule by which the default start
    drops specks, :func:`activecontour.initial.speck_area`, with its floor of
    ``DEFAULT_INIT_MIN_AREA`` px^2.  With more than two regions the contrast is that of the two
    nearest constants (the weakest interface).  ``mu="auto"`` is ``MU_PER_NOISE_VARIANCE``
    times the noise variance (:func:`activecontour.imaging.noise.auto_mu`), so at a
    signal-to-noise ratio s = |c_k - c_j| / sigma the radius is ``2 MU_PER_NOISE_VARIANCE / s^2``:
    2.2 px at SNR 3, 5 px at SNR 2.

    Parameters
    ----------
    mu : float
        The length weight (normalised units, ``result.mu``).
    constants : ndarray (K, C)
        The regions' constants in the same units.
    """
    from activecontour.initial import DEFAULT_INIT_MIN_AREA, speck_area

    constants = np.asarray(constants, dtype=np.float64).reshape(len(constants), -1)
    first, second = np.triu_indices(len(constants), k=1)
    contrast = np.mean((constants[first] - constants[second]) ** 2, axis=1)
    contrast = float(contrast.min()) if contrast.size else 0.0
    return speck_area(mu, contrast) if contrast > 0 else DEFAULT_INIT_MIN_AREA


#: A seed (an object of the frame before, :func:`split_by_seeds`) claims a part of an object when at
#: least this fraction of its area lies inside the object: a neighbour that grew into its
#: contact by a few pixels does not.
SEED_SHARE = 0.5


def split_by_seeds(objects, labels, seeds, image=None):
    """Touching objects kept apart by the objects they were: the previous frame's objects seed
    the split of this frame's.

    An object that holds two or more seeds (ids of ``seeds`` with at least ``SEED_SHARE`` of
    their pixels inside it) is cut between them: its pixels (holes filled) go to the seeds by the
    watershed of their distance to the outline, from markers that are each seed's pixels inside
    it less a pixel along the borders between seeds (so that the cut follows the neck the two
    objects make now, where there is one, not the line of the frame before); the sub-pixel
    polygon is then cut along the parts' borders as :func:`split_touching` cuts it.  Objects that
    touch keep apart however deep the contact, and two objects that merged without a waist stay
    two while they overlap.  Every other object is split by :func:`split_touching` (an object
    entering the field against another, a dividing cell).

    Objects move between frames: the seeds must still overlap their objects by ``SEED_SHARE``,
    i.e. move by less than about a third of their radius a frame.

    Parameters
    ----------
    objects : list of list of ndarray
        Object k: outer boundary, then holes; id k + 1 in ``labels``.
    labels : int ndarray (M, N)
    seeds : int ndarray (M, N)
        The previous frame's objects (0: background), e.g. its ``result.labels``.
    image : ndarray, optional
        As :func:`split_touching` takes it.

    Returns
    -------
    list of list of ndarray
        The objects, cut ones replaced by their parts.
    """
    import scipy.ndimage
    import skimage.segmentation

    from activecontour.objects.corners import _cut

    boxes = scipy.ndimage.find_objects(labels, max_label=len(objects))
    seed_area = np.bincount(seeds.ravel())
    result, rest = [], []
    for k, (curves, box) in enumerate(zip(objects, boxes, strict=True)):
        if box is None:
            rest.append(k)
            continue
        framed = np.pad(labels[box] == k + 1, 1)  # holes filled (as scipy.ndimage.binary_fill_holes)
        _kernels.fill_holes(framed.view(np.uint8))
        window = framed[1:-1, 1:-1]
        held = seeds[box] * window
        counts = np.bincount(held.ravel(), minlength=seed_area.size)
        counts[0] = 0
        claiming = np.flatnonzero(counts >= SEED_SHARE * np.maximum(seed_area, 1))
        if len(claiming) < 2:
            rest.append(k)
            continue
        lookup = np.zeros(seed_area.size, dtype=np.int32)
        lookup[claiming] = np.arange(1, len(claiming) + 1)
        markers = lookup[held]
        inner = markers * (scipy.ndimage.minimum_filter(markers, size=3, mode="nearest") ==
                           scipy.ndimage.maximum_filter(markers, size=3, mode="nearest"))
        for part in range(1, len(claiming) + 1):  # a seed of one pixel's width keeps its pixels
            if not (inner == part).any():
                inner[markers == part] = part
        parts = skimage.segmentation.watershed(-scipy.ndimage.distance_transform_edt(framed),
                                               np.pad(inner, 1), mask=framed)
        result.extend(_cut(curves, parts, np.array([box[0].start - 1, box[1].start - 1])))
    if rest:
        lookup = np.zeros(len(objects) + 1, dtype=labels.dtype)
        lookup[np.array(rest) + 1] = np.arange(1, len(rest) + 1)
        result.extend(split_touching([objects[k] for k in rest], lookup[labels], image))
    return result


def find_objects(contours, shape, image=None, *, separate=True, min_size=0.0, seeds=None):
    """The objects of a result: their curves, the label image and the measurement table.

    Parameters
    ----------
    contours : list of ndarray (K, 2), or list of such lists
        The oriented boundary of the inside region (a result's ``contours``), or one such list per
        non-background class of an N-region partition: objects are the connected pieces of each
        class, so two touching pieces of different classes are two objects (the table's ``class``
        column, 1-based, says which).
    shape : tuple (M, N)
    image : ndarray (M, N) or (M, N, C), optional
        The input image in its own units, for ``intensity_mean``.
    separate : bool
        Split touching objects along their necks, and by contrast where the image is given
        (:func:`split_touching`); False keeps the connected pieces.
    min_size : float
        Objects (after the split) whose area (px^2, of the sub-pixel outline, holes subtracted)
        is below this are left out.
    seeds : int ndarray (M, N), optional
        The objects of the frame before (a sequence's): with ``separate``, objects that hold two
        of them are cut between them (:func:`split_by_seeds`).

    Returns
    -------
    objects : list of list of ndarray
        Object k (id k + 1): outer boundary, then holes.  Objects that cover no pixel centre (a
        sub-pixel speck) have no id and are left out.
    labels : int32 ndarray (M, N)
    table : dict of str to ndarray
        :func:`measure`, with a ``class`` column.
    """
    by_class = [contours] if not contours or isinstance(contours[0], np.ndarray) else list(contours)
    objects, classes, labels, drawn = [], [], None, None
    for k, curves in enumerate(by_class):
        found = group_curves(curves)
        if separate and found:
            drawn = label_image(found, shape)
            split = (split_touching(found, drawn, image) if seeds is None else
                     split_by_seeds(found, drawn, seeds, image))
            if len(by_class) == 1 and seeds is None and len(split) == len(found):
                # nothing was cut: these are the objects in reading order (group_curves), and
                # their label image is the one just drawn
                labels = drawn
            drawn = (found, drawn) if len(by_class) == 1 else None
            found = split
        if min_size > 0:
            kept = [curves for curves in found if sum(map(signed_area, curves)) >= min_size]
            if len(kept) < len(found):  # the label image drawn holds them: draw it again
                labels = None
            found = kept
        objects += found
        classes += [k + 1] * len(found)
    order = sorted(range(len(objects)), key=lambda i: top_left(objects[i]))
    objects, classes = [objects[i] for i in order], np.array([classes[i] for i in order], dtype=np.int32)
    if labels is None:
        labels = label_image(objects, shape) if drawn is None else _redrawn(*drawn, objects)
    table = measure(objects, labels, image)
    # the objects without a pixel are left out: each row of the table is its object's alone,
    # and the count of its pixels (read in its window) says whether it has one
    present = table["num_pixels"] > 0
    if not present.all():
        objects, classes = [o for o, keep in zip(objects, present, strict=True) if keep], classes[present]
        relabel = np.concatenate([[0], np.cumsum(present) * present]).astype(np.int32)
        labels = relabel[labels]
        table = {name: column[present] for name, column in table.items()}
        table["label"] = np.arange(1, len(objects) + 1, dtype=np.int32)
    table["class"] = classes
    return objects, labels, table


#: The denominators of :func:`polygon_moments`' edge sums.
_GREEN = np.array([2.0, 6.0, 6.0, 12.0, 12.0, 24.0])


def polygon_moments(curves):
    """Exact area, first and second moments of the region bounded by oriented polygons.

    By Green's theorem each edge (r_i, c_i) -> (r_j, c_j) with cross product
    ``w = r_i c_j - r_j c_i`` adds ``w / 2`` to the area, ``(r_i + r_j) w / 6`` to ``int r``,
    ``(r_i^2 + r_i r_j + r_j^2) w / 12`` to ``int r^2``, and ``(2 r_i c_i + r_i c_j + r_j c_i +
    2 r_j c_j) w / 24`` to ``int r c``; holes (negative orientation) subtract themselves.

    Returns
    -------
    area : float
    centroid : ndarray (2,)
        (row, col).
    central : ndarray (2, 2)
        Central second moments ``int (x - xbar)(x - xbar)^T dA`` over the region, x = (row, col).
    """
    origin = np.asarray(curves[0], dtype=np.float64).mean(axis=0)  # against cancellation
    sums = np.zeros(6)  # 1, r, c, rr, cc, rc
    for curve in curves:
        p = np.asarray(curve, dtype=np.float64) - origin
        q = np.roll(p, -1, axis=0)
        r0, c0, r1, c1 = p[:, 0], p[:, 1], q[:, 0], q[:, 1]
        w = r0 * c1 - r1 * c0
        # the six edge sums in one reduction (each row summed as np.sum sums it alone)
        sums += np.sum(np.stack([w, (r0 + r1) * w, (c0 + c1) * w, (r0 * r0 + r0 * r1 + r1 * r1) * w,
                                 (c0 * c0 + c0 * c1 + c1 * c1) * w,
                                 (2 * r0 * c0 + r0 * c1 + r1 * c0 + 2 * r1 * c1) * w]), axis=1) / _GREEN
    area = sums[0]
    mean = sums[1:3] / area
    central = np.array([[sums[3], sums[5]], [sums[5], sums[4]]]) - area * np.outer(mean, mean)
    return area, origin + mean, central


def label_image(objects, shape):
    """The int32 label image: pixel centres inside object k's curves get id k + 1, others 0.

    Each object is rasterised in its own bounding box (:func:`activecontour.geometry.raster.rasterize`),
    so the cost is the objects' area, not n times the image.
    """
    labels = np.zeros(shape, dtype=np.int32)
    for index, curves in enumerate(objects):
        _draw(labels, curves, index + 1)
    return labels


def _redrawn(before, drawn, objects):
    """:func:`label_image` of ``objects`` given that of ``before`` (``drawn``), when the objects
    are some of those before (the same curves), and parts of others: the objects kept keep their
    pixels under their new ids, and only the others are drawn.  The objects of one class are
    disjoint (no pixel centre lies inside two), so no object drawn covers another's pixels."""
    number = {id(curves[0]): k for k, curves in enumerate(before)}
    relabel = np.zeros(len(before) + 1, dtype=np.int32)
    new = []
    for index, curves in enumerate(objects):
        k = number.get(id(curves[0]), -1)
        if k >= 0 and len(curves) == len(before[k]) and all(map(operator.is_, curves, before[k])):
            relabel[k + 1] = index + 1
        else:
            new.append(index)
    labels = relabel[drawn]
    for index in new:
        _draw(labels, objects[index], index + 1)
    return labels


def _draw(labels, curves, number):
    """Give the pixel centres inside ``curves`` the id ``number`` in ``labels`` (in place),
    rasterising them in their bounding box."""
    low, high = _window(curves, labels.shape)
    if np.all(high > low):
        inside = rasterize([c - low for c in curves], tuple(high - low))
        labels[low[0]:high[0], low[1]:high[1]][inside] = number


def _window(curves, shape):
    """The pixel rows and columns ``[low, high)`` that can hold a centre inside ``curves``
    (their bounding box, clipped to ``shape``; empty when ``high <= low`` somewhere)."""
    low = np.floor(np.min([c.min(axis=0) for c in curves], axis=0)).astype(int)
    high = np.ceil(np.max([c.max(axis=0) for c in curves], axis=0)).astype(int) + 1
    return np.maximum(low, 0), np.minimum(high, shape)


def _pixel_columns(objects, labels, planes):
    """The pixel columns of the table: ``bbox-0..3`` (as ``scipy.ndimage.find_objects``, zeros for
    an object without pixels), ``num_pixels`` and each plane's sum over the object's pixels, read
    in each object's :func:`_window`, which holds all its pixels since :func:`label_image` draws
    them there: the cost is the objects' area, not the image's per column."""
    boxes = np.zeros((len(objects), 4), dtype=np.int64)
    counts = np.zeros(len(objects), dtype=np.int64)
    sums = np.zeros((len(objects), len(planes)))
    for k, curves in enumerate(objects):
        low, high = _window(curves, labels.shape)
        if np.any(high <= low):
            continue
        window = (slice(low[0], high[0]), slice(low[1], high[1]))
        mine = labels[window] == k + 1
        rows, cols = np.flatnonzero(mine.any(axis=1)), np.flatnonzero(mine.any(axis=0))
        if len(rows):
            boxes[k] = low[0] + rows[0], low[1] + cols[0], low[0] + rows[-1] + 1, low[1] + cols[-1] + 1
            counts[k] = np.count_nonzero(mine)
            sums[k] = [np.sum(plane[window], where=mine, dtype=np.float64) for plane in planes]
    return boxes, counts, sums


def measure(objects, labels, image=None):
    """Per-object measurements, a dict of 1-D arrays with ``regionprops_table``'s names.

    Parameters
    ----------
    objects : list of list of ndarray
        Object k (id k + 1 in ``labels``): its outer boundary first, then its holes.
    labels : int ndarray (M, N)
        From :func:`label_image`.
    image : ndarray (M, N) or (M, N, C), optional
        The input image, in its own units, for ``intensity_mean``.

    Returns
    -------
    dict of str to ndarray
        The columns listed in the module docstring; which are exact and which count pixels is
        said there.  The second-moment columns follow ``skimage.measure.regionprops``: with the
        inertia tensor ``T = [[m_cc, -m_rc], [-m_rc, m_rr]] / area`` and its eigenvalues
        ``l1 >= l2``, ``axis_major_length = 4 sqrt(l1)``, ``eccentricity = sqrt(1 - l2 / l1)``,
        ``orientation = atan2(-2 T_01, T_11 - T_00) / 2`` (the angle from the row axis to the
        major axis, in (-pi/2, pi/2]).
    """
    n = len(objects)
    ids = np.arange(1, n + 1)
    table = {"label": ids.astype(np.int32)}
    area, centroid, tensor, perimeter, convex = (np.zeros(n), np.zeros((n, 2)), np.zeros((n, 2, 2)),
                                                 np.zeros(n), np.zeros(n))
    for k, curves in enumerate(objects):
        area[k], centroid[k], central = polygon_moments(curves)
        # regionprops' inertia tensor: the moment about each axis is the other coordinate's
        tensor[k] = np.array([[central[1, 1], -central[0, 1]], [-central[0, 1], central[0, 0]]]) / area[k]
        perimeter[k] = sum(np.sum(np.hypot(*np.diff(np.vstack([c, c[:1]]), axis=0).T)) for c in curves)
        convex[k] = hull_area(curves[0] if len(curves) == 1 else  # (an outer boundary: positive)
                              np.vstack([c for c in curves if signed_area(c) > 0]))
    eigen = np.linalg.eigvalsh(tensor)[:, ::-1].clip(min=0)  # descending
    table["area"] = area
    table["perimeter"] = perimeter
    table["centroid-0"], table["centroid-1"] = centroid[:, 0], centroid[:, 1]
    image = None if image is None else np.asarray(image)
    planes = [] if image is None else [image] if image.ndim == 2 else list(np.moveaxis(image, 2, 0))
    bbox, num_pixels, sums = _pixel_columns(objects, labels, planes)
    for j in range(4):
        table[f"bbox-{j}"] = bbox[:, j]
    table["num_pixels"] = num_pixels
    with np.errstate(divide="ignore", invalid="ignore"):
        table["eccentricity"] = np.where(eigen[:, 0] > 0,
                                         np.sqrt(np.clip(1 - eigen[:, 1] / eigen[:, 0], 0, 1)), 0.0)
    a, b, c = tensor[:, 0, 0], tensor[:, 0, 1], tensor[:, 1, 1]
    table["orientation"] = np.where(a == c, np.where(b < 0, -np.pi / 4, np.pi / 4),
                                    0.5 * np.arctan2(-2 * b, c - a))
    table["axis_major_length"] = 4 * np.sqrt(eigen[:, 0])
    table["axis_minor_length"] = 4 * np.sqrt(eigen[:, 1])
    table["area_convex"] = convex
    table["solidity"] = area / np.maximum(convex, np.finfo(float).tiny)
    table["equivalent_diameter_area"] = np.sqrt(4 * area / np.pi)
    for ch in range(len(planes)):
        name = "intensity_mean" if image.ndim == 2 else f"intensity_mean-{ch}"
        with np.errstate(divide="ignore", invalid="ignore"):
            table[name] = sums[:, ch] / table["num_pixels"]
    return table
