"""Regions of the plane bounded by oriented curves: hole grouping and shapely region operations.

:func:`group_curves` gives each outer boundary the holes directly inside it (the one rule of
nesting); :func:`complement_region` and :func:`clip_region` are exact polygon operations (shapely).
"""

from __future__ import annotations

import numpy as np

from activecontour.geometry.curve import clean, signed_area, stack_curves

__all__ = ["clip_region", "complement_region"]

def _to_shapely(curves):
    """A (Multi)Polygon from oriented curves in (row, col) (x = row, y = col)."""
    import shapely

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


def group_curves(contours):
    """Group oriented contours into objects: each outer boundary with the holes directly in it.

    Parameters
    ----------
    contours : list of ndarray (K, 2)
        Outer boundaries (positive signed area) and holes (negative), not crossing each other.

    Returns
    -------
    list of list of ndarray
        One list per object: its outer boundary first, then its holes.  Objects are ordered by
        the (row, col) of their topmost-leftmost vertex, so ids read like text.
    """
    from activecontour.geometry.topology import winding_number

    outers = [c for c in contours if signed_area(c) > 0]
    holes = [c for c in contours if signed_area(c) < 0]
    objects = [[c] for c in outers]
    if holes and outers:
        points, next_index, offsets = stack_curves(outers)
        areas = np.array([signed_area(c) for c in outers])
        for hole in holes:
            # the smallest outer boundary around the hole is the one it belongs to; every point of
            # the hole is inside it, its first vertex will do
            inside = [i for i in np.argsort(areas)
                      if winding_number(points[offsets[i]:offsets[i + 1]],
                                        next_index[offsets[i]:offsets[i + 1]] - offsets[i],
                                        hole[:1])[0] != 0]
            if inside:
                objects[inside[0]].append(hole)
    return _reading_order(objects)


def _reading_order(objects):
    """Objects sorted by the (row, col) of their topmost-leftmost vertex: ids read like text."""
    return sorted(objects, key=top_left)


def top_left(curves):
    outer = curves[0]
    return tuple(outer[np.lexsort(outer.T[::-1])[0]])

