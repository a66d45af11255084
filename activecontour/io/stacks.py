"""Stacks and sequences read frame by frame: multi-page TIFFs, folders of frames, videos.

Frames are read when they are needed, so a movie of any length streams at constant memory.
"""

from __future__ import annotations

import os
import re

import numpy as np

from activecontour.io.images import IMAGE_SUFFIXES, load_image, tiff_frame_count, tiff_is_single_image

__all__ = ["VIDEO_SUFFIXES", "is_stack", "read_frames"]

#: File name endings read as videos (OpenCV); other files are images or (multi-page) TIFFs.
VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".m4v", ".wmv", ".mpg", ".mpeg", ".webm", ".ogv")


# ------------------------------------------------------------------------------------- reading


def is_stack(path, axis=0):
    """Whether the file ``path`` holds a sequence of frames: a video, or a TIFF with more than one
    frame along ``axis``.  A file no reader opens is not a stack (reading it as an image says why)."""
    lower = os.fspath(path).lower()
    if lower.endswith(VIDEO_SUFFIXES):
        return True
    if lower.endswith((".tif", ".tiff")):
        try:
            return tiff_frame_count(path, axis) > 1
        except Exception:  # not a readable TIFF: load_image says why, in one line
            return False
    return False


def read_frames(frames, *, axis=0, select=None):
    """The frames of a sequence, read lazily: ``(iterator of (index, image), count or None)``.

    Parameters
    ----------
    frames : ndarray, sequence of arrays, iterable, or path
        * an array whose axis ``axis`` runs over frames: (T, M, N) or (T, M, N, C) for axis 0;
        * a list or tuple of 2-D images (M, N) or (M, N, C), or any iterable of them (read once);
        * the path of a multi-page TIFF (one frame per page along ``axis`` of its first series),
          of a folder of numbered frames (image files sorted by the numbers in their names:
          ``frame2.png`` before ``frame10.png``), or of a video (:data:`VIDEO_SUFFIXES`, read by
          OpenCV in RGB order).
    axis : int
        The frame axis of an array or a TIFF stack.
    select : slice, range or sequence of int, optional
        Source indices of the frames to keep, in the order given.

    Raises
    ------
    ValueError
        For a path that does not exist or holds no frames, an array with fewer than 3 dimensions,
        an ``axis`` out of range, or a ``select`` index out of range.
    """
    if isinstance(frames, (str, os.PathLike)):
        return _read_path(os.fspath(frames), axis, select)
    if isinstance(frames, np.ndarray) or hasattr(frames, "__array__") and hasattr(frames, "shape"):
        stack = np.asarray(frames) if not isinstance(frames, np.ndarray) else frames
        if stack.ndim < 3:
            raise ValueError(f"frames must be a stack (T, M, N) or (T, M, N, C), got shape {stack.shape}; "
                             "segment a single image with activecontour.segment")
        if not -stack.ndim <= axis < stack.ndim:
            raise ValueError(f"axis {axis} is out of range for frames of shape {stack.shape}")
        stack = np.moveaxis(stack, axis, 0)
        return _indexed(lambda i: stack[i], len(stack), select)
    if isinstance(frames, (list, tuple)):
        return _indexed(lambda i: np.asarray(frames[i]), len(frames), select)
    if hasattr(frames, "__iter__"):
        chosen = _selection(select, None)
        wanted = set(chosen or ())
        iterator = ((i, np.asarray(image)) for i, image in enumerate(frames)
                    if chosen is None or i in wanted)
        return iterator, (len(chosen) if chosen is not None else None)
    raise TypeError(f"frames must be an array, a list of images, an iterable or a path, "
                    f"got {type(frames).__name__}")


def _selection(select, count):
    """``select`` as a list of indices (checked against ``count`` when known), or None for all."""
    if select is None:
        return None
    if isinstance(select, slice):
        if count is None:
            raise ValueError("select as a slice needs a source of known length; pass a list of indices")
        return list(range(count)[select])
    chosen = [int(i) for i in select]
    if count is not None:
        bad = [i for i in chosen if not -count <= i < count]
        if bad:
            raise ValueError(f"select has frame index {bad[0]} but the sequence has {count} frames "
                             f"(0..{count - 1})")
        chosen = [i % count for i in chosen]
    return chosen


def _indexed(get, count, select):
    chosen = _selection(select, count)
    order = range(count) if chosen is None else chosen
    return ((i, get(i)) for i in order), len(order)


def _read_path(path, axis, select):
    if not os.path.exists(path):
        raise FileNotFoundError(f"frames not found: {path!r}")
    if os.path.isdir(path):
        names = [name for name in os.listdir(path) if name.lower().endswith(IMAGE_SUFFIXES)]
        if not names:
            raise ValueError(f"folder {path!r} holds no image files ({', '.join(IMAGE_SUFFIXES)})")
        names.sort(key=_natural_key)
        files = [os.path.join(path, name) for name in names]
        return _indexed(lambda i: load_image(files[i]), len(files), select)
    if path.lower().endswith(VIDEO_SUFFIXES):
        return _read_video(path, select)
    if path.lower().endswith((".tif", ".tiff")):
        return _read_tiff(path, axis, select)
    return _indexed(lambda i: load_image(path), 1, select)


def _natural_key(name):
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", name)]


def _read_tiff(path, axis, select):
    import tifffile

    with tifffile.TiffFile(path) as tif:
        series = tif.series[0]
        shape, axes, pages = series.shape, series.axes, len(series.pages)
    if axis == 0 and tiff_is_single_image(shape, axes):
        return _indexed(lambda i: load_image(path), 1, select)
    if axis == 0 and pages == shape[0]:  # one page per frame: read each when it is needed

        def page(i):
            with tifffile.TiffFile(path) as tif:
                return tif.series[0].asarray(key=i)

        return _indexed(page, pages, select)
    stack = np.moveaxis(tifffile.imread(path, series=0), axis, 0)  # frames across pages: read it all
    return _indexed(lambda i: stack[i], len(stack), select)


def _read_video(path, select):
    import cv2

    capture = cv2.VideoCapture(path)
    if not capture.isOpened():
        capture.release()
        raise ValueError(f"cannot read video {path!r}")
    count = int(capture.get(cv2.CAP_PROP_FRAME_COUNT)) or None
    chosen = _selection(select, count)
    chosen = None if chosen is None else sorted(set(chosen))  # a video is read forward only

    wanted = set(chosen or ())

    def frames():
        try:
            index = 0
            while True:
                ok, image = capture.read()
                if not ok:
                    return
                if chosen is None or index in wanted:
                    yield index, cv2.cvtColor(image, cv2.COLOR_BGR2RGB) if image.ndim == 3 else image
                index += 1
        finally:
            capture.release()

    return frames(), (len(chosen) if chosen is not None else count)
