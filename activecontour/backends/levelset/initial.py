"""The level set of a start: curves, masks, previous results and the checkerboard."""

from __future__ import annotations

import numpy as np

from activecontour.backends.levelset.redistancing import _redistance, curves_level_set, signed_distance
from activecontour.initial import initial_curves

#: The strings ``init`` may be, besides None, curves, masks and results.
INIT_STRINGS = ("checkerboard", "grid")


def checkerboard_level_set(shape, period):
    """Squares of p x p pixels, alternately in and out: ``(p/pi) sin(pi (r+1/2)/p) sin(pi (c+1/2)/p)``.

    The zero lines run between pixel centres (at ``r, c = k p - 1/2``), the square at the origin
    is inside, and the scaling makes ``|grad phi| = 1`` on the square sides.  A checkerboard start
    sees the whole image at once (Getreuer 2012; the default of ``skimage.segmentation.chan_vese``).
    """
    if not (np.isfinite(period) and period >= 2):
        raise ValueError(f"checkerboard_period must be a number >= 2 (pixels), got {period!r}")
    m, n = shape
    r = np.arange(m, dtype=np.float64)[:, None] + 0.5
    c = np.arange(n, dtype=np.float64)[None, :] + 0.5
    return (period / np.pi) * np.sin(np.pi * r / period) * np.sin(np.pi * c / period)


def has_phi(init):
    """Whether ``init`` is a result with a level set: its phi is the start, its zero set kept exactly."""
    return getattr(init, "phi", None) is not None and hasattr(init, "mask")


def initial_level_set(init, shape, *, band=np.inf, checkerboard_period=16.0, values=None,
                      dtype=np.float64, mu=0.0):
    """The signed-distance level set of any ``init`` that :func:`segment_levelset` accepts.

    ``values`` (M, N, C), the normalised image, and ``mu`` are used by the default start and
    ``"grid"`` (see :func:`activecontour.initial.initial_curves`: the default start leaves out the
    specks the length term ``mu`` would remove at once).  ``dtype``: of the returned array (the
    backend keeps phi in float32).

    Raises
    ------
    ValueError
        For an unknown string (listing the valid ones), a mask or ``phi`` of the wrong shape, or
        an init that leaves nothing inside or nothing outside.
    """
    if isinstance(init, str):
        if init == "checkerboard":
            return signed_distance(checkerboard_level_set(shape, checkerboard_period), band).astype(dtype)
        if init not in INIT_STRINGS:
            raise ValueError(
                f"init {init!r} is not understood by the level-set backend; the valid strings are "
                f"{', '.join(map(repr, INIT_STRINGS))} (or pass None, a (K, 2) curve, a list of "
                "curves, a bool mask or a SegmentationResult)"
            )
    if has_phi(init):
        phi = np.asarray(init.phi)
        if phi.shape != tuple(shape):
            raise ValueError(
                f"init result has phi of shape {phi.shape}, but the image has shape {tuple(shape)}"
            )
        if not np.any(phi > 0):
            raise ValueError("init result has an empty inside (phi <= 0 everywhere)")
        return _redistance(phi, band, dtype=dtype, keep_front=True).phi
    return curves_level_set(initial_curves(init, shape, values, mu), shape, band, dtype=dtype)
