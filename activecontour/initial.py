"""Initial curves: circles, rectangles, and turning any accepted ``init`` into a list of curves."""

from __future__ import annotations

import numpy as np

from activecontour.curve import as_curve, orient, signed_area
from activecontour.raster import mask_to_curves

__all__ = ["circle", "default_init", "grid", "initial_curves", "rectangle"]

#: Radius of the default initial circle, as a fraction of the image's smaller side (the same as
#: ``skimage.segmentation.morphological_chan_vese``'s default circle).
DEFAULT_RADIUS_FRACTION = 3.0 / 8.0


def circle(center, radius, n=None):
    """A positively oriented circle in (row, col).

    Parameters
    ----------
    center : (row, col)
    radius : float
        In pixels, > 0.
    n : int, optional
        Number of vertices; by default about one per pixel of arc length (at least 16).

    Returns
    -------
    ndarray (n, 2)
        Vertices at angles ``2 pi k / n``; the closing vertex is not repeated.
    """
    center = np.asarray(center, dtype=np.float64)
    if center.shape != (2,) or not np.all(np.isfinite(center)):
        raise ValueError(f"center must be a finite (row, col) pair, got {center!r}")
    if not np.isfinite(radius) or radius <= 0:
        raise ValueError(f"radius must be a positive number, got {radius!r}")
    if n is None:
        n = max(16, int(np.ceil(2 * np.pi * radius)))
    if int(n) < 3:
        raise ValueError(f"n must be at least 3, got {n}")
    angle = 2.0 * np.pi * np.arange(int(n)) / int(n)
    return center + radius * np.column_stack([np.cos(angle), np.sin(angle)])


def rectangle(start, end):
    """A positively oriented axis-aligned rectangle with opposite corners ``start``, ``end`` (row, col)."""
    (r0, c0), (r1, c1) = np.asarray(start, dtype=np.float64), np.asarray(end, dtype=np.float64)
    if r0 == r1 or c0 == c1:
        raise ValueError(f"rectangle from {tuple(start)} to {tuple(end)} has no area")
    corners = np.array([[r0, c0], [r1, c0], [r1, c1], [r0, c1]])
    return orient(corners)


#: Spacing and radius (pixels) of the circles of ``init="grid"``.
GRID_SPACING = 16.0
GRID_RADIUS = 5.0


def grid(shape, spacing=GRID_SPACING, radius=GRID_RADIUS, *, values=None):
    """Small circles on a square grid over the image: a start that assumes nothing about where.

    Circles on objects grow and merge (topology repair), so every object larger than the grid
    spacing is reached: the polygon analogue of the level set's checkerboard.  The functional
    (6.38) does not say which of two regions is the object, so given the image ``values``
    (M, N, C) only the circles on the object class are kept: the pixels are split in two classes
    by 2-means, and the background is the class that covers most of the image border.
    """
    if not (np.isfinite(spacing) and spacing > 0 and np.isfinite(radius) and 0 < radius < spacing / 2):
        raise ValueError(f"grid needs spacing > 2 radius > 0, got spacing={spacing}, radius={radius}")
    m, n = shape
    rows = np.arange(spacing / 2.0, m - 0.5, spacing) - 0.5
    cols = np.arange(spacing / 2.0, n - 0.5, spacing) - 0.5
    if rows.size == 0 or cols.size == 0:
        return [circle(((m - 1) / 2.0, (n - 1) / 2.0), min(radius, (min(m, n) - 1) / 2.0))]
    low, high = (-0.5, -0.5), (m - 0.5, n - 0.5)
    circles = [np.clip(circle((r, c), radius), low, high) for r in rows for c in cols]
    if values is None:
        return circles
    on_object = _object_class(values)[0][np.rint(rows).astype(int)[:, None], np.rint(cols).astype(int)]
    kept = [c for c, keep in zip(circles, on_object.ravel(), strict=True) if keep]
    return kept or circles


def _object_class(values, iterations=20, sample=1_000_000):
    """The object class of 2-means: a bool (M, N) mask and the squared distance of the means.

    The pixels are split in two classes by 2-means (Lloyd's iterations from the split along the
    principal axis, on at most ``sample`` pixels: the two means need no more); the background is
    the class that covers most of the image border.  The contrast is 0 when there is one class.
    """
    flat = values.reshape(-1, values.shape[2])
    fit = flat[:: max(1, len(flat) // sample)]
    centred = fit - fit.mean(axis=0)
    axis = np.linalg.svd(centred[:: max(1, len(fit) // 20000)], full_matrices=False)[2][0]
    label = centred @ axis > 0
    for _ in range(iterations):
        if label.all() or not label.any():
            return np.zeros(values.shape[:2], dtype=bool), 0.0
        low, high = fit[~label].mean(axis=0), fit[label].mean(axis=0)
        # the nearer mean: the threshold half-way between them along their difference
        new = fit @ (high - low) > 0.5 * (high + low) @ (high - low)
        if np.array_equal(new, label):
            break
        label = new
    if label.all() or not label.any():
        return np.zeros(values.shape[:2], dtype=bool), 0.0
    low, high = fit[~label].mean(axis=0), fit[label].mean(axis=0)
    direction = high - low
    threshold = 0.5 * (high + low) @ direction
    if len(direction) == 1:  # gray: one comparison per pixel, no float temporary
        plane = values[:, :, 0]
        label = plane > threshold / direction[0] if direction[0] > 0 else plane < threshold / direction[0]
    else:
        label = (flat @ direction > threshold).reshape(values.shape[:2])
    border = np.concatenate([label[0], label[-1], label[:, 0], label[:, -1]])
    # the fit terms are the channels' mean: so is the contrast
    contrast = float(np.mean((high - low) ** 2))
    return (~label if border.mean() > 0.5 else label), contrast


#: Width (pixels) of the Gaussian that takes the pixel noise off the image before the threshold of
#: the default start: enough to make its mask a few large pieces instead of noise, small enough
#: to keep a 3 px stroke.
DEFAULT_INIT_BLUR = 1.0
#: The default start drops pieces smaller than this many square pixels whatever mu is.
DEFAULT_INIT_MIN_AREA = 4.0


def default_init(shape, values=None, mu=0.0):
    """The documented default start: the objects of the length-free problem, as curves.

    Without the length term, the global minimiser of (6.38) for fixed c_in, c_out is the
    threshold of I at (c_in + c_out) / 2, and the optimal constants are those of 2-means: the
    default start is that threshold, taken on the image smoothed by a Gaussian of
    ``DEFAULT_INIT_BLUR`` px (so that pixel noise does not make it a speckle), with inside = the
    class that covers less of the image border (the objects, not the background).  Pieces the
    length term would remove at once are dropped: a disk of radius r pays ``2 pi r mu`` of length
    for ``pi r^2 (c_in - c_out)^2`` of fit, so components and holes of area below
    ``pi (2 mu / (c_in - c_out)^2)^2`` (and below ``DEFAULT_INIT_MIN_AREA``) go.  The flow then
    starts at every object at once, wherever it is, instead of reaching for them from a circle.

    Parameters
    ----------
    shape : tuple (M, N)
    values : ndarray (M, N, C), optional
        The normalised image.  Without it (or for an image with one class only), the start is a
        centred circle of radius 3/8 of the smaller side, as skimage's ``morphological_chan_vese``.
    mu : float
        The length weight the flow will use.
    """
    m, n = shape
    fallback = [circle(((m - 1) / 2.0, (n - 1) / 2.0), DEFAULT_RADIUS_FRACTION * min(m, n))]
    if values is None:
        return fallback
    import cv2  # not scipy.ndimage: it costs ~0.2 s to import on every cold start

    # scipy.ndimage.gaussian_filter(values, (b, b, 0)): the same sampled kernel (4 sigma), reflected
    planes = [cv2.GaussianBlur(np.ascontiguousarray(values[:, :, ch]), (0, 0), DEFAULT_INIT_BLUR,
                               borderType=cv2.BORDER_REFLECT) for ch in range(values.shape[2])]
    smooth = planes[0][:, :, np.newaxis] if len(planes) == 1 else np.stack(planes, axis=-1)
    inside, contrast = _object_class(smooth)
    del planes, smooth  # image-sized: free before tracing the mask's outlines
    if contrast <= 0:
        return fallback
    speck = max(DEFAULT_INIT_MIN_AREA, np.pi * (2.0 * mu / contrast) ** 2)
    curves = mask_to_curves(inside, min_area=speck)
    return curves if curves else fallback


def initial_curves(init, shape, values=None, mu=0.0):
    """Turn an ``init`` into a list of closed curves inside the image domain.

    Parameters
    ----------
    init : None, "grid", ndarray (K, 2), list of them, bool ndarray (M, N), or a SegmentationResult
        A curve, several curves (holes negatively oriented), a mask whose components and holes
        become curves, a previous result (its contours), e.g. from the other backend, or
        ``"grid"``: small circles all over the image (:func:`grid`).
    shape : tuple (M, N)
    values : ndarray (M, N, C), optional
        The normalised image, used by the default start (:func:`default_init`) and by ``"grid"``
        to keep only the circles on the object class.
    mu : float
        The length weight, for the default start.

    Returns
    -------
    list of ndarray (K, 2)

    Raises
    ------
    ValueError
        For a mask of the wrong shape or an empty one, a malformed curve, or a curve that lies
        outside the image.  Curves partly outside are clipped to the image domain
        ``[-0.5, M - 0.5] x [-0.5, N - 0.5]``; curves given by the user are oriented by nesting
        and overlaps are merged (:func:`region_boundary`).  An integer array of the image's shape
        with two values (0/1, 0/255) is a mask too.
    """
    if init is None:
        return default_init(shape, values, mu)
    from_result = hasattr(init, "contours") and hasattr(init, "mask")
    if from_result:  # a result's contours are already the oriented boundary of its region
        init = init.contours
    if _is_mask(init, shape):
        init = np.asarray(init) != 0
        if init.shape != tuple(shape):
            raise ValueError(
                f"init mask has shape {init.shape}, but the image has shape {tuple(shape)}"
            )
        # pieces under DEFAULT_INIT_MIN_AREA would be removed by the flow's first steps anyway,
        # at the price of a curve each (a speckle mask has thousands)
        curves = mask_to_curves(init, min_area=DEFAULT_INIT_MIN_AREA) or mask_to_curves(init)
        if not curves:
            raise ValueError("init mask is empty: it selects no pixel")
        return curves
    if isinstance(init, str):
        if init == "grid":
            return grid(shape, values=values)
        raise ValueError(
            f"init {init!r} is not understood: pass None, 'grid', a (K, 2) curve, a list of "
            "curves, a bool mask or a result"
        )
    arr = np.asarray(init, dtype=object) if isinstance(init, (list, tuple)) else None
    if arr is not None and (len(init) == 0 or np.ndim(init[0]) == 2):
        if len(init) == 0:
            raise ValueError("init is an empty list of curves")
        raw = list(init)
    else:
        raw = [init]
    curves = [_clip(as_curve(c, name=f"init curve {i}"), shape, i) for i, c in enumerate(raw)]
    return curves if from_result else region_boundary(curves)


def region_boundary(curves):
    """The boundary of the region a user's curves outline, oriented by nesting.

    A curve inside an even number of the others is an outer boundary (made positive), inside an
    odd number a hole (made negative), whatever orientation it was given in: a lone curve is an
    outline (``skimage.measure.find_contours`` walks them clockwise), and nested curves alternate.
    Where curves overlap or cross themselves, the region is the union, {w > 0}, rebuilt as its
    exact boundary (:func:`activecontour.topology.repair`): winding-number weights of 2 are not a
    region (6.38) is defined on.
    """
    from activecontour import topology
    from activecontour.energy import stack_curves

    oriented = []
    for i, curve in enumerate(curves):
        depth = sum(_contains(other, curve[0]) for j, other in enumerate(curves) if j != i)
        oriented.append(orient(curve, hole=depth % 2 == 1))
    repaired = topology.repair(*stack_curves(oriented))
    return oriented if repaired is None else repaired or oriented


def _contains(curve, point):
    """Whether ``point`` lies inside the closed ``curve`` (either orientation)."""
    low, high = curve.min(axis=0), curve.max(axis=0)
    if np.any(point < low) or np.any(point > high):
        return False
    from activecontour.topology import winding_number

    next_index = np.roll(np.arange(len(curve)), -1)
    return bool(winding_number(curve, next_index, point[None, :])[0] != 0)


def _is_mask(init, shape):
    """A bool array, or an integer array of the image's shape with two values (0/1, 0/255)."""
    if not isinstance(init, np.ndarray):
        return False
    if init.dtype == bool:
        return True
    return (np.issubdtype(init.dtype, np.integer) and init.ndim == 2 and init.shape == tuple(shape)
            and np.unique(init).size <= 2)


def _clip(curve, shape, index):
    m, n = shape
    low, high = np.array([-0.5, -0.5]), np.array([m - 0.5, n - 0.5])
    clipped = np.clip(curve, low, high)
    if abs(signed_area(clipped)) <= 1e-9 * max(1.0, abs(signed_area(curve))):
        raise ValueError(
            f"init curve {index} lies outside the image (rows -0.5..{m - 0.5}, "
            f"cols -0.5..{n - 0.5}); its bounding box is rows {curve[:, 0].min():.1f}.."
            f"{curve[:, 0].max():.1f}, cols {curve[:, 1].min():.1f}..{curve[:, 1].max():.1f}"
        )
    return clipped
