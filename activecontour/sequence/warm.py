"""Warm starts: frame t started from frame t-1's result plus what its threshold split adds.

See :func:`_warm_start` for the rule; the defaults it reads are :func:`activecontour.segment`'s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def _warm_kwargs(segment_kwargs):
    """The keywords of a warm frame: the polygon flow starts at its finest smoothing length (the
    contours already lie on the boundaries: nothing to move as a whole) and does not search for
    new components by nucleation (the threshold split's new pieces are in the start already).
    Both only save iterations; options the caller gives win."""
    if segment_kwargs.get("backend", "polygon") != "polygon" or segment_kwargs.get("n_regions", 2) != 2:
        return segment_kwargs
    from activecontour.backends.polygon import PolygonOptions

    given = dict(segment_kwargs.get("options") or {})
    finest = given.get("min_smoothing", PolygonOptions().min_smoothing)
    return {**segment_kwargs, "options": {"smoothing": finest, "nucleate": False, **given}}


def _warm_start(previous, image, segment_kwargs):
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
    """
    import cv2

    from activecontour.energy import evaluate
    from activecontour.geometry.curve import stack_curves
    from activecontour.geometry.raster import mask_to_curves
    from activecontour.imaging.normalize import intensity_scale, normalize_image
    from activecontour.imaging.tables import ImageModel
    from activecontour.initial import DEFAULT_INIT_BLUR, speck_area
    from activecontour.models import ChanVeseParameters

    if not previous.contours:
        return None  # nothing to follow: the default start, as at frame 0
    normalize = segment_kwargs.get("normalize", "range")
    values = normalize_image(image, color=segment_kwargs.get("color", "gray"), normalize=normalize)
    offset, scale = intensity_scale(image, normalize)
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
    followed[np.unique(pieces[previous.mask])] = True
    speck = speck_area(previous.mu, float(np.mean(difference**2)))
    new = mask_to_curves(candidate & ~followed[pieces], min_area=speck)
    starts = [list(previous.contours) + new, mask_to_curves(candidate, min_area=speck)]
    model = ImageModel(values)
    params = ChanVeseParameters(previous.mu, segment_kwargs.get("omega", 0.0),
                                segment_kwargs.get("lambda_in", 1.0), segment_kwargs.get("lambda_out", 1.0))
    energies = [evaluate(model, *stack_curves(curves)[:2], params).energy if curves else np.inf
                for curves in starts]
    curves = starts[int(np.argmin(energies))]
    return _Start(contours=curves, mask=previous.mask) if curves else None


@dataclass
class _Start:
    """A previous result's contours (with new pieces) as an ``init``: taken as already oriented,
    and, like a result, started with the small smoothing length of a start on the boundaries."""

    contours: list
    mask: np.ndarray
