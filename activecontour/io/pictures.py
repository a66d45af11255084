"""Masks and overlays: the segmentation written as images.

A mask is an 8-bit image, 0 outside and 255 inside; an overlay is the image in 8-bit RGB with the
contours drawn on it, anti-aliased at sub-pixel precision.  Both are written all or nothing
(:mod:`activecontour.io.atomic`).  A large overlay that would hardly compress (a noisy photograph)
is a PNG stored without compression: the same pixels, written four times faster
(:data:`STORE_MIN_PIXELS`).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from activecontour.geometry.curve import to_xy
from activecontour.imaging.normalize import byte_levels, normalize_image
from activecontour.io.atomic import write_atomically
from activecontour.io.contours import curve_list
from activecontour.io.images import MAX_PIXELS, load_image

__all__ = [
    "COLORS",
    "DISPLAY_PERCENTILES",
    "contrasting_color",
    "display_rgb",
    "encode_mask",
    "line_width",
    "OVERLAY_MAX_SIDE",
    "PICTURE_SUFFIXES",
    "REGION_COLORS",
    "STORE_MIN_PIXELS",
    "STORE_SHARE",
    "encode_overlay",
    "encode_picture",
    "read_mask",
    "render_overlay",
    "rgb_color",
    "write_mask",
    "write_overlay",
]

#: Suffixes of the lossless formats masks and overlays are written in (the formats read are
#: :data:`activecontour.io.images.IMAGE_SUFFIXES`).
PICTURE_SUFFIXES = (".png", ".tif", ".tiff", ".bmp")

#: Named overlay colours, RGB.
COLORS = {
    "red": (255, 0, 0),
    "green": (0, 255, 0),
    "blue": (0, 0, 255),
    "yellow": (255, 255, 0),
    "cyan": (0, 255, 255),
    "magenta": (255, 0, 255),
    "white": (255, 255, 255),
    "black": (0, 0, 0),
}


# Sub-pixel precision of the overlay polylines: OpenCV's ``shift`` (coordinates * 2**shift).
_DRAW_SHIFT = 4


def write_mask(path, mask):
    """Write a boolean mask as an 8-bit image with 0 outside and 255 inside.

    Parameters
    ----------
    path : str or os.PathLike
        Destination; ``.png`` (recommended), ``.tif``/``.tiff`` or ``.bmp`` (lossless formats only).
    mask : array_like of bool, shape (M, N)

    Returns
    -------
    pathlib.Path
        The path written.
    """
    path = Path(path)
    write_atomically(path, encode_mask(path, mask))
    return path


def read_mask(path, *, max_pixels=MAX_PIXELS):
    """Read a mask image: nonzero pixels are inside.

    Parameters
    ----------
    path : str or os.PathLike
        Any image :func:`activecontour.io.images.load_image` reads.  Gray images are used as they are; a
        gray + alpha image by its gray channel; an RGB or RGBA image is inside where any of R, G, B
        is nonzero (the alpha channel is ignored).
    max_pixels : int or None
        As in :func:`~activecontour.io.images.load_image`.

    Returns
    -------
    ndarray of bool, shape (M, N)

    Raises
    ------
    FileNotFoundError
        For a missing file.
    ValueError
        For an unreadable file or one that is not a 2-D image after dropping the channels.
    """
    image = load_image(path, max_pixels=max_pixels)
    if image.ndim == 3:
        channels = image.shape[2]
        if channels in (1, 2):
            image = image[:, :, 0]
        elif channels in (3, 4):
            image = np.any(image[:, :, :3] != 0, axis=2)
        else:
            raise ValueError(
                f"mask {os.fspath(path)!r} has {channels} channels; expected a gray, gray+alpha, "
                "RGB or RGBA image"
            )
    if image.ndim != 2:
        raise ValueError(f"mask {os.fspath(path)!r} is not a 2-D image (shape {image.shape})")
    return np.asarray(image != 0)


def encode_mask(path, mask):
    """The bytes of the mask file ``path`` (its suffix picks the format), for :func:`write_mask`."""
    import cv2

    suffix = _check_suffix(path, "mask")
    mask = np.asarray(mask)
    if mask.ndim != 2 or mask.size == 0:
        raise ValueError(f"mask must be a 2-D array of shape (M, N), got shape {mask.shape}")
    if mask.dtype != bool:
        if not (np.issubdtype(mask.dtype, np.number) and np.all(np.isfinite(mask))):
            raise ValueError("mask must be a bool array (or numbers, nonzero = inside) without NaN")
        mask = mask != 0
    ok, buffer = cv2.imencode(suffix, mask.view(np.uint8) * np.uint8(255))  # bool: bytes 0 and 1
    if not ok:
        raise ValueError(f"OpenCV could not encode a mask as {suffix}")
    return buffer.tobytes()


#: The longest side of the overlay :func:`activecontour.io.save_result` writes (and so the CLI): a
#: larger image's overlay is shrunk by area averaging, its contours with it.  An 8192^2 overlay
#: would be a 200 MB PNG that takes longer to encode than the segmentation; the mask and the
#: contour files keep the full resolution.
OVERLAY_MAX_SIDE = 4096


def write_overlay(path, image, contours, *, color="auto", thickness="auto", max_side=None):
    """Draw the contours on the image and write it as an 8-bit RGB image (PNG recommended).

    Parameters
    ----------
    path : str or os.PathLike
    image : ndarray of shape (M, N), (M, N, C) or (C, M, N)
        Gray or colour image, shown by its own range (:func:`display_rgb`).
    contours : list of ndarray (K, 2), or a SegmentationResult
        Closed curves in (row, col); drawn anti-aliased at sub-pixel precision.  A result with
        more than two regions (``class_contours``) has each region's boundary drawn, region k
        (k >= 1) in the k-th colour of :data:`REGION_COLORS` with ``color="auto"`` (where two
        regions meet, the line takes the brighter region's colour).
    color : str or (int, int, int)
        ``"auto"`` (:func:`contrasting_color`), a name from :data:`COLORS` or an RGB triple in
        0..255.
    thickness : int or "auto"
        Line width in pixels, >= 1; ``"auto"``: :func:`line_width` of the written size.
    max_side : int, optional
        Shrink an image whose longer side exceeds this (see :func:`render_overlay`); None keeps
        the full size.

    Returns
    -------
    pathlib.Path
    """
    path = Path(path)
    write_atomically(path, encode_overlay(path, image, contours, color, thickness, max_side))
    return path


def render_overlay(image, contours, color="auto", thickness="auto", max_side=None):
    """The overlay as an (M, N, 3) uint8 RGB array (see :func:`write_overlay`).

    With ``max_side``, an image whose longer side exceeds it is shrunk to that side first (area
    averaging), and the contours are mapped with it: pixel centres stay pixel centres,
    ``x' = (x + 1/2) s - 1/2``.  ``"auto"`` line widths follow the shrunk size.
    """
    import cv2

    # a result of K > 2 regions: the curves of regions 1..K-1, each region its own colour
    regions = getattr(contours, "class_contours", None)
    groups = [curve_list(contours)] if regions is None else [curve_list(c) for c in regions[1:]]
    if thickness != "auto" and (isinstance(thickness, bool) or not isinstance(thickness, (int, np.integer))
                                or thickness < 1):
        raise ValueError(f"thickness must be an integer >= 1 or 'auto', got {thickness!r}")
    if max_side is not None and not (isinstance(max_side, (int, np.integer)) and max_side >= 16):
        raise ValueError(f"max_side must be None or an integer >= 16, got {max_side!r}")
    if not (isinstance(color, str) and color == "auto"):
        color = rgb_color(color)
    shown = _display(image)
    scale = 1.0
    if max_side is not None and max(shown.shape[:2]) > max_side:
        # shrunk before a gray image becomes RGB: area averaging is the same on every channel,
        # so this is the RGB image shrunk, at a third of the pixels read
        scale = max_side / max(shown.shape[:2])
        size = (max(1, round(shown.shape[1] * scale)), max(1, round(shown.shape[0] * scale)))
        shown = cv2.resize(shown, size, interpolation=cv2.INTER_AREA)
    rgb = _as_rgb(shown)
    if isinstance(color, str):
        colors = ([contrasting_color(rgb)] if regions is None else
                  [COLORS[REGION_COLORS[k % len(REGION_COLORS)]] for k in range(len(groups))])
    else:
        colors = [color] * len(groups)
    if thickness == "auto":
        thickness = line_width(rgb.shape)
    for curves, line_color in zip(groups, colors, strict=True):
        polylines = [
            np.round(((to_xy(curve) + 0.5) * scale - 0.5) * (1 << _DRAW_SHIFT)).astype(np.int32)
            .reshape(-1, 1, 2)
            for curve in curves
        ]
        if polylines:
            cv2.polylines(rgb, polylines, True, line_color, int(thickness), cv2.LINE_AA, _DRAW_SHIFT)
    return rgb


def line_width(shape):
    """The ``"auto"`` overlay line width for an image of ``shape``: 1 px per started 1024 px of its
    longer side (1 up to 1024 px, 4 at 4096 px), so that a line stays visible when the whole image
    is shown on a screen."""
    return max(1, round(max(shape[:2]) / 1024))


#: The colours :func:`contrasting_color` chooses from, in order of preference.
_LINE_COLORS = ("red", "yellow", "cyan", "green", "magenta", "blue")
#: The overlay colours of regions 1, 2, ... of a result with more than two regions (cycled).
REGION_COLORS = ("red", "yellow", "cyan", "magenta", "green", "blue")


def contrasting_color(rgb):
    """The ``"auto"`` overlay colour for a display image (M, N, 3) uint8: the colour of
    :data:`_LINE_COLORS` farthest from the image's colours.

    Red on a gray image (a hue stands out on any gray); on a colour image the candidate whose
    distance in RGB to the image's pixels is largest at its 5th percentile, so that the line stands
    out against nearly every pixel it may cross (red on a red retina or coffee image would vanish).
    """
    rgb = np.asarray(rgb)
    sample = rgb.reshape(-1, 3)[:: max(1, rgb.shape[0] * rgb.shape[1] // 65536)].astype(np.float64)
    if np.ptp(sample, axis=1).max(initial=0) <= 8:  # gray
        return COLORS[_LINE_COLORS[0]]
    scores = [np.percentile(np.linalg.norm(sample - COLORS[name], axis=1), 5) for name in _LINE_COLORS]
    return COLORS[_LINE_COLORS[int(np.argmax(scores))]]


#: The percentiles of an image's values shown as black and white by :func:`display_rgb`: robust to
#: a few hot or dead pixels, and equal to the minimum and maximum on most images.
DISPLAY_PERCENTILES = (0.01, 99.99)


def display_rgb(image):
    """The image as (M, N, 3) uint8 RGB for display, scaled by its own range.

    The one place where images are scaled for display (the overlays and the viewer): the values
    of every channel together are mapped from their :data:`DISPLAY_PERCENTILES` onto 0..255, so a
    uint16 image holding 0..235, a 12-bit image or floats 0..1000 are shown with their full
    contrast, as the segmentation sees them (:func:`activecontour.imaging.normalize.normalize_image`).  An
    image whose pixels are all alike is shown by its dtype's range (uint8 / 255, floats clipped to
    [0, 1]), in its own colour.  Gray
    images are repeated on three channels; alpha is dropped; a channel-first (3 or 4, M, N) image
    is read as channel-last.
    """
    return _as_rgb(_display(image))


def _display(image):
    """:func:`display_rgb` before a gray image is repeated on three channels: (M, N) or (M, N, 3)
    uint8."""
    import cv2

    levels = byte_levels(image, normalize="dtype")
    if levels is None:
        values = normalize_image(image, color="vector", normalize="dtype")  # a fresh float64 copy
        pixels = values.reshape(-1, values.shape[2])
        lowest, highest = pixels.min(axis=0), pixels.max(axis=0)
        sample = pixels[:: max(1, len(pixels) // 1_000_000)]
    else:  # 8 bits: the 256 levels' normalised values (the same), shown through a table below
        codes, values = levels
        pixels = codes.reshape(len(codes) * codes.shape[1], -1)
        # the table is increasing: the extreme levels' values are the values' extremes
        lowest, highest = values[pixels.min(axis=0)], values[pixels.max(axis=0)]
        sample = values[pixels[:: max(1, len(pixels) // 1_000_000)]]
    if np.any(highest > lowest):
        low, high = np.percentile(sample, DISPLAY_PERCENTILES)
        if high <= low:  # the percentiles meet (a few pixels differ from the rest): the plain range
            low, high = float(lowest.min()), float(highest.max())
        values -= low
        values *= 255.0 / (high - low)
    else:  # every pixel alike: its value (its colour) by the dtype's range
        values *= 255.0
    np.clip(values, 0.0, 255.0, out=values)
    np.rint(values, out=values)
    display = values.astype(np.uint8)
    del values
    if levels is not None:
        display = cv2.LUT(codes, display)
    return display[:, :, 0] if display.ndim == 3 and display.shape[2] == 1 else display


def _as_rgb(display):
    """A display image (:func:`_display`) as (M, N, 3) RGB, contiguous."""
    import cv2

    if display.ndim == 2:
        return cv2.cvtColor(display, cv2.COLOR_GRAY2RGB)
    return np.ascontiguousarray(display)


def encode_overlay(path, image, contours, color, thickness, max_side=None):
    """The bytes of the overlay file ``path``, for :func:`write_overlay`."""
    _check_suffix(path, "overlay")
    return encode_picture(path, render_overlay(image, contours, color, thickness, max_side))


#: A PNG picture of at least this many pixels is written without compression (stored) when
#: OpenCV's default compression of a sample of its rows (every :data:`_SAMPLE_STEP`-th) keeps at
#: least :data:`STORE_SHARE` of their bytes: a noisy photograph, whose compression takes 4-5 times
#: as long as storing it (0.54 s against 0.12 s for a 4096^2 overlay) to save 1-11 % of its size
#: (the overlays of bench_scale's noisy disk at 4096^2, and at 8192^2 shrunk to 4096^2).  Images
#: that compress well (the samples of scikit-image: to 0.2-0.35 of their bytes) keep the defaults.
STORE_MIN_PIXELS = 1 << 20
#: See :data:`STORE_MIN_PIXELS`: a stored file is at most ~1/0.85 of the compressed one's size.
STORE_SHARE = 0.85
_SAMPLE_STEP = 16


def encode_picture(path, rgb):
    """The bytes of an RGB picture (M, N, 3) uint8 in the lossless format of ``path``'s suffix
    (:data:`PICTURE_SUFFIXES`); a large PNG that would not compress is stored
    (:data:`STORE_MIN_PIXELS`)."""
    import cv2

    suffix = _check_suffix(path, "picture")
    bgr = cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2BGR)  # OpenCV wants BGR
    ok, buffer = cv2.imencode(suffix, bgr, _stored_png(bgr) if suffix == ".png" else [])
    if not ok:
        raise ValueError(f"OpenCV could not encode a picture as {suffix}")
    return buffer.tobytes()


def _stored_png(bgr):
    """OpenCV's parameters for writing ``bgr`` as a PNG without compression or filtering when it is
    large and a sample of its rows does not compress (:data:`STORE_MIN_PIXELS`); else none (its
    defaults)."""
    import cv2

    if bgr.shape[0] * bgr.shape[1] < STORE_MIN_PIXELS:
        return []
    sample = np.ascontiguousarray(bgr[::_SAMPLE_STEP])
    ok, buffer = cv2.imencode(".png", sample)
    if not ok or len(buffer) < STORE_SHARE * sample.nbytes:
        return []
    return [cv2.IMWRITE_PNG_COMPRESSION, 0, cv2.IMWRITE_PNG_FILTER, cv2.IMWRITE_PNG_FILTER_NONE]


def _check_suffix(path, kind):
    """``path``'s suffix, lower case, when it is one of :data:`PICTURE_SUFFIXES`."""
    suffix = Path(path).suffix.lower()
    if suffix not in PICTURE_SUFFIXES:
        raise ValueError(f"{kind} file must end in one of {PICTURE_SUFFIXES}, got {os.fspath(path)!r}")
    return suffix


def rgb_color(color):
    """An overlay colour as an RGB triple in 0..255: a name from :data:`COLORS` or a triple;
    ValueError naming the valid ones otherwise."""
    if isinstance(color, str):
        if color.lower() not in COLORS:
            raise ValueError(f"color must be one of {tuple(COLORS)} or an RGB triple, got {color!r}")
        return COLORS[color.lower()]
    try:
        values = tuple(int(v) for v in color)
    except (TypeError, ValueError):
        raise ValueError(f"color must be a name or an RGB triple in 0..255, got {color!r}") from None
    if len(values) != 3 or not all(0 <= v <= 255 for v in values):
        raise ValueError(f"color must be an RGB triple in 0..255, got {color!r}")
    return values
