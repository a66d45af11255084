"""Initial curves: circles, rectangles, and turning any accepted ``init`` into a list of curves."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from activecontour.geometry.curve import as_curve, orient, signed_area
from activecontour.geometry.raster import mask_to_curves
from activecontour.imaging.strips import STRIP_ROWS, Kept, block_means, blurred_rows, strip

__all__ = ["Start", "circle", "default_init", "grid", "initial_curves", "rectangle", "threshold_mask",
           "threshold_split", "threshold_starts"]

#: Radius of the default initial circle, as a fraction of the image's smaller side (the same as
#: ``skimage.segmentation.morphological_chan_vese``'s default circle).
DEFAULT_RADIUS_FRACTION = 3.0 / 8.0


@dataclass
class Start:
    """Curves that lie on the objects' boundaries already, as an ``init``: like a result, they are
    taken as oriented and started with the small smoothing length of a start on the boundaries
    (a sequence's warm start, the object a ``roi="init"`` run continues from).

    Attributes
    ----------
    contours : list of ndarray (K, 2)
        Oriented as a result's (outer boundaries positive, holes negative).
    mask : bool ndarray (M, N)
        Their inside.
    seeds : int ndarray (M, N), optional
        The objects these curves were (a sequence's frame before: its ``labels``): objects that
        hold two of them are cut between them
        (:func:`activecontour.objects.measure.split_by_seeds`), so touching objects keep apart.
    """

    contours: list
    mask: np.ndarray
    seeds: np.ndarray | None = None


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


def grid(shape, spacing=GRID_SPACING, radius=GRID_RADIUS, *, values=None, mu=0.0):
    """Small circles on a square grid over the image: a start that assumes nothing about where.

    Circles on objects grow and merge (topology repair), so every object larger than the grid
    spacing is reached: the polygon analogue of the level set's checkerboard.  The functional
    (6.38) does not say which of two regions is the object, so given the image ``values``
    (M, N, C) only the circles on the object class are kept: the pixels are split in two classes
    by the global threshold split of :func:`threshold_split` (with the length weight ``mu``), and
    the background is the class that covers most of the image border.
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
    on_object = _object_class(values, mu=mu)[0][np.rint(rows).astype(int)[:, None], np.rint(cols).astype(int)]
    kept = [c for c, keep in zip(circles, on_object.ravel(), strict=True) if keep]
    return kept or circles


#: Bins of the threshold scan of :func:`threshold_split`: the threshold is exact to the range of
#: the projected values / ``SPLIT_BINS`` (6e-5 of an image's range).
SPLIT_BINS = 1 << 14
#: The scan reads every ``s``-th row (with its horizontal neighbour pairs and the pairs to the row
#: below) of an image with more pixels than this: ~1 Mpx is plenty for two means and a length.
_SPLIT_SAMPLE = 1 << 20


def threshold_split(smooth, values=None, mu=0.0, bins=SPLIT_BINS):
    """The global minimiser of (6.38) over the threshold sets of ``smooth``: an exact scan.

    For a threshold t along a direction a (the image itself for gray), the region is
    ``{smooth . a > t}``, its constants (6.42) are the class means of ``values``, and its length
    is measured by the Cauchy-Crofton count of the 4-neighbour pixel pairs the boundary separates
    (each counts pi / 4 px on average over directions).  The cost

        J(t) = mean_ch [ sum_{in} (I - c_in)^2 + sum_{out} (I - c_out)^2 ] + mu (pi / 4) B(t)

    is evaluated for every one of ``bins`` equal bins of the projected values at once, from
    per-bin counts and sums and a histogram of the pairs' lower and upper bins
    (a pair is separated by t when its lower value is below t and its upper one is not), so the
    minimiser is exact to the bin width, (max - min) / bins.  With ``mu = 0`` this is the global
    2-means split (Otsu's criterion): the length term is what keeps a small object (1 % of the
    pixels at SNR 2) from losing to a split of the background's noise in two halves, which
    2-means prefers once the noise variance times the background's area exceeds the object's
    contrast^2 times its area.

    A vector image is scanned along each of its principal axes and the lowest cost kept: the
    two classes of 2-means are separated by the hyperplane orthogonal to their mean difference,
    which is the principal axis whenever the between-class spread exceeds the within-class one
    along every other axis; the other axes cover a strong within-class spread (e.g. a shared
    brightness gradient).

    Parameters
    ----------
    smooth : ndarray (M, N, C), or rows made on demand (:mod:`activecontour.imaging.strips`)
        The values whose threshold sets are scanned (the image smoothed against pixel noise);
        only the sampled rows are read.
    values : ndarray (M, N, C), or rows made on demand, optional
        The intensities the fit terms read (the image itself); ``smooth`` when None.
    mu : float
        The length weight.
    bins : int

    Returns
    -------
    direction : ndarray (C,)
        Unit vector (1 for gray) along which ``smooth`` is thresholded.
    threshold : float
        The region is ``smooth @ direction >= threshold``; -inf when one class is best (no split).
    cost : float
        J at the threshold, in the units of the sampled pixels.
    """
    values = smooth if values is None else values
    m, n, channels = smooth.shape
    step = _scan_step(m, n)
    top, below = _sampled_rows(smooth, step)
    fit = values[::step].reshape(-1, channels)
    squares = float(np.einsum("ij,ij->", fit, fit))  # the same for every split
    if channels == 1:
        axes = np.ones((1, 1))
    else:
        flat = top.reshape(-1, channels)
        centred = flat[:: max(1, len(flat) // 20000)] - flat.mean(axis=0)
        axes = np.linalg.svd(centred, full_matrices=False)[2]
    best = (axes[0], -np.inf, np.inf)
    for axis in axes:
        # gray: the values themselves (the direction is 1), no product
        upper, lower = (top[:, :, 0], below[:, :, 0]) if channels == 1 else (top @ axis, below @ axis)
        low, high = float(upper.min()), float(upper.max())
        if not high > low:
            continue
        scale = bins / (high - low)

        def index(x, low=low, scale=scale):
            # clipped at both ends: the rows below the sampled ones can lie outside [low, high]
            # (truncated first, then clipped as integers: the same bins, one float temporary)
            shifted = x - low
            shifted *= scale
            where = shifted.astype(np.intp)
            return np.clip(where, 0, bins - 1, out=where)

        where = index(upper)
        count = np.bincount(where.ravel(), minlength=bins).astype(np.float64)
        sums = np.stack([np.bincount(where.ravel(), fit[:, ch], minlength=bins) for ch in range(channels)])
        # pairs separated by the threshold after bin k: lower bin <= k < upper bin.  The bin of
        # the larger value is the larger bin (the binning is monotone: rounding is), so a pair's
        # bins are those of its values, and the rows below are binned once
        separated = np.zeros(bins)
        pairs = [(where[:, 1:], where[:, :-1]), (where[: len(lower)], index(lower))]
        for a, b in pairs:
            a, b = np.maximum(a, b).ravel(), np.minimum(a, b).ravel()
            separated += np.bincount(b, minlength=bins) - np.bincount(a, minlength=bins)
        # the cost after bin k (no threshold after the last bin), where most bins are empty (a
        # small image) only at the bins where something changes: a bin without pixels or
        # separated pairs adds exact zeros to every running sum, so its cost equals the bin's
        # before it, which argmin (the first of equal minima) prefers; bin 0 holds the minimum.
        # The totals are summed over all bins, as the running sums' ends would be
        total_count, total_sums = count.sum(), sums.sum(axis=1)[:, None]
        changes = np.flatnonzero((count[:-1] != 0) | (separated[:-1] != 0))
        kept = slice(0, bins - 1) if 2 * len(changes) > bins else changes
        below_count = np.cumsum(count[kept])
        below_sums = np.cumsum(sums[:, kept], axis=1)
        above_count = total_count - below_count
        above_sums = total_sums - below_sums
        with np.errstate(divide="ignore", invalid="ignore"):
            fit_cost = (squares - np.sum(below_sums**2, axis=0) / below_count
                        - np.sum(above_sums**2, axis=0) / above_count) / channels
        cost = step * (fit_cost + mu * np.pi / 4.0 * np.cumsum(separated[kept]))
        cost[(below_count == 0) | (above_count == 0)] = np.inf
        i = int(np.argmin(cost))
        if cost[i] < best[2]:
            k = i if isinstance(kept, slice) else int(changes[i])
            best = (axis, low + (k + 1) / scale, float(cost[i]))
    return best


def _scan_step(m, n):
    """The scan of :func:`threshold_split` reads every this many-th row of an (m, n) image."""
    return max(1, int(np.ceil(m * n / _SPLIT_SAMPLE)))


def _scan_rows(m, step):
    """The rows the scan reads: every ``step``-th row and the rows below them, sorted."""
    return np.arange(m) if step == 1 else np.union1d(np.arange(0, m, step), np.arange(1, m, step))


def _sampled_rows(smooth, step):
    """The scan's rows of ``smooth``: every ``step``-th row, and the rows below them, as (top,
    below), fetched at once (a :class:`~activecontour.imaging.strips.Rows` makes each pair in one strip)."""
    rows = smooth[_scan_rows(smooth.shape[0], step)]
    return (rows, rows[1:]) if step == 1 else (rows[0::2], rows[1::2])


def _object_class(smooth, values=None, mu=0.0):
    """The object class of the threshold split of :func:`threshold_split`: a bool (M, N) mask and
    the contrast (:func:`_classes`)."""
    values = smooth if values is None else values
    direction, threshold = threshold_split(smooth, values, mu)[:2]
    return _classes(_threshold_set(smooth, direction, threshold)[0], values)


def _threshold_set(smooth, direction, threshold, step=None):
    """``smooth @ direction >= threshold``, a bool (M, N) (None when ``threshold`` is not finite),
    made a strip of rows at a time (a :class:`~activecontour.imaging.strips.Rows` is never made
    whole), and with ``step`` the sample ``smooth[::step, ::step]`` as (K, C) rows (else None)."""
    if not np.isfinite(threshold):
        return None, None
    m, n, channels = smooth.shape
    label = np.empty((m, n), dtype=bool)
    height = STRIP_ROWS if step is None else max(1, STRIP_ROWS // step) * step  # a multiple of step
    samples = []
    for top in range(0, m, height):
        rows = strip(smooth, top, min(m, top + height))
        # gray: one comparison per pixel, no float temporary
        np.greater_equal(rows[:, :, 0] if len(direction) == 1 else rows @ direction, threshold,
                         out=label[top:top + len(rows)])
        if step is not None:
            samples.append(rows[::step, ::step].copy())
    return label, (None if step is None else np.concatenate(samples).reshape(-1, channels))


def _classes(label, values):
    """The object class of a threshold set ``label`` (None: one class): a bool (M, N) mask and
    the contrast.

    The background is the class that covers most of the image border.  The contrast is the
    squared distance of the class means of ``values`` (the mean over channels, as the fit
    terms); 0 when there is one class.
    """
    if label is None:
        return np.zeros(values.shape[:2], dtype=bool), 0.0
    count = np.count_nonzero(label)
    if count in (0, label.size):
        return np.zeros(values.shape[:2], dtype=bool), 0.0
    # the class means from sums over the label, without copying either class's pixels
    inside = np.array([values[:, :, ch].sum(where=label) for ch in range(values.shape[2])])
    total = values.sum(axis=(0, 1))
    low, high = (total - inside) / (label.size - count), inside / count
    border = np.concatenate([label[0], label[-1], label[:, 0], label[:, -1]])
    contrast = float(np.mean((high - low) ** 2))
    return (~label if border.mean() > 0.5 else label), contrast


#: The default start's split must hold at twice the scale: when the share of the pixels above
#: the threshold differs by more than this fraction between the image and its 2 x 2 block means,
#: the split is a fine texture's, not the objects' (see :func:`_set_that_holds_at_twice_the_scale`).
SCALE_AGREEMENT = 0.25


def _set_that_holds_at_twice_the_scale(values, smooth, mu, blur=None, split=None):
    """The threshold set of the default start, a bool (M, N) (None for one class): the exact
    scan's, unless a coarser view disagrees.

    The scan (:func:`threshold_split`) on the image blurred by ``DEFAULT_INIT_BLUR`` px can
    prefer the peaks of a fine texture (a 6 px grating inside an object) to the object: their
    threshold set is a stripe configuration the flow cannot leave, at a higher final (6.38).  On
    the image reduced by 2 x 2 block means (blurred alike, ``mu / 2``: lengths halve) the grating
    is gone.  When the two scans select shares of the pixels that differ by more than
    ``SCALE_AGREEMENT``, the coarse split is kept: its share of the pixels, taken on the finer
    image (a quantile along the coarse split's direction), so corners stay sharp.  Objects, small
    ones too, are split alike at both scales.  ``smooth``: the blurred image (a
    :class:`~activecontour.imaging.strips.Rows`: the fine split's threshold set and the sample of
    the shares are made in one pass over its rows); ``split``: :func:`threshold_split` of
    ``smooth`` when the caller has it already (it is not scanned again).
    """
    direction, threshold, _ = threshold_split(smooth, values, mu) if split is None else split
    m, n = values.shape[:2]
    step = max(1, int(np.sqrt(m * n / _SPLIT_SAMPLE)))
    label, sample = _threshold_set(smooth, direction, threshold, step)
    if min(m, n) < 32 or label is None:
        return label
    half = block_means(values)
    # the rows of the coarse blur that its scan and its share read, made in one pass
    coarse_rows = np.union1d(_scan_rows(half.shape[0], _scan_step(*half.shape[:2])),
                             np.arange(0, half.shape[0], step))
    coarse_smooth = Kept(blurred_rows(half, DEFAULT_INIT_BLUR if blur is None else blur), coarse_rows)
    coarse_direction, coarse_threshold, _ = threshold_split(coarse_smooth, half, mu / 2)
    if not np.isfinite(coarse_threshold):
        return label
    fine_share = np.mean(sample @ direction >= threshold)
    coarse_share = np.mean(coarse_smooth[::step, ::step] @ coarse_direction >= coarse_threshold)
    if abs(fine_share - coarse_share) <= SCALE_AGREEMENT * max(fine_share, coarse_share):
        return label
    return _threshold_set(smooth, coarse_direction, float(np.quantile(sample @ coarse_direction,
                                                                      1.0 - coarse_share)))[0]


#: Width (pixels) of the Gaussian that takes the pixel noise off the image before the threshold of
#: the default start: enough to make its mask a few large pieces instead of noise, small enough
#: to keep a 3 px stroke.
DEFAULT_INIT_BLUR = 1.0
#: The default start drops pieces smaller than this many square pixels whatever mu is.
DEFAULT_INIT_MIN_AREA = 4.0


def speck_area(mu, contrast):
    """Area (px^2) below which a piece of a start is dropped: a disk of radius r pays ``2 pi r mu``
    of length for ``pi r^2 contrast`` of fit, so pieces under ``pi (2 mu / contrast)^2`` (and
    under ``DEFAULT_INIT_MIN_AREA``) would vanish at once.  ``contrast`` is ``(c_in - c_out)^2``."""
    return max(DEFAULT_INIT_MIN_AREA, np.pi * (2.0 * mu / contrast) ** 2)


def default_init(shape, values=None, mu=0.0):
    """The documented default start: the global minimiser of (6.38) over threshold sets, as curves.

    Without the length term, the global minimiser of (6.38) for fixed c_in, c_out is the
    threshold of I at (c_in + c_out) / 2, and the optimal constants are those of the global
    2-means split.  The default start is the threshold set of the image smoothed by a Gaussian
    of ``DEFAULT_INIT_BLUR`` px (so that pixel noise does not make it a speckle) that minimises
    (6.38) exactly among all thresholds, with the fit terms read on the image itself and the
    length counted on the pixel grid (:func:`threshold_split`, an exact scan, not Lloyd's local
    iteration); inside = the class that covers less of the image border (the objects, not the
    background).  The length term matters: without it, on a noisy image with one small object
    (below about ``0.6 sigma_blurred^2 / contrast^2`` of the pixels) the best split cuts the
    background's noise in two.  Pieces the length term would remove at once are dropped: a
    disk of radius r pays ``2 pi r mu`` of length for ``pi r^2 (c_in - c_out)^2`` of fit, so
    components and holes of area below ``pi (2 mu / (c_in - c_out)^2)^2`` (and below
    ``DEFAULT_INIT_MIN_AREA``) go.  The flow then starts at every object at once, wherever it
    is, instead of reaching for them from a circle.

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
    return threshold_starts(values, mu)[0] or fallback


def threshold_mask(values, mu=0.0, inside="auto", *, blurs=None):
    """The default start's object class, a bool (M, N) mask, and its contrast ``(c_in - c_out)^2``
    (the mean over channels; 0 for an image with one class): the threshold set of
    :func:`default_init` with every piece (:func:`threshold_starts` drops the specks).

    ``inside``: which class is the objects, as ``segment``'s: ``"auto"`` the one covering less
    of the border, ``"bright"``/``"dark"`` the one of the larger/smaller mean (over channels).
    ``blurs``: as :func:`threshold_starts`'.
    """
    blurs = (DEFAULT_INIT_BLUR,) if blurs is None else tuple(blurs)
    blur, smooth, split = blurs[0], blurred_rows(values, blurs[0]), None
    if len(blurs) > 1:
        split = threshold_split(smooth, values, mu)
        for other in blurs[1:]:
            candidate = blurred_rows(values, other)
            other_split = threshold_split(candidate, values, mu)
            if other_split[2] < split[2]:
                blur, smooth, split = other, candidate, other_split
    mask, contrast = _classes(_set_that_holds_at_twice_the_scale(values, smooth, mu, blur, split), values)
    if inside != "auto" and contrast > 0:
        brighter = np.mean(values[mask]) > np.mean(values[~mask])
        if brighter != (inside == "bright"):
            mask = ~mask
    return mask, contrast


def threshold_starts(values, mu=0.0, *, background=False, blurs=None):
    """The curves of the default start's object class, and with ``background`` of the other one.

    The threshold set of :func:`default_init` (and its complement), without the pieces the
    length term would remove at once; empty lists for an image with one class.  The polygon flow
    moves a user's curves first to whichever of these has a lower (6.38), if any.

    Parameters
    ----------
    values : ndarray (M, N, C)
    mu : float
    background : bool
    blurs : sequence of float, optional
        Gaussian widths (px) to smooth the image by before the scan: the one whose best threshold
        set has the lowest (6.38) (the scan's cost, :func:`threshold_split`) is taken.  A strong
        length weight prefers a wider blur, whose threshold sets have smoother, shorter outlines
        (on scikit-image's camera at ``mu = 0.25``: 2 px instead of 1, and the flow then ends
        2.5 % lower).  By default ``(DEFAULT_INIT_BLUR,)``.

    Returns
    -------
    list of (list of ndarray (K, 2))
        One or two curve lists.
    """
    inside, contrast = threshold_mask(values, mu, blurs=blurs)  # the smoothed image is freed here
    if contrast <= 0:
        return [[]] * (1 + background)
    speck = speck_area(mu, contrast)
    return [mask_to_curves(part, min_area=speck) for part in ((inside, ~inside) if background else (inside,))]


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
        ``[-0.5, M - 0.5] x [-0.5, N - 0.5]`` (their regions intersected with it: a curve around
        the whole image is the whole image); curves given by the user are oriented by nesting
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
            return grid(shape, values=values, mu=mu)
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
    curves = [part for i, c in enumerate(raw)
              for part in _clip(as_curve(c, name=f"init curve {i}"), shape, i)]
    return curves if from_result else region_boundary(curves)


def region_boundary(curves):
    """The boundary of the region a user's curves outline, oriented by nesting.

    A curve inside an even number of the others is an outer boundary (made positive), inside an
    odd number a hole (made negative), whatever orientation it was given in: a lone curve is an
    outline (``skimage.measure.find_contours`` walks them clockwise), and nested curves alternate
    (the one rule of nesting, :func:`activecontour.geometry.regions.orient_by_nesting`, which
    :func:`activecontour.chan_vese_energy` reads too).  Where curves overlap, repeat or cross
    themselves, the region is their union (a self-crossing curve's loops all count), rebuilt
    exactly by :func:`activecontour.geometry.topology.region_union`: winding-number weights of 2
    are not a region (6.38) is defined on.
    """
    from activecontour.geometry import topology
    from activecontour.geometry.regions import nesting, orient_by_nesting, polygons

    nested = nesting(polygons(curves))  # once, for the orientation and the check
    oriented = orient_by_nesting(curves, nested[0])
    if topology.region_problem(oriented, nested) is None:
        return oriented
    return topology.region_union(curves) or oriented


def _is_mask(init, shape):
    """A bool array, or an integer array of the image's shape with two values (0/1, 0/255)."""
    if not isinstance(init, np.ndarray):
        return False
    if init.dtype == bool:
        return True
    return (np.issubdtype(init.dtype, np.integer) and init.ndim == 2 and init.shape == tuple(shape)
            and np.unique(init).size <= 2)


def _clip(curve, shape, index):
    """The parts of a curve's region inside the image domain, as curves: [curve] when it is inside.

    A curve that leaves the domain is intersected with it exactly (shapely): clamping its
    vertices to the border would not be its region's part inside (a curve around the whole
    image clamps to the image's corners; a large rotated square loses its corners' pieces).
    """
    m, n = shape
    low, high = np.array([-0.5, -0.5]), np.array([m - 0.5, n - 0.5])
    if np.all(curve >= low) and np.all(curve <= high):
        return [curve]
    import shapely
    from shapely.geometry.polygon import orient as orient_polygon

    box = shapely.box(low[0], low[1], high[0], high[1])
    inside = shapely.make_valid(shapely.Polygon(curve)).intersection(box)
    parts = []
    for polygon in shapely.get_parts(inside):
        if isinstance(polygon, shapely.Polygon) and polygon.area > 1e-9:
            polygon = orient_polygon(polygon, sign=1.0 if signed_area(curve) > 0 else -1.0)
            parts.extend(np.clip(np.asarray(ring.coords)[:-1], low, high)
                         for ring in (polygon.exterior, *polygon.interiors))
    if not parts:
        half = np.ptp(curve, axis=0) / 2
        box_text = ", ".join(f"{curve[:, k].min() + half[k]:.4g} +- {half[k]:.4g}" for k in (0, 1))
        raise ValueError(f"init curve {index} lies outside the image (rows -0.5..{m - 0.5}, cols "
                         f"-0.5..{n - 0.5}): it spans (row, col) = ({box_text})")
    return parts
