"""The convex hull of a point set in the plane (the compiled monotone chain), without scipy.

Qhull (``scipy.spatial.ConvexHull``) gives the same extreme points, but importing
``scipy.spatial`` costs about a third of a cold command's time, and the objects' pass only
needs hulls of outlines: the hull depth of the split (:mod:`activecontour.objects.split`) and the
convex area of the measurements (:mod:`activecontour.objects.measure`).
"""

from __future__ import annotations

import numpy as np

from activecontour._kernels import convex_hull

__all__ = ["hull_area", "hull_vertices"]


def hull_vertices(points):
    """Indices of the extreme points of ``points`` (K, 2), in one turning direction along the hull
    (collinear and repeated points left out); fewer than 3 when the points lie on a line."""
    points = np.ascontiguousarray(points, dtype=np.float64)
    order = np.lexsort((points[:, 1], points[:, 0]))
    out = np.empty(len(points) + 1, dtype=np.intp)
    return out[:convex_hull(points, order, out)]


def hull_area(points):
    """The area of the convex hull of ``points`` (K, 2) (0 on a line): the shoelace formula over
    :func:`hull_vertices`."""
    points = np.asarray(points, dtype=np.float64)
    vertices = hull_vertices(points)
    if len(vertices) < 3:
        return 0.0
    r, c = points[vertices, 0], points[vertices, 1]
    return 0.5 * abs(float(np.dot(r, np.roll(c, -1)) - np.dot(c, np.roll(r, -1))))
