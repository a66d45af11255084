"""N regions on the polygon backend: the boundary network, its H^1 flow and the region evaluator."""

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import activecontour as ac
from activecontour.backends.network import Network, h1, segment_network
from activecontour.backends.network.steps import Steps
from activecontour.energy import evaluate_partition
from activecontour.geometry.partition import chain, class_boundary, class_soup
from activecontour.geometry.raster import rasterize
from activecontour.imaging.normalize import normalize_image
from activecontour.imaging.tables import ImageModel
from activecontour.models import ChanVeseParameters


def _antialiased(shape, classify, levels, factor=8):
    """The image of a partition with constant ``levels`` per region, each pixel the mean over
    ``factor x factor`` sub-samples (exact area fractions up to 1/factor^2), and the region of
    every pixel centre."""
    m, n = shape
    offsets = (np.arange(factor) + 0.5) / factor - 0.5
    rows = np.arange(m)[:, None, None, None] + offsets[None, None, :, None]
    cols = np.arange(n)[None, :, None, None] + offsets[None, None, None, :]
    fine = classify(rows + 0 * cols, cols + 0 * rows)
    image = np.asarray(levels, dtype=np.float64)[fine].mean(axis=(2, 3))
    centre = classify(np.arange(m)[:, None] + 0.0 * np.arange(n), 0.0 * np.arange(m)[:, None] + np.arange(n))
    return image, centre


def _rings(centre, radii):
    def classify(r, c):
        distance = np.hypot(r - centre[0], c - centre[1])
        return sum((distance < radius).astype(int) for radius in radii)
    return classify


def _sectors(centre):
    """Three 120 degree sectors meeting at ``centre`` (a Y junction)."""
    def classify(r, c):
        angle = np.mod(np.arctan2(r - centre[0], c - centre[1]) + np.pi / 2, 2 * np.pi)
        return np.minimum((angle / (2 * np.pi / 3)).astype(int), 2)
    return classify


def _setup(image, mu):
    values = normalize_image(image, normalize=None, color="vector")
    return ImageModel(values), ChanVeseParameters(mu)


def test_regions_evaluator_is_the_classes_evaluator_on_a_label_partition():
    classes = np.random.default_rng(0).integers(0, 4, (13, 17))
    classes[4:9, 5:12] = 2  # a block: straight interfaces and junctions at its corners
    image = np.random.default_rng(1).random(classes.shape)
    boundary = class_boundary(classes)
    regions = [chain(*class_soup(boundary, k)) for k in range(4)]
    by_classes = ac.chan_vese_energy(image, classes=classes, mu=0.3, omega=0.2, lambda_out=0.7)
    by_regions = ac.chan_vese_energy(image, regions=regions, mu=0.3, omega=0.2, lambda_out=0.7)
    assert by_regions == pytest.approx(by_classes, rel=1e-12)


def test_regions_must_tile_the_domain():
    image = np.zeros((10, 10))
    square = np.array([[2.0, 2.0], [2.0, 6.0], [6.0, 6.0], [6.0, 2.0]])[::-1]  # positive
    border = np.array([[-0.5, -0.5], [9.5, -0.5], [9.5, 9.5], [-0.5, 9.5]])
    with pytest.raises(ValueError, match="do not tile the image domain"):
        ac.chan_vese_energy(image, regions=[[border], [square]], mu=0.1)
    with pytest.raises(TypeError, match="one of contours, classes or regions"):
        ac.chan_vese_energy(image, [square], regions=[[border], [square]])


def test_network_force_is_the_gradient_of_the_energy_at_every_kind_of_node():
    image, classes = _antialiased((20, 24), _sectors((9.3, 11.6)), [0.1, 0.5, 0.9])
    image += np.random.default_rng(2).normal(0, 0.05, image.shape)
    model, params = _setup(image, 0.2)
    network = Network.of_classes(classes)
    shift = np.random.default_rng(3).uniform(-0.2, 0.2, network.nodes.shape)
    nodes = network.nodes + shift * np.column_stack(network.free)  # off the lattice, border nodes on it
    constants = evaluate_partition(model, network.boundary(nodes), params, 3).constants
    force = h1.nodal_force(network, nodes, model, params, constants)
    degree = np.bincount(np.concatenate([network.start[network.interface], network.end[network.interface]]),
                         minlength=len(nodes))
    junction = np.flatnonzero(degree >= 3)
    sliding = np.flatnonzero(network.free[0] ^ network.free[1])
    plain = np.flatnonzero((degree == 2) & network.free[0] & network.free[1])
    assert junction.size == 1 and sliding.size == 3
    for node in [*junction, *sliding, *plain[::7]]:
        for axis in np.flatnonzero([network.free[0][node], network.free[1][node]]):
            step = 1e-6
            energy = []
            for sign in (1, -1):
                moved = nodes.copy()
                moved[node, axis] += sign * step
                energy.append(evaluate_partition(model, network.boundary(moved), params, 3, constants).energy)
            numeric = (energy[0] - energy[1]) / (2 * step)
            assert numeric == pytest.approx(force[node, axis], abs=1e-6 * max(1.0, abs(force[node, axis])))


def _moved_networks(count, seed):
    """Random networks of 3 regions, resampled, their free nodes moved by noise of several sizes
    (some nodes put exactly on another segment's midpoint): many crossing, many not."""
    import scipy.ndimage

    rng = np.random.default_rng(seed)
    for _ in range(count):
        classes = (rng.random((24, 30)) < rng.uniform(0.2, 0.6)).astype(int) + (rng.random((24, 30)) < 0.3)
        network = Network.of_classes(scipy.ndimage.median_filter(classes, 3))
        if not network.interface.any():
            continue
        network, nodes = network.resampled(network.nodes, rng.uniform(0.5, 2.0))
        free = (network.free[0] | network.free[1])[:, None]
        moved = nodes + rng.choice([0.0, 0.02, 0.1, 0.3]) * rng.normal(size=nodes.shape) * free
        if rng.random() < 0.3:
            node = rng.choice(np.flatnonzero(network.free[0] & network.free[1]))
            segment = rng.integers(len(network.start))
            moved[node] = 0.5 * (moved[network.start[segment]] + moved[network.end[segment]])
        yield network, nodes, moved


def test_simple_network_is_geos_simple_interfaces():
    # the compiled test against GEOS's is_simple of the interface segments as one multi-line string
    import shapely

    verdicts = set()
    for network, _, moved in _moved_networks(120, 7):
        chosen = np.flatnonzero(network.interface)
        lines = shapely.multilinestrings(
            [shapely.linestrings(moved[[a, b]]) for a, b in zip(network.start[chosen], network.end[chosen],
                                                                 strict=True)])
        expected = bool(shapely.is_simple(lines))
        assert network.simple(moved) == expected
        verdicts.add(expected)
    assert verdicts == {True, False}


def test_one_pass_moments_are_each_regions_green_integrals():
    # every region's moments from its own closed soup of segments (two passes over an interface),
    # on partitions (the background's are the domain's less the others')
    from activecontour.energy import partition_moments, soup_moments

    image = np.random.default_rng(8).random((24, 30))
    model, _ = _setup(image, 0.1)
    checked = 0
    for network, nodes, moved in _moved_networks(12, 9):
        steps, dt = Steps(network, nodes, moved - nodes), 1.0
        while not (steps.admissible(dt, nodes + dt * (moved - nodes))
                   and network.simple(nodes + dt * (moved - nodes))):
            dt *= 0.5
        checked += bool(np.any(moved != nodes))
        boundary = network.boundary(nodes + dt * (moved - nodes))
        areas, first, second = partition_moments(model, boundary, 3)
        for k in range(3):
            expected = soup_moments(model, *class_soup(boundary, k))
            np.testing.assert_allclose([areas[k], first[k, 0], second[k, 0]],
                                       [expected[0], expected[1][0], expected[2][0]], rtol=1e-10, atol=1e-9)
    assert checked >= 3


def test_steps_admit_what_the_direct_tests_admit():
    # the bounds of an iteration's steps against the tests on every trial: no segment reversed
    # (its new direction keeps a quarter of its length along the old one), every node in the
    # image, every face's signed area of the same sign
    rng = np.random.default_rng(10)
    verdicts = set()
    for network, nodes, _ in _moved_networks(40, 11):
        velocity = rng.normal(size=nodes.shape) * np.column_stack(network.free)
        steps = Steps(network, nodes, velocity)
        sign = np.sign(network.face_areas(nodes))
        m, n = network.shape
        old = nodes[network.end] - nodes[network.start]
        for dt in 2.0 ** -np.arange(8):
            trial = nodes + dt * velocity
            new = trial[network.end] - trial[network.start]
            expected = bool(np.all(np.sum(old * new, axis=1) > 0.25 * np.sum(old * old, axis=1))
                            and np.all((trial >= -0.5) & (trial <= np.array([m - 0.5, n - 0.5])))
                            and np.all(np.sign(network.face_areas(trial)) == sign))
            assert steps.admissible(dt, trial) == expected
            verdicts.add(expected)
    assert verdicts == {True, False}


def test_resampling_keeps_branch_nodes_and_puts_equal_steps_on_the_lines():
    rng = np.random.default_rng(12)
    for network, _, nodes in _moved_networks(30, 13):  # off the lattice
        spacing = rng.uniform(0.5, 2.0)
        resampled, new_nodes = network.resampled(nodes, spacing)
        path, offsets, inner, outer, closed = network.polylines()
        new_path, new_offsets, new_inner, new_outer, new_closed = resampled.polylines()
        assert np.array_equal(closed, new_closed)
        for k in range(len(closed)):
            old_line = nodes[path[offsets[k]:offsets[k + 1]]]
            new_line = new_nodes[new_path[new_offsets[k]:new_offsets[k + 1]]]
            if closed[k]:
                old_line, new_line = np.vstack([old_line, old_line[:1]]), np.vstack([new_line, new_line[:1]])
            else:  # the branch nodes stay, and the regions on either side
                np.testing.assert_array_equal(new_line[[0, -1]], old_line[[0, -1]])
            assert (new_inner[k], new_outer[k]) == (inner[k], outer[k])
            arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(old_line, axis=0).T))])
            pieces = max(3 if closed[k] or np.array_equal(old_line[0], old_line[-1]) else 2,
                         int(np.rint(arc[-1] / spacing)))
            assert len(new_line) - 1 == pieces
            # every sample at its arc length along the old line
            at = np.arange(pieces + 1) * arc[-1] / pieces
            expected = np.column_stack([np.interp(at, arc, old_line[:, d]) for d in range(2)])
            np.testing.assert_allclose(new_line, expected, atol=1e-9)


def test_velocity_solves_the_h1_system_on_the_free_nodes():
    # the banded factorisation in the graph's reverse Cuthill-McKee order against the sparse matrix
    rng = np.random.default_rng(14)
    for network, _, nodes in _moved_networks(10, 15):
        force = rng.normal(size=nodes.shape)
        velocity = h1.velocity(network, nodes, force)
        matrix = h1.stiffness(network, nodes)
        for component, free in enumerate(network.free):
            index = np.flatnonzero(free)
            assert np.all(velocity[~free, component] == 0)
            np.testing.assert_allclose(matrix[index][:, index] @ velocity[index, component],
                                       -force[index, component], atol=1e-9 * max(1.0, np.abs(force).max()))


def test_h1_form_integrates_linear_functions_and_kills_constants():
    _, classes = _antialiased((30, 30), _rings((14.2, 15.1), [11.0, 5.0]), [0, 1, 2])
    network = Network.of_classes(classes)
    nodes = network.nodes
    matrix = h1.stiffness(network, nodes, smoothing=1.0).toarray()
    mass = h1.stiffness(network, nodes, smoothing=0.0).toarray()
    stiffness = matrix - mass
    ones = np.ones(len(nodes))
    np.testing.assert_allclose(stiffness @ ones, 0.0, atol=1e-12)
    # int_Gamma x_r ds: per segment its length times its midpoint's row
    a, b = network.start[network.interface], network.end[network.interface]
    exact = np.sum(np.linalg.norm(nodes[b] - nodes[a], axis=1) * 0.5 * (nodes[a, 0] + nodes[b, 0]))
    assert ones @ mass @ nodes[:, 0] == pytest.approx(exact, rel=1e-12)


def test_flow_moves_interfaces_to_subpixel_position():
    centre, radii = (31.37, 32.81), [24.6, 11.3]
    image, classes = _antialiased((64, 66), _rings(centre, radii), [0.1, 0.5, 0.9])
    model, params = _setup(image, 1e-3)
    labels = ac.segment(image, n_regions=3, backend="levelset", mu=1e-3, normalize=None)
    result = segment_network(model, None, params, n_regions=3, max_num_iter=500, tol=5e-4, callback=None)
    assert result.status == 0
    assert result.energy < labels.energy
    assert np.all(np.diff(result.energies) <= 1e-12 * np.abs(result.energies[1:]))

    def radius_error(res, k, radius):
        outer = max(res.class_contours[k], key=len)
        return np.sqrt(np.mean((np.hypot(*(outer - centre).T) - radius) ** 2))

    # the label field's boundary is a staircase through pixel midpoints; the network's is as close
    # as the two-region polygon's on a disk of the same radius (the bilinear image's own limit)
    disk, _ = _antialiased((64, 66), _rings(centre, radii[:1]), [0.1, 0.9])
    two_region = ac.segment(disk, mu=1e-3, normalize=None)
    limit = np.sqrt(np.mean((np.hypot(*(two_region.contours[0] - centre).T) - radii[0]) ** 2))
    for k, radius in zip((1, 2), radii, strict=True):
        assert radius_error(labels, k, radius) > 0.15
        assert radius_error(result, k, radius) < 1.25 * limit + 0.01


def test_junction_moves_to_where_the_three_regions_meet():
    # three colours at equal distances: the blur of two is nearer either of them than the third,
    # so no region lines the interface between the other two
    centre = (20.3, 21.7)
    image, classes = _antialiased((40, 42), _sectors(centre), [[0, 0, 0], [1, 0, 0], [0.5, 0.75**0.5, 0]])
    model, params = _setup(image, 1e-3)
    result = segment_network(model, None, params, n_regions=3, max_num_iter=500, tol=5e-4, callback=None)
    start = Network.of_classes(classes)
    degree = np.bincount(np.concatenate([start.start[start.interface], start.end[start.interface]]),
                         minlength=len(start.nodes))
    assert np.count_nonzero(degree == 3) == 1
    assert np.hypot(*(start.nodes[degree == 3][0] - centre)) > 0.2  # the lattice's junction
    points = np.concatenate([np.concatenate(region) for region in result.class_contours])
    keys, counts = np.unique(np.round(points, 12), axis=0, return_counts=True)
    junction = keys[counts == 3]  # the one vertex on the boundary of all three regions
    assert len(junction) == 1
    assert np.hypot(*(junction[0] - centre)) < 0.1


def test_polygon_result_obeys_the_invariants_and_is_stationary():
    image, truth = _antialiased((80, 90), _rings((40.2, 44.6), [30.3, 14.1]), [0.2, 0.9, 0.5])
    image = image + np.random.default_rng(4).normal(0, 0.08, image.shape)
    res = ac.segment(image, n_regions=3)
    assert res.backend == "polygon" and res.success
    assert res.energies[-1] == res.energy
    assert res.energy == pytest.approx(ac.chan_vese_energy(image, regions=res.class_contours, mu=res.mu),
                                       rel=1e-12)
    assert np.array_equal(res.mask, res.classes > 0)
    # classes: 0 the background (on the border), then by mean: the middle ring is the brightest
    order = {0: 0, 2: 1, 1: 2}
    assert np.mean(np.vectorize(order.get)(truth) == res.classes) > 0.99
    # converged means stationary: a 100x smaller tol changes J and the regions by < 0.1 %
    finer = ac.segment(image, n_regions=3, tol=5e-6)
    assert abs(finer.energy - res.energy) <= 1e-3 * abs(res.energy)
    assert np.sum(finer.classes != res.classes) <= 1e-3 * np.sum(res.classes > 0)


def test_dropping_an_island_merges_it_into_the_region_around_it():
    classes = np.zeros((16, 18), dtype=np.int32)
    classes[3:12, 4:14] = 1
    classes[6:8, 7:9] = 2  # an island of region 2 inside region 1
    classes[13, 2] = 2  # and one in the background
    image = np.random.default_rng(5).random(classes.shape)
    model, params = _setup(image, 0.3)
    network = Network.of_classes(classes)
    loops = {len(loop): loop for loop, _ in network.closed_loops(network.nodes)}
    assert sorted(loops) == [4, 8, 38]  # the speck, the 2 x 2 island, the block's outline
    areas = sorted(area for _, area in network.closed_loops(network.nodes))
    # the lattice partition: a pixel's square with its corners cut (1 - 4/8), the island's
    # 2 x 2 square less its corners (4 - 4/8), the block's 9 x 10 less its corners (90 - 4/8)
    np.testing.assert_allclose(areas, [0.5, 3.5, 89.5])
    for size, around, box in ((4, 0, (13, 2)), (8, 1, (slice(6, 8), slice(7, 9)))):
        merged = classes.copy()
        merged[box] = around
        dropped = network.without_island(network.nodes, loops[size])
        expected = evaluate_partition(model, class_boundary(merged), params, 3).energy
        found = evaluate_partition(model, dropped.boundary(), params, 3).energy
        assert found == pytest.approx(expected, rel=1e-12)
    # the block's outline holds the island: dropping it would need the island's regions renamed
    assert network.without_island(network.nodes, loops[38]) is None


def test_dropping_loops_carries_the_faces_and_pieces_over_as_found_afresh():
    classes = np.zeros((20, 22), dtype=np.int32)
    classes[3:12, 4:14] = 1
    classes[6:8, 7:9] = 2  # an island inside region 1
    classes[15:17, 3:5] = classes[14, 18] = 2  # two in the background
    classes[16:19, 10:13] = 1
    network = Network.of_classes(classes)
    network.faces()
    areas = network.closed_areas(network.nodes)[0]
    loops = [network.loop_segments(k) for k in range(len(areas))]
    for dropped in ([0], [len(loops) - 1], [0, 2]):
        keep = np.ones(len(network.start), dtype=bool)
        keep[np.concatenate([loops[k] for k in dropped])] = False
        smaller = network.without_loops(keep, network.nodes)
        assert smaller._faces is not None and smaller._pieces is not None  # carried, not found again
        fresh = Network(network.nodes, network.start[keep], network.end[keep], network.inner[keep],
                        network.outer[keep], network.shape)
        for carried, found in zip(smaller.faces(), fresh.faces(), strict=True):
            np.testing.assert_array_equal(carried, found)
        carried, found = smaller.closed_areas(network.nodes)[0], fresh.closed_areas(network.nodes)[0]
        np.testing.assert_array_equal(carried, found)
        assert len(found) == len(loops) - len(dropped)
        for k in range(len(found)):
            np.testing.assert_array_equal(smaller.loop_segments(k), fresh.loop_segments(k))


@pytest.mark.parametrize("backend", ["polygon", "levelset"])
def test_a_region_pinched_at_a_junction_is_two_simple_curves(backend):
    # region 1 meets itself diagonally at the corner of region 2: its two squares touch at one
    # point, which must not make one curve that touches itself (a figure eight is not a polygon)
    from activecontour.geometry.topology import region_problem

    truth = np.zeros((30, 30), dtype=int)
    truth[5:15, 5:15] = 1
    truth[15:25, 15:25] = 1
    truth[15:25, 5:15] = 2
    image = np.array([0.1, 0.9, 0.5])[truth] + np.random.default_rng(6).normal(0, 0.02, truth.shape)
    res = ac.segment(image, n_regions=3, backend=backend)
    assert np.mean(res.classes == np.array([0, 2, 1])[truth]) > 0.99
    for curves in res.class_contours:
        assert region_problem(curves) is None
    assert len(res.class_contours[2]) == 2


_MANY = int(os.environ.get("FUZZ_EXAMPLES", "0"))


@pytest.mark.parametrize("backend", ["polygon", "levelset"])
@settings(max_examples=_MANY or 25, derandomize=not _MANY, deadline=None, database=None,
          suppress_health_check=list(HealthCheck))
@given(seed=st.integers(0, 2**32 - 1), rows=st.integers(4, 30), cols=st.integers(4, 30),
       kind=st.sampled_from(["noise", "blocks", "disk and step"]), n_regions=st.integers(3, 4),
       mu=st.sampled_from([0.0, 0.01, 0.1, 1.0]))
def test_n_region_results_obey_the_invariants(backend, seed, rows, cols, kind, n_regions, mu):
    # FUZZ_EXAMPLES=2000 tries many more, at random (as tests/api/test_fuzz.py)
    import shapely

    rng = np.random.default_rng(seed)
    r, c = np.mgrid[:rows, :cols]
    image = {"noise": lambda: rng.random((rows, cols)),
             "blocks": lambda: (rng.random((rows, cols)) > 0.5) + rng.normal(0, 0.3, (rows, cols)),
             "disk and step": lambda: ((r - rows / 2) ** 2 + (c - cols / 2) ** 2 < (min(rows, cols) / 3) ** 2)
             + 0.5 * (c > cols / 2) + rng.normal(0, 0.1, (rows, cols))}[kind]().astype(float)
    res = ac.segment(image, n_regions=n_regions, mu=mu, backend=backend)
    assert res.energy == pytest.approx(ac.chan_vese_energy(image, regions=res.class_contours, mu=mu),
                                       rel=1e-9, abs=1e-9)
    energies = res.energies
    assert energies[-1] == res.energy
    assert np.all(np.diff(energies) <= 1e-9 * np.maximum(np.abs(energies[1:]), 1.0)), energies
    assert np.array_equal(res.mask, res.classes > 0)
    assert res.energy >= -1e-9
    for k, curves in enumerate(res.class_contours):
        assert all(len(curve) >= 3 and shapely.LinearRing(curve).is_simple for curve in curves)
        if k:
            assert np.array_equal(rasterize(curves, image.shape), res.classes == k)


@pytest.mark.slow
def test_random_crops_of_real_images_obey_the_invariants():
    # 40 crops of scikit-image's pictures, 3-5 regions, gray or colour, several mu, default start
    import shapely
    import skimage.data

    rng = np.random.default_rng(1)
    names = ["camera", "coins", "page", "text", "moon", "cell", "astronaut", "chelsea",
             "immunohistochemistry", "hubble_deep_field"]
    for _ in range(40):
        picture = getattr(skimage.data, names[rng.integers(len(names))])()
        rows, cols = int(rng.integers(24, 120)), int(rng.integers(24, 120))
        r0, c0 = int(rng.integers(0, picture.shape[0] - rows)), int(rng.integers(0, picture.shape[1] - cols))
        crop = picture[r0:r0 + rows, c0:c0 + cols]
        n_regions = int(rng.integers(3, 6))
        color = "vector" if crop.ndim == 3 and rng.random() < 0.5 else "gray"
        mu = "auto" if rng.random() < 0.7 else float(rng.choice([0.0, 0.005, 0.05]))
        res = ac.segment(crop, n_regions=n_regions, mu=mu, color=color)
        assert res.success, res.message
        assert res.energy == pytest.approx(
            ac.chan_vese_energy(crop, regions=res.class_contours, mu=res.mu, color=color), rel=1e-9, abs=1e-9)
        assert np.all(np.diff(res.energies) <= 1e-9 * np.maximum(np.abs(res.energies[1:]), 1.0))
        for k, curves in enumerate(res.class_contours):
            assert all(len(curve) >= 3 and shapely.LinearRing(curve).is_simple for curve in curves)
            if k:
                assert np.array_equal(rasterize(curves, crop.shape[:2]), res.classes == k)


def test_boxes_hold_nodes_is_the_direct_test():
    # islands of one and of a few pixels, some inside others' boxes, and the nodes in use at random
    rng = np.random.default_rng(31)
    classes = np.zeros((30, 40), dtype=np.int32)
    classes[5:14, 5:16] = 1
    classes[8:11, 8:12] = 2  # a block inside the first: its loop lies within the outer box
    classes[rng.integers(0, 30, 25), rng.integers(0, 40, 25)] = 2
    network = Network.of_classes(classes)
    nodes = network.nodes + rng.uniform(-0.05, 0.05, network.nodes.shape)
    loops = [loop for loop, _ in network.closed_loops(nodes)]
    assert len(loops) >= 10
    by_row = np.argsort(nodes[:, 0], kind="stable")
    for used in (np.ones(len(nodes), dtype=bool), rng.random(len(nodes)) < 0.5):
        holds = network.boxes_hold_nodes(nodes, loops, used, by_row)
        for loop, found in zip(loops, holds, strict=True):
            a, b = nodes[network.start[loop]], nodes[network.end[loop]]
            low, high = np.minimum(a, b).min(axis=0), np.maximum(a, b).max(axis=0)
            inside = np.all((nodes > low) & (nodes < high), axis=1) & used
            assert found == inside.any()
        assert holds.any() and not holds.all()


def test_reconnecting_across_a_neck_cuts_it():
    # two 3 x 3 blocks of region 1 joined by a bridge one pixel wide and three long (row 4)
    classes = np.zeros((9, 13), dtype=np.int32)
    classes[3:6, 1:4] = classes[3:6, 9:12] = 1
    classes[4, 4:9] = 1
    image = np.random.default_rng(6).random(classes.shape)
    model, params = _setup(image, 0.3)
    network = Network.of_classes(classes)
    nodes = network.nodes
    a, b = nodes[network.start], nodes[network.end]
    middle = 0.5 * (a + b)
    # the bridge's two sides at its middle column: horizontal, a pixel apart
    top, bottom = (np.flatnonzero(network.interface & (middle[:, 1] == 6.5) & (middle[:, 0] == row))
                   for row in (3.5, 4.5))
    assert top.size == bottom.size == 1
    pair = np.array([[top[0], bottom[0]]])
    assert network.meeting_pairs(nodes).size == 0
    pressed = nodes.copy()
    pressed[[network.start[top[0]], network.end[top[0]]], 0] += 1.0  # the top side onto the bottom one
    assert {top[0], bottom[0]} in [set(found) for found in network.meeting_pairs(pressed)]
    cut, same = network.reconnected(pair, nodes)
    assert same is nodes and cut.simple(nodes)
    assert len(cut.region_curves(np.array([False, True]))) == 2  # the blocks come apart
    before = evaluate_partition(model, network.boundary(), params, 2)
    after = evaluate_partition(model, cut.boundary(), params, 2)
    # the unit square between the two sides goes to the background; the sides (1 each) give way
    # to two rungs across the bridge (1 each): the same length
    np.testing.assert_allclose(after.areas, before.areas + np.array([1.0, -1.0]), rtol=1e-12)
    assert after.length == pytest.approx(before.length, rel=1e-12)


def test_simplicity_after_a_local_change_tests_the_changed_segments():
    # the bridge of the test above: its two sides at the middle column, a -> b on top, p -> q a
    # pixel below, rejoined as the unit square's two diagonals (they cross), as its two rungs (no
    # crossing), or with the bottom side laid on the top one (they coincide)
    classes = np.zeros((9, 13), dtype=np.int32)
    classes[3:6, 1:4] = classes[3:6, 9:12] = 1
    classes[4, 4:9] = 1
    network = Network.of_classes(classes)
    nodes = network.nodes
    middle = 0.5 * (nodes[network.start] + nodes[network.end])
    top, bottom = (np.flatnonzero(network.interface & (middle[:, 1] == 6.5) & (middle[:, 0] == row))[0]
                   for row in (3.5, 4.5))
    (a, b), (p, q) = (sorted([network.start[e], network.end[e]], key=lambda k: nodes[k, 1])
                      for e in (top, bottom))
    assert network.simple(nodes)

    def changed(top_ends, bottom_ends):
        start, end = network.start.copy(), network.end.copy()
        (start[top], end[top]), (start[bottom], end[bottom]) = top_ends, bottom_ends
        child = Network(nodes, start, end, network.inner, network.outer, network.shape)
        return child.inheriting(network, np.arange(len(start)))

    diagonals, rungs, laid = changed((a, q), (p, b)), changed((a, p), (q, b)), changed((a, b), (a, b))
    same = Network(nodes, network.start, network.end, network.inner, network.outer, network.shape)
    for child, simple in ((diagonals, False), (rungs, True), (laid, False),
                          (same.inheriting(network, np.arange(len(network.start))), True)):
        assert child.simple(nodes) == simple
        assert child.simple_after(network, nodes) == simple
    # only the changed segments' neighbourhood is tested: a crossing elsewhere, which the parent
    # would have had, is not seen
    crossed = nodes.copy()
    crossed[np.flatnonzero(np.all(nodes == [4.0, 0.5], axis=1))] = [4.5, 4.5]  # onto the bridge's side
    assert not rungs.simple(crossed) and rungs.simple_after(network, crossed)


def test_a_network_changed_locally_shares_the_integrals_of_its_unchanged_segments():
    # the bridge cut by reconnecting its sides (above): the two rejoined segments are new, every
    # other segment of the moving boundary is the parent's, and the evaluation that takes the
    # parent's integrals for those is the fresh one, bit for bit
    classes = np.zeros((9, 13), dtype=np.int32)
    classes[3:6, 1:4] = classes[3:6, 9:12] = 1
    classes[4, 4:9] = 1
    model, params = _setup(np.random.default_rng(6).random(classes.shape), 0.3)
    network = Network.of_classes(classes)
    nodes = network.nodes
    middle = 0.5 * (nodes[network.start] + nodes[network.end])
    pair = np.array([[np.flatnonzero(network.interface & (middle[:, 1] == 6.5) & (middle[:, 0] == row))[0]
                      for row in (3.5, 4.5)]])
    cut, _ = network.reconnected(pair, nodes)
    parent = evaluate_partition(model, network.moving_boundary(nodes), params, 2, parts=True)
    rows = cut.shared_rows(network)
    boundary = cut.moving_boundary(nodes)
    assert np.count_nonzero(rows < 0) == 2 and len(rows) == len(boundary.start)
    kept = rows >= 0
    parent_boundary = network.moving_boundary(nodes)
    np.testing.assert_array_equal(parent_boundary.start[rows[kept]], boundary.start[kept])
    np.testing.assert_array_equal(parent_boundary.end[rows[kept]], boundary.end[kept])
    fresh = evaluate_partition(model, boundary, params, 2, parts=True)
    shared = evaluate_partition(model, boundary, params, 2, parts=True, known=(rows, parent))
    assert shared.energy == fresh.energy
    np.testing.assert_array_equal(shared.parts, fresh.parts)
    assert cut.shared_rows(cut) is None and network.shared_rows(cut) is None  # not made from it


def test_collapsing_a_vanishing_segment_keeps_the_partition():
    classes = np.zeros((10, 12), dtype=np.int32)
    classes[2:8, 3:9] = 1
    classes[4:8, 6:9] = 2  # junctions where the three regions meet
    image = np.random.default_rng(7).random(classes.shape)
    model, params = _setup(image, 0.3)
    network = Network.of_classes(classes)
    nodes = network.nodes.copy()
    degree = np.bincount(np.concatenate([network.start[network.interface], network.end[network.interface]]),
                         minlength=len(nodes))
    plain = (degree == 2) & network.free[0] & network.free[1]
    chosen = np.flatnonzero(network.interface & plain[network.start] & plain[network.end])[0]
    nodes[network.end[chosen]] = nodes[network.start[chosen]]  # the segment has vanished
    collapsed, same = network.collapsed([chosen], nodes)
    assert same is nodes and len(collapsed.start) == len(network.start) - 1
    assert collapsed.simple(nodes) and not network.simple(nodes)
    before = evaluate_partition(model, network.boundary(nodes), params, 3)
    after = evaluate_partition(model, collapsed.boundary(), params, 3)
    assert after.energy == pytest.approx(before.energy, rel=1e-12)
    # a segment between two branch nodes (junctions, the border) is not collapsed
    branch = np.flatnonzero(network.interface & ~plain[network.start] & ~plain[network.end])
    assert network.collapsed(branch, network.nodes) is None


def test_a_stall_at_a_pinch_says_so():
    # a crop of scikit-image's camera where a region thins between two others: the flow's steps are
    # held back there, J still falling, and the run ends as a stall (status 5), not as a flow that
    # found no descent step (status 4: J no longer falls) nor as converged
    import skimage.data

    from activecontour.result import STATUS_MESSAGES

    crop = skimage.data.camera()[230:263, 199:240]
    res = ac.segment(crop, n_regions=3, separate=False)
    assert res.status == 5 and res.message == STATUS_MESSAGES[5]
    assert res.message.startswith("Stalled") and "pinch" in res.message
    assert res.success and res.n_iter < 500  # before the default max_num_iter
    assert res.energies[-1] < res.energies[-2]  # still descending when it stopped
    assert all("stall" not in STATUS_MESSAGES[k].lower() for k in STATUS_MESSAGES if k != 5)


def test_interface_pieces_are_the_connected_components_at_plain_nodes():
    # the interface segments joined where two of them meet at a free node of degree two: scipy's
    # connected components (numbered from segment 0 on) are closed_loops' pieces, and a piece is
    # closed when none of its segments ends at another node
    import scipy.sparse
    from scipy.sparse.csgraph import connected_components

    checked = 0
    for network, _, _ in _moved_networks(20, 17):
        chosen = np.flatnonzero(network.interface)
        ends = np.concatenate([network.start[chosen], network.end[chosen]])
        degree = np.bincount(ends, minlength=len(network.nodes))
        plain = (degree == 2) & network.free[0] & network.free[1]
        owner = np.tile(np.arange(chosen.size), 2)
        rows, cols = [], []
        for node in np.flatnonzero(plain):
            a, b = owner[ends == node]
            rows.append(a)
            cols.append(b)
        graph = scipy.sparse.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(chosen.size,) * 2)
        count, piece = connected_components(graph, directed=False)
        found = network._interface_pieces()
        np.testing.assert_array_equal(found[1], piece)
        assert found[2] == count
        closed = [k for k in range(count) if plain[ends[np.tile(piece == k, 2)]].all()]
        np.testing.assert_array_equal(found[3], closed)
        checked += count > len(closed) > 0
    assert checked >= 3


def test_no_class_contour_is_a_sliver_through_a_pinch():
    # this crop's last step left three nearly collinear nodes between regions 0 and 2, through a
    # node of degree 4 (a pinch): a loop of area 4e-12 px^2, a degenerate contour of both regions
    # that the common evaluator refuses
    import skimage.data

    from activecontour.geometry.curve import as_curve

    crop = skimage.data.astronaut()[127:235, 256:363]
    res = ac.segment(crop, n_regions=3, mu="auto", color="vector")
    for k, curves in enumerate(res.class_contours):
        for j, curve in enumerate(curves):
            as_curve(curve, name=f"class_contours[{k}][{j}]")  # raises for a degenerate curve
    assert res.energy == pytest.approx(
        ac.chan_vese_energy(crop, regions=res.class_contours, mu=res.mu, color="vector"), rel=1e-9)


def test_a_trial_is_tested_for_crossings_in_full_once(monkeypatch):
    # a pinch resolved after a step held back by it takes the pairs that met from the flow's own
    # crossing test of that trial: no trial's nodes go through the full test twice (the camera crop
    # of the stall, whose steps cross at a pinch)
    import hashlib

    import skimage.data

    tested = []
    meeting_pairs = Network.meeting_pairs

    def spy(self, nodes, limit=16):
        tested.append(hashlib.sha256(np.ascontiguousarray(nodes).tobytes()).hexdigest())
        return meeting_pairs(self, nodes, limit)

    monkeypatch.setattr(Network, "meeting_pairs", spy)
    crop = skimage.data.camera()[230:263, 199:240]
    ac.segment(crop, n_regions=3, separate=False)
    assert tested and len(set(tested)) == len(tested)


def _hand_network(points, segments, shape):
    """A network from its nodes and ``(start, end, inner, outer)`` rows."""
    start, end, inner, outer = (np.array(column, dtype=np.intp) for column in zip(*segments, strict=True))
    return Network(np.array(points, dtype=np.float64), start, end, inner, outer, shape)


def _shoelace(points):
    points = np.asarray(points, dtype=np.float64)
    following = np.roll(points, -1, axis=0)
    return 0.5 * abs(np.sum(points[:, 0] * following[:, 1] - following[:, 0] * points[:, 1]))


# a 4 x 6 image: its corners, the ends on the top edge of a region 1 below it (v, u, its border
# segment from v to u), a node below them (x) and one on the bottom edge under it (y)
_CORNERS = [(-0.5, -0.5), (3.5, -0.5), (3.5, 5.5), (-0.5, 5.5)]
_V, _U, _X, _Y = (-0.5, 3.0), (-0.5, 2.0), (1.0, 2.5), (3.5, 2.5)


@pytest.mark.parametrize("into_start", [True, False])
@pytest.mark.parametrize("right", [0, 2])
def test_two_junctions_meeting_on_the_border_take_the_triangle_between_them_away(into_start, right):
    # region 1 a triangle (v, u, x) on the top edge, region 0 left of it and ``right`` right of it
    # (0: one region around it; 2: a third region, x a junction with an interface down to y):
    # merging v and u leaves the triangle's two sides joining the same two nodes, so it goes and
    # the interface from the merged node to x separates the regions on their other sides
    tl, bl, br, tr, v, u, x, y = range(8)
    points = [_CORNERS[0], _CORNERS[1], _CORNERS[2], _CORNERS[3], _V, _U, _X, _Y]
    border = [(tl, bl, 0, -1), (bl, y, 0, -1), (y, br, right, -1), (br, tr, right, -1), (tr, v, right, -1),
              (v, u, 1, -1), (u, tl, 0, -1)]
    sides = [(u, x, 1, 0), (x, v, 1, right)] + ([(x, y, 2, 0)] if right else [])
    network = _hand_network(points, border + sides, (4, 6))
    image = np.random.default_rng(11).random((4, 6))
    model, params = _setup(image, 0.3)
    merged, nodes = network.border_merged([5], network.nodes, into_start)
    kept = v if into_start else u
    # the expected partition, built directly: region 1 gone, the top edge from tr to tl through the
    # kept node, the interface from it down to y between 0 and ``right`` (none where that is 0)
    edge = [(tl, bl, 0, -1), (bl, y, 0, -1), (y, br, right, -1), (br, tr, right, -1), (tr, kept, right, -1),
            (kept, tl, 0, -1)]
    expected = _hand_network(points, edge + ([(kept, x, 2, 0), (x, y, 2, 0)] if right else []), (4, 6))
    assert merged.simple(nodes) and merged.faces()[0].size
    found = evaluate_partition(model, merged.boundary(nodes), params, 3)
    truth = evaluate_partition(model, expected.boundary(), params, 3)
    assert found.energy == pytest.approx(truth.energy, rel=1e-12)
    left = _shoelace([points[tl], points[bl], points[y], points[x], points[kept]]) if right else 24.0
    np.testing.assert_allclose(found.areas, [left, 0.0, 24.0 - left], atol=1e-12)
    assert np.count_nonzero(merged.interface) == (2 if right else 0)


def test_two_junctions_merged_on_the_border_leave_the_region_between_them_meeting_it_at_a_point():
    # region 1 a quadrilateral (v, u, a, b) on the top edge of a region 0: merging v into u moves
    # the interface's end at v onto u, and the region (now the triangle u, a, b) meets the edge at u
    tl, bl, br, tr, v, u, a, b = range(8)
    points = [*_CORNERS, _V, _U, (1.0, 2.0), (1.0, 3.0)]
    network = _hand_network(points, [(tl, bl, 0, -1), (bl, br, 0, -1), (br, tr, 0, -1), (tr, v, 0, -1),
                                     (v, u, 1, -1), (u, tl, 0, -1), (u, a, 1, 0), (a, b, 1, 0), (b, v, 1, 0)],
                            (4, 6))
    image = np.random.default_rng(12).random((4, 6))
    model, params = _setup(image, 0.3)
    merged, nodes = network.border_merged([4], network.nodes, False)
    moved = network.nodes.copy()
    moved[v] = moved[u]  # the same partition: the border segment between them of no length
    found = evaluate_partition(model, merged.boundary(nodes), params, 3)
    assert found.energy == pytest.approx(evaluate_partition(model, network.boundary(moved), params, 3).energy,
                                         rel=1e-12)
    np.testing.assert_allclose(found.areas[1], _shoelace([points[u], points[a], points[b]]), rtol=1e-12)
    assert merged.simple(nodes) and len(merged.start) == len(network.start) - 1
    (curve,) = merged.region_curves(np.arange(3) == 1)
    assert len(curve) == 3
    # an interface that joins the two junctions directly is not merged (it would close on itself)
    direct = _hand_network(points, [(tl, bl, 0, -1), (bl, br, 0, -1), (br, tr, 0, -1), (tr, v, 0, -1),
                                    (v, u, 1, -1), (u, tl, 0, -1), (u, v, 1, 0)], (4, 6))
    assert direct.border_merged([4], direct.nodes) is None


def test_a_junction_on_the_border_merges_the_vertex_it_has_reached():
    # an interface from u on the top edge down to y, regions 0 left and 2 right; the top edge has a
    # vertex h 0.02 px left of u: merged, the edge's segment from u goes on to the corner, J the same
    tl, bl, br, tr, u, y, h = range(7)
    points = [*_CORNERS, _U, (3.5, 2.0), (-0.5, 1.98)]
    network = _hand_network(points, [(tl, bl, 0, -1), (bl, y, 0, -1), (y, br, 2, -1), (br, tr, 2, -1),
                                     (tr, u, 2, -1), (u, h, 0, -1), (h, tl, 0, -1), (u, y, 2, 0)], (4, 6))
    image = np.random.default_rng(13).random((4, 6))
    model, params = _setup(image, 0.3)
    merged, nodes = network.border_merged([5], network.nodes)
    assert len(merged.start) == len(network.start) - 1
    assert h not in np.concatenate([merged.start, merged.end])
    assert merged.simple(nodes) and merged.faces()[0].size
    assert evaluate_partition(model, merged.boundary(nodes), params, 3).energy == pytest.approx(
        evaluate_partition(model, network.boundary(), params, 3).energy, rel=1e-12)


def test_junctions_slide_along_the_edge_past_its_vertices():
    # three vertical bands, their interfaces started 2.3 px away from the image's edges: their ends
    # on the top and bottom edges slide past the edge's vertices (one every pixel) to where the
    # bands meet, and the interfaces go all the way there
    from activecontour.backends.network.flow import _Flow

    edges = (5.3, 10.6)
    image, _ = _antialiased((12, 16), lambda r, c: (c > edges[0]).astype(int) + (c > edges[1]).astype(int),
                            [0.1, 0.9, 0.5])
    model, params = _setup(image, 1e-3)
    start = np.zeros((12, 16), dtype=np.int32)
    start[:, 3:] = 1
    start[:, 13:] = 2
    flow = _Flow(Network.of_classes(start), model, params, 3, [])
    assert flow.run(500, 5e-4, None, 0)[0] == 0
    network, nodes = flow.network, flow.nodes
    for k, edge in enumerate(edges):
        on = np.flatnonzero(network.interface & (network.inner == k + 1))
        columns = nodes[np.concatenate([network.start[on], network.end[on]]), 1]
        assert np.all(np.abs(columns - edge) < 0.1)


def test_a_sliver_along_the_edge_goes_to_the_region_around_it():
    # region 1 a sliver between the top edge's segment from v to u and an interface along it with
    # region 2 below (regions 0 and 2 either side of an interface from u down to y): the sliver's
    # edge segment goes to region 2, its interface goes, and the partition is region 2's
    from activecontour.backends.network.flow import _without_slivers

    tl, bl, br, tr, v, u, y = range(7)
    points = [*_CORNERS, _V, _U, (3.5, 2.0)]
    top = [(tl, bl, 0, -1), (bl, y, 0, -1), (y, br, 2, -1), (br, tr, 2, -1), (tr, v, 2, -1)]
    network = _hand_network(points, top + [(v, u, 1, -1), (u, tl, 0, -1), (u, v, 1, 2), (u, y, 2, 0)], (4, 6))
    expected = _hand_network(points, top + [(v, u, 2, -1), (u, tl, 0, -1), (u, y, 2, 0)], (4, 6))
    image = np.random.default_rng(14).random((4, 6))
    model, params = _setup(image, 0.3)
    found = _without_slivers(network, network.nodes)
    assert [len(curves) for curves in map(found.region_curves, np.eye(3, dtype=bool))] == [1, 0, 1]
    assert evaluate_partition(model, found.boundary(), params, 3).energy == pytest.approx(
        evaluate_partition(model, expected.boundary(), params, 3).energy, rel=1e-12)


def test_a_loop_turned_inside_out_is_caught_where_no_interfaces_meet():
    # an island of region 1 in region 0, a triangle: walked with region 1 on its inner side it is
    # an island; walked the other way round with the same sides it is a region 1 everywhere around
    # a hole of region 0 that region 0's own boundary does not hold: no two interfaces meet, but
    # the regions are not where its sides say
    tl, bl, br, tr, a, b, c = range(7)
    points = [*_CORNERS, (1.0, 2.0), (2.5, 2.0), (1.5, 3.5)]
    edge = [(tl, bl, 0, -1), (bl, br, 0, -1), (br, tr, 0, -1), (tr, tl, 0, -1)]
    island = _hand_network(points, edge + [(a, b, 1, 0), (b, c, 1, 0), (c, a, 1, 0)], (4, 6))
    model, params = _setup(np.random.default_rng(15).random((4, 6)), 0.3)
    assert evaluate_partition(model, island.boundary(), params, 2).areas[1] == pytest.approx(1.125)
    inside_out = _hand_network(points, edge + [(b, a, 1, 0), (c, b, 1, 0), (a, c, 1, 0)], (4, 6))
    inside_out.inheriting(island, np.arange(7))
    assert evaluate_partition(model, inside_out.boundary(), params, 2).areas[1] == pytest.approx(-1.125)
    assert inside_out.simple_after(island, island.nodes)
    assert not inside_out.sides_hold_after(island, island.nodes)
    same = _hand_network(points, edge + [(a, b, 1, 0), (b, c, 1, 0), (c, a, 1, 0)], (4, 6))
    assert same.inheriting(island, np.arange(7)).sides_hold_after(island, island.nodes)
    # with the sides swapped too it is the island again, walked the other way
    swapped = _hand_network(points, edge + [(b, a, 0, 1), (c, b, 0, 1), (a, c, 0, 1)], (4, 6))
    assert swapped.inheriting(island, np.arange(7)).sides_hold_after(island, island.nodes)


def test_two_slivers_side_by_side_both_go():
    # regions 1 and 2 two slivers side by side in region 0 (three runs from a to b, 1e-9 px apart:
    # 0 | 1 above, 1 | 2 between, 2 | 0 below): merging 1 into 2 changes region 2's sides, so its
    # loop is read again, not from the sides it had (which left a run of region 1 against 0 with no
    # region 1 around it); both go, and the partition is region 0's alone
    from activecontour.backends.network.flow import _without_slivers

    tl, bl, br, tr, a, m, b, t, d = range(9)
    points = [*_CORNERS, (1.0, 1.0), (1.0, 2.0), (1.0, 4.0), (1.0 - 1e-9, 2.5), (1.0 + 1e-9, 3.0)]
    edge = [(tl, bl, 0, -1), (bl, br, 0, -1), (br, tr, 0, -1), (tr, tl, 0, -1)]
    network = _hand_network(points, edge + [(a, m, 1, 2), (m, b, 1, 2), (b, t, 1, 0), (t, a, 1, 0),
                                            (a, d, 2, 0), (d, b, 2, 0)], (4, 6))
    found = _without_slivers(network, network.nodes)
    assert [len(curves) for curves in map(found.region_curves, np.eye(3, dtype=bool))] == [1, 0, 0]
    image = np.random.default_rng(15).random((4, 6))
    model, params = _setup(image, 0.3)
    assert evaluate_partition(model, found.boundary(), params, 3).energy == pytest.approx(
        evaluate_partition(model, _hand_network(points, edge, (4, 6)).boundary(), params, 3).energy,
        rel=1e-12)
