"""Regions of the plane bounded by oriented curves: hole grouping and shapely region operations.

:func:`nesting` is the one rule of nesting (which closed curve lies inside which, whatever their
orientation): :func:`orient_by_nesting` makes curves inside an even number of others outer
boundaries and the rest holes, :func:`group_curves` gives each outer boundary the holes directly
inside it, and :func:`activecontour.geometry.topology.region_problem`, ``region_union``,
:func:`activecontour.initial.initial_curves`, :func:`activecontour.chan_vese_energy` and the vector
writers read the same rule.  :func:`complement_region` and :func:`clip_region` are exact polygon
operations (shapely).
"""

from __future__ import annotations

import numpy as np

from activecontour.geometry.curve import clean, orient, signed_area

__all__ = ["clip_region", "complement_region", "group_curves", "group_indices", "nesting",
           "orient_by_nesting", "polygons"]

def _to_shapely(curves):
    """A (Multi)Polygon from oriented curves in (row, col) (x = row, y = col); one outer boundary
    (positive) is its polygon without the nesting of curves into outer boundaries and holes (a
    traced cell or an object without holes: most of those the split cuts)."""
    import shapely

    if len(curves) == 1 and signed_area(curves[0]) > 0:
        return shapely.make_valid(shapely.Polygon(curves[0]))
    polygons = [shapely.Polygon(obj[0], holes=obj[1:]) for obj in group_curves(curves)]
    return shapely.make_valid(shapely.MultiPolygon(polygons) if len(polygons) != 1 else polygons[0])


def _from_shapely(polygon):
    """An outer boundary then holes, oriented, without the closing vertex; [] if degenerate."""
    import shapely

    polygon = shapely.orient_polygons(polygon) if hasattr(shapely, "orient_polygons") else \
        shapely.geometry.polygon.orient(polygon, 1.0)
    outer = clean(np.asarray(polygon.exterior.coords)[:-1])
    if outer is None:
        return []
    holes = [clean(np.asarray(ring.coords)[:-1]) for ring in polygon.interiors]
    return [outer] + [h for h in holes if h is not None]


def complement_region(contours, shape):
    """The boundary of the image domain minus the region the contours bound (oriented curves).

    The domain is the rectangle [-0.5, M - 0.5] x [-0.5, N - 0.5] of :func:`activecontour.geometry.raster`
    (every pixel square), so the complement's mask is the region's mask inverted.
    """
    import shapely

    m, n = shape
    domain = shapely.box(-0.5, -0.5, m - 0.5, n - 0.5)
    rest = shapely.difference(domain, _to_shapely(contours)) if contours else domain
    return [curve for polygon in getattr(rest, "geoms", [rest]) if isinstance(polygon, shapely.Polygon)
            and polygon.area > 0 for curve in _from_shapely(polygon)]


def clip_region(contours, domain):
    """The boundary of the region the contours bound, intersected with the region of ``domain``
    (oriented curves too)."""
    import shapely

    if not contours:
        return []
    kept = shapely.intersection(_to_shapely(contours), _to_shapely(domain))
    return [curve for polygon in getattr(kept, "geoms", [kept]) if isinstance(polygon, shapely.Polygon)
            and polygon.area > 0 for curve in _from_shapely(polygon)]


def polygons(curves):
    """The shapely polygons of closed curves (x = row, y = col), made valid where they are not:
    a self-crossing curve is the union of its loops."""
    import shapely

    out = np.array([shapely.Polygon(np.asarray(c, dtype=np.float64)) for c in curves], dtype=object)
    invalid = ~shapely.is_valid(out) if len(out) else np.zeros(0, dtype=bool)
    out[invalid] = shapely.make_valid(out[invalid])
    return out


def nesting(shapes):
    """The one rule of nesting: which closed curve lies inside which, whatever their orientation.

    Curve i lies inside curve j when i's polygon lies within j's (shapely's ``within``: no point
    of i outside j, so a hole may touch its outer boundary) and the two are not one polygon.

    Parameters
    ----------
    shapes : sequence of shapely geometries
        The curves' polygons (:func:`polygons`).

    Returns
    -------
    depth : int ndarray (n,)
        How many of the other curves each curve lies inside: an even depth is an outer boundary
        (positive signed area), an odd one a hole (negative).
    parent : int ndarray (n,)
        The innermost curve each curve lies inside (the deepest of them), -1 for none.
    same : list of (int, int)
        Pairs i < j of curves that are one polygon (a curve given twice): neither counts as
        inside the other.
    """
    import shapely

    n = len(shapes)
    if n == 0:
        return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp), []
    shapes = np.asarray(shapes, dtype=object)
    # the pairs whose boxes meet (an STR tree), then one vectorised test: the tree's own "within"
    # predicate costs ~50x more on a thousand polygons
    inner, outer = shapely.STRtree(shapes).query(shapes)
    distinct = inner != outer
    inner, outer = inner[distinct], outer[distinct]
    within = shapely.within(shapes[inner], shapes[outer])
    inner, outer = inner[within], outer[within]
    pairs = set(zip(inner.tolist(), outer.tolist(), strict=True))
    mutual = np.array([(j, i) in pairs for i, j in zip(inner.tolist(), outer.tolist(), strict=True)],
                      dtype=bool)
    same = sorted({(min(i, j), max(i, j)) for i, j in zip(inner[mutual].tolist(), outer[mutual].tolist(),
                                                           strict=True)})
    inner, outer = inner[~mutual], outer[~mutual]
    depth = np.bincount(inner, minlength=n)
    parent = np.full(n, -1, dtype=np.intp)
    order = np.lexsort((depth[outer], inner))  # by curve, then by its enclosers' depth
    inner, outer = inner[order], outer[order]
    deepest = np.append(inner[1:] != inner[:-1], True)[:len(inner)]
    parent[inner[deepest]] = outer[deepest]
    return depth, parent, same


def orient_by_nesting(curves, depth=None):
    """The curves oriented by :func:`nesting`: a curve inside an even number of the others made an
    outer boundary (positive), inside an odd number a hole (negative), whatever orientation it was
    given in (``skimage.measure.find_contours`` walks outlines clockwise, OpenCV's
    ``findContours`` counterclockwise in (x, y), shapely either way).  ``depth``: the first of
    ``nesting(polygons(curves))`` when the caller has it (it is not computed again)."""
    depth = nesting(polygons(curves))[0] if depth is None else depth
    return [orient(np.asarray(c, dtype=np.float64), hole=d % 2 == 1)
            for c, d in zip(curves, depth, strict=True)]


def group_indices(contours):
    """Indices of oriented contours grouped as ``[outer, hole, hole, ...]``, one list per outer
    boundary in the order given: each hole goes to the innermost outer boundary around it
    (:func:`nesting`).  Holes inside no outer boundary are left out."""
    positive = [signed_area(c) > 0 for c in contours]
    parent = nesting(polygons(contours))[1]
    groups = {i: [i] for i, p in enumerate(positive) if p}
    for i, p in enumerate(positive):
        if p:
            continue
        owner = parent[i]
        while owner >= 0 and not positive[owner]:  # a hole directly inside a hole: look further out
            owner = parent[owner]
        if owner >= 0:
            groups[owner].append(i)
    return list(groups.values())


def group_curves(contours):
    """Group oriented contours into objects: each outer boundary with the holes directly in it.

    Parameters
    ----------
    contours : list of ndarray (K, 2)
        Outer boundaries (positive signed area) and holes (negative), not crossing each other.

    Returns
    -------
    list of list of ndarray
        One list per object: its outer boundary first, then its holes (:func:`group_indices`).
        Objects are ordered by the (row, col) of their topmost-leftmost vertex, so ids read like
        text.
    """
    return _reading_order([[contours[i] for i in group] for group in group_indices(contours)])


def _reading_order(objects):
    """Objects sorted by the (row, col) of their topmost-leftmost vertex: ids read like text."""
    return sorted(objects, key=top_left)


def top_left(curves):
    outer = curves[0]
    return tuple(outer[np.lexsort(outer.T[::-1])[0]])

