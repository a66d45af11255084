"""The split's shortcuts change no decision: each is a consequence of the criterion applied later.

Random outlines (seeded): clumps of two or three ellipses (concave corners, necks) and bumpy
stars, at sizes from below the smallest part to large windows.
"""

import numpy as np
import pytest
import scipy.ndimage
import shapely

import activecontour.objects.contrast as contrast
import activecontour.objects.corners as corners
import activecontour.objects.necks as necks
import activecontour.objects.shapes as shapes
from activecontour import _kernels
from activecontour.geometry.curve import orient, signed_area
from activecontour.geometry.raster import rasterize


def _ellipse(rng, centre, scale):
    t = np.linspace(0, 2 * np.pi, 120, endpoint=False)
    a, b = scale * rng.uniform(0.5, 1.0), scale * rng.uniform(0.3, 1.0)
    angle = rng.uniform(0, np.pi)
    u, v = a * np.cos(t), b * np.sin(t)
    return shapely.Polygon(np.column_stack([centre[0] + u * np.cos(angle) - v * np.sin(angle),
                                            centre[1] + u * np.sin(angle) + v * np.cos(angle)]))


def random_outline(seed):
    """A simple closed positive outline in (row, col), away from the origin (a star's radius
    stays positive: its harmonics add up to less than 1)."""
    rng = np.random.default_rng(seed)
    scale = rng.choice([2.5, 5.0, 10.0, 25.0])
    if rng.random() < 0.7:  # a clump: each ellipse overlaps the one before
        shapes, centre = [], np.array([3 * scale, 3 * scale])
        for _ in range(rng.integers(2, 4)):
            shapes.append(_ellipse(rng, centre, scale))
            centre = centre + rng.normal(0, 1, 2) * scale * 0.9
        region = shapely.union_all(shapes)
        if not isinstance(region, shapely.Polygon):
            region = max(region.geoms, key=lambda g: g.area)
        outline = np.asarray(region.exterior.coords)[:-1]
    else:  # a bumpy star
        t = np.linspace(0, 2 * np.pi, 300, endpoint=False)
        rho = scale * (1 + sum(rng.uniform(0, 0.15) * np.cos(k * t + rng.uniform(0, 6)) for k in range(2, 7)))
        outline = np.column_stack([rho * np.cos(t), rho * np.sin(t)])
    outline = outline - outline.min(axis=0) + rng.uniform(1.2, 2.0, 2)  # window coordinates
    return orient(outline)


def window_of(outline):
    shape = tuple(np.floor(outline.max(axis=0)).astype(int) + 2)
    return rasterize([outline], shape)


@pytest.mark.parametrize("seed, zoom", [(seed, 1.0) for seed in range(40)] + [(0, 12.0), (3, 9.0), (7, 5.0)])
def test_the_boundary_distance_is_the_fine_distance_transform_at_the_pixel_centres(seed, zoom):
    # (zoomed: giant windows, a coarser raster with few fine pixels per centre)
    outline = random_outline(seed) * zoom
    region = window_of(outline)
    fine = necks._supersample(region.shape)
    shape = (fine * (region.shape[0] - 1) + 1, fine * (region.shape[1] - 1) + 1)
    # the definition: the whole fine raster's Euclidean distance transform, read every fine pixels
    transform = scipy.ndimage.distance_transform_edt(rasterize([outline * fine], shape))[::fine, ::fine]
    expected = np.where(region, np.maximum((transform - 0.5) / fine, 0.0), 0.0)
    np.testing.assert_array_equal(necks._boundary_distance([outline], region, np.zeros(2)), expected)


def test_a_giant_window_measures_on_a_coarser_raster_that_is_no_power_of_two():
    # 2^20 samples over a window of 400 x 400 pixels: 2.56 times finer, rounded down to 2; 250
    # x 250 gives 4; 180 x 180 gives 5, for which _thinner_than claims nothing
    assert [necks._supersample((n, n)) for n in (400, 250, 180, 100)] == [2, 4, 5, 8]
    assert not necks._thinner_than(np.ones((180, 180), bool), np.zeros((3, 2)), 1e9)


@pytest.mark.parametrize("seed", range(60))
def test_the_pixel_raster_bounds_the_boundary_distance_and_a_thin_object_has_no_neck(seed):
    outline = random_outline(seed)
    region = window_of(outline)
    distance = necks._boundary_distance([outline], region, np.zeros(2))
    if necks._supersample(region.shape) & (necks._supersample(region.shape) - 1) == 0:
        bound = scipy.ndimage.distance_transform_edt(rasterize([outline], region.shape))
        assert np.all(distance <= bound)
    if necks._thinner_than(region, outline, shapes.MIN_SPLIT_RADIUS) and scipy.ndimage.label(region)[1] == 1:
        concavity = shapes._concavity(region, outline)
        parts = necks._neck_parts(region, concavity, distance, necks.NECK_RATIO, shapes.MIN_SPLIT_RADIUS)
        assert parts.max() == 1


def test_thin_and_thick_outlines_are_both_drawn():
    # the property above must see both sides of the shortcut
    thin = [necks._thinner_than(window_of(o), o, shapes.MIN_SPLIT_RADIUS)
            for o in map(random_outline, range(60))]
    assert 5 <= sum(thin) <= 55


@pytest.mark.parametrize("seed", range(60))
def test_the_corner_stage_shortcuts_cut_what_the_full_search_cuts(seed, monkeypatch):
    outline = random_outline(seed)
    parts = corners._corner_parts(outline)
    monkeypatch.setattr(corners, "_uncuttable", lambda area, good: False)
    full = corners._corner_parts(outline)
    assert len(parts) == len(full)
    for part, other in zip(parts, full, strict=True):
        np.testing.assert_array_equal(part, other)


@pytest.mark.parametrize("seed", range(30))
def test_the_two_sides_of_every_admissible_cut_add_up_to_the_part(seed):
    # what makes a part under twice the smallest part uncuttable
    outline = random_outline(seed)
    found, kappa, normals = corners._concave_corners(outline)
    is_corner = np.zeros(len(outline), dtype=bool)
    is_corner[found] = True
    cycle = np.arange(len(outline))
    for _, a, b in corners._cuts(outline, cycle, is_corner, kappa <= 0, normals):
        sides = signed_area(outline[cycle[a:b + 1]]), signed_area(outline[np.r_[cycle[b:], cycle[:a + 1]]])
        assert min(sides) > 0
        assert sum(sides) == pytest.approx(signed_area(outline), rel=1e-12)


@pytest.mark.parametrize("seed", range(60))
def test_neck_parts_with_one_part_thick_enough_merge_into_one(seed):
    # the merging itself (the graph of the watershed's parts), run where _neck_parts stops early
    import skimage.morphology
    import skimage.segmentation

    outline = random_outline(seed)
    region = window_of(outline)
    distance = necks._boundary_distance([outline], region, np.zeros(2))
    markers, count = scipy.ndimage.label(skimage.morphology.local_maxima(distance) & region)
    if count <= 1 or scipy.ndimage.label(region)[1] != 1:
        return
    parts = skimage.segmentation.watershed(-distance, markers, mask=region)
    peak = np.asarray(scipy.ndimage.maximum(distance, parts, np.arange(count + 1)))
    graph = necks._PartGraph(parts, distance, peak.copy(), shapes._concavity(region, outline),
                             shapes.MIN_SPLIT_RADIUS)
    graph.merge_necks(necks.NECK_RATIO)
    graph.merge_non_blobs()
    merged = graph.labels()
    if np.count_nonzero(peak >= shapes.MIN_SPLIT_RADIUS) <= 1:
        np.testing.assert_array_equal(merged, region.astype(np.int32))
    np.testing.assert_array_equal(necks._neck_parts(region, shapes._concavity(region, outline), distance,
                                                    necks.NECK_RATIO, shapes.MIN_SPLIT_RADIUS), merged)


@pytest.mark.parametrize("step", [1, 2, 3, 8])
def test_the_sampled_distance_kernel_is_the_distance_transform_read_every_step_pixels(step):
    from activecontour import _kernels

    rng = np.random.default_rng(step)
    for _ in range(40):
        m, n = rng.integers(2, 40, 2)
        shape = (step * (m - 1) + 1, step * (n - 1) + 1)
        # blobs, specks and rows or columns without an outside pixel
        smooth = scipy.ndimage.gaussian_filter(rng.random(shape), rng.uniform(0.5, 5))
        inside = smooth > rng.uniform(0.46, 0.5)
        inside[rng.integers(shape[0])] = False
        # the mask's crossings as rasterize draws them: +1 where a run of inside pixels starts,
        # -1 where it stops (at the row's end too); some rows twice over (winding 2 inside), and
        # pairs +1, -1 at one column that cancel
        change = np.diff(np.pad(inside.astype(np.int32), ((0, 0), (1, 1))), axis=1)
        rows, cols = np.nonzero(change)
        direction = change[rows, cols]
        twice = np.isin(rows, np.flatnonzero(rng.random(shape[0]) < 0.3))
        pairs = rng.integers(0, shape[0], 5), rng.integers(0, shape[1], 5)
        rows = np.concatenate([rows, rows[twice], pairs[0], pairs[0]])
        cols = np.concatenate([cols, cols[twice], pairs[1], pairs[1]])
        direction = np.concatenate([direction, direction[twice], np.ones(5, int), -np.ones(5, int)])
        order = np.lexsort((cols, rows))
        out = np.empty((m, n))
        _kernels.sampled_distance(rows[order].astype(np.intp), cols[order].astype(np.intp),
                                  direction[order].astype(np.int32), *shape, step, out)
        np.testing.assert_array_equal(out, scipy.ndimage.distance_transform_edt(inside)[::step, ::step])


@pytest.mark.parametrize("seed", range(8))
def test_the_near_reaches_kernel_is_the_squared_distance_transform_against_each_least(seed):
    from activecontour import _kernels

    rng = np.random.default_rng(seed)
    for _ in range(30):
        m, n = rng.integers(1, 45, 2)
        # blobs with holes and specks; a mask without a False pixel reaches every least
        smooth = scipy.ndimage.gaussian_filter(rng.random((m, n)), rng.uniform(0.5, 4))
        inside = smooth > np.quantile(smooth, rng.uniform(0.0, 0.6))
        if inside.all():
            squared = np.full((m, n), np.iinfo(np.int64).max)
        else:
            # the definition: squared offsets to the feature transform's nearest False pixel
            _, nearest = scipy.ndimage.distance_transform_edt(inside, return_indices=True)
            squared = np.sum((nearest - np.indices(inside.shape)) ** 2, axis=0)
        # every least up to 70: together they give the squared transform up to 70
        for least in range(-1, 71):
            out = np.empty((m, n), dtype=np.uint8)
            _kernels.near_reaches(inside.astype(np.uint8), least, out)
            np.testing.assert_array_equal(out.view(bool), squared >= least)


@pytest.mark.parametrize("seed", range(8))
def test_the_distance_peaks_kernel_is_the_distance_transform_and_its_pieces_of_peaks(seed):
    from activecontour import _kernels

    rng = np.random.default_rng(seed)
    counts = []
    for _ in range(40):
        m, n = rng.integers(1, 60, 2)
        # blobs with holes and specks, plateaus (a square) and masks of one row or column
        smooth = scipy.ndimage.gaussian_filter(rng.random((m, n)), rng.uniform(0.5, 6))
        inside = smooth > np.quantile(smooth, rng.uniform(0.0, 0.6))
        if rng.random() < 0.2:
            inside = np.pad(np.ones((m, n), bool), int(rng.integers(1, 3)))
        inside.flat[rng.integers(inside.size)] = False
        out = np.empty(inside.shape, dtype=np.int64)
        pieces = _kernels.distance_peaks(inside.astype(np.uint8), out)
        # the definitions: squared offsets to the feature transform's nearest False pixel; the
        # pixels of the mask that the 3 x 3 maximum filter of the transform does not exceed
        _, nearest = scipy.ndimage.distance_transform_edt(inside, return_indices=True)
        np.testing.assert_array_equal(out, np.sum((nearest - np.indices(inside.shape)) ** 2, axis=0))
        distance = scipy.ndimage.distance_transform_edt(inside)
        peaks = (distance >= scipy.ndimage.maximum_filter(distance, size=3)) & inside
        assert pieces == scipy.ndimage.label(peaks)[1]
        counts.append(pieces)
    assert min(counts) <= 1 and max(counts) >= 3


@pytest.mark.parametrize("seed", range(4))
def test_the_h_maxima_count_is_skimages(seed):
    """The necks' gate counts the pieces of skimage's h-maxima: distance transforms of blobs (the
    gate's input), images of a few grey levels (plateaus, ties with the marker) and smooth noise,
    at the gate's h and others; small, since skimage's own answer is the truth compared with."""
    import skimage.morphology

    rng = np.random.default_rng(seed)
    counts = []
    for trial in range(150):
        m, n = rng.integers(1, 40, 2)
        if trial % 3 == 0:
            smooth = scipy.ndimage.gaussian_filter(rng.random((m, n)), rng.uniform(0.5, 4))
            image = scipy.ndimage.distance_transform_edt(np.pad(smooth > 0.5, 1))
        elif trial % 3 == 1:
            image = rng.integers(0, 5, (m, n)).astype(float)
        else:
            image = scipy.ndimage.gaussian_filter(rng.random((m, n)), 1.5) * 10
        for h in (0.25, necks.MIN_NECK_DEPTH / 2, 1.0):
            count = necks._h_maxima_count(image, h)
            assert count == scipy.ndimage.label(skimage.morphology.h_maxima(image, h))[1]
            counts.append(count)
    assert min(counts) == 0 and max(counts) >= 3


@pytest.mark.parametrize("seed", range(4))
def test_the_fill_holes_kernel_fills_as_scipy_on_the_framed_mask(seed):
    from activecontour import _kernels

    rng = np.random.default_rng(seed)
    filled = 0
    for _ in range(60):
        m, n = rng.integers(1, 50, 2)
        # blobs with holes (rings of noise above a threshold) and masks of one row or column
        smooth = scipy.ndimage.gaussian_filter(rng.random((m, n)), rng.uniform(0.5, 4))
        inside = smooth > np.quantile(smooth, rng.uniform(0.0, 0.9))
        window = np.pad(inside, 1)
        _kernels.fill_holes(window.view(np.uint8))
        np.testing.assert_array_equal(window, np.pad(scipy.ndimage.binary_fill_holes(inside), 1))
        filled += np.count_nonzero(window) > np.count_nonzero(inside)
    assert filled >= 5  # holes were drawn


@pytest.mark.parametrize("radius", [0.0, 1.0, np.sqrt(2), 2.5, 3.0, 4.0, np.sqrt(17), np.nextafter(3.0, 4.0),
                                    np.nextafter(np.sqrt(5), 0.0)])
def test_reaches_compares_with_its_radius_as_the_distance_transform(radius):
    rng = np.random.default_rng(int(10 * radius))
    for _ in range(20):
        inside = scipy.ndimage.gaussian_filter(rng.random((40, 50)), rng.uniform(1, 5)) > 0.48
        inside[0, 0] = False
        transform = scipy.ndimage.distance_transform_edt(inside)
        np.testing.assert_array_equal(shapes._reaches(inside, radius, strict=True), transform > radius)
        np.testing.assert_array_equal(shapes._reaches(inside, radius), transform >= radius)


def test_a_piece_too_small_is_told_right_from_the_cores_alone():
    # cores of random sizes in a disk; whenever the cores' areas say that a piece will be under
    # CONTRAST_SIZE_RATIO of the largest, the pieces the pixels make say so too
    rng = np.random.default_rng(5)
    told = []
    for _ in range(200):
        rows, cols = np.indices((60, 60))
        mask = (rows - 30) ** 2 + (cols - 30) ** 2 < rng.uniform(10, 29) ** 2
        # small cores, and one covering up to all the rest of the part
        cores = np.zeros(mask.shape, dtype=np.int64)
        for k in range(2, rng.integers(3, 6)):
            r, c = rng.integers(5, 55, 2)
            cores[((rows - r) ** 2 + (cols - c) ** 2 < rng.uniform(1, 6) ** 2) & mask] = k
        cores[mask & (cores == 0) & ((rows - 30) ** 2 + (cols - 30) ** 2 < rng.uniform(3, 40) ** 2)] = 1
        present = np.unique(cores[cores > 0])
        if len(present) < 2:
            continue
        cores = (np.searchsorted(present, cores) + 1) * (cores > 0)  # ids 1..n, each present
        pieces = contrast._nearest_core(mask, cores)
        area = np.bincount(pieces.ravel())[1:]
        assert np.all(area >= np.bincount(cores.ravel())[1:])
        too_small = contrast._a_piece_too_small(mask, cores)
        if too_small:
            assert area.min() < contrast.CONTRAST_SIZE_RATIO * area.max()
        if np.count_nonzero(cores) == np.count_nonzero(mask):  # the cores are the pieces: told exactly
            assert too_small == (area.min() < contrast.CONTRAST_SIZE_RATIO * area.max())
        told.append(too_small)
    assert 10 <= sum(told) <= len(told) - 10  # both answers drawn


def _ellipse_fit_numpy(points):
    """The direct least-squares ellipse fit written with numpy alone (Halir and Flusser)."""
    mean = points.mean(axis=0)
    scale = np.sqrt(np.mean(np.sum((points - mean) ** 2, axis=1))) or 1.0
    x, y = ((points - mean) / scale).T
    quadratic = np.column_stack([x * x, x * y, y * y])
    linear = np.column_stack([x, y, np.ones_like(x)])
    s1, s2, s3 = quadratic.T @ quadratic, quadratic.T @ linear, linear.T @ linear
    t = -np.linalg.solve(s3, s2.T)
    m = s1 + s2 @ t
    _, vectors = np.linalg.eig(np.array([m[2] / 2, -m[1], m[0] / 2]))
    vectors = np.real(vectors)
    elliptic = 4 * vectors[0] * vectors[2] - vectors[1] ** 2 > 0
    if not elliptic.any():
        return None, np.inf
    a, b, c = vectors[:, np.argmax(elliptic)]
    d, e, f = t @ [a, b, c]
    value = a * x * x + b * x * y + c * y * y + d * x + e * y + f
    gradient = np.hypot(2 * a * x + b * y + d, b * x + 2 * c * y + e)
    return (a, b, c, d, e, f, mean, scale), float(np.sum((scale * value / np.maximum(gradient, 1e-12)) ** 2))


def test_the_compiled_ellipse_fits_are_the_numpy_fits():
    rng = np.random.default_rng(11)
    sides = []
    for seed in range(40):
        outline = random_outline(seed)
        a = rng.integers(0, len(outline) - 20)
        b = rng.integers(a + 20, len(outline) + 1)
        sides += [outline, outline[a:b]]  # whole outlines, and stretches of 20 vertices or more
    sides.append(np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]]))  # on a line: singular
    fits = shapes._ellipse_fits(sides)
    for points, (conic, residual) in zip(sides, fits, strict=True):
        try:
            expected_conic, expected = _ellipse_fit_numpy(points)
        except np.linalg.LinAlgError:
            expected_conic, expected = None, np.inf
        assert (conic is None) == (expected_conic is None)
        if conic is None:
            assert residual == np.inf
            continue
        # the conic up to its sign (an eigenvector's), the residual in pixels^2
        sign = np.sign(np.dot(conic[:6], expected_conic[:6]))
        np.testing.assert_allclose(sign * np.array(conic[:6]), expected_conic[:6], rtol=1e-7, atol=1e-9)
        np.testing.assert_allclose(conic[6], expected_conic[6], rtol=1e-12)
        assert conic[7] == pytest.approx(expected_conic[7], rel=1e-12)
        assert residual == pytest.approx(expected, rel=1e-7, abs=1e-9)
    assert sum(conic is None for conic, _ in fits) >= 1
    assert shapes._ellipse_fit(sides[0])[1] == fits[0][1]



@pytest.mark.parametrize("seed", range(30))
def test_may_have_necks_gives_the_concavity_or_none_by_its_tests_in_either_order(seed):
    outline = random_outline(seed)
    region = window_of(outline)
    concavity = shapes._concavity(region, outline)
    found = necks._may_have_necks(region, outline, shapes.MIN_SPLIT_RADIUS)
    whole = scipy.ndimage.label(region)[1] == 1
    # each test refuses on its own, whichever is told first
    if whole and (np.count_nonzero(concavity >= shapes.MIN_WAIST_DEPTH) < 2
                  or necks._thinner_than(region, outline, shapes.MIN_SPLIT_RADIUS)):
        assert found is None
    distance = scipy.ndimage.distance_transform_edt(region)
    if scipy.ndimage.label((distance >= scipy.ndimage.maximum_filter(distance, size=3)) & region)[1] <= 1:
        assert found is None
    if found is not None:
        np.testing.assert_array_equal(found, concavity)


@pytest.mark.parametrize("seed", range(4))
def test_the_cyclic_gaussian_is_scipys_wrapped_gaussian_to_the_last_bit(seed):
    rng = np.random.default_rng(seed)
    for _ in range(100):
        # curves shorter than the kernel (wrapped more than once), and (K, 2) normals
        count, sigma = int(rng.integers(1, 300)), rng.uniform(0.1, 40)
        values = rng.normal(size=(count,) if rng.random() < 0.5 else (count, 2)) * 10 ** rng.uniform(-3, 3)
        np.testing.assert_array_equal(corners._cyclic_gaussian(values, sigma),
                                      scipy.ndimage.gaussian_filter1d(values, sigma, axis=0, mode="wrap"))


@pytest.mark.parametrize("reach", [1, 2, 5, 9, 30])
def test_within_reach_is_the_union_of_the_shifted_arrays(reach):
    rng = np.random.default_rng(reach)
    for count in (1, 3, 10, 19, 20, 61, 200):
        marked = rng.random(count) < rng.uniform(0.0, 0.2)
        expected = np.zeros(count, dtype=bool)
        for shift in range(-reach, reach + 1):
            expected |= np.roll(marked, shift)
        np.testing.assert_array_equal(corners._within(marked, reach), expected)


def _segment_inside_numpy(edges, a, b):
    """Whether segment a-b of a simple polygon lies inside it, written with numpy alone: no proper
    crossing of an edge (those at a and b aside), and the midpoint inside (signed crossings)."""
    start, end = edges
    count = len(start)
    p, q = start[a], start[b]

    def side(u, v, w):
        return ((v[..., 0] - u[..., 0]) * (w[..., 1] - u[..., 1])
                - (v[..., 1] - u[..., 1]) * (w[..., 0] - u[..., 0]))

    index = np.arange(count)
    away = (index != a) & ((index + 1) % count != a) & (index != b) & ((index + 1) % count != b)
    crossing = ((side(p, q, start) * side(p, q, end) < 0)
                & (side(start, end, p[None]) * side(start, end, q[None]) < 0))
    if np.any(crossing & away):
        return False
    middle = 0.5 * (p + q)
    up = (start[:, 0] <= middle[0]) & (end[:, 0] > middle[0])
    down = (start[:, 0] > middle[0]) & (end[:, 0] <= middle[0])
    turn = side(start, end, middle[None])
    return np.count_nonzero(up & (turn > 0)) != np.count_nonzero(down & (turn < 0))


def test_the_compiled_segment_test_is_the_numpy_one():
    rng = np.random.default_rng(4)
    answers = []
    for seed in range(20):
        outline = random_outline(seed)
        edges = outline, np.roll(outline, -1, axis=0)
        for _ in range(60):
            a, b = sorted(rng.choice(len(outline), 2, replace=False))
            answers.append(corners._segment_inside(edges, a, b))
            assert answers[-1] == _segment_inside_numpy(edges, a, b)
    assert 100 < sum(answers) < len(answers) - 100  # both answers drawn


def _cut_ratio_numpy(part, normals, a, b):
    """The neck ratio of the cut (a, b) of a part as :func:`corners._cuts` defines it (infinity
    when it has no length or a normal does not face it)."""
    direction = part[b] - part[a]
    length = np.hypot(*direction)
    if length == 0:
        return np.inf
    direction = direction / length
    least = np.cos(np.radians(corners.CUT_ALIGN))
    if -normals[a] @ direction < least or normals[b] @ direction < least:
        return np.inf
    along = (part - part.mean(axis=0)) @ direction
    extent = min(np.ptp(along[a:b + 1]), np.ptp(np.concatenate([along[b:], along[:a + 1]])))
    return length / max(extent, 1e-12)


def test_the_compiled_cut_ratios_are_the_numpy_ones():
    rng = np.random.default_rng(6)
    finite = 0
    for seed in range(20):
        outline = random_outline(seed)
        _, _, normals = corners._concave_corners(outline)
        pairs = np.sort(np.array([rng.choice(len(outline), 2, replace=False) for _ in range(80)]), axis=1)
        ratios = np.empty(len(pairs))
        _kernels.cut_ratios(outline, outline - outline.mean(axis=0), normals,
                                  pairs[:, 0].copy(), pairs[:, 1].copy(),
                                  float(np.cos(np.radians(corners.CUT_ALIGN))), ratios)
        expected = np.array([_cut_ratio_numpy(outline, normals, a, b) for a, b in pairs])
        np.testing.assert_array_equal(np.isinf(ratios), np.isinf(expected))
        np.testing.assert_allclose(ratios[np.isfinite(ratios)], expected[np.isfinite(expected)], rtol=1e-13)
        finite += np.count_nonzero(np.isfinite(expected))
    assert 50 < finite < 20 * 80 - 50  # cuts facing their normals, and cuts that do not


def _ray_hits_numpy(outline, cycle, edges, positions, normals):
    """The definition of :func:`corners._ray_hits` in numpy (all rays against all edges)."""
    count = len(cycle)
    start, edge = edges[0], edges[1] - edges[0]
    original = np.roll(cycle, -1) == (cycle + 1) % len(outline)
    turns = [np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
             for angle in np.radians(corners.CUT_RAYS)]
    rays = np.array([[-turn @ normals[cycle[a]] for turn in turns] for a in positions])
    offset = start[None, :, :] - start[positions][:, None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        denominator = (rays[:, :, 0, None] * edge[None, None, :, 1]
                       - rays[:, :, 1, None] * edge[None, None, :, 0])
        along_ray = ((offset[:, :, 0] * edge[:, 1] - offset[:, :, 1] * edge[:, 0])[:, None, :]
                     / denominator)
        along_edge = (offset[:, None, :, 0] * rays[:, :, 1, None]
                      - offset[:, None, :, 1] * rays[:, :, 0, None]) / denominator
    index = np.arange(count)
    away = (index[None, :] != positions[:, None]) & ((index[None, :] + 1) % count != positions[:, None])
    hit = ((np.abs(denominator) > 1e-12) & (along_ray > 1e-9) & (along_edge >= 0) & (along_edge <= 1)
           & away[:, None, :])
    nearest = np.argmin(np.where(hit, along_ray, np.inf), axis=2)
    corner, angle = np.indices(nearest.shape)
    b = np.where(along_edge[corner, angle, nearest] < 0.5, nearest, (nearest + 1) % count)
    a = positions[corner]
    chosen = hit[corner, angle, nearest] & original[nearest] & (b != a)
    return list(zip(a[chosen].tolist(), b[chosen].tolist(), strict=True))


def test_the_compiled_ray_hits_are_the_numpy_ones():
    """Rays from random vertices of whole outlines and of parts cut from them (a cut's edge is
    no edge of the object's outline), and from vertices next to the part's start and end."""
    rng = np.random.default_rng(7)
    found = 0
    for seed in range(30):
        outline = random_outline(seed)
        _, _, normals = corners._concave_corners(outline)
        for _ in range(4):
            if rng.random() < 0.5:
                cycle = np.arange(len(outline))
            else:
                a, b = np.sort(rng.choice(len(outline), 2, replace=False))
                cycle = np.arange(a, b + 1)
            edges = outline[cycle], np.roll(outline[cycle], -1, axis=0)
            positions = np.unique(np.r_[rng.choice(len(cycle), min(len(cycle), 5), replace=False), 0,
                                        len(cycle) - 1])
            hits = corners._ray_hits(outline, cycle, edges, positions, normals)
            assert hits == _ray_hits_numpy(outline, cycle, edges, positions, normals)
            found += len(hits)
    assert found > 100


def test_a_split_by_contrast_needs_two_pixels_min_radius_inside():
    # a bright and a dim disk side by side, without a waist: split by contrast, and the test
    # before it lets it through; a bar 4 px wide has no pixel 3 px from its outside
    rows, cols = np.mgrid[:40, :60]
    bright = (rows - 20) ** 2 + (cols - 20) ** 2 <= 12 ** 2
    dim = (rows - 20) ** 2 + (cols - 38) ** 2 <= 12 ** 2
    region = np.pad(bright | dim, 1)
    values = np.pad(np.where(bright, 1.0, 0.4), 1)
    assert contrast._may_split_by_contrast(region, shapes.MIN_SPLIT_RADIUS)
    assert contrast._contrast_parts(region.astype(np.int32), values, 0.2, shapes.MIN_SPLIT_RADIUS).max() == 2
    bar = np.zeros((12, 60), dtype=bool)
    bar[3:7, 2:58] = True
    assert not contrast._may_split_by_contrast(bar, shapes.MIN_SPLIT_RADIUS)
    assert not contrast._may_split_by_contrast(np.pad(np.ones((7, 7), dtype=bool), 1), 3.0)  # 49 < 2 pi 9


def test_convex_clip_area_is_the_area_of_the_intersection():
    # a U of three unit-wide bars (area 7 in a 3 x 3 box: its slot 1 x 2 open at the top) clipped by
    # the box's lower half, a convex window, in either orientation: 3 x 1.5 less the slot's 1 x 0.5
    u_shape = np.array([[0, 0], [3, 0], [3, 3], [2, 3], [2, 1], [1, 1], [1, 3], [0, 3]], dtype=float)
    window = np.array([[-1, -1], [4, -1], [4, 1.5], [-1, 1.5]], dtype=float)
    for polygon in (u_shape, u_shape[::-1].copy()):
        for convex in (window, window[::-1].copy()):
            assert _kernels.convex_clip_area(polygon, convex) == pytest.approx(3 * 1.5 - 0.5, rel=1e-14)
    # a window across both arms only: two pieces, the slot between them not counted
    across = np.array([[2.0, -1], [2.5, -1], [2.5, 4], [2.0, 4]])
    assert _kernels.convex_clip_area(u_shape, np.array([[0.5, 2], [2.5, 2], [2.5, 2.5], [0.5, 2.5]])) == \
        pytest.approx(2 * 0.5 * 0.5, rel=1e-14)
    assert _kernels.convex_clip_area(u_shape, across) == pytest.approx(0.5 * 3, rel=1e-14)
    # disjoint, and the window holding all of it
    assert _kernels.convex_clip_area(u_shape, window + 10) == 0.0
    assert _kernels.convex_clip_area(u_shape, 10 * window) == pytest.approx(7.0, rel=1e-14)


@pytest.mark.parametrize("seed", range(10))
def test_convex_clip_area_is_geos_intersection_area(seed):
    outline = random_outline(seed)
    ellipse = (outline.mean(axis=0) + [2.0, -1.5], np.array([9.0, 5.0]), np.array([[0.6, -0.8], [0.8, 0.6]]))
    shape = shapes._ellipse_polygon(ellipse)
    expected = shapely.intersection(shapely.Polygon(shape), shapely.Polygon(outline)).area
    got = _kernels.convex_clip_area(np.ascontiguousarray(outline), shape)
    assert got == pytest.approx(expected, rel=1e-12)


def _circle_points(centre, semi_axes, count=40, turn=0.0):
    angle = np.linspace(0, 2 * np.pi, count, endpoint=False)
    local = np.column_stack([semi_axes[0] * np.cos(angle), semi_axes[1] * np.sin(angle)])
    rotation = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    return np.asarray(centre) + local @ rotation.T


def test_the_closed_form_ellipse_gate_rejects_what_arc_ellipse_rejects_by_shape():
    # exact ellipses: their fits are the ellipses themselves, so the truth is known
    object_outline = _circle_points((100.0, 100.0), (80.0, 80.0), count=400)  # holds them all
    cases = {  # (semi-axes): what _arc_ellipse must say
        (10.0, 10.0): True, (12.0, 4.0): True,  # radius sqrt(48) > 3, aspect 3 < 4
        (2.0, 2.0): False,  # radius 2 < MIN_SPLIT_RADIUS
        (30.0, 5.0): False,  # aspect 6 > MAX_PART_ASPECT
    }
    sides = [_circle_points((100.0, 90.0), axes, turn=0.3) for axes in cases]
    conics, found, residuals = shapes._stacked_ellipse_fits(sides)
    rejected = shapes._clearly_not_arc_ellipses(conics, found, residuals, [len(side) for side in sides])
    for side, fit, no, (axes, expected) in zip(sides, shapes._as_fits(conics, found, residuals), rejected,
                                               cases.items(), strict=True):
        assert (shapes._arc_ellipse(side, fit, object_outline) is not None) == expected, axes
        assert bool(no) == (not expected), axes


@pytest.mark.parametrize("seed", range(12))
def test_the_closed_form_ellipse_gate_never_rejects_an_ellipse_arc_ellipse_keeps(seed):
    outline = random_outline(seed)
    rng = np.random.default_rng(seed)
    sides = []
    for _ in range(30):  # stretches of the outline, as the arc grouping fits them
        a = rng.integers(0, len(outline) - 8)
        sides.append(outline[a:rng.integers(a + 8, len(outline) + 1)])
    conics, found, residuals = shapes._stacked_ellipse_fits(sides)
    rejected = shapes._clearly_not_arc_ellipses(conics, found, residuals, [len(side) for side in sides])
    for side, fit, no in zip(sides, shapes._as_fits(conics, found, residuals), rejected, strict=True):
        if no:
            assert shapes._arc_ellipse(side, fit, outline) is None


def test_a_part_around_a_hole_is_seen_on_the_pixels_and_its_piece_has_the_hole():
    # a 40 x 60 px block with a 6 x 6 px hole; two pixel parts, the left and the right half
    outer = orient(np.array([[0.0, 0.0], [0.0, 60.0], [40.0, 60.0], [40.0, 0.0]]))
    parts = np.zeros((44, 64), dtype=np.int32)  # window: the block's pixels, and a margin
    parts[1:41, 1:31], parts[1:41, 31:61] = 1, 2
    low = np.array([-1, -1])
    # a hole well inside the left part, and one across the border between the parts
    for corner, inside_one in (((15.0, 10.0), True), ((15.0, 27.0), False)):
        hole = orient(np.array([[0.0, 0.0], [0.0, 6.0], [6.0, 6.0], [6.0, 0.0]]) + corner)[::-1]
        curves = [outer, hole]
        assert corners._around_a_hole(curves, parts, low) == inside_one
        # what the shortcut stands for: the piece of that part, cut out of the polygon, has the hole
        pieces = corners._cut(curves, parts, low)
        assert any(len(piece) > 1 for piece in pieces) == inside_one


def test_an_outline_under_twice_the_smallest_part_is_split_without_its_curvature(monkeypatch):
    """An L of 39 px^2 (under 2 pi MIN_SPLIT_RADIUS^2), its inner corner 1.4 px inside its hull:
    past the concavity gate, but neither the arc stage nor the corner stage reads its curvature,
    so it is not computed, and the object stays whole."""
    import activecontour.objects.split as split

    outline = orient(np.array([[2.0, 2.0], [2.0, 10.0], [5.0, 10.0], [5.0, 5.0], [10.0, 5.0], [10.0, 2.0]]))
    assert signed_area(outline) < 2 * np.pi * shapes.MIN_SPLIT_RADIUS ** 2
    assert shapes._hull_depth(outline).max() >= shapes.MIN_WAIST_DEPTH
    labels = rasterize([outline], (14, 14)).astype(np.int32)

    def unread(_):
        raise AssertionError("the curvature was computed")

    monkeypatch.setattr(split, "_bent", unread)
    (kept,), = split.split_touching([[outline]], labels)
    np.testing.assert_array_equal(kept, outline)


@pytest.mark.parametrize("seed", range(6))
def test_the_meeting_counts_are_those_of_each_part_dilated_over_the_whole_window(seed):
    # _meeting dilates each part on its own box grown by ARC_REACH: the counts of parts within
    # reach must be those of the whole-window dilations (parts touching the window's edge too)
    import activecontour.objects.arcs as arcs

    rng = np.random.default_rng(seed)
    reach = int(arcs.ARC_REACH)
    rows, cols = np.mgrid[-reach:reach + 1, -reach:reach + 1]
    disk = rows**2 + cols**2 <= arcs.ARC_REACH**2
    for _ in range(10):
        m, n = rng.integers(12, 60, 2)
        count = int(rng.integers(3, 9))
        # cells of random centres over a random blob, so parts meet in threes here and there
        centres = rng.uniform(0, (m, n), (count, 2))
        grid = np.indices((m, n)).transpose(1, 2, 0)
        parts = np.argmin(((grid[:, :, None, :] - centres) ** 2).sum(axis=3), axis=2).astype(np.int32) + 1
        inside = scipy.ndimage.gaussian_filter(rng.random((m, n)), 3) > 0.45
        parts[~inside] = 0
        present = np.unique(parts[parts > 0])
        lookup = np.zeros(count + 2, dtype=np.int32)
        lookup[present] = np.arange(1, present.size + 1)
        parts = lookup[parts]
        count = int(parts.max())
        if count < 3:
            continue
        near = sum(scipy.ndimage.binary_dilation(parts == k, disk).astype(np.int8)
                   for k in range(1, count + 1))
        # every pixel a corner: no border is turned down for where it ends
        corners_ = np.argwhere(inside)
        assert arcs._meeting(parts, inside, corners_, count) == (int(near.max()),
                                                                 scipy.ndimage.label(near >= 3)[1])


@pytest.mark.parametrize("seed", range(12))
def test_the_traced_cells_of_a_tiling_never_overlap(seed):
    """What :func:`corners._cut` stands on: the cells of any tiling of the pixels by labels, traced
    one by one (marching squares at 0.5: a cell's two diagonal pixels of a grid square get two
    corners), share their borders and overlap nowhere, saddles and places where four meet too."""
    from activecontour.geometry.raster import mask_to_curves
    from activecontour.geometry.regions import _to_shapely

    rng = np.random.default_rng(seed)
    cells = rng.integers(1, rng.integers(2, 6), size=(9, 11))
    cells[2:4, 3:5] = [[1, 2], [2, 1]]  # a saddle, whatever the draw
    cells = np.unique(cells, return_inverse=True)[1].reshape(cells.shape) + 1
    geometries = [_to_shapely(mask_to_curves(cells == j)) for j in range(1, cells.max() + 1)]
    for j, first in enumerate(geometries):
        for second in geometries[j + 1:]:
            assert shapely.intersection(first, second).area == 0.0
    assert sum(g.area for g in geometries) <= cells.size


def _cut_by_overlays(curves, parts, low):
    """:func:`corners._cut` as it was made before: each traced cell less the union of the earlier
    cells its box meets (one overlay each), then the same simplification and intersection."""
    import activecontour.geometry.regions as regions
    from activecontour.geometry.raster import mask_to_curves

    nearest = scipy.ndimage.distance_transform_edt(parts == 0, return_distances=False, return_indices=True)
    cells = parts[tuple(nearest)]
    boxes = scipy.ndimage.find_objects(cells)
    geometries = [regions._to_shapely([c + low + (box[0].start, box[1].start)
                                       for c in mask_to_curves(cells[box] == j)])
                  for j, box in enumerate(boxes, start=1)]
    tree = shapely.STRtree(geometries)
    for j, cell in enumerate(geometries):
        earlier = [k for k in tree.query(cell) if k < j]
        if earlier:
            geometries[j] = shapely.difference(cell, shapely.union_all([geometries[k] for k in earlier]))
    return geometries


@pytest.mark.parametrize("seed", range(20))
def test_the_cut_orients_the_cells_as_the_overlays_left_them(seed, monkeypatch):
    """The cells :func:`corners._cut` simplifies are the cells less their empty overlaps with the
    earlier ones, oriented as those overlays leave them (the overlays are not made): the same
    pieces to the bit as from the overlays' cells, on random outlines cut into the pixel cells
    of two to four random seeds."""
    outline = random_outline(seed)
    rng = np.random.default_rng(seed)
    low = np.floor(outline.min(axis=0)).astype(int) - 1
    window = tuple(np.ceil(outline.max(axis=0)).astype(int) - low + 2)
    pixels = np.argwhere(rasterize([outline - low], window))
    seeds = pixels[rng.choice(len(pixels), size=min(len(pixels), rng.integers(2, 5)), replace=False)]
    nearest = np.argmin(((pixels[:, None, :] - seeds[None]) ** 2).sum(axis=2), axis=1)
    parts = np.zeros(window, dtype=np.int32)
    parts[tuple(pixels.T)] = nearest + 1
    parts = np.unique(parts, return_inverse=True)[1].reshape(parts.shape).astype(np.int32)
    ours = corners._cut([outline], parts, low)
    simplify = shapely.coverage_simplify
    monkeypatch.setattr(shapely, "coverage_simplify", lambda geometries, *args, **kwargs: simplify(
        _cut_by_overlays([outline], parts, low), *args, **kwargs))
    theirs = corners._cut([outline], parts, low)
    assert len(ours) == len(theirs) > 0
    for mine, other in zip(ours, theirs, strict=True):
        assert len(mine) == len(other)
        for a, b in zip(mine, other, strict=True):
            np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("seed", range(10))
def test_the_region_of_one_outline_is_the_nested_one(seed):
    """:func:`activecontour.geometry.regions._to_shapely` skips the nesting for one positive
    outline only: the same geometry to the bit as the curves nested into outer boundaries and
    holes, for an outline, a hole alone, an outline with a hole, and a self-touching outline."""
    from activecontour.geometry.regions import _to_shapely, group_curves

    def nested(curves):
        polygons = [shapely.Polygon(obj[0], holes=obj[1:]) for obj in group_curves(curves)]
        return shapely.make_valid(shapely.MultiPolygon(polygons) if len(polygons) != 1 else polygons[0])

    outline = random_outline(seed)
    hole = orient(outline[::3] * 0.2 + outline.mean(axis=0) * 0.8, hole=True)
    bow = orient(np.array([[0.0, 0.0], [0.0, 4.0], [2.0, 2.0], [4.0, 4.0], [4.0, 0.0], [2.0, 2.0]]) + seed)
    for curves in ([outline], [hole], [outline, hole], [bow]):
        assert shapely.to_wkb(_to_shapely(curves)) == shapely.to_wkb(nested(curves))
