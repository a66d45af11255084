"""Touching objects on the families of scenes (issue 23): the scenes, the split, the corner stage."""

import numpy as np
import pytest
import scipy.ndimage
import shapely

import activecontour as ac
from activecontour import synthetic
from activecontour.geometry.curve import orient
from activecontour.objects.arcs import (
    ARC_REACH,
    _arc_clump,
    _meet_at_corners,
    _meeting,
    _uncovered_parts,
)
from activecontour.objects.contrast import _block_spread
from activecontour.objects.corners import CUT_DEPTH, _concave_corners, _corner_parts, _ellipse_cuts
from activecontour.objects.measure import label_image
from activecontour.objects.metrics import match_instances
from activecontour.objects.shapes import MIN_WAIST_DEPTH, _ellipse_axes, _ellipse_fit, _hull_depth
from activecontour.objects.split import split_touching

# ---- the families: exact truth, what they say they draw ----------------------------------------


def test_rendering_is_the_covered_fraction_and_the_labels_the_deepest_shape():
    # two ellipses apart and one pair overlapping: the noise-free image sums to the exact union
    # area (within the sub-sampling: 16 samples a pixel, a boundary error of ~ perimeter / 16 / 4)
    shapes = [synthetic._Ellipse((20.0, 20.0), 12.0, 5.0, 0.3),
              synthetic._Ellipse((20.0, 60.0), 9.0, 9.0, 0.0),
              synthetic._Ellipse((30.0, 72.0), 9.0, 4.0, 1.0)]
    image, labels = synthetic.render_instances(shapes, (50, 90))
    polygons = [shapely.Polygon(_ellipse(s.center, s.a, s.b, s.angle, n=4000)) for s in shapes]
    union = shapely.union_all(polygons).area
    perimeter = sum(p.length for p in polygons)
    assert image.sum() == pytest.approx(union, abs=perimeter / 16)
    rr, cc = np.mgrid[:50, :90] + 0.5  # pixel centres in the scene frame
    depth = np.stack([s.depth(rr, cc) for s in shapes])
    expected = np.where(depth.min(axis=0) <= 1, depth.argmin(axis=0) + 1, 0)
    np.testing.assert_array_equal(labels, expected)


@pytest.mark.parametrize("family", ["disks", "ellipses"])
def test_touching_families_are_clumps_of_the_stated_sizes(family):
    for seed in range(3):
        image, truth = synthetic.FAMILIES[family](seed)
        ids = np.arange(1, truth.max() + 1)
        radius = np.sqrt(scipy.ndimage.sum_labels(np.ones_like(truth), truth, ids) / np.pi)
        # equal-area radii 6-40 px, less what an overlap gives to a neighbour
        assert radius.max() <= 40.0 + 1.0 and radius.min() >= 6.0 * np.sqrt(1 - 0.25) - 1.0
        # every object touches its clump: pieces of 2-8 objects (a clump whose others found no
        # room is one object)
        pieces, count = scipy.ndimage.label(truth > 0)
        sizes = np.array([len(np.unique(truth[pieces == k])) for k in range(1, count + 1)])
        assert sizes.max() <= synthetic.FAMILY_CLUMP[1] and np.mean(sizes >= 2) >= 0.75


def test_a_scene_at_half_the_pixel_size_has_four_times_the_pixels_per_object():
    fine, coarse = synthetic.touching_ellipses(2, pixel=0.5)[1], synthetic.touching_ellipses(2, pixel=1.0)[1]
    assert fine.max() == coarse.max()
    areas = [scipy.ndimage.sum_labels(np.ones_like(t), t, np.arange(1, t.max() + 1)) for t in (fine, coarse)]
    np.testing.assert_allclose(areas[0] / 4, areas[1], rtol=0.15)


# ---- the split on family scenes: F1 against the constructed truth -------------------------------

@pytest.mark.parametrize(("family", "seed", "least"), [("disks", 1, 0.9), ("disks", 3, 0.9),
                                                       ("ellipses", 4, 0.8), ("ellipses", 5, 0.8)])
def test_touching_objects_are_split(family, seed, least):
    image, truth = synthetic.FAMILIES[family](seed)
    res = ac.segment(image)
    assert match_instances(res.labels, truth)["f1"] >= least
    # the connected pieces are clumps: without the split most objects are lost
    assert match_instances(ac.segment(image, separate=False).labels, truth)["f1"] < least - 0.3


# (pieces that the necks or the corners cut off a clump whose whole outline the arc stage did not
# explain, and that are clumps of their own: :func:`activecontour.objects.split._clump_parts`)
@pytest.mark.parametrize(("family", "seed", "least"), [("ellipses", 4, 0.95), ("ellipses", 9, 0.95),
                                                       ("disks", 44, 0.9)])
def test_a_clump_cut_off_an_object_is_split_by_its_own_arcs(family, seed, least):
    image, truth = synthetic.FAMILIES[family](seed)
    assert match_instances(ac.segment(image).labels, truth)["f1"] >= least


def _clump_of(family, seed, count):
    """The connected piece of a family scene's segmentation (``separate=False``) that holds
    ``count`` true objects (20 px of each at least): its curves, its pixels, the true labels of
    the objects it holds (others 0) and the image."""
    image, truth = synthetic.FAMILIES[family](seed)
    pieces = ac.segment(image, separate=False)
    for k, curves in enumerate(pieces.object_contours):
        ids, sizes = np.unique(truth[(pieces.labels == k + 1) & (truth > 0)], return_counts=True)
        if np.count_nonzero(sizes >= 20) == count:
            return curves, pieces.labels == k + 1, np.where(np.isin(truth, ids[sizes >= 20]), truth, 0), image
    raise AssertionError(f"no piece of {count} objects")


# (ellipses seed 11: 7 objects whose contacts the contour rounded, so that the borders between the
# arcs' ellipses end 4-9 px from the corners found, :data:`activecontour.objects.split.
# ARC_END_REACH`; disks seed 0: 7 disks of which two are pressed inside the clump and own no arc,
# :func:`activecontour.objects.arcs._uncovered_parts`)
@pytest.mark.parametrize(("family", "seed", "least"), [("ellipses", 11, 0.9), ("disks", 0, 0.7)])
def test_a_clump_the_arcs_explain_only_in_part_is_split_by_them(family, seed, least):
    curves, inside, truth, image = _clump_of(family, seed, 7)
    parts = split_touching([curves], inside.astype(np.int32), image)
    assert match_instances(label_image(parts, truth.shape), truth)["f1"] >= least


# (ellipses seed 13: a chain of six, two of them side by side with no neck between them, a part
# that is no blob and took its neighbours back in the neck stage: the whole chain was one object,
# :func:`activecontour.objects.corners._as_ellipses`)
def test_a_clump_whose_necks_leave_a_part_of_two_ellipses_is_split():
    curves, inside, truth, image = _clump_of("ellipses", 13, 6)
    parts = split_touching([curves], inside.astype(np.int32), image)
    assert match_instances(label_image(parts, truth.shape), truth)["f1"] >= 0.9


def test_uncovered_pieces_as_large_as_a_part_are_parts_of_their_own():
    # two ellipses' cells of 20 x 20 px; uncovered: a block of 10 x 12 px (0.3 of a cell, above
    # ARC_SIZE_RATIO) in the first, and a sliver of 2 x 5 px in the second
    parts = np.zeros((30, 50), dtype=np.int32)
    parts[5:25, 5:25], parts[5:25, 25:45] = 1, 2
    block, sliver = np.zeros(parts.shape, dtype=bool), np.zeros(parts.shape, dtype=bool)
    block[8:18, 8:20], sliver[10:12, 30:35] = True, True
    before = parts.copy()
    assert _uncovered_parts(parts, block | sliver)
    assert (parts[block] == 3).all()  # a part of its own
    np.testing.assert_array_equal(parts[~block], before[~block])  # the sliver stays in its cell
    # nothing as large as a part: no part added, and the caller declines the clump
    parts = before.copy()
    assert not _uncovered_parts(parts, sliver)
    np.testing.assert_array_equal(parts, before)


def test_touching_objects_are_split_from_the_level_set_too():
    image, truth = synthetic.touching_disks(3)
    assert match_instances(ac.segment(image, backend="levelset").labels, truth)["f1"] >= 0.9


# (seed 7: a rod bent sharply, whose border between two ellipses ended at a wiggle of 17 degrees
# outside the bend, :data:`activecontour.objects.arcs.ARC_END_TURN`)
@pytest.mark.parametrize("seed", [1, 4, 5, 7])
def test_singles_are_never_split(seed):
    image, _ = synthetic.singles(seed)
    pieces = ac.segment(image, separate=False).labels
    labels = ac.segment(image).labels
    # the objects of labels inside each connected piece: one each
    owner = scipy.ndimage.maximum(pieces, labels, np.arange(1, labels.max() + 1))
    assert len(np.unique(owner)) == labels.max()


# ---- the corner stage on exact polygons -------------------------------------------------------

def _ellipse(center, a, b, angle, n=600):
    t = 2 * np.pi * np.arange(n) / n
    turn = np.array([[np.cos(angle), np.sin(angle)], [-np.sin(angle), np.cos(angle)]])
    return orient(np.asarray(center) + np.column_stack([a * np.cos(t), b * np.sin(t)]) @ turn)


def _union(*curves):
    region = shapely.union_all([shapely.Polygon(c) for c in curves])
    return orient(np.asarray(region.exterior.coords)[:-1])


def test_two_ellipses_side_by_side_are_cut_along_their_common_chord():
    # aspect 3, parallel, overlapping by a third of the minor axis: no neck narrower than the
    # parts (the chord is 0.75 of the major axis), but two concave corners where they cross
    a, b = 30.0, 10.0
    # (major axes along the rows, the second ellipse 2 b - 2 b / 3 further along the columns)
    first, second = _ellipse((50.0, 50.0), a, b, 0.0), _ellipse((50.0, 50.0 + 4 * b / 3), a, b, 0.0)
    outline = _union(first, second)
    corners, _, _ = _concave_corners(outline)
    assert len(corners) == 2
    # they cross half-way, at (v / b)^2 = (2/3)^2: rows 50 -+ a sqrt(1 - 4/9), column 50 + 2 b / 3
    np.testing.assert_allclose(np.sort(outline[corners, 0]), 50 + np.array([-1, 1]) * a * np.sqrt(5 / 9),
                               atol=1.0)
    np.testing.assert_allclose(outline[corners, 1], 50 + 2 * b / 3, atol=1.0)
    parts = _corner_parts(outline)
    assert len(parts) == 2
    areas = sorted(shapely.Polygon(p).area for p in parts)
    lens = shapely.Polygon(first).intersection(shapely.Polygon(second)).area
    np.testing.assert_allclose(areas, np.pi * a * b - lens / 2, rtol=0.01)
    assert sum(areas) == pytest.approx(shapely.Polygon(outline).area, rel=1e-9)  # they tile it


def test_two_ellipses_side_by_side_are_two_ellipses_of_the_outline():
    # the pair of the test above, and the pair cut off a clump at a neck: the first ellipse's far
    # end cut straight across (rows past 75, columns before the common chord at 50 + 2 b / 3),
    # vertices no ellipse fits; each side is an ellipse less half the lens, less what was cut off
    a, b = 30.0, 10.0
    first, second = _ellipse((50.0, 50.0), a, b, 0.0), _ellipse((50.0, 50.0 + 4 * b / 3), a, b, 0.0)
    outline = _union(first, second)
    lens = shapely.Polygon(first).intersection(shapely.Polygon(second)).area
    end = shapely.box(75.0, 0.0, 100.0, 50.0 + 2 * b / 3)
    piece = orient(np.asarray(shapely.Polygon(outline).difference(end).exterior.coords)[:-1])
    for part, cut_off in ((outline, 0.0), (piece, shapely.Polygon(outline).intersection(end).area)):
        sides = _ellipse_cuts(part, outline, 1)
        assert sides is not None and len(sides) == 2
        areas = sorted(shapely.Polygon(side).area for side in sides)
        assert sum(areas) == pytest.approx(shapely.Polygon(part).area, rel=1e-9)  # they tile it
        assert areas[1] == pytest.approx(np.pi * a * b - lens / 2, rel=0.02)
        assert areas[0] == pytest.approx(np.pi * a * b - lens / 2 - cut_off, rel=0.02)


def _capsule_v(width, arm, bend):
    """A rod of ``width`` bent by ``bend`` radians in the middle (round ends and joint)."""
    points = [(0.0, 0.0), (arm, 0.0), (arm + arm * np.cos(bend), arm * np.sin(bend))]
    region = shapely.LineString(points).buffer(width / 2, quad_segs=32)
    return orient(np.asarray(region.exterior.coords)[:-1] + 60.0)


def _star(radius, amplitude, arms, n=800):
    t = 2 * np.pi * np.arange(n) / n
    rho = radius * (1 + amplitude * np.cos(arms * t))
    return orient(np.column_stack([60 + rho * np.cos(t), 60 + rho * np.sin(t)]))


#: Single shapes with corners and long axes, which no stage may cut.
SINGLE_SHAPES = [
    pytest.param(_ellipse((60.0, 60.0), 36.0, 12.0, 0.4), id="ellipse aspect 3"),
    pytest.param(_capsule_v(14.0, 40.0, np.pi / 3), id="rod bent 60"),
    pytest.param(_capsule_v(10.0, 30.0, 2 * np.pi / 3), id="rod bent 120"),
    pytest.param(_star(30.0, 0.35, 5), id="star 5"),
    pytest.param(_star(25.0, 0.25, 4), id="star 4"),
]


@pytest.mark.parametrize("outline", SINGLE_SHAPES)
def test_a_single_shape_is_not_cut_at_its_corners(outline):
    assert len(_corner_parts(outline)) == 1
    assert _ellipse_cuts(outline, outline, CUT_DEPTH) is None  # (nor into ellipses of its outline)


def _resampled(outline, spacing=1.0):
    """The closed polygon with vertices every ``spacing`` px of arc length (a converged contour's)."""
    closed = np.vstack([outline, outline[:1]])
    along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(closed, axis=0).T))])
    s = np.arange(0.0, along[-1], spacing)
    return np.column_stack([np.interp(s, along, closed[:, 0]), np.interp(s, along, closed[:, 1])])


def _arc_parts(curves, extent=None):
    """The parts of an object that the arc stage decides alone (:func:`_arc_clump`, a clump that is
    not crowded), or None."""
    clump = _arc_clump(curves, extent=extent)
    return None if clump is None or clump[1] else clump[0]


def _disks_parts(centres, radius):
    """The union of disks as a polygon, its parts by :func:`_arc_parts` and each disk's expected
    part: the disk less half of each lens it shares (pixels of an overlap go to the disk they lie
    deepest in, which for equal disks is the nearer centre)."""
    disks = [shapely.Point(c).buffer(radius, quad_segs=256) for c in centres]
    outline = _resampled(_union(*[np.asarray(d.exterior.coords)[:-1] for d in disks]))
    lens = [[d.intersection(e).area if d is not e else 0.0 for e in disks] for d in disks]
    expected = [np.pi * radius**2 - sum(row) / 2 for row in lens]
    return outline, _arc_parts([outline]), expected


def test_three_disks_around_one_point_are_three_objects():
    # three disks of radius 12, each two overlapping by a sixth of the radius: three concave
    # corners, one per contact, and three arcs, one per disk; no cut between two corners leaves two
    # ellipses (one side holds two disks), so the corner stage alone cannot make three parts
    r = 12.0
    side = 2 * r - r / 6
    centres = [(60.0, 60.0), (60.0, 60.0 + side), (60.0 + side * np.sqrt(3) / 2, 60.0 + side / 2)]
    outline, parts, expected = _disks_parts(centres, r)
    assert len(_corner_parts(outline)) < 3
    assert parts is not None and len(parts) == 3
    polygons = [shapely.Polygon(part[0]) for part in parts]
    found = [next(p for p in polygons if p.contains(shapely.Point(c))) for c in centres]
    # the pixel cells cut the polygon along a staircase straightened to a pixel: the area of a part
    # is the expected within its border's length times a pixel
    for polygon, area in zip(found, expected, strict=True):
        assert polygon.area == pytest.approx(area, abs=2 * r)
    # they tile it (:func:`_cut` keeps no sliver under a pixel apart from its piece)
    assert sum(p.area for p in polygons) == pytest.approx(shapely.Polygon(outline).area, abs=1.0)


def test_a_chain_of_three_disks_gives_the_middle_one_both_its_arcs():
    # the middle disk owns two arcs, one on each side: the grouping joins them into one circle
    r = 10.0
    centres = [(50.0, 50.0), (50.0, 50.0 + 2 * r - r / 2), (50.0, 50.0 + 4 * r - r)]
    outline, parts, expected = _disks_parts(centres, r)
    assert parts is not None and len(parts) == 3
    polygons = [shapely.Polygon(p[0]) for p in parts]
    areas = [next(p for p in polygons if p.contains(shapely.Point(c))).area for c in centres]
    np.testing.assert_allclose(areas, expected, atol=2 * r)


def test_seven_disks_around_a_hidden_one_are_seven_objects():
    # six disks of radius 12 around a seventh, centres 1.85 r apart: each two neighbours overlap
    # (1.85 r < 2 r) and no pixel lies in three of them (the centre of three mutually touching
    # disks is 1.85 r / sqrt(3) > r from each); the middle disk owns no arc of the outline, and
    # three parts meet at six places: a crowded clump, which the arcs alone do not decide
    r = 12.0
    apart = 1.85 * r
    angles = np.arange(6) * np.pi / 3 + 0.2
    centres = [(60.0, 60.0)] + [(60.0 + apart * np.cos(a), 60.0 + apart * np.sin(a)) for a in angles]
    outline, parts, _ = _disks_parts(centres, r)
    assert parts is None
    clump = _arc_clump([outline])
    assert clump is not None and clump[1]  # crowded
    # split_touching weighs it against the necks and corners: every disk one object
    objects = split_touching([[outline]], label_image([[outline]], (120, 120)))
    polygons = [shapely.Polygon(curves[0]) for curves in objects]
    held = np.array([[p.contains(shapely.Point(c)) for c in centres] for p in polygons])
    assert held.shape == (7, 7) and (held.sum(axis=0) == 1).all() and (held.sum(axis=1) == 1).all()
    # they tile the object, but for slivers of the cells' staircases (under a pixel each,
    # :func:`activecontour.objects.corners._cut`) where twelve borders reach the hidden cell
    assert sum(p.area for p in polygons) == pytest.approx(shapely.Polygon(outline).area, abs=2.0)


def test_parts_meeting_are_counted_where_they_meet():
    # four quadrants meet at the centre (four parts within ARC_REACH, one place with three or
    # more); three columns meet nowhere three at a time
    inside = np.zeros((40, 40), dtype=bool)
    inside[2:38, 2:38] = True
    rows, cols = np.indices(inside.shape)
    quadrants = np.where(inside, 1 + (rows >= 20) + 2 * (cols >= 20), 0).astype(np.int32)
    corners = np.array([[2.0, 19.5], [37.0, 19.5], [19.5, 2.0], [19.5, 37.0]])
    assert _meeting(quadrants, inside, corners, 4) == (4, 1)
    assert not _meet_at_corners(quadrants, inside, corners, 4)
    columns = np.where(inside, 1 + (cols >= 14) + (cols >= 26), 0).astype(np.int32)
    ends = np.array([[2.0, 13.5], [37.0, 13.5], [2.0, 25.5], [37.0, 25.5]])
    assert 12 > 2 * ARC_REACH  # (the columns' borders farther apart than two reaches)
    assert _meeting(columns, inside, ends, 3) == (2, 0)
    assert _meet_at_corners(columns, inside, ends, 3)


def test_a_clump_that_reaches_the_image_edge_is_left_to_the_necks_and_corners():
    # two disks overlapping by a sixth of the radius: a clump of two ellipses inside the image,
    # none where the image ends at its last column (an object there may be cut off by the edge,
    # whose straight piece of outline is no object's)
    r = 12.0
    outline, parts, _ = _disks_parts([(40.0, 30.0), (40.0, 30.0 + 2 * r - r / 6)], r)
    columns = int(np.floor(outline[:, 1].max() + 0.5))  # the image's edge at column columns - 0.5
    assert len(_arc_parts([outline], extent=(100, columns + 1))) == 2
    assert _arc_parts([outline], extent=(100, columns)) is None
    assert _arc_parts([outline - [0.0, outline[:, 1].min() + 0.5]], extent=(100, 100)) is None


def test_a_piece_cut_off_goes_through_the_arc_stage_unless_it_is_convex(monkeypatch):
    import activecontour.objects.split as split

    r = 12.0
    side = 2 * r - r / 6
    centres = [(60.0, 60.0), (60.0, 60.0 + side), (60.0 + side * np.sqrt(3) / 2, 60.0 + side / 2)]
    outline, parts, _ = _disks_parts(centres, r)
    # a trefoil of disks is split as the arc stage splits it
    clump = split._clump_parts([outline], (200, 200))
    assert len(clump) == 3
    assert sorted(shapely.Polygon(p[0]).area for p in clump) == pytest.approx(
        sorted(shapely.Polygon(p[0]).area for p in parts), abs=1e-9)
    # a convex piece is itself, without the arc stage
    monkeypatch.setattr(split, "_arc_clump", lambda *args: pytest.fail("a convex piece reached the arcs"))
    disk = _ellipse((60.0, 60.0), 20.0, 12.0, 0.3)
    assert split._clump_parts([disk], (200, 200)) == [[disk]]


def test_borders_that_reach_the_outline_where_no_corner_is_are_no_clump():
    inside = np.zeros((20, 30), dtype=bool)
    inside[2:18, 2:28] = True
    parts = np.where(inside, np.where(np.arange(30) < 15, 1, 2), 0).astype(np.int32)
    # the border between the two halves reaches the outline at rows 2 and 17, columns 14-15
    assert _meet_at_corners(parts, inside, np.array([[2.0, 14.5], [17.0, 14.5]]), 2)
    assert not _meet_at_corners(parts, inside, np.array([[2.0, 14.5]]), 2)
    assert not _meet_at_corners(parts, inside, np.zeros((0, 2)), 2)


def _flower(radius, petals, length, width):
    """Petal ellipses around a disk: one shape, the centre larger than each petal."""
    shapes = [shapely.Point(60.0, 60.0).buffer(radius, quad_segs=128)]
    for k in range(petals):
        angle = 2 * np.pi * k / petals
        centre = 60.0 + (radius + length / 2) * np.array([np.cos(angle), np.sin(angle)])
        shapes.append(shapely.Polygon(_ellipse(centre, length, width, -angle)))
    return orient(np.asarray(shapely.union_all(shapes).exterior.coords)[:-1])


@pytest.mark.parametrize("outline", SINGLE_SHAPES + [
    pytest.param(_star(30.0, 0.3, 7), id="star 7"),
    pytest.param(_star(20.0, 0.2, 6), id="star 6"),
    pytest.param(_flower(12.0, 6, 8.0, 5.0), id="flower"),
])
def test_a_single_shape_is_no_clump_of_ellipses(outline):
    assert _arc_parts([_resampled(outline)]) is None


def test_the_ellipse_fit_is_exact_on_an_ellipse():
    outline = _ellipse((12.0, -4.0), 20.0, 7.0, 0.7, n=200)
    conic, residual = _ellipse_fit(outline)
    centre, semi_axes, axes = _ellipse_axes(conic)
    np.testing.assert_allclose(centre, [12.0, -4.0], atol=1e-9)
    np.testing.assert_allclose(np.sort(semi_axes), [7.0, 20.0], rtol=1e-9)
    assert residual < 1e-12
    major = axes[:, np.argmax(semi_axes)]
    assert abs(major @ [np.cos(0.7), np.sin(0.7)]) == pytest.approx(1.0, abs=1e-9)


# ---- the cheap tests that spare single objects -------------------------------------------------

def test_a_convex_object_skips_the_split(monkeypatch):
    import activecontour.imaging.noise as noise
    import activecontour.objects.split as split

    disk = [ac.circle((300.0, 300.0), 250.0, n=2000)]
    assert _hull_depth(disk[0]).max() < MIN_WAIST_DEPTH
    rr, cc = np.mgrid[:600, :600]
    labels = (np.hypot(rr - 300, cc - 300) <= 250).astype(np.int32)

    def refuse(*args, **kwargs):
        raise AssertionError("a convex object of one intensity reached the split")

    for name in ("_boundary_distance", "_may_have_necks", "_contrast_parts", "_corner_parts"):
        monkeypatch.setattr(split, name, refuse)
    monkeypatch.setattr(noise, "estimate_noise", refuse)  # nor did it need the noise
    noisy = synthetic.add_noise((labels > 0).astype(float), 0.3, seed=2)
    assert split_touching([disk], labels, noisy)[0] is disk


def test_the_block_means_see_a_contrast_and_no_noise():
    rr, cc = np.mgrid[:80, :80]
    mask = np.hypot(rr - 40, cc - 40) <= 30
    flat = synthetic.add_noise(mask * 1.0, 0.3, seed=3)
    # blocks of 6 x 6: their means carry the noise / 6, well below the least contrast 2 sigma
    assert _block_spread(mask, flat, 3.0) < 2 * 0.3
    halves = synthetic.add_noise(mask * np.where(cc < 40, 1.0, 0.5), 0.3 / 3, seed=3)
    assert _block_spread(mask, halves, 3.0) > 0.5 - 2 * 0.3 / 3  # the step, less the noise
