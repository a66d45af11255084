"""The common evaluator takes closed curves in any orientation: the nesting decides (issue 22, item 4).

scikit-image's ``find_contours``, OpenCV's ``findContours`` and shapely's rings each orient outer
boundaries and holes their own way; ``chan_vese_energy`` scores them as they are, by the same
rule of nesting ``init`` follows (:func:`activecontour.geometry.regions.orient_by_nesting`).  The
numbers come from the regions' areas: on a zero image with ``c_in = 1``, ``c_out = 0``, ``mu = 0``
and no normalisation, (6.38) is ``lambda_in`` times the area inside, which a hole scored as an
object (or an object as a hole) would change.
"""

import cv2
import numpy as np
import pytest
import shapely
import skimage.measure
from shapely.geometry.polygon import orient as orient_polygon

import activecontour as ac
from activecontour.geometry.curve import from_xy, signed_area
from activecontour.geometry.regions import nesting, orient_by_nesting, polygons

#: an object with a hole and an island in the hole: depths 0, 1, 2
MASK = np.zeros((40, 40), dtype=bool)
MASK[8:32, 6:30] = True
MASK[15:25, 12:24] = False
MASK[18:22, 16:20] = True


def area_only(curves):
    """(6.38) that is the area inside the curves (see the module docstring)."""
    return ac.chan_vese_energy(np.zeros(MASK.shape), curves, mu=0.0, c_in=1.0, c_out=0.0, normalize=None)


def region_area(rings):
    """The area of the region the rings bound, by shapely: outer minus hole plus island."""
    outer, hole, island = sorted(rings, key=lambda r: -abs(signed_area(r)))
    return shapely.Polygon(outer, [hole]).area + shapely.Polygon(island).area


def test_scikit_image_find_contours_score_as_they_are():
    curves = skimage.measure.find_contours(MASK.astype(float), 0.5)  # closed: first vertex repeated
    assert len(curves) == 3
    assert area_only(curves) == pytest.approx(region_area(curves), rel=1e-12)
    assert area_only([c[::-1] for c in curves]) == pytest.approx(region_area(curves), rel=1e-12)


def test_opencv_find_contours_score_as_they_are():
    found, _ = cv2.findContours(MASK.astype(np.uint8), cv2.RETR_CCOMP, cv2.CHAIN_APPROX_SIMPLE)
    curves = [from_xy(c[:, 0, :].astype(float)) for c in found]
    assert len(curves) == 3
    assert area_only(curves) == pytest.approx(region_area(curves), rel=1e-12)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_shapely_rings_score_as_they_are(sign):
    outer, hole, island = sorted(skimage.measure.find_contours(MASK.astype(float), 0.5),
                                 key=lambda c: -abs(signed_area(c)))
    ring = orient_polygon(shapely.Polygon(outer, [hole]), sign=sign)
    rings = [np.asarray(ring.exterior.coords), *(np.asarray(r.coords) for r in ring.interiors),
             np.asarray(orient_polygon(shapely.Polygon(island), sign=sign).exterior.coords)]
    assert area_only(rings) == pytest.approx(region_area(rings), rel=1e-12)


def test_the_evaluator_and_init_read_one_nesting():
    """A start from the same curves has the evaluator's energy: init orients them the same way."""
    image = MASK * 0.8 + 0.1
    curves = skimage.measure.find_contours(MASK.astype(float), 0.5)
    start = ac.segment(image, curves, max_num_iter=0)
    assert start.energy == pytest.approx(ac.chan_vese_energy(image, curves, mu=start.mu), rel=1e-12)
    assert np.array_equal(start.mask, MASK)


def test_nesting_depth_and_parent():
    curves = [ac.circle((20, 20), 15), ac.circle((20, 20), 10), ac.circle((20, 20), 5), ac.circle((5, 5), 3)]
    depth, parent, same = nesting(polygons(curves))
    np.testing.assert_array_equal(depth, [0, 1, 2, 0])
    np.testing.assert_array_equal(parent, [-1, 0, 1, -1])
    assert same == []
    areas = [signed_area(c) for c in orient_by_nesting(curves)]
    assert np.sign(areas).tolist() == [1, -1, 1, 1]
