"""The objects of a result in the formats other tools read: label image, GeoJSON, ImageJ ROIs, CSV.

=====================  ==============================  =============================================
format name            file                            read by
=====================  ==============================  =============================================
``labels``             ``<stem>_labels.png``           napari (Labels layer), CellProfiler, skimage:
                                                       16-bit gray, 0 = background, pixel = id
``labels-tif``         ``<stem>_labels.tif``           the same as 32-bit TIFF, for > 65535 objects
``geojson``            ``<stem>_objects.geojson``      QGIS, QuPath, shapely: one Feature per object
                                                       (its Polygon, holes included) with its
                                                       measurements as properties
``roi``                ``<stem>_rois.zip``             ImageJ/Fiji ROI Manager: one sub-pixel
                                                       polygon ROI per object (its outer boundary),
                                                       named by its id, written with ``roifile``
``csv``                ``<stem>_objects.csv``          pandas, spreadsheets: the measurement table
``classes``            ``<stem>_classes.png``          the same tools as ``labels``: 16-bit gray,
                                                       pixel = its region (``result.classes``: 0 =
                                                       background, the others by mean intensity)
=====================  ==============================  =============================================

Coordinates: GeoJSON uses the image coordinates of :mod:`activecontour.io.vector` (x = col,
y = row, pixel centres at integers); ImageJ puts the top-left corner of pixel (0, 0) at (0, 0),
so its coordinates are ``x = col + 0.5, y = row + 0.5``.  An ImageJ polygon ROI has no holes: an
object's holes are in the label image and the GeoJSON, not in its ROI.
"""

from __future__ import annotations

import io
import json
import zipfile

import numpy as np

from activecontour.geometry.curve import to_xy

__all__ = ["OBJECT_FORMATS", "encode_objects", "encode_table", "object_paths", "read_label_image",
           "read_objects_csv", "read_objects_geojson"]

#: format name -> file name suffix after the stem
OBJECT_FORMATS = {
    "labels": "_labels.png",
    "labels-tif": "_labels.tif",
    "geojson": "_objects.geojson",
    "roi": "_rois.zip",
    "csv": "_objects.csv",
    "classes": "_classes.png",
}

#: ImageJ's coordinates of our pixel centre (0, 0): the centre of its pixel square.
IMAGEJ_OFFSET = 0.5


def object_paths(output_stem, formats):
    """The files :func:`encode_objects` writes for a stem, one per format, in order."""
    from pathlib import Path

    return [Path(f"{output_stem}{OBJECT_FORMATS[fmt]}") for fmt in _check_formats(formats)]


def _check_formats(formats):
    formats = list(dict.fromkeys([formats] if isinstance(formats, str) else formats))
    for fmt in formats:
        if fmt not in OBJECT_FORMATS:
            raise ValueError(f"object formats must be chosen from {tuple(OBJECT_FORMATS)}, got {fmt!r}")
    return formats


def encode_objects(result, fmt):
    """The bytes of one object file of a result (see the module docstring for the formats)."""
    (fmt,) = _check_formats([fmt])
    if result.labels is None:
        raise ValueError("the result has no objects (it was not made by activecontour.segment)")
    if fmt == "labels":
        return _label_png(result.labels)
    if fmt == "classes":
        return _label_png(result.classes)
    if fmt == "labels-tif":
        return _label_tiff(result.labels)
    if fmt == "geojson":
        return _geojson(result.object_contours, result.objects)
    if fmt == "roi":
        return _roi_zip(result.object_contours, result.objects["label"])
    return encode_table(result.objects)


def _label_png(labels):
    import cv2

    if labels.max(initial=0) > np.iinfo(np.uint16).max:
        raise ValueError(f"{int(labels.max())} objects do not fit a 16-bit PNG: use the 'labels-tif' "
                         "object format")
    ok, buffer = cv2.imencode(".png", labels.astype(np.uint16))
    if not ok:
        raise ValueError("OpenCV could not encode the label image as PNG")
    return buffer.tobytes()


def _label_tiff(labels):
    import tifffile

    buffer = io.BytesIO()
    tifffile.imwrite(buffer, labels.astype(np.int32), compression="zlib")
    return buffer.getvalue()


def read_label_image(path):
    """A label image written by :func:`encode_objects` (PNG or TIFF), as int32."""
    from activecontour.io.images import load_image

    return np.asarray(load_image(path)).astype(np.int32)


def _rows(table):
    """The table's rows as dicts of plain Python numbers (JSON and CSV take them)."""
    names = list(table)
    columns = [np.asarray(table[name]) for name in names]
    for i in range(len(columns[0]) if columns else 0):
        yield {name: column[i].item() for name, column in zip(names, columns, strict=True)}


def _geojson(objects, table):
    features = []
    for curves, properties in zip(objects, _rows(table), strict=True):
        # (row, col) orientation is the reverse of the (x, y) one: reversed rings follow RFC 7946
        rings = [to_xy(curve[::-1]) for curve in curves]
        features.append({
            "type": "Feature", "id": properties["label"], "properties": properties,
            "geometry": {"type": "Polygon",
                         "coordinates": [np.vstack([xy, xy[:1]]).tolist() for xy in rings]},
        })
    document = {"type": "FeatureCollection", "features": features}
    return (json.dumps(document, allow_nan=False) + "\n").encode()


def read_objects_geojson(path):
    """The objects of a GeoJSON file written by :func:`encode_objects`: (ids, list of curves per
    object in (row, col), oriented as the library's, the properties of each)."""
    from activecontour.geometry.curve import from_xy

    with open(path, encoding="utf-8") as handle:
        document = json.load(handle)
    ids, objects, properties = [], [], []
    for feature in document["features"]:
        ids.append(feature["id"])
        objects.append([from_xy(np.asarray(ring, dtype=np.float64)[:-1])[::-1]
                        for ring in feature["geometry"]["coordinates"]])
        properties.append(feature["properties"])
    return ids, objects, properties


def _roi_zip(objects, ids):
    import roifile

    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for curves, label in zip(objects, ids, strict=True):
            name = f"{int(label):05d}"
            roi = roifile.ImagejRoi.frompoints(to_xy(curves[0]) + IMAGEJ_OFFSET, name=name)
            roi.roitype = roifile.ROI_TYPE.POLYGON
            # a fixed date (zip's earliest): the same objects give the same bytes, whenever written
            member = zipfile.ZipInfo(f"{name}.roi", date_time=(1980, 1, 1, 0, 0, 0))
            archive.writestr(member, roi.tobytes(), compress_type=zipfile.ZIP_DEFLATED)
    return buffer.getvalue()


def encode_table(table):
    """A table (dict of 1-D arrays, one row per object) as CSV bytes: a header of the column
    names, floats written exactly (repr)."""
    import csv

    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=list(table), lineterminator="\n")
    writer.writeheader()
    for row in _rows(table):
        writer.writerow({k: repr(v) if isinstance(v, float) else v for k, v in row.items()})
    return text.getvalue().encode()


def read_objects_csv(path):
    """The measurement table of a CSV written by :func:`encode_objects`: a dict of 1-D arrays."""
    import csv

    with open(path, newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    if not rows:
        return {}
    return {name: np.array([float(row[name]) for row in rows]) for name in rows[0]}
