"""Object files round-trip through the readers of the tools they are for."""

import json

import numpy as np
import pytest
import roifile
import shapely
import skimage.measure
import tifffile

import activecontour as ac
from activecontour import io, synthetic
from activecontour.geometry.curve import to_xy
from activecontour.io.objects import (
    IMAGEJ_OFFSET,
    OBJECT_FORMATS,
    read_label_image,
    read_objects_csv,
    read_objects_geojson,
)


@pytest.fixture(scope="module")
def result_and_image():
    shape = synthetic.union(synthetic.disk((30, 30), 14), synthetic.annulus((60, 90), 8, 20),
                            synthetic.disk((80, 25), 9))
    image, _ = synthetic.render(shape, (100, 130))
    image = (1000 * synthetic.add_noise(image, 0.05, seed=2)).clip(0, None).astype(np.uint16)
    return ac.segment(image), image


def test_every_object_format_round_trips(tmp_path, result_and_image):
    res, image = result_and_image
    assert res.labels.max() == 3
    paths = io.save_result(res, image, tmp_path / "cells", [], objects=list(OBJECT_FORMATS))
    by_suffix = {p.name.split("cells", 1)[1]: p for p in paths}
    # label image: 16-bit PNG and TIFF, equal ids pixel for pixel, regionprops reads them as is
    for suffix in ("_labels.png", "_labels.tif"):
        labels = read_label_image(by_suffix[suffix])
        np.testing.assert_array_equal(labels, res.labels)
    assert tifffile.imread(by_suffix["_labels.tif"]).dtype == np.int32
    props = skimage.measure.regionprops(read_label_image(by_suffix["_labels.png"]))
    assert [p.label for p in props] == list(res.objects["label"])
    # GeoJSON: shapely reads each Feature; its area is the object's exact area, holes subtracted
    document = json.loads(by_suffix["_objects.geojson"].read_text())
    assert [f["id"] for f in document["features"]] == list(res.objects["label"])
    for feature, area in zip(document["features"], res.objects["area"], strict=True):
        polygon = shapely.geometry.shape(feature["geometry"])
        assert polygon.is_valid
        assert polygon.area == pytest.approx(area, rel=1e-9)
        assert feature["properties"]["area"] == pytest.approx(area, rel=1e-12)
    ring = shapely.geometry.shape(document["features"][int(res.labels[60, 90 + 14]) - 1]["geometry"])
    assert len(ring.interiors) == 1 and not ring.contains(shapely.Point(90, 60))
    ids, objects, _ = read_objects_geojson(by_suffix["_objects.geojson"])
    for curves, expected in zip(objects, res.object_contours, strict=True):
        for curve, original in zip(curves, expected, strict=True):
            np.testing.assert_allclose(np.roll(curve, -int(np.argmin(np.abs(curve - original[0]).sum(1))), 0),
                                       original, atol=1e-9)
    # ImageJ ROI set, read back by roifile: names are ids, coordinates the outer boundaries
    rois = roifile.roiread(by_suffix["_rois.zip"])
    assert [int(r.name) for r in rois] == list(res.objects["label"])
    for roi, curves in zip(rois, res.object_contours, strict=True):
        np.testing.assert_allclose(roi.coordinates() - IMAGEJ_OFFSET, to_xy(curves[0]), atol=1e-3)
    # CSV: the same table
    table = read_objects_csv(by_suffix["_objects.csv"])
    assert list(table) == list(res.objects)
    for name, column in res.objects.items():
        np.testing.assert_allclose(table[name], column, rtol=1e-15)


def test_unknown_object_format_is_refused_before_writing(tmp_path, result_and_image):
    res, image = result_and_image
    with pytest.raises(ValueError, match="object formats must be chosen from"):
        io.save_result(res, image, tmp_path / "cells", [], objects=["shp"])
    assert list(tmp_path.iterdir()) == []


def test_labels_png_refuses_more_ids_than_16_bits(result_and_image):
    from activecontour.io.objects import encode_objects

    res, _ = result_and_image
    big = type("R", (), {"labels": np.array([[0, 70000]], dtype=np.int32)})()
    with pytest.raises(ValueError, match="labels-tif"):
        encode_objects(big, "labels")
    assert encode_objects(res, "labels")[:4] == b"\x89PNG"


def test_every_object_format_is_the_same_bytes_whenever_written(result_and_image, monkeypatch):
    import time

    from activecontour.io.objects import OBJECT_FORMATS, encode_objects

    res, _ = result_and_image
    first = {fmt: encode_objects(res, fmt) for fmt in OBJECT_FORMATS}
    later = time.localtime(time.time() + 3 * 86400)  # three days on: a zip's member dates would differ
    monkeypatch.setattr(time, "localtime", lambda *args: later)
    assert {fmt: encode_objects(res, fmt) for fmt in OBJECT_FORMATS} == first
