"""Contour files: closed curves with their metadata in five formats, read back exactly.

Points are (row, col) with pixel centres at integer coordinates, each vertex stored once (the curve
closes implicitly); outer boundaries have positive signed area, holes negative (the conventions of
:mod:`activecontour.geometry.curve`).  The format follows the file's suffix:

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
    x = col, y = row, one ``<path>`` per outer boundary with its holes, ``fill-rule="nonzero"``.
``.csv``
    Columns ``contour,vertex,row,col``; metadata on leading ``#`` lines.
``.npz``
    Arrays ``contour_0, contour_1, ...`` of shape (K, 2) and ``metadata`` (a JSON string).

Every written polygon is valid: the curves go through :func:`activecontour.geometry.curve.clean` (no
repeated vertex, no zero-width spike such as a back-step along the image border).  Floating-point
numbers are written with :func:`repr`, so :func:`read_contours` gives back exactly the arrays that
were written, in the same order, for every format.  Metadata numbers that are not finite (NaN,
inf) are written as null.
"""

from __future__ import annotations

import functools
import io as _stdio
import json
import math
import os
import zipfile
from pathlib import Path
from xml.etree.ElementTree import ParseError

import numpy as np

from activecontour.geometry.curve import as_curve, clean, signed_area
from activecontour.io.atomic import write_atomically
from activecontour.io.images import MAX_PIXELS, SizeLimitError
from activecontour.io.vector import geojson_bytes, read_geojson, read_svg, svg_bytes

__all__ = [
    "CONTOUR_FORMATS",
    "CONVENTION",
    "MAX_POINTS",
    "curve_list",
    "encode_contours",
    "read_contours",
    "read_metadata",
    "write_contours",
]

#: File suffix (without the dot) -> contour format.
CONTOUR_FORMATS = ("json", "geojson", "svg", "csv", "npz")


#: The coordinate convention, written into every contour file.
CONVENTION = (
    "points are (row, col) with pixel centres at integer coordinates, each vertex stored once; "
    "outer boundaries have positive signed area 0.5*sum(r_i*c_{i+1} - r_{i+1}*c_i), holes negative"
)


_FORMAT_TAG = "activecontour-contours"

#: The most vertices :func:`read_contours` reads by default, all curves together: as many as the
#: largest image :func:`activecontour.load_image` reads has pixels (no contour of an image needs
#: more).  An NPZ file's arrays are checked by their headers before anything is decompressed.
MAX_POINTS = MAX_PIXELS


def write_contours(path, contours, *, metadata=None, image_shape=None, fmt=None):
    """Write contours, with their metadata, in the format given by the file's suffix.

    Parameters
    ----------
    path : str or os.PathLike
        Ends in ``.json``, ``.geojson``, ``.svg``, ``.csv`` or ``.npz`` (see the module docstring).
    contours : SegmentationResult, list of ndarray (K, 2), or one ndarray (K, 2)
        Closed curves in (row, col).  From a result, the metadata also records the image shape,
        ``c_in``, ``c_out``, ``energy``, ``n_iter``, ``backend``, ``success`` and ``message``, and
        when set, ``n_regions`` and ``constants`` (one row per region).
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
    write_atomically(path, encode_contours(path, contours, metadata, image_shape, fmt))
    return path


def read_contours(path, *, max_points=MAX_POINTS):
    """Read contours written by :func:`write_contours` (or any GeoJSON polygon file).

    Parameters
    ----------
    path : str or os.PathLike
        A ``.json``, ``.geojson``, ``.svg``, ``.csv`` or ``.npz`` file.
    max_points : int or None
        Refuse a file of more vertices than this, all curves together (default
        :data:`MAX_POINTS`); None: no limit.

    Returns
    -------
    list of ndarray (K, 2)
        The curves in (row, col), exactly as written and in the same order.  Rings of a GeoJSON file
        from elsewhere are oriented on reading: outer boundaries positive, holes negative.

    Raises
    ------
    FileNotFoundError
        For a missing file.
    SizeLimitError
        For a file of more than ``max_points`` vertices (a ValueError).
    ValueError
        For an unknown suffix or a file that is not a valid contour file (nested too deeply
        included).
    """
    return _read(path, max_points)[0]


def read_metadata(path, *, max_points=MAX_POINTS):
    """The metadata dict stored in a contour file (``{}`` when it holds none); ``max_points`` as in
    :func:`read_contours`."""
    return _read(path, max_points)[1]


def encode_contours(path, contours, metadata, image_shape, fmt):
    """The bytes of the contour file ``path``, for :func:`write_contours`."""
    fmt = _format_of(path, fmt)
    curves = curve_list(contours)
    meta = _metadata_of(contours, metadata, image_shape)
    if fmt == "svg":
        return svg_bytes(curves, {"convention": CONVENTION, **meta})
    encoder = {"json": _json_bytes, "geojson": geojson_bytes, "csv": _csv_bytes, "npz": _npz_bytes}[fmt]
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


def curve_list(contours):
    """The curves of a result, a list of (K, 2) arrays or one array, validated and cleaned.

    Raises
    ------
    TypeError
        For something that is not a list of curves.
    ValueError
        Naming the contour, for one that is not a closed curve
        (:func:`~activecontour.geometry.curve.as_curve`) or has nothing left after
        :func:`~activecontour.geometry.curve.clean` (all spike, no area).
    """
    if hasattr(contours, "contours") and hasattr(contours, "mask"):
        contours = contours.contours
    elif isinstance(contours, np.ndarray) and contours.ndim == 2:
        contours = [contours]
    if isinstance(contours, (str, bytes)) or not hasattr(contours, "__iter__"):
        raise TypeError("contours must be a list of (K, 2) arrays in (row, col)")
    curves = []
    for i, curve in enumerate(contours):
        cleaned = clean(as_curve(curve, name=f"contour {i}"))
        if cleaned is None:
            raise ValueError(f"contour {i} is degenerate: it encloses no area once its zero-width "
                             "spikes are removed")
        curves.append(cleaned)
    return curves


def _metadata_of(contours, metadata, image_shape):
    meta = {}
    if hasattr(contours, "contours") and hasattr(contours, "mask"):
        result = contours
        meta["image_shape"] = list(np.shape(result.mask))
        for name in ("backend", "n_iter", "energy", "mu", "c_in", "c_out", "success", "status",
                     "message"):
            if hasattr(result, name):
                meta[name] = getattr(result, name)
        for name in ("n_regions", "constants"):  # the regions' count and constants (K, C)
            if getattr(result, name, None) is not None:
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
        raise ValueError(f"metadata must be JSON-serialisable: {exc}") from None
    return meta


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, np.generic):
        return _jsonable(value.item())
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if isinstance(value, float) and not math.isfinite(value):
        return None  # JSON has no NaN or inf
    return value


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
                "points": curve.tolist(),
            }
            for curve in curves
        ],
    }
    return (json.dumps(document, allow_nan=False) + "\n").encode()


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
    """An uncompressed NPZ, as :func:`numpy.savez` writes it but with a fixed time stamp on its
    entries, so that the same contours give the same bytes whenever they are written."""
    from numpy.lib import format as npy

    arrays = {f"contour_{i}": curve for i, curve in enumerate(curves)}
    arrays["metadata"] = np.array(json.dumps({"convention": CONVENTION, **meta}))
    buffer = _stdio.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_STORED, allowZip64=True) as archive:
        for name, array in arrays.items():
            entry = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            with archive.open(entry, "w", force_zip64=True) as member:
                npy.write_array(member, np.asanyarray(array), allow_pickle=False)
    return buffer.getvalue()


def _read(path, max_points):
    fmt = _format_of(path, None)
    path = os.fspath(path)
    if not os.path.exists(path):
        raise FileNotFoundError(f"contour file not found: {path!r}")
    if os.path.isdir(path):
        raise ValueError(f"contour path is a directory, not a file: {path!r}")
    reader = {
        "json": _read_json,
        "geojson": lambda path: read_geojson(_load_json(path)),
        "svg": read_svg,
        "csv": _read_csv,
        "npz": functools.partial(_read_npz, max_points=max_points),
    }[fmt]
    try:
        curves, meta = reader(path)
    except RecursionError:
        raise ValueError(f"contour file {path!r} is nested too deeply to be a contour file") from None
    except (ValueError, KeyError, TypeError, IndexError, AttributeError, OSError, EOFError,
            ParseError, zipfile.BadZipFile) as exc:
        if isinstance(exc, ValueError) and str(exc).startswith("contour file"):
            raise
        raise ValueError(f"contour file {path!r} is not a valid {fmt} contour file: {exc}") from None
    points = sum(len(curve) for curve in curves)
    if max_points is not None and points > max_points:
        raise SizeLimitError(f"contour file {path!r} holds {points:,} vertices, more than the limit "
                             f"of {max_points:,} (max_points)")
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


def _read_npz(path, *, max_points):
    if max_points is not None:
        _check_npz_headers(path, max_points)
    with np.load(path, allow_pickle=False) as data:
        keys = [k for k in data.files if k.startswith("contour_")]
        numbers = sorted(int(k[len("contour_"):]) for k in keys)
        if numbers != list(range(len(numbers))):
            raise ValueError("arrays must be named contour_0, contour_1, ...")
        curves = [np.array(data[f"contour_{i}"], dtype=np.float64) for i in numbers]
        meta = json.loads(str(data["metadata"])) if "metadata" in data.files else {}
    meta.pop("convention", None)
    return curves, meta


def _check_npz_headers(path, max_points):
    """Refuse an NPZ whose arrays declare more than ``max_points`` vertices (or a metadata text
    larger than 64 MB), from the arrays' headers: nothing is decompressed beyond them."""
    from numpy.lib import format as npy

    points, text_bytes = 0, 0
    with zipfile.ZipFile(path) as archive:
        for info in archive.infolist():
            with archive.open(info) as member:
                version = npy.read_magic(member)
                read_header = npy.read_array_header_1_0 if version == (1, 0) else npy.read_array_header_2_0
                shape, _, dtype = read_header(member)
            count = math.prod(shape)
            if info.filename.startswith("contour_"):
                points += count // 2
            else:
                text_bytes += count * dtype.itemsize
    if points > max_points:
        raise SizeLimitError(f"contour file {path!r} declares {points:,} vertices, more than the limit "
                             f"of {max_points:,} (max_points)")
    if text_bytes > 2**26:
        raise SizeLimitError(f"contour file {path!r} declares {text_bytes:,} bytes of metadata, more "
                             f"than the limit of {2**26:,}")
