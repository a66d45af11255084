"""Writers and readers of masks, overlays and contours, and the group :func:`save_result` writes.

The parts live in modules named after what they hold; this module gathers their public names:

=============================  ================================================================
:mod:`activecontour.io.atomic`    writing files all or nothing, one file or a group
:mod:`~activecontour.io.pictures`  masks (0/255 PNG) and overlays (the contours drawn on the image)
:mod:`~activecontour.io.contours`  contour files: JSON, CSV, NPZ and the formats' dispatch
:mod:`~activecontour.io.vector`  the (x, y) formats, GeoJSON and SVG
:mod:`~activecontour.io.objects`  one id per object: label image, GeoJSON, ImageJ ROIs, CSV
:mod:`~activecontour.io.sequences`  a segmented sequence: labels, tracks, objects, contact sheet
=============================  ================================================================

Every writer renders its whole output in memory first and then moves it into place with
:func:`os.replace`: a failure never leaves a half-written file.  :func:`save_result` writes a
result's mask, overlay and contour files as a group: all of them or none; :func:`save_sequence`
a sequence's files likewise.
"""

from __future__ import annotations

import os
import unicodedata
from pathlib import Path

import numpy as np

from activecontour.imaging.normalize import channels_last
from activecontour.io.atomic import check_protected, sweep_temporaries, write_group
from activecontour.io.contours import (
    CONTOUR_FORMATS,
    CONVENTION,
    MAX_POINTS,
    encode_contours,
    read_contours,
    read_metadata,
    write_contours,
)
from activecontour.io.images import MAX_PIXELS, SizeLimitError
from activecontour.io.objects import OBJECT_FORMATS, encode_objects, object_paths
from activecontour.io.pictures import (
    COLORS,
    OVERLAY_MAX_SIDE,
    display_rgb,
    encode_mask,
    encode_overlay,
    read_mask,
    write_mask,
    write_overlay,
)
from activecontour.io.sequences import save_sequence, sequence_paths

__all__ = [
    "COLORS",
    "CONTOUR_FORMATS",
    "CONVENTION",
    "MAX_PIXELS",
    "MAX_POINTS",
    "OBJECT_FORMATS",
    "SizeLimitError",
    "display_rgb",
    "output_paths",
    "output_stem",
    "read_contours",
    "read_mask",
    "read_metadata",
    "save_result",
    "save_sequence",
    "sequence_paths",
    "sweep_temporaries",
    "write_contours",
    "write_mask",
    "write_overlay",
]


def save_result(result, image, output_stem, formats=("json",), *, metadata=None, color="auto",
                thickness="auto", protect=(), objects=()):
    """Write a result's mask, overlay and contours as a group: all of them, or none.

    Parameters
    ----------
    result : SegmentationResult
    image : ndarray of shape (M, N), (M, N, C) or (C, M, N)
        The image that was segmented, for the overlay (any layout :func:`activecontour.segment`
        takes).
    output_stem : str or os.PathLike
        The files are ``<stem>_mask.png``, ``<stem>_overlay.png`` and ``<stem>_contours.<fmt>``;
        the directory must exist.
    formats : sequence of str
        Contour formats, from :data:`CONTOUR_FORMATS` (may be empty).
    metadata : dict, optional
        Extra entries for the contour files (see :func:`write_contours`).
    color, thickness
        Of the overlay's contour lines (see :func:`write_overlay`): by default a colour that stands
        out from the image and a width that grows with the overlay's size.  The overlay's longer
        side is at most :data:`~activecontour.io.pictures.OVERLAY_MAX_SIDE` (4096) pixels.
    protect : sequence of path
        Files that must not be overwritten (e.g. the input image): ValueError if an output is one.
    objects : sequence of str
        Object files, from :data:`~activecontour.io.objects.OBJECT_FORMATS` (``labels``,
        ``labels-tif``, ``geojson``, ``roi``, ``csv``): the label image, one GeoJSON Feature
        or ImageJ ROI per object, the measurement table (:mod:`activecontour.io.objects`).

    Returns
    -------
    list of pathlib.Path
        The paths written: mask, overlay, then one per format, then one per object format.

    Raises
    ------
    ValueError
        For bad arguments, an output that would overwrite a protected file, or an image whose
        shape differs from the mask's.
    OSError
        When writing fails; the files of the group already moved into place are then removed and
        any files they replaced are restored.
    """
    if isinstance(formats, str):
        formats = [formats]
    formats = list(dict.fromkeys(formats))
    objects = list(dict.fromkeys([objects] if isinstance(objects, str) else objects))
    for fmt in formats:
        if fmt not in CONTOUR_FORMATS:
            raise ValueError(f"formats must be chosen from {CONTOUR_FORMATS}, got {fmt!r}")
    mask = np.asarray(result.mask)
    image = channels_last(image)
    if image.ndim == 3 and image.shape[:2] != mask.shape and image.shape[1:] == mask.shape:
        # channel-first as segment(..., channel_axis=0) read it (2 channels, or a side <= 4 px, which
        # channels_last leaves as they are): the mask's shape says which axis the channels are on
        image = np.moveaxis(image, 0, -1)
    if image.shape[:2] != mask.shape:
        raise ValueError(
            f"image has shape {image.shape}, but the result's mask has shape {mask.shape}"
        )
    paths = output_paths(output_stem, formats, objects)
    check_protected(paths, protect)
    contents = [
        encode_mask(paths[0], mask),
        encode_overlay(paths[1], image, result, color, thickness, OVERLAY_MAX_SIDE),
    ]
    contents += [
        encode_contours(path, result, metadata, None, fmt)
        for path, fmt in zip(paths[2:], formats, strict=False)
    ]
    contents += [encode_objects(result, fmt) for fmt in objects]
    write_group(list(zip(paths, contents, strict=True)))
    return paths


def output_paths(output_stem, formats=("json",), objects=()):
    """The files :func:`save_result` writes for a stem: mask, overlay, one per format, then one
    per object format."""
    stem = os.fspath(output_stem)
    formats = list(dict.fromkeys([formats] if isinstance(formats, str) else formats))
    return [Path(f"{stem}_mask.png"), Path(f"{stem}_overlay.png")] + [
        Path(f"{stem}_contours.{fmt}") for fmt in formats
    ] + object_paths(stem, objects)


def output_stem(directory, source):
    """``directory / name``: the stem of the files written for the image ``source``, inside
    ``directory`` whatever ``source`` is called.

    ``name`` is the file name of ``source`` without its folders and its last suffix, with every
    character that could lead elsewhere or break a line replaced by ``_``: path separators,
    control characters (newlines, escapes) and leading dots (``..png`` would otherwise give
    ``directory/._mask.png``, or with ``.`` as the name, ``directory_mask.png`` beside it; a
    leading dot would also hide the outputs).  An empty name becomes ``image``.

    Parameters
    ----------
    directory : str or os.PathLike
    source : str or os.PathLike
        The input image's path (or any name).

    Returns
    -------
    pathlib.Path
    """
    name = os.fspath(source).replace("\\", "/").rsplit("/", 1)[-1]
    stem = name.rsplit(".", 1)[0] if "." in name.lstrip(".") else name
    safe = "".join("_" if unicodedata.category(ch)[0] == "C" or ch in "/\\" else ch for ch in stem)
    safe = "_" * (len(safe) - len(safe.lstrip("."))) + safe.lstrip(".")
    return Path(directory) / (safe or "image")
