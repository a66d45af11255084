"""The (x, y) contour formats, GeoJSON and SVG: polygons of an outer boundary and its holes.

Both use image coordinates ``x = col, y = row`` with pixel centres at integers (converted by
:func:`activecontour.geometry.curve.to_xy`, the one place).  Each polygon is an outer boundary followed by the
holes it contains, each hole grouped with the innermost outer boundary around it.

GeoJSON rings are closed (first position repeated last) and follow the right-hand rule of RFC 7946
in the (x, y) plane: outer rings counterclockwise, holes clockwise, which is the reverse of the
(row, col) orientation of the library.  SVG paths keep the library's vertex order and are filled
with ``fill-rule="nonzero"``; the ``viewBox`` makes pixel (0, 0) cover the top-left unit square.
"""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ElementTree

import numpy as np

from activecontour.geometry.curve import from_xy, signed_area, to_xy
from activecontour.geometry.regions import group_indices

__all__ = ["geojson_bytes", "read_geojson", "read_svg", "svg_bytes"]

_GEOJSON_CONVENTION = (
    "image coordinates x = col, y = row, pixel centres at integers (not geographic); rings closed "
    "and oriented by the right-hand rule of RFC 7946 in the (x, y) plane"
)


SVG_NAMESPACE = "http://www.w3.org/2000/svg"


def _reverse_keep_first(curve):
    """The same closed curve traversed the other way, starting at the same vertex (an involution)."""
    return np.concatenate([curve[:1], curve[:0:-1]])


def _group_polygons(curves):
    """Indices grouped as [outer, hole, hole, ...] per polygon: each hole goes to the innermost
    outer boundary around it (:func:`activecontour.geometry.regions.group_indices`)."""
    groups = group_indices(curves)
    grouped = {i for group in groups for i in group}
    for i in range(len(curves)):
        if i not in grouped:
            raise ValueError(
                f"contour {i} is a hole (negative signed area) but lies inside no outer boundary")
    return groups


def geojson_bytes(curves, meta):
    """The GeoJSON FeatureCollection of the curves, one MultiPolygon, ``meta`` as properties."""
    groups = _group_polygons(curves)
    polygons = []
    for group in groups:
        rings = []
        for i in group:
            # (row, col) orientation is the reverse of the (x, y) one: reversing makes the outer
            # rings counterclockwise in (x, y), as RFC 7946 asks
            xy = to_xy(_reverse_keep_first(curves[i]))
            rings.append(np.vstack([xy, xy[:1]]).tolist())
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


def svg_bytes(curves, meta):
    """The SVG file of the curves; ``meta`` goes into its ``<metadata>`` element as JSON."""
    if "image_shape" in meta:
        height, width = (int(v) for v in meta["image_shape"])
    elif curves:
        extent = np.max(np.vstack(curves), axis=0)
        height, width = (max(1, int(np.ceil(v + 0.5))) for v in extent)
    else:
        height = width = 1
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="{SVG_NAMESPACE}" width="{width}" height="{height}" '
        f'viewBox="-0.5 -0.5 {width} {height}">',
        f"<metadata>{_xml_escape(json.dumps(meta))}</metadata>",
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


def read_geojson(document):
    """Curves and metadata of a parsed GeoJSON document (FeatureCollection, Feature or geometry)."""
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


def read_svg(path):
    """Curves and metadata of an SVG file written by :func:`svg_bytes`."""
    root = ElementTree.parse(path).getroot()
    meta = {}
    found = root.find(f"{{{SVG_NAMESPACE}}}metadata")
    if found is not None and found.text:
        meta = json.loads(found.text)
        meta.pop("convention", None)
    curves, order = [], []
    for element in root.iter(f"{{{SVG_NAMESPACE}}}path"):
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
