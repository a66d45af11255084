"""The domain D of (6.38) restricted to a region of interest: a box, a mask, or around the init.

``segment(..., roi=...)`` solves the functional on the part of the image the user points at, so
that drawing around one object segments that object and nothing else:

* a box ``(r0, c0, r1, c1)`` (rows r0..r1-1, columns c0..c1-1, as a slice): exact; the image is
  cropped, the flow runs on the crop, and the contours are shifted back.  The crop keeps the
  whole image's normalised intensities (not stretched by its own range): (6.38) with the same
  ``mu``, ``omega`` and constants as on the whole image, only D smaller, so a result reports them
  in the units of a run on the whole image;
* a bool mask of the image's shape: the image is cropped to the mask's bounding box, and the
  pixels of the box outside the mask are given the median intensity of the mask's edge pixels
  (those inside the mask with a neighbour outside), so that they read as the background the user
  drew around; the result is then clipped to the mask, so no pixel outside it is inside.  This is
  an approximation of the restricted integral: exact when the background around the mask is
  uniform; otherwise the filled pixels pull ``c_out`` towards the edge's median;
* ``"init"``: the region of the given curves (or mask) dilated by ``ROI_INIT_MARGIN`` times its
  equivalent radius, at least ``ROI_INIT_MIN_MARGIN`` pixels (:func:`init_neighbourhood`), used
  as a mask as above.  Drawing a circle around one object and running gives that object: the
  neighbourhood holds the object and the background around it, not the neighbours.  When the
  result is empty or reaches the neighbourhood's edge (a curve drawn inside the object), the
  margin is doubled and the run repeated, up to the whole image.

The result is in the whole image's frame (mask, contours, labels); its ``roi`` attribute is the
domain used (a bool mask: pass it as ``roi`` to continue on the same domain) and its ``energy``
is (6.38) on the crop (with the filled pixels, for a mask).
"""

from __future__ import annotations

import numpy as np

__all__ = ["ROI_APART", "ROI_INIT_MARGIN", "ROI_INIT_MIN_MARGIN", "apart", "crop_init", "drawn_region",
           "init_neighbourhood", "pointed_label", "resolve_roi", "restrict_values"]

#: ``roi="init"``: the init's region grown by this fraction of its equivalent radius ...
ROI_INIT_MARGIN = 0.25
#: ... and by at least this many pixels.
ROI_INIT_MIN_MARGIN = 4.0
#: The pointed-at object's neighbours are taken out of its domain grown by this many pixels: the
#: blurred rim of an object (the default start's blur and an optics' point spread, a pixel or two)
#: is neither object nor background.
ROI_APART = 2.0


def resolve_roi(roi, shape):
    """The crop box and the domain mask inside it (None for a box) of a ``roi`` argument.

    Parameters
    ----------
    roi : bool ndarray (M, N) or (r0, c0, r1, c1)
        A mask or a box (of the kinds :class:`activecontour.settings.Settings` admits; ``"init"``
        is a mask by then, :func:`init_neighbourhood`).
    shape : tuple (M, N)

    Returns
    -------
    box : tuple (r0, c0, r1, c1) of int
    domain : bool ndarray (r1 - r0, c1 - c0) or None
    """
    m, n = shape
    array = np.asarray(roi)
    if array.dtype == bool:
        if array.shape != (m, n):
            raise ValueError(f"roi mask has shape {array.shape}, but the image has shape {(m, n)}")
        if not array.any():
            raise ValueError("roi mask is empty: it selects no pixel")
        rows, cols = np.flatnonzero(array.any(axis=1)), np.flatnonzero(array.any(axis=0))
        box = (int(rows[0]), int(cols[0]), int(rows[-1]) + 1, int(cols[-1]) + 1)
        domain = array[box[0]:box[2], box[1]:box[3]]
        return box, (None if domain.all() else domain)
    r0, c0, r1, c1 = (int(v) for v in np.clip(array, 0, [m, n, m, n]))
    if r1 - r0 < 2 or c1 - c0 < 2:
        raise ValueError(f"roi box {tuple(array.tolist())} leaves less than 2 x 2 pixels of the "
                         f"{m} x {n} image")
    return (r0, c0, r1, c1), None


def drawn_region(init, shape):
    """The bool (M, N) region the init encloses (pixel centres inside its curves or mask): what
    ``roi="init"`` points at."""
    from activecontour.geometry.raster import rasterize
    from activecontour.initial import initial_curves

    if init is None or isinstance(init, str):
        raise ValueError("roi='init' needs an init: curves, a mask or a result to draw around")
    region = rasterize(initial_curves(init, shape), shape)
    if not region.any():
        raise ValueError("roi='init': the init encloses no pixel centre")
    return region


def init_neighbourhood(region, margin=ROI_INIT_MARGIN):
    """The bool (M, N) mask of ``roi="init"``: ``region`` dilated by ``margin`` times its
    equivalent radius ``sqrt(area / pi)``, and by at least ``ROI_INIT_MIN_MARGIN`` pixels (the
    distance transform of the region's box grown by that width, not of the whole image)."""
    import scipy.ndimage

    width = max(ROI_INIT_MIN_MARGIN, margin * np.sqrt(np.count_nonzero(region) / np.pi))
    rows, cols = np.flatnonzero(region.any(axis=1)), np.flatnonzero(region.any(axis=0))
    pad = int(np.ceil(width)) + 1
    r0, c0 = max(rows[0] - pad, 0), max(cols[0] - pad, 0)
    r1, c1 = min(rows[-1] + pad + 1, region.shape[0]), min(cols[-1] + pad + 1, region.shape[1])
    neighbourhood = np.zeros_like(region)
    neighbourhood[r0:r1, c0:c1] = scipy.ndimage.distance_transform_edt(~region[r0:r1, c0:c1]) <= width
    return neighbourhood


def pointed_label(labels, drawn):
    """The id of the object holding most of the drawn region (the larger object on a tie), 0 when
    none holds any of it."""
    counts = np.bincount(labels[drawn], minlength=1)
    counts[0] = 0
    if not counts.any():
        return 0
    sizes = np.bincount(labels.ravel(), minlength=counts.size)[:counts.size]
    return int(np.lexsort((sizes, counts))[-1])


def apart(domain, others, keep):
    """The domain (bool) without the pixels ``others`` grown by ``ROI_APART`` pixels, but not into
    ``keep``; ``domain`` itself when ``others`` has none."""
    import scipy.ndimage

    if not others.any():
        return domain
    return domain & ~((scipy.ndimage.distance_transform_edt(~others) <= ROI_APART) & ~keep)


def restrict_values(values, box, domain):
    """The normalised values (M, N, C) on the crop, the pixels outside ``domain`` filled with the
    median of its edge pixels (see the module docstring)."""
    import scipy.ndimage

    r0, c0, r1, c1 = box
    crop = np.array(values[r0:r1, c0:c1])
    if domain is not None:
        edge = domain & ~scipy.ndimage.binary_erosion(domain, border_value=0)
        crop[~domain] = np.median(crop[edge], axis=0)
    return crop


def crop_init(init, box, shape):
    """The init in the crop's frame: curves shifted, a mask cropped, a result (or a
    :class:`~activecontour.initial.Start`) both, as a ``Start``; None and names as they are."""
    from activecontour.initial import Start, _is_mask

    r0, c0, r1, c1 = box
    if init is None or isinstance(init, str):
        return init
    offset = np.array([r0, c0], dtype=np.float64)
    if hasattr(init, "contours") and hasattr(init, "mask"):
        return Start([np.asarray(c, dtype=np.float64) - offset for c in init.contours],
                     np.asarray(init.mask)[r0:r1, c0:c1])
    if _is_mask(init, shape) and np.shape(init) == tuple(shape):
        return np.asarray(init)[r0:r1, c0:c1]
    if isinstance(init, (list, tuple)) and len(init) and np.ndim(init[0]) == 2:
        return [np.asarray(c, dtype=np.float64) - offset for c in init]
    return np.asarray(init, dtype=np.float64) - offset
