"""Writers and readers of masks, overlays and contours.

Every writer renders its whole output in memory first and then writes it to a temporary file in
the destination directory, which is moved into place with :func:`os.replace`: a failure never leaves
a half-written file, and a file that was already there is either replaced whole or left as it was.
:func:`save_result` extends this to a group of files (mask, overlay, contours): all of them or none.

Contour files
-------------
Points are (row, col) with pixel centres at integer coordinates, each vertex stored once (the curve
closes implicitly); outer boundaries have positive signed area, holes negative (DESIGN.md).  The
format follows the file's suffix:

``.json``
    ``{"format": "activecontour-contours", "convention": ..., "metadata": {...},
    "contours": [{"kind": "outer" | "hole", "signed_area": ..., "points": [[row, col], ...]}]}``.
``.geojson``
    A FeatureCollection with one Feature whose geometry is a MultiPolygon: one polygon per outer
    boundary, followed by the holes it contains.  Image coordinates ``x = col, y = row`` (not
    geographic ones); rings are closed (first position repeated last) and follow the right-hand
    rule of RFC 7946 in the (x, y) plane (outer rings counterclockwise, holes clockwise), which is
    the reverse of the (row, col) orientation above.  The Feature's properties hold the metadata.
``.svg``
    An SVG of the image's size (``viewBox`` such that pixel (0, 0) covers the top-left unit square),
    one ``<path>`` per outer boundary with its holes, ``fill-rule="nonzero"``.
``.csv``
    Columns ``contour,vertex,row,col``; metadata on leading ``#`` lines.
``.npz``
    Arrays ``contour_0, contour_1, ...`` of shape (K, 2) and ``metadata`` (a JSON string).

Floating-point numbers are written with :func:`repr`, so :func:`read_contours` gives back exactly
the arrays that were written, in the same order, for every format.
"""

from __future__ import annotations

import io as _stdio
import json
import os
import re
import tempfile
import xml.etree.ElementTree as ElementTree
import zipfile
from pathlib import Path

import numpy as np

from activecontour.curve import as_curve, from_xy, signed_area, to_xy
from activecontour.image import load_image, normalize_image

__all__ = [
    "COLORS",
    "CONTOUR_FORMATS",
    "CONVENTION",
    "output_paths",
    "read_contours",
    "read_mask",
    "read_metadata",
    "save_result",
    "write_contours",
    "write_mask",
    "write_overlay",
]

#: File suffix (without the dot) -> contour format.
CONTOUR_FORMATS = ("json", "geojson", "svg", "csv", "npz")

#: The coordinate convention, written into every contour file.
CONVENTION = (
    "points are (row, col) with pixel centres at integer coordinates, each vertex stored once; "
    "outer boundaries have positive signed area 0.5*sum(r_i*c_{i+1} - r_{i+1}*c_i), holes negative"
)
_GEOJSON_CONVENTION = (
    "image coordinates x = col, y = row, pixel centres at integers (not geographic); rings closed "
    "and oriented by the right-hand rule of RFC 7946 in the (x, y) plane"
)
_FORMAT_TAG = "activecontour-contours"
_MASK_SUFFIXES = (".png", ".tif", ".tiff", ".bmp")
_SVG_NS = "http://www.w3.org/2000/svg"

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


# --------------------------------------------------------------------------------------------- masks


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
    _atomic_write(path, _encode_mask(path, mask))
    return path


def read_mask(path):
    """Read a mask image: nonzero pixels are inside.

    Parameters
    ----------
    path : str or os.PathLike
        Any image :func:`activecontour.image.load_image` reads.  Gray images are used as they are; a
        gray + alpha image by its gray channel; an RGB or RGBA image is inside where any of R, G, B
        is nonzero (the alpha channel is ignored).

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
    image = load_image(path)
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


def _encode_mask(path, mask):
    import cv2

    suffix = Path(path).suffix.lower()
    if suffix not in _MASK_SUFFIXES:
        raise ValueError(f"mask file must end in one of {_MASK_SUFFIXES}, got {os.fspath(path)!r}")
    mask = np.asarray(mask)
    if mask.ndim != 2 or mask.size == 0:
        raise ValueError(f"mask must be a 2-D array of shape (M, N), got shape {mask.shape}")
    if mask.dtype != bool:
        if not (np.issubdtype(mask.dtype, np.number) and np.all(np.isfinite(mask))):
            raise ValueError("mask must be a bool array (or numbers, nonzero = inside) without NaN")
        mask = mask != 0
    ok, buffer = cv2.imencode(suffix, np.where(mask, 255, 0).astype(np.uint8))
    if not ok:
        raise ValueError(f"OpenCV could not encode a mask as {suffix}")
    return buffer.tobytes()


# ------------------------------------------------------------------------------------------ overlays


def write_overlay(path, image, contours, *, color="red", thickness=1):
    """Draw the contours on the image and write it as an 8-bit RGB image (PNG recommended).

    Parameters
    ----------
    path : str or os.PathLike
    image : ndarray of shape (M, N) or (M, N, C)
        Gray or colour image, normalised as by :func:`activecontour.image.normalize_image` (integer
        dtypes by their range; floats as given, clipped to [0, 1], or stretched from their
        min..max when they fall outside it).
    contours : list of ndarray (K, 2), or a SegmentationResult
        Closed curves in (row, col); drawn anti-aliased at sub-pixel precision.
    color : str or (int, int, int)
        A name from :data:`COLORS` or an RGB triple in 0..255.
    thickness : int
        Line width in pixels, >= 1.

    Returns
    -------
    pathlib.Path
    """
    path = Path(path)
    _atomic_write(path, _encode_overlay(path, image, contours, color, thickness))
    return path


def _render_overlay(image, contours, color="red", thickness=1):
    """The overlay as an (M, N, 3) uint8 RGB array."""
    import cv2

    rgb = _display_rgb(image)
    curves = _as_curve_list(_contours_of(contours))
    if isinstance(thickness, bool) or not isinstance(thickness, (int, np.integer)) or thickness < 1:
        raise ValueError(f"thickness must be an integer >= 1, got {thickness!r}")
    polylines = [
        np.round(to_xy(curve) * (1 << _DRAW_SHIFT)).astype(np.int32).reshape(-1, 1, 2)
        for curve in curves
    ]
    if polylines:
        cv2.polylines(rgb, polylines, True, _rgb_color(color), int(thickness), cv2.LINE_AA,
                      _DRAW_SHIFT)
    return rgb


def _encode_overlay(path, image, contours, color, thickness):
    import cv2

    suffix = Path(path).suffix.lower()
    if suffix not in _MASK_SUFFIXES:
        raise ValueError(
            f"overlay file must end in one of {_MASK_SUFFIXES}, got {os.fspath(path)!r}"
        )
    rgb = _render_overlay(image, contours, color, thickness)
    ok, buffer = cv2.imencode(suffix, np.ascontiguousarray(rgb[:, :, ::-1]))  # OpenCV wants BGR
    if not ok:
        raise ValueError(f"OpenCV could not encode an overlay as {suffix}")
    return buffer.tobytes()


def _display_rgb(image):
    values = normalize_image(image, color="vector", normalize="dtype")
    low, high = float(values.min()), float(values.max())
    if low < 0.0 or high > 1.0:
        # float images outside [0, 1] (e.g. 0..255 floats) are shown from their own range
        values = (values - low) / (high - low) if high > low else np.zeros_like(values)
    if values.shape[2] == 1:
        values = np.repeat(values, 3, axis=2)
    return np.ascontiguousarray(np.round(np.clip(values, 0.0, 1.0) * 255.0).astype(np.uint8))


def _rgb_color(color):
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


# ------------------------------------------------------------------------------------------ contours


def write_contours(path, contours, *, metadata=None, image_shape=None, fmt=None):
    """Write contours, with their metadata, in the format given by the file's suffix.

    Parameters
    ----------
    path : str or os.PathLike
        Ends in ``.json``, ``.geojson``, ``.svg``, ``.csv`` or ``.npz`` (see the module docstring).
    contours : SegmentationResult, list of ndarray (K, 2), or one ndarray (K, 2)
        Closed curves in (row, col).  From a result, the metadata also records the image shape,
        ``c_in``, ``c_out``, ``energy``, ``n_iter``, ``backend``, ``success`` and ``message``.
        A repeated closing vertex is dropped.
    metadata : dict, optional
        More JSON-serialisable entries (e.g. the source image and the parameters); they override
        those taken from a result.
    image_shape : (M, N), optional
        The image's shape, when ``contours`` is not a result; SVG uses it for its size (otherwise
        the contours' extent).
    fmt : str, optional
        One of :data:`CONTOUR_FORMATS`, overriding the suffix.

    Returns
    -------
    pathlib.Path
    """
    path = Path(path)
    _atomic_write(path, _encode_contours(path, contours, metadata, image_shape, fmt))
    return path


def read_contours(path):
    """Read contours written by :func:`write_contours` (or any GeoJSON polygon file).

    Parameters
    ----------
    path : str or os.PathLike
        A ``.json``, ``.geojson``, ``.svg``, ``.csv`` or ``.npz`` file.

    Returns
    -------
    list of ndarray (K, 2)
        The curves in (row, col), exactly as written and in the same order.  Rings of a GeoJSON file
        from elsewhere are oriented on reading: outer boundaries positive, holes negative.

    Raises
    ------
    FileNotFoundError
        For a missing file.
    ValueError
        For an unknown suffix or a file that is not a valid contour file.
    """
    return _read(path)[0]


def read_metadata(path):
    """The metadata dict stored in a contour file (``{}`` when it holds none)."""
    return _read(path)[1]


def _encode_contours(path, contours, metadata, image_shape, fmt):
    fmt = _format_of(path, fmt)
    curves = _as_curve_list(_contours_of(contours))
    meta = _metadata_of(contours, metadata, image_shape)
    encoder = {
        "json": _json_bytes,
        "geojson": _geojson_bytes,
        "svg": _svg_bytes,
        "csv": _csv_bytes,
        "npz": _npz_bytes,
    }[fmt]
    return encoder(curves, meta)


def _format_of(path, fmt):
    if fmt is None:
        fmt = Path(path).suffix.lower().lstrip(".")
        if fmt not in CONTOUR_FORMATS:
            raise ValueError(
                f"contour file {os.fspath(path)!r} must end in one of "
                f"{tuple('.' + f for f in CONTOUR_FORMATS)}"
            )
    elif fmt not in CONTOUR_FORMATS:
        raise ValueError(f"fmt must be one of {CONTOUR_FORMATS}, got {fmt!r}")
    return fmt


def _contours_of(contours):
    if hasattr(contours, "contours") and hasattr(contours, "mask"):
        return contours.contours
    if isinstance(contours, np.ndarray) and contours.ndim == 2:
        return [contours]
    return contours


def _as_curve_list(contours):
    if isinstance(contours, (str, bytes)) or not hasattr(contours, "__iter__"):
        raise TypeError("contours must be a list of (K, 2) arrays in (row, col)")
    return [as_curve(curve, name=f"contour {i}") for i, curve in enumerate(contours)]


def _metadata_of(contours, metadata, image_shape):
    meta = {}
    if hasattr(contours, "contours") and hasattr(contours, "mask"):
        result = contours
        meta["image_shape"] = list(np.shape(result.mask))
        for name in ("backend", "n_iter", "energy", "c_in", "c_out", "success", "status", "message"):
            if hasattr(result, name):
                meta[name] = getattr(result, name)
    if image_shape is not None:
        shape = tuple(int(v) for v in image_shape)
        if len(shape) != 2 or min(shape) < 1:
            raise ValueError(f"image_shape must be (M, N) with M, N >= 1, got {image_shape!r}")
        meta["image_shape"] = list(shape)
    if metadata is not None:
        if not isinstance(metadata, dict):
            raise TypeError(f"metadata must be a dict, got {type(metadata).__name__}")
        meta.update(metadata)
    meta = _jsonable(meta)
    try:
        json.dumps(meta, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"metadata must be JSON-serialisable without NaN: {exc}") from None
    return meta


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    return value


def _points_list(curve):
    return [[float(r), float(c)] for r, c in curve]


def _json_bytes(curves, meta):
    document = {
        "format": _FORMAT_TAG,
        "version": 1,
        "convention": CONVENTION,
        "metadata": meta,
        "contours": [
            {
                "kind": "outer" if signed_area(curve) > 0 else "hole",
                "signed_area": signed_area(curve),
                "points": _points_list(curve),
            }
            for curve in curves
        ],
    }
    return (json.dumps(document, allow_nan=False) + "\n").encode()


def _reverse_keep_first(curve):
    """The same closed curve traversed the other way, starting at the same vertex (an involution)."""
    return np.concatenate([curve[:1], curve[:0:-1]])


def _group_polygons(curves):
    """Indices grouped as [outer, hole, hole, ...] per polygon: each hole goes to the smallest
    outer boundary containing it."""
    areas = [signed_area(curve) for curve in curves]
    outers = [i for i, a in enumerate(areas) if a > 0]
    groups = {i: [i] for i in outers}
    for i, area in enumerate(areas):
        if area > 0:
            continue
        containing = [j for j in outers if areas[j] > -area and _contains(curves[j], curves[i])]
        if not containing:
            raise ValueError(
                f"contour {i} is a hole (negative signed area) but lies inside no outer boundary"
            )
        groups[min(containing, key=lambda j: areas[j])].append(i)
    return [groups[i] for i in outers]


def _contains(outer, inner):
    """Whether most of ``inner``'s vertices (up to 16 of them) lie inside ``outer``."""
    from activecontour.topology import winding_number

    points = inner[:: max(1, len(inner) // 16)]
    next_index = np.roll(np.arange(len(outer)), -1)
    inside = winding_number(outer, next_index, points) != 0
    return np.count_nonzero(inside) * 2 > len(points)


def _geojson_bytes(curves, meta):
    groups = _group_polygons(curves)
    polygons = []
    for group in groups:
        rings = []
        for i in group:
            # (row, col) orientation is the reverse of the (x, y) one: reversing makes the outer
            # rings counterclockwise in (x, y), as RFC 7946 asks
            xy = to_xy(_reverse_keep_first(curves[i]))
            rings.append(_points_list(np.vstack([xy, xy[:1]])))
        polygons.append(rings)
    properties = dict(meta)
    properties.update(convention=_GEOJSON_CONVENTION, contour_index=groups)
    document = {
        "type": "FeatureCollection",
        "features": [
            {
                "type": "Feature",
                "properties": properties,
                "geometry": {"type": "MultiPolygon", "coordinates": polygons},
            }
        ],
    }
    return (json.dumps(document, allow_nan=False) + "\n").encode()


def _svg_bytes(curves, meta):
    if "image_shape" in meta:
        height, width = (int(v) for v in meta["image_shape"])
    elif curves:
        extent = np.max(np.vstack(curves), axis=0)
        height, width = (max(1, int(np.ceil(v + 0.5))) for v in extent)
    else:
        height = width = 1
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="{_SVG_NS}" width="{width}" height="{height}" '
        f'viewBox="-0.5 -0.5 {width} {height}">',
        f"<metadata>{_xml_escape(json.dumps({'convention': CONVENTION, **meta}))}</metadata>",
    ]
    for group in _group_polygons(curves):
        parts = []
        for i in group:
            xy = to_xy(curves[i])
            coordinates = " ".join(f"{x!r},{y!r}" for x, y in xy.tolist())
            parts.append(f"M {coordinates} Z")
        lines.append(
            f'<path data-contours="{" ".join(map(str, group))}" fill="red" fill-opacity="0.3" '
            f'stroke="red" stroke-width="1" fill-rule="nonzero" d="{" ".join(parts)}"/>'
        )
    lines.append("</svg>")
    return ("\n".join(lines) + "\n").encode()


def _xml_escape(text):
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def _csv_bytes(curves, meta):
    lines = [
        f"# {_FORMAT_TAG}: {CONVENTION}",
        f"# metadata: {json.dumps(meta, allow_nan=False)}",
        "contour,vertex,row,col",
    ]
    for i, curve in enumerate(curves):
        lines.extend(f"{i},{k},{r!r},{c!r}" for k, (r, c) in enumerate(curve.tolist()))
    return ("\n".join(lines) + "\n").encode()


def _npz_bytes(curves, meta):
    arrays = {f"contour_{i}": curve for i, curve in enumerate(curves)}
    arrays["metadata"] = np.array(json.dumps({"convention": CONVENTION, **meta}))
    buffer = _stdio.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


# --------------------------------------------------------------------------------- reading contours


def _read(path):
    fmt = _format_of(path, None)
    path = os.fspath(path)
    if not os.path.exists(path):
        raise FileNotFoundError(f"contour file not found: {path!r}")
    if os.path.isdir(path):
        raise ValueError(f"contour path is a directory, not a file: {path!r}")
    reader = {
        "json": _read_json,
        "geojson": _read_geojson,
        "svg": _read_svg,
        "csv": _read_csv,
        "npz": _read_npz,
    }[fmt]
    try:
        curves, meta = reader(path)
    except (ValueError, KeyError, TypeError, IndexError, AttributeError, OSError, EOFError,
            ElementTree.ParseError, zipfile.BadZipFile) as exc:
        if isinstance(exc, ValueError) and str(exc).startswith("contour file"):
            raise
        raise ValueError(f"contour file {path!r} is not a valid {fmt} contour file: {exc}") from None
    curves = [np.asarray(curve, dtype=np.float64).reshape(-1, 2) for curve in curves]
    for i, curve in enumerate(curves):
        if len(curve) < 3 or not np.all(np.isfinite(curve)):
            raise ValueError(f"contour file {path!r}: contour {i} is not a closed curve of >= 3 points")
    return curves, meta


def _load_json(path):
    with open(path, encoding="utf-8") as handle:
        return json.load(handle)


def _read_json(path):
    document = _load_json(path)
    if not isinstance(document, dict) or document.get("format") != _FORMAT_TAG:
        raise ValueError(f"contour file {path!r} was not written by activecontour (no format tag)")
    curves = [np.array(entry["points"], dtype=np.float64) for entry in document["contours"]]
    return curves, dict(document.get("metadata", {}))


def _read_geojson(path):
    document = _load_json(path)
    geometries = []
    meta = {}
    if document.get("type") == "FeatureCollection":
        features = document["features"]
    elif document.get("type") == "Feature":
        features = [document]
    else:
        features = [{"geometry": document, "properties": {}}]
    order = None
    for feature in features:
        geometries.append(feature["geometry"])
        properties = feature.get("properties") or {}
        if len(features) == 1:
            meta = {k: v for k, v in properties.items() if k not in ("convention", "contour_index")}
            order = properties.get("contour_index")
    curves = []
    for geometry in geometries:
        if geometry["type"] == "Polygon":
            polygons = [geometry["coordinates"]]
        elif geometry["type"] == "MultiPolygon":
            polygons = geometry["coordinates"]
        else:
            raise ValueError(f"geometry type {geometry['type']!r} is not Polygon or MultiPolygon")
        for polygon in polygons:
            for k, ring in enumerate(polygon):
                ring = np.array(ring, dtype=np.float64)
                if len(ring) > 1 and np.array_equal(ring[0], ring[-1]):
                    ring = ring[:-1]
                curve = from_xy(ring[:, :2])
                if (signed_area(curve) > 0) != (k == 0):
                    curve = _reverse_keep_first(curve)
                curves.append(curve)
    if order is not None:
        flat = [i for group in order for i in group]
        if sorted(flat) == list(range(len(curves))):
            restored = [None] * len(curves)
            for position, i in enumerate(flat):
                restored[i] = curves[position]
            curves = restored
    return curves, meta


def _read_svg(path):
    root = ElementTree.parse(path).getroot()
    meta = {}
    found = root.find(f"{{{_SVG_NS}}}metadata")
    if found is not None and found.text:
        meta = json.loads(found.text)
        meta.pop("convention", None)
    curves, order = [], []
    for element in root.iter(f"{{{_SVG_NS}}}path"):
        indices = element.get("data-contours")
        subpaths = re.findall(r"M([^MZ]*)Z", element.get("d", ""))
        if indices is None or not subpaths:
            raise ValueError("only SVG files written by activecontour can be read")
        for subpath in subpaths:
            numbers = [float(v) for v in re.split(r"[\s,]+", subpath.strip())]
            curves.append(from_xy(np.array(numbers).reshape(-1, 2)))
        order.extend(int(i) for i in indices.split())
    restored = [None] * len(curves)
    for position, i in enumerate(order):
        restored[i] = curves[position]
    return restored, meta


def _read_csv(path):
    meta = {}
    rows = {}
    with open(path, encoding="utf-8") as handle:
        lines = handle.read().splitlines()
    body = []
    for line in lines:
        if line.startswith("# metadata:"):
            meta = json.loads(line[len("# metadata:"):])
        elif line.strip() and not line.startswith("#"):
            body.append(line)
    if not body or body[0].replace(" ", "") != "contour,vertex,row,col":
        raise ValueError("expected the header 'contour,vertex,row,col'")
    for line in body[1:]:
        contour, _vertex, row, col = line.split(",")
        rows.setdefault(int(contour), []).append((float(row), float(col)))
    if sorted(rows) != list(range(len(rows))):
        raise ValueError("contour numbers must be 0, 1, 2, ...")
    return [rows[i] for i in range(len(rows))], meta


def _read_npz(path):
    with np.load(path, allow_pickle=False) as data:
        keys = [k for k in data.files if k.startswith("contour_")]
        numbers = sorted(int(k[len("contour_"):]) for k in keys)
        if numbers != list(range(len(numbers))):
            raise ValueError("arrays must be named contour_0, contour_1, ...")
        curves = [np.array(data[f"contour_{i}"], dtype=np.float64) for i in numbers]
        meta = json.loads(str(data["metadata"])) if "metadata" in data.files else {}
    meta.pop("convention", None)
    return curves, meta


# --------------------------------------------------------------------------------------- the group


def save_result(result, image, output_stem, formats=("json",), *, metadata=None, color="red",
                thickness=1, protect=()):
    """Write a result's mask, overlay and contours as a group: all of them, or none.

    Parameters
    ----------
    result : SegmentationResult
    image : ndarray of shape (M, N) or (M, N, C)
        The image that was segmented, for the overlay.
    output_stem : str or os.PathLike
        The files are ``<stem>_mask.png``, ``<stem>_overlay.png`` and ``<stem>_contours.<fmt>``;
        the directory must exist.
    formats : sequence of str
        Contour formats, from :data:`CONTOUR_FORMATS` (may be empty).
    metadata : dict, optional
        Extra entries for the contour files (see :func:`write_contours`).
    color, thickness
        Of the overlay's contour lines (see :func:`write_overlay`).
    protect : sequence of path
        Files that must not be overwritten (e.g. the input image): ValueError if an output is one.

    Returns
    -------
    list of pathlib.Path
        The paths written: mask, overlay, then one per format.

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
    for fmt in formats:
        if fmt not in CONTOUR_FORMATS:
            raise ValueError(f"formats must be chosen from {CONTOUR_FORMATS}, got {fmt!r}")
    mask = np.asarray(result.mask)
    if np.shape(image)[:2] != mask.shape:
        raise ValueError(
            f"image has shape {np.shape(image)}, but the result's mask has shape {mask.shape}"
        )
    paths = output_paths(output_stem, formats)
    protected = [Path(p) for p in protect]
    for path in paths:
        if any(_same_file(path, other) for other in protected):
            raise ValueError(f"refusing to overwrite the input file {os.fspath(path)!r}")
    contents = [
        _encode_mask(paths[0], mask),
        _encode_overlay(paths[1], image, result, color, thickness),
    ]
    contents += [
        _encode_contours(path, result, metadata, None, fmt)
        for path, fmt in zip(paths[2:], formats, strict=True)
    ]
    _atomic_write_group(list(zip(paths, contents, strict=True)))
    return paths


def output_paths(output_stem, formats=("json",)):
    """The files :func:`save_result` writes for a stem: mask, overlay, then one per format."""
    stem = os.fspath(output_stem)
    formats = list(dict.fromkeys([formats] if isinstance(formats, str) else formats))
    return [Path(f"{stem}_mask.png"), Path(f"{stem}_overlay.png")] + [
        Path(f"{stem}_contours.{fmt}") for fmt in formats
    ]


def _same_file(a, b):
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.abspath(a) == os.path.abspath(b)


# ------------------------------------------------------------------------------------ atomic writes


def _temporary_copy(path, data):
    """Write ``data`` to a new temporary file next to ``path``; return its name."""
    directory = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(directory):
        raise FileNotFoundError(f"output directory does not exist: {directory!r}")
    handle, temporary = tempfile.mkstemp(
        prefix=f".{os.path.basename(path)}.", suffix=".part", dir=directory
    )
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
            stream.flush()
            os.fsync(stream.fileno())
        # mkstemp creates the file 0600; give it the permissions an ordinary new file would get
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(temporary, 0o666 & ~umask)
    except BaseException:
        _remove_quietly(temporary)
        raise
    return temporary


def _atomic_write(path, data):
    _atomic_write_group([(Path(path), data)])


def _atomic_write_group(items):
    """Write several files all or nothing: temporary files first, then one rename each; on a
    failure the renamed ones are removed and the files they replaced are restored."""
    for path, _ in items:
        if os.path.isdir(path):
            raise IsADirectoryError(f"output path is a directory: {os.fspath(path)!r}")
    temporaries, backups, placed = [], [], []
    try:
        for path, data in items:
            temporaries.append(_temporary_copy(path, data))
        for (path, _), temporary in zip(items, temporaries, strict=True):
            if os.path.lexists(path):
                backup = _temporary_copy(path, b"")
                os.replace(path, backup)
                backups.append((path, backup))
            os.replace(temporary, path)
            placed.append(path)
    except BaseException:
        for path in placed:
            _remove_quietly(path)
        for path, backup in backups:
            try:
                os.replace(backup, path)
            except OSError:
                pass
        for temporary in temporaries:
            _remove_quietly(temporary)
        raise
    for _, backup in backups:
        _remove_quietly(backup)


def _remove_quietly(path):
    try:
        os.remove(path)
    except OSError:
        pass
