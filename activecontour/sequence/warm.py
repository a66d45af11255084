"""Warm starts: frame t started from frame t-1's result plus what its threshold split adds.

See :func:`_warm_start` for the rule; the settings are :class:`activecontour.settings.Settings`
and the frame is prepared as :func:`activecontour.segment` prepares it
(:func:`activecontour.problem.prepare`).
"""

from __future__ import annotations

import dataclasses

import numpy as np


def _warm_settings(settings):
    """The settings of a warm frame: the polygon flow starts at its finest smoothing length (the
    contours already lie on the boundaries: nothing to move as a whole) and does not search for
    new components by nucleation (the threshold split's new pieces are in the start already).
    Both only save iterations; options the caller gives win."""
    if settings.solver.name != "polygon":
        return settings
    finest = settings.backend_options.min_smoothing
    return dataclasses.replace(settings, options={"smoothing": finest, "nucleate": False,
                                                  **(settings.options or {})})


def _warm_start(previous, problem):
    """The start of a frame after the first: the lower in (6.38), on this frame, of

    * the previous frame's contours plus the new pieces of this frame's threshold split (objects
      entering the field or appearing), and
    * the pieces of this frame's threshold split alone (where objects moved by more than the
      flow travels in a few iterations, their new outline is the nearer start).

    The threshold split is the default start's (:func:`activecontour.initial.default_init`):
    the image smoothed by ``DEFAULT_INIT_BLUR`` px, thresholded half-way between the previous
    result's region constants (along their difference, for a vector image), pieces under
    :func:`activecontour.initial.speck_area` dropped; new pieces are its connected components
    that do not touch the previous result's inside.  Its constants are the previous frame's, not
    a new global scan (a third of a frame's time on 512^2; they barely move between frames).

    ``problem`` is this frame's, prepared (:func:`activecontour.problem.prepare`) for the run that
    follows: the starts are scored on its values and, for Gaussian noise, its tables.
    """
    import cv2

    from activecontour.energy import evaluate
    from activecontour.geometry.curve import stack_curves
    from activecontour.geometry.raster import mask_to_curves
    from activecontour.initial import DEFAULT_INIT_BLUR, Start, speck_area

    if not previous.contours:
        return None  # nothing to follow: the default start, as at frame 0
    # the starts are scored by (6.38) itself (squared error, free constants) with the previous
    # frame's mu; the squared error's tables are the run's own when its noise is Gaussian
    scoring = problem.reweighted(mu=previous.mu, c_in=None, c_out=None, noise="gaussian")
    gaussian = problem.settings.noise == "gaussian"
    values = problem.normalised
    offset, scale = problem.units
    c_in = (np.atleast_1d(previous.c_in_image) - offset) / scale
    c_out = (np.atleast_1d(previous.c_out_image) - offset) / scale
    difference = c_in - c_out
    projected = np.zeros(values.shape[:2], dtype=np.float32)
    for channel in range(values.shape[2]):
        smooth = cv2.GaussianBlur(values[:, :, channel].astype(np.float32), (0, 0), DEFAULT_INIT_BLUR,
                                  borderType=cv2.BORDER_REFLECT)
        projected += difference[channel] * (smooth - 0.5 * (c_in[channel] + c_out[channel]))
    candidate = projected > 0
    count, pieces = cv2.connectedComponents(candidate.astype(np.uint8), connectivity=8)
    followed = np.zeros(count, dtype=bool)
    followed[pieces[previous.mask]] = True
    speck = speck_area(previous.mu, float(np.mean(difference**2)))
    # (no new piece, the common frame: the mask of new pieces is empty, its curves none)
    new = [] if followed[1:].all() else mask_to_curves(candidate & ~followed[pieces], min_area=speck)
    starts = [list(previous.contours) + new, mask_to_curves(candidate, min_area=speck)]
    model, params = (problem if gaussian else scoring).model()[0], scoring.working
    energies = [evaluate(model, *stack_curves(curves)[:2], params).energy if curves else np.inf
                for curves in starts]
    curves = starts[int(np.argmin(energies))]
    return Start(contours=curves, mask=previous.mask, seeds=previous.labels) if curves else None
