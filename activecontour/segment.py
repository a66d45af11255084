"""`segment`: the one public entry point, shared by the CLI, the viewer and pipelines."""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import os

import numpy as np

from activecontour.energy import ChanVeseParameters, to_frame, working_frame
from activecontour.image import ImageModel, intensity_scale, load_image, normalize_image
from activecontour.noise import auto_mu, is_auto
from activecontour.result import scalar_if_gray

__all__ = ["BACKENDS", "segment"]

#: backend name -> "module:function" implementing it (imported on first use)
BACKENDS = {
    "polygon": "activecontour.flow:segment_polygon",
    "levelset": "activecontour.levelset:segment_levelset",
}


def segment(image, init=None, *, backend="polygon", mu="auto", omega=0.0, lambda_in=1.0,
            lambda_out=1.0, max_num_iter=500, tol=5e-4, callback=None, c_in=None, c_out=None,
            color="gray", normalize="range", options=None):
    """Segment an image by minimising the Chan-Vese functional (6.38) with an active contour.

    Parameters
    ----------
    image : ndarray of shape (M, N) or (M, N, C), or a path
        Gray, gray + alpha, RGB or RGBA image (see :func:`activecontour.image.normalize_image`),
        or the path of an image file (read by :func:`activecontour.image.load_image`).
    init : None, ndarray (K, 2), list of ndarray, bool ndarray (M, N), or SegmentationResult
        Initial contour(s) in (row, col), a mask, or a previous result (of either backend).  None
        starts from a centred circle of radius 3/8 of the smaller side.  The level-set backend also
        accepts ``"checkerboard"``.
    backend : {"polygon", "levelset"}
        ``"polygon"``: the book's gradient flow (6.30)-(6.31) of a polygon with the H^1 velocity
        (6.39)-(6.40), sub-pixel.  ``"levelset"``: the same functional on the pixel grid.
    mu : float or "auto"
        Length weight (intensity^2 * pixel, intensities normalised), >= 0.  Larger gives smoother,
        shorter contours: features with a radius of curvature below about ``mu / (c_in - c_out)^2``
        pixels are smoothed away.  ``"auto"`` (default) sets it from the image's noise
        (:func:`activecontour.noise.auto_mu`); ``result.mu`` reports the value used.
    omega : float
        Area weight (intensity^2); positive shrinks, negative grows the inside.
    lambda_in, lambda_out : float
        Weights of the inside and outside fitting terms, > 0.
    max_num_iter : int
        Iteration limit.
    tol : float
        Convergence tolerance in pixels per iteration: the run has converged when the contour's
        mean normal displacement (the area it sweeps over its length), averaged over a few
        iterations, falls below ``tol`` at the finest stage.  It means the same on every image,
        whatever its size, noise or contrast; a 100x smaller ``tol`` changes neither the energy
        nor the mask measurably.  Coarse stages end at 10 tol.
    callback : callable, optional
        ``callback(state)`` with a :class:`~activecontour.result.FlowState` once per iteration;
        return True to stop.
    c_in, c_out : float or sequence, optional
        Hold the region constants fixed; by default they are updated by (6.42) every iteration.
    color : {"gray", "vector"}
        Colour images: convert to gray, or keep the channels (vector-valued functional).
    normalize : {"range", "dtype", None}
        Intensity scaling before the functional is set up: the image's own range onto [0, 1]
        (default), the dtype's range, or none (see :func:`activecontour.image.normalize_image`).
        ``result.c_in``/``c_out`` are in these normalised units; ``result.c_in_image`` and
        ``result.c_out_image`` in the input's own.  Whatever the choice, the backends compute
        where the image spans [0, 1] (:meth:`~activecontour.energy.ChanVeseParameters.in_frame`:
        no cancellation for intensities far from 0, no overflow), and report energies and
        constants in these units; weights and constants beyond ``PARAMETER_LIMIT`` (1e8) in
        that frame are refused.
    options : dict, optional
        Backend-specific settings, documented by the backend function
        (:func:`activecontour.flow.segment_polygon`, :func:`activecontour.levelset.segment_levelset`).

    Returns
    -------
    SegmentationResult
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {tuple(BACKENDS)}, got {backend!r}")
    if isinstance(max_num_iter, bool) or not isinstance(max_num_iter, (int, np.integer)):
        raise TypeError(f"max_num_iter must be an integer, got {max_num_iter!r}")
    if max_num_iter < 0:
        raise ValueError(f"max_num_iter must be >= 0, got {max_num_iter}")
    if not (isinstance(tol, (int, float, np.floating)) and np.isfinite(tol) and tol >= 0):
        raise ValueError(f"tol must be a finite number >= 0, got {tol!r}")
    if callback is not None and not callable(callback):
        raise TypeError("callback must be callable or None")
    if options is not None and not isinstance(options, dict):
        raise TypeError(f"options must be a dict or None, got {type(options).__name__}")
    if isinstance(image, (str, os.PathLike)):
        image = load_image(image)
    values = normalize_image(image, color=color, normalize=normalize)
    # the backends compute where the image spans [0, 1] (no cancellation, no overflow)
    frame_offset, frame_scale = working_frame(values)
    model = ImageModel(to_frame(values, frame_offset, frame_scale))
    del values
    square = frame_scale**2
    params = ChanVeseParameters(auto_mu(model.values) * square if is_auto(mu) else mu, omega, lambda_in,
                                lambda_out, c_in, c_out)
    working = params.in_frame(frame_offset, frame_scale)
    module_name, function_name = BACKENDS[backend].split(":")
    solver = getattr(importlib.import_module(module_name), function_name)
    _check_options(solver, backend, options or {})
    if callback is not None and working is not params:
        callback = _in_caller_units(callback, frame_offset, frame_scale)
    result = solver(model, init, working, max_num_iter=int(max_num_iter), tol=float(tol),
                    callback=callback, **(options or {}))
    if working is not params:
        result.energy *= square
        result.energies = result.energies * square
        result.c_in = scalar_if_gray(frame_offset + frame_scale * np.asarray(result.c_in))
        result.c_out = scalar_if_gray(frame_offset + frame_scale * np.asarray(result.c_out))
    offset, scale = intensity_scale(image, normalize)
    result.mu = params.mu
    result.c_in_image = scalar_if_gray(offset + scale * np.asarray(result.c_in))
    result.c_out_image = scalar_if_gray(offset + scale * np.asarray(result.c_out))
    return result


def _in_caller_units(callback, offset, scale):
    """The callback, shown each state's energy and constants in the caller's intensity units."""
    def wrapped(state):
        return callback(dataclasses.replace(
            state, energy=state.energy * scale**2,
            c_in=offset + scale * np.asarray(state.c_in), c_out=offset + scale * np.asarray(state.c_out)))

    return wrapped


def _check_options(solver, backend, options):
    """Name the valid options of a backend that lists them as keywords (others check their own)."""
    parameters = inspect.signature(solver).parameters.values()
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters):
        return
    valid = sorted(p.name for p in parameters if p.kind is inspect.Parameter.KEYWORD_ONLY
                   and p.name not in ("max_num_iter", "tol", "callback"))
    unknown = sorted(set(options) - set(valid))
    if unknown:
        raise TypeError(f"unknown option(s) {', '.join(map(repr, unknown))} for backend {backend!r}; "
                        f"the valid options are {', '.join(valid)}")
