"""The compiled convex hull against Qhull (scipy.spatial.ConvexHull) and against shapes whose hull
is known."""

import numpy as np
import pytest
import scipy.spatial

from activecontour.geometry.hull import hull_area, hull_vertices


@pytest.mark.parametrize("seed", range(40))
def test_hull_is_qhulls_on_random_points(seed):
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(int(rng.integers(3, 400)), 2)) * rng.uniform(0.1, 100, size=2)
    ours = hull_vertices(points)
    theirs = scipy.spatial.ConvexHull(points)
    assert sorted(ours) == sorted(theirs.vertices)
    assert hull_area(points) == pytest.approx(theirs.volume, rel=1e-12)


def test_hull_turns_one_way_and_closes():
    rng = np.random.default_rng(7)
    points = rng.uniform(-5, 5, size=(200, 2))
    hull = points[hull_vertices(points)]
    edges = np.roll(hull, -1, axis=0) - hull
    turns = edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1] - edges[:, 1] * np.roll(edges, -1, axis=0)[:, 0]
    assert np.all(turns > 0) or np.all(turns < 0)


def test_collinear_and_repeated_points_are_not_vertices():
    # a square with points along its sides and its corners repeated: the 4 corners only
    side = np.linspace(0, 1, 9)
    square = np.vstack([np.c_[side, 0 * side], np.c_[side, 0 * side + 1], np.c_[0 * side, side],
                        np.c_[0 * side + 1, side], [[0, 0], [1, 1], [0.5, 0.5]]])
    corners = {tuple(p) for p in square[hull_vertices(square)]}
    assert corners == {(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (1.0, 1.0)}
    assert hull_area(square) == 1.0


def test_points_on_a_line_have_no_area():
    t = np.linspace(-3, 7, 25)
    assert len(hull_vertices(np.c_[t, 2 * t + 1])) < 3
    assert hull_area(np.c_[t, 2 * t + 1]) == 0.0
    assert hull_area(np.zeros((5, 2))) == 0.0


def test_hull_area_of_a_regular_polygon_with_interior_points():
    # the hull of a regular 12-gon plus points inside it is the 12-gon: area 3 r^2
    angles = 2 * np.pi * np.arange(12) / 12
    ring = 4.0 * np.c_[np.cos(angles), np.sin(angles)]
    inside = np.random.default_rng(1).uniform(-2, 2, size=(50, 2))
    assert hull_area(np.vstack([inside, ring])) == pytest.approx(3 * 4.0**2, rel=1e-14)
