"""Reading images: any file OpenCV, scikit-image or tifffile reads, with a size limit read from the header.

An image declaring more pixels than ``max_pixels`` is refused (:class:`SizeLimitError`) before it
is decoded; a multi-page TIFF is refused with one line naming
:func:`activecontour.segment_sequence`.
"""

from __future__ import annotations

import contextlib
import os
import struct
import sys
import warnings

import numpy as np

from activecontour.imaging.normalize import channels_last

__all__ = ["IMAGE_SUFFIXES", "MAX_PIXELS", "SizeLimitError", "load_image"]

#: File name endings of the images :func:`load_image` reads, compared in lower case: what a folder
#: of images (a batch's input, a sequence's frames) is taken to hold.
IMAGE_SUFFIXES = (".png", ".tif", ".tiff", ".jpg", ".jpeg", ".jp2", ".bmp", ".gif", ".webp", ".pgm",
                  ".ppm", ".pnm")

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


def tiff_frame_count(path, axis=0):
    """Frames in a TIFF's first series along ``axis``: with ``axis=0``, 1 for a single 2-D or
    colour image; another axis is the caller's word that the file is a stack along it."""
    import tifffile

    with tifffile.TiffFile(path) as tif:
        series = tif.series[0]
        shape, axes = series.shape, series.axes
    if axis == 0 and tiff_is_single_image(shape, axes):
        return 1
    if not -len(shape) <= axis < len(shape):
        raise ValueError(f"axis {axis} is out of range for the TIFF {path!r} of shape {shape}")
    return shape[axis]


def tiff_is_single_image(shape, axes):
    """A 2-D page, or one colour image (samples "S" chunky or planar), not a stack."""
    return len(shape) == 2 or (len(shape) == 3 and "S" in axes)

