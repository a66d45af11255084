"""Coarse-to-fine starts for large images: run the flow on a reduced copy, refine at full size.

The polygon flow moves its fastest vertex by at most ``max_step`` pixels per iteration, so the
number of iterations grows with the distance the curve travels, which grows with the image's side:
on an 8192^2 image a default start is ~600 px from the object, at least 300 iterations.  On a copy
reduced by block means of s x s pixels the same scene is s times smaller (and the noise s times
weaker), so the flow gets there in the iterations a small image needs; mapped back, its contours
are within about s pixels of the answer, and a few tens of full-resolution iterations finish.

Scaling (6.38) to the reduced image: lengths shrink by s and areas by s^2.  Dividing J by s^2
keeps the region terms (so ``omega``, ``lambda_in``, ``lambda_out``, ``c_in``, ``c_out`` stay),
and turns ``mu |Gamma|`` into ``(mu / s) |Gamma_s|``: the reduced problem has ``mu / s``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from activecontour.curve import signed_area
from activecontour.image import ImageModel
from activecontour.initial import initial_curves

__all__ = ["coarse_start", "reduction_factor"]

#: the reduced copy's longer side is at most this many pixels
MAX_SIDE = 512
#: initial curves enclosing less than this on the reduced copy (its pixels^2) skip it
_MIN_REDUCED_AREA = 16.0


def reduction_factor(shape, max_side=MAX_SIDE):
    """The smallest power of two s with ``max(shape) / s <= max_side`` (1 for a small image)."""
    if not (isinstance(max_side, (int, np.integer)) and max_side >= 16):
        raise ValueError(f"max_side must be an integer >= 16 pixels, got {max_side!r}")
    factor = 1
    while max(shape[:2]) > factor * max_side:
        factor *= 2
    return factor


def coarse_start(model, init, params, *, max_side=MAX_SIDE, max_num_iter=500, tol=1e-3, **options):
    """Initial curves for ``model`` from the polygon flow on its copy reduced to ``max_side``.

    Parameters
    ----------
    model : ImageModel
        The full-resolution image.
    init : as for :func:`activecontour.segment`
        Where the reduced flow starts, in full-resolution coordinates; None is the default start
        (:func:`activecontour.initial.default_init`) of the reduced copy.
    params : ChanVeseParameters
        Of the full-resolution problem; the reduced one uses ``mu / s`` (see the module notes).
    max_side : int
        Longest side of the reduced copy, in pixels.
    max_num_iter, tol, **options
        For the reduced run, as for :func:`activecontour.backends.polygon.segment_polygon` (its pixel lengths
        are reduced pixels).

    Returns
    -------
    list of ndarray (K, 2)
        Closed curves in full-resolution (row, col); the initial curves themselves when the image
        is no larger than ``max_side`` or a curve of ``init`` is too small for the reduced copy.
    """
    from activecontour.backends.polygon import segment_polygon  # the flow is what this module feeds

    factor = reduction_factor(model.shape, max_side)
    if factor == 1:
        return initial_curves(init, model.shape, model.image, params.mu)
    m, n = model.shape[0] // factor, model.shape[1] // factor
    # block means; the last (shape % factor) rows and columns are left out of the reduced copy
    reduced, reduced_image = (
        array[: m * factor, : n * factor].reshape(m, factor, n, factor, -1).mean(axis=(1, 3))
        for array in (model.values, model.image))
    # reduced pixel (i, j) covers full pixels factor * i .. factor * i + factor - 1: its centre
    # is at factor * i + (factor - 1) / 2
    offset = (factor - 1) / 2.0
    start = None  # the default start, found on the reduced copy (it reads every pixel)
    if init is not None:
        curves = initial_curves(init, model.shape, model.image, params.mu)
        start = [(curve - offset) / factor for curve in curves]
        if min(abs(signed_area(curve)) for curve in start) < _MIN_REDUCED_AREA:
            return curves  # a curve too small to see on the reduced copy: start at full size
    result = segment_polygon(ImageModel(reduced, reduced_image), start,
                             dataclasses.replace(params, mu=params.mu / factor),
                             max_num_iter=max_num_iter, tol=tol, callback=None, **options)
    if not result.contours:
        return initial_curves(init, model.shape, model.image, params.mu)
    return [factor * curve + offset for curve in result.contours]
