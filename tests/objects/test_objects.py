"""Objects: label image, exact measurements, and touching objects kept apart."""

import numpy as np
import pytest
import skimage.measure

import activecontour as ac
from activecontour import synthetic
from activecontour.geometry.curve import orient
from activecontour.geometry.raster import rasterize
from activecontour.geometry.regions import group_curves
from activecontour.objects.measure import find_objects, label_image, measure, polygon_moments


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


@pytest.mark.parametrize("separate", [False, True])
def test_specks_between_pixel_centres_have_no_id_and_the_rest_are_numbered_in_order(separate):
    # two specks that hold no pixel centre, one first in reading order, around two disks
    speck = orient(np.array([[2.2, 2.2], [2.2, 2.8], [2.8, 2.5]]))
    curves = [speck, ac.circle((20.0, 20.0), 8.0), speck + [30.0, 1.0], ac.circle((40.0, 45.0), 6.0)]
    image = np.random.default_rng(0).random((60, 60))
    objects, labels, table = find_objects(curves, (60, 60), image, separate=separate)
    disks = [[curves[1]], [curves[3]]]
    assert len(objects) == 2 and all(np.array_equal(o[0], d[0]) for o, d in zip(objects, disks, strict=True))
    np.testing.assert_array_equal(labels, label_image(disks, (60, 60)))
    expected = measure(disks, labels, image)
    assert list(table) == list(expected) + ["class"]
    for name, column in expected.items():
        np.testing.assert_array_equal(table[name], column)


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


@pytest.mark.parametrize("min_size", [0.0, 50.0])
def test_the_labels_after_a_split_are_the_objects_drawn_anew(min_size):
    # find_objects redraws only the parts of cut objects (and drops the small ones' pixels):
    # the label image must be label_image of the objects, drawn from scratch
    import shapely

    pair = shapely.union(shapely.Polygon(ellipse((40, 30), 14, 14, n=400)),
                         shapely.Polygon(ellipse((40, 52), 14, 14, n=400)))
    curves = [orient(np.asarray(pair.exterior.coords)[:-1]), ellipse((12, 90), 9, 6, 0.3, n=300),
              ellipse((80, 20), 3, 3, n=60), ellipse((75, 80), 15, 12, n=400),
              ellipse((75, 80), 5, 4, n=200, hole=True), ellipse((12, 12), 7, 7, n=200)]
    objects, labels, _ = find_objects(curves, (100, 110), min_size=min_size)
    cut = len(group_curves(curves)) - (min_size > 0)
    assert len(objects) == cut + 1  # the pair is two, the speck dropped with min_size
    np.testing.assert_array_equal(labels, label_image(objects, (100, 110)))


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


# ---- touching objects kept apart, single objects never split -----------------------------------

def _pair(distance, radius=12.0, size=(80, 110)):
    """Two disks of ``radius`` whose centres are ``distance`` apart, noisy, and the true labels
    (a pixel of the overlap goes to the nearer centre)."""
    centers = [(40.0, 55.0 - distance / 2), (40.0, 55.0 + distance / 2)]
    image, union = synthetic.render(synthetic.union(*[synthetic.disk(c, radius) for c in centers]), size)
    rr, cc = np.mgrid[:size[0], :size[1]]
    first, second = (np.hypot(rr - r, cc - c) for r, c in centers)
    nearer = first > second
    truth = np.where(union, 1 + nearer, 0)
    return synthetic.add_noise(image, 0.1, seed=int(distance * 10)), truth


def _no_overlap_and_union_is_region(res):
    import shapely

    from activecontour.geometry.regions import _to_shapely

    polygons = [_to_shapely(curves) for curves in res.object_contours]
    region = _to_shapely(res.contours)
    total = sum(p.area for p in polygons)
    assert total == pytest.approx(region.area, rel=1e-9)  # a partition of the inside ...
    assert shapely.union_all(polygons).area == pytest.approx(total, rel=1e-9)  # ... without overlaps
    assert all(p.is_valid for p in polygons)


# neck half-width / radius = sqrt(1 - (d / 2R)^2): 0 (tangent) to 0.745 (overlap of a third of
# the diameter, d = 4R/3), below NECK_RATIO = 0.9 (the length term rounds the waist of the
# converged contour, so at d = R, 0.866 in theory, the neck is already too wide to split)
@pytest.mark.parametrize("distance", [24.5, 24.0, 22.0, 20.0, 18.0, 16.0])
def test_touching_pair_is_two_objects_at_every_contact_width(distance):
    image, truth = _pair(distance)
    res = ac.segment(image)
    assert res.labels.max() == 2
    from activecontour.objects.metrics import match_instances

    score = match_instances(res.labels, truth)
    assert score["tp"] == 2 and score["mean_iou"] > 0.85
    _no_overlap_and_union_is_region(res)
    np.testing.assert_array_equal(res.labels > 0, res.mask)
    # the split line is straight across the neck: each part is about one disk
    np.testing.assert_allclose(np.sort(res.objects["area"]), np.pi * 12.0**2 - _lens(12.0, distance) / 2,
                               rtol=0.08)
    assert ac.segment(image, separate=False).labels.max() == 1


@pytest.mark.parametrize("distance", [24.0, 16.0])
def test_touching_pair_is_two_objects_from_the_level_set_too(distance):
    image, truth = _pair(distance)
    res = ac.segment(image, backend="levelset")
    from activecontour.objects.metrics import match_instances

    assert match_instances(res.labels, truth)["tp"] == 2 and res.labels.max() == 2
    _no_overlap_and_union_is_region(res)


def _lens(radius, distance):
    """Area of the overlap of two disks of ``radius`` with centres ``distance`` apart."""
    if distance >= 2 * radius:
        return 0.0
    half_chord = np.sqrt(4 * radius**2 - distance**2) / 2
    return 2 * radius**2 * np.arccos(distance / (2 * radius)) - distance * half_chord


def test_a_peanut_with_a_wide_waist_is_one_object():
    # d = 0.6 R: waist half-width sqrt(1 - 0.09) R = 0.95 R, above NECK_RATIO: one object
    image, _ = _pair(0.6 * 12.0)
    assert ac.segment(image).labels.max() == 1


def _strokes():
    """A comb of 3 px strokes: five horizontal bars joined by two vertical ones."""
    image = np.zeros((120, 120))
    for k in range(5):
        image[15 + 20 * k: 18 + 20 * k, 10:110] = 1.0
    image[15:98, 10:13] = image[15:98, 60:63] = 1.0
    return image


def _slit_disk():
    """A disk with a slit from the left to 3/10 of its diameter from the right: a one-sided notch
    whose tip makes a neck, but no waist (the right side is convex)."""
    disk, slit = synthetic.disk((50, 50), 25), synthetic.rectangle((47, 20), (53, 65))
    return synthetic.render(lambda r, c: disk(r, c) & ~slit(r, c), (100, 100))[0]


SINGLE_OBJECTS = {
    "slit disk": _slit_disk,
    "horse": lambda: (~__import__("skimage.data").data.horse()).astype(float),
    "strokes": _strokes,
    "ring": lambda: synthetic.render(synthetic.annulus((60, 60), 25, 35), (120, 120))[0],
    "thick ring": lambda: synthetic.render(synthetic.annulus((50, 70), 9, 22), (100, 140))[0],
    "ellipse aspect 3": lambda: synthetic.render(synthetic.ellipse((60, 60), 45, 15, 0.5), (120, 120))[0],
    "star": lambda: synthetic.render(synthetic.star((60, 60), 35, amplitude=0.35, arms=5), (120, 120))[0],
}


@pytest.mark.parametrize("backend", ["polygon", "levelset"])
@pytest.mark.parametrize("name", list(SINGLE_OBJECTS))
def test_a_single_object_is_never_split(name, backend):
    image = synthetic.add_noise(SINGLE_OBJECTS[name](), 0.2, seed=len(name))
    res = ac.segment(image, backend=backend)
    assert len(group_curves(res.contours)) == 1  # one connected piece ...
    assert res.labels.max() == 1  # ... and one object


def _dented_rod(at, half_width=10.0, length=90.0, depth=1.2, spacing=0.25):
    """The outline of a rod (a stadium: half-width 10, straight part 90 px) with a dent of
    ``depth`` px (a Gaussian of 2 px) on both sides at ``at`` px from its middle: the noise of a
    converged contour on a rod of constant width, a neck of (10 - 1.2) / 10 = 0.88 of its
    inscribed radius between two pieces of the rod."""
    r0, c0 = 30.0, 70.0
    xs = np.arange(-length / 2, length / 2, spacing)
    dent = depth * np.exp(-0.5 * ((xs - at) / 2.0) ** 2)
    ends = np.arange(-np.pi / 2, np.pi / 2, spacing / half_width)
    top = np.column_stack([r0 - half_width + dent, c0 + xs])
    right = np.column_stack([r0 + half_width * np.sin(ends), c0 + length / 2 + half_width * np.cos(ends)])
    bottom = np.column_stack([r0 + half_width - dent, c0 + xs])[::-1]
    left = np.column_stack([r0 - half_width * np.sin(ends), c0 - length / 2 - half_width * np.cos(ends)])
    return orient(np.vstack([top, right, bottom, left]))


@pytest.mark.parametrize("at", [0.0, 15.0])
def test_a_rod_with_shallow_dents_is_one_object(at):
    # a neck above TUBE_NECK between two stretches of a tube (together more than TUBE_AREA times
    # their inscribed disks) is a dent, not a contact: the rod is one object (the neck stage cut
    # it in two before TUBE_NECK; issue 23's bent rods of the singles family)
    from activecontour.objects.split import split_touching

    outline = _dented_rod(at)
    assert len(split_touching([[outline]], label_image([[outline]], (60, 140)))) == 1


def _bright_and_dim_halves():
    """A disk of radius 20 cut by a chord through its centre, the left half twice as bright as
    the right one (a bright nucleus touching a dim one): the outline is a disk, no waist."""
    image = synthetic.render(synthetic.disk((40, 40), 20), (80, 80))[0]
    truth = (image > 0.5).astype(np.int32)
    truth[:, 40:] *= 2
    image[:, 40:] *= 0.5
    return image, truth


@pytest.mark.parametrize("backend", ["polygon", "levelset"])
def test_a_bright_and_a_dim_object_touching_without_a_waist_are_two(backend):
    from activecontour.objects.metrics import match_instances

    image, truth = _bright_and_dim_halves()
    noisy = synthetic.add_noise(image, 0.5 / 3, seed=1)  # SNR 3 on the step between the halves
    res = ac.segment(noisy, backend=backend)
    score = match_instances(res.labels, truth)
    # both halves found; mean IoU > 0.75 means a split line within ~4 px of the chord (a shift of
    # d px moves 40 d px of a 628 px half)
    assert res.labels.max() == 2 and score["tp"] == 2 and score["mean_iou"] > 0.75
    _no_overlap_and_union_is_region(res)
    assert ac.segment(noisy, backend=backend, separate=False).labels.max() == 1
    # the same disk of one brightness at the same noise is one object
    uniform = synthetic.add_noise((truth > 0).astype(float), 0.5 / 3, seed=1)
    assert ac.segment(uniform, backend=backend).labels.max() == 1


@pytest.mark.parametrize("name", list(SINGLE_OBJECTS))
def test_a_single_object_is_never_split_at_snr_3(name):
    # the split by contrast must not read noise as two classes: the noise at a third of the contrast
    image = synthetic.add_noise(SINGLE_OBJECTS[name](), 1 / 3, seed=len(name))
    assert ac.segment(image).labels.max() == 1


def test_n_regions_objects_are_pieces_of_each_class():
    bright, dim = synthetic.disk((40, 40), 14), synthetic.disk((40, 66), 13)  # touching, d = 26 < 27

    def values(r, c):
        return np.where(bright(r, c), 1.0, np.where(dim(r, c), 0.5, 0.0))

    # no anti-aliasing: an edge pixel between 1 and 0 would read as the middle class
    image, _ = synthetic.render(synthetic.union(bright, dim), (80, 110), values=values, supersample=1)
    image = synthetic.add_noise(image, 0.05, seed=6)
    res = ac.segment(image, n_regions=3, backend="levelset", separate=False)
    assert res.labels.max() == 2
    np.testing.assert_array_equal(res.labels > 0, res.classes > 0)
    by_class = dict(zip(res.objects["class"], res.objects["area"], strict=True))
    assert by_class[2] == pytest.approx(np.pi * 14**2, rel=0.05)  # class 2: the brighter one
    assert by_class[1] == pytest.approx(np.pi * 13**2, rel=0.05)
    assert res.labels[40, 40] != res.labels[40, 66]


# ---- the cost of splitting ---------------------------------------------------------------------


def test_thousands_of_small_watershed_parts_merge_into_one():
    # A speckled inside: a local maximum of the distance in every 3 x 3 pixels, all below
    # MIN_SPLIT_RADIUS, so every part merges whatever its neck and the region is one part.  With
    # 2551 parts this took 28 s when every merge rescanned every border (O(parts x borders)); the
    # queued merges take ~0.1 s.
    import scipy.ndimage
    import skimage.morphology

    from activecontour.objects.necks import NECK_RATIO, _neck_parts
    from activecontour.objects.shapes import MIN_SPLIT_RADIUS

    n = 150
    region = np.pad(np.ones((n, n), dtype=bool), 1)
    r, c = np.mgrid[0: n + 2, 0: n + 2] * (2 * np.pi / 3)
    distance = np.where(region, 1.0 + 0.5 * np.cos(r) * np.cos(c) ** 2 + 0.25 * np.cos(c), 0.0)
    assert distance.max() < MIN_SPLIT_RADIUS
    assert scipy.ndimage.label(skimage.morphology.local_maxima(distance) & region)[1] > 2000
    parts = _neck_parts(region, np.full(region.shape, -1.0), distance, NECK_RATIO, MIN_SPLIT_RADIUS)
    np.testing.assert_array_equal(parts, region)


def test_merged_part_shapes_are_those_of_regionprops():
    # the blob test of merged parts adds up moments and merges hulls: the solidity and the axes
    # of regionprops on the merged pixels
    import scipy.ndimage

    from activecontour.objects.necks import _PartShapes
    from activecontour.objects.shapes import MAX_PART_ASPECT, MIN_PART_SOLIDITY

    rng = np.random.default_rng(0)
    for _ in range(20):
        parts, count = scipy.ndimage.label(rng.random((30, 40)) < 0.6)
        members = {k: [k] for k in range(1, count + 1)}
        shapes = _PartShapes(parts, members)
        for gone in rng.permutation(np.arange(2, count + 1))[: count // 2]:
            members[1] += members.pop(int(gone))
            shapes.merge(1, int(gone))
        for root, numbers in members.items():
            (props,) = skimage.measure.regionprops(np.isin(parts, numbers).astype(np.uint8))
            blob, solidity = shapes.blob(root)
            assert solidity == props.solidity
            major, minor = props.axis_major_length, props.axis_minor_length
            assert blob == (solidity >= MIN_PART_SOLIDITY and major <= MAX_PART_ASPECT * max(minor, 1e-9))


def test_a_constant_image_has_no_contrast_to_split():
    # the least contrast of a split is 0 there: a range of 0 must not reach Otsu (whose upper
    # class is then empty: a mean of nothing)
    import warnings

    from activecontour.objects.split import split_touching

    square = [ac.rectangle((1.5, 1.5), (18.5, 18.5))]  # 289 px: enough for two pieces
    labels = label_image([square], (20, 20))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(split_touching([square], labels, np.zeros((20, 20)))) == 1


def test_pixel_columns_agree_with_regionprops_when_objects_overlap_nest_or_leave_the_image():
    # drawn in order, a later object covers an earlier one's pixels; a sliver between pixel
    # centres has none (bbox zeros), an object past the border keeps only its pixels inside
    objects = [[ac.circle((30.0, 30.0), 20.0)], [ac.circle((40.0, 40.0), 12.0)],
               [ac.circle((5.0, 70.0), 15.0)], [ac.rectangle((60.2, 10.2), (60.8, 40.8))],
               [ac.circle((30.0, 30.0), 25.0), orient(ac.circle((30.0, 30.0), 23.0), hole=True)],
               [ac.circle((75.0, 75.0), 9.0)]]
    labels = label_image(objects, (80, 90))
    image = np.random.default_rng(5).uniform(-1.0, 3.0, (80, 90, 2))
    table = measure(objects, labels, image)
    props = skimage.measure.regionprops_table(labels, image, properties=("label", "bbox", "num_pixels",
                                                                         "intensity_mean"))
    present = np.isin(table["label"], props["label"])
    assert list(present) == [True, True, True, False, True, True]
    for j in range(4):
        np.testing.assert_array_equal(table[f"bbox-{j}"][present], props[f"bbox-{j}"])
        assert table[f"bbox-{j}"][3] == 0
    np.testing.assert_array_equal(table["num_pixels"][present], props["num_pixels"])
    assert table["num_pixels"][3] == 0
    for ch in range(2):
        np.testing.assert_allclose(table[f"intensity_mean-{ch}"][present], props[f"intensity_mean-{ch}"],
                                   rtol=1e-12)
