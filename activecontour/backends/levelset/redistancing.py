"""Reinitialisation: the signed distance to the zero level set (or to curves), in a narrow band."""

from __future__ import annotations

import numpy as np

from activecontour import _kernels
from activecontour.backends.levelset.zeroset import _cell_segments, _change_cells
from activecontour.geometry.curve import subdivide
from activecontour.geometry.raster import rasterize

_FAR = 1e15  # a sentinel segment start: its squared distance stays finite in float32
_MIN_DISTANCE = 1e-6  # pixels: the smallest |phi| a reinitialisation writes (see _propagate)
_ONE_SWEEP_BAND = 8.0  # bands up to this half-width (pixels) need one sweep per ring
_NEIGHBOURS = ((-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (-1, 1), (1, -1), (1, 1))


class _Redistanced:
    """A band-clipped signed distance, the pixels of its band and the cells Gamma crosses."""

    def __init__(self, phi, positive, near_flat, cells, front):
        self.phi = phi  # (M, N), exact within the band, +-band beyond
        self.positive = positive  # phi > 0
        self.near_flat = near_flat  # flat indices of the pixels whose distance was computed
        self.cells = cells  # the cells with a sign change (zeroset._change_cells), the same after
        self.front = front  # flat indices of the pixels with a 4-neighbour on the other side


class _Scratch:
    """Work arrays of the band growth kept between calls, cleared on the band's pixels only.

    A framed (M + 2) x (N + 2) grid: ``visited`` (the frame marked, sparing every bounds check)
    and ``owner`` (segment ids, -1: none); ``mark``, M x N, for the search of the front next to
    the previous one.  Filling them anew for every reinitialisation would touch every pixel;
    clearing what one band touched is O(band).  ``grown`` and ``chosen``, of the framed grid's
    size: the band's pixels and the ring scratch of :func:`activecontour._kernels.grow_band`,
    written before they are read; kept so that their pages are not faulted in anew per band.
    """

    def __init__(self, shape):
        m, n = shape
        self.width = n + 2
        visited = np.zeros((m + 2, self.width), dtype=bool)
        visited[0], visited[-1], visited[:, 0], visited[:, -1] = True, True, True, True
        self.visited = visited.ravel()
        self.owner = np.full((m + 2) * self.width, -1, dtype=np.int32)
        self.mark = np.zeros(m * n, dtype=np.uint8)
        self.grown = np.empty(self.visited.size, dtype=np.intp)
        self.chosen = np.empty(self.visited.size, dtype=np.int32)


def signed_distance(phi, band=np.inf):
    """Reinitialise phi to the signed distance from its zero level set, keeping that set in place.

    Parameters
    ----------
    phi : ndarray (M, N)
        A level-set function; ``phi > 0`` is inside.
    band : float
        Narrow band: distances are computed up to ``band`` and clipped to ``[-band, band]``.

    Returns
    -------
    ndarray (M, N) float64

    Notes
    -----
    Gamma is the marching-squares zero set of phi (the segments :func:`level_set_contours`
    returns), so a straight front stays exactly where it was and a curved one within
    O(h^2 kappa).  A front pixel (one with a 4-neighbour of the other sign) is within one pixel of
    Gamma, so its nearest segment lies in one of the four grid cells around it: that search is
    exact.  The band then grows ring by ring from the front pixels: each new pixel takes the
    nearest of its eight neighbours' segments and walks along Gamma from it to nearer ones
    (closest-segment propagation, ordered like fast marching).  Within the band this is exact to
    ~1e-3 px in practice; the cost is a few passes over the image plus O(pixels in the band).
    When phi is positive everywhere, Gamma is the domain's edge (where :func:`level_set_contours`
    closes the inside, half a pixel beyond the outermost pixel centres) and phi its distance.
    """
    return _redistance(np.asarray(phi, dtype=np.float64), band).phi


def _redistance(phi, band, dtype=np.float64, scratch=None, keep_front=False, overwrite=False):
    """:func:`signed_distance` as a :class:`_Redistanced` with phi of ``dtype``.

    ``keep_front``: the front pixels keep phi's own values and the band the distances from them,
    so that the zero set is phi's exactly.  Marching squares reads only the front pixels (the ends
    of an edge with a sign change, and the four corners of a saddle cell), so for a phi that is a
    signed distance already (a previous result's) the zero set, its energy and its mask do not
    move; a second reinitialisation would move a curved front by O(h^2 kappa), up to a sixth of
    a pixel, which on a binary image changes (6.38) by percents.

    ``scratch``: a :class:`_Scratch` of phi's shape to reuse (else one is made).  ``overwrite``:
    phi (C-contiguous, of ``dtype``) is written over with the result once its zero set is located
    rather than a new array made (a start that nothing else reads: an image-sized array less).
    A phi stepped from a state is located (:func:`_locate`), scored and only then finished
    (:meth:`_Located.finish`) by the level set's driver.
    """
    located = _locate(phi, band, dtype, scratch)
    if isinstance(located, _Redistanced):
        return located
    overwrite = overwrite and not keep_front and phi.dtype == dtype and phi.flags.c_contiguous
    return located.finish(band, dtype, scratch, keep_front=keep_front, overwrite=overwrite)


class _Located:
    """phi's zero set located, before the band: its sides, front pixels, cells with a sign change
    and their segments, each front pixel's nearest segment (and, stepped from a previous state,
    the pixels that changed side).  The distances of the front pixels alone fix the zero set
    (marching squares reads only them), so an energy can be scored before the band is grown
    (:meth:`front_distances`, :meth:`finish`)."""

    def __init__(self, phi, positive, front, cells, segments, nearest, switched, changed=None):
        self.phi, self.positive, self.front, self.cells = phi, positive, front, cells
        self.segments, self.nearest, self.switched = segments, nearest, switched
        self.changed = changed  # where phi may differ from the previous state's (see _locate)

    def front_distances(self, band):
        """Write the front pixels' signed distances (those :meth:`finish` gives them) into phi."""
        _kernels.front_distances(self.front, self.phi.shape[1], self.nearest, *self.segments.columns,
                                 band, _MIN_DISTANCE, self.positive.reshape(-1).view(np.uint8),
                                 self.phi.reshape(-1))

    def finish(self, band, dtype, scratch=None, previous=None, keep_front=False, overwrite=False):
        """The :class:`_Redistanced` state: the band grown from the front (:func:`_redistance`).

        ``previous``: the state that phi was stepped from (as for :func:`_locate`); the state is
        then written into phi itself: where the step ``changed`` it (boxes) phi is first the
        previous state's again, and beyond the previous band and the switched pixels that is
        ``+-band`` on the same side, so those are reset and the band grown.  Where the step
        changed only the band's pixels nothing is copied: O(band) rather than a copy of the image.
        ``overwrite`` (no ``previous``): phi is reset to ``+-band`` by side and the band written
        into it (see :func:`_redistance`).
        """
        positive, front = self.positive, self.front
        rows, cols = np.divmod(front, positive.shape[1])
        # far from Gamma a second sweep per ring keeps the propagation exact; within the few rings
        # of a narrow band, one sweep and the walk along Gamma are
        sweeps = 1 if band <= _ONE_SWEEP_BAND else 2
        base = None
        if previous is not None:
            base = self.phi
            # the previous state's phi where the step changed it
            _kernels.copy_boxes(previous.phi, base, _boxes(self.changed))
            reset = np.concatenate([previous.near_flat, self.switched])
            base.ravel()[reset] = np.where(positive.ravel()[reset], dtype(band), dtype(-band))
        elif overwrite:  # the segments hold the zero set: phi itself is no longer read
            base = _clipped(positive, band, dtype, out=self.phi)
        state = _propagate(positive, rows, cols, self.segments, self.nearest, band, sweeps,
                           dtype=dtype, scratch=scratch, base=base)
        state.cells, state.front = self.cells, front
        if keep_front:
            given = np.clip(np.abs(self.phi.ravel()[front]), _MIN_DISTANCE, band)
            state.phi.ravel()[front] = np.where(positive.ravel()[front], given, -given)
        return state


def _locate(phi, band, dtype=np.float64, scratch=None, previous=None, changed=None, sides=None):
    """The :class:`_Located` zero set of phi, or the final :class:`_Redistanced` state where phi has
    no front (all inside or all outside).

    ``scratch``: a :class:`_Scratch` of phi's shape to reuse.  ``previous``: a
    :class:`_Redistanced` that phi was stepped from; the front is then searched only next to the
    previous front and the pixels that changed side (a front pixel whose side and whose
    neighbours' sides are unchanged was a front pixel before), which gives the same front and
    cells as a search over the image at the cost of one pass instead of a dozen.  ``changed``:
    where phi may differ from ``previous.phi``: a box (two slices), boxes (R, 4) (rows: first
    row, stop row, first column, stop column; they may overlap), the flat indices of pixels
    (1-D), or None (anywhere); the sides are read there only.  ``sides``: a bool array equal to
    ``previous.positive`` that the new sides are written into (else a copy of it is made).
    """
    switched = None
    if previous is None:
        positive = phi > 0
        front = np.flatnonzero(_front_pixels(positive))
    else:
        changed = (slice(0, phi.shape[0]), slice(0, phi.shape[1])) if changed is None else changed
        positive, switched = _sides(phi, previous.positive, changed, sides)
        mark = np.zeros(phi.size, dtype=np.uint8) if scratch is None else scratch.mark
        front, cells = _front_and_cells(positive, np.concatenate([previous.front, switched]), mark)
    if front.size == 0 and positive.all():
        return _domain_edge_distance(phi.shape, band, dtype)
    if front.size == 0:
        return _Redistanced(_clipped(positive, band, dtype), positive, np.zeros(0, dtype=np.intp),
                            np.zeros(0, dtype=np.intp), front)
    if previous is None:
        cells = _change_cells(positive)
    segments, nearest = _front_segments(phi, front, cells)
    return _Located(phi, positive, front, cells, segments, nearest, switched, changed)


def _sides(phi, before, changed, out=None):
    """``phi > 0`` and the flat indices of the pixels whose side differs from ``before`` (in
    increasing order), reading phi only where it ``changed`` (boxes or flat indices; :func:`_locate`).
    ``out``: an array equal to ``before`` that the sides are written into (else a copy of it)."""
    if isinstance(changed, np.ndarray) and changed.ndim == 1:  # pixels: the band of a step (b)
        positive = before.copy() if out is None else out
        switched = np.empty(changed.size, dtype=np.intp)
        count = _kernels.sides_at(np.ascontiguousarray(phi).reshape(-1), before.reshape(-1).view(np.uint8),
                                  positive.reshape(-1).view(np.uint8),
                                  np.ascontiguousarray(changed, dtype=np.intp), switched)
        return positive, switched[:count]
    boxes = _boxes(changed)
    # beyond the boxes the sides are before's; one pass over each box
    area = int(((boxes[:, 1] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 2])).sum())
    if out is not None:
        positive = out
    elif area == phi.size and len(boxes) == 1:
        positive = np.empty(phi.shape, dtype=bool)
    else:
        positive = before.copy()
    switched = np.empty(area, dtype=np.intp)
    count = _kernels.sides(np.ascontiguousarray(phi), np.ascontiguousarray(before).view(np.uint8),
                           positive.view(np.uint8), boxes, switched)
    # overlapping boxes find a pixel twice; a single box finds each once, in order
    return positive, (switched[:count].copy() if len(boxes) == 1 else np.unique(switched[:count]))


def _boxes(changed):
    """The boxes (R, 4) of ``changed`` as :func:`_locate` takes it (a box, boxes), or none for flat
    indices (the pixels of a step (b) are located and finished in place)."""
    if isinstance(changed, tuple):
        rows, cols = changed
        return np.array([[rows.start, rows.stop, cols.start, cols.stop]], dtype=np.intp)
    return changed if changed.ndim == 2 else np.zeros((0, 4), dtype=np.intp)


def _front_and_cells(positive, seeds, mark):
    """The front pixels among ``seeds`` (flat indices) and their 4-neighbours, and the cells with a
    sign change (as :func:`zeroset._change_cells`) around them, both sorted.

    Every cell with a sign change has an edge with one, whose two ends are front pixels, so the
    cells around the front are all of them.  ``mark``: M N zeros (uint8), returned cleared.
    Compiled: :func:`activecontour._kernels.front_and_cells`, O(seeds).
    """
    seeds = np.ascontiguousarray(seeds, dtype=np.intp)
    front = np.empty(5 * seeds.size, dtype=np.intp)
    cells = np.empty(4 * front.size, dtype=np.intp)
    n_front, n_cells = _kernels.front_and_cells(np.ascontiguousarray(positive).view(np.uint8), seeds, mark,
                                                front, cells)
    return np.sort(front[:n_front]), np.sort(cells[:n_cells])


def _domain_edge_distance(shape, band, dtype=np.float64):
    """The whole image inside: the distance to the domain's edge, Gamma of the closed padding.

    A region that fills the image is bounded by the edge of the domain, half a pixel beyond the
    outermost pixel centres; its distance lets the force move that boundary inwards like any
    other (a plateau at ``+band`` would hold the narrow-band step still).
    """
    m, n = shape
    to_rows = np.minimum(np.arange(m), np.arange(m)[::-1]) + 0.5
    to_cols = np.minimum(np.arange(n), np.arange(n)[::-1]) + 0.5
    distance = np.minimum(to_rows[:, None], to_cols[None, :])
    near = np.flatnonzero(distance < band)
    return _Redistanced(np.minimum(distance, band).astype(dtype), np.ones(shape, dtype=bool), near,
                        np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp))


def _clipped(positive, band, dtype=np.float64, out=None):
    """``+band`` inside, ``-band`` outside (inf for an infinite band), into ``out`` if given."""
    phi = np.empty(positive.shape, dtype=dtype) if out is None else out
    if not np.isfinite(band):
        np.copyto(phi, np.where(positive, dtype(band), dtype(-band)))
        return phi
    np.copyto(phi, positive)  # 0 or 1, then scaled in place: far faster than np.where
    phi *= dtype(2.0 * band)
    phi -= dtype(band)
    return phi


def _front_pixels(positive):
    front = np.zeros_like(positive)
    change = positive[1:] != positive[:-1]
    front[1:] |= change
    front[:-1] |= change
    change = positive[:, 1:] != positive[:, :-1]
    front[:, 1:] |= change
    front[:, :-1] |= change
    return front


def _segment_distance(points, starts, ends):
    """Distance from points (..., 2) to segments (..., 2); NaN segments give inf."""
    direction = ends - starts
    offset = points - starts
    length_sq = np.sum(direction * direction, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip(np.sum(offset * direction, axis=-1) / length_sq, 0.0, 1.0)
    t = np.where(length_sq > 0, t, 0.0)
    gap = np.hypot(offset[..., 0] - t * direction[..., 0], offset[..., 1] - t * direction[..., 1])
    return np.where(np.isnan(gap), np.inf, gap)


def _front_segments(phi, front, cells):
    """The zero-set segments (every cell with a sign change) and the nearest one to each front pixel.

    ``front``: the front pixels (flat indices); ``cells``: the cells with a sign change, sorted.
    A front pixel is within one pixel of Gamma, so its nearest segment lies in one of the four
    cells around it: the first nearest among their segments, in float32 (ample to rank them),
    found by a search in the list of cells, not a lookup table over the image (compiled:
    :func:`activecontour._kernels.nearest_segments`).  Returns a :class:`_Segments` (every
    segment of Gamma once, and empty saddle slots) and ``nearest (F,)``, an index into it (-1:
    none).
    """
    segments, keys = _cell_segments(phi, cells)
    table = _Segments(segments.reshape(-1, 2, 2), _links(keys.reshape(-1, 2)))
    nearest = np.empty(front.size, dtype=np.intp)
    _kernels.nearest_segments(np.ascontiguousarray(front, dtype=np.intp), phi.shape[1],
                              np.ascontiguousarray(cells, dtype=np.intp), *table.columns32, nearest)
    return table, nearest


def _links(keys):
    """The neighbours of every segment along Gamma, (S, 2), from the keys of its two ends.

    Two segments are neighbours when an end of each has the same key; -1 where there is none.
    """
    flat = keys.ravel()
    used = np.flatnonzero(flat >= 0)
    order = used[np.argsort(flat[used], kind="stable")]
    links = np.full(flat.size, -1, dtype=np.intp)
    pair = np.flatnonzero(flat[order[:-1]] == flat[order[1:]])
    links[order[pair]] = order[pair + 1] // 2
    links[order[pair + 1]] = order[pair] // 2
    return links.reshape(-1, 2)


class _Segments:
    """Segments of Gamma set up for nearest-segment queries; id -1 is a far sentinel.

    ``segments (S, 2, 2)`` holds start and end in (row, col), NaN for an empty slot (also far);
    ``links (S, 2)`` the neighbours of each along Gamma (-1: none).  ``columns``: start (row,
    col), direction (row, col) and the inverse squared length, float64, for the distances of the
    band (:func:`activecontour._kernels.grow_band`, :func:`~activecontour._kernels.band_distances`);
    ``columns32`` the same in float32 for ranking the candidates of the front pixels (ample on
    images up to ~10^4 pixels); the sentinel is the last (compiled:
    :func:`activecontour._kernels.segment_table`).
    """

    def __init__(self, segments, links):
        table = np.empty((5, len(segments) + 1))
        table32 = np.empty((5, len(segments) + 1), dtype=np.float32)
        _kernels.segment_table(np.ascontiguousarray(segments, dtype=np.float64), _FAR, table, table32)
        self.columns, self.columns32 = list(table), list(table32)
        self.links = np.concatenate([links, [[-1, -1]]])


def _propagate(positive, rows, cols, segments, nearest, band, sweeps=1, dtype=np.float64,
               scratch=None, base=None):
    """Grow the band ring by ring from the front pixels; each new pixel takes the nearest of its
    eight neighbours' segments, then walks along Gamma while that gets nearer; then each takes its
    distance to its segment (compiled loops, :func:`activecontour._kernels.grow_band` and
    :func:`~activecontour._kernels.band_distances`, O(pixels in the band), the work arrays of
    ``scratch`` cleared on the band's pixels)."""
    m, n = positive.shape
    scratch = _Scratch((m, n)) if scratch is None else scratch
    width, visited, owner = scratch.width, scratch.visited, scratch.owner
    steps = np.array([dr * width + dc for dr, dc in _NEIGHBOURS], dtype=np.intp)
    ring = ((rows + 1) * width + cols + 1).astype(np.intp)
    owner[ring] = nearest
    visited[ring] = True
    # a pixel k rings away from the front pixels is at least k - 1 from Gamma
    max_rings = int(np.ceil(band)) + 1 if np.isfinite(band) else m + n
    start_r, start_c, dir_r, dir_c, inverse = segments.columns
    out = scratch.grown
    out[: ring.size] = ring
    count = _kernels.grow_band(visited.view(np.uint8), owner, out, scratch.chosen,
                               ring.size, steps, width, max_rings, sweeps, start_r, start_c, dir_r,
                               dir_c, inverse, np.ascontiguousarray(segments.links, dtype=np.intp))
    # every pixel keeps its side, at least _MIN_DISTANCE from Gamma: the sign pattern, and so the
    # cells Gamma crosses, are those of the input (a distance that rounds to 0 would move an
    # inside pixel out), and no crossing lies closer to a pixel centre than the coordinates
    # resolve (marching squares on values ~1e-20 orients its segments by rounding errors)
    phi = _clipped(positive, band, dtype) if base is None else base  # base: +-band beyond the band
    flat = np.empty(count, dtype=np.intp)
    _kernels.band_distances(out[:count], owner, visited.view(np.uint8), width,
                            np.ascontiguousarray(positive).reshape(-1).view(np.uint8), band, _MIN_DISTANCE,
                            *segments.columns, phi.reshape(-1), flat)
    return _Redistanced(phi, positive, flat, None, None)


def curves_level_set(curves, shape, band=np.inf, *, dtype=np.float64):
    """Signed distance to closed curves (inside positive), exact in the band, as ``dtype``.

    The inside is the rasterised region (pixel centres with nonzero winding,
    :func:`activecontour.geometry.raster.rasterize`); the pixels next to its boundary get their exact
    distance to the curves (split into pieces of at most half a pixel), and the band inherits it
    by closest-segment propagation.

    Raises
    ------
    ValueError
        When the curves contain no pixel centre.  (Curves around every pixel centre give the
        distance to the domain's edge, as :func:`signed_distance` does.)
    """
    import scipy.spatial

    positive = rasterize(curves, shape)
    if not positive.any():
        raise ValueError("init selects no pixel centre of the image: nothing would be inside")
    if positive.all():  # the whole image inside: the flow starts from the domain's edge
        return _domain_edge_distance(shape, band, dtype).phi
    rows, cols = np.divmod(np.flatnonzero(_front_pixels(positive)), shape[1])
    vertices = [np.asarray(c, dtype=np.float64) for c in curves]
    starts, first, size = _densify(np.concatenate(vertices), np.array([len(c) for c in vertices]), 0.5)
    # the neighbours of piece i along its curve are i - 1 and i + 1, cyclically
    index = np.arange(len(starts))
    after = first + (index - first + 1) % size
    links = np.column_stack([first + (index - first - 1) % size, after])
    ends = starts[after]
    points = np.column_stack([rows, cols]).astype(np.float64)
    count = min(8, len(starts))
    _, near = scipy.spatial.cKDTree(0.5 * (starts + ends)).query(points, k=count)
    near = near.reshape(len(points), count)
    gap = _segment_distance(points[:, None, :], starts[near], ends[near])
    nearest = near[np.arange(len(points)), np.argmin(gap, axis=1)]
    segments = _Segments(np.stack([starts, ends], axis=1), links)
    return _propagate(positive, rows, cols, segments, nearest, band, sweeps=2, dtype=dtype).phi


def _densify(points, lengths, spacing):
    """Closed curves (stacked ``points``, ``lengths`` vertices each) with every edge split into
    pieces of at most ``spacing`` (:func:`activecontour.geometry.curve.subdivide`): the new stacked
    points, and for each its curve's first index and size in the new stack."""
    dense, new_lengths = subdivide(points, lengths, spacing)
    return (dense, np.repeat(np.cumsum(new_lengths) - new_lengths, new_lengths),
            np.repeat(new_lengths, new_lengths))
