"""Objects: label image, exact measurements, and touching objects kept apart."""

import numpy as np
import pytest
import skimage.measure

import activecontour as ac
from activecontour import synthetic
from activecontour.curve import orient
from activecontour.objects import find_objects, group_curves, label_image, measure, polygon_moments
from activecontour.raster import rasterize


def ellipse(center, a, b, angle=0.0, n=2000, hole=False):
    """A polygon ellipse with semi-axis a along the direction at ``angle`` from the row axis."""
    t = 2 * np.pi * np.arange(n) / n
    u, v = a * np.cos(t), b * np.sin(t)
    rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    return orient(np.asarray(center) + (rot @ np.vstack([u, v])).T, hole=hole)


def regular_polygon_area(radius, n):
    return 0.5 * n * radius**2 * np.sin(2 * np.pi / n)


# ---- exact polygon measurements ----------------------------------------------------------------

def test_moments_of_a_regular_polygon_are_exact():
    n, radius = 12, 10.0
    area, centroid, central = polygon_moments([ac.circle((30.0, 40.0), radius, n=n)])
    assert area == pytest.approx(regular_polygon_area(radius, n), rel=1e-12)
    np.testing.assert_allclose(centroid, [30.0, 40.0], atol=1e-12)
    # a regular polygon is isotropic: equal second moments, no product moment, and
    # int r^2 dA = n R^4 sin(2pi/n) (2 + cos(2pi/n)) / 24 over both axes together
    polar = n * radius**4 * np.sin(2 * np.pi / n) * (2 + np.cos(2 * np.pi / n)) / 24 * 2
    assert central[0, 0] == pytest.approx(polar / 2, rel=1e-12)
    assert central[1, 1] == pytest.approx(polar / 2, rel=1e-12)
    assert abs(central[0, 1]) < 1e-9 * polar


def test_disk_measurements_are_analytic():
    radius = 20.0
    objects = [[ac.circle((50.0, 50.0), radius, n=4000)]]
    table = measure(objects, label_image(objects, (100, 100)))
    assert table["area"][0] == pytest.approx(np.pi * radius**2, rel=1e-5)
    assert table["perimeter"][0] == pytest.approx(2 * np.pi * radius, rel=1e-5)
    assert table["eccentricity"][0] < 1e-3
    # the moments of a disk: major = minor = 4 sqrt(R^2 / 4) = 2 R
    assert table["axis_major_length"][0] == pytest.approx(2 * radius, rel=1e-5)
    assert table["solidity"][0] == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("angle", [0.0, 0.4, -1.1])
def test_ellipse_eccentricity_axes_and_orientation(angle):
    a, b = 30.0, 10.0
    objects = [[ellipse((60.0, 70.0), a, b, angle)]]
    labels = label_image(objects, (120, 140))
    table = measure(objects, labels)
    assert table["eccentricity"][0] == pytest.approx(np.sqrt(1 - b**2 / a**2), rel=1e-5)
    assert table["axis_major_length"][0] == pytest.approx(2 * a, rel=1e-5)
    assert table["axis_minor_length"][0] == pytest.approx(2 * b, rel=1e-5)
    assert table["orientation"][0] == pytest.approx(angle, abs=1e-5)
    # regionprops on the rasterised labels agrees to pixel accuracy
    (props,) = skimage.measure.regionprops(labels)
    assert props.orientation == pytest.approx(table["orientation"][0], abs=0.01)
    assert props.eccentricity == pytest.approx(table["eccentricity"][0], abs=0.01)
    # lattice points in an ellipse: the count is off by O(perimeter^(2/3)) (~20 px here)
    assert props.area == pytest.approx(table["area"][0], abs=3 * (2 * np.pi * a) ** (2 / 3))


def test_annulus_hole_is_subtracted_and_belongs_to_its_object():
    outer, inner = 30.0, 12.0
    curves = [ac.circle((50.0, 50.0), outer, n=4000),
              orient(ac.circle((50.0, 50.0), inner, n=4000), hole=True)]
    objects = group_curves(curves)
    assert len(objects) == 1 and len(objects[0]) == 2
    labels = label_image(objects, (100, 100))
    table = measure(objects, labels)
    assert table["area"][0] == pytest.approx(np.pi * (outer**2 - inner**2), rel=1e-5)
    assert table["perimeter"][0] == pytest.approx(2 * np.pi * (outer + inner), rel=1e-5)
    assert labels[50, 50] == 0 and labels[50, 50 + 20] == 1
    assert table["solidity"][0] == pytest.approx(1 - inner**2 / outer**2, rel=1e-4)


def test_an_object_inside_a_hole_is_another_object():
    curves = [ac.circle((50.0, 50.0), 40.0), orient(ac.circle((50.0, 50.0), 25.0), hole=True),
              ac.circle((50.0, 50.0), 10.0)]
    objects, labels, table = find_objects(curves, (100, 100), separate=False)
    assert len(objects) == 2
    assert labels[50, 50] != labels[50, 15] and labels[50, 50] > 0 and labels[50, 15] > 0
    assert labels[50, 35] == 0
    areas = sorted(table["area"])
    assert areas[0] == pytest.approx(regular_polygon_area(10.0, len(curves[2])), rel=1e-9)


def test_labels_are_the_mask_with_ids_and_agree_with_regionprops():
    rng = np.random.default_rng(3)
    curves = [ellipse(rng.uniform(20, 180, 2), rng.uniform(5, 12), rng.uniform(3, 5), rng.uniform(-1.5, 1.5),
                      n=300) for _ in range(6)]
    curves = [c for i, c in enumerate(curves)
              if all(np.hypot(*(c.mean(0) - d.mean(0))) > 30 for d in curves[:i])]
    objects, labels, table = find_objects(curves, (200, 200), separate=False)
    assert len(objects) == len(curves)
    np.testing.assert_array_equal(labels > 0, rasterize(curves, (200, 200)))
    props = skimage.measure.regionprops_table(labels, properties=("label", "area", "centroid", "bbox"))
    np.testing.assert_array_equal(props["label"], table["label"])
    np.testing.assert_allclose(props["area"], table["area"], rtol=0.08)
    np.testing.assert_allclose(props["centroid-0"], table["centroid-0"], atol=0.3)
    np.testing.assert_allclose(props["centroid-1"], table["centroid-1"], atol=0.3)
    for j in range(4):
        np.testing.assert_array_equal(props[f"bbox-{j}"], table[f"bbox-{j}"])
    assert table["label"].dtype == np.int32 and labels.dtype == np.int32


def test_intensity_mean_in_the_input_units():
    image = np.full((60, 80), 100, dtype=np.uint16)
    image[10:30, 10:30] = 1000
    image[35:55, 50:75] = 3000
    curves = [ac.rectangle((9.5, 9.5), (29.5, 29.5)), ac.rectangle((34.5, 49.5), (54.5, 74.5))]
    _, labels, table = find_objects(curves, image.shape, image)
    np.testing.assert_allclose(table["intensity_mean"], [1000, 3000])
    colour = np.stack([image, 2 * image, 3 * image], axis=-1)
    _, _, table = find_objects(curves, image.shape, colour)
    np.testing.assert_allclose(table["intensity_mean-2"], [3000, 9000])


# ---- from segment, both backends ----------------------------------------------------------------

@pytest.mark.parametrize("backend", ["polygon", "levelset"])
def test_segment_gives_labels_and_objects(backend):
    shape = synthetic.union(synthetic.disk((35, 35), 18), synthetic.annulus((60, 100), 9, 22))
    image, truth = synthetic.render(shape, (100, 140))
    image = synthetic.add_noise(image, 0.1, seed=1)
    res = ac.segment(image, backend=backend)
    assert res.labels.dtype == np.int32 and res.labels.max() == 2
    np.testing.assert_array_equal(res.labels > 0, res.mask)
    np.testing.assert_array_equal(res.classes, res.mask.astype(int))
    order = np.argsort(res.objects["centroid-0"])
    area = res.objects["area"][order]
    assert area[0] == pytest.approx(np.pi * 18**2, rel=0.03)
    assert area[1] == pytest.approx(np.pi * (22**2 - 9**2), rel=0.03)
    assert res.objects["perimeter"][order][1] == pytest.approx(2 * np.pi * (22 + 9), rel=0.05)
    assert len(res.object_contours[int(res.labels[60, 100 + 15]) - 1]) == 2  # the ring has its hole
