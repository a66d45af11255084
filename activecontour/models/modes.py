"""How many regions an image holds: the significant modes of the density of its flat pixels.

``segment(n_regions="auto")`` reads the number K of the piecewise-constant model off the image's
intensities before any segmentation, in a few milliseconds (:func:`count_regions`).

The criterion
-------------
The model (6.38) with K regions says: away from the interfaces, a pixel of region k has the value
``c_k`` plus noise of variance sigma^2.  So the intensities of the pixels inside the regions form K
bumps, one per region, each as wide as the noise; a region is a *mode* of their density.  The steps:

1. Smooth the image by a Gaussian of 1 px, as the K-means start does
   (:func:`activecontour.backends.labelfield.initial_classes`).  White noise of variance sigma^2
   leaves it with variance ``s^2 = sigma^2 / (4 pi)`` (a unit-mass Gaussian kernel of width 1
   has squared norm 1 / (4 pi)): each region's bump is ``s`` wide.
2. Keep the *flat* pixels, whose smoothed gradient (central differences) is what the noise
   gives: each component has variance ``tau^2 = sigma^2 (1 - e^-1) / (8 pi)`` (the smoothed
   noise's variance, halved, times one less its correlation e^-1 at a lag of 2 px), so on a flat
   region ``|grad|^2 / tau^2`` is chi^2 with 2 degrees of freedom; a pixel is flat below its 99%
   quantile, ``|grad| <= sqrt(-2 ln 0.01) tau = 3.03 tau``.  Pixels on an interface show blends
   of two regions (partial volume); along straight edges they pile up at a few values and would
   make bumps of their own.
3. Estimate the density of the flat pixels' intensities: their histogram (256 bins) smoothed by
   a Gaussian of width ``s``, the width of one region's bump (a kernel density estimate).
4. Count the modes that stand out: a peak of height f counts when it rises above the higher of
   the two saddles that separate it from higher ground (or from the histogram's ends) by at least
   ``f / 2`` (its *prominence*: the valley between two regions at most half the smaller peak;
   two equal bumps of width w get that deep when their levels differ by more than about 3.3 w,
   i.e. 1.3 sigma here) and by 3 standard deviations of the counts' Poisson noise (the smoothed
   count ``sum_j w_j n_j`` has variance ``sum_j w_j^2 n_j``), so sampling noise makes no mode.
5. K is the number of such modes, at least 2 (the two-region model of (6.38) is the least the
   functional knows) and at most ``max_regions``.

sigma is the larger of the image's noise (:func:`activecontour.imaging.noise.estimate_noise`) and the
noise that the length weight assumes, ``sqrt(mu / MU_PER_NOISE_VARIANCE)``
(:func:`activecontour.imaging.noise.auto_mu` sets ``mu = MU_PER_NOISE_VARIANCE sigma^2``).  So the
intensity resolution at which regions are told apart is the one the functional resolves: with
``mu="auto"``, a noise-free image is counted at sigma = sqrt(MU_FLOOR / MU_PER_NOISE_VARIANCE)
= 0.03 of its range, and a larger ``mu`` merges close levels.  Colour images (``color="vector"``)
count each channel and take the most modes: regions of one gray level but different colours are
told apart by some channel.

Why not a penalised likelihood
------------------------------
BIC or MDL adds a region when the fit energy drops by more than a penalty of order
``sigma^2 log N`` per new parameter.  Without the length term the drop is the K-means sum of
squares, and splitting one Gaussian bump of n pixels in two removes a fraction 2 / pi of its
sum of squares, about ``0.64 n sigma^2``: pure noise would get every region it is offered.  With
the length term the noise is paid for, but nothing that is not piecewise constant is: a ramp or
the shading of an unevenly lit region of span Delta over N pixels loses
``N Delta^2 (1 / K^2 - 1 / (K + 1)^2) / 12`` of fit energy by one more band, against ``mu`` times
a band's length, so the penalty never stops the count on a shaded image.  The number of regions
is a property of the shape of the intensity density (where its bumps are), not of how well K
levels fit; and reading it off the density costs one histogram instead of K_max segmentations.

What it gives: a pure-noise image, a ramp (flat density, no mode but one) and two flat regions at
SNR 3 give 2; three nested classes at SNR 3 give 3; the Shepp-Logan phantom (six levels, two of
them under 250 px) gives 6.  Shading makes modes of its own: an unevenly lit background is a
broad bump, sometimes two (the 20 faint blobs under a light gradient and a vignette of
benchmarks/bench_models.py give 2 or 3 by seed).  The count is made on the image as it is,
whatever ``fit``: dividing it by the light field of the whole image as one region (the smooth
fit's second start) was tried and dropped, since where large objects make that light it merges
their levels (the nested classes gave 2, the phantom 4).

A known limit: the count noise is taken as Poisson, though neighbouring pixels of the smoothed
image are correlated (over about 4 pi px, the area of one independent sample of smoothed noise).
Charging that (variance times 4 pi) makes real photographs count the same at every scale
(scikit-image's clock gives 2 at 0.5-2x its size, camera 4-5) but leaves the phantom's two
classes of 122 and 225 px below significance (4 instead of 6 at 400^2).  Without it, as here,
the synthetic scenes are counted right at every size tried (96-768 px), while clock gives 5 at
half its size and camera 4-6 between 0.5x and 2x: shading cut into patches by the flat-pixel test
makes bumps of its own.
"""

from __future__ import annotations

import numpy as np

__all__ = ["MAX_REGIONS", "choose_regions", "count_regions", "intensity_modes"]

#: ``n_regions="auto"`` chooses at most this many regions.
MAX_REGIONS = 6

_SMOOTHING = 1.0  # Gaussian sigma (px) of the image whose flat pixels are counted
_BINS = 256
_FLAT_QUANTILE = np.sqrt(-2.0 * np.log(0.01))  # chi^2_2's 99% quantile, as a gradient over tau
_PROMINENCE = 0.5  # a mode's rise above its saddle, over its height
_SIGNIFICANCE = 3.0  # ... and over the standard deviation of the counts' noise


def choose_regions(values, floor, mu=None, *, max_regions=MAX_REGIONS):
    """``n_regions="auto"`` of :func:`activecontour.segment`: :func:`count_regions` at the noise
    level the length weight assumes.

    In the working frame (the image spanning [0, 1], :func:`activecontour.imaging.frame.working_frame`),
    sigma is ``sqrt(mu / MU_PER_NOISE_VARIANCE)`` for the larger of ``mu`` and
    :func:`~activecontour.imaging.noise.auto_mu`'s (the image's noise, at least
    ``sqrt(MU_FLOOR / MU_PER_NOISE_VARIANCE)`` = 0.03 of its range): regions are told apart at the
    resolution the functional resolves.  :class:`activecontour.problem.Problem` gives the three.

    Parameters
    ----------
    values : ndarray (M, N, C)
        Normalised intensities in the working frame.
    floor : float
        :func:`~activecontour.imaging.noise.auto_mu` of ``values``.
    mu : float, optional
        The length weight of the run, in the working frame; None: ``mu="auto"``.
    max_regions : int

    Returns
    -------
    int
    """
    from activecontour.imaging.noise import MU_PER_NOISE_VARIANCE

    mu = floor if mu is None else max(floor, mu)
    return count_regions(values, np.sqrt(mu / MU_PER_NOISE_VARIANCE), max_regions=max_regions)


def count_regions(values, sigma, *, max_regions=MAX_REGIONS):
    """The number of regions K of ``n_regions="auto"`` (module docstring): the most significant
    modes of the flat pixels' intensities in any channel, in ``2..max_regions``.

    Parameters
    ----------
    values : ndarray (M, N, C)
        Intensities (any offset and scale; ``sigma`` in the same units).
    sigma : float
        The noise standard deviation the count resolves (> 0).
    max_regions : int
        The largest K returned (>= 2).

    Returns
    -------
    int
    """
    most = max(len(intensity_modes(values[..., ch], sigma)) for ch in range(values.shape[2]))
    return int(min(max(most, 2), max_regions))


def intensity_modes(plane, sigma):
    """The significant modes of the density of a plane's flat pixels (steps 1-4 of the module
    docstring), in increasing intensity.

    Parameters
    ----------
    plane : ndarray (M, N)
    sigma : float
        The noise standard deviation (> 0), in the plane's units.

    Returns
    -------
    ndarray (n,)
        The intensity of each mode's peak (the centre of its bin).
    """
    import cv2

    smooth = cv2.GaussianBlur(np.asarray(plane, dtype=np.float32), (0, 0), _SMOOTHING,
                              borderType=cv2.BORDER_REPLICATE).astype(np.float64)
    low, high = float(smooth.min()), float(smooth.max())
    if not high > low:
        return np.array([low])
    spread = sigma / (2.0 * np.sqrt(np.pi) * _SMOOTHING)
    tau = sigma * np.sqrt((1.0 - np.exp(-1.0)) / (8.0 * np.pi))  # for a kernel of 1 px
    if min(smooth.shape) >= 2:
        d_row, d_col = np.gradient(smooth)
        flat = smooth[np.hypot(d_row, d_col) <= _FLAT_QUANTILE * tau]
    else:
        flat = smooth.ravel()
    width = (high - low) / _BINS
    counts = np.bincount(np.minimum(((flat - low) / width).astype(np.intp), _BINS - 1),
                         minlength=_BINS).astype(np.float64)
    bandwidth = max(spread / width, 1.0)  # in bins
    reach = int(np.ceil(4.0 * bandwidth))
    kernel = np.exp(-0.5 * (np.arange(-reach, reach + 1) / bandwidth) ** 2)
    kernel /= kernel.sum()
    padded = np.pad(counts, reach)
    density = np.convolve(padded, kernel, mode="valid")
    variance = np.convolve(padded, kernel * kernel, mode="valid")
    peaks = [i for i in _peaks(density) if _significant(density, variance, i)]
    return low + width * (np.array(peaks, dtype=np.float64) + 0.5)


def _peaks(density):
    """Indices of the local maxima (the first bin of a plateau)."""
    ends = np.concatenate([[-np.inf], density, [-np.inf]])
    return np.flatnonzero((ends[1:-1] > ends[:-2]) & (ends[1:-1] >= ends[2:]))


def _significant(density, variance, peak):
    """Whether the peak's prominence is at least ``_PROMINENCE`` of its height and
    ``_SIGNIFICANCE`` standard deviations of the count noise of peak and saddle."""
    height = density[peak]
    saddles = []  # (density, index) of the lowest point before higher ground on each side
    for step in (-1, 1):
        index, lowest = peak, (height, peak)
        while 0 <= index + step < len(density) and density[index + step] <= height:
            index += step
            lowest = min(lowest, (density[index], index))
        # walking off the histogram's end: the density there is 0
        saddles.append(lowest if 0 <= index + step < len(density) else (0.0, None))
    saddle, where = max(saddles, key=lambda entry: entry[0])
    rise = height - saddle
    noise = np.sqrt(variance[peak] + (0.0 if where is None else variance[where]))
    return rise > 0.0 and rise >= _PROMINENCE * height and rise >= _SIGNIFICANCE * noise
