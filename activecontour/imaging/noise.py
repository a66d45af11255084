"""The noise level of an image, and the default length weight mu it implies."""

from __future__ import annotations

import numpy as np

__all__ = ["MU_BACKOFF", "MU_FLOOR", "MU_PER_NOISE_VARIANCE", "auto_mu", "estimate_noise", "is_auto"]

#: ``mu="auto"`` is ``MU_PER_NOISE_VARIANCE * sigma^2`` (see :func:`auto_mu`) ...  Measured on the
#: suite of ``benchmarks/bench_robust.py``: 4 leaves pixel-scale wiggles on smooth boundaries
#: (Dice 0.991 on the textured object, 0.9975 on the dim one), 16 starts to round 3 px strokes off;
#: 10 is the best of both (0.994, 0.998, strokes exact).
MU_PER_NOISE_VARIANCE = 10.0
#: ... but at least this (contrast^2 * pixel): a noise-free image still gets a smooth contour.
MU_FLOOR = 0.01
#: When ``mu="auto"`` leaves no object at all, the run is made once more at this fraction of it
#: (:func:`activecontour.segment`).  The length term removes a convex object whose area over
#: perimeter is below ``mu / (c_in - c_out)^2`` (a disk of radius r: ``pi r^2 (c_in - c_out)^2``
#: of fit against ``2 pi r mu`` of length), so at ``MU_PER_NOISE_VARIANCE sigma^2`` every object
#: with ``area / perimeter < 10 / SNR^2`` goes, SNR = |c_in - c_out| / sigma: at SNR 2.2,
#: ellipses of 4-6 px radius (``synthetic.touching_ellipses`` at twice the pixel size), which the
#: image shows plainly (each holds ~100 nats of likelihood), and the empty set then has the
#: lower (6.38).  Half the weight keeps them, and still removes every noise speck: on pure
#: Gaussian noise (32^2 to 512^2) the default run is empty down to 3 sigma^2.  Only a run that
#: ends empty is made again: one that finds an object at the default weight is unchanged.
MU_BACKOFF = 0.5

#: The Laplacian-difference mask of Immerkaer (1996): it removes linear trends, and its response
#: to white noise of variance sigma^2 has variance 36 sigma^2.
_NOISE_MASK = np.array([[1.0, -2.0, 1.0], [-2.0, 4.0, -2.0], [1.0, -2.0, 1.0]])


def estimate_noise(values, where=None):
    """Robust standard deviation of the pixel noise, per channel, of (M, N, C) values.

    The median absolute response to Immerkaer's Laplacian-difference mask, scaled to a standard
    deviation (1.4826 / 6 for Gaussian noise).  The median, not the mean, ignores edges and other
    structure that covers a minority of the pixels.  With ``where`` (bool (M, N)), only the
    responses whose 3 x 3 window lies within it count: a region of interest's crop, whose pixels
    outside the region are a constant fill (:func:`activecontour.imaging.roi.restrict_values`),
    answers those with zero and would pull the median towards no noise at all.  When no window
    lies within ``where``, all of them count.
    """
    import cv2  # not scipy.ndimage: it costs ~0.2 s to import on every cold start

    sigma = np.zeros(values.shape[2])
    if min(values.shape[:2]) < 3:
        return sigma
    step = max(1, int(np.sqrt(values.shape[0] * values.shape[1] / 1e6)))  # ~1 Mpx is plenty
    within = None
    if where is not None:  # the windows inside: the region eroded by the mask's 3 x 3 square
        within = cv2.erode(np.ascontiguousarray(where[::step, ::step], dtype=np.uint8),
                           np.ones((3, 3), np.uint8))[1:-1, 1:-1].astype(bool)
        within = within if within.any() else None
    for ch in range(values.shape[2]):
        plane = values[::step, ::step, ch] if step > 1 else values[:, :, ch]
        response = cv2.filter2D(np.ascontiguousarray(plane), cv2.CV_64F, _NOISE_MASK)[1:-1, 1:-1]
        sigma[ch] = 1.4826 / 6.0 * _median(np.abs(response if within is None else response[within]))
    return sigma


def _median(values):
    """``np.median`` of a float array, the same value bit for bit, reordering ``values`` (a copy the
    caller owns) in place: one partition at the upper middle and, for an even count, the largest
    value below it (the lower middle), averaged as ``np.median`` averages them.  ``np.median``
    partitions at both middles and the last position at once, which numpy does by a generic
    introselect; one position takes its vectorised selection, ~10x faster on 512^2 values (the
    noise is estimated on every ``mu="auto"`` run and by the objects' split by contrast)."""
    values = values.reshape(-1)
    middle = values.size // 2
    values.partition(middle)
    if np.isnan(values[middle:].max()):  # (a partition puts NaNs last; np.median answers NaN)
        return float("nan")
    upper = values[middle]
    return float(upper) if values.size % 2 else float(np.mean([values[:middle].max(), upper]))


def auto_mu(values, where=None):
    """The default length weight ``mu = MU_PER_NOISE_VARIANCE * sigma^2``, at least ``MU_FLOOR``.

    Read (6.38) as a MAP estimate: with Gaussian noise of variance sigma^2 the fitting terms are
    2 sigma^2 times a negative log-likelihood, so a length prior of fixed strength is a mu
    proportional to sigma^2.  sigma is estimated from the normalised image itself
    (:func:`activecontour.io.images.estimate_noise`; for colour, the mean variance of the channels,
    as the fitting terms are the channels' mean).  A fixed mu is too strong for a clean image with
    dim objects and too weak for a noisy one; this one keeps noise specks of the size of a few
    pixels from surviving while leaving a noise-free image's detail alone.

    Parameters
    ----------
    values : ndarray (M, N, C)
        Normalised intensities.
    where : bool ndarray (M, N), optional
        The pixels that are the image's (a region of interest's domain): :func:`estimate_noise`.

    Returns
    -------
    float
    """
    variance = float(np.mean(estimate_noise(values, where) ** 2))
    return max(MU_FLOOR, MU_PER_NOISE_VARIANCE * variance)


def is_auto(mu):
    """Whether ``mu`` asks for :func:`auto_mu`."""
    return isinstance(mu, str) and mu == "auto"
