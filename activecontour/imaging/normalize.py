"""Normalisation: an image (gray, gray + alpha, RGB, RGBA, any dtype) to the values (6.38) reads.

By default every image is scaled by its own range onto [0, 1], so mu and omega mean the same
relative to its contrast whatever its dtype or bit depth (DESIGN.md, Conventions).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "CHANNEL_COUNTS",
    "byte_levels",
    "channels_last",
    "intensity_scale",
    "normalize_image",
    "single_image",
]


def channels_last(image):
    """The image with its channels on the last axis: a view of ``image``, never a copy.

    A stack of shape (3 or 4, M, N) with M, N > 4 and a last axis that cannot be channels is
    channel-first (as some TIFF writers store colour) and is moved to (M, N, 3 or 4); any other
    shape is returned as it is.  :func:`normalize_image`, :func:`intensity_scale`, the loader and
    the writers all read an image's layout through this one function.
    """
    image = np.asarray(image)
    if (image.ndim == 3 and image.shape[0] in (3, 4) and image.shape[2] not in (2, 3, 4)
            and min(image.shape[1:]) > 4):
        return np.moveaxis(image, 0, -1)
    return image


#: Sizes of an axis that can hold channels: gray, gray + alpha, RGB, RGBA.
CHANNEL_COUNTS = (1, 2, 3, 4)


def single_image(image, channel_axis=None):
    """The array as one image, (M, N) or (M, N, C) channel-last, or a one-line error for a stack.

    The layout rule of :func:`activecontour.segment`: a 2-D array is an image; a 3-D array whose
    last axis has 1-4 entries is an image with channels (gray, gray + alpha, RGB, RGBA); a 3-D
    array whose *first* axis has 2-4 entries and whose last is longer may be that many frames or
    channel-first colour, so it is refused unless ``channel_axis`` says which axis holds the
    channels (``channel_axis=0``); any other 3-D or higher array is a stack of frames (time or z)
    and is refused with the name of :func:`activecontour.segment_sequence`.

    Parameters
    ----------
    image : ndarray
    channel_axis : int or None
        The axis holding the channels (1-4 entries) of a 3-D array; None: the rule above.  (An
        integer or None: :class:`activecontour.settings.Settings` checks that.)
    """
    image = np.asarray(image)
    if channel_axis is not None:
        if image.ndim != 3 or not -3 <= channel_axis < 3 or image.shape[channel_axis] not in CHANNEL_COUNTS:
            raise ValueError(f"channel_axis={channel_axis} must name an axis of 1-4 channels of a 3-D "
                             f"image, got shape {image.shape}")
        return np.moveaxis(image, channel_axis, -1)
    if image.ndim <= 2 or (image.ndim == 3 and image.shape[2] in CHANNEL_COUNTS):
        return image
    if image.ndim == 3 and image.shape[0] in CHANNEL_COUNTS[1:]:
        raise ValueError(
            f"image of shape {image.shape} is ambiguous: {image.shape[0]} frames or channel-first "
            f"colour? pass channel_axis=0 for colour, or segment the frames with "
            f"activecontour.segment_sequence")
    if image.ndim == 3 and image.shape[0] < min(image.shape[1:]):
        raise ValueError(
            f"image of shape {image.shape} is a stack of {image.shape[0]} frames, not one image: "
            f"segment it with activecontour.segment_sequence, or pass one frame")
    raise ValueError(
        f"image of shape {image.shape} is not one image with 1 (gray), 2 (gray + alpha), 3 (RGB) or "
        f"4 (RGBA) channels last; a stack of frames (time or z) is segmented by "
        f"activecontour.segment_sequence (axis= names the frame axis)")


def _intensity_channels(image):
    """The channels whose values are intensities (a view): alpha dropped, channel-last."""
    image = channels_last(image)
    if image.ndim == 3 and image.shape[2] in (1, 2):
        return image[:, :, 0]  # gray, or gray + alpha
    if image.ndim == 3 and image.shape[2] == 4:
        return image[:, :, :3]  # RGBA
    return image


def normalize_image(image, *, color="gray", normalize="range"):
    """Convert an image to float64 intensities of shape (M, N, C).

    Parameters
    ----------
    image : ndarray (M, N), (M, N, C) or (C, M, N)
        Gray (C = 1), gray + alpha (C = 2), RGB (3) or RGBA (4); bool, integer or float.  A
        channel-first stack (3 or 4, M, N) with M, N > 4 is read as channel-last.  Alpha is dropped.
    color : {"gray", "vector"}
        ``"gray"`` converts RGB to luminance (``skimage.color.rgb2gray`` weights); ``"vector"``
        keeps the channels, for the vector-valued functional of Chan, Sandberg and Vese.
    normalize : {"range", "dtype", None}
        ``"range"`` (default): affinely onto [0, 1] by the image's own minimum and maximum (over
        all channels), so that mu and omega mean the same relative to the image's contrast
        whatever its dtype, bit depth or intensity scale: 12-bit data in a uint16 array, values
        0..235 in uint16, int64, float 0..255 and float 0..1 of one scene give one segmentation
        (as ``skimage.segmentation.chan_vese`` does).  A constant image becomes 0.  ``"dtype"``:
        integers by their dtype's range (uint8 / 255, ...), floats as given.  None: the values
        as given.  Booleans are {0, 1} in every mode.  The plain minimum and maximum are used,
        not percentiles: on images whose objects are a tiny fraction of the pixels (stars, text)
        a percentile would cut the objects off.

    Raises
    ------
    TypeError
        For a dtype that is not bool, integer or float.
    ValueError
        For a wrong shape or number of channels, an image smaller than 2 x 2, or NaN or infinite
        values.  (``color`` and ``normalize`` are among :data:`activecontour.settings.COLOR_MODES`
        and :data:`~activecontour.settings.NORMALIZATIONS`: checked there.)
    """
    image = np.asarray(image)
    if not (image.dtype == bool or np.issubdtype(image.dtype, np.integer)
            or np.issubdtype(image.dtype, np.floating)):
        raise TypeError(f"image dtype must be bool, integer or float, got {image.dtype}")
    channels = _intensity_channels(image)
    if channels.ndim == 3 and channels.shape[2] != 3:
        raise ValueError(
            f"a colour image must have 1 (gray), 2 (gray + alpha), 3 (RGB) or 4 (RGBA) channels, "
            f"got shape {image.shape}"
        )
    if channels.ndim not in (2, 3):
        raise ValueError(f"image must have shape (M, N) or (M, N, C), got shape {image.shape}")
    if channels.shape[0] < 2 or channels.shape[1] < 2:
        raise ValueError(f"image must be at least 2 x 2 pixels, got shape {image.shape}")
    # 8-bit levels: one pass through the table of the 256 (no check), in C order, which the
    # luminance's product below then reads in the same order as a copy of the channels
    in_order = channels.ndim == 2 or color != "gray" or channels.flags.c_contiguous
    if channels.dtype in _BYTE_DTYPES and in_order:
        import cv2

        codes, table = _byte_levels(channels, image.dtype, normalize)
        values = cv2.LUT(codes, table)
    else:
        values = channels.astype(np.float64)  # this function's own copy: scaled in place below
        if not np.all(np.isfinite(values)):
            raise ValueError("image contains NaN or infinite values")
        offset, scale = _affine(values, image.dtype, normalize)
        if not np.isfinite(scale):  # intensities spanning more than the float range: halve first
            values *= 0.5
            offset, scale = _affine(values, image.dtype, normalize)
        _scale(values, offset, scale)
    if values.ndim == 3 and color == "gray":
        values = values @ np.array([0.2125, 0.7154, 0.0721])
    if values.ndim == 2:
        values = values[:, :, np.newaxis]
    return np.ascontiguousarray(values)


#: The dtypes whose intensities :func:`byte_levels` maps through a table of their 256 levels.
_BYTE_DTYPES = (np.dtype(np.uint8), np.dtype(np.bool_))


def byte_levels(image, normalize="range"):
    """``(codes, table)`` for an image of 8-bit (or bool) intensities, else None.

    ``codes`` are its intensity channels (alpha dropped) as uint8, (M, N) or (M, N, 3), and
    ``table`` the 256 normalised values of the levels, so that ``table[codes]`` is
    :func:`normalize_image` with ``color="vector"`` and this ``normalize``, bit for bit: the same
    affine map on the same float64 values, taken once per level instead of once per pixel.
    """
    image = np.asarray(image)
    channels = _intensity_channels(image)
    return _byte_levels(channels, image.dtype, normalize) if channels.dtype in _BYTE_DTYPES else None


def _byte_levels(channels, dtype, normalize):
    """:func:`byte_levels` of the intensity channels of an image of ``dtype``."""
    codes = np.ascontiguousarray(channels).view(np.uint8)  # bool: 0 and 1
    table = np.arange(256, dtype=np.float64)
    # the minimum and maximum of the levels present, as _affine takes them from the float values
    _scale(table, *_affine(codes, dtype, normalize))
    return codes, table


def _scale(values, offset, scale):
    """``(values - offset) / scale`` in place, each step skipped where it is the identity."""
    if offset != 0.0:
        values -= offset
    if scale != 1.0:
        values /= scale


def intensity_scale(image, normalize="range"):
    """``(offset, scale)`` such that an input intensity is ``offset + scale * normalised``.

    The inverse of the affine map of :func:`normalize_image`, computed by the same function over
    the same channels (an alpha channel is not an intensity), to report region constants in the
    input's own units (the luminance weights sum to 1, so it holds for gray from colour too).
    """
    image = np.asarray(image)
    return _affine(_intensity_channels(image), image.dtype, normalize)


def _affine(channels, dtype, normalize):
    """``(offset, scale)`` of ``normalize`` for the intensity channels of an image of ``dtype``:
    the normalised value is ``(value - offset) / scale``."""
    if np.dtype(dtype) == np.bool_ or normalize is None:
        return 0.0, 1.0
    if normalize == "dtype":
        if np.issubdtype(dtype, np.integer):
            info = np.iinfo(dtype)
            return float(info.min), float(info.max) - float(info.min)
        return 0.0, 1.0
    low, high = float(channels.min()), float(channels.max())
    return low, (high - low) if high > low else 1.0
