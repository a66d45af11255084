"""Closed polygonal curves and their 1-D geometry, in the book's conventions.

A closed curve is a float array of shape (K, 2) of vertices in (row, col), each stored once; edge i
joins vertex i and vertex (i + 1) mod K.  The signed area ``0.5 * sum(r_i c_{i+1} - r_{i+1} c_i)`` is
positive for an outer boundary and negative for a hole.  With the unit tangent ``tau = (t_r, t_c)``
of an edge, the normal is ``nu = (t_c, -t_r)`` (section 4.5.2): it points out of the enclosed region
Omega_i, into Omega_o, as in Figure 6.6.

Curvature follows (3.45) and (4.30): ``kappa * nu = -Laplace_Sigma(id)``, so a circle of radius R has
``kappa = 1/R``.  On the polygon it is computed in P1 weak form, ``kappa nu = M^{-1} K X``.
"""

from __future__ import annotations

import numpy as np

from activecontour.geometry import fem

__all__ = [
    "as_curve",
    "clean",
    "curvature",
    "curvature_vector",
    "edge_lengths",
    "edge_normals",
    "edge_tangents",
    "length",
    "orient",
    "resample",
    "signed_area",
    "subdivide",
    "tangential_gradient",
    "to_xy",
    "from_xy",
    "vertex_normals",
]


def as_curve(points, *, name="curve"):
    """Validate and return a closed curve as a float64 (K, 2) array.

    A repeated closing vertex (first == last) is dropped.  Raises ``ValueError`` naming ``name`` for
    a wrong shape, NaN/inf, fewer than 3 distinct vertices, or zero enclosed area.
    """
    try:
        points = np.array(points, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be an array of (row, col) points") from None
    if points.ndim != 2 or points.shape[1] != 2:
        raise ValueError(f"{name} must have shape (K, 2) in (row, col), got shape {points.shape}")
    if not np.all(np.isfinite(points)):
        raise ValueError(f"{name} contains NaN or infinite coordinates")
    if len(points) > 1 and np.array_equal(points[0], points[-1]):
        points = points[:-1]
    keep = np.any(points != np.roll(points, 1, axis=0), axis=1)
    if len(points) > 1:
        points = points[keep]
    if len(points) < 3:
        raise ValueError(f"{name} needs at least 3 distinct vertices, got {len(points)}")
    if _encloses_no_area(points):
        raise ValueError(f"{name} is degenerate: it encloses no area")
    return points


def _encloses_no_area(points):
    """Whether ``|area| <= 1e-12 max(1, length^2)``, evaluated on the curve moved to the origin and
    scaled to unit size, so that coordinates near the float range (1e200) do not overflow."""
    centred = points - points[0]
    scale = float(np.max(np.abs(centred)))
    if scale == 0.0:
        return True
    unit = centred / scale
    with np.errstate(over="ignore"):  # 1 / scale**2 is inf for a curve of 1e-160 px: no area
        floor = 1.0 / (scale * scale)
    return abs(signed_area(unit)) <= 1e-12 * max(floor, length(unit) ** 2)


#: Relative tolerance of :func:`clean`: a vertex whose turn is within this fraction of its edges'
#: lengths of a straight reversal, or an edge this much shorter than the curve, is removed.
CLEAN_TOLERANCE = 1e-9


def clean(points, *, tolerance=CLEAN_TOLERANCE):
    """Remove what makes a polygon invalid without changing the region it encloses.

    Drops repeated vertices (edges shorter than ``tolerance`` times the curve's extent) and
    zero-width spikes: a vertex where the curve goes straight back along itself (its two edges
    antiparallel to within ``tolerance``), such as a back-step of 1e-5 px along the image border
    after clipping.  Removing either changes the enclosed area by at most ``tolerance`` times
    its extent squared.  Repeats until nothing changes.

    Returns
    -------
    ndarray (K, 2), or None when fewer than 3 vertices or no area are left.
    """
    points = np.asarray(points, dtype=np.float64)
    if len(points) == 0:
        return None
    extent = float(np.ptp(points, axis=0).max())
    scale = tolerance * max(extent, 1.0)
    while len(points) >= 3:
        d = edge_vectors(points)
        h = np.hypot(d[:, 0], d[:, 1])
        keep = h > scale  # vertex i survives when the edge from it is not ~0
        if keep.all():
            before = np.roll(d, 1, axis=0)
            before_h = np.roll(h, 1)
            cross = before[:, 0] * d[:, 1] - before[:, 1] * d[:, 0]
            dot = np.einsum("ij,ij->i", before, d)
            spike = (dot < 0) & (np.abs(cross) <= tolerance * before_h * h + scale * np.minimum(before_h, h))
            if not spike.any():
                break
            # remove one spike vertex of each pair of neighbours per pass: the curve stays closed
            spike &= ~np.roll(spike, 1)
            keep = ~spike
        points = points[keep]
    if len(points) < 3 or abs(signed_area(points)) <= scale * max(extent, 1.0):
        return None
    return points


def edge_vectors(points):
    """``X[i + 1] - X[i]`` for every edge, shape (K, 2)."""
    return np.roll(points, -1, axis=0) - points


def edge_lengths(points):
    """Length of every edge, shape (K,)."""
    d = edge_vectors(points)
    return np.hypot(d[:, 0], d[:, 1])


def length(points):
    """Arc length |Sigma| (1.9) of the closed polygon."""
    return float(edge_lengths(points).sum())


def signed_area(points):
    """Signed enclosed area: positive for an outer boundary, negative for a hole."""
    r, c = points[:, 0], points[:, 1]
    return 0.5 * float(np.dot(r, np.roll(c, -1)) - np.dot(np.roll(r, -1), c))


def edge_tangents(points):
    """Unit tangent tau (3.44) of every edge, shape (K, 2); zero for a zero-length edge."""
    d = edge_vectors(points)
    h = np.hypot(d[:, 0], d[:, 1])
    return np.divide(d, h[:, None], out=np.zeros_like(d), where=h[:, None] > 0)


def edge_normals(points):
    """Unit normal ``nu = (t_c, -t_r)`` of every edge (section 4.5.2), shape (K, 2)."""
    tau = edge_tangents(points)
    return np.column_stack([tau[:, 1], -tau[:, 0]])


def vertex_normals(points):
    """Unit normal at each vertex: the normalised sum of the normals of its two edges."""
    nu = edge_normals(points)
    n = nu + np.roll(nu, 1, axis=0)
    norm = np.hypot(n[:, 0], n[:, 1])
    return np.divide(n, norm[:, None], out=np.zeros_like(n), where=norm[:, None] > 0)


def curvature_vector(points):
    """Curvature vector ``kappa nu = M^{-1} K X`` (4.30), the P1 weak form of -Laplace_Sigma id.

    A vertex repeated consecutively (a zero-length edge, where the weak form is undefined) gets the
    value of its first copy: the curve is evaluated on its distinct vertices.
    """
    distinct, owner = _distinct_vertices(points)
    h = edge_lengths(distinct)
    stiffness = fem.stiffness_diagonals(h)
    return fem.cyclic_solve(*fem.mass_diagonals(h), fem.cyclic_apply(*stiffness, distinct))[owner]


def curvature(points):
    """Signed scalar curvature at the vertices: ``(kappa nu) . nu``, 1/R on a circle (3.45).

    Repeated vertices get the curvature of their first copy (see :func:`curvature_vector`).
    """
    distinct, owner = _distinct_vertices(points)
    kappa = np.einsum("ij,ij->i", curvature_vector(distinct), vertex_normals(distinct))
    return kappa[owner]


def _distinct_vertices(points):
    """The curve without consecutive repeated vertices, and for every vertex the index of its copy.

    Raises ValueError when fewer than 3 distinct vertices remain (no curvature is defined).
    """
    points = np.asarray(points, dtype=np.float64)
    new = np.any(points != np.roll(points, 1, axis=0), axis=1)
    if np.count_nonzero(new) < 3:
        raise ValueError(f"the curve needs at least 3 distinct vertices, got {np.count_nonzero(new)}")
    starts = np.flatnonzero(new)
    # vertex k belongs to the last distinct vertex at or before it (cyclically: a run of copies
    # at the start of the array belongs to the last one)
    owner = np.searchsorted(starts, np.arange(len(points)), side="right") - 1
    return points[starts], np.where(owner < 0, len(starts) - 1, owner)


def tangential_gradient(points, values):
    """Tangential gradient grad_Sigma of a P1 field on each edge (constant per edge).

    Parameters
    ----------
    points : ndarray (K, 2)
    values : ndarray (K,) or (K, d)
        Nodal values of a scalar or vector P1 field.

    Returns
    -------
    ndarray (K, 2) for a scalar field, (K, d, 2) for a vector field: row k of the Jacobian is the
    gradient of component k, so ``trace`` gives the tangential divergence (4.22).
    """
    values = np.asarray(values, dtype=np.float64)
    h = edge_lengths(points)
    tau = edge_tangents(points)
    dv = (np.roll(values, -1, axis=0) - values) / np.where(h > 0, h, np.inf).reshape(
        (-1,) + (1,) * (values.ndim - 1)
    )
    return dv[..., None] * tau[:, None, :] if values.ndim == 2 else dv[:, None] * tau


def orient(points, *, hole=False):
    """Return the curve with positive signed area (or negative when ``hole``)."""
    area = signed_area(points)
    return points[::-1].copy() if (area < 0) != hole else points


def resample(points, spacing, *, min_vertices=8):
    """Vertices at equal arc-length steps of about ``spacing`` along the polygon.

    The first vertex is kept; the number of vertices is ``max(min_vertices, round(L / spacing))``.

    Raises
    ------
    ValueError
        For NaN or infinite coordinates, or a ``spacing`` that is not a finite number > 0.
    """
    points = np.asarray(points, dtype=np.float64)
    if not np.all(np.isfinite(points)):
        raise ValueError("resample: the curve contains NaN or infinite coordinates")
    if not (np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"spacing must be a finite number > 0 (pixels), got {spacing!r}")
    h = edge_lengths(points)
    s = np.concatenate([[0.0], np.cumsum(h)])
    total = s[-1]
    n = max(min_vertices, int(round(total / spacing)))
    closed = np.vstack([points, points[:1]])
    targets = np.arange(n) * (total / n)
    return np.column_stack(
        [np.interp(targets, s, closed[:, 0]), np.interp(targets, s, closed[:, 1])]
    )


def to_xy(points):
    """(row, col) -> (x, y) = (col, row), for OpenCV, matplotlib, SVG and GeoJSON: the only place."""
    return np.asarray(points, dtype=np.float64)[..., ::-1].copy()


def from_xy(points):
    """(x, y) -> (row, col), the inverse of :func:`to_xy`."""
    return to_xy(points)


def stack_curves(curves):
    """Stack a list of (K_i, 2) curves into one vertex array and the index of each edge's end.

    Returns ``points (sum K_i, 2)``, ``next_index`` with edge e joining ``e`` and ``next_index[e]``,
    and the start offset of every curve (length ``len(curves) + 1``).
    """
    counts = np.array([len(c) for c in curves], dtype=np.intp)
    offsets = np.concatenate([[0], np.cumsum(counts)])
    points = np.concatenate(curves, axis=0) if curves else np.zeros((0, 2))
    next_index = np.arange(offsets[-1]) + 1
    next_index[offsets[1:] - 1] = offsets[:-1]
    return points, next_index, offsets



def subdivide(points, lengths, spacing, longest=None):
    """The same closed polygons with their long edges split into equal pieces: nothing moves.

    Every edge longer than ``longest`` (``spacing`` by default) becomes ``ceil(h / spacing)``
    pieces; the other edges stay.  The polygons, and so their region and every integral over it,
    are unchanged (the new vertices lie on the old edges), unlike :func:`resample`, whose chords
    cut the corners.

    Parameters
    ----------
    points : ndarray (sum K_i, 2)
        The curves stacked one after the other, each vertex once (as :func:`stack_curves`).
    lengths : ndarray (n,) of int
        K_i, the number of vertices of each curve.
    spacing, longest : float or ndarray (sum K_i,)
        Per edge, when arrays (the edge from each vertex).

    Returns
    -------
    points : ndarray (sum L_i, 2)
    lengths : ndarray (n,) of int
        L_i, the new number of vertices of each curve.
    """
    lengths = np.asarray(lengths, dtype=np.intp)
    longest = spacing if longest is None else longest
    curve_first = np.repeat(np.cumsum(lengths) - lengths, lengths)
    index = np.arange(len(points))
    end = points[curve_first + (index - curve_first + 1) % np.repeat(lengths, lengths)]
    h = np.hypot(*(end - points).T)
    count = np.where(h > longest, np.ceil(h / spacing), 1).astype(np.intp)
    edge = np.repeat(index, count)
    t = (np.arange(edge.size) - np.repeat(np.cumsum(count) - count, count)) / count[edge]
    dense = points[edge] + t[:, None] * (end - points)[edge]
    return dense, np.add.reduceat(count, np.cumsum(lengths) - lengths) if len(lengths) else lengths
