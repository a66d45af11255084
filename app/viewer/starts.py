"""The viewer's initial curves: what a fresh run starts from, as the library makes it.

The viewer never makes a start itself: drawn and loaded curves are clipped by
:func:`activecontour.initial.initial_curves`, and for no init (or a named one) the dashed curve
is the library's own start (:func:`library_start`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["NAMED_INITS", "describe", "is_named", "library_start", "read_mask_file"]

#: The library's named starts the viewer passes on as they are (the level set's checkerboard
#: needs ``backend="levelset"``).
NAMED_INITS = ("grid", "checkerboard")


def is_named(init):
    """Whether ``init`` is the library's to make: None (its default) or a name of :data:`NAMED_INITS`."""
    return init is None or (isinstance(init, str) and init in NAMED_INITS)


def library_start(image, init, parameters):
    """The curves :func:`activecontour.segment` starts from for ``init`` (None or a named start)
    with these keywords: its result after zero iterations."""
    from activecontour import segment

    start = segment(image, init, **{**parameters, "max_num_iter": 0})
    return [np.array(c, dtype=np.float64) for c in start.contours]


def describe(init, given):
    """Words for the init set from ``given`` (the curves before clipping)."""
    if init is None:
        return "the library's default"
    if isinstance(init, str):
        return init
    count = len(init)
    clipped = given is not None and not _same_curves(init, given)
    return f"{count} curve{'s' * (count > 1)}{', clipped to the image' if clipped else ''}"


def read_mask_file(path):
    """A mask file's mask (:func:`activecontour.io.read_mask`)."""
    from activecontour.io import read_mask

    return read_mask(path)


def _same_curves(curves, init):
    """Whether the curves are the init as given (not clipped); a mask init counts as unchanged."""
    if isinstance(init, np.ndarray) and init.dtype == bool:
        return True
    try:
        given = [np.asarray(c, dtype=np.float64) for c in init]
    except (TypeError, ValueError):
        return True
    return len(given) == len(curves) and all(
        g.shape == c.shape and np.array_equal(g, c) for g, c in zip(given, curves, strict=True))
