"""N regions on the pixel grid: a label field, started from the global K-means and descended exactly.

The functional is the N-region form of (6.38) (:meth:`ChanVeseParameters.class_forms`,
:func:`activecontour.energy.evaluate_partition`):

    J = mu L + sum_k int_{Omega_k} g_k,   g_k = lambda_k mean_ch (I - c_k)^2 (+ omega, k >= 1),

with L the length of the interfaces, each counted once, and of the image border where a region
other than the background lies on it.

Why a label field
-----------------
A label per pixel partitions the image by construction: no vacuum, no overlap, junctions wherever
three regions meet, topology free, and the cost of a sweep grows with K, not with the pairs of
regions (Vese-Chan's log2 K level sets couple every region through products of Heavisides; K level
sets need a projection back onto the partition after every step).  The label image stands for a
sub-pixel partition (:mod:`activecontour.geometry.partition`: boundaries through the midpoints between
pixels of different regions, junctions at cell centres) whose length is a sum over grid cells, so
the exact change of L when one pixel changes region is local: the four cells around it.

The scheme
----------
1. Start: the global K-means of the intensities of the image smoothed by a Gaussian of 1 px
   (:func:`initial_classes`, exact by dynamic programming on the histogram): a partition that
   finds every class anywhere in the image, whatever its size.
2. Alternate, until no pixel changes (or they move less than ``tol`` px per sweep):
   the constants c_k (6.42), the region means; then one sweep of iterated conditional modes
   (Besag 1986): every pixel takes the region of least ``g_k(pixel) + mu (length in the four
   cells around it)`` (+ mu per image side for a border pixel outside the background), four
   interleaved phases of pixels that share no cell, so each phase is exact coordinate descent
   on J with the fit term as a pixel sum.  Both half-steps lower that J.

Threshold dynamics (Esedoglu and Otto 2015), the obvious faster-moving alternative, was measured
and dropped: its heat-content length is exact for straight interfaces but charges a one-pixel
speck sqrt(2 pi)/sigma (1 - 1/(2 pi sigma^2)) ~ 1.6 px of length at sigma = 1.5 px instead of its
2.8, so on noisy images it keeps specks that (6.38) removes (three nested classes at SNR 3: J 419.5
against 413.8 for this scheme, the ground truth's 413.9).

The energy of every iterate, the result's ``energy`` and ``energies`` are the common evaluator's
(exact bilinear integrals over the partition), which is also what
``chan_vese_energy(image, classes=result.classes)`` returns.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from activecontour.energy import PartitionEvaluation, evaluate_partition
from activecontour.geometry.partition import Boundary, chain, class_boundary, class_soup
from activecontour.models.kmeans import histogram_kmeans
from activecontour.result import FlowState, SegmentationResult

__all__ = ["LabelDescent", "descend_labels", "initial_classes", "segment_labels"]

_INIT_SMOOTHING = 1.0  # Gaussian sigma (px) of the image the K-means start classifies
_BINS = 256


def initial_classes(values, n_classes):
    """The global K-means of the lightly smoothed intensities (:func:`histogram_kmeans`), as labels.

    Colour images are classified by their mean channel.  Labels are in increasing intensity.
    """
    import cv2

    gray = values.mean(axis=2).astype(np.float32)
    smooth = cv2.GaussianBlur(gray, (0, 0), _INIT_SMOOTHING, borderType=cv2.BORDER_REPLICATE)
    thresholds, _ = histogram_kmeans(smooth, n_classes, bins=_BINS)
    return np.digitize(smooth, thresholds, right=True).astype(np.int32)


def order_classes(classes, values, n_classes):
    """Relabel: 0 = the region covering most of the image border (the background), the others by
    increasing mean intensity (of the mean channel).  Returns the new labels.

    The border is measured as the functional does (every border pixel side; a corner pixel has
    two), so that with equal weights the choice never raises J: the length term counts the border
    outside the background."""
    border = np.concatenate([classes[0], classes[-1], classes[:, 0], classes[:, -1]])
    background = int(np.argmax(np.bincount(border, minlength=n_classes)))
    gray = values.mean(axis=2)
    count = np.bincount(classes.ravel(), minlength=n_classes)
    mean = np.bincount(classes.ravel(), weights=gray.ravel(), minlength=n_classes) / np.maximum(count, 1)
    others = [k for k in np.argsort(mean, kind="stable") if k != background]
    mapping = np.empty(n_classes, dtype=np.int32)
    mapping[[background] + others] = np.arange(n_classes)
    return mapping[classes]


def _pixel_constants(classes, values, n_classes, params):
    """The model's constants (6.42) of every region from its pixel sums (the image mean for an
    empty region)."""
    flat = classes.ravel()
    count = np.bincount(flat, minlength=n_classes).astype(np.float64)
    first = np.empty((n_classes, values.shape[2]))
    second = np.empty((n_classes, values.shape[2]))
    for ch in range(values.shape[2]):
        channel = values[..., ch].ravel()
        first[:, ch] = np.bincount(flat, weights=channel, minlength=n_classes)
        second[:, ch] = np.bincount(flat, weights=channel * channel, minlength=n_classes)
    whole = params.region_constant(float(flat.size), first.sum(axis=0), second.sum(axis=0))
    return np.array([params.region_constant(a, f, q) if a > 0 else whole
                     for a, f, q in zip(count, first, second, strict=True)])


def segment_labels(model, init, params, *, n_regions, max_num_iter, tol, callback):
    """Minimise the N-region functional on a label field (module docstring).

    Parameters
    ----------
    model : ImageModel
    init : None, int ndarray (M, N), or SegmentationResult
        None: the global K-means of the lightly smoothed image (:func:`initial_classes`).  A label
        image with values in 0..n_regions-1, or a result with ``classes``.
    params : ChanVeseParameters
    n_regions : int
    max_num_iter : int
        Sweeps over the image.
    tol : float
        Pixels: the run has converged when the regions move less than this per sweep (changed
        pixels over the interface length); a discrete field reaches that when no pixel changes.
    callback : callable or None
        Called with a :class:`~activecontour.result.FlowState` after every sweep (its ``mask``
        is the inside, every region but the background); return True to stop.

    Returns
    -------
    SegmentationResult
        With ``classes`` (0 = background, the others by mean intensity) and ``constants``.
    """
    descent = descend_labels(model, init, params, n_regions=n_regions, max_num_iter=max_num_iter,
                             tol=tol, callback=callback)
    return _result(descent, n_regions)


class LabelDescent(NamedTuple):
    """What :func:`descend_labels` finds: the labels (named by :func:`order_classes`), their
    partition's boundary and its evaluation, the energies (ending with that evaluation's), the
    sweeps and the status."""

    classes: np.ndarray
    boundary: Boundary
    final: PartitionEvaluation
    energies: list
    n_iter: int
    status: int


def descend_labels(model, init, params, *, n_regions, max_num_iter, tol, callback):
    """:func:`segment_labels` without the result: no contours, for a caller that needs only the
    labels (the network of :mod:`activecontour.backends.network` starts from them).  The same
    parameters; returns a :class:`LabelDescent`."""
    image = model.image
    shape = tuple(model.shape)
    classes = order_classes(_initial(init, image, n_regions, shape), image, n_regions)
    run = _Descent(model, params, n_regions, max_num_iter, tol, callback)
    classes, status = run.descend(classes)
    # Local moves cannot bring back a region the descent emptied (its start sat on edges), nor
    # free one that duplicates another's level, nor find a small region that K-means missed (it
    # halves large noisy regions instead).  So at convergence: free a label (an empty region, or
    # the cheapest merge of two regions by Ward's cost), give it to the pixels that stand out
    # most significantly in some region (:func:`_split`), descend, and keep the result if J is
    # lower; most significant split first, until none lowers J.  A start from a previous result
    # (a smooth fit's next round, a sequence's next frame) keeps its regions: no reseeding.
    for _ in range(0 if hasattr(init, "classes") else 2 * n_regions):
        if status not in (0, 4):
            break
        trial = _reseed(classes, image, n_regions, run, model, params)
        if trial is None:
            break
        classes, status = trial
    classes = order_classes(classes, image, n_regions)
    boundary = class_boundary(classes)
    final = evaluate_partition(model, boundary, params, n_regions)
    energies = list(run.energies)
    if not np.isclose(energies[-1], final.energy, rtol=1e-9, atol=0.0):
        energies.append(final.energy)
    energies[-1] = final.energy
    return LabelDescent(classes, boundary, final, energies, run.n_iter, status)


def _reseed(classes, image, n_regions, run, model, params, tries=3):
    """One merge-and-split move (see :func:`segment_labels`): (labels, status) or None.

    A candidate is descended only if it can pay: the most its pixels' fit can gain (their squared
    distance to their region's mean) must exceed the merge's cost (Ward's, 0 for an empty
    region).  Well separated regions then cost no trial at all.
    """
    gray = image.mean(axis=2)
    weight = float(np.mean(params.weights(image.shape[2])[0])) * image.shape[2]
    count = np.bincount(classes.ravel(), minlength=n_regions)
    empty = np.flatnonzero(count == 0)
    if empty.size:
        base, label, merge_cost = classes, int(empty[0]), 0.0
    else:
        mean = np.bincount(classes.ravel(), weights=gray.ravel(), minlength=n_regions) / count
        pairs = [(count[a] * count[b] / (count[a] + count[b]) * (mean[a] - mean[b]) ** 2, a, b)
                 for a in range(n_regions) for b in range(a + 1, n_regions)]
        merge_cost, keep, label = min(pairs)
        merge_cost *= weight
        base = np.where(classes == label, keep, classes).astype(classes.dtype)
    splits = [_split(base, image, region, label)
              for region in np.flatnonzero(np.bincount(base.ravel(), minlength=n_regions) > 1)]
    splits = sorted((split for split in splits if split is not None), key=lambda split: -split[0])
    for _, start in splits[:tries]:
        moved = start == label
        region = base[moved][0]
        if weight * np.sum((gray[moved] - gray[base == region].mean()) ** 2) <= merge_cost:
            continue
        trial, status = run.descend(start, record=False)
        energy = evaluate_partition(model, class_boundary(trial), params, n_regions).energy
        if energy < run.energies[-1] * (1.0 - 1e-9):
            run.energies.append(energy)
            return trial, status
    return None


class _Descent:
    """Alternating constants (6.42) and sweeps (:func:`_sweep`) until no pixel changes."""

    def __init__(self, model, params, n_regions, max_num_iter, tol, callback):
        self.model, self.params, self.n_regions = model, params, n_regions
        self.max_num_iter, self.tol, self.callback = max_num_iter, tol, callback
        shape = tuple(model.shape)
        self.wall = np.zeros(shape, dtype=np.float32)
        if params.mu > 0:  # a region other than the background pays for the image border it covers
            for edge in (self.wall[0], self.wall[-1], self.wall[:, 0], self.wall[:, -1]):
                edge += np.float32(params.mu)
        self.energies, self.n_iter = [], 0

    def descend(self, classes, record=True):
        """Returns the labels and the status (0 converged, 1 out of iterations, 2 callback, 4 the
        next sweep would raise J)."""
        model, params, n_regions = self.model, self.params, self.n_regions
        values = model.values
        if record:
            self.energies.append(evaluate_partition(model, class_boundary(classes), params, n_regions).energy)
        while self.n_iter < self.max_num_iter:
            cost = np.empty((n_regions,) + tuple(model.shape), dtype=np.float32)
            constants = _pixel_constants(classes, values, n_regions, params)
            for k, form in enumerate(params.class_forms(constants)):
                cost[k] = form.density(values)
                if k > 0:
                    cost[k] += self.wall
            new, changed = _sweep(classes, cost, params.mu)
            if changed == 0:
                return classes, 0
            # named as the result will be: the partition's saddle cells depend on the names
            new = order_classes(new, values, n_regions)
            if record:
                # the sweep descends on the fit term as a pixel sum; J integrates the bilinear
                # image over the sub-pixel partition: a sweep that raises J is not taken
                current = evaluate_partition(model, class_boundary(new), params, n_regions)
                if current.energy > self.energies[-1] + 1e-12 * abs(self.energies[-1]):
                    return classes, 4
                self.energies.append(current.energy)
            classes = new
            self.n_iter += 1
            if record:
                if self.callback is not None and self.callback(FlowState(
                        self.n_iter, [], current.energy, None, None, tuple(model.shape), self.max_num_iter,
                        phi=np.where(classes > 0, 1.0, -1.0))):
                    return classes, 2
                if changed <= self.tol * max(current.length, 1.0):
                    return classes, 0
        return classes, 1


def _split(classes, values, region, label):
    """Give ``label`` to the pixels of ``region`` that stand out from it: (weight, labels) with
    the sum of their squared deviations, or None.

    The intensities are smoothed within the region (normalised convolution: no neighbouring
    region's edge leaks in); a pixel stands out when it lies more than 3 robust standard deviations
    (1.4826 MAD) from the region's median, on the side (above or below) whose deviations weigh
    more.  Not a 2-means split: on a large noisy region 2-means halves the noise, whatever small
    structure the region hides.
    """
    import cv2

    member = classes == region
    weight = member.astype(np.float32)
    gray = values.mean(axis=2).astype(np.float32) * weight
    blur = {"ksize": (0, 0), "sigmaX": _INIT_SMOOTHING, "borderType": cv2.BORDER_REPLICATE}
    smooth = cv2.GaussianBlur(gray, **blur) / np.maximum(cv2.GaussianBlur(weight, **blur), 1e-6)
    inside = smooth[member]
    centre = np.median(inside)
    spread = 1.4826 * np.median(np.abs(inside - centre))
    deviation = smooth - centre
    upper = member & (deviation > 3.0 * spread) & (deviation > 0)
    lower = member & (deviation < -3.0 * spread) & (deviation < 0)
    weight = max(np.sum(deviation[upper] ** 2), np.sum(deviation[lower] ** 2))
    side = upper if np.sum(deviation[upper] ** 2) >= np.sum(deviation[lower] ** 2) else lower
    if not side.any():
        return None
    out = classes.copy()
    out[side] = label
    return weight, out


def _initial(init, values, n_regions, shape):
    if init is None:
        return initial_classes(values, n_regions)
    classes = getattr(init, "classes", init)
    classes = np.asarray(classes)
    if classes.shape != shape or not np.issubdtype(classes.dtype, np.integer):
        raise ValueError(f"init for n_regions={n_regions} must be None, a label image of shape {shape} "
                         f"or a result with classes, got {type(init).__name__}")
    if classes.min() < 0 or classes.max() >= n_regions:
        raise ValueError(f"init labels must lie in 0..{n_regions - 1}")
    return classes.astype(np.int32)


def _result(descent, n_regions):
    classes, boundary, final = descent.classes, descent.boundary, descent.final
    # the inside: every region but the background; its boundary, positively oriented
    foreground = (boundary.inner > 0) & (boundary.outer <= 0)
    background = (boundary.inner == 0) & (boundary.outer > 0)
    contours = chain(np.vstack([boundary.start[foreground], boundary.end[background]]),
                     np.vstack([boundary.end[foreground], boundary.start[background]]))
    mask = classes > 0
    areas = final.areas
    inside = areas[1:].sum()
    c_in = (areas[1:, None] * final.constants[1:]).sum(axis=0) / inside if inside > 0 else final.constants[0]
    class_contours = [chain(*class_soup(boundary, k)) for k in range(n_regions)]
    return SegmentationResult(mask=mask, contours=contours, c_in=c_in, c_out=final.constants[0],
                              energy=final.energy, energies=descent.energies, n_iter=descent.n_iter,
                              status=3 if not mask.any() else descent.status, backend="levelset",
                              classes=classes, constants=final.constants,
                              class_contours=class_contours)


_HALF = np.sqrt(0.5)


def _cell_length(tl, tr, br, bl):
    """Boundary length inside grid cells with these corner classes, by the rule of
    :mod:`activecontour.geometry.partition`: a straight cut 1, a corner cut sqrt(1/2), a saddle two corner
    cuts, a junction 1/2 per cell edge whose ends differ."""
    top, right, bottom, left = tl != tr, tr != br, bl != br, tl != bl
    count = top.astype(np.int8) + right + bottom + left
    straight = (top & bottom) | (left & right)
    length = np.where(count == 2, np.where(straight, 1.0, _HALF), 0.5 * count)
    saddle = (count == 4) & (tl == br) & (tr == bl)
    return np.where(saddle, 2.0 * _HALF, length)


def _sweep(classes, cost, mu):
    """One sweep of iterated conditional modes on the exact boundary length of the partition.

    Pixels two apart in both directions share no cell, so each of the four phases moves all its
    pixels at once, each to the region of least ``cost_k + mu * (length in the four cells around
    it)``: with the fit term as a pixel sum this is exact coordinate descent on J.  Only pixels
    that can change are visited: those on a boundary and those whose data prefer another region
    (an interior pixel of its data's region would only add length).  Returns the new labels and
    the number of pixels that changed.
    """
    m, n = classes.shape
    classes = classes.copy()
    # an interior pixel pays at least 4 corner cuts (half of them at the image border) to change
    own = np.take_along_axis(cost, classes[None].astype(np.intp), axis=0)[0]
    prefers_other = own - cost.min(axis=0) > np.float32(2.0 * _HALF * mu)
    changed = 0
    for pi in range(2):
        for pj in range(2):
            padded = np.pad(classes, 1, mode="edge")
            centre = padded[1:-1, 1:-1]
            boundary = np.zeros((m, n), dtype=bool)
            for di in (-1, 0, 1):
                for dj in (-1, 0, 1):
                    if di or dj:
                        boundary |= padded[1 + di: 1 + di + m, 1 + dj: 1 + dj + n] != centre
            active = boundary | prefers_other
            mask = np.zeros((m, n), dtype=bool)
            mask[pi::2, pj::2] = True
            rows, cols = np.nonzero(active & mask)
            if rows.size == 0:
                continue
            nb = {(di, dj): padded[rows + 1 + di, cols + 1 + dj] for di in (-1, 0, 1) for dj in (-1, 0, 1)}
            margin = [((rows == 0) | (cols == 0)), ((rows == 0) | (cols == n - 1)),
                      ((rows == m - 1) | (cols == 0)), ((rows == m - 1) | (cols == n - 1))]
            factor = [np.where(edge, 0.5, 1.0) for edge in margin]
            best = choice = None
            for k in range(cost.shape[0]):
                length = (factor[0] * _cell_length(nb[-1, -1], nb[-1, 0], k, nb[0, -1])
                          + factor[1] * _cell_length(nb[-1, 0], nb[-1, 1], nb[0, 1], k)
                          + factor[2] * _cell_length(nb[0, -1], k, nb[1, 0], nb[1, -1])
                          + factor[3] * _cell_length(k, nb[0, 1], nb[1, 1], nb[1, 0]))
                total = cost[k, rows, cols] + mu * length
                if best is None:
                    best, choice = total, np.zeros(rows.size, dtype=classes.dtype)
                else:
                    better = total < best
                    best = np.where(better, total, best)
                    choice[better] = k
            moved = choice != classes[rows, cols]
            changed += int(np.count_nonzero(moved))
            classes[rows, cols] = choice
    return classes, changed
