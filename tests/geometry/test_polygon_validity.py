"""Every written polygon is valid (shapely): on real results of both backends, and on a contour
with a zero-width back-step along the image border; NaN metadata is written as null."""

import json
import re

import numpy as np
import pytest
import shapely
import skimage.data
from shapely.geometry import MultiPolygon, Polygon, shape

import activecontour as ac
from activecontour import io
from activecontour.geometry.curve import signed_area, to_xy


@pytest.fixture(scope="module", params=["polygon", "levelset"])
def blobs_result(request):
    # the same hundred blobs at any length (their size scales with it): 14 outlines and a hole at 128 px
    image = skimage.data.binary_blobs(length=128, rng=1)
    return image, ac.segment(image, "grid", backend=request.param)


def geojson_geometry(path):
    (feature,) = json.loads(path.read_text())["features"]
    return shape(feature["geometry"])


def svg_geometry(path):
    """The SVG paths as shapely polygons in (x, y), each path an outer ring and its holes."""
    polygons = []
    for d in re.findall(r' d="([^"]*)"', path.read_text()):
        rings = [np.array([float(v) for v in re.split(r"[\s,]+", sub.strip())]).reshape(-1, 2)
                 for sub in re.findall(r"M([^MZ]*)Z", d)]
        polygons.append(Polygon(rings[0], rings[1:]))
    return MultiPolygon(polygons)


def nested_geometry(curves):
    """(row, col) curves as one shapely MultiPolygon in (x, y): each hole (negative signed area)
    with the smallest outer boundary that contains it."""
    outers = [Polygon(to_xy(c)) for c in curves if signed_area(c) > 0]
    holes = {i: [] for i in range(len(outers))}
    for c in curves:
        if signed_area(c) < 0:
            ring = Polygon(to_xy(c))
            owner = min((i for i, o in enumerate(outers) if o.contains(ring.representative_point())),
                        key=lambda i: outers[i].area)
            holes[owner].append(to_xy(c))
    return MultiPolygon([Polygon(o.exterior.coords, holes[i]) for i, o in enumerate(outers)])


def test_every_written_polygon_of_a_real_result_is_valid(blobs_result, tmp_path):
    image, result = blobs_result
    written = io.save_result(result, image, tmp_path / "blobs", ["json", "geojson", "svg", "csv", "npz"])
    geometries = {
        "geojson": geojson_geometry(written[3]),
        "svg": svg_geometry(written[4]),
        **{fmt: nested_geometry(io.read_contours(path))
           for fmt, path in zip(["json", "csv", "npz"], [written[2], written[5], written[6]], strict=True)},
    }
    truth_area = float(np.count_nonzero(image))
    for fmt, geometry in geometries.items():
        assert shapely.is_valid(geometry), (fmt, shapely.is_valid_reason(geometry))
        assert len(geometry.geoms) >= 10
        # the same region in every format, and about the blobs' pixel count
        assert geometry.area == pytest.approx(geometries["geojson"].area, rel=1e-12), fmt
        assert geometry.area == pytest.approx(truth_area, rel=0.02), fmt
    for polygon in geometries["geojson"].geoms:  # RFC 7946: outer rings counterclockwise in (x, y)
        assert polygon.exterior.is_ccw and not any(ring.is_ccw for ring in polygon.interiors)


def test_a_back_step_along_the_border_is_removed_before_writing(tmp_path):
    # a box along the top border of a 40 x 60 image that steps back 3e-5 px at col 20 (a clipped
    # vertex): the ring overlaps itself there, which makes the polygon invalid
    box = np.array([[-0.5, 5.0], [30.0, 5.0], [30.0, 50.0], [-0.5, 50.0], [-0.5, 19.99997],
                    [-0.5, 20.0], [-0.5, 12.0]])
    xy_rows = np.vstack([to_xy(box), to_xy(box[:1])])
    assert not shapely.is_valid(Polygon(xy_rows))
    expected = np.delete(box, 4, axis=0)  # without the spike vertex, the same region
    for fmt in ("geojson", "svg", "json"):
        path = io.write_contours(tmp_path / f"box.{fmt}", [box], image_shape=(40, 60))
        geometry = geojson_geometry(path) if fmt == "geojson" else (
            svg_geometry(path) if fmt == "svg" else nested_geometry(io.read_contours(path)))
        assert shapely.is_valid(geometry), fmt
        assert geometry.area == pytest.approx(30.5 * 45.0, rel=1e-9)
        (back,) = io.read_contours(path)
        assert len(back) == len(expected)
        assert np.allclose(np.sort(back, axis=0), np.sort(expected, axis=0), atol=1e-12)


def test_nan_and_inf_metadata_are_written_as_null(tmp_path):
    curve = ac.circle((20.0, 20.0), 5.0)
    meta = {"c_in": float("nan"), "energy": np.float64(np.inf), "values": [1.0, np.nan]}
    for fmt in ("json", "geojson", "svg", "csv", "npz"):
        path = io.write_contours(tmp_path / f"c.{fmt}", [curve], metadata=meta)
        back = io.read_metadata(path)
        assert (back["c_in"], back["energy"], back["values"]) == (None, None, [1.0, None]), fmt
