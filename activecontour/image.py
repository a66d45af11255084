"""Images: loading, normalising, and the tables that make region integrals cheap.

The image is modelled as the continuous bilinear interpolant of the pixel values, pixel centres at
integer (row, col), extended by a constant over the half-pixel margin, on the domain
``D = [-0.5, M - 0.5] x [-0.5, N - 0.5]`` (the union of the pixel squares).

Region integrals of 1, I and I^2 over Omega_i turn into boundary integrals by Green's theorem,
``int_Omega g = closed integral of G(r, c) dc``, with ``G(r, c) = int^r g(s, c) ds`` the
antiderivative of g along the rows.  :class:`ImageModel` precomputes G at the pixel centres of
every row (of every 8th row on a large image) in one pass; G at any other point is a short
polynomial evaluation (after a few increments from the stored row below).  Because the bilinear
interpolant is a polynomial on each grid cell, both G and I are integrated *exactly* along the
pieces of a polygon edge between grid lines, which is what makes the discrete energy and its shape
derivative consistent to rounding error (see :mod:`activecontour.energy`).

The tables live in *padded* coordinates ``(u, v) = (r + 1, c + 1)`` of the image padded by one
replicated pixel, so that the interpolation cell of every point of D exists; the evaluation on a
cell is in :func:`activecontour._kernels.edge_integrals`.
"""

from __future__ import annotations

import contextlib
import os
import struct
import sys
import warnings

import numpy as np

from activecontour import _kernels

__all__ = ["CHANNEL_COUNTS", "MAX_PIXELS", "NORMALIZATIONS", "ImageModel", "SizeLimitError", "channels_last",
           "intensity_scale", "load_image", "normalize_image", "single_image"]

_COLOR_MODES = ("gray", "vector")
#: bytes up to which :class:`ImageModel` stores the antiderivatives at every row (3 float64 per
#: pixel and channel: a 1600^2 gray image); above, at every ``_SPARSE_ANCHOR``-th row (3/8 float64)
_FULL_TABLE_BYTES = 1 << 26
_SPARSE_ANCHOR = 8
#: The choices of ``normalize``: the image's own range (default), its dtype's range, or as given.
NORMALIZATIONS = ("range", "dtype", None)


#: The largest image :func:`load_image` reads by default, in pixels (rows x columns): 2**27, e.g.
#: 11585 x 11585 or 16384 x 8192.  Segmenting takes about 30 bytes per pixel (an 8192^2 image about
#: 2 GB), so this bounds a run near 4 GB.  The size a file declares is checked before it is decoded,
#: so a small file that declares a huge image (a "decompression bomb") costs nothing.  Raise it with
#: ``max_pixels=`` (``--max-pixels`` on the command line).
MAX_PIXELS = 2**27


class SizeLimitError(ValueError):
    """An input larger than a documented limit (``max_pixels``); a ValueError."""


#: Leading bytes of the formats the readers know, for saying what an unreadable file is.
_SIGNATURES = (
    (b"\x89PNG\r\n\x1a\n", "PNG"), (b"\xff\xd8\xff", "JPEG"), (b"II*\x00", "TIFF"),
    (b"MM\x00*", "TIFF"), (b"II+\x00", "BigTIFF"), (b"MM\x00+", "BigTIFF"), (b"BM", "BMP"),
    (b"GIF87a", "GIF"), (b"GIF89a", "GIF"), (b"RIFF", "WebP"), (b"\x00\x00\x00\x0cjP", "JPEG 2000"),
)


def _why_unreadable(path, error):
    """One true line for a file no reader could open: empty, text, damaged, or the reader's words
    (never the readers' advice to install plugins for a format the file is not in)."""
    with open(path, "rb") as handle:
        head = handle.read(4096)
    if not head:
        return "the file is empty (0 bytes)"
    known = next((name for magic, name in _SIGNATURES if head.startswith(magic)), None)
    if known is not None:
        first_line = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        return f"the {known} data is damaged or truncated ({first_line})"
    text = head.decode("utf-8", errors="ignore")  # the 4096th byte may cut a character in two
    if all(ch.isprintable() or ch in "\t\r\n" for ch in text):
        return "the file holds text, not an image"
    return "not an image in a format the readers know (PNG, JPEG, TIFF, BMP, GIF, WebP, ...)"


def load_image(path, *, max_pixels=MAX_PIXELS):
    """Read an image file into an array, with a clear error for a missing or unreadable file.

    Parameters
    ----------
    path : str or os.PathLike
        Any format OpenCV or scikit-image reads (PNG, JPEG, TIFF, BMP, ... including 16-bit PNG/TIFF).
    max_pixels : int or None
        Refuse an image of more pixels (rows x columns) than this, by the size the file declares,
        before decoding it (default :data:`MAX_PIXELS`); None: no limit.

    Returns
    -------
    ndarray of shape (M, N) or (M, N, C)
        The pixel values in their stored dtype; colour in RGB(A) channel order.

    Raises
    ------
    FileNotFoundError
        For a missing file.
    SizeLimitError
        For an image larger than ``max_pixels`` (a ValueError).
    ValueError
        For a file that is not a readable image (one line saying why: empty, text, damaged, ...).
    """
    path = os.fspath(path)
    if not os.path.exists(path):
        raise FileNotFoundError(f"image file not found: {path!r}")
    if os.path.isdir(path):
        raise ValueError(f"image path is a directory, not a file: {path!r}")
    if max_pixels is not None:
        _check_size(path, _declared_pixels(path), max_pixels)
    if path.lower().endswith((".tif", ".tiff")):
        from activecontour.sequence import tiff_frame_count

        try:
            frames = tiff_frame_count(path)
        except Exception:  # not a TIFF tifffile reads: the readers below say what it is
            frames = 1
        if frames > 1:
            raise ValueError(f"{path!r} is a stack of {frames} frames, not one image: segment it with "
                             f"activecontour.segment_sequence")
    image = _read_opencv(path)
    if image is None:  # a format or variant OpenCV does not read
        import skimage.io

        try:
            with warnings.catch_warnings():  # imageio's plugin probing warns about unrelated plugins
                warnings.simplefilter("ignore", DeprecationWarning)
                image = skimage.io.imread(path)
        except Exception as exc:  # every reader raises its own type; report them all the same way
            raise ValueError(f"cannot read image {path!r}: {_why_unreadable(path, exc)}") from None
    image = channels_last(np.asarray(image))
    if image.ndim not in (2, 3) or image.size == 0:
        raise ValueError(f"image {path!r} is not a 2-D image (shape {image.shape})")
    if max_pixels is not None:
        rows, cols = image.shape[:2]
        _check_size(path, (rows * cols, f"{rows} x {cols} = {rows * cols:,}"), max_pixels)
    return image


def _check_size(path, declared, max_pixels):
    """Refuse ``declared = (pixels, how to say it)`` over ``max_pixels``; None passes."""
    if declared is not None and declared[0] > max_pixels:
        raise SizeLimitError(f"image {path!r} has {declared[1]} pixels, more than the limit of "
                             f"{max_pixels:,} (max_pixels)")


def _declared_pixels(path):
    """``(pixels, how to say it)`` as the file's header declares them, without decoding the
    pixels; None when the header cannot be read this way (the size is then checked after
    decoding)."""
    with open(path, "rb") as handle:
        head = handle.read(24)
    if head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR":
        cols, rows = struct.unpack(">II", head[16:24])
        return rows * cols, f"{rows} x {cols} = {rows * cols:,}"
    try:
        from PIL import Image
    except ModuleNotFoundError:  # pragma: no cover - Pillow comes with scikit-image
        return None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # Pillow's own (lower) decompression-bomb warning
            with Image.open(path) as opened:
                cols, rows = opened.size
    except Image.DecompressionBombError:  # over twice Pillow's own limit, by how much it does not say
        return 2 * Image.MAX_IMAGE_PIXELS + 1, f"more than {2 * Image.MAX_IMAGE_PIXELS:,}"
    except Exception:  # not a format Pillow knows, or damaged: the readers below say so
        return None
    return rows * cols, f"{rows} x {cols} = {rows * cols:,}"


def _read_opencv(path):
    """The image as OpenCV reads it, in RGB(A) order, or None.

    OpenCV comes first: the command line imports it for its outputs anyway, and it reads a PNG
    several times faster than scikit-image's imageio plugins, which also cost ~0.3 s to import.
    """
    import cv2

    with _quiet_stderr():  # libpng and OpenCV print their own lines for a damaged file
        image = cv2.imread(path, cv2.IMREAD_UNCHANGED)  # stored dtype and channels, EXIF ignored
    if image is not None and image.ndim == 3 and image.shape[2] in (3, 4):
        image = cv2.cvtColor(image, cv2.COLOR_BGR2RGB if image.shape[2] == 3 else cv2.COLOR_BGRA2RGBA)
    return image


@contextlib.contextmanager
def _quiet_stderr():
    """Send what C libraries write on file descriptor 2 to /dev/null meanwhile (Python's own
    ``sys.stderr`` is flushed first; other threads' writes to fd 2 are lost meanwhile)."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, AttributeError, ValueError):  # no file descriptor 2
        yield
        return
    try:
        with open(os.devnull, "wb") as devnull:
            os.dup2(devnull.fileno(), 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


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
        The axis holding the channels (1-4 entries) of a 3-D array; None: the rule above.
    """
    image = np.asarray(image)
    if channel_axis is not None:
        if isinstance(channel_axis, bool) or not isinstance(channel_axis, (int, np.integer)):
            raise TypeError(f"channel_axis must be an integer axis or None, got {channel_axis!r}")
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
        For a wrong shape or number of channels, an image smaller than 2 x 2, NaN or infinite
        values, or an unknown ``color`` or ``normalize``.
    """
    if color not in _COLOR_MODES:
        raise ValueError(f"color must be one of {_COLOR_MODES}, got {color!r}")
    if normalize not in NORMALIZATIONS:
        raise ValueError(f"normalize must be one of {NORMALIZATIONS}, got {normalize!r}")
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
    values = channels.astype(np.float64)  # this function's own copy: scaled in place below
    if not np.all(np.isfinite(values)):
        raise ValueError("image contains NaN or infinite values")
    offset, scale = _affine(values, image.dtype, normalize)
    if not np.isfinite(scale):  # intensities spanning more than the float range: halve first
        values *= 0.5
        offset, scale = _affine(values, image.dtype, normalize)
    if offset != 0.0:
        values -= offset
    if scale != 1.0:
        values /= scale
    if values.ndim == 3 and color == "gray":
        values = values @ np.array([0.2125, 0.7154, 0.0721])
    if values.ndim == 2:
        values = values[:, :, np.newaxis]
    return np.ascontiguousarray(values)


def intensity_scale(image, normalize="range"):
    """``(offset, scale)`` such that an input intensity is ``offset + scale * normalised``.

    The inverse of the affine map of :func:`normalize_image`, computed by the same function over
    the same channels (an alpha channel is not an intensity), to report region constants in the
    input's own units (the luminance weights sum to 1, so it holds for gray from colour too).
    """
    if normalize not in NORMALIZATIONS:
        raise ValueError(f"normalize must be one of {NORMALIZATIONS}, got {normalize!r}")
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


class ImageModel:
    """The bilinear image on D with its row-antiderivative tables (one pass over the pixels).

    Parameters
    ----------
    values : ndarray of shape (M, N, C)
        Normalised intensities, as returned by :func:`normalize_image`, or the feature channels
        of a model whose integrands are quadratic forms in them (:mod:`activecontour.models`).
    image : ndarray of shape (M, N, C'), optional
        What a start looks at (:func:`activecontour.initial.initial_curves`): the intensities
        when ``values`` are features (the smooth fit's image corrected by its light field);
        by default ``values``.

    Attributes
    ----------
    shape : tuple
        (M, N).
    n_channels : int
        C.
    totals : tuple of (float, ndarray (C,), ndarray (C,))
        ``int_D 1``, ``int_D I`` and ``int_D I^2``, exactly, for the outside region by subtraction.
    """

    def __init__(self, values, image=None):
        values = np.ascontiguousarray(values, dtype=np.float64)
        if values.ndim != 3:
            raise ValueError("ImageModel expects normalised values of shape (M, N, C)")
        self.values = values
        self.image = values if image is None else image
        self.shape = values.shape[:2]
        self.n_channels = values.shape[2]
        m, n = self.shape
        full = 24 * (m + 2) * (n + 2) * self.n_channels <= _FULL_TABLE_BYTES
        #: padded rows between two stored rows of ``table``
        self.anchor = 1 if full else _SPARSE_ANCHOR
        #: ((M + 1) // anchor + 1, N + 2, C, 3): the row-antiderivatives (t1, t2, t3) at every
        #: anchor-th padded row, built in one pass without temporaries
        #: (:func:`activecontour._kernels.build_tables`, which also says why float64)
        self.table = np.empty(((m + 1) // self.anchor + 1, n + 2, self.n_channels, 3))
        total1, total2 = np.empty(self.n_channels), np.empty(self.n_channels)
        _kernels.build_tables(values, self.table, self.anchor, total1, total2)
        self.bounds = np.array([[-0.5, -0.5], [m - 0.5, n - 0.5]])
        self.totals = (float(m * n), total1, total2)
