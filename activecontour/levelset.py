"""The level-set backend: the Chan-Vese functional (6.38) on a function phi over the pixel grid.

The inside region is ``Omega_i = {phi > 0}`` and Gamma is the zero level set of phi.  The backend
minimises the same functional as the polygon backend, with the same parameters and units,

    J = mu |Gamma| + omega |Omega_i| + lambda_in  int_{Omega_i} mean_ch (I - c_in)^2
                                     + lambda_out int_{Omega_o} mean_ch (I - c_out)^2         (6.38)

but Gamma may split, merge, open holes and grow new components.  The zero level set is returned
as sub-pixel contours (marching squares) in the polygon backend's convention, so either backend
can start from the other's result (level set for the topology, polygon for a sub-pixel finish).

One iteration
-------------
1. ``c_in, c_out`` by (6.42) for the current zero set, from the common evaluator (below), unless
   they are fixed.
2. A semi-implicit step of the level-set form of the gradient flow of (6.38).  Every level line
   moves with the normal velocity ``-(mu kappa + f)``, where ``f = omega + lambda_in mean (I -
   c_in)^2 - lambda_out mean (I - c_out)^2`` is the integrand of (6.41); in level-set form
   ``phi_t = |grad phi| (mu div(grad phi / |grad phi|) - f)``, and as phi is kept a signed
   distance (``|grad phi| = 1``) this is ``phi_t = mu Laplace(phi) - f``.  (With delta(phi) in place
   of |grad phi| it would be the equation of Chan & Vese 2001; |grad phi| makes it the level-set
   motion of Osher & Sethian 1988, which moves every level line, not only those near Gamma.)  The
   pixels on the image border carry ``mu`` more per border side in f: a region that covers them
   closes along the domain edge, and (6.38) of the returned contours counts that length, as the
   polygon backend does.  Two forms of the step, with ``S = (1 - tau mu Laplace)^{-1}``:

   (a) smoothed force: ``phi^{k+1} = S (phi^k - tau f)``, i.e. the velocity
       ``S (mu Laplace(phi) - f)``: a Sobolev (H^1-type) gradient with smoothing length
       ``l = sqrt(tau mu)``, the level-set counterpart of the polygon's H^1 velocity (6.39).
       It moves whole regions at once and, with large tau, flips regions far from Gamma (see
       below); but its fixed point is biased by the smoothing, so it is only the first stage;
   (b) unsmoothed force: ``phi^{k+1} = S phi^k - tau f``: implicit curvature, explicit force, the
       L^2 flow (6.25) whose fixed point is ``mu kappa + f = 0`` on Gamma, i.e. (6.41) = 0.

   ``S`` has constant coefficients: one pair of discrete cosine transforms applies it exactly
   (Neumann boundary), unconditionally stable.
3. Reinitialisation: phi is replaced by the signed distance to its zero level set, computed in a
   narrow band ``|phi| < band`` only and clipped to ``+-band`` beyond (:func:`signed_distance`).
4. The step is accepted if (6.38) of the new zero set, by the common evaluator, is not larger;
   otherwise tau is halved and the step retried (backtracking).

Steps in pixels
---------------
A step is given as ``step`` pixels of travel: ``tau = step / |f|_typ`` with ``|f|_typ`` the mean
``|f|`` over the pixels (about ``(c_in - c_out)^2`` once the regions have formed), so that a front
at a pixel of typical force moves ``step`` pixels whatever the image's contrast or the parameters'
scale; the smoothing length ``sqrt(tau mu)`` is kept below ``step`` (that binds only where the
force is weak against the length term, as on a checkerboard start).  The first step is ``dt``,
but at most half the width (area over length) of the start's regions; it doubles after every
accepted step until the first rejection, then grows by 1.25 after two first-try acceptances in a
row.  Coarse to fine, like the polygon's smoothing length: a smoothed-force stage runs with steps
up to a ceiling (first ``dt_max``) and has settled when Gamma moves less than 2 % of the step (or
10 tol) per iteration, averaged over 3 iterations, or when two halvings of its step find no
descent; the ceiling is then divided by 4, and below ``dt_min`` stage (b) follows, with steps
``<= dt_min`` and the force applied within the band only, so that no pixel far from Gamma (at
``+-band``) flips on its own.
Stage (b) converges (status 0) when Gamma moves less than ``tol`` pixels per iteration on average
over 3 iterations, or ends with status 4 when ``max_backtracks`` halvings find no descent.  Its
steps are explicit on the band when ``tau mu <= 1/4`` (stable, no DCT).  The unsmoothed flow can
stop in a pixel-scale local minimum that a smoothed step leaves (a continued run would then move
on), so when it ends a smoothed stage of the first step size is tried, up to twice: if its first
step finds no descent the end stands, otherwise the stages run on from there.

How far Gamma moved is measured geometrically, in pixels: the area between the old and the new
zero set, ``sum_px |H_eps(d_new) - H_eps(d_old)|`` over the band, divided by the length of Gamma,
i.e. the mean normal displacement.  ``H_eps`` is the cosine-regularised Heaviside of Zhao, Chan,
Merriman & Osher (1996),

    H_eps(s) = (1 + s/eps + sin(pi s/eps)/pi) / 2  for |s| < eps (0 and 1 beyond),  eps = 1,

whose integer translates sum to the exact length of a half-line at any sub-pixel offset (its
derivative's Fourier transform vanishes at every non-zero multiple of 2 pi): the swept area is exact
for straight fronts and second-order accurate for curved ones.  Unlike a relative energy decrease
(the energy holds the noise energy sigma^2 |D|, which grows with the pixel count) this means the
same on every image size.

Why large steps are safe and useful: ``S`` is stable for every tau, and the backtracking keeps every
accepted step a descent step.  Far from Gamma phi sits at ``+-band``, and a step (a) moves it by
about ``-tau f`` smoothed over ``l``: where a whole region inside Gamma looks like the outside (the
hole of an annulus) phi crosses zero and a hole opens without a seed, while single noisy pixels
are held by the smoothing; the energy test accepts such a change only when it pays, length
included.

Cost: an iteration is one DCT pair over the image (O(MN log MN), float32), a few vectorised passes
over the image, and the reinitialisation on the pixels of the narrow band only.

The energy
----------
The energy of every iterate, the acceptance test and ``res.energy`` are one number: (6.38) of the
zero set by the common evaluator :func:`activecontour.energy.evaluate`, exact for the bilinear
image.  The zero set is taken as the marching-squares segments of phi padded by ``-|phi|``
(:func:`zero_set_edges`, the segments of :func:`level_set_contours`, closed along the domain edge
where a region touches it), scored as an unchained soup of oriented edges: Green's theorem makes
region and length integrals sums over edges, so this costs O(|Gamma|) after the O(MN) sign test.
A reinitialisation changes the energy only through the O(h^2 kappa) chord error of re-deriving
Gamma from a distance function, and every acceptance test compares energies after it: the history
is non-increasing at every iteration, reinitialisations included.
"""

from __future__ import annotations

import numpy as np
import scipy.fft

from activecontour import _kernels
from activecontour.energy import evaluate
from activecontour.initial import initial_curves
from activecontour.raster import level_curves, rasterize
from activecontour.result import FlowState, build_result

__all__ = [
    "DEFAULT_OPTIONS",
    "checkerboard_level_set",
    "curves_level_set",
    "heaviside",
    "initial_level_set",
    "level_set_contours",
    "segment_levelset",
    "signed_distance",
    "zero_set_edges",
]

#: The backend-specific keywords of :func:`segment_levelset` and their defaults.
DEFAULT_OPTIONS = {
    "dt": 16.0,
    "dt_min": 1.0,
    "dt_max": 64.0,
    "band": 4.0,
    "checkerboard_period": 16.0,
    "max_backtracks": 3,
}

#: The strings ``init`` may be, besides None, curves, masks and results.
INIT_STRINGS = ("checkerboard", "grid")

_FAR = 1e15  # a sentinel segment start: its squared distance stays finite in float32
_ONE_SWEEP_BAND = 8.0  # bands up to this half-width (pixels) need one sweep per ring
_STAGE_TOL = 10.0  # a smoothed-force stage ends at 10 tol: the next, finer one moves faster
_WINDOW = 3  # stages end when Gamma's mean displacement over this many iterations is small
_SETTLED = 0.02  # a smoothed-force stage has settled when Gamma moves < 2% of the step per iteration
_RECHECKS = 2  # smoothed steps tried after the unsmoothed stage ends (see segment_levelset)
_NEIGHBOURS = ((-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (-1, 1), (1, -1), (1, 1))


# --------------------------------------------------------------------------------------------
# Regularised Heaviside (the swept-area measure)


def heaviside(phi, epsilon=1.0):
    """The cosine-regularised Heaviside ``H_eps``: 0 below -eps, 1 above eps, smooth between."""
    s = np.asarray(phi, dtype=np.float64) / epsilon
    ramp = 0.5 * (1.0 + s + np.sin(np.pi * np.clip(s, -1.0, 1.0)) / np.pi)
    return np.where(s >= 1.0, 1.0, np.where(s <= -1.0, 0.0, ramp))



# --------------------------------------------------------------------------------------------
# Signed distance to the zero level set (reinitialisation), in a narrow band


class _Redistanced:
    """A band-clipped signed distance and the pixels of its band (for the swept area)."""

    def __init__(self, phi, positive, near_flat, near_distance):
        self.phi = phi  # (M, N) float64, exact within the band, +-band beyond
        self.positive = positive  # phi > 0
        self.near_flat = near_flat  # flat indices of the pixels whose distance was computed
        self.near_distance = near_distance  # their signed distances


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
    """
    return _redistance(np.asarray(phi, dtype=np.float64), band).phi


def _redistance(phi, band):
    positive = phi > 0
    front = np.flatnonzero(_front_pixels(positive))
    if front.size == 0:
        return _Redistanced(_clipped(positive, band), positive, np.zeros(0, dtype=np.intp),
                            np.zeros(0))
    rows, cols = np.divmod(front, phi.shape[1])
    segments, nearest = _front_segments(phi, positive, rows, cols)
    # far from Gamma a second sweep per ring keeps the propagation exact; within the few rings
    # of a narrow band, one sweep and the walk along Gamma are
    sweeps = 1 if band <= _ONE_SWEEP_BAND else 2
    return _propagate(positive, rows, cols, segments, nearest, band, sweeps)


def _clipped(positive, band):
    """``+band`` inside, ``-band`` outside (inf for an infinite band)."""
    if np.isfinite(band):
        return positive * (2.0 * band) - band
    return np.where(positive, np.inf, -np.inf)


def _front_pixels(positive):
    front = np.zeros_like(positive)
    change = positive[1:] != positive[:-1]
    front[1:] |= change
    front[:-1] |= change
    change = positive[:, 1:] != positive[:, :-1]
    front[:, 1:] |= change
    front[:, :-1] |= change
    return front


def _cell_segments(phi, positive, cell_r, cell_c):
    """Marching-squares segments of the zero set in grid cells, shape (K, 2 slots, 2 ends, 2).

    Cell (i, j) has the corners (i, j), (i, j+1), (i+1, j+1), (i+1, j).  Slot 1 is used by saddle
    cells only; unused slots are NaN.  A saddle isolates its two inside corners, the rule of
    ``skimage.measure.find_contours`` (``fully_connected="low"``), so the segments are those of
    :func:`level_set_contours`.  Also returns the key of the grid edge of every segment end
    (K, 2, 2), -1 for unused slots: two segments with a common key meet there.
    """
    width = phi.shape[1]
    a = phi[cell_r, cell_c]
    b = phi[cell_r, cell_c + 1]
    c = phi[cell_r + 1, cell_c + 1]
    d = phi[cell_r + 1, cell_c]
    sa, sb = positive[cell_r, cell_c], positive[cell_r, cell_c + 1]
    sc, sd = positive[cell_r + 1, cell_c + 1], positive[cell_r + 1, cell_c]
    r, q = cell_r.astype(np.float64), cell_c.astype(np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        # crossings on the edges top (a-b), right (b-c), bottom (d-c), left (a-d)
        points = np.stack([
            np.column_stack([r, q + a / (a - b)]),
            np.column_stack([r + b / (b - c), q + 1.0]),
            np.column_stack([r + 1.0, q + d / (d - c)]),
            np.column_stack([r + a / (a - d), q]),
        ], axis=1)
    exists = np.column_stack([sa != sb, sb != sc, sd != sc, sa != sd])
    # every crossing is named by its grid edge: 2 (row n + col) for the edge from (row, col) to
    # (row, col + 1), plus 1 for the edge from (row, col) to (row + 1, col)
    cell = cell_r * width + cell_c
    keys = np.column_stack([2 * cell, 2 * (cell + 1) + 1, 2 * (cell + width), 2 * cell + 1])
    count = exists.sum(axis=1)
    segments = np.full((len(a), 2, 2, 2), np.nan)
    segment_keys = np.full((len(a), 2, 2), -1, dtype=np.intp)
    simple = count == 2
    order = np.argsort(~exists[simple], axis=1, kind="stable")[:, :2]
    segments[simple, 0] = np.take_along_axis(points[simple], order[:, :, None], axis=1)
    segment_keys[simple, 0] = np.take_along_axis(keys[simple], order, axis=1)
    saddle = count == 4
    if saddle.any():
        p, k = points[saddle], keys[saddle]
        a_inside = sa[saddle][:, None]
        # inside corners a and c: cut off a (top, left) and c (right, bottom); else b and d
        segments[saddle, 0] = np.where(a_inside[:, :, None], p[:, [0, 3]], p[:, [0, 1]])
        segments[saddle, 1] = np.where(a_inside[:, :, None], p[:, [1, 2]], p[:, [3, 2]])
        segment_keys[saddle, 0] = np.where(a_inside, k[:, [0, 3]], k[:, [0, 1]])
        segment_keys[saddle, 1] = np.where(a_inside, k[:, [1, 2]], k[:, [3, 2]])
    return segments, segment_keys


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


def _front_segments(phi, positive, rows, cols):
    """The zero-set segments (every cell with a sign change) and the nearest one to each front pixel.

    Returns a :class:`_Segments` (every segment of Gamma once, and empty saddle slots) and
    ``nearest (F,)``, an index into it.
    """
    m, n = phi.shape
    corner = positive[:-1, :-1]
    change = (corner != positive[:-1, 1:]) | (corner != positive[1:, 1:]) | (corner != positive[1:, :-1])
    cells = np.flatnonzero(change)
    segments, keys = _cell_segments(phi, positive, cells // (n - 1), cells % (n - 1))
    segments, keys = segments.reshape(-1, 2, 2), keys.reshape(-1, 2)
    # the cells around every front pixel, as slots into ``cells`` (-1: none, or no sign change)
    slot = np.full(m * n, -1, dtype=np.int32)  # indexed by cell row * n + cell col (int32: half the traffic)
    slot[(cells // (n - 1)) * n + cells % (n - 1)] = np.arange(cells.size)
    around = []
    for dr, dc in ((-1, -1), (-1, 0), (0, -1), (0, 0)):
        r, c = rows + dr, cols + dc
        inside = (r >= 0) & (r < m - 1) & (c >= 0) & (c < n - 1)
        around.append(np.where(inside, slot[np.clip(r, 0, m - 1) * n + np.clip(c, 0, n - 1)], -1))
    around = np.column_stack(around)
    candidates = np.where(around[:, :, None] >= 0, 2 * around[:, :, None] + np.arange(2), -1)
    candidates = candidates.reshape(len(rows), 8)
    table = _Segments(segments, _links(keys))
    gap = table.squared_gap(rows.astype(np.float32)[:, None], cols.astype(np.float32)[:, None], candidates)
    nearest = candidates[np.arange(len(rows)), np.argmin(gap, axis=1)]
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
    ``links (S, 2)`` the neighbours of each along Gamma (-1: none).  The queries run in float32
    (a quarter of the memory traffic, ample to rank candidates on images up to ~10^4 pixels);
    ``exact=True`` gives float64 for the final distances.
    """

    def __init__(self, segments, links):
        start = np.nan_to_num(segments[:, 0], nan=_FAR)
        direction = np.nan_to_num(segments[:, 1] - segments[:, 0])
        length_sq = np.sum(direction * direction, axis=1)
        inverse = np.divide(1.0, length_sq, out=np.zeros_like(length_sq), where=length_sq > 0)
        table = np.concatenate([np.column_stack([start, direction, inverse]), [[_FAR, _FAR, 0, 0, 0]]])
        self.columns = [np.ascontiguousarray(column) for column in table.T]
        self.columns32 = [column.astype(np.float32) for column in self.columns]
        self.links = np.concatenate([links, [[-1, -1]]])

    def squared_gap(self, point_r, point_c, ids, exact=False):
        """Squared distance from points to the segments ``ids`` (broadcast together)."""
        columns = self.columns if exact else self.columns32
        start_r, start_c, dir_r, dir_c, inverse = (column[ids] for column in columns)
        off_r = point_r - start_r
        off_c = point_c - start_c
        t = (off_r * dir_r + off_c * dir_c) * inverse
        np.clip(t, 0.0, 1.0, out=t)
        off_r -= t * dir_r
        off_c -= t * dir_c
        off_r *= off_r
        off_c *= off_c
        off_r += off_c
        return off_r


def _propagate(positive, rows, cols, segments, nearest, band, sweeps=1):
    """Grow the band ring by ring from the front pixels; each new pixel takes the nearest of its
    eight neighbours' segments, then walks along Gamma while that gets nearer (a compiled loop,
    :func:`activecontour._kernels.grow_band`, O(pixels in the band))."""
    m, n = positive.shape
    width = n + 2  # a one-pixel frame, marked visited, spares every bounds check
    visited = np.zeros((m + 2, width), dtype=bool)
    visited[0], visited[-1], visited[:, 0], visited[:, -1] = True, True, True, True
    visited = visited.ravel()
    owner = np.full((m + 2) * width, -1, dtype=np.int32)  # segment ids; -1 is the far sentinel
    steps = np.array([dr * width + dc for dr, dc in _NEIGHBOURS], dtype=np.intp)
    ring = ((rows + 1) * width + cols + 1).astype(np.intp)
    owner[ring] = nearest
    visited[ring] = True
    # a pixel k rings away from the front pixels is at least k - 1 from Gamma
    max_rings = int(np.ceil(band)) + 1 if np.isfinite(band) else m + n
    start_r, start_c, dir_r, dir_c, inverse = segments.columns
    out = np.empty(visited.size, dtype=np.intp)
    out[: ring.size] = ring
    count = _kernels.grow_band(visited.view(np.uint8), owner, out, np.empty(visited.size, np.int32),
                               ring.size, steps, width, max_rings, sweeps, start_r, start_c, dir_r,
                               dir_c, inverse, np.ascontiguousarray(segments.links, dtype=np.intp))
    flat = out[:count]
    r, c = np.divmod(flat, width)
    distance = np.sqrt(segments.squared_gap((r - 1).astype(np.float64), (c - 1).astype(np.float64),
                                            owner[flat], exact=True))
    flat = (r - 1) * n + (c - 1)
    signed = np.where(positive.ravel()[flat], distance, -distance)
    phi = _clipped(positive, band)
    phi.ravel()[flat] = np.clip(signed, -band, band)
    return _Redistanced(phi, positive, flat, signed)


def curves_level_set(curves, shape, band=np.inf):
    """Signed distance to closed curves (inside positive), exact in the band.

    The inside is the rasterised region (pixel centres with nonzero winding,
    :func:`activecontour.raster.rasterize`); the pixels next to its boundary get their exact
    distance to the curves (split into pieces of at most half a pixel), and the band inherits it
    by closest-segment propagation.

    Raises
    ------
    ValueError
        When the curves contain no pixel centre, or all of them.
    """
    import scipy.spatial

    positive = rasterize(curves, shape)
    if not positive.any():
        raise ValueError("init selects no pixel centre of the image: nothing would be inside")
    if positive.all():  # the whole image inside: the flow starts from the domain's edge
        return _clipped(positive, band if np.isfinite(band) else float(max(shape)))
    rows, cols = np.divmod(np.flatnonzero(_front_pixels(positive)), shape[1])
    pieces = [_densify(np.asarray(c, dtype=np.float64), 0.5) for c in curves]
    starts = np.concatenate(pieces)
    ends = np.concatenate([np.roll(piece, -1, axis=0) for piece in pieces])
    # the neighbours of piece i along its curve are i - 1 and i + 1, cyclically
    offsets = np.cumsum([0] + [len(piece) for piece in pieces])
    index = np.arange(len(starts))
    first = np.repeat(offsets[:-1], np.diff(offsets))
    size = np.repeat(np.diff(offsets), np.diff(offsets))
    links = np.column_stack([first + (index - first - 1) % size, first + (index - first + 1) % size])
    points = np.column_stack([rows, cols]).astype(np.float64)
    count = min(8, len(starts))
    _, near = scipy.spatial.cKDTree(0.5 * (starts + ends)).query(points, k=count)
    near = near.reshape(len(points), count)
    gap = _segment_distance(points[:, None, :], starts[near], ends[near])
    nearest = near[np.arange(len(points)), np.argmin(gap, axis=1)]
    segments = _Segments(np.stack([starts, ends], axis=1), links)
    return _propagate(positive, rows, cols, segments, nearest, band, sweeps=2).phi


def _densify(curve, spacing):
    end = np.roll(curve, -1, axis=0)
    length = np.hypot(*(end - curve).T)
    count = np.maximum(np.ceil(length / spacing).astype(np.intp), 1)
    edge = np.repeat(np.arange(len(curve)), count)
    t = (np.arange(edge.size) - np.repeat(np.cumsum(count) - count, count)) / count[edge]
    return curve[edge] + t[:, None] * (end - curve)[edge]


def checkerboard_level_set(shape, period):
    """Squares of p x p pixels, alternately in and out: ``(p/pi) sin(pi (r+1/2)/p) sin(pi (c+1/2)/p)``.

    The zero lines run between pixel centres (at ``r, c = k p - 1/2``), the square at the origin
    is inside, and the scaling makes ``|grad phi| = 1`` on the square sides.  A checkerboard start
    sees the whole image at once (Getreuer 2012; the default of ``skimage.segmentation.chan_vese``).
    """
    if not (np.isfinite(period) and period >= 2):
        raise ValueError(f"checkerboard_period must be a number >= 2 (pixels), got {period!r}")
    m, n = shape
    r = np.arange(m, dtype=np.float64)[:, None] + 0.5
    c = np.arange(n, dtype=np.float64)[None, :] + 0.5
    return (period / np.pi) * np.sin(np.pi * r / period) * np.sin(np.pi * c / period)


def initial_level_set(init, shape, *, band=np.inf, checkerboard_period=16.0, values=None):
    """The signed-distance level set of any ``init`` that :func:`segment_levelset` accepts.

    ``values`` (M, N, C), the normalised image, is used by ``"grid"`` only (see
    :func:`activecontour.initial.grid`).

    Raises
    ------
    ValueError
        For an unknown string (listing the valid ones), a mask or ``phi`` of the wrong shape, or
        an init that leaves nothing inside or nothing outside.
    """
    if isinstance(init, str):
        if init == "checkerboard":
            return signed_distance(checkerboard_level_set(shape, checkerboard_period), band)
        if init not in INIT_STRINGS:
            raise ValueError(
                f"init {init!r} is not understood by the level-set backend; the valid strings are "
                f"{', '.join(map(repr, INIT_STRINGS))} (or pass None, a (K, 2) curve, a list of "
                "curves, a bool mask or a SegmentationResult)"
            )
    phi = getattr(init, "phi", None)
    if phi is not None and hasattr(init, "mask"):
        phi = np.asarray(phi, dtype=np.float64)
        if phi.shape != tuple(shape):
            raise ValueError(
                f"init result has phi of shape {phi.shape}, but the image has shape {tuple(shape)}"
            )
        if not np.any(phi > 0):
            raise ValueError("init result has an empty inside (phi <= 0 everywhere)")
        return signed_distance(phi, band)
    return curves_level_set(initial_curves(init, shape, values), shape, band)


# --------------------------------------------------------------------------------------------
# Contours of the zero level set


def level_set_contours(phi):
    """The zero level set of phi as closed sub-pixel curves in the convention of :mod:`activecontour.curve`.

    Marching squares (``skimage.measure.find_contours``) on phi padded by one pixel of
    ``-|phi|`` (:func:`_closed_padding`): a region that touches the image border closes along the
    domain edge, half a pixel outside the outermost pixel centres, so every curve is closed.
    With ``positive_orientation="high"`` outer boundaries have positive signed area and holes
    negative.  Each vertex is stored once.
    """
    return level_curves(_closed_padding(phi), 0.0)


def _closed_padding(phi):
    """phi padded by one pixel of ``-|phi|``: the zero set closes on the domain edge (inside only)."""
    padded = np.pad(np.asarray(phi, dtype=np.float64), 1, mode="edge")
    padded[0], padded[-1] = -np.abs(padded[0]), -np.abs(padded[-1])
    padded[:, 0], padded[:, -1] = -np.abs(padded[:, 0]), -np.abs(padded[:, -1])
    padded[padded == 0] = -1e-300  # phi = 0 is outside, as in the mask phi > 0
    return padded


def zero_set_edges(phi):
    """The segments of :func:`level_set_contours`, oriented but not chained: ``(S, 2 ends, 2)``.

    The same marching-squares segments (the saddle rule of :func:`_cell_segments`, the closing
    along the domain edge of :func:`_closed_padding`), each directed so that the inside lies on
    its left, i.e. its normal ``nu = (t_c, -t_r)`` points out of the inside as for the polygons.
    Region and length integrals are sums over edges (Green's theorem), so the common evaluator
    scores this soup exactly as it scores the chained contours, without the O(M N) Python work of
    chaining them.
    """
    padded = _closed_padding(phi)
    positive = padded > 0
    corner = positive[:-1, :-1]
    change = (corner != positive[:-1, 1:]) | (corner != positive[1:, 1:]) | (corner != positive[1:, :-1])
    cell_r, cell_c = np.nonzero(change)
    segments, _ = _cell_segments(padded, positive, cell_r, cell_c)
    corners = np.stack([positive[cell_r, cell_c], positive[cell_r, cell_c + 1],
                        positive[cell_r + 1, cell_c + 1], positive[cell_r + 1, cell_c]], axis=1)
    offsets = np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]])
    base = np.column_stack([cell_r, cell_c]).astype(np.float64)
    # a point on the inside of each segment: the mean of the inside corners of a simple cell;
    # in a saddle each segment cuts off one inside corner (a and c, or b and d)
    reference = np.repeat((base + corners @ offsets / corners.sum(axis=1)[:, None])[:, None], 2, axis=1)
    saddle = corners.sum(axis=1) == 2
    saddle &= corners[:, 0] == corners[:, 2]
    a_in = corners[saddle, 0][:, None]
    reference[saddle, 0] = base[saddle] + np.where(a_in, offsets[0], offsets[1])
    reference[saddle, 1] = base[saddle] + np.where(a_in, offsets[2], offsets[3])
    segments, reference = segments.reshape(-1, 2, 2), reference.reshape(-1, 2)
    valid = ~np.isnan(segments[:, 0, 0])
    segments, reference = segments[valid], reference[valid]
    tangent = segments[:, 1] - segments[:, 0]
    offset = reference - segments[:, 0]
    # inside on the left: (x - p) . nu < 0 for the inside point x
    flip = offset[:, 0] * tangent[:, 1] - offset[:, 1] * tangent[:, 0] > 0
    segments[flip] = segments[flip, ::-1]
    return segments - 1.0


# --------------------------------------------------------------------------------------------
# The energy by the common evaluator, the force f of (6.41) and the steps (a), (b)


class _Problem:
    """Image, parameters and the pieces of the energy, the force f and the operator S."""

    def __init__(self, model, params, settings):
        self.model = model
        self.shape = tuple(model.shape)
        self.n_channels = model.n_channels
        self.values = model.values
        self.params = params
        self.lambda_in, self.lambda_out = params.weights(self.n_channels)
        if np.any(self.lambda_in != self.lambda_out):
            self.intensity_sq = self.values * self.values @ (self.lambda_in - self.lambda_out)
        self.band = settings["band"]
        m, n = self.shape
        stride = max(1, int(np.sqrt(m * n / 2.0**16)))
        self.sample = (slice(stride // 2, None, stride), slice(stride // 2, None, stride))
        # eigenvalues of -Laplace (5-point, Neumann) in the DCT-II basis
        wave_r = 4.0 * np.sin(np.pi * np.arange(m) / (2.0 * m)) ** 2
        wave_c = 4.0 * np.sin(np.pi * np.arange(n) / (2.0 * n)) ** 2
        self.laplace_symbol = (wave_r[:, None] + wave_c[None, :]).astype(np.float32)

    def redistance(self, phi):
        return _redistance(phi, self.band)

    def evaluate(self, state):
        """(6.38) of the zero level set by the common evaluator, as an ``Evaluation``.

        The zero set is the segment soup of :func:`zero_set_edges`: the returned contours, closed
        along the domain edge.  An empty region has the evaluator's value for the empty set.
        """
        points = zero_set_edges(state.phi).reshape(-1, 2)
        next_index = np.repeat(np.arange(1, len(points), 2), 2)  # start -> end -> itself
        return evaluate(self.model, points, next_index, self.params, empty_ok=True)

    def force(self, c_in, c_out):
        """f of (6.41) per pixel and its contrast scale.

        ``f = omega + lambda_in mean (I - c_in)^2 - lambda_out mean (I - c_out)^2``, plus ``mu`` per
        side of the image that a pixel lies on: a region that covers a border pixel closes along
        the domain edge there, and the evaluator counts that length (the wall term).  The scale
        is the mean ``|f|`` over the pixels (a regular sample of about 2^16 of them): about
        ``|c_in - c_out|^2`` once the regions have settled, the size of the force of every pixel
        before that (a checkerboard start, where ``c_in ~ c_out``).  Time steps are measured in
        pixels of travel at that force.
        """
        p = self.params
        c_in = np.nan_to_num(np.asarray(c_in, dtype=np.float64))
        c_out = np.nan_to_num(np.asarray(c_out, dtype=np.float64))
        linear = -2.0 * (self.lambda_in * c_in - self.lambda_out * c_out)
        constant = p.omega + self.lambda_in @ (c_in * c_in) - self.lambda_out @ (c_out * c_out)
        f = self.values @ linear + constant
        if hasattr(self, "intensity_sq"):
            f += self.intensity_sq
        if p.mu > 0:
            for edge in (f[0], f[-1], f[:, 0], f[:, -1]):
                edge += p.mu
        return f, max(float(np.mean(np.abs(f[self.sample]))), 1e-12)

    def time_step(self, step, scale):
        """tau for a step of ``step`` pixels at the force ``scale``: ``step / scale``.

        A front at a pixel of typical force moves ``step`` pixels.  The smoothing length
        ``sqrt(tau mu)`` of S is kept below ``step``: that binds where the force is weak against
        the length term (a checkerboard start, whose constants hardly differ), where S would
        otherwise flatten phi over the whole image at once.
        """
        tau = step / scale
        return min(tau, step * step / self.params.mu) if self.params.mu > 0 else tau

    def step(self, state, force, tau, smooth_force):
        """Step (a) ``S (phi - tau f)`` with ``smooth_force``, else (b) ``S phi - tau f``.

        ``S = (1 - tau mu Laplace)^{-1}`` by DCT-II in float32 (phi is a distance of a few pixels:
        its rounding, ~1e-6 px, is far below what matters).  In step (b) the force acts within the
        band only, so that no pixel far from Gamma (at +-band) flips on its own; and when
        ``tau mu <= 1/4`` the explicit step ``phi + tau mu Laplace(phi) - tau f`` is stable and has
        the same fixed point, so it is taken on the band's pixels alone (O(band) instead of a DCT
        pair over the image).
        """
        if not smooth_force and tau * self.params.mu <= 0.25:
            return self._explicit_step(state, force, tau)
        phi = state.phi
        rhs = (phi - tau * force if smooth_force else phi).astype(np.float32)
        if self.params.mu > 0:
            spectrum = scipy.fft.dctn(rhs, norm="ortho")
            spectrum /= 1.0 + np.float32(tau * self.params.mu) * self.laplace_symbol
            rhs = scipy.fft.idctn(spectrum, norm="ortho")
        out = rhs.astype(np.float64)
        if not smooth_force:
            near = np.abs(phi) < self.band
            out[near] -= tau * force[near]
        return out

    def _explicit_step(self, state, force, tau):
        """``phi + tau mu Laplace(phi) - tau f`` on the band (5-point, Neumann: a mirrored pixel)."""
        m, n = self.shape
        flat = state.near_flat
        values = state.phi.ravel()
        centre = values[flat]
        row, col = np.divmod(flat, n)
        laplace = (values[np.where(row > 0, flat - n, flat)] + values[np.where(row < m - 1, flat + n, flat)]
                   + values[np.where(col > 0, flat - 1, flat)] + values[np.where(col < n - 1, flat + 1, flat)]
                   - 4.0 * centre)
        moved = centre + (tau * self.params.mu) * laplace
        near = np.abs(centre) < self.band
        moved[near] -= tau * force.ravel()[flat[near]]
        out = state.phi.copy()
        out.ravel()[flat] = moved
        return out


def _swept_area(old, new):
    """Area between the zero sets of two redistanced states, ``sum_px |H_eps(new) - H_eps(old)|``.

    With eps = 1 the integer translates of H_eps sum to the exact length of a half-line (module
    docstring), so this is the exact area between two parallel straight fronts at any sub-pixel
    offset, and second-order accurate for curved ones.  Only pixels in either band can differ.
    """
    if old.near_flat.size == 0 or new.near_flat.size == 0:
        return float(np.count_nonzero(old.positive != new.positive))
    seen = np.zeros(old.phi.size, dtype=bool)  # each band holds its pixels once: mark, not sort
    seen[old.near_flat] = True
    flat = np.concatenate([old.near_flat, new.near_flat[~seen[new.near_flat]]])
    return float(np.sum(np.abs(heaviside(new.phi.ravel()[flat]) - heaviside(old.phi.ravel()[flat]))))


def _parse_options(options):
    unknown = sorted(set(options) - set(DEFAULT_OPTIONS))
    if unknown:
        raise TypeError(
            f"unknown option(s) {', '.join(map(repr, unknown))} for backend 'levelset'; "
            f"the valid options are {', '.join(sorted(DEFAULT_OPTIONS))}"
        )
    settings = {**DEFAULT_OPTIONS, **options}
    for name in ("dt", "dt_min", "dt_max", "band", "checkerboard_period"):
        value = settings[name]
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise TypeError(f"option {name!r} must be a number, got {type(value).__name__}")
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"option {name!r} must be a positive finite number, got {value!r}")
        settings[name] = float(value)
    value = settings["max_backtracks"]
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ValueError(f"option 'max_backtracks' must be an integer >= 0, got {value!r}")
    settings["max_backtracks"] = int(value)
    # a first step outside the default range widens it (a viewer's step slider, say); only
    # bounds given explicitly must hold
    if "dt_min" not in options:
        settings["dt_min"] = min(settings["dt_min"], settings["dt"])
    if "dt_max" not in options:
        settings["dt_max"] = max(settings["dt_max"], settings["dt"])
    if not settings["dt_min"] <= settings["dt"] <= settings["dt_max"]:
        raise ValueError(
            f"options must satisfy dt_min <= dt <= dt_max, got dt_min={settings['dt_min']}, "
            f"dt={settings['dt']}, dt_max={settings['dt_max']}"
        )
    if settings["band"] < 2.0:
        raise ValueError(f"option 'band' must be at least 2 (pixels), got {settings['band']}")
    return settings


# --------------------------------------------------------------------------------------------
# The backend


def segment_levelset(model, init, params, *, max_num_iter, tol, callback, **options):
    """Minimise the Chan-Vese functional (6.38) with a level set over the pixel grid.

    Called by :func:`activecontour.segment` with ``backend="levelset"``; the keywords under
    Other Parameters are passed there as ``options={...}``.  The scheme, the step schedule and the
    energy are described in :mod:`activecontour.levelset`.

    Parameters
    ----------
    model : activecontour.image.ImageModel
    init : None, ndarray (K, 2), list of them, bool ndarray (M, N), SegmentationResult, or str
        None: the default start (:func:`activecontour.initial.initial_curves`).  Curves, masks
        and ``"grid"`` as for the polygon backend (pixel centres with nonzero winding are
        inside).  A result of either backend: its ``phi`` when it has one, else its contours.
        ``"checkerboard"``: squares of ``checkerboard_period`` x ``checkerboard_period`` pixels,
        at most a quarter of the image's smaller side (:func:`checkerboard_level_set`); it has no
        preferred phase, so when the functional is symmetric (omega = 0, lambda_in = lambda_out,
        c free) the phase of lower energy is returned (phi or -phi: they differ by the length
        along the image border, which the inside pays), i.e. the one whose inside touches the
        border less.
    params : activecontour.energy.ChanVeseParameters
        mu, omega, lambda_in, lambda_out and optional fixed c_in, c_out of (6.38), as for the
        polygon backend.
    max_num_iter : int
        Largest number of step attempts (accepted iterations, and stage changes without one).
    tol : float
        Pixels: the flow has converged (status 0) when the zero level set moves less than
        ``tol`` pixels per iteration (swept area over length, the mean normal displacement),
        averaged over the last three iterations of the final, unsmoothed stage.  The run also ends
        when no step, down to the current one halved ``max_backtracks`` times, decreases the
        energy (status 4: stationary to working precision).  Either way, continuing with a
        smaller tol changes neither the energy nor the mask measurably.
    callback : callable or None
        Called with a :class:`~activecontour.result.FlowState` (contours and ``phi``) after every
        accepted iteration; returning True stops the flow (status 2).

    Other Parameters
    ----------------
    dt : float, default 16.0
        First step, pixels of travel at the typical force (module docstring), at most half the
        width of the start's regions (but not below ``dt_min``).
    dt_min : float, default 1.0
        Below this ceiling the smoothed-force stages end and the unsmoothed stage (b) runs, with
        steps up to ``dt_min`` and the force within the band only (no single pixel far from
        Gamma flips).
    dt_max : float, default 64.0
        Largest step (pixels), the ceiling of the first stage.  A ``dt`` outside
        ``[dt_min, dt_max]`` widens the defaults; bounds given explicitly must satisfy
        ``dt_min <= dt <= dt_max``.
    band : float, default 4.0
        Narrow band: phi is the signed distance up to ``band`` pixels from Gamma and is clipped to
        ``+-band`` beyond.  At least 2.
    checkerboard_period : float, default 16.0
        Side (pixels) of the squares of the ``"checkerboard"`` start.
    max_backtracks : int, default 3
        Halvings of the step of the final stage before an iteration counts as stationary.

    Returns
    -------
    SegmentationResult
        Built by :func:`activecontour.result.build_result`: ``contours`` the zero level set
        (marching squares, outer boundaries positive, holes negative), ``mask`` their inside,
        ``energy`` (6.38) of the contours by the common evaluator, ``energies`` the same energy
        before the first and after every iteration (not increasing), and ``phi`` the final
        signed distance (clipped to the band; ``-band`` everywhere when the result is empty).

    Raises
    ------
    TypeError
        For an unknown option (the message lists the valid ones) or an option of the wrong type.
    ValueError
        For an unknown ``init`` string, a mask of the wrong shape, an init with nothing inside,
        or an option out of range.  (An init that covers the whole image is a valid start.)
    """
    settings = _parse_options(options)
    shape = tuple(model.shape)
    problem = _Problem(model, params, settings)
    if isinstance(init, str) and init == "checkerboard":
        # squares of at most a quarter of the smaller side: a small image gets several of them
        period = min(settings["checkerboard_period"], max(2.0, min(shape) / 4.0))
        phi = checkerboard_level_set(shape, period)  # redistanced below
    else:
        phi = initial_level_set(init, shape, band=settings["band"], values=model.values)
    state = problem.redistance(phi)
    current = problem.evaluate(state)
    energies, moves = [current.energy], []
    # step: pixels of travel at the typical force; ceiling: the largest step of this stage.  The
    # first step is at most the width of the start's regions (the smaller area over the length):
    # a larger one jumps past the start's own shapes into whatever basin it lands in.
    width = min(current.area, model.totals[0] - current.area) / max(current.length, 1.0)
    step = min(settings["dt"], max(0.5 * width, settings["dt_min"]))
    first_step, ceiling, grow, smooth_force = step, settings["dt_max"], True, True
    status, n_iter, stage_start, streak = 1, 0, 0, 0
    # When the unsmoothed stage ends, one smoothed step of the first size is tried (a recheck):
    # the unsmoothed flow stops at pixel-scale local minima that a smoothed step can leave.
    rechecks, pending = 0, None  # pending: the end status while a recheck runs
    for _ in range(max_num_iter):
        if not state.positive.any():
            status = 3
            break
        force, scale = problem.force(current.c_in, current.c_out)
        tau = problem.time_step(step, scale)
        # a smoothed-force stage whose step fails twice has reached its (biased) fixed point
        tries = 3 if smooth_force else settings["max_backtracks"] + 1
        for attempt in range(tries):  # noqa: B007 (attempt is read after the loop)
            trial = problem.redistance(problem.step(state, force, tau, smooth_force))
            evaluation = problem.evaluate(trial)
            # Emptying or filling the image is left to the unsmoothed force: a smoothed step that
            # does it has flattened phi rather than followed the force.
            degenerate = smooth_force and (not trial.positive.any() or trial.positive.all())
            if evaluation.energy <= current.energy and not degenerate:
                break
            step, tau, grow = 0.5 * step, 0.5 * tau, False
        else:
            if not smooth_force:
                if rechecks < _RECHECKS:
                    rechecks, pending, smooth_force = rechecks + 1, 4, True
                    step = ceiling = first_step
                    stage_start, streak = len(moves), 0
                    continue
                status = 4
                break
            if pending is not None and len(moves) == stage_start:
                status = pending  # the recheck found no descent: the end stands
                break
            evaluation = None
        if evaluation is not None:
            n_iter += 1
            # mean normal displacement of Gamma in this iteration, pixels: swept area over length
            moves.append(_swept_area(state, trial) / max(evaluation.length, current.length, 1.0))
            state, current = trial, evaluation
            energies.append(current.energy)
            streak = streak + 1 if attempt == 0 else 0
            if callback is not None:
                flow_state = FlowState(
                    iteration=n_iter, contours=level_set_contours(state.phi), energy=current.energy,
                    c_in=current.c_in, c_out=current.c_out, shape=shape, max_num_iter=max_num_iter,
                    phi=state.phi,
                )
                if callback(flow_state):
                    status = 2
                    break
        window = moves[stage_start:][-_WINDOW:]
        if smooth_force:
            # a smoothed-force stage has settled when Gamma moves by less than a small fraction
            # of the step (or 10 tol) per iteration; its fixed point is biased by the smoothing
            # of width sqrt(tau mu), so go on with a 4x smaller step, then unsmoothed
            settled = evaluation is None or (
                len(window) == _WINDOW and np.mean(window) < max(_STAGE_TOL * tol, _SETTLED * step))
            if settled:
                pending = None  # a recheck that moved on is a new descent, ended as usual
                ceiling = 0.25 * min(ceiling, 2.0 * step)
                if ceiling < settings["dt_min"]:
                    smooth_force, step = False, settings["dt_min"]
                else:
                    step = min(step, ceiling)
                stage_start, streak = len(moves), 0
            elif grow or streak >= 2:
                # accepted at once: speed up, doubling until the first rejection
                step = min(step * (2.0 if grow else 1.25), ceiling)
        elif len(window) == _WINDOW and np.mean(window) < tol:
            if rechecks < _RECHECKS:
                rechecks, pending, smooth_force = rechecks + 1, 0, True
                step = ceiling = first_step
                stage_start, streak = len(moves), 0
                continue
            status = 0
            break
        elif streak >= 2:
            step = min(1.25 * step, settings["dt_min"])
    phi = state.phi
    if isinstance(init, str) and init == "checkerboard" and _symmetric(params):
        # The checkerboard has no preferred phase and the symmetric functional prefers one only
        # through the length along the image border, which the inside pays: take the phase of
        # lower energy (-phi is stationary too, but for that border term).
        flipped = problem.evaluate(problem.redistance(-phi))
        if flipped.energy < current.energy:
            phi = -phi
            energies.append(flipped.energy)
    result = build_result(model, params, level_set_contours(phi), energies=energies, n_iter=n_iter,
                          status=status, backend="levelset", phi=phi)
    if not result.mask.any():  # collapsed, or the empty set is lower: phi says the same
        result.phi = np.full(shape, -settings["band"])
    return result


def _symmetric(params):
    return (params.omega == 0 and params.lambda_in == params.lambda_out
            and params.c_in is None and params.c_out is None)
