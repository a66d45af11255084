"""The working frame: intensities mapped so that the image spans [0, 1] while the flow computes.

Weights and constants are carried into the frame and energies back by
:meth:`~activecontour.models.ChanVeseParameters.in_frame`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["to_frame", "working_frame"]

def working_frame(values):
    """``(offset, scale)`` with ``(values - offset) / scale`` spanning [0, 1]; (0, 1) for values
    already within [0, 1] (every image ``normalize="range"`` gives, and integers by ``"dtype"``).

    A constant image gets scale 1.

    Raises
    ------
    ValueError
        For intensities (``normalize=None`` or float ``"dtype"``) whose span squared overflows:
        (6.38) of such intensities is not a float.
    """
    low, high = float(values.min()), float(values.max())
    if 0.0 <= low and high <= 1.0:
        return 0.0, 1.0
    with np.errstate(over="ignore"):
        span = high - low
        if not np.isfinite(span * span * values.shape[0] * values.shape[1]):
            raise ValueError(f"the image's intensities span {low:.3g}..{high:.3g}: (6.38) of them overflows; "
                             "pass normalize='range' (the default) to scale them to [0, 1]")
    return low, (span if span > 0 else 1.0)


def to_frame(values, offset, scale):
    """``(values - offset) / scale``: the image in the frame of :func:`working_frame`."""
    return values if offset == 0.0 and scale == 1.0 else (values - offset) / scale
