"""Every result bounds a region: simple polygons that do not cross each other (shapely), never
worse than the start, energies that never rise; the evaluator refuses curves that bound no region."""

import numpy as np
import pytest
import shapely
from shapely.geometry import MultiPolygon, Polygon

import activecontour as ac
from activecontour import _kernels
from activecontour.geometry import topology
from activecontour.geometry.curve import signed_area


def region_of(curves):
    """The region of oriented curves by nesting, as one shapely geometry ((row, col) as (x, y))."""
    outers = [Polygon(c) for c in curves if signed_area(c) > 0]
    holes = {i: [] for i in range(len(outers))}
    for c in curves:
        if signed_area(c) < 0:
            owner = min((i for i, o in enumerate(outers) if o.contains(Polygon(c).representative_point())),
                        key=lambda i: outers[i].area)
            holes[owner].append(c)
    return MultiPolygon([Polygon(o.exterior.coords, holes[i]) for i, o in enumerate(outers)])


def assert_bounds_a_region(image, result):
    for curve in result.contours:
        assert shapely.is_valid(Polygon(curve)), shapely.is_valid_reason(Polygon(curve))
    region = region_of(result.contours)
    assert shapely.is_valid(region), shapely.is_valid_reason(region)
    assert topology.region_problem(result.contours) is None
    # the mask is the region: its pixel count is its area to within the boundary's pixels
    assert abs(result.mask.sum() - region.area) <= 1 + sum(len(c) for c in result.contours)
    assert result.energy >= 0  # omega = 0: every term of (6.38) is >= 0
    assert 0.0 <= result.c_in <= 1.0 and 0.0 <= result.c_out <= 1.0
    assert result.energy == pytest.approx(ac.chan_vese_energy(image, result.contours, mu=result.mu),
                                          rel=1e-9, abs=1e-9)
    assert np.all(np.diff(result.energies) <= 1e-9 * np.abs(result.energies[1:]))


RAMP16 = np.add.outer(np.arange(16.0), np.arange(16.0))
RAMP32 = np.add.outer(np.arange(32.0), np.arange(32.0))


@pytest.mark.parametrize("global_start", [True, False])
@pytest.mark.parametrize("image, init", [(RAMP16, np.ones((16, 16), bool)), (RAMP32, "grid")],
                         ids=["ramp16-full-mask", "ramp32-grid"])
def test_a_ramp_from_the_border_gives_simple_polygons(image, init, global_start):
    result = ac.segment(image, init, options={"global_start": global_start})
    assert_bounds_a_region(image, result)


def test_a_curve_given_twice_counts_once():
    image = np.zeros((40, 40))
    image[12:28, 12:28] = 1
    curve = ac.circle((20, 20), 8)
    once, twice = ac.segment(image, curve), ac.segment(image, [curve, curve[::-1].copy()])
    assert twice.energy == pytest.approx(once.energy, rel=1e-9)
    assert np.array_equal(twice.mask, once.mask)
    # and the start is the disk, counted once: (6.38) of the circle by the evaluator
    start = ac.segment(image, [curve, curve.copy()], max_num_iter=0)
    assert start.energy == pytest.approx(ac.chan_vese_energy(image, [curve], mu=start.mu), rel=1e-12)


def test_overlapping_init_curves_are_their_union():
    a, b = ac.rectangle((10, 10), (30, 30)), ac.rectangle((20, 20), (40, 40))
    (union,) = ac.initial.initial_curves([a, b, a.copy()], (50, 50))
    assert signed_area(union) == pytest.approx(2 * 400 - 100)


@pytest.mark.parametrize("contours, match", [
    ([ac.circle((20, 20), 8)] * 2, "same curve"),
    ([np.array([[5.0, 5.0], [30.0, 30.0], [30.0, 5.0], [5.0, 20.0]])], "crosses or touches itself"),
    ([ac.rectangle((5, 5), (25, 25)), ac.rectangle((15, 15), (35, 35))], "cross or overlap"),
    # along the top border twice: a strip of winding number 2
    ([np.array([[-0.5, -0.5], [10.0, -0.5], [10.0, 20.0], [-0.5, 20.0], [-0.5, 30.0], [5.0, 30.0],
                [5.0, 10.0], [-0.5, 10.0]])], "crosses or touches itself"),
])
def test_the_evaluator_refuses_curves_that_bound_no_region(contours, match):
    with pytest.raises(ValueError, match=match):
        ac.chan_vese_energy(np.zeros((40, 40)), contours, mu=0.1)


def test_border_overlap_sees_collinear_edges_on_the_border():
    bounds = np.array([[-0.5, -0.5], [39.5, 39.5]])
    twice = np.array([[-0.5, 0.0], [-0.5, 20.0], [5.0, 20.0], [5.0, 25.0], [-0.5, 25.0], [-0.5, 10.0],
                      [10.0, 5.0]])
    following = np.roll(np.arange(len(twice)), -1)
    assert topology.border_overlap(twice, following, bounds)
    square = ac.rectangle((-0.5, -0.5), (10, 10))
    assert not topology.border_overlap(square, np.roll(np.arange(4), -1), bounds)



def _border_overlap_reference(points, next_index, bounds):
    """border_overlap as it was written in numpy before the compiled kernel: the specification."""
    rows, cols = points[:, 0], points[:, 1]
    on = np.flatnonzero((rows == bounds[0, 0]) | (rows == bounds[1, 0]) | (cols == bounds[0, 1])
                        | (cols == bounds[1, 1]))
    if on.size < 2:
        return False
    start, end = points[on], points[next_index[on]]
    for corner_r in bounds[:, 0]:
        for corner_c in bounds[:, 1]:
            at = (start[:, 0] == corner_r) & (start[:, 1] == corner_c)
            if np.count_nonzero(at & ~((end[:, 0] == corner_r) & (end[:, 1] == corner_c))) > 1:
                return True
    for axis in (0, 1):
        for side in bounds[:, axis]:
            edge_on = (start[:, axis] == side) & (end[:, axis] == side)
            if np.count_nonzero(edge_on) < 2:
                continue
            low = np.minimum(start[edge_on, 1 - axis], end[edge_on, 1 - axis])
            high = np.maximum(start[edge_on, 1 - axis], end[edge_on, 1 - axis])
            order = np.argsort(low, kind="stable")
            reach = np.maximum.accumulate(high[order])[:-1]
            if np.any(low[order][1:] < reach - 1e-12 * max(1.0, abs(float(side)))):
                return True
    return False


def test_border_overlap_in_compiled_code_equals_its_numpy_definition():
    # vertices drawn from a coarse grid that holds the border's rows and columns several times:
    # corners visited once and twice, edges along a side forwards, backwards, of zero length and
    # nested, curves touching the border at a vertex; in order or in any cyclic order
    rng = np.random.default_rng(7)
    seen = set()
    for _ in range(4000):
        bounds = np.array([[-0.5, -0.5], [rng.choice([2.5, 3.5]), rng.choice([1.5, 3.5])]])
        grid_r = np.concatenate([np.repeat(bounds[:, 0], 3), np.arange(-0.5, bounds[1, 0] + 0.5, 0.5)])
        grid_c = np.concatenate([np.repeat(bounds[:, 1], 3), np.arange(-0.5, bounds[1, 1] + 0.5, 0.5)])
        k = rng.integers(1, 12)
        points = np.column_stack([rng.choice(grid_r, k), rng.choice(grid_c, k)])
        next_index = rng.permutation(k) if rng.random() < 0.3 else np.roll(np.arange(k), -1)
        expected = _border_overlap_reference(points, next_index, bounds)
        assert _kernels.border_overlap(points, next_index, bounds) == expected
        assert topology.border_overlap(points, next_index, bounds) is expected
        seen.add(expected)
    assert seen == {False, True}


def test_dropping_small_curves_never_raises_the_energy():
    # a 3 px object (below min_area = 4 px^2) that is still worth its curve: the flow must not
    # collapse to the empty set, whose energy is higher
    image = np.zeros((32, 32))
    image[15, 14:17] = 1.0
    result = ac.segment(image, ac.circle((15, 15), 4), options={"global_start": False})
    empty = ac.chan_vese_energy(image, [], mu=result.mu)
    assert result.energy < empty
    assert result.status != 3 and result.mask.sum() == 3
    assert np.all(np.diff(result.energies) <= 0)


def _count_nesting(monkeypatch):
    """Count the calls of the one rule of nesting, wherever it is read from."""
    from activecontour.geometry import regions

    calls = []
    original = regions.nesting

    def counted(shapes):
        calls.append(len(shapes))
        return original(shapes)

    monkeypatch.setattr(regions, "nesting", counted)
    monkeypatch.setattr(topology, "nesting", counted)
    return calls


def test_nested_curves_are_nested_once_for_the_orientation_and_the_check(monkeypatch):
    from activecontour.initial import region_boundary

    # an outer square, a hole in it, an island in the hole, all given clockwise
    curves = [ac.rectangle((0, 0), (30, 30))[::-1], ac.rectangle((5, 5), (25, 25))[::-1],
              ac.rectangle((10, 10), (20, 20))[::-1]]
    calls = _count_nesting(monkeypatch)
    oriented = region_boundary(curves)
    assert calls == [3]
    assert [signed_area(c) > 0 for c in oriented] == [True, False, True]
    image = np.zeros((32, 32))
    del calls[:]
    # a blank image, mu = 0: every term of (6.38) is 0; what counts is the nesting's calls
    assert ac.chan_vese_energy(image, curves, mu=0.0) == pytest.approx(0.0, abs=1e-12)
    assert calls == [3]


def test_the_region_check_reads_a_nesting_it_is_given():
    from activecontour.geometry.regions import nesting, polygons

    outer, hole = ac.rectangle((0, 0), (30, 30)), ac.rectangle((5, 5), (25, 25))[::-1]
    for curves in ([outer, hole], [outer, outer[::-1]], [outer, hole[::-1]]):
        nested = nesting(polygons(curves))
        assert topology.region_problem(curves, nested) == topology.region_problem(curves)
    # a nesting that says the hole lies in nothing makes it a wrongly oriented outer boundary
    assert "negatively oriented inside 0" in topology.region_problem(
        [outer, hole], (np.array([0, 0]), np.array([-1, -1]), []))
