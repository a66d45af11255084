"""Several curves, holes, splitting and merging, nucleation, grid start and colour (polygon backend)."""

import numpy as np
import pytest

import activecontour as ac
from activecontour import synthetic
from activecontour.geometry import topology
from activecontour.geometry.curve import signed_area, stack_curves
from activecontour.initial import grid

SIZE = (128, 128)


def assert_monotone(result):
    assert np.all(np.diff(result.energies) <= 0.0), "the energy increased"


def test_crossings_are_found_and_exact():
    square = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]])
    shifted = square + [2.0, 2.0]
    points, nxt, _ = stack_curves([square, shifted])
    first, second, s, t = topology.crossings(points, nxt)
    assert len(first) == 2  # two outlines of overlapping squares cross twice
    cross = points[first] + s[:, None] * (points[nxt[first]] - points[first])
    np.testing.assert_allclose(sorted(map(tuple, cross)), [(2.0, 4.0), (4.0, 2.0)])
    assert topology.crossings(*stack_curves([square])[:2])[0].size == 0


def test_one_grid_test_for_curves_and_networks():
    """_kernels.segments_meet serves both: for curves (touching=False) the proper crossings with
    their parameters, for a network (touching=True) also a touch and a collinear overlap, and
    never two segments that only share a node."""
    from activecontour import _kernels

    nodes = np.array([[0.0, 0.0], [4.0, 0.0], [2.0, -1.0], [2.0, 3.0],  # 0-1 crossed by 2-3 at (2, 0)
                      [4.0, 2.0], [4.0, -2.0],  # 1-4 and 1-5 share node 1 only
                      [6.0, 0.0], [5.0, 0.0], [8.0, 0.0],  # 6-8 and 7-8 overlap along 7-8
                      [10.0, -1.0], [10.0, 1.0], [10.0, 0.0], [12.0, 0.0]])  # 11 lies on 9-10
    start = np.array([0, 2, 1, 1, 6, 7, 9, 11], dtype=np.intp)
    end = np.array([1, 3, 4, 5, 8, 8, 10, 12], dtype=np.intp)
    pairs, where = np.empty((16, 2), dtype=np.intp), np.empty((16, 2))
    found = _kernels.segments_meet(nodes, start, end, False, 100, pairs, where)
    assert found == 1 and tuple(pairs[0]) == (0, 1)
    np.testing.assert_allclose(where[0], [0.5, 0.25])  # (2, 0): half of 0-1, a quarter of 2-3
    found = _kernels.segments_meet(nodes, start, end, True, 100, pairs, np.empty((0, 2)))
    assert sorted(map(tuple, pairs[:found])) == [(0, 1), (4, 5), (6, 7)]
    assert _kernels.segments_meet(nodes, start, end, True, 1, pairs, np.empty((0, 2))) == 1  # the limit


def test_repair_of_overlapping_curves_is_their_union():
    a = ac.circle((20.0, 20.0), 10.0, 200)
    b = ac.circle((20.0, 32.0), 10.0, 200)
    (union,) = topology.repair(*stack_curves([a, b]))
    # area of the union of two unit-spaced... circles of radius 10 at distance 12 (lens formula)
    d, r = 12.0, 10.0
    lens = 2 * r * r * np.arccos(d / (2 * r)) - 0.5 * d * np.sqrt(4 * r * r - d * d)
    assert signed_area(union) == pytest.approx(2 * np.pi * r * r - lens, rel=2e-3)


def test_repair_of_a_crossed_neck_splits_into_two_lobes():
    # Two 20 x 10 lobes joined by a neck whose sides have crossed: the side that should be at
    # larger rows dips to r = -1 and the other rises to r = +1, crossing at (0, 14) and (0, 16).
    dumbbell = np.array([
        (-10, 0), (10, 0), (10, 10), (4, 10), (-1, 15), (4, 20), (10, 20), (10, 30),
        (-10, 30), (-10, 20), (-4, 20), (1, 15), (-4, 10), (-10, 10)], dtype=float)
    assert signed_area(dumbbell) > 0
    pieces = topology.repair(*stack_curves([dumbbell]))
    assert len(pieces) == 2 and all(signed_area(p) > 0 for p in pieces)
    # each lobe: 200 px square plus the neck wedge up to the crossing, 0.5 * 4 * (4 + 4) = 16
    np.testing.assert_allclose(sorted(signed_area(p) for p in pieces), [216.0, 216.0])


def test_repair_of_a_figure_eight_keeps_the_positive_lobe():
    t = 2 * np.pi * (np.arange(200) + 0.5) / 200  # no vertex exactly on the crossing
    eight = np.column_stack([10 * np.sin(2 * t), 20 * np.sin(t)])  # lobes of opposite winding
    (lobe,) = topology.repair(*stack_curves([eight]))
    assert signed_area(lobe) > 0
    # area of one lobe of (10 sin 2t, 20 sin t): integral over t in [0, pi] of r dc
    assert signed_area(lobe) == pytest.approx(800.0 / 3.0, rel=2e-3)


def test_nested_curves_do_not_cross():
    outer = ac.circle((50.0, 50.0), 20.0, 300)
    inner = ac.circle((50.0, 50.0), 8.0, 120)[::-1]
    assert topology.repair(*stack_curves([outer, inner])) is None


def test_repair_drops_curves_turned_over_without_a_crossing():
    # no edges cross, but a positive curve inside a positive one bounds w = 2 and a negative one
    # alone w = -1: neither separates {w > 0} from the rest, so only the outer curve is left
    outer = ac.circle((50.0, 50.0), 20.0, 300)
    nested = ac.circle((50.0, 50.0), 8.0, 120)
    alone = ac.circle((10.0, 10.0), 3.0, 40)[::-1]
    for extra in (nested, alone):
        (kept,) = topology.repair(*stack_curves([outer, extra]))
        np.testing.assert_array_equal(kept, outer)


def test_winding_number_counts_orientation():
    outer = ac.circle((0.0, 0.0), 10.0, 100)
    hole = ac.circle((0.0, 0.0), 4.0, 50)[::-1]
    points, nxt, _ = stack_curves([outer, hole])
    w = topology.winding_number(points, nxt, np.array([[0.0, 0.0], [7.0, 0.0], [20.0, 0.0]]))
    np.testing.assert_array_equal(w, [0, 1, 0])


def test_two_separated_disks_from_one_enclosing_circle():
    shape = synthetic.union(synthetic.disk((64.3, 34.6), 19.0), synthetic.disk((63.7, 93.2), 21.0))
    image, truth = synthetic.render(shape, SIZE, inside=0.75, outside=0.25)
    result = ac.segment(synthetic.add_noise(image, 0.1, 1), ac.circle((63.5, 63.5), 60.0))
    assert len(result.contours) == 2 and all(signed_area(c) > 0 for c in result.contours)
    assert synthetic.dice(result.mask, truth) >= 0.97
    assert_monotone(result)


def test_annulus_from_one_circle_gets_a_hole():
    image, truth = synthetic.render(synthetic.annulus((63.5, 64.2), 14.0, 36.0), SIZE)
    result = ac.segment(synthetic.add_noise(image, 0.1, 2), ac.circle((63.5, 64.0), 50.0))
    areas = sorted(signed_area(c) for c in result.contours)
    assert len(areas) == 2 and areas[0] < 0 < areas[1]  # a hole and an outer boundary
    assert synthetic.dice(result.mask, truth) >= 0.97
    assert_monotone(result)


def test_grid_start_finds_every_coin_and_invents_none():
    image, truth, centers = synthetic.coins()
    result = ac.segment(image, "grid")
    assert len(result.contours) == 12
    for contour in result.contours:  # one curve per disk: each encloses exactly one centre
        inside = [c for c in centers if np.hypot(*(contour.mean(axis=0) - c)) < 8.0]
        assert signed_area(contour) > 0 and len(inside) == 1
    assert synthetic.dice(result.mask, truth) >= 0.97
    assert_monotone(result)


def test_grid_covers_the_image():
    circles = grid((100, 60))
    centers = np.array([c.mean(axis=0) for c in circles])
    assert len(circles) == 6 * 4
    assert centers[:, 0].min() < 16 and centers[:, 0].max() > 100 - 16


def test_colour_regions_of_equal_gray_level():
    image, truth = synthetic.equal_gray_colour()
    result = ac.segment(image, ac.circle((64.0, 64.0), 50.0), color="vector")
    assert synthetic.dice(result.mask, truth) >= 0.98
    assert np.shape(result.c_in) == (3,)
    np.testing.assert_allclose(result.c_in, [0.8, 0.2, 0.2], atol=0.03)
    assert_monotone(result)
    # Documented limitation: as gray the two regions are the same level, nothing to segment.
    gray = ac.segment(image, ac.circle((64.0, 64.0), 50.0), color="gray")
    assert synthetic.dice(gray.mask, truth) < 0.9


def test_per_channel_weights_select_channels():
    image, truth = synthetic.equal_gray_colour()
    # weight only the blue channel, equal in both regions: no contrast left to follow
    blind = ac.segment(image, ac.circle((64.0, 64.0), 50.0), color="vector",
                       lambda_in=[1e-6, 1e-6, 1.0], lambda_out=[1e-6, 1e-6, 1.0])
    seeing = ac.segment(image, ac.circle((64.0, 64.0), 50.0), color="vector",
                        lambda_in=[1.0, 1e-6, 1e-6], lambda_out=[1.0, 1e-6, 1e-6])
    assert synthetic.dice(seeing.mask, truth) >= 0.98
    assert synthetic.dice(blind.mask, truth) < 0.9
    with pytest.raises(ValueError, match="lambda_in has 2 weights"):
        ac.segment(image, color="vector", lambda_in=[1.0, 1.0])


def test_nucleation_sites_skip_no_band_that_holds_a_candidate(monkeypatch):
    from activecontour.imaging.normalize import normalize_image
    from activecontour.models.base import QuadraticForm

    # a region at its constant 0.7 on a background at 0.3, a dark patch deep inside it and a
    # bright one far outside: g = (I - 0.7)^2 - (I - 0.3)^2 is +-0.16, and a 7 x 7 patch holds
    # 45 of a radius-4 disk's 49 pixels, so the disk's mean there is +-41 * 0.16 / 49, far beyond
    # 2 mu / radius; nowhere else does a disk's mean pass on its own side
    image = np.full((120, 50), 0.3)
    inside = np.zeros(image.shape, dtype=bool)
    inside[10:70, 5:45] = True
    image[inside] = 0.7
    image[30:37, 20:27] = 0.3
    image[95:102, 20:27] = 0.7
    values = normalize_image(image, normalize=None)
    form = QuadraticForm.of_fit([1.0], [0.7]) - QuadraticForm.of_fit([1.0], [0.3])
    whole = topology.nucleation_sites(values, inside, form, 0.05, 4.0)
    assert [(tuple(center), hole) for center, hole in whole] == [((33.0, 23.0), True), ((98.0, 23.0), False)]
    # in bands of 6 rows most are skipped (no pixel's g passes there, or none on its own side)
    monkeypatch.setattr(topology, "_BAND_PIXELS", 6 * image.shape[1])
    banded = topology.nucleation_sites(values, inside, form, 0.05, 4.0)
    assert [(tuple(center), hole) for center, hole in banded] == [((33.0, 23.0), True), ((98.0, 23.0), False)]
